//! Motion curves through a pixel's three known positions p(-1), p(0), p(+1), for `scatter`
//! (Guertin & Nowrouzezahrai, §3.2).
//!
//! - [`Bezier`]: the paper's quadratic Bézier with B(0) = p(-1), B(½) = p(0), B(1) = p(+1).
//!   Two errata in the paper are fixed (docs/DESIGN.md): the curve is
//!   `(1-s)²B0 + 2(1-s)s·B1 + s²B2` (the paper prints `(1-s²)`), and the middle control point
//!   is `B1 = 2·p(0) - (p(-1) + p(1))/2` (the printed `p(0) - (p(-1) - p(1))/2` does not pass
//!   through p(0)). Time t ∈ [-1, 1] maps to s = (t + 1)/2, so this is the quadratic
//!   interpolating the three positions in time.
//! - [`Arc`]: the circle through the three positions, with the angle quadratic in time. Exact
//!   for steady rotation (and steadily accelerating rotation), which the quadratic only
//!   approximates; [`Arc::fit`] declines near-collinear or coincident points, where the
//!   Bézier is the right curve anyway.
//!
//! Geometry is f64: positions may lie millions of pixels off-screen and still have to clip to
//! sub-pixel accuracy.

use std::f64::consts::{PI, TAU};

pub type Point = [f64; 2];

fn sub(a: Point, b: Point) -> Point {
    [a[0] - b[0], a[1] - b[1]]
}

pub fn length(a: Point) -> f64 {
    (a[0] * a[0] + a[1] * a[1]).sqrt()
}

fn cross(a: Point, b: Point) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// A quadratic Bézier B(s), s ∈ [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bezier {
    pub b0: Point,
    pub b1: Point,
    pub b2: Point,
}

impl Bezier {
    /// The curve through `prev` at s = 0, `now` at s = ½ and `next` at s = 1.
    pub fn through(prev: Point, now: Point, next: Point) -> Bezier {
        Bezier {
            b0: prev,
            b1: [
                2.0 * now[0] - 0.5 * (prev[0] + next[0]),
                2.0 * now[1] - 0.5 * (prev[1] + next[1]),
            ],
            b2: next,
        }
    }

    pub fn at(&self, s: f64) -> Point {
        let (u, v) = ((1.0 - s) * (1.0 - s), 2.0 * (1.0 - s) * s);
        let w = s * s;
        [
            u * self.b0[0] + v * self.b1[0] + w * self.b2[0],
            u * self.b0[1] + v * self.b1[1] + w * self.b2[1],
        ]
    }

    /// |B''| = 2·|B0 − 2·B1 + B2|: how fast the curve leaves its chord.
    pub fn bend(&self) -> f64 {
        self.bend_squared().sqrt()
    }

    /// |B''|², without a root.
    pub fn bend_squared(&self) -> f64 {
        let (x, y) = (
            self.b0[0] - 2.0 * self.b1[0] + self.b2[0],
            self.b0[1] - 2.0 * self.b1[1] + self.b2[1],
        );
        4.0 * (x * x + y * y)
    }

    /// Segments needed over a span of `span` in s so no chord strays more than `tolerance`
    /// pixels from the curve (a chord over Δs strays at most |B''|·Δs²/8), at least 1 and at
    /// most `most`. A `tolerance` of 0 always gives `most`.
    pub fn segments(&self, span: f64, tolerance: f64, most: usize) -> usize {
        if tolerance <= 0.0 {
            return most.max(1);
        }
        // needed² = span²·|B''| / (8·tolerance), compared squared again first: most curves need
        // one segment, and then no root is taken.
        let limit = 8.0 * tolerance;
        let fourth = span * span * span * span * self.bend_squared();
        if fourth <= limit * limit {
            return 1;
        }
        let needed = -crate::motion::line::floor(-(span * (self.bend() / limit).sqrt()));
        if needed.is_finite() {
            (needed as usize).clamp(1, most.max(1))
        } else {
            most.max(1)
        }
    }
}

/// A circular arc: centre, radius, and the angle as a quadratic in time t ∈ [-1, 1],
/// θ(t) = θ0 + t·ω + t²·α, through the three positions at t = -1, 0, 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arc {
    pub centre: Point,
    pub radius: f64,
    pub theta: f64,
    pub omega: f64,
    pub alpha: f64,
}

/// Below this |sin| of the turn at p(0) the points count as collinear.
pub(crate) const COLLINEAR: f64 = 1e-4;
/// Arcs wider than this (pixels) are straight lines for any image.
pub(crate) const LARGEST_RADIUS: f64 = 1e7;

