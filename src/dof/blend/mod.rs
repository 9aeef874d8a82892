//! `blend`: Wloka's depth-of-field blend (Arce & Wloka, seed 004, "Depth of Field:
//! Technique Overview" to "Render to Backbuffer").
//!
//! Inputs: colour and the signed CoC plane of [`super::coc_plane`]. Output: the colour with
//! depth of field. It sits before motion blur.
//!
//! - **Blurriness interpolator** `T = clamp((|CoC| − ε)/(E − ε), 0, 1)` per pixel.
//! - **Copies.** The talk's filter blit takes four bilinear taps whose effective kernel is
//!   `e/4 + (b+d+f+h)/8 + (a+c+g+i)/16`: the 3×3 binomial, which is [1 2 1]/4 across times
//!   [1 2 1]/4 down. n passes of it are exactly one pass of the binomial kernel
//!   C(2n, k)/4ⁿ across and down (variance n/2 px² per axis), so copy n is made in one
//!   separable pass of that kernel (cut where its weights fall below 1e-7 and renormalised)
//!   and copy 2n by another from copy n: O(√n) per pixel instead of O(n) passes.
//! - **Where the copies sit.** A disc of diameter C has variance C²/16 per axis, so copy n
//!   looks like a CoC of √(8n) px and copy 2n like √(16n). By default n = E²/16, so copy 2n
//!   stands for E. The talk blends sharp → n → 2n over T ∈ [0, ½, 1]; here each copy is
//!   placed at the CoC it actually shows and the blend runs along CoC = ε + T·(E − ε), which
//!   keeps a pixel's blur equal to its CoC between the copies.
//! - **Ghosting at transitions.** The talk lists "blurriness interpolator interpolation" and
//!   names the problem ("visibility on blurred edges potentially wrong") without giving the
//!   fix, so this is ours, in two parts:
//!   1. The copies blur colour premultiplied by `w = max(T, 1/64)` and divide by the blurred
//!      w, so sharp pixels lend almost nothing to the copies: an in-focus subject does not
//!      leave a ghost halo on the blurred background around it.
//!   2. The copies also blur `T_near` (T of pixels in front of the focus plane, 0 behind),
//!      and a pixel blends with `max(T, blurred T_near)`: a blurred foreground spreads over
//!      the sharp background behind its edge instead of stopping hard at its silhouette
//!      (the spread takes over only where it exceeds T by [`SPREAD_MARGIN`]).
//! - **Skip**: a frame whose CoC stays below ε is returned as it is (see [`super::apply`]);
//!   the copies are made only over the box around out-of-focus pixels that can reach any
//!   output, and pixels with T = 0 and no near blur reaching them are copied.
//!
//! Output is a convex mix of weighted averages of input pixels, computed in a fixed order.

use rayon::prelude::*;

use super::DofConfig;
use crate::frame::Color;

/// Weight of an in-focus pixel in the copies (relative to 1 for a fully blurred one).
const IN_FOCUS_WEIGHT: f32 = 1.0 / 64.0;

/// Binomial weights below this fraction of the centre weight are cut.
const CUT: f64 = 1e-7;

/// Depth of field by blending progressively blurred images of the frame; `coc` is the signed
/// CoC plane (px, diameter). The form (`config.blend_form`): 0 the pyramid, 1 the talk's two
/// copies.
pub fn blend(config: &DofConfig, color: Color, coc: &[f32]) -> Color {
    match config.blend_form {
        1 => talk(config, &color, coc),
        _ => pyramid(config, color, coc),
    }
}

// ---------------------------------------------------------------------------------------
// The pyramid.

/// One texel of a pyramid level: the colour offset by the reference and premultiplied by w
/// (r, g, b, a; a is 0 without alpha), w, T_near, and two lanes of padding, so that a texel is
/// one 8-lane vector and every sum over texels runs on all lanes at once.
type Texel = [f32; 8];

/// The lane of w in a [`Texel`].
const W: usize = 4;
/// The lane of T_near in a [`Texel`].
const NEAR: usize = 5;

const ZERO: Texel = [0.0; 8];

/// The most levels a pyramid gets (level 12 stands for a CoC of about 12 000 px).
const MAX_LEVELS: usize = 12;

/// Output rows of a level made by one task: its input rows are made once for the band, and
/// only the two rows at each end of a band twice.
const BAND: usize = 16;

/// One level of the pyramid: level L has a texel per 2^L × 2^L pixels of the frame.
struct Level {
    width: usize,
    height: usize,
    texels: Vec<Texel>,
}

/// Per-axis variance (px²) of the blur a pixel of the frame sees when it samples level L
/// bilinearly, averaged over the pixel's position in the level's grid.
///
/// Each halving filters with [1 3 3 1]/8 (variance 3/4 in the texels it reads, each of which
/// carries the variance of its own level, centred), so level L's texels have
/// Σ_{j<L} ¾·4ʲ = (4ᴸ − 1)/4. Bilinear sampling at offset φ from a texel (spacing s = 2ᴸ)
/// adds φ(1 − φ)·s²; the frame's pixel centres sit at φ = (k + ½)/2ᴸ, whose mean of
/// φ(1 − φ) is 1/6 + 1/(12·4ᴸ). Level 0 is the sharp frame. The tests blur an impulse
/// through the pyramid and check its second moment against this.
pub fn level_variance(level: usize) -> f64 {
    if level == 0 {
        return 0.0;
    }
    let s2 = 4f64.powi(level as i32);
    (s2 - 1.0) / 4.0 + s2 / 6.0 + 1.0 / 12.0
}

/// The CoC diameter (px) of a disc that blurs like a Gaussian of standard deviation σ (px):
/// `COC_PER_SIGMA · σ`. A disc of diameter C has variance C²/16 per axis, so matching the
/// variance would give 4σ; but the variance only fixes the lowest frequencies, and a disc's
/// response falls faster than a Gaussian's through the middle ones (the textures a viewer
/// sees blur). Here the two responses are equal where they have fallen to a quarter:
/// 2·J₁(πρC)/(πρC) = ¼ at πρC = 2.9268 and exp(−2π²σ²ρ²) = ¼ at 2πρσ = √(2 ln 4) = 1.6651,
/// so C = 2 · 2.9268 / 1.6651 · σ. Measured on `layers` at 640×360 (region RMSE, levels
/// mixed linearly in CoC): 0.0404 with 4σ, 0.0333 with this, 0.0335 with 3.33σ, 0.0350 with
/// 3.2σ (BENCHMARKS.md).
pub const COC_PER_SIGMA: f64 = 2.0 * 2.926_846 / 1.665_109;

/// Per-axis variance (px²) of the half step between the sharp frame and level 1: one pass of
/// the 3×3 filter, [1 2 1]/4 across and down, at full resolution. Level 1 stands for a CoC of
/// 4.3 px; without this step a pixel of CoC 2 would mix the sharp frame with it, and at
/// 240×135 on `layers` (CoCs up to 6 px) the pyramid erred more than the talk's copies.
const HALF_VARIANCE: f64 = 0.5;

