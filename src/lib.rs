//! shutter: an offline compositor that adds motion blur and depth of field to rendered frame
//! sequences. See DESIGN.md (shared) for the conventions and algorithms, README.md for use.
//!
//! - [`frame`]: the planar passes of one frame, canonical convention.
//! - [`io`]: EXR and 8/16-bit images, pass files and presets, sequences, atomic output.
//! - [`numeric`]: what non-finite and extreme values become, and the jitter hash.
//! - [`process`]: one frame: the numeric policy, depth of field, then motion blur.
//! - [`dof`], [`motion`]: the effects, siblings that never import each other.
//! - [`gpu`]: the wgpu backend: the GPU context and the WGSL twins of the CPU stages.
//! - [`pipeline`]: preflight, then read → process → write overlapped.
//! - [`settings`]: every setting defined once (flag, preset key, range, default, help).
//! - [`cli`]: the command line (the only part that prints).

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
pub mod stages;

pub use error::{Error, Problem, ProblemKind, Result};
pub use frame::{Frame, Passes};
