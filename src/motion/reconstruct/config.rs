//! reconstruct's parameters and the numbers every stage reads: the variants, the config
//! (the GPU twin's uniform, `ReconstructConfig` in src/gpu/motion/reconstruct.wgsl), the
//! clamped half-spread velocity of each form, and the texel layouts the pack writes and the
//! gathers and the matte read.

use crate::motion::shutter::Shutter;
use crate::numeric::HUGE;

/// Half a pixel: velocities at or below it do not blur (the paper's 0.5 px).
pub const HALF_PIXEL: f32 = 0.5;

/// The paper's ε: guards `|q| + ε` and the early-out test.
pub const EPSILON: f32 = 0.01;

/// |V|² above which a pixel blurs: (0.5 px + ε)².
pub const MOVING_SQUARED: f32 = (HALF_PIXEL + EPSILON) * (HALF_PIXEL + EPSILON);

/// Which taps the gather takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Listing 1: every tap along ±NeighborMax.
    Paper,
    /// Every other tap along the pixel's own velocity instead (McGuire's later G3D code and
    /// Jimenez 2014 sample both directions), so a pixel moving across its neighbourhood's
    /// dominant motion still blurs along its own.
    Dual,
    /// Guertin, McGuire & Nowrouzezahrai 2014 with Jimenez 2014's changes, as Blender's EEVEE
    /// and compositor Vector Blur run it: tiles dilated along their motion ([`dilate`]), taps
    /// along both the tile's and the pixel's own vector on each side, foreground and
    /// background accumulated apart (see [`gather_pixel_2014`]).
    Stable,
    /// The 2014 filter with the box shutter's weights (ours, measured in BENCHMARKS.md): a
    /// tap reaches the centre within half a pixel of its spread (not a whole one), the tap
    /// count alone normalises (the centre holds no slot of its own), a tap counts whichever
    /// way it moves along its line (the shutter is centred: a tap moving against the line
    /// reaches the centre in the other half), and what the taps leave uncovered is filled
    /// with the centre's own surface for the share of the shutter it covers the pixel
    /// (1/(2|V|)) and the background behind it for the rest. Each tap is read between
    /// pixels and split by surface ([`split`]), by each pixel's coverage where a moving
    /// surface's edge crosses it ([`split_by_cover`], [`matte`]), and the taps along
    /// the pixel's own vector sit half a step from those along the tile's.
    Exposure,
}

impl Variant {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, Variant)] = &[
        ("paper", Variant::Paper),
        ("dual", Variant::Dual),
        ("2014", Variant::Stable),
        ("exposure", Variant::Exposure),
    ];

    /// The number the config carries.
    #[inline]
    pub fn code(self) -> u32 {
        match self {
            Variant::Paper => 0,
            Variant::Dual => 1,
            Variant::Stable => 2,
            Variant::Exposure => 3,
        }
    }

    /// The variant a config's code names ([`Variant::code`]); an unknown code is the
    /// default's.
    #[inline]
    pub fn from_code(code: u32) -> Variant {
        Variant::ALL
            .iter()
            .map(|&(_, v)| v)
            .find(|v| v.code() == code)
            .unwrap_or(Variant::Exposure)
    }

    /// Whether this variant is the 2014 filter's (dilated tiles, split accumulation).
    #[inline]
    pub fn is_2014(self) -> bool {
        matches!(self, Variant::Stable | Variant::Exposure)
    }
}

/// Parameters. The defaults are the exposure variant's, the lowest error of the variants on
/// every truth scene (BENCHMARKS.md); the paper's were k 20, S 15.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReconstructParams {
    /// k: the largest blur radius in pixels. paper and dual: also the tile size (paper: 20);
    /// the 2014 variants' tiles stay at 8 px and their dilation carries longer vectors.
    pub max_blur: usize,
    /// S: filter taps, odd. paper and dual: taps along the line; the 2014 variants: ⌈S/4⌉ per
    /// side of the centre along each of the tile's and the pixel's own vector (S + 1 in all
    /// when the pixel moves).
    pub taps: usize,
    /// SOFT_Z_EXTENT in scene units (the paper used 1 mm to 10 cm).
    pub soft_z: f32,
    /// Jitter the taps per pixel (a hash of frame and pixel) to trade ghosting for noise.
    pub jitter: bool,
    pub variant: Variant,
}

