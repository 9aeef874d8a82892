//! The device side of scatter's twin: its two shader modules (the beauty alone, and the
//! beauty carrying light layers), their pipelines, bindings and buffers, and one run of the
//! stages (upload, reach → prepare → accumulate → resolve in one submission, readback). What
//! a run computes and why: [`super`].

use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

use crate::frame::{Color, Positions};
use crate::motion::scatter::{Fringe, ScatterConfig};

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, kept, read_back, Caught, StageError};

/// The source of the beauty alone: the stages, the curves, and the light layers' hooks
/// empty (`alone.wgsl`).
pub const SHADER: &str = concat!(
    include_str!("../../prelude.wgsl"),
    include_str!("scatter.wgsl"),
    include_str!("fixed.wgsl"),
    include_str!("behind.wgsl"),
    include_str!("../curve.wgsl"),
    include_str!("alone.wgsl")
);

/// The source of the beauty carrying light layers: the same stages and curves, the hooks
/// filled (`carrying.wgsl`).
pub const SHADER_CARRYING: &str = concat!(
    include_str!("../../prelude.wgsl"),
    include_str!("scatter.wgsl"),
    include_str!("fixed.wgsl"),
    include_str!("behind.wgsl"),
    include_str!("../curve.wgsl"),
    include_str!("carrying.wgsl")
);

/// What a run reads beside the colours: depth, the prev and next positions, and the fringe
/// ([`crate::motion::scatter::fringe`], found on the CPU).
pub(super) type Inputs<'a> = (&'a [f32], [&'a Positions; 2], &'a Fringe);

/// Storage buffers the beauty alone binds (every binding but the uniform).
pub const STORAGE_BUFFERS: u32 = 13;
/// Storage buffers a run carrying layers binds: the beauty's and the layers' three (their
/// input, sums and output, group 1).
pub const CARRYING_STORAGE_BUFFERS: u32 = STORAGE_BUFFERS + 3;
/// Most light layers one run carries (`MOST_LAYERS` in carrying.wgsl): a curve's layer
/// values are a private array, three a layer (24 floats; more would spill to memory on most
/// GPUs), and past eight layers the curves a further run draws again are a small share of
/// its cost beside the layers' own deposits.
pub const MOST_LAYERS: usize = 8;

/// Words of the `state` buffer the host writes (keep in sync with scatter.wgsl): the moving
/// count, the accumulate dispatch (x, y, z), the farthest reach, the host's flags, the
/// layers carried and the fringe's entries; from [`BLOCKS`] each block's words and the far
/// curves' (fixed.wgsl), which the host clears.
pub(super) const DISPATCH: u64 = 1;
pub(super) const MOST_REACH: usize = 4;
pub(super) const FLAGS: usize = 8;
pub(super) const LAYERS: usize = 9;
pub(super) const FRINGES: usize = 10;
pub(super) const BLOCKS: usize = 16;
/// Colours with a scale of their own: the beauty's R, G and B, its alpha, and each carried
/// layer's R, G and B ([`MOST_LAYERS`]).
pub(super) const COLOURS: usize = 2 + MOST_LAYERS;
/// A block's words: its curves, its reach, and per colour its largest |value| and the sum of
/// its values' exponents.
pub(super) const BLOCK_WORDS: usize = 2 + 2 * COLOURS;
/// A tile's words: its curves, and per colour a factor (a byte, four to a word), a shift and
/// an exponent.
pub(super) const TILE_WORDS: usize = 1 + COLOURS.div_ceil(4) + 2 * COLOURS;
/// Words of the `state` buffer for a frame of `width` × `height`: the host's, then a block's
/// words for each [`BLOCK`]-pixel square and the far curves' (as many).
fn state_words(width: u32, height: u32) -> usize {
    BLOCKS + (blocks(width, height) + 1) * BLOCK_WORDS
}
/// Words of the `moving` buffer: the moving list (two words an entry, at most one a pixel),
/// then a tile's words for each [`BLOCK`]-pixel square (`scales` writes every one).
fn moving_words(width: u32, height: u32) -> usize {
    2 * width as usize * height as usize + blocks(width, height) * TILE_WORDS
}
/// The [`BLOCK`]-pixel squares of a frame of `width` × `height`.
fn blocks(width: u32, height: u32) -> usize {
    width.div_ceil(BLOCK) as usize * height.div_ceil(BLOCK) as usize
}
/// The pixels square of a block and tile, the CPU's [`crate::motion::scatter::config::BLOCK`]
/// (`BLOCK` in fixed.wgsl).
pub(super) const BLOCK: u32 = 16;
pub(super) const OPAQUE: u32 = 1;
pub(super) const HAS_Z: u32 = 2;
/// Most workgroups along one dispatch dimension (WebGPU's limit).
pub(super) const MOST_GROUPS: u32 = 65535;
/// Bytes of the largest binding of a run carrying `layers` over `pixels`: the layers' sums,
/// two words a channel and pixel.
pub(super) fn carried_sum_bytes(pixels: usize, layers: usize) -> u64 {
    (3 * layers * pixels * 8) as u64
}

