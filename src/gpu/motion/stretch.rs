//! stretch on the GPU (`stretch.wgsl`): the twin of [`crate::motion::stretch`], its four
//! stages under their CPU names — `texture_blur` and `move_vertices` as compute dispatches,
//! `rasterise` as a render pipeline, `cover` as a compute dispatch over its targets — over
//! the same buffers: the [`StretchConfig`] uniform, the colour planes (R, G, B, A one after
//! the other; an opaque alpha where the frame has none), depth and velocity (interleaved x, y
//! as the CPU's `[[f32; 2]]`) in; the pre-blurred planes, the vertices (shift x, shift y,
//! alpha: the CPU's `([f32; 2], f32)`), `swept` and the covered colour out.
//!
//! **rasterise: a render pipeline, not a compute rasteriser.** The CPU draws every untorn
//! triangle with a moved vertex over the sharp frame, farthest first (the depth of its
//! farthest corner, triangle index as the tie-break), alpha blended, each fragment
//! depth-tested against the frame without writing depth. The result depends on the order of
//! the blends, so the GPU must blend in that same fixed order whatever its scheduling (the
//! project's rule: bit-identical output for the same inputs on the same backend):
//! - a render pipeline gives that for free: Vulkan, Metal and D3D12 blend the fragments of
//!   one pixel in primitive order;
//! - a compute rasteriser would have to rebuild that order: per-pixel fragment lists sorted
//!   by triangle rank and then blended, or tiles each walking the whole sorted list (the
//!   CPU's bands). Fragments per pixel are unbounded (128-px slivers overlapping by the
//!   hundred in the stress frames), so a list needs a count pass, a prefix sum, a fill and a
//!   per-pixel sort — four more stages to get what the blender does in order — and a tile
//!   walk costs triangles × tiles. Judged on that cost, not built.
//!
//! Coverage is the CPU's, not the fixed-function rasteriser's. Drawing the triangles
//! themselves was measured first (the frames of tests/gpu_stretch.rs, lavapipe): lavapipe
//! owns centres on top-left edges on screen where the CPU's [`crate::motion::triangle`] owns
//! bottom-right ones (its "top-left" is in a y-up frame), and unmoved edges run exactly
//! through pixel centres beside triangles that are not drawn, so 1–24 % of pixels differed;
//! with the image turned half a turn to swap the rules, the sub-pixel snapping (1/256 px)
//! still flipped up to 10 % of the pixels of the stress frames, whose 128-px slivers have
//! long edges. So each triangle is drawn as its bounding box grown to whole pixels and one
//! more, and the fragment shader decides coverage with the CPU's edge functions and tie rule
//! and takes the CPU's barycentric weights from them; fragments outside are discarded. The
//! edge functions run in f32 on corners relative to the pixel centre (integer offsets, exact,
//! plus the shifts), so unmoved edges are exact; a shift too small to survive the CPU's f64
//! sum `x + ½ + shift` (1e-30 px velocities beside 1e7 px ones in the stress frames) is
//! rounded as that sum rounds it (`absorbed` in stretch.wgsl). With that, the same rasteriser
//! restated in Rust (a check written while building this, not kept) gave lavapipe's output
//! bit for bit, and the GPU is within 3e-5 of the range of the CPU on every frame of the
//! parity tests. The cost is the box's area instead of
//! the triangle's — what the CPU's loop over the box pays too.
//!
//! What the render pipeline cannot do alone is the sort itself. `select_triangles` (compute)
//! gives every triangle a key — the ordered bits of its farthest corner's depth, or "not
//! drawn" — and the host sorts the drawn ones (key descending, index ascending: a total
//! order, so any sort gives the same list) and uploads the list the vertex shader reads.
//! The host's share is one pass over the keys (4 bytes a triangle, read back) and a parallel
//! sort of the drawn ones, which touch moving silhouettes only; it was not timed apart from
//! the draw (BENCHMARKS.md has the stage's whole time on lavapipe). A GPU sort (a bitonic
//! network: log²(n)/2 dispatches) is the way to drop the round trip if it ever shows on a
//! hardware GPU.
//!
//! Blending: the sharp frame is drawn first (one full-screen triangle, no blending), then the
//! triangles, each fragment writing R, G, B with its alpha into one `Rgba32Float` target and
//! the alpha plane with the same alpha into a second (a target's blend factor is its own
//! source alpha), blended `src·α + dst·(1 − α)` — the CPU's `mix` up to rounding. Blending
//! 32-bit float targets needs `FLOAT32_BLENDABLE`, requested where the adapter has it; without
//! it, or for a frame over the device's texture or binding limits, the CPU stages run
//! (counted in [`Gpu::stages_on_cpu`], with the first reason kept for the run's warning).
//!
//! Where the frame is not wholly covered (an alpha below 1), the CPU's fragments are not
//! blended there but leave `swept` (motion x, y, depth, 1; the last fragment's) to `cover`.
//! `draw_fragment` discards those; the same triangles are drawn a second time, in the same
//! order, into a third `Rgba32Float` target by `sweep_fragment`, unblended, so the last
//! fragment stays as on the CPU. A second pass rather than a third target in the first:
//! WebGPU's least limit on a pass's colour bytes per sample is 32, which the two blended
//! targets fill (asking for more would send stretch to the CPU on devices that have only
//! that). Where every pixel is wholly covered (the host sees the alpha plane), the second
//! pass only clears. `cover` then reads the three targets as textures and writes the four
//! planes into one buffer, which is read back.
//!
//! Where the two sides differ, and by how much, is the business of tests/gpu_stretch.rs:
//! rounding (f32 edge functions against f64, the blend's form, WGSL's `sqrt` and division,
//! fused multiply-adds), and in rare pixels a decision that rounding moves.

