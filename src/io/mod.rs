//! Everything between files on disk and frames in memory: EXR and integer images, pass files
//! and presets, frame sequences, and atomic output.

pub mod exr;
pub mod file;
pub mod image;
pub mod output;
pub mod passes;
pub mod preset;
pub mod sequence;
