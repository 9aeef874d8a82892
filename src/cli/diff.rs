//! `shutter diff`: compare images or sequences, gate CI on a metric.

use crate::error::{Error, Result};
use crate::io::preset::Preset;
use crate::io::sequence::{parse_frames, PathPattern};

use super::args::DiffArgs;
use super::out;

/// Frames for a pair of patterns: `--frames`, else those on disk for the first.
fn frames_for(
    first: &PathPattern,
    others: &[&PathPattern],
    spec: Option<&str>,
) -> Result<Vec<Option<i64>>> {
    let sequence = first.is_sequence();
    if others.iter().any(|p| p.is_sequence() != sequence) {
        return Err(Error::usage(
            "give all paths as patterns (#### or %04d) or all as single files",
        ));
    }
    match (spec, sequence) {
        (Some(_), false) => Err(Error::usage("--frames needs patterns with #### or %04d")),
        (Some(spec), true) => Ok(parse_frames(spec)?.into_iter().map(Some).collect()),
        (None, true) => {
            let found = first.discover()?;
            if found.is_empty() {
                return Err(Error::usage(format!(
                    "no files match '{}'; check the pattern or pass --frames",
                    first.raw
                )));
            }
            Ok(found.into_iter().map(Some).collect())
        }
        (None, false) => Ok(vec![None]),
    }
}

fn format_scores(s: &crate::lab::metrics::Scores) -> String {
    format!(
        "rmse {:.6}  psnr {:.2} dB  ssim {:.5}  flip {:.5}  ({} px{})",
        s.rmse,
        s.psnr,
        s.ssim,
        s.flip,
        s.pixels,
        if s.non_finite > 0 {
            format!(", {} non-finite samples", s.non_finite)
        } else {
            String::new()
        }
    )
}

pub fn diff(args: DiffArgs) -> Result<i32> {
    let metric = crate::lab::metrics::Metric::parse(&args.metric).ok_or_else(|| {
        Error::usage(format!(
            "unknown metric '{}'; use rmse, psnr, ssim or flip",
            args.metric
        ))
    })?;
    for (flag, value) in [
        ("--warn", args.warn),
        ("--fail", args.fail),
        ("--fail-pixel", args.fail_pixel),
        ("--warn-pixel", args.warn_pixel),
    ] {
        if value.is_some_and(|v| !v.is_finite()) {
            return Err(Error::usage(format!("{flag} must be a finite number")));
        }
    }
    if !(0.0..=100.0).contains(&args.fail_percent) {
        return Err(Error::usage("--fail-percent must be between 0 and 100"));
    }
    let a = PathPattern::parse(&args.a)?;
    let b = PathPattern::parse(&args.b)?;
    let sharp = args.sharp.as_deref().map(PathPattern::parse).transpose()?;
    let heatmap = args
        .heatmap
        .as_deref()
        .map(PathPattern::parse)
        .transpose()?;
    let mut others = vec![&b];
    others.extend(sharp.as_ref());
    let frames = frames_for(&a, &others, args.frames.as_deref())?;
    if let Some(heatmap) = &heatmap {
        if frames.len() > 1 && !heatmap.is_sequence() {
            return Err(Error::usage(
                "--heatmap must be a pattern with #### or %04d when comparing sequences",
            ));
        }
    }
    let job = crate::lab::diff::DiffJob {
        a,
        b,
        sharp,
        frames,
        metric,
        warn: args.warn,
        fail: args.fail,
        heatmap,
        preset: Preset::load(&args.preset)?,
        linear: args.linear,
        fail_pixel: args.fail_pixel,
        warn_pixel: args.warn_pixel,
        allow_pixels: args.allow_pixels,
        fail_percent: args.fail_percent,
        allow_nonfinite: args.allow_nonfinite,
    };
    let report = crate::lab::diff::run(&job)?;
    if args.json {
        out(&(serde_json::to_string_pretty(&report).unwrap_or_default() + "\n"));
    } else {
        let mut text = String::new();
        for f in &report.frames {
            let label = f.frame.map_or(String::new(), |n| format!("frame {n}: "));
            text += &format!("{label}{}\n", format_scores(&f.whole));
            let m = &f.largest;
            if m.error > 0.0 {
                text += &format!(
                    "{label}largest difference {:.6} at ({}, {}) {}: {} against {}\n",
                    m.error, m.x, m.y, m.channel, m.a, m.b
                );
            }
            if let Some(region) = &f.region {
                text += &format!("{label}changed region: {}\n", format_scores(region));
            }
        }
        if report.frames.len() > 1 {
            text += &format!(
                "worst {}: {:.6} over {} frames\n",
                report.metric,
                report.worst,
                report.frames.len()
            );
        }
        out(&text);
    }
    for warning in &report.warnings {
        eprintln!("shutter: warning: {warning}");
    }
    if report.failed {
        let failed: Vec<&crate::lab::diff::FrameDiff> =
            report.frames.iter().filter(|f| f.failed).collect();
        let first = failed[0];
        let at = first
            .frame
            .map_or(String::new(), |n| format!(" (first: frame {n})"));
        eprintln!(
            "shutter: FAIL: {} of {} frames fail{at}: {}",
            failed.len(),
            report.frames.len(),
            first.why.as_deref().unwrap_or("")
        );
        return Ok(1);
    }
    Ok(0)
}
