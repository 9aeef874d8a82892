//! The frame pipeline: preflight every frame, then read → process → write with the three
//! stages overlapped (frame n+1 decodes while frame n is processed and frame n-1 is written),
//! rayon inside each stage. Hand-offs are rendezvous channels, so at most about three frames
//! are in memory whatever the sequence length. The library never prints: progress goes to a
//! callback, the summary comes back as a [`Report`].

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::Instant;

use serde::Serialize;

use crate::error::{Problem, ProblemKind, Result};
use crate::frame::Frame;
use crate::gpu::{Backend, BackendReport};
use crate::io::lock::OutputLock;
use crate::io::output::{remove_stale_temporaries, write_views, OutputFormat, OutputOptions};
use crate::io::output_notes::output_notes;
use crate::io::passes::{
    output_folder_problems, preflight, read_frame_keeping, FramePlan, Inputs, PlanOptions,
    VectorCheck,
};
use crate::io::preset::Preset;
use crate::io::sequence::PathPattern;
use crate::motion::Algorithm;
use crate::numeric::Replaced;
use crate::process::{depth_kind, process_on, Params};

mod existing;
mod hints;
mod memory;
mod warnings;
use existing::{existing_output, made_otherwise_warning, other_settings, Existing};
pub use memory::{memory_limit, peak_rss_mib};
use warnings::replaced_warnings;

/// A blur job, fully resolved (preset merged, flags applied, frames listed).
#[derive(Clone, Debug)]
pub struct Job {
    pub inputs: Inputs,
    pub output: PathPattern,
    /// Frame numbers; `[None]` for a single still.
    pub frames: Vec<Option<i64>>,
    pub preset: Preset,
    pub layer: Option<String>,
    /// A stack of view layers, front first (`--layers`, or `--color` repeated): each read,
    /// blurred alone and merged front over back (`crate::stack`). Empty: no stack.
    pub stack: Vec<StackLayer>,
    /// The view of multi-view EXRs to read (`--view`). `None`: every view of a multi-view
    /// colour file into an EXR output of every channel, else each file's default.
    pub view: Option<String>,
    pub algorithm: Algorithm,
    pub params: Params,
    pub output_options: OutputOptions,
    pub skip_existing: bool,
    /// Where the stages that have a GPU twin run (`--backend`).
    pub backend: Backend,
    /// The largest input frame in pixels (setting `max-pixels`).
    pub max_pixels: usize,
    /// The most memory the run may need, in bytes (setting `max-memory`); `None`:
    /// [`memory_limit`].
    pub max_memory: Option<u64>,
    /// Preflight only: report what each frame would do, read no pixels, write nothing.
    pub dry_run: bool,
    /// Warnings found while resolving the job (flags that do not apply), reported by [`run`].
    pub warnings: Vec<String>,
    /// Fit the stored vectors against the motion in the frames read, and warn when the
    /// preset's reading fits clearly worse than another (`--check-vectors`;
    /// `io::passes::VectorCheck`).
    pub check_vectors: bool,
}

/// A layer of a stack.
#[derive(Clone, Debug)]
pub struct StackLayer {
    /// Its name: in a file of several view layers, the one `--layers` gave; with a file of
    /// its own, what its channels are named under in the output (`fg.R`), unless they are
    /// already (`FG.Combined.R`).
    pub name: String,
    /// Its own pass files (one file a layer); `None`: the job's (a file of view layers).
    pub inputs: Option<Inputs>,
    /// What `{layer}` stands for in the preset's channel names when it reads this layer
    /// (`None`: the view layer found in the file).
    pub layer: Option<String>,
}

/// What the pipeline tells its caller while it runs.
#[derive(Clone, Debug)]
pub enum Event {
    /// Preflight passed; this many frames will be written.
    Started { frames: usize },
    /// A frame was written.
    Written { frame: Option<i64>, path: PathBuf },
    /// A frame was skipped because its output exists and is a finished frame of the right
    /// size and format (`--skip-existing`).
    Skipped { frame: Option<i64>, path: PathBuf },
    /// Something the user should know; the job goes on.
    Warning(String),
}

