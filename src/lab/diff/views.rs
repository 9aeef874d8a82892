//! Which views of a frame `shutter diff` compares, and the names of one view's outputs.
//!
//! In: the job and a frame's headers (no pixel is decoded). Out: the views to compare, in
//! the order the reference lists them, and the candidate's views left out; or a problem
//! naming the view the candidate lacks. Where it sits: before any frame is read, with the
//! check that no `--heatmap` names an input, so both are found from the headers alone.
//!
//! A multi-view (stereo) reference is compared in every view it holds (`io::view`), each
//! view an entry of the report, without `--view`: compared in its default view alone, a
//! change confined to the other eye passed a CI gate. A view the reference holds and the
//! candidate lacks is refused, as a missing input is (the comparison of that view cannot be
//! made); a view the candidate holds and the reference lacks is warned, as a channel the
//! candidate adds is (nothing of the reference is lost). `--view NAME` compares that view
//! alone, as it did; a reference of one view, or none, is compared as it was.

use std::path::{Path, PathBuf};

use crate::error::{Problem, ProblemKind};
use crate::io::file::FileInfo;
use crate::io::sequence::PathPattern;
use crate::io::view::Views;

use super::DiffJob;

/// The views of one frame to compare.
#[derive(Clone, Debug)]
pub struct FrameViews {
    pub frame: Option<i64>,
    /// Each view to read: `[None]` for the file's default (a file of one view or none), or
    /// `[--view]`, or every view of a multi-view reference.
    pub views: Vec<Option<String>>,
    /// Where every view of a multi-view reference is compared: each view's name as it goes
    /// into the names of its outputs ([`output_path`]), beside `views`.
    pub outputs: Option<Vec<String>>,
    /// The candidate's views that the reference lacks, not compared (warned).
    pub extra: Vec<String>,
}

/// The views of the file of `pattern`'s `frame`, or why its header cannot be read (as the
/// plan of its colour says it).
fn views_of(pattern: &PathPattern, frame: Option<i64>) -> Result<Option<Views>, Problem> {
    FileInfo::probe(&pattern.path(frame))
        .map(|info| info.views)
        .map_err(|problem| problem.pass("color").frame(frame))
}

/// The views of `frame` that `job` compares: every view of a multi-view reference (the
/// candidate must hold each), else the one asked for or the file's own.
pub fn of_frame(job: &DiffJob, frame: Option<i64>) -> Result<FrameViews, Problem> {
    let one = FrameViews {
        frame,
        views: vec![job.view.clone()],
        outputs: None,
        extra: Vec::new(),
    };
    if job.view.is_some() {
        return Ok(one);
    }
    // A reference that cannot be read is compared as one of no views: its plan says why.
    let Ok(Some(views)) = views_of(&job.a, frame) else {
        return Ok(one);
    };
    if views.names.len() < 2 {
        return Ok(one);
    }
    let theirs = views_of(&job.b, frame)?.map_or(Vec::new(), |v| v.names);
    let missing: Vec<&str> = views
        .names
        .iter()
        .filter(|v| !theirs.contains(v))
        .map(String::as_str)
        .collect();
    if !missing.is_empty() {
        let held = if theirs.is_empty() {
            "it holds no views".to_string()
        } else {
            format!("its own are {}", theirs.join(", "))
        };
        return Err(Problem::new(
            ProblemKind::View,
            job.b.path(frame),
            format!(
                "lacks the view{} {} of the reference {} (every view of the reference is \
                 compared: {}); {held}. --view NAME compares one view alone",
                if missing.len() == 1 { "" } else { "s" },
                missing.join(", "),
                job.a.path(frame).display(),
                views.names.join(", ")
            ),
        )
        .frame(frame));
    }
    Ok(FrameViews {
        frame,
        extra: theirs
            .into_iter()
            .filter(|v| !views.names.contains(v))
            .collect(),
        outputs: Some(file_names(&views.names)),
        views: views.names.into_iter().map(Some).collect(),
    })
}

