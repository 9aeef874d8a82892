//! The bokeh gather's inner loops ([`super`]): one tile row of up to [`TILE`] pixels over a
//! tile's taps, for the beauty ([`gather_run`], which also keeps each tap's weights and the
//! composite's scales when planes are carried beside it, for [`super::carry`]); the far field
//! of small bokehs over the dense grid ([`dense_far`]); and the padded planes they read
//! ([`Padded`]: what counts outside the frame).

use rayon::prelude::*;

use crate::dof::tiles::{LAYER, TILE};
use crate::frame::Color;

/// Smallest bokeh radius a weight divides by (px): a pixel's own footprint.
pub(super) const SMALLEST_RADIUS: f32 = 0.5;

/// 1 / bokeh area (px⁻²) of a pixel of signed CoC `coc` (diameter, px): the weight of its
/// light per pixel it covers.
#[inline(always)]
pub fn inverse_area(coc: f32, unit_area: f32) -> f32 {
    let r = (0.5 * coc).abs().max(SMALLEST_RADIUS);
    1.0 / (unit_area * r * r)
}

/// One tap of a tile's pattern: a whole-pixel offset (as an index step in the padded
/// planes), the aperture norms of the offset, and the area it stands for (px²).
#[derive(Clone, Copy, Debug)]
pub(super) struct PixelTap {
    pub(super) step: isize,
    /// The offset itself (dx, dy), for the carried planes ([`super::carry`]), which read
    /// planes of other row lengths.
    pub(super) offset: (i32, i32),
    pub(super) norm_far: f32,
    pub(super) norm_near: f32,
    pub(super) area: f32,
}

/// Which fields a tile row gathers, and over which taps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Fields {
    /// No near field: the far field over the far taps.
    Far,
    /// Both fields in one loop over the same taps (the tile's own radius sets its reach).
    Both,
    /// The far field over its own (denser) taps, then the near field over the reach's.
    Apart,
}

/// The planes the gather reads, padded by `pad` pixels on every side (and a tile more on the
/// right), so taps never need bounds checks: colour and CoC mirrored about the frame's
/// edges, 1 / bokeh area 0 outside it, so a tap there weighs nothing. The far field is then
/// the renormalised average of the taps inside the frame, and the near field's opacity
/// counts the near pixels the frame holds.
///
/// Beyond the frame the world goes on and a post-process cannot see it; the estimate must
/// not invent structure. Measured (issue 34, BENCHMARKS.md "Frame borders"), by the worst
/// case: mirroring (today's before) doubles the edge cell of a fine texture, so within a
/// CoC radius of the border the pattern no longer averages out (a 4 px checker under a 9 px
/// CoC: 0.30 off its mean at the corners; first 12 px against the texture continued,
/// RMSE 0.0278 where this errs 0.0115, worst case over the fine and coarse frames 0.0412
/// against 0.0358); clamping smears the border row (worst 0.0516); reflecting about the
/// edge pixel itself breaks the texture's period too (worst 0.0480). Mirroring the near
/// field while renormalising the far one changed 271 pixels of `border-coarse` (its disc cut
/// by the corner) at 640×360 by an RMSE of 4e-5 there, and scaling the near field's opacity
/// by the share of its taps inside raised their error by a quarter: neither is kept. What
/// this costs: on the coarse truth scenes a few percent of region RMSE (`border-coarse`
/// 0.0108 → 0.0116, `layers` 0.0218 → 0.0222 at 320×180), within the references' noise.
pub(super) struct Padded {
    pub(super) stride: usize,
    pub(super) pad: usize,
    /// r, g, b, a (zero without alpha), signed bokeh radius, 1 / bokeh area.
    pub(super) planes: [Vec<f32>; 6],
}

/// Index `i` of a row or column of `n` pixels reflected into it about its edges (the edge
/// pixel repeated: …, 1, 0 | 0, 1, …, n − 1 | n − 1, n − 2, …), for any i: where the padding
/// takes its colour and CoC from. Outside the frame those only fill the planes (every
/// weight there is 0); the bits of the padding are then the same whatever the reflection.
pub(super) fn mirror(i: isize, n: usize) -> usize {
    let period = 2 * n as isize;
    let m = i.rem_euclid(period);
    (if m >= n as isize { period - 1 - m } else { m }) as usize
}

