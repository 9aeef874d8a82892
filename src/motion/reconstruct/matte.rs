//! matte — how much of each pixel at a silhouette a moving surface covers, for
//! [`super`]'s exposure variant.
//!
//! A rendered pixel is an area: where a moving surface's edge crosses it, its colour mixes
//! the surface's and what lies behind, while its depth and motion (sampled at the pixel's
//! centre) name one surface alone. The gather reads each tap between pixels and splits it by
//! surface; with the surfaces' shares taken from those point labels, the edge sits halfway
//! between a moving and a still pixel centre wherever it really is, and a still pixel's own
//! colour keeps the fringe it had at the frame's time while the taps add the surface again
//! (on `sparse` at 320×180, still pixels beside a disc moving along its rim came out 0.04–0.1
//! too bright).
//!
//! The matte takes each pixel where moving and still pixels meet, with the moving ones in
//! front, and finds the pair of colours, one from a moving pixel and one from a still pixel
//! of its 5×5 neighbourhood (those whose own 3×3 is all of one kind first), whose line passes
//! nearest to its colour (a local colour-line model, as in matting; the colour is RGBA,
//! premultiplied, alpha a fourth channel mixed by coverage as R, G and B are): its coverage α
//! is where its colour projects on that line, kept on its own side of one half (a pixel whose
//! centre the surface covers is at least half covered) unless the still colour is empty space
//! (a view layer's pixels beside its surface, colour and alpha 0, where a pixel's alpha is its
//! coverage, rendered, and its label may be a neighbour's motion given by the stack), and the
//! two colours are remembered by the pixels they came from. Where no pair explains the colour
//! (the residual over 2 % of the pair's squared distance, or two colours too alike to tell
//! apart), the pixel keeps its label: α 1 moving, 0 still. Everywhere else α is the label.
//!
//! The gather then splits a tap's four pixels by coverage: each gives α of its weight to the
//! moving surface, in the surface's colour (a moving pixel's own colour with the still
//! pair's taken out, a still pixel's moving partner's), and 1 − α to the still one (the
//! other way round). Measured in BENCHMARKS.md ("the matte").
//!
//! Why alpha is a channel of the fit and of the unmixing (issue 33): in an opaque frame
//! alpha is 1 everywhere and adds nothing to either (the same bits as an RGB fit). In a view
//! layer over empty space (still neighbours transparent: colour and alpha 0) a surface's edge
//! pixel is premultiplied colour and alpha in the same proportion; unmixing R, G and B alone
//! pushed the colour to the surface's while its alpha stayed the pixel's fraction, so
//! colour came out above alpha (on `pan`'s FG layer, a still rim pixel (0.627, 0.627, 0.627,
//! α 0.660) became (0.884, 0.884, 0.916, α 0.661): 1.39 unpremultiplied). Fitted and unmixed
//! as a fourth channel, a surface's colour and alpha stay one premultiplied colour, and a
//! dark surface over empty space, whose RGB does not tell it from nothing, is told apart by
//! its alpha.

use rayon::prelude::*;

use super::config::{ReconstructConfig, Texel2014, HALF_PIXEL, LENGTH, Z};
use super::unmix::fits;
pub use super::unmix::{extrapolation, fit, over_empty, CANDIDATES};
use super::window::{silhouettes, Window};

/// Per pixel: α (the moving surface's coverage), then the pixels the moving and the still
/// colours of its pair come from, as `f32::from_bits` of their indices (the pixel's own
/// index where it has no pair), then how far its own surface's colour is extrapolated from
/// its partner's through its own in each of R, G, B and A ([`surfaces`], [`extrapolation`];
/// 0 without a pair). The GPU reads the same [`WORDS`] words.
///
/// All seven are fitted on the beauty's colour and given as they are to every light layer
/// (issue 29): with the unmixing's clamp to the colours' range turned into a factor per
/// channel, a tap's colour is linear in the colour it is read from, so light layers that
/// add up to the beauty channel by channel still do after the gather (a layer's R, G and B
/// take the beauty's R, G and B factors; `crate::process` places them so).
pub type Matte = [f32; WORDS];

