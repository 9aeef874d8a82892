//! One frame's scatter as its stages see it ([`Scatter`]): the input buffers, the config and
//! the exposure, with each pixel's motion (its three positions, and the parabola's bound on
//! how far its curve strays) and the weight along a curve. [`super::reach`], [`super::accumulate`] and
//! [`super::resolve`] add the stages' own methods.

use super::config::{ScatterConfig, Weight, STILL};
use crate::frame::{Color, Positions};
use crate::motion::curve::{length, Point};
use crate::motion::shutter::Shutter;

/// A moving pixel's three positions.
#[derive(Clone, Copy)]
pub(super) struct Moving {
    pub(super) prev: Point,
    pub(super) now: Point,
    pub(super) next: Point,
}

/// The still pixels at a silhouette (what the `fringe` stage finds), in index order, each
/// with its moving partner and the partner's coverage of it; and which pixels move, as the
/// stage found it (empty where it did not look), so `reach` does not test them again.
#[derive(Default, Debug, Clone, PartialEq)]
pub struct Fringe {
    pub pixels: Vec<u32>,
    pub partners: Vec<u32>,
    pub cover: Vec<f32>,
    pub moving: Vec<bool>,
}

impl Fringe {
    /// Pixel `i`'s partner and its coverage, where `i` is a fringe pixel.
    #[inline]
    pub(super) fn get(&self, i: usize) -> Option<(usize, f32)> {
        let k = self.pixels.binary_search(&(i as u32)).ok()?;
        Some((self.partners[k] as usize, self.cover[k]))
    }

    /// The entries of the pixels in `range`, as a range of entries.
    pub(super) fn within(&self, range: std::ops::Range<usize>) -> std::ops::Range<usize> {
        let start = self.pixels.partition_point(|&p| (p as usize) < range.start);
        let end = self.pixels.partition_point(|&p| (p as usize) < range.end);
        start..end
    }

    pub fn is_empty(&self) -> bool {
        self.pixels.is_empty()
    }
}

static NO_FRINGE: Fringe = Fringe {
    pixels: Vec::new(),
    partners: Vec::new(),
    cover: Vec::new(),
    moving: Vec::new(),
};

/// One frame's scatter: its input buffers and config.
pub(super) struct Scatter<'a> {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) color: &'a Color,
    /// Colour planes carried beside the beauty (light layers), blurred with its weights.
    pub(super) extra: Vec<&'a [f32]>,
    /// The still pixels at a silhouette, each with the moving surface's share of it.
    pub(super) fringe: &'a Fringe,
    pub(super) depth: &'a [f32],
    pub(super) prev: &'a Positions,
    pub(super) next: &'a Positions,
    pub(super) config: ScatterConfig,
    /// The exposure: t ∈ [t0, t1] (frames from the frame's instant).
    pub(super) t0: f64,
    pub(super) t1: f64,
    /// The farthest the exposure gets from the frame's instant, max(|t0|, |t1|): half the
    /// shutter when it is centred.
    pub(super) half: f64,
    /// The middle of the exposure, (t0 + t1)/2: where the Gaussian weight peaks.
    pub(super) middle: f64,
}

impl<'a> Scatter<'a> {
    pub(super) fn new(
        config: ScatterConfig,
        color: &'a Color,
        depth: &'a [f32],
        prev: &'a Positions,
        next: &'a Positions,
    ) -> Self {
        let (t0, t1) = Shutter {
            open: config.shutter,
            offset: config.offset,
        }
        .interval();
        let (t0, t1) = (t0 as f64, t1 as f64);
        Scatter {
            width: config.width as usize,
            height: config.height as usize,
            color,
            extra: Vec::new(),
            fringe: &NO_FRINGE,
            depth,
            prev,
            next,
            config,
            t0,
            t1,
            half: t0.abs().max(t1.abs()),
            middle: 0.5 * (t0 + t1),
        }
    }
}

