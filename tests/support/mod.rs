//! Helpers shared by the integration tests: writing EXRs with any channels, running the
//! binary, and assertions over the library's one approximate comparison
//! (`shutter::numeric::close`).
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use shutter::frame::Windows;
use shutter::io::exr::{write_channels, ExrOptions};

pub mod malformed;

/// Writes a single-part scan-line EXR with the given f32 channels (ZIP).
pub fn write_exr(path: &Path, width: usize, height: usize, channels: Vec<(&str, Vec<f32>)>) {
    write_exr_with(path, width, height, channels, ExrOptions::default());
}

pub fn write_exr_with(
    path: &Path,
    width: usize,
    height: usize,
    channels: Vec<(&str, Vec<f32>)>,
    options: ExrOptions,
) {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let channels = channels
        .into_iter()
        .map(|(n, p)| (n.to_string(), p))
        .collect();
    write_channels(
        file,
        width,
        height,
        Windows::full(width, height),
        channels,
        options,
    )
    .unwrap();
}

/// A part of an EXR to write: its name, `view` and `multiView` attributes and channels.
pub struct Part {
    pub name: Option<&'static str>,
    pub view: Option<&'static str>,
    pub multi_view: Option<&'static [&'static str]>,
    pub channels: Vec<(String, Vec<f32>)>,
}

/// Writes `channels` as one part of `views` (OpenEXR's one-part multi-view scheme: a
/// `multiView` list, the first the default, channels named with their view).
pub fn write_views(
    path: &Path,
    size: (usize, usize),
    views: &'static [&'static str],
    channels: Vec<(String, Vec<f32>)>,
) {
    let part = Part {
        name: None,
        view: None,
        multi_view: Some(views),
        channels,
    };
    write_parts(path, size, vec![part]);
}

/// Writes the parts as one EXR (several parts make a multi-part file) through the exr
/// crate, which writes `multiView` and `view` from its layer attributes.
pub fn write_parts(path: &Path, (w, h): (usize, usize), parts: Vec<Part>) {
    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::meta::attribute::{IntegerBounds, Text};
    use exr::meta::header::{ImageAttributes, LayerAttributes};
    use exr::prelude::{Blocks, LineOrder, WritableImage};
    let layers: Vec<_> = parts
        .into_iter()
        .map(|part| {
            let attributes = LayerAttributes {
                layer_name: part.name.map(Text::from),
                view_name: part.view.map(Text::from),
                multi_view_names: part
                    .multi_view
                    .map(|views| views.iter().map(|v| Text::from(*v)).collect()),
                ..LayerAttributes::default()
            };
            let channels = part
                .channels
                .into_iter()
                .map(|(name, plane)| AnyChannel::new(name.as_str(), FlatSamples::F32(plane)))
                .collect();
            let encoding = Encoding {
                blocks: Blocks::ScanLines,
                line_order: LineOrder::Increasing,
                ..Encoding::default()
            };
            Layer::new((w, h), attributes, encoding, AnyChannels::sort(channels))
        })
        .collect();
    let attributes = ImageAttributes::new(IntegerBounds::new((0, 0), (w, h)));
    Image::from_layers(attributes, layers)
        .write()
        .to_file(path)
        .unwrap();
}

/// A deterministic pseudo-random plane, values in [lo, hi).
pub fn noise(n: usize, seed: u32, lo: f32, hi: f32) -> Vec<f32> {
    (0..n as u32)
        .map(|i| {
            let mut h = i.wrapping_mul(0x9E37_79B9) ^ seed.wrapping_mul(0x85EB_CA6B);
            h ^= h >> 15;
            h = h.wrapping_mul(0x2C1B_3C6D);
            h ^= h >> 12;
            lo + (hi - lo) * (h as f32 / u32::MAX as f32)
        })
        .collect()
}

