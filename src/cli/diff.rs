//! `shutter diff`: compare images or sequences, gate CI on a metric.

use std::path::Path;

use crate::error::{printable, Error, Result};
use crate::io::preset::Preset;
use crate::io::sequence::{parse_frames, PathPattern};

use super::args::DiffArgs;
use super::out_text;

/// Frames for a pair of patterns: `--frames`, else those on disk for the first (with a
/// warning for the holes between them).
fn frames_for(
    first: &PathPattern,
    others: &[&PathPattern],
    spec: Option<&str>,
) -> Result<(Vec<Option<i64>>, Vec<String>)> {
    let sequence = first.is_sequence();
    if others.iter().any(|p| p.is_sequence() != sequence) {
        return Err(Error::usage(
            "give all paths as patterns (#### or %04d) or all as single files",
        ));
    }
    match (spec, sequence) {
        (Some(_), false) => Err(Error::usage("--frames needs patterns with #### or %04d")),
        (Some(spec), true) => Ok((
            parse_frames(spec)?.into_iter().map(Some).collect(),
            Vec::new(),
        )),
        (None, true) => {
            let discovered = first.discover()?;
            let beyond = discovered.beyond_note(first);
            let padding = discovered.padding_note(first);
            let found = discovered.frames;
            if found.is_empty() {
                // Nothing to compare: the files are not there (not a bad command line).
                return Err(Error::Files(vec![crate::error::Problem::new(
                    crate::error::ProblemKind::MissingFile,
                    std::path::Path::new(&first.raw),
                    super::resolve::no_match(beyond.or(padding)),
                )]));
            }
            let holes = crate::io::holes::holes(&found);
            let mut warnings: Vec<String> = beyond.into_iter().collect();
            if !holes.is_empty() {
                warnings.push(format!(
                    "'{}' has no frame{} {} between {} and {}{}: not compared (--frames names \
                     every frame wanted and makes a missing one an error)",
                    first.raw,
                    if holes.len() == 1 { "" } else { "s" },
                    crate::io::sequence::format_frames(&holes),
                    found[0],
                    found[found.len() - 1],
                    crate::io::holes::mixed_steps(&found)
                        .map_or(String::new(), |m| format!(" ({m})"))
                ));
            }
            Ok((found.into_iter().map(Some).collect(), warnings))
        }
        (None, false) => Ok((vec![None], Vec::new())),
    }
}

/// A difference in the text output: six decimals, or three significant digits where it is
/// not 0 yet under 0.0001, so that a real difference of 1e-7 never prints as 0.000000.
fn figure(v: f64) -> String {
    if v != 0.0 && v.abs() < 1e-4 {
        format!("{v:.2e}")
    } else {
        format!("{v:.6}")
    }
}

