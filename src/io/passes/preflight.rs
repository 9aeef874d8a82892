//! Preflight: every input of every frame checked from its headers before anything is decoded
//! or written (files, channels, sizes, compression, layout; outputs that would overwrite an
//! input, folders in the way of outputs, output folders that cannot be made or written);
//! every problem found is returned, each naming its file and frame.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::error::{Error, Problem, ProblemKind, Result};
use crate::io::sequence::PathPattern;

use super::plan::{plan_frame, FramePlan, PlanOptions};
use super::Inputs;

/// True when writing `output` would replace the file `input` names: the same path once
/// symbolic links and `..` are resolved, or (Unix) the same name in the same folder, the
/// folder told by its device and inode, so that a second mount of the input folder (a bind
/// mount, another NFS mount point of the same export) is caught; or the same file (device
/// and inode) when the output exists, which a hard link of the input would be.
fn same_file(input: &Path, output: &Path) -> bool {
    let paths_agree = match (input.canonicalize(), output.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => {
            let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
            absolute(input) == absolute(output)
        }
    };
    paths_agree || same_entry(input, output)
}

/// The same file, or the same name in the same folder, by device and inode (Unix).
#[cfg(unix)]
fn same_entry(input: &Path, output: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    let id = |meta: std::fs::Metadata| (meta.dev(), meta.ino());
    if let (Ok(a), Ok(b)) = (std::fs::metadata(input), std::fs::metadata(output)) {
        if id(a) == id(b) {
            return true;
        }
    }
    // The entry a path names: its folder's identity and its name. The input's is taken
    // through its links (what is read is the file they lead to), and as written.
    let entry = |p: &Path| -> Option<((u64, u64), std::ffi::OsString)> {
        let name = p.file_name()?.to_os_string();
        let folder = match p.parent() {
            Some(f) if !f.as_os_str().is_empty() => f,
            _ => Path::new("."),
        };
        Some((id(std::fs::metadata(folder).ok()?), name))
    };
    let Some(out) = entry(output) else {
        return false;
    };
    let resolved = input.canonicalize().ok();
    let same = [Some(input), resolved.as_deref()]
        .into_iter()
        .flatten()
        .any(|p| entry(p).as_ref() == Some(&out));
    same
}

#[cfg(not(unix))]
fn same_entry(_input: &Path, _output: &Path) -> bool {
    false
}

/// What a file is, to tell an input under another name: its device and inode (Unix, through
/// links, so a hard or symbolic link of an input is the input), else its resolved path.
fn identity(path: &Path) -> Option<(u64, u64, Option<PathBuf>)> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        let meta = std::fs::metadata(path).ok()?;
        Some((meta.dev(), meta.ino(), None))
    }
    #[cfg(not(unix))]
    {
        Some((0, 0, Some(path.canonicalize().ok()?)))
    }
}

/// Outputs that would replace an input, for a command that writes files of its own beside
/// what it reads (`diff --heatmap`, `vectors --write-preset`): `writes` holds each output
/// with the inputs of its frame. Each output is checked against those by [`same_file`], as
/// [`preflight`] checks blur's `-o`, and against every other input by what the file is
/// ([`identity`]): an input that is read exists, so an output that would replace it exists
/// too, and one look-up per output does for a whole sequence. Returns, for each output that
/// would replace one, its index in `writes` and the input.
pub fn outputs_over_inputs(writes: &[(&Path, Vec<PathBuf>)]) -> Vec<(usize, PathBuf)> {
    let mut inputs = std::collections::HashMap::new();
    for input in writes.iter().flat_map(|(_, inputs)| inputs) {
        if let Some(id) = identity(input) {
            inputs.entry(id).or_insert_with(|| input.clone());
        }
    }
    writes
        .par_iter()
        .enumerate()
        .filter_map(|(i, (output, own))| {
            let clash = own
                .iter()
                .find(|input| same_file(input, output))
                .cloned()
                .or_else(|| identity(output).and_then(|id| inputs.get(&id).cloned()));
            clash.map(|input| (i, input))
        })
        .collect()
}

/// What stands where an output would go that a rename cannot replace: a folder, or
/// something that is not a file (a device, a FIFO, a socket); `None` where nothing, a file
/// or a symbolic link is (blur's outputs, and the files `diff` writes, are refused alike).
pub fn in_the_way(output: &Path) -> Option<&'static str> {
    let meta = std::fs::symlink_metadata(output).ok()?;
    if meta.is_file() || meta.file_type().is_symlink() {
        return None;
    }
    Some(if meta.is_dir() {
        "a folder"
    } else {
        "something that is not a file"
    })
}

/// A folder (or anything but a file) where a frame's output would go: it cannot be
/// replaced, so the run would stop at that frame.
fn output_in_the_way(output: &Path, frame: Option<i64>) -> Option<Problem> {
    let what = in_the_way(output)?;
    Some(
        Problem::new(
            ProblemKind::Output,
            output,
            format!(
                "{what} is in the way of this frame's output and cannot be replaced; move it \
                 away, or write elsewhere with -o"
            ),
        )
        .frame(frame),
    )
}

