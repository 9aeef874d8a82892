//! Deterministic sampling: every random number is a pure hash of (seed, stream, a, b), so a
//! reference is bit-identical for any thread count or frame order.

use glam::DVec2;

/// SplitMix64 finaliser: a good 64-bit mix.
pub fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A hash of four numbers.
pub fn hash(seed: u64, stream: u64, a: u64, b: u64) -> u64 {
    let mut h = mix(seed ^ 0x9E37_79B9_7F4A_7C15);
    h = mix(h ^ stream.wrapping_mul(0xD6E8_FEB8_6659_FD93));
    h = mix(h ^ a.wrapping_mul(0xA076_1D64_78BD_642F));
    mix(h ^ b.wrapping_mul(0xE703_7ED1_A0B4_28DB))
}

/// A uniform number in [0, 1) from the hash.
pub fn hash01(seed: u64, stream: u64, a: u64, b: u64) -> f64 {
    (hash(seed, stream, a, b) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Dimensions of a reference sample: sub-pixel x, y, time, aperture u, v.
pub const DIMENSIONS: usize = 5;

/// The generalised golden ratio for 5 dimensions: the positive root of x⁶ = x + 1.
const PHI_5: f64 = 1.134_724_138_401_519_4;

/// Point `k` of a randomly shifted Kronecker (R₅) sequence: `frac(shift + k·α)` with
/// `αᵢ = φ₅^-(i+1)`. Every prefix is well spread in all five dimensions jointly (unlike
/// independent per-dimension stratification), so edges and streaks converge faster; the
/// per-pixel shift (Cranley–Patterson rotation) comes from the hash and decorrelates pixels.
pub fn kronecker(k: usize, shift: &[f64; DIMENSIONS]) -> [f64; DIMENSIONS] {
    let mut out = [0.0; DIMENSIONS];
    let mut alpha = 1.0;
    for (d, value) in out.iter_mut().enumerate() {
        alpha /= PHI_5;
        *value = (shift[d] + k as f64 * alpha).fract();
    }
    out
}

/// The per-pixel shift of the Kronecker sequence.
pub fn pixel_shift(seed: u64, pixel: u64) -> [f64; DIMENSIONS] {
    let mut shift = [0.0; DIMENSIONS];
    for (d, value) in shift.iter_mut().enumerate() {
        *value = hash01(seed, 100 + d as u64, pixel, 0);
    }
    shift
}

/// Shirley–Chiu concentric map from the unit square to the unit disk (area-preserving, low
/// distortion, so stratification survives).
pub fn concentric_disk(u: f64, v: f64) -> DVec2 {
    let (a, b) = (2.0 * u - 1.0, 2.0 * v - 1.0);
    if a == 0.0 && b == 0.0 {
        return DVec2::ZERO;
    }
    let (r, phi) = if a.abs() > b.abs() {
        (a, std::f64::consts::FRAC_PI_4 * (b / a))
    } else {
        (
            b,
            std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (a / b),
        )
    };
    DVec2::new(phi.cos(), phi.sin()) * r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn hash01_is_uniform_enough() {
        let n = 100_000;
        let mean: f64 = (0..n).map(|i| hash01(5, 1, i, 0)).sum::<f64>() / n as f64;
        assert!(close(mean, 0.5, 0.01), "{mean}");
    }

    #[test]
    fn phi_5_solves_its_equation() {
        assert!(close(PHI_5.powi(6) - PHI_5, 1.0, 1e-12));
    }

    #[test]
    fn kronecker_points_fill_each_dimension_evenly() {
        let shift = pixel_shift(3, 4);
        for d in 0..DIMENSIONS {
            let mut bins = [0usize; 8];
            for k in 0..256 {
                bins[(kronecker(k, &shift)[d] * 8.0) as usize] += 1;
            }
            assert!(
                bins.iter().all(|&b| (28..=36).contains(&b)),
                "dim {d}: {bins:?}"
            );
        }
    }

    #[test]
    fn concentric_map_stays_in_the_disk_and_covers_it() {
        let mut max: f64 = 0.0;
        for i in 0..=20 {
            for j in 0..=20 {
                let p = concentric_disk(i as f64 / 20.0, j as f64 / 20.0);
                max = max.max(p.length());
            }
        }
        assert!(max <= 1.0 + 1e-12 && max > 0.999);
    }
}
