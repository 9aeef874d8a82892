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
//! Determinism: output pixels are accumulated tile by tile; each tile visits the curves that
//! reach it in pixel order, in f64. Curves are binned to tiles by fixed bands of rows, never by
//! thread, so the sums run in the same order for any thread count. f64 also keeps a million
//! overlapping deposits of one colour at that colour (f32 would drift by ~1e-4).
//!
//! Numerics: NaN colour reads as 0 and colour is clamped to ±[`HUGE`]; NaN positions make a
//! pixel still, infinite ones are clamped to ±[`FAR`] px; NaN or negative depth is far or 0; a
//! curve longer than 2·`max_blur` px is scaled about p(0) to that length, which bounds the
//! work per curve. Output is finite and, as a weighted average with non-negative weights,
//! within the per-channel range of the input colours.

use rayon::prelude::*;

use super::curve::{length, Arc, Bezier, Point};
use super::line::{draw, Clip};
use crate::frame::{Color, Frame, Positions};

/// Colour magnitudes beyond this are clamped.
pub const HUGE: f32 = 1e30;
/// Positions beyond this many pixels are clamped (still far beyond any image, and well inside
/// f64's exact integers).
pub const FAR: f64 = 1e12;
/// A pixel whose curve stays within this many pixels of p(0) over the shutter is still: its
/// streak would be under half a pixel.
pub const STILL: f64 = 0.25;
/// The most segments a curve is cut into.
pub const MOST_SEGMENTS: usize = 64;
/// Output tiles are this many pixels square.
const TILE: usize = 64;
/// Curves are binned by bands of this many rows.
const BAND: usize = 16;
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

/// How accumulated curves and the pixel's own colour combine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Normalize {
    /// Eq. 4 with background weight w_b.
    Paper,
    /// Deposits as shares of the exposure, the rest filled with what lies behind.
    Exposure,
}

/// The curve through the three positions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// The paper's quadratic Bézier.
    Bezier,
    /// A circular arc where the points turn, else the Bézier.
    Arc,
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
    /// Largest blur radius in pixels: a curve is at most twice this long.
    pub max_blur: f32,
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
            max_blur: 128.0,
            flatness: 0.1,
            depth_tolerance: 0.02,
        }
    }
}

fn sanitize_color(v: f32) -> f32 {
    if v.is_nan() {
        0.0
    } else {
        v.clamp(-HUGE, HUGE)
    }
}

/// Depth as a comparable value: NaN is far, negative is 0.
fn sanitize_depth(z: f32) -> f32 {
    if z.is_nan() {
        f32::INFINITY
    } else {
        z.max(0.0)
    }
}