/// How the padded planes are made: colour and CoC [`mirror`]ed, 1 / bokeh area 0 outside the
/// frame (a tap there weighs nothing in either field).
impl Padded {
    pub(super) fn new(
        color: &Color,
        coc: &[f32],
        (width, height): (usize, usize),
        pad: usize,
        unit_area: f32,
    ) -> Self {
        // A tile's last run reads a whole TILE of lanes: room for that on the right.
        let stride = width + 2 * pad + TILE;
        let rows = height + 2 * pad;
        // Each padded column's source column, found once for every row and plane.
        let columns: Vec<usize> = (0..stride)
            .map(|px| mirror(px as isize - pad as isize, width))
            .collect();
        // `inside`: whether the plane is 0 outside the frame rather than mirrored.
        let padded = |value: &(dyn Fn(usize) -> f32 + Sync), inside: bool| {
            let mut out = vec![0.0f32; stride * rows];
            out.par_chunks_mut(stride)
                .enumerate()
                .for_each(|(py, row)| {
                    let y = mirror(py as isize - pad as isize, height);
                    for (v, &x) in row.iter_mut().zip(&columns) {
                        *v = value(y * width + x);
                    }
                    if inside {
                        if py < pad || py >= pad + height {
                            row.fill(0.0);
                        } else {
                            row[..pad].fill(0.0);
                            row[pad + width..].fill(0.0);
                        }
                    }
                });
            out
        };
        // A plane mirrored as it is: each row's inside copied whole, only its borders
        // through `columns` (the same values as `padded`, without a call a value: with
        // six light layers, eighteen such planes).
        let mirrored = |plane: &[f32]| {
            let mut out = vec![0.0f32; stride * rows];
            out.par_chunks_mut(stride)
                .enumerate()
                .for_each(|(py, row)| {
                    let y = mirror(py as isize - pad as isize, height);
                    let source = &plane[y * width..(y + 1) * width];
                    row[pad..pad + width].copy_from_slice(source);
                    for px in (0..pad).chain(pad + width..stride) {
                        row[px] = source[columns[px]];
                    }
                });
            out
        };
        let planes = [
            mirrored(&color.r),
            mirrored(&color.g),
            mirrored(&color.b),
            match &color.a {
                Some(a) => mirrored(a),
                None => vec![0.0f32; stride * rows],
            },
            padded(&|i| 0.5 * coc[i], false),
            padded(&|i| inverse_area(coc[i], unit_area), true),
        ];
        Padded {
            stride,
            pad,
            planes,
        }
    }

    pub(super) fn index(&self, x: usize, y: usize) -> usize {
        (y + self.pad) * self.stride + x + self.pad
    }
}

