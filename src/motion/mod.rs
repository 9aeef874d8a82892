//! Motion-blur algorithms. Each takes a canonical [`Frame`] holding the passes it declared in
//! [`Algorithm::needs`] and returns the blurred colour: `reconstruct` (McGuire 2012: the
//! `tile_max`, `neighbor_max` and `reconstruct` passes) and `scatter` (Guertin &
//! Nowrouzezahrai: the `curve`, `line` and `scatter` modules) and `stretch` (Wloka: the
//! `triangle` and `stretch` modules).

pub mod curve;
pub mod line;
pub mod neighbor_max;
pub mod reconstruct;
pub mod scatter;
pub mod stretch;
pub mod tile_max;
pub mod triangle;

use crate::frame::{Frame, Passes};

/// Colour (and reconstruct's depth) magnitudes beyond this are clamped: far above any
/// radiance, and small enough that sums of many stay finite in f32.
pub const HUGE: f32 = 1e30;

/// Colour made finite: NaN reads as 0, magnitudes are clamped to [`HUGE`].
#[inline]
pub(crate) fn sanitize_color(v: f32) -> f32 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(-HUGE, HUGE)
    }
}

/// Depth made comparable: NaN is far (+∞), negative is 0.
#[inline]
pub(crate) fn sanitize_depth_far(z: f32) -> f32 {
    if z.is_nan() {
        f32::INFINITY
    } else {
        z.max(0.0)
    }
}
pub use reconstruct::{ReconstructParams, Variant};
pub use scatter::{CurveKind, Normalize, ScatterParams, Weight};
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

/// Parameters shared by every blur.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlurParams {
    /// Fraction of the frame interval the shutter is open (0.5 = 180°), centred on the frame.
    pub shutter: f32,
    pub reconstruct: ReconstructParams,
    pub scatter: ScatterParams,
    pub stretch: StretchParams,
    /// Depth of field, run before the motion blur when set ("DoF before MB", Sousa).
    pub dof: Option<crate::dof::DofParams>,
}

impl Default for BlurParams {
    fn default() -> Self {
        BlurParams {
            shutter: 0.5,
            reconstruct: ReconstructParams::default(),
            scatter: ScatterParams::default(),
            stretch: StretchParams::default(),
            dof: None,
        }
    }
}

/// The passes a job reads: the algorithm's, and colour and depth for depth of field.
pub fn needs(algorithm: Algorithm, params: &BlurParams) -> Passes {
    let mut passes = algorithm.needs();
    if let Some(dof) = &params.dof {
        passes = passes.union(dof.needs());
    }
    passes
}

/// Applies depth of field when asked for, then the algorithm, to frame number `frame_number` (it seeds the per-pixel jitter, so
/// the output depends on nothing else). The output frame holds the blurred colour (other
/// passes are dropped: only colour is written).
pub fn apply(algorithm: Algorithm, params: &BlurParams, frame: Frame, frame_number: i64) -> Frame {
    let frame = match &params.dof {
        Some(dof) => crate::dof::apply(frame, dof),
        None => frame,
    };
    match algorithm {
        Algorithm::Reconstruct => reconstruct::reconstruct(
            frame,
            &params.reconstruct,
            params.shutter,
            frame_number as u64,
        ),
        Algorithm::Scatter => scatter::scatter(frame, &params.scatter, params.shutter),
        Algorithm::Stretch => stretch::stretch(frame, &params.stretch, params.shutter),
        Algorithm::None => Frame {
            depth: None,
            velocity: None,
            prev: None,
            next: None,
            ..frame
        },
    }
}
