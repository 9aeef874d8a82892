//! `--algorithm none` throughput against the floor set by the exr crate alone.
//!
//! ```text
//! cargo bench --bench io_throughput            # 10 frames of 1920x1080
//! cargo bench --bench io_throughput -- 4 640 360   # frames, width, height
//! ```
//!
//! Writes a sequence of single-part EXRs holding RGBA f32 + Z + velocity (X, Y), ZIP, under
//! `target/bench-data/`, then times, over the same frames:
//! - **floor**: the exr crate alone decoding each file (all channels, its bulk flat-sample
//!   reader, default parallelism) and encoding them all again as f32 ZIP scan lines (what
//!   shutter's output holds since it keeps every channel, issue 29), frame after frame;
//! - **shutter**: `shutter blur --algorithm none --color frame.####.exr -o out.####.exr`,
//!   run in-process (preflight, read, process, write, atomic rename), best of 3.
//!
//! The ratio shutter / floor is what BENCHMARKS.md records.

use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Parser;
use exr::prelude::*;
use shutter::cli::args::{Cli, Command};
use shutter::frame::Windows;
use shutter::io::exr::{write_channels, ExrOptions};

fn scene(width: usize, height: usize, frame: usize) -> Vec<(String, Vec<f32>)> {
    // Smooth gradients, a moving disc and fine texture: compresses like a render, not
    // like noise or flat colour.
    let n = width * height;
    let mut planes: Vec<Vec<f32>> = (0..7).map(|_| vec![0.0; n]).collect();
    let (cx, cy) = (
        width as f32 * (0.3 + 0.02 * frame as f32),
        height as f32 * 0.5,
    );
    let radius = height as f32 * 0.2;
    for j in 0..height {
        for i in 0..width {
            let k = j * width + i;
            let (x, y) = (i as f32 + 0.5, j as f32 + 0.5);
            let inside = (x - cx).powi(2) + (y - cy).powi(2) < radius * radius;
            let texture = ((x * 0.37).sin() * (y * 0.23).cos()) * 0.05;
            let (r, g, b) = if inside {
                (1.5 + texture, 0.4, 0.2 + texture)
            } else {
                (
                    x / width as f32 * 0.5 + texture,
                    y / height as f32 * 0.4,
                    0.3,
                )
            };
            planes[0][k] = r;
            planes[1][k] = g;
            planes[2][k] = b;
            planes[3][k] = 1.0;
            planes[4][k] = if inside { 4.0 } else { 40.0 + y * 0.01 };
            planes[5][k] = if inside { 25.0 } else { 2.0 };
            planes[6][k] = if inside { 0.0 } else { -1.0 };
        }
    }
    let names = ["R", "G", "B", "A", "Z", "velocity.X", "velocity.Y"];
    names.iter().map(|n| n.to_string()).zip(planes).collect()
}

fn floor(paths: &[PathBuf], out_dir: &Path) -> f64 {
    let start = Instant::now();
    for (index, path) in paths.iter().enumerate() {
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(path)
            .expect("floor read");
        let layer = image.layer_data;
        let size = layer.size;
        let every = layer.channel_data.list;
        let out = Image::from_layer(Layer::new(
            size,
            LayerAttributes::default(),
            Encoding {
                compression: Compression::ZIP16,
                blocks: Blocks::ScanLines,
                line_order: LineOrder::Increasing,
            },
            AnyChannels::sort(every),
        ));
        out.write()
            .to_file(out_dir.join(format!("floor.{index:04}.exr")))
            .expect("floor write");
    }
    start.elapsed().as_secs_f64()
}

fn shutter_run(
    pattern: &str,
    out_pattern: &str,
    frames: usize,
) -> (f64, shutter::pipeline::Report) {
    let spec = format!("1-{frames}");
    let cli = Cli::try_parse_from([
        "shutter",
        "blur",
        "--algorithm",
        "none",
        "--color",
        pattern,
        "--frames",
        &spec,
        "-o",
        out_pattern,
    ])
    .expect("arguments");
    let Command::Blur(args) = cli.command else {
        unreachable!()
    };
    let job = shutter::cli::resolve(&args).expect("job");
    let start = Instant::now();
    let report = shutter::pipeline::run(&job, &mut |_| {}).expect("run");
    (start.elapsed().as_secs_f64(), report)
}

fn main() {
    let numbers: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let frames = numbers.first().copied().unwrap_or(10);
    let width = numbers.get(1).copied().unwrap_or(1920);
    let height = numbers.get(2).copied().unwrap_or(1080);
    let dir = PathBuf::from(format!("target/bench-data/io_{width}x{height}"));
    let out_dir = dir.join("out");
    std::fs::create_dir_all(&out_dir).expect("mkdir");

    let mut paths = Vec::new();
    for frame in 1..=frames {
        let path = dir.join(format!("frame.{frame:04}.exr"));
        if !path.exists() {
            let file = std::io::BufWriter::new(std::fs::File::create(&path).expect("create"));
            write_channels(
                file,
                width,
                height,
                Windows::full(width, height),
                scene(width, height, frame),
                ExrOptions::default(),
            )
            .expect("write input");
        }
        paths.push(path);
    }
    let bytes: u64 = paths
        .iter()
        .map(|p| std::fs::metadata(p).map(|m| m.len()).unwrap_or(0))
        .sum();
    println!(
        "{frames} frames {width}x{height}, RGBA f32 + Z + velocity, ZIP, {:.1} MB per file",
        bytes as f64 / frames as f64 / 1e6
    );

    // Warm the page cache and the code paths once, then best of three for each.
    let _ = floor(&paths[..1], &out_dir);
    let pattern = format!("{}/frame.####.exr", dir.display());
    let out_pattern = format!("{}/shutter.####.exr", out_dir.display());
    let mut floor_best = f64::MAX;
    let mut shutter_best = f64::MAX;
    let mut best_report = None;
    for _ in 0..3 {
        floor_best = floor_best.min(floor(&paths, &out_dir));
        let (seconds, report) = shutter_run(&pattern, &out_pattern, frames);
        if seconds < shutter_best {
            shutter_best = seconds;
            best_report = Some(report);
        }
    }
    let report = best_report.expect("ran");
    let threads = rayon::current_num_threads();
    println!("threads: {threads}");
    println!(
        "floor (exr decode + encode):  {:.3} s  {:.1} ms/frame",
        floor_best,
        floor_best * 1e3 / frames as f64
    );
    println!(
        "shutter blur --algorithm none: {:.3} s  {:.1} ms/frame  (read {:.3} s, process {:.3} s, write {:.3} s summed over overlapping stages; preflight {:.3} s)",
        shutter_best,
        shutter_best * 1e3 / frames as f64,
        report.read_seconds,
        report.process_seconds,
        report.write_seconds,
        report.preflight_seconds
    );
    println!(
        "ratio shutter / floor: {:.3}  (peak RSS {:.0} MiB)",
        shutter_best / floor_best,
        report.peak_rss_mib.unwrap_or(0.0)
    );
}
