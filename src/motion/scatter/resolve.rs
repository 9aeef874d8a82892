//! Stage 3, `resolve`: each pixel's output from its accumulated cell, by the normalisation
//! (the paper's eq. 4, or the exposure shares with the uncovered rest filled from behind).

use crate::motion::curve::{length, Point};

use super::config::{Normalize, BLOCK, COVERED};
use super::job::{Moving, Scatter};
use super::reach::Reach;

/// How a pixel's output is made from its cell, the same for every channel: found once per
/// pixel from the weight sum, then applied to the beauty's channels and to every carried one
/// ([`Scatter::channel`]), so light layers get exactly the beauty's weights.
pub(super) enum Resolution {
    /// No curve deposited: the input.
    Own,
    /// The paper's eq. 4, with the background weight `wb`.
    Paper { wb: f64, total: f64 },
    /// Covered for `total` < 1 of the exposure: the deposits, and what lies behind for the
    /// rest.
    Rest { rest: f64, behind: Behind },
    /// Covered at least once over: the deposits averaged.
    Mean { total: f64 },
}

/// What lies behind a pixel not wholly covered: its own colour, or the average of the pixels
/// found (the first farther pixel along its motion either way, or what `unseen` reads).
pub(super) enum Behind {
    Own,
    Found {
        pixels: [usize; BEHIND_PIXELS],
        count: usize,
    },
}

/// Points read on the frame's border for each side of a streak that runs off the frame,
/// spread evenly over the part past the edge (the clamped streak's mean; two left an HDR spot
/// on the edge column over-weighted: BENCHMARKS.md, "A still subject before a pan").
pub(super) const OFF_FRAME_TAPS: usize = 4;

/// The most pixels a [`Behind`] averages: the off-frame taps of both sides.
pub(super) const BEHIND_PIXELS: usize = 2 * OFF_FRAME_TAPS;

