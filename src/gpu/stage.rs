//! What every GPU stage shares: a compute pipeline whose bindings are, in order, the stage's
//! uniform config, its inputs (read-only storage) and its outputs (read-write storage) — the
//! CPU function's arguments and results, in the order vello's `fn pass(config, inputs,
//! outputs)` takes them — and the buffers of one set of sizes, kept and reused by every frame
//! of that size.
//!
//! A stage may have several entry points (depth of field's tiles: a reduction per tile, then
//! the neighbourhood), dispatched in order in one compute pass over the same bindings; wgpu
//! orders the storage writes of one dispatch before the reads of the next.

use std::collections::HashMap;
use std::sync::Mutex;
use std::time::Instant;

use super::context::Gpu;
pub use super::context::StageError;

/// Sets of sizes whose buffers are kept at once per stage or pass (a sequence has one; more
/// are dropped).
const KEPT_SIZES: usize = 2;

/// The buffers kept for `key` in `cache`, made with `make` when there are none; the cache
/// is emptied first when it already holds [`KEPT_SIZES`] other keys.
pub(crate) fn kept<'a, K: std::hash::Hash + Eq + Clone, B>(
    cache: &'a mut HashMap<K, B>,
    key: &K,
    make: impl FnOnce() -> B,
) -> &'a mut B {
    if !cache.contains_key(key) && cache.len() >= KEPT_SIZES {
        cache.clear();
    }
    cache.entry(key.clone()).or_insert_with(make)
}

/// The device's out-of-memory and validation error scopes, pushed together: errors from here
/// on (buffers' and pipelines' creation included) come back from [`Caught::check`] as a
/// [`StageError`], for the caller to run the CPU stage, rather than reaching wgpu's
/// uncaptured-error handler. (Fields drop in order: validation, pushed last, pops first.)
pub(crate) struct Caught {
    validation: wgpu::ErrorScopeGuard,
    memory: wgpu::ErrorScopeGuard,
}

impl Caught {
    pub(crate) fn push(device: &wgpu::Device) -> Caught {
        let memory = device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = device.push_error_scope(wgpu::ErrorFilter::Validation);
        Caught { validation, memory }
    }

    /// Pops both scopes: the error either caught, if any.
    pub(crate) fn check(self) -> Result<(), StageError> {
        let invalid = pollster::block_on(self.validation.pop());
        let out_of_memory = pollster::block_on(self.memory.pop());
        match invalid.or(out_of_memory) {
            Some(error) => Err(StageError::Device(error.to_string())),
            None => Ok(()),
        }
    }
}

/// One dispatch of a [`Stage`]: its entry point and workgroup counts.
pub(crate) struct Dispatch {
    pub entry: usize,
    pub groups: [u32; 3],
}

