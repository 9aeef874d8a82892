//! reconstruct's `gather` on the GPU (src/gpu/motion/reconstruct.wgsl) against the CPU reference
//! (src/motion/reconstruct/), every variant, on generated frames: moving stripes and edges,
//! a still subject over a moving background, noise with random motion, and stress frames
//! (NaN, ±∞, huge and tiny velocity and depth, through the numeric policy as a run applies
//! it); and `blur --backend wgpu` through the CLI. Skips as tests/gpu.rs says without an
//! adapter (a failure under `SHUTTER_REQUIRE_GPU=1`).

#![cfg(feature = "gpu")]

use std::io::Write;

use shutter::frame::{Color, Frame, Velocity};
use shutter::gpu::Gpu;
use shutter::motion::reconstruct::classify::{classify, TileKind};
use shutter::motion::reconstruct::matte::Matte;
use shutter::motion::reconstruct::{
    reconstruct, reconstruct_layers_with, reconstruct_with, GatherInputs, ReconstructConfig,
    Stages, Texel2014, TileMask,
};
use shutter::motion::tile_max::TileGrid;
use shutter::motion::{ReconstructParams, Shutter, Variant};
use shutter::numeric::{sanitize, DepthKind};
use shutter::stages::Cpu;

use crate::gpu::with_gpu::gpu;
use crate::support::*;

/// What the GPU may differ by, relative to the range of the CPU's output channel.
///
/// Both sides compute in f32 with the same operations in the same order, so a pixel whose
/// taps land on the same texels with the same classification agrees to rounding: WGSL
/// allows `sqrt` and division a few ulp and a driver may fuse a multiply and an add, and the
/// output is a normalised sum of up to ~260 weighted taps, each term rounded: a few hundred
/// ulp of the range at the very worst, ~1e-5 of it. [`AGREE`] is ten times that.
///
/// A pixel differs by more where one of those roundings moves a decision: a tap position on
/// a pixel boundary (`u32(x + 0.5 + d·t)` with d·t fused or not) reads the neighbouring
/// texel, or a depth difference on the soft-z threshold flips a weight. A flipped tap moves
/// the output by its weight over the tap count times the colour step: at most a sixth of
/// the range with the fewest taps compared here (S = 9: three per side, six counted), which
/// [`MAX`] allows. (A tile lookup shifted across a tile boundary would change a whole
/// gather; it needs `x + shift` within an ulp of a multiple of the tile size.) Flips need a
/// value within an ulp of a boundary, so they are rare: [`FLIPS`] bounds their share, and
/// the mean over all pixels, flips included, stays within [`MEAN`].
///
/// Measured on lavapipe (Mesa 22.3, LLVM 15) over every frame and variant here: max 1.5e-5
/// (a stress frame, paper variant), mean ≤ 6e-8, no pixel outside [`AGREE`]; the jitter-free
/// variants and the 2014 filter mostly agree bit for bit.
pub(crate) const AGREE: f32 = 1e-4;
/// The largest difference at any pixel.
pub(crate) const MAX: f32 = 0.25;
/// The share of pixels allowed outside [`AGREE`].
pub(crate) const FLIPS: f64 = 0.002;
/// The mean absolute difference, relative to the range.
pub(crate) const MEAN: f64 = 1e-5;
/// The four above as one bound (agree, max, share outside, mean), for parity tests elsewhere.
pub(crate) const BOUND: (f32, f32, f64, f64) = (AGREE, MAX, FLIPS, MEAN);

/// This file's [`parity_within`]: pixels outside [`AGREE`] counted.
fn parity(got: &[f32], cpu: &[f32]) -> Parity {
    parity_within(got, cpu, AGREE)
}

/// reconstruct's stages with the gather on the GPU, which must run (no fallback to the CPU
/// stage), and every other stage on the CPU; `ran` says whether a gather ran.
pub(crate) struct GatherOnGpu<'a> {
    pub gpu: &'a Gpu,
    pub ran: std::cell::Cell<bool>,
}

impl<'a> GatherOnGpu<'a> {
    pub fn new(gpu: &'a Gpu) -> Self {
        GatherOnGpu {
            gpu,
            ran: std::cell::Cell::new(false),
        }
    }
}

impl Stages for GatherOnGpu<'_> {
    fn gather(&self, config: &ReconstructConfig, inputs: GatherInputs<'_>, color: &mut Color) {
        self.gpu
            .try_reconstruct_gather(config, &inputs, color)
            .expect("the GPU gather runs");
        self.ran.set(true);
    }
}