/// The CoC diameter (px) that level L stands for (level 0, the sharp frame, for 0).
pub fn level_coc(level: usize) -> f32 {
    (COC_PER_SIGMA * level_variance(level).sqrt()) as f32
}

/// The CoC each blurred image stands for, and where a CoC sits between them. Image 0 is the
/// sharp frame (CoC 0); with `half`, image 1 is the frame under one pass of the 3×3 filter
/// (made where a pixel asks for it) and image j ≥ 2 is level j − 1; without, image j is
/// level j.
pub(crate) struct Ladder {
    pub cocs: Vec<f32>,
    /// 1 / (CoC of image k + 1 − CoC of image k).
    pub inverse_gaps: Vec<f32>,
    /// The CoCs of images 1 ..= top − 1 (then +∞): a CoC's image below is the count of
    /// these it reaches, found without a branch.
    bounds: [f32; BOUNDS],
    /// The image that is level 1.
    first: usize,
}

/// Room in [`Ladder::bounds`]: the sharp frame, the half step and every level.
const BOUNDS: usize = 16;
const _: () = assert!(MAX_LEVELS <= BOUNDS);

impl Ladder {
    /// The sharp frame, the half step if asked for, and levels 1 ..= `top`.
    fn new(top: usize, half: bool) -> Self {
        let mut cocs = vec![0.0];
        if half {
            cocs.push((COC_PER_SIGMA * HALF_VARIANCE.sqrt()) as f32);
        }
        cocs.extend((1..=top).map(level_coc));
        let inverse_gaps = cocs.windows(2).map(|c| 1.0 / (c[1] - c[0])).collect();
        let mut bounds = [f32::INFINITY; BOUNDS];
        let inner = &cocs[1..cocs.len() - 1];
        bounds[..inner.len()].copy_from_slice(inner);
        Ladder {
            cocs,
            inverse_gaps,
            bounds,
            first: if half { 2 } else { 1 },
        }
    }

    /// (k, f): level k mixed with level k + 1 by f, linearly in CoC between the CoCs the
    /// two stand for (clamped to the top level). The CoCs rise, so k, the last image below
    /// c short of the top, is the number of bounds c reaches.
    #[inline(always)]
    fn bracket(&self, c: f32) -> (usize, f32) {
        let top = self.cocs.len() - 1;
        let reached: u32 = self.bounds[..top - 1]
            .iter()
            .map(|&b| u32::from(c >= b))
            .sum();
        let k = reached as usize;
        let f = ((c - self.cocs[k]) * self.inverse_gaps[k]).clamp(0.0, 1.0);
        (k, f)
    }
}

/// Halves one row: texel i of the result is [1 3 3 1]/8 over texels 2i − 1 ..= 2i + 2 of
/// `row`, clamped to its ends.
#[inline(always)]
fn halve_row(row: &[Texel], out: &mut [Texel]) {
    let last = row.len() - 1;
    for (i, o) in out.iter_mut().enumerate() {
        let c = 2 * i;
        let (a, b) = (&row[c.saturating_sub(1)], &row[c.min(last)]);
        let (d, e) = (&row[(c + 1).min(last)], &row[(c + 2).min(last)]);
        for k in 0..8 {
            o[k] = 0.125 * (a[k] + e[k]) + 0.375 * (b[k] + d[k]);
        }
    }
}

/// Halves four rows down into one: [1 3 3 1]/8 over `rows`, texel by texel.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn halve_down(rows: [&[Texel]; 4], out: &mut [Texel]) {
    let [a, b, d, e] = rows;
    for (i, t) in out.iter_mut().enumerate() {
        for k in 0..8 {
            t[k] = 0.125 * (a[i][k] + e[i][k]) + 0.375 * (b[i][k] + d[i][k]);
        }
    }
}

/// [`halve_row`] compiled for the CPU at hand.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn halve_across(row: &[Texel], out: &mut [Texel]) {
    halve_row(row, out)
}

/// The next level down from rows of `width` × `height`: `across(y, out, scratch)` writes row
/// y halved across into `out` (`scratch` is the task's own buffer); the rows are then halved
/// down with the same filter, a band of output rows per task. Each texel is the same sum in
/// the same order whatever the bands and threads.
fn halve<F>(width: usize, height: usize, across: F) -> Level
where
    F: Fn(usize, &mut [Texel], &mut Vec<Texel>) + Sync,
{
    let (w2, h2) = (width.div_ceil(2), height.div_ceil(2));
    let last = height as isize - 1;
    let mut texels = vec![ZERO; w2 * h2];
    texels.par_chunks_mut(w2 * BAND).enumerate().for_each_init(
        || (Vec::new(), Vec::new()),
        |(rows, scratch): &mut (Vec<Texel>, Vec<Texel>), (band, out)| {
            let count = out.len() / w2;
            // Input rows 2j − 1 ..= 2j + 2 for the band's output rows j.
            let first = (2 * band * BAND) as isize - 1;
            let needed = 2 * count + 2;
            rows.resize(needed * w2, ZERO);
            for (r, row) in rows.chunks_mut(w2).enumerate() {
                let y = (first + r as isize).clamp(0, last) as usize;
                across(y, row, scratch);
            }
            for (j, o) in out.chunks_mut(w2).enumerate() {
                let r = |k: usize| &rows[(2 * j + k) * w2..(2 * j + k + 1) * w2];
                let (a, b, d, e) = (r(0), r(1), r(2), r(3));
                for (i, t) in o.iter_mut().enumerate() {
                    for k in 0..8 {
                        t[k] = 0.125 * (a[i][k] + e[i][k]) + 0.375 * (b[i][k] + d[i][k]);
                    }
                }
            }
        },
    );
    Level {
        width: w2,
        height: h2,
        texels,
    }
}

/// What turns a frame pixel into a level-0 texel, and what the compose stage reads of the
/// frame: the colour planes, the signed CoC, and the blurriness interpolator's constants.
struct Source<'a> {
    planes: Vec<&'a [f32]>,
    coc: &'a [f32],
    /// The reference colour the texels are offset by (a uniform frame stays exact).
    reference: [f32; 4],
    epsilon: f32,
    /// E, the frame's largest CoC.
    largest: f32,
    /// 1 / (E − ε).
    inverse_span: f32,
}

impl Source<'_> {
    /// The blurriness interpolator T = clamp((|CoC| − ε)/(E − ε), 0, 1).
    #[inline(always)]
    fn interpolator(&self, c: f32) -> f32 {
        ((c.abs() - self.epsilon) * self.inverse_span).clamp(0.0, 1.0)
    }
}

/// Lanes of a texel that carry something: colour (4), w, T_near.
const LANES: usize = 6;

