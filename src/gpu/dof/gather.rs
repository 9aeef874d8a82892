//! Depth of field's bokeh gather on the GPU (`gather.wgsl`): the twin of
//! [`crate::dof::gather::gather`] (Sousa's near and far fields over a tile's taps).
//!
//! In: the colour, the signed CoC plane and the tile min/max ([`Tiles`]). Out: the colour
//! with depth of field. Entry `gather_carrying` gathers the beauty and light layers beside it
//! (up to [`MOST_COLOURS`] colours a dispatch, their planes one colour after another in the
//! same bindings), each tap's weights computed once for all of them: the twin of
//! [`crate::dof::gather::gather_carrying`]. Bindings, in order: the [`GatherConfig`] uniform; the colour planes
//! r, g, b, a one after the other (a zero without alpha); the CoC plane followed by each
//! pixel's 1 / bokeh area; the taps ([`crate::dof::gather::OffsetTap`]); the tiles' plan
//! ([`crate::dof::gather::TileTaps`]); the prefilter levels' box sides; then the output
//! planes r, g, b, a, and the levels themselves (scratch), which entry `prefilter` makes first
//! (one dispatch, a level per z) as the CPU's `Padded::level` does, and which the ring taps
//! read.
//!
//! What each tile gathers and over which taps is the CPU's own decision,
//! [`crate::dof::gather::plan`], made on the host (a few thousand tiles; every tap list once)
//! and uploaded as it is: the twin only runs the per-pixel loop, one invocation per pixel, the
//! taps in the CPU's order. The bokeh areas are the CPU's [`inverse_area`] (WGSL's division
//! is not correctly rounded). What may still differ from the CPU is rounding: the two
//! divisions of the composite, and a driver may fuse a product into a sum (WGSL allows it);
//! the tolerance in tests/gpu_dof.rs says how much that is.

use crate::dof::bokeh::Aperture;
use crate::dof::gather::{inverse_area, plan, GatherConfig, TilePlan};
use crate::dof::tiles::{Tiles, TILE};
use crate::dof::DofConfig;
use crate::frame::Color;

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, Dispatch, Stage, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(include_str!("../prelude.wgsl"), include_str!("gather.wgsl"));

/// Most colours one dispatch of `gather_carrying` gathers (`MOST_COLOURS` in the shader).
pub const MOST_COLOURS: usize = 8;

/// The compiled stage: bindings config, color, coc, taps, tiles, sides, then out and the
/// prefilter levels (scratch); entries `gather`, `gather_carrying` and `prefilter`.
pub(crate) fn stage(device: &wgpu::Device) -> Stage {
    Stage::new(
        device,
        "gather",
        SHADER,
        &["gather", "gather_carrying", "prefilter"],
        std::mem::size_of::<GatherConfig>(),
        5,
        2,
        1,
    )
}

impl Gpu {
    /// [`crate::dof::gather::gather`] on the GPU, or why it could not run;
    /// [`crate::dof::Stages::gather`] falls back to the CPU stage.
    pub fn try_dof_gather(
        &self,
        config: &DofConfig,
        color: &Color,
        coc: &[f32],
        tiles: &Tiles,
    ) -> Result<Color, StageError> {
        let (width, height) = (config.width, config.height);
        let n = width * height;
        let has_alpha = color.a.is_some();
        if n == 0 {
            return Ok(color.clone());
        }
        let plan = plan(config, tiles);
        let mut planes = Vec::with_capacity(4 * n);
        push_planes(&mut planes, color, n);
        let unit_area = Aperture::new(config.blades, config.blade_rotation).unit_area();
        let mut radii = Vec::with_capacity(2 * n);
        radii.extend_from_slice(&coc[..n]);
        radii.extend(coc[..n].iter().map(|&c| inverse_area(c, unit_area)));
        let uniform = GatherConfig {
            levels: plan.sides.len() as u32,
            ..GatherConfig::new(config, has_alpha)
        };
        let mut out = self.dispatch_gather(&uniform, 0, &planes, &radii, &plan)?;
        let a = has_alpha.then(|| out.split_off(3 * n));
        out.truncate(3 * n);
        let b = out.split_off(2 * n);
        let g = out.split_off(n);
        Ok(Color { r: out, g, b, a })
    }

