//! scatter — the curve scatter of Guertin & Nowrouzezahrai, *High Performance Non-linear
//! Moving Blur* (§3), on the CPU.
//!
//! Every moving pixel draws its motion curve through p(-1), p(0), p(+1) ([`super::curve`]),
//! the part inside the shutter only, as line segments ([`super::line`]) into an accumulation
//! buffer: its colour times a weight into RGBA, the weight into a fifth channel. A depth test
//! against the frame's depth (no depth writes) lets curves pass behind nearer surfaces. A
//! final pass normalises each pixel.
//!
//! Stages, in the order a GPU would dispatch them: [`fringe`] (the still pixels at a
//! silhouette: their still surface unmixed, the moving surface's sliver of them given a curve
//! of its own; on the CPU for every backend) → [`reach`] (how far each block's curves can
//! deposit) → [`accumulate`] (each tile draws the curves that reach it into f64 cells) →
//! [`resolve`] (each pixel's output from its cell, by the normalisation).
//!
//! Two normalisations:
//! - [`Normalize::Paper`], eq. 4: `c' = (A.rgba + w_b·c) / (A.w + w_b)`, each pixel a curve
//!   crosses weighted by its coverage times the weight along the curve.
//! - [`Normalize::Exposure`] (beyond the paper; docs/DESIGN.md "where the paper's weighting goes
//!   wrong"): each curve deposits its *share of the exposure*, coverage / curve length (times
//!   the normalised weight along the curve), so A.w is the fraction of the shutter interval a
//!   pixel is covered by moving surfaces. A pixel covered less than the whole interval shows
//!   what lies behind for the rest: its own colour where it does not move, and where it does
//!   (a moving surface revealing what was behind it), the colour of the nearest farther
//!   surface along its motion, or, if none is found, the part of its streak hidden behind a
//!   nearer surface read a streak's length back and the part past the frame's edge read on
//!   the border ([`resolve`]'s `unseen`), else its own colour. Covered more than once
//!   (overlapping moving surfaces), the deposits are averaged.
//!
//! Weights along the curve, by s ∈ [0, 1] (s = ½ at the frame): the paper's Gaussian
//! (μ = ½, σ) and the box (every instant of the exposure counts the same: the ideal shutter).
//! Weights are linear between segment ends.
//!
//! Determinism and work: output pixels are accumulated tile by tile, in f64. A first pass
//! records, per 16×16 block of pixels, how far its curves can reach (a cheap bound where it
//! holds, the Bézier within `max_curve`; else the farthest point of the curve as it is drawn);
//! each tile then visits the blocks that can reach it, and in them the pixels
//! whose own bound reaches it, always in the same order, and draws only those curves, clipped
//! to the tile. So the sums run in the same order for any thread count, no list of curves is
//! stored, and a curve is built about 1.4 times on average (30 px streaks, 256×128 tiles;
//! an arc, or a Bézier longer than `max_curve`, once more, by `reach`).
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
pub mod config;
pub mod fringe;
mod job;
mod path;
mod reach;
mod resolve;

use rayon::prelude::*;

use crate::frame::{Color, Frame, Positions};
use crate::motion::shutter::Shutter;
use crate::stages::Cpu;
pub use config::{
    CurveKind, Normalize, ScatterConfig, ScatterParams, Weight, MOST_SEGMENTS, STILL,
};
use config::{TILE_H, TILE_W};
pub use fringe::fringe;
pub use job::Fringe;
use job::Scatter;
use reach::Reach;

/// Applies the filter: [`reach`] → [`accumulate`] → [`resolve`]. The frame must hold colour,
/// depth, prev and next; the output holds colour alone. A frame in which nothing moves keeps
/// its colour untouched.
pub fn scatter(frame: Frame, params: &ScatterParams, shutter: impl Into<Shutter>) -> Frame {
    scatter_with(frame, params, shutter, &Cpu)
}

