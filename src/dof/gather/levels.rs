//! The bokeh gather's prefilter levels ([`super`]): the padded planes ([`Padded`]) box-averaged
//! over a ring step, colour weighted by 1 / bokeh area, which the ring taps read ([`Level`]),
//! and the carried planes (light layers) prefiltered alike. Made where the tiles' taps read
//! them and nowhere else ([`Reads`]), every plane of a level in one pass over the frame, a
//! band of [`TILE`] rows at a time (in parallel), each band's box sums in a few small rows of
//! scratch.
//!
//! Each box sum adds the same values in the same order as it did when a level was made over
//! the whole frame a plane at a time (across, then down, each box's values left to right and
//! top to bottom, as the GPU twin adds them), so every level value a tap reads has the same
//! bits. Measured (the 1080p `dof` bench frame, one level of side 3; the levels' CPU time in
//! the process, old and new alternated; BENCH-NOTE of the `levels` branch): made a plane at
//! a time over the whole frame through frame-sized temporaries, 50–57 ms for the beauty and
//! 256–264 ms with six RGB light layers; made so, 25–31 and 120–150 ms. Most of what is left
//! is the first touch of the levels' own planes (page faults) and reading the carried planes.

use rayon::prelude::*;

use super::run::Padded;
use crate::dof::tiles::TILE;

/// The padded planes prefiltered by a box of `side` × `side` px, for taps that stand for
/// about that area each: colour the box's average weighted by 1 / bokeh area, 1 / bokeh
/// area the box's mean (0 where the box's pixel is outside the frame; the signed radius is
/// the box's own pixel's, the padded plane itself). An even box covers offsets
/// −side/2 ..= side/2 − 1: its centre lies half a pixel up and left of its pixel. Made only
/// where a tap reads it ([`Reads`]); 0 elsewhere.
pub(super) struct Level {
    pub(super) side: usize,
    /// r, g, b, a.
    colour: [Vec<f32>; 4],
    weight: Vec<f32>,
    /// The carried planes (the frame's own, `width` × `height`) prefiltered as the beauty's
    /// colour is, on the frame's own pixels: the same sums in the same order.
    pub(super) carried: Vec<Vec<f32>>,
}

impl Level {
    /// The level's planes in [`Padded::planes`]' order.
    pub(super) fn planes<'a>(&'a self, padded: &'a Padded) -> [&'a [f32]; 6] {
        let [r, g, b, a] = &self.colour;
        [r, g, b, a, &padded.planes[4], &self.weight].map(|p| p.as_slice())
    }
}

/// Where the taps read a level: blocks of [`TILE`] × [`TILE`] px over the padded planes,
/// aligned with the frame's tiles (block (0, 0) begins a whole number of blocks up and left
/// of the frame's first pixel, at or beyond the padding's corner).
pub(super) struct Reads {
    /// Where block (0, 0) begins, in frame pixels (x and y alike; ≤ −pad).
    first: isize,
    columns: usize,
    rows: usize,
    marked: Vec<bool>,
    /// The padded area, in frame pixels: x in [−pad, `right`), y in [−pad, `bottom`).
    pad: isize,
    right: isize,
    bottom: isize,
}

impl Reads {
    /// No block read yet, over the padded planes of a frame `height` rows high.
    pub(super) fn new(padded: &Padded, height: usize) -> Self {
        let pad = padded.pad as isize;
        let first = -(padded.pad.div_ceil(TILE) as isize) * TILE as isize;
        let right = padded.stride as isize - pad;
        let bottom = height as isize + pad;
        let columns = (right - first) as usize;
        let rows = (bottom - first) as usize;
        let (columns, rows) = (columns.div_ceil(TILE), rows.div_ceil(TILE));
        Reads {
            first,
            columns,
            rows,
            marked: vec![false; columns * rows],
            pad,
            right,
            bottom,
        }
    }