/// Reads every channel of an EXR through exr's own image API (independent of our reader).
pub fn read_exr_reference(path: &Path) -> Vec<(String, Vec<f32>)> {
    let mut out = Vec::new();
    for layer in read_exr_layers(path) {
        for channel in layer.channel_data.list {
            let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
            out.push((channel.name.to_string(), values));
        }
    }
    out
}

/// Every layer of an EXR with its channels as stored (the exr crate's reader).
pub fn read_exr_layers(
    path: &Path,
) -> Vec<exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>>> {
    use exr::prelude::*;
    read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap()
        .layer_data
        .into_iter()
        .collect()
}

/// The layer (part) of `layers` named `name`.
pub fn part_named<'a>(
    layers: &'a [exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>>],
    name: &str,
) -> &'a exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>> {
    let named = |l: &&exr::image::Layer<_>| {
        let layer_name = l.attributes.layer_name.as_ref().map(|t| t.to_string());
        layer_name.as_deref() == Some(name)
    };
    (layers.iter())
        .find(named)
        .unwrap_or_else(|| panic!("no part {name}"))
}

pub fn channel<'a>(channels: &'a [(String, Vec<f32>)], name: &str) -> &'a [f32] {
    &channels
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no channel {name}"))
        .1
}

/// The one approximate comparison, the library's (`shutter::numeric`: NaN close only to NaN,
/// infinities only to themselves), so integration and unit tests share its rules.
pub use shutter::numeric::{all_close, close, close_relative};

/// [`all_close`] for every sample; panics naming the first differing index.
pub fn assert_close(actual: &[f32], expected: &[f32], tolerance: f32, what: &str) {
    if let Err(mismatch) = all_close(actual, expected, tolerance) {
        panic!("{what}: {mismatch} (tolerance {tolerance})");
    }
}

/// Exact comparison (tolerance 0, NaN rules as above; −0 equals +0).
pub fn assert_exact(actual: &[f32], expected: &[f32], what: &str) {
    assert_close(actual, expected, 0.0, what);
}

/// Bit-for-bit comparison (−0 differs from +0, NaNs by payload); panics naming the first
/// differing index.
pub fn assert_same_bits(actual: &[f32], expected: &[f32], what: &str) {
    assert_eq!(actual.len(), expected.len(), "{what}: lengths differ");
    if let Some(i) = (0..actual.len()).find(|&i| actual[i].to_bits() != expected[i].to_bits()) {
        panic!(
            "{what}: index {i}: got {}, expected {} (bit for bit)",
            actual[i], expected[i]
        );
    }
}

/// Runs the shutter binary.
pub fn shutter(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shutter"))
        .args(args)
        .output()
        .expect("run shutter")
}

/// Runs the shutter binary with `args` under an address-space cap of `kib` KiB (`ulimit -v`,
/// through `sh`): what a machine with that little memory, or a farm's limit, allows.
#[cfg(unix)]
pub fn shutter_capped(kib: u64, args: &[&str]) -> Output {
    let quoted: Vec<String> = args
        .iter()
        .map(|a| format!("'{}'", a.replace('\'', "'\\''")))
        .collect();
    let script = format!(
        "ulimit -v {kib}; exec '{}' {}",
        env!("CARGO_BIN_EXE_shutter"),
        quoted.join(" ")
    );
    Command::new("sh")
        .args(["-c", &script])
        .output()
        .expect("run sh")
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// Every file under a folder with its size and modification time, to check that a failed run
/// left it exactly as it was.
pub fn snapshot(dir: &Path) -> Vec<(PathBuf, u64, std::time::SystemTime)> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for entry in entries.flatten() {
            let meta = entry.metadata().unwrap();
            if meta.is_dir() {
                out.push((entry.path(), 0, meta.modified().unwrap()));
                out.extend(snapshot(&entry.path()));
            } else {
                out.push((entry.path(), meta.len(), meta.modified().unwrap()));
            }
        }
    }
    out.sort();
    out
}

pub fn s(path: &Path) -> String {
    path.display().to_string()
}