/// Runs reconstruct on the CPU and with the gather on the GPU (which must run: no fallback)
/// and checks the tolerance on every channel; prints the worst (max, mean, outside) seen.
fn compare(
    what: &str,
    frame: &Frame,
    params: &ReconstructParams,
    shutter: impl Into<Shutter> + Copy + std::fmt::Debug,
    seed: u32,
) {
    let Some(gpu) = gpu() else { return };
    let cpu = reconstruct(frame.clone(), params, shutter, seed);
    let on_gpu = GatherOnGpu::new(gpu);
    let got = reconstruct_with(frame.clone(), params, shutter, seed, &on_gpu);
    let ran = on_gpu.ran.get();
    let (cpu, got) = (cpu.color.unwrap(), got.color.unwrap());
    let channels = [
        ("R", &cpu.r, &got.r),
        ("G", &cpu.g, &got.g),
        ("B", &cpu.b, &got.b),
    ];
    let mut worst = (0.0f32, 0.0f64, 0.0f64);
    for (name, c, g) in channels
        .into_iter()
        .chain(cpu.a.as_ref().zip(got.a.as_ref()).map(|(c, g)| ("A", c, g)))
    {
        let p = parity(g, c);
        crate::support::diag_pixels(
            &format!("reconstruct {what} {:?} {name}", params.max_blur),
            frame,
            g,
            c,
            AGREE,
        );
        let at = (p.worst % frame.width, p.worst / frame.width);
        assert!(
            p.max <= MAX && p.mean <= MEAN && p.outside <= FLIPS,
            "{what}, {params:?}, shutter {shutter:?}, {name}: max {:e} at {at:?} (GPU {} CPU {}), \
             mean {:e}, {:.4}% outside {AGREE:e}",
            p.max,
            g[p.worst],
            c[p.worst],
            p.mean,
            p.outside * 100.0
        );
        worst = (
            worst.0.max(p.max),
            worst.1.max(p.mean),
            worst.2.max(p.outside),
        );
    }
    let _ = writeln!(
        std::io::stderr(),
        "gpu: reconstruct {what} {:?} taps {} k {} jitter {}: {} max {:e} mean {:e} outside {:.3}%",
        params.variant,
        params.taps,
        params.max_blur,
        params.jitter,
        if ran { "gathered" } else { "nothing moved" },
        worst.0,
        worst.1,
        worst.2 * 100.0
    );
}

