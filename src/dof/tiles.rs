//! Tile min/max CoC (Sousa, seed 003, "tile min/max CoC"): the stage between `coc`
//! ([`super::coc_plane`]) and the bokeh [`super::gather`], which reads what it finds to
//! choose, per tile of [`TILE`]×[`TILE`] pixels, how far to gather, over which taps and
//! whether a near field can reach it at all. Its GPU twin is `crate::gpu::dof::tiles`, which
//! reads a [`TilesConfig`].
//!
//! In: the signed CoC plane (px, diameter). Out: [`Tiles`]: each tile's gather radius
//! (`reach`), its own largest bokeh radius (`own`) and whether it has no near field
//! (`far_only`). A tile's reach is the largest radius of any tile whose bokeh can reach it
//! (the near field's tile max of Sousa); its flag compares the tile min of its neighbourhood
//! with its own max, the gather's layer test ([`LAYER`]) made once per tile.

/// Tile edge (px): the tiles of this stage and of the gather.
pub const TILE: usize = 16;

/// Two pixels whose signed CoC differ by less than this (px) are the same layer (the gather's
/// near/far test, which `far_only` anticipates).
pub const LAYER: f32 = 1.0;

/// The stage's uniform, as its GPU twin reads it (`TilesConfig` in src/gpu/dof/tiles.wgsl; a
/// test there holds the two layouts together): eight 4-byte fields, a multiple of 16 bytes
/// as uniforms need. The CPU stage reads the frame, ε and the grid from it.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct TilesConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// Tile edge, pixels ([`TILE`]).
    pub tile: u32,
    /// The grid: ⌈width/tile⌉ × ⌈height/tile⌉ tiles.
    pub columns: u32,
    pub rows: u32,
    /// ε: CoC diameters below it are in focus (px).
    pub epsilon: f32,
    /// [`LAYER`]: signed radii closer than this are one layer (px).
    pub layer: f32,
    /// 1/tile: the twin's (overall + 1)/tile is a product with it, WGSL's division not being
    /// correctly rounded (exact for a power of two, which [`TILE`] is).
    pub inv_tile: f32,
}

// (overall + 1)/TILE is computed as a product with 1/TILE on the GPU: exact only for a power
// of two.
const _: () = assert!(TILE.is_power_of_two());

impl TilesConfig {
    /// The config for a `width`×`height` frame in focus below `epsilon` (px).
    pub fn new(width: usize, height: usize, epsilon: f32) -> Self {
        TilesConfig {
            width: width as u32,
            height: height as u32,
            tile: TILE as u32,
            columns: width.div_ceil(TILE) as u32,
            rows: height.div_ceil(TILE) as u32,
            epsilon,
            layer: LAYER,
            inv_tile: 1.0 / TILE as f32,
        }
    }
}

/// What the gather needs to know per tile (Sousa's tile min/max CoC).
#[derive(Clone, Debug, PartialEq)]
pub struct Tiles {
    /// The gather radius (px): the largest bokeh radius of any tile whose bokeh can reach
    /// this one (0 where none out of focus can). Radii below ε/2 count as in focus.
    pub reach: Vec<f32>,
    /// The tile's own largest bokeh radius (px; 0 where all of it is in focus): the far
    /// field's reach, since a far sample counts only within the pixel's own bokeh.
    pub own: Vec<f32>,
    /// True where no sample the tile can read is nearer than its own nearest-to-far pixel
    /// by a layer: the tile min of the neighbourhood against the tile's own max. Such a tile
    /// has no near field and skips that half of the work (with the same result: its near
    /// weights would all be 0).
    pub far_only: Vec<bool>,
}

/// The distance (px) between the nearest pixels of two tiles `dx` and `dy` tiles apart: the
/// gap per axis is the whole tiles between them. The GPU twin (src/gpu/dof/tiles.rs) takes a
/// table of these from here (WGSL's square root is not correctly rounded, and the reach test
/// compares it with a radius).
pub fn gap_distance(dx: usize, dy: usize) -> f32 {
    let gap = |a: usize| a.saturating_sub(1) as f32 * TILE as f32;
    let (gx, gy) = (gap(dx), gap(dy));
    (gx * gx + gy * gy).sqrt()
}

