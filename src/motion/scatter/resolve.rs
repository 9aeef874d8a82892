//! Stage 3, `resolve`: each pixel's output from its accumulated cell, by the normalisation
//! (the paper's eq. 4, or the exposure shares with the uncovered rest filled from behind).

use crate::motion::curve::length;

use super::config::{Normalize, BLOCK, COVERED};
use super::job::{Moving, Scatter};
use super::reach::Reach;

impl Scatter<'_> {
    /// The output of pixel `i` from its accumulated `cell`.
    pub(super) fn resolve(&self, cell: &[f64; 5], x: usize, y: usize, reach: &Reach) -> [f32; 4] {
        let i = y * self.width + x;
        let own = self.color(i);
        let total = cell[4];
        if total.is_nan() || total <= 0.0 {
            return own;
        }
        if self.config.normalize() == Normalize::Paper {
            // The paper's eq. 4 (w_b is at least 0).
            let wb = self.config.background_weight as f64;
            std::array::from_fn(|ch| ((cell[ch] + wb * own[ch] as f64) / (total + wb)) as f32)
        } else if total < 1.0 {
            let rest = 1.0 - total;
            let behind = if rest > COVERED {
                self.behind(x, y, reach)
            } else {
                own
            };
            std::array::from_fn(|ch| (cell[ch] + rest * behind[ch] as f64) as f32)
        } else {
            std::array::from_fn(|ch| (cell[ch] / total) as f32)
        }
    }

    /// The colour behind moving pixel `i`: the nearest farther surface along its motion
    /// (either way; the average if both), else its own colour.
    fn behind(&self, x: usize, y: usize, reach: &Reach) -> [f32; 4] {
        let i = y * self.width + x;
        let own = self.color(i);
        let Some(Moving {
            prev, now, next, ..
        }) = self.motion(x, y)
        else {
            return own;
        };
        let v = [next[0] - prev[0], next[1] - prev[1]];
        let l = length(v);
        if l.is_nan() || l <= 0.0 {
            return own;
        }
        let dir = [v[0] / l, v[1] / l];
        let limit = self.depth[i] * (1.0 + self.config.depth_tolerance);
        let steps = (self
            .extent(prev, now, next)
            .min(self.config.max_curve as f64)
            + 2.0)
            .ceil() as usize;
        // Nothing farther within the search: its blocks' deepest depth tells without a walk.
        let (x, y) = (now[0] as usize, now[1] as usize);
        let (bx0, by0) = (
            x.saturating_sub(steps) / BLOCK,
            y.saturating_sub(steps) / BLOCK,
        );
        let bx1 = ((x + steps) / BLOCK).min(reach.across - 1);
        let by1 = ((y + steps) / BLOCK).min(reach.down - 1);
        let deepest = |bx: usize, by: usize| reach.deepest[by * reach.across + bx];
        if (by0..=by1).all(|by| (bx0..=bx1).all(|bx| deepest(bx, by) <= limit)) {
            return own;
        }
        let mut sum = [0.0f64; 4];
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
                    for (s, c) in sum.iter_mut().zip(self.color(j)) {
                        *s += c as f64;
                    }
                    found += 1;
                    break;
                }
            }
        }
        if found == 0 {
            own
        } else {
            sum.map(|s| (s / found as f64) as f32)
        }
    }
}
