//! The truth scenes: deterministic files, exact motion, converged references.

use shutter::lab::metrics::{changed_region, rmse};
use shutter::lab::truth::render::{render_passes, render_reference, Reference, RenderSettings};
use shutter::lab::truth::scenes::{build, SCENES};
use shutter::lab::truth::write::{write_scene, write_scene_of, SceneOptions, DEFAULT_SAMPLES};

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
        // A scene with a lens adds its depth-of-field references.
        let lens = build(name, 8, 8, 1).unwrap().lens.is_some();
        let expected = if lens { 17 } else { 13 };
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

/// What a pixel of a written scene should hold, worked out by the test from the scene's
/// description (not from the code that writes it).
enum Seen {
    /// On an edge, within rounding of either side: not checked.
    Unsure,
    /// A surface that does not move on screen: p(−1) = p(+1) = the pixel centre, exactly.
    Still,
    /// A surface that moves: where the point seen at the pixel centre is at t − 1 and t + 1.
    Moving { prev: (f64, f64), next: (f64, f64) },
}

/// `(x, y)` turned by `angle` radians about `about` (x right, y down: from +x towards +y, as
/// the scenes spin).
fn turned((x, y): (f64, f64), about: (f64, f64), angle: f64) -> (f64, f64) {
    let (dx, dy) = (x - about.0, y - about.1);
    let (s, c) = angle.sin_cos();
    (about.0 + c * dx - s * dy, about.1 + s * dx + c * dy)
}

/// Whether `value` is within rounding of an edge at `edge`.
fn on_edge(value: f64, edge: f64) -> bool {
    close(value, edge, 1e-6)
}

/// Frame `frame` (scene time `frame − 1`) of scene `name` at `w`×`h` as `shutter scene`
/// writes it, read back by exr's own reader; checks every pixel's depth (when `depth` gives
/// one), velocity, p(−1) and p(+1) against `seen` (and `depth`) of its centre. Returns how
/// many pixels moved and how many were still.
fn check_written_motion(
    name: &str,
    (w, h): (usize, usize),
    frame: usize,
    seen: impl Fn((f64, f64)) -> Seen,
    depth: impl Fn((f64, f64)) -> Option<f32>,
) -> (usize, usize) {
    let dir = small_scene(name, w, h, frame, 1);
    let read = |role: &str| read_exr_reference(&dir.path().join(format!("{role}.{frame:04}.exr")));
    let (z, v, prev, next) = (read("depth"), read("velocity"), read("prev"), read("next"));
    let plane = |file: &[(String, Vec<f32>)], name: &str| channel(file, name).to_vec();
    let z = plane(&z, "Z");
    let (vx, vy) = (plane(&v, "X"), plane(&v, "Y"));
    let (px, py) = (plane(&prev, "X"), plane(&prev, "Y"));
    let (nx, ny) = (plane(&next, "X"), plane(&next, "Y"));
    let (mut moving, mut still) = (0, 0);
    for i in 0..w * h {
        let p = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
        let at = format!("{name} frame {frame}, pixel {p:?}");
        if let Some(expected) = depth(p) {
            assert_eq!(z[i], expected, "{at}: depth");
        }
        let got = [vx[i], vy[i], px[i], py[i], nx[i], ny[i]];
        match seen(p) {
            Seen::Unsure => {}
            Seen::Still => {
                let centre = [0.0, 0.0, p.0, p.1, p.0, p.1].map(|c| c as f32);
                assert_eq!(got, centre, "{at}: still (v, prev, next)");
                still += 1;
            }
            Seen::Moving { prev, next } => {
                // The canonical velocity is p(0) − p(−1), in pixels per frame.
                let expected = [p.0 - prev.0, p.1 - prev.1, prev.0, prev.1, next.0, next.1];
                let expected = expected.map(|c| c as f32);
                assert!(
                    got.iter().zip(&expected).all(|(&g, &e)| close(g, e, 1e-3)),
                    "{at}: moving (v, prev, next) {got:?}, expected {expected:?}"
                );
                moving += 1;
            }
        }
    }
    (moving, still)
}

