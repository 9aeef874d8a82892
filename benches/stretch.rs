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
//! - **sparse**: one moving square covering a given share of the pixels.
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
    for (label, params) in [("default", &default), ("plain (no texture blur)", &plain)] {
        println!(
            "1920x1080 every pixel moving, {label}: {:.1} ms",
            median_ms(&moving, params, 5)
        );
    }
    let still = frame(|_, _| None);
    println!("1920x1080 static: {:.2} ms", median_ms(&still, &default, 5));
    for share in [0.01f32, 0.05, 0.25] {
        let side = ((W * H) as f32 * share).sqrt() as usize;
        let sparse = frame(|x, y| (x < side && y < side).then_some((24.0, 8.0)));
        println!(
            "1920x1080 sparse, a {side}x{side} square moving ({:.0}% of pixels): {:.1} ms",
            share * 100.0,
            median_ms(&sparse, &default, 5)
        );
    }
}
