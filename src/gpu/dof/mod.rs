//! Depth of field's GPU twins, mirroring [`crate::dof`]: `coc`, tile min/max (`tiles`), the
//! bokeh `gather` and `blend`'s pyramid.

use crate::gpu::context::Gpu;

pub mod blend;
pub mod coc;
pub mod gather;
pub mod tiles;
/// Depth of field's stages with a twin run here: `coc` and tile min/max (each falls back to
/// the CPU stage, counted, where the GPU cannot run it).
impl crate::dof::Stages for Gpu {
    fn coc_plane(&self, frame: &crate::frame::Frame, params: &crate::dof::DofParams) -> Vec<f32> {
        Gpu::coc_plane(self, frame, params)
    }

    fn tiles(
        &self,
        coc: &[f32],
        width: usize,
        height: usize,
        epsilon: f32,
    ) -> crate::dof::gather::Tiles {
        Gpu::tiles(self, coc, width, height, epsilon)
    }

    fn gather(
        &self,
        config: &crate::dof::DofConfig,
        color: &crate::frame::Color,
        coc: &[f32],
        tiles: &crate::dof::gather::Tiles,
    ) -> crate::frame::Color {
        Gpu::dof_gather(self, config, color, coc, tiles)
    }

    fn blend(
        &self,
        config: &crate::dof::DofConfig,
        color: crate::frame::Color,
        coc: &[f32],
    ) -> crate::frame::Color {
        Gpu::dof_blend(self, config, color, coc)
    }
}
