//! `shutter scene`: writes a scene's passes and references as EXR sequences in the canonical
//! convention, so `shutter blur` reads them with nothing but the pass paths.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::layers::render_layers;
use super::model::Scene;
use super::render::{
    render_layer_references, render_passes, render_reference, Reference, RenderSettings,
};
use super::scenes::build;
use crate::error::{Error, Problem, ProblemKind, Result};
use crate::frame::{Plane, Windows};
use crate::io::exr::ExrOptions;
use crate::io::output::{write_exr_atomic, write_passes};

/// Default reference samples per pixel: enough for the convergence test (`tests/truth.rs`).
pub const DEFAULT_SAMPLES: usize = 1024;
/// Default output size.
pub const DEFAULT_SIZE: (usize, usize) = (640, 360);

/// What to write.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneOptions {
    pub width: usize,
    pub height: usize,
    pub frames: usize,
    pub samples: usize,
    pub shutter: f64,
    /// Where the exposure sits about the frame, in exposures (0 centred, +½ opening at the
    /// frame, −½ closing at it; `motion::Shutter`).
    pub shutter_offset: f64,
    pub seed: u64,
    /// Also write `layers.####.exr`: the scene as Blender's multilayer render of two view
    /// layers, `FG` and `BG` ([`super::layers`]), and `reference_fg.####.exr` and
    /// `reference_bg.####.exr`, each layer's own motion-blur reference (FG over a transparent
    /// film, premultiplied RGBA).
    pub layers: bool,
    /// The most memory the scene may need, in bytes ([`memory_needed`]); `None`: the
    /// default `max-memory`'s, [`crate::pipeline::memory_limit`].
    pub max_memory: Option<u64>,
}

impl Default for SceneOptions {
    fn default() -> Self {
        SceneOptions {
            width: DEFAULT_SIZE.0,
            height: DEFAULT_SIZE.1,
            frames: 1,
            samples: DEFAULT_SAMPLES,
            shutter: 0.5,
            shutter_offset: 0.0,
            seed: 1,
            layers: false,
            max_memory: None,
        }
    }
}

/// The description written beside the frames (`scene.json`).
#[derive(Clone, Debug, Serialize)]
pub struct SceneDescription {
    pub scene: String,
    pub width: usize,
    pub height: usize,
    pub frames: usize,
    pub samples: usize,
    pub shutter: f64,
    /// The references' shutter offset, in exposures (0 centred, 0.5 start, −0.5 end).
    pub shutter_offset: f64,
    pub seed: u64,
    /// Frame f is scene time f − 1 (frames).
    pub first_frame: usize,
    /// Patterns of the files written, by role.
    pub files: Vec<(String, String)>,
    pub lens: Option<LensDescription>,
}

#[derive(Clone, Debug, Serialize)]
pub struct LensDescription {
    pub focal_mm: f64,
    pub f_number: f64,
    pub focus: f64,
    pub sensor_mm: f64,
}

/// How many planes of the frame's size a scene holds at once, at most: the passes (colour,
/// depth, velocity, prev, next), a reference and its sums, and the encoder's copies. Peak
/// RSS measured over every scene (2026-12, 1024², 2048² and 4096², one sample): 13 to 18
/// planes above the program's own memory.
const SCENE_PLANES: u64 = 20;
/// The same with `--layers`: each view layer's passes and references besides (34 to 38
/// measured).
const SCENE_LAYERS_PLANES: u64 = 40;

/// The memory writing a `width`×`height` scene needs at most (with `layers`, its view
/// layers too): [`SCENE_PLANES`] (or [`SCENE_LAYERS_PLANES`]) f32 planes and the program's own
/// ([`crate::io::passes::BASE_MEMORY`]).
pub fn memory_needed(width: usize, height: usize, layers: bool) -> u64 {
    let planes = if layers {
        SCENE_LAYERS_PLANES
    } else {
        SCENE_PLANES
    };
    (width as u64)
        .saturating_mul(height as u64)
        .saturating_mul(4 * planes)
        .saturating_add(crate::io::passes::BASE_MEMORY)
}