/// The variants compared: every variant with the defaults, and with other taps, k and
/// jitter (sizes off the 8-px tiles of the 2014 filter and the paper's k).
fn variants() -> Vec<ReconstructParams> {
    let mut all = Vec::new();
    for variant in [
        Variant::Exposure,
        Variant::Stable,
        Variant::Paper,
        Variant::Dual,
    ] {
        all.push(ReconstructParams {
            variant,
            ..ReconstructParams::default()
        });
        all.push(ReconstructParams {
            variant,
            taps: 9,
            max_blur: 13,
            jitter: false,
            soft_z: 0.5,
        });
    }
    all
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

/// Vertical stripes 5 px wide moving right by `speed` px a frame, with a nearer square
/// moving down-left across them: edges in both directions and an occlusion boundary.
fn stripes(w: usize, h: usize, speed: f32) -> Frame {
    let n = w * h;
    let mut color = [vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![1.0; n]];
    let mut depth = vec![10.0; n];
    let mut v = [vec![speed; n], vec![0.0; n]];
    for i in 0..n {
        let (x, y) = (i % w, i / w);
        let on = (x / 5) % 2 == 0;
        color[0][i] = if on { 3.0 } else { 0.1 };
        color[1][i] = if on { 0.2 } else { 0.9 };
        color[2][i] = (x as f32) / w as f32;
        if (w / 3..w / 3 + 14).contains(&x) && (h / 4..h / 4 + 14).contains(&y) {
            color[0][i] = 0.5;
            color[1][i] = 0.5;
            color[2][i] = 2.0;
            color[3][i] = 0.75;
            depth[i] = 2.0;
            v[0][i] = -0.6 * speed;
            v[1][i] = 0.8 * speed;
        }
    }
    frame(w, h, color, depth, v)
}

/// A still disc in front of a background of noise moving diagonally.
fn still_subject(w: usize, h: usize, speed: f32) -> Frame {
    let n = w * h;
    let color = [
        noise(n, 3, 0.0, 4.0),
        noise(n, 4, 0.0, 1.0),
        noise(n, 5, -0.2, 1.0),
        vec![1.0; n],
    ];
    let mut depth = noise(n, 6, 20.0, 30.0);
    let mut v = [vec![speed; n], vec![0.5 * speed; n]];
    let (cx, cy, radius) = (w as f32 * 0.5, h as f32 * 0.5, h as f32 * 0.3);
    for i in 0..n {
        let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
        if (x - cx).hypot(y - cy) < radius {
            depth[i] = 3.0;
            v[0][i] = 0.0;
            v[1][i] = 0.0;
        }
    }
    frame(w, h, color, depth, v)
}

/// Noise colour over two depth layers with random motion up to `speed` px a frame.
fn noisy(w: usize, h: usize, seed: u32, speed: f32) -> Frame {
    let mut f = noise_frame(w, h, seed);
    f.velocity = Some(Velocity {
        x: noise(w * h, seed + 5, -speed, speed),
        y: noise(w * h, seed + 6, -speed, speed),
    });
    f
}

/// [`noisy`] poisoned with NaN, ±∞, huge, tiny and subnormal values in colour, depth and
/// velocity, then put through the numeric policy as a run does before any pass.
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
fn reconstruct_gather_matches_the_cpu_on_stripes_and_edges() {
    for params in variants() {
        compare("stripes", &stripes(61, 37, 9.0), &params, 0.5, 1);
        compare("stripes fast", &stripes(77, 45, 40.0), &params, 1.0, 2);
    }
}

/// Noise over two depths moving as one smooth flow: a pan (`zoom` 0) or a zoom about the
/// centre (`zoom` px a frame per px) on top of it. The exposure gather reads such tiles by
/// the box (src/motion/reconstruct/uniform.rs).
fn flow(w: usize, h: usize, pan: (f32, f32), zoom: f32) -> Frame {
    let mut f = noise_frame(w, h, 9);
    let (cx, cy) = (w as f32 / 2.0, h as f32 / 2.0);
    f.velocity = Some(Velocity {
        x: (0..w * h)
            .map(|i| pan.0 + zoom * ((i % w) as f32 - cx))
            .collect(),
        y: (0..w * h)
            .map(|i| pan.1 + zoom * ((i / w) as f32 - cy))
            .collect(),
    });
    f
}

#[test]
fn reconstruct_gather_matches_the_cpu_on_uniform_tiles() {
    for params in variants() {
        compare("pan", &flow(67, 41, (13.0, -5.0), 0.0), &params, 0.5, 4);
        compare("zoom", &flow(67, 41, (3.0, 2.0), 0.01), &params, 0.5, 5);
        for offset in [0.5, -0.3] {
            let shutter = Shutter { open: 0.5, offset };
            compare(
                "pan offset",
                &flow(67, 41, (0.0, 11.0), 0.0),
                &params,
                shutter,
                6,
            );
            compare(
                "zoom offset",
                &flow(67, 41, (-3.0, 2.0), 0.02),
                &params,
                shutter,
                7,
            );
        }
    }
}

#[test]
fn reconstruct_gather_matches_the_cpu_with_the_shutter_offset() {
    // Opening at the frame, closing at it, and between: the offset line of taps, each side's
    // share of it, and the dilation of scaled tiles (issue 19).
    for params in variants() {
        for offset in [0.5, -0.5, 0.2] {
            let shutter = Shutter { open: 0.5, offset };
            compare(
                "stripes offset",
                &stripes(61, 37, 9.0),
                &params,
                shutter,
                11,
            );
            let shutter = Shutter { open: 1.0, offset };
            compare(
                "still subject offset",
                &still_subject(70, 50, 12.0),
                &params,
                shutter,
                12,
            );
            compare(
                "noise offset",
                &noisy(53, 41, 7, 30.0),
                &params,
                shutter,
                13,
            );
        }
    }
}

#[test]
fn reconstruct_gather_matches_the_cpu_on_a_still_subject_over_motion() {
    for params in variants() {
        compare(
            "still subject",
            &still_subject(70, 50, 12.0),
            &params,
            0.5,
            3,
        );
    }
}

#[test]
fn reconstruct_gather_matches_the_cpu_on_noise_and_random_motion() {
    for params in variants() {
        compare("noise", &noisy(53, 41, 7, 30.0), &params, 0.75, 4);
    }
}

#[test]
fn reconstruct_gather_matches_the_cpu_on_stress_frames() {
    for params in variants() {
        compare("stress", &stress(50, 40, 9), &params, 0.5, 5);
        compare("stress", &stress(33, 70, 10), &params, 1.0, 6);
    }
}

/// reconstruct's stages with the classification run on both backends: the GPU's (which must
/// run, where one is given) must equal the CPU's tile for tile; `seen` counts the kinds
/// compared, and `kept` keeps each frame's kinds and tile columns.
struct ClassifyOnBoth<'a> {
    gpu: Option<&'a Gpu>,
    seen: std::cell::Cell<[usize; 4]>,
    kept: std::cell::RefCell<Vec<(usize, Vec<TileKind>)>>,
}

