//! Motion blur's GPU twins, mirroring [`crate::motion`]: reconstruct's tile stages
//! (`tile_max`, `neighbor_max`, `dilate`) and its gather (`reconstruct`), `scatter` and
//! `stretch`.

use crate::gpu::Gpu;

pub mod dilate;
pub mod neighbor_max;
pub mod reconstruct;
pub mod scatter;
pub mod stretch;
pub mod tile_max;

/// Reconstruct's tile stages run here (each falls back to the CPU stage, counted, where the
/// GPU cannot run it).
impl crate::motion::TileStages for Gpu {
    fn tile_max(
        &self,
        vx: &[f32],
        vy: &[f32],
        width: usize,
        height: usize,
        size: usize,
    ) -> crate::motion::tile_max::TileGrid {
        self.or_cpu(
            "tile_max",
            || self.try_tile_max(vx, vy, width, height, size),
            || crate::motion::tile_max::tile_max(vx, vy, width, height, size),
        )
    }

    fn neighbor_max(
        &self,
        tiles: &crate::motion::tile_max::TileGrid,
    ) -> crate::motion::tile_max::TileGrid {
        self.or_cpu(
            "neighbor_max",
            || self.try_neighbor_max(tiles),
            || crate::motion::neighbor_max::neighbor_max(tiles),
        )
    }

    fn dilate(
        &self,
        tiles: &crate::motion::tile_max::TileGrid,
    ) -> crate::motion::tile_max::TileGrid {
        self.or_cpu(
            "dilate",
            || self.try_dilate(tiles),
            || crate::motion::dilate::dilate(tiles),
        )
    }
}