    /// [`crate::dof::gather::gather_carrying`] on the GPU: `colours` (the beauty, then light
    /// layers with its alpha) gathered with the beauty's weights, each tap's weights computed
    /// once for as many colours as one dispatch holds (at most [`MOST_COLOURS`], and as many
    /// as fit one storage binding), or why it could not run.
    pub fn try_dof_gather_carrying(
        &self,
        config: &DofConfig,
        colours: &[&Color],
        coc: &[f32],
        tiles: &Tiles,
    ) -> Result<Vec<Color>, StageError> {
        let (width, height) = (config.width, config.height);
        let n = width * height;
        if n == 0 {
            return Ok(colours.iter().map(|&c| c.clone()).collect());
        }
        let plan = plan(config, tiles);
        let unit_area = Aperture::new(config.blades, config.blade_rotation).unit_area();
        let mut radii = Vec::with_capacity(2 * n);
        radii.extend_from_slice(&coc[..n]);
        radii.extend(coc[..n].iter().map(|&c| inverse_area(c, unit_area)));
        // As many colours a dispatch as one binding holds (16 bytes a pixel each, and as
        // much again a prefilter level).
        let levels = plan.sides.len() as u64;
        let fit = (self.max_binding() / (16 * n as u64 * levels.max(1))).max(1) as usize;
        let per_dispatch = MOST_COLOURS.min(fit);
        let mut gathered = Vec::with_capacity(colours.len());
        for chunk in colours.chunks(per_dispatch) {
            let mut planes = Vec::with_capacity(4 * n * chunk.len());
            for color in chunk {
                push_planes(&mut planes, color, n);
            }
            let uniform = GatherConfig {
                colours: chunk.len() as u32,
                levels: plan.sides.len() as u32,
                ..GatherConfig::new(config, chunk[0].a.is_some())
            };
            let out = self.dispatch_gather(&uniform, 1, &planes, &radii, &plan)?;
            for (color, planes) in chunk.iter().zip(out.chunks_exact(4 * n)) {
                let plane = |k: usize| planes[k * n..(k + 1) * n].to_vec();
                gathered.push(Color {
                    r: plane(0),
                    g: plane(1),
                    b: plane(2),
                    a: color.a.is_some().then(|| plane(3)),
                });
            }
        }
        Ok(gathered)
    }
}

impl Gpu {
    /// One dispatch of the gather's entry `entry` (0 `gather`, 1 `gather_carrying`) over the
    /// colours' `planes` (four a colour, `uniform.colours` of them), with the CoC and bokeh
    /// areas (`radii`) and the plan, after the `prefilter` of the plan's levels; returns the
    /// output planes.
    fn dispatch_gather(
        &self,
        uniform: &GatherConfig,
        entry: usize,
        planes: &[f32],
        radii: &[f32],
        plan: &TilePlan,
    ) -> Result<Vec<f32>, StageError> {
        let groups = [uniform.columns, uniform.height.div_ceil(TILE as u32), 1];
        let levels = plan.sides.len() as u32;
        let n = (uniform.width * uniform.height) as u64;
        let level_bytes = levels as u64 * (1 + 4 * uniform.colours as u64) * n * 4;
        let mut out = self.compiled("gather", stage).run(
            self,
            bytemuck::bytes_of(uniform),
            &[
                bytemuck::cast_slice(planes),
                bytemuck::cast_slice(radii),
                bytemuck::cast_slice(&plan.taps),
                bytemuck::cast_slice(&plan.tiles),
                bytemuck::cast_slice(&plan.sides),
            ],
            &[(planes.len() * 4) as u64, level_bytes],
            &[],
            &[
                Dispatch {
                    entry: 2,
                    groups: [groups[0], groups[1], levels],
                },
                Dispatch { entry, groups },
            ],
        )?;
        Ok(floats(out.swap_remove(0)))
    }
}

/// `color`'s r, g, b and a planes (a zero without alpha) after `planes`, as the shader reads
/// a colour.
fn push_planes(planes: &mut Vec<f32>, color: &Color, n: usize) {
    planes.extend_from_slice(&color.r[..n]);
    planes.extend_from_slice(&color.g[..n]);
    planes.extend_from_slice(&color.b[..n]);
    match &color.a {
        Some(a) => planes.extend_from_slice(&a[..n]),
        None => planes.resize(planes.len() + n, 0.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dof::gather::{OffsetTap, TileTaps};

    #[test]
    fn the_shared_structs_are_the_shader_s() {
        // The uniform is eight 4-byte fields (a multiple of 16), a tap five and a tile nine
        // (their array stride in a storage buffer).
        assert_eq!(std::mem::align_of::<OffsetTap>(), 4);
        crate::gpu::layout::assert_same_layout!(
            GatherConfig,
            SHADER,
            "GatherConfig",
            [width, height, columns, has_alpha, layer, colours, small, levels]
        );
        crate::gpu::layout::assert_same_layout!(
            OffsetTap,
            SHADER,
            "Tap",
            [dx, dy, norm_far, norm_near, area]
        );
        crate::gpu::layout::assert_same_layout!(
            TileTaps,
            SHADER,
            "Tile",
            [
                fields,
                taps_start,
                taps_count,
                far_start,
                far_count,
                dense_start,
                dense_count,
                level,
                far_level
            ]
        );
    }
}