/// Halves a plane's row across, [1 3 3 1]/8 over 2i − 1 ..= 2i + 2, clamped to its ends (the
/// planar twin of [`halve_row`], the same sums in the same order).
#[inline(always)]
fn halve_plane_row(row: &[f32], out: &mut [f32]) {
    let last = row.len() - 1;
    let tap = |i: usize| {
        let c = 2 * i;
        0.125 * (row[c.saturating_sub(1)] + row[(c + 2).min(last)])
            + 0.375 * (row[c.min(last)] + row[(c + 1).min(last)])
    };
    let n = out.len();
    // Texels 1 .. inner read 2i − 1 ..= 2i + 2 inside the row, that is the pairs (2i − 1,
    // 2i) and (2i + 1, 2i + 2): pairs i − 1 and i of the row from its second sample.
    let inner = ((row.len() - 1) / 2).clamp(1, n);
    out[0] = tap(0);
    let (pairs, _) = row[1..].as_chunks::<2>();
    for ((o, p), q) in out[1..inner]
        .iter_mut()
        .zip(pairs)
        .zip(pairs.iter().skip(1))
    {
        *o = 0.125 * (p[0] + q[1]) + 0.375 * (p[1] + q[0]);
    }
    for (i, o) in out.iter_mut().enumerate().skip(inner) {
        *o = tap(i);
    }
}

/// A level-1 task's buffers: w and T_near of a frame row, one premultiplied channel of it,
/// and the band's rows halved across, lane by lane.
#[derive(Default)]
struct FirstScratch {
    w: Vec<f32>,
    near: Vec<f32>,
    channel: Vec<f32>,
    rows: Vec<f32>,
    down: Vec<f32>,
}

/// Frame row y halved across, as `LANES` planes of `out.len() / LANES` texels.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn first_row(source: &Source, width: usize, y: usize, out: &mut [f32], s: &mut FirstScratch) {
    let w2 = out.len() / LANES;
    let span = y * width..(y + 1) * width;
    let coc = &source.coc[span.clone()];
    s.w.resize(width, 0.0);
    s.near.resize(width, 0.0);
    s.channel.resize(width, 0.0);
    for ((w, near), &c) in s.w.iter_mut().zip(s.near.iter_mut()).zip(coc) {
        let t = source.interpolator(c);
        *w = t.max(IN_FOCUS_WEIGHT);
        *near = if c < 0.0 { t } else { 0.0 };
    }
    let mut lanes = out.chunks_mut(w2);
    for ch in 0..4 {
        let lane = lanes.next().expect("a lane per channel");
        match source.planes.get(ch) {
            Some(plane) => {
                let reference = source.reference[ch];
                for ((o, v), w) in s.channel.iter_mut().zip(&plane[span.clone()]).zip(&s.w) {
                    *o = (v - reference) * w;
                }
                halve_plane_row(&s.channel, lane);
            }
            None => lane.fill(0.0),
        }
    }
    halve_plane_row(&s.w, lanes.next().expect("the w lane"));
    halve_plane_row(&s.near, lanes.next().expect("the T_near lane"));
}

/// Level 1 from the frame: rows halved across as planes (a lane at a time, so the sums run
/// along memory), halved down, then gathered into texels. The same sums in the same order as
/// [`halve`] over texels would make.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn first_level_band(
    source: &Source,
    width: usize,
    height: usize,
    band: usize,
    out: &mut [Texel],
    s: &mut FirstScratch,
) {
    let w2 = width.div_ceil(2);
    let count = out.len() / w2;
    let last = height as isize - 1;
    let first = (2 * band * BAND) as isize - 1;
    let needed = 2 * count + 2;
    let stride = LANES * w2;
    let mut rows = std::mem::take(&mut s.rows);
    rows.resize(needed * stride, 0.0);
    for (r, row) in rows.chunks_mut(stride).enumerate() {
        let y = (first + r as isize).clamp(0, last) as usize;
        first_row(source, width, y, row, s);
    }
    s.down.resize(stride, 0.0);
    for (j, o) in out.chunks_mut(w2).enumerate() {
        let r = |k: usize, lane: usize| {
            let start = (2 * j + k) * stride + lane * w2;
            &rows[start..start + w2]
        };
        for lane in 0..LANES {
            let (a, b, d, e) = (r(0, lane), r(1, lane), r(2, lane), r(3, lane));
            let down = &mut s.down[lane * w2..(lane + 1) * w2];
            for i in 0..w2 {
                down[i] = 0.125 * (a[i] + e[i]) + 0.375 * (b[i] + d[i]);
            }
        }
        for (i, t) in o.iter_mut().enumerate() {
            for (lane, v) in t.iter_mut().enumerate().take(LANES) {
                *v = s.down[lane * w2 + i];
            }
        }
    }
    s.rows = rows;
}

/// Levels 1 ..= `count` of the pyramid over the frame, each halved from the one above.
fn build(source: &Source, width: usize, height: usize, count: usize) -> Vec<Level> {
    let mut levels: Vec<Level> = Vec::with_capacity(count);
    let (w2, h2) = (width.div_ceil(2), height.div_ceil(2));
    let mut texels = vec![ZERO; w2 * h2];
    texels
        .par_chunks_mut(w2 * BAND)
        .enumerate()
        .for_each_init(FirstScratch::default, |s, (band, out)| {
            first_level_band(source, width, height, band, out, s)
        });
    levels.push(Level {
        width: w2,
        height: h2,
        texels,
    });
    while levels.len() < count {
        let above = levels.last().expect("level 1 is made first");
        let next = halve(above.width, above.height, |y, out, _| {
            halve_across(&above.texels[y * above.width..(y + 1) * above.width], out)
        });
        levels.push(next);
    }
    levels
}

/// Where pixel centres of a frame axis of `size` land in a level 2^L times smaller: for each
/// pixel, the texel before it and the one after (clamped to the level) and the weight of the
/// one after.
fn axis_taps(size: usize, level: usize, texels: usize) -> Vec<(u32, u32, f32)> {
    let scale = 0.5f64.powi(level as i32);
    let last = texels as isize - 1;
    (0..size)
        .map(|x| {
            let p = (x as f64 + 0.5) * scale - 0.5;
            let before = p.floor();
            let f = (p - before) as f32;
            let i0 = (before as isize).clamp(0, last) as u32;
            let i1 = (before as isize + 1).clamp(0, last) as u32;
            (i0, i1, f)
        })
        .collect()
}

#[inline(always)]
fn lerp(a: &Texel, b: &Texel, f: f32) -> Texel {
    let mut o = ZERO;
    for k in 0..8 {
        o[k] = a[k] + f * (b[k] - a[k]);
    }
    o
}

/// Texel rows `a` and `b` mixed by f into `out`, colour divided by w. The mix runs over the
/// rows' floats and the division a texel at a time (one 8-lane division by (w, w, w, w, 1,
/// 1, 1, 1)): written over texels at once, the compiler transposes eight of them.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn normalised_row(a: &[Texel], b: &[Texel], f: f32, out: &mut [Texel]) {
    for ((o, a), b) in out
        .as_flattened_mut()
        .iter_mut()
        .zip(a.as_flattened())
        .zip(b.as_flattened())
    {
        *o = a + f * (b - a);
    }
    for t in out.iter_mut() {
        // max(w, MIN_POSITIVE), NaN included, in one comparison.
        let w = if t[W] > f32::MIN_POSITIVE {
            t[W]
        } else {
            f32::MIN_POSITIVE
        };
        let divisor = [w, w, w, w, 1.0, 1.0, 1.0, 1.0];
        for (v, d) in t.iter_mut().zip(divisor) {
            *v /= d;
        }
    }
}

