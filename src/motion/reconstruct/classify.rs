//! Which form of the exposure gather each tile takes, found once a frame before the gather
//! (issue 35: "the classification is a stage of its own with a GPU twin"): the full gather,
//! its plain copy, the uniform tiles' box, or the hollow tiles' box at their bodies and the
//! full gather at the rest ([`TileKind`]). Every backend's gather reads the
//! kinds it is handed, and every colour carried through it is gathered on the same kinds.
//!
//! Twin: `classify_tiles` and `classify_kinds` in src/gpu/motion/classify.wgsl, run by
//! `crate::gpu::motion::classify`; their kinds equal these on every frame the parity test
//! (tests/gpu_reconstruct.rs) runs. Both read each tile's pixels once ([`Summary`]: whether a
//! pixel fails, its longest |V|, its steepest step of V), then each tile's reach over the
//! summaries. The CPU counts the failing tiles of a plain tile's reach on a summed-area table
//! and the GPU, one invocation a tile, loops over them; the answers are the same counts.
//!
//! Only ours (the exposure variant, at any shutter offset) has the faster copies; Blender's
//! form (the 2014 filter) is run as Blender runs it, every tile [`TileKind::Full`].

use rayon::prelude::*;

use super::config::{reach_factor, Form, ReconstructConfig, Texel2014, HALF_PIXEL, LENGTH, VX, VY};
use super::matte::{self, Matte};
use super::tiles::near_blur;
use super::unmix::transparent;
use crate::motion::tile_max::TileGrid;

/// How much (px) a uniform tile lets the motion change across a reach: the largest change of
/// either component of V from a pixel to its right or lower neighbour, times the reach (the
/// longest streak that can arrive plus two pixels), at most this. A smooth flow passes (a
/// pan's perspective, a zoom); an edge between two motions (a jump of a pixel or more) does
/// not. Measured on the truth scenes and the two real renders (BENCHMARKS.md, "Uniform
/// tiles"), every value from 1/16 to 1 px errs the same to the fourth digit but `zoom` at
/// 640×360 (1/16: 0.01379, the rest 0.01370); an eighth of a pixel keeps the margin.
pub const UNIFORM_SPREAD: f32 = 0.125;

/// The gather a tile's pixels take. Uniform tiles are plain too; the numbers are the GPU
/// twin's words (`FULL`, `PLAIN`, `UNIFORM` in classify.wgsl).
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TileKind {
    /// The full gather: per-tap depth weights, each tap split by surface, the matte.
    Full = 0,
    /// Plain: every texel a tap of any of its pixels can read moves and has no matte pair,
    /// so [`split_by_cover`](super::taps::split_by_cover) finds no matte there and
    /// [`split`](super::taps::split) puts all four of a tap's pixels in one part, the
    /// nearest's (part B empty): the gather then reads each tap as that part alone, without
    /// the tests, and weighs no second part, with the same bits (most of a camera pan: the
    /// 1080p `pan`'s whole process 1.21–1.23 → 0.94–0.96 s).
    Plain = 1,
    /// Plain, and the motion within reach of its pixels one smooth flow: the box shutter's
    /// line integral ([`super::uniform::box_pixel`]).
    Uniform = 2,
    /// A view layer's smooth flow over empty space (issue 33): within its streaks' reach
    /// nothing but empty pixels (still, colour and alpha 0: what a layer does not cover) and
    /// one smooth flow, which may be failing pixels' (a rim's, paired by the matte) or lie
    /// beyond a plain tile's longer reach. Its moving pixels without a pair take the box
    /// (over a layer's empty space the box is still the exposure's integral: the empty
    /// pixels it reads hold nothing); its still pixels and its rim the full gather, which
    /// brings the surface's streak over empty space. Before, a layer's whole surface took the
    /// full gather within reach of its edge, and lost to the one-layer frame on `zoom`
    /// (BENCHMARKS.md, "Hollow tiles").
    Hollow = 3,
}

/// What a tile's own pixels tell its classification (each tile read once, up to its first
/// failing pixel): `own`, its longest |V|, or `None` when a pixel fails (is still, or has a
/// matte pair: a plain tile's taps must read neither; a tile the pack left out fails at its
/// first pixel, its texels zero); `step`, the largest change of V (either component) from any
/// of its pixels to the pixel right of it or below it, or `None` when no tile within one of
/// it blurs (the gather does not run there, so nothing within a uniform tile's reach may be
/// such a tile). A failing tile's step is not read: any tile within a uniform tile's reach is
/// within its plain reach, which holds no failing tile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Summary {
    pub own: Option<f32>,
    pub step: Option<f32>,
    pub hollow: Option<Hollow>,
}