/// The rotor's hub and four blades turn 0.35 rad per frame about the frame's centre; the
/// wall behind is still. Checked on frame 2 (time 1, the blades a step past their start), so
/// a sign, a scale or an offset of the frame or of the times ∓1 in the writer fails.
#[test]
fn rotor_passes_turn_about_the_centre_at_the_spin_of_the_scene() {
    let (w, h) = (128, 72);
    let u = h as f64 / 360.0;
    let centre = (w as f64 / 2.0, h as f64 / 2.0);
    let (spin, time) = (0.35, 1.0);
    let (hub, length, root, tip) = (22.0 * u, 130.0 * u, 34.0 * u, 18.0 * u);
    // Which surface a point shows: Some(depth), or None on an edge.
    let surface = |p: (f64, f64)| -> Option<f32> {
        let r = (p.0 - centre.0).hypot(p.1 - centre.1);
        if on_edge(r, hub) {
            return None;
        }
        if r < hub {
            return Some(4.9);
        }
        let mut on_blade = false;
        for k in 0..4 {
            // The point in blade k's frame: the blade lies along +x from the centre.
            let angle = k as f64 * std::f64::consts::TAU / 4.0 + spin * time;
            let (x, y) = turned(p, centre, -angle);
            let (x, y) = (x - centre.0, y - centre.1);
            let half = 0.5 * (root + (tip - root) * x / length);
            if on_edge(x, 0.0) || on_edge(x, length) || on_edge(y.abs(), half) {
                return None;
            }
            on_blade |= (0.0..length).contains(&x) && y.abs() < half;
        }
        Some(if on_blade { 5.0 } else { 50.0 })
    };
    let seen = |p| match surface(p) {
        None => Seen::Unsure,
        Some(50.0) => Seen::Still,
        Some(_) => Seen::Moving {
            prev: turned(p, centre, -spin),
            next: turned(p, centre, spin),
        },
    };
    let (moving, still) = check_written_motion("rotor", (w, h), 2, seen, surface);
    // Every pixel but the few on an edge was checked (500 on the blades and 8716 on the
    // wall, measured).
    assert!(
        moving > 450 && still > 8500,
        "{moving} moving, {still} still"
    );
}

/// `pan`: the camera pans 10 px per frame (at 640 wide) to the left while tracking a disc of
/// radius 60 px at the centre: the disc is still on screen, everything else (fixed in the
/// world) moves 10 px per frame to the left. `zoom`: the camera zooms by e^0.05 per frame
/// about the centre, and every point moves away from the centre by that factor per frame
/// (so p(+1) − p(0) is longer than p(0) − p(−1): a writer that made one from the other
/// fails).
#[test]
fn pan_and_zoom_passes_follow_the_camera() {
    let (w, h) = (128, 72);
    let u = h as f64 / 360.0;
    let centre = (w as f64 / 2.0, h as f64 / 2.0);
    let (pan, disc) = (10.0 * u, 60.0 * u);
    let seen = |p: (f64, f64)| {
        let r = (p.0 - centre.0).hypot(p.1 - centre.1);
        if on_edge(r, disc) {
            Seen::Unsure
        } else if r < disc {
            Seen::Still
        } else {
            Seen::Moving {
                prev: (p.0 + pan, p.1),
                next: (p.0 - pan, p.1),
            }
        }
    };
    let (moving, still) = check_written_motion("pan", (w, h), 2, seen, |_| None);
    // The disc covers π·12² ≈ 452 pixels.
    assert!(
        moving > 8700 && still > 440,
        "pan: {moving} moving, {still} still"
    );
    let zoom = 0.05f64;
    let scaled = |p: (f64, f64), by: f64| {
        (
            centre.0 + by * (p.0 - centre.0),
            centre.1 + by * (p.1 - centre.1),
        )
    };
    let seen = |p| Seen::Moving {
        prev: scaled(p, (-zoom).exp()),
        next: scaled(p, zoom.exp()),
    };
    let (moving, _) = check_written_motion("zoom", (w, h), 2, seen, |_| None);
    assert_eq!(moving, w * h);
}

