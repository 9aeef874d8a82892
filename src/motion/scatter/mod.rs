//! scatter — the curve scatter of Guertin & Nowrouzezahrai, *High Performance Non-linear
//! Moving Blur* (§3), on the CPU.
//!
//! Every moving pixel draws its motion curve through p(-1), p(0), p(+1) ([`super::curve`]),
//! the part inside the shutter only, as line segments ([`super::line`]) into an accumulation
//! buffer: its colour times a weight into RGBA, the weight into a fifth channel. A depth test
//! against the frame's depth (no depth writes) lets curves pass behind nearer surfaces. A
//! final pass normalises each pixel.
//!
//! Stages, in the order a GPU would dispatch them: [`reach`] (how far each block's curves can
//! deposit) → [`accumulate`] (each tile draws the curves that reach it into f64 cells) →
//! [`resolve`] (each pixel's output from its cell, by the normalisation).
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

mod accumulate;
mod reach;
mod resolve;

use rayon::prelude::*;

use super::curve::{length, Point};
use crate::frame::{Color, Frame, Positions};
use reach::Reach;

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
pub(crate) const COVERED: f64 = 1e-3;

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
struct Moving {
    prev: Point,
    now: Point,
    next: Point,
    reach: f64,
}

/// Everything scatter's stages read besides their buffers, as plain numbers: the shape of the
/// uniform of its GPU twin, `ScatterConfig` in src/gpu/scatter.wgsl (keep the two in sync;
/// the size test here and the field test in src/gpu/scatter.rs guard the layout).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct ScatterConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// Fraction of the frame interval the shutter is open.
    pub shutter: f32,
    /// Where the exposure sits about the frame, in exposures ([`super::Shutter::offset`]):
    /// the curve is kept over t ∈ [(offset − ½)·shutter, (offset + ½)·shutter].
    pub offset: f32,
    /// Line segments per curve, at most, in 1..=[`MOST_SEGMENTS`].
    pub segments: u32,
    /// σ of the Gaussian weight, in units of s.
    pub sigma: f32,
    /// 1 for the paper's Gaussian weight along the curve, 0 for the box.
    pub gaussian: u32,
    /// w_b of the paper's normalisation.
    pub background_weight: f32,
    /// 1 for the exposure normalisation, 0 for the paper's eq. 4.
    pub exposure: u32,
    /// 1 for circular arcs where the motion turns, 0 for the paper's Bézier.
    pub arc: u32,
    /// The longest a curve may be, pixels.
    pub max_curve: f32,
    /// Fewer segments where they stray at most this far from the curve, pixels.
    pub flatness: f32,
    /// A curve passes a pixel whose depth is at least its own / (1 + this).
    pub depth_tolerance: f32,
}

impl ScatterConfig {
    pub fn new(
        width: usize,
        height: usize,
        params: &ScatterParams,
        shutter: impl Into<super::Shutter>,
    ) -> Self {
        let shutter = shutter.into();
        ScatterConfig {
            width: width as u32,
            height: height as u32,
            shutter: shutter.open,
            offset: shutter.offset,
            segments: params.segments.clamp(1, MOST_SEGMENTS) as u32,
            sigma: params.sigma,
            gaussian: (params.weight == Weight::Gaussian) as u32,
            background_weight: params.background_weight.max(0.0),
            exposure: (params.normalize == Normalize::Exposure) as u32,
            arc: (params.curve == CurveKind::Arc) as u32,
            max_curve: params.max_curve,
            flatness: params.flatness,
            depth_tolerance: params.depth_tolerance,
        }
    }
}

/// One frame's scatter: its input buffers and config.
struct Scatter<'a> {
    width: usize,
    height: usize,
    color: &'a Color,
    depth: &'a [f32],
    prev: &'a Positions,
    next: &'a Positions,
    config: ScatterConfig,
    /// The exposure: t ∈ [t0, t1] (frames from the frame's instant).
    t0: f64,
    t1: f64,
    /// The farthest the exposure gets from the frame's instant, max(|t0|, |t1|): half the
    /// shutter when it is centred.
    half: f64,
    /// The middle of the exposure, (t0 + t1)/2: where the Gaussian weight peaks.
    middle: f64,
}

impl<'a> Scatter<'a> {
    fn new(
        config: ScatterConfig,
        color: &'a Color,
        depth: &'a [f32],
        prev: &'a Positions,
        next: &'a Positions,
    ) -> Self {
        let (t0, t1) = super::Shutter {
            open: config.shutter,
            offset: config.offset,
        }
        .interval();
        let (t0, t1) = (t0 as f64, t1 as f64);
        Scatter {
            width: config.width as usize,
            height: config.height as usize,
            color,
            depth,
            prev,
            next,
            config,
            t0,
            t1,
            half: t0.abs().max(t1.abs()),
            middle: 0.5 * (t0 + t1),
        }
    }
}

