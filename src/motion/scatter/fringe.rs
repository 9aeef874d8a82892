//! Stage 0, `fringe`: the still pixels at a moving surface's silhouette, split by reconstruct's
//! matte ([`crate::motion::reconstruct::matte`]) into the still surface they show and the
//! moving surface's share of them, which is drawn as a curve of its own.
//!
//! A rendered pixel is an area. Where a moving surface's edge crosses a still pixel, its
//! colour holds a sliver of the surface (its coverage α, at the frame's instant) beside the
//! still surface behind; its depth and motion, sampled at the pixel's centre, say "still".
//! Kept whole, that pixel shows its own colour for the share of the exposure no curve
//! covers, so the sliver stays put while the surface's own curves bring the surface over the
//! pixel again: the fringe is counted twice and does not move (at the trailing edge of
//! `sparse`'s disc, a still pixel came out 0.334 where the exposure gives 0.177). Here each
//! such pixel takes its still surface's colour (the matte's unmixing, `c + e·(c − f)`, as
//! [`matte::surfaces_of`] gives it), and the sliver becomes a curve: the pixel's moving
//! partner's colour and motion, drawn from the pixel's own centre, depth-tested as the
//! partner, its weights times α. So the sliver moves with its surface, and what the pixel
//! shows for the rest of the exposure is the surface behind it.
//!
//! Light layers (issue 29) are unmixed with the beauty's factors and their slivers drawn with
//! the beauty's curves (a sliver's colour is its partner's, in every layer), so layers that
//! add up to the beauty still do.
//!
//! The matte is fitted only in the tiles with moving and still pixels in their 3×3 tiles (a
//! silhouette and every pixel its fit reads lie there), reading the frame's own buffers in
//! place ([`Texels`]: nothing is packed), so a frame with no silhouette, or a pan where
//! everything moves, costs a motion test a pixel, and that test is `reach`'s too (handed on
//! in [`Fringe::moving`]). A pixel's still partner must be pure (its 3×3 all still,
//! [`Fallback::PureStill`]): it is the colour the pixel is unmixed towards, and a still pixel
//! beside a moving one holds a sliver itself; on a frame of noise, where almost no pixel is
//! pure, the stage then fits almost nothing. Only under the exposure normalisation (the
//! default): the paper's eq. 4 is kept as the paper has it.
//!
//! Measured in BENCHMARKS.md ("scatter: the fringe's own curves").

use rayon::prelude::*;

use super::config::{Normalize, ScatterConfig};
use super::job::{Fringe, Scatter};
use crate::frame::{Color, Positions};
use crate::motion::reconstruct::config::{finite_depth, Texel2014};
use crate::motion::reconstruct::matte::{self, Fallback, Matte, Texels};
use crate::motion::reconstruct::{ReconstructConfig, ReconstructParams};

/// Finds the fringe of the frame and unmixes its pixels' colour in place: the beauty's and
/// every carried layer's R, G and B (`layers`).
pub fn fringe(
    config: &ScatterConfig,
    color: &mut Color,
    layers: &mut [Color],
    depth: &[f32],
    [prev, next]: [&Positions; 2],
) -> Fringe {
    if config.normalize() != Normalize::Exposure {
        return Fringe::default();
    }
    let (found, moving) = {
        let job = Scatter::new(*config, color, depth, prev, next);
        find(&job)
    };
    let mut fringe = Fringe {
        moving,
        ..Fringe::default()
    };
    let mut factors = Vec::new();
    for (i, m) in found {
        if m[0] <= 0.0 {
            continue;
        }
        fringe.pixels.push(i as u32);
        fringe.partners.push(m[1].to_bits());
        fringe.cover.push(m[0]);
        factors.push([m[3], m[4], m[5], m[6]]);
    }
    // The still surface: c + e·(c − f), channel by channel, as matte::surfaces_of gives it;
    // a layer's R, G and B take the beauty's factors (its alpha is the beauty's).
    let mut planes: Vec<(&mut Vec<f32>, usize)> =
        vec![(&mut color.r, 0), (&mut color.g, 1), (&mut color.b, 2)];
    planes.extend(color.a.as_mut().map(|a| (a, 3)));
    for layer in layers.iter_mut() {
        planes.extend([(&mut layer.r, 0), (&mut layer.g, 1), (&mut layer.b, 2)]);
    }
    for (plane, ch) in planes {
        for ((&i, &f), e) in fringe.pixels.iter().zip(&fringe.partners).zip(&factors) {
            let (c, f) = (plane[i as usize], plane[f as usize]);
            plane[i as usize] = c + e[ch] * (c - f);
        }
    }
    fringe
}

