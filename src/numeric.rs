//! The numeric policy: what every non-finite or extreme input value becomes, written down once
//! and applied once, where a frame enters processing ([`sanitize`], called by
//! [`crate::process`]). Every pass after it may assume its inputs obey these rules, so no
//! kernel (and no GPU twin) carries sanitising of its own, every written frame is finite, and
//! every pass's work stays bounded by the frame size whatever comes in. Replaced values are
//! counted ([`Replaced`]) so the caller can report them; nothing is hidden.
//!
//! The rules, per pass, with their reasons:
//!
//! | pass | NaN | ±Inf and huge | negative |
//! |---|---|---|---|
//! | colour (R, G, B, A) | 0: no light, and transparent | clamped to ±[`HUGE`] | kept (HDR composites carry negative lobes) |
//! | depth | +∞: far, so it hides nothing | +∞ kept (far); −∞ is negative | 0: at the camera |
//! | CoC map (read as depth) | 0: in focus | clamped by depth of field to its largest CoC | 0 |
//! | velocity (x, y) | 0: still | clamped to ±[`VELOCITY_LIMIT`] | kept (a direction) |
//! | positions p(−1), p(+1) (x, y) | the pixel is still: both become its centre | clamped to ±[`POSITION_LIMIT`] | kept (off-screen) |
//! | positions' depth (z) | as depth | as depth | as depth |
//! | shutter φ | 0 (no exposure) | clamped to [0, 1] | 0 |
//!
//! Written as half (a half plate, `--half`), colour saturates at ±65504, half's largest value
//! ([`half_saturated`]): a pixel clamped to ±[`HUGE`] and blurred would otherwise overflow to
//! ±Inf around it. Data channels go back as they came.
//!
//! And in every pass but the shutter, a subnormal value (magnitude below 2⁻¹²⁶, `f32::MIN_POSITIVE`)
//! is 0: a GPU may flush subnormals to zero in any arithmetic (Vulkan leaves it to the
//! driver, and NVIDIA's does), so a depth of 1e-40 beside a depth of 0 would be nearer on the
//! CPU and the same on the GPU. Made 0 here, the two backends read the same numbers; nothing
//! visible is lost (a subnormal colour is 10⁻³⁸ of white, a subnormal depth is at the camera,
//! a subnormal velocity is still).
//!
//! The jitter of every pass comes from one 32-bit hash, [`hash`] (WGSL has no 64-bit
//! integers, so the GPU twins compute the same numbers).
//!
//! The one approximate comparison of floats every test uses, unit and integration alike, is
//! here too ([`close`], [`close_relative`], and [`all_close`] for slices), with its rules for
//! NaN and infinities written once (the `exr` crate keeps one such helper for the same reason).

use rayon::prelude::*;
use serde::Serialize;

use crate::frame::{Frame, Plane, Positions};

/// Colour magnitudes beyond this are clamped: far above any radiance, and small enough that
/// sums of many stay finite in f32 (1e30 · 1e8 taps < 3.4e38).
pub const HUGE: f32 = 1e30;

/// Velocity components beyond this many pixels per frame are clamped: 5000 times the width of
/// an 8K frame, so a clamped pixel still blurs by every pass's largest blur, and small enough
/// that |v|² (1e14) and sums of it stay finite in f32 without `hypot`.
pub const VELOCITY_LIMIT: f32 = 1e7;

/// Position coordinates beyond this many pixels are clamped: far beyond any image, so the
/// motion keeps its direction and is cut to the largest blur by the pass, and well inside
/// f64's exact integers for the curve arithmetic.
pub const POSITION_LIMIT: f32 = 1e12;

/// Whether `v` is subnormal (nonzero, below the least normal f32).
#[inline]
fn subnormal(v: f32) -> bool {
    v != 0.0 && v.abs() < f32::MIN_POSITIVE
}

/// Whether `v` is 0 or normal in magnitude (not subnormal; false for NaN), branch-free.
#[inline]
fn not_subnormal(v: f32) -> bool {
    let a = v.abs();
    a == 0.0 || a >= f32::MIN_POSITIVE
}