/// What a tile's pixels tell a [`TileKind::Hollow`] classification, read over its body (its
/// moving pixels without a matte pair): the longest |V|, the largest change of V (either
/// component) to a body pixel right of it or below it, and the least and greatest V (x, y).
/// `None` where a pixel is still and not [`empty`]: a surface that does not move. (A tile
/// none of whose pixels fails is all body.)
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hollow {
    pub own: f32,
    pub step: f32,
    pub low: [f32; 2],
    pub high: [f32; 2],
}

/// The GPU twin's words a tile's [`Summary`]: `own` and `step` (-1 for `None`), then the
/// [`Hollow`]'s six (its `own` -1 for `None`).
pub const SUMMARY_WORDS: usize = 8;

/// Whether a texel is empty space: still, and its colour and alpha 0 (what a view layer
/// does not cover).
#[inline]
pub fn empty(texel: &Texel2014) -> bool {
    texel[LENGTH] < HALF_PIXEL && transparent(texel)
}

/// Whether pixel `j` fails a plain tile: still, or paired by its matte (the taps a plain tile
/// reads must meet neither). In a [`TileKind::Hollow`] tile such a pixel (empty, or a rim)
/// takes the full gather, the rest the box. (`fails` in classify.wgsl.)
#[inline]
pub fn fails(texels: &[Texel2014], mattes: &[Matte], j: usize) -> bool {
    texels[j][LENGTH] < HALF_PIXEL || (!mattes.is_empty() && !matte::unpaired(&mattes[j], j))
}

