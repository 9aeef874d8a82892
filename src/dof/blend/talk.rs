//! blend's talk form (seed 004, "Depth of Field: Render to Backbuffer"): the sharp frame and
//! two blurred copies of it, texture n and texture 2n, mixed per pixel by the blurriness
//! interpolator T. Chosen by `--blend-form talk`; the default is the [`super::pyramid`].
//!
//! Inputs: colour and the signed CoC plane (px, diameter). Output: the colour with depth of
//! field. It runs on the CPU on either backend (it has no GPU twin).
//!
//! - **Copies.** The talk's filter blit takes four bilinear taps whose effective kernel is
//!   `e/4 + (b+d+f+h)/8 + (a+c+g+i)/16`: the 3×3 binomial, which is [1 2 1]/4 across times
//!   [1 2 1]/4 down. n passes of it are exactly one pass of the binomial kernel
//!   C(2n, k)/4ⁿ across and down (variance n/2 px² per axis), so copy n is made in one
//!   separable pass of that kernel ([`binomial`], cut where its weights fall below 1e-7 and
//!   renormalised) and copy 2n by another from copy n: O(√n) per pixel instead of O(n)
//!   passes.
//! - **Where the copies sit.** A disc of diameter C has variance C²/16 per axis, so copy n
//!   looks like a CoC of √(8n) px and copy 2n like √(16n) ([`equivalent_coc`]). By default
//!   n = E²/16, so copy 2n stands for E ([`default_passes`]). The talk blends sharp → n → 2n
//!   over T ∈ [0, ½, 1]; here each copy is placed at the CoC it actually shows and the blend
//!   runs along CoC = ε + T·(E − ε), which keeps a pixel's blur equal to its CoC between the
//!   copies.
//! - The copies carry colour premultiplied by w and T_near as [`super`] says, and are made
//!   only over the box around out-of-focus pixels that can reach any output.

use rayon::prelude::*;

use super::{largest_coc, IN_FOCUS_WEIGHT};
use crate::dof::DofConfig;
use crate::frame::Color;

/// Binomial weights below this fraction of the centre weight are cut.
const CUT: f64 = 1e-7;

/// The kernel of n passes of [1 2 1]/4: C(2n, n + j)/4ⁿ for j = −h..=h, renormalised.
pub fn binomial(passes: usize) -> Vec<f32> {
    let n = passes as f64;
    // Walk out from the centre with the ratio C(2n, n+j+1)/C(2n, n+j) = (n − j)/(n + j + 1).
    let mut half = vec![1.0f64];
    let mut j = 0.0;
    while j < n {
        let next = half[half.len() - 1] * (n - j) / (n + j + 1.0);
        if next < CUT {
            break;
        }
        half.push(next);
        j += 1.0;
    }
    let mut kernel: Vec<f64> = half.iter().rev().chain(half[1..].iter()).copied().collect();
    let sum: f64 = kernel.iter().sum();
    kernel.iter_mut().for_each(|w| *w /= sum);
    kernel.into_iter().map(|w| w as f32).collect()
}

/// The CoC diameter (px) that `passes` passes of the filter look like: √(8·passes).
pub fn equivalent_coc(passes: usize) -> f32 {
    (8.0 * passes as f32).sqrt()
}

/// The default n: copy 2n stands for a CoC of E.
pub fn default_passes(largest: f32) -> usize {
    ((largest * largest / 16.0).round() as usize).max(1)
}

/// Planar channels over a rectangle.
struct Planes {
    width: usize,
    height: usize,
    channels: Vec<Vec<f32>>,
}

/// One separable pass of `kernel` over every channel, clamped at the rectangle's edges.
fn convolve(planes: &Planes, kernel: &[f32]) -> Planes {
    let (w, h) = (planes.width, planes.height);
    let half = (kernel.len() / 2) as isize;
    let channels = planes
        .channels
        .par_iter()
        .map(|plane| {
            // Across.
            let mut across = vec![0.0f32; w * h];
            across
                .chunks_mut(w)
                .zip(plane.chunks(w))
                .for_each(|(out, row)| {
                    for (x, o) in out.iter_mut().enumerate() {
                        let mut sum = 0.0f32;
                        for (k, weight) in kernel.iter().enumerate() {
                            let sx = (x as isize + k as isize - half).clamp(0, w as isize - 1);
                            sum += weight * row[sx as usize];
                        }
                        *o = sum;
                    }
                });
            // Down, a row at a time so the inner loop runs along memory.
            let mut down = vec![0.0f32; w * h];
            down.chunks_mut(w).enumerate().for_each(|(y, out)| {
                for (k, weight) in kernel.iter().enumerate() {
                    let sy = (y as isize + k as isize - half).clamp(0, h as isize - 1) as usize;
                    let row = &across[sy * w..(sy + 1) * w];
                    out.iter_mut().zip(row).for_each(|(o, v)| *o += weight * v);
                }
            });
            down
        })
        .collect();
    Planes {
        width: w,
        height: h,
        channels,
    }
}