/// The reference with N and 2N samples must differ ten times less than the error of the
/// unblurred frame (`none`) over the region that blur changes. (reconstruct's errors on pan
/// and zoom are only 3–5 times the reference noise at 320×180: BENCHMARKS.md.) 256×144 keeps
/// the test short; `cargo run --release --example convergence -- 256 144 1024` prints the
/// table for every scene (BENCHMARKS.md).
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
    assert!(!dir.path().join("layers.0002.exr").exists());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("scene.json")).unwrap())
            .unwrap();
    assert_eq!(json["lens"]["f_number"], 1.4);
    let o = shutter(&["scene", "nope", "-o", &s(dir.path())]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("rotor"));
}

/// `--layers` adds `layers.####.exr`, Blender's naming of a multilayer render with the view
/// layers FG and BG, and scene.json names it.
#[test]
fn scene_command_writes_the_view_layers_with_layers() {
    let dir = tempfile::tempdir().unwrap();
    let o = shutter(&[
        "scene",
        "crossing",
        "-o",
        &s(dir.path()),
        "--size",
        "40x24",
        "--samples",
        "4",
        "--frames",
        "2",
        "--layers",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let file = read_exr_reference(&dir.path().join("layers.0002.exr"));
    let mut names: Vec<&str> = file.iter().map(|(n, _)| n.as_str()).collect();
    names.sort();
    let mut expected = Vec::new();
    for layer in ["BG", "FG"] {
        for pass in [
            "Combined.A",
            "Combined.B",
            "Combined.G",
            "Combined.R",
            "Depth.Z",
            "Vector.W",
            "Vector.X",
            "Vector.Y",
            "Vector.Z",
        ] {
            expected.push(format!("{layer}.{pass}"));
        }
    }
    assert_eq!(names, expected);
    // The background is opaque and 50 away; FG pixels that see nothing are transparent, at
    // Blender's 1e10, still.
    assert!(channel(&file, "BG.Combined.A").iter().all(|&a| a == 1.0));
    assert!(channel(&file, "BG.Depth.Z").iter().all(|&z| z == 50.0));
    let (a, z, x) = (
        channel(&file, "FG.Combined.A"),
        channel(&file, "FG.Depth.Z"),
        channel(&file, "FG.Vector.X"),
    );
    let empty: Vec<usize> = (0..a.len()).filter(|&k| a[k] == 0.0).collect();
    assert!(!empty.is_empty() && empty.len() < a.len());
    assert!(empty.iter().all(|&k| z[k] == 1e10 && x[k] == 0.0));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("scene.json")).unwrap())
            .unwrap();
    assert!(
        json["files"]
            .as_array()
            .unwrap()
            .iter()
            .any(|f| f[0] == "layers" && f[1] == "layers.####.exr"),
        "{json}"
    );
    // The FG layer's own reference: premultiplied over nothing; where every sample hit a
    // shape, the very colour of the scene's reference (the same samples), and empty where
    // none did.
    let fg = read_exr_reference(&dir.path().join("reference_fg.0002.exr"));
    let whole = read_exr_reference(&dir.path().join("reference.0002.exr"));
    let a = channel(&fg, "A");
    assert!(a.contains(&0.0) && a.contains(&1.0));
    for c in ["R", "G", "B"] {
        let (fg, whole) = (channel(&fg, c), channel(&whole, c));
        for k in 0..a.len() {
            assert!(
                (0.0..=1.0).contains(&a[k]) && fg[k] <= a[k] + 1e-6,
                "{c} at {k}"
            );
            assert!(
                a[k] < 1.0 || fg[k] == whole[k],
                "{c} at {k}: {} {}",
                fg[k],
                whole[k]
            );
        }
    }
    // The BG layer's own reference: opaque, and where no sample hit a shape (the FG's is
    // empty) the very colour of the scene's reference.
    let bg = read_exr_reference(&dir.path().join("reference_bg.0002.exr"));
    assert!(channel(&bg, "A").iter().all(|&v| v == 1.0));
    for c in ["R", "G", "B"] {
        let (bg, whole) = (channel(&bg, c), channel(&whole, c));
        assert!((0..a.len()).all(|k| a[k] > 0.0 || bg[k] == whole[k]), "{c}");
        assert!(
            (0..a.len()).any(|k| a[k] == 1.0 && bg[k] != whole[k]),
            "{c}"
        );
    }
    let files = json["files"].as_array().unwrap();
    assert!(["reference_fg", "reference_bg"]
        .iter()
        .all(|role| files.iter().any(|f| f[0] == *role)));
}

