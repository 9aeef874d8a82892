//! Depth of field's `coc` stage on the GPU (`coc.wgsl`): the twin of
//! [`crate::dof::coc_plane`], the first stage of both depth-of-field methods.
//!
//! In: the depth plane (or a painted map read as depth). Out: the signed CoC diameter of every
//! pixel in pixels, clamped to ±`max_coc` (negative in front of the focus plane). Bindings,
//! in order: the [`CocConfig`] uniform, depth, coc — the CPU function's arguments and result.
//!
//! The CPU evaluates the thin lens in f64; the shader in f32 with the lens folded into the
//! far-limit CoC K and the focus distance P on the host (`CocConfig::new`, `coc.wgsl`'s
//! header). The difference this makes is bounded and tested in tests/gpu_dof.rs.
//!
//! Buffers are kept per frame size in the context and reused by every frame of that size.

use crate::dof::coc::CocConfig;
use crate::dof::DofParams;
use crate::frame::Frame;

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, Dispatch, Stage, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(include_str!("../prelude.wgsl"), include_str!("coc.wgsl"));

/// Pixels per workgroup side (`@workgroup_size(16, 16)` in coc.wgsl).
const WORKGROUP: u32 = 16;

/// The compiled stage: bindings config, depth, coc.
pub(crate) fn stage(device: &wgpu::Device) -> Stage {
    Stage::new(
        device,
        "coc",
        SHADER,
        &["main"],
        std::mem::size_of::<CocConfig>(),
        1,
        1,
        0,
    )
}

impl Gpu {
    /// [`crate::dof::coc_plane`] on the GPU, or why it could not run (a frame over the
    /// device's limits); [`crate::dof::Stages::coc_plane`] falls back to the CPU stage.
    pub fn try_coc_plane(&self, frame: &Frame, params: &DofParams) -> Result<Vec<f32>, StageError> {
        let pixels = frame.pixel_count();
        let Some(depth) = frame.depth.as_ref() else {
            return Ok(vec![0.0; pixels]);
        };
        if pixels == 0 {
            return Ok(Vec::new());
        }
        let bytes = (pixels * 4) as u64;
        let config = CocConfig::new(
            frame.width,
            frame.height,
            frame.windows.display.width,
            params,
        );
        let mut out = self.compiled("coc", stage).run(
            self,
            bytemuck::bytes_of(&config),
            &[bytemuck::cast_slice(depth)],
            &[bytes],
            &[],
            &[Dispatch {
                entry: 0,
                groups: [
                    config.width.div_ceil(WORKGROUP),
                    config.height.div_ceil(WORKGROUP),
                    1,
                ],
            }],
        )?;
        Ok(floats(out.remove(0)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_config_is_the_shader_s() {
        // Eight 4-byte fields, no padding but the last, a multiple of 16 as uniforms need.
        assert_eq!(std::mem::align_of::<CocConfig>(), 4);
        crate::gpu::layout::assert_same_layout!(
            CocConfig,
            SHADER,
            "CocConfig",
            [width, height, source, limit, scale, focus, cap]
        );
    }
}