/// The summary of a run.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Report {
    /// The version of the `--json` document's form ([`crate::JSON_SCHEMA`]).
    pub schema: u32,
    /// The command that ran (`blur`, `dof`: the command line sets it).
    pub command: &'static str,
    /// True: the run finished (a failed run's `--json` is an error object instead).
    pub ok: bool,
    pub algorithm: String,
    pub preset: String,
    /// The exposure the motion blur rendered: the fraction of the frame interval the shutter
    /// is open, and where it sits about the frame in exposures (0 centred, 0.5 opening at the
    /// frame, −0.5 closing at it; `motion::Shutter`).
    pub shutter: f32,
    pub shutter_offset: f32,
    pub frames_written: usize,
    pub frames_skipped: usize,
    /// Seconds spent in each stage, summed over frames (the stages overlap in time).
    pub read_seconds: f64,
    pub process_seconds: f64,
    pub write_seconds: f64,
    pub preflight_seconds: f64,
    /// What the vector check did (`--check-vectors`); absent when it was off or had nothing
    /// to check (a still, no motion read).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vector_check: Option<crate::io::passes::CheckReport>,
    /// Wall-clock seconds for the whole job.
    pub wall_seconds: f64,
    /// Peak resident memory of the process, in MiB, where the OS reports it.
    pub peak_rss_mib: Option<f64>,
    pub warnings: Vec<String>,
    /// The backend asked for and the one used (and why `auto` fell back to the CPU).
    pub backend: BackendReport,
    /// Input values the numeric policy replaced (NaN, infinite or out of range), per pass,
    /// summed over frames.
    pub replaced: Replaced,
    /// With `--dry-run`: what the run would do for each frame (nothing is read beyond the
    /// headers, nothing written).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub planned: Vec<Planned>,
    /// The frames written, in frame order, and those `--skip-existing` skipped.
    pub outputs: Vec<Output>,
    pub skipped: Vec<Output>,
}

/// One frame's output file.
#[derive(Clone, Debug, Serialize, PartialEq, Eq, PartialOrd, Ord)]
pub struct Output {
    pub frame: Option<i64>,
    pub path: PathBuf,
}

/// One frame of a dry run: its output and what a run would do with it.
#[derive(Clone, Debug, Serialize)]
pub struct Planned {
    pub frame: Option<i64>,
    pub output: PathBuf,
    /// `write`, `overwrite`, `skip` (with --skip-existing, a whole frame exists) or `redo`
    /// (one exists but is not whole: `why` says what is wrong with it).
    pub action: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub why: Option<String>,
    /// The input files the frame reads.
    pub inputs: Vec<PathBuf>,
}

/// The most warnings a report keeps (the same warning on every frame is kept once).
const MAX_WARNINGS: usize = 50;

/// What a thread of the pool needs in memory of its own ([`run`]'s preflight).
const PER_THREAD: u64 = 3 << 20;

fn warn(report: &mut Report, on_event: &mut dyn FnMut(Event), message: String) {
    if report.warnings.len() < MAX_WARNINGS && !report.warnings.contains(&message) {
        report.warnings.push(message.clone());
        on_event(Event::Warning(message));
    }
}

/// The problems of a preflight with what they miss named as the user gives it, and the
/// other ways to give it (`hints::name_pass`).
fn name_pass(job: &Job, error: crate::Error, view: Option<&str>) -> crate::Error {
    let coc_map = depth_kind(&job.params) == crate::numeric::DepthKind::CocMap;
    hints::name_pass(
        error,
        &job.preset,
        (coc_map, job.params.dof.is_some()),
        view,
    )
}

