//! Motion blur's `scatter` pass on the GPU (`scatter.wgsl`): the twin of
//! [`crate::motion::scatter::scatter`] (Guertin & Nowrouzezahrai's curve scatter), every
//! normalisation (paper, exposure), curve kind (Bézier, arc) and weight (box, Gaussian), the
//! flatness-adaptive segment counts and the shutter offset, stage for stage:
//!
//! 1. `reach`: per pixel, the CPU's motion test (`Scatter::motion`: the curve's extent over
//!    the exposure against [`STILL`]); moving pixels join a list through an atomic counter
//!    and raise a per-channel bound on |colour|. `prepare` turns the count into the size of
//!    the next dispatch (indirect), so a still frame or still pixels cost no curve work.
//! 2. `accumulate`: one invocation per moving pixel builds its path as `Scatter::path` does
//!    (segments, weights, depths, scaling to `max_curve`, the exposure share) and walks each
//!    segment with [`crate::motion::line`]'s coverage model (a column's exact length, split
//!    linearly between the two nearest pixel centres), depth-tested against the frame, into
//!    fixed-point sums.
//! 3. `resolve`: per pixel, eq. 4 or the exposure normalisation, with `behind` (the search
//!    along the motion for a farther surface) where a pixel is not wholly covered.
//!
//! Bindings, in order: the [`ScatterConfig`] uniform (the CPU's own struct), colour, depth,
//! prev, next (the CPU's inputs, planes one after the other), then `state`, the moving list,
//! the five sums and the output colour.
//!
//! **Why a compute rasteriser with integer atomics, not the render pipeline's lines.** The
//! paper draws its segments as GL lines with additive blending into a float target. Measured
//! (docs/CRATES.md): lavapipe draws a 1-px line as a rectangle (coverage = Euclidean length) where
//! GL and many GPUs use the longer axis (~15 % less energy), so the same frame gives other
//! images on other drivers; and float blending adds in whatever order the hardware retires
//! fragments, so not even one driver repeats itself bit for bit. A compute rasteriser instead
//! runs our own coverage model — the CPU's, so the two can be compared at all — and
//! deposits into **64-bit fixed-point integer sums**: integer addition is associative, so the
//! result is the same for any dispatch order, workgroup size or thread count, bit for bit, by
//! construction (tests/gpu_scatter.rs checks two runs, two workgroup sizes and a reversed
//! list). WGSL has neither 64-bit integers nor 64-bit atomics, so each sum is two
//! `atomic<u32>` words: `atomicAdd` on the low word returns the old value, and where the
//! addition wrapped the high word takes the carry (with the high part); in two's complement,
//! so negative colours add too, and the sum modulo 2⁶⁴ does not depend on order. Float
//! atomics (`SHADER_FLOAT32_ATOMIC`) would be order-dependent; a sort of deposits by pixel
//! would be deterministic but costs a global sort per frame.
//!
//! **The fixed point.** 32 fractional bits, so a sum holds |Σ| < 2³¹ and a deposit is rounded
//! to 2⁻³² of its channel's scale. Each colour channel is scaled by 2^−e, the power of two
//! just above the largest |colour| of a moving pixel in that channel (found by `reach` with
//! `atomicMax` on the bits, so exactly, and the scaling loses nothing): a deposit
//! (coverage × weight × colour) is then below its weight in magnitude. The weights are at
//! most ~1.4 per column and pixel, so a pixel's weight sum stays below 2³¹ unless more than
//! ~10⁹ curve columns cross it (π·max_curve² moving pixels × 64 segments is 1.3·10⁷ at the
//! default 256 px). Resolution: 2⁻³² ≈ 2.3·10⁻¹⁰ of the channel's bound per deposit, far
//! below f32 for any real frame; a frame whose bound is huge (the numeric policy's 10³⁰)
//! loses the small colours of the pixels those huge ones reach, relative to that bound — a
//! difference of 10⁻¹⁰ of the frame's range, which the parity test bounds. Resolve computes
//! in the scaled units and scales back at the end, so sums of huge colours stay finite.
//!
//! **The f32 form.** WGSL has no f64, and the CPU's geometry is absolute f64 (positions may
//! lie 10¹² px off-screen). Here every position is taken relative to the corner of the
//! moving pixel (p(0) = (½, ½), pixel boundaries at integers), so after the scaling to
//! `max_curve` every point of a curve lies within `max_curve` px of the origin and f32 holds
//! it to ~2⁻¹⁵ px; far positions lose only their own relative rounding (6·10⁻⁸), which the
//! scaling shrinks with them. The arc's points are formed in chord form about p(0) (see
//! `arc_at` in the shader) because the CPU's centre + r·(cos, sin) cancels digits of the
//! radius (up to 10⁷ px), and its turns from p(0) to p(±1) are taken at once (atan2 of the
//! cross and dot products of the two radii) rather than as differences of absolute angles
//! (measured: the arcs' largest difference from the CPU fell from 1.8·10⁻⁴ to 3·10⁻⁵ of the
//! range). The CPU keeps its f64: the two agree to f32 rounding of the
//! geometry, which moves a coverage by ~10⁻⁵ of a pixel; where a rounding moves a decision (a
//! segment count at a flatness boundary, a depth test on its threshold, the still test at
//! exactly [`STILL`]) a pixel differs by more, rarely; tests/gpu_scatter.rs states and
//! measures both. (Making the CPU follow the f32 form would change nothing it measures and
//! give up what f64 buys it: sums that repeat a colour exactly.)
//!
//! Other differences from the CPU, none visible in output: the CPU visits curves tile by tile
//! and keeps f64 sums; the GPU visits each curve once (the sums make order immaterial). A
//! segment whose depth is not finite at either end draws nothing, as on the CPU (where its
//! depth change is NaN and fails every test). The CPU's block-deepest shortcut in `behind`
//! only skips searches that find nothing and is dropped.
//!
//! A frame larger than one storage binding (its colour, 16 bytes a pixel: 128 MiB on
//! lavapipe, a 4K frame), or a device with fewer than [`STORAGE_BUFFERS`] storage buffers per
//! stage, runs on the CPU, counted and warned about, as every twin does.

