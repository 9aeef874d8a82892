//! `shutter bench`: every scene × algorithm × setting of the sweep, timed (compute only, and
//! end to end through the `shutter blur` binary with its I/O) and scored against the scene's
//! brute-force reference; written as bench.json, bench.md, pareto.svg/.png and one contact
//! sheet per scene. Each reference is rendered a second time with other samples, so that each
//! error also comes corrected for the reference's own noise ([`noise`]); other programs'
//! outputs on the same scene files are scored beside shutter's ([`peers`]).

pub mod noise;
pub mod peers;
pub mod plot;

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use crate::dof::{BlendForm, CocSource, DofParams, Lens, Method};
use crate::error::{Error, Problem, ProblemKind, Result};
use crate::frame::Frame;
use crate::gpu::{Backend, GpuTimes};
use crate::io::passes::{plan_frame, read_color, read_frame, Inputs, PlanOptions};
use crate::io::preset::Preset;
use crate::io::sequence::PathPattern;
use crate::lab::metrics::{self, Rgb, Scores};
use crate::lab::truth::scenes::SCENES;
use crate::lab::truth::write::{
    resampled_role, write_resampled_references, write_scene, SceneOptions,
};
use crate::motion::{
    Algorithm, Anchor, CurveKind, Normalize, ReconstructParams, ScatterParams, StretchParams,
    Variant, Weight,
};
use crate::numeric;
use crate::process::{self, apply, Params};
use crate::settings;

/// One point of the sweep: an algorithm with its parameters. The flags that run it come from
/// the settings' definitions ([`settings::flags`]).
#[derive(Clone, Debug)]
pub struct Setting {
    pub label: String,
    pub algorithm: Algorithm,
    pub params: Params,
}

impl Setting {
    /// The `shutter blur` flags that run this setting.
    pub fn flags(&self) -> Vec<String> {
        settings::flags(&settings::Settings::of(self.algorithm, &self.params))
    }
}

/// The sweep: every algorithm that exists, with its settings. Later issues add theirs here.
pub fn sweep() -> Vec<Setting> {
    let mut settings = vec![Setting {
        label: "none".into(),
        algorithm: Algorithm::None,
        params: Params::default(),
    }];
    let reconstruct = |taps: usize, max_blur: usize, variant: Variant| {
        let name = Variant::ALL
            .iter()
            .find(|(_, v)| *v == variant)
            .map_or("?", |(n, _)| n);
        Setting {
            label: format!("reconstruct {name} S{taps} k{max_blur}"),
            algorithm: Algorithm::Reconstruct,
            params: Params {
                reconstruct: ReconstructParams {
                    taps,
                    max_blur,
                    variant,
                    ..ReconstructParams::default()
                },
                ..Params::default()
            },
        }
    };
    for taps in [5, 9, 15, 25] {
        settings.push(reconstruct(taps, 20, Variant::Paper));
    }
    for max_blur in [10, 40] {
        settings.push(reconstruct(15, max_blur, Variant::Paper));
    }
    settings.push(reconstruct(15, 20, Variant::Dual));
    // The 2014 filter as Blender runs it, and ours (the default: S 31, k 128) against taps
    // and k.
    settings.push(reconstruct(31, 128, Variant::Stable));
    for (taps, max_blur) in [(15, 128), (31, 128), (63, 128), (31, 20)] {
        settings.push(reconstruct(taps, max_blur, Variant::Exposure));
    }
    settings.extend(scatter_sweep());
    settings.extend(stretch_sweep());
    settings
}

/// stretch's settings: the default (centred, texture pre-blur), then one change at a time.
fn stretch_sweep() -> Vec<Setting> {
    let default = StretchParams::default();
    [
        default,
        StretchParams {
            anchor: Anchor::Rear,
            ..default
        },
        StretchParams {
            texture_blur: false,
            ..default
        },
        StretchParams {
            anchor: Anchor::Rear,
            texture_blur: false,
            ..default
        },
        StretchParams {
            extent: 8.0,
            ..default
        },
        StretchParams {
            extent: 32.0,
            ..default
        },
    ]
    .into_iter()
    .map(|p| {
        let anchor = match p.anchor {
            Anchor::Centre => "centre",
            Anchor::Rear => "rear",
        };
        let mut label = format!("stretch {anchor} extent{}", p.extent);
        if !p.texture_blur {
            label += " plain";
        }
        Setting {
            label,
            algorithm: Algorithm::Stretch,
            params: Params {
                stretch: p,
                ..Params::default()
            },
        }
    })
    .collect()
}