/// Whether `scene` fits in the memory `options` allows: the allocations are refused here,
/// before any is made, rather than aborting the process part-way (Rust's allocator aborts
/// when the system refuses memory).
fn check_memory(scene: &Scene, dir: &Path, options: &SceneOptions) -> Result<()> {
    let needed = memory_needed(scene.width, scene.height, options.layers);
    let limit = options
        .max_memory
        .unwrap_or_else(crate::pipeline::memory_limit);
    if needed <= limit {
        return Ok(());
    }
    let mib = |bytes: u64| bytes.div_ceil(1 << 20);
    Err(Problem::new(
        ProblemKind::TooLarge,
        dir,
        format!(
            "a {}x{} scene{} needs about {} MiB, over the {} MiB --max-memory allows{}; use a \
             smaller --size, or raise --max-memory if the machine has it",
            scene.width,
            scene.height,
            if options.layers { " with --layers" } else { "" },
            mib(needed),
            mib(limit),
            if options.max_memory.is_none() {
                " (by default half the machine's memory, within its limits)"
            } else {
                ""
            }
        ),
    )
    .into())
}

/// Builds a scene or explains which names exist.
pub fn scene_by_name(name: &str, options: &SceneOptions) -> Result<Scene> {
    if options.width == 0 || options.height == 0 {
        return Err(Error::usage("--size must be at least 1x1"));
    }
    build(name, options.width, options.height, options.seed).ok_or_else(|| {
        let names: Vec<&str> = super::scenes::SCENES.iter().map(|(n, _)| *n).collect();
        Error::usage(format!(
            "unknown scene '{name}'; scenes are {}",
            names.join(", ")
        ))
    })
}

fn write(path: &Path, scene: &Scene, channels: Vec<(&str, Plane)>) -> Result<()> {
    let channels = channels
        .into_iter()
        .map(|(n, p)| (n.to_string(), p))
        .collect();
    write_channels(path, scene, channels)
}

/// Writes named planes of the scene's size as one single-part float EXR.
fn write_channels(path: &Path, scene: &Scene, channels: Vec<(String, Plane)>) -> Result<()> {
    write_exr_atomic(
        path,
        scene.width,
        scene.height,
        Windows::full(scene.width, scene.height),
        channels,
        ExrOptions::default(),
    )
    .map_err(|detail| Problem::new(ProblemKind::Output, path, detail).into())
}

/// The references a scene has: its role (file name stem) and what it renders.
fn reference_kinds(scene: &Scene) -> Vec<(&'static str, Reference)> {
    let mut kinds = vec![("reference", Reference::MotionBlur)];
    if scene.lens.is_some() {
        kinds.push(("reference_dof", Reference::DepthOfField));
        kinds.push(("reference_both", Reference::Both));
    }
    kinds
}

/// Renders and writes every reference of frame time `t`, each to `file(role)`.
fn write_frame_references(
    scene: &Scene,
    t: f64,
    settings: &RenderSettings,
    file: &mut dyn FnMut(&str) -> PathBuf,
) -> Result<Vec<PathBuf>> {
    let n = scene.width * scene.height;
    let mut written = Vec::new();
    for (role, kind) in reference_kinds(scene) {
        let [r, g, b] = render_reference(scene, t, kind, settings);
        let path = file(role);
        write(
            &path,
            scene,
            vec![("R", r), ("G", g), ("B", b), ("A", vec![1.0; n])],
        )?;
        written.push(path);
    }
    Ok(written)
}

/// The role of a reference rendered again with sampling seed `sampling_seed`
/// ([`write_resampled_references`]): `reference_seed2` for `reference` and seed 2.
pub fn resampled_role(role: &str, sampling_seed: u64) -> String {
    format!("{role}_seed{sampling_seed}")
}

/// Renders frame 1's references again into `dir`, with the scene laid out by `options.seed`
/// as [`write_scene`] lays it out but sampled with `sampling_seed` (sub-pixel, time and
/// aperture samples), as `ROLE_seedS.0001.exr` ([`resampled_role`]). Two renders that differ
/// only in their samples measure the references' Monte Carlo noise (the bench's noise floor).
/// Returns the files written, in the order of the references.
pub fn write_resampled_references(
    name: &str,
    dir: &Path,
    options: &SceneOptions,
    sampling_seed: u64,
) -> Result<Vec<PathBuf>> {
    let scene = scene_by_name(name, options)?;
    check_memory(&scene, dir, options)?;
    let settings = RenderSettings {
        samples: options.samples.max(1),
        shutter: options.shutter,
        shutter_offset: options.shutter_offset,
        seed: sampling_seed,
    };
    write_frame_references(&scene, 0.0, &settings, &mut |role| {
        dir.join(format!("{}.0001.exr", resampled_role(role, sampling_seed)))
    })
}