fn position(v: f32) -> Option<f64> {
    (!v.is_nan()).then(|| (v as f64).clamp(-FAR, FAR))
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
    color: [f64; 4],
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
            sanitize_color(self.color.r[i]),
            sanitize_color(self.color.g[i]),
            sanitize_color(self.color.b[i]),
            self.color.a.as_ref().map_or(1.0, |a| sanitize_color(a[i])),
        ]
    }

    /// p(-1), p(0), p(+1) of a moving pixel; `None` where it is still (or its positions are
    /// NaN).
    fn motion(&self, i: usize) -> Option<(Point, Point, Point)> {
        let now = [(i % self.width) as f64 + 0.5, (i / self.width) as f64 + 0.5];
        let prev = [position(self.prev.x[i])?, position(self.prev.y[i])?];
        let next = [position(self.next.x[i])?, position(self.next.y[i])?];
        (self.extent(prev, now, next) >= STILL).then_some((prev, now, next))
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

    /// The curve of pixel `i` inside the shutter, or `None` if it is still.
    fn path(&self, i: usize) -> Option<Path> {
        let (prev, now, next) = self.motion(i)?;
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
        let mut path = Path {
            segments,
            points: [[0.0; 2]; MOST_SEGMENTS + 1],
            weights: [0.0; MOST_SEGMENTS + 1],
            depths: [0.0; MOST_SEGMENTS + 1],
            color: self.color(i).map(f64::from),
        };
        let z0 = sanitize_depth(self.depth[i]);
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
        for k in 0..=segments {
            let t = t0 + (t1 - t0) * k as f64 / segments as f64;
            path.points[k] = match &arc {
                Some(arc) => arc.at_time(t),
                None => bezier.at(0.5 * (t + 1.0)),
            };
            path.weights[k] = self.weight(t);
            path.depths[k] = depth_at.map_or(z0, |f| f(t));
            if k > 0 {
                total += length([
                    path.points[k][0] - path.points[k - 1][0],
                    path.points[k][1] - path.points[k - 1][1],
                ]);
            }
        }
        if total.is_nan() || total <= 1e-9 {
            return None;
        }
        let longest = 2.0 * p.max_blur.max(0.5) as f64;
        if total > longest {
            let f = longest / total;
            for q in &mut path.points[..=segments] {
                *q = [now[0] + f * (q[0] - now[0]), now[1] + f * (q[1] - now[1])];
            }
        }
        if p.normalize == Normalize::Exposure {
            // The curve's deposits add up to Σ length × mean weight of each segment (weights
            // are linear along a segment): divide so they add up to 1.
            let mut sum = 0.0;
            for k in 0..segments {
                let (a, b) = (path.points[k], path.points[k + 1]);
                let l = length([b[0] - a[0], b[1] - a[1]]);
                sum += l * 0.5 * (path.weights[k] + path.weights[k + 1]);
            }
            if !(sum > 0.0 && sum.is_finite()) {
                return None;
            }
            for w in &mut path.weights[..=segments] {
                *w /= sum;
            }
        }
        Some(path)
    }

    /// Pixels the path can deposit into (inclusive), clamped to the image; `None` if none.
    fn reach(&self, path: &Path) -> Option<[usize; 4]> {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for q in &path.points[..=path.segments] {
            for d in 0..2 {
                lo[d] = lo[d].min(q[d]);
                hi[d] = hi[d].max(q[d]);
            }
        }
        // A segment deposits at most one pixel beside itself.
        let x0 = (lo[0].floor() - 1.0).max(0.0);
        let y0 = (lo[1].floor() - 1.0).max(0.0);
        let x1 = (hi[0].floor() + 1.0).min((self.width - 1) as f64);
        let y1 = (hi[1].floor() + 1.0).min((self.height - 1) as f64);
        (x0 <= x1 && y0 <= y1).then_some([x0 as usize, y0 as usize, x1 as usize, y1 as usize])
    }

    /// The colour behind moving pixel `i`: the nearest farther surface along its motion
    /// (either way; the average if both), else its own colour.
    fn behind(&self, i: usize) -> [f32; 4] {
        let own = self.color(i);
        let Some((prev, now, next)) = self.motion(i) else {
            return own;
        };
        let v = [next[0] - prev[0], next[1] - prev[1]];
        let l = length(v);
        if l.is_nan() || l <= 0.0 {
            return own;
        }
        let dir = [v[0] / l, v[1] / l];
        let limit = sanitize_depth(self.depth[i]) * (1.0 + self.params.depth_tolerance);
        let steps = (self
            .extent(prev, now, next)
            .min(2.0 * self.params.max_blur as f64)
            + 2.0)
            .ceil() as usize;
        let mut sum = [0.0f64; 4];
        let mut found = 0;
        for side in [1.0, -1.0] {
            for k in 1..=steps {
                let x = now[0] + side * k as f64 * dir[0];
                let y = now[1] + side * k as f64 * dir[1];
                if !(x >= 0.0 && y >= 0.0 && x < self.width as f64 && y < self.height as f64) {
                    break;
                }
                let j = y as usize * self.width + x as usize;
                if sanitize_depth(self.depth[j]) > limit {
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

/// Curves binned to tiles for one band of rows: emitter indices sorted by tile (in pixel
/// order within a tile), and where each tile's run starts.
struct Bins {
    emitters: Vec<u32>,
    starts: Vec<u32>,
}

impl Bins {
    fn of(&self, tile: usize) -> &[u32] {
        &self.emitters[self.starts[tile] as usize..self.starts[tile + 1] as usize]
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
    let shutter = if shutter.is_finite() {
        shutter.clamp(0.0, 1.0)
    } else {
        0.0
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
    let columns = width.div_ceil(TILE);
    let tiles = columns * height.div_ceil(TILE);

    // Bin every moving pixel's curve to the tiles it reaches, band by band.
    let bins: Vec<Bins> = (0..height.div_ceil(BAND))
        .into_par_iter()
        .map(|band| {
            let mut pairs: Vec<(u32, u32)> = Vec::new();
            for i in band * BAND * width..((band + 1) * BAND).min(height) * width {
                let Some(path) = job.path(i) else { continue };
                let Some([x0, y0, x1, y1]) = job.reach(&path) else {
                    continue;
                };
                for row in y0 / TILE..=y1 / TILE {
                    for column in x0 / TILE..=x1 / TILE {
                        pairs.push(((row * columns + column) as u32, i as u32));
                    }
                }
            }
            pairs.sort_by_key(|&(tile, _)| tile); // stable: pixel order within a tile
            let mut starts = vec![0u32; tiles + 1];
            for &(tile, _) in &pairs {
                starts[tile as usize + 1] += 1;
            }
            for t in 0..tiles {
                starts[t + 1] += starts[t];
            }
            Bins {
                emitters: pairs.into_iter().map(|(_, i)| i).collect(),
                starts,
            }
        })
        .collect();
    if bins.iter().all(|b| b.emitters.is_empty()) || n == 0 {
        frame.color = Some(color);
        frame.depth = Some(depth);
        frame.prev = Some(prev);
        frame.next = Some(next);
        return frame;
    }

    // Accumulate and normalise tile by tile, into fresh planes.
    let has_alpha = color.a.is_some();
    let mut out: [Vec<f32>; 4] = std::array::from_fn(|_| vec![0.0f32; n]);
    let [r, g, b, a] = &mut out;
    let strip = TILE * width;
    r.par_chunks_mut(strip)
        .zip(g.par_chunks_mut(strip))
        .zip(b.par_chunks_mut(strip))
        .zip(a.par_chunks_mut(strip))
        .enumerate()
        .for_each(|(tile_row, (((r, g), b), a))| {
            let mut planes = [r, g, b, a];
            for column in 0..columns {
                let tile = tile_row * columns + column;
                let (tx0, ty0) = (column * TILE, tile_row * TILE);
                let (tx1, ty1) = ((tx0 + TILE).min(width), (ty0 + TILE).min(height));
                job.tile(&bins, tile, [tx0, ty0, tx1, ty1], &mut planes);
            }
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
    /// Accumulates the curves reaching one tile and writes its normalised pixels into
    /// `planes` (the tile's strip of rows).
    fn tile(&self, bins: &[Bins], tile: usize, rect: [usize; 4], planes: &mut [&mut [f32]; 4]) {
        let [tx0, ty0, tx1, ty1] = rect;
        let tw = tx1 - tx0;
        let width = self.width;
        let mut acc = vec![[0.0f64; 5]; tw * (ty1 - ty0)];
        let clip = Clip {
            x0: tx0 as i64,
            y0: ty0 as i64,
            x1: tx1 as i64,
            y1: ty1 as i64,
        };
        let tolerance = 1.0 + self.params.depth_tolerance;
        for band in bins {
            for &e in band.of(tile) {
                let Some(path) = self.path(e as usize) else {
                    continue;
                };
                for k in 0..path.segments {
                    let (w0, w1) = (path.weights[k], path.weights[k + 1]);
                    let (z0, z1) = (path.depths[k], path.depths[k + 1]);
                    draw(path.points[k], path.points[k + 1], clip, |x, y, c, u| {
                        let (x, y) = (x as usize, y as usize);
                        let z = z0 + (z1 - z0) * u as f32;
                        if z > sanitize_depth(self.depth[y * width + x]) * tolerance {
                            return;
                        }
                        let w = c * (w0 + (w1 - w0) * u);
                        add(&mut acc[(y - ty0) * tw + (x - tx0)], w, &path.color);
                    });
                }
            }
        }
        for y in ty0..ty1 {
            for x in tx0..tx1 {
                let i = y * width + x;
                let value = self.resolve(&acc[(y - ty0) * tw + (x - tx0)], i);
                // The strip starts at the tile's first row.
                let o = (y - ty0) * width + x;
                for (plane, v) in planes.iter_mut().zip(value) {
                    plane[o] = v;
                }
            }
        }
    }

    /// The output of pixel `i` from its accumulated `cell`.
    fn resolve(&self, cell: &[f64; 5], i: usize) -> [f32; 4] {
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
                let behind = if rest > COVERED { self.behind(i) } else { own };
                std::array::from_fn(|ch| (cell[ch] + rest * behind[ch] as f64) as f32)
            }
            Normalize::Exposure => std::array::from_fn(|ch| (cell[ch] / total) as f32),
        }
    }
}

/// Adds a deposit of weight `w` and colour `color` to an accumulation cell.
#[inline]
fn add(cell: &mut [f64; 5], w: f64, color: &[f64; 4]) {
    for ch in 0..4 {
        cell[ch] += w * color[ch];
    }
    cell[4] += w;
}

#[cfg(test)]
mod tests {
    use super::*;

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
                    add(&mut cell, c * weight, &own);
                    crossed = true;
                });
                crossings += crossed as usize;
            }
            assert!(crossings >= 900_000, "{crossings}");
            let got = job.resolve(&cell, 4);
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
