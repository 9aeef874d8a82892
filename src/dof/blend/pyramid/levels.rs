//! The pyramid's levels: what each stands for and how each is made.
//!
//! In: the frame's colour planes and signed CoC, as a [`Source`]. Out: levels 1 ..= L of a
//! binomial pyramid ([`build`]), each half the size of the one before, whose texels carry the
//! colour premultiplied by w and offset by a reference colour, w itself and T_near (the
//! blend's ghosting fixes, [`crate::dof::blend`]); and the blur each level shows to a pixel
//! that samples it bilinearly, as a variance ([`level_variance`]) and as the CoC that looks
//! like it ([`level_coc`]), from which a [`Ladder`] places every image of the blend at its
//! CoC. This is the talk's copy-and-blur with "resolution reduction" (seed 004, "Depth of
//! Field: Copy and Blur Textures"), the filter being [1 3 3 1]/8 across and down.
//!
//! Level 1 is made from the frame a plane at a time (the sums run along memory), the others
//! from the level before a texel (8 lanes) at a time; both make the same sums in the same
//! order whatever the bands and threads. The GPU twin (`crate::gpu::dof::blend`) makes the
//! same levels in its `first_level` and `halve` entry points.

use rayon::prelude::*;

use crate::dof::blend::IN_FOCUS_WEIGHT;

/// One texel of a pyramid level: the colour offset by the reference and premultiplied by w
/// (r, g, b, a; a is 0 without alpha), w, T_near, and two lanes of padding, so that a texel is
/// one 8-lane vector and every sum over texels runs on all lanes at once.
pub(super) type Texel = [f32; 8];

/// The lane of w in a [`Texel`].
pub(super) const W: usize = 4;
/// The lane of T_near in a [`Texel`].
pub(super) const NEAR: usize = 5;

pub(super) const ZERO: Texel = [0.0; 8];

/// The most levels a pyramid gets (level 12 stands for a CoC of about 12 000 px).
pub(super) const MAX_LEVELS: usize = 12;

/// Output rows of a level made by one task: its input rows are made once for the band, and
/// only the two rows at each end of a band twice.
pub(super) const BAND: usize = 16;

/// One level of the pyramid: level L has a texel per 2^L × 2^L pixels of the frame.
pub(super) struct Level {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) texels: Vec<Texel>,
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

/// The CoC diameter (px) that level L stands for (level 0, the sharp frame, for 0).
pub fn level_coc(level: usize) -> f32 {
    (COC_PER_SIGMA * level_variance(level).sqrt()) as f32
}

/// The CoC each image stands for, and where a CoC sits between them: image 0 is the sharp
/// frame (CoC 0), image j ≥ 1 level j. (Pixels blurred by their own CoC below level 3's read
/// the lens's disc instead, `super::disc`; the ladder serves the rest and the near field's
/// spread. Until then a half step, one pass of the 3×3 filter at full resolution, sat between
/// the sharp frame and level 1; the discs left it unread.)
pub(crate) struct Ladder {
    pub cocs: Vec<f32>,
    /// 1 / (CoC of image k + 1 − CoC of image k).
    pub inverse_gaps: Vec<f32>,
    /// The CoCs of images 1 ..= top − 1 (then +∞): a CoC's image below is the count of
    /// these it reaches, found without a branch.
    bounds: [f32; BOUNDS],
}

/// Room in [`Ladder::bounds`]: the sharp frame and every level.
const BOUNDS: usize = 16;
const _: () = assert!(MAX_LEVELS <= BOUNDS);

impl Ladder {
    /// The sharp frame and levels 1 ..= `top`.
    pub(super) fn new(top: usize) -> Self {
        let mut cocs = vec![0.0];
        cocs.extend((1..=top).map(level_coc));
        let inverse_gaps = cocs.windows(2).map(|c| 1.0 / (c[1] - c[0])).collect();
        let mut bounds = [f32::INFINITY; BOUNDS];
        let inner = &cocs[1..cocs.len() - 1];
        bounds[..inner.len()].copy_from_slice(inner);
        Ladder {
            cocs,
            inverse_gaps,
            bounds,
        }
    }

