//! What the processing benches share: the synthetic 1920×1080 velocity frames and the
//! median timer.

#![allow(dead_code)] // each bench uses its part

use std::time::Instant;

use shutter::frame::{Color, Frame, Velocity};
use shutter::motion::Algorithm;
use shutter::process::{apply, Params};

pub const W: usize = 1920;
pub const H: usize = 1080;

/// A checker and gradients over two depth layers in blocks; `moving(x, y)` gives a pixel's
/// velocity in px per frame (`None`: still).
pub fn frame(moving: impl Fn(usize, usize) -> Option<(f32, f32)>) -> Frame {
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

/// Median processing time (ms) of `runs` runs of `algorithm` on `f`, after a warm-up run.
pub fn median_ms(algorithm: Algorithm, f: &Frame, params: &Params, runs: usize) -> f64 {
    let _ = apply(algorithm, params, f.clone(), 1);
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let input = f.clone();
            let t = Instant::now();
            let out = apply(algorithm, params, input, 1);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            drop(out);
            ms
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}
