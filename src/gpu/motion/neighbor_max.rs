//! Motion blur's `neighbor_max` stage on the GPU (`neighbor_max.wgsl`): the twin of
//! [`crate::motion::neighbor_max::neighbor_max`], reconstruct's second stage for the paper and
//! dual variants (McGuire et al. 2012, eq. 2).
//!
//! In: TileMax's [`TileGrid`]. Out: the grid of the same size holding each tile's dominant
//! vector of its 3×3 neighbourhood. Bindings, in order: the [`NeighborMaxConfig`] uniform,
//! the grid's x and y, then the result's x and y.
//!
//! NaN and infinity as on the CPU; agreement stated and tested in tests/gpu.rs. Buffers are
//! kept per grid size and reused.

use crate::motion::neighbor_max::NeighborMaxConfig;
use crate::motion::tile_max::TileGrid;

use crate::gpu::context::Gpu;
use crate::gpu::stage::{tile_grid, Dispatch, Stage, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(
    include_str!("../prelude.wgsl"),
    include_str!("neighbor_max.wgsl")
);

/// Tiles per workgroup side (`@workgroup_size(8, 8)` in neighbor_max.wgsl).
const WORKGROUP: u32 = 8;

/// The compiled stage: bindings config, tiles x, tiles y, x, y.
pub(crate) fn stage(device: &wgpu::Device) -> Stage {
    Stage::new(
        device,
        "neighbor_max",
        SHADER,
        &["main"],
        std::mem::size_of::<NeighborMaxConfig>(),
        2,
        2,
        0,
    )
}

impl Gpu {
    /// [`crate::motion::neighbor_max::neighbor_max`] on the GPU, or why it could not run.
    pub fn try_neighbor_max(&self, tiles: &TileGrid) -> Result<TileGrid, StageError> {
        let (columns, rows) = (tiles.columns, tiles.rows);
        let n = columns * rows;
        if n == 0 {
            return Ok(tiles.clone());
        }
        let config = NeighborMaxConfig::of(tiles);
        let bytes = (n * 4) as u64;
        let out = self.compiled("neighbor_max", stage).run(
            self,
            bytemuck::bytes_of(&config),
            &[
                bytemuck::cast_slice(&tiles.x[..n]),
                bytemuck::cast_slice(&tiles.y[..n]),
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
    fn the_config_is_four_plain_words() {
        // Keep in sync with neighbor_max.wgsl: four 4-byte fields, 16 bytes.
        assert_eq!(std::mem::size_of::<NeighborMaxConfig>(), 16);
        assert_eq!(std::mem::align_of::<NeighborMaxConfig>(), 4);
        crate::gpu::layout::assert_same_layout!(
            NeighborMaxConfig,
            SHADER,
            "NeighborMaxConfig",
            [columns, rows]
        );
    }
}
