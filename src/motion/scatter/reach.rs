//! Stage 1, `reach`: for each block of pixels, how far its curves can deposit, each pixel's
//! own reach ([`Scatter::reach`]: a cheap bound from the three positions where it holds, else
//! the farthest point of the curve as `accumulate` builds it, as the GPU twin's `count_curve`
//! takes it), and each block's deepest and nearest depths (so `resolve` can skip a search
//! behind a pixel and the walk over its unseen part). A frame whose `most` is 0 does not move.

use rayon::prelude::*;

use super::config::{CurveKind, BLOCK};
use super::job::{Moving, Scatter};
use super::path::Path;
use crate::motion::curve::Arc;

/// For each BLOCK×BLOCK block of pixels, how far from its pixels their curves can deposit
/// (0 where none moves): lets a tile find the pixels whose curves can reach it.
pub(super) struct Reach {
    pub(super) across: usize,
    pub(super) down: usize,
    /// Per pixel (0 where still, negative at a fringe pixel: its partner's), so tiles test
    /// it without rebuilding the motion.
    pub(super) pixel: Vec<f32>,
    pub(super) block: Vec<f32>,
    pub(super) most: f32,
    /// The deepest depth in each block.
    pub(super) deepest: Vec<f32>,
    /// The nearest depth in each block (NaN never lowers it: a NaN depth is never nearer).
    pub(super) nearest: Vec<f32>,
}

impl Reach {
    pub(super) fn of(job: &Scatter) -> Reach {
        let (width, height) = (job.width, job.height);
        let (across, down) = (width.div_ceil(BLOCK), height.div_ceil(BLOCK));
        let mut pixel = vec![0.0f32; width * height];
        let mut block = vec![0.0f32; across * down];
        let mut deepest = vec![0.0f32; across * down];
        let mut nearest = vec![f32::INFINITY; across * down];
        // One row of blocks at a time: its pixels' reach (rounded up with a margin, so the f32
        // never falls short of the f64), then its blocks' largest reach, deepest and nearest
        // depths.
        pixel
            .par_chunks_mut(BLOCK * width.max(1))
            .zip(block.par_chunks_mut(across.max(1)))
            .zip(deepest.par_chunks_mut(across.max(1)))
            .zip(nearest.par_chunks_mut(across.max(1)))
            .enumerate()
            .for_each(|(by, (((pixel, block), deepest), nearest))| {
                let y0 = by * BLOCK;
                // Where a curve must be built to know its reach.
                let mut path = Path::new();
                // Which pixels move: the fringe's answer where it looked, else the test.
                let known = job.fringe.moving.len() == width * height;
                let mut tested = vec![false; if known { 0 } else { width }];
                for (y, row) in (y0..).zip(pixel.chunks_mut(width)) {
                    let moves = if known {
                        &job.fringe.moving[y * width..(y + 1) * width]
                    } else {
                        job.moving_row(y, &mut tested);
                        &tested[..]
                    };
                    for (x, r) in row.iter_mut().enumerate().filter(|&(x, _)| moves[x]) {
                        *r = job.moving(x, y).map_or(0.0, |(motion, extent)| {
                            stored(job.reach(y * width + x, &motion, extent, &mut path))
                        });
                    }
                }
                // A fringe pixel's curve is its partner's motion (which moves) from its own
                // centre, as `accumulate` draws it: marked negative.
                let rows = y0 * width..((y0 + BLOCK) * width).min(width * height);
                for k in job.fringe.within(rows) {
                    let (i, m) = (
                        job.fringe.pixels[k] as usize,
                        job.fringe.partners[k] as usize,
                    );
                    let reach = job.moving(m % width, m / width).map_or(0.0, |(_, extent)| {
                        let motion = job.fringe_positions(i % width, i / width, m);
                        job.reach(m, &motion, extent, &mut path)
                    });
                    pixel[i - y0 * width] = -stored(reach);
                }
                let blocks = block.iter_mut().zip(deepest).zip(nearest);
                for (bx, ((most, deepest), nearest)) in blocks.enumerate() {
                    for y in 0..BLOCK.min(height - y0) {
                        let row = y * width + bx * BLOCK..y * width + ((bx + 1) * BLOCK).min(width);
                        *most = pixel[row.clone()]
                            .iter()
                            .fold(*most, |m, &r| m.max(r.abs()));
                        let depth = &job.depth[y0 * width + row.start..y0 * width + row.end];
                        *deepest = depth.iter().fold(*deepest, |d, &z| d.max(z));
                        *nearest = depth.iter().fold(*nearest, |d, &z| d.min(z));
                    }
                }
            });
        let most = block.iter().copied().fold(0.0, f32::max);
        Reach {
            across,
            down,
            pixel,
            block,
            most,
            deepest,
            nearest,
        }
    }
}

/// A reach as stored (f32), a hundredth of a pixel over it, and never under it: past 2¹⁷ px
/// (a huge `--max-curve`) an f32's rounding to the nearest exceeds the hundredth.
fn stored(reach: f64) -> f32 {
    let r = (reach + 0.01) as f32;
    if (r as f64) < reach {
        r.next_up()
    } else {
        r
    }
}

