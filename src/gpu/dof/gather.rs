//! Depth of field's bokeh gather on the GPU (`gather.wgsl`): the twin of
//! [`crate::dof::gather::gather`] (Sousa's near and far fields over a tile's taps).
//!
//! In: the colour, the signed CoC plane and the tile min/max ([`Tiles`]). Out: the colour
//! with depth of field. Bindings, in order: the [`GatherConfig`] uniform; the colour planes
//! r, g, b, a one after the other (a zero without alpha); the CoC plane followed by each
//! pixel's 1 / bokeh area; the taps; the tiles' plan; then the output planes r, g, b, a.
//!
//! What each tile gathers and over which taps is the CPU's own decision,
//! [`crate::dof::gather::plan`], made on the host (a few thousand tiles; every tap list once):
//! the twin only runs the per-pixel loop, one invocation per pixel, the taps in the CPU's
//! order. The bokeh areas are the CPU's [`inverse_area`] (WGSL's division is not correctly
//! rounded). What may still differ from the CPU is rounding: the two divisions of the
//! composite, and a driver may fuse a product into a sum (WGSL allows it); the tolerance in
//! tests/gpu.rs says how much that is.

use bytemuck::{Pod, Zeroable};

use crate::dof::bokeh::Aperture;
use crate::dof::gather::{inverse_area, plan, Tiles, LAYER, TILE};
use crate::dof::DofConfig;
use crate::frame::Color;

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, Dispatch, Stage, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(include_str!("../prelude.wgsl"), include_str!("gather.wgsl"));

/// The stage's uniform. Keep in sync with `GatherConfig` in gather.wgsl (the size test guards
/// the layout: eight 4-byte fields, a multiple of 16 bytes as uniforms need).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GatherConfig {
    pub width: u32,
    pub height: u32,
    /// Tiles per row.
    pub columns: u32,
    /// 1 where the frame has alpha.
    pub has_alpha: u32,
    /// [`LAYER`].
    pub layer: f32,
    pub _pad: [u32; 3],
}

/// One tap. Keep in sync with `Tap` in gather.wgsl (five 4-byte fields).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuTap {
    pub dx: i32,
    pub dy: i32,
    pub norm_far: f32,
    pub norm_near: f32,
    pub area: f32,
}

/// One tile's plan. Keep in sync with `Tile` in gather.wgsl (five 4-byte fields).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuTile {
    pub fields: u32,
    pub taps_start: u32,
    pub taps_count: u32,
    pub far_start: u32,
    pub far_count: u32,
}

/// The compiled stage: bindings config, color, coc, taps, tiles, then out.
pub(crate) fn stage(device: &wgpu::Device) -> Stage {
    Stage::new(
        device,
        "gather",
        SHADER,
        &["gather"],
        std::mem::size_of::<GatherConfig>(),
        4,
        1,
        0,
    )
}

impl Gpu {
    /// [`crate::dof::gather::gather`] on the GPU; the CPU stage where the GPU cannot run it,
    /// counted in [`Gpu::stages_on_cpu`].
    pub fn dof_gather(
        &self,
        config: &DofConfig,
        color: &Color,
        coc: &[f32],
        tiles: &Tiles,
    ) -> Color {
        self.try_dof_gather(config, color, coc, tiles)
            .unwrap_or_else(|e| {
                self.note_cpu_stage("gather", &e);
                crate::dof::gather::gather(config, color, coc, tiles)
            })
    }

    /// [`crate::dof::gather::gather`] on the GPU, or why it could not run.
    pub fn try_dof_gather(
        &self,
        config: &DofConfig,
        color: &Color,
        coc: &[f32],
        tiles: &Tiles,
    ) -> Result<Color, StageError> {
        let (width, height) = (config.width as usize, config.height as usize);
        let n = width * height;
        let has_alpha = color.a.is_some();
        if n == 0 {
            return Ok(color.clone());
        }
        let plan = plan(config, tiles);
        let taps: Vec<GpuTap> = plan
            .taps
            .iter()
            .map(|t| GpuTap {
                dx: t.offset[0],
                dy: t.offset[1],
                norm_far: t.norm_far,
                norm_near: t.norm_near,
                area: t.area,
            })
            .collect();
        let tile_plan: Vec<GpuTile> = plan
            .tiles
            .iter()
            .map(|t| GpuTile {
                fields: t.fields,
                taps_start: t.taps[0],
                taps_count: t.taps[1],
                far_start: t.far[0],
                far_count: t.far[1],
            })
            .collect();
        let mut planes = Vec::with_capacity(4 * n);
        planes.extend_from_slice(&color.r[..n]);
        planes.extend_from_slice(&color.g[..n]);
        planes.extend_from_slice(&color.b[..n]);
        match &color.a {
            Some(a) => planes.extend_from_slice(&a[..n]),
            None => planes.resize(4 * n, 0.0),
        }
        let unit_area = Aperture::new(config.blades, config.blade_rotation).unit_area();
        let mut radii = Vec::with_capacity(2 * n);
        radii.extend_from_slice(&coc[..n]);
        radii.extend(coc[..n].iter().map(|&c| inverse_area(c, unit_area)));
        let uniform = GatherConfig {
            width: width as u32,
            height: height as u32,
            columns: width.div_ceil(TILE) as u32,
            has_alpha: has_alpha as u32,
            layer: LAYER,
            _pad: [0; 3],
        };
        let groups = [width.div_ceil(TILE) as u32, height.div_ceil(TILE) as u32, 1];
        let mut out = self.compiled("gather", stage).run(
            self,
            bytemuck::bytes_of(&uniform),
            &[
                bytemuck::cast_slice(&planes),
                bytemuck::cast_slice(&radii),
                bytemuck::cast_slice(&taps),
                bytemuck::cast_slice(&tile_plan),
            ],
            &[(4 * n * 4) as u64],
            &[],
            &[Dispatch { entry: 0, groups }],
        )?;
        let mut out = floats(out.pop().expect("one output"));
        let a = has_alpha.then(|| out.split_off(3 * n));
        out.truncate(3 * n);
        let b = out.split_off(2 * n);
        let g = out.split_off(n);
        Ok(Color { r: out, g, b, a })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_shared_structs_are_plain_words() {
        // Keep in sync with gather.wgsl: the uniform is eight 4-byte fields (a multiple of
        // 16), a tap and a tile five each (their array stride in a storage buffer).
        assert_eq!(std::mem::size_of::<GatherConfig>(), 32);
        assert_eq!(std::mem::size_of::<GpuTap>(), 20);
        assert_eq!(std::mem::size_of::<GpuTile>(), 20);
        assert_eq!(std::mem::align_of::<GpuTap>(), 4);
    }
}
