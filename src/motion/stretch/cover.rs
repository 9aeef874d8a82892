//! stretch's fourth stage, cover: the pixels the frame does not wholly cover (alpha below 1:
//! the empty and the partly covered pixels of a view layer, premultiplied) that a smear
//! sweeps get the smear's coverage over the exposure, where the talk blends the smear's
//! colour at its guessed opacity.
//!
//! The talk's blend, `mix(pixel, smear, alpha)` with `alpha = max(min_alpha, 1 − |M|/extent)`
//! falling from 1 at the inner (unmoved) vertex, a pixel inside the object, to the floor at
//! the moved one, is a translucency judged by eye over a background. Where there is no
//! background, it *is* the output's alpha, and it is wrong: on a Cycles render's FG layer
//! (a fan and a cube over empty space, `--layer FG`) the smears came out more opaque than
//! the exposure makes them (alpha 0.92 beside the silhouette where the object covers the
//! pixel half the exposure, 0.5; the total alpha 10 % over the sharp frame's, which motion
//! keeps), cut off at the 0.1 floor at the streak's end, and combed at staircase
//! silhouettes, where a triangle with an empty corner is torn and leaves a gap a pixel high
//! in the streak (docs/DESIGN.md "stretch").
//!
//! So a fragment over such a pixel is not blended ([`rasterise`](super::rasterise) writes
//! its motion and depth into `swept`, the nearest fragment's), and here each such pixel
//! averages the sharp frame along that motion over the exposure, as the pre-blur averages a
//! moving pixel along its own ([`for_each_tap`]: the same samples, leaving out what is
//! nearer than the smear): what comes out is the premultiplied colour and the alpha the
//! exposure gives, a ramp from half the object's coverage at a silhouette (centred) to 0
//! where the streak ends, whatever the talk's `extent` and floor. A pixel no fragment
//! reached takes the nearest (in depth) of its eight neighbours' sweeps that passes its depth
//! test, which closes the one-pixel gaps of the torn triangles; a sweep that reaches too far
//! costs nothing, as the average finds no coverage there.
//!
//! Inputs: the config, the colour planes (R, G, B, A), depth, `swept` and the drawn planes;
//! output: the drawn planes, with the swept pixels replaced. Where every pixel is wholly
//! covered (an opaque frame, or none with alpha) nothing is swept and the stage changes
//! nothing. Each value is `own + Σ w·(tap − own) / Σ w` (own: the pixel's sharp value, so a
//! uniform colour stays exactly uniform), clamped to the least and greatest tap it averages.

use rayon::prelude::*;

use super::config::StretchConfig;
use super::texture_blur::for_each_tap;

