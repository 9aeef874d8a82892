//! The wgpu backend (docs/DESIGN.md "wgpu backend"): the GPU context, created once per run and
//! reused across frames, and the WGSL twins of the CPU stages in a tree that mirrors the
//! effects' (vello's `cpu/` and `shader/` pairing): the twin of `crate::dof::X` is
//! `gpu::dof::X` + `X.wgsl`, of `crate::motion::X` is `gpu::motion::X` + `X.wgsl`, with the
//! CPU stages' names inside.
//!
//! - [`dof`]: `coc`, `tiles` (tile min/max), `gather` (the bokeh gather) and `blend` (the
//!   pyramid), and `impl crate::dof::Stages for Gpu`;
//! - [`motion`]: reconstruct's `tile_max`, `neighbor_max`, `dilate` and its gather
//!   (`reconstruct`, every variant), `scatter` (reach → accumulate → resolve) and `stretch`
//!   (texture_blur, move_vertices, rasterise as a render pipeline, cover), and the `Stages`
//!   impls of the three passes;
//! - `context`: [`Gpu`], its one fallback ([`Gpu`]`::or_cpu`) and what the twins compiled;
//!   `stage`: what most twins share (bindings config → inputs → outputs, buffers kept per
//!   size, readback, error scopes); `times`: [`GpuTimes`]; `prelude.wgsl`: what every shader
//!   shares.
//!
//! The CPU passes are the reference; each twin has a parity test against them
//! (tests/gpu.rs, tests/gpu_dof.rs, tests/gpu_reconstruct.rs, tests/gpu_scatter.rs,
//! tests/gpu_stretch.rs) with its tolerance stated and justified beside it. Under `--backend
//! wgpu` every pass runs through its `Stages` trait ([`crate::stages`]) on [`Gpu`]; stages
//! without a twin (blend's talk form, reconstruct's pack and matte) run on the CPU in the same
//! run.
//!
//! The backend is a run's choice ([`Backend`], `--backend cpu|wgpu|auto`):
//! - `cpu` never touches wgpu;
//! - `wgpu` takes the best suitable adapter, a software driver (Mesa's lavapipe) included, and
//!   fails before any output is touched when there is none ([`open`]);
//! - `auto` takes a hardware adapter when there is one and the CPU otherwise: a software
//!   driver is for testing and never chosen by `auto`.
//!
//! The instance is restricted to Vulkan, Metal and DX12: wgpu's GL backend (its silent
//! fallback when no Vulkan driver is installed) lacks what the passes need (renderable
//! `Rgba32Float`, buffer atomics; docs/CRATES.md).
//!
//! Built without the `gpu` feature (`cargo build --no-default-features`) this module keeps
//! only [`Backend`], [`BackendReport`] and [`open`], which refuses `wgpu` and runs `auto` on
//! the CPU; [`Gpu`] is then a type with no values.

use serde::Serialize;

#[cfg(feature = "gpu")]
mod context;
#[cfg(feature = "gpu")]
pub mod dof;
#[cfg(all(test, feature = "gpu"))]
mod layout;
#[cfg(feature = "gpu")]
pub mod motion;
#[cfg(feature = "gpu")]
mod stage;
mod times;
#[cfg(feature = "gpu")]
pub use context::StageError;

#[cfg(feature = "gpu")]
pub use context::{Gpu, Need};
pub use times::GpuTimes;

/// Without the `gpu` feature there is no context: a type with no values, so code that takes
/// an `Option<&Gpu>` compiles the same way in both builds.
#[cfg(not(feature = "gpu"))]
#[derive(Debug)]
pub enum Gpu {}

/// Without the `gpu` feature the context has every pass's stages with no twin: each trait's
/// defaults, the CPU stages (never called: there is no value). This is the one place the
/// feature reaches outside this module's own files; [`crate::process`] runs either build
/// through the same code.
#[cfg(not(feature = "gpu"))]
mod no_twins {
    use super::Gpu;
    impl crate::dof::Stages for Gpu {}
    impl crate::motion::reconstruct::Stages for Gpu {}
    impl crate::motion::scatter::Stages for Gpu {}
    impl crate::motion::stretch::Stages for Gpu {}
}

#[cfg(not(feature = "gpu"))]
impl Gpu {
    pub fn adapter(&self) -> String {
        match *self {}
    }

    pub fn set_profiling(&self, _on: bool) {
        match *self {}
    }

    pub fn take_times(&self) -> GpuTimes {
        match *self {}
    }

    pub fn stages_on_cpu(&self) -> u64 {
        match *self {}
    }
}

/// Where the passes run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Backend {
    /// The CPU (rayon): the reference. The default for now.
    #[default]
    Cpu,
    /// wgpu on any suitable adapter, a software driver included; an error when there is none.
    Wgpu,
    /// wgpu on a hardware GPU when there is one, else the CPU.
    Auto,
}