/// The kind of every tile of `tiles` (the dilated grid the gather reads), row by row:
/// [`TileKind::Full`] everywhere but under ours ([`Form::OURS`]); there, plain where no tile
/// within the tile's tap reach holds a failing pixel ([`Summary`]), uniform where it is plain
/// and the steps within its streaks' reach times that reach are at most
/// [`UNIFORM_SPREAD`]; where it is not plain, hollow where no tile within its streaks' reach
/// holds a still surface and its bodies there are one smooth flow ([`Hollow`]: the steps as
/// a uniform tile's, and the range of their motions at most UNIFORM_SPREAD per reach of the
/// tiles' span, which a linear flow that passes the steps passes and two bodies moving apart
/// across empty space, whose steps see no jump, do not).
///
/// The reaches. A tap of a pixel of tile (c, r) reads within `reach_factor · |M|` of the
/// pixel along the vector it looks up (|M| at most the largest of the 3×3 dilated tiles
/// around, which the jittered lookup reaches, or the pixel's own |V|, at most its tile's
/// longest), a slid tap `2·|V|` further, and a bilinear read one pixel more: a plain tile's
/// reach is `m·reach_factor + 2m + 2` px, m the longer of the two. A uniform tile's pixels
/// integrate along their own motion and read bilinearly within `m·reach_factor + 2` px: the
/// flow must be smooth that far. Each reach is counted in whole tiles ([`tiles_across`]).
pub fn classify(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    mattes: &[Matte],
    tiles: &TileGrid,
) -> Vec<TileKind> {
    let (columns, rows) = (tiles.columns, tiles.rows);
    if config.form() != Form::OURS || texels.is_empty() {
        return vec![TileKind::Full; columns * rows];
    }
    let summaries: Vec<Summary> = (0..columns * rows)
        .into_par_iter()
        .map(|t| summary(config, texels, mattes, tiles, t % columns, t / columns))
        .collect();
    // table[r·(columns + 1) + c]: the failing tiles above and left of tile (c, r). (A table
    // of pixels, made on one thread, had cost the 1080p `sparse` 5 to 20 ms of 45.)
    let stride = columns + 1;
    let mut table = vec![0u32; stride * (rows + 1)];
    for r in 0..rows {
        let mut row = 0u32;
        for c in 0..columns {
            row += summaries[r * columns + c].own.is_none() as u32;
            table[(r + 1) * stride + c + 1] = table[r * stride + c + 1] + row;
        }
    }
    let failing = |(c0, r0): (usize, usize), (c1, r1): (usize, usize)| {
        table[r1 * stride + c1] + table[r0 * stride + c0]
            - table[r0 * stride + c1]
            - table[r1 * stride + c0]
    };
    let (width, height) = (config.width as usize, config.height as usize);
    let size = config.tile as usize;
    let within = |(c, r): (usize, usize), across: usize| {
        (
            (c.saturating_sub(across), r.saturating_sub(across)),
            ((c + across + 1).min(columns), (r + across + 1).min(rows)),
        )
    };
    // The longest |M| a tap of tile (c, r) can be taken along: its pixels' longest, `own`,
    // or a dilated tile's within one (the jittered lookup's).
    let longest = |(c, r): (usize, usize), own: f32| {
        let mut m = own;
        for rr in r.saturating_sub(1)..(r + 2).min(rows) {
            for cc in c.saturating_sub(1)..(c + 2).min(columns) {
                m = m.max(tiles.length(cc, rr));
            }
        }
        m
    };
    // A tile with a failing tile in its plain reach: hollow where every tile within its
    // uniform reach is (no still surface), the steps between its bodies' pixels within that
    // reach times the reach are at most UNIFORM_SPREAD, and their motions' range at most
    // UNIFORM_SPREAD per reach of the tiles' span (a linear flow that passes the steps passes
    // it; two bodies moving apart across empty space do not).
    let hollow_kind = |t: usize| {
        let (c, r) = (t % columns, t / columns);
        let Some(own) = summaries[t].hollow else {
            return TileKind::Full;
        };
        let m = longest((c, r), own.own);
        let reach = m * reach_factor(config) + 2.0;
        if !reach.is_finite() || reach > (width + height) as f32 {
            return TileKind::Full;
        }
        let across = tiles_across(reach, size);
        let ((c0, r0), (c1, r1)) = within((c, r), across);
        let (mut step, mut low, mut high) = (0.0f32, [f32::MAX; 2], [f32::MIN; 2]);
        for rr in r0..r1 {
            for cc in c0..c1 {
                let Some(h) = summaries[rr * columns + cc].hollow else {
                    return TileKind::Full;
                };
                step = step.max(h.step);
                for k in 0..2 {
                    low[k] = low[k].min(h.low[k]);
                    high[k] = high[k].max(h.high[k]);
                }
            }
        }
        let span = ((2 * across + 1) * size) as f32;
        // (No body within reach: no range, and no sentinels subtracted.)
        let range = if high[0] >= low[0] {
            (high[0] - low[0]).max(high[1] - low[1])
        } else {
            0.0
        };
        if step * reach <= UNIFORM_SPREAD && range * reach <= UNIFORM_SPREAD * span {
            TileKind::Hollow
        } else {
            TileKind::Full
        }
    };
    (0..columns * rows)
        .into_par_iter()
        .map(|t| {
            let (c, r) = (t % columns, t / columns);
            let Some(own) = summaries[t].own else {
                return hollow_kind(t);
            };
            let m = longest((c, r), own);
            let streak = m * reach_factor(config);
            let reach = streak + 2.0 * m + 2.0;
            if !reach.is_finite() || reach > (width + height) as f32 {
                return TileKind::Full;
            }
            let (start, end) = within((c, r), tiles_across(reach, size));
            if failing(start, end) != 0 {
                return hollow_kind(t);
            }
            let reach = streak + 2.0;
            let ((c0, r0), (c1, r1)) = within((c, r), tiles_across(reach, size));
            let mut step = 0.0f32;
            for rr in r0..r1 {
                for cc in c0..c1 {
                    let Some(s) = summaries[rr * columns + cc].step else {
                        return TileKind::Plain;
                    };
                    step = step.max(s);
                }
            }
            if step * reach <= UNIFORM_SPREAD {
                TileKind::Uniform
            } else {
                TileKind::Plain
            }
        })
        .collect()
}

/// Tile (c, r)'s [`Summary`].
pub fn summary(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    mattes: &[Matte],
    tiles: &TileGrid,
    c: usize,
    r: usize,
) -> Summary {
    let steep = !near_blur(tiles, c, r, 1);
    match scan(config, texels, mattes, (c, r), Scan::Plain { steep }) {
        Some(all) => {
            let step = (!steep).then_some(all.step);
            Summary {
                own: Some(all.own),
                step,
                hollow: step.map(|_| all),
            }
        }
        None => Summary {
            own: None,
            step: None,
            hollow: scan(config, texels, mattes, (c, r), Scan::Bodies),
        },
    }
}