/// A level sampled bilinearly at the frame's pixel centres, a row at a time: the row
/// between the two texel rows that bracket a frame row is made once, and each pixel of the
/// frame row interpolates across it.
struct Sampler<'a> {
    level: &'a Level,
    across: Vec<(u32, u32, f32)>,
    /// `across` as three planes, for loops that read one lane of many pixels.
    across_planes: AxisPlanes,
    down: Vec<(u32, u32, f32)>,
}

/// An axis's taps as planes: the texel before each pixel, the one after, the weight of the
/// one after.
struct AxisPlanes {
    before: Vec<u32>,
    after: Vec<u32>,
    weight: Vec<f32>,
}

impl<'a> Sampler<'a> {
    fn new(level: &'a Level, number: usize, width: usize, height: usize) -> Self {
        let across = axis_taps(width, number, level.width);
        let across_planes = AxisPlanes {
            before: across.iter().map(|t| t.0).collect(),
            after: across.iter().map(|t| t.1).collect(),
            weight: across.iter().map(|t| t.2).collect(),
        };
        Sampler {
            level,
            across,
            across_planes,
            down: axis_taps(height, number, level.height),
        }
    }

    /// Fills `row` with this level interpolated down to frame row y, its colour then divided
    /// by its w: so the weights count across texel rows and within texels, and pixels
    /// interpolate the normalised colour across (one division per texel of the row, not two
    /// per pixel; on `layers` at 640×360 it errs a little less, 0.0476 against 0.0478).
    fn row(&self, y: usize, row: &mut Vec<Texel>) {
        let (r0, r1, f) = self.down[y];
        let w = self.level.width;
        let a = &self.level.texels[r0 as usize * w..(r0 as usize + 1) * w];
        let b = &self.level.texels[r1 as usize * w..(r1 as usize + 1) * w];
        row.resize(w, ZERO);
        normalised_row(a, b, f, row);
    }

    /// The level at frame pixel x, from the row [`Sampler::row`] made.
    #[inline(always)]
    fn at(&self, row: &[Texel], x: usize) -> Texel {
        let (c0, c1, f) = self.across[x];
        lerp(&row[c0 as usize], &row[c1 as usize], f)
    }

    /// T_near alone at frame pixel x, from the row [`Sampler::row`] made.
    #[inline(always)]
    fn near_at(&self, row: &[Texel], x: usize) -> f32 {
        let (c0, c1, f) = self.across[x];
        let (a, b) = (row[c0 as usize][NEAR], row[c1 as usize][NEAR]);
        a + f * (b - a)
    }
}

/// A compose task's own buffers: each level's row for the current frame row, and per pixel
/// its blurriness.
#[derive(Default)]
struct Scratch {
    made: Vec<Vec<Texel>>,
    blur: Vec<f32>,
    /// Each blurred pixel's mix of two images, offset by the reference.
    mixed: Vec<Texel>,
    /// T_near of the two levels that bracket E, as planes.
    near_lower: Vec<f32>,
    near_upper: Vec<f32>,
}

/// The compose stage for frame row y: each pixel's blurriness, the levels the row needs,
/// then each pixel mixed from the two levels that bracket its CoC (the sharp pixel as level
/// 0). `out` holds the row of each plane, sharp, and is written in place; `window` holds
/// copies of the rows around it as they were.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn compose_row(
    pyramid: &Pyramid,
    y: usize,
    window: &Window,
    scratch: &mut Scratch,
    out: &mut [&mut [f32]],
) {
    let Pyramid {
        source,
        samplers,
        ladders,
        near,
    } = pyramid;
    let near = *near;
    let width = out[0].len();
    let row = y * width;
    let coc = &source.coc[row..row + width];
    let height = source.coc.len() / width;
    let Scratch {
        made,
        blur,
        mixed,
        near_lower,
        near_upper,
    } = scratch;
    made.resize(samplers.len(), Vec::new());
    let mut ready = [false; MAX_LEVELS + 1];
    // Makes level l's row (l ≥ 1) once.
    let mut make = |l: usize, made: &mut Vec<Vec<Texel>>| {
        if l > 0 && !ready[l] {
            samplers[l - 1].row(y, &mut made[l - 1]);
            ready[l] = true;
        }
    };

    // Blurriness: the pixel's own T, or the near field's blurred T_near if larger (`near`
    // counts in levels, without the half step).
    blur.resize(width, 0.0);
    for (t, &c) in blur.iter_mut().zip(coc) {
        *t = source.interpolator(c);
    }
    if let Some((k, f)) = near {
        make(k, made);
        make(k + 1, made);
        let (upper, upper_row) = (&samplers[k], &made[k]);
        if k == 0 {
            for (x, (t, &c)) in blur.iter_mut().zip(coc).enumerate() {
                let lower = if c < 0.0 { *t } else { 0.0 };
                spread(t, lower, upper.near_at(upper_row, x), f);
            }
        } else {
            // T_near of the two levels' rows as planes, read with indices clamped to them
            // (the taps are inside already; the clamp lets the loop run on vectors).
            near_lane(&made[k - 1], near_lower);
            near_lane(upper_row, near_upper);
            let (lower, upper) = (&samplers[k - 1].across_planes, &upper.across_planes);
            let (near_lower, near_upper) = (&near_lower[..], &near_upper[..]);
            let (lower_last, upper_last) = (near_lower.len() - 1, near_upper.len() - 1);
            assert!(lower_last < near_lower.len() && upper_last < near_upper.len());
            let at = |lane: &[f32], last: usize, before: u32, after: u32, weight: f32| {
                let a = lane[(before as usize).min(last)];
                let b = lane[(after as usize).min(last)];
                a + weight * (b - a)
            };
            for (t, (((b0, a0), w0), ((b1, a1), w1))) in blur.iter_mut().zip(
                lower
                    .before
                    .iter()
                    .zip(&lower.after)
                    .zip(&lower.weight)
                    .zip(upper.before.iter().zip(&upper.after).zip(&upper.weight)),
            ) {
                spread(
                    t,
                    at(near_lower, lower_last, *b0, *a0, *w0),
                    at(near_upper, upper_last, *b1, *a1, *w1),
                    f,
                );
            }
        }
    }

    // The levels the row needs: those that bracket its least and its most blurred pixel,
    // and all between.
    let (mut least, mut most) = (f32::INFINITY, 0.0f32);
    for &t in blur.iter() {
        let t = t.abs();
        if t > 0.0 {
            least = least.min(t);
            most = most.max(t);
        }
    }
    let (epsilon, largest) = (source.epsilon, source.largest);
    let to_coc = |t: f32| epsilon + t * (largest - epsilon);
    // Image k of the ladder without the half step is level k, and either ladder brackets a
    // CoC between the same levels from level 1 up.
    let [ladder, plain] = ladders;
    if most > 0.0 {
        let (lo, _) = plain.bracket(to_coc(least));
        let (hi, _) = plain.bracket(to_coc(most));
        for l in lo.max(1)..=hi + 1 {
            make(l, made);
        }
    }

    let mut reference = ZERO;
    reference[..4].copy_from_slice(&source.reference);
    // `out` holds the sharp row: pixels left sharp are not touched.
    let channels = out.len();
    let images = Images {
        source,
        window,
        channels,
        reference: &reference,
        width,
        height,
        y,
        samplers,
        made,
    };
    mixed.resize(width, ZERO);
    for (x, (&t, m)) in blur.iter().zip(mixed.iter_mut()).enumerate() {
        if t == 0.0 {
            continue;
        }
        // A pixel blurred by the near field's spread mixes levels only: the half step shows
        // its own neighbourhood, which the near field's blur reaches farther than.
        let ladder = if t < 0.0 { plain } else { ladder };
        let (k, f) = ladder.bracket(to_coc(t.abs()));
        let lower = images.at(k, ladder.first, x);
        let upper = images.at(k + 1, ladder.first, x);
        *m = lerp(&lower, &upper, f);
    }
    // Then into the planes (the match gives the loop each plane's own iterator, so no
    // store checks its bounds).
    let blurred = blur.iter().zip(mixed.iter());
    match out {
        [r, g, b, a] => {
            let planes = r
                .iter_mut()
                .zip(g.iter_mut())
                .zip(b.iter_mut())
                .zip(a.iter_mut());
            for ((&t, m), (((r, g), b), a)) in blurred.zip(planes) {
                if t != 0.0 {
                    *r = reference[0] + m[0];
                    *g = reference[1] + m[1];
                    *b = reference[2] + m[2];
                    *a = reference[3] + m[3];
                }
            }
        }
        [r, g, b] => {
            let planes = r.iter_mut().zip(g.iter_mut()).zip(b.iter_mut());
            for ((&t, m), ((r, g), b)) in blurred.zip(planes) {
                if t != 0.0 {
                    *r = reference[0] + m[0];
                    *g = reference[1] + m[1];
                    *b = reference[2] + m[2];
                }
            }
        }
        _ => unreachable!("colour has three planes or four"),
    }
}