impl Arc {
    /// The arc from `prev` through `now` to `next`, or `None` where the points are
    /// (nearly) collinear or coincident.
    pub fn fit(prev: Point, now: Point, next: Point) -> Option<Arc> {
        let (a, b) = (sub(now, prev), sub(next, now));
        let turn = cross(a, b);
        let (la, lb) = (length(a), length(b));
        if !(la > 0.0 && lb > 0.0 && turn.abs() > COLLINEAR * la * lb) {
            return None;
        }
        // Circumcentre, relative to `now`.
        let (p, q) = (sub(prev, now), sub(next, now));
        let d = 2.0 * cross(p, q);
        let (pp, qq) = (p[0] * p[0] + p[1] * p[1], q[0] * q[0] + q[1] * q[1]);
        let offset = [(q[1] * pp - p[1] * qq) / d, (p[0] * qq - q[0] * pp) / d];
        let radius = length(offset);
        if !(radius.is_finite() && radius < LARGEST_RADIUS) {
            return None;
        }
        let centre = [now[0] + offset[0], now[1] + offset[1]];
        let angle = |pt: Point| (pt[1] - centre[1]).atan2(pt[0] - centre[0]);
        let theta = angle(now);
        // The arc runs the way the path turns: angles grow where the turn is positive.
        let (ahead, behind) = if turn > 0.0 {
            (
                (angle(next) - theta).rem_euclid(TAU),
                -(theta - angle(prev)).rem_euclid(TAU),
            )
        } else {
            (
                -(theta - angle(next)).rem_euclid(TAU),
                (angle(prev) - theta).rem_euclid(TAU),
            )
        };
        // Quadratic through (-1, behind), (0, 0), (1, ahead).
        Some(Arc {
            centre,
            radius,
            theta,
            omega: 0.5 * (ahead - behind),
            alpha: 0.5 * (ahead + behind),
        })
    }

    pub fn angle(&self, t: f64) -> f64 {
        self.theta + t * (self.omega + t * self.alpha)
    }

    pub fn at_time(&self, t: f64) -> Point {
        let a = self.angle(t);
        [
            self.centre[0] + self.radius * a.cos(),
            self.centre[1] + self.radius * a.sin(),
        ]
    }

    /// The angles the arc sweeps over t ∈ [t0, t1], lowest and highest: the angle is
    /// monotonic or turns once, so the ends and the vertex bound it.
    fn sweep(&self, t0: f64, t1: f64) -> (f64, f64) {
        let mut lo = self.angle(t0).min(self.angle(t1));
        let mut hi = self.angle(t0).max(self.angle(t1));
        if self.alpha != 0.0 {
            let vertex = -self.omega / (2.0 * self.alpha);
            if vertex > t0 && vertex < t1 {
                lo = lo.min(self.angle(vertex));
                hi = hi.max(self.angle(vertex));
            }
        }
        (lo, hi)
    }

    /// How far the arc over t ∈ [t0, t1] strays from its point at t = 0 (`now`, at angle
    /// θ): the chord 2r·|sin((a − θ)/2)| to its swept angle `a` farthest round the circle,
    /// 2r where the sweep passes the far side (θ + π). That chord grows up to the far side
    /// and shrinks past it, so elsewhere the farthest is at an end of the sweep. Chords drawn
    /// between points of the arc lie within it too, and so does the arc scaled about `now`.
    pub fn farthest(&self, t0: f64, t1: f64) -> f64 {
        let (lo, hi) = self.sweep(t0, t1);
        let far_side = self.theta + PI;
        let passes = far_side + ((lo - far_side) / TAU).ceil() * TAU <= hi;
        if passes || hi - lo >= TAU {
            return 2.0 * self.radius;
        }
        let chord = |a: f64| 2.0 * self.radius * (0.5 * (a - self.theta)).sin().abs();
        chord(lo).max(chord(hi))
    }

