//! The gather's taps and the shape of the diaphragm (Sousa, "DoF sampling" and "diaphragm
//! simulation").
//!
//! Taps sit on concentric rings: the centre, then ring k of `rings` at radius k/rings with
//! 8k taps, every other ring turned half a step. Ring k stands for the annulus between
//! radii (k − ½)/rings and (k + ½)/rings, whose area π·2k/rings² split over 8k taps is the
//! same for every tap — the even spread that Sousa gets from Shirley's concentric mapping,
//! with rings so that a pixel's taps never depend on anything but the ring count.
//!
//! With n blades the shape is the regular n-gon of circumradius 1 given by Sousa's morph
//! `r_ngon = r·cos(π/n) / cos(θ − (2π/n)·floor((n·θ + π)/(2π)))` (his f = 1: a fully
//! polygonal aperture). The same polygon gives the "norm" used for coverage: a point o lies
//! inside the n-gon of circumradius r when `norm(o) ≤ r`.
//!
//! **Orientation.** Angles are in the image's own axes (x right, y down, so a positive
//! angle turns clockwise on screen). At rotation 0 the middle of an edge lies on +x: a
//! triangle has a vertical flat edge on the right and points left (vertices at 60°, 180° and
//! 300°), a pentagon points left, a square stands on an edge; `--blade-rotation` turns the
//! shape clockwise. This is the bokeh of a point **behind** the focus plane: its light
//! crosses before the sensor and lands turned over, and the picture, turned over again to
//! be upright, shows the aperture as it stands (the shape as one sees the diaphragm from
//! behind the camera). A point **in front of** the focus plane meets the sensor before its
//! light converges: its bokeh is the same shape turned 180° about its centre (real lenses
//! flip: a triangle pointing left behind focus points right in front of it). Even blade
//! counts and the round aperture are the same both ways.
//!
//! The gather reads this as scatter: a pixel p takes light from a source at p + d when p
//! lies inside the source's bokeh, that is when −d lies inside the aperture (source behind
//! the focus plane, [`Aperture::norm`] of −d) or d does (source in front: of d). It tells
//! the two by field, not by each source's side of the focus plane: the far field takes the
//! norm of −d, the near field of d. They differ where a tile's sources in front of focus have
//! nothing nearer (one layer in front of focus: far field, not turned) or a source behind
//! focus lies before a farther background (near field, turned); choosing per source was built
//! (each lane by the sign of its CoC) and measured: the gather's loop took half as many
//! instructions again for every aperture, the round one included (cachegrind, 640×360, 1.05
//! → 1.56 G), for a reason not found, so it was not kept. A tile's
//! taps must therefore cover both the shape and its reflection: each tap is pushed out to
//! the farther of the two in its direction ([`Aperture::reach`]; for a symmetric shape the
//! shape itself), and the area a tap stands for grows with the square of that factor (the
//! morph's Jacobian). Covering only the shape, as before, let a source behind focus count
//! only where −d lay inside it as well: the shape cut by its own reflection, a hexagon for
//! three blades and a decagon for five, and a CPU and GPU that disagreed on which taps the
//! dense grid held.

use std::f32::consts::PI;

/// The diaphragm: round, or a regular polygon of `blades` sides turned by `rotation` radians.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aperture {
    pub blades: u32,
    pub rotation: f32,
}

impl Aperture {
    pub fn new(blades: u32, rotation_degrees: f32) -> Self {
        Aperture {
            blades,
            rotation: rotation_degrees.to_radians(),
        }
    }

    fn round(&self) -> bool {
        self.blades < 3
    }

    /// Whether the shape is its own reflection through its centre (round, or an even number
    /// of blades): then a source's bokeh is the same in front of focus and behind it.
    pub fn symmetric(&self) -> bool {
        self.round() || self.blades.is_multiple_of(2)
    }

    /// How far the taps must reach in direction `theta` (circumradius 1): the farther of
    /// the shape and its reflection, [`Aperture::extent`] of `theta` and of `theta + π`
    /// (the shape's own extent where it is [`Aperture::symmetric`]).
    pub fn reach(&self, theta: f32) -> f32 {
        if self.symmetric() {
            return self.extent(theta);
        }
        self.extent(theta).max(self.extent(theta + PI))
    }