/// The words of a [`Matte`]: α, the two partners, and the extrapolation of R, G, B and A
/// (`MATTE_WORDS` in reconstruct.wgsl, which a unit test holds to this).
pub const WORDS: usize = 7;

/// Where a matte's pair points: pixel `i` itself when it has none.
#[inline]
pub fn unpaired(m: &Matte, i: usize) -> bool {
    m[1].to_bits() as usize == i && m[2].to_bits() as usize == i
}

/// A pair must explain the colour within this share of the pair's squared distance.
pub const RESIDUAL: f32 = 0.02;
/// Two colours closer than this (squared distance) do not tell coverage apart.
pub const DISTINCT: f32 = 1e-4;

/// The 5×5 neighbourhood without its centre, nearest first (the 3×3 ring, then the outer),
/// each ring in reading order.
#[rustfmt::skip]
const NEIGHBOURS: [(i64, i64); 24] = [
    (-1, -1), (0, -1), (1, -1), (-1, 0), (1, 0), (-1, 1), (0, 1), (1, 1),
    (-2, -2), (-1, -2), (0, -2), (1, -2), (2, -2), (-2, -1), (2, -1), (-2, 0),
    (2, 0), (-2, 1), (2, 1), (-2, 2), (-1, 2), (0, 2), (1, 2), (2, 2),
];

/// Where a pixel's pair may come from when either kind has no pure candidate (a 3×3 all of
/// its kind) in its 5×5: reconstruct's mattes take `Any` pixel of each kind; scatter's
/// fringe (`PureStill`) still takes any moving one (a tooth or a strand two pixels wide has
/// no pure pixel, and its colour is the best the frame has of it) but a still one only if
/// pure: the still partner is the colour a fringe pixel is unmixed towards, and a still
/// pixel with a moving neighbour holds a sliver itself. On a frame of noise, where almost
/// no pixel is pure, this leaves the fringe almost nothing to fit (BENCHMARKS.md).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Fallback {
    Any,
    PureStill,
}

/// What the matte reads of a pixel: its texel (colour, RGBA, then depth at `Z` and the
/// motion's length at `LENGTH`; nothing else is read). Reconstruct hands its packed texels;
/// scatter's fringe reads its own buffers in place, with nothing packed.
pub trait Texels: Sync {
    fn texel(&self, i: usize) -> Texel2014;

    /// `texel(i)[Z]` alone.
    #[inline(always)]
    fn depth(&self, i: usize) -> f32 {
        self.texel(i)[Z]
    }

    /// Whether pixel `i` moves (its motion's length, `texel(i)[LENGTH]`, half a pixel or more).
    #[inline(always)]
    fn moves(&self, i: usize) -> bool {
        moves(&self.texel(i))
    }
}

impl Texels for [Texel2014] {
    #[inline(always)]
    fn texel(&self, i: usize) -> Texel2014 {
        self[i]
    }
}

impl Texels for Vec<Texel2014> {
    #[inline(always)]
    fn texel(&self, i: usize) -> Texel2014 {
        self[i]
    }
}

#[inline]
fn moves(t: &Texel2014) -> bool {
    t[LENGTH] >= HALF_PIXEL
}

/// The matte of every pixel of the tiles `selected(column, row)` picks (the texels packed
/// there; a neighbour in a tile not picked is not read); elsewhere the label.
pub fn mattes(
    config: &ReconstructConfig,
    texels: &(impl Texels + ?Sized),
    selected: impl Fn(usize, usize) -> bool + Sync,
) -> Vec<Matte> {
    let (width, size) = (config.width as usize, config.tile as usize);
    let mut out = vec![[0.0f32; WORDS]; width * config.height as usize];
    let moving = |i: usize| texels.moves(i);
    // A row of tiles at a time: every pixel's label, then the mattes of the selected tiles'
    // pixels at a silhouette.
    out.par_chunks_mut((size * width).max(1))
        .enumerate()
        .for_each(|(r, rows)| {
            let first = r * size * width;
            for (k, m) in rows.iter_mut().enumerate() {
                let own = f32::from_bits((first + k) as u32);
                let label = texels.moves(first + k) as u32 as f32;
                *m = [label, own, own, 0.0, 0.0, 0.0, 0.0];
            }
            silhouettes(config, &moving, &selected, (r, false), |window, (x, y)| {
                if let Some(found) = matte(config, texels, window, (x, y), Fallback::Any) {
                    rows[y * width + x - first] = found;
                }
            });
        });
    out
}

