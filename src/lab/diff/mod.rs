//! `shutter diff`: compares two images or two sequences frame by frame, every channel of
//! them (`channels`), with gates for CI (aggregate metric, per-pixel thresholds, non-finite
//! values, channels lost), a heatmap of the per-pixel error and an HTML report (`report`).

pub mod channels;
mod data;
pub mod report;
mod verdict;
pub mod views;

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Serialize;

use crate::error::{Error, Problem, ProblemKind, Result};

use crate::io::passes::{plan_color_in, read_frame, FramePlan};
use crate::io::preset::Preset;
use crate::io::sequence::PathPattern;
use crate::lab::metrics::{self, Metric, Rgb, Scores};

pub use channels::{EveryChannel, Gates, Largest, LayerDiff};

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
    /// The view layer whose beauty is scored (`--layer`), and the view of multi-view EXRs
    /// compared (`--view`); found in the files where `None`.
    pub layer: Option<String>,
    pub view: Option<String>,
    pub linear: bool,
    /// Per-pixel gates: a pixel with a channel over its class's threshold fails, and a frame
    /// with more failing pixels than `allow_pixels`/`fail_percent` allow fails.
    pub gates: Gates,
    /// How many pixels may fail `fail_pixel`: a count, or a share of the frame (the larger).
    pub allow_pixels: usize,
    pub fail_percent: f64,
    /// What share of a frame's pixels (percent) may be over the per-pixel warning
    /// thresholds before the frame warns (idiff's `-warnpercent`).
    pub warn_percent: f64,
    /// Non-finite values (NaN, ±∞) in either image do not fail the frame.
    pub allow_nonfinite: bool,
    /// A folder for the HTML report and its thumbnails (`report`).
    pub report: Option<PathBuf>,
}

/// Scores of one frame.
#[derive(Clone, Debug, Serialize)]
pub struct FrameDiff {
    pub frame: Option<i64>,
    /// The view compared, where the reference is a multi-view file (absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view: Option<String>,
    pub a: PathBuf,
    pub b: PathBuf,
    /// The beauty's RGB (SSIM and FLIP on its display image).
    pub whole: Scores,
    /// Over the pixels where `sharp` and `a` differ (when `--sharp` is given).
    pub region: Option<Scores>,
    /// The gating metric's value for this frame.
    pub value: f64,
    /// Every channel the same in both, NaN and infinities alike, none lacking
    /// ([`channels::Compared::identical`]).
    pub identical: bool,
    /// The largest difference of one sample of any channel, where and what (infinite, `null`
    /// in JSON, at the first sample that became NaN or infinite where one counts).
    pub largest: Largest,
    /// Every channel at once, as idiff gives its figures.
    pub every_channel: EveryChannel,
    /// Each layer's figures: the beauty first.
    pub layers: Vec<LayerDiff>,
    /// Channels of the reference the candidate lacks (a failure), and the reverse (warned).
    pub missing_channels: Vec<String>,
    pub extra_channels: Vec<String>,
    /// The candidate's views the reference lacks, not compared (warned), on the first view's
    /// entry of the frame.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub extra_views: Vec<String>,
    /// The candidate holds views where the reference holds one or none (compared in its
    /// default view, and warned): channel sets that differ, for `--idiff`.
    #[serde(skip)]
    pub candidate_views: bool,
    /// Pixels with a channel over its gate (`--fail-pixel` for colour, `--data-fail-pixel`
    /// for data), and over the warning thresholds.
    pub pixels_over_fail: usize,
    pub pixels_over_warn: usize,
    /// Samples over `--hard-fail`.
    pub samples_over_hard: usize,
    pub warned: bool,
    pub failed: bool,
    /// Why it failed, in words.
    pub why: Option<String>,
    /// What was not compared, and why (parts of another data window).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// With `--report`: the thumbnails written, relative to the report's folder.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub thumbnails: Option<report::Thumbnails>,
    /// What reading each file's colour took for granted (the file's pattern, the warning):
    /// said once a run, in the report's warnings.
    #[serde(skip)]
    pub read_warnings: Vec<(String, String)>,
}

