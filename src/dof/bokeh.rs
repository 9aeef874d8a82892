//! The gather's taps and the shape of the diaphragm (Sousa, "DoF sampling" and "diaphragm
//! simulation").
//!
//! Taps sit on concentric rings: the centre, then ring k of `rings` at radius k/rings with
//! 8k taps, every other ring turned half a step. Ring k stands for the annulus between
//! radii (k − ½)/rings and (k + ½)/rings, whose area π·2k/rings² split over 8k taps is the
//! same for every tap — the even spread that Sousa gets from Shirley's concentric mapping,
//! with rings so that a pixel's taps never depend on anything but the ring count.
//!
//! With n blades each tap is pushed out to the regular n-gon of circumradius 1 by Sousa's
//! morph `r_ngon = r·cos(π/n) / cos(θ − (2π/n)·floor((n·θ + π)/(2π)))` (his f = 1: a fully
//! polygonal aperture), and the area a tap stands for grows with the square of that factor.
//! The same polygon gives the "norm" used for coverage: a point o lies inside the n-gon of
//! circumradius r when `norm(o) ≤ r`. The gather takes it of each tap's whole-pixel offset
//! (of o for the near field, where the image is turned over, and of −o for the far field).

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

    /// The radius of the unit shape in direction `theta` (1 at a polygon's vertices,
    /// cos(π/n) at the middle of its edges).
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

/// The taps of `rings` rings for the aperture, the centre first.
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
            let scale = aperture.extent(theta);
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

/// Every whole-pixel offset whose norm is at most `radius` + ½, the centre first, each
/// standing for one pixel's area: the exact neighbourhood, used where a bokeh is small enough
/// that rings would sample it no better than its own pixels.
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
            if (ox, oy) != (0, 0) && aperture.norm(dx, dy) <= radius as f32 + 0.5 {
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
