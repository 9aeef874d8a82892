//! scatter — the curve scatter of Guertin & Nowrouzezahrai, *High Performance Non-linear
//! Motion Blur* (§3), on the CPU.
//!
//! Every moving pixel draws its motion curve through p(-1), p(0), p(+1) ([`super::curve`]),
//! the part inside the shutter only, as line segments ([`super::line`]) into an accumulation
//! buffer: its colour times a weight into RGBA, the weight into a fifth channel. A depth test
//! against the frame's depth (no depth writes) lets curves pass behind nearer surfaces. A
//! final pass normalises each pixel.
//!
//! Two normalisations:
//! - [`Normalize::Paper`], eq. 4: `c' = (A.rgba + w_b·c) / (A.w + w_b)`, each pixel a curve
//!   crosses weighted by its coverage times the weight along the curve.
//! - [`Normalize::Exposure`] (beyond the paper; DESIGN.md "where the paper's weighting goes
//!   wrong"): each curve deposits its *share of the exposure*, coverage / curve length (times
//!   the normalised weight along the curve), so A.w is the fraction of the shutter interval a
//!   pixel is covered by moving surfaces. A pixel covered less than the whole interval shows
//!   what lies behind for the rest: its own colour where it does not move, and where it does
//!   (a moving surface revealing what was behind it), the colour of the nearest farther
//!   surface along its motion, or its own colour if none is found. Covered more than once
//!   (overlapping moving surfaces), the deposits are averaged.
//!
//! Weights along the curve, by s ∈ [0, 1] (s = ½ at the frame): the paper's Gaussian
//! (μ = ½, σ) and the box (every instant of the exposure counts the same: the ideal shutter).
//! Weights are linear between segment ends.
//!
//! Determinism and work: output pixels are accumulated tile by tile, in f64. A first pass
//! records, per 16×16 block of pixels, how far its curves can reach (a cheap bound, no curve
//! is built); each tile then visits the blocks that can reach it, and in them the pixels
//! whose own bound reaches it, always in the same order, and draws only those curves, clipped
//! to the tile. So the sums run in the same order for any thread count, no list of curves is
//! stored, and a curve is built about 1.4 times on average (30 px streaks, 256×128 tiles).
//! f64 also keeps a million overlapping deposits of one colour at that colour (f32 would drift
//! by ~1e-4). A tile's cells (four sums where the frame is opaque, five with alpha) carry a
//! border where a walk's unclipped rows land, with a depth limit of −∞ there, and live in a
//! per-thread scratch reused from tile to tile.
//!
//! Numerics: inputs obey the numeric policy ([`crate::numeric`]: finite colour, positions
//! within ±[`POSITION_LIMIT`](crate::numeric::POSITION_LIMIT) px and a pixel with a NaN
//! position still, depth in [0, +∞]); a
//! curve longer than `max_curve` px is scaled about p(0) to that length, which bounds the
//! work per curve. Output is finite and, as a weighted average with non-negative weights,
//! within the per-channel range of the input colours.

use rayon::prelude::*;

use super::curve::{length, Arc, Bezier, Point};
use super::line::{Clip, Column, Walk, Whole, OVERHANG};
use crate::frame::{Color, Frame, Positions};

/// A pixel whose curve stays within this many pixels of p(0) over the shutter is still: its
/// streak would be under half a pixel.
pub const STILL: f64 = 0.25;
/// The most segments a curve is cut into.
pub const MOST_SEGMENTS: usize = 64;
/// Output tiles are this many pixels wide and high.
const TILE_W: usize = 256;
const TILE_H: usize = 128;
/// Reach is kept per block of this many pixels square.
const BLOCK: usize = 16;
/// Below this uncovered share an exposure-normalised pixel needs no background estimate.
const COVERED: f64 = 1e-3;

/// The weight along the curve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Weight {
    /// The paper's Gaussian in s, μ = ½.
    Gaussian,
    /// Every instant of the exposure the same: the ideal shutter.
    Box,
}