/// A finite colour value as half, saturated at half's largest magnitude (65504) where f16
/// A number as a message shows it: plainly where that is short, in exponent form beyond
/// (`{}` of 5e-324 or 1e308 is over 300 digits).
pub fn shown(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e15).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// [`shown`] of an `f32`: as short as reads back as the same f32 (`1.3`, not the
/// `1.2999999523162842` of the f64 it widens to).
pub fn shown_f32(v: f32) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e15).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A figure taken from an image's samples and held as f64 (idiff's PSNR peak, the largest
/// magnitude in either image): as [`shown_f32`] where it is an f32 sample widened, else as
/// [`shown`] (a u32 ID beyond 2^24, which no f32 holds).
pub fn shown_sample(v: f64) -> String {
    let narrow = v as f32;
    if f64::from(narrow) == v {
        shown_f32(narrow)
    } else {
        shown(v)
    }
}

/// would overflow to ±Inf; NaN stays NaN (the numeric policy leaves none in colour).
pub fn half_saturated(v: f32) -> exr::prelude::f16 {
    use exr::prelude::f16;
    let limit = f16::MAX.to_f32();
    if v.is_finite() {
        f16::from_f32(v.clamp(-limit, limit))
    } else {
        f16::from_f32(v)
    }
}

/// Colour made finite: NaN and subnormals read as 0, magnitudes are clamped to [`HUGE`].
#[inline]
pub fn color(v: f32) -> f32 {
    if v.is_nan() || subnormal(v) {
        0.0
    } else {
        v.clamp(-HUGE, HUGE)
    }
}

/// Depth made comparable: NaN is far (+∞), negative and subnormal are 0.
#[inline]
pub fn depth(z: f32) -> f32 {
    if z.is_nan() {
        f32::INFINITY
    } else if subnormal(z) {
        0.0
    } else if z == 0.0 {
        // −0 kept, as the clean test keeps it (`max` may make it +0).
        z
    } else {
        z.max(0.0)
    }
}

/// A painted CoC map value made usable: NaN is in focus (0), negative and subnormal are 0.
/// (Depth of field clamps large values to its largest CoC.)
#[inline]
pub fn coc_map(v: f32) -> f32 {
    if v.is_nan() || subnormal(v) {
        0.0
    } else {
        v.max(0.0)
    }
}

/// A velocity component made finite: NaN and subnormals are still, magnitudes are clamped to
/// [`VELOCITY_LIMIT`].
#[inline]
pub fn velocity(v: f32) -> f32 {
    if v.is_nan() || subnormal(v) {
        0.0
    } else {
        v.clamp(-VELOCITY_LIMIT, VELOCITY_LIMIT)
    }
}

/// A position coordinate made finite, subnormals 0 (NaN is handled per pixel by
/// [`sanitize`]).
#[inline]
pub fn position(v: f32) -> f32 {
    if subnormal(v) {
        0.0
    } else {
        v.clamp(-POSITION_LIMIT, POSITION_LIMIT)
    }
}

/// The shutter fraction made usable: NaN is 0 (no exposure), the rest clamped to [0, 1].
#[inline]
pub fn shutter(phi: f32) -> f32 {
    if phi.is_nan() {
        0.0
    } else {
        phi.clamp(0.0, 1.0)
    }
}

/// The shutter offset made usable: NaN is 0 (centred), the rest clamped to [−½, ½].
#[inline]
pub fn shutter_offset(o: f32) -> f32 {
    if o.is_nan() {
        0.0
    } else {
        o.clamp(-0.5, 0.5)
    }
}

/// How many values of each pass [`sanitize`] replaced.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Replaced {
    pub color: usize,
    pub depth: usize,
    pub velocity: usize,
    /// Pixels whose p(−1) or p(+1) had a NaN coordinate, plus clamped coordinates and depths.
    pub positions: usize,
}

impl Replaced {
    pub fn any(&self) -> bool {
        *self != Replaced::default()
    }

    pub fn add(&mut self, other: Replaced) {
        self.color += other.color;
        self.depth += other.depth;
        self.velocity += other.velocity;
        self.positions += other.positions;
    }
}

