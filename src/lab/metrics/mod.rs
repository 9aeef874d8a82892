//! Image error metrics: RMSE, PSNR, SSIM and FLIP, over the whole frame or over a region
//! (a mask, e.g. the pixels that blur changes).
//!
//! **HDR handling.** RMSE and PSNR are computed on the scene-linear values as they are
//! (radiance errors, HDR highlights included; PSNR takes 1.0 as the peak). SSIM and FLIP are
//! perceptual and defined on display values: before them each image is exposed at 0 EV
//! (no scaling), clamped to [0, 1] and sRGB-encoded — what an 8-bit sRGB preview shows.
//! FLIP is LDR-FLIP (Andersson et al. 2020) through the `nv-flip` crate (NVIDIA's C++ code),
//! at 67.02 pixels per degree (FLIP's default viewing conditions); its means are checked against NVIDIA's `flip-evaluator`.
//! Non-finite samples count as 0 and are reported separately.

pub mod ssim;

use crate::io::image::linear_to_srgb;

/// An RGB image for comparison: three planes of `width * height` scene-linear values.
#[derive(Clone, Debug)]
pub struct Rgb<'a> {
    pub width: usize,
    pub height: usize,
    pub planes: [&'a [f32]; 3],
}

impl<'a> Rgb<'a> {
    /// Three colour planes of `width` × `height` pixels.
    pub fn new(planes: &'a [Vec<f32>; 3], width: usize, height: usize) -> Rgb<'a> {
        Rgb {
            width,
            height,
            planes: [&planes[0], &planes[1], &planes[2]],
        }
    }

    /// The RGB of a frame's colour pass, if it has one.
    pub fn of(frame: &'a crate::frame::Frame) -> Option<Rgb<'a>> {
        let color = frame.color.as_ref()?;
        Some(Rgb {
            width: frame.width,
            height: frame.height,
            planes: [&color.r, &color.g, &color.b],
        })
    }
}

/// The metrics of one comparison.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Scores {
    pub rmse: f64,
    /// Mean absolute difference per channel sample.
    pub mae: f64,
    /// PSNR for a peak of 1.0 (display white in scene-linear): `-20 log10(rmse)`.
    pub psnr: f64,
    pub ssim: f64,
    pub flip: f64,
    /// Pixels compared (the region's size).
    pub pixels: usize,
    /// Samples that were NaN or infinite in either image.
    pub non_finite: usize,
}

/// Which metric gates `shutter diff`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    Rmse,
    Psnr,
    Ssim,
    Flip,
}

impl Metric {
    pub const ALL: &'static [(&'static str, Metric)] = &[
        ("rmse", Metric::Rmse),
        ("psnr", Metric::Psnr),
        ("ssim", Metric::Ssim),
        ("flip", Metric::Flip),
    ];

    pub fn parse(name: &str) -> Option<Metric> {
        Self::ALL
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|(_, m)| *m)
    }

    pub fn name(self) -> &'static str {
        Self::ALL
            .iter()
            .find(|(_, m)| *m == self)
            .map_or("?", |(n, _)| n)
    }

    /// True when larger values mean more error (RMSE, FLIP); PSNR and SSIM are similarities.
    pub fn higher_is_worse(self) -> bool {
        matches!(self, Metric::Rmse | Metric::Flip)
    }

    pub fn of(self, scores: &Scores) -> f64 {
        match self {
            Metric::Rmse => scores.rmse,
            Metric::Psnr => scores.psnr,
            Metric::Ssim => scores.ssim,
            Metric::Flip => scores.flip,
        }
    }

    /// Whether `value` is worse than `threshold` for this metric.
    pub fn exceeds(self, value: f64, threshold: f64) -> bool {
        if value.is_nan() {
            return true;
        }
        if self.higher_is_worse() {
            value > threshold
        } else {
            value < threshold
        }
    }
}

fn finite(v: f32) -> f32 {
    if v.is_finite() {
        v
    } else {
        0.0
    }
}

