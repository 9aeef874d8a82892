//! scatter's parameters and the numbers its stages read: the weights, normalisations and
//! curves to choose from, and the config (the GPU twin's uniform, `ScatterConfig` in
//! src/gpu/motion/scatter/scatter.wgsl), with the constants that bound the work.

use crate::motion::shutter::Shutter;

/// A pixel whose curve stays within this many pixels of p(0) over the shutter is still: its
/// streak would be under half a pixel.
pub const STILL: f64 = 0.25;
/// The most segments a curve is cut into.
pub const MOST_SEGMENTS: usize = 64;
/// Output tiles are this many pixels wide and high.
pub(super) const TILE_W: usize = 256;
pub(super) const TILE_H: usize = 128;
/// Reach is kept per block of this many pixels square.
pub(crate) const BLOCK: usize = 16;
/// Below this uncovered share an exposure-normalised pixel needs no background estimate.
pub const COVERED: f64 = 1e-3;

/// The weight along the curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weight {
    /// The paper's Gaussian in s, μ = ½.
    Gaussian,
    /// Every instant of the exposure the same: the ideal shutter.
    Box,
}

impl Weight {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, Weight)] =
        &[("box", Weight::Box), ("gaussian", Weight::Gaussian)];
}

/// How accumulated curves and the pixel's own colour combine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Normalize {
    /// Eq. 4 with background weight w_b.
    Paper,
    /// Deposits as shares of the exposure, the rest filled with what lies behind.
    Exposure,
}

impl Normalize {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, Normalize)] = &[
        ("exposure", Normalize::Exposure),
        ("paper", Normalize::Paper),
    ];
}

/// The curve through the three positions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// The paper's quadratic Bézier.
    Bezier,
    /// A circular arc where the points turn, else the Bézier.
    Arc,
}

impl CurveKind {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, CurveKind)] =
        &[("bezier", CurveKind::Bezier), ("arc", CurveKind::Arc)];
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScatterParams {
    /// Line segments per curve (at most; see `flatness`). The paper's Δ = 11 points is 10
    /// segments.
    pub segments: usize,
    /// σ of the Gaussian weight, in units of s (the whole frame interval −1..1 is s = 0..1).
    pub sigma: f32,
    pub weight: Weight,
    /// w_b of eq. 4 (paper normalisation only).
    pub background_weight: f32,
    pub normalize: Normalize,
    pub curve: CurveKind,
    /// The longest a curve may be, in pixels: longer ones are scaled about p(0) to this length
    /// (which bounds the work per curve).
    pub max_curve: f32,
    /// Fewer segments where they stray no more than this many pixels from the curve (0: always
    /// `segments`). Short, straight motion then costs one segment.
    pub flatness: f32,
    /// A curve passes a pixel whose depth is at least its own depth / (1 + this) (relative).
    pub depth_tolerance: f32,
}

impl Default for ScatterParams {
    fn default() -> Self {
        ScatterParams {
            segments: 10,
            sigma: 2.0,
            weight: Weight::Box,
            background_weight: 5.0,
            normalize: Normalize::Exposure,
            curve: CurveKind::Bezier,
            max_curve: 256.0,
            flatness: 0.1,
            depth_tolerance: 0.02,
        }
    }
}

/// Everything scatter's stages read besides their buffers, as plain numbers: the shape of the
/// uniform of its GPU twin, `ScatterConfig` in src/gpu/motion/scatter/scatter.wgsl (keep the two
/// in sync; the size test here and the field test in src/gpu/motion/scatter/mod.rs guard the
/// layout).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct ScatterConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// Fraction of the frame interval the shutter is open.
    pub shutter: f32,
    /// Where the exposure sits about the frame, in exposures ([`super::Shutter::offset`]):
    /// the curve is kept over t ∈ [(offset − ½)·shutter, (offset + ½)·shutter].
    pub offset: f32,
    /// Line segments per curve, at most, in 1..=[`MOST_SEGMENTS`].
    pub segments: u32,
    /// σ of the Gaussian weight, in units of s.
    pub sigma: f32,
    /// 1 for the paper's Gaussian weight along the curve, 0 for the box.
    pub gaussian: u32,
    /// w_b of the paper's normalisation.
    pub background_weight: f32,
    /// 1 for the exposure normalisation, 0 for the paper's eq. 4.
    pub exposure: u32,
    /// 1 for circular arcs where the motion turns, 0 for the paper's Bézier.
    pub arc: u32,
    /// The longest a curve may be, pixels.
    pub max_curve: f32,
    /// Fewer segments where they stray at most this far from the curve, pixels.
    pub flatness: f32,
    /// A curve passes a pixel whose depth is at least its own / (1 + this).
    pub depth_tolerance: f32,
}

impl ScatterConfig {
    /// The weight along the curve, typed (the GPU reads `gaussian`).
    pub fn weight(&self) -> Weight {
        if self.gaussian != 0 {
            Weight::Gaussian
        } else {
            Weight::Box
        }
    }

    /// The normalisation, typed (the GPU reads `exposure`).
    pub fn normalize(&self) -> Normalize {
        if self.exposure != 0 {
            Normalize::Exposure
        } else {
            Normalize::Paper
        }
    }

    /// The curve, typed (the GPU reads `arc`).
    pub fn curve(&self) -> CurveKind {
        if self.arc != 0 {
            CurveKind::Arc
        } else {
            CurveKind::Bezier
        }
    }

    pub fn new(
        width: usize,
        height: usize,
        params: &ScatterParams,
        shutter: impl Into<Shutter>,
    ) -> Self {
        let shutter = shutter.into();
        ScatterConfig {
            width: width as u32,
            height: height as u32,
            shutter: shutter.open,
            offset: shutter.offset,
            segments: params.segments.clamp(1, MOST_SEGMENTS) as u32,
            sigma: params.sigma,
            gaussian: (params.weight == Weight::Gaussian) as u32,
            background_weight: params.background_weight.max(0.0),
            exposure: (params.normalize == Normalize::Exposure) as u32,
            arc: (params.curve == CurveKind::Arc) as u32,
            max_curve: params.max_curve,
            flatness: params.flatness,
            depth_tolerance: params.depth_tolerance,
        }
    }
}
