//! stretch, processing only (no I/O), on synthetic 1920×1080 frames:
//!
//! ```text
//! cargo bench --bench stretch
//! ```
//!
//! - **moving**: every pixel moves (a rotating velocity field, 10–40 px per frame, two depth
//!   layers in blocks, so silhouettes run along every block edge), default settings
//!   (centred, texture pre-blur), then without the pre-blur (the talk's plain form);
//! - **static**: nothing moves;
//! - **sparse**: one moving square covering a given share of the pixels;
//! - **wgpu**: the default on every-pixel-moving and on the 5 % sparse frame with the three
//!   stages on the GPU (src/gpu/motion/stretch.rs), wherever an adapter is present — on Mesa's
//!   lavapipe a record, not a speed: it runs the shaders on the same CPU cores.
//!
//! Median of 5 runs after one warm-up run.

mod common;

use common::{frame, H, W};
use shutter::motion::{Algorithm, StretchParams};
use shutter::process::Params;

fn median_ms(f: &shutter::frame::Frame, params: &Params, runs: usize) -> f64 {
    common::median_ms(Algorithm::Stretch, f, params, runs)
}

fn main() {
    println!("threads: {}", rayon::current_num_threads());
    let default = Params::default();
    let plain = Params {
        stretch: StretchParams {
            texture_blur: false,
            ..StretchParams::default()
        },
        ..default
    };
    let moving = frame(common::rotating);
    let side = ((W * H) as f32 * 0.05).sqrt() as usize;
    let sparse = frame(|x, y| (x < side && y < side).then_some((24.0, 8.0)));
    // The GPU rows first, so `cargo bench --bench stretch -- wgpu` stops after them.
    match common::gpu() {
        Some(gpu) => {
            for (label, f) in [("every pixel moving", &moving), ("sparse 5 %", &sparse)] {
                let (ms, t) = common::median_ms_on(&gpu, Algorithm::Stretch, f, &default, 5);
                println!(
                    "1920x1080 {label}, default [wgpu on {}]: {ms:.1} ms (GPU stages per run: \
                     upload {:.1} ms, compute {:.1} ms, readback {:.1} ms; stages on the CPU: \
                     {})",
                    gpu.adapter(),
                    t.upload_ms,
                    t.compute_ms,
                    t.readback_ms,
                    gpu.stages_on_cpu()
                );
            }
        }
        None => println!("wgpu rows skipped: no GPU adapter"),
    }
    if std::env::args().any(|a| a == "wgpu") {
        return;
    }
    for (label, params) in [("default", &default), ("plain (no texture blur)", &plain)] {
        println!(
            "1920x1080 every pixel moving, {label}: {:.1} ms",
            median_ms(&moving, params, 5)
        );
    }
    let still = frame(|_, _| None);
    println!("1920x1080 static: {:.2} ms", median_ms(&still, &default, 5));
    common::sparse_rows(|f| median_ms(f, &default, 5));
}
