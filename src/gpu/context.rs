//! The GPU context of a run: instance, adapter, device and queue, the compiled stages, and
//! their buffers, created once and reused by every frame.

use std::any::Any;
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use wgpu::{Backends, DeviceType};

use super::times::GpuTimes;

/// The backends with what the passes need: compute, float storage and u32 buffer atomics
/// (scatter's fixed-point sums). Never GL (see the module doc).
const BACKENDS: Backends = Backends::VULKAN
    .union(Backends::METAL)
    .union(Backends::DX12);

/// Why a GPU stage did not run (the caller runs the CPU stage instead).
#[derive(Debug)]
pub enum StageError {
    /// A buffer is larger than one storage binding of this device.
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

/// Which adapters a run accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Need {
    /// Any suitable adapter, a software driver included (`--backend wgpu`).
    Any,
    /// A hardware adapter (`--backend auto`): never a software driver (device type CPU).
    Hardware,
}

/// The GPU context: created once per run ([`Gpu::new`]), used by every frame.
pub struct Gpu {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    /// What the twins compiled on this device — pipelines, with their buffers kept by size —
    /// by name ([`Gpu::compiled`]): the context knows no twin, so adding one touches only its
    /// own files.
    compiled: Mutex<HashMap<&'static str, Arc<dyn Any + Send + Sync>>>,
    /// Stages with a twin that ran on the CPU for a frame (see [`Gpu::note_cpu_stage`]).
    stages_on_cpu: AtomicU64,
    /// The first stage that ran on the CPU instead, and why ([`Gpu::note_cpu_stage`]).
    fallback: Mutex<Option<String>>,
    /// Whether stages time their upload, compute and readback apart ([`Gpu::set_profiling`]).
    pub(crate) profiling: AtomicBool,
    /// What they measured since [`Gpu::take_times`] last took it.
    pub(crate) times: Mutex<GpuTimes>,
}

impl std::fmt::Debug for Gpu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Gpu").field("adapter", &self.info).finish()
    }
}

/// What the driver says of the missing API, per platform, and what to install.
fn missing_driver() -> &'static str {
    if cfg!(target_os = "macos") || cfg!(target_os = "ios") {
        "no Metal adapter found: use a Mac with Metal support or use --backend cpu"
    } else if cfg!(windows) {
        "no DirectX 12 or Vulkan adapter found: install or update the graphics driver, or use \
         --backend cpu"
    } else {
        "no Vulkan adapter found: install a Vulkan driver (Debian/Ubuntu: mesa-vulkan-drivers) \
         or use --backend cpu"
    }
}

/// Preference among suitable adapters: hardware first, discrete before integrated.
fn rank(device_type: DeviceType) -> u8 {
    match device_type {
        DeviceType::DiscreteGpu => 0,
        DeviceType::IntegratedGpu => 1,
        DeviceType::VirtualGpu => 2,
        DeviceType::Other => 3,
        DeviceType::Cpu => 4,
    }
}

/// The features the stages use, requested explicitly: none (the stages are plain compute on
/// storage buffers; `tiles` and scatter use u32 atomics, which WGSL has without a feature,
/// and scatter's indirect dispatch is core; no float atomics, whose sums depend on order).
fn required_features() -> wgpu::Features {
    wgpu::Features::empty()
}

/// Features requested where the adapter has them, whose stages run on the CPU where it has
/// not: blending `Rgba32Float` targets, for stretch's rasterise.
fn optional_features() -> wgpu::Features {
    wgpu::Features::FLOAT32_BLENDABLE
}

/// The limits requested: WebGPU's defaults, with the adapter's own largest storage binding
/// and buffer, so a frame plane as large as the device allows fits, and its own count of
/// storage buffers per stage (scatter binds 12; a device with fewer runs it on the CPU).
fn required_limits(adapter: &wgpu::Limits) -> wgpu::Limits {
    wgpu::Limits {
        max_storage_buffer_binding_size: adapter.max_storage_buffer_binding_size,
        max_buffer_size: adapter.max_buffer_size,
        max_storage_buffers_per_shader_stage: adapter.max_storage_buffers_per_shader_stage,
        ..wgpu::Limits::default()
    }
}