/// The output folders (one check each, naming the first frame that goes there) that cannot
/// be written: a file where a folder must be (read only, part of [`preflight`]), and with
/// `probe`, a folder where no file can be created. That is tried by creating and removing a
/// hidden probe file in the nearest existing folder, which answers for permissions,
/// read-only mounts and ACLs alike and leaves nothing behind but the folder's modification
/// time: so the pipeline probes after the preflight and the device check, as the last step
/// before it takes the output lock.
pub fn output_folder_problems(
    output: &PathPattern,
    frames: &[Option<i64>],
    probe: bool,
) -> Vec<Problem> {
    let mut seen = std::collections::HashSet::new();
    let mut problems = Vec::new();
    for &frame in frames {
        let path = output.path(frame);
        let folder = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => std::path::PathBuf::from("."),
        };
        if !seen.insert(folder.clone()) {
            continue;
        }
        let problem =
            |detail: String| Problem::new(ProblemKind::Output, &path, detail).frame(frame);
        // The nearest part of the folder's path that exists.
        let mut existing = folder.as_path();
        while std::fs::metadata(existing).is_err() {
            match existing.parent() {
                Some(p) if !p.as_os_str().is_empty() => existing = p,
                _ => {
                    existing = Path::new(".");
                    break;
                }
            }
        }
        match std::fs::metadata(existing) {
            Ok(meta) if !meta.is_dir() => problems.push(problem(format!(
                "the output folder cannot be made: {} is a file, not a folder; choose another -o",
                existing.display()
            ))),
            Ok(_) if probe => match probe_writable(existing) {
                Err(e) if crate::error::is_out_of_space(&e) => problems.push(
                    Problem::new(
                        ProblemKind::WriteFailed,
                        &path,
                        format!(
                            "the disk holding {} is full ({e}); make room and rerun",
                            existing.display()
                        ),
                    )
                    .frame(frame),
                ),
                Err(e) if crate::error::is_transient_io(&e) => problems.push(
                    Problem::new(
                        ProblemKind::WriteFailed,
                        &path,
                        format!(
                            "the folder {} could not be checked for now ({e}); rerun",
                            existing.display()
                        ),
                    )
                    .frame(frame),
                ),
                Err(e) => problems.push(problem(format!(
                    "the folder {} is not writable ({e}); change its permissions or write \
                     elsewhere with -o",
                    existing.display()
                ))),
                Ok(()) => {}
            },
            Ok(_) => {}
            Err(e) => problems.push(problem(format!("the output folder cannot be checked: {e}"))),
        }
    }
    problems
}