    /// Marks the pixels x in [x0, x1), y in [y0, y1) (frame pixels; clipped to the padded
    /// planes) as read.
    pub(super) fn mark(&mut self, (x0, x1): (isize, isize), (y0, y1): (isize, isize)) {
        let (x0, x1) = (x0.max(-self.pad), x1.min(self.right));
        let (y0, y1) = (y0.max(-self.pad), y1.min(self.bottom));
        if x0 >= x1 || y0 >= y1 {
            return;
        }
        let block = |v: isize| ((v - self.first) / TILE as isize) as usize;
        for by in block(y0)..=block(y1 - 1) {
            self.marked[by * self.columns + block(x0)..=by * self.columns + block(x1 - 1)]
                .fill(true);
        }
    }

    /// Block `b`'s pixels along an axis, in padded pixels, clipped to [0, `len`).
    fn span(&self, b: usize, len: usize) -> (usize, usize) {
        let start = self.first + self.pad + (b * TILE) as isize;
        let clip = |v: isize| v.clamp(0, len as isize) as usize;
        (clip(start), clip(start + TILE as isize))
    }

    /// The runs of read blocks in block row `by`, as padded columns [c0, c1) of planes of row
    /// length `stride`.
    fn runs(&self, by: usize, stride: usize) -> Vec<(usize, usize)> {
        let row = &self.marked[by * self.columns..(by + 1) * self.columns];
        let mut runs: Vec<(usize, usize)> = Vec::new();
        for (bx, _) in row.iter().enumerate().filter(|(_, &m)| m) {
            let (c0, c1) = self.span(bx, stride);
            match runs.last_mut() {
                Some(last) if last.1 == c0 => last.1 = c1,
                _ if c0 < c1 => runs.push((c0, c1)),
                _ => {}
            }
        }
        runs
    }
}

/// Columns a box sum makes at once: a band's rows of them, across and down, stay in the
/// first caches.
const CHUNK: usize = 256;

/// The levels of box sides `sides` of `padded` (a frame of `width` × `height`, with alpha
/// or not: without, its alpha level is 0 as its plane is), and the carried planes `extra` at
/// each, made where `reads` (one a side) says the taps read them.
pub(super) fn build(
    padded: &Padded,
    sides: &[usize],
    reads: &[Reads],
    extra: &[Vec<f32>],
    alpha: bool,
    (width, height): (usize, usize),
) -> Vec<Level> {
    sides
        .iter()
        .zip(reads)
        .map(|(&side, reads)| level(padded, side, reads, extra, alpha, (width, height)))
        .collect()
}

/// One band of [`TILE`] rows of a level, the slices of its planes it writes: padded rows
/// [y0, y1) of the level's colour and weight, frame rows [y0 − pad, y1 − pad) (clipped) of
/// its carried planes.
struct Band<'a> {
    by: usize,
    y0: usize,
    y1: usize,
    colour: Vec<&'a mut [f32]>,
    weight: &'a mut [f32],
    carried: Vec<&'a mut [f32]>,
}

/// `plane` (rows of `row_len`) split at the row `ends`, in order.
fn split_rows<'a>(plane: &'a mut [f32], row_len: usize, ends: &[usize]) -> Vec<&'a mut [f32]> {
    let mut rest = plane;
    let mut at = 0;
    let mut out = Vec::with_capacity(ends.len());
    for &end in ends {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut((end - at) * row_len);
        out.push(head);
        rest = tail;
        at = end;
    }
    out
}