impl Weight {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, Weight)] =
        &[("box", Weight::Box), ("gaussian", Weight::Gaussian)];
}

/// How accumulated curves and the pixel's own colour combine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Normalize {
    /// Eq. 4 with background weight w_b.
    Paper,
    /// Deposits as shares of the exposure, the rest filled with what lies behind.
    Exposure,
}

impl Normalize {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, Normalize)] = &[
        ("exposure", Normalize::Exposure),
        ("paper", Normalize::Paper),
    ];
}

/// The curve through the three positions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// The paper's quadratic Bézier.
    Bezier,
    /// A circular arc where the points turn, else the Bézier.
    Arc,
}

impl CurveKind {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, CurveKind)] =
        &[("bezier", CurveKind::Bezier), ("arc", CurveKind::Arc)];
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScatterParams {
    /// Line segments per curve (at most; see `flatness`). The paper's Δ = 11 points is 10
    /// segments.
    pub segments: usize,
    /// σ of the Gaussian weight, in units of s (the whole frame interval −1..1 is s = 0..1).
    pub sigma: f32,
    pub weight: Weight,
    /// w_b of eq. 4 (paper normalisation only).
    pub background_weight: f32,
    pub normalize: Normalize,
    pub curve: CurveKind,
    /// The longest a curve may be, in pixels: longer ones are scaled about p(0) to this length
    /// (which bounds the work per curve).
    pub max_curve: f32,
    /// Fewer segments where they stray no more than this many pixels from the curve (0: always
    /// `segments`). Short, straight motion then costs one segment.
    pub flatness: f32,
    /// A curve passes a pixel whose depth is at least its own depth / (1 + this) (relative).
    pub depth_tolerance: f32,
}

impl Default for ScatterParams {
    fn default() -> Self {
        ScatterParams {
            segments: 10,
            sigma: 2.0,
            weight: Weight::Box,
            background_weight: 5.0,
            normalize: Normalize::Exposure,
            curve: CurveKind::Bezier,
            max_curve: 256.0,
            flatness: 0.1,
            depth_tolerance: 0.02,
        }
    }
}

/// A moving pixel's three positions, and how far from p(0) its curve can deposit.
#[derive(Clone, Copy)]
struct Motion {
    prev: Point,
    now: Point,
    next: Point,
    reach: f64,
}

/// One curve, cut into segments, ready to draw.
struct Path {
    segments: usize,
    points: [Point; MOST_SEGMENTS + 1],
    /// Weight along the curve at each point, already divided by the curve's total in exposure
    /// normalisation.
    weights: [f64; MOST_SEGMENTS + 1],
    /// The curve's depth at each point.
    depths: [f32; MOST_SEGMENTS + 1],
    /// Segment lengths before scaling to `max_curve`.
    lengths: [f64; MOST_SEGMENTS],
    color: [f64; 4],
}

impl Path {
    fn new() -> Self {
        Path {
            segments: 0,
            points: [[0.0; 2]; MOST_SEGMENTS + 1],
            weights: [0.0; MOST_SEGMENTS + 1],
            depths: [0.0; MOST_SEGMENTS + 1],
            lengths: [0.0; MOST_SEGMENTS],
            color: [0.0; 4],
        }
    }
}

struct Scatter<'a> {
    width: usize,
    height: usize,
    color: &'a Color,
    depth: &'a [f32],
    prev: &'a Positions,
    next: &'a Positions,
    params: ScatterParams,
    /// Half the shutter: the exposure is t ∈ [−half, half].
    half: f64,
}

