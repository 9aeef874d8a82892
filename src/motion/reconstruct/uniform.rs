//! The exposure variant's fast path: tiles where everything a pixel's exposure can see moves
//! as one smooth flow ([`TileKind::Uniform`], found by [`super::classify`]), whose pixels take the box shutter's line integral
//! of the colour ([`box_pixel`]) instead of the depth-weighted gather (issue 35: Jimenez's
//! fast-path tiles are the precedent).
//!
//! Why it is right, not only fast: where the motion of everything whose streak can reach a
//! pixel changes smoothly (a camera pan, a translating plate, a zoom, the inside of a large
//! moving surface), nothing uncovers or covers anything during the exposure, whatever the
//! depths, and the pixel integrates the frame's image along its own motion:
//! `(1/2) ∫ I(x + u·V) du` over u ∈ [−1, 1] (V the half-spread, a centred exposure; an
//! offset one moves the line 2·offset·V back along the motion). The
//! gather approximates that through its weights (every tap then weighs one, foreground or
//! background, but at the streak's ends, where its weights ramp and the centre fills in);
//! here the integral is read directly: as many taps as the gather takes, at the midpoints of
//! equal parts of the line, each read bilinearly (clamped at the frame's edge, as the
//! gather's), with the line shortened for the blur the bilinear read adds ([`shortened`]).
//! No depth, no weights, no matte: at 1080p on a camera pan the whole process 0.94 → 0.4 s,
//! and every truth scene's error the same or lower (BENCHMARKS.md, "Uniform tiles").
//!
//! Twin: `box_pixel` in src/gpu/motion/reconstruct.wgsl.

#[cfg(doc)]
use super::classify::TileKind;
use super::config::{
    ReconstructConfig, Texel2014, HALF_PIXEL, LENGTH, MAX_TAPS_PER_SIDE, TAP_SPACING, VX, VY,
};
#[cfg(doc)]
use super::taps::around_index;
use super::taps::Colours;

/// The box shutter's integral of the colours along pixel (x, y)'s own motion V (its texel's),
/// with n = 4k taps at the midpoints u = −1 + (i + ½)·2/n, i < n, of n equal parts of the
/// line, each the colours read bilinearly at (x, y) − 2·offset·V + u·V' (the line centred
/// where the exposure's middle saw the surface), summed (even and odd taps apart,
/// then together) and divided by n. k is the gather's taps a side for the pixel (at least
/// S/4, one every [`TAP_SPACING`] px of |V|, at most [`MAX_TAPS_PER_SIDE`]), so the line is
/// read as densely as the gather reads it. V' is V shortened by [`shortened`]. Only for a
/// moving pixel of a uniform tile, or of a hollow tile's body ([`TileKind::Hollow`]).
///
/// Midpoints, not the gather's per-pixel jitter: the colours read bilinearly are linear
/// between pixel centres, and the midpoint rule is exact on a line that is, where a comb
/// jittered as one errs by its offset at both ends of the line (on the 320×180 `pan`, stripes
/// 2.5 px streaks: region RMSE 0.00746 jittered, 0.00732 midpoints, before the shortening).
#[inline(always)]
pub fn box_pixel<const G: usize>(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    colour: &impl Fn(usize) -> Colours<G>,
    x: usize,
    y: usize,
) -> Colours<G> {
    let (width, height) = (config.width as usize, config.height as usize);
    let centre = &texels[y * width + x];
    let length = centre[LENGTH];
    debug_assert!(length >= HALF_PIXEL);
    let k = (config.taps.div_ceil(4).max(1) as usize)
        .max(((length / TAP_SPACING).ceil() as usize).min(MAX_TAPS_PER_SIDE));
    let n = 4 * k;
    let factor = shortened(length);
    let v = (centre[VX] * factor, centre[VY] * factor);
    // An offset exposure's streak is the centred one moved by 2·offset·V against the motion
    // (opening at the frame, the pixel sees what was behind it along V): the line's centre.
    let shift = -2.0 * config.offset;
    let centre_offset = (centre[VX] * shift, centre[VY] * shift);
    // A line along a row (or a column) reads every tap at a whole row (column): two of its
    // four corners weigh exactly 0 and are not read (the same sums: a zero product adds
    // nothing), half the reads of a sideways pan.
    let line = (centre_offset, v);
    // Centred, the line's centre is the pixel: a copy without its add (10 % of the pan's
    // time).
    match (v.1 == 0.0, v.0 == 0.0, config.offset == 0.0) {
        (true, _, true) => box_sums::<G, ROW, true>(colour, (width, height), (x, y), line, n),
        (true, _, false) => box_sums::<G, ROW, false>(colour, (width, height), (x, y), line, n),
        (_, true, true) => box_sums::<G, COLUMN, true>(colour, (width, height), (x, y), line, n),
        (_, true, false) => box_sums::<G, COLUMN, false>(colour, (width, height), (x, y), line, n),
        (_, _, true) => box_sums::<G, ANY, true>(colour, (width, height), (x, y), line, n),
        (_, _, false) => box_sums::<G, ANY, false>(colour, (width, height), (x, y), line, n),
    }
}

