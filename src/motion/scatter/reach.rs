//! Stage 1, `reach`: for each block of pixels, how far its curves can deposit (a cheap bound
//! from the three positions; no curve is built), each pixel's own bound, and each block's
//! deepest and nearest depths (so `resolve` can skip a search behind a pixel and the walk
//! over its unseen part). A frame whose `most` is 0 does not move.

use rayon::prelude::*;

use super::config::BLOCK;
use super::job::Scatter;

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
                        *r = job.motion(x, y).map_or(0.0, |m| (m.reach + 0.01) as f32);
                    }
                }
                // A fringe pixel reaches as far as its partner, which moves: marked negative.
                let rows = y0 * width..((y0 + BLOCK) * width).min(width * height);
                for k in job.fringe.within(rows) {
                    let (i, m) = (
                        job.fringe.pixels[k] as usize,
                        job.fringe.partners[k] as usize,
                    );
                    let reach = job.motion(m % width, m / width).map_or(0.0, |m| m.reach);
                    pixel[i - y0 * width] = -((reach + 0.01) as f32);
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