impl Scatter<'_> {
    fn color(&self, i: usize) -> [f32; 4] {
        [
            self.color.r[i],
            self.color.g[i],
            self.color.b[i],
            self.color.a.as_ref().map_or(1.0, |a| a[i]),
        ]
    }

    /// The motion of a moving pixel; `None` where it is still.
    #[inline]
    fn motion(&self, x: usize, y: usize) -> Option<Motion> {
        let i = y * self.width + x;
        let now = [x as f64 + 0.5, y as f64 + 0.5];
        let prev = [self.prev.x[i] as f64, self.prev.y[i] as f64];
        let next = [self.next.x[i] as f64, self.next.y[i] as f64];
        let extent = self.extent(prev, now, next);
        (extent >= STILL).then_some(Motion {
            prev,
            now,
            next,
            // What the scaling to max_curve leaves, and the pixel a segment reaches beside it.
            reach: extent.min(self.params.max_curve as f64) + 1.0,
        })
    }

    /// The positions of a pixel known to move, with its reach `r` from the reach pass
    /// (skips [`Scatter::motion`]'s bound).
    #[inline]
    fn positions(&self, x: usize, y: usize, reach: f64) -> Motion {
        let i = y * self.width + x;
        Motion {
            prev: [self.prev.x[i] as f64, self.prev.y[i] as f64],
            now: [x as f64 + 0.5, y as f64 + 0.5],
            next: [self.next.x[i] as f64, self.next.y[i] as f64],
            reach,
        }
    }

    /// A bound on how far the curve strays from p(0) during the exposure: with
    /// p(t) = p0 + t·v + t²·a, at most h·|v| + h²·|a| for |t| ≤ h.
    fn extent(&self, prev: Point, now: Point, next: Point) -> f64 {
        let v = [0.5 * (next[0] - prev[0]), 0.5 * (next[1] - prev[1])];
        let a = [
            0.5 * (next[0] + prev[0]) - now[0],
            0.5 * (next[1] + prev[1]) - now[1],
        ];
        self.half * length(v) + self.half * self.half * length(a)
    }

    fn weight(&self, t: f64) -> f64 {
        match self.params.weight {
            Weight::Box => 1.0,
            Weight::Gaussian => {
                let d = 0.5 * t; // s − ½
                let sigma = self.params.sigma as f64;
                (-d * d / (2.0 * sigma * sigma)).exp()
            }
        }
    }

    /// The curve of moving pixel `i` inside the shutter, into `path`; false if it has none.
    fn path(&self, i: usize, motion: &Motion, path: &mut Path) -> bool {
        let Motion {
            prev, now, next, ..
        } = *motion;
        let p = &self.params;
        let (t0, t1) = (-self.half, self.half);
        let most = p.segments.clamp(1, MOST_SEGMENTS);
        let tolerance = p.flatness as f64;
        let arc = match p.curve {
            CurveKind::Arc => Arc::fit(prev, now, next),
            CurveKind::Bezier => None,
        };
        let bezier = Bezier::through(prev, now, next);
        let segments = match &arc {
            Some(arc) => arc.segments(t0, t1, tolerance, most),
            None => bezier.segments(0.5 * (t1 - t0), tolerance, most),
        };
        path.segments = segments;
        path.color = self.color(i).map(f64::from);
        let z0 = self.depth[i];
        let depth_at = match (&self.prev.z, &self.next.z) {
            (Some(zp), Some(zn)) if zp[i].is_finite() && zn[i].is_finite() && z0.is_finite() => {
                let (zp, zn) = (zp[i] as f64, zn[i] as f64);
                let z0 = z0 as f64;
                Some(move |t: f64| {
                    (z0 + t * 0.5 * (zn - zp) + t * t * (0.5 * (zn + zp) - z0)).max(0.0) as f32
                })
            }
            _ => None,
        };
        let mut total = 0.0;
        // (Counts convert to f64 through u32: one instruction instead of usize's several.)
        let step = (t1 - t0) / (segments as u32) as f64;
        for k in 0..segments + 1 {
            let t = t0 + step * (k as u32) as f64;
            path.points[k] = match &arc {
                Some(arc) => arc.at_time(t),
                None => bezier.at(0.5 * (t + 1.0)),
            };
            path.weights[k] = self.weight(t);
            path.depths[k] = depth_at.map_or(z0, |f| f(t));
            if k > 0 {
                let (a, b) = (path.points[k - 1], path.points[k]);
                path.lengths[k - 1] = length([b[0] - a[0], b[1] - a[1]]);
                total += path.lengths[k - 1];
            }
        }
        if total.is_nan() || total <= 1e-9 {
            return false;
        }
        let longest = p.max_curve.max(1.0) as f64;
        let mut scale = 1.0;
        if total > longest {
            // Scaled about p(0): a similarity, so every length scales the same.
            scale = longest / total;
            for q in &mut path.points[..=segments] {
                *q = [
                    now[0] + scale * (q[0] - now[0]),
                    now[1] + scale * (q[1] - now[1]),
                ];
            }
        }
        if p.normalize == Normalize::Exposure {
            // The curve's deposits add up to Σ length × mean weight of each segment (weights
            // are linear along a segment): divide so they add up to 1.
            // (With the box weight every mean is 1 and the sum is the total length, bit for bit.)
            let mut sum = if p.weight == Weight::Box {
                total
            } else {
                let mut sum = 0.0;
                for k in 0..segments {
                    sum += path.lengths[k] * 0.5 * (path.weights[k] + path.weights[k + 1]);
                }
                sum
            };
            sum *= scale;
            if !(sum > 0.0 && sum.is_finite()) {
                return false;
            }
            let inverse = 1.0 / sum;
            for w in &mut path.weights[..=segments] {
                *w *= inverse;
            }
        }
        true
    }

    /// The colour behind moving pixel `i`: the nearest farther surface along its motion
    /// (either way; the average if both), else its own colour.
    fn behind(&self, x: usize, y: usize, reach: &Reach) -> [f32; 4] {
        let i = y * self.width + x;
        let own = self.color(i);
        let Some(Motion {
            prev, now, next, ..
        }) = self.motion(x, y)
        else {
            return own;
        };
        let v = [next[0] - prev[0], next[1] - prev[1]];
        let l = length(v);
        if l.is_nan() || l <= 0.0 {
            return own;
        }
        let dir = [v[0] / l, v[1] / l];
        let limit = self.depth[i] * (1.0 + self.params.depth_tolerance);
        let steps = (self
            .extent(prev, now, next)
            .min(self.params.max_curve as f64)
            + 2.0)
            .ceil() as usize;
        // Nothing farther within the search: its blocks' deepest depth tells without a walk.
        let (x, y) = (now[0] as usize, now[1] as usize);
        let (bx0, by0) = (
            x.saturating_sub(steps) / BLOCK,
            y.saturating_sub(steps) / BLOCK,
        );
        let bx1 = ((x + steps) / BLOCK).min(reach.across - 1);
        let by1 = ((y + steps) / BLOCK).min(reach.down - 1);
        let deepest = |bx: usize, by: usize| reach.deepest[by * reach.across + bx];
        if (by0..=by1).all(|by| (bx0..=bx1).all(|bx| deepest(bx, by) <= limit)) {
            return own;
        }
        let mut sum = [0.0f64; 4];
        let mut found = 0;
        for side in [1.0, -1.0] {
            for k in 1..steps + 1 {
                let x = now[0] + side * k as f64 * dir[0];
                let y = now[1] + side * k as f64 * dir[1];
                if !(x >= 0.0 && y >= 0.0 && x < self.width as f64 && y < self.height as f64) {
                    break;
                }
                let j = y as usize * self.width + x as usize;
                if self.depth[j] > limit {
                    for (s, c) in sum.iter_mut().zip(self.color(j)) {
                        *s += c as f64;
                    }
                    found += 1;
                    break;
                }
            }
        }
        if found == 0 {
            own
        } else {
            sum.map(|s| (s / found as f64) as f32)
        }
    }
}