/// A small canonical frame written as separate pass files `C`, `Z`, `V` (with `.####` when
/// `frame` is given); returns the colour it wrote.
pub fn write_canonical_frame(
    dir: &Path,
    frame: Option<i64>,
    width: usize,
    height: usize,
) -> [Vec<f32>; 4] {
    let n = width * height;
    let seed = frame.unwrap_or(0) as u32;
    let rgba = [
        noise(n, seed * 10 + 1, 0.0, 4.0),
        noise(n, seed * 10 + 2, 0.0, 1.0),
        noise(n, seed * 10 + 3, -0.1, 1.0),
        noise(n, seed * 10 + 4, 0.0, 1.0),
    ];
    let suffix = frame.map_or(String::new(), |f| format!(".{f:04}"));
    write_exr(
        &dir.join(format!("C{suffix}.exr")),
        width,
        height,
        vec![
            ("R", rgba[0].clone()),
            ("G", rgba[1].clone()),
            ("B", rgba[2].clone()),
            ("A", rgba[3].clone()),
        ],
    );
    write_exr(
        &dir.join(format!("Z{suffix}.exr")),
        width,
        height,
        vec![("Z", noise(n, seed * 10 + 5, 1.0, 100.0))],
    );
    write_exr(
        &dir.join(format!("V{suffix}.exr")),
        width,
        height,
        vec![
            ("X", noise(n, seed * 10 + 6, -20.0, 20.0)),
            ("Y", noise(n, seed * 10 + 7, -20.0, 20.0)),
        ],
    );
    rgba
}

/// Writes a small truth scene into a fresh folder.
pub fn small_scene(
    name: &str,
    width: usize,
    height: usize,
    frames: usize,
    samples: usize,
) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let options = shutter::lab::truth::write::SceneOptions {
        width,
        height,
        frames,
        samples,
        ..Default::default()
    };
    shutter::lab::truth::write::write_scene(name, dir.path(), &options, &mut |_, _| {}).unwrap();
    dir
}

/// The sequence pattern of one role (`color`, `depth`, ...) in a scene folder.
pub fn role_pattern(dir: &Path, role: &str) -> String {
    format!("{}/{role}.####.exr", dir.display())
}

/// Premultiplied R, G, B, A of a frame with alpha.
pub fn planes(f: &shutter::frame::Frame) -> [&[f32]; 4] {
    let c = f.color.as_ref().unwrap();
    [&c.r, &c.g, &c.b, c.a.as_deref().unwrap()]
}

/// The invariants every motion-blur algorithm keeps (docs/DESIGN.md "Algorithms"), checked on
/// frames from `frame(width, height, seed, speed)` under each of `variants`.
pub mod invariants {
    use shutter::frame::{Color, Frame};
    use shutter::motion::Algorithm;
    use shutter::process::{apply, Params};

    use super::{assert_close, assert_same_bits, planes};

    pub type Make = fn(usize, usize, u32, f32) -> Frame;

    /// A frame that does not move comes back unchanged (`still` is a frame whose motion is
    /// below the algorithm's threshold). Each pass returns such a frame before its first
    /// stage ([`still_far_from_motion_is_identity`] checks the stages themselves).
    pub fn zero_motion_is_identity(algorithm: Algorithm, still: &Frame, variants: &[Params]) {
        for params in variants {
            let out = apply(algorithm, params, still.clone(), 3);
            for (a, b) in planes(&out).iter().zip(planes(still)) {
                assert_same_bits(a, b, "zero motion");
            }
        }
    }

    /// Columns of the moving strip [`still_far_from_motion_is_identity`] puts at the left.
    pub const STRIP: usize = 16;

