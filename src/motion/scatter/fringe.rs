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
//! silhouette and every pixel its fit reads lie there), so a frame with no silhouette, or a
//! pan where everything moves, costs a motion test a pixel. Only under the exposure
//! normalisation (the default): the paper's eq. 4 is kept as the paper has it.
//!
//! Measured in BENCHMARKS.md ("scatter: the fringe's own curves").

use rayon::prelude::*;

use super::config::{Normalize, ScatterConfig};
use super::job::{Fringe, Scatter};
use crate::frame::{Color, Positions};
use crate::motion::reconstruct::config::{finite_depth, Texel2014};
use crate::motion::reconstruct::matte::{self, Matte};
use crate::motion::reconstruct::pack::pack_tiles;
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
    let found = {
        let job = Scatter::new(*config, color, depth, prev, next);
        find(&job)
    };
    let mut fringe = Fringe::default();
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
fn find(job: &Scatter) -> Vec<(usize, Matte)> {
    let (width, height) = (job.width, job.height);
    let params = ReconstructParams::default();
    let config = ReconstructConfig::new(width, height, &params, 1.0, 0);
    let size = config.tile as usize;
    let (columns, rows) = (width.div_ceil(size), height.div_ceil(size));
    // Which pixels move (scatter's test, once), and which tiles hold moving pixels (bit 1)
    // and still ones (bit 2).
    let mut moves = vec![false; width * height];
    moves
        .par_chunks_mut(width.max(1))
        .enumerate()
        .for_each(|(y, row)| {
            for (x, m) in row.iter_mut().enumerate() {
                *m = job.motion(x, y).is_some();
            }
        });
    let mut kinds = vec![0u8; columns * rows];
    kinds
        .par_chunks_mut(columns.max(1))
        .enumerate()
        .for_each(|(row, kinds)| {
            for y in row * size..((row + 1) * size).min(height) {
                for (x, &m) in moves[y * width..(y + 1) * width].iter().enumerate() {
                    kinds[x / size] |= if m { 1 } else { 2 };
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
        return Vec::new();
    }
    let selected = |c: usize, row: usize| selected[row * columns + c];
    let texels: Vec<Texel2014> = pack_tiles(&config, columns, [0.0; 8], selected, |i| {
        let c = job.color(i);
        // Depth, and a length that says whether it moves: all the matte reads beside colour.
        let length = moves[i] as u32 as f32;
        [
            c[0],
            c[1],
            c[2],
            c[3],
            finite_depth(job.depth[i]),
            0.0,
            0.0,
            length,
        ]
    });
    // Still pixels only: a moving one's sliver of what is behind it is drawn with it.
    matte::pairs(&config, &texels, selected, |i| !moves[i])
}