/// For each BLOCK×BLOCK block of pixels, how far from its pixels their curves can deposit
/// (0 where none moves): lets a tile find the pixels whose curves can reach it.
struct Reach {
    across: usize,
    down: usize,
    /// Per pixel (0 where still), so tiles test it without rebuilding the motion.
    pixel: Vec<f32>,
    block: Vec<f32>,
    most: f32,
    /// The deepest (sanitised) depth in each block.
    deepest: Vec<f32>,
}

impl Reach {
    fn of(job: &Scatter) -> Reach {
        let (width, height) = (job.width, job.height);
        let (across, down) = (width.div_ceil(BLOCK), height.div_ceil(BLOCK));
        let mut pixel = vec![0.0f32; width * height];
        let mut block = vec![0.0f32; across * down];
        let mut deepest = vec![0.0f32; across * down];
        // One row of blocks at a time: its pixels' reach (rounded up with a margin, so the f32
        // never falls short of the f64), then its blocks' largest reach and deepest depth.
        pixel
            .par_chunks_mut(BLOCK * width.max(1))
            .zip(block.par_chunks_mut(across.max(1)))
            .zip(deepest.par_chunks_mut(across.max(1)))
            .enumerate()
            .for_each(|(by, ((pixel, block), deepest))| {
                let y0 = by * BLOCK;
                for (y, row) in (y0..).zip(pixel.chunks_mut(width)) {
                    for (x, r) in row.iter_mut().enumerate() {
                        *r = job.motion(x, y).map_or(0.0, |m| (m.reach + 0.01) as f32);
                    }
                }
                for (bx, (most, deepest)) in block.iter_mut().zip(deepest).enumerate() {
                    for y in 0..BLOCK.min(height - y0) {
                        let row = y * width + bx * BLOCK..y * width + ((bx + 1) * BLOCK).min(width);
                        *most = pixel[row.clone()].iter().fold(*most, |m, &r| m.max(r));
                        let depth = &job.depth[y0 * width + row.start..y0 * width + row.end];
                        *deepest = depth.iter().fold(*deepest, |d, &z| d.max(z));
                    }
                }
            });
        let most = block.iter().copied().fold(0.0, f32::max);
        Reach {
            across,
            down,
            pixel,
            block,
            most,
            deepest,
        }
    }
}

