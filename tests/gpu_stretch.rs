//! stretch on the GPU (src/gpu/motion/stretch.wgsl: texture_blur, move_vertices, rasterise as a
//! render pipeline) against the CPU reference (src/motion/stretch.rs), both anchors, with and
//! without the texture pre-blur, with shutter offsets, on generated frames (a near square
//! over a far moving background, noise over two depth layers so silhouettes are everywhere)
//! and stress frames (NaN, ±∞, huge and tiny velocity and depth, depth 0, through the numeric
//! policy as a run applies it), on the golden scene, and through the CLI. Skips as
//! tests/gpu.rs says without an adapter (a failure under `SHUTTER_REQUIRE_GPU=1`).

#![cfg(feature = "gpu")]

use std::io::Write;

use shutter::frame::{Color, Frame, Velocity};
use shutter::motion::stretch::{stretch, stretch_with, Stages, StretchConfig};
use shutter::motion::{Anchor, Shutter, StretchParams};
use shutter::numeric::{sanitize, DepthKind};

use crate::gpu::with_gpu::gpu;
use crate::support::*;

/// What the GPU may differ by, relative to the range of the CPU's output channel.
///
/// The GPU decides coverage and barycentric weights with the CPU's edge functions and tie
/// rule (src/gpu/motion/stretch.rs), draws in the CPU's order and blends in primitive order, so a
/// pixel gets the same fragments in the same order on both sides and they differ by rounding:
/// the edge functions in f32 on corners relative to the pixel centre against f64 on absolute
/// positions, `src·α + dst·(1 − α)` against `dst + α·(src − dst)` per layer, WGSL's `sqrt`
/// and division (a few ulp) in the vertex moves and the pre-blur, and a driver's fused
/// multiply-adds. Over a few dozen blended layers that is ~1e-5 of the range at the very
/// worst; [`AGREE`] is ten times that. Where the frame is not wholly covered (alpha below 1,
/// as in most pixels of the noise and stress frames) cover averages along a motion
/// interpolated between the corners: the weights' last bits times that motion (cut to move
/// at most 128 px, 256 px a frame under a half shutter) move its samples by ~1e-5 px.
///
/// A pixel differs by more where one of those roundings moves a decision: a pixel centre
/// within ~1e-6 px of a moved edge (inside in f64, outside in f32), a vertex's `moving` test
/// (|v|·φ ≥ ½) or a pre-blur sample on a pixel boundary (`floor` of a fused or unfused
/// `x + v·t`, which gives a neighbour a weight of an ulp: with the stress frames' 1e30
/// colours, 1e23 at that pixel, still an ulp of the range). A flipped fragment moves a pixel
/// by its alpha times the colour step, up to the whole range, so [`MAX`] is the range; what
/// bounds flips is their rarity: [`FLIPS`] bounds their share and [`MEAN`] the mean over all
/// pixels, flips included.
///
/// Measured on lavapipe (Mesa 22.3, LLVM 15) over every frame, variant and offset here: max
/// 2.8e-5 (the fast square), mean ≤ 2.5e-7, no pixel outside [`AGREE`]; with cover, max
/// 6.4e-5 (a stress frame, rear anchor, half shutter), mean ≤ 1.1e-7, none outside. (Before
/// its motion was cut, one pixel of a stress frame, beside a 1e7 px velocity, was 0.029 of
/// the range off, and its mean over the frame 1.25e-5.) (Drawing the
/// triangles with the fixed-function rasteriser's coverage instead, 1–24 % of pixels were
/// outside; src/gpu/motion/stretch.rs says why.) A shader that drops the depth test, the tear or the
/// anchor fails these bounds
/// ([`stretch_parity_fails_without_the_depth_test_the_tear_or_the_anchor`]).
pub(crate) const AGREE: f32 = 1e-4;
/// The share of pixels allowed outside [`AGREE`].
pub(crate) const FLIPS: f64 = 0.001;
/// The mean absolute difference, relative to the range.
pub(crate) const MEAN: f64 = 1e-5;
/// The four above as one bound (agree, max, share outside, mean), for parity tests elsewhere.
pub(crate) const BOUND: (f32, f32, f64, f64) = (AGREE, MAX, FLIPS, MEAN);
/// The largest difference at any pixel: a flipped fragment can move a pixel across the range.
pub(crate) const MAX: f32 = 1.0;