    /// The smaller of [`Aperture::norm`] of `(dx, dy)` and of its reflection: the smallest r
    /// such that the shape of circumradius r or its reflection holds the offset, as far as
    /// a bokeh of radius r reaches either way.
    pub fn norm_either(&self, dx: f32, dy: f32) -> f32 {
        if self.symmetric() {
            return self.norm(dx, dy);
        }
        self.norm(dx, dy).min(self.norm(-dx, -dy))
    }

    /// The radius of the unit shape in direction `theta` (1 at a polygon's vertices,
    /// cos(π/n) at the middle of its edges, the first edge's middle at `rotation`).
    pub fn extent(&self, theta: f32) -> f32 {
        if self.round() {
            return 1.0;
        }
        let n = self.blades as f32;
        let t = (theta - self.rotation).rem_euclid(2.0 * PI);
        let nearest = (2.0 * PI / n) * ((n * t + PI) / (2.0 * PI)).floor();
        (PI / n).cos() / (t - nearest).cos()
    }

    /// The smallest r such that `(dx, dy)` lies inside the shape of circumradius r.
    pub fn norm(&self, dx: f32, dy: f32) -> f32 {
        let length = (dx * dx + dy * dy).sqrt();
        if length == 0.0 {
            return 0.0;
        }
        // A round shape's extent is 1 in every direction: no angle to find.
        if self.round() {
            return length;
        }
        length / self.extent(dy.atan2(dx))
    }

    /// Area of the shape of circumradius 1: π, or (n/2)·sin(2π/n).
    pub fn unit_area(&self) -> f32 {
        if self.round() {
            PI
        } else {
            let n = self.blades as f32;
            0.5 * n * (2.0 * PI / n).sin()
        }
    }
}

/// One tap of the unit pattern.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tap {
    /// Offset from the pixel, in units of the gather radius.
    pub dx: f32,
    pub dy: f32,
    /// The area this tap stands for, in units of radius²; the taps' areas sum to the
    /// shape's area (out to the outer ring's half step).
    pub area: f32,
}

/// The taps of `rings` rings for the aperture, the centre first, pushed out to
/// [`Aperture::reach`]: they cover the shape and its reflection.
pub fn taps(rings: usize, aperture: &Aperture) -> Vec<Tap> {
    let rings = rings.max(1);
    let step = 1.0 / rings as f32;
    let mut taps = vec![Tap {
        dx: 0.0,
        dy: 0.0,
        area: PI * (0.5 * step) * (0.5 * step),
    }];
    for k in 1..=rings {
        let count = 8 * k;
        let radius = k as f32 * step;
        let turn = if k % 2 == 1 { 0.5 } else { 0.0 };
        let area = PI * 2.0 * k as f32 * step * step / count as f32;
        for j in 0..count {
            let theta = 2.0 * PI * (j as f32 + turn) / count as f32;
            let scale = aperture.reach(theta);
            let (dx, dy) = (radius * scale * theta.cos(), radius * scale * theta.sin());
            taps.push(Tap {
                dx,
                dy,
                area: area * scale * scale,
            });
        }
    }
    taps
}

/// Every whole-pixel offset whose norm, or its reflection's ([`Aperture::norm_either`]), is at
/// most `radius` + ½, the centre first, each standing for one pixel's area: the exact
/// neighbourhood of a bokeh behind focus or in front of it, used where a bokeh is small
/// enough that rings would sample it no better than its own pixels. A larger radius's grid
/// holds a smaller one's offsets in the same order (row by row), and each offset it adds lies
/// beyond the smaller radius's bokehs either way.
pub fn grid(radius: usize, aperture: &Aperture) -> Vec<Tap> {
    let r = radius as isize;
    let mut taps = vec![Tap {
        dx: 0.0,
        dy: 0.0,
        area: 1.0,
    }];
    for oy in -r..=r {
        for ox in -r..=r {
            let (dx, dy) = (ox as f32, oy as f32);
            if (ox, oy) != (0, 0) && aperture.norm_either(dx, dy) <= radius as f32 + 0.5 {
                taps.push(Tap { dx, dy, area: 1.0 });
            }
        }
    }
    taps
}

