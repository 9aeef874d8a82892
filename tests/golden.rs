//! Golden images: one small output per algorithm and depth-of-field method, on the passes of
//! a truth scene, against `fixtures/golden/NAME.exr`. The GPU parity tests stand on these:
//! the same inputs, the CPU output as the reference. The goldens were written from code
//! whose outputs were checked bit-identical to the previous release's on every truth scene
//! and bench frame (scripts/same_bits.sh); `SHUTTER_BLESS=1 cargo test golden` rewrites them
//! after an intended change (review the images and say why in the commit).
//!
//! Tolerance: |got − golden| ≤ 1e-5 · max(1, |golden|) per sample — the CPU passes are
//! deterministic, so this only absorbs last-bit differences of the scene's libm-computed
//! passes between machines. A failure writes `target/golden/NAME.got.exr` and
//! `NAME.diff.png` (white where a sample is off by 1e-3 or more) and reports the largest
//! difference, the mean and the share of samples off.

use std::path::{Path, PathBuf};

use shutter::dof::{CocSource, DofParams, Lens, Method};
use shutter::frame::{Color, Frame};
use shutter::io::output::{write_frame, OutputOptions};
use shutter::io::passes::{plan_frame, read_frame, Inputs, PlanOptions};
use shutter::io::preset::Preset;
use shutter::io::sequence::PathPattern;
use shutter::motion::Algorithm;
use shutter::process::{apply, Params};

use crate::support::*;

const SIZE: (usize, usize) = (96, 54);

/// The `layers` lens: 50 mm f/1.4 focused at 3 m on a 36 mm sensor.
const LENS: Lens = Lens {
    focal_mm: 50.0,
    f_number: 1.4,
    focus: 3.0,
    sensor_mm: 36.0,
};

/// A truth scene's passes, read as `shutter blur` reads them.
pub(crate) fn scene_passes(name: &str) -> Frame {
    let dir = small_scene(name, SIZE.0, SIZE.1, 1, 1);
    let role = |r: &str| Some(PathPattern::parse(&role_pattern(dir.path(), r)).unwrap());
    let inputs = Inputs {
        color: PathPattern::parse(&role_pattern(dir.path(), "color")).unwrap(),
        depth: role("depth"),
        velocity: role("velocity"),
        prev: role("prev"),
        next: role("next"),
    };
    let preset = Preset::builtin("shutter").unwrap();
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: shutter::frame::Passes::ALL,
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    read_frame(&plan_frame(&inputs, Some(1), &options).unwrap()).unwrap()
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/golden")
}

/// Compares `out` with the golden `name`, or writes it under `SHUTTER_BLESS`.
fn check(name: &str, out: Frame) {
    let golden = golden_dir().join(format!("{name}.exr"));
    let exr = OutputOptions::default();
    if std::env::var_os("SHUTTER_BLESS").is_some() {
        std::fs::create_dir_all(golden_dir()).unwrap();
        write_frame(&golden, out, &exr, None).unwrap();
        return;
    }
    let expected = read_exr_reference(&golden);
    let color = out.color.as_ref().unwrap();
    let got = [&color.r, &color.g, &color.b, color.a.as_ref().unwrap()];
    let (mut worst, mut sum, mut off, mut count) = (0.0f32, 0.0f64, 0usize, 0usize);
    let mut heat = vec![0.0f32; out.pixel_count()];
    for (plane, channel_name) in got.iter().zip(["R", "G", "B", "A"]) {
        let expected = channel(&expected, channel_name);
        assert_eq!(plane.len(), expected.len(), "{name}: size differs");
        for (i, (&g, &e)) in plane.iter().zip(expected).enumerate() {
            let d = (g - e).abs();
            worst = worst.max(d);
            sum += d as f64;
            count += 1;
            if !close(g, e, 1e-5 * e.abs().max(1.0)) {
                off += 1;
            }
            heat[i] = heat[i].max((d * 1e3).min(1.0));
        }
    }
    if off > 0 {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/golden");
        std::fs::create_dir_all(&dir).unwrap();
        let mut diff = Frame::new(out.width, out.height);
        diff.color = Some(Color {
            r: heat.clone(),
            g: heat.clone(),
            b: heat,
            a: None,
        });
        write_frame(&dir.join(format!("{name}.diff.png")), diff, &exr, None).unwrap();
        write_frame(&dir.join(format!("{name}.got.exr")), out, &exr, None).unwrap();
        panic!(
            "{name}: {off} of {count} samples off the golden (largest difference {worst}, mean \
             {}); see {}",
            sum / count as f64,
            dir.display()
        );
    }
}

#[test]
fn golden_motion_blur_of_every_algorithm_on_rotor() {
    // (At this size gears moves too little for reconstruct to blur: rotor does.)
    let passes = scene_passes("rotor");
    for (name, algorithm) in [
        ("reconstruct", Algorithm::Reconstruct),
        ("scatter", Algorithm::Scatter),
        ("stretch", Algorithm::Stretch),
    ] {
        check(
            name,
            apply(algorithm, &Params::default(), passes.clone(), 1),
        );
    }
}

#[test]
fn golden_depth_of_field_of_every_method_on_layers() {
    let passes = scene_passes("layers");
    for (name, method) in [("dof_gather", Method::Gather), ("dof_blend", Method::Blend)] {
        let params = Params {
            dof: Some(DofParams {
                method,
                blades: 6,
                ..DofParams::new(CocSource::Lens(LENS))
            }),
            ..Params::default()
        };
        check(name, apply(Algorithm::None, &params, passes.clone(), 1));
    }
}