/// The talk's form: the sharp frame and two blurred copies (n and 2n passes), blended by T;
/// `coc` is the signed CoC plane (px, diameter).
pub fn blend(config: &DofConfig, color: &Color, coc: &[f32]) -> Color {
    let (width, height) = (config.width, config.height);
    let epsilon = config.epsilon;
    let largest = largest_coc(coc, epsilon);
    let passes = match config.passes {
        None | Some(0) => default_passes(largest),
        Some(n) => n,
    };
    let kernel = binomial(passes);
    let (coc_1, coc_2) = (equivalent_coc(passes), equivalent_coc(2 * passes));
    let interpolator = |c: f32| ((c.abs() - epsilon) / (largest - epsilon)).clamp(0.0, 1.0);

    // The input, offset by one reference colour so a uniform frame stays exact.
    let inputs: Vec<Vec<f32>> = color.planes().into_iter().map(<[f32]>::to_vec).collect();
    let reference: Vec<f32> = inputs.iter().map(|p| p[0]).collect();
    let channels = inputs.len();

    // The box the copies are needed in: out-of-focus pixels, grown by how far copy 2n
    // reaches, and that again for the pixels they read.
    let reach = (kernel.len() / 2) * 2;
    let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
    for (i, &c) in coc.iter().enumerate() {
        if interpolator(c) > 0.0 {
            let (x, y) = (i % width, i / width);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x);
            y1 = y1.max(y);
        }
    }
    if x0 > x1 {
        return to_color(inputs, color.a.is_some());
    }
    let grow = 2 * reach;
    let (bx0, by0) = (x0.saturating_sub(grow), y0.saturating_sub(grow));
    let (bx1, by1) = ((x1 + grow).min(width - 1), (y1 + grow).min(height - 1));
    let (bw, bh) = (bx1 - bx0 + 1, by1 - by0 + 1);

    // Copy channels: (colour − reference)·w for each channel, w, T_near.
    let mut planes = Planes {
        width: bw,
        height: bh,
        channels: vec![vec![0.0; bw * bh]; channels + 2],
    };
    for y in 0..bh {
        for x in 0..bw {
            let i = (by0 + y) * width + bx0 + x;
            let j = y * bw + x;
            let t = interpolator(coc[i]);
            let w = t.max(IN_FOCUS_WEIGHT);
            for k in 0..channels {
                planes.channels[k][j] = (inputs[k][i] - reference[k]) * w;
            }
            planes.channels[channels][j] = w;
            planes.channels[channels + 1][j] = if coc[i] < 0.0 { t } else { 0.0 };
        }
    }
    let copy_1 = convolve(&planes, &kernel);
    drop(planes);
    let copy_2 = convolve(&copy_1, &kernel);

    let rows: Vec<(usize, Vec<Vec<f32>>)> = (0..bh)
        .into_par_iter()
        .map(|y| {
            let mut row = vec![vec![0.0f32; bw]; channels];
            for x in 0..bw {
                let i = (by0 + y) * width + bx0 + x;
                let j = y * bw + x;
                let t = interpolator(coc[i]).max(copy_2.channels[channels + 1][j]);
                let sharp = |k: usize| inputs[k][i] - reference[k];
                if t <= 0.0 {
                    for (k, r) in row.iter_mut().enumerate() {
                        r[x] = inputs[k][i];
                    }
                    continue;
                }
                let blurred = |copy: &Planes, k: usize| {
                    copy.channels[k][j] / copy.channels[channels][j].max(f32::MIN_POSITIVE)
                };
                let c = epsilon + t * (largest - epsilon);
                for (k, r) in row.iter_mut().enumerate() {
                    let v = if c < coc_1 {
                        let f = c / coc_1;
                        sharp(k) + f * (blurred(&copy_1, k) - sharp(k))
                    } else if c < coc_2 {
                        let f = (c - coc_1) / (coc_2 - coc_1);
                        blurred(&copy_1, k) + f * (blurred(&copy_2, k) - blurred(&copy_1, k))
                    } else {
                        blurred(&copy_2, k)
                    };
                    r[x] = reference[k] + v;
                }
            }
            (y, row)
        })
        .collect();
    // The rows are made: the input planes become the output.
    let mut out = inputs;
    for (y, row) in rows {
        for (k, values) in row.into_iter().enumerate() {
            let start = (by0 + y) * width + bx0;
            out[k][start..start + bw].copy_from_slice(&values);
        }
    }
    to_color(out, color.a.is_some())
}

fn to_color(mut planes: Vec<Vec<f32>>, alpha: bool) -> Color {
    let a = alpha.then(|| planes.pop().expect("alpha plane"));
    let b = planes.pop().expect("b");
    let g = planes.pop().expect("g");
    let r = planes.pop().expect("r");
    Color { r, g, b, a }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn binomial_is_repeated_talk_filter() {
        // Three passes of [1 2 1]/4, convolved by hand: [1 6 15 20 15 6 1]/64.
        let k = binomial(3);
        let expected = [1.0, 6.0, 15.0, 20.0, 15.0, 6.0, 1.0].map(|v: f32| v / 64.0);
        assert_eq!(k.len(), 7);
        for (a, b) in k.iter().zip(expected) {
            assert!(close(*a, b, 1e-7), "{a} vs {b}");
        }
        // Variance n/2 per pass count n, also for long kernels that are cut.
        for n in [1usize, 10, 144] {
            let k = binomial(n);
            let h = (k.len() / 2) as f32;
            let var: f32 = k
                .iter()
                .enumerate()
                .map(|(i, w)| w * (i as f32 - h).powi(2))
                .sum();
            assert!(close(var, n as f32 / 2.0, 1e-3 * n as f32), "{n}: {var}");
        }
        // The 2D kernel of one pass is the talk's e/4 + (b+d+f+h)/8 + (a+c+g+i)/16.
        let k = binomial(1);
        assert_eq!(k, vec![0.25, 0.5, 0.25]);
        assert_eq!(k[1] * k[1], 0.25);
        assert_eq!(k[0] * k[1], 0.125);
        assert_eq!(k[0] * k[0], 0.0625);
    }

    #[test]
    fn copy_two_n_stands_for_e() {
        for e in [8.0f32, 32.0, 48.0] {
            let n = default_passes(e);
            assert!(close(equivalent_coc(2 * n), e, 0.1 * e), "{e}");
        }
    }
}