fn level(
    padded: &Padded,
    side: usize,
    reads: &Reads,
    extra: &[Vec<f32>],
    alpha: bool,
    (width, height): (usize, usize),
) -> Level {
    let (stride, pad) = (padded.stride, padded.pad);
    let rows = padded.planes[0].len() / stride;
    let mut colour = [0, 1, 2, 3].map(|_| vec![0.0f32; stride * rows]);
    let mut weight = vec![0.0f32; stride * rows];
    let mut carried: Vec<Vec<f32>> = extra.iter().map(|_| vec![0.0f32; width * height]).collect();
    // Each block row's padded rows, and its frame rows.
    let spans: Vec<(usize, usize)> = (0..reads.rows).map(|by| reads.span(by, rows)).collect();
    let ends: Vec<usize> = spans.iter().map(|s| s.1).collect();
    let frame_ends: Vec<usize> = ends
        .iter()
        .map(|&e| e.saturating_sub(pad).min(height))
        .collect();
    let mut colour_bands: Vec<Vec<&mut [f32]>> = colour
        .iter_mut()
        .map(|p| split_rows(p, stride, &ends))
        .collect();
    let mut carried_bands: Vec<Vec<&mut [f32]>> = carried
        .iter_mut()
        .map(|p| split_rows(p, width, &frame_ends))
        .collect();
    let weight_bands = split_rows(&mut weight, stride, &ends);
    let mut bands: Vec<Band> = Vec::with_capacity(spans.len());
    for (by, (weight, &(y0, y1))) in weight_bands.into_iter().zip(&spans).enumerate().rev() {
        bands.push(Band {
            by,
            y0,
            y1,
            colour: colour_bands
                .iter_mut()
                .map(|b| b.pop().unwrap_or_default())
                .collect(),
            weight,
            carried: carried_bands
                .iter_mut()
                .map(|b| b.pop().unwrap_or_default())
                .collect(),
        });
    }
    bands.into_par_iter().for_each(|mut band| {
        let mut scratch = Scratch::default();
        for (c0, c1) in reads.runs(band.by, stride) {
            for c in (c0..c1).step_by(CHUNK) {
                let block = Block {
                    side,
                    rows: (band.y0, band.y1),
                    columns: (c, (c + CHUNK).min(c1)),
                };
                make(
                    &block,
                    padded,
                    extra,
                    alpha,
                    (width, height),
                    &mut band,
                    &mut scratch,
                );
            }
        }
    });
    Level {
        side,
        colour,
        weight,
        carried,
    }
}

/// A box sum's scratch: the source row (a product of planes), the across sums of a block's
/// source rows, the box sums of 1 / bokeh area over its rows, and one row's box sums.
#[derive(Default)]
struct Scratch {
    source: Vec<f32>,
    across: Vec<f32>,
    sums: Vec<f32>,
    down: Vec<f32>,
}

/// Padded rows [y0, y1) and columns [c0, c1) of a level, made together.
struct Block {
    side: usize,
    rows: (usize, usize),
    columns: (usize, usize),
}

impl Block {
    /// The box's offsets from its pixel, in order.
    #[inline(always)]
    fn offsets(&self) -> impl Iterator<Item = isize> {
        let lo = (self.side / 2) as isize;
        (0..self.side as isize).map(move |o| o - lo)
    }

    /// The padded columns the block's boxes cover, clipped to [0, `stride`).
    #[inline(always)]
    fn reach(&self, stride: usize) -> (usize, usize) {
        let lo = self.side / 2;
        let (c0, c1) = self.columns;
        (c0.saturating_sub(lo), (c1 + self.side - 1 - lo).min(stride))
    }

    /// The padded rows the block's boxes cover, clipped to [0, `rows`).
    #[inline(always)]
    fn rows_read(&self, rows: usize) -> (usize, usize) {
        let lo = self.side / 2;
        let (y0, y1) = self.rows;
        (y0.saturating_sub(lo), (y1 + self.side - 1 - lo).min(rows))
    }

    /// The across sums of `source` (the values of padded columns [s0, s1), those of
    /// [`Block::reach`]) over the block's columns into `out`: each box's values left to right,
    /// from 0, those beyond the planes left out.
    #[inline(always)]
    fn across(&self, source: &[f32], s0: usize, stride: usize, out: &mut [f32]) {
        let (c0, c1) = self.columns;
        out.fill(0.0);
        for o in self.offsets() {
            let from = (c0 as isize).max(-o);
            let to = (c1 as isize).min(stride as isize - o);
            if from >= to {
                continue;
            }
            let (from, to) = (from as usize, to as usize);
            let first = (from as isize + o) as usize - s0;
            for (d, &v) in out[from - c0..to - c0].iter_mut().zip(&source[first..]) {
                *d += v;
            }
        }
    }