impl Scatter<'_> {
    #[inline]
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
    fn motion(&self, x: usize, y: usize) -> Option<Moving> {
        let i = y * self.width + x;
        let now = [x as f64 + 0.5, y as f64 + 0.5];
        let prev = [self.prev.x[i] as f64, self.prev.y[i] as f64];
        let next = [self.next.x[i] as f64, self.next.y[i] as f64];
        let extent = self.extent(prev, now, next);
        (extent >= STILL).then_some(Moving {
            prev,
            now,
            next,
            // What the scaling to max_curve leaves, and the pixel a segment reaches beside it.
            reach: extent.min(self.config.max_curve as f64) + 1.0,
        })
    }

    /// The positions of a pixel known to move, with its reach `r` from the reach pass
    /// (skips [`Scatter::motion`]'s bound).
    #[inline]
    fn positions(&self, x: usize, y: usize, reach: f64) -> Moving {
        let i = y * self.width + x;
        Moving {
            prev: [self.prev.x[i] as f64, self.prev.y[i] as f64],
            now: [x as f64 + 0.5, y as f64 + 0.5],
            next: [self.next.x[i] as f64, self.next.y[i] as f64],
            reach,
        }
    }

    /// A bound on how far the curve strays from p(0) during the exposure: with
    /// p(t) = p0 + t·v + t²·a, at most h·|v| + h²·|a| for |t| ≤ h (h = `half`, the farthest
    /// the exposure gets from the frame).
    #[inline]
    fn extent(&self, prev: Point, now: Point, next: Point) -> f64 {
        let v = [0.5 * (next[0] - prev[0]), 0.5 * (next[1] - prev[1])];
        let a = [
            0.5 * (next[0] + prev[0]) - now[0],
            0.5 * (next[1] + prev[1]) - now[1],
        ];
        self.half * length(v) + self.half * self.half * length(a)
    }

    #[inline]
    fn weight(&self, t: f64) -> f64 {
        if self.config.gaussian == 0 {
            1.0
        } else {
            let d = 0.5 * (t - self.middle); // s − s(middle), μ at the exposure's middle
            let sigma = self.config.sigma as f64;
            (-d * d / (2.0 * sigma * sigma)).exp()
        }
    }
}

/// Applies the filter: [`reach`] → [`accumulate`] → [`resolve`]. The frame must hold colour,
/// depth, prev and next; the output holds colour alone. A frame in which nothing moves keeps
/// its colour untouched.
pub fn scatter(
    mut frame: Frame,
    params: &ScatterParams,
    shutter: impl Into<super::Shutter>,
) -> Frame {
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
    let config = ScatterConfig::new(width, height, params, shutter);
    let job = Scatter::new(config, &color, &depth, &prev, &next);
    let n = width * height;
    let columns = width.div_ceil(TILE_W);

    // How far each block's curves reach; nothing to do if nothing moves.
    let reach = Reach::of(&job);
    if reach.most == 0.0 || n == 0 {
        // Colour alone, as on every path.
        frame.color = Some(color);
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
    // Every tile writes all its pixels: those no curve reaches get their input.
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

#[cfg(test)]
mod tests {
    use super::accumulate::add;
    use super::*;
    use crate::motion::line::{draw, Clip};

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
    fn the_config_is_thirteen_plain_words() {
        // Uploaded as one uniform by the GPU twin: thirteen 4-byte fields, no padding.
        assert_eq!(std::mem::size_of::<ScatterConfig>(), 52);
        let many = ScatterParams {
            segments: 1000,
            background_weight: -1.0,
            ..ScatterParams::default()
        };
        let c = ScatterConfig::new(4, 3, &many, 0.5);
        assert_eq!(
            (c.segments, c.background_weight),
            (MOST_SEGMENTS as u32, 0.0)
        );
        // The defaults: exposure, box, Bézier.
        assert_eq!((c.exposure, c.gaussian, c.arc), (1, 0, 0));
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
        let config = ScatterConfig::new(w, h, &ScatterParams::default(), 1.0);
        let (prev, next) = (f.prev.as_ref().unwrap(), f.next.as_ref().unwrap());
        let mut job = Scatter::new(config, color, depth, prev, next);
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
            job.config.exposure = (normalize == Normalize::Exposure) as u32;
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
            let params = ScatterParams {
                normalize,
                ..ScatterParams::default()
            };
            let config = ScatterConfig::new(3, 3, &params, 0.5);
            let (prev, next) = (f.prev.as_ref().unwrap(), f.next.as_ref().unwrap());
            let job = Scatter::new(config, color, depth, prev, next);
            let mut cell = [0.0f64; 5];
            let mut crossings = 0;
            for k in 0..1_000_000u64 {
                let r = |j: u64| crate::lab::truth::sample::hash01(3, k, j, 0);
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