/// Applies the filter. The frame must hold colour, depth, prev and next (velocity is
/// dropped). A frame in which nothing moves is returned untouched.
pub fn scatter(mut frame: Frame, params: &ScatterParams, shutter: f32) -> Frame {
    let (width, height) = (frame.width, frame.height);
    frame.velocity = None;
    let (Some(color), Some(depth), Some(prev), Some(next)) = (
        frame.color.take(),
        frame.depth.take(),
        frame.prev.take(),
        frame.next.take(),
    ) else {
        return frame;
    };
    let job = Scatter {
        width,
        height,
        color: &color,
        depth: &depth,
        prev: &prev,
        next: &next,
        params: *params,
        half: 0.5 * shutter as f64,
    };
    let n = width * height;
    let columns = width.div_ceil(TILE_W);

    // How far each block's curves reach; nothing to do if nothing moves.
    let reach = Reach::of(&job);
    if reach.most == 0.0 || n == 0 {
        frame.color = Some(color);
        frame.depth = Some(depth);
        frame.prev = Some(prev);
        frame.next = Some(next);
        return frame;
    }
    // Accumulate and normalise tile by tile, into new planes (curves read the input colours
    // while tiles are written).
    let has_alpha = color.a.is_some();
    // Where every pixel is opaque, alpha sums equal weight sums: cells then hold four sums.
    let opaque = color
        .a
        .as_ref()
        .is_none_or(|a| a.par_iter().all(|&v| v == 1.0));
    // Every tile writes all its pixels: those no curve reaches get the (sanitised) input.
    let mut out: [Vec<f32>; 4] = std::array::from_fn(|_| vec![0.0; n]);
    let [r, g, b, a] = &mut out;
    let strip = TILE_H * width;
    r.par_chunks_mut(strip)
        .zip(g.par_chunks_mut(strip))
        .zip(b.par_chunks_mut(strip))
        .zip(a.par_chunks_mut(strip))
        .enumerate()
        .for_each(|(tile_row, (((r, g), b), a))| {
            let ty0 = tile_row * TILE_H;
            let ty1 = (ty0 + TILE_H).min(height);
            // Each tile's pieces of the strip's rows, R, G, B and A.
            let mut tiles: Vec<Vec<[&mut [f32]; 4]>> =
                (0..columns).map(|_| Vec::with_capacity(TILE_H)).collect();
            let rows = r
                .chunks_mut(width)
                .zip(g.chunks_mut(width))
                .zip(b.chunks_mut(width))
                .zip(a.chunks_mut(width));
            for (((r, g), b), a) in rows {
                let pieces = r
                    .chunks_mut(TILE_W)
                    .zip(g.chunks_mut(TILE_W))
                    .zip(b.chunks_mut(TILE_W))
                    .zip(a.chunks_mut(TILE_W));
                for (tile, (((r, g), b), a)) in tiles.iter_mut().zip(pieces) {
                    tile.push([r, g, b, a]);
                }
            }
            // Tiles of the strip in parallel too (a 1080p frame has only 9 strips).
            tiles
                .into_par_iter()
                .enumerate()
                .for_each(|(column, mut rows)| {
                    let tx0 = column * TILE_W;
                    let rect = [tx0, ty0, (tx0 + TILE_W).min(width), ty1];
                    if opaque {
                        job.tile::<4>(&reach, rect, &mut rows);
                    } else {
                        job.tile::<5>(&reach, rect, &mut rows);
                    }
                });
        });
    let [r, g, b, a] = out;
    frame.color = Some(Color {
        r,
        g,
        b,
        a: has_alpha.then_some(a),
    });
    frame
}