use std::collections::HashMap;
use std::sync::Mutex;

use crate::frame::Color;
use crate::motion::scatter::ScatterConfig;

#[cfg(doc)]
use crate::motion::scatter::STILL;

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, kept, read_back, Caught, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(
    include_str!("../prelude.wgsl"),
    include_str!("scatter.wgsl"),
    include_str!("curve.wgsl")
);

/// Storage buffers the stages bind (every binding but the uniform).
pub const STORAGE_BUFFERS: u32 = 12;

/// Words of the `state` buffer (keep in sync with scatter.wgsl): the moving count, the
/// accumulate dispatch (x, y, z), the colour bounds (R, G, B, A), the host's flags.
const STATE_WORDS: usize = 16;
const DISPATCH: u64 = 1;
const FLAGS: usize = 8;
const OPAQUE: u32 = 1;
const HAS_Z: u32 = 2;
/// Most workgroups along one dispatch dimension (WebGPU's limit).
const MOST_GROUPS: u32 = 65535;

/// How the stages are dispatched: their workgroup size and whether `accumulate` walks the
/// moving list backwards. The output must not depend on either (a test hook; runs use
/// [`Order::default`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Order {
    pub workgroup: u32,
    pub reversed: bool,
}

impl Default for Order {
    fn default() -> Self {
        Order {
            workgroup: 64,
            reversed: false,
        }
    }
}