/// Per-pixel squared error summed over the three channels, and the count of non-finite
/// samples.
pub fn squared_error_map(a: &Rgb, b: &Rgb) -> (Vec<f64>, usize) {
    let n = a.width * a.height;
    let mut map = vec![0.0; n];
    let mut bad = 0;
    for c in 0..3 {
        for (i, m) in map.iter_mut().enumerate() {
            let (x, y) = (a.planes[c][i], b.planes[c][i]);
            if !x.is_finite() || !y.is_finite() {
                bad += 1;
            }
            let d = (finite(x) - finite(y)) as f64;
            *m += d * d;
        }
    }
    (map, bad)
}

/// RMSE over the three channels of the pixels in `mask` (all when `None`).
pub fn rmse(a: &Rgb, b: &Rgb, mask: Option<&[bool]>) -> f64 {
    rmse_of_map(&squared_error_map(a, b).0, mask)
}

/// RMSE from a per-pixel squared-error map summed over three channels.
fn rmse_of_map(squared: &[f64], mask: Option<&[bool]>) -> f64 {
    let (sum, count) = masked_sum(squared, mask);
    if count == 0 {
        0.0
    } else {
        (sum / (3 * count) as f64).sqrt()
    }
}

/// Mean absolute difference over the three channels of the pixels in `mask` (all when
/// `None`); non-finite samples count as 0, as in [`rmse`].
pub fn mean_absolute(a: &Rgb, b: &Rgb, mask: Option<&[bool]>) -> f64 {
    let n = a.width * a.height;
    let mut map = vec![0.0f64; n];
    for c in 0..3 {
        for (i, m) in map.iter_mut().enumerate() {
            *m += (finite(a.planes[c][i]) as f64 - finite(b.planes[c][i]) as f64).abs();
        }
    }
    let (sum, count) = masked_sum(&map, mask);
    if count == 0 {
        0.0
    } else {
        sum / (3 * count) as f64
    }
}

/// PSNR in dB for a peak of 1.0; infinite for identical images.
pub fn psnr_from_rmse(rmse: f64) -> f64 {
    if rmse == 0.0 {
        f64::INFINITY
    } else {
        -20.0 * rmse.log10()
    }
}

fn masked_sum(map: &[f64], mask: Option<&[bool]>) -> (f64, usize) {
    match mask {
        Some(mask) => map
            .iter()
            .zip(mask)
            .filter(|(_, &m)| m)
            .fold((0.0, 0), |(s, n), (v, _)| (s + v, n + 1)),
        None => (map.iter().sum(), map.len()),
    }
}

/// The display encoding used before the perceptual metrics: exposure 0 EV, clamp to
/// [0, 1], sRGB transfer; as 8-bit codes, interleaved RGB.
pub fn display_rgb8(image: &Rgb) -> Vec<u8> {
    let n = image.width * image.height;
    let mut out = Vec::with_capacity(n * 3);
    for i in 0..n {
        for c in 0..3 {
            out.push(crate::io::image::encode(image.planes[c][i], true, 255) as u8);
        }
    }
    out
}

/// Display luma (Rec. 709 weights on the display-encoded values), for SSIM.
pub fn display_luma(image: &Rgb) -> Vec<f32> {
    let n = image.width * image.height;
    (0..n)
        .map(|i| {
            let e = |c: usize| linear_to_srgb(finite(image.planes[c][i]).clamp(0.0, 1.0));
            0.2126 * e(0) + 0.7152 * e(1) + 0.0722 * e(2)
        })
        .collect()
}

/// The per-pixel LDR-FLIP error map of `test` against `reference`.
pub fn flip_map(reference: &Rgb, test: &Rgb) -> Vec<f32> {
    flip_map_rgb8(
        reference.width,
        reference.height,
        &display_rgb8(reference),
        &display_rgb8(test),
    )
}

/// FLIP's default viewing conditions (0.7 m from a 0.7 m wide 3840-pixel display):
/// 67.02 pixels per degree, as NVIDIA's tools compute it.
pub fn pixels_per_degree() -> f32 {
    nv_flip::pixels_per_degree(0.7, 3840.0, 0.7)
}

/// LDR-FLIP of two interleaved sRGB 8-bit images.
pub fn flip_map_rgb8(width: usize, height: usize, reference: &[u8], test: &[u8]) -> Vec<f32> {
    if width == 0 || height == 0 {
        return Vec::new();
    }
    let (w, h) = (width as u32, height as u32);
    let reference = nv_flip::FlipImageRgb8::with_data(w, h, reference);
    let test = nv_flip::FlipImageRgb8::with_data(w, h, test);
    nv_flip::flip(reference, test, pixels_per_degree()).to_vec()
}

