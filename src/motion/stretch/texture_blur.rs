//! stretch's first stage, the texture pre-blur: each moving pixel's colour averaged along its
//! own motion, for the beauty and, with the same taps and weights, the light layers carried
//! beside it.

use rayon::prelude::*;

use super::config::{StretchConfig, MOST_SAMPLES};
use super::mesh::swept_motion;

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
            // The merged taps of the motion a run of pixels shares (made at a run's second
            // pixel, so a frame of motions all different pays nothing for them).
            let mut kernel: Option<Kernel> = None;
            let mut scratch = Vec::new();
            #[allow(clippy::needless_range_loop)] // x indexes four rows and the frame
            for x in 0..width {
                let i = y * width + x;
                if !config.moving(v[i]) {
                    continue;
                }
                // Along the motion the mesh gives its fragments, cut to MAX_SHIFT as theirs
                // is: an uncut motion of thousands of pixels read its samples off the frame
                // (the pixel kept its sharp colour) or spread over it (background only).
                let vi = swept_motion(config, v[i]);
                let own: [f32; 4] = std::array::from_fn(|c| planes[c][i]);
                let mut sum = [0.0f32; 4];
                let mut total = 0.0f32;
                if CARRY {
                    taps.clear();
                }
                let mut add = |j: usize, w: f32| {
                    let texel = &texels[j];
                    for c in 0..4 {
                        sum[c] += w * (texel[c] - own[c]);
                    }
                    total += w;
                    if CARRY {
                        taps.push((j, w));
                    }
                };
                if kernel.as_ref().is_none_or(|k| !k.serves(vi))
                    && x > 0
                    && v[i - 1].map(f32::to_bits) == v[i].map(f32::to_bits)
                {
                    kernel = Some(Kernel::new(config, vi, &mut scratch));
                }
                match &kernel {
                    Some(k) if k.serves(vi) => {
                        for &(ox, oy, weight) in &k.taps {
                            if let Some(j) =
                                tap_at(config, (x, y), (ox, oy), z[i], |j| texels[j][4])
                            {
                                add(j, weight);
                            }
                        }
                    }
                    _ => for_each_tap(config, (x, y), vi, z[i], |j| texels[j][4], add),
                }
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
    v: [f32; 2],
    depth: f32,
    depth_of: impl Fn(usize) -> f32,
    mut tap: impl FnMut(usize, f32),
) {
    for_each_offset(config, v, |offset, w| {
        if let Some(j) = tap_at(config, (x, y), offset, depth, &depth_of) {
            tap(j, w);
        }
    });
}

/// The pixel at `offset` from pixel (x, y), where it lies in the frame and is not nearer than
/// `depth` beyond the tear (a tap [`for_each_tap`] and the kernels read).
#[inline(always)]
fn tap_at(
    config: &StretchConfig,
    (x, y): (usize, usize),
    (ox, oy): (i64, i64),
    depth: f32,
    depth_of: impl Fn(usize) -> f32,
) -> Option<usize> {
    let (sx, sy) = (x as i64 + ox, y as i64 + oy);
    if sx < 0 || sy < 0 || sx >= config.width as i64 || sy >= config.height as i64 {
        return None;
    }
    let j = sy as usize * config.width as usize + sx as usize;
    if depth_of(j) * config.tear < depth {
        return None;
    }
    Some(j)
}