impl Parity {
    fn within(&self) -> bool {
        self.max <= MAX && self.mean <= MEAN && self.outside <= FLIPS
    }
}

/// This file's [`parity_within`]: pixels outside [`AGREE`] counted.
fn parity(got: &[f32], cpu: &[f32]) -> Parity {
    parity_within(got, cpu, AGREE)
}

/// The worst parity over the channels of two colours.
fn parity_of(got: &Color, cpu: &Color) -> Parity {
    let mut worst = Parity::default();
    let channels = [(&got.r, &cpu.r), (&got.g, &cpu.g), (&got.b, &cpu.b)];
    for (g, c) in channels
        .into_iter()
        .chain(got.a.as_ref().zip(cpu.a.as_ref()))
    {
        worst = worst.worse(parity(g, c));
    }
    worst
}

/// stretch's stages on the GPU, which must run them (no fallback to the CPU stages).
struct StagesOnGpu<'a>(&'a shutter::gpu::Gpu);

impl Stages for StagesOnGpu<'_> {
    fn stages(
        &self,
        config: &StretchConfig,
        planes: &[Vec<f32>; 4],
        z: &[f32],
        v: &[[f32; 2]],
    ) -> [Vec<f32>; 4] {
        self.0
            .try_stretch(config, planes, z, v)
            .expect("the GPU stages run")
    }
}

/// stretch with its stages on the GPU, which must run them (no fallback).
fn on_gpu(frame: &Frame, params: &StretchParams, shutter: Shutter) -> Option<Color> {
    let gpu = gpu()?;
    let out = stretch_with(frame.clone(), params, shutter, &StagesOnGpu(gpu));
    Some(out.color.unwrap())
}

/// Runs stretch on the CPU and on the GPU, checks the tolerance on every channel and that a
/// second GPU run gives the same bits; prints the worst (max, mean, outside) seen.
fn compare(what: &str, frame: &Frame, params: &StretchParams, shutter: Shutter) -> Option<Parity> {
    let got = on_gpu(frame, params, shutter)?;
    let again = on_gpu(frame, params, shutter)?;
    let cpu = stretch(frame.clone(), params, shutter).color.unwrap();
    let bits = |c: &Color| -> Vec<u32> {
        [&c.r, &c.g, &c.b]
            .into_iter()
            .chain(c.a.as_ref())
            .flat_map(|p| p.iter().map(|v| v.to_bits()))
            .collect()
    };
    assert!(
        bits(&got) == bits(&again),
        "{what}, {params:?}: two GPU runs differ"
    );
    let p = parity_of(&got, &cpu);
    for (k, (g, c)) in got.planes().iter().zip(cpu.planes()).enumerate() {
        crate::support::diag_pixels(
            &format!("stretch {what} {:?} {k}", params.anchor),
            frame,
            g,
            c,
            AGREE,
        );
    }
    let at = (p.worst % frame.width, p.worst / frame.width);
    let _ = writeln!(
        std::io::stderr(),
        "gpu: stretch {what} {:?} blur {} shutter {}/{}: max {:e} at {at:?} mean {:e} outside \
         {:.3}%",
        params.anchor,
        params.texture_blur,
        shutter.open,
        shutter.offset,
        p.max,
        p.mean,
        p.outside * 100.0
    );
    assert!(
        p.within(),
        "{what}, {params:?}, {shutter:?}: max {:e} at {at:?}, mean {:e}, {:.4}% outside {AGREE:e}",
        p.max,
        p.mean,
        p.outside * 100.0
    );
    Some(p)
}

/// The variants compared: both anchors, with and without the pre-blur, and the other
/// parameters off their defaults (tests/stretch.rs's set).
fn variants() -> Vec<StretchParams> {
    let default = StretchParams::default();
    vec![
        default,
        StretchParams {
            anchor: Anchor::Rear,
            ..default
        },
        StretchParams {
            anchor: Anchor::Rear,
            texture_blur: false,
            extent: 40.0,
            ..default
        },
        StretchParams {
            texture_blur: false,
            ..default
        },
        StretchParams {
            min_alpha: 0.5,
            tear: 0.0,
            depth_tolerance: 0.0,
            ..default
        },
    ]
}

fn centred(open: f32) -> Shutter {
    Shutter { open, offset: 0.0 }
}

