//! Stage 2, `accumulate`: tile by tile, the curves of the pixels whose reach touches the tile
//! are built ([`Scatter::path`]: cut into segments, weighted along the shutter, scaled to
//! `max_curve`) and drawn as line segments with sub-pixel coverage into f64 cells, depth-tested
//! against the frame; each pixel of the tile is then resolved ([`super::resolve`]).

use crate::motion::line::{Clip, Column, Walk, Whole, OVERHANG};

use super::config::BLOCK;
use super::job::Scatter;
use super::path::Path;
use super::reach::Reach;

impl Scatter<'_> {
    /// Accumulates the curves reaching one tile and writes its normalised pixels into `rows`
    /// (the tile's pieces of its rows of R, G, B and A) and `carried` (of the carried planes,
    /// [`Scatter::extra`], row by row), or where no curve reaches the tile, its input pixels.
    pub(super) fn tile<const N: usize>(
        &self,
        reach: &Reach,
        rect: [usize; 4],
        rows: &mut [[&mut [f32]; 4]],
        carried: &mut [Vec<&mut [f32]>],
    ) {
        // Compiled apart with and without carried planes, so a beauty alone pays nothing for
        // them (3.6 % at 1080p when one deposit loop served both).
        SCRATCH.with_borrow_mut(|scratch| {
            if self.extra.is_empty() {
                self.tile_in::<N, false>(reach, rect, rows, carried, scratch)
            } else {
                self.tile_in::<N, true>(reach, rect, rows, carried, scratch)
            }
        });
    }

    fn tile_in<const N: usize, const CARRY: bool>(
        &self,
        reach: &Reach,
        rect: [usize; 4],
        rows: &mut [[&mut [f32]; 4]],
        carried: &mut [Vec<&mut [f32]>],
        scratch: &mut Scratch,
    ) {
        let [tx0, ty0, tx1, ty1] = rect;
        let (tw, th) = (tx1 - tx0, ty1 - ty0);
        let width = self.width;
        // The tile's cells with a border of OVERHANG on every side, where a walk's rows may
        // land, and per cell the deepest a curve may be and still pass: depth × (1 +
        // tolerance), with NaN depth as far and negative as 0. The border's is −∞, so nothing
        // is ever deposited there.
        let pad = OVERHANG as usize;
        let pw = tw + 2 * pad;
        let cells = pw * (th + 2 * pad);
        scratch.sums.clear();
        scratch.sums.resize(cells * N, 0.0);
        let (acc, _) = scratch.sums.as_chunks_mut::<N>();
        // The carried planes' sums, cell by cell (each cell's `e` sums together).
        let e = self.extra.len();
        scratch.extra.clear();
        scratch.extra.resize(cells * e, 0.0);
        let extra = &mut scratch.extra;
        let limit = &mut scratch.limit;
        limit.clear();
        limit.resize(cells, f32::NEG_INFINITY);
        let tolerance = 1.0 + self.config.depth_tolerance;
        for y in ty0..ty1 {
            let o = (y - ty0 + pad) * pw + pad;
            let depth = &self.depth[y * width + tx0..y * width + tx1];
            for (l, &z) in limit[o..o + tw].iter_mut().zip(depth) {
                *l = z * tolerance;
            }
        }
        let limit = &*limit;
        // Cell of pixel (x, y): origin + x + y·pw.
        let origin = (pad * pw + pad) as i64 - (ty0 * pw + tx0) as i64;
        let clip = Clip {
            x0: tx0 as i64,
            y0: ty0 as i64,
            x1: tx1 as i64,
            y1: ty1 as i64,
        };
        let mut path = Path::new();
        let mut reached = false;
        // Blocks near enough for their largest reach to touch the tile, in a fixed order (so
        // every sum runs in the same order); in them, pixels whose own reach touches it.
        let touches = |x: f64, y: f64, r: f64| {
            x + r >= tx0 as f64 && x - r < tx1 as f64 && y + r >= ty0 as f64 && y - r < ty1 as f64
        };
        let most = reach.most as usize + BLOCK;
        let (bx0, by0) = (
            tx0.saturating_sub(most) / BLOCK,
            ty0.saturating_sub(most) / BLOCK,
        );
        let bx1 = ((tx1 + most) / BLOCK + 1).min(reach.across);
        let by1 = ((ty1 + most) / BLOCK + 1).min(reach.down);
        for by in by0..by1 {
            for bx in bx0..bx1 {
                let r = reach.block[by * reach.across + bx] as f64;
                let (x0, y0) = ((bx * BLOCK) as f64, (by * BLOCK) as f64);
                let side = BLOCK as f64;
                if r == 0.0 || !touches(x0 + 0.5 * side, y0 + 0.5 * side, r + 0.5 * side) {
                    continue;
                }
                for y in by * BLOCK..((by + 1) * BLOCK).min(self.height) {
                    for x in bx * BLOCK..((bx + 1) * BLOCK).min(width) {
                        let e = y * width + x;
                        // A fringe pixel's reach is negative ([`Reach`]).
                        let r = reach.pixel[e] as f64;
                        if r == 0.0 || !touches(x as f64 + 0.5, y as f64 + 0.5, r.abs()) {
                            continue;
                        }
                        // Moving (its reach is not 0), so its positions are not NaN; or a
                        // fringe pixel, drawn with its partner's motion.
                        let fringe = if r < 0.0 { self.fringe.get(e) } else { None };
                        let motion = match fringe {
                            Some((m, _)) => self.fringe_positions(x, y, m),
                            None => self.positions(x, y),
                        };
                        if !self.path(e, &motion, &mut path, fringe) {
                            continue;
                        }
                        reached = true;
                        // Colour (alpha too unless opaque) and 1 for the weight.
                        let color: [f64; N] =
                            std::array::from_fn(|k| if k == N - 1 { 1.0 } else { path.color[k] });
                        for k in 0..path.segments {
                            let Some(walk) = Walk::new(path.points[k], path.points[k + 1], clip)
                            else {
                                continue;
                            };
                            let (w0, w1) = (path.weights[k], path.weights[k + 1]);
                            let (z0, z1) = (path.depths[k], path.depths[k + 1]);
                            let (dz, dw) = (z1 - z0, w1 - w0);
                            // Steps in the cells along the walk's columns and rows.
                            let (along, across) = if walk.swapped {
                                (pw as i64, 1)
                            } else {
                                (1, pw as i64)
                            };
                            let mut segment = Segment::<N, CARRY> {
                                acc: &mut *acc,
                                extra: &mut extra[..],
                                limit,
                                color: &color,
                                extra_color: &path.extra,
                                origin,
                                along,
                                across,
                                z0,
                                dz,
                                w0,
                                dw,
                            };
                            // The columns crossed whole step in fixed point; the segment's
                            // ends (at most one column each side) take the exact walk.
                            let whole = walk.whole();
                            for column in walk.first..whole.first {
                                segment.put(column, walk.column(column));
                            }
                            segment.whole(&whole);
                            for column in whole.last + 1..walk.last + 1 {
                                segment.put(column, walk.column(column));
                            }
                        }
                    }
                }
            }
        }
        if !reached {
            let color = self.color;
            for (y, (row, carried)) in (ty0..ty1).zip(rows.iter_mut().zip(carried.iter_mut())) {
                let span = y * width + tx0..y * width + tx1;
                for (to, from) in carried.iter_mut().zip(&self.extra) {
                    to.copy_from_slice(&from[span.clone()]);
                }
                let [r, g, b, a] = row;
                for (to, from) in [(r, &color.r), (g, &color.g), (b, &color.b)] {
                    to.copy_from_slice(&from[span.clone()]);
                }
                match &color.a {
                    Some(alpha) => a.copy_from_slice(&alpha[span]),
                    None => a.fill(1.0),
                }
            }
            return;
        }
        for (y, (row, carried)) in (ty0..ty1).zip(rows.iter_mut().zip(carried.iter_mut())) {
            for x in tx0..tx1 {
                let at = (origin + (x + y * pw) as i64) as usize;
                let cell = &acc[at];
                // An opaque frame's alpha sums are its weight sums.
                let cell = std::array::from_fn(|k| cell[k.min(N - 1)]);
                let i = y * width + x;
                // Found once, from the beauty's weight sum, for the beauty and every carried
                // plane.
                let resolution = self.resolution(cell[4], x, y, reach);
                let value = self.resolved(&resolution, &cell, i);
                for (plane, v) in row.iter_mut().zip(value) {
                    plane[x - tx0] = v;
                }
                if e > 0 {
                    let sums = &extra[at * e..at * e + e];
                    for ((plane, &sum), from) in carried.iter_mut().zip(sums).zip(&self.extra) {
                        plane[x - tx0] = self.channel(&resolution, sum, i, |j| from[j]);
                    }
                }
            }
        }
    }
}