/// [`mattes`]' pairs alone: each pixel of the tiles `selected(column, row)` picks that has
/// a pair and that `wanted(index)` asks for, in index order, with its matte (every other
/// pixel's is its label). For a pass that needs some silhouettes only (scatter's fringe: the
/// still pixels), without a matte for every pixel.
pub fn pairs(
    config: &ReconstructConfig,
    texels: &(impl Texels + ?Sized),
    selected: impl Fn(usize, usize) -> bool + Sync,
    wanted: impl Fn(usize) -> bool + Sync,
    fallback: Fallback,
) -> Vec<(usize, Matte)> {
    let (width, height) = (config.width as usize, config.height as usize);
    let size = config.tile as usize;
    let moving = |i: usize| texels.moves(i);
    // A row of tiles at a time, its pairs sorted (block by block they come in no index
    // order; no two share an index).
    let rows: Vec<Vec<(usize, Matte)>> = (0..height.div_ceil(size))
        .into_par_iter()
        .map(|r| {
            let mut found = Vec::new();
            let near_pure_still = fallback == Fallback::PureStill;
            silhouettes(
                config,
                &moving,
                &selected,
                (r, near_pure_still),
                |window, (x, y)| {
                    let i = y * width + x;
                    if wanted(i) {
                        if let Some(m) = matte(config, texels, window, (x, y), fallback) {
                            if !unpaired(&m, i) {
                                found.push((i, m));
                            }
                        }
                    }
                },
            );
            found.sort_unstable_by_key(|&(i, _)| i);
            found
        })
        .collect();
    rows.concat()
}