/// [`box_pixel`]'s taps' lines: any, along a row, along a column.
const ANY: u8 = 0;
const ROW: u8 = 1;
const COLUMN: u8 = 2;

/// [`box_pixel`]'s mean of its `n` taps along `v` about `centre` from pixel (x, y), for lines
/// of kind `LINE` (`CENTRED`: `centre` is ±0, not added: the same sums).
#[inline(always)]
fn box_sums<const G: usize, const LINE: u8, const CENTRED: bool>(
    colour: &impl Fn(usize) -> Colours<G>,
    size: (usize, usize),
    (x, y): (usize, usize),
    (centre, v): ((f32, f32), (f32, f32)),
    n: usize,
) -> Colours<G> {
    let step = 2.0 / n as f32;
    // Two sums, the even taps' and the odd ones' (n is even), each tap's four corners added
    // in pairs: one chain of adds through every tap held the path back.
    let (mut even, mut odd) = ([[0.0f32; 4]; G], [[0.0f32; 4]; G]);
    for pair in 0..n / 2 {
        let at = |u: f32| {
            if CENTRED {
                (v.0 * u, v.1 * u)
            } else {
                (centre.0 + v.0 * u, centre.1 + v.1 * u)
            }
        };
        let u = ((2 * pair) as f32 + 0.5) * step - 1.0;
        add_tap::<G, LINE>(&mut even, colour, size, (x, y), at(u));
        let u = ((2 * pair + 1) as f32 + 0.5) * step - 1.0;
        add_tap::<G, LINE>(&mut odd, colour, size, (x, y), at(u));
    }
    let count = n as f32;
    for g in 0..G {
        for ch in 0..4 {
            even[g][ch] = (even[g][ch] + odd[g][ch]) / count;
        }
    }
    even
}

/// The factor [`box_pixel`] shortens a half-spread of length `length` by: to
/// `sqrt(|V|² − 1/4)`, at least |V|/2 (the streak L = 2|V| to `sqrt(L² − 1)`).
///
/// Why: the colours are pixel areas, and reading them bilinearly between centres adds a
/// tent's blur (variance 1/6 px² along any line) to what the exposure's box blurs, wherever
/// an edge does not fall on a pixel boundary. Modelled in one dimension (steps on a pixel
/// boundary, steps and bars of 0.7–3.1 px at random sub-pixel places; streaks of 1 to 15 px;
/// the worst of the three kinds), taking c px² off L² errs least at c = 1 for streaks of
/// 1.5 px and more (c = 0: 0.0315 at 1.5 px, c = 1: 0.0223, c = 2: 0.0383) and no more
/// than c = 0.5 anywhere; c = 0 is exact only on the pixel-aligned steps. Measured on the
/// truth scenes (BENCHMARKS.md, "Uniform tiles"): c = 1 errs least on `pan` and `layers` at
/// 320×180 (0.00732 → 0.00624, 0.01914 → 0.01858) with the others within 0.5 %; c = 2 raised
/// `pan` to 0.00823.
#[inline]
pub fn shortened(length: f32) -> f32 {
    (length * length - 0.25).max(0.25 * length * length).sqrt() / length
}