/// Writes every frame of the named scene into `dir`; calls `on_frame` after each.
pub fn write_scene(
    name: &str,
    dir: &Path,
    options: &SceneOptions,
    on_frame: &mut dyn FnMut(usize, &Path),
) -> Result<SceneDescription> {
    check(options)?;
    let scene = scene_by_name(name, options)?;
    write_scene_of(&scene, dir, options, on_frame)
}

/// Whether the options can be written: shutter, offset, frames and samples in range.
fn check(options: &SceneOptions) -> Result<()> {
    if !(0.0..=1.0).contains(&options.shutter) {
        return Err(Error::usage(format!(
            "--shutter {} is outside 0..1",
            options.shutter
        )));
    }
    if !(-0.5..=0.5).contains(&options.shutter_offset) {
        return Err(Error::usage(format!(
            "--shutter-offset {} is outside -0.5..0.5 (start 0.5, centre 0, end -0.5)",
            options.shutter_offset
        )));
    }
    if options.frames == 0 || options.samples == 0 {
        return Err(Error::usage("--frames and --samples must be at least 1"));
    }
    Ok(())
}

/// Writes every frame of `scene` (one built by [`scene_by_name`], or changed after, as a
/// test does) into `dir`, as [`write_scene`] does: the size is the scene's (`options`' is not
/// read), `options.seed` seeds the samples. Calls `on_frame` after each frame.
pub fn write_scene_of(
    scene: &Scene,
    dir: &Path,
    options: &SceneOptions,
    on_frame: &mut dyn FnMut(usize, &Path),
) -> Result<SceneDescription> {
    check(options)?;
    check_memory(scene, dir, options)?;
    std::fs::create_dir_all(dir).map_err(|e| {
        Problem::new(
            ProblemKind::Output,
            dir,
            format!("cannot create the folder: {e}"),
        )
    })?;
    let settings = RenderSettings {
        samples: options.samples,
        shutter: options.shutter,
        shutter_offset: options.shutter_offset,
        seed: options.seed,
    };
    let mut roles = vec!["color", "depth", "velocity", "prev", "next", "reference"];
    if scene.lens.is_some() {
        roles.extend(["reference_dof", "reference_both"]);
    }
    if options.layers {
        roles.extend(["layers", "reference_fg", "reference_bg"]);
    }
    let file = |role: &str, frame: usize| -> PathBuf { dir.join(format!("{role}.{frame:04}.exr")) };
    for frame in 1..=options.frames {
        let t = (frame - 1) as f64;
        let passes = render_passes(scene, t, options.samples, options.seed);
        write_passes(passes, |role| file(role, frame))?;
        if options.layers {
            let channels = render_layers(scene, t, options.samples, options.seed)
                .into_iter()
                .flat_map(|layer| layer.channels())
                .collect();
            write_channels(&file("layers", frame), scene, channels)?;
            let [r, g, b, a, br, bg, bb] = render_layer_references(scene, t, &settings);
            let name = |(n, p): (&str, Plane)| (n.to_string(), p);
            let fg = [("R", r), ("G", g), ("B", b), ("A", a)].map(name).into();
            write_channels(&file("reference_fg", frame), scene, fg)?;
            let opaque = vec![1.0; scene.width * scene.height];
            let bg = [("R", br), ("G", bg), ("B", bb), ("A", opaque)]
                .map(name)
                .into();
            write_channels(&file("reference_bg", frame), scene, bg)?;
        }
        write_frame_references(scene, t, &settings, &mut |role| file(role, frame))?;
        on_frame(frame, &file("color", frame));
    }
    let description = SceneDescription {
        scene: scene.name.clone(),
        width: scene.width,
        height: scene.height,
        frames: options.frames,
        samples: options.samples,
        shutter: options.shutter,
        shutter_offset: options.shutter_offset,
        seed: options.seed,
        first_frame: 1,
        files: roles
            .iter()
            .map(|r| (r.to_string(), format!("{r}.####.exr")))
            .collect(),
        lens: scene.lens.map(|l| LensDescription {
            focal_mm: l.focal_mm,
            f_number: l.f_number,
            focus: l.focus,
            sensor_mm: l.sensor_mm,
        }),
    };
    let json = serde_json::to_string_pretty(&description).unwrap_or_default();
    let path = dir.join("scene.json");
    crate::io::output::write_atomic(&path, |w| {
        use std::io::Write;
        w.write_all(json.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(|detail| Problem::new(ProblemKind::Output, &path, detail))?;
    Ok(description)
}