/// A frame of `w`×`h` with the given planes; colour RGBA.
fn frame(w: usize, h: usize, color: [Vec<f32>; 4], depth: Vec<f32>, v: [Vec<f32>; 2]) -> Frame {
    let mut f = Frame::new(w, h);
    let [r, g, b, a] = color;
    f.color = Some(Color {
        r,
        g,
        b,
        a: Some(a),
    });
    f.depth = Some(depth);
    let [x, y] = v;
    f.velocity = Some(Velocity { x, y });
    f
}

/// A near textured square moving down-right over a far background of stripes moving left:
/// silhouettes on every side, torn from the background, smears drawn over it, and a still
/// nearer bar a pixel ahead of the square's right side that its smear must stay behind (the
/// depth test).
fn square(w: usize, h: usize, speed: f32) -> Frame {
    let n = w * h;
    let mut color = [vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![1.0; n]];
    let mut depth = vec![20.0; n];
    let mut v = [vec![-0.3 * speed; n], vec![0.0; n]];
    let (x0, y0, side) = (w / 4, h / 4, h / 3);
    for i in 0..n {
        let (x, y) = (i % w, i / w);
        let on = (x / 4) % 2 == 0;
        color[0][i] = if on { 2.0 } else { 0.1 };
        color[1][i] = 0.3 + 0.5 * (y as f32 / h as f32);
        color[2][i] = 0.2;
        if (x0..x0 + side).contains(&x) && (y0..y0 + side).contains(&y) {
            color[0][i] = 0.2 + (x - x0) as f32 / side as f32;
            color[1][i] = 1.5;
            color[2][i] = if (x + y) % 3 == 0 { 3.0 } else { 0.5 };
            color[3][i] = 0.8;
            depth[i] = 5.0 + 0.01 * (x as f32);
            v[0][i] = 0.8 * speed;
            v[1][i] = 0.6 * speed;
        }
        if (x0 + side + 1..x0 + side + 5).contains(&x) && y >= y0 {
            color[0][i] = 0.0;
            color[1][i] = 0.0;
            color[2][i] = 4.0;
            depth[i] = 1.0;
            v[0][i] = 0.0;
        }
    }
    frame(w, h, color, depth, v)
}

/// Noise colour over two depth layers (silhouettes everywhere) with random motion up to
/// `speed` px a frame (tests/stretch.rs's frame).
fn noisy(w: usize, h: usize, seed: u32, speed: f32) -> Frame {
    let n = w * h;
    let mut f = noise_frame(w, h, seed);
    f.velocity = Some(Velocity {
        x: noise(n, seed + 5, -speed, speed),
        y: noise(n, seed + 6, -speed, speed),
    });
    f
}

/// [`noisy`] poisoned with NaN, ±∞, huge, tiny, subnormal and zero values in colour, depth
/// and velocity (huge velocities hit the 128-px cut of a vertex's move; depth 0 tears the
/// mesh around it), then put through the numeric policy as a run does before any pass.
fn stress(w: usize, h: usize, seed: u32) -> Frame {
    let mut f = noisy(w, h, seed, 25.0);
    let n = w * h;
    let values = [
        f32::NAN,
        f32::INFINITY,
        f32::NEG_INFINITY,
        1e38,
        -1e38,
        1e30,
        1e-30,
        1e-40,
        0.0,
        -0.0,
    ];
    let c = f.color.as_mut().unwrap();
    for (k, &value) in values.iter().cycle().take(n / 5).enumerate() {
        let i = (k * 5 + 1) % n;
        [&mut c.r, &mut c.g, &mut c.b][k % 3][i] = value;
        f.depth.as_mut().unwrap()[(k * 7 + 2) % n] = value;
        let v = f.velocity.as_mut().unwrap();
        v.x[(k * 11 + 3) % n] = value;
        v.y[(k * 13 + 4) % n] = value;
    }
    sanitize(&mut f, DepthKind::Depth);
    f
}

#[test]
fn stretch_matches_the_cpu_on_a_square_over_a_moving_background() {
    for params in variants() {
        compare("square", &square(80, 60, 12.0), &params, centred(0.5));
        compare("square fast", &square(97, 71, 60.0), &params, centred(1.0));
    }
}

#[test]
fn stretch_matches_the_cpu_on_noise_over_two_layers() {
    for params in variants() {
        compare("noise", &noisy(57, 43, 3, 15.0), &params, centred(0.75));
    }
}