/// The pairs of the frame's still pixels at a silhouette (reconstruct's matte, fitted with
/// scatter's motion test).
fn find(job: &Scatter) -> (Vec<(usize, Matte)>, Vec<bool>) {
    let (width, height) = (job.width, job.height);
    let params = ReconstructParams::default();
    let config = ReconstructConfig::new(width, height, &params, 1.0, 0);
    let size = config.tile as usize;
    let (columns, rows) = (width.div_ceil(size), height.div_ceil(size));
    // Which pixels move (scatter's test, once), and which tiles hold moving pixels (bit 1)
    // and still ones (bit 2), a row of tiles at a time.
    let mut moves = vec![false; width * height];
    let mut kinds = vec![0u8; columns * rows];
    moves
        .par_chunks_mut((size * width).max(1))
        .zip(kinds.par_chunks_mut(columns.max(1)))
        .enumerate()
        .for_each(|(row, (moves, kinds))| {
            for (y, line) in (row * size..).zip(moves.chunks_mut(width)) {
                job.moving_row(y, line);
                for (kind, pixels) in kinds.iter_mut().zip(line.chunks(size)) {
                    let (any, all) = pixels
                        .iter()
                        .fold((false, true), |(a, l), &m| (a | m, l & m));
                    *kind |= any as u8 | (2 * !all as u8);
                }
            }
        });
    // A tile whose 3×3 tiles hold both kinds.
    let mut selected = vec![false; columns * rows];
    for row in 0..rows {
        for c in 0..columns {
            let mut both = 0;
            for r in row.saturating_sub(1)..(row + 2).min(rows) {
                for k in c.saturating_sub(1)..(c + 2).min(columns) {
                    both |= kinds[r * columns + k];
                }
            }
            selected[row * columns + c] = both == 3;
        }
    }
    if !selected.contains(&true) {
        return (Vec::new(), moves);
    }
    let selected = |c: usize, row: usize| selected[row * columns + c];
    // Still pixels only: a moving one's sliver of what is behind it is drawn with it.
    let texels = Pixels { job, moves: &moves };
    let pairs = matte::pairs(
        &config,
        &texels,
        selected,
        |i| !moves[i],
        Fallback::PureStill,
    );
    (pairs, moves)
}

/// The frame as the matte reads it, in place: colour, depth, and a length that says whether
/// the pixel moves (scatter's test, found once).
struct Pixels<'a> {
    job: &'a Scatter<'a>,
    moves: &'a [bool],
}

impl Texels for Pixels<'_> {
    #[inline(always)]
    fn texel(&self, i: usize) -> Texel2014 {
        let c = self.job.color(i);
        let length = self.moves[i] as u32 as f32;
        let depth = finite_depth(self.job.depth[i]);
        [c[0], c[1], c[2], c[3], depth, 0.0, 0.0, length]
    }

    #[inline(always)]
    fn depth(&self, i: usize) -> f32 {
        finite_depth(self.job.depth[i])
    }

    #[inline(always)]
    fn moves(&self, i: usize) -> bool {
        self.moves[i]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::scatter::ScatterParams;

    /// A 24×12 frame over a still grey background (depth 10); `moves(x)` says which columns
    /// move (depth 1, 3 px a frame to the right), in red, and `sliver(x)` how much of the red
    /// a still column holds.
    fn columns(moves: impl Fn(usize) -> bool, sliver: impl Fn(usize) -> f32) -> Fringe {
        let (w, h) = (24usize, 12usize);
        let n = w * h;
        let (mut r, mut g, mut depth) = (vec![0.0f32; n], vec![0.0f32; n], vec![10.0f32; n]);
        let mut prev = Positions {
            x: vec![0.0; n],
            y: vec![0.0; n],
            z: None,
        };
        let mut next = prev.clone();
        for i in 0..n {
            let (x, y) = (i % w, i / w);
            let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
            let a = if moves(x) { 1.0 } else { sliver(x) };
            (r[i], g[i]) = (a + (1.0 - a) * 0.5, (1.0 - a) * 0.5);
            let shift = if moves(x) { 3.0 } else { 0.0 };
            if moves(x) {
                depth[i] = 1.0;
            }
            (prev.x[i], prev.y[i]) = (cx - shift, cy);
            (next.x[i], next.y[i]) = (cx + shift, cy);
        }
        let b = g.clone();
        let mut color = Color { r, g, b, a: None };
        let config = ScatterConfig::new(w, h, &ScatterParams::default(), 0.5);
        fringe(&config, &mut color, &mut [], &depth, [&prev, &next])
    }

    #[test]
    fn a_strand_two_pixels_wide_has_a_fringe() {
        // Columns 10 and 11 move: no moving pixel's 3×3 is all moving, so the partner is
        // taken from those mixed ones (a tooth, a strand); column 9 holds 0.3 of the strand.
        let found = columns(|x| x == 10 || x == 11, |x| if x == 9 { 0.3 } else { 0.0 });
        let at_9: Vec<usize> = (0..found.pixels.len())
            .filter(|&k| found.pixels[k] as usize % 24 == 9)
            .collect();
        // Every row of column 9 but the frame's first and last (whose 5×5 is cut).
        assert!(at_9.len() >= 10, "{:?}", found.pixels);
        for k in at_9 {
            let partner = found.partners[k] as usize % 24;
            assert!(partner == 10 || partner == 11, "{partner}");
            assert!((found.cover[k] - 0.3).abs() < 1e-4, "{}", found.cover[k]);
        }
    }

    #[test]
    fn no_fringe_without_a_clean_still_pixel_near() {
        // Every other column moves: no still pixel's 3×3 is all still, so no still pixel has
        // a colour of its own surface to be unmixed towards (on a frame of noise, almost
        // every pixel), though the still columns hold 0.3 of the red.
        let found = columns(|x| x % 2 == 1, |_| 0.3);
        assert!(found.is_empty(), "{:?}", found.pixels);
        // Beside a clean background (columns 0..=9 still and clean), the same stripes have a
        // fringe where a pure still pixel is within two: column 10, and its coverage. (With
        // any still pixel as a partner, column 10's still neighbours, holding the same
        // sliver, explain its colour exactly with no coverage at all, and it has none.)
        let found = columns(
            |x| x >= 10 && x % 2 == 1,
            |x| if x >= 10 { 0.3 } else { 0.0 },
        );
        assert!(found.pixels.len() >= 10, "{:?}", found.pixels);
        for (&p, &cover) in found.pixels.iter().zip(&found.cover) {
            assert_eq!(p as usize % 24, 10);
            assert!((cover - 0.3).abs() < 1e-4, "{cover}");
        }
    }
}
