//! A moving pixel's curve as it is drawn ([`Scatter::path`]: cut into segments, weighted
//! along the shutter, scaled to `max_curve` about p(0)): built by [`super::accumulate`] for
//! each tile the curve reaches, and by [`super::reach`] where only the built curve says how
//! far from p(0) it goes ([`Path::farthest`]). The GPU twin's `path` is in
//! src/gpu/motion/scatter/scatter.wgsl, its `farthest` in fixed.wgsl.

use crate::motion::curve::{length, Arc, Bezier, Point};

use super::config::{CurveKind, Normalize, MOST_SEGMENTS};
use super::job::{Moving, Scatter};

/// One curve, cut into segments, ready to draw.
pub(super) struct Path {
    pub(super) segments: usize,
    pub(super) points: [Point; MOST_SEGMENTS + 1],
    /// Weight along the curve at each point, already divided by the curve's total in exposure
    /// normalisation.
    pub(super) weights: [f64; MOST_SEGMENTS + 1],
    /// The curve's depth at each point.
    pub(super) depths: [f32; MOST_SEGMENTS + 1],
    /// Segment lengths before scaling to `max_curve`.
    pub(super) lengths: [f64; MOST_SEGMENTS],
    pub(super) color: [f64; 4],
    /// The carried planes' values at the curve's pixel.
    pub(super) extra: Vec<f64>,
}

impl Path {
    pub(super) fn new() -> Self {
        Path {
            segments: 0,
            points: [[0.0; 2]; MOST_SEGMENTS + 1],
            weights: [0.0; MOST_SEGMENTS + 1],
            depths: [0.0; MOST_SEGMENTS + 1],
            lengths: [0.0; MOST_SEGMENTS],
            color: [0.0; 4],
            extra: Vec::new(),
        }
    }

    /// How far the built curve's farthest point lies from `from` (its p(0)): its segments,
    /// and so its walks, lie within it (a segment is no farther from a point than its ends).
    pub(super) fn farthest(&self, from: Point) -> f64 {
        self.points[..=self.segments]
            .iter()
            .fold(0.0, |r, q| r.max(length([q[0] - from[0], q[1] - from[1]])))
    }
}

impl Scatter<'_> {
    /// The curve of moving pixel `i` inside the shutter, into `path`; false if it has none.
    /// A fringe pixel's ([`super::fringe`]) is its partner's (`fringe`: the partner and its
    /// coverage): the partner's colours and depths, along `motion` from the pixel's own
    /// centre, its weights times the coverage.
    pub(super) fn path(
        &self,
        i: usize,
        motion: &Moving,
        path: &mut Path,
        fringe: Option<(usize, f32)>,
    ) -> bool {
        let Moving {
            prev, now, next, ..
        } = *motion;
        let p = &self.config;
        let (t0, t1) = (self.t0, self.t1);
        let most = p.segments as usize;
        let tolerance = p.flatness as f64;
        let arc = if p.curve() == CurveKind::Arc {
            Arc::fit(prev, now, next)
        } else {
            None
        };
        let bezier = Bezier::through(prev, now, next);
        let segments = match &arc {
            Some(arc) => arc.segments(t0, t1, tolerance, most),
            None => bezier.segments(0.5 * (t1 - t0), tolerance, most),
        };
        path.segments = segments;
        let (i, cover) = fringe.map_or((i, 1.0), |(m, alpha)| (m, alpha as f64));
        path.color = self.color(i).map(f64::from);
        path.extra.clear();
        path.extra
            .extend(self.extra.iter().map(|plane| plane[i] as f64));
        let z0 = self.depth[i];
        let depth_at = match (&self.prev.z, &self.next.z) {
            (Some(zp), Some(zn)) if zp[i].is_finite() && zn[i].is_finite() && z0.is_finite() => {
                let (zp, zn) = (zp[i] as f64, zn[i] as f64);
                let z0 = z0 as f64;
                Some(move |t: f64| {
                    (z0 + t * 0.5 * (zn - zp) + t * t * (0.5 * (zn + zp) - z0)).max(0.0) as f32
                })
            }
            _ => None,
        };
        let mut total = 0.0;
        // (Counts convert to f64 through u32: one instruction instead of usize's several.)
        let step = (t1 - t0) / (segments as u32) as f64;
        for k in 0..segments + 1 {
            let t = t0 + step * (k as u32) as f64;
            path.points[k] = match &arc {
                Some(arc) => arc.at_time(t),
                None => bezier.at(0.5 * (t + 1.0)),
            };
            path.weights[k] = self.weight(t);
            path.depths[k] = depth_at.map_or(z0, |f| f(t));
            if k > 0 {
                let (a, b) = (path.points[k - 1], path.points[k]);
                path.lengths[k - 1] = length([b[0] - a[0], b[1] - a[1]]);
                total += path.lengths[k - 1];
            }
        }
        if total.is_nan() || total <= 1e-9 {
            return false;
        }
        let longest = p.max_curve.max(1.0) as f64;
        let mut scale = 1.0;
        if total > longest {
            // Scaled about p(0): a similarity, so every length scales the same.
            scale = longest / total;
            for q in &mut path.points[..=segments] {
                *q = [
                    now[0] + scale * (q[0] - now[0]),
                    now[1] + scale * (q[1] - now[1]),
                ];
            }
        }
        if p.normalize() == Normalize::Exposure {
            // The curve's deposits add up to Σ length × mean weight of each segment (weights
            // are linear along a segment): divide so they add up to 1.
            // (With the box weight every mean is 1 and the sum is the total length, bit for bit.)
            let mut sum = if p.gaussian == 0 {
                total
            } else {
                let mut sum = 0.0;
                for k in 0..segments {
                    sum += path.lengths[k] * 0.5 * (path.weights[k] + path.weights[k + 1]);
                }
                sum
            };
            sum *= scale;
            if !(sum > 0.0 && sum.is_finite()) {
                return false;
            }
            // (A fringe's weights times its coverage: α of a curve.)
            let inverse = cover / sum;
            for w in &mut path.weights[..=segments] {
                *w *= inverse;
            }
        }
        true
    }
}
