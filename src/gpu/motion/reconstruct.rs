//! reconstruct's `gather` stage on the GPU (`reconstruct.wgsl`): the twin of
//! [`crate::motion::reconstruct::gather`] (paper and dual) and
//! [`crate::motion::reconstruct::gather_2014`] (2014 and exposure), the last stage of the
//! motion-blur reconstruction.
//!
//! In: what [`reconstruct_with`] hands its gather ([`GatherInputs`]): the packed texels, the
//! pixel velocity (paper and dual), the tile grid and the exposure variant's mattes
//! ([`crate::motion::reconstruct::matte`]), all built on the CPU (tile_max, neighbor_max, dilate, pack and
//! matte stay there). In and out: the premultiplied colour, written in place where the CPU
//! writes it. Bindings, in order: the [`ReconstructConfig`] uniform, texels, velocity, tiles,
//! colour, mattes — the CPU functions' arguments; planar structs travel as their planes one
//! after the other.
//!
//! Both sides compute in f32 with the same operations in the same order and the same hash
//! ([`crate::numeric::hash`]); what can differ is the rounding of `sqrt` and division (WGSL
//! allows a few ulp), and a driver's fusing of a multiply and an add. The parity tests in
//! tests/gpu_reconstruct.rs bound the effect.
//!
//! Buffers are kept per frame shape in the context and reused by every frame of that shape.
//! The whole colour is uploaded so that the pixels the gather leaves alone come back as they
//! went (the CPU's in-place write); a frame larger than one storage binding runs on the CPU.

use std::collections::HashMap;
use std::sync::Mutex;

use crate::frame::Color;
#[cfg(doc)]
use crate::motion::reconstruct::reconstruct_with;
use crate::motion::reconstruct::{GatherInputs, ReconstructConfig};

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, kept, read_back, Caught, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(
    include_str!("../prelude.wgsl"),
    include_str!("reconstruct.wgsl")
);

/// Pixels per workgroup side (`@workgroup_size(8, 8)` in reconstruct.wgsl).
const WORKGROUP: u32 = 8;

/// What the buffers of one frame depend on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Shape {
    pixels: usize,
    tiles: usize,
    /// Floats per texel: 6 (paper, dual) or 8 (2014, exposure).
    texel: usize,
    /// Whether the gather reads the pixel velocity (paper, dual).
    velocity: bool,
    /// Whether the gather reads the mattes (exposure).
    mattes: bool,
}

/// The buffers of one frame shape.
struct Buffers {
    config: wgpu::Buffer,
    texels: wgpu::Buffer,
    velocity: wgpu::Buffer,
    tiles: wgpu::Buffer,
    color: wgpu::Buffer,
    mattes: wgpu::Buffer,
    readback: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// The compiled stage (both entry points) and its buffers, kept in the context.
pub(crate) struct ReconstructPass {
    gather: wgpu::ComputePipeline,
    gather_2014: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    buffers: Mutex<HashMap<Shape, Buffers>>,
}

impl ReconstructPass {
    pub(crate) fn new(device: &wgpu::Device) -> ReconstructPass {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("reconstruct.wgsl"),
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
            label: Some("reconstruct"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(
                            std::mem::size_of::<ReconstructConfig>() as u64,
                        ),
                    },
                    count: None,
                },
                storage(1, true),
                storage(2, true),
                storage(3, true),
                storage(4, false),
                storage(5, true),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("reconstruct"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        ReconstructPass {
            gather: pipeline("gather"),
            gather_2014: pipeline("gather_2014"),
            layout,
            buffers: Mutex::new(HashMap::new()),
        }
    }

