//! reconstruct's pack stage: each pixel of the tiles a gather will read, as one texel — its
//! colour, depth made finite and motion, packed so a tap reads one cache line. Pixels of
//! other tiles are never read: their texels stay zero in a zero-allocated buffer, whose
//! untouched pages cost nothing.
//!
//! In: the config, colour, depth, velocity and the tiles. Out: [`Texel`]s (paper and dual) or
//! [`Texel2014`]s (the 2014 variants). Runs on the CPU for every backend; the GPU's gather
//! reads what it packs.

use rayon::prelude::*;

use super::config::{
    finite_depth, reach_factor, spread_2014, spread_length, ReconstructConfig, Texel, Texel2014,
};
use super::tiles::{near_blur, TileMask};
use crate::frame::{Color, Velocity};
use crate::motion::tile_max::TileGrid;

/// Stage 3: each pixel of the tiles that blur and their neighbours (taps reach at most k px,
/// one tile) packed as a [`Texel`]: colour, depth made finite, and 1/|V|. The buffer is
/// zero-allocated, so untouched pages cost nothing.
pub fn pack(
    config: &ReconstructConfig,
    color: &Color,
    depth: &[f32],
    velocity: &Velocity,
    neighbors: &TileGrid,
) -> Vec<Texel> {
    pack_tiles(
        config,
        neighbors.columns,
        [0.0; 6],
        |c, row| near_blur(neighbors, c, row, reach_factor(config).ceil() as usize),
        |i| {
            let length = spread_length(velocity.x[i], velocity.y[i], config.shutter, config.k);
            [
                color.r[i],
                color.g[i],
                color.b[i],
                color.a.as_ref().map_or(1.0, |a| a[i]),
                finite_depth(depth[i]),
                // 1/|V|: infinite for a still pixel, whose cones and cylinders are then 0 at
                // any distance (it spreads nowhere).
                1.0 / length,
            ]
        },
    )
}

/// The 2014 filter's pack: pixels within two tiles of a blurring tile (a pixel gathers when
/// a tile of its 3×3 neighbourhood blurs, since its tile lookup is jittered by up to a
/// quarter tile; its taps reach at most k = one tile further).
pub fn pack_2014(
    config: &ReconstructConfig,
    color: &Color,
    depth: &[f32],
    velocity: &Velocity,
    tiles: &TileGrid,
    packed: &TileMask,
) -> Vec<Texel2014> {
    pack_tiles(
        config,
        tiles.columns,
        [0.0; 8],
        |c, row| packed.get(c, row),
        |i| {
            let v = spread_2014(velocity.x[i], velocity.y[i], config);
            [
                color.r[i],
                color.g[i],
                color.b[i],
                color.a.as_ref().map_or(1.0, |a| a[i]),
                finite_depth(depth[i]),
                v.0,
                v.1,
                (v.0 * v.0 + v.1 * v.1).sqrt(),
            ]
        },
    )
}

/// The texel `texel(i)` of every pixel of the tiles `selected(column, row)` picks, in a
/// buffer of `zero`s elsewhere; zero-allocated, so untouched pages cost nothing.
pub(crate) fn pack_tiles<T: Copy + Send + Sync>(
    config: &ReconstructConfig,
    columns: usize,
    zero: T,
    selected: impl Fn(usize, usize) -> bool + Sync,
    texel: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    let width = config.width as usize;
    let size = config.tile as usize;
    let mut texels = vec![zero; width * config.height as usize];
    texels
        .par_chunks_mut(size * width)
        .enumerate()
        .for_each(|(row, chunk)| {
            for c in (0..columns).filter(|&c| selected(c, row)) {
                for local_y in 0..chunk.len() / width {
                    let y = row * size + local_y;
                    for x in c * size..((c + 1) * size).min(width) {
                        chunk[local_y * width + x] = texel(y * width + x);
                    }
                }
            }
        });
    texels
}
