//! The lens's disc, gathered directly where the pyramid cannot show it: a pixel blurred by
//! its own CoC below level 3's (18.1 px) takes the disc of that CoC over the sharp frame, or
//! over level 1, instead of the levels' mix.
//!
//! Why: the pyramid's images are Gaussian-like, and a disc is not. A disc passes a texture
//! whose period is near its diameter inverted (its first side lobe, −13 % of the texture's
//! contrast); no Gaussian of any width does, and the half step and level 1 alias a texture of
//! a few pixels besides (a 2 px checker under a 5 px CoC came out upright: `border`,
//! BENCHMARKS.md "Frame borders and the near rim"). Below level 2's CoC (9.0 px) the pyramid
//! mixed the sharp frame, a half step and levels 1 and 2, where both faults are largest; a
//! disc there is about 70 taps at most, 89 in the mix of the two discs (the half step is
//! gone: nothing reads it now).
//!
//! Which image a pixel of CoC c reads ([`kernel`]), L2 and L3 being levels 2 and 3's CoCs:
//! - c ≤ ¾·L2: the disc over the sharp frame ([`frame_disc`]);
//! - ¾·L2 < c ≤ L2: that disc mixed into the disc over level 1, linearly in c;
//! - L2 < c ≤ 0.9·L3: the disc over level 1 ([`level_disc`]): level 1's texels (premultiplied
//!   by w, already filtered) sampled over a disc narrowed by the texels' own blur (variance
//!   ¾ px²): √(c² − 16·¾) px across, half that in texels;
//! - 0.9·L3 < c < L3: that disc mixed into the pyramid's mix;
//! - c ≥ L3, or a pixel the near field's spread blurs: the pyramid's mix alone.
//!
//! Both discs weigh a tap by its coverage (the share of the pixel or texel inside the disc,
//! `clamp(r + ½ − d, 0, 1)`, so the disc grows smoothly with c) times its w, as the levels
//! do (an in-focus pixel lends almost nothing), and renormalise over the taps inside the frame
//! (what lies outside is unknown); except that a pixel in front of the focus plane takes
//! every tap by its coverage alone: its frame disc scales each tap by 1/w ([`frame_disc`]'s
//! `plain`), and its level disc reads the plain level 1, made from the frame with w = 1
//! (`levels::Source::plain`; 8 bytes a frame pixel, made only where such a pixel reads it).
//! The GPU twin (`frame_disc`, `level_disc`, `disc_sum` and `span` in
//! src/gpu/dof/blend.wgsl) sums the same taps in the same order. Measured (BENCHMARKS.md,
//! "blend: the disc below level 3" and "blend: the near pixel's disc"): region RMSE on
//! `border` 0.06213 → 0.02952 → 0.02861 and on
//! `layers dof` at 640×360 0.03278 → 0.02171; every level's disc (the pyramid kept only for
//! the near field) erred a little less still but took 0.3 s at 1080p, twice the gather.

use super::levels::{divisor, level_coc, Level, Source, Texel, NEAR, W, ZERO};

/// The lane of 1/w in the beauty's frame texels ([`frame_texels`]; lane [`NEAR`] of a
/// level's texel, unused in the frame's): a near pixel's disc weighs each tap by it, undoing
/// the tap's w ([`frame_disc`]).
pub(super) const INVERSE: usize = NEAR;

/// Per-axis variance (px² of the frame) of level 1's texels: one [1 3 3 1]/8 halving.
const LEVEL_1_VARIANCE: f32 = 0.75;

/// Where, as a share of level 2's CoC, the frame's disc starts to give way to level 1's.
pub const FRAME_UNTIL: f32 = 0.75;
/// Where, as a share of level 3's CoC, level 1's disc starts to give way to the pyramid.
pub const LEVEL_UNTIL: f32 = 0.9;

/// The image a pixel blurred by its own CoC reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Kernel {
    /// The disc over the sharp frame.
    Frame,
    /// The frame's disc mixed with level 1's by f.
    FrameToLevel(f32),
    /// The disc over level 1.
    Level,
    /// Level 1's disc mixed with the pyramid's mix by f.
    LevelToPyramid(f32),
    /// The pyramid's mix.
    Pyramid,
}