/// Creates and removes a hidden file in `folder`.
fn probe_writable(folder: &Path) -> std::io::Result<()> {
    let probe = folder.join(format!(".shutter-probe.{}.tmp", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(&probe)?;
    std::fs::remove_file(&probe)
}

/// More frames than this without a colour file are reported as one problem, by ranges,
/// before any frame is planned (a frame spec of a million frames over a sequence of three
/// would otherwise make, hold and print a million problems).
pub const MISSING_IN_BULK: usize = 100;

/// The frames of `frames` that have no colour file, found from one listing of its folder,
/// as one problem when there are more than [`MISSING_IN_BULK`]; `None` otherwise (and when
/// the folder cannot be listed: the frames' own checks then say why).
fn missing_in_bulk(color: &PathPattern, frames: &[Option<i64>]) -> Option<Problem> {
    if !color.is_sequence() || frames.len() <= MISSING_IN_BULK {
        return None;
    }
    let found: std::collections::HashSet<i64> = color.discover().ok()?.frames.into_iter().collect();
    let mut missing: Vec<i64> = frames
        .iter()
        .flatten()
        .copied()
        .filter(|f| !found.contains(f))
        .collect();
    if missing.len() <= MISSING_IN_BULK {
        return None;
    }
    missing.sort_unstable();
    let listed = crate::io::sequence::format_frames(&missing);
    let shown: String = if listed.len() > 200 {
        let cut = listed[..200].rfind(',').unwrap_or(200);
        format!("{}, …", &listed[..cut])
    } else {
        listed
    };
    Some(Problem::new(
        ProblemKind::MissingFile,
        Path::new(&color.raw),
        format!(
            "{} of the {} frames asked for have no colour file (frames {shown}); {} were found; \
             check --frames",
            missing.len(),
            frames.len(),
            found.len()
        ),
    ))
}

/// A picture output's hard limit on a side, held against the picture a frame makes (its
/// display window): refused here, naming both, rather than by the encoder once the frame is
/// blurred (a failure then reads as the moment's, exit 75, and a retry cannot help).
fn too_large_for_its_format(output: &Path, plan: &FramePlan) -> Option<Problem> {
    let format = crate::io::image::ImageFormat::from_path(output)?;
    let (width, height) = plan
        .color_windows
        .as_ref()
        .map_or((plan.width, plan.height), |w| {
            (w.display.width, w.display.height)
        });
    // A picture is made whole in memory: one larger than the pixel limit (a display window
    // far bigger than the data, as a header may declare) is refused here too; the writer
    // refused it only once the frame was blurred, as the moment's failure (exit 75).
    let limit = crate::io::file::DEFAULT_MAX_PIXELS;
    if (width as u64).saturating_mul(height as u64) > limit as u64 {
        return Some(
            Problem::new(
                ProblemKind::TooLarge,
                output,
                format!(
                    "the picture is the display window, {width}x{height}, more than the \
                     {limit} pixels a picture may hold; write an .exr (which keeps the data \
                     window alone) or fix the file's display window"
                ),
            )
            .frame(plan.frame),
        );
    }
    let most = format.most_a_side();
    (width as u64 > most || height as u64 > most).then(|| {
        Problem::new(
            ProblemKind::Output,
            output,
            format!(
                "the frame is {width}x{height}, and {} holds at most {most} pixels a side; \
                 write a .png, .tif or .exr instead, or crop the frame",
                format.name()
            ),
        )
        .frame(plan.frame)
    })
}

/// Plans every frame of `frames` and checks that each output can be written without
/// overwriting an input; returns the plans, or all the problems found.
/// The problem of a colour PNG whose read would refuse its colour (a cICP of high dynamic
/// range or narrow range: `image::cicp_refused`), found before any frame is read; none where
/// its codes are taken as they are (`--linear`).
fn colour_refused(plan: &FramePlan) -> Option<Problem> {
    let color = plan.color.as_ref().filter(|c| c.decode_srgb)?;
    let info = &plan.files[color.rgb[0].file].info;
    if !matches!(
        info.kind,
        crate::io::file::FileKind::Image { format: "PNG", .. }
    ) {
        return None;
    }
    let photo = crate::io::image::read_photo(&info.path).ok()?;
    let why = crate::io::image::cicp_refused(&photo)?;
    let problem = Problem::new(ProblemKind::Unsupported, &info.path, why);
    Some(problem.frame(plan.frame).pass("color"))
}

pub fn preflight(
    inputs: &Inputs,
    output: &PathPattern,
    frames: &[Option<i64>],
    options: &PlanOptions,
) -> Result<Vec<FramePlan>> {
    if let Some(problem) = missing_in_bulk(&inputs.color, frames) {
        return Err(Error::Files(vec![problem]));
    }
    // Every input of every frame, by what the file is: an output that is another frame's
    // input (a link to a file of the outputs, an earlier run's output read back) would change
    // what that frame reads, or has read (an outside probe: frame 2's output replaced the file
    // frame 3 read through a link, with exit 0).
    let every_input: std::collections::HashMap<_, PathBuf> = frames
        .par_iter()
        .flat_map_iter(|&frame| {
            inputs
                .all()
                .into_iter()
                .map(move |(_, p)| p.path(frame))
                .filter_map(|input| identity(&input).map(|id| (id, input)))
        })
        .collect::<Vec<_>>()
        .into_iter()
        .rev()
        .collect();
    let results: Vec<std::result::Result<FramePlan, Vec<Problem>>> = frames
        .par_iter()
        .map(|&frame| {
            let mut plan = plan_frame(inputs, frame, options);
            let output = output.path(frame);
            let clash = inputs
                .all()
                .into_iter()
                .map(|(_, p)| p.path(frame))
                .find(|input| same_file(input, &output))
                .or_else(|| identity(&output).and_then(|id| every_input.get(&id).cloned()));
            let too_large = plan
                .as_ref()
                .ok()
                .and_then(|p| too_large_for_its_format(&output, p));
            if let Some(problem) = too_large {
                plan = Err(vec![problem]);
            }
            if let Some(problem) = plan.as_ref().ok().and_then(colour_refused) {
                plan = Err(vec![problem]);
            }
            if let Some(problem) = output_in_the_way(&output, frame) {
                plan = match plan {
                    Ok(_) => Err(vec![problem]),
                    Err(mut problems) => {
                        problems.push(problem);
                        Err(problems)
                    }
                };
            }
            if let Some(input) = clash {
                let problem = Problem::new(
                    ProblemKind::Output,
                    &output,
                    format!(
                        "the output would overwrite the input {}; choose another -o",
                        input.display()
                    ),
                )
                .frame(frame);
                plan = match plan {
                    Ok(_) => Err(vec![problem]),
                    Err(mut problems) => {
                        problems.push(problem);
                        Err(problems)
                    }
                };
            }
            plan
        })
        .collect();
    let mut plans = Vec::with_capacity(results.len());
    let mut problems = Vec::new();
    for result in results {
        match result {
            Ok(plan) => plans.push(plan),
            Err(found) => problems.extend(found),
        }
    }
    problems.extend(output_folder_problems(output, frames, false));
    if problems.is_empty() {
        Ok(plans)
    } else {
        Err(Error::Files(problems))
    }
}