use std::collections::HashMap;
use std::sync::Mutex;

use rayon::prelude::*;

use crate::motion::stretch::{partly_covered, StretchConfig};

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, kept, read_back, Caught, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(
    include_str!("../prelude.wgsl"),
    include_str!("stretch.wgsl")
);

/// Invocations per workgroup of the 1-D stages (`GROUP` in stretch.wgsl).
const GROUP: u32 = 256;
/// Pixels per workgroup side of texture_blur (`@workgroup_size(8, 8)`).
const TILE: u32 = 8;
/// Workgroups per row of a 1-D dispatch (WebGPU's least limit per dimension).
const ROW: u32 = 65535;
/// The key of a triangle that is not drawn (`NOT_DRAWN` in stretch.wgsl).
pub const NOT_DRAWN: u32 = 0;
/// The render targets: R, G, B and the blend alpha; the alpha plane and the blend alpha;
/// `swept` (velocity x, y, depth, 1 where swept).
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// What the buffers of one frame depend on: its size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Shape {
    width: u32,
    height: u32,
}

impl Shape {
    fn pixels(self) -> u64 {
        self.width as u64 * self.height as u64
    }

    fn triangles(self) -> u64 {
        2 * (self.width.max(1) as u64 - 1) * (self.height.max(1) as u64 - 1)
    }
}

/// The buffers and targets of one frame size.
struct Buffers {
    config: wgpu::Buffer,
    planes: wgpu::Buffer,
    z: wgpu::Buffer,
    v: wgpu::Buffer,
    /// Written and read on the device only (through the bind groups).
    _blurred: wgpu::Buffer,
    _vertices: wgpu::Buffer,
    keys: wgpu::Buffer,
    range: wgpu::Buffer,
    order: wgpu::Buffer,
    /// The drawn colour, the drawn alpha plane, `swept` (read through `views`).
    _targets: [wgpu::Texture; 3],
    views: [wgpu::TextureView; 3],
    covered: wgpu::Buffer,
    keys_readback: wgpu::Buffer,
    color_readback: wgpu::Buffer,
    compute: wgpu::BindGroup,
    render: wgpu::BindGroup,
    cover: wgpu::BindGroup,
}

