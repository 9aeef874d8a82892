//! stretch's first stage, the texture pre-blur: each moving pixel's colour averaged along its
//! own motion, for the beauty and, with the same taps and weights, the light layers carried
//! beside it.

use rayon::prelude::*;

use super::config::{StretchConfig, MOST_SAMPLES};

/// Stage 1: each moving pixel's colour averaged along its own motion over the exposure
/// (bilinear samples, leaving out nearer surfaces), clamped to the frame's range per channel;
/// still pixels keep theirs. Returns the frame to draw first.
///
/// At time t the pixel at x shows the point of its surface that was at x − v·t at the frame,
/// so the samples read x − v·t for t over [t0, t1]. (Centred, [t0, t1] is symmetric and the
/// sign does not matter; until issue 19 this read x + v·t, which mirrored the streak about
/// the pixel for the rear anchor and for an offset shutter.)
pub fn texture_blur(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
) -> [Vec<f32>; 4] {
    blur::<false>(config, planes, z, v, &[], 0).0
}

/// [`texture_blur`], and the light layers' `channels` carried planes (`carried`, pixel-major:
/// pixel i's values at `i·channels..(i + 1)·channels`) averaged along the same samples with
/// the same weights: each pixel's taps (those of its own surface, with their bilinear
/// weights) are found once, from its depth and motion alone, and each carried channel is
/// summed over them in the order the beauty's are, then clamped to its own range. So a
/// carried channel comes out with the bits it gets in the beauty's place. Returns the
/// beauty's planes and the carried ones, packed as they came.
pub fn texture_blur_carrying(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
    carried: &[f32],
    channels: usize,
) -> ([Vec<f32>; 4], Vec<f32>) {
    if channels == 0 {
        blur::<false>(config, planes, z, v, &[], 0)
    } else {
        blur::<true>(config, planes, z, v, carried, channels)
    }
}

/// The pre-blur of the beauty, and where `CARRY` of the carried planes too (one copy of the
/// loop each way, so the beauty's alone records no taps).
fn blur<const CARRY: bool>(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
    carried: &[f32],
    channels: usize,
) -> ([Vec<f32>; 4], Vec<f32>) {
    let (width, height) = (config.width as usize, config.height as usize);
    let n = width * height;
    // Colour and depth together, so a tap reads one cache line.
    let texels: Vec<[f32; 5]> = (0..n)
        .into_par_iter()
        .map(|i| [planes[0][i], planes[1][i], planes[2][i], planes[3][i], z[i]])
        .collect();
    // The frame's range per channel: averages are clamped to it against rounding.
    let range: [(f32, f32); 4] = std::array::from_fn(|c| {
        planes[c]
            .par_iter()
            .fold(
                || (f32::INFINITY, f32::NEG_INFINITY),
                |(lo, hi), &v| (lo.min(v), hi.max(v)),
            )
            .reduce(
                || (f32::INFINITY, f32::NEG_INFINITY),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            )
    });
    let carried_range = range_of(carried, channels);
    let mut blurred = planes.clone();
    let mut carried_blurred = carried.to_vec();
    // Each row's carried values (none for the beauty alone).
    let carried_rows: Vec<&mut [f32]> = if CARRY {
        carried_blurred.chunks_mut(width * channels).collect()
    } else {
        (0..height).map(|_| Default::default()).collect()
    };
    let [r, g, b, a] = &mut blurred;
    r.par_chunks_mut(width)
        .zip(g.par_chunks_mut(width))
        .zip(b.par_chunks_mut(width))
        .zip(a.par_chunks_mut(width))
        .zip(carried_rows)
        .enumerate()
        .for_each(|(y, ((((r, g), b), a), carried_row))| {
            let rows = [r, g, b, a];
            // A pixel's taps: where (pixel index) and with what weight, in the order summed.
            let mut taps: Vec<(usize, f32)> = Vec::new();
            let mut sums = vec![0.0f32; channels];
            #[allow(clippy::needless_range_loop)] // x indexes four rows and the frame
            for x in 0..width {
                let i = y * width + x;
                if !config.moving(v[i]) {
                    continue;
                }
                let own: [f32; 4] = std::array::from_fn(|c| planes[c][i]);
                let mut sum = [0.0f32; 4];
                let mut total = 0.0f32;
                if CARRY {
                    taps.clear();
                }
                let depth_of = |j: usize| texels[j][4];
                for_each_tap(config, (x, y), v[i], z[i], depth_of, |j, w| {
                    let texel = &texels[j];
                    for c in 0..4 {
                        sum[c] += w * (texel[c] - own[c]);
                    }
                    total += w;
                    if CARRY {
                        taps.push((j, w));
                    }
                });
                if total > 0.0 {
                    for c in 0..4 {
                        let value = own[c] + sum[c] / total;
                        rows[c][x] = value.clamp(range[c].0, range[c].1);
                    }
                    if CARRY {
                        // The same sums over the same taps, channel by channel as above.
                        let own = &carried[i * channels..][..channels];
                        sums.fill(0.0);
                        for &(j, w) in &taps {
                            let texel = &carried[j * channels..][..channels];
                            for c in 0..channels {
                                sums[c] += w * (texel[c] - own[c]);
                            }
                        }
                        let out = &mut carried_row[x * channels..][..channels];
                        for c in 0..channels {
                            let value = own[c] + sums[c] / total;
                            out[c] = value.clamp(carried_range[c].0, carried_range[c].1);
                        }
                    }
                }
            }
        });
    (blurred, carried_blurred)
}

