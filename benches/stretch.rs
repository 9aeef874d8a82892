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

use std::time::Instant;

use shutter::frame::{Color, Frame, Velocity};
use shutter::motion::{apply, Algorithm, BlurParams, StretchParams};

const W: usize = 1920;
const H: usize = 1080;

fn frame(moving: impl Fn(usize, usize) -> Option<(f32, f32)>) -> Frame {
    let n = W * H;
    let mut f = Frame::new(W, H);
    let mut r = vec![0.0; n];
    let mut g = vec![0.0; n];
    let mut b = vec![0.0; n];
    let mut depth = vec![0.0; n];
    let mut vx = vec![0.0; n];
    let mut vy = vec![0.0; n];
    for y in 0..H {
        for x in 0..W {
            let i = y * W + x;
            r[i] = ((x / 16 + y / 16) % 2) as f32;
            g[i] = x as f32 / W as f32;
            b[i] = y as f32 / H as f32;
            depth[i] = if (x / 200 + y / 150) % 3 == 0 {
                2.0
            } else {
                10.0
            };
            if let Some((u, v)) = moving(x, y) {
                vx[i] = u;
                vy[i] = v;
            }
        }
    }
    f.color = Some(Color {
        r,
        g,
        b,
        a: Some(vec![1.0; n]),
    });
    f.depth = Some(depth);
    f.velocity = Some(Velocity { x: vx, y: vy });
    f
}

fn median_ms(f: &Frame, params: &BlurParams, runs: usize) -> f64 {
    let _ = apply(Algorithm::Stretch, params, f.clone(), 1);
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let input = f.clone();
            let t = Instant::now();
            let out = apply(Algorithm::Stretch, params, input, 1);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            drop(out);
            ms
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}

fn main() {
    println!("threads: {}", rayon::current_num_threads());
    let default = BlurParams::default();
    let plain = BlurParams {
        stretch: StretchParams {
            texture_blur: false,
            ..StretchParams::default()
        },
        ..default
    };
    let moving = frame(|x, y| {
        let a = (x as f32 * 0.002) + (y as f32 * 0.003);
        let speed = 10.0 + 30.0 * ((x + y) % 97) as f32 / 96.0;
        Some((a.cos() * speed, a.sin() * speed))
    });
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
