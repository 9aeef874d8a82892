//! The bench's layered rows (`shutter bench --layers`, issue 33): each CPU setting run on the
//! scene's view layers (`layers.0001.exr`, `shutter scene --layers`: BG the background plane,
//! FG every shape) two ways, scored against the same reference as the one-layer row:
//!
//! - `[layers]`: the stack, `blur --preset blender --layers FG,BG` ([`crate::stack`]), timed
//!   compute only and end to end;
//! - `[hand merge]`: what a compositor does by hand, each layer blurred alone as it comes and
//!   merged front over back ([`crate::stack::merge`]), compute only.

use std::path::Path;
use std::time::Instant;

use super::options::BenchOptions;
use super::sweep::Setting;
use super::timing::{end_to_end, EndToEnd};
use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::io::passes::{plan_frame, read_frame, Inputs, PlanOptions};
use crate::io::preset::Preset;
use crate::io::sequence::PathPattern;
use crate::process::{self, apply};

/// A layered row's figures and the frame it made.
pub(super) struct Layered {
    pub label: String,
    pub compute_ms: f64,
    pub end_to_end: Option<EndToEnd>,
    pub frame: Frame,
}

/// The view layers, front first.
const LAYERS: [&str; 2] = ["FG", "BG"];

/// Each view layer of the scene in `dir` as `setting` reads it, the numeric policy applied.
fn layer_frames(dir: &Path, setting: &Setting) -> Result<Vec<Frame>> {
    let preset = Preset::builtin("blender")?;
    let pattern = PathPattern::parse(&format!("{}/layers.####.exr", dir.display()))?;
    let inputs = Inputs::color_only(pattern);
    (LAYERS.iter())
        .map(|layer| {
            let options = PlanOptions {
                preset: &preset,
                layer: Some(layer),
                view: None,
                needs: process::needs(setting.algorithm, &setting.params),
                max_pixels: crate::io::file::DEFAULT_MAX_PIXELS,
            };
            let plan = plan_frame(&inputs, Some(1), &options).map_err(Error::Files)?;
            let mut frame = read_frame(&plan)?;
            crate::numeric::sanitize(&mut frame, process::depth_kind(&setting.params));
            Ok(frame)
        })
        .collect()
}

/// The median of `runs` timings of `run`, and its last output.
fn timed(runs: usize, mut run: impl FnMut() -> Frame) -> (f64, Frame) {
    let mut times = Vec::with_capacity(runs);
    let mut last = None;
    for _ in 0..runs {
        let t = Instant::now();
        let out = run();
        times.push(t.elapsed().as_secs_f64() * 1e3);
        last = Some(out);
    }
    times.sort_by(f64::total_cmp);
    let median = match times.len() {
        0 => 0.0,
        n if n % 2 == 1 => times[n / 2],
        n => 0.5 * (times[n / 2 - 1] + times[n / 2]),
    };
    (median, last.unwrap_or_else(|| Frame::new(0, 0)))
}

/// The layered rows of `setting` on the scene in `dir` (target `name`).
pub(super) fn rows(
    options: &BenchOptions,
    dir: &Path,
    name: &str,
    setting: &Setting,
) -> Result<Vec<Layered>> {
    let frames = layer_frames(dir, setting)?;
    let (algorithm, params) = (setting.algorithm, &setting.params);
    let (stack_ms, stack) = timed(options.runs, || {
        crate::stack::process_stack(algorithm, params, frames.clone(), 1, None)
    });
    let label = format!("{} [layers]", setting.label);
    let flags: Vec<String> = [
        "--preset",
        "blender",
        "--layers",
        "FG,BG",
        "--beauty-only",
        "--color",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain([format!("{}/layers.####.exr", dir.display())])
    .collect();
    let ended = end_to_end(options, name, &label, setting, false, &flags)?;
    let (hand_ms, hand) = timed(options.runs, || {
        let blurred = (frames.iter())
            .map(|layer| apply(algorithm, params, layer.clone(), 1))
            .collect();
        crate::stack::merge(blurred)
    });
    Ok(vec![
        Layered {
            label,
            compute_ms: stack_ms,
            end_to_end: Some(ended),
            frame: stack,
        },
        Layered {
            label: format!("{} [hand merge]", setting.label),
            compute_ms: hand_ms,
            end_to_end: None,
            frame: hand,
        },
    ])
}