/// Scatter's stages that a backend may run elsewhere: reach → accumulate → resolve, as one
/// (the GPU keeps the curves' sums on the device between them). The default is the CPU's
/// [`stages`], the reference; [`Cpu`] takes it, and the GPU (`crate::gpu::motion`) overrides
/// it with its twin, which must return the same colour within the tolerance its parity test
/// states (tests/gpu_scatter.rs).
pub trait Stages {
    /// [`stages`].
    fn stages(
        &self,
        config: &ScatterConfig,
        color: Color,
        depth: &[f32],
        positions: [&Positions; 2],
        fringe: &Fringe,
    ) -> Color {
        stages(config, color, depth, positions, fringe)
    }

    /// [`stages`] with `layers` (light layers beside the beauty) blurred in place with the
    /// beauty's weights: on the CPU carried through the same curves ([`stages_carrying`]).
    fn stages_carrying(
        &self,
        config: &ScatterConfig,
        color: Color,
        depth: &[f32],
        positions: [&Positions; 2],
        fringe: &Fringe,
        layers: &mut [Color],
    ) -> Color {
        stages_carrying(config, color, depth, positions, fringe, layers)
    }
}

impl Stages for Cpu {}

/// [`scatter`] with its [`Stages`] run by `stages` (the CPU's, [`Cpu`], or a backend's twin);
/// the config is made here from the frame's size, so it always matches the frame.
pub fn scatter_with(
    frame: Frame,
    params: &ScatterParams,
    shutter: impl Into<Shutter>,
    stages: &impl Stages,
) -> Frame {
    scatter_layers_with(frame, &mut [], params, shutter, stages)
}

/// [`scatter_with`], and `layers` (light layers beside the beauty) blurred in place with
/// exactly the beauty's weights ([`Stages::stages_carrying`]); their alpha is the beauty's
/// and is left as it came.
pub fn scatter_layers_with(
    mut frame: Frame,
    layers: &mut [Color],
    params: &ScatterParams,
    shutter: impl Into<Shutter>,
    stages: &impl Stages,
) -> Frame {
    let (width, height) = (frame.width, frame.height);
    frame.velocity = None;
    let (Some(mut color), Some(depth), Some(prev), Some(next)) = (
        frame.color.take(),
        frame.depth.take(),
        frame.prev.take(),
        frame.next.take(),
    ) else {
        return frame;
    };
    let config = ScatterConfig::new(width, height, params, shutter);
    // Colour alone, as on every path.
    frame.color = Some(if width * height == 0 {
        color
    } else {
        // The fringe's stage runs here for every backend (its matte on the CPU).
        let fringe = fringe(&config, &mut color, layers, &depth, [&prev, &next]);
        if layers.is_empty() {
            stages.stages(&config, color, &depth, [&prev, &next], &fringe)
        } else {
            stages.stages_carrying(&config, color, &depth, [&prev, &next], &fringe, layers)
        }
    });
    frame
}

/// The three stages on the CPU after [`fringe`] (whose colour and fringe they take): [`reach`],
/// then where anything moves [`accumulate`] and [`resolve`] tile by tile into new planes;
/// the colour as it came where nothing moves.
pub fn stages(
    config: &ScatterConfig,
    color: Color,
    depth: &[f32],
    positions: [&Positions; 2],
    fringe: &Fringe,
) -> Color {
    stages_carrying(config, color, depth, positions, fringe, &mut [])
}