/// T_near of a level's row, as a plane.
#[inline(always)]
fn near_lane(row: &[Texel], lane: &mut Vec<f32>) {
    lane.clear();
    lane.extend(row.iter().map(|t| t[NEAR]));
}

/// How far the near field's spread must exceed a pixel's own blurriness (in T) to take
/// over. Inside a uniformly blurred foreground the spread is the pixel's own T blurred, equal
/// to it but for rounding, and the two ladders (with and without the half step) give
/// different mixes there: compared bare, the last bit decided between them pixel by pixel,
/// a pattern of dots over the foreground (seen between the CPU and the GPU twin on `layers`
/// with ε = 3 px, up to 0.04 apart). 1e-3 of the blur range is 0.03 px of CoC at E = 32.
pub(crate) const SPREAD_MARGIN: f32 = 1e-3;

/// A pixel's blurriness `t` given the near field's T_near read at the two levels that
/// bracket E, mixed by f: negative where the near field's spread sets the blur.
#[inline(always)]
fn spread(t: &mut f32, lower: f32, upper: f32, f: f32) {
    let spread = lower + f * (upper - lower);
    if spread > *t + SPREAD_MARGIN {
        *t = -spread;
    }
}

/// What the compose stage mixes for frame row y: the sharp frame (offset by the reference),
/// the half step, and the levels' rows made for the row.
struct Images<'a> {
    source: &'a Source<'a>,
    window: &'a Window<'a>,
    channels: usize,
    reference: &'a Texel,
    width: usize,
    height: usize,
    y: usize,
    samplers: &'a [Sampler<'a>],
    made: &'a [Vec<Texel>],
}

impl Images<'_> {
    /// Image j of a ladder whose level 1 is image `first`, at frame pixel x (a method, not
    /// a closure: `multiversion` would leave a closure compiled for the baseline CPU, out
    /// of line).
    #[inline(always)]
    fn at(&self, j: usize, first: usize, x: usize) -> Texel {
        if j >= first {
            self.samplers[j - first].at(&self.made[j - first], x)
        } else if j == 0 {
            let mut offset = ZERO;
            for (lane, rows) in self.window.iter().take(self.channels).enumerate() {
                offset[lane] = rows[1][x] - self.reference[lane];
            }
            offset
        } else {
            half(
                self.source,
                self.window,
                self.channels,
                self.reference,
                self.width,
                self.height,
                x,
                self.y,
            )
        }
    }
}

/// What every compose task reads: the frame's constants and CoC, the levels' samplers, the
/// two ladders (with and without the half step), and where T_near is read (in levels, if any
/// pixel is in front of the focus plane).
struct Pyramid<'a> {
    source: &'a Source<'a>,
    samplers: &'a [Sampler<'a>],
    ladders: &'a [Ladder; 2],
    near: Option<(usize, f32)>,
}

/// Frame rows y − 1, y and y + 1 (clamped to the frame) of each colour plane, as they were
/// before the compose stage wrote any of them: the compose stage writes in place.
type Window<'a> = [[&'a [f32]; 3]; 4];

/// The half step at pixel (x, y): the 3×3 filter over the premultiplied neighbourhood,
/// normalised (colour offset by the reference).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn half(
    source: &Source,
    window: &Window,
    channels: usize,
    reference: &Texel,
    width: usize,
    height: usize,
    x: usize,
    y: usize,
) -> Texel {
    const TAPS: [f32; 3] = [0.25, 0.5, 0.25];
    let ys = [y.saturating_sub(1), y, (y + 1).min(height - 1)];
    let xs = [x.saturating_sub(1), x, (x + 1).min(width - 1)];
    let (mut sum, mut weights) = (ZERO, 0.0f32);
    for (r, (ky, &sy)) in TAPS.iter().zip(&ys).enumerate() {
        for (kx, &sx) in TAPS.iter().zip(&xs) {
            let i = sy * width + sx;
            let w = ky * kx * source.interpolator(source.coc[i]).max(IN_FOCUS_WEIGHT);
            for ((v, rows), reference) in sum.iter_mut().zip(window).zip(reference).take(channels) {
                *v += w * (rows[r][sx] - reference);
            }
            weights += w;
        }
    }
    for v in sum.iter_mut() {
        *v /= weights;
    }
    sum
}

/// What the pyramid form decides for a frame before it blurs a pixel, the GPU twin's too.
pub(crate) struct Plan {
    /// E.
    pub largest: f32,
    /// Levels 1 ..= `levels` are made.
    pub levels: usize,
    /// The ladder with the half step, and the plain one (the near field's spread).
    pub ladders: [Ladder; 2],
    /// Where T_near is read: the plain ladder's bracket of E, if any pixel is in front of
    /// the focus plane.
    pub near: Option<(usize, f32)>,
    /// The colour the texels are offset by: each plane's first sample (0 without alpha).
    pub reference: [f32; 4],
    /// 1 / (E − ε).
    pub inverse_span: f32,
}