impl<'a> ClassifyOnBoth<'a> {
    fn new(gpu: Option<&'a Gpu>) -> Self {
        Self {
            gpu,
            seen: std::cell::Cell::new([0; 4]),
            kept: std::cell::RefCell::new(Vec::new()),
        }
    }
}

impl Stages for ClassifyOnBoth<'_> {
    fn classify(
        &self,
        config: &ReconstructConfig,
        texels: &[Texel2014],
        mattes: &[Matte],
        tiles: &TileGrid,
    ) -> Vec<TileKind> {
        let cpu = classify(config, texels, mattes, tiles);
        if let Some(gpu) = self.gpu {
            let got = gpu
                .try_classify(config, texels, mattes, tiles)
                .expect("the GPU's classification runs");
            for (t, (g, c)) in got.iter().zip(&cpu).enumerate() {
                assert_eq!(
                    g, c,
                    "tile {t} ({} columns), variant {}, offset {}",
                    tiles.columns, config.variant, config.offset
                );
            }
            assert_eq!(got.len(), cpu.len());
        }
        let mut seen = self.seen.get();
        for kind in &cpu {
            seen[*kind as usize] += 1;
        }
        self.seen.set(seen);
        self.kept.borrow_mut().push((tiles.columns, cpu.clone()));
        cpu
    }
}

/// Each frame through both 2014 variants under three shutter offsets, classified on both
/// backends ([`ClassifyOnBoth`]); how many tiles of each kind were compared.
fn classify_on_both(gpu: &Gpu, frames: &[Frame]) -> [usize; 4] {
    let both = ClassifyOnBoth::new(Some(gpu));
    for params in variants().into_iter().filter(|p| p.variant.is_2014()) {
        for frame in frames {
            for offset in [0.0, 0.5, -0.3] {
                let shutter = Shutter { open: 0.5, offset };
                reconstruct_with(frame.clone(), &params, shutter, 3, &both);
            }
        }
    }
    both.seen.get()
}

/// The classification's twin (src/gpu/motion/classify.wgsl) finds every tile's kind as the
/// CPU does (its tolerance: none, the kinds are decisions), on frames with every kind: a
/// pan and a zoom (uniform), a jump between two motions (plain beside it), a still subject,
/// edges, noise and stress frames (full), centred and under offset exposures, each variant
/// (the 2014 filter's tiles are all full).
#[test]
fn classify_on_the_gpu_finds_the_cpu_s_kinds() {
    let Some(gpu) = gpu() else { return };
    // Jumps between two motions and zooms, each at speeds and rates in steps, so that some
    // tile's reach or steepness lies close to where its kind changes.
    let jump = |speed: f32| {
        let mut f = flow(90, 50, (speed, 0.0), 0.0);
        let v = f.velocity.as_mut().unwrap();
        for i in 0..90 * 50 {
            v.x[i] = if i % 90 < 45 { speed } else { speed + 8.0 };
        }
        f
    };
    // A fast pan with one still pixel: the tiles whose plain reach holds it are full, and
    // that reach spans several tiles (a reach a tile shorter or longer moves kinds).
    let mut dot = flow(120, 64, (40.0, 3.0), 0.0);
    let v = dot.velocity.as_mut().unwrap();
    (v.x[30 * 120 + 70], v.y[30 * 120 + 70]) = (0.0, 0.0);
    let frames = [
        dot,
        flow(67, 41, (13.0, -5.0), 0.0),
        flow(67, 41, (3.0, 2.0), 0.01),
        flow(80, 45, (0.0, 9.0), 0.002),
        still_subject(70, 50, 12.0),
        stripes(61, 37, 9.0),
        noisy(53, 41, 7, 30.0),
        stress(50, 40, 9),
    ]
    .into_iter()
    .chain((8..24).map(|speed| jump(speed as f32)))
    .chain((1..16).map(|z| flow(72, 40, (6.0, 2.0), 0.01 * z as f32)))
    .collect::<Vec<_>>();
    let [full, plain, uniform, hollow] = classify_on_both(gpu, &frames);
    eprintln!(
        "classify: {full} full, {plain} plain, {uniform} uniform, {hollow} hollow tiles compared"
    );
    assert!(
        full > 0 && plain > 0 && uniform > 0 && hollow > 0,
        "every kind compared"
    );
}