/// scatter's settings: the paper's defaults, then one change at a time.
fn scatter_sweep() -> Vec<Setting> {
    let paper = ScatterParams {
        normalize: Normalize::Paper,
        weight: Weight::Gaussian,
        curve: CurveKind::Bezier,
        ..ScatterParams::default()
    };
    let exposure = ScatterParams {
        normalize: Normalize::Exposure,
        weight: Weight::Box,
        ..paper
    };
    let variants = [
        paper,
        ScatterParams {
            background_weight: 1.0,
            ..paper
        },
        ScatterParams {
            background_weight: 20.0,
            ..paper
        },
        ScatterParams {
            curve: CurveKind::Arc,
            ..paper
        },
        exposure,
        ScatterParams {
            curve: CurveKind::Arc,
            ..exposure
        },
        ScatterParams {
            weight: Weight::Gaussian,
            sigma: 0.25,
            ..exposure
        },
        ScatterParams {
            segments: 4,
            ..exposure
        },
        ScatterParams {
            flatness: 0.0,
            segments: 20,
            ..exposure
        },
    ];
    variants.into_iter().map(scatter_setting).collect()
}

fn scatter_setting(p: ScatterParams) -> Setting {
    let normalize = match p.normalize {
        Normalize::Paper => "paper",
        Normalize::Exposure => "exposure",
    };
    let weight = match p.weight {
        Weight::Gaussian => "gaussian",
        Weight::Box => "box",
    };
    let curve = match p.curve {
        CurveKind::Bezier => "bezier",
        CurveKind::Arc => "arc",
    };
    let mut label = format!("scatter {normalize} {curve} {weight}");
    if p.weight == Weight::Gaussian {
        label += &format!(" σ{}", p.sigma);
    }
    if p.normalize == Normalize::Paper {
        label += &format!(" wb{}", p.background_weight);
    }
    label += &format!(" Δ{}", p.segments);
    if p.flatness == 0.0 {
        label += " fixed";
    }
    Setting {
        label,
        algorithm: Algorithm::Scatter,
        params: Params {
            scatter: p,
            ..Params::default()
        },
    }
}

/// What a scene is scored on: one of its references and the settings scored against it.
#[derive(Clone, Debug)]
pub struct Target {
    /// The scene's name in the rows, plots and contact sheets ("layers", "layers dof").
    pub label: String,
    /// The reference file's role: reference, reference_dof or reference_both.
    pub reference: &'static str,
    pub settings: Vec<Setting>,
}

/// A scene's targets: the motion-blur sweep against its motion reference and, for a scene
/// with a lens, the depth-of-field sweep against the lens reference and depth of field with
/// motion blur against the reference with both.
pub fn targets(name: &str, lens: Option<Lens>) -> Vec<Target> {
    let mut targets = vec![Target {
        label: name.to_string(),
        reference: "reference",
        settings: sweep(),
    }];
    if let Some(lens) = lens {
        targets.push(Target {
            label: format!("{name} dof"),
            reference: "reference_dof",
            settings: dof_sweep(lens),
        });
        targets.push(Target {
            label: format!("{name} dof+motion"),
            reference: "reference_both",
            settings: combined_sweep(lens),
        });
    }
    targets
}

/// A depth-of-field setting (with a motion-blur algorithm after it, or none).
fn dof_setting(label: String, algorithm: Algorithm, dof: DofParams) -> Setting {
    Setting {
        label,
        algorithm,
        params: Params {
            dof: Some(dof),
            ..Params::default()
        },
    }
}