impl FrameDiff {
    /// The entry as lines and messages name it (`frame 12, view right`), or `None` for a
    /// still of no views.
    pub fn name(&self) -> Option<String> {
        match (self.frame, &self.view) {
            (Some(n), Some(view)) => Some(format!("frame {n}, view {view}")),
            (Some(n), None) => Some(format!("frame {n}")),
            (None, Some(view)) => Some(format!("view {view}")),
            (None, None) => None,
        }
    }

    /// [`FrameDiff::name`] as the start of a line: `frame 12, view right: `, or nothing.
    pub fn label(&self) -> String {
        self.name()
            .map_or(String::new(), |name| format!("{name}: "))
    }
}

/// The outcome of a diff.
#[derive(Clone, Debug, Serialize)]
pub struct DiffReport {
    /// The version of this JSON's form (README: "JSON").
    pub schema: u32,
    pub command: &'static str,
    /// True: the comparison was made (whatever its verdict, `failed`).
    pub ok: bool,
    pub metric: &'static str,
    pub warn: Option<f64>,
    pub fail: Option<f64>,
    /// One entry a frame, or one a view of a frame where the reference is multi-view.
    pub frames: Vec<FrameDiff>,
    /// The worst value of the gating metric over the entries.
    pub worst: f64,
    pub warnings: Vec<String>,
    pub failed: bool,
}

impl DiffReport {
    /// What the entries are, for messages: `frames`, or `views` (of frames) where the
    /// reference is a multi-view file.
    pub fn entries(&self) -> &'static str {
        if self.frames.iter().any(|f| f.view.is_some()) {
            "views"
        } else {
            "frames"
        }
    }
}

/// The colour's plan, from its header alone, in the job's view layer and in `view`.
fn plan(
    pattern: &PathPattern,
    frame: Option<i64>,
    view: Option<&str>,
    job: &DiffJob,
    preset: &Preset,
) -> Result<FramePlan, Problem> {
    let chosen = (job.layer.as_deref(), view);
    plan_color_in(pattern, frame, preset, chosen).map_err(|mut problems| problems.remove(0))
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

/// A per-pixel map in [0, 1] as interleaved 8-bit RGB through the magma colour map.
fn magma(map: &[f32]) -> Vec<u8> {
    let lut = nv_flip::magma_lut().to_vec();
    let mut bytes = Vec::with_capacity(map.len() * 3);
    for v in map {
        let index = (v.clamp(0.0, 1.0) * 255.0).round() as usize;
        bytes.extend_from_slice(&lut[index * 3..index * 3 + 3]);
    }
    bytes
}

/// Writes a per-pixel error map in [0, 1] as a PNG with the magma colour map.
pub fn write_heatmap(path: &Path, width: usize, height: usize, map: &[f32]) -> Result<()> {
    let bytes = magma(map);
    if let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| {
            Problem::new(ProblemKind::Output, parent, format!("cannot create: {e}"))
        })?;
    }
    crate::lab::bench::plot::write_png(path, width, height, &bytes)
}

/// The files a run would write (heatmaps; the report's pages and thumbnails) where a
/// folder or something that is not a file (a device, a FIFO) stands, and a report's folders
/// where something else does: refused before anything is written, as blur refuses its
/// outputs (a rename would put a file in a FIFO's or a device's place).
fn outputs_in_the_way(job: &DiffJob, entries: &[Entry]) -> Vec<Problem> {
    let mut writes: Vec<(Option<i64>, PathBuf, &str)> = Vec::new();
    for entry in entries {
        if let Some(heatmap) = &job.heatmap {
            let path = heatmap.path(entry.frame);
            let path =
                (entry.output).map_or_else(|| path.clone(), |v| views::output_path(&path, v));
            writes.push((entry.frame, path, "--heatmap"));
        }
        if let Some(dir) = &job.report {
            let names = report::Thumbnails::of(entry.frame, entry.output);
            for name in names.all() {
                writes.push((entry.frame, dir.join(name), "--report"));
            }
        }
    }
    let mut problems = Vec::new();
    if let Some(dir) = &job.report {
        for name in report::PAGES {
            writes.push((None, dir.join(name), "--report"));
        }
        for folder in [dir.clone(), dir.join("thumbs")] {
            if std::fs::metadata(&folder).is_ok_and(|m| !m.is_dir()) {
                let detail = "the report's folder is not a folder; choose another --report";
                problems.push(Problem::new(ProblemKind::Output, &folder, detail));
            }
        }
    }
    problems.extend(writes.into_iter().filter_map(|(frame, path, flag)| {
        let what = crate::io::passes::in_the_way(&path)?;
        let detail = format!(
            "{what} is in the way of this output and cannot be replaced; move it away, or \
             choose another {flag}"
        );
        Some(Problem::new(ProblemKind::Output, &path, detail).frame(frame))
    }));
    problems
}