    /// The box sums of padded row `y` from the across sums of the rows `rows_read` holds
    /// (`across`, rows of the block's width), into `out`: top to bottom, from 0, rows beyond
    /// the planes left out.
    #[inline(always)]
    fn down(&self, y: usize, across: &[f32], (r0, r1): (usize, usize), out: &mut [f32]) {
        let n = out.len();
        out.fill(0.0);
        for o in self.offsets() {
            let r = y as isize + o;
            if r >= r0 as isize && r < r1 as isize {
                let row = &across[(r as usize - r0) * n..(r as usize - r0 + 1) * n];
                for (d, &v) in out.iter_mut().zip(row) {
                    *d += v;
                }
            }
        }
    }

    /// The across sums of every row the block's boxes read, each row's source values made
    /// by `source(row, s0, s1, into)` (padded columns [s0, s1)), into `scratch.across`.
    #[inline(always)]
    fn across_rows(
        &self,
        stride: usize,
        rows: usize,
        scratch: &mut Scratch,
        source: impl Fn(usize, (usize, usize), &mut Vec<f32>),
    ) {
        let n = self.columns.1 - self.columns.0;
        let (s0, s1) = self.reach(stride);
        let (r0, r1) = self.rows_read(rows);
        scratch.across.resize((r1 - r0) * n, 0.0);
        for r in r0..r1 {
            source(r, (s0, s1), &mut scratch.source);
            let out = &mut scratch.across[(r - r0) * n..(r - r0 + 1) * n];
            self.across(&scratch.source, s0, stride, out);
        }
    }
}

/// Makes `block` of every plane of the level: the box sums of 1 / bokeh area, then each
/// colour's and each carried plane's weighted sums over them.
///
/// Compiled twice, chosen at run time by `multiversion` (as [`super::run::gather_run`] is):
/// only lanes change, never the order of operations, and nothing is fused, so both versions
/// give the same bits.
#[multiversion::multiversion(targets("x86_64+avx512f+avx512vl"))]
fn make(
    block: &Block,
    padded: &Padded,
    extra: &[Vec<f32>],
    alpha: bool,
    (width, height): (usize, usize),
    band: &mut Band,
    scratch: &mut Scratch,
) {
    let (stride, pad) = (padded.stride, padded.pad);
    let rows = padded.planes[0].len() / stride;
    let ia = &padded.planes[5];
    let (c0, c1) = block.columns;
    let n = c1 - c0;
    let (y0, y1) = block.rows;
    let read = block.rows_read(rows);
    let area = (block.side * block.side) as f32;
    // 1 / bokeh area's box sums, and its level (the mean inside the frame).
    block.across_rows(stride, rows, scratch, |r, (s0, s1), out| {
        out.clear();
        out.extend_from_slice(&ia[r * stride + s0..r * stride + s1]);
    });
    scratch.sums.resize((y1 - y0) * n, 0.0);
    for y in y0..y1 {
        let sums = &mut scratch.sums[(y - y0) * n..(y - y0 + 1) * n];
        block.down(y, &scratch.across, read, sums);
        if (pad..pad + height).contains(&y) {
            let (f0, f1) = (c0.max(pad), c1.min(pad + width));
            if f0 < f1 {
                let out = &mut band.weight[(y - y0) * stride + f0..(y - y0) * stride + f1];
                for (o, &w) in out.iter_mut().zip(&sums[f0 - c0..]) {
                    *o = w / area;
                }
            }
        }
    }
    scratch.down.resize(n, 0.0);
    // Each colour: the box average weighted by 1 / bokeh area, the pixel's own colour
    // where the box weighs nothing. Without alpha, the alpha plane and its level are 0.
    for k in 0..if alpha { 4 } else { 3 } {
        let plane = &padded.planes[k];
        block.across_rows(stride, rows, scratch, |r, (s0, s1), out| {
            let i = r * stride;
            out.clear();
            out.extend(
                ia[i + s0..i + s1]
                    .iter()
                    .zip(&plane[i + s0..i + s1])
                    .map(|(a, v)| a * v),
            );
        });
        for y in y0..y1 {
            block.down(y, &scratch.across, read, &mut scratch.down);
            let sums = &scratch.sums[(y - y0) * n..(y - y0 + 1) * n];
            let own = &plane[y * stride + c0..y * stride + c1];
            let out = &mut band.colour[k][(y - y0) * stride + c0..(y - y0) * stride + c1];
            for (((o, &s), &w), &own) in out.iter_mut().zip(&scratch.down).zip(sums).zip(own) {
                *o = if w > 0.0 { s / w } else { own };
            }
        }
    }
    // Each carried plane, on the frame's own pixels: its products with 1 / bokeh area
    // inside the frame, 0 outside it.
    let (f0, f1) = (c0.max(pad), c1.min(pad + width));
    if f0 >= f1 {
        return;
    }
    let first_row = y0.max(pad);
    for (plane, out) in extra.iter().zip(band.carried.iter_mut()) {
        block.across_rows(stride, rows, scratch, |r, (s0, s1), into| {
            into.clear();
            into.resize(s1 - s0, 0.0);
            if (pad..pad + height).contains(&r) {
                let (g0, g1) = (s0.max(pad), s1.min(pad + width));
                if g0 < g1 {
                    let values = &plane[(r - pad) * width + g0 - pad..(r - pad) * width + g1 - pad];
                    let weights = &ia[r * stride + g0..r * stride + g1];
                    for ((o, &a), &v) in into[g0 - s0..g1 - s0].iter_mut().zip(weights).zip(values)
                    {
                        *o = a * v;
                    }
                }
            }
        });
        for y in first_row..y1.min(pad + height) {
            block.down(y, &scratch.across, read, &mut scratch.down);
            let sums = &scratch.sums[(y - y0) * n..(y - y0 + 1) * n];
            let row = (y - pad) * width;
            let own = &plane[row + f0 - pad..row + f1 - pad];
            let at = (y - first_row) * width + f0 - pad;
            let out = &mut out[at..at + f1 - f0];
            let (s, w) = (&scratch.down[f0 - c0..f1 - c0], &sums[f0 - c0..f1 - c0]);
            for (((o, &s), &w), &own) in out.iter_mut().zip(s).zip(w).zip(own) {
                *o = if w > 0.0 { s / w } else { own };
            }
        }
    }
}

