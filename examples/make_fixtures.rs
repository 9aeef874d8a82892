#![allow(clippy::needless_range_loop)] // per-pixel maths reads best with an index
//! Writes the small fixtures in `fixtures/` (run from the repository root):
//!
//! ```text
//! cargo run --example make_fixtures
//! ```
//!
//! - `fixtures/canonical/{color,depth,velocity,prev,next}.####.exr`, frames 1-3, 96x64: a
//!   textured disc moving right and down over a static checker wall, in the canonical
//!   convention (velocity p(0)-p(-1), absolute positions, y down), ZIP, f32 (depth f16).
//! - `fixtures/blender/shot.0001.exr`: the same frame 2 as one Blender multi-layer file
//!   (`ViewLayer.Combined.RGBA`, `ViewLayer.Depth.Z`, `ViewLayer.Vector.XYZW`, y up).
//!
//! - `fixtures/flip/{name}_{ref,test}.png`: small 8-bit sRGB image pairs whose mean FLIP
//!   error NVIDIA's own implementation computed (`scripts/flip_vectors.py` writes
//!   `fixtures/flip/expected.json`); the metrics tests compare ours against them.
//!
//! The motion is known in closed form, so passes are exact, not estimated.

use std::fs::File;
use std::io::BufWriter;

use shutter::frame::Windows;
use shutter::io::exr::{write_channels, ExrOptions};

const W: usize = 96;
const H: usize = 64;
const RADIUS: f32 = 14.0;

/// Disc centre at time t (frames).
fn centre(t: f32) -> (f32, f32) {
    (30.0 + 6.0 * t, 26.0 + 2.0 * t)
}

struct Passes {
    rgba: [Vec<f32>; 4],
    z: Vec<f32>,
    velocity: [Vec<f32>; 2],
    prev: [Vec<f32>; 2],
    next: [Vec<f32>; 2],
}

fn render(t: f32) -> Passes {
    let n = W * H;
    let mut p = Passes {
        rgba: [vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![1.0; n]],
        z: vec![0.0; n],
        velocity: [vec![0.0; n], vec![0.0; n]],
        prev: [vec![0.0; n], vec![0.0; n]],
        next: [vec![0.0; n], vec![0.0; n]],
    };
    let (cx, cy) = centre(t);
    let (px, py) = centre(t - 1.0);
    let (nx, ny) = centre(t + 1.0);
    for j in 0..H {
        for i in 0..W {
            let k = j * W + i;
            let (x, y) = (i as f32 + 0.5, j as f32 + 0.5);
            let (dx, dy) = (x - cx, y - cy);
            if dx * dx + dy * dy <= RADIUS * RADIUS {
                // Disc: stripes in its own frame (they move with it), HDR rim.
                let stripe = ((dx + 100.0) / 4.0) as i32 % 2 == 0;
                let rim = dx * dx + dy * dy > (RADIUS - 2.0) * (RADIUS - 2.0);
                let (r, g, b) = if rim {
                    (4.0, 3.0, 1.0)
                } else if stripe {
                    (0.9, 0.2, 0.1)
                } else {
                    (0.2, 0.6, 0.9)
                };
                p.rgba[0][k] = r;
                p.rgba[1][k] = g;
                p.rgba[2][k] = b;
                p.z[k] = 5.0;
                p.velocity[0][k] = cx - px;
                p.velocity[1][k] = cy - py;
                p.prev[0][k] = x + (px - cx);
                p.prev[1][k] = y + (py - cy);
                p.next[0][k] = x + (nx - cx);
                p.next[1][k] = y + (ny - cy);
            } else {
                let checker = ((i / 8) + (j / 8)) % 2 == 0;
                let v = if checker { 0.18 } else { 0.05 };
                p.rgba[0][k] = v;
                p.rgba[1][k] = v;
                p.rgba[2][k] = v * 1.2;
                p.z[k] = 20.0;
                p.prev[0][k] = x;
                p.prev[1][k] = y;
                p.next[0][k] = x;
                p.next[1][k] = y;
            }
        }
    }
    p
}

fn write(path: &str, channels: Vec<(&str, Vec<f32>)>, half: bool) {
    let file = BufWriter::new(File::create(path).expect("create fixture"));
    let channels = channels
        .into_iter()
        .map(|(n, p)| (n.to_string(), p))
        .collect();
    let options = ExrOptions {
        half,
        ..ExrOptions::default()
    };
    write_channels(file, W, H, Windows::full(W, H), channels, options).expect("write fixture");
}

/// A deterministic value in [0, 1) per (seed, index).
fn hash01(seed: u32, i: u32) -> f32 {
    let mut h = i.wrapping_mul(0x9E37_79B9) ^ seed.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 12;
    h as f32 / u32::MAX as f32
}