impl Default for ReconstructParams {
    fn default() -> Self {
        ReconstructParams {
            max_blur: 128,
            taps: 31,
            soft_z: 0.1,
            jitter: true,
            variant: Variant::Exposure,
        }
    }
}

/// Everything reconstruct's stages read besides their buffers, as plain numbers: the uniform
/// of its GPU twin, `ReconstructConfig` in src/gpu/motion/reconstruct.wgsl (keep the two in sync; the
/// size test below guards the layout).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct ReconstructConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// k: the tile size, pixels (the paper's tiles are k×k).
    pub tile: u32,
    /// k as the largest half-spread, pixels.
    pub k: f32,
    /// Fraction of the frame interval the shutter is open.
    pub shutter: f32,
    /// Where the exposure sits about the frame, in exposures ([`Shutter::offset`]): 0 centred,
    /// +½ opening at the frame, −½ closing at it. A surface's streak is its centred one
    /// moved by 2·offset·V along its own half-spread V.
    pub offset: f32,
    /// S: taps per pixel, odd.
    pub taps: u32,
    /// 1 / SOFT_Z_EXTENT, per scene unit.
    pub inv_soft_z: f32,
    /// 1 to jitter the taps per pixel, else 0.
    pub jitter: u32,
    /// The variant: 0 paper, 1 dual (every other tap along the pixel's own velocity), 2 the
    /// 2014 filter, 3 the 2014 filter with exposure weights ([`Variant::code`]).
    pub variant: u32,
    /// The jitter's seed: the frame number modulo 2³².
    pub seed: u32,
}

impl ReconstructConfig {
    /// The variant, typed ([`Variant::from_code`] of the code the GPU reads).
    #[inline]
    pub fn variant(&self) -> Variant {
        Variant::from_code(self.variant)
    }

    /// Whether the taps are jittered per pixel, typed (the GPU reads the word).
    #[inline]
    pub fn jitters(&self) -> bool {
        self.jitter != 0
    }

    /// The 2014 gather's form under this config ([`Form::of`]).
    #[inline]
    pub fn form(&self) -> Form {
        Form::of(self)
    }
}

/// The most taps the exposure variant takes per side and direction however long the streak.
pub const MAX_TAPS_PER_SIDE: usize = 64;
/// The exposure variant's widest spacing of taps along a streak (px).
pub const TAP_SPACING: f32 = 2.0;

/// The numbers that tell the 2014 filter's two forms apart — Blender's (`2014`) and ours with
/// the box shutter's weights (`exposure`) — computed once per frame from the config, so the
/// gather reads what each choice does instead of asking which variant runs. The WGSL twin
/// computes the same in `fn form()` (src/gpu/motion/reconstruct.wgsl); each field's comment
/// gives both forms' values, ours first, and why ours differs (measured in BENCHMARKS.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Form {
    /// Where the jittered tile lookup lands on a tile the dilation left still, look up the
    /// pixel's own tile instead: ours always; Blender's only under an offset exposure, which
    /// reaches twice as far on one side and so misses more (a small fast object's corners).
    pub own_tile: bool,
    /// At least one tap per this many pixels of the longer vector on each side (up to
    /// [`MAX_TAPS_PER_SIDE`]), so a long streak is sampled as densely as a short one:
    /// ours [`TAP_SPACING`]; Blender's 0, ⌈S/4⌉ taps alone.
    pub tap_spacing: f32,
    /// How far past the centre's own spread a background tap still counts, px: ours half a
    /// pixel (the centre pixel's half-width, so a still pixel takes nothing from its
    /// neighbours behind it); Blender's a whole pixel.
    pub edge: f32,
    /// How far past its own spread a still foreground tap reaches, px (a moving one: a whole
    /// pixel in both): ours half a pixel, a still tap does not spread; Blender's a whole one.
    pub still_reach: f32,
    /// The slots of the tap count the centre holds: ours none (the taps alone normalise);
    /// Blender's one.
    pub centre_count: f32,
    /// Whether a still centre takes a second set of taps along the tile's vector, as a moving
    /// centre does along its own: ours (a still pixel a moving surface crosses samples its
    /// exposure as finely); Blender's gathers one set.
    pub still_second_set: bool,
    /// Whether the second set sits half a step off the first: ours (where the two vectors
    /// are one, the step halves instead of repeating); Blender's repeats the offset.
    pub half_step: bool,
    /// Whether each tap is read between pixels and split by surface (ours: [`super::gather_2014`]'s
    /// `split` and `split_by_cover`), or whole, colour bilinear over its nearest surface
    /// (Blender's, as a GPU's filtered texture read).
    pub split_taps: bool,
    /// Whether a tap moving against the line it was taken along counts: ours (the shutter is
    /// centred, so it reaches the centre in the other half); Blender's gathers each half of
    /// the shutter on its own side.
    pub either_way: bool,
    /// What the taps leave uncovered: ours the centre's own surface for the share of the
    /// shutter it covers the pixel, 1/(2|V|), and the background taps' average for the rest;
    /// Blender's the background average with a little of the centre mixed in.
    pub exposure_fill: bool,
    /// Whether a moving centre's taps that fall on a nearer surface which does not reach it
    /// (the background its streak runs behind, hidden at the frame's instant) read the
    /// background a whole streak's length (2|V|) back along the line instead, where it is
    /// visible: ours, except at a pixel beside such a surface (its rim, which holds part of
    /// that surface in its colour); Blender's fills them with the background taps' average.
    /// See [`super::gather_2014`].
    pub slide_hidden: bool,
}