/// The buffers of one set of sizes.
struct Buffers {
    config: wgpu::Buffer,
    inputs: Vec<wgpu::Buffer>,
    outputs: Vec<wgpu::Buffer>,
    /// Every output, one after the other (at 4-byte-aligned offsets), mapped once.
    readback: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// A compiled stage: its pipelines (one per entry point), the layout of its bindings, and its
/// buffers by size.
pub(crate) struct Stage {
    label: &'static str,
    pipelines: Vec<wgpu::ComputePipeline>,
    layout: wgpu::BindGroupLayout,
    config_bytes: u64,
    inputs: usize,
    outputs: usize,
    /// The last `scratch` outputs hold what one dispatch hands the next and are not read back.
    scratch: usize,
    /// Buffers by the byte sizes of inputs and outputs, reused across frames of one size.
    buffers: Mutex<HashMap<Vec<u64>, Buffers>>,
}

/// Byte sizes are rounded up to whole words and never zero (wgpu refuses empty bindings).
fn padded(bytes: u64) -> u64 {
    bytes.max(4).next_multiple_of(4)
}

impl Stage {
    /// Compiles `source` with its entry points `entries`; the bindings are the uniform of
    /// `config_bytes`, `inputs` read-only storage buffers, then `outputs` read-write ones, of
    /// which the last `scratch` are not read back.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn new(
        device: &wgpu::Device,
        label: &'static str,
        source: &str,
        entries: &[&str],
        config_bytes: usize,
        inputs: usize,
        outputs: usize,
        scratch: usize,
    ) -> Stage {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(label),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let mut bindings = vec![wgpu::BindGroupLayoutEntry {
            binding: 0,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: wgpu::BufferSize::new(config_bytes as u64),
            },
            count: None,
        }];
        for k in 0..inputs + outputs {
            bindings.push(wgpu::BindGroupLayoutEntry {
                binding: 1 + k as u32,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage {
                        read_only: k < inputs,
                    },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            });
        }
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &bindings,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipelines = entries
            .iter()
            .map(|entry| {
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(label),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
            })
            .collect();
        Stage {
            label,
            pipelines,
            layout,
            config_bytes: config_bytes as u64,
            inputs,
            outputs,
            scratch,
            buffers: Mutex::new(HashMap::new()),
        }
    }

    fn make_buffers(&self, device: &wgpu::Device, sizes: &[u64]) -> Buffers {
        let buffer = |size, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(self.label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let config = buffer(self.config_bytes, U::UNIFORM | U::COPY_DST);
        let (input_sizes, output_sizes) = sizes.split_at(self.inputs);
        let inputs: Vec<_> = input_sizes
            .iter()
            .map(|&bytes| buffer(bytes, U::STORAGE | U::COPY_DST))
            .collect();
        // Outputs are written whole by the shaders, or cleared first (COPY_DST).
        let outputs: Vec<_> = output_sizes
            .iter()
            .map(|&bytes| buffer(bytes, U::STORAGE | U::COPY_SRC | U::COPY_DST))
            .collect();
        let read = &output_sizes[..self.outputs - self.scratch];
        let readback = buffer(read.iter().sum::<u64>().max(4), U::MAP_READ | U::COPY_DST);
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: config.as_entire_binding(),
        }];
        for (k, b) in inputs.iter().chain(&outputs).enumerate() {
            entries.push(wgpu::BindGroupEntry {
                binding: 1 + k as u32,
                resource: b.as_entire_binding(),
            });
        }
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &self.layout,
            entries: &entries,
        });
        Buffers {
            config,
            inputs,
            outputs,
            readback,
            bind_group,
        }
    }

    /// Runs the stage: writes `config` and `inputs`, clears the outputs named in `clear`,
    /// runs `dispatches` in order, and returns each output's first `output_bytes[k]` bytes as
    /// 32-bit words (scratch outputs excepted).
    pub(crate) fn run(
        &self,
        gpu: &Gpu,
        config: &[u8],
        inputs: &[&[u8]],
        output_bytes: &[u64],
        clear: &[usize],
        dispatches: &[Dispatch],
    ) -> Result<Vec<Vec<u32>>, StageError> {
        debug_assert_eq!(config.len() as u64, self.config_bytes);
        debug_assert_eq!(
            (inputs.len(), output_bytes.len()),
            (self.inputs, self.outputs)
        );
        let sizes: Vec<u64> = inputs
            .iter()
            .map(|i| padded(i.len() as u64))
            .chain(output_bytes.iter().map(|&b| padded(b)))
            .collect();
        let limit = gpu.max_binding();
        if let Some(&bytes) = sizes.iter().find(|&&b| b > limit) {
            return Err(StageError::TooLarge { bytes, limit });
        }
        // Errors from here on, the buffers' creation included, come back as a StageError
        // (the caller runs the CPU stage) rather than to wgpu's uncaptured-error handler:
        // out of memory as well as validation.
        let caught = Caught::push(&gpu.device);
        let mut cache = self.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let buffers = kept(&mut cache, &sizes, || {
            self.make_buffers(&gpu.device, &sizes)
        });

        let mut clock = Instant::now();
        gpu.queue.write_buffer(&buffers.config, 0, config);
        for (buffer, data) in buffers.inputs.iter().zip(inputs) {
            if !data.is_empty() {
                gpu.queue.write_buffer(buffer, 0, data);
            }
        }
        gpu.uploaded(&mut clock)?;
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some(self.label),
            });
        for &k in clear {
            encoder.clear_buffer(&buffers.outputs[k], 0, None);
        }
        {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(self.label),
                timestamp_writes: None,
            });
            compute.set_bind_group(0, &buffers.bind_group, &[]);
            for dispatch in dispatches {
                compute.set_pipeline(&self.pipelines[dispatch.entry]);
                let [x, y, z] = dispatch.groups;
                if x > 0 && y > 0 && z > 0 {
                    compute.dispatch_workgroups(x, y, z);
                }
            }
        }
        gpu.computed(&mut encoder, self.label, &mut clock)?;
        let mut offset = 0;
        let mut ranges = Vec::new();
        let read = self.outputs - self.scratch;
        for (buffer, &bytes) in buffers.outputs.iter().zip(output_bytes).take(read) {
            let bytes = bytes.next_multiple_of(4);
            if bytes > 0 {
                encoder.copy_buffer_to_buffer(buffer, 0, &buffers.readback, offset, bytes);
            }
            ranges.push(offset as usize..(offset + bytes) as usize);
            offset += padded(bytes);
        }
        gpu.queue.submit([encoder.finish()]);
        if let Err(error) = caught.check() {
            // Buffers that failed are not kept for the next frame.
            cache.remove(&sizes);
            return Err(error);
        }
        let words = read_back(&gpu.device, &buffers.readback, offset)?;
        gpu.mark(|t| &mut t.readback_ms, &mut clock)?;
        Ok(ranges
            .into_iter()
            .map(|r| words[r.start / 4..r.end / 4].to_vec())
            .collect())
    }
}

/// Maps `buffer`'s first `bytes`, copies them out as 32-bit words and unmaps it.
pub(crate) fn read_back(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    bytes: u64,
) -> Result<Vec<u32>, StageError> {
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
        bytemuck::cast_slice::<u8, u32>(&view).to_vec()
    };
    buffer.unmap();
    Ok(out)
}

/// 32-bit words read back as f32 (bit for bit).
pub(crate) fn floats(words: Vec<u32>) -> Vec<f32> {
    bytemuck::cast_vec(words)
}

/// A tile stage's two outputs (x, then y) as the grid they make.
pub(crate) fn tile_grid(
    mut out: Vec<Vec<u32>>,
    columns: usize,
    rows: usize,
    size: usize,
) -> crate::motion::tile_max::TileGrid {
    let y = floats(out.pop().expect("two outputs"));
    let x = floats(out.pop().expect("two outputs"));
    crate::motion::tile_max::TileGrid {
        columns,
        rows,
        size,
        x,
        y,
    }
}