/// The buffers of one frame size.
struct Buffers {
    config: wgpu::Buffer,
    color: wgpu::Buffer,
    depth: wgpu::Buffer,
    prev: wgpu::Buffer,
    next: wgpu::Buffer,
    state: wgpu::Buffer,
    /// The accumulate dispatch, copied out of `state` (a buffer bound for writing cannot be
    /// the indirect argument of a dispatch that binds it).
    indirect: wgpu::Buffer,
    sums: Vec<wgpu::Buffer>,
    out: wgpu::Buffer,
    readback: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// The compiled stages (one pipeline per entry point) and their buffers by pixel count.
pub(crate) struct ScatterPass {
    order: Order,
    reach: wgpu::ComputePipeline,
    prepare: wgpu::ComputePipeline,
    accumulate: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    buffers: Mutex<HashMap<usize, Buffers>>,
}

impl ScatterPass {
    pub(crate) fn new(device: &wgpu::Device, order: Order) -> ScatterPass {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("scatter.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let mut entries = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(std::mem::size_of::<ScatterConfig>() as u64),
            },
            count: None,
        }];
        for binding in 1..=STORAGE_BUFFERS {
            entries.push(wgpu::BindGroupLayoutEntry {
                binding,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    // Colour, depth, prev and next are read; the rest written.
                    ty: wgpu::BufferBindingType::Storage {
                        read_only: binding <= 4,
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            });
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scatter"),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scatter"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let constants = [
            ("WORKGROUP", order.workgroup as f64),
            ("REVERSED", order.reversed as u32 as f64),
        ];
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants: &constants,
                    ..Default::default()
                },
                cache: None,
            })
        };
        ScatterPass {
            order,
            reach: pipeline("reach"),
            prepare: pipeline("prepare"),
            accumulate: pipeline("accumulate"),
            resolve: pipeline("resolve"),
            layout,
            buffers: Mutex::new(HashMap::new()),
        }
    }

    fn make_buffers(&self, device: &wgpu::Device, pixels: usize) -> Buffers {
        let bytes = |words: usize| (words.max(1) * 4) as u64;
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let input = U::STORAGE | U::COPY_DST;
        let config = buffer(
            "scatter config",
            std::mem::size_of::<ScatterConfig>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let color = buffer("scatter color", bytes(4 * pixels), input);
        let depth = buffer("scatter depth", bytes(pixels), input);
        let prev = buffer("scatter prev", bytes(3 * pixels), input);
        let next = buffer("scatter next", bytes(3 * pixels), input);
        let state = buffer("scatter state", bytes(STATE_WORDS), input | U::COPY_SRC);
        let indirect = buffer("scatter dispatch", 12, U::INDIRECT | U::COPY_DST);
        let moving = buffer("scatter moving", bytes(pixels), U::STORAGE);
        let sums: Vec<_> = ["scatter sum r", "scatter sum g", "scatter sum b"]
            .into_iter()
            .chain(["scatter sum a", "scatter sum w"])
            .map(|label| buffer(label, bytes(2 * pixels), input))
            .collect();
        let out = buffer("scatter out", bytes(4 * pixels), U::STORAGE | U::COPY_SRC);
        let readback = buffer(
            "scatter readback",
            bytes(4 * pixels),
            U::MAP_READ | U::COPY_DST,
        );
        let bound: Vec<&wgpu::Buffer> = [&config, &color, &depth, &prev, &next, &state, &moving]
            .into_iter()
            .chain(&sums)
            .chain([&out])
            .collect();
        let entries: Vec<wgpu::BindGroupEntry> = bound
            .iter()
            .enumerate()
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding: binding as u32,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scatter"),
            layout: &self.layout,
            entries: &entries,
        });
        Buffers {
            config,
            color,
            depth,
            prev,
            next,
            state,
            indirect,
            sums,
            out,
            readback,
            bind_group,
        }
    }

    /// Workgroups for one invocation per pixel: x × y with x ≤ [`MOST_GROUPS`].
    fn groups(&self, pixels: usize) -> (u32, u32) {
        let groups = (pixels as u64).div_ceil(self.order.workgroup as u64) as u32;
        let x = groups.min(MOST_GROUPS);
        (x, if x == 0 { 0 } else { groups.div_ceil(x) })
    }
}