    /// `still` with its first [`STRIP`] columns taken, every pass, from `moving` (the same
    /// size).
    pub fn moving_strip(still: &Frame, moving: &Frame) -> Frame {
        let w = still.width;
        let splice = |to: &mut Vec<f32>, from: &[f32]| {
            for (i, v) in to.iter_mut().enumerate() {
                if i % w < STRIP {
                    *v = from[i];
                }
            }
        };
        let mut f = still.clone();
        if let (Some(to), Some(from)) = (f.color.as_mut(), moving.color.as_ref()) {
            splice(&mut to.r, &from.r);
            splice(&mut to.g, &from.g);
            splice(&mut to.b, &from.b);
            if let (Some(to), Some(from)) = (to.a.as_mut(), from.a.as_ref()) {
                splice(to, from);
            }
        }
        if let (Some(to), Some(from)) = (f.depth.as_mut(), moving.depth.as_ref()) {
            splice(to, from);
        }
        if let (Some(to), Some(from)) = (f.velocity.as_mut(), moving.velocity.as_ref()) {
            splice(&mut to.x, &from.x);
            splice(&mut to.y, &from.y);
        }
        for (to, from) in [(&mut f.prev, &moving.prev), (&mut f.next, &moving.next)] {
            if let (Some(to), Some(from)) = (to.as_mut(), from.as_ref()) {
                splice(&mut to.x, &from.x);
                splice(&mut to.y, &from.y);
                if let (Some(to), Some(from)) = (to.z.as_mut(), from.z.as_ref()) {
                    splice(to, from);
                }
            }
        }
        f
    }

    /// The pass's stages leave still pixels alone: on `still` with a moving strip at its left
    /// ([`moving_strip`]), so that the whole pass runs (the strip must change), every pixel
    /// `far` columns or more right of the strip (beyond the pass's reach from it) comes out
    /// bit for bit as it went in.
    pub fn still_far_from_motion_is_identity(
        algorithm: Algorithm,
        still: &Frame,
        moving: &Frame,
        variants: &[Params],
        far: usize,
    ) {
        let f = moving_strip(still, moving);
        let w = f.width;
        assert!(w > STRIP + far, "{w} columns leave none far from the strip");
        for (k, params) in variants.iter().enumerate() {
            let out = apply(algorithm, params, f.clone(), 3);
            for (channel, (o, i)) in planes(&out).iter().zip(planes(&f)).enumerate() {
                let far = |p: &usize| p % w >= STRIP + far;
                let changed = |p: &usize| o[*p].to_bits() != i[*p].to_bits();
                if let Some(p) = (0..i.len()).filter(far).find(changed) {
                    panic!(
                        "variant {k}, channel {channel}: still pixel ({}, {}) (the moving \
                         strip ends at x = {STRIP}) came out {} from {}",
                        p % w,
                        p / w,
                        o[p],
                        i[p]
                    );
                }
            }
            let strip = |plane: &[f32]| -> Vec<f32> {
                (0..plane.len())
                    .filter(|p| p % w < STRIP)
                    .map(|p| plane[p])
                    .collect()
            };
            assert!(
                strip(planes(&out)[0]) != strip(planes(&f)[0]),
                "variant {k}: the moving strip must change (the whole pass must run)"
            );
        }
    }

    /// A uniform colour comes back uniform, the same colour (up to `slack` relative: the
    /// rounding of a weighted sum divided by its weights).
    pub fn uniform_stays_uniform(
        algorithm: Algorithm,
        make: Make,
        variants: &[Params],
        slack: f32,
    ) {
        let (w, h) = (61, 37);
        let n = w * h;
        let mut f = make(w, h, 2, 30.0);
        f.color = Some(Color {
            r: vec![0.7; n],
            g: vec![3.5; n],
            b: vec![0.0; n],
            a: Some(vec![1.0; n]),
        });
        for params in variants {
            let out = apply(algorithm, params, f.clone(), 1);
            let c = out.color.unwrap();
            for (plane, value, what) in [(&c.r, 0.7, "r"), (&c.g, 3.5, "g"), (&c.b, 0.0, "b")] {
                assert_close(plane, &vec![value; n], slack * value, what);
            }
        }
    }