impl Scatter<'_> {
    /// How far from p(0) (`motion.now`) the curve of `motion` (pixel `i`'s colour) can
    /// deposit: its farthest point, and the pixel beside it that a column's coverage is split
    /// into. `extent` is the parabola's bound ([`Scatter::extent`]): the Bézier's curve stays
    /// within it, and the scaling to `max_curve` about p(0) only brings it nearer, so where it
    /// is within `max_curve` it is taken as it is, no curve built. Elsewhere the curve is built
    /// as `accumulate` builds it ([`Scatter::path`]) and its farthest point taken
    /// ([`Path::farthest`]), as the GPU twin's `count_curve` does: an arc strays beyond the
    /// parabola through the same three positions (turning past its circle's far side, up to
    /// twice its radius from p(0)), and a curve scaled to `max_curve` about p(0) may end
    /// farther than `max_curve` from it (its chords need not pass through p(0)).
    pub(super) fn reach(&self, i: usize, motion: &Moving, extent: f64, path: &mut Path) -> f64 {
        let longest = self.config.max_curve as f64;
        if self.config.curve() == CurveKind::Bezier && extent <= longest {
            return extent + 1.0;
        }
        // An arc's farthest point has a closed form (`Arc::farthest`), which bounds the
        // built curve's (its points lie on the arc, scaled about p(0) at most); a millionth
        // of a pixel a pixel of radius for the rounding of the built points.
        if self.config.curve() == CurveKind::Arc {
            if let Some(arc) = Arc::fit(motion.prev, motion.now, motion.next) {
                let far = arc.farthest(self.t0, self.t1);
                if far.is_finite() {
                    return far + 1.0 + 1e-6 * (1.0 + arc.radius);
                }
            }
        }
        if self.path(i, motion, path, None) {
            path.farthest(motion.now) + 1.0
        } else {
            // No curve to draw: `accumulate` draws nothing either.
            extent.min(longest) + 1.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{Color, Positions};
    use crate::motion::scatter::config::{TILE_H, TILE_W};
    use crate::motion::scatter::fringe::fringe;
    use crate::motion::scatter::{CurveKind, Normalize, ScatterConfig, ScatterParams};
    use crate::motion::shutter::Shutter;

    /// A stored reach is never under the reach: rounding to f32 past 2¹⁷ px loses more than
    /// the hundredth it is given (2¹⁸ + 0.005 went in as 2¹⁸, 10⁷ + 0.3 as 10⁷).
    #[test]
    fn a_stored_reach_is_never_under_the_reach() {
        for reach in [
            0.5,
            17.25,
            131_071.99,
            262_144.005,
            1e7 + 0.3,
            3.0e9 + 100.7,
        ] {
            let r = stored(reach);
            assert!(r as f64 >= reach, "{reach} stored as {r}");
            assert!(
                (r as f64) <= reach + 0.01 + 1e-7 * reach,
                "{reach} stored as {r}"
            );
        }
    }

    /// A 300×150 frame (four tiles) of grey at depth 10 with a 6×6 red square at depth 1 at
    /// (`left`, 60), the column left of it holding 0.3 of the red (a silhouette's sliver, for
    /// the fringe), each of the square's pixels at p(0) + `offset(t)` at t = ∓1.
    fn frame(
        left: usize,
        offset: impl Fn(f64) -> [f64; 2],
    ) -> (Color, Vec<f32>, Positions, Positions) {
        let (w, h) = (300usize, 150usize);
        let n = w * h;
        let inside = |x: usize, y: usize| (left..left + 6).contains(&x) && (60..66).contains(&y);
        let mut color = Color {
            r: vec![0.5; n],
            g: vec![0.5; n],
            b: vec![0.5; n],
            a: None,
        };
        let depth = (0..n)
            .map(|i| if inside(i % w, i / w) { 1.0 } else { 10.0 })
            .collect();
        let centre = |i: usize| [(i % w) as f64 + 0.5, (i / w) as f64 + 0.5];
        let mut prev = Positions {
            x: (0..n).map(|i| centre(i)[0] as f32).collect(),
            y: (0..n).map(|i| centre(i)[1] as f32).collect(),
            z: None,
        };
        let mut next = prev.clone();
        for i in 0..n {
            let (x, y) = (i % w, i / w);
            if inside(x, y) {
                (color.r[i], color.g[i], color.b[i]) = (4.0, 0.0, 0.0);
                let (p, q, c) = (offset(-1.0), offset(1.0), centre(i));
                (prev.x[i], prev.y[i]) = ((c[0] + p[0]) as f32, (c[1] + p[1]) as f32);
                (next.x[i], next.y[i]) = ((c[0] + q[0]) as f32, (c[1] + q[1]) as f32);
            } else if inside(x + 1, y) {
                (color.r[i], color.g[i], color.b[i]) = (0.3 * 4.0 + 0.7 * 0.5, 0.35, 0.35);
            }
        }
        (color, depth, prev, next)
    }

    /// Every tile of the frame as `stages` runs it, with `reach`: the output's bits.
    fn tiles(job: &Scatter, reach: &Reach) -> Vec<u32> {
        let (w, h) = (job.width, job.height);
        let mut planes: [Vec<f32>; 4] = std::array::from_fn(|_| vec![f32::NAN; w * h]);
        for ty0 in (0..h).step_by(TILE_H) {
            for tx0 in (0..w).step_by(TILE_W) {
                let rect = [tx0, ty0, (tx0 + TILE_W).min(w), (ty0 + TILE_H).min(h)];
                let mut pieces: Vec<[Vec<f32>; 4]> = (rect[1]..rect[3])
                    .map(|_| std::array::from_fn(|_| vec![0.0; rect[2] - rect[0]]))
                    .collect();
                let mut rows: Vec<[&mut [f32]; 4]> = pieces
                    .iter_mut()
                    .map(|[r, g, b, a]| [&mut r[..], &mut g[..], &mut b[..], &mut a[..]])
                    .collect();
                let mut carried: Vec<Vec<&mut [f32]>> =
                    (rect[1]..rect[3]).map(|_| Vec::new()).collect();
                job.tile::<5>(reach, rect, &mut rows, &mut carried);
                for (y, piece) in (rect[1]..).zip(&pieces) {
                    for (plane, from) in planes.iter_mut().zip(piece) {
                        plane[y * w + rect[0]..y * w + rect[2]].copy_from_slice(from);
                    }
                }
            }
        }
        planes.iter().flatten().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn no_curve_deposits_beyond_its_reach() {
        // Each moving pixel's reach against a reach so large that every tile draws every
        // curve: where the reach bounds where a curve deposits, the two give the same bits.
        // An arc whose angle runs from −20° through 0° (at the frame) to 300° about its
        // centre (R = 30 px), p(0) 41 px left of the next tile: opening at the frame, past
        // its circle's far side, 60 px from p(0); centred, to 295°, 51 px from it; where the
        // parabola's bound on the same three positions is about R, or R/3. And a parabola
        // going out and back (p(±1) 100 px ahead of p(0)) cut to one segment and 10 px, the
        // shutter off centre, 12 px left of the next tile: its one chord, scaled about p(0),
        // ends 12.25 px from it, past `max_curve`.
        let r = 30.0;
        let on_circle = |degrees: f64| {
            let a = (180.0 + degrees).to_radians();
            [r + r * a.cos(), r * a.sin()]
        };
        let arc = |t: f64| on_circle(if t < 0.0 { -20.0 } else { 300.0 });
        let out_and_back = |_: f64| [100.0, 0.0];
        let arcs = ScatterParams {
            curve: CurveKind::Arc,
            max_curve: 2000.0,
            ..ScatterParams::default()
        };
        let chord = ScatterParams {
            segments: 1,
            max_curve: 10.0,
            ..ScatterParams::default()
        };
        let start = Shutter {
            open: 1.0,
            offset: 0.5,
        };
        type Case<'a> = (
            &'a str,
            usize,
            &'a dyn Fn(f64) -> [f64; 2],
            ScatterParams,
            Shutter,
        );
        let cases: [Case; 3] = [
            ("arc, opening at the frame", 215, &arc, arcs, start),
            ("arc, centred", 215, &arc, arcs, Shutter::centred(1.0)),
            (
                "chord cut short",
                244,
                &out_and_back,
                chord,
                Shutter {
                    open: 1.0,
                    offset: 0.2,
                },
            ),
        ];
        let mut wrong = Vec::new();
        for (what, left, offset, params, shutter) in cases {
            for normalize in [Normalize::Paper, Normalize::Exposure] {
                let params = ScatterParams {
                    normalize,
                    ..params
                };
                let (mut color, depth, prev, next) = frame(left, offset);
                let config = ScatterConfig::new(300, 150, &params, shutter);
                let found = fringe(&config, &mut color, &mut [], &depth, [&prev, &next]);
                assert_eq!(found.is_empty(), normalize == Normalize::Paper, "{what}");
                let mut job = Scatter::new(config, &color, &depth, &prev, &next);
                job.fringe = &found;
                let reach = Reach::of(&job);
                let mut everywhere = Reach::of(&job);
                for r in everywhere.pixel.iter_mut().chain(&mut everywhere.block) {
                    if *r != 0.0 {
                        *r = 1e6f32.copysign(*r);
                    }
                }
                everywhere.most = 1e6;
                let (got, want) = (tiles(&job, &reach), tiles(&job, &everywhere));
                let differ = got.iter().zip(&want).filter(|(a, b)| a != b).count();
                // The curves do deposit across the tile: the comparison is not of nothing.
                let lit = (0..300 * 150)
                    .filter(|&i| i % 300 >= 256 && f32::from_bits(want[i]) != 0.5)
                    .count();
                assert!(
                    lit > 0,
                    "{what}, {normalize:?}: nothing reaches the next tile"
                );
                if differ > 0 {
                    wrong.push(format!("{what}, {normalize:?}: {differ} values differ"));
                }
            }
        }
        assert!(wrong.is_empty(), "{wrong:#?}");
    }
}
