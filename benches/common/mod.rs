//! What the processing benches share: the synthetic 1920×1080 velocity frames and the
//! median timer.

#![allow(dead_code)] // each bench uses its part

use std::time::Instant;

use shutter::frame::{CarriedChannel, Color, Frame, LayerClass, Positions, Velocity};
use shutter::motion::Algorithm;
use shutter::numeric;
use shutter::process::{self, process_clean, Params};

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

/// The same checker, gradients and depths with prev/next positions instead of velocity (the
/// scatter bench's frame): `moving(x, y)` gives (velocity, bend) in px per frame, p(t) = p0 +
/// t·v + t²·a.
pub fn positions_frame(moving: impl Fn(usize, usize) -> Option<([f32; 2], [f32; 2])>) -> Frame {
    let n = W * H;
    let mut f = Frame::new(W, H);
    let mut c = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
    let mut depth = vec![0.0; n];
    let mut prev = Positions {
        x: vec![0.0; n],
        y: vec![0.0; n],
        z: None,
    };
    let mut next = prev.clone();
    for y in 0..H {
        for x in 0..W {
            let i = y * W + x;
            c[0][i] = ((x / 16 + y / 16) % 2) as f32;
            c[1][i] = x as f32 / W as f32;
            c[2][i] = y as f32 / H as f32;
            depth[i] = if (x / 200 + y / 150) % 3 == 0 {
                2.0
            } else {
                10.0
            };
            let (v, a) = moving(x, y).unwrap_or(([0.0; 2], [0.0; 2]));
            let p0 = [x as f32 + 0.5, y as f32 + 0.5];
            prev.x[i] = p0[0] - v[0] + a[0];
            prev.y[i] = p0[1] - v[1] + a[1];
            next.x[i] = p0[0] + v[0] + a[0];
            next.y[i] = p0[1] + v[1] + a[1];
        }
    }
    let [r, g, b] = c;
    f.color = Some(Color {
        r,
        g,
        b,
        a: Some(vec![1.0; n]),
    });
    f.depth = Some(depth);
    f.prev = Some(prev);
    f.next = Some(next);
    f
}

/// The "every pixel moving" field of the reconstruct and stretch benches: 10–40 px per frame
/// in directions that rotate across the frame.
pub fn rotating(x: usize, y: usize) -> Option<(f32, f32)> {
    let a = (x as f32 * 0.002) + (y as f32 * 0.003);
    let speed = 10.0 + 30.0 * ((x + y) % 97) as f32 / 96.0;
    Some((a.cos() * speed, a.sin() * speed))
}

/// The scatter bench's motion: 30 px per frame along the same rotating directions, bent by
/// 3 px (velocity, bend) for [`positions_frame`].
pub fn curving(x: usize, y: usize) -> Option<([f32; 2], [f32; 2])> {
    let a = (x as f32 * 0.002) + (y as f32 * 0.003);
    let (c, s) = (a.cos(), a.sin());
    Some(([30.0 * c, 30.0 * s], [-3.0 * s, 3.0 * c]))
}

/// The depth-of-field bench's frame: the checker in blocks at 1.5 m, 3 m, 6 m and infinity,
/// no motion passes.
pub fn lens_frame() -> Frame {
    let mut f = frame(|_, _| None);
    f.velocity = None;
    let depths = [1.5f32, 3.0, 6.0, f32::INFINITY];
    f.depth = Some(
        (0..W * H)
            .map(|i| depths[(i % W / 200 + i / W / 150) % 4])
            .collect(),
    );
    f
}

/// The light layers of issue 29's cost bound: `f` with six RGB layers beside its beauty
/// (`diffuse`, `specular`, `emission`, `sss`, `transmission`, `volume`), each the beauty's
/// colour scaled by its own factor per channel, as a renderer's EXR brings them: colour
/// channels blurred with the beauty's weights.
pub fn with_light_layers(f: &Frame) -> Frame {
    let mut out = f.clone();
    let color = f.color.as_ref().expect("a beauty");
    let names = [
        "diffuse",
        "specular",
        "emission",
        "sss",
        "transmission",
        "volume",
    ];
    for (l, layer) in names.iter().enumerate() {
        for (c, (channel, plane)) in [("R", &color.r), ("G", &color.g), ("B", &color.b)]
            .into_iter()
            .enumerate()
        {
            let scale = 0.2 + 0.1 * l as f32 + 0.05 * c as f32;
            let name = format!("{layer}.{channel}");
            out.carried.channels.push(CarriedChannel {
                name: name.clone(),
                stored: name,
                shared: false,
                part: 0,
                class: LayerClass::Colour,
                plane: plane.iter().map(|v| v * scale).collect(),
                exact: None,
                window: None,
            });
        }
    }
    out
}

