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
//! reached takes a motion from around it ([`sweep_at`]: its neighbours' sweeps, which close
//! the one-pixel gaps of the torn triangles; else a moving neighbour's own motion; else the
//! sweeps two away); a sweep that reaches too far costs nothing, as the average finds no
//! coverage there.
//!
//! Inputs: the config, the colour planes (R, G, B, A), depth, velocity, `swept` and the drawn planes;
//! output: the drawn planes, with the swept pixels replaced. Where every pixel is wholly
//! covered (an opaque frame, or none with alpha) nothing is swept and the stage changes
//! nothing. Each value is `own + Σ w·(tap − own) / Σ w` (own: the pixel's sharp value, so a
//! uniform colour stays exactly uniform), clamped to the least and greatest tap it averages.

use rayon::prelude::*;

use super::config::StretchConfig;
use super::mesh::swept_motion;
use super::texture_blur::for_each_tap;

/// A pixel's eight neighbours, nearest first (the four beside it, then the four diagonal),
/// each group in reading order, (dx, dy).
#[rustfmt::skip]
const NEIGHBOURS: [(i64, i64); 8] = [
    (0, -1), (-1, 0), (1, 0), (0, 1),
    (-1, -1), (1, -1), (-1, 1), (1, 1),
];

/// The sixteen pixels two away (the 5×5 square's rim), nearest first (the four straight
/// out, the eight beside them, the four corners), each group in reading order, (dx, dy):
/// [`sweep_at`] looks there last (`RINGS` in stretch.wgsl).
#[rustfmt::skip]
pub const SECOND_RING: [(i64, i64); 16] = [
    (0, -2), (-2, 0), (2, 0), (0, 2),
    (-1, -2), (1, -2), (-2, -1), (2, -1), (-2, 1), (2, 1), (-1, 2), (1, 2),
    (-2, -2), (2, -2), (-2, 2), (2, 2),
];

/// Stage 4: each pixel the frame does not wholly cover that a smear swept (its own
/// fragment's sweep, or a neighbour's) takes the average of the sharp frame along the
/// sweep's motion over the exposure, over the samples not nearer than the sweep's depth.
pub fn cover(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    geometry: (&[f32], &[[f32; 2]]),
    swept: &[[f32; 4]],
    out: &mut [Vec<f32>; 4],
) {
    run::<false>(config, planes, geometry, swept, out, &[], &mut [], 0);
}

/// [`cover`], and the light layers' `channels` carried planes (`carried`, pixel-major, as
/// [`texture_blur_carrying`](super::texture_blur_carrying) takes them) averaged over the same
/// taps into `carried_out`, each clamped to its own taps: a carried channel comes out with
/// the bits it gets in the beauty's place.
#[allow(clippy::too_many_arguments)] // the beauty's buffers, then the carried ones
pub fn cover_carrying(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    geometry: (&[f32], &[[f32; 2]]),
    swept: &[[f32; 4]],
    out: &mut [Vec<f32>; 4],
    carried: &[f32],
    carried_out: &mut [f32],
    channels: usize,
) {
    if channels == 0 {
        run::<false>(config, planes, geometry, swept, out, &[], &mut [], 0);
    } else {
        run::<true>(
            config,
            planes,
            geometry,
            swept,
            out,
            carried,
            carried_out,
            channels,
        );
    }
}

