//! Integration tests: one binary, a module per area.
#![allow(clippy::needless_range_loop)] // per-pixel maths reads best with an index

mod support;

mod automation;
mod bench;
mod cli;
mod diff;
mod dof;
mod farm;
mod gate;
mod golden;
mod gpu;
mod gpu_dof;
mod gpu_reconstruct;
mod gpu_scatter;
mod gpu_stretch;
mod hostile;
mod invariants;
mod io;
mod layers;
mod lost;
mod metrics;
mod offset;
mod photo_tags;
mod photos;
mod presets;
mod properties;
mod reconstruct;
mod scatter;
mod settings;
mod stretch;
mod structure;
mod suggest;
mod survives;
mod truth;
mod unknown_compression;
mod vectors;
mod views;