/// The samples along a motion, which the pre-blur and [`cover`](super::cover) average:
/// for pixel (x, y) moving at `v` px per frame, `samples` times spread evenly over the
/// exposure [t0, t1] (the midpoints of equal parts, one more than the streak is pixels long,
/// 2 to [`MOST_SAMPLES`]), and at each time t the bilinear taps of the four pixel centres
/// around x − v·t (pixel (x, y) sits at (x, y)) that lie in the frame with a weight above 0
/// and are not nearer than `depth` beyond the tear (`depth_of(j) · tear < depth` leaves tap
/// j out): `tap(j, w)` for each, in that order. At time t the pixel shows the point of the
/// moving surface that was at x − v·t at the frame.
#[inline(always)]
pub(super) fn for_each_tap(
    config: &StretchConfig,
    (x, y): (usize, usize),
    [vx, vy]: [f32; 2],
    depth: f32,
    depth_of: impl Fn(usize) -> f32,
    mut tap: impl FnMut(usize, f32),
) {
    let (width, height) = (config.width as usize, config.height as usize);
    let (t0, t1) = (config.t0, config.t1);
    let length = (vx * vx + vy * vy).sqrt() * (t1 - t0);
    let samples = (length.ceil() as usize + 1).clamp(2, MOST_SAMPLES);
    for k in 0..samples {
        let t = t0 + (t1 - t0) * (k as f32 + 0.5) / samples as f32;
        // Bilinear between the four nearest centres, over those not nearer (so a sub-pixel
        // streak still blurs).
        let (px, py) = (x as f32 - vx * t, y as f32 - vy * t);
        let (fx, fy) = (px.floor(), py.floor());
        let (ax, ay) = (px - fx, py - fy);
        for (dx, dy, w) in [
            (0, 0, (1.0 - ax) * (1.0 - ay)),
            (1, 0, ax * (1.0 - ay)),
            (0, 1, (1.0 - ax) * ay),
            (1, 1, ax * ay),
        ] {
            let (sx, sy) = (fx + dx as f32, fy + dy as f32);
            if !(w > 0.0 && sx >= 0.0 && sy >= 0.0 && sx < width as f32 && sy < height as f32) {
                continue;
            }
            let j = sy as usize * width + sx as usize;
            if depth_of(j) * config.tear < depth {
                continue;
            }
            tap(j, w);
        }
    }
}

/// The least and greatest value of each of the `channels` carried planes (`carried`, pixel-major).
fn range_of(carried: &[f32], channels: usize) -> Vec<(f32, f32)> {
    let none = || vec![(f32::INFINITY, f32::NEG_INFINITY); channels];
    if channels == 0 {
        return Vec::new();
    }
    carried
        .par_chunks(channels * 1024)
        .fold(none, |mut range, values| {
            for pixel in values.chunks(channels) {
                for (r, &v) in range.iter_mut().zip(pixel) {
                    *r = (r.0.min(v), r.1.max(v));
                }
            }
            range
        })
        .reduce(none, |mut a, b| {
            for (a, b) in a.iter_mut().zip(b) {
                *a = (a.0.min(b.0), a.1.max(b.1));
            }
            a
        })
}
