//! The seam between a pass and the backend its stages run on, one shape for every pass.
//!
//! Each pass defines a `Stages` trait ([`crate::dof::Stages`],
//! [`crate::motion::reconstruct::Stages`], [`crate::motion::scatter::Stages`],
//! [`crate::motion::stretch::Stages`]) whose methods are the stages a backend may run
//! elsewhere, with the CPU stages as their default bodies, and one entry `X_with(frame, …,
//! &impl Stages)` that runs the pass with them (its frame prologue, its skips and the stages
//! that run on the CPU for every backend written once, there). [`Cpu`] takes every default:
//! the reference. `crate::gpu::Gpu` implements each trait with its WGSL twins, each stage
//! through `Gpu::or_cpu`, the one fallback to the CPU stage where the device cannot run it.
//! A stage without a twin is simply not overridden.
//!
//! [`crate::process`] runs one frame on either backend through these traits alone: the
//! choice of backend costs no `cfg` and no arm per algorithm.

/// Every stage on the CPU (rayon): the reference each GPU twin is tested against.
#[derive(Clone, Copy, Debug, Default)]
pub struct Cpu;