impl Backend {
    pub const ALL: &'static [(&'static str, Backend)] = &[
        ("cpu", Backend::Cpu),
        ("wgpu", Backend::Wgpu),
        ("auto", Backend::Auto),
    ];

    pub fn name(self) -> &'static str {
        match self {
            Backend::Cpu => "cpu",
            Backend::Wgpu => "wgpu",
            Backend::Auto => "auto",
        }
    }
}

/// What a run asked for and what it got, for the `--json` summary.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BackendReport {
    /// `--backend` as resolved: cpu, wgpu or auto.
    pub requested: String,
    /// Where the GPU-capable stages ran: cpu or wgpu; none in a dry run.
    pub used: String,
    /// The adapter: name, wgpu backend, device type and driver; `None` on the CPU.
    pub adapter: Option<String>,
    /// Why `auto` runs on the CPU (no hardware adapter, a build without the GPU backend).
    pub fallback: Option<String>,
    /// Seconds spent looking for an adapter and creating the context (instance, adapter,
    /// device). Each twin's pipelines compile when it first runs, so a run compiles only
    /// what it uses.
    pub context_seconds: f64,
    /// Stages that have a GPU twin but ran on the CPU for a frame (e.g. a frame larger than
    /// the device's buffer limit), counted over frames.
    pub stages_on_cpu: u64,
}

/// Opens the backend a run asked for: the GPU context when it runs on wgpu, and the report.
/// `Err` holds the one line to print for `--backend wgpu` with no suitable adapter.
pub fn open(backend: Backend) -> Result<(Option<Gpu>, BackendReport), String> {
    let mut report = BackendReport {
        requested: backend.name().to_string(),
        used: "cpu".to_string(),
        ..BackendReport::default()
    };
    match backend {
        Backend::Cpu => Ok((None, report)),
        #[cfg(feature = "gpu")]
        Backend::Wgpu | Backend::Auto => {
            let need = if backend == Backend::Wgpu {
                Need::Any
            } else {
                Need::Hardware
            };
            let start = std::time::Instant::now();
            let opened = Gpu::new(need);
            report.context_seconds = start.elapsed().as_secs_f64();
            match opened {
                Ok(gpu) => {
                    report.used = "wgpu".to_string();
                    report.adapter = Some(gpu.adapter().to_string());
                    Ok((Some(gpu), report))
                }
                Err(missing) if backend == Backend::Auto => {
                    report.fallback = Some(missing);
                    Ok((None, report))
                }
                Err(missing) => Err(missing),
            }
        }
        #[cfg(not(feature = "gpu"))]
        Backend::Wgpu => Err(NO_GPU_FEATURE.to_string()),
        #[cfg(not(feature = "gpu"))]
        Backend::Auto => {
            report.fallback = Some(NO_GPU_FEATURE.to_string());
            Ok((None, report))
        }
    }
}

#[cfg(not(feature = "gpu"))]
const NO_GPU_FEATURE: &str = "this shutter was built without the GPU backend \
    (cargo build --no-default-features): rebuild with the default features or use --backend cpu";

/// Whether a GPU twin must run: `SHUTTER_REQUIRE_GPU=1` (CI sets it) turns a missing adapter
/// into a test failure instead of a skip.
pub fn required() -> bool {
    std::env::var("SHUTTER_REQUIRE_GPU").is_ok_and(|v| !v.is_empty() && v != "0")
}

#[cfg(all(test, feature = "gpu"))]
mod tests {
    use wgpu::naga;

    /// Every twin's shader, prelude included, as the device compiles it (vello validates its
    /// shaders at build time; here a unit test does, with no device needed): each family's
    /// list, kept beside its twins, and scatter's second module, the one that carries light
    /// layers.
    fn shaders() -> Vec<(&'static str, &'static str)> {
        let carrying = [
            ("scatter carrying", super::motion::scatter::SHADER_CARRYING),
            (
                "reconstruct carrying",
                super::motion::reconstruct::SHADER_CARRYING,
            ),
        ];
        [super::dof::SHADERS, super::motion::SHADERS, &carrying].concat()
    }

    #[test]
    fn every_shader_parses_and_validates_without_a_device() {
        let shaders = shaders();
        for (name, shader) in &shaders {
            let module = naga::front::wgsl::parse_str(shader)
                .unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(shader)));
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::empty(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(shader)));
        }
        // Every .wgsl file under src/gpu is part of a shader above (the prelude of each).
        fn files(dir: &std::path::Path, out: &mut Vec<std::path::PathBuf>) {
            for path in std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()) {
                if path.is_dir() {
                    files(&path, out);
                } else if path.extension().is_some_and(|e| e == "wgsl") {
                    out.push(path);
                }
            }
        }
        let mut found = Vec::new();
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/gpu");
        files(&dir, &mut found);
        assert!(found.len() > shaders.len(), "{found:?}");
        for path in found {
            let text = std::fs::read_to_string(&path).unwrap();
            assert!(
                shaders.iter().any(|(_, shader)| shader.contains(&text)),
                "{} is in no shader",
                path.display()
            );
        }
    }
}
