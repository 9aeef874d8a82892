//! reconstruct's `gather` stage on the GPU (`reconstruct.wgsl`): the twin of
//! [`crate::motion::reconstruct::gather`] (paper and dual) and
//! [`crate::motion::reconstruct::gather_2014`] (2014 and exposure), the last stage of the
//! motion-blur reconstruction.
//!
//! In: what [`reconstruct_with`] hands its gather ([`GatherInputs`]): the packed texels, the
//! pixel velocity (paper and dual), the tile grid, its kinds ([`Stages::classify`], whose twin
//! runs in the same module: src/gpu/motion/classify.rs) and the exposure variant's mattes
//! ([`crate::motion::reconstruct::matte`]), built by the tile stages (or their twins) and on
//! the CPU (pack and matte). In and out: the premultiplied colour, written in place where the
//! CPU writes it. Bindings, in order: the [`ReconstructConfig`] uniform, texels, velocity,
//! tiles, colour, mattes, carried colours, kinds, the classification's summaries — the CPU
//! functions' arguments; planar structs travel as their planes one after the other.
//!
//! Both sides compute in f32 with the same operations in the same order and the same hash
//! ([`crate::numeric::hash`]); what can differ is the rounding of `sqrt` and division (WGSL
//! allows a few ulp), and a driver's fusing of a multiply and an add. The parity tests in
//! tests/gpu_reconstruct.rs bound the effect.
//!
//! The 2014 gather also carries light layers (`gather_2014_carrying`, the twin of
//! [`crate::motion::reconstruct::gather_2014::gather_2014_carrying`]): the same entry, its
//! pipeline compiled with the shader's `COLOURS` set to the count, reads up to
//! [`MOST_COLOURS`] colours packed beside the texels and mixes them all along each tap, whose
//! weights it computes once (each count has its own pipeline, as it has its own copy on the
//! CPU).
//!
//! Buffers are kept per frame shape in the context and reused by every frame of that shape.
//! The whole colour is uploaded so that the pixels the gather leaves alone come back as they
//! went (the CPU's in-place write); a frame larger than one storage binding runs on the CPU.

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use crate::frame::Color;
use crate::motion::reconstruct::classify::{TileKind, SUMMARY_WORDS};
use crate::motion::reconstruct::matte::{self, Matte};
use crate::motion::reconstruct::pack::pack_tiles;
#[cfg(doc)]
use crate::motion::reconstruct::reconstruct_with;
#[cfg(doc)]
use crate::motion::reconstruct::Stages;
use crate::motion::reconstruct::{GatherInputs, ReconstructConfig, Texel2014, TileMask};
use crate::motion::tile_max::TileGrid;

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, kept, read_back, Caught, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(
    include_str!("../prelude.wgsl"),
    include_str!("reconstruct.wgsl"),
    include_str!("reconstruct_taps.wgsl"),
    include_str!("classify.wgsl"),
    "const MOST_COLOURS: u32 = 1u;\n"
);

/// The carrying module's source: the same stages, up to eight colours a pipeline
/// ([`MOST_COLOURS`]; a unit test holds the two together).
pub const SHADER_CARRYING: &str = concat!(
    include_str!("../prelude.wgsl"),
    include_str!("reconstruct.wgsl"),
    include_str!("reconstruct_taps.wgsl"),
    include_str!("classify.wgsl"),
    "const MOST_COLOURS: u32 = 8u;\n"
);

/// Most colours one dispatch of the 2014 gather carries (`MOST_COLOURS` in the shader): the
/// CPU's most a pass.
pub use crate::motion::reconstruct::gather_2014::MOST_COLOURS;

/// Pixels per workgroup side (`@workgroup_size(8, 8)` in reconstruct.wgsl).
const WORKGROUP: u32 = 8;

/// What the buffers of one frame depend on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) struct Shape {
    pub(super) pixels: usize,
    pub(super) tiles: usize,
    /// Floats per texel: 6 (paper, dual) or 8 (2014, exposure).
    pub(super) texel: usize,
    /// Whether the gather reads the pixel velocity (paper, dual).
    pub(super) velocity: bool,
    /// Whether the gather reads the mattes (exposure).
    pub(super) mattes: bool,
    /// The colours the 2014 gather carries (0: the beauty alone, from the texels).
    pub(super) colours: usize,
}