/// What the depth plane holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthKind {
    /// Distance along the view axis.
    Depth,
    /// A painted circle-of-confusion map read in place of depth.
    CocMap,
}

/// Values handed to one task: enough work per task, and a fixed split so nothing depends on
/// the thread count (each value is replaced on its own anyway).
const CHUNK: usize = 1 << 14;

/// One pass's rule: `clean(v)` is true where `v` needs no change (a test that compiles to a
/// compare per value, so clean frames cost one read-only pass), `rule` makes any value clean.
struct Rule {
    clean: fn(f32) -> bool,
    rule: fn(f32) -> f32,
}

const COLOR: Rule = Rule {
    clean: |v| v.abs() <= HUGE && not_subnormal(v),
    rule: color,
};
const DEPTH: Rule = Rule {
    // +∞ is clean (far); NaN, negatives and subnormals are not (−0.0 compares equal to 0 and
    // is kept).
    clean: |z| z == 0.0 || z >= f32::MIN_POSITIVE,
    rule: depth,
};
const COC_MAP: Rule = Rule {
    clean: |v| v == 0.0 || v >= f32::MIN_POSITIVE,
    rule: coc_map,
};
const VELOCITY: Rule = Rule {
    clean: |v| v.abs() <= VELOCITY_LIMIT && not_subnormal(v),
    rule: velocity,
};
const POSITION: Rule = Rule {
    clean: |v| v.abs() <= POSITION_LIMIT && not_subnormal(v),
    rule: position,
};

/// Whether every value of `chunk` is clean (branch-free, so it vectorises).
#[inline]
fn all_clean(chunk: &[f32], clean: fn(f32) -> bool) -> bool {
    chunk.iter().fold(true, |ok, &v| ok & clean(v))
}

/// Applies `rule` to every value of `plane`, returning how many it changed. Chunks that are
/// clean are only read.
fn apply(plane: &mut Plane, rule: &Rule) -> usize {
    plane
        .par_chunks_mut(CHUNK)
        .map(|chunk| {
            if all_clean(chunk, rule.clean) {
                return 0;
            }
            let mut changed = 0;
            for v in chunk {
                let clean = (rule.rule)(*v);
                changed += (clean.to_bits() != v.to_bits()) as usize;
                *v = clean;
            }
            changed
        })
        .sum()
}

/// Applies the policy to every pass the frame holds, in place.
pub fn sanitize(frame: &mut Frame, depth_kind: DepthKind) -> Replaced {
    let mut replaced = Replaced::default();
    if let Some(color) = frame.color.as_mut() {
        for plane in [&mut color.r, &mut color.g, &mut color.b] {
            replaced.color += apply(plane, &COLOR);
        }
        if let Some(a) = color.a.as_mut() {
            replaced.color += apply(a, &COLOR);
        }
    }
    // The colour layers carried beside the beauty are blurred with it: the same policy.
    // Data layers come back as they were read.
    for channel in &mut frame.carried.channels {
        if channel.class == crate::frame::LayerClass::Colour {
            replaced.color += apply(&mut channel.plane, &COLOR);
        }
    }
    if let Some(plane) = frame.depth.as_mut() {
        replaced.depth += match depth_kind {
            DepthKind::Depth => apply(plane, &DEPTH),
            DepthKind::CocMap => apply(plane, &COC_MAP),
        };
    }
    if let Some(v) = frame.velocity.as_mut() {
        replaced.velocity += apply(&mut v.x, &VELOCITY) + apply(&mut v.y, &VELOCITY);
    }
    let width = frame.width;
    for positions in [frame.prev.as_mut(), frame.next.as_mut()]
        .into_iter()
        .flatten()
    {
        if let Some(z) = positions.z.as_mut() {
            replaced.positions += apply(z, &DEPTH);
        }
    }
    // Coordinates: clean frames are only read. Otherwise a NaN coordinate in either position
    // makes the pixel still (both become its centre), and the rest are clamped.
    let planes_clean = |p: &Positions| {
        p.x.par_chunks(CHUNK)
            .chain(p.y.par_chunks(CHUNK))
            .all(|c| all_clean(c, POSITION.clean))
    };
    let (prev, next) = (frame.prev.as_mut(), frame.next.as_mut());
    if prev.as_deref().is_some_and(|p| !planes_clean(p))
        || next.as_deref().is_some_and(|p| !planes_clean(p))
    {
        replaced.positions += still_where_nan(prev, next, width);
    }
    replaced
}