/// How the stages are dispatched: their workgroup size, whether `accumulate` walks the
/// moving list backwards, and how many light layers one run carries at most (fewer where
/// their sums would not fit one binding; 0: each layer alone in the beauty's place), and
/// whether a run that fails is tried again with fewer. The output must not depend on any of
/// them (a test hook; runs use [`Order::default`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Order {
    pub workgroup: u32,
    pub reversed: bool,
    pub layers: usize,
    pub retry: bool,
}

impl Default for Order {
    fn default() -> Self {
        Order {
            workgroup: 64,
            reversed: false,
            layers: MOST_LAYERS,
            retry: true,
        }
    }
}

impl Order {
    /// Whether the default pipelines serve this order (the layers per run are the host's).
    fn compiles_as_default(&self) -> bool {
        let default = Order::default();
        (self.workgroup, self.reversed) == (default.workgroup, default.reversed)
    }
}

/// The beauty's buffers of one frame size (group 0, both modules).
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
    /// The fringe's entries, three words each (at most one a pixel).
    fringe: wgpu::Buffer,
    readback: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// The light layers' buffers of one frame size (group 1): their input planes, sums and
/// output planes, three a layer, for `layers` of them (a run may carry fewer).
struct CarriedBuffers {
    layers: usize,
    input: wgpu::Buffer,
    sums: wgpu::Buffer,
    out: wgpu::Buffer,
    readback: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// One module's stages, one pipeline per entry point.
struct Pipelines {
    reach: wgpu::ComputePipeline,
    reach_fringe: wgpu::ComputePipeline,
    scales: wgpu::ComputePipeline,
    prepare: wgpu::ComputePipeline,
    accumulate: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
}

impl Pipelines {
    fn new(
        device: &wgpu::Device,
        label: &str,
        source: &str,
        groups: &[&wgpu::BindGroupLayout],
        order: Order,
    ) -> Pipelines {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().map(|&g| Some(g)).collect();
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &groups,
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
        Pipelines {
            reach: pipeline("reach"),
            reach_fringe: pipeline("reach_fringe"),
            scales: pipeline("scales"),
            prepare: pipeline("prepare"),
            accumulate: pipeline("accumulate"),
            resolve: pipeline("resolve"),
        }
    }
}

/// A bind group layout: a uniform of `uniform` bytes at binding 0 where given, then `storage`
/// storage buffers, the first `read` of them read-only.
fn storage_layout(
    device: &wgpu::Device,
    label: &str,
    uniform: Option<u64>,
    storage: u32,
    read: u32,
) -> wgpu::BindGroupLayout {
    let mut entries = Vec::new();
    if let Some(size) = uniform {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(size),
            },
            count: None,
        });
    }
    let first = uniform.is_some() as u32;
    for k in 0..storage {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: first + k,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage {
                    read_only: k < read,
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        });
    }
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &entries,
    })
}

/// The compiled stages of the beauty alone, their buffers by frame size (the blocks' words
/// follow its width and height), and the carrying module, compiled the first time a frame
/// brings light layers (a beauty alone never pays for it).
pub(crate) struct ScatterPass {
    order: Order,
    alone: Pipelines,
    layout: wgpu::BindGroupLayout,
    buffers: Mutex<HashMap<(u32, u32), Buffers>>,
    carrying: OnceLock<CarryingPass>,
}

/// The carrying module's stages (bind groups 0, the beauty's, and 1, the layers'), and the
/// layers' buffers by pixel count.
struct CarryingPass {
    pipelines: Pipelines,
    layout: wgpu::BindGroupLayout,
    buffers: Mutex<HashMap<usize, CarriedBuffers>>,
}