/// The samples' corners as offsets from the pixel, whatever the pixel: `corner((dx, dy), w)`
/// for each of the four pixel centres around −v·t at each sample time t (in order, the
/// same times as [`for_each_tap`]) with a weight above 0. The sample's point is −v·t from
/// the pixel, its whole part and fraction taken of −v·t alone, so every pixel of one motion
/// reads the same offsets with the same weights, bit for bit (x − v·t, rounded at x's
/// magnitude, gave weights that drifted by up to 2⁻¹² across a 1080p row).
#[inline(always)]
pub(super) fn for_each_offset(
    config: &StretchConfig,
    [vx, vy]: [f32; 2],
    mut corner: impl FnMut((i64, i64), f32),
) {
    let (t0, t1) = (config.t0, config.t1);
    let length = (vx * vx + vy * vy).sqrt() * (t1 - t0);
    let samples = (length.ceil() as usize + 1).clamp(2, MOST_SAMPLES);
    for k in 0..samples {
        let t = t0 + (t1 - t0) * (k as f32 + 0.5) / samples as f32;
        // Bilinear between the four nearest centres (so a sub-pixel streak still blurs).
        let (px, py) = (-(vx * t), -(vy * t));
        let (fx, fy) = (px.floor(), py.floor());
        let (ax, ay) = (px - fx, py - fy);
        // (|v·t| ≤ the numeric policy's 1e7 px: exact in i64.)
        let (ox, oy) = (fx as i64, fy as i64);
        for (dx, dy, w) in [
            (0, 0, (1.0 - ax) * (1.0 - ay)),
            (1, 0, ax * (1.0 - ay)),
            (0, 1, (1.0 - ax) * ay),
            (1, 1, ax * ay),
        ] {
            if w > 0.0 {
                corner((ox + dx, oy + dy), w);
            }
        }
    }
}

/// The pre-blur's taps for one motion, merged: each offset from the pixel once, with the sum
/// of the weights its samples give it (in sample order), sorted by row then column. Every
/// pixel of that motion reads these (a camera pan: most of a frame), so a pixel costs one
/// read per pixel its streak crosses, not four per sample, and no floor: on a 1080p pan
/// (every background pixel 30 px a frame, 16 samples) 17 taps where there were 32.
struct Kernel {
    /// The motion's bits (a kernel serves exactly the motion it was made for).
    motion: [u32; 2],
    taps: Vec<(i64, i64, f32)>,
}

impl Kernel {
    fn new(config: &StretchConfig, v: [f32; 2], taps: &mut Vec<(i64, i64, f32)>) -> Kernel {
        taps.clear();
        for_each_offset(config, v, |(ox, oy), w| taps.push((ox, oy, w)));
        // Stable: the weights of one offset are summed in sample order.
        taps.sort_by_key(|&(ox, oy, _)| (oy, ox));
        let mut merged: Vec<(i64, i64, f32)> = Vec::with_capacity(taps.len());
        for &(ox, oy, w) in taps.iter() {
            match merged.last_mut() {
                Some(last) if (last.0, last.1) == (ox, oy) => last.2 += w,
                _ => merged.push((ox, oy, w)),
            }
        }
        Kernel {
            motion: v.map(f32::to_bits),
            taps: merged,
        }
    }