/// The views' names as they go into file names: letters, digits, `-` and `_` kept, any
/// other character `_` (a view's name is the file's text: no `/` of it may reach a path),
/// and each numbered after its place in the file where two come out alike.
fn file_names(views: &[String]) -> Vec<String> {
    let safe: Vec<String> = views
        .iter()
        .map(|v| {
            let name: String = v
                .chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                        c
                    } else {
                        '_'
                    }
                })
                .collect();
            if name.is_empty() {
                "view".to_string()
            } else {
                name
            }
        })
        .collect();
    let distinct = safe
        .iter()
        .enumerate()
        .all(|(i, name)| !safe[..i].contains(name));
    if distinct {
        safe
    } else {
        safe.into_iter()
            .enumerate()
            .map(|(i, name)| format!("{name}-{}", i + 1))
            .collect()
    }
}

/// One view's output: the view's name before the extension (`heat.0012.png` →
/// `heat.0012.left.png`).
pub fn output_path(path: &Path, view: &str) -> PathBuf {
    let stem = path.file_stem().unwrap_or_default().to_string_lossy();
    let name = match path.extension() {
        Some(ext) => format!("{stem}.{view}.{}", ext.to_string_lossy()),
        None => format!("{stem}.{view}"),
    };
    path.with_file_name(name)
}

/// The heatmaps the job writes, each with its frame: one a frame, or one a view of a frame.
fn heatmaps(heatmap: &PathPattern, planned: &[FrameViews]) -> Vec<(Option<i64>, PathBuf)> {
    let mut paths = Vec::new();
    for f in planned {
        let path = heatmap.path(f.frame);
        match &f.outputs {
            Some(views) => paths.extend(views.iter().map(|v| (f.frame, output_path(&path, v)))),
            None => paths.push((f.frame, path)),
        }
    }
    paths
}

/// Problems, before anything is written, with a `--heatmap` that would replace an input of
/// its frame: the check blur makes of `-o` (the same path, another spelling, a symbolic or
/// hard link). Every heatmap concerned is named; diff answers it as an output it cannot
/// write.
pub fn heatmaps_over_inputs(job: &DiffJob, planned: &[FrameViews]) -> Vec<Problem> {
    let Some(heatmap) = &job.heatmap else {
        return Vec::new();
    };
    let outputs = heatmaps(heatmap, planned);
    let writes: Vec<(&Path, Vec<PathBuf>)> = outputs
        .iter()
        .map(|(frame, output)| {
            let inputs = [Some(&job.a), Some(&job.b), job.sharp.as_ref()];
            let read = inputs.iter().flatten().map(|p| p.path(*frame)).collect();
            (output.as_path(), read)
        })
        .collect();
    crate::io::passes::outputs_over_inputs(&writes)
        .into_iter()
        .map(|(i, input)| {
            Problem::new(
                ProblemKind::Output,
                &outputs[i].1,
                format!(
                    "the heatmap would overwrite the input {}; choose another --heatmap",
                    input.display()
                ),
            )
            .frame(outputs[i].0)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_views_output_is_named_before_the_extension() {
        let out = |p: &str, v: &str| output_path(Path::new(p), v);
        assert_eq!(out("heat.png", "left"), PathBuf::from("heat.left.png"));
        assert_eq!(
            out("out/heat.0012.png", "right"),
            PathBuf::from("out/heat.0012.right.png")
        );
        assert_eq!(out("heat", "left"), PathBuf::from("heat.left"));
    }

    #[test]
    fn view_names_in_file_names_are_safe_and_distinct() {
        let names = |v: &[&str]| file_names(&v.iter().map(|s| s.to_string()).collect::<Vec<_>>());
        assert_eq!(names(&["left", "right"]), ["left", "right"]);
        assert_eq!(names(&["../up", ""]), ["___up", "view"]);
        assert_eq!(names(&["a/b", "a_b"]), ["a_b-1", "a_b-2"]);
    }
}