/// The pyramid's [`Plan`] for a frame.
pub(crate) fn plan(config: &DofConfig, color: &Color, coc: &[f32]) -> Plan {
    let epsilon = config.epsilon;
    let largest = largest_coc(coc, epsilon);
    let mut reference = [0.0; 4];
    for (r, p) in reference.iter_mut().zip(color.planes()) {
        *r = p[0];
    }
    let inverse_span = 1.0 / (largest - epsilon);
    // Enough levels that the last one is at least as blurred as E, so every CoC (and
    // T_near, spread at E) is bracketed.
    let mut levels = 1;
    while levels < MAX_LEVELS && level_coc(levels) < largest {
        levels += 1;
    }
    let ladders = [Ladder::new(levels, true), Ladder::new(levels, false)];
    let interpolator = |c: f32| ((c.abs() - epsilon) * inverse_span).clamp(0.0, 1.0);
    // T_near is read at the blur of E, where any pixel is in front of the focus plane.
    let near = coc
        .par_iter()
        .any(|&c| c < 0.0 && interpolator(c) > 0.0)
        .then(|| ladders[1].bracket(largest));
    Plan {
        largest,
        levels,
        ladders,
        near,
        reference,
        inverse_span,
    }
}

/// E: the frame's largest CoC (the plane is already clamped to --max-coc), at least a pixel
/// above ε, so the blur is spent on what the frame has.
fn largest_coc(coc: &[f32], epsilon: f32) -> f32 {
    coc.par_iter()
        .map(|c| c.abs())
        .reduce(|| 0.0, f32::max)
        .max(epsilon + 1.0)
}

/// The pyramid form: the blurred images are the levels of a binomial pyramid, and each
/// pixel mixes the two whose blur brackets its CoC.
pub fn pyramid(config: &DofConfig, mut color: Color, coc: &[f32]) -> Color {
    let (width, height) = (config.width as usize, config.height as usize);
    let Plan {
        largest,
        levels: count,
        ladders,
        near,
        reference,
        inverse_span,
    } = plan(config, &color, coc);
    let source = Source {
        planes: color.planes(),
        coc,
        reference,
        epsilon: config.epsilon,
        largest,
        inverse_span,
    };
    let epsilon = config.epsilon;
    let levels = build(&source, width, height, count);
    let samplers: Vec<Sampler> = levels
        .iter()
        .enumerate()
        .map(|(l, level)| Sampler::new(level, l + 1, width, height))
        .collect();

    // The compose stage writes the frame in place, a band of rows per task. The half step
    // reads a pixel's neighbours as they were: each task keeps copies of the rows around the
    // one it writes, and the rows just outside each band are copied before any task starts.
    let bands = height.div_ceil(BAND);
    let copy = |y: usize| -> Vec<f32> {
        source
            .planes
            .iter()
            .flat_map(|p| &p[y * width..(y + 1) * width])
            .copied()
            .collect()
    };
    // The row above and the row below each band (clamped to the frame).
    let edges: Vec<[Vec<f32>; 2]> = (0..bands)
        .map(|b| {
            let above = (b * BAND).saturating_sub(1);
            let below = ((b + 1) * BAND).min(height - 1);
            [copy(above), copy(below)]
        })
        .collect();
    let source = Source {
        planes: Vec::new(),
        coc,
        reference,
        epsilon,
        largest,
        inverse_span: source.inverse_span,
    };
    let mut chunks: Vec<_> = [
        Some(&mut color.r),
        Some(&mut color.g),
        Some(&mut color.b),
        color.a.as_mut(),
    ]
    .into_iter()
    .flatten()
    .map(|p| p.chunks_mut(width * BAND))
    .collect();
    let band_planes: Vec<Vec<&mut [f32]>> = (0..bands)
        .map(|_| {
            chunks
                .iter_mut()
                .map(|c| c.next().expect("a band per plane"))
                .collect()
        })
        .collect();
    let pyramid = Pyramid {
        source: &source,
        samplers: &samplers,
        ladders: &ladders,
        near,
    };
    band_planes
        .into_par_iter()
        .zip(edges.par_iter())
        .enumerate()
        .for_each_init(
            || (Scratch::default(), [Vec::new(), Vec::new(), Vec::new()]),
            |(scratch, ring), (band, (mut planes, edge))| {
                let rows = planes[0].len() / width;
                // ring[0], ring[1], ring[2]: copies of rows j − 1, j and j + 1 of the band.
                let load = |buffer: &mut Vec<f32>, planes: &[&mut [f32]], j: usize| {
                    buffer.clear();
                    for p in planes {
                        buffer.extend_from_slice(&p[j * width..(j + 1) * width]);
                    }
                };
                load(&mut ring[1], &planes, 0);
                for j in 0..rows {
                    let y = band * BAND + j;
                    if j + 1 < rows {
                        load(&mut ring[2], &planes, j + 1);
                    }
                    let above: &[f32] = match (j, y) {
                        (_, 0) => &ring[1],
                        (0, _) => &edge[0],
                        _ => &ring[0],
                    };
                    let below: &[f32] = if y + 1 == height {
                        &ring[1]
                    } else if j + 1 == rows {
                        &edge[1]
                    } else {
                        &ring[2]
                    };
                    // Channel ch of a copied row (empty past the frame's channels).
                    fn plane(rows: &[f32], ch: usize, width: usize) -> &[f32] {
                        rows.get(ch * width..(ch + 1) * width).unwrap_or(&[])
                    }
                    let window: Window = std::array::from_fn(|ch| {
                        [
                            plane(above, ch, width),
                            plane(&ring[1], ch, width),
                            plane(below, ch, width),
                        ]
                    });
                    let mut out: Vec<&mut [f32]> = planes
                        .iter_mut()
                        .map(|p| &mut p[j * width..(j + 1) * width])
                        .collect();
                    compose_row(&pyramid, y, &window, scratch, &mut out);
                    ring.rotate_left(1);
                }
            },
        );
    color
}

// ---------------------------------------------------------------------------------------
// The talk's form.

/// The kernel of n passes of [1 2 1]/4: C(2n, n + j)/4ⁿ for j = −h..=h, renormalised.
pub fn binomial(passes: usize) -> Vec<f32> {
    let n = passes as f64;
    // Walk out from the centre with the ratio C(2n, n+j+1)/C(2n, n+j) = (n − j)/(n + j + 1).
    let mut half = vec![1.0f64];
    let mut j = 0.0;
    while j < n {
        let next = half[half.len() - 1] * (n - j) / (n + j + 1.0);
        if next < CUT {
            break;
        }
        half.push(next);
        j += 1.0;
    }
    let mut kernel: Vec<f64> = half.iter().rev().chain(half[1..].iter()).copied().collect();
    let sum: f64 = kernel.iter().sum();
    kernel.iter_mut().for_each(|w| *w /= sum);
    kernel.into_iter().map(|w| w as f32).collect()
}

