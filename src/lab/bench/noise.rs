//! The references' noise floor. A reference is a Monte Carlo estimate: its own noise adds to
//! every error measured against it, in quadrature, and hides differences between settings
//! whose errors are within a few times that noise.
//!
//! Rendering the reference twice with different sampling seeds (the same scene layout, other
//! sub-pixel, time and aperture samples) gives two independent estimates r1, r2 of the
//! converged image c with the same per-pixel variance σ²: E[(r1 − r2)²] = 2σ². For an output
//! x whose error does not depend on r1's noise, E[(x − r1)²] = E[(x − c)²] + σ², so the error
//! against the converged reference is estimated by
//! `corrected = sqrt(max(0, RMSE² − σ̂²))` with `σ̂² = mean((r1 − r2)²) / 2`, both means over
//! the same pixels and channels as the RMSE.
//!
//! Where an output shares r1's samples its error is correlated with r1's noise and the
//! correction over-subtracts: the truth scenes' colour pass uses the reference's sub-pixel
//! positions, so pixels that nothing crosses are equal in both (that is why the region
//! leaves them out); in the region, outputs are computed from a frame at one instant and
//! share no time or aperture samples with it.

use crate::lab::metrics::{squared_error_map, Rgb};

/// The per-sample noise variance of a reference estimated from two renders with different
/// sampling seeds, over the pixels in `mask` (all when `None`) and the three channels:
/// mean((r1 − r2)²) / 2. Zero over an empty region.
pub fn noise_variance(first: &Rgb, second: &Rgb, mask: Option<&[bool]>) -> f64 {
    let (squared, _) = squared_error_map(first, second);
    let (sum, count) = squared
        .iter()
        .enumerate()
        .filter(|(i, _)| mask.is_none_or(|m| m[*i]))
        .fold((0.0, 0usize), |(s, n), (_, v)| (s + v, n + 1));
    if count == 0 {
        0.0
    } else {
        sum / (3 * count) as f64 / 2.0
    }
}

/// The RMSE against the converged reference, estimated from the RMSE against a noisy one and
/// that reference's noise variance: sqrt(max(0, rmse² − variance)).
pub fn corrected_rmse(rmse: f64, variance: f64) -> f64 {
    (rmse * rmse - variance).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::metrics::rmse;
    use crate::numeric::close;

    /// Walsh functions of index `k` over `n` samples: ±1, mutually orthogonal over any
    /// multiple of 2^(bits) samples, so sums of their products vanish exactly.
    fn walsh(k: usize, n: usize) -> Vec<f32> {
        (0..n)
            .map(|i| {
                if (i & k).count_ones().is_multiple_of(2) {
                    1.0
                } else {
                    -1.0
                }
            })
            .collect()
    }

    #[test]
    fn the_correction_recovers_the_error_against_the_converged_image_exactly() {
        // A converged image c, an output c + δ·d and two references c + σ·a, c + σ·b with
        // d, a, b orthogonal ±1 patterns: the output's error against c is δ exactly, its RMSE
        // against the first reference sqrt(δ² + σ²), and mean((a − b)²)/2 = 1.
        let (w, h) = (16, 8);
        let n = w * h;
        let (delta, sigma) = (0.03f32, 0.02f32);
        let c: Vec<f32> = (0..n).map(|i| 0.2 + 0.001 * i as f32).collect();
        let plus = |pattern: &[f32], scale: f32| -> [Vec<f32>; 3] {
            let p: Vec<f32> = c.iter().zip(pattern).map(|(c, p)| c + scale * p).collect();
            [p.clone(), p.clone(), p]
        };
        let converged = [c.clone(), c.clone(), c.clone()];
        let output = plus(&walsh(1, n), delta);
        let first = plus(&walsh(2, n), sigma);
        let second = plus(&walsh(4, n), sigma);
        let (output, first, second, converged) = (
            Rgb::new(&output, w, h),
            Rgb::new(&first, w, h),
            Rgb::new(&second, w, h),
            Rgb::new(&converged, w, h),
        );
        let truth = rmse(&converged, &output, None);
        assert!(close(truth, delta as f64, 1e-6), "{truth}");
        let variance = noise_variance(&first, &second, None);
        assert!(close(variance.sqrt(), sigma as f64, 1e-6), "{variance}");
        let raw = rmse(&first, &output, None);
        assert!(close(raw, (delta as f64).hypot(sigma as f64), 1e-6));
        let corrected = corrected_rmse(raw, variance);
        assert!(close(corrected, truth, 1e-6), "{corrected} vs {truth}");
    }

    #[test]
    fn the_noise_variance_is_taken_over_the_region_only() {
        let first = [vec![0.0, 0.0], vec![0.0, 0.0], vec![0.0, 0.0]];
        let second = [vec![0.2, 5.0], vec![0.2, 5.0], vec![0.2, 5.0]];
        let (a, b) = (Rgb::new(&first, 2, 1), Rgb::new(&second, 2, 1));
        let v = noise_variance(&a, &b, Some(&[true, false]));
        assert!(close(v, 0.02, 1e-9), "{v}");
        assert_eq!(noise_variance(&a, &b, Some(&[false, false])), 0.0);
    }

    #[test]
    fn an_error_below_the_noise_floor_is_zero_not_imaginary() {
        assert_eq!(corrected_rmse(0.01, 0.0004), 0.0);
        assert!(close(corrected_rmse(0.05, 0.0009), 0.04, 1e-12));
    }

    #[test]
    fn independent_random_noise_is_removed_within_its_sampling_error() {
        // Independent uniform noise of variance σ² = s²/3 in both references and an output
        // with a smooth error of RMSE e: the corrected RMSE lands near e.
        let (w, h) = (256, 256);
        let n = w * h;
        let s = 0.05f64;
        let noise = |seed: u32| -> Vec<f32> {
            (0..n)
                .map(|i| {
                    let u = crate::numeric::unit(seed, 0, i as u32) as f64;
                    (s * (2.0 * u - 1.0)) as f32
                })
                .collect()
        };
        let c: Vec<f32> = (0..n).map(|i| ((i % w) as f32 / w as f32) * 0.5).collect();
        let e = 0.02f32;
        let out: Vec<f32> = c
            .iter()
            .enumerate()
            .map(|(i, c)| c + e * ((i / w) as f32 * 0.1).sin() * std::f32::consts::SQRT_2)
            .collect();
        let add =
            |a: &[f32], b: &[f32]| -> Vec<f32> { a.iter().zip(b).map(|(a, b)| a + b).collect() };
        let (n1, n2, n3, n4, n5, n6) = (noise(1), noise(2), noise(3), noise(4), noise(5), noise(6));
        let first = [add(&c, &n1), add(&c, &n2), add(&c, &n3)];
        let second = [add(&c, &n4), add(&c, &n5), add(&c, &n6)];
        let output = [out.clone(), out.clone(), out];
        let converged = [c.clone(), c.clone(), c];
        let truth = rmse(&Rgb::new(&converged, w, h), &Rgb::new(&output, w, h), None);
        let raw = rmse(&Rgb::new(&first, w, h), &Rgb::new(&output, w, h), None);
        let variance = noise_variance(&Rgb::new(&first, w, h), &Rgb::new(&second, w, h), None);
        assert!(close(variance, s * s / 3.0, 0.02 * s * s), "{variance}");
        let corrected = corrected_rmse(raw, variance);
        assert!(
            raw > 1.5 * truth,
            "the noise matters here: {raw} vs {truth}"
        );
        assert!(
            close(corrected, truth, 0.03 * truth),
            "{corrected} vs {truth}"
        );
    }
}