/// The buffers of one frame shape.
pub(super) struct Buffers {
    config: wgpu::Buffer,
    texels: wgpu::Buffer,
    velocity: wgpu::Buffer,
    tiles: wgpu::Buffer,
    color: wgpu::Buffer,
    mattes: wgpu::Buffer,
    carried: wgpu::Buffer,
    pub(super) kinds: wgpu::Buffer,
    pub(super) readback: wgpu::Buffer,
    pub(super) bind_group: wgpu::BindGroup,
}

/// The compiled stage (both entry points; the 2014 gather's carrying pipelines as each count
/// is first asked for) and its buffers, kept in the context.
pub(crate) struct ReconstructPass {
    /// [`SHADER_CARRYING`]'s module, made the first time a frame carries layers.
    carrying_module: OnceLock<wgpu::ShaderModule>,
    pipeline_layout: wgpu::PipelineLayout,
    gather: wgpu::ComputePipeline,
    gather_2014: wgpu::ComputePipeline,
    /// The classification's two entries (classify.wgsl).
    pub(super) classify_tiles: wgpu::ComputePipeline,
    pub(super) classify_kinds: wgpu::ComputePipeline,
    /// `gather_2014` with COLOURS = n + 1 at n.
    carrying: [OnceLock<wgpu::ComputePipeline>; MOST_COLOURS],
    layout: wgpu::BindGroupLayout,
    pub(super) buffers: Mutex<HashMap<Shape, Buffers>>,
}

/// The 2014 gather's pipeline for `colours` colours (0: the beauty alone, from the texels).
fn pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    entry: &str,
    colours: usize,
) -> wgpu::ComputePipeline {
    let constants = [("COLOURS", colours as f64)];
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(entry),
        layout: Some(layout),
        module,
        entry_point: Some(entry),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: &constants,
            ..Default::default()
        },
        cache: None,
    })
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
                storage(6, true),
                storage(7, false),
                storage(8, false),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("reconstruct"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        ReconstructPass {
            gather: pipeline(device, &module, &pipeline_layout, "gather", 0),
            gather_2014: pipeline(device, &module, &pipeline_layout, "gather_2014", 0),
            classify_tiles: pipeline(device, &module, &pipeline_layout, "classify_tiles", 0),
            classify_kinds: pipeline(device, &module, &pipeline_layout, "classify_kinds", 0),
            carrying: Default::default(),
            carrying_module: OnceLock::new(),
            pipeline_layout,
            layout,
            buffers: Mutex::new(HashMap::new()),
        }
    }

    /// The 2014 gather's pipeline carrying `colours` colours (1 to [`MOST_COLOURS`]),
    /// compiled the first time it is asked for.
    fn carrying(&self, device: &wgpu::Device, colours: usize) -> &wgpu::ComputePipeline {
        self.carrying[colours - 1].get_or_init(|| {
            let module = self.carrying_module.get_or_init(|| {
                device.create_shader_module(wgpu::ShaderModuleDescriptor {
                    label: Some("reconstruct.wgsl, carrying"),
                    source: wgpu::ShaderSource::Wgsl(SHADER_CARRYING.into()),
                })
            });
            pipeline(
                device,
                module,
                &self.pipeline_layout,
                "gather_2014",
                colours,
            )
        })
    }

    pub(super) fn make_buffers(&self, device: &wgpu::Device, shape: Shape) -> Buffers {
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
        // x, then y, then |M| as the CPU's gather works it out (`tile_length` in the shader).
        let tiles = buffer("reconstruct tiles", floats(3 * shape.tiles), input);
        // Each tile's kind (classify.wgsl), written by the classification or uploaded, and
        // read back by the classification's twin; and its two summary words.
        let kinds = buffer(
            "reconstruct tile kinds",
            floats(shape.tiles),
            U::STORAGE | U::COPY_DST | U::COPY_SRC,
        );
        let summaries = buffer(
            "reconstruct tile summaries",
            floats(SUMMARY_WORDS * shape.tiles),
            U::STORAGE,
        );
        let color_bytes = floats(4 * shape.colours.max(1) * shape.pixels);
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
        let matte_floats = if shape.mattes {
            matte::WORDS * shape.pixels
        } else {
            1
        };
        let mattes = buffer("reconstruct mattes", floats(matte_floats), input);
        // The plain gather does not read it: one RGBA (its element), to fill the binding.
        let carried = buffer(
            "reconstruct carried colours",
            floats((4 * shape.colours * shape.pixels).max(4)),
            input,
        );
        let entries: Vec<wgpu::BindGroupEntry> = [
            &config, &texels, &velocity, &tiles, &color, &mattes, &carried, &kinds, &summaries,
        ]
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
            carried,
            kinds,
            readback,
            bind_group,
        }
    }
}

