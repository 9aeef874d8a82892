//! shutter: an offline compositor that adds motion blur and depth of field to rendered frame
//! sequences. See DESIGN.md (shared) for the conventions and algorithms, README.md for use.
//!
//! - [`frame`]: the planar passes of one frame, canonical convention.
//! - [`io`]: EXR and 8/16-bit images, pass files and presets, sequences, atomic output.
//! - [`motion`]: the blur algorithms.
//! - [`pipeline`]: preflight, then read → process → write overlapped.
//! - [`cli`]: the command line (the only part that prints).

pub mod bench;
pub mod cli;
pub mod diff;
pub mod dof;
pub mod error;
pub mod frame;
pub mod io;
pub mod metrics;
pub mod motion;
pub mod pipeline;
pub mod truth;

pub use error::{Error, Problem, ProblemKind, Result};
pub use frame::{Frame, Passes};
