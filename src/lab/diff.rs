//! `shutter diff`: compares two images or two sequences frame by frame, with a metric gate
//! for CI (warn and fail thresholds) and a heatmap of the per-pixel error.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Problem, ProblemKind, Result};

use crate::io::passes::{plan_color, read_frame, FramePlan};
use crate::io::preset::Preset;
use crate::io::sequence::PathPattern;
use crate::lab::metrics::{self, Largest, Metric, Rgb, Scores};

/// A diff job.
#[derive(Clone, Debug)]
pub struct DiffJob {
    pub a: PathPattern,
    pub b: PathPattern,
    /// The sharp (unblurred) frames, to score the region blur changes as well.
    pub sharp: Option<PathPattern>,
    pub frames: Vec<Option<i64>>,
    pub metric: Metric,
    pub warn: Option<f64>,
    pub fail: Option<f64>,
    pub heatmap: Option<PathPattern>,
    pub preset: Preset,
    pub linear: bool,
    /// Per-pixel gates: a pixel whose largest channel difference is over `fail_pixel` fails,
    /// and a frame with more failing pixels than `allowed_pixels` allows fails.
    pub fail_pixel: Option<f64>,
    pub warn_pixel: Option<f64>,
    /// How many pixels may fail `fail_pixel`: a count, or a share of the frame (the larger).
    pub allow_pixels: usize,
    pub fail_percent: f64,
    /// Non-finite values (NaN, ±∞) in either image do not fail the frame.
    pub allow_nonfinite: bool,
}

/// Why a frame fails, in words, or `None`.
fn failure(job: &DiffJob, whole: &Scores, value: f64, over_fail: usize) -> Option<String> {
    if whole.non_finite > 0 && !job.allow_nonfinite {
        return Some(format!(
            "{} non-finite samples (NaN or infinite; --allow-nonfinite lets them through)",
            whole.non_finite
        ));
    }
    if let Some(limit) = job.fail {
        if job.metric.exceeds(value, limit) {
            return Some(format!(
                "{} {value:.6} worse than --fail {limit}",
                job.metric.name()
            ));
        }
    }
    if let Some(threshold) = job.fail_pixel {
        let allowed = allowed_pixels(job, whole.pixels);
        if over_fail > allowed {
            return Some(format!(
                "{over_fail} pixels differ by more than --fail-pixel {threshold} (allowed: {allowed})"
            ));
        }
    }
    None
}

/// How many pixels of `pixels` may fail the per-pixel gate.
fn allowed_pixels(job: &DiffJob, pixels: usize) -> usize {
    job.allow_pixels
        .max((job.fail_percent / 100.0 * pixels as f64).floor() as usize)
}

/// Scores of one frame.
#[derive(Clone, Debug, Serialize)]
pub struct FrameDiff {
    pub frame: Option<i64>,
    pub a: PathBuf,
    pub b: PathBuf,
    pub whole: Scores,
    /// Over the pixels where `sharp` and `a` differ (when `--sharp` is given).
    pub region: Option<Scores>,
    /// The gating metric's value for this frame.
    pub value: f64,
    /// The largest difference of one channel (finite samples), where and what.
    pub largest: Largest,
    /// Pixels whose largest channel difference is over `--fail-pixel` and `--warn-pixel`.
    pub pixels_over_fail: usize,
    pub pixels_over_warn: usize,
    pub warned: bool,
    pub failed: bool,
    /// Why it failed, in words.
    pub why: Option<String>,
}

/// The outcome of a diff.
#[derive(Clone, Debug, Serialize)]
pub struct DiffReport {
    pub metric: &'static str,
    pub warn: Option<f64>,
    pub fail: Option<f64>,
    pub frames: Vec<FrameDiff>,
    /// The worst value of the gating metric over the frames.
    pub worst: f64,
    pub warnings: Vec<String>,
    pub failed: bool,
}

/// The colour's plan, from its header alone.
fn plan(pattern: &PathPattern, frame: Option<i64>, preset: &Preset) -> Result<FramePlan, Problem> {
    plan_color(pattern, frame, preset).map_err(|mut problems| problems.remove(0))
}

/// The per-pixel error map of the gating metric, in [0, 1] for the heatmap, and the value
/// that maps to 1.
fn error_map(metric: Metric, a: &Rgb, b: &Rgb) -> (Vec<f32>, f64) {
    match metric {
        Metric::Flip => (metrics::flip_map(a, b), 1.0),
        Metric::Ssim => {
            let map = metrics::ssim::ssim_map(
                &metrics::display_luma(a),
                &metrics::display_luma(b),
                a.width,
                a.height,
            );
            (map.iter().map(|s| (1.0 - s).clamp(0.0, 1.0)).collect(), 1.0)
        }
        Metric::Rmse | Metric::Psnr => {
            let (squared, _) = metrics::squared_error_map(a, b);
            let map: Vec<f32> = squared.iter().map(|s| (s / 3.0).sqrt() as f32).collect();
            let max = map.iter().copied().fold(0.0f32, f32::max).max(1e-12);
            (map.iter().map(|v| v / max).collect(), max as f64)
        }
    }
}

/// Writes a per-pixel error map in [0, 1] as a PNG with the magma colour map.
pub fn write_heatmap(path: &Path, width: usize, height: usize, map: &[f32]) -> Result<()> {
    let lut = nv_flip::magma_lut().to_vec();
    let mut bytes = Vec::with_capacity(map.len() * 3);
    for v in map {
        let index = (v.clamp(0.0, 1.0) * 255.0).round() as usize;
        bytes.extend_from_slice(&lut[index * 3..index * 3 + 3]);
    }
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| {
            Problem::new(ProblemKind::Output, parent, format!("cannot create: {e}"))
        })?;
    }
    crate::io::output::write_atomic(path, |w| {
        use image::ImageEncoder;
        image::codecs::png::PngEncoder::new(w)
            .write_image(
                &bytes,
                width as u32,
                height as u32,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(|e| e.to_string())
    })
    .map_err(|detail| Problem::new(ProblemKind::Output, path, detail).into())
}