/// The error of a run stopped by `problems`, in diff's words: no pass named (the colour it
/// compares is read as blur reads a colour pass, but diff has none: the file says which
/// input it is), and a problem said once (one bad file given as both inputs was said twice).
fn stopped(problems: Vec<Problem>) -> Error {
    let mut said: Vec<Problem> = Vec::with_capacity(problems.len());
    for mut problem in problems {
        problem.pass = None;
        if !said.contains(&problem) {
            said.push(problem);
        }
    }
    Error::Files(said)
}

/// Compares every frame, each view of a multi-view reference apart ([`views`]). Unreadable
/// inputs, views the candidate lacks and size mismatches are errors (all of them reported);
/// metric results, warnings and failures are in the report.
pub fn run(job: &DiffJob) -> Result<DiffReport> {
    let mut preset = job.preset.clone();
    if job.linear {
        preset.color.transfer = crate::io::preset::Transfer::Linear;
    }
    // The views of each frame, from the headers, and the heatmaps' names with them: a view
    // the candidate lacks, or a heatmap over an input, stops the run before anything is
    // decoded or written.
    let mut problems = Vec::new();
    let mut planned = Vec::new();
    for result in job
        .frames
        .par_iter()
        .map(|&frame| views::of_frame(job, frame))
        .collect::<Vec<_>>()
    {
        match result {
            Ok(frame) => planned.push(frame),
            Err(problem) => problems.push(problem),
        }
    }
    problems.extend(views::heatmaps_over_inputs(job, &planned));
    if !problems.is_empty() {
        return Err(stopped(problems));
    }
    let entries: Vec<Entry> = planned
        .iter()
        .flat_map(|f| {
            f.views.iter().enumerate().map(move |(i, view)| Entry {
                frame: f.frame,
                view: view.as_deref(),
                output: f.outputs.as_ref().map(|names| names[i].as_str()),
                extra: if i == 0 { &f.extra[..] } else { &[] },
            })
        })
        .collect();
    // Every entry's files found and planned from their headers before any is compared, so a
    // frame missing from either sequence stops the run before a heatmap or thumbnail is
    // written. (A candidate lacking the reference's colour channels is compared: a lost
    // channel, which fails its frame.)
    let inputs = |entry: &Entry| {
        let (frame, view) = (entry.frame, entry.view);
        let patterns = [Some(&job.a), Some(&job.b), job.sharp.as_ref()];
        patterns
            .into_iter()
            .flatten()
            .filter_map(|pattern| plan(pattern, frame, view, job, &preset).err())
            .filter(|p| {
                // (A candidate lacking colour is a lost channel; a reference of none is
                // compared as data.)
                let data =
                    p.path == job.a.path(frame) && data::holds_no_colour(&p.path, &preset, false);
                p.kind != ProblemKind::MissingChannel || !(p.path == job.b.path(frame) || data)
            })
            .collect::<Vec<_>>()
    };
    problems.extend(entries.par_iter().flat_map(inputs).collect::<Vec<_>>());
    problems.extend(outputs_in_the_way(job, &entries));
    if !problems.is_empty() {
        return Err(stopped(problems));
    }
    let results: Vec<std::result::Result<FrameDiff, Problem>> = entries
        .par_iter()
        .map(|entry| compare(job, &preset, entry))
        .collect();
    let mut frames = Vec::new();
    for result in results {
        match result {
            Ok(frame) => frames.push(frame),
            Err(problem) => problems.push(problem),
        }
    }
    if !problems.is_empty() {
        return Err(stopped(problems));
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
    let mut warnings = read_warnings(&frames);
    for f in &frames {
        let label = f.label();
        if job.warn.is_some_and(|w| job.metric.exceeds(f.value, w)) {
            warnings.push(format!(
                "{label}{name} {:.6} crosses --warn {}",
                f.value,
                job.warn.unwrap_or_default()
            ));
        }
        if verdict::warns_by_pixels(job, f.pixels_over_warn, f.whole.pixels) {
            // The allowance named only where one was given.
            let allowed = match job.warn_percent > 0.0 {
                true => format!(", more than --warn-percent {} allows", job.warn_percent),
                false => String::new(),
            };
            warnings.push(format!(
                "{label}{} pixels over the per-pixel warning (--warn-pixel / \
                 --data-warn-pixel){allowed}",
                f.pixels_over_warn
            ));
        }
        for note in &f.notes {
            warnings.push(format!("{label}{note}"));
        }
        if !f.extra_views.is_empty() {
            // The frame's, not its first view's.
            let label = f.frame.map_or(String::new(), |n| format!("frame {n}: "));
            warnings.push(format!(
                "{label}{} holds the view{} {}, which {} lacks: not compared",
                f.b.display(),
                if f.extra_views.len() == 1 { "" } else { "s" },
                f.extra_views.join(", "),
                f.a.display()
            ));
        }
        if !f.extra_channels.is_empty() {
            warnings.push(format!(
                "{label}the candidate has channels the reference lacks: {}",
                f.extra_channels.join(", ")
            ));
        }
    }
    Ok(DiffReport {
        schema: crate::JSON_SCHEMA,
        command: "diff",
        ok: true,
        metric: name,
        warn: job.warn,
        fail: job.fail,
        failed: frames.iter().any(|f| f.failed),
        frames,
        worst,
        warnings,
    })
}

/// Each warning of the files' reading once, however many frames and files gave it, after the
/// files that did (`a.####.exr and b.####.exr: view right: …`), in the order first met.
fn read_warnings(frames: &[FrameDiff]) -> Vec<String> {
    let mut said: Vec<(&str, Vec<&str>)> = Vec::new();
    for (pattern, warning) in frames.iter().flat_map(|f| &f.read_warnings) {
        match said.iter_mut().find(|(w, _)| w == warning) {
            Some((_, patterns)) if !patterns.contains(&pattern.as_str()) => patterns.push(pattern),
            Some(_) => {}
            None => said.push((warning, vec![pattern])),
        }
    }
    said.into_iter()
        .map(|(warning, patterns)| format!("{}: {warning}", patterns.join(" and ")))
        .collect()
}

/// One comparison: a frame, or a view of a frame.
struct Entry<'a> {
    frame: Option<i64>,
    /// The view read (`None`: the file's default, or a file of no views).
    view: Option<&'a str>,
    /// The view's name in its outputs' names, where every view of the reference is compared.
    output: Option<&'a str>,
    /// The candidate's views the reference lacks (the frame's first entry holds them).
    extra: &'a [String],
}