#[test]
fn stretch_matches_the_cpu_with_the_shutter_offset() {
    // Centre follows the offset exposure; rear stays the rear curtain whatever the offset.
    for params in variants() {
        for offset in [0.5, -0.5, 0.2] {
            let shutter = Shutter { open: 0.5, offset };
            compare("square offset", &square(80, 60, 12.0), &params, shutter);
            let shutter = Shutter { open: 1.0, offset };
            compare("noise offset", &noisy(53, 41, 7, 20.0), &params, shutter);
        }
    }
}

#[test]
fn stretch_matches_the_cpu_on_stress_frames() {
    for params in variants() {
        compare("stress", &stress(50, 40, 9), &params, centred(0.5));
        compare("stress", &stress(33, 70, 10), &params, centred(1.0));
    }
}

#[test]
fn stretch_matches_the_cpu_without_alpha_and_on_thin_frames() {
    let mut f = square(45, 29, 9.0);
    f.color.as_mut().unwrap().a = None;
    for params in variants() {
        compare("square without alpha", &f, &params, centred(0.5));
        // One row and one column: no triangles, the pre-blur alone.
        compare("one row", &noisy(40, 1, 2, 10.0), &params, centred(0.5));
        compare("one column", &noisy(1, 30, 2, 10.0), &params, centred(0.5));
    }
}

/// The golden scene (tests/golden.rs: rotor at 96×54, default settings) on the GPU against
/// its golden image, within the tolerance above.
#[test]
fn stretch_on_the_gpu_matches_the_golden_image() {
    let Some(gpu) = gpu() else { return };
    let mut passes = crate::golden::scene_passes("rotor");
    sanitize(&mut passes, DepthKind::Depth);
    let got = stretch_with(passes, &StretchParams::default(), centred(0.5), gpu);
    assert_eq!(gpu.stages_on_cpu(), 0, "the GPU stages ran");
    let golden = read_exr_reference(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/golden/stretch.exr"),
    );
    let color = got.color.unwrap();
    let mut worst = Parity::default();
    for (plane, name) in [&color.r, &color.g, &color.b, color.a.as_ref().unwrap()]
        .into_iter()
        .zip(["R", "G", "B", "A"])
    {
        let p = parity(plane, channel(&golden, name));
        worst = worst.worse(p);
        assert!(p.within(), "{name}: {p:?}");
    }
    worst.report("stretch golden rotor");
}

/// The tolerance is not vacuous: the GPU's output fails it against a CPU run without the
/// depth test (a huge tolerance), without the tear (a huge tear ratio), and with the other
/// anchor — what a shader that dropped one of them would give.
#[test]
fn stretch_parity_fails_without_the_depth_test_the_tear_or_the_anchor() {
    let f = square(80, 60, 12.0);
    // Nearly opaque smears, so what they cover shows.
    let default = StretchParams {
        extent: 40.0,
        ..StretchParams::default()
    };
    let Some(got) = on_gpu(&f, &default, centred(0.5)) else {
        return;
    };
    for (what, other) in [
        (
            "no depth test",
            StretchParams {
                depth_tolerance: 1e9,
                ..default
            },
        ),
        (
            "no tear",
            StretchParams {
                tear: 1e9,
                ..default
            },
        ),
        (
            "rear anchor",
            StretchParams {
                anchor: Anchor::Rear,
                ..default
            },
        ),
    ] {
        let cpu = stretch(f.clone(), &other, centred(0.5)).color.unwrap();
        let p = parity_of(&got, &cpu);
        assert!(!p.within(), "{what} passes: {p:?}");
    }
}

/// `blur --algorithm stretch --backend wgpu` writes the CPU's output within the tolerance
/// above, with every stage on the GPU, and that output is blurred (not the input copied).
#[test]
fn blur_stretch_on_wgpu_equals_the_cpu_within_the_tolerance() {
    if gpu().is_none() {
        return;
    }
    let dir = small_scene("rotor", 96, 54, 1, 4);
    let (color, depth, velocity) = (
        role_pattern(dir.path(), "color"),
        role_pattern(dir.path(), "depth"),
        role_pattern(dir.path(), "velocity"),
    );
    let args = [
        "--algorithm",
        "stretch",
        "--color",
        &color,
        "--depth",
        &depth,
        "--velocity",
        &velocity,
    ];
    let mut outputs = Vec::new();
    for backend in ["cpu", "wgpu"] {
        let (json, frame) = blur_on(dir.path(), &args, backend, backend, None);
        if backend == "wgpu" {
            assert_eq!(json["backend"]["stages_on_cpu"], 0, "{json}");
        }
        outputs.push(read_exr_reference(&frame));
    }
    let input = read_exr_reference(&dir.path().join("color.0001.exr"));
    for name in ["R", "G", "B"] {
        let (cpu, got) = (channel(&outputs[0], name), channel(&outputs[1], name));
        assert_ne!(cpu, channel(&input, name), "{name}: nothing was blurred");
        let p = parity(got, cpu);
        assert!(p.within(), "{name}: {p:?}");
    }
}