impl Gpu {
    /// Scatter's three stages on the GPU ([`crate::motion::scatter::stages`]' arguments and
    /// result), dispatched in `order` (a test hook: the output must not depend on it), or why
    /// they could not run.
    pub fn try_scatter(
        &self,
        config: &ScatterConfig,
        color: &Color,
        depth: &[f32],
        positions: [&crate::frame::Positions; 2],
        order: Order,
    ) -> Result<Color, StageError> {
        if config.width == 0 || config.height == 0 {
            return Ok(color.clone());
        }
        self.run_scatter(config, color, depth, positions, order)
    }

    fn run_scatter(
        &self,
        config: &ScatterConfig,
        color: &Color,
        depth: &[f32],
        positions: [&crate::frame::Positions; 2],
        order: Order,
    ) -> Result<Color, StageError> {
        let pixels = config.width as usize * config.height as usize;
        let largest = (16 * pixels) as u64;
        if largest > self.max_binding() {
            return Err(StageError::TooLarge {
                bytes: largest,
                limit: self.max_binding(),
            });
        }
        let allowed = self.device.limits().max_storage_buffers_per_shader_stage;
        if allowed < STORAGE_BUFFERS {
            return Err(StageError::Device(format!(
                "scatter binds {STORAGE_BUFFERS} storage buffers and the device allows {allowed}"
            )));
        }
        // Errors from here on, the pipelines' and buffers' creation included, come back as a
        // StageError (the caller runs the CPU pass): out of memory as well as validation.
        let caught = Caught::push(&self.device);
        let pass = if order == Order::default() {
            self.compiled("scatter", |device| ScatterPass::new(device, order))
        } else {
            std::sync::Arc::new(ScatterPass::new(&self.device, order))
        };
        let mut cache = pass.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let buffers = kept(&mut cache, &pixels, || {
            pass.make_buffers(&self.device, pixels)
        });

        let mut clock = std::time::Instant::now();
        let queue = &self.queue;
        let plane = (pixels * 4) as u64;
        queue.write_buffer(&buffers.config, 0, bytemuck::bytes_of(config));
        let ones;
        let alpha = match &color.a {
            Some(a) => a,
            None => {
                ones = vec![1.0f32; pixels];
                &ones
            }
        };
        for (k, channel) in [&color.r, &color.g, &color.b, alpha]
            .into_iter()
            .enumerate()
        {
            queue.write_buffer(
                &buffers.color,
                k as u64 * plane,
                bytemuck::cast_slice(channel),
            );
        }
        queue.write_buffer(&buffers.depth, 0, bytemuck::cast_slice(depth));
        let has_z = positions.iter().all(|p| p.z.is_some());
        for (buffer, p) in [&buffers.prev, &buffers.next].into_iter().zip(positions) {
            queue.write_buffer(buffer, 0, bytemuck::cast_slice(&p.x));
            queue.write_buffer(buffer, plane, bytemuck::cast_slice(&p.y));
            if let (true, Some(z)) = (has_z, &p.z) {
                queue.write_buffer(buffer, 2 * plane, bytemuck::cast_slice(z));
            }
        }
        // Where every pixel is opaque, alpha sums equal weight sums: four sums, as the CPU.
        let opaque = color.a.as_ref().is_none_or(|a| a.iter().all(|&v| v == 1.0));
        let mut state = [0u32; STATE_WORDS];
        state[FLAGS] = if opaque { OPAQUE } else { 0 } | if has_z { HAS_Z } else { 0 };
        queue.write_buffer(&buffers.state, 0, bytemuck::cast_slice(&state));
        self.uploaded(&mut clock)?;
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("scatter"),
            });
        for sum in &buffers.sums {
            encoder.clear_buffer(sum, 0, None);
        }
        let (x, y) = pass.groups(pixels);
        {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("scatter reach"),
                timestamp_writes: None,
            });
            compute.set_bind_group(0, &buffers.bind_group, &[]);
            compute.set_pipeline(&pass.reach);
            compute.dispatch_workgroups(x, y, 1);
            compute.set_pipeline(&pass.prepare);
            compute.dispatch_workgroups(1, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&buffers.state, 4 * DISPATCH, &buffers.indirect, 0, 12);
        {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("scatter accumulate"),
                timestamp_writes: None,
            });
            compute.set_bind_group(0, &buffers.bind_group, &[]);
            compute.set_pipeline(&pass.accumulate);
            compute.dispatch_workgroups_indirect(&buffers.indirect, 0);
            compute.set_pipeline(&pass.resolve);
            compute.dispatch_workgroups(x, y, 1);
        }
        self.computed(&mut encoder, "scatter", &mut clock)?;
        let channels = if color.a.is_some() { 4 } else { 3 };
        let bytes = channels * plane;
        encoder.copy_buffer_to_buffer(&buffers.out, 0, &buffers.readback, 0, bytes);
        queue.submit([encoder.finish()]);
        if let Err(error) = caught.check() {
            // Buffers that failed are not kept for the next frame.
            cache.remove(&pixels);
            return Err(error);
        }
        let out = floats(read_back(&self.device, &buffers.readback, bytes)?);
        self.mark(|t| &mut t.readback_ms, &mut clock)?;
        let mut planes = out.chunks_exact(pixels).map(<[f32]>::to_vec);
        let mut plane = || planes.next().expect("one plane per channel");
        Ok(Color {
            r: plane(),
            g: plane(),
            b: plane(),
            a: color.a.is_some().then(plane),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::scatter as cpu;

    #[test]
    fn the_config_is_the_cpu_s_thirteen_words_in_both_languages() {
        // Keep in sync with scatter.wgsl: thirteen 4-byte fields, no padding.
        assert_eq!(std::mem::size_of::<ScatterConfig>(), 52);
        assert_eq!(std::mem::align_of::<ScatterConfig>(), 4);
        crate::gpu::layout::assert_same_layout!(
            ScatterConfig,
            SHADER,
            "ScatterConfig",
            [
                width,
                height,
                shutter,
                offset,
                segments,
                sigma,
                gaussian,
                background_weight,
                exposure,
                arc,
                max_curve,
                flatness,
                depth_tolerance
            ]
        );
    }

    #[test]
    fn the_shader_s_constants_are_the_cpu_s() {
        let has = |line: String| assert!(SHADER.contains(&line), "scatter.wgsl lacks {line}");
        has(format!("const STILL: f32 = {:?};", cpu::STILL as f32));
        has(format!(
            "const MOST_SEGMENTS: u32 = {}u;",
            cpu::MOST_SEGMENTS
        ));
        has(format!(
            "const COVERED: f32 = {:?};",
            cpu::config::COVERED as f32
        ));
        has(format!(
            "const COLLINEAR: f32 = {:?};",
            crate::motion::curve::COLLINEAR as f32
        ));
        has(format!(
            "const LARGEST_RADIUS: f32 = {:?};",
            crate::motion::curve::LARGEST_RADIUS as f32
        ));
        has(format!("const TAU: f32 = {:?};", std::f32::consts::TAU));
        has(format!("const PI: f32 = {:?};", std::f32::consts::PI));
        has(format!("const FLAGS: u32 = {FLAGS}u;"));
        has(format!("const DISPATCH: u32 = {DISPATCH}u;"));
        has(format!("const OPAQUE: u32 = {OPAQUE}u;"));
        has(format!("const HAS_Z: u32 = {HAS_Z}u;"));
        has(format!("const MOST_GROUPS: u32 = {MOST_GROUPS}u;"));
        has(format!(
            "@binding({STORAGE_BUFFERS}) var<storage, read_write> out"
        ));
        // The private path arrays hold the most segments.
        has(format!(
            "var<private> lengths: array<f32, {}>;",
            cpu::MOST_SEGMENTS
        ));
        has(format!(
            "var<private> points: array<vec2<f32>, {}>;",
            cpu::MOST_SEGMENTS + 1
        ));
    }
}