impl Scatter<'_> {
    /// Accumulates the curves reaching one tile and writes its normalised pixels into `rows`
    /// (the tile's pieces of its rows of R, G, B and A), or where no curve reaches the tile,
    /// its input pixels.
    fn tile<const N: usize>(&self, reach: &Reach, rect: [usize; 4], rows: &mut [[&mut [f32]; 4]]) {
        SCRATCH.with_borrow_mut(|scratch| self.tile_in::<N>(reach, rect, rows, scratch));
    }

    fn tile_in<const N: usize>(
        &self,
        reach: &Reach,
        rect: [usize; 4],
        rows: &mut [[&mut [f32]; 4]],
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
        let limit = &mut scratch.limit;
        limit.clear();
        limit.resize(cells, f32::NEG_INFINITY);
        let tolerance = 1.0 + self.params.depth_tolerance;
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
                        let r = reach.pixel[e] as f64;
                        if r == 0.0 || !touches(x as f64 + 0.5, y as f64 + 0.5, r) {
                            continue;
                        }
                        // Moving (its reach is not 0), so its positions are not NaN.
                        let motion = self.positions(x, y, r);
                        if !self.path(e, &motion, &mut path) {
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
                            let mut segment = Segment {
                                acc: &mut *acc,
                                limit,
                                color: &color,
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
            for (y, row) in (ty0..ty1).zip(rows) {
                let span = y * width + tx0..y * width + tx1;
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
        for (y, row) in (ty0..ty1).zip(rows) {
            for x in tx0..tx1 {
                let cell = &acc[(origin + (x + y * pw) as i64) as usize];
                // An opaque frame's alpha sums are its weight sums.
                let cell = std::array::from_fn(|k| cell[k.min(N - 1)]);
                let value = self.resolve(&cell, x, y, reach);
                for (plane, v) in row.iter_mut().zip(value) {
                    plane[x - tx0] = v;
                }
            }
        }
    }

    /// The output of pixel `i` from its accumulated `cell`.
    fn resolve(&self, cell: &[f64; 5], x: usize, y: usize, reach: &Reach) -> [f32; 4] {
        let i = y * self.width + x;
        let own = self.color(i);
        let total = cell[4];
        if total.is_nan() || total <= 0.0 {
            return own;
        }
        match self.params.normalize {
            Normalize::Paper => {
                let wb = self.params.background_weight.max(0.0) as f64;
                std::array::from_fn(|ch| ((cell[ch] + wb * own[ch] as f64) / (total + wb)) as f32)
            }
            Normalize::Exposure if total < 1.0 => {
                let rest = 1.0 - total;
                let behind = if rest > COVERED {
                    self.behind(x, y, reach)
                } else {
                    own
                };
                std::array::from_fn(|ch| (cell[ch] + rest * behind[ch] as f64) as f32)
            }
            Normalize::Exposure => std::array::from_fn(|ch| (cell[ch] / total) as f32),
        }
    }
}

/// A thread's tile buffers, kept from tile to tile (allocating them afresh for every tile
/// costs a page fault per 4 KiB).
#[derive(Default)]
struct Scratch {
    sums: Vec<f64>,
    limit: Vec<f32>,
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::default();
}

/// One segment of a curve being drawn into a tile's cells.
struct Segment<'a, const N: usize> {
    acc: &'a mut [[f64; N]],
    limit: &'a [f32],
    color: &'a [f64; N],
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

impl<const N: usize> Segment<'_, N> {
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
        }
        if z <= self.limit[j] {
            add(&mut self.acc[j], c.c1 * w, self.color);
        }
    }
}

