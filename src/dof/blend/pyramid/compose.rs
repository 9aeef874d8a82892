//! The pyramid's compose stage: each output pixel mixed from the two images that bracket its
//! CoC (seed 004, "Depth of Field: Render to Backbuffer", with the pyramid's levels for the
//! talk's textures).
//!
//! In: the frame (written in place, a band of rows per task, with copies of the rows around
//! the one written: a [`Window`]), its signed CoC and constants ([`Source`]), the levels
//! ([`super::levels::build`]) each read through a [`Sampler`], and the frame's [`super::Plan`]
//! (its [`Ladder`], where T_near is read). Out: each pixel's colour, where it is blurred.
//!
//! Per frame row ([`compose_row`]): each pixel's blurriness T, raised to the near field's
//! blurred T_near where that spreads over it by more than [`SPREAD_MARGIN`]; the level rows
//! the row needs, each made once (two texel rows mixed, colour divided by w); then each
//! blurred pixel: below level 3's CoC, blurred by its own CoC, the lens's disc
//! ([`super::disc`]); otherwise mixed from the two images the ladder brackets it between,
//! the sharp pixel or a level sampled bilinearly. The GPU twin's `compose` entry point (`crate::gpu::dof::blend`) runs the same
//! sums per pixel.

use super::disc::{frame_disc, kernel, level_disc, normalised, DiscRows, Kernel};
use super::levels::{divisor, Ladder, Level, Source, Texel, MAX_LEVELS, NEAR, W, ZERO};

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
pub(super) fn lerp(a: &Texel, b: &Texel, f: f32) -> Texel {
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
        let w = divisor(t[W]);
        let divisor = [w, w, w, w, 1.0, 1.0, 1.0, 1.0];
        for (v, d) in t.iter_mut().zip(divisor) {
            *v /= d;
        }
    }
}

/// [`normalised_row`] for a carried group: texel rows `a` and `b` mixed by f into `out`,
/// every lane divided by the w of `beauty`'s texel (that of the beauty's row mixed by the
/// same f, so each lane gets the divisor the beauty's colour got).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn carried_normalised_row(a: &[Texel], b: &[Texel], f: f32, beauty: &[Texel], out: &mut [Texel]) {
    for ((o, a), b) in out
        .as_flattened_mut()
        .iter_mut()
        .zip(a.as_flattened())
        .zip(b.as_flattened())
    {
        *o = a + f * (b - a);
    }
    for (t, u) in out.iter_mut().zip(beauty) {
        let w = divisor(u[W]);
        for v in t.iter_mut() {
            *v /= w;
        }
    }
}