/// The matte of pixel (x, y) of the block whose [`Window`] is `window`, where it is at a
/// silhouette and has a pair (see the module doc), else `None`.
fn matte(
    config: &ReconstructConfig,
    texels: &(impl Texels + ?Sized),
    window: &Window,
    (x, y): (usize, usize),
    fallback: Fallback,
) -> Option<Matte> {
    // A pixel whose 3×3 is of one kind (all moving or all still, as read) is no silhouette:
    // no depth step there, and no pair.
    let (x, y) = (x as i64, y as i64);
    if window.get(&window.pure_moving, x, y) || window.get(&window.pure_still, x, y) {
        return None;
    }
    let width = config.width as i64;
    // A pixel is read where it lies in the frame and its tile is selected (every pixel this
    // reads lies within two of (x, y), in the window).
    let at = |x: i64, y: i64| -> Option<Texel2014> {
        window
            .get(&window.read, x, y)
            .then(|| texels.texel((y * width + x) as usize))
    };
    let centre = at(x, y)?;
    let moving = moves(&centre);
    // One kind throughout a pixel's 3×3 (the frame's and the tiles' edges leave it out).
    // A candidate of kind `kind` (moving or still), pure if `only_pure`.
    let candidate = |x: i64, y: i64, kind: bool, only_pure: bool| {
        let pure = if kind {
            &window.pure_moving
        } else {
            &window.pure_still
        };
        window.get(&window.read, x, y)
            && window.get(&window.moves, x, y) == kind
            && (!only_pure || window.get(pure, x, y))
    };
    // Candidates of the 5×5, nearest first and at most CANDIDATES of each kind: the pure
    // ones, or any when either kind has none pure.
    let mut best: Option<(f32, f32, i64, i64)> = None;
    // Each kind's candidates listed once (the pairs' loop reads the still ones once per moving
    // one: listed there, each pure test ran eight times over on a frame of noise).
    let candidates = |kind: bool, only_pure: bool| {
        let mut list = [(0i64, 0i64); CANDIDATES];
        let mut count = 0;
        for &(dx, dy) in &NEIGHBOURS {
            let (cx, cy) = (x + dx, y + dy);
            if candidate(cx, cy, kind, only_pure) {
                list[count] = (cx, cy);
                count += 1;
                if count == CANDIDATES {
                    break;
                }
            }
        }
        (list, count)
    };
    // The fringe's pairs need a pure still candidate (every pair's still one is): none, no
    // pair, and no 3×3 read (on a frame of noise, almost every still pixel).
    // (PURE_STILL is set on read still pixels alone: a moving one is in its own 3×3.)
    if fallback == Fallback::PureStill {
        let shift = x - 2 - window.x0;
        let pure = (y - 2..y + 3)
            .any(|ny| (window.pure_still[(ny - window.y0) as usize] >> shift) & 0b11111 != 0);
        if !pure {
            return None;
        }
    }
    // A silhouette: moving and still pixels in the 3×3, the moving ones in front (their
    // kinds from the bits, which say what `moves` of their texels says).
    let (mut front, mut back) = (f32::INFINITY, f32::NEG_INFINITY);
    for ny in y - 1..y + 2 {
        for nx in x - 1..x + 2 {
            if window.get(&window.read, nx, ny) {
                let z = texels.depth((ny * width + nx) as usize);
                if window.get(&window.moves, nx, ny) {
                    front = front.min(z);
                } else {
                    back = back.max(z);
                }
            }
        }
    }
    let separated = (back - front) * config.inv_soft_z >= 1.0;
    if !separated {
        return None;
    }
    for only_pure in [true, false] {
        // (In the second pass as in the first: with no candidate of a kind, no pair.)
        let (movers, m) = candidates(true, only_pure);
        if m == 0 {
            continue;
        }
        let (stills, s) = candidates(false, only_pure || fallback == Fallback::PureStill);
        if s == 0 {
            continue;
        }
        // The still candidates' colours a channel a row, so each moving candidate is fitted
        // against all of them at once ([`fits`]).
        let mut lanes = [[0.0f32; CANDIDATES]; 4];
        for (l, &(bx, by)) in stills[..s].iter().enumerate() {
            let b = at(bx, by).expect("a candidate");
            for (ch, row) in lanes.iter_mut().enumerate() {
                row[l] = b[ch];
            }
        }
        let c = [centre[0], centre[1], centre[2], centre[3]];
        for &(fx, fy) in &movers[..m] {
            let f = at(fx, fy).expect("a candidate");
            let [alphas, residuals, spreads] = fits(&c, &[f[0], f[1], f[2], f[3]], &lanes);
            for (l, &(bx, by)) in stills[..s].iter().enumerate() {
                let (alpha, residual, spread) = (alphas[l], residuals[l], spreads[l]);
                if spread < DISTINCT || residual.is_nan() || residual > RESIDUAL * spread {
                    continue;
                }
                if best.is_none_or(|(r, ..)| residual < r) {
                    best = Some((residual, alpha, fy * width + fx, by * width + bx));
                }
            }
        }
        break;
    }
    let (_, alpha, f, b) = best?;
    let (fc, bc) = (texels.texel(f as usize), texels.texel(b as usize));
    let alpha = if over_empty(&fc, &bc) {
        alpha
    } else if moving {
        alpha.max(0.5)
    } else {
        alpha.min(0.5)
    };
    let [er, eg, eb, ea] = extrapolation(&centre, &fc, &bc, alpha, moving);
    Some([
        alpha,
        f32::from_bits(f as u32),
        f32::from_bits(b as u32),
        er,
        eg,
        eb,
        ea,
    ])
}

/// Pixel `i`'s coverage and its two surfaces' colours (RGBA, premultiplied): the moving
/// surface's and the still one's. A moving pixel's own is its colour extrapolated away from
/// its still partner's by the matte's last four words ([`extrapolation`]), a still pixel's
/// likewise from its moving partner's; the other is its partner's colour. A pixel with no
/// pair gives its own colour to both. Linear in the texels' colours: the matte, fitted on the
/// beauty, holds every number that depends on colour.
/// Which of the beauty's channels (0 to 3: R, G, B, A) each value of `G` colours is, for
/// [`surfaces_of`]'s extrapolation.
pub type Kinds<const G: usize> = [[u8; 4]; G];

