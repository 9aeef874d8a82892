//! Motion-blur algorithms. Each takes a canonical [`crate::frame::Frame`] holding the passes it
//! declared in [`Algorithm::needs`], already through the numeric policy
//! ([`crate::numeric`]), and returns the blurred colour: `reconstruct` (McGuire 2012: the
//! `tile_max`, `neighbor_max` and `reconstruct` passes) and `scatter` (Guertin &
//! Nowrouzezahrai: the `curve`, `line` and `scatter` modules) and `stretch` (Wloka: the
//! `triangle` and `stretch` modules).

pub mod curve;
pub mod dilate;
pub mod line;
pub mod neighbor_max;
pub mod reconstruct;
pub mod scatter;
pub mod stretch;
pub mod tile_max;
pub mod triangle;

use crate::frame::Passes;
pub use reconstruct::{ReconstructParams, Variant};
pub use scatter::{CurveKind, Normalize, ScatterParams, Weight};
pub use stretch::{Anchor, StretchParams};
use tile_max::TileGrid;

/// The blur algorithms shutter knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Algorithm {
    /// Copies colour through unchanged: the whole read/write path with no blur.
    None,
    /// McGuire et al. 2012's reconstruction filter (gather along the dominant velocity).
    Reconstruct,
    /// Guertin & Nowrouzezahrai's curve scatter (non-linear motion from prev/next positions).
    Scatter,
    /// Wloka & Zeleznik's vertex stretch (the image as a mesh, silhouettes stretched).
    Stretch,
}

impl Algorithm {
    /// Every algorithm, by name, for help texts and messages.
    pub const ALL: &'static [(&'static str, Algorithm)] = &[
        ("none", Algorithm::None),
        ("reconstruct", Algorithm::Reconstruct),
        ("scatter", Algorithm::Scatter),
        ("stretch", Algorithm::Stretch),
    ];

    pub fn parse(name: &str) -> Option<Algorithm> {
        Self::ALL
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|(_, a)| *a)
    }

    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, a)| *a == self)
            .map_or("?", |(n, _)| n)
    }

    /// The passes this algorithm reads; nothing else is decoded.
    pub fn needs(self) -> Passes {
        match self {
            Algorithm::None => Passes::COLOR,
            Algorithm::Reconstruct => Passes {
                color: true,
                depth: true,
                velocity: true,
                prev: false,
                next: false,
            },
            Algorithm::Stretch => Passes {
                color: true,
                depth: true,
                velocity: true,
                prev: false,
                next: false,
            },
            Algorithm::Scatter => Passes {
                color: true,
                depth: true,
                velocity: false,
                prev: true,
                next: true,
            },
        }
    }
}

/// Reconstruct's tile stages, which a backend may run elsewhere (the GPU): `tile_max`, then
/// `neighbor_max` (paper, dual) or `dilate` (the 2014 variants). Each must return what the CPU
/// stage it stands for returns (the defaults are the CPU stages; a GPU twin's parity with
/// them is tested in tests/gpu.rs).
pub trait TileStages {
    /// [`tile_max::tile_max`].
    fn tile_max(
        &self,
        vx: &[f32],
        vy: &[f32],
        width: usize,
        height: usize,
        size: usize,
    ) -> TileGrid {
        tile_max::tile_max(vx, vy, width, height, size)
    }

    /// [`neighbor_max::neighbor_max`].
    fn neighbor_max(&self, tiles: &TileGrid) -> TileGrid {
        neighbor_max::neighbor_max(tiles)
    }

    /// [`dilate::dilate`].
    fn dilate(&self, tiles: &TileGrid) -> TileGrid {
        dilate::dilate(tiles)
    }
}

/// Every tile stage on the CPU: the reference.
#[derive(Clone, Copy, Debug, Default)]
pub struct Cpu;

impl TileStages for Cpu {}