/// Adds a deposit of weight `w` and colour `color` to an accumulation cell (the colour's
/// last channel is 1: the cell's last is the weight).
#[inline(always)]
fn add<const N: usize>(cell: &mut [f64; N], w: f64, color: &[f64; N]) {
    for (sum, c) in cell.iter_mut().zip(color) {
        *sum += w * c;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::line::draw;

    fn still_frame(w: usize, h: usize) -> Frame {
        let n = w * h;
        let mut f = Frame::new(w, h);
        f.color = Some(Color {
            r: vec![0.25; n],
            g: vec![0.5; n],
            b: vec![1.0; n],
            a: None,
        });
        f.depth = Some(vec![5.0; n]);
        let centres = |axis: usize| -> Vec<f32> {
            (0..n)
                .map(|i| [(i % w) as f32 + 0.5, (i / w) as f32 + 0.5][axis])
                .collect()
        };
        f.prev = Some(Positions {
            x: centres(0),
            y: centres(1),
            z: None,
        });
        f.next = f.prev.clone();
        f
    }

    #[test]
    fn opaque_cells_of_four_sums_give_the_same_bits_as_five() {
        // A curving, shearing motion over two depth layers, opaque: the four-sum cells (alpha
        // sums taken from weight sums) against the five-sum cells, tile by tile.
        let (w, h) = (300, 150);
        let mut f = still_frame(w, h);
        let color = f.color.as_mut().unwrap();
        for i in 0..w * h {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            color.r[i] = (x * 0.37).sin() + 1.0;
            color.g[i] = (y * 0.21).cos();
            color.b[i] = ((x + y) * 0.05).fract();
        }
        color.a = Some(vec![1.0; w * h]);
        f.depth = Some(
            (0..w * h)
                .map(|i| if i % 7 < 3 { 2.0 } else { 8.0 })
                .collect(),
        );
        let (prev, next) = (f.prev.as_mut().unwrap(), f.next.as_mut().unwrap());
        for i in 0..w * h {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            prev.x[i] -= 9.0 + y * 0.05;
            prev.y[i] += 3.0;
            next.x[i] += 7.0;
            next.y[i] += 2.0 + x * 0.02;
        }
        let color = f.color.as_ref().unwrap();
        let depth = f.depth.as_ref().unwrap();
        let mut job = Scatter {
            width: w,
            height: h,
            color,
            depth,
            prev: f.prev.as_ref().unwrap(),
            next: f.next.as_ref().unwrap(),
            params: ScatterParams::default(),
            half: 0.5,
        };
        let reach = Reach::of(&job);
        // A tile's output bits (NaN where it writes nothing).
        fn bits<const N: usize>(job: &Scatter, reach: &Reach, rect: [usize; 4]) -> Vec<u32> {
            let [x0, y0, x1, y1] = rect;
            let mut planes = vec![[vec![f32::NAN; x1 - x0], vec![], vec![], vec![]]; y1 - y0];
            for row in &mut planes {
                for k in 1..4 {
                    row[k] = row[0].clone();
                }
            }
            let mut rows: Vec<[&mut [f32]; 4]> = planes
                .iter_mut()
                .map(|[r, g, b, a]| [&mut r[..], &mut g[..], &mut b[..], &mut a[..]])
                .collect();
            job.tile::<N>(reach, rect, &mut rows);
            planes
                .iter()
                .flatten()
                .flatten()
                .map(|v| v.to_bits())
                .collect()
        }
        for normalize in [Normalize::Exposure, Normalize::Paper] {
            job.params.normalize = normalize;
            for rect in [[0, 0, 256, 128], [256, 0, 300, 128], [0, 128, 256, 150]] {
                let four = bits::<4>(&job, &reach, rect);
                assert!(four.iter().all(|&v| !f32::from_bits(v).is_nan()));
                assert_eq!(
                    four,
                    bits::<5>(&job, &reach, rect),
                    "{normalize:?} {rect:?}"
                );
            }
        }
    }

    #[test]
    fn a_million_curves_of_one_colour_give_that_colour() {
        // A million short random segments crossing pixel (1, 1) of a 3×3 frame of the same
        // colour, accumulated and resolved as `scatter` does.
        let f = still_frame(3, 3);
        let own = [0.25f64, 0.5, 1.0, 1.0];
        let (color, depth) = (f.color.as_ref().unwrap(), f.depth.as_ref().unwrap());
        for normalize in [Normalize::Paper, Normalize::Exposure] {
            let job = Scatter {
                width: 3,
                height: 3,
                color,
                depth,
                prev: f.prev.as_ref().unwrap(),
                next: f.next.as_ref().unwrap(),
                params: ScatterParams {
                    normalize,
                    ..ScatterParams::default()
                },
                half: 0.25,
            };
            let mut cell = [0.0f64; 5];
            let mut crossings = 0;
            for k in 0..1_000_000u64 {
                let r = |j: u64| crate::truth::sample::hash01(3, k, j, 0);
                let a = [1.0 + r(0), 1.0 + r(1)];
                let b = [a[0] + 3.0 * (r(2) - 0.5), a[1] + 3.0 * (r(3) - 0.5)];
                let clip = Clip {
                    x0: 1,
                    y0: 1,
                    x1: 2,
                    y1: 2,
                };
                // A weight that varies from curve to curve, as exposure shares do.
                let weight = 0.01 + r(4);
                let mut crossed = false;
                draw(a, b, clip, |_, _, c, _| {
                    add(
                        &mut cell,
                        c * weight,
                        &[own[0], own[1], own[2], own[3], 1.0],
                    );
                    crossed = true;
                });
                crossings += crossed as usize;
            }
            assert!(crossings >= 900_000, "{crossings}");
            let got = job.resolve(&cell, 1, 1, &Reach::of(&job));
            for ch in 0..4 {
                let want = own[ch] as f32;
                assert!(
                    ((got[ch] - want) / want).abs() <= 1e-5,
                    "{normalize:?}: {} vs {want}",
                    got[ch]
                );
            }
        }
    }
}