    fn serves(&self, v: [f32; 2]) -> bool {
        self.motion == v.map(f32::to_bits)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::stretch::StretchParams;
    use crate::numeric::unit;

    #[test]
    fn a_pan_s_kernel_is_one_tap_per_pixel_its_streak_crosses() {
        // 30 px a frame under a centred 0.5 shutter: −v·t over [−7.5, 7.5] px, 16 samples.
        let config = StretchConfig::new(100, 10, &StretchParams::default(), 0.5);
        let kernel = Kernel::new(&config, [30.0, 0.0], &mut Vec::new());
        let offsets: Vec<(i64, i64)> = kernel.taps.iter().map(|t| (t.0, t.1)).collect();
        let want: Vec<(i64, i64)> = (-8..=8).map(|o| (o, 0)).collect();
        assert_eq!(offsets, want);
        // Each sample's two weights add up to 1, and the streak is symmetric about the pixel.
        let total: f32 = kernel.taps.iter().map(|t| t.2).sum();
        assert!((total - 16.0).abs() < 1e-4, "{total}");
        for k in 0..kernel.taps.len() {
            let (a, b) = (kernel.taps[k].2, kernel.taps[kernel.taps.len() - 1 - k].2);
            assert!((a - b).abs() < 1e-5, "{k}: {a} against {b}");
        }
    }

    /// The pre-blur of pixel (x, y) by its definition, in f64: `samples` bilinear reads of
    /// x − v·t over the exposure, taps nearer than the pixel beyond the tear left out, the
    /// mean clamped to the frame's range.
    fn by_definition(
        config: &StretchConfig,
        planes: &[Vec<f32>; 4],
        z: &[f32],
        v: [f32; 2],
        (x, y): (usize, usize),
    ) -> [f64; 4] {
        let (w, h) = (config.width as usize, config.height as usize);
        let i = y * w + x;
        let (t0, t1) = (config.t0 as f64, config.t1 as f64);
        // (The count as the reference defines it, in f32.)
        let length = (v[0] * v[0] + v[1] * v[1]).sqrt() * (config.t1 - config.t0);
        let samples = (length.ceil() as usize + 1).clamp(2, MOST_SAMPLES);
        let (mut sum, mut total) = ([0.0f64; 4], 0.0f64);
        for k in 0..samples {
            let t = t0 + (t1 - t0) * (k as f64 + 0.5) / samples as f64;
            let (px, py) = (x as f64 - v[0] as f64 * t, y as f64 - v[1] as f64 * t);
            let (fx, fy) = (px.floor(), py.floor());
            for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                let wx = if dx == 0.0 { 1.0 - (px - fx) } else { px - fx };
                let wy = if dy == 0.0 { 1.0 - (py - fy) } else { py - fy };
                let (sx, sy) = (fx + dx, fy + dy);
                if wx * wy <= 0.0 || sx < 0.0 || sy < 0.0 || sx >= w as f64 || sy >= h as f64 {
                    continue;
                }
                let j = sy as usize * w + sx as usize;
                if z[j] * config.tear < z[i] {
                    continue;
                }
                for c in 0..4 {
                    sum[c] += wx * wy * planes[c][j] as f64;
                }
                total += wx * wy;
            }
        }
        std::array::from_fn(|c| {
            let lo = planes[c].iter().copied().fold(f32::INFINITY, f32::min) as f64;
            let hi = planes[c].iter().copied().fold(f32::NEG_INFINITY, f32::max) as f64;
            if total > 0.0 {
                (sum[c] / total).clamp(lo, hi)
            } else {
                planes[c][i] as f64
            }
        })
    }

    #[test]
    fn runs_of_one_motion_blur_as_each_pixel_alone_would() {
        // A texture whose rows move alike in runs (the kernel's case), broken by pixels of
        // their own motion and by a nearer block the taps must leave out.
        let (w, h) = (61usize, 23usize);
        let n = w * h;
        let planes: [Vec<f32>; 4] =
            std::array::from_fn(|c| (0..n).map(|i| unit(7, c as u32, i as u32)).collect());
        let z: Vec<f32> = (0..n)
            .map(|i| {
                if (20..26).contains(&(i % w)) {
                    2.0
                } else {
                    6.0
                }
            })
            .collect();
        let v: Vec<[f32; 2]> = (0..n)
            .map(|i| match (i % w) % 13 {
                0 => [-4.1, 9.7],
                _ if i / w < 11 => [11.3, 2.9],
                _ => [-0.7, -6.25],
            })
            .collect();
        for shutter in [0.5, 1.0] {
            let config = StretchConfig::new(w, h, &StretchParams::default(), shutter);
            let got = texture_blur(&config, &planes, &z, &v);
            for i in 0..n {
                let want = by_definition(&config, &planes, &z, v[i], (i % w, i / w));
                for c in 0..4 {
                    let d = (got[c][i] as f64 - want[c]).abs();
                    assert!(
                        d < 2e-6,
                        "pixel {i} channel {c}: {} against {}",
                        got[c][i],
                        want[c]
                    );
                }
            }
        }
    }
}
