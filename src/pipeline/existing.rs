//! What stands at a frame's output before a run writes it, judged once for the run and for
//! `--dry-run` alike: nothing, something overwritten, or with `--skip-existing` a whole frame
//! (skipped), one that is not (written again, saying why), or a whole one made with other
//! settings than the run's (written again, said once a run: a farm job resubmitted with
//! another algorithm over the same folder).

use std::path::Path;

use crate::io::output::{existing_frame_problem, recorded_settings, OutputFormat};
use crate::io::passes::FramePlan;
use crate::io::sequence::PathPattern;

/// What is at a frame's output before the run writes it.
pub(super) enum Existing {
    /// Nothing.
    None,
    /// Something, and no --skip-existing: it is overwritten.
    Kept,
    /// With --skip-existing, a whole frame of the plan's size and the output's format: skipped.
    Whole,
    /// With --skip-existing, something else (empty, cut short, another size): written again.
    Broken(String),
    /// With --skip-existing, a whole frame that records other settings than this run's
    /// (`shutter/settings`, those it records): written again, said once a run.
    Other(String),
}

/// The one judgement of an existing output, for the run and for --dry-run alike.
pub(super) fn existing_output(
    skip_existing: bool,
    record: &str,
    plan: &FramePlan,
    output: &Path,
    views: &[Option<String>],
) -> Existing {
    if std::fs::symlink_metadata(output).is_err() {
        return Existing::None;
    }
    if !skip_existing {
        return Existing::Kept;
    }
    let views: Vec<&str> = views.iter().flatten().map(String::as_str).collect();
    let views = if views.len() > 1 { &views[..] } else { &[] };
    // A picture is the display window (`io::output::write_views`): an EXR's overscan is cut
    // off, its bounding box padded; an EXR output keeps the data window.
    let picture = matches!(
        OutputFormat::from_path(output),
        Some(OutputFormat::Image(_))
    );
    let (width, height, largest) = match plan.windows() {
        Some(windows) if picture => (windows.display.width, windows.display.height, 0),
        _ => (plan.width, plan.height, plan.largest_part()),
    };
    if let Some(why) = existing_frame_problem(output, width, height, largest, views) {
        return Existing::Broken(why);
    }
    // A frame another run made with other settings (a farm job resubmitted with another
    // algorithm over the same folder) is not this run's frame.
    // A TIFF holds them in ASCII (`io::image::record`).
    let held = match OutputFormat::from_path(output) {
        Some(OutputFormat::Image(format)) => crate::io::image::record_as_held(record, format),
        _ => record.to_string(),
    };
    // A frame with no record at all was not made by shutter (the plate copied in, another
    // tool's output of the same size): not this run's frame either.
    match recorded_settings(output) {
        Some(recorded) if !record.is_empty() && recorded != held => Existing::Other(recorded),
        None if !record.is_empty() => Existing::Broken(
            "it holds no record of the settings that made it (shutter/settings), so it is \
             not a frame shutter made"
                .into(),
        ),
        _ => Existing::Whole,
    }
}

/// Why a frame made with `recorded` settings is written again, beside this run's `record`.
pub(super) fn other_settings(recorded: &str, record: &str) -> String {
    format!("it was made with other settings ({recorded}; this run: {record})")
}

/// The run's one warning of the frames made with other settings (`frames`: each frame and
/// what it records, in order): the first frame's output, both settings, and how many more.
pub(super) fn made_otherwise_warning(
    frames: &[(Option<i64>, &String)],
    output: &PathPattern,
    record: &str,
) -> Option<String> {
    let &(frame, recorded) = frames.first()?;
    let at = frame.map_or(String::new(), |f| format!(", frame {f}"));
    let more = match frames.len() {
        1 => String::new(),
        2 => ", as 1 more frame was".to_string(),
        n => format!(", as {} more frames were", n - 1),
    };
    let why = other_settings(recorded, record);
    let path = output.path(frame);
    Some(format!(
        "{}{at} exists but is written again: {why}{more}",
        path.display()
    ))
}