    /// Every output channel within the input's [min, max] (up to `slack` relative), and the
    /// motion changes something.
    pub fn within_input_range(algorithm: Algorithm, make: Make, variants: &[Params], slack: f32) {
        for seed in [3, 30, 300] {
            let f = make(64, 48, seed, 20.0);
            for params in variants {
                let out = apply(algorithm, params, f.clone(), seed as i64);
                for (o, i) in planes(&out).iter().zip(planes(&f)) {
                    let lo = i.iter().copied().fold(f32::INFINITY, f32::min);
                    let hi = i.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                    let slack = slack * hi.abs().max(lo.abs()).max(1.0);
                    assert!(
                        o.iter().all(|v| *v >= lo - slack && *v <= hi + slack),
                        "out of [{lo}, {hi}]"
                    );
                }
                assert!(
                    planes(&out)[0] != planes(&f)[0],
                    "motion must change something"
                );
            }
        }
    }

    /// Finite output for a frame `f` poisoned with NaN, infinite and huge values.
    pub fn finite_output(algorithm: Algorithm, f: &Frame, variants: &[Params]) {
        for params in variants {
            let out = apply(algorithm, params, f.clone(), 9);
            for plane in planes(&out) {
                assert!(plane.iter().all(|v| v.is_finite()), "non-finite output");
            }
        }
    }

    /// Poisons colour and depth with NaN, infinite, huge, negative and zero values.
    pub fn poison_color_and_depth(f: &mut Frame) {
        let c = f.color.as_mut().unwrap();
        c.r[0] = f32::NAN;
        c.g[100] = f32::INFINITY;
        c.b[200] = f32::NEG_INFINITY;
        c.r[300] = 3e38;
        let d = f.depth.as_mut().unwrap();
        d[50] = f32::NAN;
        d[60] = f32::INFINITY;
        d[70] = -5.0;
        d[80] = 1e38;
        d[81] = 0.0;
    }

    /// `shutter blur --algorithm NAME` on a small truth scene gives the same bytes with 1
    /// and 2 threads. `passes` are the scene roles to pass (`color` first).
    pub fn same_bytes_for_any_thread_count(
        name: &str,
        scene: &str,
        passes: &[&str],
        extra: &[&str],
    ) {
        let dir = super::small_scene(scene, 96, 54, 1, 4);
        let mut outputs = Vec::new();
        for threads in ["1", "2"] {
            let mut args = vec!["blur".to_string(), "--algorithm".into(), name.into()];
            for role in passes {
                args.push(format!("--{role}"));
                args.push(super::role_pattern(dir.path(), role));
            }
            args.extend(extra.iter().map(|s| s.to_string()));
            args.push("-o".into());
            args.push(format!("{}/t{threads}.####.exr", dir.path().display()));
            let o = std::process::Command::new(env!("CARGO_BIN_EXE_shutter"))
                .env("RAYON_NUM_THREADS", threads)
                .args(&args)
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            outputs.push(std::fs::read(dir.path().join(format!("t{threads}.0001.exr"))).unwrap());
        }
        assert_eq!(outputs[0], outputs[1]);
    }
}

/// Three colour planes as a metrics image.
pub fn rgb(planes: &[Vec<f32>; 3], w: usize, h: usize) -> shutter::lab::metrics::Rgb<'_> {
    shutter::lab::metrics::Rgb::new(planes, w, h)
}

/// Noise colour (RGBA, HDR red, negative blue) over two depth layers (2 and 9) scattered
/// per pixel, so edges and tiles see every case; no motion passes yet. Seeds `seed` to
/// `seed + 4`.
pub fn noise_frame(w: usize, h: usize, seed: u32) -> shutter::frame::Frame {
    let n = w * h;
    let mut f = shutter::frame::Frame::new(w, h);
    f.color = Some(shutter::frame::Color {
        r: noise(n, seed, 0.0, 4.0),
        g: noise(n, seed + 1, 0.0, 1.0),
        b: noise(n, seed + 2, -0.5, 1.0),
        a: Some(noise(n, seed + 3, 0.0, 1.0)),
    });
    let layer = noise(n, seed + 4, 0.0, 1.0);
    f.depth = Some(
        layer
            .iter()
            .map(|&v| if v < 0.5 { 2.0 } else { 9.0 })
            .collect(),
    );
    f
}