/// `blur --algorithm stretch --backend wgpu` writes the same bytes with one and two threads
/// (the host's share — the keys' sort, the planes' unpacking — is a total order or
/// per-pixel, and the GPU blends in primitive order), for both anchors.
#[test]
fn stretch_on_wgpu_is_identical_for_one_and_two_threads() {
    if gpu().is_none() {
        return;
    }
    for anchor in ["centre", "rear"] {
        crate::support::invariants::same_bytes_for_any_thread_count(
            "stretch",
            "crossing",
            &["color", "depth", "velocity"],
            &["--backend", "wgpu", "--anchor", anchor],
        );
    }
}

/// A frame too large for the device's storage bindings (made so by lowering the limit to
/// 4 KiB with SHUTTER_GPU_MAX_BINDING) runs stretch's stages on the CPU: the CPU's bytes,
/// counted in the summary and said in a warning with the reason.
#[test]
fn stretch_over_the_device_s_limits_runs_on_the_cpu_and_says_so() {
    if gpu().is_none() {
        return;
    }
    let dir = small_scene("rotor", 96, 54, 1, 1);
    let mut bytes = Vec::new();
    for (backend, limit) in [("cpu", None), ("wgpu", Some("4096"))] {
        let out = s(&dir.path().join(format!("{backend}.####.exr")));
        let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_shutter"));
        command.args([
            "blur",
            "--algorithm",
            "stretch",
            "--color",
            &role_pattern(dir.path(), "color"),
            "--depth",
            &role_pattern(dir.path(), "depth"),
            "--velocity",
            &role_pattern(dir.path(), "velocity"),
            "-o",
            &out,
            "--backend",
            backend,
            "--json",
        ]);
        if let Some(limit) = limit {
            command.env("SHUTTER_GPU_MAX_BINDING", limit);
        }
        let o = command.output().unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        if backend == "wgpu" {
            assert!(
                json["backend"]["stages_on_cpu"].as_u64().unwrap() >= 1,
                "{json}"
            );
            let warnings = json["warnings"].to_string();
            assert!(
                warnings.contains("fell back to the CPU") && warnings.contains("exceeds"),
                "{json}"
            );
        }
        bytes.push(std::fs::read(dir.path().join(format!("{backend}.0001.exr"))).unwrap());
    }
    assert!(
        bytes[0] == bytes[1],
        "the fallback wrote other bytes than the CPU"
    );
}

/// The cost of the pass on the GPU at 960×540 (a square over a moving background, the
/// defaults), printed beside the CPU's (benchmarks measure, tests assert).
#[test]
fn stretch_at_540p_prints_its_time() {
    let Some(gpu) = gpu() else { return };
    let f = square(960, 540, 24.0);
    let params = StretchParams::default();
    // Compiled and buffers made here.
    let _ = stretch_with(f.clone(), &params, centred(0.5), gpu);
    let start = std::time::Instant::now();
    let got = stretch_with(f.clone(), &params, centred(0.5), gpu);
    let seconds = start.elapsed().as_secs_f64();
    let start = std::time::Instant::now();
    let cpu = stretch(f, &params, centred(0.5));
    let cpu_seconds = start.elapsed().as_secs_f64();
    let p = parity_of(&got.color.unwrap(), &cpu.color.unwrap());
    let _ = writeln!(
        std::io::stderr(),
        "gpu: stretch 960x540 square, every stage on the GPU (upload, dispatch, draw, \
         readback) {:.1} ms (cpu {:.1} ms); max {:e} mean {:e} outside {:.3}%",
        seconds * 1e3,
        cpu_seconds * 1e3,
        p.max,
        p.mean,
        p.outside * 100.0
    );
    assert!(p.within(), "{p:?}");
}