/// What [`scan`] reads of a tile: every pixel, none failing (`None` at the first that fails;
/// no steps where the tile is `steep`: no tile within one of it blurs), or its bodies alone
/// (`None` at the first still pixel that is not empty; steps between bodies only).
#[derive(Clone, Copy)]
enum Scan {
    Plain { steep: bool },
    Bodies,
}

/// Tile (c, r)'s pixels read once, as `how` says: the longest |V|, the largest step of V
/// to the pixel right or below, and the least and greatest V.
fn scan(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    mattes: &[Matte],
    (c, r): (usize, usize),
    how: Scan,
) -> Option<Hollow> {
    let (width, height) = (config.width as usize, config.height as usize);
    let size = config.tile as usize;
    let (bodies, steep) = match how {
        Scan::Plain { steep } => (false, steep),
        Scan::Bodies => (true, false),
    };
    let mut h = Hollow {
        own: 0.0,
        step: 0.0,
        low: [f32::MAX; 2],
        high: [f32::MIN; 2],
    };
    for y in r * size..((r + 1) * size).min(height) {
        for x in c * size..((c + 1) * size).min(width) {
            let j = y * width + x;
            let texel = &texels[j];
            if bodies && texel[LENGTH] < HALF_PIXEL && !empty(texel) {
                return None;
            }
            if fails(texels, mattes, j) {
                if bodies {
                    continue;
                }
                return None;
            }
            h.own = h.own.max(texel[LENGTH]);
            for (k, v) in [texel[VX], texel[VY]].into_iter().enumerate() {
                h.low[k] = h.low[k].min(v);
                h.high[k] = h.high[k].max(v);
            }
            if steep {
                continue;
            }
            for k in [
                (x + 1 < width).then_some(j + 1),
                (y + 1 < height).then_some(j + width),
            ]
            .into_iter()
            .flatten()
            .filter(|&k| !(bodies && fails(texels, mattes, k)))
            {
                let other = &texels[k];
                h.step = h
                    .step
                    .max((other[VX] - texel[VX]).abs())
                    .max((other[VY] - texel[VY]).abs());
            }
        }
    }
    Some(h)
}

/// The whole tiles of `size` px a reach of `reach` px spans beyond the tile's own: ⌈reach /
/// size⌉, found exactly (the quotient's rounding corrected by products, which are exact), so
/// the GPU twin, whose division may be a few ulp off, counts the same.
pub fn tiles_across(reach: f32, size: usize) -> usize {
    ceiling_of(reach / size as f32, reach, size)
}

/// ⌈reach / size⌉ from `quotient`, an estimate of reach / size within an ulp or two of it
/// (the GPU's division is allowed 2.5 ulp).
fn ceiling_of(quotient: f32, reach: f32, size: usize) -> usize {
    let size = size as f32;
    let mut across = quotient.ceil().max(0.0);
    if across > 0.0 && (across - 1.0) * size >= reach {
        across -= 1.0;
    }
    if across * size < reach {
        across += 1.0;
    }
    across as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reach_in_tiles_is_the_exact_ceiling_from_an_inexact_quotient() {
        // Whole multiples stay, anything above takes one more tile, for sizes whose
        // reciprocal is inexact as well as powers of two, from the quotient as computed and
        // from quotients two ulp off either way (a GPU's division).
        let ulps = |q: f32, d: i32| f32::from_bits((q.to_bits() as i32 + d).max(0) as u32);
        for size in [1usize, 3, 7, 8, 13, 32] {
            for n in 0..40usize {
                let whole = (n * size) as f32;
                let above = f32::from_bits(whole.to_bits() + 1).max(f32::MIN_POSITIVE);
                assert_eq!(tiles_across(whole, size), n, "{n} × {size}");
                assert_eq!(tiles_across(above, size), n + 1, "just above {n} × {size}");
                for d in [-2, -1, 1, 2] {
                    let q = ulps(whole / size as f32, d);
                    assert_eq!(ceiling_of(q, whole, size), n, "{n} × {size}, {d} ulp");
                    let q = ulps(above / size as f32, d);
                    assert_eq!(ceiling_of(q, above, size), n + 1, "above, {d} ulp");
                }
            }
        }
    }
}
