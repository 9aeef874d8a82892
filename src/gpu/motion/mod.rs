//! Motion blur's GPU twins, mirroring [`crate::motion`]: reconstruct's tile stages
//! (`tile_max`, `neighbor_max`, `dilate`) and its gather (`reconstruct`), `scatter` and
//! `stretch`.

pub mod dilate;
pub mod neighbor_max;
pub mod reconstruct;
pub mod scatter;
pub mod stretch;
pub mod tile_max;