/// Mean of a per-pixel map over `mask` (all when `None`).
pub fn masked_mean(map: &[f32], mask: Option<&[bool]>) -> f64 {
    let map: Vec<f64> = map.iter().map(|&v| v as f64).collect();
    let (sum, count) = masked_sum(&map, mask);
    if count == 0 {
        0.0
    } else {
        sum / count as f64
    }
}

/// Every metric of `test` against `reference` over `mask` (all pixels when `None`).
pub fn compare(reference: &Rgb, test: &Rgb, mask: Option<&[bool]>) -> Scores {
    let (squared, non_finite) = squared_error_map(reference, test);
    let pixels = mask.map_or(squared.len(), |m| m.iter().filter(|&&v| v).count());
    let rmse = rmse_of_map(&squared, mask);
    let mae = mean_absolute(reference, test, mask);
    let ssim_map = ssim::ssim_map(
        &display_luma(reference),
        &display_luma(test),
        reference.width,
        reference.height,
    );
    let flip = flip_map(reference, test);
    Scores {
        rmse,
        mae,
        psnr: psnr_from_rmse(rmse),
        ssim: if pixels == 0 {
            1.0
        } else {
            masked_mean(&ssim_map, mask)
        },
        flip: masked_mean(&flip, mask),
        pixels,
        non_finite,
    }
}

/// The region that blur changes: pixels where the reference differs from the sharp frame by
/// more than `threshold` in any channel.
pub fn changed_region(sharp: &Rgb, reference: &Rgb, threshold: f32) -> Vec<bool> {
    let n = sharp.width * sharp.height;
    (0..n)
        .map(|i| (0..3).any(|c| (sharp.planes[c][i] - reference.planes[c][i]).abs() > threshold))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn rmse_by_hand() {
        // Differences 0.1, 0.2, 0.3 and three zeros over two pixels: sqrt(0.14 / 6).
        let a = [vec![0.0, 0.0], vec![0.0, 0.0], vec![0.0, 0.0]];
        let b = [vec![0.1, 0.0], vec![0.2, 0.0], vec![0.3, 0.0]];
        let r = rmse(&Rgb::new(&a, 2, 1), &Rgb::new(&b, 2, 1), None);
        assert!(close(r, (0.14f64 / 6.0).sqrt(), 1e-7), "{r}");
        let only_first = [true, false];
        let r = rmse(&Rgb::new(&a, 2, 1), &Rgb::new(&b, 2, 1), Some(&only_first));
        assert!(close(r, (0.14f64 / 3.0).sqrt(), 1e-7), "{r}");
        assert_eq!(psnr_from_rmse(0.1), 20.0);
    }

    #[test]
    fn identical_images_score_perfectly() {
        let a = [vec![0.3; 64], vec![0.5; 64], vec![2.0; 64]];
        let s = compare(&Rgb::new(&a, 8, 8), &Rgb::new(&a, 8, 8), None);
        assert_eq!(s.rmse, 0.0);
        assert!(s.psnr.is_infinite());
        assert!(close(s.ssim, 1.0, 1e-6));
        assert_eq!(s.flip, 0.0);
    }

    #[test]
    fn non_finite_samples_are_counted_not_propagated() {
        let a = [vec![f32::NAN, 0.0], vec![0.0; 2], vec![f32::INFINITY, 0.0]];
        let b = [vec![0.0; 2], vec![0.0; 2], vec![0.0; 2]];
        let s = compare(&Rgb::new(&a, 2, 1), &Rgb::new(&b, 2, 1), None);
        assert_eq!(s.non_finite, 2);
        assert!(s.rmse.is_finite() && s.ssim.is_finite() && s.flip.is_finite());
    }

    #[test]
    fn metric_direction() {
        assert!(Metric::Rmse.exceeds(0.2, 0.1));
        assert!(!Metric::Psnr.exceeds(40.0, 30.0));
        assert!(Metric::Ssim.exceeds(0.8, 0.9));
        assert!(Metric::Flip.exceeds(f64::NAN, 0.1));
    }
}