/// A thread's tile buffers, kept from tile to tile (allocating them afresh for every tile
/// costs a page fault per 4 KiB).
#[derive(Default)]
struct Scratch {
    sums: Vec<f64>,
    /// The carried planes' sums.
    extra: Vec<f64>,
    limit: Vec<f32>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::default();
}

/// Drops every pool thread's sums of carried planes ([`Scratch::extra`]).
pub(super) fn free_carried_sums() {
    rayon::broadcast(|_| SCRATCH.with_borrow_mut(|scratch| scratch.extra = Vec::new()));
}

/// One segment of a curve being drawn into a tile's cells.
struct Segment<'a, const N: usize, const CARRY: bool> {
    acc: &'a mut [[f64; N]],
    /// The carried planes' sums, `extra_color.len()` a cell.
    extra: &'a mut [f64],
    limit: &'a [f32],
    color: &'a [f64; N],
    /// The carried planes' values at the curve's pixel.
    extra_color: &'a [f64],
    /// Cell of (column, row): origin + column·along + row·across.
    origin: i64,
    along: i64,
    across: i64,
    /// Depth and weight at the segment's start, and their change along it.
    z0: f32,
    dz: f32,
    w0: f64,
    dw: f64,
}

impl<const N: usize, const CARRY: bool> Segment<'_, N, CARRY> {
    /// Depth and weight `u` along the segment.
    #[inline(always)]
    fn at(&self, u: f64) -> (f32, f64) {
        (self.z0 + self.dz * u as f32, self.w0 + self.dw * u)
    }

    /// Deposits column `column`'s coverage where the depth test passes.
    #[inline(always)]
    fn put(&mut self, column: i64, c: Column) {
        let (z, w) = self.at(c.u);
        self.deposit(column, c, z, w);
    }

    /// Deposits the columns the segment crosses whole, as [`Segment::put`] does, with the
    /// depth and weight hoisted where they are constant along the segment (the box weight and
    /// no depth motion): nothing then depends on where along it a column is.
    #[inline(always)]
    fn whole(&mut self, whole: &Whole) {
        if self.dz == 0.0 && self.dw == 0.0 {
            self.whole_steps::<false>(whole);
        } else {
            self.whole_steps::<true>(whole);
        }
    }

    #[inline(always)]
    fn whole_steps<const VARYING: bool>(&mut self, whole: &Whole) {
        // (Exclusive ranges: an inclusive one costs a flag per step.)
        for k in 0..whole.last - whole.first + 1 {
            let c = whole.column(k);
            let (z, w) = if VARYING {
                self.at(c.u)
            } else {
                (self.z0, self.w0)
            };
            self.deposit(whole.first + k, c, z, w);
        }
    }

    #[inline(always)]
    fn deposit(&mut self, column: i64, c: Column, z: f32, w: f64) {
        let i = (self.origin + column * self.along + c.row * self.across) as usize;
        let j = i + self.across as usize;
        if z <= self.limit[i] {
            add(&mut self.acc[i], c.c0 * w, self.color);
            self.carry(i, c.c0 * w);
        }
        if z <= self.limit[j] {
            add(&mut self.acc[j], c.c1 * w, self.color);
            self.carry(j, c.c1 * w);
        }
    }

    /// The deposit of weight `w` into cell `i`'s carried sums, as [`add`] makes the beauty's.
    #[inline(always)]
    fn carry(&mut self, i: usize, w: f64) {
        let e = self.extra_color.len();
        if CARRY {
            for (sum, c) in self.extra[i * e..i * e + e]
                .iter_mut()
                .zip(self.extra_color)
            {
                *sum += w * c;
            }
        }
    }
}

/// Adds a deposit of weight `w` and colour `color` to an accumulation cell (the colour's
/// last channel is 1: the cell's last is the weight).
#[inline(always)]
pub(super) fn add<const N: usize>(cell: &mut [f64; N], w: f64, color: &[f64; N]) {
    for (sum, c) in cell.iter_mut().zip(color) {
        *sum += w * c;
    }
}
