//! The scene files the bench measures on: each truth scene written once at the bench's size,
//! sample count and shutter offset, and its references rendered a second time with the next
//! sampling seed (for [`noise`](super::noise)); both reused while their JSON record matches.
//! Then the passes as `shutter blur` reads them, and frames read back as colour.

use std::path::Path;

use super::options::BenchOptions;
use super::write::write_text;
use crate::error::{Error, Result};
use crate::frame::Frame;
use crate::io::passes::{read_color, Inputs};
use crate::io::preset::Preset;
use crate::io::sequence::PathPattern;
use crate::lab::metrics::Rgb;
use crate::lab::truth::write::{write_resampled_references, write_scene, SceneOptions};

/// The one-frame scene the bench makes at its size and sample count.
fn scene_options(options: &BenchOptions) -> SceneOptions {
    SceneOptions {
        width: options.width,
        height: options.height,
        frames: 1,
        samples: options.samples,
        shutter_offset: options.shutter_offset as f64,
        layers: options.layers,
        ..SceneOptions::default()
    }
}

/// Whether the JSON record at `path` holds every key of `wanted` with its value (a cached
/// scene or resampled reference made with these settings).
fn recorded(path: &Path, wanted: &serde_json::Value) -> bool {
    let Ok(text) = std::fs::read_to_string(path) else {
        return false;
    };
    let Ok(found) = serde_json::from_str::<serde_json::Value>(&text) else {
        return false;
    };
    wanted
        .as_object()
        .is_some_and(|w| w.iter().all(|(k, v)| found.get(k) == Some(v)))
}

/// Makes (or reuses, when its scene.json matches) a scene's files.
pub(super) fn ensure_scene(name: &str, dir: &Path, options: &BenchOptions) -> Result<()> {
    let scene_options = scene_options(options);
    let wanted = serde_json::json!({
        "scene": name, "width": options.width, "height": options.height,
        "samples": options.samples, "shutter": scene_options.shutter, "seed": scene_options.seed,
        "shutter_offset": scene_options.shutter_offset,
    });
    // A scene without its view layers is made again when they are asked for.
    let layers_there = !options.layers || dir.join("layers.0001.exr").exists();
    if layers_there && recorded(&dir.join("scene.json"), &wanted) {
        return Ok(());
    }
    write_scene(name, dir, &scene_options, &mut |_, _| {})?;
    Ok(())
}

/// Renders (or reuses, when its record matches) the scene's references again with the next
/// sampling seed and the same layout; returns that seed.
pub(super) fn ensure_resampled(name: &str, dir: &Path, options: &BenchOptions) -> Result<u64> {
    let scene_options = scene_options(options);
    let sampling_seed = scene_options.seed + 1;
    let wanted = serde_json::json!({
        "scene": name, "width": options.width, "height": options.height,
        "samples": options.samples, "shutter": scene_options.shutter,
        "seed": scene_options.seed, "sampling_seed": sampling_seed,
        "shutter_offset": scene_options.shutter_offset,
    });
    let record = dir.join("resampled.json");
    if recorded(&record, &wanted) {
        return Ok(sampling_seed);
    }
    write_resampled_references(name, dir, &scene_options, sampling_seed)?;
    write_text(
        &record,
        &serde_json::to_string_pretty(&wanted).unwrap_or_default(),
    )?;
    Ok(sampling_seed)
}

pub(super) fn scene_inputs(dir: &Path) -> Inputs {
    let pattern = |role: &str| {
        PathPattern::parse(&format!("{}/{role}.####.exr", dir.display())).expect("valid pattern")
    };
    Inputs {
        color: pattern("color"),
        depth: Some(pattern("depth")),
        velocity: Some(pattern("velocity")),
        prev: Some(pattern("prev")),
        next: Some(pattern("next")),
    }
}

pub(super) fn read_rgb(path: &Path) -> Result<Frame> {
    let pattern = PathPattern::parse(&path.display().to_string())?;
    read_color(&pattern, None, &Preset::builtin("shutter")?).map_err(Error::Files)
}

pub(super) fn rgb(frame: &Frame) -> Rgb<'_> {
    Rgb::of(frame).expect("colour read")
}