fn format_scores(s: &crate::lab::metrics::Scores) -> String {
    format!(
        "rmse {}  mae {}  psnr {:.2} dB (peak 1)  ssim {:.5}  flip {:.5}  ({} px{})",
        figure(s.rmse),
        figure(s.mae),
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

/// How `diff` reports its outcome as an exit code: its own table, or idiff's (README:
/// "Exit codes").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Codes {
    Shutter { warn_exit: bool },
    Idiff,
}

impl Codes {
    pub fn of(args: &DiffArgs) -> Codes {
        if args.idiff {
            Codes::Idiff
        } else {
            Codes::Shutter {
                warn_exit: args.warn_exit,
            }
        }
    }

    /// The code for a comparison made: failed, warned, and whether the channel sets differ.
    fn verdict(self, failed: bool, warned: bool, channels_differ: bool) -> i32 {
        match self {
            Codes::Shutter { warn_exit } => {
                if failed {
                    1
                } else if warned && warn_exit {
                    4
                } else {
                    0
                }
            }
            // Debian's idiff 2.4 fails images whose channels differ (exit 2), as sizes.
            Codes::Idiff if failed || channels_differ => 2,
            Codes::Idiff if warned => 1,
            Codes::Idiff => 0,
        }
    }

    /// The code for a comparison not made: a bad command line, sizes that differ, or an
    /// input that cannot be read.
    pub fn error(self, error: &Error) -> i32 {
        let sizes = !error.problems().is_empty()
            && error
                .problems()
                .iter()
                .all(|p| p.kind == crate::error::ProblemKind::SizeMismatch);
        match (self, error) {
            (Codes::Shutter { .. }, Error::Usage(_)) => 2,
            (Codes::Shutter { .. }, _) => 3,
            // Debian's idiff 2.4 compares sizes that differ and fails them (exit 2).
            (Codes::Idiff, _) if sizes => 2,
            (Codes::Idiff, _) => 4,
        }
    }
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
        ("--data-fail-pixel", args.data_fail_pixel),
        ("--data-warn-pixel", args.data_warn_pixel),
        ("--hard-fail", args.hard_fail),
        ("--fail-relative", Some(args.fail_relative)),
        ("--warn-relative", Some(args.warn_relative)),
    ] {
        if value.is_some_and(|v| !v.is_finite()) {
            return Err(Error::usage(format!("{flag} must be a finite number")));
        }
        if flag != "--warn" && flag != "--fail" && value.is_some_and(|v| v < 0.0) {
            return Err(Error::usage(format!("{flag} must not be negative")));
        }
    }
    for (flag, percent) in [
        ("--fail-percent", args.fail_percent),
        ("--warn-percent", args.warn_percent),
    ] {
        if !(0.0..=100.0).contains(&percent) {
            return Err(Error::usage(format!("{flag} must be between 0 and 100")));
        }
    }
    let a = PathPattern::parse(&args.a)?;
    let b = PathPattern::parse(&args.b)?;
    let sharp = args.sharp.as_deref().map(PathPattern::parse).transpose()?;
    let heatmap = args
        .heatmap
        .as_deref()
        .map(PathPattern::parse)
        .transpose()?;
    if let Some(heatmap) = &heatmap {
        let png = Path::new(&heatmap.raw)
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("png"));
        if !png {
            return Err(Error::usage(format!(
                "--heatmap {}: the heatmap is written as PNG; give a name ending in .png",
                heatmap.raw
            )));
        }
    }
    let mut others = vec![&b];
    others.extend(sharp.as_ref());
    let (frames, hole_warnings) = frames_for(&a, &others, args.frames.as_deref())?;
    // A heatmap that names an input is refused by the run, before anything is written,
    // with each view's name (`lab::diff::views`). Its form follows the inputs', as blur's
    // -o does: a pattern of single files would be written under its placeholder's name
    // (`one.####.png`).
    if let Some(heatmap) = &heatmap {
        if frames.len() > 1 && !heatmap.is_sequence() {
            return Err(Error::usage(
                "--heatmap must be a pattern with #### or %04d when comparing sequences",
            ));
        }
        if !a.is_sequence() && heatmap.is_sequence() {
            return Err(Error::usage(format!(
                "--heatmap '{}' is a frame pattern but the inputs are single files; give a \
                 file name ending in .png (or input patterns and --frames)",
                heatmap.raw
            )));
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
        layer: args.layer.clone(),
        view: args.view.clone(),
        linear: args.linear,
        gates: gates(&args),
        allow_pixels: args.allow_pixels,
        fail_percent: args.fail_percent,
        warn_percent: args.warn_percent,
        allow_nonfinite: args.allow_nonfinite,
        report: args.report.clone(),
    };
    let mut report = crate::lab::diff::run(&job)?;
    report.warnings.splice(0..0, hole_warnings);
    // With no gate, a picture that changed passes: said, so that `shutter diff golden out`
    // in CI is not taken for a check of the pixels (an outside tester's finding).
    let gates = &job.gates;
    // (A warning threshold is a choice too: a run that asks only to be warned is told so.)
    let gated = job.fail.is_some()
        || job.warn.is_some()
        || [gates.fail, gates.data_fail, gates.hard_fail]
            .iter()
            .chain([&gates.warn, &gates.data_warn])
            .any(Option::is_some);
    let differ = (report.frames.iter())
        .filter(|f| !f.identical && !f.failed)
        .count();
    if !gated && differ > 0 {
        report.warnings.push(format!(
            "{differ} of {} {} differ and pass: no gate was given (--fail, --fail-pixel, \
             --data-fail-pixel or --hard-fail), so only non-finite values and lost channels \
             fail a frame",
            report.frames.len(),
            report.entries()
        ));
    }
    if args.json {
        super::out_json(&report)?;
    } else {
        let mut text = String::new();
        for f in &report.frames {
            let label = f.label();
            text += &format!("{label}{}\n", format_scores(&f.whole));
            let e = &f.every_channel;
            let m = &f.largest;
            // The figures count a non-finite sample as 0: said, where there are some, so
            // that "psnr inf" beside a NaN does not read as identical.
            let left_out: usize = f.layers.iter().map(|l| l.non_finite).sum();
            text += &format!(
                "{label}every channel ({}): mean error {}  rms error {}  psnr {:.2} dB (peak {}){}\n",
                e.channels,
                figure(e.mean_error),
                figure(e.rms_error),
                e.psnr,
                crate::numeric::shown_sample(e.psnr_peak),
                if left_out > 0 {
                    format!(", {left_out} non-finite samples counted as 0")
                } else {
                    String::new()
                }
            );
            if m.error > 0.0 {
                text += &format!(
                    "{label}largest difference {} at ({}, {}) {}: {} against {}\n",
                    figure(m.error),
                    m.x,
                    m.y,
                    printable(&m.channel),
                    m.value_text(m.a),
                    m.value_text(m.b)
                );
            }
            for layer in f.layers.iter().skip(1) {
                if layer.largest.error > 0.0 || layer.non_finite > 0 {
                    text += &format!(
                        "{label}layer {} ({}): rmse {}  mae {}  largest {} at ({}, {}) {}{}\n",
                        printable(&layer.layer),
                        layer.class,
                        figure(layer.rmse),
                        figure(layer.mae),
                        figure(layer.largest.error),
                        layer.largest.x,
                        layer.largest.y,
                        printable(&layer.largest.channel),
                        if layer.non_finite > 0 {
                            format!(", {} non-finite", layer.non_finite)
                        } else {
                            String::new()
                        }
                    );
                }
            }
            if !f.missing_channels.is_empty() {
                text += &format!(
                    "{label}missing from the candidate: {}\n",
                    printable(&f.missing_channels.join(", "))
                );
            }
            if let Some(region) = &f.region {
                text += &format!("{label}changed region: {}\n", format_scores(region));
            }
        }
        if report.frames.len() > 1 {
            text += &format!(
                "worst {}: {:.6} over {} {}\n",
                report.metric,
                report.worst,
                report.frames.len(),
                report.entries()
            );
        }
        out_text(&text)?;
    }
    if let Some(dir) = &args.report {
        crate::lab::diff::report::write(dir, &report)?;
    }
    if !args.quiet {
        for warning in &report.warnings {
            say!("shutter: warning: {warning}");
        }
    }
    let warned = report.frames.iter().any(|f| f.warned);
    let channels_differ = report.frames.iter().any(|f| {
        !f.missing_channels.is_empty()
            || !f.extra_channels.is_empty()
            || !f.extra_views.is_empty()
            || f.candidate_views
    });
    let code = Codes::of(&args).verdict(report.failed, warned, channels_differ);
    if report.failed {
        let failed: Vec<&crate::lab::diff::FrameDiff> =
            report.frames.iter().filter(|f| f.failed).collect();
        let first = failed[0];
        let at = first
            .name()
            .map_or(String::new(), |name| format!(" (first: {name})"));
        say!(
            "shutter: FAIL: {} of {} {} fail{at}: {}",
            failed.len(),
            report.frames.len(),
            report.entries(),
            first.why.as_deref().unwrap_or("")
        );
    }
    Ok(code)
}

/// The per-pixel gates the flags give; with --idiff, idiff's default thresholds where no
/// threshold of that kind is given.
fn gates(args: &DiffArgs) -> crate::lab::diff::Gates {
    let idiff = |given: Option<f64>| given.or(args.idiff.then_some(1e-6));
    crate::lab::diff::Gates {
        fail: idiff(args.fail_pixel),
        warn: idiff(args.warn_pixel),
        data_fail: idiff(args.data_fail_pixel),
        data_warn: idiff(args.data_warn_pixel),
        fail_relative: args.fail_relative,
        warn_relative: args.warn_relative,
        hard_fail: args.hard_fail,
        allow_nonfinite: args.allow_nonfinite,
    }
}