/// `none`'s region RMSE, each run's, the scene's passes and each run's output.
pub type SceneErrors = (
    f64,
    Vec<f64>,
    shutter::frame::Frame,
    Vec<shutter::frame::Frame>,
);

/// Renders truth scene `name` at `w`×`h` (256 samples, shutter 0.5) and scores each
/// algorithm with its parameters against the motion-blur reference over the region blur
/// changes. Returns the unblurred frame's error, each run's error, the passes and outputs.
pub fn scene_errors(
    name: &str,
    size: (usize, usize),
    runs: &[(shutter::motion::Algorithm, shutter::process::Params)],
) -> SceneErrors {
    scene_errors_against(
        name,
        size,
        shutter::lab::truth::render::Reference::MotionBlur,
        runs,
    )
}

/// [`scene_errors`] against the reference of `kind` (motion blur, the lens, or both).
pub fn scene_errors_against(
    name: &str,
    (w, h): (usize, usize),
    kind: shutter::lab::truth::render::Reference,
    runs: &[(shutter::motion::Algorithm, shutter::process::Params)],
) -> SceneErrors {
    use shutter::lab::metrics::{changed_region, rmse};
    use shutter::lab::truth::render::{render_passes, render_reference, RenderSettings};
    let scene = shutter::lab::truth::scenes::build(name, w, h, 1).unwrap();
    let passes = render_passes(&scene, 0.0, 256, 1);
    let settings = RenderSettings {
        samples: 256,
        shutter: 0.5,
        shutter_offset: 0.0,
        seed: 1,
    };
    let reference = render_reference(&scene, 0.0, kind, &settings);
    let c = passes.color.clone().unwrap();
    let sharp = [c.r, c.g, c.b];
    let region = changed_region(&rgb(&sharp, w, h), &rgb(&reference, w, h), 1e-3);
    let none = rmse(&rgb(&sharp, w, h), &rgb(&reference, w, h), Some(&region));
    let mut errors = Vec::new();
    let mut outputs = Vec::new();
    for (algorithm, params) in runs {
        let out = shutter::process::apply(*algorithm, params, passes.clone(), 1);
        let c = out.color.clone().unwrap();
        let blurred = [c.r, c.g, c.b];
        errors.push(rmse(
            &rgb(&blurred, w, h),
            &rgb(&reference, w, h),
            Some(&region),
        ));
        outputs.push(out);
    }
    (none, errors, passes, outputs)
}

/// The largest change in red inside the tracked disc of `pan` at 160×90 (radius 60 px at
/// 640×360, so 15 px here, centred; its inner 10 px), between two frames.
pub fn tracked_disc_change(before: &shutter::frame::Frame, after: &shutter::frame::Frame) -> f32 {
    let (w, h) = (160, 90);
    let (a, b) = (
        &before.color.as_ref().unwrap().r,
        &after.color.as_ref().unwrap().r,
    );
    let mut worst = 0.0f32;
    for y in 0..h {
        for x in 0..w {
            let (dx, dy) = (x as f32 + 0.5 - 80.0, y as f32 + 0.5 - 45.0);
            if dx * dx + dy * dy < 10.0 * 10.0 {
                let i = y * w + x;
                worst = worst.max((a[i] - b[i]).abs());
            }
        }
    }
    worst
}

/// Per-channel difference statistics of a GPU twin's output against the CPU reference's,
/// relative to the CPU channel's range ([`parity_within`]).
#[derive(Debug, Default, Clone, Copy)]
pub struct Parity {
    /// The largest difference, and the pixel where it is.
    pub max: f32,
    pub worst: usize,
    /// The mean difference.
    pub mean: f64,
    /// The share of pixels whose difference exceeds the tolerance asked for.
    pub outside: f64,
}