/// The BG layer, read through `--preset blender --layer BG`, blurs as the canonical
/// single-layer passes of the same scene with no FG at all: so Blender's Vector (y up,
/// `p(−1) − p(0)` in X, Y and `p(0) − p(+1)` in Z, W) is written the way the preset reads
/// it. The camera pans diagonally and zooms, so a wrong sign of either y, or Z, W taken for
/// X, Y (the zoom makes p(+1) − p(0) longer than p(0) − p(−1)), changes the blur; every
/// algorithm runs, scatter with the curves through p(−1) and p(+1).
#[test]
fn blender_bg_layer_blurs_as_the_canonical_passes_of_a_scene_without_fg() {
    let (w, h) = (96, 54);
    let mut scene = build("pan", w, h, 1).unwrap();
    scene.shapes.clear();
    scene.camera.pan = glam::DVec2::new(4.0, -3.0);
    scene.camera.zoom = 0.06;
    let dir = tempfile::tempdir().unwrap();
    let options = SceneOptions {
        samples: 4,
        layers: true,
        ..SceneOptions::default()
    };
    write_scene_of(&scene, dir.path(), &options, &mut |_, _| {}).unwrap();
    let file = |role: &str| s(&dir.path().join(format!("{role}.0001.exr")));
    for algorithm in ["reconstruct", "scatter", "stretch"] {
        let canonical = dir.path().join(format!("{algorithm}_canonical.exr"));
        let o = shutter(&[
            "blur",
            "--algorithm",
            algorithm,
            "--color",
            &file("color"),
            "--depth",
            &file("depth"),
            "--velocity",
            &file("velocity"),
            "--prev",
            &file("prev"),
            "--next",
            &file("next"),
            "-o",
            &s(&canonical),
        ]);
        assert!(o.status.success(), "{algorithm}: {}", stderr(&o));
        let blender = dir.path().join(format!("{algorithm}_bg.exr"));
        let o = shutter(&[
            "blur",
            "--preset",
            "blender",
            "--layer",
            "BG",
            "--algorithm",
            algorithm,
            "--color",
            &file("layers"),
            "--beauty-only",
            "-o",
            &s(&blender),
        ]);
        assert!(o.status.success(), "{algorithm}: {}", stderr(&o));
        let (canonical, blender) = (read_exr_reference(&canonical), read_exr_reference(&blender));
        // The sharp frame, to be sure that the blur moved something.
        let sharp = read_exr_reference(&dir.path().join("color.0001.exr"));
        let mut moved = 0.0f32;
        for c in ["R", "G", "B", "A"] {
            let got = channel(&blender, &format!("BG.Combined.{c}"));
            assert_close(
                got,
                channel(&canonical, c),
                1e-4,
                &format!("{algorithm} {c}"),
            );
            let changed = got.iter().zip(channel(&sharp, c));
            moved = changed.fold(moved, |m, (a, b)| m.max((a - b).abs()));
        }
        assert!(moved > 0.05, "{algorithm}: the blur moved at most {moved}");
    }
}