impl ScatterPass {
    pub(crate) fn new(device: &wgpu::Device, order: Order) -> ScatterPass {
        // Colour, depth, prev and next are read; the rest written.
        let config = std::mem::size_of::<ScatterConfig>() as u64;
        let layout = storage_layout(device, "scatter", Some(config), STORAGE_BUFFERS, 4);
        ScatterPass {
            order,
            alone: Pipelines::new(device, "scatter.wgsl", SHADER, &[&layout], order),
            layout,
            buffers: Mutex::new(HashMap::new()),
            carrying: OnceLock::new(),
        }
    }

    fn carrying(&self, device: &wgpu::Device) -> &CarryingPass {
        self.carrying.get_or_init(|| {
            // The layers' input is read; their sums and output written.
            let layout = storage_layout(device, "scatter carried", None, 3, 1);
            let groups = [&self.layout, &layout];
            let label = "scatter.wgsl carrying";
            CarryingPass {
                pipelines: Pipelines::new(device, label, SHADER_CARRYING, &groups, self.order),
                layout,
                buffers: Mutex::new(HashMap::new()),
            }
        })
    }

    fn make_buffers(&self, device: &wgpu::Device, (width, height): (u32, u32)) -> Buffers {
        use wgpu::BufferUsages as U;
        let pixels = width as usize * height as usize;
        let input = U::STORAGE | U::COPY_DST;
        let config = buffer(
            device,
            "scatter config",
            std::mem::size_of::<ScatterConfig>() as u64,
            U::UNIFORM | U::COPY_DST,
        );
        let plane = |label, words| buffer(device, label, bytes(words), input);
        let color = plane("scatter color", 4 * pixels);
        let depth = plane("scatter depth", pixels);
        let prev = plane("scatter prev", 3 * pixels);
        let next = plane("scatter next", 3 * pixels);
        let state = buffer(
            device,
            "scatter state",
            bytes(state_words(width, height)),
            input | U::COPY_SRC,
        );
        let indirect = buffer(device, "scatter dispatch", 12, U::INDIRECT | U::COPY_DST);
        // Two words an entry (the pixel or fringe entry, and its curve's reach), then the
        // tiles' scales.
        let moving = buffer(
            device,
            "scatter moving",
            bytes(moving_words(width, height)),
            U::STORAGE,
        );
        let sums: Vec<_> = ["scatter sum r", "scatter sum g", "scatter sum b"]
            .into_iter()
            .chain(["scatter sum a", "scatter sum w"])
            .map(|label| plane(label, 2 * pixels))
            .collect();
        let out = buffer(
            device,
            "scatter out",
            bytes(4 * pixels),
            U::STORAGE | U::COPY_SRC,
        );
        let readback = buffer(
            device,
            "scatter readback",
            bytes(4 * pixels),
            U::MAP_READ | U::COPY_DST,
        );
        let fringe = plane("scatter fringe", 3 * pixels);
        let bound: Vec<&wgpu::Buffer> = [&config, &color, &depth, &prev, &next, &state, &moving]
            .into_iter()
            .chain(&sums)
            .chain([&out, &fringe])
            .collect();
        let bind_group = bind_group(device, "scatter", &self.layout, &bound);
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
            fringe,
            readback,
            bind_group,
        }
    }

    /// Workgroups for one invocation per pixel (or any item): x × y with x ≤ [`MOST_GROUPS`].
    fn groups(&self, pixels: usize) -> (u32, u32) {
        let groups = (pixels as u64).div_ceil(self.order.workgroup as u64) as u32;
        let x = groups.min(MOST_GROUPS);
        (x, if x == 0 { 0 } else { groups.div_ceil(x) })
    }
}

impl CarryingPass {
    fn make_buffers(&self, device: &wgpu::Device, pixels: usize, layers: usize) -> CarriedBuffers {
        use wgpu::BufferUsages as U;
        let planes = 3 * layers * pixels;
        let input = buffer(
            device,
            "scatter carried",
            bytes(planes),
            U::STORAGE | U::COPY_DST,
        );
        let sums = buffer(
            device,
            "scatter carried sums",
            bytes(2 * planes),
            U::STORAGE | U::COPY_DST,
        );
        let out = buffer(
            device,
            "scatter carried out",
            bytes(planes),
            U::STORAGE | U::COPY_SRC,
        );
        let readback = buffer(
            device,
            "scatter carried readback",
            bytes(planes),
            U::MAP_READ | U::COPY_DST,
        );
        let bound = [&input, &sums, &out];
        let bind_group = bind_group(device, "scatter carried", &self.layout, &bound);
        CarriedBuffers {
            layers,
            input,
            sums,
            out,
            readback,
            bind_group,
        }
    }
}