/// Levels 2 and 3's CoCs, where the discs end (the GPU twin's uniform carries them).
pub fn disc_bounds() -> [f32; 2] {
    [level_coc(2), level_coc(3)]
}

/// The image a pixel of own CoC `c` (px, diameter) reads; `bounds` is [`disc_bounds`].
#[inline(always)]
pub(super) fn kernel(c: f32, [level_2, level_3]: [f32; 2]) -> Kernel {
    let frame_until = FRAME_UNTIL * level_2;
    let level_until = LEVEL_UNTIL * level_3;
    if c <= frame_until {
        Kernel::Frame
    } else if c <= level_2 {
        Kernel::FrameToLevel((c - frame_until) / (level_2 - frame_until))
    } else if c <= level_until {
        Kernel::Level
    } else if c < level_3 {
        Kernel::LevelToPyramid((c - level_until) / (level_3 - level_until))
    } else {
        Kernel::Pyramid
    }
}

/// Every pixel of the frame as a texel, as level 1's are made before their halving: each of
/// `planes` offset by its `reference` and premultiplied by the pixel's w (w itself in lane
/// [`W`] and 1/w in lane [`INVERSE`] when `with_w`: the beauty's; the carried planes' lanes
/// fill all eight and divide by the beauty's).
pub(super) fn frame_texels(
    source: &Source,
    planes: &[&[f32]],
    reference: &Texel,
    with_w: bool,
) -> Vec<Texel> {
    use rayon::prelude::*;
    let mut texels = vec![ZERO; source.coc.len()];
    texels.par_iter_mut().enumerate().for_each(|(i, t)| {
        let w = source.weight(source.coc[i]);
        for ((v, plane), r) in t.iter_mut().zip(planes).zip(reference) {
            *v = (plane[i] - r) * w;
        }
        if with_w {
            t[W] = w;
            t[INVERSE] = 1.0 / w;
        }
    });
    texels
}

/// The disc of diameter `c` about frame pixel (x, y) over the frame's texels
/// ([`frame_texels`]), not normalised: each lane's sum of the texels times their coverage
/// (lane [`W`], the weight to divide by, where the texels carry w).
///
/// `plain`, for a pixel in front of the focus plane, holds the beauty's texels (those
/// `texels` are, or those a carried group's were made beside): each tap is weighed by its
/// coverage times its 1/w (lane [`INVERSE`]), so every tap counts alike, the sharp ones
/// too. w is there so that an in-focus pixel lends nothing to a blurred one behind it; a near
/// pixel is the blurrier one, and what lies behind its rim is seen through its blur. On the
/// real Cycles frame (a fan 4–6 px out of focus before an 8.5 px wall) the region RMSE fell
/// from 0.01490 to 0.01357, on `layers dof` from 0.02512 to 0.02426 (BENCHMARKS.md, "blend:
/// the near pixel's disc").
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn frame_disc(
    texels: &[Texel],
    width: usize,
    height: usize,
    x: usize,
    y: usize,
    c: f32,
    rows: &mut DiscRows,
    plain: Option<&[Texel]>,
) -> Texel {
    let spans = rows.about(0.5 * c + 0.5, 0.0, 0.0);
    let grid = Grid {
        texels,
        width,
        height,
    };
    disc_sum(grid, plain, (x as isize, y as isize), 0.0, spans)
}

/// The disc of diameter `c` about frame pixel (x, y) over `level` (level 1, a texel per
/// 2 × 2 pixels), not normalised: each lane's sum of the texels times their coverage (lane
/// [`W`] is the weight to divide by). `rows` is kept per column parity (the centre's
/// fraction alternates).
#[inline(always)]
pub(super) fn level_disc(
    level: &Level,
    x: usize,
    y: usize,
    c: f32,
    rows: &mut [DiscRows; 2],
) -> Texel {
    let diameter = (c * c - 16.0 * LEVEL_1_VARIANCE).max(0.0).sqrt();
    // The pixel's centre in level 1's texels, (x + ½)/2 − ½: a whole texel and ¼ or ¾.
    let (px, py) = ((x as f32 + 0.5) * 0.5 - 0.5, (y as f32 + 0.5) * 0.5 - 0.5);
    let (cx, cy) = (px.floor(), py.floor());
    let (fx, fy) = (px - cx, py - cy);
    let spans = rows[x % 2].about(0.25 * diameter + 0.5, fx, fy);
    let grid = Grid {
        texels: &level.texels,
        width: level.width,
        height: level.height,
    };
    disc_sum(grid, None, (cx as isize, cy as isize), fx, spans)
}