/// `flow`'s frame as a view layer: outside the discs (centre, radius) empty (colour, alpha
/// and motion 0); a ring a pixel wide inside each rim a third covered (colour and alpha a
/// third, the body's motion), and in each disc the motion `flow` gives plus the disc's own.
fn layer(
    w: usize,
    h: usize,
    flow_of: (f32, f32, f32),
    discs: &[(f32, f32, f32, f32, f32)],
) -> Frame {
    let mut f = flow(w, h, (flow_of.0, flow_of.1), flow_of.2);
    let color = f.color.as_mut().unwrap();
    let v = f.velocity.as_mut().unwrap();
    for i in 0..w * h {
        let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
        let inside = discs
            .iter()
            .find(|d| (x - d.0).hypot(y - d.1) < d.2)
            .copied();
        let Some((cx, cy, radius, dx, dy)) = inside else {
            color.r[i] = 0.0;
            color.g[i] = 0.0;
            color.b[i] = 0.0;
            color.a.as_mut().unwrap()[i] = 0.0;
            (v.x[i], v.y[i]) = (0.0, 0.0);
            continue;
        };
        (v.x[i], v.y[i]) = (v.x[i] + dx, v.y[i] + dy);
        let alpha = color.a.as_mut().unwrap();
        alpha[i] = 1.0;
        if (x - cx).hypot(y - cy) > radius - 1.0 {
            for c in [&mut color.r, &mut color.g, &mut color.b, alpha] {
                c[i] /= 3.0;
            }
        }
    }
    f
}

/// The classification's twin on view layers (issue 33): a disc panning or zooming over empty
/// space (its tiles hollow), two discs moving apart across an empty gap and a disc beside a
/// still one (full), under three shutter offsets; the kinds must be the CPU's, hollow ones
/// among them.
#[test]
fn classify_on_the_gpu_finds_the_cpu_s_kinds_on_view_layers() {
    let Some(gpu) = gpu() else { return };
    let frames = [
        layer(96, 64, (9.0, 2.0, 0.0), &[(40.0, 30.0, 22.0, 0.0, 0.0)]),
        layer(96, 64, (3.0, -2.0, 0.02), &[(50.0, 34.0, 25.0, 0.0, 0.0)]),
        layer(
            120,
            64,
            (0.0, 0.0, 0.0),
            &[(30.0, 32.0, 20.0, 7.0, 0.0), (90.0, 32.0, 20.0, -7.0, 0.0)],
        ),
        layer(
            120,
            64,
            (0.0, 0.0, 0.0),
            &[(30.0, 32.0, 20.0, 7.0, 1.0), (90.0, 32.0, 20.0, 0.0, 0.0)],
        ),
    ]
    .into_iter()
    // Two discs across a gap, their motions apart by steps of a quarter pixel: so that
    // the range of motions within some tile's reach lies close to where its kind changes.
    .chain((1..24).map(|d| {
        layer(
            112,
            64,
            (0.0, 0.0, 0.0),
            &[
                (30.0, 32.0, 20.0, 4.0, 0.0),
                (84.0, 32.0, 20.0, 5.0 + 0.25 * d as f32, 0.0),
            ],
        )
    }))
    .collect::<Vec<_>>();
    let [full, plain, uniform, hollow] = classify_on_both(gpu, &frames);
    eprintln!(
        "classify, view layers: {full} full, {plain} plain, {uniform} uniform, {hollow} hollow"
    );
    assert!(hollow > 0 && full > 0, "hollow and full tiles compared");
}

/// The tolerance is not vacuous: a gather that misses one tap per pixel (a hash that is not
/// the CPU's would do worse) fails it. Here the GPU's output is compared with the CPU's for
/// another frame number, i.e. another jitter.
#[test]
fn reconstruct_parity_fails_for_another_jitter() {
    let Some(gpu) = gpu() else { return };
    let frame = stripes(61, 37, 9.0);
    let params = ReconstructParams::default();
    let cpu = reconstruct(frame.clone(), &params, 0.5, 1).color.unwrap();
    let got = reconstruct_with(frame, &params, 0.5, 2, &GatherOnGpu::new(gpu))
        .color
        .unwrap();
    let p = parity(&got.r, &cpu.r);
    assert!(
        p.mean > MEAN || p.outside > FLIPS,
        "another seed passes: mean {:e}, outside {}",
        p.mean,
        p.outside
    );
}

