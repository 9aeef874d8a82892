//! The truth scenes: deterministic files, exact motion, converged references.

use shutter::lab::metrics::{changed_region, rmse};
use shutter::lab::truth::render::{render_passes, render_reference, Reference, RenderSettings};
use shutter::lab::truth::scenes::{build, SCENES};
use shutter::lab::truth::write::{write_scene, SceneOptions, DEFAULT_SAMPLES};

use crate::support::*;

#[test]
fn every_scene_builds_and_writes_byte_identical_files_twice() {
    let dir = tempfile::tempdir().unwrap();
    let options = SceneOptions {
        width: 48,
        height: 27,
        frames: 2,
        samples: 8,
        ..SceneOptions::default()
    };
    for (name, _) in SCENES {
        let a = dir.path().join(format!("{name}_a"));
        let b = dir.path().join(format!("{name}_b"));
        write_scene(name, &a, &options, &mut |_, _| {}).unwrap();
        write_scene(name, &b, &options, &mut |_, _| {}).unwrap();
        let mut files: Vec<_> = std::fs::read_dir(&a)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        files.sort();
        let expected = if *name == "layers" { 17 } else { 13 };
        assert_eq!(files.len(), expected, "{name}: {files:?}");
        for file in files {
            assert_eq!(
                std::fs::read(a.join(&file)).unwrap(),
                std::fs::read(b.join(&file)).unwrap(),
                "{name}: {file:?} differs between two runs"
            );
        }
    }
}

#[test]
fn shutter_blur_reads_a_scene_with_nothing_but_the_pass_paths() {
    let dir = small_scene("rotor", 32, 18, 2, 4);
    let p = |role: &str| role_pattern(dir.path(), role);
    let o = shutter(&[
        "blur",
        "--color",
        &p("color"),
        "--depth",
        &p("depth"),
        "--velocity",
        &p("velocity"),
        "--prev",
        &p("prev"),
        "--next",
        &p("next"),
        "-o",
        &format!("{}/out/o.####.exr", dir.path().display()),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(dir.path().join("out/o.0002.exr").exists());
}

#[test]
fn tracked_object_in_pan_is_still_and_the_world_moves() {
    let scene = build("pan", 320, 180, 1).unwrap();
    let frame = render_passes(&scene, 0.0, 1, 1);
    let v = frame.velocity.unwrap();
    let centre = 90 * 320 + 160;
    assert!(v.x[centre].abs() < 1e-4 && v.y[centre].abs() < 1e-4);
    // The background moves with the camera pan: -10 px per frame at 640x360 → -5 here.
    let corner = 5 * 320 + 5;
    assert!((v.x[corner] + 5.0).abs() < 1e-4, "{}", v.x[corner]);
}

#[test]
fn sparse_moves_under_five_percent_and_static_not_at_all() {
    let frame = render_passes(&build("sparse", 320, 180, 1).unwrap(), 0.0, 4, 1);
    let v = frame.velocity.unwrap();
    let moving =
        v.x.iter()
            .zip(&v.y)
            .filter(|(x, y)| x.hypot(**y) > 0.0)
            .count();
    assert!(moving > 0 && moving * 20 < v.x.len(), "{moving}");
    let frame = render_passes(&build("static", 320, 180, 1).unwrap(), 0.0, 4, 1);
    let v = frame.velocity.unwrap();
    assert!(v.x.iter().chain(&v.y).all(|&c| c == 0.0));
}

#[test]
fn huge_moves_hundreds_of_pixels() {
    let frame = render_passes(&build("huge", 640, 360, 1).unwrap(), 0.0, 1, 1);
    let v = frame.velocity.unwrap();
    let max =
        v.x.iter()
            .zip(&v.y)
            .map(|(x, y)| x.hypot(*y))
            .fold(0.0, f32::max);
    assert!(max > 400.0, "{max}");
}

#[test]
fn positions_are_consistent_with_velocity() {
    // prev = centre - velocity exactly as written (same closed form), for a rotating scene.
    let frame = render_passes(&build("rotor", 64, 36, 1).unwrap(), 0.0, 1, 1);
    let (v, prev) = (frame.velocity.unwrap(), frame.prev.unwrap());
    for k in 0..v.x.len() {
        let (cx, _) = shutter::frame::pixel_centre(k, 64);
        assert!((cx - v.x[k] - prev.x[k]).abs() < 1e-3);
    }
}

/// The reference with N and 2N samples must differ ten times less than the error of the
/// unblurred frame (`none`) over the region that blur changes. (reconstruct's errors on pan
/// and zoom are only 3–5 times the reference noise at 320×180: BENCHMARKS.md.) 256×144 keeps the test short; `cargo run --release --example
/// convergence -- 256 144 1024` prints the table for every scene (BENCHMARKS.md).
#[test]
fn references_converge_at_the_default_sample_count() {
    let (w, h) = (256, 144);
    for (name, kind) in [
        ("rotor", Reference::MotionBlur),
        ("gears", Reference::MotionBlur),
        ("pan", Reference::MotionBlur),
        ("layers", Reference::Both),
    ] {
        let scene = build(name, w, h, 1).unwrap();
        let settings = |samples: usize, seed: u64| RenderSettings {
            samples,
            shutter: 0.5,
            shutter_offset: 0.0,
            seed,
        };
        let n = render_reference(&scene, 0.0, kind, &settings(DEFAULT_SAMPLES, 1));
        let n2 = render_reference(&scene, 0.0, kind, &settings(2 * DEFAULT_SAMPLES, 2));
        let sharp = render_passes(&scene, 0.0, 2 * DEFAULT_SAMPLES, 2)
            .color
            .unwrap();
        let sharp = [sharp.r, sharp.g, sharp.b];
        let region = changed_region(&rgb(&sharp, w, h), &rgb(&n2, w, h), 1e-3);
        let convergence = rmse(&rgb(&n, w, h), &rgb(&n2, w, h), Some(&region));
        let unblurred = rmse(&rgb(&sharp, w, h), &rgb(&n2, w, h), Some(&region));
        assert!(
            convergence * 10.0 <= unblurred,
            "{name} {kind:?}: reference noise {convergence} vs error {unblurred}"
        );
    }
}

#[test]
fn scene_command_writes_the_passes_and_references() {
    let dir = tempfile::tempdir().unwrap();
    let o = shutter(&[
        "scene",
        "layers",
        "-o",
        &s(dir.path()),
        "--size",
        "40x24",
        "--samples",
        "8",
        "--frames",
        "2",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    for role in [
        "color",
        "depth",
        "velocity",
        "prev",
        "next",
        "reference",
        "reference_dof",
        "reference_both",
    ] {
        assert!(
            dir.path().join(format!("{role}.0002.exr")).exists(),
            "{role}"
        );
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("scene.json")).unwrap())
            .unwrap();
    assert_eq!(json["lens"]["f_number"], 1.4);
    let o = shutter(&["scene", "nope", "-o", &s(dir.path())]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("rotor"));
}
