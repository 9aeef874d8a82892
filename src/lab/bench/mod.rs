//! `shutter bench`: every scene × algorithm × setting of the sweep, timed (compute only, and
//! end to end through the `shutter blur` binary with its I/O) and scored against the scene's
//! brute-force reference; written as bench.json, bench.md, pareto.svg/.png and one contact
//! sheet per scene. Each reference is rendered a second time with other samples, so that each
//! error also comes corrected for the reference's own noise ([`noise`]); other programs'
//! outputs on the same scene files are scored beside shutter's ([`peers`]).
//!
//! The files, each one part of that run:
//!
//! - `sweep`: the settings run on every scene ([`sweep()`], [`targets`], [`Setting`],
//!   [`Target`]);
//! - `scenes`: the scene files, made or reused, and read back;
//! - `timing`: one setting on one frame, timed compute only and end to end;
//! - `report`: the rows, the report and what is written from it (bench.json, bench.md, the
//!   plots through [`plot`]);
//! - [`noise`], [`peers`], [`plot`] as above; this file holds the options and [`run`], the loop
//!   over scenes, targets, settings and backends.

mod layers;
pub mod noise;
mod options;
pub mod peers;
pub mod plot;
mod report;
mod scenes;
mod sweep;
mod timing;
mod write;

use std::time::Instant;

use crate::error::{Error, Problem, ProblemKind, Result};
use crate::gpu::Backend;
use crate::io::preset::Preset;
use crate::lab::metrics;
use crate::lab::truth::scenes::SCENES;
use crate::lab::truth::write::{resampled_role, SceneOptions};

pub use options::BenchOptions;
pub use report::{markdown, BenchReport, NoiseFloor, Row};
pub use sweep::{sweep, targets, Setting, Target};

use scenes::{ensure_resampled, ensure_scene, read_rgb, rgb, scene_inputs};
use sweep::has_twin;
use timing::{Compute, EndToEnd};
use write::write_outputs;

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
                let Compute {
                    compute_ms,
                    gpu_stages,
                    stages_on_cpu,
                } = timing::compute(setting, &inputs, &preset, options.runs, on_gpu)?;
                let EndToEnd {
                    output,
                    end_to_end_ms,
                    peak_rss_mib,
                } = timing::end_to_end(
                    options,
                    name,
                    &label,
                    setting,
                    on_gpu.is_some(),
                    &timing::input_flags(&inputs),
                )?;
                let blurred = read_rgb(&output)?;
                let whole = metrics::compare(&rgb(&reference), &rgb(&blurred), None);
                let scored = metrics::compare(&rgb(&reference), &rgb(&blurred), Some(&region));
                progress(format!(
                    "{name}: {label} compute {compute_ms:.2} ms, end to end {:.1} ms, region RMSE \
                     {:.5}",
                    end_to_end_ms, scored.rmse
                ));
                rows.push(Row {
                    scene: name.clone(),
                    setting: label.clone(),
                    // What a user gets without choosing: the CPU (the default backend).
                    default: setting.is_default() && on_gpu.is_none(),
                    backend: if on_gpu.is_some() { "wgpu" } else { "cpu" }.to_string(),
                    gpu_stages,
                    stages_on_cpu,
                    peer: None,
                    peer_settings: serde_json::Value::Null,
                    compute_ms,
                    end_to_end_ms: Some(end_to_end_ms),
                    peak_rss_mib,
                    whole,
                    region: scored,
                    region_rmse_corrected: noise::corrected_rmse(scored.rmse, noise_variance),
                });
                outputs.push((label, blurred));
                if options.layers && on_gpu.is_none() {
                    for layered in layers::rows(options, &dir, name, setting)? {
                        let blurred = match &layered.end_to_end {
                            Some(ended) => read_rgb(&ended.output)?,
                            None => layered.frame,
                        };
                        let whole = metrics::compare(&rgb(&reference), &rgb(&blurred), None);
                        let scored =
                            metrics::compare(&rgb(&reference), &rgb(&blurred), Some(&region));
                        progress(format!(
                            "{name}: {} compute {:.2} ms, region RMSE {:.5}",
                            layered.label, layered.compute_ms, scored.rmse
                        ));
                        rows.push(Row {
                            scene: name.clone(),
                            setting: layered.label.clone(),
                            // The stack is what `--layers` gives; a hand merge is no output
                            // of shutter's.
                            default: setting.is_default() && layered.end_to_end.is_some(),
                            backend: "cpu".to_string(),
                            gpu_stages: None,
                            stages_on_cpu: None,
                            peer: None,
                            peer_settings: serde_json::Value::Null,
                            compute_ms: layered.compute_ms,
                            end_to_end_ms: layered.end_to_end.as_ref().map(|e| e.end_to_end_ms),
                            peak_rss_mib: layered.end_to_end.as_ref().and_then(|e| e.peak_rss_mib),
                            whole,
                            region: scored,
                            region_rmse_corrected: noise::corrected_rmse(
                                scored.rmse,
                                noise_variance,
                            ),
                        });
                        outputs.push((layered.label, blurred));
                    }
                }
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
                    default: false,
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
