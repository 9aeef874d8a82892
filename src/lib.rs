//! shutter: an offline compositor that adds motion blur and depth of field to rendered frame
//! sequences. docs/DESIGN.md gives the conventions and the algorithms, README.md the use,
//! docs/ARCHITECTURE.md the map of every file.
//!
//! The modules, from the bottom up (no two import each other; tests/structure.rs):
//! - [`frame`]: the planar passes of one frame, in the canonical convention.
//! - [`error`]: what went wrong, where, and what to do ([`Error`], [`Problem`]).
//! - [`numeric`]: what non-finite and extreme values become, the jitter hash, and the one
//!   approximate float comparison.
//! - [`stages`]: the seam between a pass and its backend: each pass's `Stages` trait, whose
//!   defaults are the CPU stages, and [`stages::Cpu`].
//! - [`dof`], [`motion`]: the effects — depth of field and motion blur — siblings that never
//!   import each other.
//! - [`gpu`]: the wgpu backend: the context, and the WGSL twins of the CPU stages, mirroring
//!   the effects' tree (`gpu::dof`, `gpu::motion`).
//! - [`process`]: one frame: the numeric policy, depth of field, then motion blur, on a
//!   backend.
//! - [`io`]: EXR and 8/16-bit images, pass files and presets, sequences, locks, atomic output.
//! - [`settings`]: every setting defined once (flag, preset key, range, default, help).
//! - [`pipeline`]: preflight, then read → process → write overlapped.
//! - [`lab`]: the measuring lab — truth scenes, metrics, `diff`, `bench` — which the product
//!   never imports.
//! - [`cli`]: the command line, the only part that prints.
//! - [`alloc`]: the process's allocator (the system's, large buffers advised to huge pages).

pub mod alloc;
pub mod cli;
pub mod dof;
pub mod error;
pub mod frame;
pub mod gpu;
pub mod io;
pub mod lab;
pub mod motion;
pub mod numeric;
pub mod pipeline;
pub mod process;
pub mod settings;
pub mod stack;
pub mod stages;

pub use error::{Error, Problem, ProblemKind, Result};
pub use frame::{Frame, Passes};

/// The version of the form of every command's `--json` document (`"schema"` in each): raised
/// when a field is removed or changes meaning, not when one is added (README: "JSON").
pub const JSON_SCHEMA: u32 = 1;