/// The sweep pixel `i` takes (motion x, y, depth, 1), the first of:
/// 1. its own, where a fragment came;
/// 2. of its eight neighbours' sweeps, the nearest in depth that passes the pixel's depth test
///    (as a fragment's: `depth ≤ z · (1 + depth_tolerance)`). Eight, not four: the mesh's
///    edges run through pixel centres, and the rasteriser owns a centre on an edge on two
///    sides of a triangle only, so at a corner of a streak a pixel's four neighbours can all
///    lie on unowned edges;
/// 3. of its eight neighbours that move, the nearest in depth that passes the test, with its
///    own motion (cut as a fragment's, [`swept_motion`]) and depth;
/// 4. of the sweeps of the sixteen pixels two away ([`SECOND_RING`]), as in 2;
///
/// each time the first of equals in the order listed (the nearest pixels first); `None` where
/// none. Why 3 and 4: a smear's triangles reach out from its moved silhouette vertices, and
/// where those move less than a pixel out (a pixel beyond the rim is covered a quarter of the
/// exposure by an edge moving 3.8 px a frame across itself under a half shutter), no fragment
/// reaches the pixel just beyond the rim, nor any of its neighbours: its solid neighbours are
/// the smear's own surface, which keeps no sweep. Such pixels (464 in gears' FG layer) kept
/// their sharp value where the exposure covers them, a hole along the streak. A motion taken from
/// farther than the streak reaches costs nothing, as [`cover`]'s average along it finds no
/// coverage there. Measured on the truth scenes' view layers (BENCHMARKS.md, "stretch: no
/// hole beside the rim"): gears' hand-made merge 0.01650 → 0.01401 and its stack 0.01671 →
/// 0.01408, zoom's 0.01793 → 0.01675.
pub fn sweep_at(
    config: &StretchConfig,
    (z, v): (&[f32], &[[f32; 2]]),
    swept: &[[f32; 4]],
    i: usize,
) -> Option<[f32; 4]> {
    if swept[i][3] != 0.0 {
        return Some(swept[i]);
    }
    let of_sweeps = |j: usize| (swept[j][3] != 0.0).then_some(swept[j]);
    let of_motion = |j: usize| {
        config.moving(v[j]).then(|| {
            let [mx, my] = swept_motion(config, v[j]);
            [mx, my, z[j], 1.0]
        })
    };
    nearest(config, z, i, &NEIGHBOURS, of_sweeps)
        .or_else(|| nearest(config, z, i, &NEIGHBOURS, of_motion))
        .or_else(|| nearest(config, z, i, &SECOND_RING, of_sweeps))
}

/// Of the pixels at `offsets` from pixel `i` (those in the frame), the sweep `sweep_of` gives
/// the nearest (in depth) whose depth passes pixel `i`'s test, the first of equals in the
/// order given.
fn nearest(
    config: &StretchConfig,
    z: &[f32],
    i: usize,
    offsets: &[(i64, i64)],
    sweep_of: impl Fn(usize) -> Option<[f32; 4]>,
) -> Option<[f32; 4]> {
    let (width, height) = (config.width as usize, config.height as usize);
    let (x, y) = (i % width, i / width);
    let mut best: Option<[f32; 4]> = None;
    for &(dx, dy) in offsets {
        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
        if nx < 0 || ny < 0 || nx >= width as i64 || ny >= height as i64 {
            continue;
        }
        let Some(sweep) = sweep_of(ny as usize * width + nx as usize) else {
            continue;
        };
        if sweep[2] <= z[i] * config.depth_limit && best.is_none_or(|b| sweep[2] < b[2]) {
            best = Some(sweep);
        }
    }
    best
}

/// Whether any pixel of alpha plane `alpha` is not wholly covered (below 1): only then does a
/// fragment leave a sweep, and cover change anything (the GPU's host asks before it draws
/// the sweeps).
pub fn partly_covered(alpha: &[f32]) -> bool {
    alpha.par_iter().any(|&a| a < 1.0)
}

/// Whether each pixel has a pixel that a fragment swept or that moves within two of it (the
/// 5×5 square about it): where not, [`sweep_at`] finds nothing, and [`run`] does not look.
/// (In a view layer most pixels are empty space far from any streak, and looking took the
/// 1080p `layers` stack 15 % longer.)
fn near_candidates(config: &StretchConfig, v: &[[f32; 2]], swept: &[[f32; 4]]) -> Vec<bool> {
    let (width, height) = (config.width as usize, config.height as usize);
    let candidate: Vec<bool> = swept
        .par_iter()
        .zip(v)
        .map(|(sweep, &motion)| sweep[3] != 0.0 || config.moving(motion))
        .collect();
    let mut across = vec![false; candidate.len()];
    across
        .par_chunks_mut(width)
        .zip(candidate.par_chunks(width))
        .for_each(|(row, from)| {
            for (x, near) in row.iter_mut().enumerate() {
                *near = from[x.saturating_sub(2)..(x + 3).min(width)].contains(&true);
            }
        });
    let mut near = vec![false; candidate.len()];
    near.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for dy in y.saturating_sub(2)..(y + 3).min(height) {
            for (near, &a) in row.iter_mut().zip(&across[dy * width..][..width]) {
                *near |= a;
            }
        }
    });
    near
}