impl Parity {
    /// The worse of two, statistic by statistic.
    pub fn worse(self, other: Parity) -> Parity {
        Parity {
            max: self.max.max(other.max),
            mean: self.mean.max(other.mean),
            outside: self.outside.max(other.outside),
            worst: if other.max > self.max {
                other.worst
            } else {
                self.worst
            },
        }
    }

    /// Prints `gpu: what: max … mean … outside …%` to the process's stderr, past the test
    /// harness's capture, so every run's log holds the figures.
    pub fn report(&self, what: &str) {
        let _ = writeln!(
            std::io::stderr(),
            "gpu: {what}: max {:e} mean {:e} outside {:.3}%",
            self.max,
            self.mean,
            self.outside * 100.0
        );
    }
}

/// The [`Parity`] of channel `got` against `cpu`, counting the pixels that differ by more than
/// `agree` of the range. A channel constant but for rounding (an alpha of 1 with a few outputs
/// an ulp below) has no range to be relative to: its differences are taken as they are. Every
/// value of `got` must be finite.
pub fn parity_within(got: &[f32], cpu: &[f32], agree: f32) -> Parity {
    assert_eq!(got.len(), cpu.len());
    let range = parity_range(cpu);
    let mut p = Parity::default();
    for (i, (&g, &c)) in got.iter().zip(cpu).enumerate() {
        assert!(g.is_finite(), "pixel {i}: GPU gave {g}");
        let e = (g - c).abs() / range;
        if e > p.max {
            p.max = e;
            p.worst = i;
        }
        if e > agree {
            p.outside += 1.0;
        }
        p.mean += e as f64;
    }
    let n = got.len().max(1) as f64;
    p.mean /= n;
    p.outside /= n;
    p
}

/// A twin's parity bound: the share of the range two values agree within ([`parity_within`]'s
/// `agree`), then the most the largest difference, the share of pixels outside `agree` and
/// the mean difference may be.
pub type ParityBound = (f32, f32, f64, f64);

/// Asserts that channel `got` is `cpu`'s within `bound`, naming `what`, and prints its
/// [`Parity`] ([`Parity::report`]).
pub fn assert_twin_within(what: &str, got: &[f32], cpu: &[f32], bound: ParityBound) {
    let (agree, max, flips, mean) = bound;
    let p = parity_within(got, cpu, agree);
    p.report(what);
    assert!(
        p.max <= max && p.mean <= mean && p.outside <= flips,
        "{what}: max {:e} mean {:e} outside {}",
        p.max,
        p.mean,
        p.outside
    );
}