/// Buffers are kept per shape and reused: frames of one size and variant, then another
/// variant (another texel size), then the first again, all match the CPU.
#[test]
fn reconstruct_gather_reuses_its_buffers_across_frames_and_variants() {
    let paper = ReconstructParams {
        variant: Variant::Paper,
        ..ReconstructParams::default()
    };
    for (seed, params) in [
        (1, ReconstructParams::default()),
        (2, ReconstructParams::default()),
        (3, paper),
        (4, ReconstructParams::default()),
    ] {
        compare("reuse", &noisy(40, 24, seed, 20.0), &params, 0.5, seed);
    }
}

/// `blur --algorithm reconstruct --backend wgpu` (the default variant) writes the CPU's
/// output within the tolerance above, and that output is blurred (not the input copied).
#[test]
fn blur_on_wgpu_equals_the_cpu_within_the_tolerance() {
    if gpu().is_none() {
        return;
    }
    let dir = small_scene("sparse", 96, 54, 1, 4);
    let (color, depth, velocity) = (
        role_pattern(dir.path(), "color"),
        role_pattern(dir.path(), "depth"),
        role_pattern(dir.path(), "velocity"),
    );
    let args = [
        "--algorithm",
        "reconstruct",
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
        assert_twin_within(&format!("blur sparse {name}"), got, cpu, BOUND);
    }
}

/// One view layer of a stack (issue 33): a disc of colour (0.9, 0.6, 0.3), premultiplied,
/// with an anti-aliased rim (coverage of 4×4 samples), moving over empty space (colour and
/// alpha 0, still and far); a rim pixel moves with the disc where the disc covers its centre.
/// The exposure variant's mattes pair the rim with the disc and the empty space, and unmix
/// its alpha with its colour.
fn layer_over_empty_space(w: usize, h: usize, speed: f32) -> Frame {
    let n = w * h;
    let (cx, cy, radius) = (w as f32 * 0.4, h as f32 * 0.5, h as f32 * 0.3);
    let cover = |i: usize| {
        let (x, y) = ((i % w) as f32, (i / w) as f32);
        let inside = (0..16)
            .filter(|s| {
                let (sx, sy) = ((s % 4) as f32 + 0.5, (s / 4) as f32 + 0.5);
                (x + sx / 4.0 - cx).hypot(y + sy / 4.0 - cy) < radius
            })
            .count();
        inside as f32 / 16.0
    };
    let a: Vec<f32> = (0..n).map(cover).collect();
    let centre = |i: usize| {
        let (x, y) = ((i % w) as f32 + 0.5, (i / w) as f32 + 0.5);
        (x - cx).hypot(y - cy) < radius
    };
    let color = [
        a.iter().map(|a| 0.9 * a).collect(),
        a.iter().map(|a| 0.6 * a).collect(),
        a.iter().map(|a| 0.3 * a).collect(),
        a,
    ];
    let depth = (0..n).map(|i| if centre(i) { 3.0 } else { 1e6 }).collect();
    let moving = |i: usize, v: f32| if centre(i) { v } else { 0.0 };
    let v = [
        (0..n).map(|i| moving(i, speed)).collect(),
        (0..n).map(|i| moving(i, 0.4 * speed)).collect(),
    ];
    frame(w, h, color, depth, v)
}

#[test]
fn reconstruct_gather_matches_the_cpu_on_a_layer_over_empty_space() {
    for params in variants() {
        compare(
            "layer over empty space",
            &layer_over_empty_space(61, 37, 9.0),
            &params,
            0.5,
            8,
        );
    }
}

/// A frame without alpha: the gather's alpha is dropped, as on the CPU.
#[test]
fn reconstruct_gather_matches_the_cpu_without_alpha() {
    let mut f = stripes(45, 29, 9.0);
    f.color.as_mut().unwrap().a = None;
    for params in variants() {
        compare("stripes without alpha", &f, &params, 0.5, 7);
    }
}