    /// Segments over t ∈ [t0, t1] so no chord's sagitta r·(1 − cos(δ/2)) ≈ r·δ²/8 exceeds
    /// `tolerance` pixels, at least 1 and at most `most` (`most` for a tolerance of 0).
    pub fn segments(&self, t0: f64, t1: f64, tolerance: f64, most: usize) -> usize {
        if tolerance <= 0.0 {
            return most.max(1);
        }
        let (lo, hi) = self.sweep(t0, t1);
        let sweep = (hi - lo).min(2.0 * PI * 4.0);
        let needed = (sweep * (self.radius / (8.0 * tolerance)).sqrt()).ceil();
        if needed.is_finite() {
            (needed as usize).clamp(1, most.max(1))
        } else {
            most.max(1)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Point, b: Point, tolerance: f64) -> bool {
        length(sub(a, b)) <= tolerance
    }

    /// `Arc::farthest` is the farthest of the arc's points from its p(0), sampled finely:
    /// sweeps short of the far side, past it, turning back (a vertex inside the exposure),
    /// and shutters opening at the frame and centred on it.
    #[test]
    fn an_arcs_farthest_point_is_the_sampled_arcs() {
        let arcs = [
            ([-3.0, 0.0], [0.0, 2.0], [3.0, 0.0]),
            ([10.0, 0.0], [0.0, 10.0], [-10.0, 0.5]),
            ([0.0, -4.0], [4.0, 0.0], [0.0, 4.5]),
            ([5.0, 0.0], [0.0, 5.0], [1.0, 4.9]),
        ];
        for (prev, now, next) in arcs {
            let arc = Arc::fit(prev, now, next).unwrap();
            for (t0, t1) in [(-0.25, 0.25), (0.0, 1.0), (-1.0, 1.0), (0.3, 0.9)] {
                let sampled = (0..=100_000)
                    .map(|k| arc.at_time(t0 + (t1 - t0) * k as f64 / 100_000.0))
                    .fold(0.0f64, |r, q| r.max(length(sub(q, now))));
                let far = arc.farthest(t0, t1);
                assert!(
                    far >= sampled - 1e-9 && far <= sampled + 1e-3,
                    "{prev:?} {now:?} {next:?} over [{t0}, {t1}]: {far} against {sampled}"
                );
            }
        }
    }

    #[test]
    fn bezier_passes_through_the_three_positions() {
        let (prev, now, next) = ([10.0, 20.0], [14.0, 18.5], [30.0, 25.0]);
        let b = Bezier::through(prev, now, next);
        assert!(close(b.at(0.0), prev, 1e-12));
        assert!(close(b.at(0.5), now, 1e-12));
        assert!(close(b.at(1.0), next, 1e-12));
        // The printed formula B1 = p(0) − (p(−1) − p(1))/2 would miss p(0) at s = ½.
        let printed = Bezier {
            b1: [
                now[0] - 0.5 * (prev[0] - next[0]),
                now[1] - 0.5 * (prev[1] - next[1]),
            ],
            ..b
        };
        assert!(!close(printed.at(0.5), now, 1.0));
    }

    #[test]
    fn bezier_is_the_quadratic_in_time() {
        // p(t) = p0 + t·v + t²·a sampled at −1, 0, 1 is reproduced at every t.
        let (p0, v, a) = ([5.0, -3.0], [7.0, 2.0], [-1.5, 4.0]);
        let p = |t: f64| {
            [
                p0[0] + t * v[0] + t * t * a[0],
                p0[1] + t * v[1] + t * t * a[1],
            ]
        };
        let b = Bezier::through(p(-1.0), p(0.0), p(1.0));
        for t in [-1.0, -0.3, 0.2, 0.77, 1.0] {
            assert!(close(b.at((t + 1.0) / 2.0), p(t), 1e-12));
        }
        // Straight curves need one segment; bent ones more, capped.
        let straight = Bezier::through([0.0, 0.0], [5.0, 5.0], [10.0, 10.0]);
        assert_eq!(straight.segments(1.0, 0.1, 10), 1);
        // |B''| = 4·|p''(t)| = 8·|a| = 8·4.272 = 34.18 px; over Δs = 1 a chord strays
        // 34.18/8 px, so 0.1 px needs √(34.18 / 0.8) = 6.54 → 7 segments; over Δs = 0.1, 1.
        assert!(crate::numeric::close(
            b.bend(),
            8.0 * (1.5f64.hypot(4.0)),
            1e-9
        ));
        assert_eq!(b.segments(1.0, 0.1, 10), 7);
        assert_eq!(b.segments(1.0, 0.1, 5), 5);
        assert_eq!(b.segments(0.1, 0.1, 10), 1);
        assert_eq!(b.segments(1.0, 0.0, 7), 7);
    }

    #[test]
    fn arc_is_exact_for_steady_rotation() {
        let (c, r, w) = ([100.0, 50.0], 40.0, 0.9);
        let at = |t: f64| {
            [
                c[0] + r * (0.3 + w * t).cos(),
                c[1] + r * (0.3 + w * t).sin(),
            ]
        };
        let arc = Arc::fit(at(-1.0), at(0.0), at(1.0)).unwrap();
        for t in [-1.0, -0.6, -0.1, 0.0, 0.25, 0.5, 1.0] {
            assert!(close(arc.at_time(t), at(t), 1e-9), "t = {t}");
        }
        // The quadratic strays from the circle in between.
        let b = Bezier::through(at(-1.0), at(0.0), at(1.0));
        assert!(!close(b.at((0.5 + 1.0) / 2.0), at(0.5), 0.05));
        // Clockwise, and sweeping more than π on one side.
        let at = |t: f64| {
            [
                c[0] + r * (1.0 - 2.5 * t).cos(),
                c[1] + r * (1.0 - 2.5 * t).sin(),
            ]
        };
        let arc = Arc::fit(at(-1.0), at(0.0), at(1.0)).unwrap();
        for t in [-1.0, -0.5, 0.3, 1.0] {
            assert!(close(arc.at_time(t), at(t), 1e-9), "t = {t}");
        }
        assert!(arc.segments(-1.0, 1.0, 0.1, 64) > 10);
    }

    #[test]
    fn arc_declines_collinear_and_coincident_points() {
        assert!(Arc::fit([0.0, 0.0], [1.0, 1.0], [2.0, 2.0]).is_none());
        assert!(Arc::fit([0.0, 0.0], [0.0, 0.0], [2.0, 1.0]).is_none());
        assert!(Arc::fit([0.0, 0.0], [1.0, 1e-9], [2.0, 0.0]).is_none());
        assert!(Arc::fit([f64::NAN, 0.0], [1.0, 1.0], [2.0, 0.0]).is_none());
    }
}