/// A disc's rows about a centre (cx + fx, cy + fy), cx and cy whole, as offsets from
/// (cx, cy): the texels each covers and those wholly inside (d ≤ reach − 1, weight 1),
/// worked out once per reach and fraction (neighbouring pixels mostly share both).
#[derive(Default)]
pub(super) struct DiscRows {
    key: Option<(f32, f32, f32)>,
    rows: Vec<Span>,
    reach: f32,
}

/// One row of a disc, as offsets from its centre's whole texel.
#[derive(Clone, Copy)]
struct Span {
    dy: isize,
    dy2: f32,
    from: isize,
    to: isize,
    /// Wholly inside: [inner_from, inner_to] (empty where inner_from > inner_to).
    inner_from: isize,
    inner_to: isize,
}

impl DiscRows {
    /// The rows of the disc of `reach` about a centre whose fractions are (fx, fy).
    #[inline(always)]
    fn about(&mut self, reach: f32, fx: f32, fy: f32) -> &DiscRows {
        if self.key != Some((reach, fx, fy)) {
            self.key = Some((reach, fx, fy));
            self.reach = reach;
            self.rows.clear();
            let inner = reach - 1.0;
            let top = (fy - reach).ceil() as isize;
            let bottom = (fy + reach).floor() as isize;
            for dy in top..=bottom {
                let d = dy as f32 - fy;
                let dy2 = d * d;
                let across = (reach * reach - dy2).max(0.0).sqrt();
                let from = (fx - across).ceil() as isize;
                let to = (fx + across).floor() as isize;
                if to < from {
                    continue;
                }
                let (inner_from, inner_to) = if inner > 0.0 && inner * inner > dy2 {
                    let half = (inner * inner - dy2).sqrt();
                    (
                        ((fx - half).ceil() as isize).max(from),
                        ((fx + half).floor() as isize).min(to),
                    )
                } else {
                    (to + 1, to)
                };
                self.rows.push(Span {
                    dy,
                    dy2,
                    from,
                    to,
                    inner_from,
                    inner_to,
                });
            }
        }
        self
    }
}

/// The sum of a grid's texels over the disc `spans` about (cx + fx, cy + ·) whose coverage of
/// a texel at distance d is `clamp(reach − d, 0, 1)`: rows top to bottom, each left to
/// right, texels outside the grid left out. The texels wholly inside (d ≤ reach − 1) weigh
/// 1 and are added without a square root (most of a disc's taps; eight lanes at once).
/// `scales` (the beauty's frame texels, for a near pixel's frame disc) weighs each tap by
/// its lane [`INVERSE`] too: the same taps in the same order, a multiply and add each.
#[inline(always)]
fn disc_sum(
    grid: Grid,
    scales: Option<&[Texel]>,
    (cx, cy): (isize, isize),
    fx: f32,
    spans: &DiscRows,
) -> Texel {
    let mut sum = ZERO;
    let width = grid.width;
    for span in &spans.rows {
        let Some((j, from, to, inner_from, inner_to)) = grid.clipped((cx, cy), span) else {
            continue;
        };
        let row = &grid.texels[j * width..(j + 1) * width];
        // A match, not `map` with a closure (`multiversion`: see `rim`).
        #[allow(clippy::manual_map)]
        let scale = match scales {
            Some(s) => Some(&s[j * width..(j + 1) * width]),
            None => None,
        };
        for i in from..inner_from.min(to + 1) {
            let (t, k, dx) = (&row[i as usize], factor(scale, i), (i - cx) as f32 - fx);
            rim(&mut sum, t, k, dx, span.dy2, spans.reach);
        }
        if inner_from <= inner_to {
            let (a, b) = (inner_from as usize, inner_to as usize + 1);
            match scale {
                None => {
                    for t in &row[a..b] {
                        for (v, t) in sum.iter_mut().zip(t) {
                            *v += t;
                        }
                    }
                }
                Some(scale) => {
                    for (t, s) in row[a..b].iter().zip(&scale[a..b]) {
                        add(&mut sum, t, s[INVERSE]);
                    }
                }
            }
        }
        for i in (inner_to + 1).max(from)..=to {
            let (t, k, dx) = (&row[i as usize], factor(scale, i), (i - cx) as f32 - fx);
            rim(&mut sum, t, k, dx, span.dy2, spans.reach);
        }
    }
    sum
}

