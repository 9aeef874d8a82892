//! Colours too far apart for one fixed point, carried in bands.
//!
//! A tile's sums count units of 2^(e − G) (fixed.wgsl; mod.rs, "The fixed point"), 2^e above
//! the largest |value| that can land in the tile and G at most 62 − ⌈log₂ N⌉ − w fractional
//! bits (40 to 49 of them). A value 2^b brighter than its neighbours leaves them
//! G − b bits: beside the numeric policy's largest colour, 10³⁰ (2¹⁰⁰), none, and every
//! ordinary pixel within the bright one's reach came out black, where the CPU's f64 sums keep
//! it. Scatter is linear in colour once its weights are found (they read depth, motion and
//! the fringe's factors, never the colour; each pixel's resolution is a weighted sum of
//! deposits and of input values), so a colour is split into bands, v = Σₖ bandₖ(v), each
//! band carried through the same dispatches as a light layer with fixed points of its own,
//! and the outputs added back. Band 0 is v clamped to ±2²⁴ ([`BAND`]), what a frame with a
//! firefly of 10⁷ holds today, its neighbours keeping ~25 bits; band k ≥ 1 is the part of v
//! between 2^(24k) and 2^(24(k+1)). Within a band a deposit is rounded to 2^−(G−24) of the
//! band's largest value, and a value of another pixel that is 0 in the band deposits exactly
//! 0: an ordinary pixel's output is band 0's, whatever lies in reach, and a bright pixel's
//! keeps 2^−(G−24) of its own magnitude. Five bands reach 2¹²⁰, past 10³⁰.
//!
//! A frame needs them only where some |value| exceeds 2²⁴ (1.7·10⁷, above any radiance a
//! renderer's firefly carries in practice); every other frame runs as before, the same bits.
//! Alpha's bands ride as a layer's R (its G and B zero), since a pixel's alpha is resolved as
//! each colour channel is. Each band of each colour that holds a value other than 0 costs one
//! carried layer.

use crate::frame::Color;

/// A colour's R, G and B planes.
fn rgb(c: &Color) -> [&[f32]; 3] {
    [&c.r, &c.g, &c.b]
}

/// The width of a band, 2²⁴: band 0 holds what one tile's fixed point holds beside a unit
/// colour with ~25 bits to spare.
pub(super) const BAND: f32 = 16_777_216.0;

/// The top of band k: 2^(24(k + 1)), +∞ past f32's range.
fn top(k: usize) -> f32 {
    BAND.powi(k as i32 + 1)
}

/// Band k of `v` (finite): the part of v between the tops of bands k − 1 and k.
pub(super) fn band(v: f32, k: usize) -> f32 {
    let upper = v.clamp(-top(k), top(k));
    if k == 0 {
        upper
    } else {
        upper - v.clamp(-top(k - 1), top(k - 1))
    }
}

/// Whose a carried band is: the beauty's colour, its alpha, or light layer i's colour.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Owner {
    Colour,
    Alpha,
    Layer(usize),
}

/// A frame's colours split into bands: band 0 of the beauty and of each layer in their
/// places, the bands above as extra layers after them, and whose each extra layer is.
pub(super) struct Split {
    pub(super) beauty: Color,
    pub(super) layers: Vec<Color>,
    owners: Vec<Owner>,
    given: usize,
}

/// The bands `color` and `layers` need beyond band 0, or None where every value lies in band
/// 0 (the frame runs as it is).
pub(super) fn split(color: &Color, layers: &[Color]) -> Option<Split> {
    let beyond = |plane: &[f32]| plane.iter().any(|v| v.abs() > BAND);
    let alpha = color.a.as_deref();
    let any = rgb(color).into_iter().chain(alpha).any(beyond)
        || layers.iter().any(|l| rgb(l).into_iter().any(beyond));
    if !any {
        return None;
    }
    let banded =
        |plane: &[f32], k: usize| -> Vec<f32> { plane.iter().map(|&v| band(v, k)).collect() };
    let zeros = vec![0.0; color.r.len()];
    let lowest = |c: &Color, a: Option<&[f32]>| Color {
        r: banded(&c.r, 0),
        g: banded(&c.g, 0),
        b: banded(&c.b, 0),
        a: a.map(|a| banded(a, 0)),
    };
    let beauty = lowest(color, alpha);
    let mut out: Vec<Color> = layers
        .iter()
        .map(|l| lowest(l, beauty.a.as_deref()))
        .collect();
    let mut owners = Vec::new();
    // Each owner's planes, R, G, B (alpha's in R).
    let mut sources: Vec<(Owner, [&[f32]; 3])> = vec![(Owner::Colour, rgb(color))];
    if let Some(a) = alpha {
        sources.push((Owner::Alpha, [a, &zeros, &zeros]));
    }
    sources.extend(
        layers
            .iter()
            .enumerate()
            .map(|(i, l)| (Owner::Layer(i), rgb(l))),
    );
    for (owner, planes) in sources {
        for k in 1.. {
            let reaches = |plane: &[f32]| plane.iter().any(|v| v.abs() > top(k - 1));
            if !planes.iter().any(|p| reaches(p)) {
                break;
            }
            let [r, g, b] = planes.map(|p| banded(p, k));
            out.push(Color {
                r,
                g,
                b,
                a: beauty.a.clone(),
            });
            owners.push(owner);
        }
    }
    Some(Split {
        beauty,
        layers: out,
        owners,
        given: layers.len(),
    })
}