/// Runs the job: preflight (every input header, every output place), the output lock and
/// the removal of temporary files dead runs left, `--skip-existing`'s checks, then every
/// frame through read → process → write. The lock is released and the lock file removed
/// however the run ends.
pub fn run(job: &Job, on_event: &mut dyn FnMut(Event)) -> Result<Report> {
    let start = Instant::now();
    let mut report = Report {
        schema: crate::JSON_SCHEMA,
        ok: true,
        algorithm: job.algorithm.name().to_string(),
        preset: job.preset.name.clone(),
        shutter: crate::numeric::shutter(job.params.shutter),
        shutter_offset: crate::numeric::shutter_offset(job.params.shutter_offset),
        ..Report::default()
    };

    // What the outputs record of the settings that made them (`shutter/settings`).
    let record = job.output_options.record.as_str();
    // Every frame is planned, those --skip-existing may skip included: the plan gives the
    // size their output must have.
    let preflight_start = Instant::now();
    // An EXR output holds every channel of the colour file's part, so they are read too.
    let every_channel = OutputFormat::from_path(&job.output.path(None)) == Some(OutputFormat::Exr)
        && !job.output_options.beauty_only;
    // And every view of a multi-view colour file, each planned, read and processed as that
    // view alone (the first is the default), then written into one file.
    // A stack of layers is read from one view: a multi-view file's EXR output would hold
    // one of its views, so one must be asked for.
    let views = views_to_write(job, every_channel);
    if !job.stack.is_empty() && views.len() > 1 {
        let path = job.inputs.color.path(job.frames.first().copied().flatten());
        let problem = crate::stack::views_problem(&path, &views);
        return Err(crate::Error::Files(vec![problem]));
    }
    let options = PlanOptions {
        preset: &job.preset,
        layer: job
            .stack
            .first()
            .map_or(job.layer.as_deref(), |l| l.layer.as_deref()),
        view: views[0].as_deref(),
        needs: crate::process::needs(job.algorithm, &job.params),
        max_pixels: job.max_pixels,
    };
    // A stack's first layer's files are the job's inputs.
    let mut plans = preflight(&job.inputs, &job.output, &job.frames, &options)
        .map_err(|e| name_pass(job, e, options.view))?;
    // The other views' (or the stack's other layers') plans, frame by frame.
    let mut others: Vec<Vec<FramePlan>> = plans.iter().map(|_| Vec::new()).collect();
    let more: Vec<(&Inputs, PlanOptions)> = if job.stack.is_empty() {
        (views[1..].iter())
            .map(|view| {
                let options = PlanOptions {
                    view: view.as_deref(),
                    ..options.clone()
                };
                (&job.inputs, options)
            })
            .collect()
    } else {
        (job.stack[1..].iter())
            .map(|layer| {
                let options = PlanOptions {
                    layer: layer.layer.as_deref(),
                    ..options.clone()
                };
                (layer.inputs.as_ref().unwrap_or(&job.inputs), options)
            })
            .collect()
    };
    for (inputs, options) in &more {
        let unit_plans = preflight(inputs, &job.output, &job.frames, options)
            .map_err(|e| name_pass(job, e, options.view))?;
        for (frame, plan) in others.iter_mut().zip(unit_plans) {
            frame.push(plan);
        }
    }
    // The view layers of one file, by name (a stack of one file a layer reads each whole).
    let shared: Vec<String> = if job.stack.iter().any(|l| l.inputs.is_some()) {
        Vec::new()
    } else {
        job.stack.iter().map(|l| l.name.clone()).collect()
    };
    if !job.stack.is_empty() {
        let names: Vec<String> = job.stack.iter().map(|l| l.name.clone()).collect();
        // Every frame's problem, as the preflight lists them.
        let problems: Vec<_> = (plans.iter().zip(&others))
            .filter_map(|(first, rest)| {
                crate::io::passes::stack_problem(first, rest, &names, !shared.is_empty())
            })
            .collect();
        if !problems.is_empty() {
            return Err(crate::Error::Files(problems));
        }
    }
    if every_channel {
        for (plan, layer) in plans.iter_mut().map(|p| (p, 0)).chain(
            (others.iter_mut()).flat_map(|o| o.iter_mut().enumerate().map(|(i, p)| (p, i + 1))),
        ) {
            match (shared.get(layer), &job.layer) {
                (Some(own), _) => {
                    if layer == 0 {
                        plan.leave_out_composite();
                    }
                    plan.read_layer_channels(own, &shared, layer == 0)
                }
                // One view layer of a file of several (`--layer`): the others come back as
                // they came, not blurred with this one's weights.
                (None, Some(own)) if job.stack.is_empty() => {
                    plan.read_layer_channels(own, std::slice::from_ref(own), true)
                }
                (None, _) => {
                    plan.read_every_channel();
                    plan.read_parts_apart();
                }
            }
        }
    }
    // Depth of field draws a lens's disc round in pixels: on pixels that are not square it
    // comes out stretched once the picture is shown at its aspect.
    let aspect = plans.first().and_then(FramePlan::pixel_aspect);
    if let Some(aspect) = aspect.filter(|a| job.params.dof.is_some() && (a - 1.0).abs() > 1e-3) {
        let path = plans[0].paths().first().map(|p| p.display().to_string());
        warn(
            &mut report,
            on_event,
            format!(
                "{}: its pixels are {aspect}:1 (pixelAspectRatio), and depth of field draws each \
                 bokeh round in pixels, so shown at that aspect it comes out {aspect} times as \
                 wide as tall; resize to square pixels first for a round one",
                path.unwrap_or_default()
            ),
        );
    }
    // Said once the run knows it writes a frame (not by a rerun that skips them all).
    let unwritten_views = (views.len() == 1)
        .then(|| plans.first().and_then(FramePlan::unwritten_views))
        .flatten();
    // What the frames need in memory, from their headers, against the limit.
    let (limit, said) = match job.max_memory {
        Some(limit) => (limit, String::new()),
        None => {
            let (limit, said) = memory::memory_limit_said();
            (limit, format!(" (by default {said})"))
        }
    };
    let gpu = job.backend != Backend::Cpu;
    // The vector check holds a few planes of one frame besides.
    let checks = job.check_vectors && VectorCheck::applies(&job.inputs.color, options.needs);
    let needed_alone = |plan: &FramePlan| {
        let check = if checks {
            VectorCheck::memory(plan.width, plan.height)
        } else {
            0
        };
        let layers = job.algorithm.layer_copies() * plan.light_layer_bytes();
        let dof =
            (job.params.dof.as_ref()).map_or(0, |d| d.method.memory_besides(plan.decoded_bytes()));
        plan.memory_needed(gpu)
            .saturating_add(check)
            .saturating_add(layers)
            .saturating_add(dof)
    };
    // Each thread's own (its stack and allocator arena as touched: 1.7–2.1 MiB a thread
    // measured from 2 to 64 threads, 1080p and 4K).
    let threads = rayon::current_num_threads() as u64 * PER_THREAD;
    // A frame of several views: each stage of the pipeline holds all of a frame's views, so
    // each view counts in full.
    let views_of = |index: usize| std::iter::once(&plans[index]).chain(&others[index]);
    let needed = |index: usize| views_of(index).map(needed_alone).sum::<u64>() + threads;
    let decoded = |index: usize| views_of(index).map(FramePlan::decoded_bytes).sum::<u64>();
    if let Some(index) = (0..plans.len()).max_by_key(|&i| needed(i)) {
        let (plan, needed, decoded) = (&plans[index], needed(index), decoded(index));
        if needed > limit {
            let mib = |bytes: u64| bytes.div_ceil(1 << 20);
            return Err(crate::Error::Files(vec![Problem::new(
                ProblemKind::TooLarge,
                plan.paths().first().copied().unwrap_or(Path::new("")),
                format!(
                    "this frame needs about {} MiB (its passes decode to {} MiB, a picture \
                     decoder holds {} MiB more), over the {} MiB max-memory allows{}; raise \
                     --max-memory if the machine has it, or give the job to one that does",
                    mib(needed),
                    mib(decoded),
                    mib(plan.decoder_bytes()),
                    mib(limit),
                    said
                ),
            )
            .frame(plan.frame)]));
        }
    }
    report.preflight_seconds = preflight_start.elapsed().as_secs_f64();
    if job.dry_run {
        // Nothing runs: the backend asked for is said, none used ("none", not an empty
        // string a script cannot tell from a missing value).
        report.backend.requested = job.backend.name().to_string();
        report.backend.used = "none".to_string();
        for plan in &plans {
            let (frame, output) = (plan.frame, job.output.path(plan.frame));
            let (action, why) =
                match existing_output(job.skip_existing, record, plan, &output, &views) {
                    Existing::None => ("write", None),
                    Existing::Kept => ("overwrite", None),
                    Existing::Whole => ("skip", None),
                    Existing::Broken(why) => ("redo", Some(why)),
                    Existing::Other(recorded) => ("redo", Some(other_settings(&recorded, record))),
                };
            let inputs = plan.paths().into_iter().map(Path::to_path_buf).collect();
            report.planned.push(Planned {
                frame,
                output,
                action,
                why,
                inputs,
            });
        }
        if report.planned.iter().any(|p| p.action != "skip") {
            if let Some(warning) = unwritten_views {
                warn(&mut report, on_event, warning);
            }
        }
        for warning in &job.warnings {
            warn(&mut report, on_event, warning.clone());
        }
        report.wall_seconds = start.elapsed().as_secs_f64();
        return Ok(report);
    }
    // The GPU context, once per run, before any output is touched: `--backend wgpu` with no
    // suitable adapter stops here with one line.
    let (gpu, backend) = crate::gpu::open(job.backend).map_err(crate::Error::Device)?;
    report.backend = backend;
    if let Some(reason) = report.backend.fallback.clone() {
        warn(
            &mut report,
            on_event,
            format!("--backend auto runs on the CPU: {reason}"),
        );
    }

    // What is there already (`--skip-existing`): a frame found whole stays whole, as
    // outputs are only ever replaced by whole frames.
    let existing: Vec<Existing> = plans
        .iter()
        .map(|plan| {
            let output = job.output.path(plan.frame);
            existing_output(job.skip_existing, record, plan, &output, &views)
        })
        .collect();
    if !existing.iter().all(|e| matches!(e, Existing::Whole)) {
        if let Some(warning) = unwritten_views {
            warn(&mut report, on_event, warning);
        }
    }
    // A finished run run again writes nothing: it needs neither a folder it may write in
    // (a delivered sequence made read-only) nor the lock (an outside probe: it failed as
    // "not writable").
    let (mut _lock, mut stale) = (None, Vec::new());
    if existing.iter().all(|e| matches!(e, Existing::Whole)) {
        // What a killed run left is still removed where the lock can be had (never a file
        // a job on another host may be writing): not in a folder made read-only.
        _lock = OutputLock::acquire(&job.output, &job.frames).ok();
        if _lock.is_some() {
            let outputs: Vec<PathBuf> = job.frames.iter().map(|&f| job.output.path(f)).collect();
            stale = remove_stale_temporaries(&outputs);
        }
    } else {
        // Output folders no file can be created in, tried with a probe file now that
        // nothing else can fail first (the probe changes the folder's modification time).
        // Of the frames to write: those found whole are skipped, not locked, so a retry
        // beside a job still writing is stopped by (and names) a frame it would write.
        let writes: Vec<Option<i64>> = (plans.iter().zip(&existing))
            .filter(|(_, e)| !matches!(e, Existing::Whole))
            .map(|(plan, _)| plan.frame)
            .collect();
        let unwritable = output_folder_problems(&job.output, &writes, true);
        if !unwritable.is_empty() {
            return Err(crate::Error::Files(unwritable));
        }
        // The first thing written: the lock on the frames this job writes (another job on
        // any of them stops here), released when `_lock` drops, whatever way the run ends.
        _lock = Some(OutputLock::acquire(&job.output, &writes)?);
        let outputs: Vec<PathBuf> = writes.iter().map(|&f| job.output.path(f)).collect();
        stale = remove_stale_temporaries(&outputs);
    }
    if !stale.is_empty() {
        warn(
            &mut report,
            on_event,
            format!(
                "removed {} temporary file{} that a stopped run left beside the outputs \
                 (first: {})",
                stale.len(),
                if stale.len() == 1 { "" } else { "s" },
                stale[0].display()
            ),
        );
    }
    // Frames made with other settings are said once a run.
    let made_otherwise: Vec<(Option<i64>, &String)> = (plans.iter().zip(&existing))
        .filter_map(|(plan, e)| match e {
            Existing::Other(recorded) => Some((plan.frame, recorded)),
            _ => None,
        })
        .collect();
    if let Some(message) = made_otherwise_warning(&made_otherwise, &job.output, record) {
        warn(&mut report, on_event, message);
    }
    let mut todo = Vec::with_capacity(plans.len());
    let mut todo_others = Vec::with_capacity(plans.len());
    for ((plan, other_views), existing) in plans.into_iter().zip(others).zip(existing) {
        let (frame, path) = (plan.frame, job.output.path(plan.frame));
        match existing {
            Existing::Whole => {
                report.frames_skipped += 1;
                report.skipped.push(Output {
                    frame,
                    path: path.clone(),
                });
                on_event(Event::Skipped { frame, path });
                continue;
            }
            Existing::Broken(why) => {
                let at = frame.map_or(String::new(), |f| format!(", frame {f}"));
                warn(
                    &mut report,
                    on_event,
                    format!("{}{at} exists but is written again: {why}", path.display()),
                );
            }
            Existing::None | Existing::Kept | Existing::Other(_) => {}
        }
        todo.push(plan);
        todo_others.push(other_views);
    }
    let (plans, others) = (todo, todo_others);
    let todo: Vec<Option<i64>> = plans.iter().map(|p| p.frame).collect();
    let gpu = gpu.as_ref();
    // Pass files given but not read (the algorithm does not need them, or the pass came
    // from another file): say so.
    if let Some(plan) = plans.first() {
        let read = plan.paths();
        for (pass, pattern) in job.inputs.all() {
            if !read.contains(&pattern.path(plan.frame).as_path()) {
                warn(
                    &mut report,
                    on_event,
                    format!(
                        "--{pass} is not read: algorithm {} does not need it",
                        job.algorithm.name()
                    ),
                );
            }
        }
    }
    for warning in &job.warnings {
        warn(&mut report, on_event, warning.clone());
    }
    for plan in plans.iter().chain(others.iter().flatten()) {
        for warning in plan.warnings.iter().cloned().chain(plan.unread_warnings()) {
            warn(&mut report, on_event, warning);
        }
    }

    on_event(Event::Started {
        frames: plans.len(),
    });
    let mut check = job
        .check_vectors
        .then(|| VectorCheck::new(&job.inputs.color, &options, &todo))
        .flatten();
    type Checked = Option<crate::io::passes::CheckReport>;
    let (read_seconds, process_seconds, vector_check) =
        std::thread::scope(|scope| -> Result<(f64, f64, Checked)> {
            // The read stage applies the numeric policy, so its scan overlaps processing.
            // A frame (each view's), what the numeric policy replaced in it, and the read's
            // notes.
            type Read = (Vec<Frame>, Vec<Replaced>, Vec<String>);
            let (read_tx, read_rx) = mpsc::sync_channel::<std::result::Result<Read, Problem>>(0);
            type Done = (Option<i64>, Vec<Frame>, Vec<Replaced>, Vec<String>);
            let (done_tx, done_rx) = mpsc::sync_channel::<std::result::Result<Done, Problem>>(0);

            let reader = scope.spawn(move || {
                let (mut seconds, mut check_seconds) = (0.0, 0.0);
                // A painted map in colour is noted at the first frame it is found in.
                let mut grey_noted = false;
                for (index, plan) in plans.iter().enumerate() {
                    let t = Instant::now();
                    let keep = check.as_ref().is_some_and(|c| c.keeps(index));
                    let mut frame = read_frame_keeping(plan, keep, &mut grey_noted).map(
                        |(mut frame, mut notes, stored)| {
                            let replaced =
                                crate::numeric::sanitize(&mut frame, depth_kind(&job.params));
                            if let Some(c) = check.as_mut().filter(|c| !c.done()) {
                                let t = Instant::now();
                                notes.extend(c.offer(index, &frame, stored));
                                check_seconds += t.elapsed().as_secs_f64();
                            }
                            (vec![frame], vec![replaced], notes)
                        },
                    );
                    // The other views of the frame, read alike (the vector check has seen
                    // the first).
                    for view in &others[index] {
                        let Ok((frames, replaced, notes)) = &mut frame else {
                            break;
                        };
                        match read_frame_keeping(view, false, &mut grey_noted) {
                            Ok((mut read, more, _)) => {
                                replaced.push(crate::numeric::sanitize(
                                    &mut read,
                                    depth_kind(&job.params),
                                ));
                                notes.extend(more);
                                frames.push(read);
                            }
                            Err(problem) => frame = Err(problem),
                        }
                    }
                    seconds += t.elapsed().as_secs_f64();
                    let failed = frame.is_err();
                    if read_tx.send(frame).is_err() || failed {
                        break;
                    }
                }
                let report = check.map(|c| crate::io::passes::CheckReport {
                    seconds: check_seconds,
                    ..c.report()
                });
                (seconds, report)
            });

            let frames: Vec<Option<i64>> = todo.clone();
            let processor = scope.spawn(move || {
                let mut seconds = 0.0;
                // A reversed stack is named once a run, at its first frame.
                let mut order_named = false;
                for (frame_number, frame) in frames.into_iter().zip(read_rx) {
                    let message = match frame {
                        Ok((frames, replaced, mut notes)) => {
                            let t = Instant::now();
                            let number = frame_number.unwrap_or(0);
                            let out = if job.stack.is_empty() {
                                (frames.into_iter())
                                    .map(|frame| {
                                        process_on(job.algorithm, &job.params, frame, number, gpu)
                                    })
                                    .collect()
                            } else {
                                // A layer of a file of its own goes out under its name.
                                let mut frames = frames;
                                let names: Vec<String> =
                                    job.stack.iter().map(|l| l.name.clone()).collect();
                                let note = (!order_named)
                                    .then(|| crate::stack::order_note(&frames, &names))
                                    .flatten();
                                if let Some(note) = note {
                                    order_named = true;
                                    let at = frame_number.map(|n| format!(" (first in frame {n})"));
                                    notes.push(format!("{note}{}", at.unwrap_or_default()));
                                }
                                for (frame, layer) in frames.iter_mut().zip(&job.stack) {
                                    if layer.inputs.is_some() {
                                        crate::stack::name_layer(frame, &layer.name);
                                    }
                                }
                                vec![crate::stack::process_stack(
                                    job.algorithm,
                                    &job.params,
                                    frames,
                                    number,
                                    gpu,
                                )]
                            };
                            seconds += t.elapsed().as_secs_f64();
                            Ok((frame_number, out, replaced, notes))
                        }
                        Err(problem) => Err(problem),
                    };
                    let failed = message.is_err();
                    if done_tx.send(message).is_err() || failed {
                        break;
                    }
                }
                seconds
            });

            let mut failure = None;
            // What earlier frames replaced, each stack layer's apart.
            let mut seen_each = Vec::new();
            // What writing found (a DWA highlight capped), said for the first frame alone: a
            // warning a frame would crowd out the run's others.
            let mut written_said = false;
            for message in done_rx {
                match message {
                    Ok((frame, out, replaced, notes)) => {
                        for note in notes {
                            warn(&mut report, on_event, note);
                        }
                        let (inputs, kind) = (&job.inputs, depth_kind(&job.params));
                        let layers: Vec<(&str, &Inputs)> = (job.stack.iter())
                            .map(|l| (l.name.as_str(), l.inputs.as_ref().unwrap_or(inputs)))
                            .collect();
                        let seen = &mut seen_each;
                        for w in replaced_warnings(&replaced, seen, frame, inputs, &layers, kind) {
                            warn(&mut report, on_event, w);
                        }
                        replaced.into_iter().for_each(|r| report.replaced.add(r));
                        let path = job.output.path(frame);
                        let notes = output_notes(&path, &out[0], &job.output_options);
                        for note in notes {
                            warn(&mut report, on_event, format!("{}: {note}", job.output.raw));
                        }
                        let t = Instant::now();
                        // The output folder is the lock's, made with it (and removed with it
                        // while empty), never made again here: gone, the frames written in it
                        // went with it, and the write stops the run for a rerun (exit 75).
                        let written = write_views(&path, out, &job.output_options, frame);
                        report.write_seconds += t.elapsed().as_secs_f64();
                        match written {
                            Ok(notes) => {
                                for note in notes.iter().filter(|_| !written_said) {
                                    let (path, first) = (path.display(), frame.is_some());
                                    let later = [" (and maybe later frames: said once)", ""];
                                    warn(
                                        &mut report,
                                        on_event,
                                        format!("{path}: {note}{}", later[usize::from(!first)]),
                                    );
                                }
                                written_said |= !notes.is_empty();
                                report.frames_written += 1;
                                report.outputs.push(Output {
                                    frame,
                                    path: path.clone(),
                                });
                                on_event(Event::Written { frame, path });
                            }
                            Err(problem) => {
                                failure = Some(problem);
                                break;
                            }
                        }
                    }
                    Err(problem) => {
                        failure = Some(problem);
                        break;
                    }
                }
            }
            // Dropping the receiver (end of the loop) unblocks and stops the other stages.
            let (read_seconds, vector_check) = reader.join().unwrap_or((0.0, None));
            let process_seconds = processor.join().unwrap_or(0.0);
            match failure {
                Some(problem) => Err(name_pass(job, problem.into(), views[0].as_deref())),
                None => Ok((read_seconds, process_seconds, vector_check)),
            }
        })?;
    report.read_seconds = read_seconds;
    report.vector_check = vector_check;
    report.process_seconds = process_seconds;
    report.outputs.sort();
    #[cfg(feature = "gpu")]
    if let Some(gpu) = gpu {
        report.backend.stages_on_cpu = gpu.stages_on_cpu();
        // A frame over the device's limits runs those stages on the CPU (the same output):
        // said once, with the first reason.
        if let Some(why) = gpu.fallback() {
            warn(
                &mut report,
                on_event,
                format!(
                    "{} GPU stage runs fell back to the CPU (first, {why})",
                    gpu.stages_on_cpu()
                ),
            );
        }
    }
    report.wall_seconds = start.elapsed().as_secs_f64();
    report.peak_rss_mib = peak_rss_mib();
    Ok(report)
}

/// The views a run reads and writes: `--view`'s; else, for an EXR output of every channel,
/// every view of a multi-view colour file (the first frame's; a later frame without one of
/// them stops the preflight), the default first; else each file's default (`None`).
fn views_to_write(job: &Job, every_channel: bool) -> Vec<Option<String>> {
    if job.view.is_some() || !every_channel {
        return vec![job.view.clone()];
    }
    let first = job.frames.first().copied().flatten();
    let Ok(info) = crate::io::file::FileInfo::probe(&job.inputs.color.path(first)) else {
        // The preflight says what is wrong with it.
        return vec![None];
    };
    match info.views {
        Some(views) if views.names.len() > 1 => views.in_order().into_iter().map(Some).collect(),
        _ => vec![None],
    }
}