/// A tap's scale: its lane [`INVERSE`] in `scale`'s row, or 1.
#[inline(always)]
fn factor(scale: Option<&[Texel]>, i: isize) -> f32 {
    match scale {
        Some(s) => s[i as usize][INVERSE],
        None => 1.0,
    }
}

/// A grid of texels: the frame's or a level's.
#[derive(Clone, Copy)]
struct Grid<'a> {
    texels: &'a [Texel],
    width: usize,
    height: usize,
}

impl Grid<'_> {
    /// A row of a disc about (cx + ·, cy + ·) clipped to the grid: the row, the texels
    /// covered [from, to] and those wholly inside [inner_from, inner_to] (empty where
    /// inner_from > inner_to); none where the row misses the grid. (A function, not an
    /// iterator's closure: `multiversion` compiles closures for the baseline CPU.)
    #[inline(always)]
    fn clipped(
        &self,
        (cx, cy): (isize, isize),
        span: &Span,
    ) -> Option<(usize, isize, isize, isize, isize)> {
        let (last_column, last_row) = (self.width as isize - 1, self.height as isize - 1);
        let j = cy + span.dy;
        if j < 0 || j > last_row {
            return None;
        }
        let from = (cx + span.from).max(0);
        let to = (cx + span.to).min(last_column);
        if to < from {
            return None;
        }
        let inner_from = (cx + span.inner_from).max(from);
        let inner_to = (cx + span.inner_to).min(to);
        let (inner_from, inner_to) = if span.inner_from > span.inner_to || inner_from > inner_to {
            (to + 1, to)
        } else {
            (inner_from, inner_to)
        };
        Some((j as usize, from, to, inner_from, inner_to))
    }
}

/// `sum += k · t`, every lane.
#[inline(always)]
fn add(sum: &mut Texel, t: &Texel, k: f32) {
    for (v, t) in sum.iter_mut().zip(t) {
        *v += k * t;
    }
}

/// A texel on a disc's rim, at (dx, dy) from its centre, added by its coverage times `k` (1,
/// or its 1/w in a near pixel's frame disc; a function, not a closure, so that it is compiled
/// with its caller's instructions: `multiversion`).
#[inline(always)]
fn rim(sum: &mut Texel, t: &Texel, k: f32, dx: f32, dy2: f32, reach: f32) {
    let cover = (reach - (dx * dx + dy2).sqrt()).clamp(0.0, 1.0);
    add(sum, t, cover * k);
}

/// A [`level_disc`]'s colour lanes divided by its w (as a level's row is: at least the
/// smallest positive float), and the w.
#[inline(always)]
pub(super) fn normalised(mut sum: Texel) -> (Texel, f32) {
    let w = divisor(sum[W]);
    for v in sum.iter_mut().take(4) {
        *v /= w;
    }
    (sum, w)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kernel_runs_from_the_frame_to_the_pyramid_continuously() {
        let bounds = disc_bounds();
        let [l2, l3] = bounds;
        assert!(
            (l2 - 8.96).abs() < 0.01 && (l3 - 18.1).abs() < 0.05,
            "{l2} {l3}"
        );
        assert_eq!(kernel(1.5, bounds), Kernel::Frame);
        assert_eq!(kernel(0.75 * l2, bounds), Kernel::Frame);
        assert_eq!(kernel(l2, bounds), Kernel::FrameToLevel(1.0));
        assert_eq!(kernel(12.0, bounds), Kernel::Level);
        match kernel(0.95 * l3, bounds) {
            Kernel::LevelToPyramid(f) => assert!((f - 0.5).abs() < 1e-4, "{f}"),
            other => panic!("{other:?}"),
        }
        assert_eq!(kernel(l3, bounds), Kernel::Pyramid);
        assert_eq!(kernel(40.0, bounds), Kernel::Pyramid);
    }
}