/// The CoC diameter (px) that `passes` passes of the filter look like: √(8·passes).
pub fn equivalent_coc(passes: usize) -> f32 {
    (8.0 * passes as f32).sqrt()
}

/// The default n: copy 2n stands for a CoC of E.
pub fn default_passes(largest: f32) -> usize {
    ((largest * largest / 16.0).round() as usize).max(1)
}

/// Planar channels over a rectangle.
struct Planes {
    width: usize,
    height: usize,
    channels: Vec<Vec<f32>>,
}

/// One separable pass of `kernel` over every channel, clamped at the rectangle's edges.
fn convolve(planes: &Planes, kernel: &[f32]) -> Planes {
    let (w, h) = (planes.width, planes.height);
    let half = (kernel.len() / 2) as isize;
    let channels = planes
        .channels
        .par_iter()
        .map(|plane| {
            // Across.
            let mut across = vec![0.0f32; w * h];
            across
                .chunks_mut(w)
                .zip(plane.chunks(w))
                .for_each(|(out, row)| {
                    for (x, o) in out.iter_mut().enumerate() {
                        let mut sum = 0.0f32;
                        for (k, weight) in kernel.iter().enumerate() {
                            let sx = (x as isize + k as isize - half).clamp(0, w as isize - 1);
                            sum += weight * row[sx as usize];
                        }
                        *o = sum;
                    }
                });
            // Down, a row at a time so the inner loop runs along memory.
            let mut down = vec![0.0f32; w * h];
            down.chunks_mut(w).enumerate().for_each(|(y, out)| {
                for (k, weight) in kernel.iter().enumerate() {
                    let sy = (y as isize + k as isize - half).clamp(0, h as isize - 1) as usize;
                    let row = &across[sy * w..(sy + 1) * w];
                    out.iter_mut().zip(row).for_each(|(o, v)| *o += weight * v);
                }
            });
            down
        })
        .collect();
    Planes {
        width: w,
        height: h,
        channels,
    }
}