/// The aperture's norms of the whole-pixel offsets within `half` px each way, made once a
/// frame: every tile takes two a tap (of −offset and of the offset), and a polygon's each
/// took an arc tangent (with six blades, 4.5 % of the instructions of the bench's 1080p
/// frame out of focus, by cachegrind). Offsets beyond are normed as they come.
pub struct Norms {
    pub aperture: Aperture,
    half: isize,
    table: Vec<f32>,
}

impl Norms {
    pub fn new(aperture: Aperture, half: usize) -> Self {
        let half = half as isize;
        let table = (-half..=half)
            .flat_map(|dy| (-half..=half).map(move |dx| aperture.norm(dx as f32, dy as f32)))
            .collect();
        Norms {
            aperture,
            half,
            table,
        }
    }

    /// [`Aperture::norm`] of the offset (dx, dy): the same value.
    pub fn of(&self, dx: isize, dy: isize) -> f32 {
        let h = self.half;
        if dx.abs() <= h && dy.abs() <= h {
            self.table[((dy + h) * (2 * h + 1) + dx + h) as usize]
        } else {
            self.aperture.norm(dx as f32, dy as f32)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn round_taps_cover_the_disc_evenly() {
        let round = Aperture::new(0, 0.0);
        for rings in 1..=6 {
            let t = taps(rings, &round);
            assert_eq!(t.len(), 1 + 4 * rings * (rings + 1));
            // Areas sum to the disc out to half a ring step beyond the outer ring.
            let outer = 1.0 + 0.5 / rings as f32;
            let sum: f32 = t.iter().map(|t| t.area).sum();
            assert!(close(sum, PI * outer * outer, 1e-4), "{rings}: {sum}");
            for tap in &t {
                let r = (tap.dx * tap.dx + tap.dy * tap.dy).sqrt();
                let (far, near) = (round.norm(-tap.dx, -tap.dy), round.norm(tap.dx, tap.dy));
                assert!(close(far, r, 1e-5) && close(near, r, 1e-5));
            }
        }
    }

    #[test]
    fn grid_taps_are_the_pixels_of_the_disc() {
        let round = Aperture::new(0, 0.0);
        // Radius 1: the centre and its 8 neighbours (the diagonals at √2 ≤ 1.5).
        assert_eq!(grid(1, &round).len(), 9);
        // Radius 2: offsets with x² + y² ≤ 6.25, counted by hand: 1 + 4 + 4 + 4 + 8 = 21.
        assert_eq!(grid(2, &round).len(), 21);
        assert_eq!(grid(3, &round)[0].dx, 0.0);
    }

    #[test]
    fn polygon_shape_matches_sousas_morph() {
        let hexagon = Aperture::new(6, 0.0);
        // Vertices at θ = ±π/6 lie at radius 1, edge middles (θ = 0) at cos(π/6).
        assert!(close(hexagon.extent(PI / 6.0), 1.0, 1e-6));
        assert!(close(hexagon.extent(0.0), (PI / 6.0).cos(), 1e-6));
        // Every tap lies inside the unit hexagon, on its own ring's polygon.
        for tap in taps(4, &hexagon) {
            let r = hexagon.norm(tap.dx, tap.dy);
            assert!(r <= 1.0 + 1e-5);
            let ring = (r * 4.0).round() / 4.0;
            assert!(close(r, ring, 1e-4), "{r}");
        }
        // Area of a regular hexagon of circumradius 1: 3√3/2.
        assert!(close(hexagon.unit_area(), 1.5 * 3f32.sqrt(), 1e-5));
        // A pentagon is not symmetric: the near field sees it turned over.
        let pentagon = Aperture::new(5, 0.0);
        let tap = taps(2, &pentagon)[3];
        assert!((pentagon.norm(-tap.dx, -tap.dy) - pentagon.norm(tap.dx, tap.dy)).abs() > 1e-3);
        // Rotating the blades turns the shape.
        let turned = Aperture::new(6, 30.0);
        assert!(close(turned.extent(PI / 6.0), (PI / 6.0).cos(), 1e-5));
    }

    #[test]
    fn odd_blades_taps_cover_the_shape_and_its_reflection() {
        for aperture in [Aperture::new(3, 0.0), Aperture::new(5, 20.0)] {
            // A triangle at rotation 0 points left: its vertex at 180°, an edge's middle at
            // 0° (cos(π/3) = ½ from the centre); the taps reach the vertex both ways.
            if aperture.blades == 3 {
                assert!(close(aperture.extent(PI), 1.0, 1e-6));
                assert!(close(aperture.extent(0.0), 0.5, 1e-6));
                assert!(close(aperture.reach(0.0), 1.0, 1e-6));
                assert!(close(aperture.reach(PI), 1.0, 1e-6));
            }
            // Every ring tap lies inside the shape or its reflection, and at the outer ring
            // each of the shape's vertices, and each of its reflection's, has a tap within
            // half a ring step.
            let rings = 8;
            let t = taps(rings, &aperture);
            for tap in &t {
                assert!(aperture.norm_either(tap.dx, tap.dy) <= 1.0 + 1e-5);
            }
            let n = aperture.blades as usize;
            for k in 0..n {
                let theta = aperture.rotation + PI / n as f32 + 2.0 * PI * k as f32 / n as f32;
                for sign in [1.0, -1.0] {
                    let (vx, vy) = (sign * theta.cos(), sign * theta.sin());
                    let nearest = t
                        .iter()
                        .map(|t| ((t.dx - vx).powi(2) + (t.dy - vy).powi(2)).sqrt())
                        .fold(f32::MAX, f32::min);
                    assert!(nearest < 0.5 / rings as f32, "{aperture:?} {k} {sign}");
                }
            }
            // The grid holds every offset either shape holds, and nothing else.
            let g = grid(4, &aperture);
            for oy in -6i32..=6 {
                for ox in -6i32..=6 {
                    let (dx, dy) = (ox as f32, oy as f32);
                    let inside = aperture.norm(dx, dy).min(aperture.norm(-dx, -dy)) <= 4.5;
                    let held = g.iter().any(|t| (t.dx, t.dy) == (dx, dy));
                    assert_eq!(held, inside, "{aperture:?} ({ox}, {oy})");
                }
            }
            // A larger grid keeps a smaller one's offsets in order (the GPU reads one grid for
            // every small bokeh, the CPU the smallest that holds it).
            let small: Vec<_> = grid(3, &aperture).iter().map(|t| (t.dx, t.dy)).collect();
            let large: Vec<_> = g
                .iter()
                .map(|t| (t.dx, t.dy))
                .filter(|o| small.contains(o))
                .collect();
            assert_eq!(small, large);
        }
        // A symmetric shape's taps are its own: the norms of an offset and its reflection
        // agree to the bit for a round aperture.
        let round = Aperture::new(0, 0.0);
        for (dx, dy) in [(3.0, -2.0), (0.5, 7.25)] {
            assert_eq!(round.norm_either(dx, dy), round.norm(dx, dy));
            assert_eq!(round.norm(-dx, -dy).to_bits(), round.norm(dx, dy).to_bits());
        }
    }

    #[test]
    fn the_table_s_norms_are_the_aperture_s_inside_it_and_beyond() {
        for aperture in [
            Aperture::new(0, 0.0),
            Aperture::new(6, 15.0),
            Aperture::new(5, 0.0),
        ] {
            let norms = Norms::new(aperture, 4);
            for dy in -7isize..=7 {
                for dx in -7isize..=7 {
                    let expected = aperture.norm(dx as f32, dy as f32);
                    assert_eq!(
                        norms.of(dx, dy).to_bits(),
                        expected.to_bits(),
                        "({dx}, {dy})"
                    );
                }
            }
        }
    }
}