impl Form {
    /// Ours, the exposure variant's, whatever the offset.
    pub const OURS: Form = Form {
        own_tile: true,
        tap_spacing: TAP_SPACING,
        edge: 0.5,
        still_reach: 0.5,
        centre_count: 0.0,
        still_second_set: true,
        half_step: true,
        split_taps: true,
        either_way: true,
        exposure_fill: true,
        slide_hidden: true,
    };

    /// Blender's, under a centred exposure (offset, it looks up its own tile too).
    pub const BLENDER: Form = Form {
        own_tile: false,
        tap_spacing: 0.0,
        edge: 1.0,
        still_reach: 1.0,
        centre_count: 1.0,
        still_second_set: false,
        half_step: false,
        split_taps: false,
        either_way: false,
        exposure_fill: false,
        slide_hidden: false,
    };

    /// The form `config` runs (paper and dual, which do not read it, get Blender's).
    #[inline]
    pub fn of(config: &ReconstructConfig) -> Form {
        if config.variant() == Variant::Exposure {
            Form::OURS
        } else {
            Form {
                own_tile: config.offset != 0.0,
                ..Form::BLENDER
            }
        }
    }
}

impl ReconstructConfig {
    pub fn new(
        width: usize,
        height: usize,
        params: &ReconstructParams,
        shutter: impl Into<Shutter>,
        seed: u32,
    ) -> Self {
        let shutter = shutter.into();
        let size = params.max_blur.max(1);
        ReconstructConfig {
            width: width as u32,
            height: height as u32,
            // The 2014 filter's tiles stay at most 32 px (Blender's size) whatever k: its
            // dilation carries longer vectors across as many tiles as they reach.
            tile: if params.variant.is_2014() {
                size.min(TILE_2014)
            } else {
                size
            } as u32,
            k: size as f32,
            shutter: shutter.open,
            offset: shutter.offset,
            taps: (params.taps.max(1) | 1) as u32,
            inv_soft_z: 1.0 / params.soft_z.max(1e-6),
            jitter: params.jitter as u32,
            variant: params.variant.code(),
            seed,
        }
    }
}

/// How far a streak reaches from its pixel, in half-spreads |V|: `1 + 2·|offset|` (1 for the
/// centred shutter, 2 when it opens or closes at the frame).
#[inline]
pub fn reach_factor(config: &ReconstructConfig) -> f32 {
    1.0 + 2.0 * config.offset.abs()
}

/// Far depth (+∞ under the numeric policy) as a finite number, so that the soft depth
/// comparison's differences stay finite.
#[inline]
pub(crate) fn finite_depth(z: f32) -> f32 {
    z.min(HUGE)
}

/// The clamped half-spread velocity of the paper: `V = q·max(0.5, min(|q|, k)) / (|q| + ε)`
/// with `q = ½·v·φ`.
#[inline]
pub fn half_spread(vx: f32, vy: f32, shutter: f32, k: f32) -> (f32, f32) {
    let (qx, qy) = (0.5 * vx * shutter, 0.5 * vy * shutter);
    let length = (qx * qx + qy * qy).sqrt();
    if length == 0.0 {
        return (0.0, 0.0);
    }
    let scale = HALF_PIXEL.max(length.min(k)) / (length + EPSILON);
    (qx * scale, qy * scale)
}

