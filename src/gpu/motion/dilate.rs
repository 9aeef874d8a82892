//! Motion blur's `dilate` stage on the GPU (`dilate.wgsl`): the twin of
//! [`crate::motion::dilate::dilate`], the tile stage of reconstruct's 2014 variants (`2014`
//! and `exposure`): each tile's vector spread along its own line, each tile keeping the
//! longest that reaches it.
//!
//! In: the tile grid of half-spread vectors. Out: the dilated grid. Bindings, in order: the
//! [`DilateConfig`] uniform, the grid's x and y, the per-tile [`SourceTile`]s, then the
//! result's x and y. The CPU function takes the grid alone; the source tiles are its own
//! per-tile numbers ([`crate::motion::dilate::Source`]), made on the host with the CPU's code
//! because WGSL's square root and division are not correctly rounded and the reach test
//! meets its threshold exactly for diagonal motion (one pass over the grid, a few thousand
//! tiles at 1080p). The shader does the scan, the part whose cost grows with the vectors'
//! lengths.
//!
//! Agreement with the CPU stated and tested in tests/gpu.rs. Buffers are kept per grid size.

use bytemuck::{Pod, Zeroable};

use crate::motion::dilate::Source;
use crate::motion::tile_max::TileGrid;

use crate::gpu::stage::{tile_grid, Dispatch, Stage, StageError};
use crate::gpu::Gpu;

/// The shader's source.
pub const SHADER: &str = concat!(include_str!("../prelude.wgsl"), include_str!("dilate.wgsl"));

/// Tiles per workgroup side (`@workgroup_size(8, 8)` in dilate.wgsl).
const WORKGROUP: u32 = 8;

/// The stage's uniform. Keep in sync with `DilateConfig` in dilate.wgsl (the size test guards
/// the layout: four 4-byte fields, 16 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct DilateConfig {
    /// The grid, tiles.
    pub columns: u32,
    pub rows: u32,
    /// The largest span of any live source, clamped to the grid, tiles: the scan's radius.
    pub radius: u32,
    pub _pad: u32,
}

/// One tile as a source: [`Source`] for the shader. Keep in sync with `SourceTile` in
/// dilate.wgsl (eight 4-byte fields, 32 bytes; the size test guards it).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SourceTile {
    /// |M|², px².
    pub length2: f32,
    /// ⌈|M_x|/tile⌉ and ⌈|M_y|/tile⌉ as the CPU's loop takes them (`as usize`: NaN is 0,
    /// larger values saturate), here to u32.
    pub span_x: u32,
    pub span_y: u32,
    /// The unit normal of M's line.
    pub nx: f32,
    pub ny: f32,
    /// 1 when M can reach another tile: |M|² > 0 (not NaN) and a finite normal. On the CPU a
    /// NaN |M|² never wins and a non-finite normal makes the reach test compare a NaN.
    pub live: u32,
    pub _pad: [u32; 2],
}

impl SourceTile {
    pub fn new(m: (f32, f32), size: f32) -> SourceTile {
        let s = Source::new(m, size);
        let live = s.length2 > 0.0 && s.nx.is_finite() && s.ny.is_finite();
        SourceTile {
            length2: s.length2,
            span_x: s.span_x as u32,
            span_y: s.span_y as u32,
            nx: s.nx,
            ny: s.ny,
            live: live as u32,
            _pad: [0; 2],
        }
    }
}

/// The compiled stage: bindings config, tiles x, tiles y, sources, x, y.
pub(crate) fn stage(device: &wgpu::Device) -> Stage {
    Stage::new(
        device,
        "dilate",
        SHADER,
        &["main"],
        std::mem::size_of::<DilateConfig>(),
        3,
        2,
        0,
    )
}

impl Gpu {
    /// [`crate::motion::dilate::dilate`] on the GPU, or why it could not run.
    pub fn try_dilate(&self, tiles: &TileGrid) -> Result<TileGrid, StageError> {
        let (columns, rows) = (tiles.columns, tiles.rows);
        let n = columns * rows;
        if n == 0 {
            return Ok(tiles.clone());
        }
        let size = tiles.size.max(1) as f32;
        let sources: Vec<SourceTile> = tiles.x[..n]
            .iter()
            .zip(&tiles.y[..n])
            .map(|(&x, &y)| SourceTile::new((x, y), size))
            .collect();
        let radius = sources
            .iter()
            .filter(|s| s.live != 0)
            .map(|s| s.span_x.max(s.span_y))
            .max()
            .unwrap_or(0)
            .min(columns.max(rows) as u32);
        let config = DilateConfig {
            columns: columns as u32,
            rows: rows as u32,
            radius,
            _pad: 0,
        };
        let bytes = (n * 4) as u64;
        let out = self.dilate.run(
            self,
            bytemuck::bytes_of(&config),
            &[
                bytemuck::cast_slice(&tiles.x[..n]),
                bytemuck::cast_slice(&tiles.y[..n]),
                bytemuck::cast_slice(&sources),
            ],
            &[bytes, bytes],
            &[],
            &[Dispatch {
                entry: 0,
                groups: [
                    config.columns.div_ceil(WORKGROUP),
                    config.rows.div_ceil(WORKGROUP),
                    1,
                ],
            }],
        )?;
        Ok(tile_grid(out, columns, rows, tiles.size))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_structs_are_plain_words() {
        // Keep in sync with dilate.wgsl: four and eight 4-byte fields, multiples of 16.
        assert_eq!(std::mem::size_of::<DilateConfig>(), 16);
        assert_eq!(std::mem::size_of::<SourceTile>(), 32);
        assert_eq!(std::mem::align_of::<SourceTile>(), 4);
    }

    #[test]
    fn the_shader_s_threshold_is_the_cpu_s() {
        // dilate.wgsl spells √2 by its bits.
        assert_eq!(crate::motion::dilate::REACH.to_bits(), 0x3fb5_04f3);
        assert!(SHADER.contains("0x3fb504f3u"));
    }

    #[test]
    fn sources_that_reach_nothing_are_not_live() {
        assert_eq!(SourceTile::new((0.0, 0.0), 8.0).live, 0);
        assert_eq!(SourceTile::new((f32::NAN, 1.0), 8.0).live, 0);
        // |M| = ∞ with infinite components: the normal is NaN.
        assert_eq!(SourceTile::new((f32::INFINITY, 0.0), 8.0).live, 0);
        // |M|² overflows with finite components: the normal is 0, and it reaches its span.
        let huge = SourceTile::new((1e20, 0.0), 8.0);
        assert_eq!((huge.live, huge.span_x), (1, u32::MAX));
        let s = SourceTile::new((10.0, -3.0), 8.0);
        assert_eq!((s.live, s.span_x, s.span_y), (1, 2, 1));
    }
}
