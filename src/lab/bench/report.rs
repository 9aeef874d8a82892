//! What the bench reports: a row per setting (or peer) and target, with its timings and
//! errors ([`Row`]), each target's reference noise ([`NoiseFloor`]), the whole report
//! ([`BenchReport`]), and its markdown table ([`markdown`]); `write` puts it in files.

use serde::Serialize;

use crate::gpu::GpuTimes;
use crate::lab::metrics::Scores;

/// One row of the results.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub scene: String,
    pub setting: String,
    /// Whether the row is what a user gets without choosing: a default setting
    /// ([`super::sweep::Setting::is_default`]) on the CPU, alone or as a `[layers]` stack (not
    /// `[wgpu]`, not `[hand merge]`); marked in bench.md and the plot.
    pub default: bool,
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
    /// reference's noise: sqrt(max(0, region RMSE² − noise variance)) ([`noise`](super::noise)).
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
        "\n**(default)** marks each algorithm's defaults, what `--algorithm NAME` (and, for \
         depth of field, `--method NAME` with the lens) gives with no other flag, alone and \
         as a `--layers` stack: so a scene has one for each algorithm. `shutter blur` with no \
         flag at all runs reconstruct's, `shutter dof` the bokeh gather's.\n",
    );
    text.push_str(
        "\n| scene | setting | peer | compute ms | end-to-end ms | peak RSS MiB | region px | RMSE | RMSE corr. | PSNR dB | SSIM | FLIP | RMSE whole |\n\
         |---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for row in &report.rows {
        text.push_str(&format!(
            "| {} | {}{} | {} | {:.2} | {} | {} | {} | {:.5} | {:.5} | {:.2} | {:.4} | {:.4} | {:.5} |\n",
            row.scene,
            row.setting,
            if row.default { " **(default)**" } else { "" },
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