/// `shutter blur ARGS --backend BACKEND --json -o DIR/STEM.####.exr` on frame files in `dir`
/// (with the environment variable `env` set, when given), which must succeed and say it ran
/// on `backend`: its JSON summary and the path of the frame it wrote.
pub fn blur_on(
    dir: &Path,
    args: &[&str],
    backend: &str,
    stem: &str,
    env: Option<(&str, &str)>,
) -> (serde_json::Value, PathBuf) {
    let out = s(&dir.join(format!("{stem}.####.exr")));
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_shutter"));
    command
        .arg("blur")
        .args(args)
        .args(["-o", &out, "--backend", backend, "--json"]);
    if let Some((name, value)) = env {
        command.env(name, value);
    }
    let o = command.output().unwrap();
    assert!(o.status.success(), "{stem}: {}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(json["backend"]["used"], backend, "{json}");
    (json, dir.join(format!("{stem}.0001.exr")))
}

/// Runs a real client (`idiff`, `exiftool`, …), or `None` (with a note) where it is not
/// installed and `SHUTTER_REQUIRE_TOOLS=1` does not ask for it.
pub fn run_tool(name: &str, args: &[&str]) -> Option<Output> {
    match Command::new(name).args(args).output() {
        Ok(o) => Some(o),
        Err(_) if std::env::var("SHUTTER_REQUIRE_TOOLS").as_deref() == Ok("1") => {
            panic!("{name} is not installed and SHUTTER_REQUIRE_TOOLS=1")
        }
        Err(_) => {
            eprintln!("note: {name} is not installed; its part of the test is skipped");
            None
        }
    }
}

/// `oiiotool --info -v` of a file, or `None` (with a note) where it is not installed and
/// `SHUTTER_REQUIRE_TOOLS` does not ask for it.
pub fn oiiotool_info(path: &Path) -> Option<String> {
    match Command::new("oiiotool")
        .args(["--info", "-v", &s(path)])
        .output()
    {
        Ok(out) => {
            assert!(
                out.status.success(),
                "oiiotool failed on {}",
                path.display()
            );
            Some(String::from_utf8_lossy(&out.stdout).into_owned())
        }
        Err(_) if std::env::var_os("SHUTTER_REQUIRE_TOOLS").is_some() => {
            panic!("SHUTTER_REQUIRE_TOOLS is set and oiiotool is not installed")
        }
        Err(_) => {
            eprintln!("note: oiiotool is not installed; only our reader checks the output");
            None
        }
    }
}

/// The exact exposure of pixel column `x` of a texture `texture(u)` (u in pixels) moving
/// right `speed` px a frame under the default shutter (half the frame, centred): its mean
/// over the pixel's width and the exposure, by a 400 × 400 midpoint rule, worked out apart
/// from the code under test.
pub fn exposure_of_column(texture: &dyn Fn(f64) -> f64, x: usize, speed: f64) -> f64 {
    let n = 400;
    let mut sum = 0.0;
    for a in 0..n {
        let u = x as f64 + (a as f64 + 0.5) / n as f64;
        for b in 0..n {
            let t = -0.25 + 0.5 * (b as f64 + 0.5) / n as f64;
            sum += texture(u - speed * t);
        }
    }
    sum / (n * n) as f64
}

/// With `SHUTTER_DIAG` set, prints the pixels of a GPU plane that [`parity_within`] counts
/// outside `agree` (the same range and test), the first 25 with the frame's depth and
/// velocity there, and their count: what a parity failure on a lent GPU needs to be read
/// (scripts/device/figures.sh passes the variable through; docs/history/device-parity-*.md).
pub(crate) fn diag_pixels(
    what: &str,
    frame: &shutter::frame::Frame,
    got: &[f32],
    cpu: &[f32],
    agree: f32,
) {
    if std::env::var_os("SHUTTER_DIAG").is_none() {
        return;
    }
    let w = frame.width;
    let range = parity_range(cpu);
    let mut n = 0;
    for (i, (g, c)) in got.iter().zip(cpu).enumerate() {
        let d = (g - c).abs() / range;
        if d > agree {
            n += 1;
            if n <= 25 {
                let v = frame.velocity.as_ref().map(|v| (v.x[i], v.y[i]));
                let z = frame.depth.as_ref().map(|z| z[i]);
                eprintln!(
                    "DIAG {what} ({}, {}): GPU {g:e} CPU {c:e} d {d:e} z {z:?} v {v:?}",
                    i % w,
                    i / w
                );
            }
        }
    }
    eprintln!("DIAG {what}: {n} of {} outside", got.len());
}

/// What [`parity_within`] divides a difference by: the CPU plane's range (its largest value
/// less its least), or 1 where that is under 1e-4 of its magnitude (a flat plane).
fn parity_range(cpu: &[f32]) -> f32 {
    let (lo, hi) = cpu
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    if hi - lo > 1e-4 * hi.abs().max(lo.abs()).max(1.0) {
        hi - lo
    } else {
        1.0
    }
}

/// A lens for depth of field tests: 50 mm at f/2, focused at 3 m.
pub const LENS_ARGS: [&str; 6] = [
    "--focal-length",
    "50",
    "--f-stop",
    "2",
    "--focus-distance",
    "3",
];