    fn make_buffers(&self, device: &wgpu::Device, shape: Shape) -> Buffers {
        let floats = |n: usize| (n.max(1) * 4) as u64;
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
            "reconstruct config",
            std::mem::size_of::<ReconstructConfig>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let input = U::STORAGE | U::COPY_DST;
        let texels = buffer(
            "reconstruct texels",
            floats(shape.pixels * shape.texel),
            input,
        );
        // The 2014 gather does not read it: a word, to fill the binding.
        let velocity_floats = if shape.velocity { 2 * shape.pixels } else { 1 };
        let velocity = buffer("reconstruct velocity", floats(velocity_floats), input);
        let tiles = buffer("reconstruct tiles", floats(2 * shape.tiles), input);
        let color_bytes = floats(4 * shape.pixels);
        let color = buffer(
            "reconstruct color",
            color_bytes,
            input | U::STORAGE | U::COPY_SRC,
        );
        let readback = buffer(
            "reconstruct readback",
            color_bytes,
            U::MAP_READ | U::COPY_DST,
        );
        // Other variants do not read it: a word, to fill the binding.
        let matte_floats = if shape.mattes { 6 * shape.pixels } else { 1 };
        let mattes = buffer("reconstruct mattes", floats(matte_floats), input);
        let entries: Vec<wgpu::BindGroupEntry> =
            [&config, &texels, &velocity, &tiles, &color, &mattes]
                .into_iter()
                .enumerate()
                .map(|(binding, buffer)| wgpu::BindGroupEntry {
                    binding: binding as u32,
                    resource: buffer.as_entire_binding(),
                })
                .collect();
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("reconstruct"),
            layout: &self.layout,
            entries: &entries,
        });
        Buffers {
            config,
            texels,
            velocity,
            tiles,
            color,
            mattes,
            readback,
            bind_group,
        }
    }
}

