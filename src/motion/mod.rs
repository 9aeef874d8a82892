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

/// The exposure of a frame: how long the shutter is open and where that interval sits about
/// the frame's own instant (DESIGN.md, "Conventions").
///
/// With `open` = φ (the fraction of the frame interval the shutter is open) and `offset` = o,
/// the exposure covers the frame times t ∈ [(o − ½)·φ, (o + ½)·φ]: o is the middle of the
/// exposure, measured in exposures (fractions of φ), from the frame's instant. The named
/// offsets, as Nuke's `shutteroffset` and Blender's Cycles *Shutter Position* name them:
/// `centre` o = 0, [−φ/2, φ/2] (the default, and before issue 19 the only form); `start`
/// o = +½, [0, φ] (the shutter opens at the frame); `end` o = −½, [−φ, 0] (it closes at
/// the frame). Any o in [−½, ½] is allowed: the frame's instant then lies inside the
/// exposure, where the passes describe the image, and for φ ≤ 1 the exposure stays within
/// [−1, 1], the frames p(−1) and p(+1) span (so scatter's curves interpolate, never
/// extrapolate). Nuke's `custom` offset c (the time, in frames, at which the shutter opens)
/// is o = c/φ + ½.
///
/// A linearly moving point p(t) = p(0) + v·t smears over p(0) + v·[(o − ½)φ, (o + ½)φ]: the
/// centred streak ± v·φ/2 moved along its motion by v·o·φ, twice the offset in units of the
/// half-spread q = ½·v·φ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shutter {
    /// φ: fraction of the frame interval the shutter is open, in [0, 1].
    pub open: f32,
    /// o: the middle of the exposure after the frame's instant, in exposures, in [−½, ½].
    pub offset: f32,
}

impl Shutter {
    /// The named offsets, by the name flags and presets use.
    pub const OFFSETS: &'static [(&'static str, f32)] =
        &[("centre", 0.0), ("start", 0.5), ("end", -0.5)];

    /// A shutter open `open` of the frame, centred on it.
    pub const fn centred(open: f32) -> Shutter {
        Shutter { open, offset: 0.0 }
    }

    /// The exposure [t0, t1], frames relative to the frame's instant.
    #[inline]
    pub fn interval(self) -> (f32, f32) {
        (
            (self.offset - 0.5) * self.open,
            (self.offset + 0.5) * self.open,
        )
    }
}

impl From<f32> for Shutter {
    /// A centred shutter open `open` of the frame.
    fn from(open: f32) -> Shutter {
        Shutter::centred(open)
    }
}

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