#[cfg(test)]
impl Reads {
    /// Whether the level is made at padded pixel (`px`, `py`).
    pub(super) fn is_read(&self, px: usize, py: usize) -> bool {
        let block = |v: usize| ((v as isize - self.pad - self.first) / TILE as isize) as usize;
        self.marked[block(py) * self.columns + block(px)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Color;

    /// The sums over boxes of `side` × `side` of a padded plane of row length `stride`, each at
    /// the box's pixel, as a level was made over the whole frame before (across, then down,
    /// each box's values added in order, those beyond the plane left out).
    fn box_sum(values: &[f32], stride: usize, side: usize) -> Vec<f32> {
        let rows = values.len() / stride;
        let lo = (side / 2) as isize;
        let mut across = vec![0.0f32; values.len()];
        for y in 0..rows {
            for o in (0..side as isize).map(|o| o - lo) {
                for x in 0..stride {
                    let sx = x as isize + o;
                    if sx >= 0 && (sx as usize) < stride {
                        across[y * stride + x] += values[y * stride + sx as usize];
                    }
                }
            }
        }
        let mut out = vec![0.0f32; values.len()];
        for y in 0..rows {
            for o in (0..side as isize).map(|o| o - lo) {
                let sy = y as isize + o;
                if sy >= 0 && (sy as usize) < rows {
                    for x in 0..stride {
                        out[y * stride + x] += across[sy as usize * stride + x];
                    }
                }
            }
        }
        out
    }

    /// A frame of `width` × `height` whose values and bokehs vary from pixel to pixel (so
    /// that a sum in another order has other bits), negative zeros and negative values
    /// among them, with alpha or without, and two carried planes.
    fn frame(width: usize, height: usize, alpha: bool) -> (Color, Vec<f32>, Vec<Vec<f32>>) {
        let value = |seed: usize| -> Vec<f32> {
            (0..width * height)
                .map(|i| match (i * 2654435761 + seed) % 1009 {
                    0..=40 => -0.0,
                    v => v as f32 / 37.0 - 9.0,
                })
                .collect()
        };
        let coc: Vec<f32> = (0..width * height)
            .map(|i| ((i * 7919) % 53) as f32 - 26.0)
            .collect();
        let color = Color {
            r: value(1),
            g: value(2),
            b: value(3),
            a: alpha.then(|| value(4)),
        };
        (color, coc, vec![value(5), value(6)])
    }

    #[test]
    fn a_level_has_the_bits_of_the_whole_frame_box_sums_where_it_is_read_and_is_0_elsewhere() {
        // The levels were made over the whole frame a plane at a time; now only where the
        // taps read them, in bands and columns. Wherever they are made, every value must
        // have the bits the whole frame's sums gave it (the same additions in the same
        // order), colour, weight and carried planes, for boxes of every size up to the
        // largest, one larger than the padding, with alpha or without, up to every edge of
        // the padded planes.
        let (width, height) = (61, 37);
        for alpha in [true, false] {
            let (color, coc, extra) = frame(width, height, alpha);
            let padded = Padded::new(&color, &coc, (width, height), 9, 2.7);
            let (stride, pad) = (padded.stride, padded.pad);
            let ia = &padded.planes[5];
            let sides = [2, 3, 4, 7, 16];
            let reads: Vec<Reads> = sides
                .iter()
                .map(|_| {
                    let mut reads = Reads::new(&padded, height);
                    reads.mark((11, 37), (11, 37));
                    reads.mark((-30, 10), (25, 60));
                    reads.mark((50, 60), (-5, 3));
                    reads.mark((80, 200), (30, 200));
                    reads
                })
                .collect();
            let levels = build(&padded, &sides, &reads, &extra, alpha, (width, height));
            let bits = |v: f32| v.to_bits();
            for ((level, reads), &side) in levels.iter().zip(&reads).zip(&sides) {
                let sum = box_sum(ia, stride, side);
                let area = (side * side) as f32;
                let colour: Vec<Vec<f32>> = (0..4)
                    .map(|k| {
                        let plane = &padded.planes[k];
                        let products: Vec<f32> = ia.iter().zip(plane).map(|(a, v)| a * v).collect();
                        let weighted = box_sum(&products, stride, side);
                        (0..plane.len())
                            .map(|i| {
                                if sum[i] > 0.0 {
                                    weighted[i] / sum[i]
                                } else {
                                    plane[i]
                                }
                            })
                            .collect()
                    })
                    .collect();
                let inside = |px: usize, py: usize| {
                    (pad..pad + width).contains(&px) && (pad..pad + height).contains(&py)
                };
                let mut made = 0;
                for py in 0..ia.len() / stride {
                    for px in 0..stride {
                        let i = py * stride + px;
                        let planes = level.planes(&padded);
                        if !reads.is_read(px, py) {
                            for plane in [0, 1, 2, 3, 5] {
                                assert_eq!(bits(planes[plane][i]), 0, "side {side}: ({px}, {py})");
                            }
                            continue;
                        }
                        made += 1;
                        for k in 0..4 {
                            let want = if k < 3 || alpha { colour[k][i] } else { 0.0 };
                            assert_eq!(
                                bits(planes[k][i]),
                                bits(want),
                                "side {side}, {k}: ({px}, {py})"
                            );
                        }
                        let weight = if inside(px, py) { sum[i] / area } else { 0.0 };
                        assert_eq!(
                            bits(planes[5][i]),
                            bits(weight),
                            "side {side}: ({px}, {py})"
                        );
                    }
                }
                assert!(made > 0 && made < ia.len());
                for (plane, got) in extra.iter().zip(&level.carried) {
                    let mut products = vec![0.0f32; ia.len()];
                    for (j, &v) in plane.iter().enumerate() {
                        let i = padded.index(j % width, j / width);
                        products[i] = ia[i] * v;
                    }
                    let weighted = box_sum(&products, stride, side);
                    for j in 0..plane.len() {
                        let (x, y) = (j % width, j / width);
                        let i = padded.index(x, y);
                        let want = match (reads.is_read(x + pad, y + pad), sum[i] > 0.0) {
                            (false, _) => 0.0,
                            (true, true) => weighted[i] / sum[i],
                            (true, false) => plane[j],
                        };
                        assert_eq!(bits(got[j]), bits(want), "side {side}, carried: ({x}, {y})");
                    }
                }
            }
        }
    }
}