/// Tile max |CoC| (the reach) and tile min/max signed CoC (the far-only tiles) of the
/// signed CoC plane `coc`, over the frame and tile grid of `config`.
pub fn tiles(config: &TilesConfig, coc: &[f32]) -> Tiles {
    let width = config.width as usize;
    let (tiles_x, tiles_y) = (config.columns as usize, config.rows as usize);
    let epsilon = config.epsilon;
    let count = tiles_x * tiles_y;
    let mut largest = vec![0.0f32; count];
    // Signed radii, as the gather compares them.
    let mut lowest = vec![f32::INFINITY; count];
    let mut highest = vec![f32::NEG_INFINITY; count];
    for (y, row) in coc.chunks(width).enumerate() {
        for (x, &c) in row.iter().enumerate() {
            let t = (y / TILE) * tiles_x + x / TILE;
            let r = 0.5 * c.abs();
            if r >= 0.5 * epsilon && r > largest[t] {
                largest[t] = r;
            }
            lowest[t] = lowest[t].min(0.5 * c);
            highest[t] = highest[t].max(0.5 * c);
        }
    }
    let overall = largest.iter().fold(0.0f32, |m, &r| m.max(r));
    let span = ((overall + 1.0) / TILE as f32).ceil() as isize;
    let mut reach = vec![0.0f32; count];
    let mut far_only = vec![false; count];
    for ty in 0..tiles_y as isize {
        for tx in 0..tiles_x as isize {
            let mut best = 0.0f32;
            // The taps of this tile stay within `span` tiles (its radius + 1 px).
            let mut nearest = f32::INFINITY;
            for oy in (ty - span).max(0)..=(ty + span).min(tiles_y as isize - 1) {
                for ox in (tx - span).max(0)..=(tx + span).min(tiles_x as isize - 1) {
                    let other = oy as usize * tiles_x + ox as usize;
                    nearest = nearest.min(lowest[other]);
                    let r = largest[other];
                    if r <= best {
                        continue;
                    }
                    let (dx, dy) = ((tx - ox).unsigned_abs(), (ty - oy).unsigned_abs());
                    if gap_distance(dx, dy) <= r + 1.0 {
                        best = r;
                    }
                }
            }
            let t = ty as usize * tiles_x + tx as usize;
            reach[t] = best;
            // The gather's test: a sample is far when its radius > the pixel's − LAYER/2.
            far_only[t] = nearest > highest[t] - 0.5 * LAYER;
        }
    }
    Tiles {
        reach,
        own: largest,
        far_only,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_know_their_reach_and_whether_a_near_field_can_reach_them() {
        // 64×16: four tiles in a row. CoC (diameter) 10 behind everywhere, but −20 (in
        // front) in the first tile.
        let (w, h) = (64, 16);
        let coc: Vec<f32> = (0..w * h)
            .map(|i| if i % w < 16 { -20.0 } else { 10.0 })
            .collect();
        let t = tiles(&TilesConfig::new(w, h, 1.0), &coc);
        // Radius 10 reaches the second tile from the first; the others see radius 5.
        assert_eq!(t.reach, vec![10.0, 10.0, 5.0, 5.0]);
        // Neighbourhoods span ceil((10 + 1) / 16) = 1 tile each way. The front tile has
        // nothing nearer than itself; the second has the front tile beside it; the third
        // and fourth see only radius 5.
        assert_eq!(t.far_only, vec![true, false, true, true]);
        // All in focus: nothing to gather, nothing near.
        let t = tiles(&TilesConfig::new(w, h, 1.0), &vec![0.2; w * h]);
        assert_eq!(t.reach, vec![0.0; 4]);
        assert_eq!(t.far_only, vec![true; 4]);
    }

    #[test]
    fn the_config_holds_the_grid() {
        let c = TilesConfig::new(33, 16, 1.0);
        assert_eq!((c.columns, c.rows, c.tile), (3, 1, 16));
        // The reciprocal is exact: x·(1/tile) is x/tile.
        assert_eq!(c.inv_tile * TILE as f32, 1.0);
    }
}
