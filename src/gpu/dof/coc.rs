//! Depth of field's `coc` stage on the GPU (`coc.wgsl`): the twin of
//! [`crate::dof::coc_plane`], the first stage of both depth-of-field methods.
//!
//! In: the depth plane (or a painted map read as depth). Out: the signed CoC diameter of every
//! pixel in pixels, clamped to ±`max_coc` (negative in front of the focus plane). Bindings,
//! in order: the [`CocConfig`] uniform, depth, coc — the CPU function's arguments and result.
//!
//! The CPU evaluates the thin lens in f64; the shader in f32 with the lens folded into the
//! far-limit CoC K and the focus distance P on the host (`CocConfig::new`, `coc.wgsl`'s
//! header). The difference this makes is bounded and tested in tests/gpu.rs.
//!
//! Buffers are kept per frame size in the context and reused by every frame of that size.

use bytemuck::{Pod, Zeroable};

use crate::dof::{CocSource, DofParams};
use crate::frame::Frame;

use crate::gpu::context::Gpu;
pub use crate::gpu::stage::StageError;
use crate::gpu::stage::{floats, Dispatch, Stage};

/// The shader's source.
pub const SHADER: &str = concat!(include_str!("../prelude.wgsl"), include_str!("coc.wgsl"));

/// Pixels per workgroup side (`@workgroup_size(16, 16)` in coc.wgsl).
const WORKGROUP: u32 = 16;

/// The `coc` stage's uniform. Keep in sync with `CocConfig` in coc.wgsl (the size test
/// guards the layout: eight 4-byte fields, a multiple of 16 bytes as uniforms need).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct CocConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// 0: the thin lens and the depth pass; 1: a painted map.
    pub source: u32,
    /// The largest |CoC| (px): `max_coc`.
    pub limit: f32,
    /// lens: K, the far-limit CoC (px), `Lens::signed_coc(∞)`. map: the CoC of a stored 1.
    pub scale: f32,
    /// lens: the focus distance P (scene units).
    pub focus: f32,
    /// map: limit/scale, the largest stored value below the limit (0 when scale is 0).
    pub cap: f32,
    pub _pad: u32,
}

impl CocConfig {
    /// The uniform for a `width`×`height` frame whose picture (display window) is
    /// `display_width` pixels wide (0: the frame's width), as `coc_plane` reads them.
    pub fn new(width: usize, height: usize, display_width: usize, params: &DofParams) -> Self {
        let limit = params.max_coc.min(crate::dof::coc::LARGEST as f32);
        let mut config = CocConfig {
            width: width as u32,
            height: height as u32,
            source: 0,
            limit,
            scale: 0.0,
            focus: 0.0,
            cap: 0.0,
            _pad: 0,
        };
        match params.source {
            CocSource::Lens(lens) => {
                // The sensor spans the display window, as on the CPU.
                let span = if display_width > 0 {
                    display_width
                } else {
                    width
                } as f64;
                // The CPU's own function at D = ∞ gives K rounded exactly as it rounds the
                // far field; it is at most LARGEST (1e6), far below the 1e15 the shader's
                // floor on P/D assumes.
                config.scale = lens.signed_coc(f64::INFINITY, span) as f32;
                config.focus = lens.focus as f32;
            }
            CocSource::Map { scale } => {
                config.source = 1;
                config.scale = scale;
                config.cap = if scale > 0.0 {
                    ((limit as f64 / scale as f64).min(f32::MAX as f64)) as f32
                } else {
                    0.0
                };
            }
        }
        config
    }
}

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
    /// [`crate::dof::coc_plane`] on the GPU; the CPU stage where the GPU cannot run it (a
    /// frame over the device's limits), counted in [`Gpu::stages_on_cpu`].
    pub fn coc_plane(&self, frame: &Frame, params: &DofParams) -> Vec<f32> {
        match self.try_coc_plane(frame, params) {
            Ok(coc) => coc,
            Err(e) => {
                self.note_cpu_stage("coc", &e);
                crate::dof::coc_plane(frame, params)
            }
        }
    }

    /// [`crate::dof::coc_plane`] on the GPU, or why it could not run.
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
    use crate::dof::Lens;

    #[test]
    fn the_config_is_eight_plain_words() {
        // Keep in sync with coc.wgsl: eight 4-byte fields, no padding, a multiple of 16.
        assert_eq!(std::mem::size_of::<CocConfig>(), 32);
        assert_eq!(std::mem::align_of::<CocConfig>(), 4);
    }

    #[test]
    fn the_far_limit_is_the_cpu_s_own() {
        let lens = Lens {
            focal_mm: 50.0,
            f_number: 2.0,
            focus: 2.0,
            sensor_mm: 36.0,
        };
        let config = CocConfig::new(1920, 4, 0, &DofParams::new(CocSource::Lens(lens)));
        // A·F/(P − F) at 1920 px over 36 mm: 34.188 px (src/dof/coc.rs).
        assert!((config.scale - 34.188).abs() < 1e-3, "{}", config.scale);
        let map = CocConfig::new(4, 4, 0, &DofParams::default());
        assert_eq!((map.source, map.scale, map.cap), (1, 32.0, 1.5));
    }
}