/// The four pixels around pixel (x, y) + `offset`, as indices, with their bilinear weights:
/// the point clamped into the frame first ([`around_index`] clamps the pixels instead, so a
/// point past the edge weighs the edge pixel twice, by w and 1 − w, where here it weighs it
/// once by 1), so that every conversion is of a number in [0, width) (`as i32`, whose
/// saturation costs less than `as usize`'s).
#[inline(always)]
fn corners(
    (width, height): (usize, usize),
    x: usize,
    y: usize,
    offset: (f32, f32),
) -> [(usize, f32); 4] {
    let fx = (x as f32 + offset.0).clamp(0.0, (width - 1) as f32);
    let fy = (y as f32 + offset.1).clamp(0.0, (height - 1) as f32);
    let (x0, y0) = (fx as i32 as usize, fy as i32 as usize);
    let (wx, wy) = (fx - x0 as f32, fy - y0 as f32);
    let (x1, y1) = ((x0 + 1).min(width - 1), (y0 + 1).min(height - 1));
    [
        (y0 * width + x0, (1.0 - wx) * (1.0 - wy)),
        (y0 * width + x1, wx * (1.0 - wy)),
        (y1 * width + x0, (1.0 - wx) * wy),
        (y1 * width + x1, wx * wy),
    ]
}

