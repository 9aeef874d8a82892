//! scatter, processing only (no I/O), on synthetic 1920×1080 frames:
//!
//! ```text
//! cargo bench --bench scatter
//! ```
//!
//! - **moving**: every pixel moves 30 px per frame on a gently curved path (a rotating
//!   direction field with a 3 px bend) over two depth layers, shutter 1.0, so every streak
//!   is about 30 px long; the default settings (exposure normalisation, box weight, Bézier,
//!   at most 10 segments, the paper's Δ = 11 points), then the paper's normalisation and
//!   Gaussian, the arc, and a fixed 10 segments (no flatness test); then the default
//!   settings under the default 180° shutter (15 px streaks), and with a fixed 10 segments;
//! - **static**: nothing moves;
//! - **sparse**: one moving square covering a given share of the pixels;
//! - the moving frame (default and paper settings) and the static one on the GPU, where an
//!   adapter is present (`[wgpu]` rows; on a software driver such as lavapipe, far slower
//!   than a GPU);
//! - the moving frame's default with six RGB light layers beside the beauty, against the
//!   beauty alone (issue 29's cost bound: at most 1.5×).
//!
//! Median of 5 runs after one warm-up run. Words after `--` choose the rows whose label holds
//! one of them (`cargo bench --bench scatter -- "light layers"`); none, every row.

mod common;

use common::{positions_frame as frame, H, W};
use shutter::frame::Frame;
use shutter::motion::{Algorithm, CurveKind, Normalize, ScatterParams, Weight};
use shutter::process::Params;

fn median_ms(f: &Frame, params: &Params, runs: usize) -> f64 {
    common::median_ms(Algorithm::Scatter, f, params, runs)
}

fn main() {
    println!("threads: {}", rayon::current_num_threads());
    let chosen = common::chosen_rows();
    let with = |scatter: ScatterParams| Params {
        shutter: 1.0,
        scatter,
        ..Params::default()
    };
    let default = ScatterParams::default();
    let moving = frame(common::curving);
    for (label, params) in [
        ("default (exposure, box, bezier, ≤10 segments)", default),
        (
            "paper (eq. 4, gaussian σ 2, w_b 5)",
            ScatterParams {
                normalize: Normalize::Paper,
                weight: Weight::Gaussian,
                ..default
            },
        ),
        (
            "arc",
            ScatterParams {
                curve: CurveKind::Arc,
                ..default
            },
        ),
        (
            "fixed 10 segments",
            ScatterParams {
                flatness: 0.0,
                ..default
            },
        ),
    ] {
        let label = format!("1920x1080 every pixel moving 30 px, {label}");
        if chosen(&label) {
            println!("{label}: {:.1} ms", median_ms(&moving, &with(params), 5));
        }
    }
    if chosen("1920x1080 every pixel moving 30 px, default, six RGB light layers") {
        common::light_layers_row(
            "every pixel moving 30 px, default",
            Algorithm::Scatter,
            &moving,
            &with(default),
        );
    }
    // The GPU rows (reach, accumulate and resolve on the GPU), wherever an adapter is
    // present: the default and the paper's settings on the same frame, and the still frame.
    let gpu = if chosen("[wgpu]") {
        common::gpu()
    } else {
        None
    };
    match gpu {
        Some(gpu) => {
            let paper = ScatterParams {
                normalize: Normalize::Paper,
                weight: Weight::Gaussian,
                ..default
            };
            let still = frame(|_, _| None);
            for (label, f, params) in [
                ("every pixel moving 30 px, default", &moving, default),
                ("every pixel moving 30 px, paper", &moving, paper),
                ("static, default", &still, default),
            ] {
                let (ms, t) = common::median_ms_on(&gpu, Algorithm::Scatter, f, &with(params), 3);
                common::print_gpu_row(label, &gpu, (ms, t));
            }
        }
        None if chosen("[wgpu]") => println!("wgpu rows skipped: no GPU adapter"),
        None => {}
    }
    // The same motion under the default 180° shutter: 15 px streaks.
    let half = Params {
        shutter: 0.5,
        ..with(default)
    };
    if chosen("shutter 0.5") {
        println!(
            "1920x1080 every pixel moving 30 px, default settings, shutter 0.5 (15 px streaks): {:.1} ms",
            median_ms(&moving, &half, 5)
        );
    }
    let fixed = Params {
        shutter: 0.5,
        ..with(ScatterParams {
            flatness: 0.0,
            ..default
        })
    };
    if chosen("fixed 10 segments, shutter 0.5") {
        println!(
            "1920x1080 every pixel moving 30 px, fixed 10 segments, shutter 0.5: {:.1} ms",
            median_ms(&moving, &fixed, 5)
        );
    }
    let still = frame(|_, _| None);
    if chosen("static") {
        println!(
            "1920x1080 static: {:.2} ms",
            median_ms(&still, &with(default), 5)
        );
    }
    for share in [0.01f32, 0.05, 0.25]
        .into_iter()
        .filter(|_| chosen("sparse"))
    {
        let side = ((W * H) as f32 * share).sqrt() as usize;
        let sparse = frame(|x, y| (x < side && y < side).then_some(([24.0, 8.0], [0.0, 2.0])));
        println!(
            "1920x1080 sparse, a {side}x{side} square moving ({:.0}% of pixels): {:.1} ms",
            share * 100.0,
            median_ms(&sparse, &with(default), 5)
        );
    }
}