/// The compiled stages and their buffers, kept in the context.
pub(crate) struct StretchPass {
    frame_range: wgpu::ComputePipeline,
    texture_blur: wgpu::ComputePipeline,
    move_vertices: wgpu::ComputePipeline,
    select_triangles: wgpu::ComputePipeline,
    sharp: wgpu::RenderPipeline,
    draw: wgpu::RenderPipeline,
    sweep: wgpu::RenderPipeline,
    cover: wgpu::ComputePipeline,
    compute_layout: wgpu::BindGroupLayout,
    render_layout: wgpu::BindGroupLayout,
    cover_layout: wgpu::BindGroupLayout,
    buffers: Mutex<HashMap<Shape, Buffers>>,
}

fn entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl StretchPass {
    pub(crate) fn new(device: &wgpu::Device) -> StretchPass {
        use wgpu::BufferBindingType::{Storage, Uniform};
        use wgpu::ShaderStages as S;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("stretch.wgsl"),
            source: wgpu::ShaderSource::Wgsl(SHADER.into()),
        });
        let read = Storage { read_only: true };
        let write = Storage { read_only: false };
        let compute_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("stretch compute"),
            entries: &[
                entry(0, S::COMPUTE, Uniform),
                entry(1, S::COMPUTE, read),
                entry(2, S::COMPUTE, read),
                entry(3, S::COMPUTE, read),
                entry(4, S::COMPUTE, write),
                entry(5, S::COMPUTE, write),
                entry(6, S::COMPUTE, write),
                entry(7, S::COMPUTE, write),
            ],
        });
        let render_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("stretch rasterise"),
            entries: &[
                entry(0, S::VERTEX_FRAGMENT, Uniform),
                entry(1, S::FRAGMENT, read),
                entry(2, S::FRAGMENT, read),
                entry(3, S::FRAGMENT, read),
                entry(11, S::VERTEX_FRAGMENT, read),
                entry(12, S::FRAGMENT, read),
                entry(13, S::VERTEX, read),
            ],
        });
        let texture = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: S::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let cover_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("stretch cover"),
            entries: &[
                entry(0, S::COMPUTE, Uniform),
                entry(1, S::COMPUTE, read),
                entry(2, S::COMPUTE, read),
                entry(3, S::COMPUTE, read),
                texture(20),
                texture(21),
                texture(22),
                entry(23, S::COMPUTE, write),
            ],
        });
        let layout = |label, group: &wgpu::BindGroupLayout| {
            device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(label),
                bind_group_layouts: &[Some(group)],
                immediate_size: 0,
            })
        };
        let compute = layout("stretch compute", &compute_layout);
        let render = layout("stretch rasterise", &render_layout);
        let covering = layout("stretch cover", &cover_layout);
        let pipeline = |entry: &str, layout: &wgpu::PipelineLayout| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        // src·α + dst·(1 − α) on R, G, B (and on the alpha plane in the second target); the
        // targets' own alpha channel keeps what it holds.
        let blend = wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::SrcAlpha,
                dst_factor: wgpu::BlendFactor::OneMinusSrcAlpha,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::Zero,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
        };
        let target = |blend| {
            Some(wgpu::ColorTargetState {
                format: FORMAT,
                blend,
                write_mask: wgpu::ColorWrites::ALL,
            })
        };
        let drawing = |label, vertex: &str, fragment: &str, targets: &[_]| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&render),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vertex),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState {
                    topology: wgpu::PrimitiveTopology::TriangleList,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: None,
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        StretchPass {
            frame_range: pipeline("frame_range", &compute),
            texture_blur: pipeline("texture_blur", &compute),
            move_vertices: pipeline("move_vertices", &compute),
            select_triangles: pipeline("select_triangles", &compute),
            cover: pipeline("cover", &covering),
            sharp: drawing(
                "stretch sharp",
                "sharp_vertex",
                "sharp_fragment",
                &[target(None), target(None)],
            ),
            draw: drawing(
                "stretch rasterise",
                "draw_vertex",
                "draw_fragment",
                &[target(Some(blend)), target(Some(blend))],
            ),
            // Unblended: the last fragment of a pixel in primitive order stays.
            sweep: drawing(
                "stretch rasterise, swept",
                "draw_vertex",
                "sweep_fragment",
                &[target(None)],
            ),
            compute_layout,
            render_layout,
            cover_layout,
            buffers: Mutex::new(HashMap::new()),
        }
    }

    fn make_buffers(&self, device: &wgpu::Device, shape: Shape) -> Buffers {
        let words = |n: u64| n.max(1) * 4;
        let buffer = |label, size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let n = shape.pixels();
        let input = U::STORAGE | U::COPY_DST;
        let config = buffer(
            "stretch config",
            std::mem::size_of::<StretchConfig>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let planes = buffer("stretch planes", words(4 * n), input);
        let z = buffer("stretch z", words(n), input);
        let v = buffer("stretch v", words(2 * n), input);
        let blurred = buffer("stretch blurred", words(4 * n), U::STORAGE);
        let vertices = buffer("stretch vertices", words(3 * n), U::STORAGE);
        let keys = buffer(
            "stretch keys",
            words(shape.triangles()),
            U::STORAGE | U::COPY_SRC,
        );
        let range = buffer("stretch range", 32, U::STORAGE | U::COPY_DST);
        let order = buffer("stretch order", words(shape.triangles()), input);
        let keys_readback = buffer(
            "stretch keys readback",
            words(shape.triangles()),
            U::MAP_READ | U::COPY_DST,
        );
        let covered = buffer("stretch covered", words(4 * n), U::STORAGE | U::COPY_SRC);
        let color_readback = buffer(
            "stretch colour readback",
            words(4 * n),
            U::MAP_READ | U::COPY_DST,
        );
        let targets = [0, 1, 2].map(|_| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some("stretch target"),
                size: wgpu::Extent3d {
                    width: shape.width,
                    height: shape.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        });
        let views = [0, 1, 2].map(|k| targets[k].create_view(&Default::default()));
        let group = |label, layout, bound: &[(u32, &wgpu::Buffer)]| {
            let entries: Vec<wgpu::BindGroupEntry> = bound
                .iter()
                .map(|&(binding, buffer)| wgpu::BindGroupEntry {
                    binding,
                    resource: buffer.as_entire_binding(),
                })
                .collect();
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout,
                entries: &entries,
            })
        };
        let compute = group(
            "stretch compute",
            &self.compute_layout,
            &[
                (0, &config),
                (1, &planes),
                (2, &z),
                (3, &v),
                (4, &blurred),
                (5, &vertices),
                (6, &keys),
                (7, &range),
            ],
        );
        let render = group(
            "stretch rasterise",
            &self.render_layout,
            &[
                (0, &config),
                (1, &planes),
                (2, &z),
                (3, &v),
                (11, &vertices),
                (12, &blurred),
                (13, &order),
            ],
        );
        let view = |binding, view| wgpu::BindGroupEntry {
            binding,
            resource: wgpu::BindingResource::TextureView(view),
        };
        let cover = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stretch cover"),
            layout: &self.cover_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: config.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: planes.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: z.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: v.as_entire_binding(),
                },
                view(20, &views[0]),
                view(21, &views[1]),
                view(22, &views[2]),
                wgpu::BindGroupEntry {
                    binding: 23,
                    resource: covered.as_entire_binding(),
                },
            ],
        });
        Buffers {
            config,
            planes,
            z,
            v,
            _blurred: blurred,
            _vertices: vertices,
            keys,
            range,
            order,
            _targets: targets,
            views,
            covered,
            keys_readback,
            color_readback,
            compute,
            render,
            cover,
        }
    }
}