/// Depth of field alone: the sharp frame, then gather and blend with their quality settings.
fn dof_sweep(lens: Lens) -> Vec<Setting> {
    let gather = DofParams::new(CocSource::Lens(lens));
    let blend = DofParams {
        method: Method::Blend,
        ..gather
    };
    let mut settings = vec![Setting {
        label: "none".into(),
        algorithm: Algorithm::None,
        params: Params::default(),
    }];
    for rings in [1, 2, 4, 6] {
        let p = DofParams { rings, ..gather };
        settings.push(dof_setting(format!("gather R{rings}"), Algorithm::None, p));
    }
    let hexagon = DofParams {
        blades: 6,
        ..gather
    };
    settings.push(dof_setting(
        "gather R6 6 blades".into(),
        Algorithm::None,
        hexagon,
    ));
    settings.push(dof_setting("blend".into(), Algorithm::None, blend));
    // The talk's form: two copies, the 2n one at E; and the talk's example n = 5 passes.
    let talk = DofParams {
        blend_form: BlendForm::Talk,
        ..blend
    };
    settings.push(dof_setting("blend talk".into(), Algorithm::None, talk));
    let example = DofParams {
        passes: Some(5),
        ..talk
    };
    settings.push(dof_setting(
        "blend talk n5".into(),
        Algorithm::None,
        example,
    ));
    let wide = DofParams {
        epsilon: 3.0,
        ..blend
    };
    settings.push(dof_setting("blend eps3".into(), Algorithm::None, wide));
    settings
}

/// Depth of field then motion blur, against the reference with both; each alone too.
fn combined_sweep(lens: Lens) -> Vec<Setting> {
    let gather = DofParams::new(CocSource::Lens(lens));
    let blend = DofParams {
        method: Method::Blend,
        ..gather
    };
    let motion = |label: &str, algorithm: Algorithm| Setting {
        label: label.into(),
        algorithm,
        params: Params::default(),
    };
    vec![
        motion("none", Algorithm::None),
        motion("scatter", Algorithm::Scatter),
        dof_setting("gather".into(), Algorithm::None, gather),
        dof_setting("gather + scatter".into(), Algorithm::Scatter, gather),
        dof_setting(
            "gather + reconstruct".into(),
            Algorithm::Reconstruct,
            gather,
        ),
        dof_setting("blend + scatter".into(), Algorithm::Scatter, blend),
    ]
}

/// What to run.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    pub scenes: Vec<String>,
    pub width: usize,
    pub height: usize,
    pub out: PathBuf,
    /// Reference samples per pixel.
    pub samples: usize,
    /// Timed runs per measurement (the median is kept); at least 5.
    pub runs: usize,
    /// The shutter offset of the references and of every setting run against them
    /// (`motion::Shutter::offset`; 0 centred).
    pub shutter_offset: f32,
    /// The shutter binary for the end-to-end runs.
    pub binary: PathBuf,
    /// A folder with a peers.json ([`peers`]) whose outputs are scored too.
    pub peers: Option<PathBuf>,
}

/// One row of the results.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub setting: String,
    /// Where shutter's stages ran: cpu, or wgpu (the stages with a GPU twin on the GPU, the
    /// rest on the CPU; the setting's label ends in "[wgpu]"); empty for a peer's row.
    pub backend: String,
    /// On wgpu, the GPU stages' upload, dispatch and readback per run, ms (measured apart
    /// with the queue drained between them, see [`crate::gpu::Gpu::set_profiling`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_stages: Option<GpuTimes>,
    /// On wgpu, stage runs with a twin that ran on the CPU instead during the compute runs
    /// (a frame over the device's limits); 0 when every twin ran on the GPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stages_on_cpu: Option<u64>,
    /// The program that made the output, for a peer's row ("blender 5.2.3"); none for
    /// shutter's own.
    pub peer: Option<String>,
    /// The settings a peer reports it ran with (null for shutter's rows: the label says).
    #[serde(skip_serializing_if = "serde_json::Value::is_null")]
    pub peer_settings: serde_json::Value,
    /// Median processing time, ms (the algorithm on decoded passes, no I/O).
    pub compute_ms: f64,
    /// Median wall time of `shutter blur` on the frame, ms (process start, read, write); for a
    /// peer, what it measured (null when nothing).
    pub end_to_end_ms: Option<f64>,
    /// Peak resident memory of that process, MiB.
    pub peak_rss_mib: Option<f64>,
    /// Errors against the reference over the whole frame.
    pub whole: Scores,
    /// Errors over the region blur changes (reference differs from the sharp frame).
    pub region: Scores,
    /// The region RMSE against the converged reference, estimated by taking out the
    /// reference's noise: sqrt(max(0, region RMSE² − noise variance)) ([`noise`]).
    pub region_rmse_corrected: f64,
}