impl Split {
    /// The outputs put together: `beauty` (band 0's output) plus its bands', and `layers` (as
    /// many as were given) each band 0's output plus its bands', in the order split made them.
    pub(super) fn join(
        self,
        mut beauty: Color,
        mut outputs: Vec<Color>,
        layers: &mut [Color],
    ) -> Color {
        let extra = outputs.split_off(self.given);
        for (band, owner) in extra.into_iter().zip(self.owners) {
            let add =
                |to: &mut [f32], from: &[f32]| to.iter_mut().zip(from).for_each(|(t, f)| *t += f);
            match owner {
                Owner::Colour => {
                    add(&mut beauty.r, &band.r);
                    add(&mut beauty.g, &band.g);
                    add(&mut beauty.b, &band.b);
                }
                Owner::Alpha => {
                    if let Some(a) = beauty.a.as_mut() {
                        add(a, &band.r);
                    }
                }
                Owner::Layer(i) => {
                    let to = &mut outputs[i];
                    add(&mut to.r, &band.r);
                    add(&mut to.g, &band.g);
                    add(&mut to.b, &band.b);
                }
            }
        }
        for (layer, out) in layers.iter_mut().zip(outputs) {
            layer.r = out.r;
            layer.g = out.g;
            layer.b = out.b;
        }
        beauty
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bands_of_a_value_add_up_to_it() {
        // Each band's part, written out: 2²⁴ and 2⁴⁸ are the tops of bands 0 and 1.
        let v = 3.0 * 2f32.powi(50);
        assert_eq!(band(v, 0), 16_777_216.0);
        assert_eq!(band(v, 1), 2f32.powi(48) - 16_777_216.0);
        assert_eq!(band(v, 2), v - 2f32.powi(48));
        assert_eq!(band(v, 3), 0.0);
        assert_eq!(band(-5.5, 0), -5.5);
        assert_eq!(band(-5.5, 1), 0.0);
        for v in [1e30f32, -1e30, 7e20, 2e7, -3e9, f32::MAX] {
            let sum: f32 = (0..6).map(|k| band(v, k)).sum();
            assert!((sum - v).abs() <= v.abs() * 1e-6, "{v}: {sum}");
        }
    }

    #[test]
    fn a_frame_within_band_0_is_not_split_and_one_beyond_it_is() {
        let plain = Color {
            r: vec![1.0, 1.6e7],
            g: vec![0.5; 2],
            b: vec![-1.0e7; 2],
            a: Some(vec![1.0; 2]),
        };
        assert!(split(&plain, std::slice::from_ref(&plain)).is_none());
        let mut hot = plain.clone();
        hot.g[1] = 1e30;
        let mut layer = plain.clone();
        layer.a = None;
        layer.b[0] = -1e10;
        let s = split(&hot, &[layer.clone()]).expect("split");
        // The beauty's G needs bands 1 to 4 (1e30 < 2⁹⁶·2²⁴); the layer's B band 1.
        assert_eq!(s.layers.len(), 1 + 4 + 1);
        assert_eq!(s.beauty.g, vec![0.5, BAND]);
        assert_eq!(s.layers[0].b[0], -BAND);
        // Joined back without a blur (each output its input), every value comes back.
        let outputs = s.layers.clone();
        let beauty = s.beauty.clone();
        let mut layers = [layer.clone()];
        let joined = s.join(beauty, outputs, &mut layers);
        assert!((joined.g[1] - 1e30).abs() <= 1e24);
        assert_eq!(joined.r, hot.r);
        assert_eq!(layers[0].b, layer.b);
    }
}