/// Every colour RGBA: the beauty's kinds.
pub const RGBA: Kinds<1> = [[0, 1, 2, 3]];

#[inline]
pub fn surfaces(texels: &[Texel2014], mattes: &[Matte], i: usize) -> (f32, [f32; 4], [f32; 4]) {
    let colour = |j: usize| {
        let t = &texels[j];
        [[t[0], t[1], t[2], t[3]]]
    };
    let (alpha, [moving], [still]) = surfaces_of(texels, mattes, i, &colour, &RGBA);
    (alpha, moving, still)
}

/// [`surfaces`] of `G` colours at once (the beauty's and carried layers', `colour(j)` those
/// of pixel j): each unmixed with the beauty's matte, channel by channel, as the beauty is,
/// each value with the extrapolation of the beauty's channel `kinds` names for it (0 to 3:
/// R, G, B, A; [`RGBA`] for colours that are RGBA each, the light layers' channels packed
/// four to a colour otherwise).
#[inline(always)]
pub fn surfaces_of<const G: usize>(
    texels: &[Texel2014],
    mattes: &[Matte],
    i: usize,
    colour: &impl Fn(usize) -> [[f32; 4]; G],
    kinds: &Kinds<G>,
) -> (f32, [[f32; 4]; G], [[f32; 4]; G]) {
    let m = &mattes[i];
    let [alpha, f, b, er, eg, eb, ea] = *m;
    let e = [er, eg, eb, ea];
    let c = colour(i);
    if unpaired(m, i) {
        // No pair: α is the label (0 or 1), and the colour is both surfaces'.
        return (alpha, c, c);
    }
    let f = colour(f.to_bits() as usize);
    let b = colour(b.to_bits() as usize);
    let mut moving = [[0.0f32; 4]; G];
    let mut still = [[0.0f32; 4]; G];
    let own_moves = moves(&texels[i]);
    for g in 0..G {
        for ch in 0..4 {
            let e = e[usize::from(kinds[g][ch] & 3)];
            if own_moves {
                moving[g][ch] = c[g][ch] + e * (c[g][ch] - b[g][ch]);
                still[g][ch] = b[g][ch];
            } else {
                moving[g][ch] = f[g][ch];
                still[g][ch] = c[g][ch] + e * (c[g][ch] - f[g][ch]);
            }
        }
    }
    (alpha, moving, still)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::reconstruct::{ReconstructConfig, ReconstructParams};
    use crate::numeric::{all_close, close};

    fn texel(rgb: [f32; 3], z: f32, v: f32) -> Texel2014 {
        [rgb[0], rgb[1], rgb[2], 1.0, z, v, 0.0, v]
    }

    /// A 12×6 frame: rows 0..3 still background (z 10) of colour `bg`, rows 3..6 a moving
    /// surface (z 1, 3 px half-spread) of colour `fg`, with row 2 (still) holding `fringe`
    /// of the surface.
    fn edge(
        fg: [f32; 3],
        bg: [f32; 3],
        fringe: f32,
        moving_z: f32,
    ) -> (ReconstructConfig, Vec<Texel2014>) {
        let (w, h) = (12usize, 6usize);
        let config = ReconstructConfig::new(w, h, &ReconstructParams::default(), 0.5, 0);
        let mix = |a: f32| [0, 1, 2].map(|c| a * fg[c] + (1.0 - a) * bg[c]);
        let texels = (0..w * h)
            .map(|i| match i / w {
                0 | 1 => texel(bg, 10.0, 0.0),
                2 => texel(mix(fringe), 10.0, 0.0),
                _ => texel(fg, moving_z, 3.0),
            })
            .collect();
        (config, texels)
    }

    #[test]
    fn a_still_pixel_s_fringe_is_its_coverage() {
        // Checked by hand: 0.3 of (0.9, 0.5, 0.1) over (0.1, 0.2, 0.6) projects back to 0.3.
        let (config, texels) = edge([0.9, 0.5, 0.1], [0.1, 0.2, 0.6], 0.3, 1.0);
        let m = mattes(&config, &texels, |_, _| true);
        let (alpha, moving, still) = surfaces(&texels, &m, 2 * 12 + 5);
        assert!(close(alpha, 0.3, 1e-5), "{alpha}");
        for (got, want) in moving.iter().zip([0.9, 0.5, 0.1, 1.0]) {
            assert!(close(*got, want, 1e-5), "{moving:?}");
        }
        for (got, want) in still.iter().zip([0.1, 0.2, 0.6, 1.0]) {
            assert!(close(*got, want, 1e-5), "{still:?}");
        }
        // Away from the edge, and on the moving side, the labels.
        assert_eq!(m[5][0], 0.0);
        assert_eq!(m[4 * 12 + 5][0], 1.0);
        // The moving pixel next to the fringe is pure in colour: fully covered.
        assert_eq!(m[3 * 12 + 5][0], 1.0);
    }

    #[test]
    fn a_still_pixel_is_at_most_half_covered_and_a_moving_one_at_least_half() {
        let (config, texels) = edge([0.9, 0.5, 0.1], [0.1, 0.2, 0.6], 0.8, 1.0);
        let m = mattes(&config, &texels, |_, _| true);
        assert_eq!(m[2 * 12 + 5][0], 0.5);
    }

    #[test]
    fn no_matte_where_the_moving_surface_is_behind_or_the_colour_is_unexplained() {
        // The moving surface behind the still one (z 20 against 10): labels.
        let (config, texels) = edge([0.9, 0.5, 0.1], [0.1, 0.2, 0.6], 0.3, 20.0);
        let m = mattes(&config, &texels, |_, _| true);
        assert_eq!(m[2 * 12 + 5][0], 0.0);
        // A fringe colour far off the line between the two (pure green): labels.
        let (config, mut texels) = edge([0.9, 0.5, 0.1], [0.1, 0.2, 0.6], 0.3, 1.0);
        texels[2 * 12 + 5][..3].copy_from_slice(&[0.0, 1.0, 0.0]);
        let m = mattes(&config, &texels, |_, _| true);
        assert_eq!(m[2 * 12 + 5][0], 0.0);
        let (_, moving, still) = surfaces(&texels, &m, 2 * 12 + 5);
        assert_eq!(moving, [0.0, 1.0, 0.0, 1.0]);
        assert_eq!(still, [0.0, 1.0, 0.0, 1.0]);
    }

    #[test]
    fn alpha_is_a_channel_of_the_fit_and_of_the_unmixing() {
        // A view layer: the surface (alpha 1) moves over empty space (colour and alpha 0), and
        // the still row 2 holds 0.3 of it, premultiplied: 0.3 × (colour, 1). Checked by hand:
        // the pixel is 0.3 of the way from nothing to the surface s in each of R, G, B and A,
        // so α is 0.3, its moving surface is s (alpha 1), and its still one is
        // 0.3·s + (0.3/0.7)·(0.3·s − s) = 0 in every channel, alpha included. A black surface
        // is told from nothing by its alpha alone.
        for fg in [[0.9, 0.5, 0.1], [0.0, 0.0, 0.0]] {
            let (config, mut texels) = edge(fg, [0.0; 3], 0.3, 1.0);
            for (i, t) in texels.iter_mut().enumerate() {
                t[3] = match i / 12 {
                    0 | 1 => 0.0,
                    2 => 0.3,
                    _ => 1.0,
                };
            }
            let m = mattes(&config, &texels, |_, _| true);
            let (alpha, moving, still) = surfaces(&texels, &m, 2 * 12 + 5);
            assert!(close(alpha, 0.3, 1e-5), "{fg:?}: {alpha}");
            let want_moving = [fg[0], fg[1], fg[2], 1.0];
            for (got, want) in moving.iter().zip(want_moving) {
                assert!(close(*got, want, 1e-5), "{fg:?}: {moving:?}");
            }
            for got in still {
                assert!(close(got, 0.0, 1e-5), "{fg:?}: {still:?}");
            }
        }
    }

    #[test]
    fn over_empty_space_a_pixel_s_alpha_is_its_coverage_whatever_its_label() {
        // A view layer's surface (alpha 1) moving over empty space (colour and alpha 0). Its
        // edge pixels' alpha is their coverage, rendered: a still pixel 0.8 covered (its
        // centre missed the surface's rim) is 0.8, not the label's 0.5, and unmixes to
        // nothing (0.8·s + 4·(0.8·s − s) = 0); a moving pixel 0.3 covered (a layer's pixel
        // given its surface's motion by the stack) is 0.3, and its moving surface is s
        // (0.3·s + (7/3)·0.3·s = s), both checked by hand.
        let fg = [0.9, 0.5, 0.1];
        let layer = |fringe: f32| {
            let (config, mut texels) = edge(fg, [0.0; 3], fringe, 1.0);
            for (i, t) in texels.iter_mut().enumerate() {
                t[3] = match i / 12 {
                    0 | 1 => 0.0,
                    2 => fringe,
                    _ => 1.0,
                };
            }
            (config, texels)
        };
        let surface = [fg[0], fg[1], fg[2], 1.0];
        let (config, texels) = layer(0.8);
        let m = mattes(&config, &texels, |_, _| true);
        let (alpha, moving, still) = surfaces(&texels, &m, 2 * 12 + 5);
        assert!(close(alpha, 0.8, 1e-5), "{alpha}");
        assert!(all_close(&moving, &surface, 1e-5).is_ok(), "{moving:?}");
        assert!(all_close(&still, &[0.0; 4], 1e-5).is_ok(), "{still:?}");
        let (config, mut texels) = layer(0.0);
        let i = 3 * 12 + 5;
        for ch in 0..4 {
            texels[i][ch] = 0.3 * surface[ch];
        }
        let m = mattes(&config, &texels, |_, _| true);
        let (alpha, moving, still) = surfaces(&texels, &m, i);
        assert!(close(alpha, 0.3, 1e-5), "{alpha}");
        assert!(all_close(&moving, &surface, 1e-5).is_ok(), "{moving:?}");
        assert!(all_close(&still, &[0.0; 4], 1e-5).is_ok(), "{still:?}");
        // The opposite case: alpha 0 that holds light (an additive glow beside the surface,
        // 0.2 in each of R, G, B) is not empty space, and the still pixel 0.8 of the way to
        // the surface is bounded by its label as in an opaque frame.
        let (config, mut texels) = layer(0.8);
        for t in texels.iter_mut().take(2 * 12) {
            t[..3].copy_from_slice(&[0.2; 3]);
        }
        for t in &mut texels[2 * 12..3 * 12] {
            for ch in 0..3 {
                t[ch] = 0.8 * surface[ch] + 0.2 * 0.2;
            }
        }
        let m = mattes(&config, &texels, |_, _| true);
        assert_eq!(m[2 * 12 + 5][0], 0.5);
    }

    /// A 70×52 frame of moving blobs (z 1) over a still background (z 10) with fringes and
    /// specks of one pixel, colours from a hash: silhouettes of every shape.
    fn blobs() -> (usize, usize, Vec<Texel2014>) {
        let (w, h) = (70usize, 52usize);
        let hash = |i: usize, k: usize| {
            let mut v = (i as u64 * 4 + k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
            v ^= v >> 29;
            (v.wrapping_mul(0xBF58_476D_1CE4_E5B9) >> 40) as f32 / (1u64 << 24) as f32
        };
        let texels = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                let blob = ((x - 20.0).hypot(y - 18.0) < 9.5)
                    || ((x - 50.0).abs() < 6.0 && y > 25.0)
                    || hash(i, 3) < 0.03;
                let rgb = [0, 1, 2].map(|k| hash(i, k));
                if blob {
                    texel(rgb, 1.0, 3.0)
                } else {
                    texel(rgb.map(|v| 0.2 + 0.1 * v), 10.0, 0.0)
                }
            })
            .collect();
        (w, h, texels)
    }

    #[test]
    fn the_mattes_do_not_depend_on_the_tiles_when_every_tile_is_read() {
        // Each tile (and each 32 px block of a larger one) is read through a window of its
        // own: a window too narrow for a candidate's 3×3, or a block cut wrong, shows at the
        // tiles' seams, which move with the tile size.
        let (w, h, texels) = blobs();
        let of = |tile: u32, fallback: Fallback| {
            let mut config = ReconstructConfig::new(w, h, &ReconstructParams::default(), 0.5, 0);
            config.tile = tile;
            let all = mattes(&config, &texels, |_, _| true);
            let found = pairs(&config, &texels, |_, _| true, |_| true, fallback);
            (all, found)
        };
        let (eight, found) = of(8, Fallback::Any);
        assert!(found.len() > 100, "{}", found.len());
        // The pairs are the mattes that have one, in index order.
        let paired: Vec<(usize, Matte)> = (0..w * h)
            .filter(|&i| !unpaired(&eight[i], i))
            .map(|i| (i, eight[i]))
            .collect();
        assert_eq!(found, paired);
        // The fringe's pairs skip, a row of bits at a time, the pixels with no pure still one
        // in their 5×5: those matte() turns down itself.
        let config = ReconstructConfig::new(w, h, &ReconstructParams::default(), 0.5, 0);
        let mut each = Vec::new();
        for r in 0..h.div_ceil(8) {
            silhouettes(
                &config,
                &|i| moves(&texels[i]),
                &|_, _| true,
                (r, false),
                |window, p| {
                    let found = matte(&config, &texels, window, p, Fallback::PureStill);
                    let i = p.1 * w + p.0;
                    each.extend(found.filter(|m| !unpaired(m, i)).map(|m| (i, m)));
                },
            );
        }
        each.sort_unstable_by_key(|&(i, _)| i);
        let skipping = pairs(&config, &texels, |_, _| true, |_| true, Fallback::PureStill);
        assert!(
            skipping.len() > 50 && skipping != found,
            "{}",
            skipping.len()
        );
        assert!(each == skipping);
        for tile in [1, 3, 5, 32, 45, 70] {
            let (all, pairs_any) = of(tile, Fallback::Any);
            assert!(all == eight, "tile {tile}");
            assert!(pairs_any == found, "tile {tile}");
            assert!(
                of(tile, Fallback::PureStill).1 == of(8, Fallback::PureStill).1,
                "{tile}"
            );
        }
    }

    #[test]
    fn a_tile_not_picked_is_not_read() {
        // Only the tiles of columns 0..16 picked: no pixel of the others is a matte's
        // candidate, and the mattes there are labels.
        let (w, h, texels) = blobs();
        let config = ReconstructConfig::new(w, h, &ReconstructParams::default(), 0.5, 0);
        assert_eq!(config.tile, 8);
        let m = mattes(&config, &texels, |c, _| c < 2);
        let mut paired = 0;
        for (i, matte) in m.iter().enumerate() {
            let x = i % w;
            if x >= 16 {
                assert_eq!(matte[0], moves(&texels[i]) as u32 as f32, "{i}");
                assert!(unpaired(matte, i), "{i}");
            } else if !unpaired(matte, i) {
                paired += 1;
                for partner in [matte[1], matte[2]] {
                    assert!((partner.to_bits() as usize % w) < 16, "{i}: {matte:?}");
                }
            }
        }
        assert!(paired > 20, "{paired}");
    }

    #[test]
    fn huge_colours_give_labels_not_nan() {
        let (config, texels) = edge([3e38, 0.5, 0.1], [-3e38, 0.2, 0.6], 0.3, 1.0);
        let m = mattes(&config, &texels, |_, _| true);
        for (i, matte) in m.iter().enumerate() {
            assert!(matte[0].is_finite(), "{i}: {matte:?}");
            let (alpha, moving, still) = surfaces(&texels, &m, i);
            assert!(alpha.is_finite());
            assert!(moving.iter().chain(&still).all(|v| !v.is_nan()), "{i}");
        }
    }
}
