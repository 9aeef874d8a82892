//! reconstruct, processing only (no I/O), on synthetic 1920×1080 frames:
//!
//! ```text
//! cargo bench --bench reconstruct
//! ```
//!
//! - **moving**: every pixel moves (a rotating velocity field, 10–40 px per frame, two depth
//!   layers), the default settings (exposure, k = 128, S = 31), shutter 0.5;
//! - **static**: nothing moves (the early-out);
//! - **sparse**: one moving square covering a given share of the tiles;
//! - the moving frame again at S = 1, 7 and 31, to separate fixed costs from per-tap costs;
//! - the moving frame through each variant, and the 2014 filters at more taps and larger k;
//! - the default on the GPU (its tile stages and gather), where an adapter is present;
//! - the moving frame's default with six RGB light layers beside the beauty, against the
//!   beauty alone (issue 29's cost bound: at most 1.5×).
//!
//! Median of 9 runs after one warm-up run.

mod common;

use common::frame;
use shutter::motion::{Algorithm, Variant};
use shutter::process::Params;

fn median_ms(f: &shutter::frame::Frame, runs: usize) -> f64 {
    common::median_ms(Algorithm::Reconstruct, f, &Params::default(), runs)
}

fn median_ms_with(f: &shutter::frame::Frame, runs: usize, params: &Params) -> f64 {
    common::median_ms(Algorithm::Reconstruct, f, params, runs)
}

fn main() {
    let chosen = common::chosen_rows();
    println!("threads: {}", rayon::current_num_threads());
    let moving = frame(common::rotating);
    if chosen("the default") {
        println!(
            "1920x1080 every pixel moving, the default (exposure k=128 S=31): {:.1} ms",
            median_ms(&moving, 9)
        );
    }
    // The GPU row: the default with its tile stages and gather on the GPU (pack on the CPU),
    // wherever an adapter is present.
    if chosen("the default [wgpu]") {
        match common::gpu() {
            Some(gpu) => {
                let (ms, t) = common::median_ms_on(
                    &gpu,
                    Algorithm::Reconstruct,
                    &moving,
                    &Params::default(),
                    5,
                );
                common::print_gpu_row("every pixel moving, the default", &gpu, (ms, t));
            }
            None => println!("wgpu row skipped: no GPU adapter"),
        }
    }
    // The profile: cost against taps. S = 1 takes no taps (TileMax, NeighborMax, texel
    // packing and per-pixel set-up only); the slope is the cost per tap.
    if chosen("taps") {
        for taps in [1, 7, 31] {
            let mut params = Params::default();
            params.reconstruct.taps = taps;
            println!(
                "1920x1080 every pixel moving, exposure k=128 S={taps}: {:.1} ms",
                median_ms_with(&moving, 5, &params)
            );
        }
    }
    // The variants side by side (paper is the default above), and the 2014 filters' time
    // against taps and k: BENCHMARKS.md sets these against their errors.
    if chosen("variants") {
        for (variant, taps, max_blur) in [
            (Variant::Paper, 15, 20),
            (Variant::Stable, 15, 20),
            (Variant::Exposure, 15, 20),
            (Variant::Stable, 15, 128),
            (Variant::Exposure, 15, 128),
            (Variant::Exposure, 31, 128),
            (Variant::Exposure, 63, 128),
            (Variant::Paper, 15, 20),
        ] {
            let mut params = Params::default();
            params.reconstruct.variant = variant;
            params.reconstruct.taps = taps;
            params.reconstruct.max_blur = max_blur;
            let name = Variant::ALL.iter().find(|(_, v)| *v == variant).unwrap().0;
            println!(
                "1920x1080 every pixel moving, {name} k={max_blur} S={taps}: {:.1} ms",
                median_ms_with(&moving, 5, &params)
            );
        }
    }
    if chosen("numeric policy scan") {
        println!(
            "1920x1080 numeric policy scan of the moving frame (read stage): {:.2} ms",
            common::median_policy_ms(&moving, 9)
        );
    }
    if chosen("light layers") {
        common::light_layers_row(
            "every pixel moving, the default",
            Algorithm::Reconstruct,
            &moving,
            &Params::default(),
        );
    }
    if chosen("static") {
        let still = frame(|_, _| None);
        println!("1920x1080 static: {:.2} ms", median_ms(&still, 9));
    }
    if chosen("sparse") {
        common::sparse_rows(|f| median_ms(f, 9));
    }
}