/// A target's reference noise over its region, from two renders with different sampling seeds.
#[derive(Clone, Debug, Serialize)]
pub struct NoiseFloor {
    pub scene: String,
    /// The sampling seeds of the two renders (the scene's layout is the same).
    pub seeds: [u64; 2],
    /// Pixels of the region.
    pub pixels: usize,
    /// The RMS noise of one reference over the region: sqrt(mean((r1 − r2)²) / 2).
    pub noise_rmse: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub width: usize,
    pub height: usize,
    /// The shutter offset of the references and the settings (0 centred).
    pub shutter_offset: f32,
    pub samples: usize,
    pub runs: usize,
    pub threads: usize,
    pub rows: Vec<Row>,
    /// Each target's reference noise.
    pub noise: Vec<NoiseFloor>,
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n == 0 {
        0.0
    } else if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// The one-frame scene the bench makes at its size and sample count.
fn scene_options(options: &BenchOptions) -> SceneOptions {
    SceneOptions {
        width: options.width,
        height: options.height,
        frames: 1,
        samples: options.samples,
        shutter_offset: options.shutter_offset as f64,
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
fn ensure_scene(name: &str, dir: &Path, options: &BenchOptions) -> Result<()> {
    let scene_options = scene_options(options);
    let wanted = serde_json::json!({
        "scene": name, "width": options.width, "height": options.height,
        "samples": options.samples, "shutter": scene_options.shutter, "seed": scene_options.seed,
        "shutter_offset": scene_options.shutter_offset,
    });
    if recorded(&dir.join("scene.json"), &wanted) {
        return Ok(());
    }
    write_scene(name, dir, &scene_options, &mut |_, _| {})?;
    Ok(())
}

/// Renders (or reuses, when its record matches) the scene's references again with the next
/// sampling seed and the same layout; returns that seed.
fn ensure_resampled(name: &str, dir: &Path, options: &BenchOptions) -> Result<u64> {
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

fn scene_inputs(dir: &Path) -> Inputs {
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

fn read_rgb(path: &Path) -> Result<Frame> {
    let pattern = PathPattern::parse(&path.display().to_string())?;
    read_color(&pattern, None, &Preset::builtin("shutter")?).map_err(Error::Files)
}

fn rgb(frame: &Frame) -> Rgb<'_> {
    Rgb::of(frame).expect("colour read")
}

/// Runs the whole bench; `progress` gets a line per step.
pub fn run(options: &BenchOptions, progress: &mut dyn FnMut(String)) -> Result<BenchReport> {
    if options.runs < 5 {
        return Err(Error::usage("--runs must be at least 5"));
    }
    for name in &options.scenes {
        if !SCENES.iter().any(|(n, _)| n == name) {
            let names: Vec<&str> = SCENES.iter().map(|(n, _)| *n).collect();
            return Err(Error::usage(format!(
                "unknown scene '{name}'; scenes are {}",
                names.join(", ")
            )));
        }
    }
    let peers = match &options.peers {
        Some(dir) => peers::read(dir)?,
        None => Vec::new(),
    };
    let preset = Preset::builtin("shutter")?;
    // GPU rows beside the CPU's wherever an adapter is present (a software driver included:
    // its figures are for the record, not for speed).
    let gpu = crate::gpu::open(Backend::Wgpu)
        .ok()
        .and_then(|(gpu, _)| gpu);
    if let Some(gpu) = &gpu {
        progress(format!("GPU rows on {}", gpu.adapter()));
    }
    let mut rows = Vec::new();
    let mut noise_floors = Vec::new();
    let mut sheets = Vec::new();
    for scene_name in &options.scenes {
        let dir = options.out.join("scenes").join(scene_name);
        let started = Instant::now();
        ensure_scene(scene_name, &dir, options)?;
        let sampling_seed = ensure_resampled(scene_name, &dir, options)?;
        progress(format!(
            "{scene_name}: scene ready ({:.1} s)",
            started.elapsed().as_secs_f64()
        ));
        let inputs = scene_inputs(&dir);
        let sharp = read_rgb(&dir.join("color.0001.exr"))?;
        let lens = crate::lab::truth::scenes::build(scene_name, options.width, options.height, 1)
            .and_then(|scene| scene.lens);
        for mut target in targets(scene_name, lens) {
            // The settings run with the references' shutter offset.
            for setting in &mut target.settings {
                setting.params.shutter_offset = options.shutter_offset;
            }
            let name = &target.label;
            let reference = read_rgb(&dir.join(format!("{}.0001.exr", target.reference)))?;
            let region = metrics::changed_region(&rgb(&sharp), &rgb(&reference), 1e-3);
            let resampled = read_rgb(&dir.join(format!(
                "{}.0001.exr",
                resampled_role(target.reference, sampling_seed)
            )))?;
            let noise_variance =
                noise::noise_variance(&rgb(&reference), &rgb(&resampled), Some(&region));
            noise_floors.push(NoiseFloor {
                scene: name.clone(),
                seeds: [SceneOptions::default().seed, sampling_seed],
                pixels: region.iter().filter(|&&r| r).count(),
                noise_rmse: noise_variance.sqrt(),
            });
            let mut outputs = Vec::new();
            let runs = target.settings.iter().flat_map(|setting| {
                let gpu = gpu.as_ref().filter(|_| has_twin(setting));
                std::iter::once((setting, None)).chain(gpu.map(|g| (setting, Some(g))))
            });
            for (setting, on_gpu) in runs {
                let label = match on_gpu {
                    Some(_) => format!("{} [wgpu]", setting.label),
                    None => setting.label.clone(),
                };
                // Compute only: the algorithm on decoded passes, median of `runs`.
                let plan_options = PlanOptions {
                    preset: &preset,
                    layer: None,
                    view: None,
                    needs: crate::process::needs(setting.algorithm, &setting.params),
                    max_pixels: crate::io::file::DEFAULT_MAX_PIXELS,
                };
                let plan = plan_frame(&inputs, Some(1), &plan_options).map_err(Error::Files)?;
                let frame = read_frame(&plan)?;
                let mut times = Vec::with_capacity(options.runs);
                let fallbacks_before = on_gpu.map_or(0, |gpu| gpu.stages_on_cpu());
                if let Some(gpu) = on_gpu {
                    gpu.take_times();
                    gpu.set_profiling(true);
                }
                for _ in 0..options.runs {
                    let mut input = frame.clone();
                    let t = Instant::now();
                    let out = match on_gpu {
                        None => apply(setting.algorithm, &setting.params, input, 1),
                        Some(gpu) => {
                            let params = &setting.params;
                            let _ = numeric::sanitize(&mut input, process::depth_kind(params));
                            process::process_on(setting.algorithm, params, input, 1, Some(gpu))
                        }
                    };
                    times.push(t.elapsed().as_secs_f64() * 1e3);
                    drop(out);
                }
                let compute_ms = median(times);
                // The GPU stages' split, per run (a mean: the parts are summed over runs).
                let gpu_stages = on_gpu.map(|gpu| {
                    gpu.set_profiling(false);
                    gpu.take_times().per_run(options.runs)
                });
                // Stages with a twin that ran on the CPU instead in those runs (a frame over
                // the device's limits): the row is then not all GPU.
                let stages_on_cpu = on_gpu.map(|gpu| gpu.stages_on_cpu() - fallbacks_before);

                // End to end: the shutter binary on the frame, median of `runs`.
                let out_dir = options.out.join("runs").join(name.replace(' ', "_"));
                let file_stem = label.replace(' ', "_");
                let output = out_dir.join(format!("{file_stem}.0001.exr"));
                let mut walls = Vec::with_capacity(options.runs);
                let mut peak: Option<f64> = None;
                for _ in 0..options.runs {
                    let mut command = std::process::Command::new(&options.binary);
                    command.arg("blur").args(setting.flags());
                    if on_gpu.is_some() {
                        command.args(["--backend", "wgpu"]);
                    }
                    for (flag, pattern) in inputs.all() {
                        command.arg(format!("--{flag}")).arg(&pattern.raw);
                    }
                    command
                        .args(["--frames", "1", "--json", "-o"])
                        .arg(out_dir.join(format!("{file_stem}.####.exr")));
                    let t = Instant::now();
                    let result = command.output().map_err(|e| {
                        Problem::new(
                            ProblemKind::MissingFile,
                            &options.binary,
                            format!("cannot run the shutter binary: {e}"),
                        )
                    })?;
                    walls.push(t.elapsed().as_secs_f64() * 1e3);
                    if !result.status.success() {
                        return Err(Problem::new(
                            ProblemKind::Output,
                            &output,
                            format!(
                                "shutter blur failed: {}",
                                String::from_utf8_lossy(&result.stderr).trim()
                            ),
                        )
                        .into());
                    }
                    let report: serde_json::Value =
                        serde_json::from_slice(&result.stdout).unwrap_or_default();
                    if let Some(rss) = report["peak_rss_mib"].as_f64() {
                        peak = Some(peak.map_or(rss, |p: f64| p.max(rss)));
                    }
                }
                let blurred = read_rgb(&output)?;
                let whole = metrics::compare(&rgb(&reference), &rgb(&blurred), None);
                let scored = metrics::compare(&rgb(&reference), &rgb(&blurred), Some(&region));
                progress(format!(
                    "{name}: {label} compute {compute_ms:.2} ms, end to end {:.1} ms, region RMSE \
                     {:.5}",
                    median(walls.clone()),
                    scored.rmse
                ));
                rows.push(Row {
                    scene: name.clone(),
                    setting: label.clone(),
                    backend: if on_gpu.is_some() { "wgpu" } else { "cpu" }.to_string(),
                    gpu_stages,
                    stages_on_cpu,
                    peer: None,
                    peer_settings: serde_json::Value::Null,
                    compute_ms,
                    end_to_end_ms: Some(median(walls)),
                    peak_rss_mib: peak,
                    whole,
                    region: scored,
                    region_rmse_corrected: noise::corrected_rmse(scored.rmse, noise_variance),
                });
                outputs.push((label, blurred));
            }
            for peer in peers
                .iter()
                .filter(|p| &p.scene == scene_name && &p.target == name)
            {
                let output = read_rgb(&peer.output)?;
                if (output.width, output.height) != (sharp.width, sharp.height) {
                    return Err(Problem::new(
                        ProblemKind::SizeMismatch,
                        &peer.output,
                        format!(
                            "the peer's output is {}x{}, the scene {}x{}",
                            output.width, output.height, sharp.width, sharp.height
                        ),
                    )
                    .into());
                }
                let whole = metrics::compare(&rgb(&reference), &rgb(&output), None);
                let scored = metrics::compare(&rgb(&reference), &rgb(&output), Some(&region));
                progress(format!(
                    "{name}: peer {} compute {:.2} ms, region RMSE {:.5}",
                    peer.label, peer.compute_ms, scored.rmse
                ));
                rows.push(Row {
                    scene: name.clone(),
                    setting: peer.label.clone(),
                    backend: String::new(),
                    gpu_stages: None,
                    stages_on_cpu: None,
                    peer: Some(peer.peer.clone()),
                    peer_settings: peer.settings.clone(),
                    compute_ms: peer.compute_ms,
                    end_to_end_ms: peer.end_to_end_ms,
                    peak_rss_mib: None,
                    whole,
                    region: scored,
                    region_rmse_corrected: noise::corrected_rmse(scored.rmse, noise_variance),
                });
                outputs.push((peer.label.clone(), output));
            }
            sheets.push((name.clone(), sharp.clone(), outputs, reference));
        }
    }
    let report = BenchReport {
        width: options.width,
        height: options.height,
        shutter_offset: options.shutter_offset,
        samples: options.samples,
        runs: options.runs,
        threads: rayon::current_num_threads(),
        rows,
        noise: noise_floors,
    };
    write_outputs(options, &report, &sheets)?;
    Ok(report)
}

type Sheet = (String, Frame, Vec<(String, Frame)>, Frame);

/// Whether a setting runs any stage that has a GPU twin: depth of field's, reconstruct's,
/// scatter's and stretch's.
fn has_twin(setting: &Setting) -> bool {
    setting.params.dof.is_some()
        || matches!(
            setting.algorithm,
            Algorithm::Reconstruct | Algorithm::Scatter | Algorithm::Stretch
        )
}

fn output_problem(path: &Path, detail: String) -> Error {
    Problem::new(ProblemKind::Output, path, detail).into()
}

fn write_text(path: &Path, text: &str) -> Result<()> {
    crate::io::output::write_atomic(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(|d| output_problem(path, d))
}

fn write_outputs(options: &BenchOptions, report: &BenchReport, sheets: &[Sheet]) -> Result<()> {
    let out = &options.out;
    std::fs::create_dir_all(out.join("contact")).map_err(|e| output_problem(out, e.to_string()))?;
    write_text(
        &out.join("bench.json"),
        &serde_json::to_string_pretty(report).unwrap_or_default(),
    )?;
    write_text(&out.join("bench.md"), &markdown(report))?;
    let svg = plot::pareto_svg(report);
    write_text(&out.join("pareto.svg"), &svg)?;
    let (w, h, pixels) = plot::pareto_png(report);
    plot::write_png(&out.join("pareto.png"), w, h, &pixels)?;
    for (name, sharp, outputs, reference) in sheets {
        let mut panels: Vec<(&str, &Frame)> = vec![("sharp input", sharp)];
        for (label, frame) in outputs {
            panels.push((label, frame));
        }
        panels.push(("reference", reference));
        let (w, h, pixels) = plot::contact_sheet(&panels);
        plot::write_png(
            &out.join("contact")
                .join(format!("{}.png", name.replace([' ', '+'], "-"))),
            w,
            h,
            &pixels,
        )?;
    }
    Ok(())
}

/// The results as a Markdown table.
pub fn markdown(report: &BenchReport) -> String {
    let mut text = format!(
        "{}×{}, reference {} samples per pixel, median of {} runs, {} threads.\n\n\
         Errors against the brute-force reference over the region blur changes (RMSE, PSNR \
         on linear values; SSIM, FLIP on the sRGB display image) and RMSE over the whole \
         frame. RMSE corr. is the region RMSE with the reference's own noise taken out, \
         sqrt(max(0, RMSE² − noise²)); rows with a peer are another program's output on the \
         same files, with the time it measured.\n\n",
        report.width, report.height, report.samples, report.runs, report.threads
    );
    text.push_str(
        "Reference noise over each target's region (RMS, from a second render with other \
         samples):\n\n| scene | region px | noise RMSE |\n|---|---:|---:|\n",
    );
    for floor in &report.noise {
        text.push_str(&format!(
            "| {} | {} | {:.5} |\n",
            floor.scene, floor.pixels, floor.noise_rmse
        ));
    }
    text.push_str(
        "\n| scene | setting | peer | compute ms | end-to-end ms | peak RSS MiB | region px | RMSE | RMSE corr. | PSNR dB | SSIM | FLIP | RMSE whole |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for row in &report.rows {
        text.push_str(&format!(
            "| {} | {} | {} | {:.2} | {} | {} | {} | {:.5} | {:.5} | {:.2} | {:.4} | {:.4} | {:.5} |\n",
            row.scene,
            row.setting,
            row.peer.as_deref().unwrap_or("-"),
            row.compute_ms,
            row.end_to_end_ms
                .map_or("-".to_string(), |m| format!("{m:.1}")),
            row.peak_rss_mib
                .map_or("-".to_string(), |m| format!("{m:.0}")),
            row.region.pixels,
            row.region.rmse,
            row.region_rmse_corrected,
            row.region.psnr,
            row.region.ssim,
            row.region.flip,
            row.whole.rmse,
        ));
    }
    let gpu_rows: Vec<&Row> = report
        .rows
        .iter()
        .filter(|r| r.gpu_stages.is_some())
        .collect();
    if !gpu_rows.is_empty() {
        text.push_str(
            "\nGPU stages of the [wgpu] rows per run (ms; measured apart, the queue drained \
             between them; the rest of compute ms is the stages on the CPU and the host's \
             packing; fallbacks: stage runs with a twin that ran on the CPU instead):\n\n\
             | scene | setting | upload | compute | readback | fallbacks |\n|---|---|---:|---:|---:|---:|\n",
        );
        for row in gpu_rows {
            let t = row.gpu_stages.expect("filtered");
            text.push_str(&format!(
                "| {} | {} | {:.2} | {:.2} | {:.2} | {} |\n",
                row.scene,
                row.setting,
                t.upload_ms,
                t.compute_ms,
                t.readback_ms,
                row.stages_on_cpu.unwrap_or(0)
            ));
        }
    }
    text
}