/// A pixel's eight neighbours in reading order, (dx, dy).
const NEIGHBOURS: [(i64, i64); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

/// Stage 4: each pixel the frame does not wholly cover that a smear swept (its own
/// fragment's sweep, or a neighbour's) takes the average of the sharp frame along the
/// sweep's motion over the exposure, over the samples not nearer than the sweep's depth.
pub fn cover(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    swept: &[[f32; 4]],
    out: &mut [Vec<f32>; 4],
) {
    run::<false>(config, planes, z, swept, out, &[], &mut [], 0);
}

/// [`cover`], and the light layers' `channels` carried planes (`carried`, pixel-major, as
/// [`texture_blur_carrying`](super::texture_blur_carrying) takes them) averaged over the same
/// taps into `carried_out`, each clamped to its own taps: a carried channel comes out with
/// the bits it gets in the beauty's place.
#[allow(clippy::too_many_arguments)] // the beauty's buffers, then the carried ones
pub fn cover_carrying(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    swept: &[[f32; 4]],
    out: &mut [Vec<f32>; 4],
    carried: &[f32],
    carried_out: &mut [f32],
    channels: usize,
) {
    if channels == 0 {
        run::<false>(config, planes, z, swept, out, &[], &mut [], 0);
    } else {
        run::<true>(
            config,
            planes,
            z,
            swept,
            out,
            carried,
            carried_out,
            channels,
        );
    }
}

/// The sweep pixel `i` takes: its own where a fragment came, else of its eight neighbours'
/// the nearest whose depth passes the pixel's depth test (as a fragment's: `depth ≤ z · (1 +
/// depth_tolerance)`), the first of equals in reading order; `None` where none. (Eight, not
/// four: the mesh's edges run through pixel centres, and the rasteriser owns a centre on an
/// edge on two sides of a triangle only, so at a corner of a streak a pixel's four
/// neighbours can all lie on unowned edges.)
pub fn sweep_at(
    config: &StretchConfig,
    z: &[f32],
    swept: &[[f32; 4]],
    i: usize,
) -> Option<[f32; 4]> {
    if swept[i][3] != 0.0 {
        return Some(swept[i]);
    }
    let (width, height) = (config.width as usize, config.height as usize);
    let (x, y) = (i % width, i / width);
    let mut best: Option<[f32; 4]> = None;
    for (dx, dy) in NEIGHBOURS {
        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
        if nx < 0 || ny < 0 || nx >= width as i64 || ny >= height as i64 {
            continue;
        }
        let sweep = swept[ny as usize * width + nx as usize];
        if sweep[3] != 0.0
            && sweep[2] <= z[i] * config.depth_limit
            && best.is_none_or(|b| sweep[2] < b[2])
        {
            best = Some(sweep);
        }
    }
    best
}

/// The stage for the beauty, and where `CARRY` for the carried planes too.
#[allow(clippy::too_many_arguments)]
fn run<const CARRY: bool>(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    swept: &[[f32; 4]],
    out: &mut [Vec<f32>; 4],
    carried: &[f32],
    carried_out: &mut [f32],
    channels: usize,
) {
    let width = config.width as usize;
    let height = config.height as usize;
    // Each row's carried values (none for the beauty alone).
    let carried_rows: Vec<&mut [f32]> = if CARRY {
        carried_out.chunks_mut(width * channels).collect()
    } else {
        (0..height).map(|_| Default::default()).collect()
    };
    let [r, g, b, a] = out;
    r.par_chunks_mut(width)
        .zip(g.par_chunks_mut(width))
        .zip(b.par_chunks_mut(width))
        .zip(a.par_chunks_mut(width))
        .zip(carried_rows)
        .enumerate()
        .for_each(|(y, ((((r, g), b), a), carried_row))| {
            let rows = [r, g, b, a];
            let mut taps: Vec<(usize, f32)> = Vec::new();
            let mut sums = vec![0.0f32; channels];
            let mut bounds = vec![(0.0f32, 0.0f32); channels];
            for x in 0..width {
                let i = y * width + x;
                if planes[3][i] >= 1.0 {
                    continue;
                }
                let Some(sweep) = sweep_at(config, z, swept, i) else {
                    continue;
                };
                let own: [f32; 4] = std::array::from_fn(|c| planes[c][i]);
                let mut sum = [0.0f32; 4];
                let mut lo = [f32::INFINITY; 4];
                let mut hi = [f32::NEG_INFINITY; 4];
                let mut total = 0.0f32;
                if CARRY {
                    taps.clear();
                }
                let motion = [sweep[0], sweep[1]];
                for_each_tap(
                    config,
                    (x, y),
                    motion,
                    sweep[2],
                    |j| z[j],
                    |j, w| {
                        for c in 0..4 {
                            let value = planes[c][j];
                            sum[c] += w * (value - own[c]);
                            lo[c] = lo[c].min(value);
                            hi[c] = hi[c].max(value);
                        }
                        total += w;
                        if CARRY {
                            taps.push((j, w));
                        }
                    },
                );
                if total <= 0.0 {
                    continue;
                }
                for c in 0..4 {
                    rows[c][x] = (own[c] + sum[c] / total).clamp(lo[c], hi[c]);
                }
                if CARRY {
                    // The same sums over the same taps, channel by channel as above.
                    let own = &carried[i * channels..][..channels];
                    sums.fill(0.0);
                    bounds.fill((f32::INFINITY, f32::NEG_INFINITY));
                    for &(j, w) in &taps {
                        let texel = &carried[j * channels..][..channels];
                        for c in 0..channels {
                            sums[c] += w * (texel[c] - own[c]);
                            bounds[c] = (bounds[c].0.min(texel[c]), bounds[c].1.max(texel[c]));
                        }
                    }
                    let out = &mut carried_row[x * channels..][..channels];
                    for c in 0..channels {
                        out[c] = (own[c] + sums[c] / total).clamp(bounds[c].0, bounds[c].1);
                    }
                }
            }
        });
}