/// The entry of a frame whose candidate lacks the reference's colour channels (`problem`,
/// its plan's): failed, no figure made.
fn lost_colour(job: &DiffJob, entry: &Entry, a: &FramePlan, problem: Problem) -> FrameDiff {
    let frame = entry.frame;
    // The reference's colour channels the candidate's file does not hold (all of them where
    // it cannot be listed).
    let held = crate::io::file::FileInfo::probe(&job.b.path(frame)).ok();
    let colour = (a.colour_channel_names().into_iter())
        .filter(|name| held.as_ref().is_none_or(|info| info.find(name).is_none()))
        .collect();
    FrameDiff {
        frame,
        view: entry.view.map(str::to_string),
        a: job.a.path(frame),
        b: job.b.path(frame),
        // Not scored: no figure stands for it.
        whole: Scores {
            rmse: f64::NAN,
            mae: f64::NAN,
            psnr: f64::NAN,
            ssim: f64::NAN,
            flip: f64::NAN,
            ..Scores::default()
        },
        region: None,
        value: f64::NAN,
        identical: false,
        largest: Largest::default(),
        every_channel: EveryChannel::default(),
        layers: Vec::new(),
        missing_channels: colour,
        extra_channels: Vec::new(),
        extra_views: entry.extra.to_vec(),
        candidate_views: false,
        pixels_over_fail: 0,
        pixels_over_warn: 0,
        samples_over_hard: 0,
        warned: false,
        failed: true,
        why: Some(format!(
            "the candidate lacks the reference's colour, not compared: {}",
            problem.detail
        )),
        notes: Vec::new(),
        thumbnails: None,
        read_warnings: Vec::new(),
    }
}

