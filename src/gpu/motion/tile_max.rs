//! Motion blur's `tile_max` stage on the GPU (`tile_max.wgsl`): the twin of
//! [`crate::motion::tile_max::tile_max`], the first stage of reconstruct (McGuire et al. 2012,
//! eq. 1).
//!
//! In: the velocity planes (px per frame). Out: the [`TileGrid`] of each k×k tile's dominant
//! vector (largest |v|², the first in row-major order on ties). Bindings, in order: the
//! [`TileMaxConfig`] uniform, vx, vy, then the grid's x and y — the CPU function's arguments
//! and result.
//!
//! The CPU's treatment of non-finite input (a NaN |v|² never wins, +∞ always does) is the
//! shader's, by comparing |v|² by its bits. Its agreement with the CPU (exact but for
//! near-ties a driver may resolve through an fma, and subnormal |v|²) is stated and tested
//! in tests/gpu.rs.
//!
//! Buffers are kept per frame size in the context and reused by every frame of that size.

use crate::motion::tile_max::{TileGrid, TileMaxConfig};

use crate::gpu::context::Gpu;
use crate::gpu::stage::{tile_grid, Dispatch, Stage, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(
    include_str!("../prelude.wgsl"),
    include_str!("tile_max.wgsl")
);

/// The compiled stage: bindings config, vx, vy, x, y.
pub(crate) fn stage(device: &wgpu::Device) -> Stage {
    Stage::new(
        device,
        "tile_max",
        SHADER,
        &["main"],
        std::mem::size_of::<TileMaxConfig>(),
        2,
        2,
        0,
    )
}

impl Gpu {
    /// [`crate::motion::tile_max::tile_max`] on the GPU, or why it could not run.
    pub fn try_tile_max(
        &self,
        vx: &[f32],
        vy: &[f32],
        width: usize,
        height: usize,
        size: usize,
    ) -> Result<TileGrid, StageError> {
        let config = TileMaxConfig::new(width, height, size);
        let (columns, rows) = (config.columns as usize, config.rows as usize);
        let tiles = columns * rows;
        if tiles == 0 {
            return Ok(TileGrid {
                columns,
                rows,
                size: config.size as usize,
                x: Vec::new(),
                y: Vec::new(),
            });
        }
        let n = width * height;
        let bytes = (tiles * 4) as u64;
        let out = self.compiled("tile_max", stage).run(
            self,
            bytemuck::bytes_of(&config),
            &[
                bytemuck::cast_slice(&vx[..n]),
                bytemuck::cast_slice(&vy[..n]),
            ],
            &[bytes, bytes],
            &[],
            &[Dispatch {
                entry: 0,
                groups: [config.columns, config.rows, 1],
            }],
        )?;
        Ok(tile_grid(out, columns, rows, config.size as usize))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_config_is_eight_plain_words() {
        // Keep in sync with tile_max.wgsl: eight 4-byte fields, no padding, a multiple of 16.
        assert_eq!(std::mem::size_of::<TileMaxConfig>(), 32);
        assert_eq!(std::mem::align_of::<TileMaxConfig>(), 4);
        crate::gpu::layout::assert_same_layout!(
            TileMaxConfig,
            SHADER,
            "TileMaxConfig",
            [width, height, size, columns, rows]
        );
        // Partial tiles at the right and bottom count; a size of 0 is 1.
        let c = TileMaxConfig::new(17, 9, 8);
        assert_eq!((c.columns, c.rows), (3, 2));
        assert_eq!(TileMaxConfig::new(3, 2, 0).size, 1);
    }
}