/// One row of issue 29's cost bound: `label`'s time on the beauty alone and with the six
/// light layers of [`with_light_layers`], and their ratio (at most 1.5× asked). The beauty is
/// timed again here rather than taken from an earlier row, so that both times come from the
/// same minutes of a host whose speed drifts by a quarter or more.
pub fn light_layers_row(label: &str, algorithm: Algorithm, f: &Frame, params: &Params) {
    let beauty = median_ms(algorithm, f, params, 5);
    let layered = median_ms(algorithm, &with_light_layers(f), params, 5);
    println!(
        "1920x1080 {label}, six RGB light layers: {layered:.1} ms against the beauty's \
         {beauty:.1} ms ({:.2}x)",
        layered / beauty
    );
}

/// Median processing time (ms) of `runs` runs of `algorithm` on `f`, after a warm-up run:
/// the pipeline's processing stage. The numeric policy's scan runs in the read stage; it is
/// timed on its own by [`median_policy_ms`].
pub fn median_ms(algorithm: Algorithm, f: &Frame, params: &Params, runs: usize) -> f64 {
    let mut clean = f.clone();
    let _ = numeric::sanitize(&mut clean, process::depth_kind(params));
    let _ = process_clean(algorithm, params, clean.clone(), 1);
    median(runs, || {
        let input = clean.clone();
        let t = Instant::now();
        let out = process_clean(algorithm, params, input, 1);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        drop(out);
        ms
    })
}

/// The GPU context for the benches' GPU rows: any adapter, a software driver included (its
/// figures are for the record, not for speed); `None` without one, or in a build without the
/// `gpu` feature.
#[allow(dead_code)]
pub fn gpu() -> Option<shutter::gpu::Gpu> {
    shutter::gpu::open(shutter::gpu::Backend::Wgpu)
        .ok()
        .and_then(|(gpu, _)| gpu)
}

/// [`median_ms`] with the stages that have a GPU twin on `gpu`, and the GPU stages' upload,
/// dispatch and readback per run (timed apart: [`shutter::gpu::Gpu::set_profiling`]).
#[allow(dead_code)]
pub fn median_ms_on(
    gpu: &shutter::gpu::Gpu,
    algorithm: Algorithm,
    f: &Frame,
    params: &Params,
    runs: usize,
) -> (f64, shutter::gpu::GpuTimes) {
    let mut clean = f.clone();
    let _ = numeric::sanitize(&mut clean, process::depth_kind(params));
    let _ = process::process_on(algorithm, params, clean.clone(), 1, Some(gpu));
    gpu.take_times();
    gpu.set_profiling(true);
    let ms = median(runs, || {
        let input = clean.clone();
        let t = Instant::now();
        let out = process::process_on(algorithm, params, input, 1, Some(gpu));
        let ms = t.elapsed().as_secs_f64() * 1e3;
        drop(out);
        ms
    });
    gpu.set_profiling(false);
    (ms, gpu.take_times().per_run(runs))
}

/// Median time (ms) of the numeric policy's scan of `f` (the read stage's share).
pub fn median_policy_ms(f: &Frame, runs: usize) -> f64 {
    median(runs, || {
        let mut input = f.clone();
        let t = Instant::now();
        let replaced = numeric::sanitize(&mut input, numeric::DepthKind::Depth);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        assert!(!replaced.any());
        ms
    })
}

fn median(runs: usize, mut time: impl FnMut() -> f64) -> f64 {
    let mut times: Vec<f64> = (0..runs).map(|_| time()).collect();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}

/// Which rows a bench runs: those whose label contains a word given after `--` (`cargo bench
/// --bench reconstruct -- "light layers"`), every row when none is (`cargo bench` passes
/// `--bench`, which is not a word).
#[allow(dead_code)]
pub fn chosen_rows() -> impl Fn(&str) -> bool {
    let words: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    move |label: &str| words.is_empty() || words.iter().any(|w| label.contains(w.as_str()))
}

/// The sparse rows: one moving square covering 1 %, 5 % and 25 % of a 1080p frame, each
/// timed by `time`.
#[allow(dead_code)]
pub fn sparse_rows(time: impl Fn(&Frame) -> f64) {
    for share in [0.01f32, 0.05, 0.25] {
        let side = ((W * H) as f32 * share).sqrt() as usize;
        let sparse = frame(|x, y| (x < side && y < side).then_some((24.0, 8.0)));
        println!(
            "1920x1080 sparse, a {side}x{side} square moving ({:.0}% of pixels): {:.1} ms",
            share * 100.0,
            time(&sparse)
        );
    }
}

/// Prints a GPU row: `label`'s median time on `gpu` and its GPU stages' upload, compute and
/// readback per run ([`median_ms_on`]'s).
#[allow(dead_code)]
pub fn print_gpu_row(label: &str, gpu: &shutter::gpu::Gpu, (ms, t): (f64, shutter::gpu::GpuTimes)) {
    println!(
        "1920x1080 {label} [wgpu on {}]: {ms:.1} ms (GPU stages per run: upload {:.1} ms, \
         compute {:.1} ms, readback {:.1} ms)",
        gpu.adapter(),
        t.upload_ms,
        t.compute_ms,
        t.readback_ms
    );
}