/// The talk's form: the sharp frame and two blurred copies (n and 2n passes), blended by T;
/// `coc` is the signed CoC plane (px, diameter).
pub fn talk(config: &DofConfig, color: &Color, coc: &[f32]) -> Color {
    let (width, height) = (config.width as usize, config.height as usize);
    let epsilon = config.epsilon;
    let largest = largest_coc(coc, epsilon);
    let passes = match config.passes {
        0 => default_passes(largest),
        n => n as usize,
    };
    let kernel = binomial(passes);
    let (coc_1, coc_2) = (equivalent_coc(passes), equivalent_coc(2 * passes));
    let interpolator = |c: f32| ((c.abs() - epsilon) / (largest - epsilon)).clamp(0.0, 1.0);

    // The input, offset by one reference colour so a uniform frame stays exact.
    let inputs: Vec<Vec<f32>> = color.planes().into_iter().map(<[f32]>::to_vec).collect();
    let reference: Vec<f32> = inputs.iter().map(|p| p[0]).collect();
    let channels = inputs.len();

    // The box the copies are needed in: out-of-focus pixels, grown by how far copy 2n
    // reaches, and that again for the pixels they read.
    let reach = (kernel.len() / 2) * 2;
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for (i, &c) in coc.iter().enumerate() {
        if interpolator(c) > 0.0 {
            let (x, y) = (i % width, i / width);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
    }
    if x0 > x1 {
        return to_color(inputs, color.a.is_some());
    }
    let grow = 2 * reach;
    let (bx0, by0) = (x0.saturating_sub(grow), y0.saturating_sub(grow));
    let (bx1, by1) = ((x1 + grow).min(width - 1), (y1 + grow).min(height - 1));
    let (bw, bh) = (bx1 - bx0 + 1, by1 - by0 + 1);

    // Copy channels: (colour − reference)·w for each channel, w, T_near.
    let mut planes = Planes {
        width: bw,
        height: bh,
        channels: vec![vec![0.0; bw * bh]; channels + 2],
    };
    for y in 0..bh {
        for x in 0..bw {
            let i = (by0 + y) * width + bx0 + x;
            let j = y * bw + x;
            let t = interpolator(coc[i]);
            let w = t.max(IN_FOCUS_WEIGHT);
            for k in 0..channels {
                planes.channels[k][j] = (inputs[k][i] - reference[k]) * w;
            }
            planes.channels[channels][j] = w;
            planes.channels[channels + 1][j] = if coc[i] < 0.0 { t } else { 0.0 };
        }
    }
    let copy_1 = convolve(&planes, &kernel);
    drop(planes);
    let copy_2 = convolve(&copy_1, &kernel);

    let rows: Vec<(usize, Vec<Vec<f32>>)> = (0..bh)
        .into_par_iter()
        .map(|y| {
            let mut row = vec![vec![0.0f32; bw]; channels];
            for x in 0..bw {
                let i = (by0 + y) * width + bx0 + x;
                let j = y * bw + x;
                let t = interpolator(coc[i]).max(copy_2.channels[channels + 1][j]);
                let sharp = |k: usize| inputs[k][i] - reference[k];
                if t <= 0.0 {
                    for (k, r) in row.iter_mut().enumerate() {
                        r[x] = inputs[k][i];
                    }
                    continue;
                }
                let blurred = |copy: &Planes, k: usize| {
                    copy.channels[k][j] / copy.channels[channels][j].max(f32::MIN_POSITIVE)
                };
                let c = epsilon + t * (largest - epsilon);
                for (k, r) in row.iter_mut().enumerate() {
                    let v = if c < coc_1 {
                        let f = c / coc_1;
                        sharp(k) + f * (blurred(&copy_1, k) - sharp(k))
                    } else if c < coc_2 {
                        let f = (c - coc_1) / (coc_2 - coc_1);
                        blurred(&copy_1, k) + f * (blurred(&copy_2, k) - blurred(&copy_1, k))
                    } else {
                        blurred(&copy_2, k)
                    };
                    r[x] = reference[k] + v;
                }
            }
            (y, row)
        })
        .collect();
    // The rows are made: the input planes become the output.
    let mut out = inputs;
    for (y, row) in rows {
        for (k, values) in row.into_iter().enumerate() {
            let start = (by0 + y) * width + bx0;
            out[k][start..start + bw].copy_from_slice(&values);
        }
    }
    to_color(out, color.a.is_some())
}

fn to_color(mut planes: Vec<Vec<f32>>, alpha: bool) -> Color {
    let a = alpha.then(|| planes.pop().expect("alpha plane"));
    let b = planes.pop().expect("b");
    let g = planes.pop().expect("g");
    let r = planes.pop().expect("r");
    Color { r, g, b, a }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pyramid over a frame of `width` × `height` whose red is 1 at pixel (x0, y0) and 0
    /// elsewhere, every pixel fully blurred (T = 1, so w = 1): level L's red sampled at every
    /// pixel's centre, as the compose stage reads it.
    fn impulse_response(width: usize, height: usize, x0: usize, y0: usize, l: usize) -> Vec<f32> {
        let mut r = vec![0.0; width * height];
        r[y0 * width + x0] = 1.0;
        let zero = vec![0.0; width * height];
        let coc = vec![8.0; width * height];
        let source = Source {
            planes: vec![&r, &zero, &zero],
            coc: &coc,
            reference: [0.0; 4],
            epsilon: 1.0,
            largest: 8.0,
            inverse_span: 1.0 / 7.0,
        };
        let levels = build(&source, width, height, l);
        let sampler = Sampler::new(&levels[l - 1], l, width, height);
        let mut out = Vec::new();
        let mut row = Vec::new();
        for y in 0..height {
            sampler.row(y, &mut row);
            out.extend((0..width).map(|x| sampler.at(&row, x)[0]));
        }
        out
    }

    #[test]
    fn each_level_blurs_an_impulse_by_its_stated_variance() {
        // The second moment across of an impulse's response, averaged over the impulse's
        // position in the level's grid, is `level_variance` (the tests of the maths behind
        // `level_coc`); the response keeps its mass (1 on average) and its centre.
        let (width, height) = (256, 128);
        for l in 1..=4 {
            let phases = 1 << l;
            let mut variance = 0.0;
            for phase in 0..phases {
                let x0 = 96 + phase;
                let response = impulse_response(width, height, x0, 64, l);
                let (mut mass, mut first, mut second) = (0.0f64, 0.0f64, 0.0f64);
                for (i, &v) in response.iter().enumerate() {
                    let d = (i % width) as f64 - x0 as f64;
                    mass += v as f64;
                    first += v as f64 * d;
                    second += v as f64 * d * d;
                }
                assert!(
                    (mass - 1.0).abs() < 0.02,
                    "level {l} phase {phase}: mass {mass}"
                );
                assert!(
                    (first / mass).abs() < 0.5,
                    "level {l} phase {phase}: centre {first}"
                );
                variance += second / mass / phases as f64;
            }
            let stated = level_variance(l);
            assert!(
                (variance - stated).abs() < 0.01 * stated,
                "level {l}: measured {variance}, stated {stated}"
            );
        }
    }

    #[test]
    fn the_ladder_mixes_continuously_between_levels() {
        let ladder = Ladder::new(5, false);
        // Level CoCs grow about twofold a level (3.5155 σ; level 1: σ² = 3/4 + 2/3 + 1/12).
        assert!((level_coc(1) - 4.305).abs() < 0.01, "{}", level_coc(1));
        for l in 1..5 {
            let ratio = level_coc(l + 1) / level_coc(l);
            assert!((1.9..2.1).contains(&ratio), "{l}: {ratio}");
        }
        // Continuous in CoC: as c crosses a level's CoC, (k, f) goes from (k − 1, 1) to
        // (k, 0), the same image; and f grows linearly between.
        let mix = |c: f32| {
            let (k, f) = ladder.bracket(c);
            k as f32 + f
        };
        let mut last = mix(0.0);
        assert_eq!(last, 0.0);
        for step in 1..=4000 {
            let c = step as f32 * 0.02;
            let m = mix(c);
            assert!(m >= last && m - last < 0.02, "at {c}: {last} → {m}");
            last = m;
        }
        assert_eq!(ladder.bracket(1e9), (4, 1.0));
    }

    #[test]
    fn the_half_step_reads_the_frame_as_it_was_across_bands() {
        // Every pixel at CoC 2 (E = 2, so T = 1 and w = 1 everywhere): each output is the
        // sharp pixel mixed with the 3×3 filter [1 2 1]/4 × [1 2 1]/4 of the input (clamped
        // to the frame) by f = 2 / (the half step's CoC). The frame is taller than two bands,
        // so rows next to a band's edge read rows another task writes in place.
        let (width, height) = (7, 2 * BAND + 5);
        let n = width * height;
        let value = |i: usize, k: usize| ((i * 7919 + k * 104_729) % 1000) as f32 / 1000.0;
        let planes: Vec<Vec<f32>> = (0..4)
            .map(|k| (0..n).map(|i| value(i, k)).collect())
            .collect();
        let color = Color {
            r: planes[0].clone(),
            g: planes[1].clone(),
            b: planes[2].clone(),
            a: Some(planes[3].clone()),
        };
        let coc = vec![2.0f32; n];
        let config = DofConfig::new(width, height, &crate::dof::DofParams::default());
        let out = pyramid(&config, color, &coc);
        let f = 2.0 / (COC_PER_SIGMA * HALF_VARIANCE.sqrt());
        let taps = [0.25, 0.5, 0.25];
        for (k, got) in out.planes().iter().enumerate() {
            for y in 0..height {
                for x in 0..width {
                    let mut filtered = 0.0f64;
                    for (dy, ky) in taps.iter().enumerate() {
                        for (dx, kx) in taps.iter().enumerate() {
                            let sy = (y + dy).saturating_sub(1).min(height - 1);
                            let sx = (x + dx).saturating_sub(1).min(width - 1);
                            filtered += ky * kx * planes[k][sy * width + sx] as f64;
                        }
                    }
                    let sharp = planes[k][y * width + x] as f64;
                    let expected = sharp + f * (filtered - sharp);
                    let got = got[y * width + x] as f64;
                    assert!(
                        (got - expected).abs() < 1e-5,
                        "plane {k} ({x}, {y}): {got} against {expected}"
                    );
                }
            }
        }
    }

    #[test]
    fn binomial_is_repeated_talk_filter() {
        // Three passes of [1 2 1]/4, convolved by hand: [1 6 15 20 15 6 1]/64.
        let k = binomial(3);
        let expected = [1.0, 6.0, 15.0, 20.0, 15.0, 6.0, 1.0].map(|v: f32| v / 64.0);
        assert_eq!(k.len(), 7);
        for (a, b) in k.iter().zip(expected) {
            assert!((a - b).abs() < 1e-7, "{a} vs {b}");
        }
        // Variance n/2 per pass count n, also for long kernels that are cut.
        for n in [1usize, 10, 144] {
            let k = binomial(n);
            let h = (k.len() / 2) as f32;
            let var: f32 = k
                .iter()
                .enumerate()
                .map(|(i, w)| w * (i as f32 - h).powi(2))
                .sum();
            assert!((var - n as f32 / 2.0).abs() < 1e-3 * n as f32, "{n}: {var}");
        }
        // The 2D kernel of one pass is the talk's e/4 + (b+d+f+h)/8 + (a+c+g+i)/16.
        let k = binomial(1);
        assert_eq!(k, vec![0.25, 0.5, 0.25]);
        assert_eq!(k[1] * k[1], 0.25);
        assert_eq!(k[0] * k[1], 0.125);
        assert_eq!(k[0] * k[0], 0.0625);
    }

    #[test]
    fn copy_two_n_stands_for_e() {
        for e in [8.0f32, 32.0, 48.0] {
            let n = default_passes(e);
            assert!((equivalent_coc(2 * n) - e).abs() < 0.1 * e, "{e}");
        }
    }
}