/// Compares one entry: sizes and windows from the headers, then every channel.
fn compare(
    job: &DiffJob,
    preset: &Preset,
    entry: &Entry,
) -> std::result::Result<FrameDiff, Problem> {
    let (frame, view) = (entry.frame, entry.view);
    // Sizes from the headers, before anything is decoded: two large images of
    // different sizes are told apart in milliseconds.
    // A reference that holds no colour image (a depth, vector or ID pass on its own) is
    // compared channel by channel as data.
    let a = match plan(&job.a, frame, view, job, preset) {
        // (Only a colour read from a luminance `Y` may be a vector pass's: the header is
        // read again for no other.)
        Ok(a) if data::luminance(&a) && data::holds_no_colour(&job.a.path(frame), preset, true) => {
            return data::compare(job, entry);
        }
        Ok(a) => a,
        Err(problem)
            if problem.kind == ProblemKind::MissingChannel
                && data::holds_no_colour(&job.a.path(frame), preset, false) =>
        {
            return data::compare(job, entry);
        }
        Err(problem) => return Err(problem),
    };
    let b = match plan(&job.b, frame, view, job, preset) {
        Ok(b) => b,
        Err(problem) if problem.kind == ProblemKind::MissingChannel => {
            return Ok(lost_colour(job, entry, &a, problem));
        }
        Err(problem) => return Err(problem),
    };
    let sharp = job
        .sharp
        .as_ref()
        .map(|sharp| plan(sharp, frame, view, job, preset))
        .transpose()?;
    // The view in the report: each of a multi-view reference's, or the one --view names in
    // one; none where the reference is not multi-view (its entries as they always were).
    let multi_view = a.colour_views().is_some_and(|v| v.names.len() > 1);
    let candidate_views = !multi_view && b.colour_views().is_some_and(|v| v.names.len() > 1);
    let named = view.filter(|_| entry.output.is_some() || multi_view);
    let in_view = |detail: String| match named {
        Some(view) => format!("view {view}: {detail}"),
        None => detail,
    };
    let (wa, ha, wb, hb) = (a.width, a.height, b.width, b.height);
    if (wa, ha) != (wb, hb) {
        return Err(Problem::new(
            ProblemKind::SizeMismatch,
            job.b.path(frame),
            in_view(format!(
                "{wb}x{hb} but {} is {wa}x{ha}",
                job.a.path(frame).display()
            )),
        )
        .frame(frame));
    }
    // The same size at another place is another picture (idiff fails it too): the
    // data windows' corners and the display windows must agree, or the pixels
    // compared index by index are not the same pixels.
    if let (Some(wa), Some(wb)) = (a.windows(), b.windows()) {
        let at = |w: crate::frame::Windows| {
            let d = w.display;
            format!(
                "data window at ({}, {}), display window {}x{} at ({}, {})",
                w.data_origin.0, w.data_origin.1, d.width, d.height, d.x, d.y
            )
        };
        if wa != wb {
            return Err(Problem::new(
                ProblemKind::SizeMismatch,
                job.b.path(frame),
                in_view(format!(
                    "{} but {} has its {}",
                    at(wb),
                    job.a.path(frame).display(),
                    at(wa)
                )),
            )
            .frame(frame));
        }
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
    let (mut a, mut b) = (a, b);
    a.read_every_channel();
    b.read_every_channel();
    // Parts the read leaves out (another data window, deep data) are not compared.
    let notes: Vec<String> = [(&a, &job.a), (&b, &job.b)]
        .into_iter()
        .filter(|(plan, _)| !plan.parts_left_out.is_empty())
        .map(|(plan, pattern)| {
            format!(
                "{} of {}: a data window other than the beauty's, deep data, or data \
                 shutter does not decode: not compared",
                plan.parts_left_out.join(", "),
                pattern.path(frame).display()
            )
        })
        .collect();
    // What reading the colour of each file took for granted (grey from a luminance
    // channel, a --view of files that hold none), as `blur` warns it: said once a run
    // ([`read_warnings`]). The parts left out, unreadable ones among them, are the note
    // above.
    let mut read_warnings = Vec::new();
    for (plan, pattern) in [(Some(&a), &job.a), (Some(&b), &job.b)]
        .into_iter()
        .chain([(sharp.as_ref(), job.sharp.as_ref().unwrap_or(&job.a))])
    {
        for warning in plan.map_or(&[][..], |p| &p.warnings[..]) {
            read_warnings.push((pattern.raw.clone(), warning.clone()));
        }
    }
    // Parts not compared, and (below) types that differ, are warnings (`--warn-exit`); the
    // other notes say what was read.
    let mut doubtful = !notes.is_empty();
    let mut notes = notes;
    // A multi-view candidate of a reference of one view or none is compared in its default
    // view: say so, and how to compare another.
    if view.is_none() {
        notes.extend(
            [(&a, &job.a), (&b, &job.b)]
                .into_iter()
                .filter_map(|(plan, pattern)| {
                    let views = plan.colour_views()?;
                    let shown = views.choose(None).ok()?;
                    (views.names.len() > 1).then(|| {
                        format!(
                            "{} holds the views {}: view {shown} is compared (--view \
                         NAME compares another)",
                            pattern.path(frame).display(),
                            views.list()
                        )
                    })
                }),
        );
    }
    // A part the reference's read leaves out that the candidate's does not hold alike (gone,
    // or moved to the beauty's window) is a change no figure shows: lost.
    let parts_lost: Vec<String> = a
        .parts_left_out
        .iter()
        .filter(|part| !b.parts_left_out.contains(part))
        .cloned()
        .collect();
    let (a, b) = (read_frame(&a)?, read_frame(&b)?);
    let (ra, rb) = (
        Rgb::of(&a).expect("colour read"),
        Rgb::of(&b).expect("colour read"),
    );
    let whole = metrics::compare(&ra, &rb, None);
    let region = match &sharp {
        Some(sharp) => {
            let s = read_frame(sharp)?;
            let mask = metrics::changed_region(&Rgb::of(&s).expect("colour read"), &ra, 1e-3);
            Some(metrics::compare(&ra, &rb, Some(&mask)))
        }
        None => None,
    };
    if let Some(heatmap) = &job.heatmap {
        let (map, _) = error_map(job.metric, &ra, &rb);
        let path = heatmap.path(frame);
        let path = entry
            .output
            .map_or_else(|| path.clone(), |v| views::output_path(&path, v));
        write_heatmap(&path, wa, ha, &map).map_err(|e| e.problems()[0].clone())?;
    }
    let value = job.metric.of(&whole);
    // Every channel: the beauty's alpha (a missing alpha reads as opaque), every light
    // and data layer, each against its class's gate.
    let mut compared = channels::compare(&a, &b, &job.gates);
    compared.missing.extend(parts_lost);
    if !compared.retyped.is_empty() {
        doubtful = true;
        notes.push(format!(
            "{} stored as u32 in one file and as float in the other: compared as stored",
            compared.retyped.join(", ")
        ));
    }
    let thumbnails = job
        .report
        .as_ref()
        .map(|dir| report::thumbnails(dir, frame, entry.output, &ra, &rb, &compared.errors))
        .transpose()?;
    let why = verdict::failure(job, &compared, value, wa * ha);
    Ok(FrameDiff {
        frame,
        view: named.map(str::to_string),
        a: job.a.path(frame),
        b: job.b.path(frame),
        whole,
        region,
        value,
        identical: compared.identical(),
        largest: compared.every.max_error.clone(),
        pixels_over_fail: compared.pixels_over_fail,
        pixels_over_warn: compared.pixels_over_warn,
        samples_over_hard: compared.over_hard,
        warned: job.warn.is_some_and(|w| job.metric.exceeds(value, w))
            || verdict::warns_by_pixels(job, compared.pixels_over_warn, wa * ha)
            || !compared.extra.is_empty()
            || !entry.extra.is_empty()
            || doubtful,
        every_channel: compared.every,
        layers: compared.layers,
        missing_channels: compared.missing,
        extra_channels: compared.extra,
        extra_views: entry.extra.to_vec(),
        candidate_views,
        thumbnails,
        notes,
        read_warnings,
        failed: why.is_some(),
        why,
    })
}