/// Workgroups for `count` invocations of a 1-D stage: rows of [`ROW`].
fn groups(count: u64) -> (u32, u32) {
    let groups = count.div_ceil(GROUP as u64);
    let x = groups.min(ROW as u64) as u32;
    (x, groups.div_ceil(ROW as u64).max(1) as u32)
}

impl Gpu {
    /// texture_blur → move_vertices → rasterise on the GPU, with the arguments and result of
    /// the CPU's [`stages`](crate::motion::stretch::stages), or why they could not run.
    pub fn try_stretch(
        &self,
        config: &StretchConfig,
        planes: &[Vec<f32>; 4],
        z: &[f32],
        v: &[[f32; 2]],
    ) -> Result<[Vec<f32>; 4], StageError> {
        let shape = Shape {
            width: config.width,
            height: config.height,
        };
        let n = shape.pixels() as usize;
        if n == 0 {
            return Ok(planes.clone());
        }
        if !self
            .device
            .features()
            .contains(wgpu::Features::FLOAT32_BLENDABLE)
        {
            return Err(StageError::Device(
                "the device cannot blend 32-bit float targets (FLOAT32_BLENDABLE)".into(),
            ));
        }
        let side = self.device.limits().max_texture_dimension_2d;
        if shape.width > side || shape.height > side {
            return Err(StageError::Device(format!(
                "a {}×{} frame exceeds the device's largest texture side of {side}",
                shape.width, shape.height
            )));
        }
        let largest = 16 * shape.pixels().max(shape.triangles() / 4);
        if largest > self.max_binding() {
            return Err(StageError::TooLarge {
                bytes: largest,
                limit: self.max_binding(),
            });
        }
        let pass = self.compiled("stretch", StretchPass::new);
        // Errors from here on, the buffers' creation included, come back as a StageError
        // (the caller runs the CPU stages): out of memory as well as validation.
        let caught = Caught::push(&self.device);
        let mut cache = pass.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let buffers = kept(&mut cache, &shape, || {
            pass.make_buffers(&self.device, shape)
        });
        let result = self.run_stretch(&pass, buffers, config, planes, z, v);
        if let Err(error) = caught.check() {
            // Buffers that failed are not kept for the next frame.
            cache.remove(&shape);
            return Err(error);
        }
        result
    }