impl Scatter<'_> {
    /// The output of pixel (x, y) from its accumulated `cell`.
    #[cfg(test)]
    pub(super) fn resolve(&self, cell: &[f64; 5], x: usize, y: usize, reach: &Reach) -> [f32; 4] {
        let resolution = self.resolution(cell[4], x, y, reach);
        self.resolved(&resolution, cell, y * self.width + x)
    }

    /// The beauty's channels of pixel `i` by `resolution`, from its `cell`.
    pub(super) fn resolved(&self, resolution: &Resolution, cell: &[f64; 5], i: usize) -> [f32; 4] {
        let alpha = |j: usize| self.color.a.as_ref().map_or(1.0, |a| a[j]);
        [
            self.channel(resolution, cell[0], i, |j| self.color.r[j]),
            self.channel(resolution, cell[1], i, |j| self.color.g[j]),
            self.channel(resolution, cell[2], i, |j| self.color.b[j]),
            self.channel(resolution, cell[3], i, alpha),
        ]
    }

    /// How pixel (x, y), whose deposits weigh `total`, is resolved.
    pub(super) fn resolution(&self, total: f64, x: usize, y: usize, reach: &Reach) -> Resolution {
        if total.is_nan() || total <= 0.0 {
            Resolution::Own
        } else if self.config.normalize() == Normalize::Paper {
            // The paper's eq. 4 (w_b is at least 0).
            let wb = self.config.background_weight as f64;
            Resolution::Paper { wb, total }
        } else if total < 1.0 {
            let rest = 1.0 - total;
            let behind = if rest > COVERED {
                self.behind(x, y, reach)
            } else {
                Behind::Own
            };
            Resolution::Rest { rest, behind }
        } else {
            Resolution::Mean { total }
        }
    }

    /// One channel of pixel `i` resolved: `sum` its deposits, `plane` its input values.
    #[inline]
    pub(super) fn channel(
        &self,
        resolution: &Resolution,
        sum: f64,
        i: usize,
        plane: impl Fn(usize) -> f32,
    ) -> f32 {
        match *resolution {
            Resolution::Own => plane(i),
            Resolution::Paper { wb, total } => ((sum + wb * plane(i) as f64) / (total + wb)) as f32,
            Resolution::Rest { rest, ref behind } => {
                let behind = match *behind {
                    Behind::Own => plane(i),
                    Behind::Found { pixels, count } => {
                        let mut s = 0.0f64;
                        for &j in &pixels[..count] {
                            s += plane(j) as f64;
                        }
                        (s / count as f64) as f32
                    }
                };
                (sum + rest * behind as f64) as f32
            }
            Resolution::Mean { total } => (sum / total) as f32,
        }
    }

    /// What stands for the part of moving pixel i's streak that no curve brought, where
    /// nothing farther lies along its motion: walking along the motion (`dir`, unit) up to its
    /// half-length `q` either way, the part hidden behind a nearer surface on one side (the
    /// background streaming behind a still subject) is read a whole streak's length back on
    /// the other side, where it is visible (two pixels, at a quarter and three quarters of
    /// the slid span, that lie on the pixel's surface: within the depth tolerance); the part
    /// past the frame's edge, on one side or both (a corner), is read on the frame's border
    /// there (`OFF_FRAME_TAPS` of the streak's points on each such side, clamped to the frame,
    /// as reconstruct's taps read them). Else its own colour.
    /// Not at a pixel beside the nearer surface (its rim, whose colour holds part of it).
    /// Measured in BENCHMARKS.md ("A still subject before a pan"). `nearer`: whether any
    /// block the streak crosses holds a surface nearer than the pixel's (from [`Reach`]);
    /// where none does and both ends of the streak lie in the frame (which is convex, so
    /// every point does), the walk would find nothing and is skipped: the same output.
    fn unseen(&self, i: usize, now: Point, dir: Point, q: f64, nearer: bool) -> Behind {
        let tolerance = 1.0 + self.config.depth_tolerance;
        let (near, far) = (self.depth[i] / tolerance, self.depth[i] * tolerance);
        let at = |d: f64| -> Option<usize> {
            let x = now[0] + d * dir[0];
            let y = now[1] + d * dir[1];
            (x >= 0.0 && y >= 0.0 && x < self.width as f64 && y < self.height as f64)
                .then(|| y as usize * self.width + x as usize)
        };
        if !nearer && at(q.ceil()).is_some() && at(-q.ceil()).is_some() {
            return Behind::Own;
        }
        // Per side: where the streak goes behind a nearer surface, or off the frame.
        let mut hidden = [None; 2];
        let mut off = [None; 2];
        for (s, side) in [1.0, -1.0].into_iter().enumerate() {
            let mut k = 1.0;
            while k <= q.ceil() {
                match at(side * k) {
                    None => {
                        off[s] = Some((side, k - 0.5));
                        break;
                    }
                    Some(j) if self.depth[j] < near => {
                        hidden[s] = Some((side, k - 0.5));
                        break;
                    }
                    _ => {}
                }
                k += 1.0;
            }
        }
        let mut pixels = [0; BEHIND_PIXELS];
        let mut count = 0;
        match (hidden, off) {
            ([Some((side, b)), None] | [None, Some((side, b))], _) => {
                if b >= q || b < 1.0 {
                    return Behind::Own;
                }
                for f in [0.25, 0.75] {
                    if let Some(j) = at(-side * (q + (q - b) * f)) {
                        if (near..=far).contains(&self.depth[j]) {
                            pixels[count] = j;
                            count += 1;
                        }
                    }
                }
            }
            ([None, None], _) => {
                for (side, b) in off.into_iter().flatten() {
                    for t in 0..OFF_FRAME_TAPS {
                        let f = (t as f64 + 0.5) / OFF_FRAME_TAPS as f64;
                        let d = side * (b + (q - b) * f);
                        let x = (now[0] + d * dir[0]).clamp(0.0, self.width as f64 - 0.5);
                        let y = (now[1] + d * dir[1]).clamp(0.0, self.height as f64 - 0.5);
                        pixels[count] = y as usize * self.width + x as usize;
                        count += 1;
                    }
                }
            }
            _ => {}
        }
        if count == 0 {
            Behind::Own
        } else {
            Behind::Found { pixels, count }
        }
    }

    /// What lies behind moving pixel (x, y): the nearest farther surface along its motion
    /// (either way; the average if both), else its own colour.
    fn behind(&self, x: usize, y: usize, reach: &Reach) -> Behind {
        let i = y * self.width + x;
        let Some(Moving {
            prev, now, next, ..
        }) = self.motion(x, y)
        else {
            return Behind::Own;
        };
        let v = [next[0] - prev[0], next[1] - prev[1]];
        let l = length(v);
        if l.is_nan() || l <= 0.0 {
            return Behind::Own;
        }
        let dir = [v[0] / l, v[1] / l];
        let tolerance = 1.0 + self.config.depth_tolerance;
        let limit = self.depth[i] * tolerance;
        // How far the search looks either way: the streak's half-length along its motion as
        // the parabola gives it, as the GPU twin's behind.wgsl takes it (where to look for
        // what lies behind, not a bound on where the curve deposits: `Scatter::reach`).
        let q = self
            .extent(prev, now, next)
            .min(self.config.max_curve as f64);
        let steps = (q + 2.0).ceil() as usize;
        // Nothing farther within the search: its blocks' deepest depth tells without a walk
        // (and their nearest whether `unseen` need walk).
        let (x, y) = (now[0] as usize, now[1] as usize);
        let (bx0, by0) = (
            x.saturating_sub(steps) / BLOCK,
            y.saturating_sub(steps) / BLOCK,
        );
        let bx1 = ((x + steps) / BLOCK).min(reach.across - 1);
        let by1 = ((y + steps) / BLOCK).min(reach.down - 1);
        let deepest = |bx: usize, by: usize| reach.deepest[by * reach.across + bx];
        let near = self.depth[i] / tolerance;
        let nearer = || {
            (by0..=by1).any(|by| (bx0..=bx1).any(|bx| reach.nearest[by * reach.across + bx] < near))
        };
        if (by0..=by1).all(|by| (bx0..=bx1).all(|bx| deepest(bx, by) <= limit)) {
            return self.unseen(i, now, dir, q, nearer());
        }
        let mut pixels = [0; BEHIND_PIXELS];
        let mut found = 0;
        for side in [1.0, -1.0] {
            for k in 1..steps + 1 {
                let x = now[0] + side * k as f64 * dir[0];
                let y = now[1] + side * k as f64 * dir[1];
                if !(x >= 0.0 && y >= 0.0 && x < self.width as f64 && y < self.height as f64) {
                    break;
                }
                let j = y as usize * self.width + x as usize;
                if self.depth[j] > limit {
                    pixels[found] = j;
                    found += 1;
                    break;
                }
            }
        }
        if found == 0 {
            self.unseen(i, now, dir, q, nearer())
        } else {
            Behind::Found {
                pixels,
                count: found,
            }
        }
    }
}