/// Makes pixels with a NaN coordinate in p(−1) or p(+1) still (both positions at the pixel's
/// centre), then clamps every coordinate; returns the pixels made still plus the
/// coordinates clamped.
fn still_where_nan(
    mut prev: Option<&mut Positions>,
    mut next: Option<&mut Positions>,
    width: usize,
) -> usize {
    let nan_at = |p: &Option<&mut Positions>, i: usize| {
        p.as_ref()
            .is_some_and(|p| p.x[i].is_nan() || p.y[i].is_nan())
    };
    let n = prev.as_ref().or(next.as_ref()).map_or(0, |p| p.x.len());
    let still: Vec<usize> = (0..n)
        .filter(|&i| nan_at(&prev, i) || nan_at(&next, i))
        .collect();
    for p in [prev.as_deref_mut(), next.as_deref_mut()]
        .into_iter()
        .flatten()
    {
        for &i in &still {
            let (x, y) = crate::frame::pixel_centre(i, width);
            (p.x[i], p.y[i]) = (x, y);
        }
    }
    let mut changed = still.len();
    for p in [prev, next].into_iter().flatten() {
        changed += apply(&mut p.x, &POSITION) + apply(&mut p.y, &POSITION);
    }
    changed
}

/// PCG's output permutation (Jarzynski & Olano 2020, *Hash Functions for GPU Rendering*:
/// the best quality per cost of the 32-bit hashes they measured).
#[inline]
fn pcg(v: u32) -> u32 {
    let state = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The one hash of every jitter: a well-mixed 32-bit value of (seed, stream, index), each
/// 32 bits (frame numbers and pixel indices wrap), computed the same in WGSL.
#[inline]
pub fn hash(seed: u32, stream: u32, index: u32) -> u32 {
    pcg(index ^ pcg(stream ^ pcg(seed)))
}

/// A uniform number in [0, 1) from [`hash`]: its top 24 bits, exact in f32.
#[inline]
pub fn unit(seed: u32, stream: u32, index: u32) -> f32 {
    (hash(seed, stream, index) >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// The float types the approximate comparisons take: f32 and f64.
pub trait Float:
    Copy
    + PartialOrd
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::fmt::Debug
    + std::fmt::Display
    + sealed::Sealed
{
    fn is_nan(self) -> bool;
    fn is_infinite(self) -> bool;
    fn abs(self) -> Self;
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for f64 {}
}

macro_rules! float {
    ($t:ty) => {
        impl Float for $t {
            #[inline]
            fn is_nan(self) -> bool {
                <$t>::is_nan(self)
            }
            #[inline]
            fn is_infinite(self) -> bool {
                <$t>::is_infinite(self)
            }
            #[inline]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
        }
    };
}
float!(f32);
float!(f64);

/// Whether `a` and `b` agree within `tolerance`: |a − b| ≤ tolerance.
///
/// The rules for what is not a number, so a test never passes by accident:
/// - NaN is close only to NaN: a NaN where a number was expected fails, whatever the
///   tolerance, and a NaN expected must come out NaN (any payload).
/// - An infinity is close only to the same infinity, whatever the tolerance (+∞ is not close
///   to −∞, nor to `f32::MAX`).
/// - A tolerance of 0 asks for equality (−0 equals +0); a NaN or negative tolerance makes no
///   two finite numbers close.
#[inline]
pub fn close<T: Float>(a: T, b: T, tolerance: T) -> bool {
    if a.is_nan() || b.is_nan() {
        a.is_nan() && b.is_nan()
    } else if a.is_infinite() || b.is_infinite() {
        a == b
    } else {
        (a - b).abs() <= tolerance
    }
}

/// Whether `actual` is within `relative` of `expected`'s magnitude: |actual − expected| ≤
/// relative·|expected|, with [`close`]'s rules for NaN and infinities. (An expected 0 asks for
/// exactly 0: give an absolute tolerance to [`close`] where values near 0 are meant.)
#[inline]
pub fn close_relative<T: Float>(actual: T, expected: T, relative: T) -> bool {
    close(actual, expected, relative * expected.abs())
}

/// Where two slices compared by [`all_close`] first disagree.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mismatch<T> {
    /// The slices differ in length.
    Lengths { actual: usize, expected: usize },
    /// The first index whose values are not [`close`].
    At {
        index: usize,
        actual: T,
        expected: T,
    },
}

impl<T: Float> std::fmt::Display for Mismatch<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Mismatch::Lengths { actual, expected } => {
                write!(f, "{actual} values where {expected} were expected")
            }
            Mismatch::At {
                index,
                actual,
                expected,
            } => write!(f, "index {index}: got {actual}, expected {expected}"),
        }
    }
}