/// Bytes of `words` 4-byte words (at least one: no buffer is empty).
fn bytes(words: usize) -> u64 {
    (words.max(1) * 4) as u64
}

fn buffer(
    device: &wgpu::Device,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage,
        mapped_at_creation: false,
    })
}

/// `buffers` bound whole at bindings 0, 1, … of `layout`.
fn bind_group(
    device: &wgpu::Device,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    buffers: &[&wgpu::Buffer],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = buffers
        .iter()
        .enumerate()
        .map(|(binding, buffer)| wgpu::BindGroupEntry {
            binding: binding as u32,
            resource: buffer.as_entire_binding(),
        })
        .collect();
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

impl Gpu {
    /// One run of scatter's stages over `color` and `layers` (light layers carried through
    /// the same dispatches, at most [`MOST_LAYERS`]; none: the beauty alone, with the module
    /// and buffers of the beauty alone), dispatched in `order`: the beauty's output and the
    /// layers' R, G, B planes, three a layer, or why they could not run.
    pub(super) fn run_scatter(
        &self,
        config: &ScatterConfig,
        color: &Color,
        (depth, positions, fringe): Inputs,
        order: Order,
        layers: &[&Color],
    ) -> Result<(Color, Vec<Vec<f32>>), StageError> {
        let pixels = config.width as usize * config.height as usize;
        let size = (config.width, config.height);
        let largest = (16 * pixels as u64)
            .max(carried_sum_bytes(pixels, layers.len()))
            .max(bytes(state_words(config.width, config.height)))
            .max(bytes(moving_words(config.width, config.height)));
        if largest > self.max_binding() {
            return Err(StageError::TooLarge {
                bytes: largest,
                limit: self.max_binding(),
            });
        }
        let allowed = self.device.limits().max_storage_buffers_per_shader_stage;
        let binds = if layers.is_empty() {
            STORAGE_BUFFERS
        } else {
            CARRYING_STORAGE_BUFFERS
        };
        if allowed < binds {
            return Err(StageError::Device(format!(
                "scatter binds {binds} storage buffers and the device allows {allowed}"
            )));
        }
        assert!(
            layers.len() <= MOST_LAYERS,
            "a run carries at most {MOST_LAYERS} layers"
        );
        // Errors from here on, the pipelines' and buffers' creation included, come back as a
        // StageError (the caller runs the CPU pass): out of memory as well as validation.
        let caught = Caught::push(&self.device);
        let pass = if order.compiles_as_default() {
            self.compiled("scatter", |device| ScatterPass::new(device, order))
        } else {
            std::sync::Arc::new(ScatterPass::new(&self.device, order))
        };
        let mut cache = pass.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let buffers = kept(&mut cache, &size, || pass.make_buffers(&self.device, size));
        // The layers' module and buffers, where there are layers.
        let carrying = (!layers.is_empty()).then(|| pass.carrying(&self.device));
        let mut carried_cache =
            carrying.map(|c| c.buffers.lock().unwrap_or_else(|e| e.into_inner()));
        let carried = match (carrying, carried_cache.as_mut()) {
            (Some(carrying), Some(cache)) => {
                // Kept buffers for more layers serve fewer (the last run of a split).
                if cache.get(&pixels).is_some_and(|b| b.layers < layers.len()) {
                    cache.remove(&pixels);
                }
                Some(kept(cache, &pixels, || {
                    carrying.make_buffers(&self.device, pixels, layers.len())
                }))
            }
            _ => None,
        };

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
        if let Some(carried) = &carried {
            let channels = layers.iter().flat_map(|l| [&l.r, &l.g, &l.b]);
            for (k, channel) in channels.enumerate() {
                queue.write_buffer(
                    &carried.input,
                    k as u64 * plane,
                    bytemuck::cast_slice(channel),
                );
            }
        }
        // Where every pixel is opaque, alpha sums equal weight sums: four sums, as the CPU.
        let opaque = color.a.as_ref().is_none_or(|a| a.iter().all(|&v| v == 1.0));
        let mut state = [0u32; BLOCKS];
        // `reach` raises the farthest reach from 0.
        state[MOST_REACH] = 0;
        state[FLAGS] = if opaque { OPAQUE } else { 0 } | if has_z { HAS_Z } else { 0 };
        state[LAYERS] = layers.len() as u32;
        let fringes = fringe.pixels.len();
        state[FRINGES] = fringes as u32;
        if fringes > 0 {
            let entries: Vec<u32> = (0..fringes)
                .flat_map(|k| {
                    let cover = fringe.cover[k].to_bits();
                    [fringe.pixels[k], fringe.partners[k], cover]
                })
                .collect();
            queue.write_buffer(&buffers.fringe, 0, bytemuck::cast_slice(&entries));
        }
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
        // The blocks' words (the host's, before them, are written above).
        encoder.clear_buffer(&buffers.state, bytes(BLOCKS), None);
        // The stages and what they bind: the beauty alone's, or the carrying module's with
        // the layers' group.
        let (stages, group) = match (carrying, &carried) {
            (Some(carrying), Some(carried)) => {
                let used = carried_sum_bytes(pixels, layers.len());
                encoder.clear_buffer(&carried.sums, 0, Some(used));
                (&carrying.pipelines, Some(&carried.bind_group))
            }
            _ => (&pass.alone, None),
        };
        let (x, y) = pass.groups(pixels);
        {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("scatter reach"),
                timestamp_writes: None,
            });
            compute.set_bind_group(0, &buffers.bind_group, &[]);
            if let Some(group) = group {
                compute.set_bind_group(1, group, &[]);
            }
            compute.set_pipeline(&stages.reach);
            compute.dispatch_workgroups(x, y, 1);
            if fringes > 0 {
                let (x, y) = pass.groups(fringes);
                compute.set_pipeline(&stages.reach_fringe);
                compute.dispatch_workgroups(x, y, 1);
            }
            // One invocation per tile.
            let tiles = config.width.div_ceil(BLOCK) * config.height.div_ceil(BLOCK);
            let (x, y) = pass.groups(tiles as usize);
            compute.set_pipeline(&stages.scales);
            compute.dispatch_workgroups(x, y, 1);
            compute.set_pipeline(&stages.prepare);
            compute.dispatch_workgroups(1, 1, 1);
        }
        encoder.copy_buffer_to_buffer(&buffers.state, 4 * DISPATCH, &buffers.indirect, 0, 12);
        {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("scatter accumulate"),
                timestamp_writes: None,
            });
            compute.set_bind_group(0, &buffers.bind_group, &[]);
            if let Some(group) = group {
                compute.set_bind_group(1, group, &[]);
            }
            compute.set_pipeline(&stages.accumulate);
            compute.dispatch_workgroups_indirect(&buffers.indirect, 0);
            compute.set_pipeline(&stages.resolve);
            compute.dispatch_workgroups(x, y, 1);
        }
        self.computed(&mut encoder, "scatter", &mut clock)?;
        let channels = if color.a.is_some() { 4 } else { 3 };
        let bytes = channels * plane;
        encoder.copy_buffer_to_buffer(&buffers.out, 0, &buffers.readback, 0, bytes);
        let carried_bytes = 3 * layers.len() as u64 * plane;
        if let Some(carried) = &carried {
            encoder.copy_buffer_to_buffer(&carried.out, 0, &carried.readback, 0, carried_bytes);
        }
        queue.submit([encoder.finish()]);
        if let Err(error) = caught.check() {
            // Buffers that failed are not kept for the next frame.
            cache.remove(&size);
            if let Some(cache) = carried_cache.as_mut() {
                cache.remove(&pixels);
            }
            return Err(error);
        }
        let out = floats(read_back(&self.device, &buffers.readback, bytes)?);
        let carried_out = match &carried {
            Some(carried) => floats(read_back(&self.device, &carried.readback, carried_bytes)?),
            None => Vec::new(),
        };
        self.mark(|t| &mut t.readback_ms, &mut clock)?;
        let mut planes = out.chunks_exact(pixels).map(<[f32]>::to_vec);
        let mut plane = || planes.next().expect("one plane per channel");
        let beauty = Color {
            r: plane(),
            g: plane(),
            b: plane(),
            a: color.a.is_some().then(plane),
        };
        let carried_planes = carried_out.chunks_exact(pixels).map(<[f32]>::to_vec);
        Ok((beauty, carried_planes.collect()))
    }
}