/// The cost of the pass with the gather on the GPU at 960×540 (a still subject over a moving
/// background, the default variant), printed beside the CPU's (benchmarks measure, tests
/// assert; a quarter of 1080p keeps the test short on a software driver).
#[test]
fn reconstruct_at_540p_prints_its_time() {
    let Some(gpu) = gpu() else { return };
    let frame = still_subject(960, 540, 12.0);
    let params = ReconstructParams::default();
    // Compiled and buffers made here.
    let _ = reconstruct_with(frame.clone(), &params, 0.5, 1, gpu);
    let start = std::time::Instant::now();
    let got = reconstruct_with(frame.clone(), &params, 0.5, 1, gpu);
    let seconds = start.elapsed().as_secs_f64();
    let start = std::time::Instant::now();
    let cpu = reconstruct(frame, &params, 0.5, 1);
    let cpu_seconds = start.elapsed().as_secs_f64();
    assert_eq!(gpu.stages_on_cpu(), 0, "the GPU gather ran");
    let p = parity(&got.color.unwrap().r, &cpu.color.unwrap().r);
    let _ = writeln!(
        std::io::stderr(),
        "gpu: reconstruct 960x540 exposure, gather on the GPU (tiles and pack on the CPU, \
         upload, dispatch, readback) {:.1} ms (cpu {:.1} ms); R max {:e} mean {:e}",
        seconds * 1e3,
        cpu_seconds * 1e3,
        p.max,
        p.mean
    );
    assert!(p.max <= MAX && p.mean <= MEAN && p.outside <= FLIPS);
}

/// reconstruct's stages with the carrying 2014 gather on the GPU in groups of at most
/// `per_dispatch` colours, each of which must run (no fallback to the CPU); `dispatches`
/// counts them.
struct CarryingOnGpu<'a> {
    gpu: &'a Gpu,
    per_dispatch: usize,
    dispatches: std::cell::Cell<usize>,
}

impl Stages for CarryingOnGpu<'_> {
    fn gather_2014_carrying(
        &self,
        config: &ReconstructConfig,
        inputs: (&[Texel2014], &[Matte], &TileGrid, &[TileKind]),
        packed: &TileMask,
        colours: &mut [&mut Color],
    ) {
        for group in colours.chunks_mut(self.per_dispatch) {
            self.gpu
                .try_reconstruct_gather_carrying(config, inputs, packed, group)
                .expect("the GPU's carrying gather runs");
            self.dispatches.set(self.dispatches.get() + 1);
        }
    }
}

/// `n` light layers for `frame`, each its own noise (no two alike, none the beauty), with the
/// beauty's alpha, as a run hands them to the pass.
fn light_layers(frame: &Frame, n: u32) -> Vec<Color> {
    let pixels = frame.width * frame.height;
    let alpha = frame.color.as_ref().unwrap().a.clone();
    (0..n)
        .map(|k| Color {
            r: noise(pixels, 40 + 3 * k, 0.0, 2.0 + k as f32),
            g: noise(pixels, 41 + 3 * k, 0.0, 1.0),
            b: noise(pixels, 42 + 3 * k, -0.1, 0.5),
            a: alpha.clone(),
        })
        .collect()
}

/// The planes of `color` by name (alpha where it has one).
fn planes(color: &Color) -> Vec<(&'static str, &Vec<f32>)> {
    let mut out = vec![("R", &color.r), ("G", &color.g), ("B", &color.b)];
    out.extend(color.a.as_ref().map(|a| ("A", a)));
    out
}

/// Light layers carried through the GPU's 2014 gather beside the beauty (issue 29: the same
/// weights, computed once a tap for every colour of a dispatch) come out as the CPU carries
/// them, within the gather's parity above, in one dispatch or in several: nine layers and the
/// beauty in groups of eight and two, and of three (the real backend's grouping, as many as
/// a binding holds, is run too). Both 2014 forms, with alpha and without; every layer moved.
#[test]
fn reconstruct_carries_light_layers_in_its_dispatches_as_the_cpu_does() {
    let Some(gpu) = gpu() else { return };
    let mut without_alpha = stripes(45, 29, 9.0);
    without_alpha.color.as_mut().unwrap().a = None;
    let frames = [
        ("stripes", stripes(61, 45, 9.0)),
        ("still subject", still_subject(52, 40, 11.0)),
        ("stripes without alpha", without_alpha),
    ];
    let params = [
        ReconstructParams::default(),
        ReconstructParams {
            variant: Variant::Stable,
            ..ReconstructParams::default()
        },
        ReconstructParams {
            taps: 9,
            max_blur: 13,
            jitter: false,
            ..ReconstructParams::default()
        },
    ];
    for (what, frame) in &frames {
        let layers = light_layers(frame, 9);
        for params in &params {
            let mut cpu_layers = layers.clone();
            let cpu = reconstruct_layers_with(frame.clone(), &mut cpu_layers, params, 0.5, 7, &Cpu);
            for per_dispatch in [8, 3, 0] {
                let mut got_layers = layers.clone();
                let on_gpu = CarryingOnGpu {
                    gpu,
                    per_dispatch,
                    dispatches: std::cell::Cell::new(0),
                };
                let got = if per_dispatch == 0 {
                    let got = reconstruct_layers_with(
                        frame.clone(),
                        &mut got_layers,
                        params,
                        0.5,
                        7,
                        gpu,
                    );
                    assert_eq!(gpu.stages_on_cpu(), 0, "the GPU gather ran");
                    got
                } else {
                    let got = reconstruct_layers_with(
                        frame.clone(),
                        &mut got_layers,
                        params,
                        0.5,
                        7,
                        &on_gpu,
                    );
                    assert_eq!(on_gpu.dispatches.get(), 10usize.div_ceil(per_dispatch));
                    got
                };
                let colours =
                    std::iter::once((cpu.color.as_ref().unwrap(), got.color.as_ref().unwrap()))
                        .chain(cpu_layers.iter().zip(&got_layers));
                for (k, (cpu, got)) in colours.enumerate() {
                    let input = if k == 0 {
                        frame.color.as_ref().unwrap()
                    } else {
                        &layers[k - 1]
                    };
                    let moved = planes(cpu)
                        .into_iter()
                        .zip(planes(input))
                        .any(|((_, c), (_, i))| c != i);
                    assert!(moved, "{what}, {params:?}: colour {k} did not move");
                    for ((name, c), (_, g)) in planes(cpu).into_iter().zip(planes(got)) {
                        let p = parity(g, c);
                        assert!(
                            p.max <= MAX && p.mean <= MEAN && p.outside <= FLIPS,
                            "{what}, {params:?}, {per_dispatch} a dispatch, colour {k} {name}: \
                             max {:e} (GPU {} CPU {}), mean {:e}, {:.4}% outside {AGREE:e}",
                            p.max,
                            g[p.worst],
                            c[p.worst],
                            p.mean,
                            p.outside * 100.0
                        );
                    }
                }
            }
        }
    }
}

