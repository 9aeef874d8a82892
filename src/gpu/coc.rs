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

use std::collections::HashMap;
use std::sync::Mutex;

use bytemuck::{Pod, Zeroable};

use crate::dof::{CocSource, DofParams};
use crate::frame::Frame;

use super::Gpu;

/// The shader's source.
pub const SHADER: &str = include_str!("coc.wgsl");

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

/// The buffers of one frame size.
struct Buffers {
    config: wgpu::Buffer,
    depth: wgpu::Buffer,
    coc: wgpu::Buffer,
    readback: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// The compiled stage and its buffers, kept in the context.
pub(crate) struct CocPass {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    /// Buffers by pixel count, reused across frames of one size.
    buffers: Mutex<HashMap<usize, Buffers>>,
}

/// Frame sizes whose buffers are kept at once (a sequence has one; more are dropped).
const KEPT_SIZES: usize = 2;

impl CocPass {
    pub(crate) fn new(device: &wgpu::Device) -> CocPass {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("coc.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("coc"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(
                            std::mem::size_of::<CocConfig>() as u64
                        ),
                    },
                    count: None,
                },
                storage(1, true),
                storage(2, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("coc"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("coc"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        CocPass {
            pipeline,
            layout,
            buffers: Mutex::new(HashMap::new()),
        }
    }

    fn make_buffers(&self, device: &wgpu::Device, pixels: usize) -> Buffers {
        let bytes = (pixels.max(1) * 4) as u64;
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let config = buffer(
            "coc config",
            std::mem::size_of::<CocConfig>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let depth = buffer("coc depth", bytes, U::STORAGE | U::COPY_DST);
        let coc = buffer("coc", bytes, U::STORAGE | U::COPY_SRC);
        let readback = buffer("coc readback", bytes, U::MAP_READ | U::COPY_DST);
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("coc"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: config.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: depth.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: coc.as_entire_binding(),
                },
            ],
        });
        Buffers {
            config,
            depth,
            coc,
            readback,
            bind_group,
        }
    }
}

/// Why a GPU stage did not run (the caller runs the CPU stage instead).
#[derive(Debug)]
pub enum StageError {
    /// The plane is larger than one storage binding of this device.
    TooLarge { bytes: u64, limit: u64 },
    /// The device reported an error (validation, out of memory, lost).
    Device(String),
}

impl std::fmt::Display for StageError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StageError::TooLarge { bytes, limit } => write!(
                f,
                "a plane of {bytes} bytes exceeds the device's storage binding limit of {limit}"
            ),
            StageError::Device(e) => write!(f, "{e}"),
        }
    }
}

impl Gpu {
    /// [`crate::dof::coc_plane`] on the GPU; the CPU stage where the GPU cannot run it (a
    /// frame over the device's limits), counted in [`Gpu::stages_on_cpu`].
    pub fn coc_plane(&self, frame: &Frame, params: &DofParams) -> Vec<f32> {
        match self.try_coc_plane(frame, params) {
            Ok(coc) => coc,
            Err(_) => {
                self.note_cpu_stage();
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
        if bytes > self.max_binding() {
            return Err(StageError::TooLarge {
                bytes,
                limit: self.max_binding(),
            });
        }
        let config = CocConfig::new(
            frame.width,
            frame.height,
            frame.windows.display.width,
            params,
        );
        let pass = &self.coc;
        let mut cache = pass.buffers.lock().unwrap_or_else(|e| e.into_inner());
        if !cache.contains_key(&pixels) && cache.len() >= KEPT_SIZES {
            cache.clear();
        }
        let buffers = cache
            .entry(pixels)
            .or_insert_with(|| pass.make_buffers(&self.device, pixels));

        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        self.queue
            .write_buffer(&buffers.config, 0, bytemuck::bytes_of(&config));
        self.queue
            .write_buffer(&buffers.depth, 0, bytemuck::cast_slice(depth));
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("coc") });
        {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("coc"),
                timestamp_writes: None,
            });
            compute.set_pipeline(&pass.pipeline);
            compute.set_bind_group(0, &buffers.bind_group, &[]);
            compute.dispatch_workgroups(
                config.width.div_ceil(WORKGROUP),
                config.height.div_ceil(WORKGROUP),
                1,
            );
        }
        encoder.copy_buffer_to_buffer(&buffers.coc, 0, &buffers.readback, 0, bytes);
        self.queue.submit([encoder.finish()]);
        if let Some(error) = pollster::block_on(scope.pop()) {
            return Err(StageError::Device(error.to_string()));
        }
        read_back(&self.device, &buffers.readback, bytes)
    }
}

/// Maps `buffer`'s first `bytes`, copies them out as f32 and unmaps it.
pub(super) fn read_back(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    bytes: u64,
) -> Result<Vec<f32>, StageError> {
    let slice = buffer.slice(..bytes);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        let _ = tx.send(result);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| StageError::Device(e.to_string()))?;
    match rx.recv() {
        Ok(Ok(())) => {}
        Ok(Err(e)) => return Err(StageError::Device(e.to_string())),
        Err(_) => return Err(StageError::Device("the readback was dropped".into())),
    }
    let out = {
        let view = slice
            .get_mapped_range()
            .map_err(|e| StageError::Device(e.to_string()))?;
        bytemuck::cast_slice::<u8, f32>(&view).to_vec()
    };
    buffer.unmap();
    Ok(out)
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
