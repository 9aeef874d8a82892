//! SSIM (Wang et al. 2004) with the standard parameters: an 11×11 Gaussian window with
//! σ = 1.5, K1 = 0.01, K2 = 0.03, dynamic range 1, on display luma. The window is applied
//! separably with clamped borders, so every pixel has an SSIM value.

const RADIUS: usize = 5;
const SIGMA: f64 = 1.5;
const C1: f64 = 0.01 * 0.01;
const C2: f64 = 0.03 * 0.03;

fn kernel() -> [f64; 2 * RADIUS + 1] {
    let mut k = [0.0; 2 * RADIUS + 1];
    for (i, v) in k.iter_mut().enumerate() {
        let d = i as f64 - RADIUS as f64;
        *v = (-d * d / (2.0 * SIGMA * SIGMA)).exp();
    }
    let sum: f64 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    k
}

/// Separable Gaussian blur with clamped borders (f64: SSIM subtracts nearly equal sums).
fn blur(input: &[f64], width: usize, height: usize) -> Vec<f64> {
    let k = kernel();
    let mut tmp = vec![0.0; input.len()];
    for j in 0..height {
        for i in 0..width {
            let mut s = 0.0;
            for (t, w) in k.iter().enumerate() {
                let x = (i as isize + t as isize - RADIUS as isize).clamp(0, width as isize - 1);
                s += w * input[j * width + x as usize];
            }
            tmp[j * width + i] = s;
        }
    }
    let mut out = vec![0.0; input.len()];
    for j in 0..height {
        for i in 0..width {
            let mut s = 0.0;
            for (t, w) in k.iter().enumerate() {
                let y = (j as isize + t as isize - RADIUS as isize).clamp(0, height as isize - 1);
                s += w * tmp[y as usize * width + i];
            }
            out[j * width + i] = s;
        }
    }
    out
}

/// The per-pixel SSIM of two luma images.
pub fn ssim_map(a: &[f32], b: &[f32], width: usize, height: usize) -> Vec<f32> {
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let a: Vec<f64> = a.iter().map(|&v| v as f64).collect();
    let b: Vec<f64> = b.iter().map(|&v| v as f64).collect();
    let mu_a = blur(&a, width, height);
    let mu_b = blur(&b, width, height);
    let aa: Vec<f64> = a.iter().map(|v| v * v).collect();
    let bb: Vec<f64> = b.iter().map(|v| v * v).collect();
    let ab: Vec<f64> = a.iter().zip(&b).map(|(x, y)| x * y).collect();
    let (s_aa, s_bb, s_ab) = (
        blur(&aa, width, height),
        blur(&bb, width, height),
        blur(&ab, width, height),
    );
    (0..a.len())
        .map(|i| {
            let (ma, mb) = (mu_a[i], mu_b[i]);
            let va = (s_aa[i] - ma * ma).max(0.0);
            let vb = (s_bb[i] - mb * mb).max(0.0);
            let cov = s_ab[i] - ma * mb;
            (((2.0 * ma * mb + C1) * (2.0 * cov + C2))
                / ((ma * ma + mb * mb + C1) * (va + vb + C2))) as f32
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn identical_is_one_and_a_constant_shift_lowers_luminance_term_only() {
        let a: Vec<f32> = (0..400).map(|i| ((i * 7) % 13) as f32 / 13.0).collect();
        let map = ssim_map(&a, &a, 20, 20);
        assert!(map.iter().all(|&v| close(v, 1.0, 1e-5)));
        // Flat images differing by a constant: SSIM = (2ab + C1) / (a² + b² + C1).
        let flat_a = vec![0.5; 400];
        let flat_b = vec![0.3; 400];
        let expected = ((2.0 * 0.5 * 0.3 + C1) / (0.25 + 0.09 + C1)) as f32;
        let map = ssim_map(&flat_a, &flat_b, 20, 20);
        assert!(map.iter().all(|&v| close(v, expected, 1e-5)), "{}", map[0]);
    }
}