    fn run_stretch(
        &self,
        pass: &StretchPass,
        buffers: &Buffers,
        config: &StretchConfig,
        planes: &[Vec<f32>; 4],
        z: &[f32],
        v: &[[f32; 2]],
    ) -> Result<[Vec<f32>; 4], StageError> {
        let shape = Shape {
            width: config.width,
            height: config.height,
        };
        let n = shape.pixels();
        let queue = &self.queue;
        let mut clock = std::time::Instant::now();
        queue.write_buffer(&buffers.config, 0, bytemuck::bytes_of(config));
        for (c, plane) in planes.iter().enumerate() {
            queue.write_buffer(
                &buffers.planes,
                c as u64 * 4 * n,
                bytemuck::cast_slice(plane),
            );
        }
        queue.write_buffer(&buffers.z, 0, bytemuck::cast_slice(z));
        queue.write_buffer(&buffers.v, 0, bytemuck::cast_slice(v));
        self.uploaded(&mut clock)?;

        // texture_blur (after the frame's range) and move_vertices, then the triangles' keys.
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("stretch"),
            });
        encoder.clear_buffer(&buffers.range, 0, None);
        {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("stretch texture_blur, move_vertices"),
                timestamp_writes: None,
            });
            compute.set_bind_group(0, &buffers.compute, &[]);
            if config.texture_blur != 0 {
                let (x, y) = groups(n);
                compute.set_pipeline(&pass.frame_range);
                compute.dispatch_workgroups(x, y, 1);
                compute.set_pipeline(&pass.texture_blur);
                compute.dispatch_workgroups(
                    config.width.div_ceil(TILE),
                    config.height.div_ceil(TILE),
                    1,
                );
            }
            let (x, y) = groups(n);
            compute.set_pipeline(&pass.move_vertices);
            compute.dispatch_workgroups(x, y, 1);
            let triangles = shape.triangles();
            if triangles > 0 {
                let (x, y) = groups(triangles);
                compute.set_pipeline(&pass.select_triangles);
                compute.dispatch_workgroups(x, y, 1);
            }
        }
        let key_bytes = 4 * shape.triangles();
        if key_bytes > 0 {
            encoder.copy_buffer_to_buffer(&buffers.keys, 0, &buffers.keys_readback, 0, key_bytes);
        }
        queue.submit([encoder.finish()]);
        // The drawn triangles, farthest first, index as the tie-break (the CPU's order).
        let order: Vec<u32> = if key_bytes > 0 {
            let keys = read_back(&self.device, &buffers.keys_readback, key_bytes)?;
            let mut drawn: Vec<(u32, u32)> = keys
                .par_iter()
                .enumerate()
                .filter(|&(_, &key)| key != NOT_DRAWN)
                .map(|(t, &key)| (key, t as u32))
                .collect();
            drawn.par_sort_unstable_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
            drawn.into_iter().map(|(_, t)| t).collect()
        } else {
            Vec::new()
        };
        if !order.is_empty() {
            queue.write_buffer(&buffers.order, 0, bytemuck::cast_slice(&order));
        }

        // rasterise: the sharp frame, then the triangles in order.
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("stretch rasterise"),
            });
        let attachment = |view| {
            Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    store: wgpu::StoreOp::Store,
                },
            })
        };
        {
            let mut render = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("stretch rasterise"),
                color_attachments: &[attachment(&buffers.views[0]), attachment(&buffers.views[1])],
                ..Default::default()
            });
            render.set_bind_group(0, &buffers.render, &[]);
            render.set_pipeline(&pass.sharp);
            render.draw(0..3, 0..1);
            if !order.is_empty() {
                render.set_pipeline(&pass.draw);
                render.draw(0..6 * order.len() as u32, 0..1);
            }
        }
        {
            // The same triangles into `swept`, where a pixel is not wholly covered (cleared
            // alone where every pixel is).
            let mut render = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("stretch rasterise, swept"),
                color_attachments: &[attachment(&buffers.views[2])],
                ..Default::default()
            });
            if !order.is_empty() && partly_covered(&planes[3]) {
                render.set_bind_group(0, &buffers.render, &[]);
                render.set_pipeline(&pass.sweep);
                render.draw(0..6 * order.len() as u32, 0..1);
            }
        }
        // cover, over the drawn targets, into `covered`, copied out.
        {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("stretch cover"),
                timestamp_writes: None,
            });
            compute.set_bind_group(0, &buffers.cover, &[]);
            compute.set_pipeline(&pass.cover);
            compute.dispatch_workgroups(
                config.width.div_ceil(TILE),
                config.height.div_ceil(TILE),
                1,
            );
        }
        self.computed(&mut encoder, "stretch readback", &mut clock)?;
        encoder.copy_buffer_to_buffer(&buffers.covered, 0, &buffers.color_readback, 0, 16 * n);
        queue.submit([encoder.finish()]);
        let values = floats(read_back(&self.device, &buffers.color_readback, 16 * n)?);
        let plane = |c: usize| values[c * n as usize..][..n as usize].to_vec();
        let out = [plane(0), plane(1), plane(2), plane(3)];
        self.mark(|t| &mut t.readback_ms, &mut clock)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::stretch as cpu;

    #[test]
    fn the_config_is_twelve_plain_words_in_both_languages() {
        // Keep in sync with stretch.wgsl: eleven 4-byte fields and one of padding.
        assert_eq!(std::mem::size_of::<StretchConfig>(), 48);
        assert_eq!(std::mem::align_of::<StretchConfig>(), 4);
        crate::gpu::layout::assert_same_layout!(
            StretchConfig,
            SHADER,
            "StretchConfig",
            [
                width,
                height,
                shutter,
                t0,
                t1,
                tear,
                extent,
                min_alpha,
                depth_limit,
                texture_blur,
                zero
            ]
        );
    }

    #[test]
    fn the_shader_s_constants_are_the_cpu_s() {
        let has = |line: String| assert!(SHADER.contains(&line), "stretch.wgsl lacks {line}");
        has(format!("const STILL: f32 = {:?};", cpu::STILL));
        has(format!("const MOST_SAMPLES: u32 = {}u;", cpu::MOST_SAMPLES));
        has(format!("const MAX_SHIFT: f32 = {:?};", cpu::MAX_SHIFT));
        has(format!("const NOT_DRAWN: u32 = {NOT_DRAWN}u;"));
        has(format!("const GROUP: u32 = {GROUP}u;"));
        has(format!("@workgroup_size({TILE}, {TILE})"));
    }
}