impl Scatter<'_> {
    #[inline]
    pub(super) fn color(&self, i: usize) -> [f32; 4] {
        [
            self.color.r[i],
            self.color.g[i],
            self.color.b[i],
            self.color.a.as_ref().map_or(1.0, |a| a[i]),
        ]
    }

    /// The motion of a moving pixel; `None` where it is still.
    #[inline]
    pub(super) fn motion(&self, x: usize, y: usize) -> Option<Moving> {
        self.moving(x, y).map(|(motion, _)| motion)
    }

    /// [`Scatter::motion`], with its [`Scatter::extent`] (the parabola's bound, which decided).
    #[inline]
    pub(super) fn moving(&self, x: usize, y: usize) -> Option<(Moving, f64)> {
        let i = y * self.width + x;
        let now = [x as f64 + 0.5, y as f64 + 0.5];
        let prev = [self.prev.x[i] as f64, self.prev.y[i] as f64];
        let next = [self.next.x[i] as f64, self.next.y[i] as f64];
        let extent = self.extent(prev, now, next);
        (extent >= STILL).then_some((Moving { prev, now, next }, extent))
    }

    /// Which pixels of row `y` move (`out[x]`, as [`Scatter::motion`] decides it): a bound in
    /// f32 over the whole row (lanes the compiler vectorises), and the f64 test only where the
    /// f32 figure lies within its rounding of the threshold (or is not finite). Most frames are
    /// mostly still or mostly moving, so the f64 test, paid twice a frame (the fringe and
    /// reach), runs on few pixels.
    pub(super) fn moving_row(&self, y: usize, out: &mut [bool]) {
        let row = y * self.width..(y + 1) * self.width;
        let (px, py) = (&self.prev.x[row.clone()], &self.prev.y[row.clone()]);
        let (nx, ny) = (&self.next.x[row.clone()], &self.next.y[row]);
        let h = self.half as f32;
        let (hh, cy) = (h * h, y as f32 + 0.5);
        // f32 rounding of the sums and the centre: a few ulps of the largest coordinate,
        // scaled by the bound's factors, well above it.
        let slack = 1e-6 * (1.0 + h + hh);
        let still = STILL as f32;
        // Chunks of 32: the bound over a chunk, then the f64 test for its unsure pixels.
        const CHUNK: usize = 32;
        for (c, out) in out.chunks_mut(CHUNK).enumerate() {
            let x0 = c * CHUNK;
            let span = x0..x0 + out.len();
            let (px, py) = (&px[span.clone()], &py[span.clone()]);
            let (nx, ny) = (&nx[span.clone()], &ny[span]);
            let mut stays = [false; CHUNK];
            for k in 0..out.len().min(CHUNK) {
                let (px, py, nx, ny) = (px[k], py[k], nx[k], ny[k]);
                let cx = (x0 + k) as f32 + 0.5;
                let (vx, vy) = (0.5 * (nx - px), 0.5 * (ny - py));
                let (ax, ay) = (0.5 * (nx + px) - cx, 0.5 * (ny + py) - cy);
                let extent = h * (vx * vx + vy * vy).sqrt() + hh * (ax * ax + ay * ay).sqrt();
                let scale = px.abs() + py.abs() + nx.abs() + ny.abs() + cx + cy;
                let tolerance = 1e-3 + slack * scale;
                // NaN anywhere leaves both comparisons false: the f64 test decides.
                out[k] = extent - still > tolerance;
                stays[k] = still - extent > tolerance;
            }
            for (k, o) in out.iter_mut().enumerate() {
                if !*o && !stays[k] {
                    *o = self.motion(x0 + k, y).is_some();
                }
            }
        }
    }

    /// The positions of a pixel known to move (skips [`Scatter::motion`]'s test).
    #[inline]
    pub(super) fn positions(&self, x: usize, y: usize) -> Moving {
        let i = y * self.width + x;
        Moving {
            prev: [self.prev.x[i] as f64, self.prev.y[i] as f64],
            now: [x as f64 + 0.5, y as f64 + 0.5],
            next: [self.next.x[i] as f64, self.next.y[i] as f64],
        }
    }

    /// A bound on how far the parabola through the three positions strays from p(0) during
    /// the exposure: with p(t) = p0 + t·v + t²·a, at most h·|v| + h²·|a| for |t| ≤ h (h =
    /// `half`, the farthest the exposure gets from the frame). The Bézier's, not the arc's
    /// (which may turn past its circle's far side): [`Scatter::reach`] says when it bounds
    /// where a curve deposits.
    #[inline]
    pub(super) fn extent(&self, prev: Point, now: Point, next: Point) -> f64 {
        let v = [0.5 * (next[0] - prev[0]), 0.5 * (next[1] - prev[1])];
        let a = [
            0.5 * (next[0] + prev[0]) - now[0],
            0.5 * (next[1] + prev[1]) - now[1],
        ];
        self.half * length(v) + self.half * self.half * length(a)
    }

    #[inline]
    pub(super) fn weight(&self, t: f64) -> f64 {
        if self.config.weight() == Weight::Box {
            1.0
        } else {
            let d = 0.5 * (t - self.middle); // s − s(middle), μ at the exposure's middle
            let sigma = self.config.sigma as f64;
            (-d * d / (2.0 * sigma * sigma)).exp()
        }
    }
}

