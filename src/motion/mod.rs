//! Motion-blur algorithms. Each takes a canonical [`crate::frame::Frame`] holding the passes it
//! declared in [`Algorithm::needs`], already through the numeric policy
//! ([`crate::numeric`]), and returns the blurred colour:
//! - [`reconstruct`]: the gather filters (McGuire et al. 2012; Guertin et al. 2014 and ours),
//!   with its tile stages [`tile_max`], [`neighbor_max`] and [`dilate`];
//! - [`scatter`]: Guertin & Nowrouzezahrai's curve scatter, on [`curve`] (the Bézier and the
//!   arc) and [`line`] (the segments' rasteriser);
//! - [`stretch`]: Wloka & Zeleznik's vertex stretch, on [`triangle`] (its rasteriser).
//!
//! Each pass hands the stages a backend may run elsewhere to it through its own `Stages` trait
//! ([`crate::stages`]); [`Stages`] is all three, the bound a backend meets.

pub mod carry;
pub mod curve;
pub mod dilate;
pub mod line;

pub mod neighbor_max;
pub mod reconstruct;
pub mod scatter;
pub mod shutter;
pub mod stretch;
pub mod tile_max;
pub mod triangle;

use crate::frame::Passes;
pub use reconstruct::{ReconstructParams, Variant};
pub use scatter::{CurveKind, Normalize, ScatterParams, Weight};
pub use shutter::Shutter;
pub use stretch::{Anchor, StretchParams};

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

    /// Copies of a frame's light layers the pass holds beyond what the memory estimate's
    /// planes factor counts (`io::passes::memory`): stretch carries them packed pixel-major,
    /// its input and output side by side, one more copy than the layers read (four 1080p
    /// frames of seventeen RGB layers peaked at 2541–2706 MiB where the planes alone allowed
    /// 2414; the passes that run each layer in the beauty's place or sum into their own
    /// planes stay within it).
    pub fn layer_copies(self) -> u64 {
        match self {
            Algorithm::Stretch => 1,
            _ => 0,
        }
    }

    /// Whether the algorithm moves each pixel's colour along that pixel's own motion and
    /// nothing else (scatter's curves; reconstruct gathers through a tile grid of its
    /// neighbours' longest motions, stretch draws a mesh of them), so that a view layer's
    /// edge pixel keeps its own vector where it is the surface's rather than its misses'
    /// average (`stack::prepare_for_motion`).
    pub fn moves_each_pixel_alone(self) -> bool {
        self == Algorithm::Scatter
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

/// Every motion pass's stages, as a backend runs them: the bound [`crate::process`] puts on
/// a backend (each pass's own trait says what it may run elsewhere; the CPU's defaults are
/// the reference).
pub trait Stages: reconstruct::Stages + scatter::Stages + stretch::Stages {}

impl<T: reconstruct::Stages + scatter::Stages + stretch::Stages> Stages for T {}
