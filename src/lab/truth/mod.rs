//! Truth: procedural scenes whose motion is known in closed form, their passes, and
//! brute-force references to measure every algorithm against (docs/DESIGN.md, "Measuring
//! accuracy").

pub mod layers;
pub mod model;
pub mod render;
pub mod sample;
pub mod scenes;
pub mod write;