/// The stage for the beauty, and where `CARRY` for the carried planes too.
#[allow(clippy::too_many_arguments)]
fn run<const CARRY: bool>(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    (z, v): (&[f32], &[[f32; 2]]),
    swept: &[[f32; 4]],
    out: &mut [Vec<f32>; 4],
    carried: &[f32],
    carried_out: &mut [f32],
    channels: usize,
) {
    let width = config.width as usize;
    let height = config.height as usize;
    if !partly_covered(&planes[3]) {
        // Every pixel wholly covered (an opaque frame): nothing to sweep.
        return;
    }
    let near = near_candidates(config, v, swept);
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
                if planes[3][i] >= 1.0 || !near[i] {
                    continue;
                }
                let Some(sweep) = sweep_at(config, (z, v), swept, i) else {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::stretch::StretchParams;

    /// `sweep_at` of the centre of a 5×5 frame at depth 10 (everything else at depth 10 and
    /// still, unless set) in the order its doc gives: a neighbour's sweep, then a moving
    /// neighbour's own motion, then a sweep two away; of equal depths the nearest pixel's; a
    /// candidate farther than the pixel (failing its depth test) never.
    #[test]
    fn a_pixel_no_fragment_reached_takes_the_nearest_motion_in_the_order_given() {
        let config = StretchConfig::new(5, 5, &StretchParams::default(), 0.5);
        let at = |x: usize, y: usize| y * 5 + x;
        let centre = at(2, 2);
        let sweep = |vx: f32, depth: f32| [vx, 0.0, depth, 1.0];
        let case = |swept_at: &[(usize, [f32; 4])], moving_at: &[(usize, f32, f32)]| {
            let mut z = vec![10.0f32; 25];
            let mut v = vec![[0.0f32; 2]; 25];
            let mut swept = vec![[0.0f32; 4]; 25];
            for &(j, s) in swept_at {
                swept[j] = s;
            }
            for &(j, vx, depth) in moving_at {
                v[j] = [vx, 0.0];
                z[j] = depth;
            }
            sweep_at(&config, (&z, &v), &swept, centre)
        };
        assert_eq!(case(&[], &[]), None);
        // Two away, and nothing nearer.
        assert_eq!(
            case(&[(at(4, 2), sweep(1.0, 5.0))], &[]),
            Some(sweep(1.0, 5.0))
        );
        // A moving neighbour before a sweep two away, with its motion and depth.
        assert_eq!(
            case(&[(at(4, 2), sweep(1.0, 5.0))], &[(at(1, 2), 3.0, 6.0)]),
            Some(sweep(3.0, 6.0))
        );
        // A neighbour's sweep before a moving neighbour, even a nearer one.
        assert_eq!(
            case(&[(at(3, 3), sweep(2.0, 5.0))], &[(at(2, 1), 3.0, 4.0)]),
            Some(sweep(2.0, 5.0))
        );
        // Of equal depths, the nearest pixel's: beside before diagonal.
        assert_eq!(
            case(
                &[(at(1, 1), sweep(4.0, 5.0)), (at(3, 2), sweep(5.0, 5.0))],
                &[]
            ),
            Some(sweep(5.0, 5.0))
        );
        // Of different depths, the nearer.
        assert_eq!(
            case(
                &[(at(1, 1), sweep(4.0, 4.0)), (at(3, 2), sweep(5.0, 5.0))],
                &[]
            ),
            Some(sweep(4.0, 4.0))
        );
        // Farther than the pixel: no candidate.
        assert_eq!(
            case(&[(at(3, 2), sweep(5.0, 20.0))], &[(at(1, 2), 3.0, 30.0)]),
            None
        );
        // A still neighbour lends no motion.
        assert_eq!(case(&[], &[(at(1, 2), 0.0, 5.0)]), None);
    }
}
