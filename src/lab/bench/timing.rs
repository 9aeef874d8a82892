//! One setting on one scene's frame, timed two ways, each the median of the bench's runs:
//! compute only (the algorithm on passes already decoded, on the CPU or, for a `[wgpu]` row,
//! with the stages that have a GPU twin on the GPU, whose upload, dispatch and readback are
//! booked apart), and end to end (the `shutter blur` binary on the files: process start,
//! read, compute, write), with the process's peak memory and the frame it wrote, which is
//! what gets scored.

use std::path::PathBuf;
use std::time::Instant;

use super::options::BenchOptions;
use super::sweep::Setting;
use crate::error::{Error, Problem, ProblemKind, Result};
use crate::gpu::{Gpu, GpuTimes};
use crate::io::passes::{plan_frame, read_frame, Inputs, PlanOptions};
use crate::io::preset::Preset;
use crate::numeric;
use crate::process::{self, apply};

/// The median of `values`; 0 for none.
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

/// A setting's compute-only timing.
pub(super) struct Compute {
    /// Median processing time, ms.
    pub compute_ms: f64,
    /// On wgpu, the GPU stages' upload, dispatch and readback per run.
    pub gpu_stages: Option<GpuTimes>,
    /// On wgpu, stage runs with a twin that ran on the CPU instead.
    pub stages_on_cpu: Option<u64>,
}

/// Times `setting` on the frame of `inputs`, compute only, `runs` times; on `on_gpu` when
/// given.
pub(super) fn compute(
    setting: &Setting,
    inputs: &Inputs,
    preset: &Preset,
    runs: usize,
    on_gpu: Option<&Gpu>,
) -> Result<Compute> {
    // Compute only: the algorithm on decoded passes, median of `runs`.
    let plan_options = PlanOptions {
        preset,
        layer: None,
        view: None,
        needs: crate::process::needs(setting.algorithm, &setting.params),
        max_pixels: crate::io::file::DEFAULT_MAX_PIXELS,
    };
    let plan = plan_frame(inputs, Some(1), &plan_options).map_err(Error::Files)?;
    let frame = read_frame(&plan)?;
    let mut times = Vec::with_capacity(runs);
    let fallbacks_before = on_gpu.map_or(0, |gpu| gpu.stages_on_cpu());
    if let Some(gpu) = on_gpu {
        gpu.take_times();
        gpu.set_profiling(true);
    }
    for _ in 0..runs {
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
        gpu.take_times().per_run(runs)
    });
    // Stages with a twin that ran on the CPU instead in those runs (a frame over the device's
    // limits): the row is then not all GPU.
    let stages_on_cpu = on_gpu.map(|gpu| gpu.stages_on_cpu() - fallbacks_before);
    Ok(Compute {
        compute_ms,
        gpu_stages,
        stages_on_cpu,
    })
}

/// A setting's end-to-end timing.
pub(super) struct EndToEnd {
    /// The frame the last run wrote.
    pub output: PathBuf,
    /// Median wall time of the process, ms.
    pub end_to_end_ms: f64,
    /// Peak resident memory of the process over the runs, MiB, when it reported one.
    pub peak_rss_mib: Option<f64>,
}

/// The `shutter blur` flags that read `inputs`.
pub(super) fn input_flags(inputs: &Inputs) -> Vec<String> {
    (inputs.all().into_iter())
        .flat_map(|(flag, pattern)| [format!("--{flag}"), pattern.raw.clone()])
        .collect()
}

/// Runs the shutter binary with `setting` on the inputs `input_flags` name (with `--backend
/// wgpu` when `wgpu`), `options.runs` times, writing under the bench's runs folder by target
/// `name` and `label`.
pub(super) fn end_to_end(
    options: &BenchOptions,
    name: &str,
    label: &str,
    setting: &Setting,
    wgpu: bool,
    input_flags: &[String],
) -> Result<EndToEnd> {
    // End to end: the shutter binary on the frame, median of `runs`.
    let out_dir = options.out.join("runs").join(name.replace(' ', "_"));
    let file_stem = label.replace(' ', "_");
    let output = out_dir.join(format!("{file_stem}.0001.exr"));
    let mut walls = Vec::with_capacity(options.runs);
    let mut peak: Option<f64> = None;
    for _ in 0..options.runs {
        let mut command = std::process::Command::new(&options.binary);
        command.arg("blur").args(setting.flags());
        if wgpu {
            command.args(["--backend", "wgpu"]);
        }
        command.args(input_flags);
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
        let report: serde_json::Value = serde_json::from_slice(&result.stdout).unwrap_or_default();
        if let Some(rss) = report["peak_rss_mib"].as_f64() {
            peak = Some(peak.map_or(rss, |p: f64| p.max(rss)));
        }
    }
    Ok(EndToEnd {
        output,
        end_to_end_ms: median(walls),
        peak_rss_mib: peak,
    })
}