/// |V| of [`half_spread`] without forming V.
#[inline]
pub(crate) fn spread_length(vx: f32, vy: f32, shutter: f32, k: f32) -> f32 {
    let (qx, qy) = (0.5 * vx * shutter, 0.5 * vy * shutter);
    let length = (qx * qx + qy * qy).sqrt();
    if length == 0.0 {
        return 0.0;
    }
    HALF_PIXEL.max(length.min(k)) * length / (length + EPSILON)
}

/// The 2014 filter's half-spread: `q = ½·v·φ`, its length clamped to k (not raised to half a
/// pixel: the filter treats vectors under half a pixel as still).
#[inline]
pub fn spread_2014(vx: f32, vy: f32, config: &ReconstructConfig) -> (f32, f32) {
    let (qx, qy) = (0.5 * vx * config.shutter, 0.5 * vy * config.shutter);
    let length = (qx * qx + qy * qy).sqrt();
    if length > config.k {
        let scale = config.k / length;
        (qx * scale, qy * scale)
    } else {
        (qx, qy)
    }
}

/// One pixel's data for the gather, packed so a tap reads one cache line:
/// premultiplied R, G, B, A, depth, and 1 / |V| (infinite where still).
pub type Texel = [f32; 6];
pub(crate) const Z: usize = 4;
pub(crate) const INV_LENGTH: usize = 5;

/// One pixel's data for the 2014 gather: premultiplied R, G, B, A, depth, the half-spread
/// vector V (clamped to k, not raised to half a pixel) and |V|.
pub type Texel2014 = [f32; 8];
pub(crate) const VX: usize = 5;
pub(crate) const VY: usize = 6;
pub(crate) const LENGTH: usize = 7;

/// The 2014 filters' tile size at most (px), whatever k: the dilation carries longer vectors
/// across as many tiles as they reach. Smaller tiles keep the dominant vector local: on the
/// truth scenes at k 128, S 31, tiles of 8 px err 5–13 % less than 20 px on rotor, orbit,
/// figure and gears (BENCHMARKS.md), at no cost worth measuring.
pub(crate) const TILE_2014: usize = 8;

/// Taps evaluated together in the gather.
pub(crate) const LANES: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn half_spread_clamps_between_half_a_pixel_and_k() {
        // v = 10 px, φ = 0.5: q = 2.5 px, kept (up to ε).
        let (x, y) = half_spread(10.0, 0.0, 0.5, 20.0);
        assert!(close(x, 2.5 * 2.5 / 2.51, 1e-6) && y == 0.0);
        // Far above k: length k·|q|/(|q|+ε) ≈ k, direction kept.
        let (x, y) = half_spread(0.0, -1e6, 1.0, 20.0);
        assert!(x == 0.0 && close(y, -20.0, 1e-3));
        // Tiny motion grows to half a pixel; none stays none.
        let (x, _) = half_spread(0.1, 0.0, 0.5, 20.0);
        assert!(close(x, 0.5 * 0.025 / 0.035, 1e-6));
        assert_eq!(half_spread(0.0, 0.0, 0.5, 20.0), (0.0, 0.0));
        // Through the numeric policy, NaN is still and infinity is clamped to k.
        let v = crate::numeric::velocity;
        assert_eq!(half_spread(v(f32::NAN), 0.0, 0.5, 20.0), (0.0, 0.0));
        let (x, _) = half_spread(v(f32::INFINITY), 0.0, 0.5, 20.0);
        assert!(close(x, 20.0, 1e-3));
    }

    #[test]
    fn the_config_is_eleven_plain_words() {
        // Uploaded as one uniform by the GPU twin: eleven 4-byte fields, no padding.
        assert_eq!(std::mem::size_of::<ReconstructConfig>(), 44);
        let even = ReconstructParams {
            taps: 14,
            ..ReconstructParams::default()
        };
        // S is made odd (the centre tap is the pixel itself).
        assert_eq!(ReconstructConfig::new(8, 8, &even, 0.5, 1).taps, 15);
    }
}