    /// (k, f): level k mixed with level k + 1 by f, linearly in CoC between the CoCs the
    /// two stand for (clamped to the top level). The CoCs rise, so k, the last image below
    /// c short of the top, is the number of bounds c reaches.
    #[inline(always)]
    pub(super) fn bracket(&self, c: f32) -> (usize, f32) {
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
pub(super) struct Source<'a> {
    pub(super) planes: Vec<&'a [f32]>,
    pub(super) coc: &'a [f32],
    /// The reference colour the texels are offset by (a uniform frame stays exact).
    pub(super) reference: [f32; 4],
    pub(super) epsilon: f32,
    /// E, the frame's largest CoC.
    pub(super) largest: f32,
    /// 1 / (E − ε).
    pub(super) inverse_span: f32,
    /// Every pixel fully blurred, T = 1 whatever its CoC ([`Source::plain`]).
    pub(super) plain: bool,
}

impl Source<'_> {
    /// The blurriness interpolator T = clamp((|CoC| − ε)/(E − ε), 0, 1).
    #[inline(always)]
    pub(super) fn interpolator(&self, c: f32) -> f32 {
        if self.plain {
            return 1.0;
        }
        ((c.abs() - self.epsilon) * self.inverse_span).clamp(0.0, 1.0)
    }

    /// A pixel's weight in the blurred images, w = max(T, [`IN_FOCUS_WEIGHT`]).
    #[inline(always)]
    pub(super) fn weight(&self, c: f32) -> f32 {
        self.interpolator(c).max(IN_FOCUS_WEIGHT)
    }

    /// The same frame with every pixel fully blurred (T = 1 whatever its CoC, as the twin's
    /// `frame_texel` takes it), so that a level made from it sums its pixels by the filter
    /// alone, w = 1: the plain level 1 a near pixel's disc reads (`super::disc`).
    pub(super) fn plain(&self) -> Self {
        Source {
            planes: self.planes.clone(),
            plain: true,
            ..*self
        }
    }
}

/// What a sum of weights w is divided by: w, or the smallest positive float where w is
/// below it (NaN included, in one comparison).
#[inline(always)]
pub(super) fn divisor(w: f32) -> f32 {
    if w > f32::MIN_POSITIVE {
        w
    } else {
        f32::MIN_POSITIVE
    }
}

/// Lanes of a texel that carry something: colour (4), w, T_near.
const LANES: usize = 6;

/// Halves a plane's row across, [1 3 3 1]/8 over 2i − 1 ..= 2i + 2, clamped to its ends (the
/// planar twin of [`halve_row`], the same sums in the same order).
#[inline(always)]
pub(super) fn halve_plane_row(row: &[f32], out: &mut [f32]) {
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
pub(super) fn build(source: &Source, width: usize, height: usize, count: usize) -> Vec<Level> {
    let mut levels: Vec<Level> = Vec::with_capacity(count);
    levels.push(first_level(source, width, height));
    halve_levels(&mut levels, count);
    levels
}

/// Level 1 over the frame (of [`Source::plain`]: the plain level 1).
pub(super) fn first_level(source: &Source, width: usize, height: usize) -> Level {
    let (w2, h2) = (width.div_ceil(2), height.div_ceil(2));
    let mut texels = vec![ZERO; w2 * h2];
    texels
        .par_chunks_mut(w2 * BAND)
        .enumerate()
        .for_each_init(FirstScratch::default, |s, (band, out)| {
            first_level_band(source, width, height, band, out, s)
        });
    Level {
        width: w2,
        height: h2,
        texels,
    }
}

/// Levels 2 ..= `count` halved from level 1, the first of `levels` (for the beauty's texels
/// and the carried planes' alike: the same sums lane by lane).
pub(super) fn halve_levels(levels: &mut Vec<Level>, count: usize) {
    while levels.len() < count {
        let above = levels.last().expect("level 1 is made first");
        let next = halve(above.width, above.height, |y, out, _| {
            halve_across(&above.texels[y * above.width..(y + 1) * above.width], out)
        });
        levels.push(next);
    }
}

#[cfg(test)]
mod tests {
    use super::super::compose::Sampler;
    use super::*;
    use crate::numeric::close;

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
            plain: false,
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
                    close(mass, 1.0, 0.02),
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
                close(variance, stated, 0.01 * stated),
                "level {l}: measured {variance}, stated {stated}"
            );
        }
    }

    #[test]
    fn the_ladder_mixes_continuously_between_levels() {
        let ladder = Ladder::new(5);
        // Level CoCs grow about twofold a level (3.5155 σ; level 1: σ² = 3/4 + 2/3 + 1/12).
        assert!(close(level_coc(1), 4.305, 0.01), "{}", level_coc(1));
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
}
