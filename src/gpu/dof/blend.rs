//! Depth of field's blend on the GPU (`blend.wgsl`): the twin of
//! [`crate::dof::blend::pyramid`], the binomial pyramid and the blurriness interpolation
//! between its levels (the talk's two-copy form stays on the CPU).
//!
//! In: the colour and the signed CoC plane. Out: the colour with depth of field. Bindings, in
//! order: the [`BlendConfig`] uniform; the colour planes r, g, b, a one after the other (a
//! zero without alpha); the CoC plane; each level's geometry (width, height, first texel);
//! the ladder's CoCs and inverse gaps; then the output planes and, not read back, every
//! level's texels.
//!
//! What a frame needs decided before any pixel is blurred — E, the number of levels, the
//! ladder, whether and where T_near is read, the reference colour — is the CPU's own
//! `crate::dof::blend::pyramid::plan`, made on the host. Three entry points run in order in
//! one compute pass: level 1 from the frame, each further level from the one before, then one
//! invocation per pixel (the discs below level 3's CoC, the levels' mix above). What may
//! differ from the CPU is rounding: WGSL's division and square root are not correctly
//! rounded (a level's colour divided by its w, the discs' normalisation and coverage) and a
//! driver may fuse a product into a sum; the tolerance in tests/gpu_dof.rs says how much.

use crate::dof::blend::pyramid::{plan, BlendConfig};
use crate::dof::DofConfig;
use crate::frame::Color;

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, Dispatch, Stage, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(include_str!("../prelude.wgsl"), include_str!("blend.wgsl"));

/// Workgroups are 8 × 8 invocations.
const GROUP: usize = 8;

/// The compiled stage: bindings config, color, coc, geometry, ladder, then out and the
/// levels' texels (scratch).
pub(crate) fn stage(device: &wgpu::Device) -> Stage {
    Stage::new(
        device,
        "blend",
        SHADER,
        &["first_level", "halve", "compose"],
        std::mem::size_of::<BlendConfig>(),
        4,
        2,
        1,
    )
}

impl Gpu {
    /// [`crate::dof::blend::pyramid::blend`] on the GPU, or why it could not run;
    /// [`crate::dof::Stages::blend`] falls back to the CPU stage.
    pub fn try_dof_blend(
        &self,
        config: &DofConfig,
        color: &Color,
        coc: &[f32],
    ) -> Result<Color, StageError> {
        let (width, height) = (config.width, config.height);
        let n = width * height;
        let has_alpha = color.a.is_some();
        if n == 0 {
            return Ok(color.clone());
        }
        let plan = plan(config, color, coc);
        // Each level's geometry, and where its texels start.
        let mut geometry = Vec::with_capacity(3 * plan.levels + 3);
        let (mut w, mut h, mut first) = (width, height, 0usize);
        for _ in 0..plan.levels {
            (w, h) = (w.div_ceil(2), h.div_ceil(2));
            geometry.extend([w as u32, h as u32, first as u32]);
            first += w * h;
        }
        // The plain level 1 (`first_level`'s z 1: a near pixel's level disc), after them.
        let (w2, h2) = (width.div_ceil(2), height.div_ceil(2));
        geometry.extend([w2 as u32, h2 as u32, first as u32]);
        let texels = first + w2 * h2;
        let ladder: Vec<f32> = [&plan.ladder.cocs, &plan.ladder.inverse_gaps]
            .into_iter()
            .flatten()
            .copied()
            .collect();
        let mut planes = Vec::with_capacity(4 * n);
        planes.extend_from_slice(&color.r[..n]);
        planes.extend_from_slice(&color.g[..n]);
        planes.extend_from_slice(&color.b[..n]);
        match &color.a {
            Some(a) => planes.extend_from_slice(&a[..n]),
            None => planes.resize(4 * n, 0.0),
        }
        let uniform = BlendConfig::new(config, &plan, has_alpha);
        let groups = |w: usize, h: usize| [w.div_ceil(GROUP) as u32, h.div_ceil(GROUP) as u32];
        let mut dispatches = Vec::with_capacity(plan.levels + 1);
        for (l, g) in geometry.chunks(3).take(plan.levels).enumerate() {
            let [x, y] = groups(g[0] as usize, g[1] as usize);
            // Level l + 1: level 1 from the frame (and the plain level 1, z 1); the others
            // from the level before, the level number riding in the z count (blend.wgsl,
            // `halve`).
            dispatches.push(match l {
                // The plain level 1 only where some pixel is in front of the focus plane
                // (the plan's `near`): only such a pixel reads it.
                0 => Dispatch {
                    entry: 0,
                    groups: [x, y, if plan.near.is_some() { 2 } else { 1 }],
                },
                _ => Dispatch {
                    entry: 1,
                    groups: [x, y, l as u32],
                },
            });
        }
        let [x, y] = groups(width, height);
        dispatches.push(Dispatch {
            entry: 2,
            groups: [x, y, 1],
        });
        let mut out = self.compiled("blend", stage).run(
            self,
            bytemuck::bytes_of(&uniform),
            &[
                bytemuck::cast_slice(&planes),
                bytemuck::cast_slice(&coc[..n]),
                bytemuck::cast_slice(&geometry),
                bytemuck::cast_slice(&ladder),
            ],
            &[(4 * n * 4) as u64, (texels * 32) as u64],
            &[],
            &dispatches,
        )?;
        let mut out = floats(out.swap_remove(0));
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
    fn the_config_is_the_shader_s() {
        // `reference` (a vec4) at byte 16, the whole a multiple of 16 as uniforms need.
        assert_eq!(std::mem::offset_of!(BlendConfig, reference), 16);
        assert_eq!(std::mem::offset_of!(BlendConfig, epsilon), 32);
        crate::gpu::layout::assert_same_layout!(
            BlendConfig,
            SHADER,
            "BlendConfig",
            [
                width,
                height,
                levels,
                has_alpha,
                reference,
                epsilon,
                inverse_span,
                largest,
                near,
                near_k,
                near_f,
                disc_level_2,
                disc_level_3
            ]
        );
    }
}