impl Gpu {
    /// Creates the context on the best adapter that `need` accepts. `Err` is one line saying
    /// what is missing and what to install or use instead.
    pub fn new(need: Need) -> Result<Gpu, String> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: BACKENDS,
            flags: wgpu::InstanceFlags::from_build_config().with_env(),
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapters = pollster::block_on(instance.enumerate_adapters(BACKENDS));
        if adapters.is_empty() {
            return Err(missing_driver().to_string());
        }
        let mut suitable: Vec<(wgpu::Adapter, wgpu::AdapterInfo)> = Vec::new();
        let mut lacking = Vec::new();
        for adapter in adapters {
            let info = adapter.get_info();
            let limits = required_limits(&adapter.limits());
            let missing_features = required_features() - adapter.features();
            if !missing_features.is_empty() {
                lacking.push(format!("{} lacks {missing_features:?}", info.name));
            } else if let Some(name) = {
                let mut failed = None;
                limits.check_limits_with_fail_fn(&adapter.limits(), true, |name, _, _| {
                    failed = Some(name)
                });
                failed
            } {
                lacking.push(format!("{} has too low a limit {name}", info.name));
            } else {
                suitable.push((adapter, info));
            }
        }
        suitable.sort_by_key(|(_, info)| rank(info.device_type));
        let chosen = match need {
            Need::Any => suitable.into_iter().next(),
            Need::Hardware => suitable
                .into_iter()
                .find(|(_, info)| info.device_type != DeviceType::Cpu),
        };
        let Some((adapter, info)) = chosen else {
            return Err(match (need, lacking.is_empty()) {
                (Need::Hardware, true) => {
                    "no hardware GPU adapter (software drivers are for --backend wgpu only)"
                        .to_string()
                }
                (_, false) => format!(
                    "no suitable GPU adapter ({}): update the graphics driver or use \
                     --backend cpu",
                    lacking.join("; ")
                ),
                (Need::Any, true) => missing_driver().to_string(),
            });
        };
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("shutter"),
            required_features: required_features() | (adapter.features() & optional_features()),
            required_limits: required_limits(&adapter.limits()),
            ..wgpu::DeviceDescriptor::default()
        }))
        .map_err(|e| {
            format!(
                "cannot open GPU adapter {}: {e}; use --backend cpu",
                info.name
            )
            .replace('\n', " ")
        })?;
        Ok(Gpu {
            device,
            queue,
            info,
            compiled: Mutex::new(HashMap::new()),
            stages_on_cpu: AtomicU64::new(0),
            fallback: Mutex::new(None),
            profiling: AtomicBool::new(false),
            times: Mutex::new(GpuTimes::default()),
        })
    }

    /// The adapter in words: name, wgpu backend, device type, driver.
    pub fn adapter(&self) -> String {
        let info = &self.info;
        let driver = [info.driver.as_str(), info.driver_info.as_str()]
            .iter()
            .filter(|s| !s.is_empty())
            .copied()
            .collect::<Vec<_>>()
            .join(" ");
        format!(
            "{} ({:?}, {:?}{})",
            info.name,
            info.backend,
            info.device_type,
            if driver.is_empty() {
                String::new()
            } else {
                format!(", {driver}")
            }
        )
    }

    /// Whether the adapter is a software driver (lavapipe, WARP, SwiftShader).
    pub fn is_software(&self) -> bool {
        self.info.device_type == DeviceType::Cpu
    }

    /// What a twin compiled under `name` (its pipelines and kept buffers), made by `make` on
    /// first use and kept for the run. One type per name.
    pub(crate) fn compiled<T: Any + Send + Sync>(
        &self,
        name: &'static str,
        make: impl FnOnce(&wgpu::Device) -> T,
    ) -> Arc<T> {
        let mut compiled = self.compiled.lock().unwrap_or_else(|e| e.into_inner());
        let entry = compiled
            .entry(name)
            .or_insert_with(|| Arc::new(make(&self.device)));
        Arc::clone(entry)
            .downcast::<T>()
            .unwrap_or_else(|_| panic!("{name} was compiled as another type"))
    }

    /// The one fallback of every stage with a twin: `gpu`, or where it could not run (a frame
    /// over the device's limits, a device without a feature the stage needs, an error the
    /// device reported), `cpu` — the CPU stage it stands for, whose result it must equal
    /// within the twin's stated tolerance — counted in [`Gpu::stages_on_cpu`] and named in the
    /// run's warning ([`Gpu::fallback`]).
    pub(crate) fn or_cpu<T>(
        &self,
        stage: &str,
        gpu: impl FnOnce() -> Result<T, StageError>,
        cpu: impl FnOnce() -> T,
    ) -> T {
        gpu().unwrap_or_else(|why| {
            self.note_cpu_stage(stage, &why);
            cpu()
        })
    }

    /// Records that a stage with a GPU twin ran on the CPU for one frame, and why (the first
    /// reason is kept for the run's warning).
    pub(crate) fn note_cpu_stage(&self, stage: &str, why: &StageError) {
        self.stages_on_cpu.fetch_add(1, Ordering::Relaxed);
        let mut first = self.fallback.lock().unwrap_or_else(|e| e.into_inner());
        if first.is_none() {
            *first = Some(format!("{stage}: {why}"));
        }
    }

    /// Why a stage first ran on the CPU instead (`None` if none has).
    pub fn fallback(&self) -> Option<String> {
        self.fallback
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .clone()
    }

    /// Times each stage's upload, compute and readback apart from now on (`true`), or not.
    /// Timing drains the queue between the three, which a run does not otherwise do: for
    /// `shutter bench`'s GPU rows, not for production runs.
    pub fn set_profiling(&self, on: bool) {
        self.profiling.store(on, Ordering::Relaxed);
    }

    /// With profiling on, drains the queue and adds the time since `clock` to `part`, then
    /// restarts `clock`; nothing otherwise. Stages call it after their upload, their
    /// dispatches and their readback.
    pub(crate) fn mark(
        &self,
        part: fn(&mut GpuTimes) -> &mut f64,
        clock: &mut std::time::Instant,
    ) -> Result<(), StageError> {
        if self.profiling.load(Ordering::Relaxed) {
            self.device
                .poll(wgpu::PollType::wait_indefinitely())
                .map_err(|e| StageError::Device(e.to_string()))?;
            let mut times = self.times.lock().unwrap_or_else(|e| e.into_inner());
            *part(&mut times) += clock.elapsed().as_secs_f64() * 1e3;
            *clock = std::time::Instant::now();
        }
        Ok(())
    }

    /// The end of a stage's uploads: with profiling on, waits for them and books their time
    /// as upload ([`Gpu::mark`]).
    pub(crate) fn uploaded(&self, clock: &mut std::time::Instant) -> Result<(), StageError> {
        if self.profiling() {
            self.queue.submit([]);
        }
        self.mark(|t| &mut t.upload_ms, clock)
    }

    /// The end of a stage's compute: with profiling on, submits what `encoder` holds, books
    /// its time as compute, and leaves a fresh encoder (labelled `label`) in its place for the
    /// readback; without, leaves the encoder as it is.
    pub(crate) fn computed(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        label: &str,
        clock: &mut std::time::Instant,
    ) -> Result<(), StageError> {
        if self.profiling() {
            let fresh = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
            self.queue
                .submit([std::mem::replace(encoder, fresh).finish()]);
            self.mark(|t| &mut t.compute_ms, clock)?;
        }
        Ok(())
    }

    /// Whether stages time their parts apart ([`Gpu::set_profiling`]).
    pub(crate) fn profiling(&self) -> bool {
        self.profiling.load(Ordering::Relaxed)
    }

    /// The times measured since the last call (zero unless profiling).
    pub fn take_times(&self) -> GpuTimes {
        std::mem::take(&mut *self.times.lock().unwrap_or_else(|e| e.into_inner()))
    }

    /// Stages with a twin that ran on the CPU so far, counted over frames.
    pub fn stages_on_cpu(&self) -> u64 {
        self.stages_on_cpu.load(Ordering::Relaxed)
    }

    /// The largest buffer (bytes) one storage binding can hold on this device; lowered by
    /// the environment variable `SHUTTER_GPU_MAX_BINDING` (bytes), which the tests use to
    /// make a small frame take the path of one too large for the device.
    pub(crate) fn max_binding(&self) -> u64 {
        let limits = self.device.limits();
        let device = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size);
        let lowered = std::env::var("SHUTTER_GPU_MAX_BINDING")
            .ok()
            .and_then(|v| v.parse::<u64>().ok());
        lowered.map_or(device, |l| l.min(device))
    }
}