/// Compares every frame. Unreadable inputs and size mismatches are errors (all of them
/// reported); metric results, warnings and failures are in the report.
pub fn run(job: &DiffJob) -> Result<DiffReport> {
    let mut preset = job.preset.clone();
    if job.linear {
        preset.color.transfer = crate::io::preset::Transfer::Linear;
    }
    let results: Vec<std::result::Result<FrameDiff, Problem>> = job
        .frames
        .par_iter()
        .map(|&frame| {
            // Sizes from the headers, before anything is decoded: two large images of
            // different sizes are told apart in milliseconds.
            let (a, b) = (plan(&job.a, frame, &preset)?, plan(&job.b, frame, &preset)?);
            let sharp = job
                .sharp
                .as_ref()
                .map(|sharp| plan(sharp, frame, &preset))
                .transpose()?;
            let (wa, ha, wb, hb) = (a.width, a.height, b.width, b.height);
            if (wa, ha) != (wb, hb) {
                return Err(Problem::new(
                    ProblemKind::SizeMismatch,
                    job.b.path(frame),
                    format!("{wb}x{hb} but {} is {wa}x{ha}", job.a.path(frame).display()),
                )
                .frame(frame));
            }
            if let (Some(s), Some(path)) = (&sharp, &job.sharp) {
                let (ws, hs) = (s.width, s.height);
                if (ws, hs) != (wa, ha) {
                    return Err(Problem::new(
                        ProblemKind::SizeMismatch,
                        path.path(frame),
                        format!("{ws}x{hs} but the images are {wa}x{ha}"),
                    )
                    .frame(frame));
                }
            }
            let (a, b) = (read_frame(&a)?, read_frame(&b)?);
            let (ra, rb) = (
                Rgb::of(&a).expect("colour read"),
                Rgb::of(&b).expect("colour read"),
            );
            let whole = metrics::compare(&ra, &rb, None);
            let region = match &sharp {
                Some(sharp) => {
                    let s = read_frame(sharp)?;
                    let mask =
                        metrics::changed_region(&Rgb::of(&s).expect("colour read"), &ra, 1e-3);
                    Some(metrics::compare(&ra, &rb, Some(&mask)))
                }
                None => None,
            };
            if let Some(heatmap) = &job.heatmap {
                let (map, _) = error_map(job.metric, &ra, &rb);
                write_heatmap(&heatmap.path(frame), wa, ha, &map)
                    .map_err(|e| e.problems()[0].clone())?;
            }
            let value = job.metric.of(&whole);
            let (mut errors, mut largest) = metrics::pixel_errors(&ra, &rb);
            // Alpha too (a missing alpha reads as opaque): an alpha-only change is a change.
            fn alpha(f: &crate::frame::Frame) -> Option<&[f32]> {
                f.color.as_ref().and_then(|c| c.a.as_deref())
            }
            let (a_alpha, b_alpha) = (alpha(&a), alpha(&b));
            if a_alpha.is_some() || b_alpha.is_some() {
                let ones = vec![1.0; wa * ha];
                metrics::add_channel(
                    a_alpha.unwrap_or(&ones),
                    b_alpha.unwrap_or(&ones),
                    ("A", wa),
                    &mut errors,
                    &mut largest,
                );
            }
            let over = |threshold: Option<f64>| {
                threshold.map_or(0, |t| errors.iter().filter(|&&e| e as f64 > t).count())
            };
            let (pixels_over_fail, pixels_over_warn) = (over(job.fail_pixel), over(job.warn_pixel));
            let why = failure(job, &whole, value, pixels_over_fail);
            Ok(FrameDiff {
                frame,
                a: job.a.path(frame),
                b: job.b.path(frame),
                whole,
                region,
                value,
                largest,
                pixels_over_fail,
                pixels_over_warn,
                warned: job.warn.is_some_and(|w| job.metric.exceeds(value, w))
                    || pixels_over_warn > 0,
                failed: why.is_some(),
                why,
            })
        })
        .collect();
    let mut frames = Vec::new();
    let mut problems = Vec::new();
    for result in results {
        match result {
            Ok(frame) => frames.push(frame),
            Err(problem) => problems.push(problem),
        }
    }
    if !problems.is_empty() {
        return Err(Error::Files(problems));
    }
    let worst = frames
        .iter()
        .map(|f| f.value)
        .reduce(|a, b| {
            if job.metric.exceeds(a, b) || a.is_nan() {
                a
            } else {
                b
            }
        })
        .unwrap_or(0.0);
    let name = job.metric.name();
    let mut warnings = Vec::new();
    for f in &frames {
        let label = f.frame.map_or(String::new(), |n| format!("frame {n}: "));
        if job.warn.is_some_and(|w| job.metric.exceeds(f.value, w)) {
            warnings.push(format!(
                "{label}{name} {:.6} crosses --warn {}",
                f.value,
                job.warn.unwrap_or_default()
            ));
        }
        if f.pixels_over_warn > 0 {
            warnings.push(format!(
                "{label}{} pixels differ by more than --warn-pixel {}",
                f.pixels_over_warn,
                job.warn_pixel.unwrap_or_default()
            ));
        }
    }
    Ok(DiffReport {
        metric: name,
        warn: job.warn,
        fail: job.fail,
        failed: frames.iter().any(|f| f.failed),
        frames,
        worst,
        warnings,
    })
}