impl Gpu {
    /// The gather ([`GatherInputs::gather`]) on the GPU, in place, or why it could not run
    /// (then `color` is untouched).
    pub fn try_reconstruct_gather(
        &self,
        config: &ReconstructConfig,
        inputs: &GatherInputs<'_>,
        color: &mut Color,
    ) -> Result<(), StageError> {
        let pixels = config.width as usize * config.height as usize;
        if pixels == 0 {
            return Ok(());
        }
        let (texels, velocity, tiles, mattes, entry): (&[f32], _, _, &[f32], _) = match *inputs {
            GatherInputs::Paper {
                texels,
                velocity,
                neighbors,
            } => (
                bytemuck::cast_slice(texels),
                Some(velocity),
                neighbors,
                &[],
                false,
            ),
            GatherInputs::Stable {
                texels,
                mattes,
                tiles,
            } => (
                bytemuck::cast_slice(texels),
                None,
                tiles,
                bytemuck::cast_slice(mattes),
                true,
            ),
        };
        let shape = Shape {
            pixels,
            tiles: tiles.x.len(),
            texel: texels.len() / pixels,
            velocity: velocity.is_some(),
            mattes: !mattes.is_empty(),
        };
        let largest = (texels.len().max(4 * pixels) * 4) as u64;
        if largest > self.max_binding() {
            return Err(StageError::TooLarge {
                bytes: largest,
                limit: self.max_binding(),
            });
        }
        let pass = self.compiled("reconstruct", ReconstructPass::new);
        // Errors from here on, the buffers' creation included, come back as a StageError
        // (the caller runs the CPU gather): out of memory as well as validation.
        let caught = Caught::push(&self.device);
        let mut cache = pass.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let buffers = kept(&mut cache, &shape, || {
            pass.make_buffers(&self.device, shape)
        });

        let mut clock = std::time::Instant::now();
        let queue = &self.queue;
        let plane = (pixels * 4) as u64;
        queue.write_buffer(&buffers.config, 0, bytemuck::bytes_of(config));
        queue.write_buffer(&buffers.texels, 0, bytemuck::cast_slice(texels));
        if !mattes.is_empty() {
            queue.write_buffer(&buffers.mattes, 0, bytemuck::cast_slice(mattes));
        }
        if let Some(velocity) = velocity {
            queue.write_buffer(&buffers.velocity, 0, bytemuck::cast_slice(&velocity.x));
            queue.write_buffer(&buffers.velocity, plane, bytemuck::cast_slice(&velocity.y));
        }
        let tile_plane = (tiles.x.len() * 4) as u64;
        queue.write_buffer(&buffers.tiles, 0, bytemuck::cast_slice(&tiles.x));
        queue.write_buffer(&buffers.tiles, tile_plane, bytemuck::cast_slice(&tiles.y));
        // Alpha, when the frame has none, is not written: the gather's alpha is dropped then.
        let planes = [
            Some(&color.r),
            Some(&color.g),
            Some(&color.b),
            color.a.as_ref(),
        ];
        for (p, channel) in planes.iter().enumerate() {
            if let Some(channel) = channel {
                queue.write_buffer(
                    &buffers.color,
                    p as u64 * plane,
                    bytemuck::cast_slice(channel),
                );
            }
        }
        self.uploaded(&mut clock)?;
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("reconstruct"),
            });
        {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("reconstruct gather"),
                timestamp_writes: None,
            });
            compute.set_pipeline(if entry {
                &pass.gather_2014
            } else {
                &pass.gather
            });
            compute.set_bind_group(0, &buffers.bind_group, &[]);
            compute.dispatch_workgroups(
                config.width.div_ceil(WORKGROUP),
                config.height.div_ceil(WORKGROUP),
                1,
            );
        }
        self.computed(&mut encoder, "reconstruct", &mut clock)?;
        let channels = if color.a.is_some() { 4 } else { 3 };
        let bytes = channels * plane;
        encoder.copy_buffer_to_buffer(&buffers.color, 0, &buffers.readback, 0, bytes);
        queue.submit([encoder.finish()]);
        if let Err(error) = caught.check() {
            // Buffers that failed are not kept for the next frame.
            cache.remove(&shape);
            return Err(error);
        }
        let out = floats(read_back(&self.device, &buffers.readback, bytes)?);
        self.mark(|t| &mut t.readback_ms, &mut clock)?;
        let mut planes = out.chunks_exact(pixels);
        for channel in [
            Some(&mut color.r),
            Some(&mut color.g),
            Some(&mut color.b),
            color.a.as_mut(),
        ]
        .into_iter()
        .flatten()
        {
            channel.copy_from_slice(planes.next().expect("one plane per channel"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::reconstruct as cpu;

    #[test]
    fn the_config_is_eleven_plain_words_in_both_languages() {
        // Keep in sync with reconstruct.wgsl: eleven 4-byte fields, no padding.
        assert_eq!(std::mem::size_of::<ReconstructConfig>(), 44);
        assert_eq!(std::mem::align_of::<ReconstructConfig>(), 4);
        crate::gpu::layout::assert_same_layout!(
            ReconstructConfig,
            SHADER,
            "ReconstructConfig",
            [width, height, tile, k, shutter, offset, taps, inv_soft_z, jitter, variant, seed]
        );
    }

    #[test]
    fn the_shader_s_constants_are_the_cpu_s() {
        let has = |line: String| assert!(SHADER.contains(&line), "reconstruct.wgsl lacks {line}");
        has(format!("const HALF_PIXEL: f32 = {:?};", cpu::HALF_PIXEL));
        has(format!("const EPSILON: f32 = {:?};", cpu::EPSILON));
        has(format!(
            "const MOVING_SQUARED_BITS: u32 = {:#x}u;",
            cpu::config::MOVING_SQUARED.to_bits()
        ));
        has(format!(
            "const MAX_TAPS_PER_SIDE: u32 = {}u;",
            cpu::config::MAX_TAPS_PER_SIDE
        ));
        has(format!(
            "const TAP_SPACING: f32 = {:?};",
            cpu::config::TAP_SPACING
        ));
        has(format!(
            "const COVER_SLOPE: f32 = {:?};",
            cpu::gather_2014::COVER_SLOPE
        ));
        has(format!(
            "const SALT_TILE: u32 = {:#x}u;",
            cpu::gather_2014::SALT_TILE
        ));
        has(format!(
            "const SALT_TAPS: u32 = {:#x}u;",
            cpu::gather_2014::SALT_TAPS
        ));
        has(format!(
            "const SALT_PAPER: u32 = {:#x}u;",
            cpu::gather_2012::SALT_PAPER
        ));
        for (name, variant) in [("PAPER", cpu::Variant::Paper), ("DUAL", cpu::Variant::Dual)] {
            has(format!("const {name}: u32 = {}u;", variant.code()));
        }
        has(format!(
            "const EXPOSURE: u32 = {}u;",
            cpu::Variant::Exposure.code()
        ));
    }
}