/// [`stages`], carrying the R, G and B planes of `layers` (light layers) through the same
/// curves: each curve deposits their values at its pixel with the weights it deposits the
/// beauty's, into sums of their own beside the beauty's cells, and each pixel resolves them
/// as it resolves the beauty (the same normalisation, the same pixels behind). So a layer
/// comes out with the bits it would get in the beauty's place, at the cost of its sums
/// alone: no curve is built twice.
pub fn stages_carrying(
    config: &ScatterConfig,
    color: Color,
    depth: &[f32],
    [prev, next]: [&Positions; 2],
    fringe: &Fringe,
    layers: &mut [Color],
) -> Color {
    let (width, height) = (config.width as usize, config.height as usize);
    let inputs: Vec<Vec<f32>> = layers
        .iter_mut()
        .flat_map(|l| [&mut l.r, &mut l.g, &mut l.b])
        .map(std::mem::take)
        .collect();
    let mut job = Scatter::new(*config, &color, depth, prev, next);
    job.extra = inputs.iter().map(Vec::as_slice).collect();
    job.fringe = fringe;
    let n = width * height;
    let columns = width.div_ceil(TILE_W);

    // How far each block's curves reach; nothing to do if nothing moves.
    let reach = Reach::of(&job);
    if reach.most == 0.0 || n == 0 {
        drop(job);
        give_back(layers, inputs);
        return color;
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
    let mut out_extra: Vec<Vec<f32>> = inputs.iter().map(|_| vec![0.0; n]).collect();
    let [r, g, b, a] = &mut out;
    let strip = TILE_H * width;
    // The carried planes' strips, strip by strip.
    let mut extra_strips: Vec<Vec<&mut [f32]>> = (0..height.div_ceil(TILE_H))
        .map(|_| Vec::with_capacity(out_extra.len()))
        .collect();
    for plane in out_extra.iter_mut() {
        for (strips, piece) in extra_strips.iter_mut().zip(plane.chunks_mut(strip)) {
            strips.push(piece);
        }
    }
    r.par_chunks_mut(strip)
        .zip(g.par_chunks_mut(strip))
        .zip(b.par_chunks_mut(strip))
        .zip(a.par_chunks_mut(strip))
        .zip(extra_strips)
        .enumerate()
        .for_each(|(tile_row, ((((r, g), b), a), extra))| {
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
            // The same for the carried planes: per tile, per row, each plane's piece.
            let mut carried: Vec<Vec<Vec<&mut [f32]>>> =
                (0..columns).map(|_| Vec::with_capacity(TILE_H)).collect();
            for _ in ty0..ty1 {
                for tile in carried.iter_mut() {
                    tile.push(Vec::with_capacity(extra.len()));
                }
            }
            for plane in extra {
                for (row, piece) in plane.chunks_mut(width).enumerate() {
                    for (tile, piece) in carried.iter_mut().zip(piece.chunks_mut(TILE_W)) {
                        tile[row].push(piece);
                    }
                }
            }
            // Tiles of the strip in parallel too (a 1080p frame has only 9 strips).
            tiles.into_par_iter().zip(carried).enumerate().for_each(
                |(column, (mut rows, mut carried))| {
                    let tx0 = column * TILE_W;
                    let rect = [tx0, ty0, (tx0 + TILE_W).min(width), ty1];
                    if opaque {
                        job.tile::<4>(&reach, rect, &mut rows, &mut carried);
                    } else {
                        job.tile::<5>(&reach, rect, &mut rows, &mut carried);
                    }
                },
            );
        });
    drop(job);
    give_back(layers, out_extra);
    if !layers.is_empty() {
        // Each thread's sums of the carried planes are dropped with the frame: kept, every
        // thread of the pool would hold a tile's worth of them (3.5 % of the carried planes
        // each) until it ends.
        accumulate::free_carried_sums();
    }
    let [r, g, b, a] = out;
    Color {
        r,
        g,
        b,
        a: has_alpha.then_some(a),
    }
}

/// `planes` (three a layer, R, G, B) put back into `layers`.
fn give_back(layers: &mut [Color], planes: Vec<Vec<f32>>) {
    let mut planes = planes.into_iter();
    for layer in layers {
        for plane in [&mut layer.r, &mut layer.g, &mut layer.b] {
            *plane = planes.next().expect("three planes a layer");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::accumulate::add;
    use super::*;
    use crate::motion::line::{draw, Clip};
    use crate::numeric::close_relative;

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
            let mut carried: Vec<Vec<&mut [f32]>> = (y0..y1).map(|_| Vec::new()).collect();
            job.tile::<N>(reach, rect, &mut rows, &mut carried);
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
    fn carried_layers_get_the_bits_they_get_in_the_beautys_place() {
        // A block moving over a still background (so the exposure normalisation fills what
        // the block uncovers from behind), with and without alpha, each normalisation: a
        // layer carried through the beauty's curves must come out bit for bit as it does
        // blurred alone in the beauty's place, and the beauty as it does with no layer.
        let (w, h) = (300, 150);
        let mut f = still_frame(w, h);
        let moving = |i: usize| (100..200).contains(&(i % w)) && (30..120).contains(&(i / w));
        let wave = |i: usize, k: f32| (i as f32 * k).sin() + 1.0;
        let color = f.color.as_mut().unwrap();
        for i in 0..w * h {
            color.r[i] = wave(i, 0.37);
            color.g[i] = wave(i, 0.21);
        }
        f.depth = Some(
            (0..w * h)
                .map(|i| if moving(i) { 2.0 } else { 8.0 })
                .collect(),
        );
        let (prev, next) = (f.prev.as_mut().unwrap(), f.next.as_mut().unwrap());
        for i in (0..w * h).filter(|&i| moving(i)) {
            prev.x[i] -= 12.0;
            next.x[i] += 9.0;
            next.y[i] += 3.0;
        }
        let layer = |k: f32, alpha: &Option<Vec<f32>>| Color {
            r: (0..w * h).map(|i| wave(i, k)).collect(),
            g: (0..w * h).map(|i| wave(i, 2.0 * k)).collect(),
            b: vec![0.125; w * h],
            a: alpha.clone(),
        };
        let bits = |plane: &[f32]| plane.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        for alpha in [
            None,
            Some((0..w * h).map(|i| wave(i, 0.05) / 2.0).collect()),
        ] {
            f.color.as_mut().unwrap().a = alpha.clone();
            for normalize in [Normalize::Paper, Normalize::Exposure] {
                let params = ScatterParams {
                    normalize,
                    ..ScatterParams::default()
                };
                let mut layers = [layer(0.11, &alpha), layer(0.07, &alpha)];
                let carried = scatter_layers_with(f.clone(), &mut layers, &params, 1.0, &Cpu);
                let beauty = scatter(f.clone(), &params, 1.0).color.unwrap();
                let got = carried.color.unwrap();
                assert_eq!(bits(&got.r), bits(&beauty.r), "{normalize:?}");
                assert_eq!(bits(&got.b), bits(&beauty.b), "{normalize:?}");
                // Each layer alone in the beauty's place, with the beauty's fringe (its
                // matte is the beauty's: the layers unmixed with its factors).
                let config = ScatterConfig::new(w, h, &params, 1.0);
                let depth = f.depth.as_ref().unwrap();
                let positions = [f.prev.as_ref().unwrap(), f.next.as_ref().unwrap()];
                let mut colour = f.color.clone().unwrap();
                let mut unmixed = [layer(0.11, &alpha), layer(0.07, &alpha)];
                let found = fringe(&config, &mut colour, &mut unmixed, depth, positions);
                assert_eq!(found.is_empty(), normalize == Normalize::Paper);
                let inputs = unmixed.into_iter().zip(&layers);
                for (k, (input, carried)) in [0.11, 0.07].into_iter().zip(inputs) {
                    let input = Color {
                        a: colour.a.clone(),
                        ..input
                    };
                    let want = stages(&config, input, depth, positions, &found);
                    // The layer moved: the comparison is not of a copy.
                    assert_ne!(bits(&want.r), bits(&layer(k, &alpha).r));
                    assert_eq!(bits(&carried.r), bits(&want.r), "{normalize:?} {k}");
                    assert_eq!(bits(&carried.g), bits(&want.g), "{normalize:?} {k}");
                    assert_eq!(bits(&carried.b), bits(&want.b), "{normalize:?} {k}");
                }
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
                    close_relative(got[ch], want, 1e-5),
                    "{normalize:?}: {} vs {want}",
                    got[ch]
                );
            }
        }
    }
}