/// What one gather dispatch uploads besides the config: the texels, the pixel velocity
/// (paper and dual), the tiles, their kinds (the 2014 gather's, [`Stages::classify`]'s; all
/// [`TileKind::Full`] otherwise), the mattes (exposure), the colours carried (the 2014 gather
/// carrying layers: each colour's packed texels, colour after colour).
struct Upload<'a> {
    texels: &'a [f32],
    velocity: Option<&'a crate::frame::Velocity>,
    tiles: &'a TileGrid,
    kinds: Vec<u32>,
    mattes: &'a [f32],
    carried: &'a [[f32; 4]],
}

/// The kinds as the shader's words.
fn words(kinds: &[TileKind]) -> Vec<u32> {
    kinds.iter().map(|&kind| kind as u32).collect()
}

/// Writes what the classification and the gather both read: the config, the texels, the
/// mattes (none: not written) and the tiles (x, y, then |M| made here as the CPU's gather makes
/// it).
pub(super) fn write_frame(
    queue: &wgpu::Queue,
    buffers: &Buffers,
    config: &ReconstructConfig,
    (texels, mattes, tiles): (&[f32], &[f32], &TileGrid),
) {
    queue.write_buffer(&buffers.config, 0, bytemuck::bytes_of(config));
    queue.write_buffer(&buffers.texels, 0, bytemuck::cast_slice(texels));
    if !mattes.is_empty() {
        queue.write_buffer(&buffers.mattes, 0, bytemuck::cast_slice(mattes));
    }
    let tile_plane = (tiles.x.len() * 4) as u64;
    queue.write_buffer(&buffers.tiles, 0, bytemuck::cast_slice(&tiles.x));
    queue.write_buffer(&buffers.tiles, tile_plane, bytemuck::cast_slice(&tiles.y));
    // |M| of each tile, made here by the function `gather_2014` uses
    // (`TileGrid::length`): the shader's own
    // `sqrt(x·x + y·y)` is not the CPU's bits (a driver may fuse a product into the sum,
    // NVIDIA's does, and WGSL's square root is not correctly rounded), and the gather
    // compares it with the pixel's own |V| (packed on the CPU) and takes a tap count
    // from it, so an ulp moved decisions: on an H200, clamped to `max_blur` 13 (many
    // tiles and pixels at exactly 13 px), a pixel's own vector won over its tile's
    // where the CPU kept the tile's (docs/history/device-parity-2026-12-04.md). The
    // classification reads it too.
    let lengths: Vec<f32> = (0..tiles.rows)
        .flat_map(|r| (0..tiles.columns).map(move |c| tiles.length(c, r)))
        .collect();
    queue.write_buffer(
        &buffers.tiles,
        2 * tile_plane,
        bytemuck::cast_slice(&lengths),
    );
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
        let upload = match *inputs {
            GatherInputs::Paper {
                texels,
                velocity,
                neighbors,
            } => Upload {
                texels: bytemuck::cast_slice(texels),
                velocity: Some(velocity),
                tiles: neighbors,
                kinds: vec![TileKind::Full as u32; neighbors.columns * neighbors.rows],
                mattes: &[],
                carried: &[],
            },
            GatherInputs::Stable {
                texels,
                mattes,
                tiles,
                kinds,
            } => Upload {
                texels: bytemuck::cast_slice(texels),
                velocity: None,
                tiles,
                kinds: words(kinds),
                mattes: bytemuck::cast_slice(mattes),
                carried: &[],
            },
        };
        self.dispatch_reconstruct(config, upload, &mut [color])
    }

    /// How many colours one dispatch of the carrying 2014 gather takes at most for a frame of
    /// `pixels`: [`MOST_COLOURS`], or as many as one storage binding holds (16 bytes a pixel
    /// each); 0 where not even the texels fit.
    pub fn reconstruct_colours_per_dispatch(&self, pixels: usize) -> usize {
        let limit = self.max_binding();
        if 32 * pixels as u64 > limit {
            return 0;
        }
        MOST_COLOURS.min((limit / (16 * pixels.max(1) as u64)) as usize)
    }

    /// [`crate::motion::reconstruct::gather_2014::gather_2014_carrying`] on the GPU for one
    /// dispatch's `colours` (1 to [`Gpu::reconstruct_colours_per_dispatch`]: the beauty
    /// first, or a further group of light layers), each in place with the beauty's weights,
    /// or why it could not run (then the colours are untouched). `texels` are the beauty's,
    /// packed on `packed`, whose tiles the colours are packed on too.
    pub fn try_reconstruct_gather_carrying(
        &self,
        config: &ReconstructConfig,
        (texels, mattes, tiles, kinds): (&[Texel2014], &[Matte], &TileGrid, &[TileKind]),
        packed: &TileMask,
        colours: &mut [&mut Color],
    ) -> Result<(), StageError> {
        let pixels = config.width as usize * config.height as usize;
        let most = self.reconstruct_colours_per_dispatch(pixels);
        if colours.len() > most {
            return Err(StageError::TooLarge {
                bytes: (16 * pixels * colours.len()) as u64,
                limit: self.max_binding(),
            });
        }
        let mut carried = Vec::with_capacity(colours.len() * pixels);
        for c in colours.iter() {
            let alpha = c.a.as_deref();
            carried.extend(pack_tiles(
                config,
                tiles.columns,
                [0.0; 4],
                |column, row| packed.get(column, row),
                |i| [c.r[i], c.g[i], c.b[i], alpha.map_or(1.0, |a| a[i])],
            ));
        }
        let upload = Upload {
            texels: bytemuck::cast_slice(texels),
            velocity: None,
            tiles,
            kinds: words(kinds),
            mattes: bytemuck::cast_slice(mattes),
            carried: &carried,
        };
        self.dispatch_reconstruct(config, upload, colours)
    }

    /// One dispatch of the gather over `upload`, `colours` written back in place.
    fn dispatch_reconstruct(
        &self,
        config: &ReconstructConfig,
        upload: Upload<'_>,
        colours: &mut [&mut Color],
    ) -> Result<(), StageError> {
        let pixels = config.width as usize * config.height as usize;
        if pixels == 0 {
            return Ok(());
        }
        // The carrying gather reads its colours from `carried`; the others from the texels.
        let carrying = !upload.carried.is_empty();
        let shape = Shape {
            pixels,
            tiles: upload.tiles.x.len(),
            texel: upload.texels.len() / pixels,
            velocity: upload.velocity.is_some(),
            mattes: !upload.mattes.is_empty(),
            colours: if carrying { colours.len() } else { 0 },
        };
        let plane = (pixels * 4) as u64;
        let planes = 4 * shape.colours.max(1);
        let largest = ((upload.texels.len() * 4) as u64).max(planes as u64 * plane);
        if largest > self.max_binding() {
            return Err(StageError::TooLarge {
                bytes: largest,
                limit: self.max_binding(),
            });
        }
        let pass = self.compiled("reconstruct", ReconstructPass::new);
        // Errors from here on, the buffers' and a carrying pipeline's creation included, come
        // back as a StageError (the caller runs the CPU gather): out of memory as well as
        // validation.
        let caught = Caught::push(&self.device);
        let pipeline = if carrying {
            pass.carrying(&self.device, shape.colours)
        } else if shape.texel == 8 {
            &pass.gather_2014
        } else {
            &pass.gather
        };
        let mut cache = pass.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let buffers = kept(&mut cache, &shape, || {
            pass.make_buffers(&self.device, shape)
        });

        let mut clock = std::time::Instant::now();
        let queue = &self.queue;
        let frame = (upload.texels, upload.mattes, upload.tiles);
        write_frame(queue, buffers, config, frame);
        queue.write_buffer(&buffers.kinds, 0, bytemuck::cast_slice(&upload.kinds));
        if carrying {
            queue.write_buffer(&buffers.carried, 0, bytemuck::cast_slice(upload.carried));
        }
        if let Some(velocity) = upload.velocity {
            queue.write_buffer(&buffers.velocity, 0, bytemuck::cast_slice(&velocity.x));
            queue.write_buffer(&buffers.velocity, plane, bytemuck::cast_slice(&velocity.y));
        }
        // Alpha, where a colour has none, is not written: the gather's alpha is dropped then.
        for (g, color) in colours.iter().enumerate() {
            let channels = [
                Some(&color.r),
                Some(&color.g),
                Some(&color.b),
                color.a.as_ref(),
            ];
            for (p, channel) in channels.iter().enumerate() {
                if let Some(channel) = channel {
                    let at = (4 * g + p) as u64 * plane;
                    queue.write_buffer(&buffers.color, at, bytemuck::cast_slice(channel));
                }
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
            compute.set_pipeline(pipeline);
            compute.set_bind_group(0, &buffers.bind_group, &[]);
            compute.dispatch_workgroups(
                config.width.div_ceil(WORKGROUP),
                config.height.div_ceil(WORKGROUP),
                1,
            );
        }
        self.computed(&mut encoder, "reconstruct", &mut clock)?;
        // Every colour's planes up to the last one written (the last colour's alpha only if
        // it has one).
        let last_alpha = colours.last().is_some_and(|c| c.a.is_some());
        let bytes = (planes as u64 - u64::from(!last_alpha)) * plane;
        encoder.copy_buffer_to_buffer(&buffers.color, 0, &buffers.readback, 0, bytes);
        queue.submit([encoder.finish()]);
        if let Err(error) = caught.check() {
            // Buffers that failed are not kept for the next frame.
            cache.remove(&shape);
            return Err(error);
        }
        let out = floats(read_back(&self.device, &buffers.readback, bytes)?);
        self.mark(|t| &mut t.readback_ms, &mut clock)?;
        for (g, color) in colours.iter_mut().enumerate() {
            let plane_of = |p: usize| &out[(4 * g + p) * pixels..(4 * g + p + 1) * pixels];
            color.r.copy_from_slice(plane_of(0));
            color.g.copy_from_slice(plane_of(1));
            color.b.copy_from_slice(plane_of(2));
            if let Some(a) = color.a.as_mut() {
                a.copy_from_slice(plane_of(3));
            }
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
        assert!(SHADER_CARRYING.ends_with(&format!(
            "const MOST_COLOURS: u32 = {}u;\n",
            cpu::gather_2014::MOST_COLOURS
        )));
        assert!(SHADER.ends_with("const MOST_COLOURS: u32 = 1u;\n"));
        assert_eq!(
            SHADER.trim_end_matches("const MOST_COLOURS: u32 = 1u;\n"),
            SHADER_CARRYING.trim_end_matches("const MOST_COLOURS: u32 = 8u;\n")
        );
        has(format!(
            "const COVER_SLOPE: f32 = {:?};",
            cpu::gather_2014::COVER_SLOPE
        ));
        // The mattes travel as a flat array of words, MATTE_WORDS a pixel.
        has(format!("const MATTE_WORDS: u32 = {}u;", cpu::matte::WORDS));
        assert_eq!(std::mem::size_of::<Matte>(), 4 * cpu::matte::WORDS);
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