/// One tile row's run: `span` (≤ [`TILE`]) consecutive pixels from padded index `start`, the
/// far field's taps and the tile's taps, and which fields it gathers over them.
#[derive(Clone, Copy)]
pub(super) struct Row<'a> {
    pub(super) start: usize,
    pub(super) span: usize,
    pub(super) far_taps: &'a [PixelTap],
    pub(super) taps: &'a [PixelTap],
    pub(super) fields: Fields,
    /// Where the tile's far taps are rings: the whole-pixel grids by radius (0 ..= `rings`),
    /// over which the lanes whose own bokeh radius is at most `small` gather their far field
    /// instead (the rings of a larger radius are too sparse for a small bokeh); empty
    /// elsewhere.
    pub(super) grids: &'a [Vec<PixelTap>],
    pub(super) small: f32,
    /// The planes `far_taps` read and those `taps` read ([`Padded::planes`]' order): the
    /// padded planes themselves, or a prefilter level of them (`super::levels::Level`) where
    /// the taps are rings sparser than a pixel.
    pub(super) far_planes: [&'a [f32]; 6],
    pub(super) planes: [&'a [f32]; 6],
    /// Whether the far taps read a level: then a lane that gathers them (its bokeh beyond
    /// `small`) takes its own sample from the level too (the centre tap's box).
    pub(super) far_level: bool,
    /// Whether `taps` read a level.
    pub(super) level: bool,
}

/// One tile row's weights as [`gather_run`] computed them, for [`super::carry::fold`]: each
/// far tap's
/// far weights and each near tap's near weights (lane by lane, in tap order, each with its
/// tap's step), and the composite's scales of the near and the far sums. A tap whose weights
/// are 0 in every lane is not kept ([`counts`]).
#[derive(Default)]
pub(super) struct RowWeights {
    /// Whether [`gather_run`] keeps them (only when planes are carried).
    pub(super) keep: bool,
    pub(super) far: Vec<Kept>,
    pub(super) near: Vec<Kept>,
    pub(super) near_scale: [f32; TILE],
    pub(super) far_scale: [f32; TILE],
    /// The dense grid's far weights (lane by lane, in tap order) and the lanes whose far
    /// field it gave.
    pub(super) dense: Vec<Kept>,
    pub(super) dense_lanes: [bool; TILE],
}

/// A kept tap: its offset (dx, dy) and its weights, lane by lane.
pub(super) type Kept = ((i32, i32), [f32; TILE]);

/// Whether a tap's weights `w` count for the carried planes: a tap whose weight is 0 in every
/// lane adds w × s = ±0 to each carried sum, which leaves it as it was (a sum starts at the
/// centre's share, and the samples are finite, by the numeric policy), so the carried loops
/// skip it. On the `dof` bench frame out of focus 43 % of the kept taps were such (26.96 M of
/// them, 11.51 M all 0).
pub(super) fn counts(w: &[f32; TILE]) -> bool {
    w.iter().any(|&v| v != 0.0)
}

/// Gathers one tile row ([`Row`]) over its tile's taps: taps outside, pixels inside, so the
/// inner loop runs along memory; keeps the weights in `weights` when it is asked to.
///
/// Compiled twice, chosen at run time by `multiversion`: with AVX-512 a tile row of 16 pixels
/// is one vector (2.6× faster at 1080p on the dev machine; AVX2 alone gave nothing). Only
/// lanes change, never the order of operations, and nothing is fused, so both versions give
/// the same bits.
#[multiversion::multiversion(targets("x86_64+avx512f+avx512vl"))]
pub(super) fn gather_run(
    padded: &Padded,
    row: &Row,
    out: &mut [[f32; TILE]; 4],
    weights: &mut RowWeights,
) {
    let Row {
        start,
        span,
        far_taps,
        taps,
        fields,
        grids,
        small,
        far_planes,
        planes,
        far_level,
        ..
    } = *row;
    let keep = weights.keep;
    weights.far.clear();
    weights.near.clear();
    weights.dense.clear();
    let [pr, pg, pb, pa, pc, pia] = &padded.planes;
    let centre = |plane: &[f32]| -> [f32; TILE] {
        let mut v = [0.0f32; TILE];
        v[..span].copy_from_slice(&plane[start..start + span]);
        v
    };
    let (cr, cg, cb, ca, cc, cia) = (
        centre(pr),
        centre(pg),
        centre(pb),
        centre(pa),
        centre(pc),
        centre(pia),
    );
    let mut rp = [0.0f32; TILE];
    let mut split = [0.0f32; TILE];
    for x in 0..TILE {
        rp[x] = cc[x].abs();
        split[x] = cc[x] - 0.5 * LAYER;
    }
    // Sums of weight × (sample − centre), so a uniform frame stays exact. p's own weight
    // starts the far sum.
    let mut far = [[0.0f32; TILE]; 4];
    let mut far_weight = cia;
    if far_level {
        // The centre tap stands for the same area as every ring tap: it reads its box.
        for x in 0..span {
            if rp[x] > small {
                let i = start + x;
                let w = far_planes[5][i];
                let s = [
                    far_planes[0][i],
                    far_planes[1][i],
                    far_planes[2][i],
                    far_planes[3][i],
                ];
                let c = [cr[x], cg[x], cb[x], ca[x]];
                for k in 0..4 {
                    far[k][x] = w * (s[k] - c[k]);
                }
                far_weight[x] = w;
            }
        }
    }
    let mut near = [[0.0f32; TILE]; 4];
    let mut opacity = [0.0f32; TILE];
    // Each tap's weights, lane by lane, kept for the carried planes.
    let mut kept_far = [0.0f32; TILE];
    let mut kept_near = [0.0f32; TILE];
    if fields == Fields::Far || fields == Fields::Apart {
        // The far half of the loop below, alone (with no near field, the same bits: there
        // every near weight would be 0). The six lane slices are spelt out in each loop:
        // taking them through one helper (an array `map`) lost the vectorisation (699 ms
        // against ~250 at 1080p).
        let [pr, pg, pb, pa, pc, pia] = far_planes;
        for tap in far_taps {
            let base = (start as isize + tap.step) as usize;
            let sr = &pr[base..base + TILE];
            let sg = &pg[base..base + TILE];
            let sb = &pb[base..base + TILE];
            let sa = &pa[base..base + TILE];
            let sc = &pc[base..base + TILE];
            let sia = &pia[base..base + TILE];
            for x in 0..TILE {
                let rs = sc[x].abs();
                // In `Apart`, a nearer sample is the near field's, counted below.
                let is_far = fields == Fields::Far || sc[x] > split[x];
                let cover_far = (rs.min(rp[x]) - tap.norm_far + 0.5).clamp(0.0, 1.0);
                let wf = if is_far { cover_far * sia[x] } else { 0.0 };
                let d = [sr[x] - cr[x], sg[x] - cg[x], sb[x] - cb[x], sa[x] - ca[x]];
                for k in 0..4 {
                    far[k][x] += wf * d[k];
                }
                far_weight[x] += wf;
                kept_far[x] = wf;
            }
            if keep && counts(&kept_far) {
                weights.far.push((tap.offset, kept_far));
            }
        }
    }
    if fields == Fields::Apart {
        // The near half of the loop below, alone.
        let [pr, pg, pb, pa, pc, pia] = planes;
        for tap in taps {
            let base = (start as isize + tap.step) as usize;
            let sr = &pr[base..base + TILE];
            let sg = &pg[base..base + TILE];
            let sb = &pb[base..base + TILE];
            let sa = &pa[base..base + TILE];
            let sc = &pc[base..base + TILE];
            let sia = &pia[base..base + TILE];
            for x in 0..TILE {
                let rs = sc[x].abs();
                let cover_near = (rs - tap.norm_near + 0.5).clamp(0.0, 1.0);
                let wn = if sc[x] > split[x] {
                    0.0
                } else {
                    cover_near * tap.area * sia[x]
                };
                let d = [sr[x] - cr[x], sg[x] - cg[x], sb[x] - cb[x], sa[x] - ca[x]];
                for k in 0..4 {
                    near[k][x] += wn * d[k];
                }
                opacity[x] += wn;
                kept_near[x] = wn;
            }
            if keep && counts(&kept_near) {
                weights.near.push((tap.offset, kept_near));
            }
        }
    }
    if fields == Fields::Both {
        let [pr, pg, pb, pa, pc, pia] = planes;
        for tap in taps {
            let base = (start as isize + tap.step) as usize;
            let sr = &pr[base..base + TILE];
            let sg = &pg[base..base + TILE];
            let sb = &pb[base..base + TILE];
            let sa = &pa[base..base + TILE];
            let sc = &pc[base..base + TILE];
            let sia = &pia[base..base + TILE];
            for x in 0..TILE {
                let rs = sc[x].abs();
                let is_far = sc[x] > split[x];
                let cover_far = (rs.min(rp[x]) - tap.norm_far + 0.5).clamp(0.0, 1.0);
                let cover_near = (rs - tap.norm_near + 0.5).clamp(0.0, 1.0);
                let wf = if is_far { cover_far * sia[x] } else { 0.0 };
                let wn = if is_far {
                    0.0
                } else {
                    cover_near * tap.area * sia[x]
                };
                let d = [sr[x] - cr[x], sg[x] - cg[x], sb[x] - cb[x], sa[x] - ca[x]];
                for k in 0..4 {
                    far[k][x] += wf * d[k];
                    near[k][x] += wn * d[k];
                }
                far_weight[x] += wf;
                opacity[x] += wn;
                kept_far[x] = wf;
                kept_near[x] = wn;
            }
            // Both fields' sums run over one list of taps: kept where either counts.
            if keep && (counts(&kept_far) || counts(&kept_near)) {
                weights.far.push((tap.offset, kept_far));
                weights.near.push((tap.offset, kept_near));
            }
        }
    }
    // Lanes whose own bokeh fits the grids, in a tile whose far taps are rings: their far
    // field over every pixel of their bokeh instead ([`dense_far`]). A lane whose radius is
    // half a pixel or less takes no tap whichever the taps (its sums stay 0).
    let mut lanes = [false; TILE];
    let mut need = 0.0f32;
    if !grids.is_empty() {
        for x in 0..span {
            if rp[x] > 0.5 && rp[x] <= small {
                lanes[x] = true;
                need = need.max(rp[x]);
            }
        }
    }
    weights.dense_lanes = lanes;
    if need > 0.0 {
        let radius = (need.ceil() as usize).min(grids.len() - 1);
        let centre = [cr, cg, cb, ca, cc, cia];
        dense_far(
            padded,
            row,
            &grids[radius],
            &centre,
            &lanes,
            &mut far,
            &mut far_weight,
            weights,
        );
    }
    let base = [cr, cg, cb, ca];
    for x in 0..span {
        let (near_scale, rest) = if opacity[x] > 1.0 {
            (1.0 / opacity[x], 0.0)
        } else {
            (1.0, 1.0 - opacity[x])
        };
        let far_scale = rest / far_weight[x];
        for k in 0..4 {
            out[k][x] = base[k][x] + near[k][x] * near_scale + far[k][x] * far_scale;
        }
        weights.near_scale[x] = near_scale;
        weights.far_scale[x] = far_scale;
    }
}

/// The far field of the lanes in `lanes` over the whole-pixel grid `grid` (the far half of
/// [`gather_run`]'s loops), written over their sums in `far` and `far_weight`; the weights
/// kept when they are asked for. Apart from the main loops, which it would otherwise slow
/// down where it does not run (the 1080p bench: +25 % with it inline).
#[allow(clippy::too_many_arguments)]
#[inline(never)]
fn dense_far(
    padded: &Padded,
    row: &Row,
    grid: &[PixelTap],
    centre: &[[f32; TILE]; 6],
    lanes: &[bool; TILE],
    far: &mut [[f32; TILE]; 4],
    far_weight: &mut [f32; TILE],
    weights: &mut RowWeights,
) {
    let [pr, pg, pb, pa, pc, pia] = &padded.planes;
    let [cr, cg, cb, ca, cc, cia] = centre;
    let start = row.start;
    let mut rp = [0.0f32; TILE];
    let mut split = [0.0f32; TILE];
    for x in 0..TILE {
        rp[x] = cc[x].abs();
        split[x] = cc[x] - 0.5 * LAYER;
    }
    let mut dense_far = [[0.0f32; TILE]; 4];
    let mut dense_weight = *cia;
    let mut kept_far = [0.0f32; TILE];
    for tap in grid {
        let base = (start as isize + tap.step) as usize;
        let sr = &pr[base..base + TILE];
        let sg = &pg[base..base + TILE];
        let sb = &pb[base..base + TILE];
        let sa = &pa[base..base + TILE];
        let sc = &pc[base..base + TILE];
        let sia = &pia[base..base + TILE];
        for x in 0..TILE {
            let rs = sc[x].abs();
            let is_far = row.fields == Fields::Far || sc[x] > split[x];
            let cover_far = (rs.min(rp[x]) - tap.norm_far + 0.5).clamp(0.0, 1.0);
            let wf = if is_far { cover_far * sia[x] } else { 0.0 };
            let d = [sr[x] - cr[x], sg[x] - cg[x], sb[x] - cb[x], sa[x] - ca[x]];
            for k in 0..4 {
                dense_far[k][x] += wf * d[k];
            }
            dense_weight[x] += wf;
            kept_far[x] = wf;
        }
        if weights.keep && counts(&kept_far) {
            weights.dense.push((tap.offset, kept_far));
        }
    }
    for x in 0..TILE {
        if lanes[x] {
            for k in 0..4 {
                far[k][x] = dense_far[k][x];
            }
            far_weight[x] = dense_weight[x];
        }
    }
}