fn flip_pairs() {
    const FW: usize = 64;
    const FH: usize = 48;
    std::fs::create_dir_all("fixtures/flip").expect("mkdir");
    let save = |name: &str, f: &dyn Fn(usize, usize, usize) -> f32| {
        let mut bytes = Vec::with_capacity(FW * FH * 3);
        for j in 0..FH {
            for i in 0..FW {
                for c in 0..3 {
                    bytes.push((f(i, j, c).clamp(0.0, 1.0) * 255.0).round() as u8);
                }
            }
        }
        image::save_buffer(
            format!("fixtures/flip/{name}.png"),
            &bytes,
            FW as u32,
            FH as u32,
            image::ColorType::Rgb8,
        )
        .expect("save png");
    };
    let gradient = |i: usize, j: usize, c: usize| {
        (i as f32 / FW as f32) * [1.0, 0.6, 0.3][c] + (j as f32 / FH as f32) * 0.3
    };
    save("gradient_ref", &gradient);
    save("gradient_test", &|i, j, c| {
        gradient(i, j, c) + 0.08 * (hash01(1, (j * FW + i) as u32 * 3 + c as u32) - 0.5)
    });
    let checker = |i: usize, j: usize, _c: usize| {
        if (i / 8 + j / 8).is_multiple_of(2) {
            0.9
        } else {
            0.1
        }
    };
    save("checker_ref", &checker);
    save("checker_test", &|i, j, c| checker(i + 1, j, c));
    let disc = |i: usize, j: usize, c: usize, r: f32| {
        let (x, y) = (i as f32 - 32.0, j as f32 - 24.0);
        if x * x + y * y < r * r {
            [0.9, 0.3, 0.1][c]
        } else {
            [0.1, 0.2, 0.4][c]
        }
    };
    save("disc_ref", &|i, j, c| disc(i, j, c, 14.0));
    save("disc_test", &|i, j, c| disc(i, j, c, 16.0));
    save("noise_ref", &|i, j, c| {
        hash01(2, (j * FW + i) as u32 * 3 + c as u32)
    });
    save("noise_test", &|i, j, c| {
        hash01(3, (j * FW + i) as u32 * 3 + c as u32)
    });
}

fn main() {
    flip_pairs();
    std::fs::create_dir_all("fixtures/canonical").expect("mkdir");
    std::fs::create_dir_all("fixtures/blender").expect("mkdir");
    for frame in 1..=3 {
        let p = render(frame as f32);
        let [r, g, b, a] = p.rgba;
        write(
            &format!("fixtures/canonical/color.{frame:04}.exr"),
            vec![("R", r), ("G", g), ("B", b), ("A", a)],
            false,
        );
        write(
            &format!("fixtures/canonical/depth.{frame:04}.exr"),
            vec![("Z", p.z)],
            true,
        );
        let [vx, vy] = p.velocity;
        write(
            &format!("fixtures/canonical/velocity.{frame:04}.exr"),
            vec![("X", vx), ("Y", vy)],
            false,
        );
        let [px, py] = p.prev;
        write(
            &format!("fixtures/canonical/prev.{frame:04}.exr"),
            vec![("X", px), ("Y", py)],
            false,
        );
        let [nx, ny] = p.next;
        write(
            &format!("fixtures/canonical/next.{frame:04}.exr"),
            vec![("X", nx), ("Y", ny)],
            false,
        );
    }

    // Blender: Vector X,Y = p(-1) - p(0), Z,W = p(0) - p(+1), y up.
    let p = render(2.0);
    let n = W * H;
    let (mut vx, mut vy, mut vz, mut vw) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for k in 0..n {
        let (x, y) = ((k % W) as f32 + 0.5, (k / W) as f32 + 0.5);
        vx[k] = p.prev[0][k] - x;
        vy[k] = -(p.prev[1][k] - y);
        vz[k] = x - p.next[0][k];
        vw[k] = -(y - p.next[1][k]);
    }
    let [r, g, b, a] = p.rgba;
    write(
        "fixtures/blender/shot.0001.exr",
        vec![
            ("ViewLayer.Combined.R", r),
            ("ViewLayer.Combined.G", g),
            ("ViewLayer.Combined.B", b),
            ("ViewLayer.Combined.A", a),
            ("ViewLayer.Depth.Z", p.z),
            ("ViewLayer.Vector.X", vx),
            ("ViewLayer.Vector.Y", vy),
            ("ViewLayer.Vector.Z", vz),
            ("ViewLayer.Vector.W", vw),
        ],
        false,
    );
}
