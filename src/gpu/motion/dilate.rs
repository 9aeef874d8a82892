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

use crate::motion::dilate::{DilateConfig, SourceTile};
use crate::motion::tile_max::TileGrid;

use crate::gpu::context::Gpu;
use crate::gpu::stage::{tile_grid, Dispatch, Stage, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(include_str!("../prelude.wgsl"), include_str!("dilate.wgsl"));

/// Tiles per workgroup side (`@workgroup_size(8, 8)` in dilate.wgsl).
const WORKGROUP: u32 = 8;

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
        let out = self.compiled("dilate", stage).run(
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
        crate::gpu::layout::assert_same_layout!(
            DilateConfig,
            SHADER,
            "DilateConfig",
            [columns, rows, radius]
        );
        crate::gpu::layout::assert_same_layout!(
            SourceTile,
            SHADER,
            "SourceTile",
            [length2, span_x, span_y, nx, ny, live]
        );
    }

    #[test]
    fn the_shader_s_threshold_is_the_cpu_s() {
        // dilate.wgsl spells √2 by its bits.
        assert_eq!(crate::motion::dilate::REACH.to_bits(), 0x3fb5_04f3);
        assert!(SHADER.contains("0x3fb504f3u"));
    }
}