/// Adds to `sum` the colours read bilinearly at pixel (x, y) + `offset`, the four corners
/// added in pairs; on a line of kind `LINE` ([`ROW`], [`COLUMN`]) the two whose weight is 0
/// left out.
#[inline(always)]
fn add_tap<const G: usize, const LINE: u8>(
    sum: &mut Colours<G>,
    colour: &impl Fn(usize) -> Colours<G>,
    size: (usize, usize),
    (x, y): (usize, usize),
    offset: (f32, f32),
) {
    let [(j0, w0), (j1, w1), (j2, w2), (j3, w3)] = corners(size, x, y, offset);
    match LINE {
        ROW => {
            let (c0, c1) = (colour(j0), colour(j1));
            for g in 0..G {
                for ch in 0..4 {
                    sum[g][ch] += w0 * c0[g][ch] + w1 * c1[g][ch];
                }
            }
        }
        COLUMN => {
            let (c0, c2) = (colour(j0), colour(j2));
            for g in 0..G {
                for ch in 0..4 {
                    sum[g][ch] += w0 * c0[g][ch] + w2 * c2[g][ch];
                }
            }
        }
        _ => {
            let (c0, c1, c2, c3) = (colour(j0), colour(j1), colour(j2), colour(j3));
            for g in 0..G {
                for ch in 0..4 {
                    sum[g][ch] +=
                        (w0 * c0[g][ch] + w1 * c1[g][ch]) + (w2 * c2[g][ch] + w3 * c3[g][ch]);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{Color, Velocity};
    use crate::motion::reconstruct::classify::{classify, TileKind};
    use crate::motion::reconstruct::matte::Matte;
    use crate::motion::reconstruct::{
        matte, pack_2014, packed_2014, spread_2014, ReconstructParams, Variant,
    };
    use crate::motion::tile_max::TileGrid;
    use crate::motion::{dilate::dilate, tile_max::tile_max};

    /// A `w`×`h` frame of one depth whose colour is `grey(x)` and whose motion (px a frame)
    /// is `motion(x, y)`, under `params` and a 0.5 shutter: its config, texels, dilated tiles
    /// and uniform tiles, and its mattes.
    fn frame(
        (w, h): (usize, usize),
        params: &ReconstructParams,
        grey: impl Fn(usize) -> f32,
        motion: impl Fn(usize, usize) -> (f32, f32),
    ) -> (
        ReconstructConfig,
        Vec<Texel2014>,
        TileGrid,
        Vec<bool>,
        Vec<Matte>,
    ) {
        let plane: Vec<f32> = (0..w * h).map(|i| grey(i % w)).collect();
        let color = Color {
            r: plane.clone(),
            g: plane.clone(),
            b: plane,
            a: None,
        };
        let (vx, vy): (Vec<f32>, Vec<f32>) = (0..w * h).map(|i| motion(i % w, i / w)).unzip();
        let config = ReconstructConfig::new(w, h, params, 0.5, 3);
        let mut tiles = tile_max(&vx, &vy, w, h, config.tile as usize);
        for (x, y) in tiles.x.iter_mut().zip(tiles.y.iter_mut()) {
            (*x, *y) = spread_2014(*x, *y, &config);
        }
        let dilated = dilate(&tiles);
        let packed = packed_2014(&config, &dilated);
        let velocity = Velocity { x: vx, y: vy };
        let depth = vec![4.0; w * h];
        let texels = pack_2014(&config, &color, &depth, &velocity, &dilated, &packed);
        let mattes = matte::mattes(&config, &texels, |c, row| packed.get(c, row));
        let uniform = uniform_of(&config, &texels, &mattes, &dilated);
        (config, texels, dilated, uniform, mattes)
    }

    /// Which tiles [`classify`] finds uniform.
    fn uniform_of(
        config: &ReconstructConfig,
        texels: &[Texel2014],
        mattes: &[Matte],
        tiles: &TileGrid,
    ) -> Vec<bool> {
        classify(config, texels, mattes, tiles)
            .into_iter()
            .map(|kind| kind == TileKind::Uniform)
            .collect()
    }

    #[test]
    fn the_box_integrates_the_bilinear_colour_along_the_shortened_streak() {
        // A step from 0 to 1 between columns 29 and 30, moving 10 px a frame sideways: read
        // bilinearly the colour ramps from 0 at x = 29 to 1 at x = 30, so along the pixel's
        // line the box's mean is (F(x + a) − F(x − a)) / 2a, F the ramp's integral and
        // a = sqrt(|V|² − 1/4) the shortened half-spread.
        let params = ReconstructParams::default();
        let (config, texels, _, uniform, _) = frame(
            (64, 16),
            &params,
            |x| (x >= 30) as u8 as f32,
            |_, _| (10.0, 0.0),
        );
        assert!(
            uniform.iter().all(|&u| u),
            "one motion everywhere: every tile uniform"
        );
        let integral = |s: f32| {
            if s <= 29.0 {
                0.0
            } else if s <= 30.0 {
                (s - 29.0) * (s - 29.0) / 2.0
            } else {
                0.5 + (s - 30.0)
            }
        };
        let colour = |j: usize| [[texels[j][0], texels[j][1], texels[j][2], texels[j][3]]];
        // Centred, the line about the pixel; opening at the frame (offset ½), about the
        // point |V| behind it along the motion (it sees what was there).
        for offset in [0.0, 0.5] {
            let config = ReconstructConfig { offset, ..config };
            for x in 24..40 {
                let length = texels[8 * 64 + x][LENGTH];
                let a = (length * length - 0.25).sqrt();
                let middle = x as f32 - 2.0 * offset * length;
                let expected = (integral(middle + a) - integral(middle - a)) / (2.0 * a);
                let got = box_pixel(&config, &texels, &colour, x, 8)[0];
                assert!(
                    (got[0] - expected).abs() < 1e-3 && got[1] == got[0] && got[3] == 1.0,
                    "offset {offset}, x = {x}: {got:?} against {expected}"
                );
            }
        }
    }

    #[test]
    fn carried_colours_get_the_bits_each_gets_alone() {
        // Lines of every kind (a row, a column, any), each pixel's box of the beauty and of a
        // second colour carried beside it against each alone.
        let params = ReconstructParams::default();
        let texture = |x: usize| (x as f32 * 0.37).sin() * 2.0 + 2.1;
        for motion in [(9.0, 0.0), (0.0, -7.0), (6.0, 5.0)] {
            let (config, texels, _, uniform, _) = frame((40, 24), &params, texture, |_, _| motion);
            assert!(uniform.iter().all(|&u| u));
            let beauty = |j: usize| texels[j][..4].try_into().unwrap();
            let other = |j: usize| -> [f32; 4] { [(j % 7) as f32, 0.5, -1.0, (j % 3) as f32] };
            let both = |j: usize| [beauty(j), other(j)];
            for (x, y) in [(0, 0), (13, 11), (39, 23), (20, 5)] {
                let [a, b] = box_pixel(&config, &texels, &both, x, y);
                let alone_a = box_pixel(&config, &texels, &|j| [beauty(j)], x, y)[0];
                let alone_b = box_pixel(&config, &texels, &|j| [other(j)], x, y)[0];
                assert_eq!(a.map(f32::to_bits), alone_a.map(f32::to_bits));
                assert_eq!(b.map(f32::to_bits), alone_b.map(f32::to_bits));
            }
        }
    }

    #[test]
    fn a_smooth_flow_is_uniform_and_a_jump_or_a_still_pixel_is_not() {
        let params = ReconstructParams::default();
        let size = (96, 64);
        let texture = |x: usize| (x as f32 * 0.7).sin();
        let column = |uniform: &[bool], c: usize| (0..8).all(|r| uniform[r * 12 + c]);
        // A gentle zoom (the motion grows 0.004 px a frame per px): smooth everywhere.
        let (.., gentle, _) = frame(size, &params, texture, |x, y| {
            (12.0 + 0.004 * x as f32, 4.0 + 0.004 * y as f32)
        });
        assert!(gentle.iter().all(|&u| u));
        // Steeper (0.2 px a frame per px: a half-spread step of 0.05 px, over a reach of 5 px
        // and more above an eighth of a pixel): nowhere.
        let (.., steep, _) = frame(size, &params, texture, |x, y| {
            (12.0 + 0.2 * x as f32, 4.0 + 0.004 * y as f32)
        });
        assert!(!steep.contains(&true));
        // A jump between columns 63 and 64 (12 → 20 px a frame; |V| 3 and 5 px, reach 7 px):
        // the tiles whose reach holds it (columns 6 to 8) are not uniform, the others are
        // (tile 9's pixels read back to x = 67 at most, all of one motion).
        let (.., jump, _) = frame(size, &params, texture, |x, _| {
            (if x < 64 { 12.0 } else { 20.0 }, 0.0)
        });
        assert!((0..6).chain(9..12).all(|c| column(&jump, c)));
        assert!(!(6..9).any(|c| (0..8).any(|r| jump[r * 12 + c])));
        // One still pixel at (40, 30): the tiles that reach it are not plain, so not uniform.
        let (.., still, _) = frame(size, &params, texture, |x, y| {
            if (x, y) == (40, 30) {
                (0.0, 0.0)
            } else {
                (12.0, 0.0)
            }
        });
        assert!(!still[3 * 12 + 5] && still[7 * 12]);
        // Blender's form: never. Ours under an offset exposure: as centred, its reach
        // grown by the offset (|M| × 2 + 2 px: tile 9's reach, 12 px, now holds the jump).
        let blender = ReconstructParams {
            variant: Variant::Stable,
            ..params
        };
        let (.., none, _) = frame(size, &blender, texture, |_, _| (12.0, 0.0));
        assert!(!none.contains(&true));
        let (mut config, texels, tiles, _, mattes) = frame(size, &params, texture, |x, _| {
            (if x < 64 { 12.0 } else { 20.0 }, 0.0)
        });
        config.offset = 0.5;
        let offset = uniform_of(&config, &texels, &mattes, &tiles);
        assert!((0..6).chain(10..12).all(|c| column(&offset, c)));
        assert!(!(6..10).any(|c| (0..8).any(|r| offset[r * 12 + c])));
    }
}
