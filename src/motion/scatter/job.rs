//! One frame's scatter as its stages see it ([`Scatter`]): the input buffers, the config and
//! the exposure, with each pixel's motion (its three positions and how far its curve can
//! reach) and the weight along a curve. [`super::reach`], [`super::accumulate`] and
//! [`super::resolve`] add the stages' own methods.

use super::config::{ScatterConfig, Weight, STILL};
use crate::frame::{Color, Positions};
use crate::motion::curve::{length, Point};
use crate::motion::shutter::Shutter;

/// A moving pixel's three positions, and how far from p(0) its curve can deposit.
#[derive(Clone, Copy)]
pub(super) struct Moving {
    pub(super) prev: Point,
    pub(super) now: Point,
    pub(super) next: Point,
    pub(super) reach: f64,
}

/// The still pixels at a silhouette (what the `fringe` stage finds), in index order, each
/// with its moving partner and the partner's coverage of it.
#[derive(Default, Debug, Clone, PartialEq)]
pub struct Fringe {
    pub pixels: Vec<u32>,
    pub partners: Vec<u32>,
    pub cover: Vec<f32>,
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
        let i = y * self.width + x;
        let now = [x as f64 + 0.5, y as f64 + 0.5];
        let prev = [self.prev.x[i] as f64, self.prev.y[i] as f64];
        let next = [self.next.x[i] as f64, self.next.y[i] as f64];
        let extent = self.extent(prev, now, next);
        (extent >= STILL).then_some(Moving {
            prev,
            now,
            next,
            // What the scaling to max_curve leaves, and the pixel a segment reaches beside it.
            reach: extent.min(self.config.max_curve as f64) + 1.0,
        })
    }

    /// The positions of a pixel known to move, with its reach `r` from the reach pass
    /// (skips [`Scatter::motion`]'s bound).
    #[inline]
    pub(super) fn positions(&self, x: usize, y: usize, reach: f64) -> Moving {
        let i = y * self.width + x;
        Moving {
            prev: [self.prev.x[i] as f64, self.prev.y[i] as f64],
            now: [x as f64 + 0.5, y as f64 + 0.5],
            next: [self.next.x[i] as f64, self.next.y[i] as f64],
            reach,
        }
    }

    /// A bound on how far the curve strays from p(0) during the exposure: with
    /// p(t) = p0 + t·v + t²·a, at most h·|v| + h²·|a| for |t| ≤ h (h = `half`, the farthest
    /// the exposure gets from the frame).
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
    /// centre (the same motion, so the same reach).
    #[inline]
    pub(super) fn fringe_positions(&self, x: usize, y: usize, m: usize, reach: f64) -> Moving {
        let (mx, my) = ((m % self.width) as f64, (m / self.width) as f64);
        let d = [x as f64 - mx, y as f64 - my];
        Moving {
            prev: [self.prev.x[m] as f64 + d[0], self.prev.y[m] as f64 + d[1]],
            now: [x as f64 + 0.5, y as f64 + 0.5],
            next: [self.next.x[m] as f64 + d[0], self.next.y[m] as f64 + d[1]],
            reach,
        }
    }
}