/// A level sampled bilinearly at the frame's pixel centres, a row at a time: the row
/// between the two texel rows that bracket a frame row is made once, and each pixel of the
/// frame row interpolates across it.
pub(super) struct Sampler<'a> {
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
    pub(super) fn new(level: &'a Level, number: usize, width: usize, height: usize) -> Self {
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
    pub(super) fn row(&self, y: usize, row: &mut Vec<Texel>) {
        let (r0, r1, f) = self.down[y];
        let w = self.level.width;
        let a = &self.level.texels[r0 as usize * w..(r0 as usize + 1) * w];
        let b = &self.level.texels[r1 as usize * w..(r1 as usize + 1) * w];
        row.resize(w, ZERO);
        normalised_row(a, b, f, row);
    }

    /// [`Sampler::row`] of a carried group's level (this level's size, `super::carry`): the
    /// texel rows mixed the same way and every lane divided by the w of `beauty`, the row
    /// [`Sampler::row`] made of this level for the same frame row.
    pub(super) fn carried_row(
        &self,
        level: &Level,
        y: usize,
        beauty: &[Texel],
        row: &mut Vec<Texel>,
    ) {
        let (r0, r1, f) = self.down[y];
        let w = level.width;
        let a = &level.texels[r0 as usize * w..(r0 as usize + 1) * w];
        let b = &level.texels[r1 as usize * w..(r1 as usize + 1) * w];
        row.resize(w, ZERO);
        carried_normalised_row(a, b, f, beauty, row);
    }

    /// The level this sampler reads.
    pub(super) fn level_ref(&self) -> &'a Level {
        self.level
    }

    /// The level at frame pixel x, from the row [`Sampler::row`] made.
    #[inline(always)]
    pub(super) fn at(&self, row: &[Texel], x: usize) -> Texel {
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
pub(super) struct Scratch {
    /// Level l's row (l ≥ 1) at l − 1, colour divided by w and w itself (the carried
    /// planes' rows divide by it: `super::carry`).
    pub(super) made: Vec<Vec<Texel>>,
    /// Each pixel's blurriness, negative where the near field's spread sets it.
    pub(super) blur: Vec<f32>,
    /// The levels made for the row's mixes (first, last), if any pixel of it is blurred.
    pub(super) mixing: Option<(usize, usize)>,
    /// Each blurred pixel's mix of two images, offset by the reference.
    mixed: Vec<Texel>,
    /// T_near of the two levels that bracket E, as planes.
    near_lower: Vec<f32>,
    near_upper: Vec<f32>,
    /// Per pixel that reads a disc, its w: the frame's and level 1's (the carried planes
    /// divide by them).
    pub(super) frame_w: Vec<f32>,
    pub(super) level_w: Vec<f32>,
    /// The last discs' rows (`super::disc::DiscRows`): the frame's, level 1's per column
    /// parity.
    frame_rows: DiscRows,
    level_rows: [DiscRows; 2],
}

/// The compose stage for frame row y: each pixel's blurriness, the levels the row needs,
/// then each pixel mixed from the two levels that bracket its CoC (the sharp pixel as level
/// 0). `out` holds the row of each plane, sharp, and is written in place; `window` holds
/// copies of the rows around it as they were.
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub(super) fn compose_row(
    pyramid: &Pyramid,
    y: usize,
    window: &Window,
    scratch: &mut Scratch,
    out: &mut [&mut [f32]],
) {
    let Pyramid {
        source,
        samplers,
        ladder,
        near,
        frame: frame_texels,
        plain,
        bounds,
    } = pyramid;
    let near = *near;
    let width = out[0].len();
    let row = y * width;
    let coc = &source.coc[row..row + width];
    let height = source.coc.len() / width;
    let Scratch {
        made,
        blur,
        mixing,
        mixed,
        near_lower,
        near_upper,
        frame_w,
        level_w,
        frame_rows,
        level_rows,
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
    // Image k of the ladder is level k.
    *mixing = None;
    if most > 0.0 {
        let (lo, _) = ladder.bracket(to_coc(least));
        let (hi, _) = ladder.bracket(to_coc(most));
        for l in lo.max(1)..=hi + 1 {
            make(l, made);
        }
        *mixing = Some((lo.max(1), hi + 1));
    }

    let mut reference = ZERO;
    reference[..4].copy_from_slice(&source.reference);
    // `out` holds the sharp row: pixels left sharp are not touched.
    let channels = out.len();
    let images = Images {
        window,
        channels,
        reference: &reference,
        samplers,
        made,
        frame: frame_texels,
        plain: *plain,
        coc,
        width,
        height,
        y,
    };
    mixed.resize(width, ZERO);
    frame_w.resize(width, 0.0);
    level_w.resize(width, 0.0);
    for (x, (((&t, m), frame_w), level_w)) in blur
        .iter()
        .zip(mixed.iter_mut())
        .zip(frame_w.iter_mut())
        .zip(level_w.iter_mut())
        .enumerate()
    {
        if t == 0.0 {
            continue;
        }
        let c = to_coc(t.abs());
        // Below level 3's CoC a pixel's own blur is the lens's disc (`super::disc`); the
        // near field's spread mixes levels only (T_near is the levels' own). (Methods, not
        // closures: `multiversion` compiles a closure for the baseline CPU, and there the
        // discs' rounding became calls to `ceilf` and `floorf`.)
        let kernel = if t > 0.0 {
            kernel(c, *bounds)
        } else {
            Kernel::Pyramid
        };
        *m = match kernel {
            Kernel::Frame => {
                let frame;
                (frame, *frame_w) = images.frame_disc(x, c, frame_rows);
                frame
            }
            Kernel::FrameToLevel(f) => {
                let (frame, level);
                (frame, *frame_w) = images.frame_disc(x, c, frame_rows);
                (level, *level_w) = images.level_disc(x, c, level_rows);
                lerp(&frame, &level, f)
            }
            Kernel::Level => {
                let level;
                (level, *level_w) = images.level_disc(x, c, level_rows);
                level
            }
            Kernel::LevelToPyramid(f) => {
                let level;
                (level, *level_w) = images.level_disc(x, c, level_rows);
                lerp(&level, &images.mix(ladder, c, x), f)
            }
            Kernel::Pyramid => images.mix(ladder, c, x),
        };
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
/// to it but for rounding, and the two give different images there (the pixel's own blur
/// the disc of its CoC, the spread the levels' mix): compared bare, the last bit decided
/// between them pixel by pixel, a pattern of dots over the foreground (seen between the CPU
/// and the GPU twin on `layers` with ε = 3 px, up to 0.04 apart, when the two were the
/// ladders with and without a half step). 1e-3 of the blur range is 0.03 px of CoC at E = 32.
const SPREAD_MARGIN: f32 = 1e-3;

/// A pixel's blurriness `t` given the near field's T_near read at the two levels that
/// bracket E, mixed by f: negative where the near field's spread sets the blur.
#[inline(always)]
fn spread(t: &mut f32, lower: f32, upper: f32, f: f32) {
    let spread = lower + f * (upper - lower);
    if spread > *t + SPREAD_MARGIN {
        *t = -spread;
    }
}

/// What the compose stage mixes for frame row y: the sharp frame (offset by the reference)
/// and the levels' rows made for the row.
struct Images<'a> {
    window: &'a Window<'a>,
    channels: usize,
    reference: &'a Texel,
    samplers: &'a [Sampler<'a>],
    made: &'a [Vec<Texel>],
    /// The frame as texels, for the frame's disc.
    frame: &'a [Texel],
    /// The plain level 1, for a near pixel's level disc.
    plain: Option<&'a Level>,
    /// The row's signed CoC.
    coc: &'a [f32],
    width: usize,
    height: usize,
    y: usize,
}

impl Images<'_> {
    /// The ladder's mix of the two images that bracket CoC c at frame pixel x.
    #[inline(always)]
    fn mix(&self, ladder: &Ladder, c: f32, x: usize) -> Texel {
        let (k, f) = ladder.bracket(c);
        lerp(&self.at(k, x), &self.at(k + 1, x), f)
    }

    /// The frame's disc of diameter c about frame pixel x, normalised, and its w; every tap
    /// alike where the pixel is in front of the focus plane (`super::disc::frame_disc`).
    #[inline(always)]
    fn frame_disc(&self, x: usize, c: f32, rows: &mut DiscRows) -> (Texel, f32) {
        let plain = (self.coc[x] < 0.0).then_some(self.frame);
        normalised(frame_disc(
            self.frame,
            self.width,
            self.height,
            x,
            self.y,
            c,
            rows,
            plain,
        ))
    }

    /// Level 1's disc of diameter c about frame pixel x, normalised, and its w: over the
    /// plain level 1 where the pixel is in front of the focus plane (every tap alike, as
    /// its frame disc takes them: `super::disc::frame_disc`).
    #[inline(always)]
    fn level_disc(&self, x: usize, c: f32, rows: &mut [DiscRows; 2]) -> (Texel, f32) {
        let level = match self.plain {
            Some(plain) if self.coc[x] < 0.0 => plain,
            _ => self.samplers[0].level_ref(),
        };
        normalised(level_disc(level, x, self.y, c, rows))
    }

    /// Image j of the ladder (level j, the sharp frame for 0) at frame pixel x (a method,
    /// not a closure: `multiversion` would leave a closure compiled for the baseline CPU, out
    /// of line).
    #[inline(always)]
    fn at(&self, j: usize, x: usize) -> Texel {
        if j >= 1 {
            self.samplers[j - 1].at(&self.made[j - 1], x)
        } else {
            let mut offset = ZERO;
            for (lane, rows) in self.window.iter().take(self.channels).enumerate() {
                offset[lane] = rows[1][x] - self.reference[lane];
            }
            offset
        }
    }
}

/// What every compose task reads: the frame's constants and CoC, the levels' samplers, the
/// ladder, and where T_near is read (in levels, if any pixel is in front of the focus
/// plane).
pub(super) struct Pyramid<'a> {
    pub(super) source: &'a Source<'a>,
    pub(super) samplers: &'a [Sampler<'a>],
    pub(super) ladder: &'a Ladder,
    pub(super) near: Option<(usize, f32)>,
    /// The frame as texels, premultiplied by w (`super::disc::frame_texels`; empty where no
    /// pixel reads the frame's disc).
    pub(super) frame: &'a [Texel],
    /// The plain level 1 (`levels::Source::plain`), where a pixel in front of the focus
    /// plane reads level 1's disc.
    pub(super) plain: Option<&'a Level>,
    /// Levels 2 and 3's CoCs (`super::disc::disc_bounds`).
    pub(super) bounds: [f32; 2],
}

/// Frame rows y − 1, y and y + 1 (clamped to the frame) of each colour plane, as they were
/// before the compose stage wrote any of them: the compose stage writes in place.
pub(super) type Window<'a> = [[&'a [f32]; 3]; 4];