impl Scatter<'_> {
    /// Fringe pixel (x, y)'s curve: its partner `m`'s three positions moved to its own
    /// centre (the same motion).
    #[inline]
    pub(super) fn fringe_positions(&self, x: usize, y: usize, m: usize) -> Moving {
        let (mx, my) = ((m % self.width) as f64, (m / self.width) as f64);
        let d = [x as f64 - mx, y as f64 - my];
        Moving {
            prev: [self.prev.x[m] as f64 + d[0], self.prev.y[m] as f64 + d[1]],
            now: [x as f64 + 0.5, y as f64 + 0.5],
            next: [self.next.x[m] as f64 + d[0], self.next.y[m] as f64 + d[1]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::truth::sample::hash01;
    use crate::motion::scatter::ScatterParams;

    #[test]
    fn a_row_s_motion_test_is_each_pixel_s() {
        // Rows of pixels whose bound lies within rounding of the threshold, random ones, and
        // hostile ones (NaN, infinities, 1e30), at small and large coordinates, under four
        // shutters: the row's test must say what the pixel's f64 test says, pixel by pixel.
        let (w, h) = (2048usize, 2048usize);
        let mut near = 0;
        for (open, offset) in [(0.5f32, 0.0f32), (1.0, 0.0), (0.5, 0.5), (2.0, -0.3)] {
            let shutter = Shutter { open, offset };
            let config = ScatterConfig::new(w, h, &ScatterParams::default(), shutter);
            let (t0, t1) = shutter.interval();
            let half = (t0.abs().max(t1.abs())) as f64;
            let mut prev = Positions {
                x: vec![0.0; w * h],
                y: vec![0.0; w * h],
                z: None,
            };
            let mut next = prev.clone();
            let rows = [0usize, 1000, h - 1];
            for (k, &y) in rows.iter().enumerate() {
                for x in 0..w {
                    let r = |j: u64| hash01(7, (k * w + x) as u64, j, open.to_bits() as u64);
                    let now = [x as f64 + 0.5, y as f64 + 0.5];
                    let angle = std::f64::consts::TAU * r(0);
                    let (v, a) = match x % 4 {
                        // |v| at the threshold within a part in 1e5: h·|v| ≈ STILL.
                        0 => (STILL / half * (1.0 + (r(1) - 0.5) * 2e-5), 0.0),
                        // A velocity and an acceleration, the threshold crossed both ways.
                        1 => (0.6 * r(1) / half, 0.4 * r(2) / (half * half)),
                        _ => (0.0, 0.0),
                    };
                    let (c, s) = (angle.cos(), angle.sin());
                    let i = y * w + x;
                    let p = [now[0] - v * c + a * s, now[1] - v * s - a * c];
                    let n = [now[0] + v * c + a * s, now[1] + v * s - a * c];
                    let hostile = [f32::NAN, f32::INFINITY, -f32::INFINITY, 1e30, -1e30];
                    (prev.x[i], prev.y[i]) = (p[0] as f32, p[1] as f32);
                    (next.x[i], next.y[i]) = (n[0] as f32, n[1] as f32);
                    if x % 4 == 2 {
                        prev.x[i] = hostile[(x / 4) % hostile.len()];
                        next.y[i] = hostile[(x / 8) % hostile.len()];
                    }
                }
            }
            let color = Color::empty();
            let job = Scatter::new(config, &color, &[], &prev, &next);
            for &y in &rows {
                let mut out = vec![false; w];
                job.moving_row(y, &mut out);
                for (x, &moves) in out.iter().enumerate() {
                    let want = job.motion(x, y).is_some();
                    assert_eq!(moves, want, "({x}, {y}), shutter {open} {offset}");
                    let extent = job.extent(
                        [prev.x[y * w + x] as f64, prev.y[y * w + x] as f64],
                        [x as f64 + 0.5, y as f64 + 0.5],
                        [next.x[y * w + x] as f64, next.y[y * w + x] as f64],
                    );
                    near += ((extent - STILL).abs() < 1e-4) as usize;
                }
            }
        }
        // The cases at the threshold are there.
        assert!(near > 1000, "{near}");
    }
}