/// Whether every value of `actual` is [`close`] to the value of `expected` at the same index
/// (and the lengths agree); otherwise the first place they disagree.
pub fn all_close<T: Float>(actual: &[T], expected: &[T], tolerance: T) -> Result<(), Mismatch<T>> {
    if actual.len() != expected.len() {
        return Err(Mismatch::Lengths {
            actual: actual.len(),
            expected: expected.len(),
        });
    }
    match actual
        .iter()
        .zip(expected)
        .position(|(&a, &e)| !close(a, e, tolerance))
    {
        Some(index) => Err(Mismatch::At {
            index,
            actual: actual[index],
            expected: expected[index],
        }),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{Color, Velocity};

    #[test]
    fn every_rule_gives_finite_or_far_values() {
        for v in [
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1e38,
            -1e38,
            -1.0,
            0.5,
        ] {
            assert!(color(v).is_finite());
            assert!(velocity(v).is_finite());
            // (NaN positions are made still per pixel by `sanitize`.)
            assert!(position(v).is_finite() || v.is_nan());
            assert!(coc_map(v).is_finite() || v == f32::INFINITY);
            assert!(depth(v) >= 0.0, "{v}");
            assert!((0.0..=1.0).contains(&shutter(v)));
        }
        assert_eq!(color(f32::NAN), 0.0);
        assert_eq!(depth(f32::NAN), f32::INFINITY);
        assert_eq!(depth(-3.0), 0.0);
        assert_eq!(coc_map(f32::NAN), 0.0);
        assert_eq!(velocity(f32::INFINITY), VELOCITY_LIMIT);
        assert_eq!(shutter(f32::NAN), 0.0);
        // (VELOCITY_LIMIT·√2)² stays finite in f32.
        let v = VELOCITY_LIMIT;
        assert!((v * v + v * v).is_finite());
    }

    #[test]
    fn sanitize_counts_what_it_replaced_and_stills_nan_positions() {
        let mut f = Frame::new(3, 1);
        f.color = Some(Color {
            r: vec![f32::NAN, 1.0, 2.0],
            g: vec![0.0, f32::INFINITY, 0.0],
            b: vec![0.0; 3],
            a: None,
        });
        f.depth = Some(vec![-1.0, f32::NAN, 4.0]);
        f.velocity = Some(Velocity {
            x: vec![f32::NAN, 1.0, 0.0],
            y: vec![0.0; 3],
        });
        let at = |x: Vec<f32>| Positions {
            x,
            y: vec![0.5; 3],
            z: None,
        };
        f.prev = Some(at(vec![0.5, f32::NAN, 2.0]));
        f.next = Some(at(vec![0.5, 1.5, f32::INFINITY]));
        let replaced = sanitize(&mut f, DepthKind::Depth);
        assert_eq!(
            replaced,
            Replaced {
                color: 2,
                depth: 2,
                velocity: 1,
                // The infinite next x, and the pixel with a NaN prev x.
                positions: 2,
            }
        );
        let color = f.color.as_ref().unwrap();
        assert_eq!(color.r[0], 0.0);
        assert_eq!(color.g[1], HUGE);
        assert_eq!(f.depth.as_ref().unwrap(), &vec![0.0, f32::INFINITY, 4.0]);
        // Pixel 1 is still: both positions are its centre (1.5, 0.5).
        let (prev, next) = (f.prev.as_ref().unwrap(), f.next.as_ref().unwrap());
        assert_eq!(
            (prev.x[1], prev.y[1], next.x[1], next.y[1]),
            (1.5, 0.5, 1.5, 0.5)
        );
        assert_eq!(next.x[2], POSITION_LIMIT);
        // A second pass replaces nothing.
        assert!(!sanitize(&mut f, DepthKind::Depth).any());
    }

    #[test]
    fn subnormal_values_read_as_zero_in_every_pass() {
        // 1e-40 and −1e-40 are subnormal f32: a GPU may flush them to 0 in any arithmetic
        // (NVIDIA's does), so the policy makes them 0 for both backends; 0, −0 and the least
        // normal value stay as they are.
        let tiny = f32::MIN_POSITIVE;
        let mut f = Frame::new(4, 1);
        let values = vec![1e-40, -1e-40, -0.0, tiny];
        f.color = Some(Color {
            r: values.clone(),
            g: values.clone(),
            b: values.clone(),
            a: Some(values.clone()),
        });
        f.depth = Some(values.clone());
        f.velocity = Some(Velocity {
            x: values.clone(),
            y: values.clone(),
        });
        let at = || Positions {
            x: values.clone(),
            y: values.clone(),
            z: Some(values.clone()),
        };
        f.prev = Some(at());
        f.next = Some(at());
        let replaced = sanitize(&mut f, DepthKind::Depth);
        assert_eq!(
            replaced,
            Replaced {
                color: 8,
                depth: 2,
                velocity: 4,
                positions: 12,
            }
        );
        let bits = |p: &[f32]| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        let want = bits(&[0.0, 0.0, -0.0, tiny]);
        let color = f.color.as_ref().unwrap();
        for plane in [&color.r, &color.g, &color.b, color.a.as_ref().unwrap()] {
            assert_eq!(bits(plane), want);
        }
        // Depth: −1e-40 is negative (0 by the policy), −0 is kept.
        assert_eq!(bits(f.depth.as_ref().unwrap()), want);
        let v = f.velocity.as_ref().unwrap();
        assert_eq!((bits(&v.x), bits(&v.y)), (want.clone(), want.clone()));
        for p in [f.prev.as_ref().unwrap(), f.next.as_ref().unwrap()] {
            assert_eq!(bits(&p.x), want);
            assert_eq!(bits(&p.y), want);
            assert_eq!(bits(p.z.as_ref().unwrap()), want);
        }
        let mut coc = Frame::new(2, 1);
        coc.depth = Some(vec![1e-40, 2.0]);
        sanitize(&mut coc, DepthKind::CocMap);
        assert_eq!(coc.depth.unwrap(), vec![0.0, 2.0]);
    }

    #[test]
    fn a_coc_map_reads_nan_as_in_focus() {
        let mut f = Frame::new(2, 1);
        f.depth = Some(vec![f32::NAN, -2.0]);
        sanitize(&mut f, DepthKind::CocMap);
        assert_eq!(f.depth.unwrap(), vec![0.0, 0.0]);
    }

    #[test]
    fn the_hash_matches_pcg_and_spreads_evenly() {
        // PCG's permutation of 0, worked by hand: state = 2891336453 = 0xAC564B05;
        // state >> 28 = 10, so word = ((state >> 14) ^ state) · 277803737 mod 2³².
        let state: u32 = 2_891_336_453;
        let word = ((state >> 14) ^ state).wrapping_mul(277_803_737);
        assert_eq!(pcg(0), (word >> 22) ^ word);
        // Uniform in [0, 1): 64k draws into 16 bins pass a χ² test (15 degrees of freedom:
        // 37.7 is the 99.9 % quantile; a constant or a 4-valued hash scores in the thousands).
        let mut bins = [0usize; 16];
        let n = 1 << 16;
        for i in 0..n {
            let u = unit(7, 1, i);
            assert!((0.0..1.0).contains(&u));
            bins[(u * 16.0) as usize] += 1;
        }
        let expected = (n / 16) as f64;
        let chi2: f64 = bins
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        assert!(chi2 < 37.7, "{chi2} {bins:?}");
        // Neighbouring seeds and pixels are uncorrelated: half the bits differ on average.
        let flips: u32 = (0..1000u32)
            .map(|i| {
                (hash(1, 0, i) ^ hash(2, 0, i)).count_ones()
                    + (hash(1, 0, i) ^ hash(1, 0, i + 1)).count_ones()
            })
            .sum();
        let mean = flips as f64 / 2000.0;
        assert!(close(mean, 16.0, 0.5), "{mean}");
    }

    #[test]
    fn close_compares_within_the_tolerance_inclusive() {
        assert!(close(1.0f32, 1.25, 0.25));
        assert!(close(1.25f32, 1.0, 0.25));
        assert!(!close(1.0f32, 1.25, 0.2));
        assert!(close(-0.0f32, 0.0, 0.0));
        assert!(close(3.0f64, 3.0, 0.0));
        assert!(!close(3.0f64, 3.0 + 1e-12, 0.0));
        // A NaN or negative tolerance makes no two numbers close, equal ones included.
        assert!(!close(1.0f32, 1.0, f32::NAN));
        assert!(!close(1.0f64, 1.0, -1.0));
    }

    #[test]
    fn close_holds_nan_close_only_to_nan_and_infinities_only_to_themselves() {
        for tolerance in [0.0, 1.0, f32::MAX, f32::INFINITY] {
            assert!(close(f32::NAN, f32::NAN, tolerance));
            assert!(!close(f32::NAN, 0.0, tolerance));
            assert!(!close(0.0, f32::NAN, tolerance));
            assert!(!close(f32::NAN, f32::INFINITY, tolerance));
            assert!(close(f32::INFINITY, f32::INFINITY, tolerance));
            assert!(close(f32::NEG_INFINITY, f32::NEG_INFINITY, tolerance));
            assert!(!close(f32::INFINITY, f32::NEG_INFINITY, tolerance));
            assert!(!close(f32::INFINITY, f32::MAX, tolerance));
            assert!(!close(f32::MAX, f32::INFINITY, tolerance));
        }
        // Any NaN payload.
        assert!(close(f64::NAN, -f64::NAN, 0.0));
    }

    #[test]
    fn close_relative_scales_with_the_expected_value() {
        assert!(close_relative(101.0f64, 100.0, 0.01));
        assert!(!close_relative(101.5f64, 100.0, 0.01));
        assert!(close_relative(-99.0f32, -100.0, 0.01));
        // Relative to the expected value, not the actual one.
        assert!(!close_relative(100.0f64, 99.0, 0.01));
        assert!(close_relative(0.0f32, 0.0, 0.5));
        assert!(!close_relative(1e-30f32, 0.0, 0.5));
        assert!(!close_relative(f32::NAN, 1.0, 1.0));
        assert!(close_relative(f64::INFINITY, f64::INFINITY, 0.0));
    }

    #[test]
    fn all_close_names_the_first_disagreement_or_the_lengths() {
        assert_eq!(
            all_close(&[1.0f32, f32::NAN], &[1.1, f32::NAN], 0.2),
            Ok(())
        );
        assert_eq!(all_close::<f64>(&[], &[], 0.0), Ok(()));
        let got = all_close(&[1.0f32, 2.0, 5.0, 9.0], &[1.0, 2.5, 5.0, 0.0], 0.1);
        assert_eq!(
            got,
            Err(Mismatch::At {
                index: 1,
                actual: 2.0,
                expected: 2.5
            })
        );
        assert_eq!(got.unwrap_err().to_string(), "index 1: got 2, expected 2.5");
        let got = all_close(&[0.0f64; 2], &[0.0; 3], 1.0);
        assert_eq!(
            got,
            Err(Mismatch::Lengths {
                actual: 2,
                expected: 3
            })
        );
        assert_eq!(
            got.unwrap_err().to_string(),
            "2 values where 3 were expected"
        );
    }
}