/// Which tiles are hollow (issue 33), on the CPU: a view layer's disc panning over empty space
/// has its inside tiles hollow (the box), though empty pixels lie within their reach; two
/// discs moving apart across an empty gap are not one flow (the tile between them is full,
/// though each disc alone is smooth); nor is a disc beside a still one (a still surface
/// within reach). 8 px tiles, the default exposure variant, centred.
#[test]
fn hollow_tiles_are_a_layer_s_one_smooth_flow_over_empty_space() {
    let kinds_of = |frame: Frame| {
        let cpu = ClassifyOnBoth::new(None);
        reconstruct_with(frame, &ReconstructParams::default(), 0.5, 1, &cpu);
        let (columns, kinds) = cpu.kept.into_inner().pop().expect("classified");
        move |c: usize, r: usize| kinds[r * columns + c]
    };
    let panning = kinds_of(layer(
        96,
        64,
        (9.0, 2.0, 0.0),
        &[(40.0, 30.0, 22.0, 0.0, 0.0)],
    ));
    assert_eq!(panning(5, 3), TileKind::Hollow, "inside the panning disc");
    let apart = kinds_of(layer(
        120,
        64,
        (0.0, 0.0, 0.0),
        &[(30.0, 32.0, 20.0, 7.0, 0.0), (90.0, 32.0, 20.0, -7.0, 0.0)],
    ));
    assert_eq!(apart(3, 4), TileKind::Hollow, "inside the left disc");
    assert_eq!(apart(7, 4), TileKind::Full, "between discs moving apart");
    let beside = kinds_of(layer(
        120,
        64,
        (0.0, 0.0, 0.0),
        &[(30.0, 32.0, 20.0, 7.0, 0.0), (90.0, 32.0, 20.0, 0.0, 0.0)],
    ));
    assert_eq!(beside(3, 4), TileKind::Hollow, "inside the moving disc");
    assert_eq!(beside(8, 4), TileKind::Full, "at the still disc's rim");
}

/// An opaque frame comes back exactly opaque with the gather on the GPU too, in every
/// variant (the twin's normalised weights round as the CPU's).
#[test]
fn an_opaque_frame_comes_back_exactly_opaque_on_the_gpu() {
    let Some(gpu) = gpu() else { return };
    let (w, h) = (96, 72);
    let mut opaque = noisy(w, h, 3, 30.0);
    opaque.color.as_mut().unwrap().a = Some(vec![1.0; w * h]);
    for params in variants() {
        let on_gpu = GatherOnGpu::new(gpu);
        let out = reconstruct_with(opaque.clone(), &params, 0.5, 1, &on_gpu);
        assert!(on_gpu.ran.get());
        let a = out.color.unwrap().a.unwrap();
        let off = a.iter().filter(|&&v| v != 1.0).count();
        assert_eq!(off, 0, "{:?}: alphas not 1", params.variant);
    }
}
