//! `shutter diff` as a CI gate.

use crate::support::*;

fn pair(dir: &std::path::Path, name: &str, w: usize, h: usize, seed: u32, offset: f32) -> String {
    let path = dir.join(name);
    write_exr(
        &path,
        w,
        h,
        vec![
            (
                "R",
                noise(w * h, seed, 0.0, 1.0)
                    .iter()
                    .map(|v| v + offset)
                    .collect(),
            ),
            ("G", noise(w * h, seed + 1, 0.0, 1.0)),
            ("B", noise(w * h, seed + 2, 0.0, 2.0)),
        ],
    );
    s(&path)
}

#[test]
fn identical_images_pass_different_ones_fail_missing_ones_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let a = pair(dir.path(), "a.exr", 40, 30, 1, 0.0);
    let b = pair(dir.path(), "b.exr", 40, 30, 1, 0.0);
    let c = pair(dir.path(), "c.exr", 40, 30, 7, 0.0);
    let o = shutter(&["diff", &a, &b, "--fail", "0"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stdout(&o).contains("rmse 0.000000"));
    let o = shutter(&["diff", &a, &c, "--fail", "0.01"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("FAIL"));
    // Could not compare: 3 (2 is a usage error, as for every command).
    let o = shutter(&["diff", &a, &s(&dir.path().join("nope.exr"))]);
    assert_eq!(o.status.code(), Some(3));
    assert!(stderr(&o).contains("missing file"));
    let small = pair(dir.path(), "small.exr", 20, 30, 1, 0.0);
    let o = shutter(&["diff", &a, &small]);
    assert_eq!(o.status.code(), Some(3));
    assert!(stderr(&o).contains("size mismatch"), "{}", stderr(&o));
}

#[test]
fn rmse_agrees_with_an_independent_computation() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (37, 23);
    let a = pair(dir.path(), "a.exr", w, h, 3, 0.0);
    let b = pair(dir.path(), "b.exr", w, h, 5, 0.25);
    let o = shutter(&["diff", &a, &b, "--json"]);
    assert_eq!(o.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let ours = report["frames"][0]["whole"]["rmse"].as_f64().unwrap();
    // Independent: straight from the files, in f64.
    let (ra, rb) = (
        read_exr_reference(std::path::Path::new(&a)),
        read_exr_reference(std::path::Path::new(&b)),
    );
    let mut sum = 0.0f64;
    for name in ["R", "G", "B"] {
        for (x, y) in channel(&ra, name).iter().zip(channel(&rb, name)) {
            sum += (*x as f64 - *y as f64).powi(2);
        }
    }
    let expected = (sum / (3 * w * h) as f64).sqrt();
    assert!(close(ours, expected, 1e-6), "{ours} vs {expected}");
    let psnr = report["frames"][0]["whole"]["psnr"].as_f64().unwrap();
    assert!(close(psnr, -20.0 * expected.log10(), 1e-4), "{psnr}");
}

#[test]
fn warn_is_reported_whenever_crossed_even_when_the_gate_passes() {
    let dir = tempfile::tempdir().unwrap();
    let a = pair(dir.path(), "a.exr", 16, 16, 1, 0.0);
    let b = pair(dir.path(), "b.exr", 16, 16, 1, 0.02);
    // RMSE is 0.02 / sqrt(3) = 0.0115: over --warn 0.01, under --fail 0.05.
    let o = shutter(&["diff", &a, &b, "--warn", "0.01", "--fail", "0.05"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(stderr(&o).contains("crosses --warn 0.01"), "{}", stderr(&o));
    let o = shutter(&["diff", &a, &b, "--warn", "0.02"]);
    assert!(!stderr(&o).contains("warn"), "{}", stderr(&o));
    // Similarity metrics gate the other way: SSIM below --fail fails.
    let o = shutter(&["diff", &a, &b, "--metric", "ssim", "--fail", "0.99999"]);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
}

#[test]
fn sequences_are_compared_frame_by_frame_with_heatmaps() {
    let dir = tempfile::tempdir().unwrap();
    for frame in 1..=3 {
        pair(dir.path(), &format!("a.{frame:04}.exr"), 24, 16, frame, 0.0);
        let offset = if frame == 2 { 0.5 } else { 0.0 };
        pair(
            dir.path(),
            &format!("b.{frame:04}.exr"),
            24,
            16,
            frame,
            offset,
        );
    }
    let p = |n: &str| format!("{}/{n}.####.exr", dir.path().display());
    let heat = format!("{}/heat/h.####.png", dir.path().display());
    let o = shutter(&[
        "diff",
        &p("a"),
        &p("b"),
        "--fail",
        "0.1",
        "--heatmap",
        &heat,
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let failed: Vec<bool> = report["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["failed"].as_bool().unwrap())
        .collect();
    assert_eq!(failed, [false, true, false]);
    for frame in 1..=3 {
        let png = image::open(dir.path().join(format!("heat/h.{frame:04}.png"))).unwrap();
        assert_eq!((png.width(), png.height()), (24, 16));
    }
}

#[test]
fn sharp_frame_adds_changed_region_scores() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (8, 8);
    let flat = |v: f32| vec![v; w * h];
    let mut changed = flat(0.5);
    changed[0] = 0.9; // one pixel differs from the sharp frame
    let write = |name: &str, r: Vec<f32>| {
        let path = dir.path().join(name);
        write_exr(
            &path,
            w,
            h,
            vec![("R", r), ("G", flat(0.5)), ("B", flat(0.5))],
        );
        s(&path)
    };
    let sharp = write("sharp.exr", flat(0.5));
    let reference = write("ref.exr", changed.clone());
    let mut test_r = changed;
    test_r[0] = 0.6;
    let test = write("test.exr", test_r);
    let o = shutter(&["diff", &reference, &test, "--sharp", &sharp, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let region = &report["frames"][0]["region"];
    assert_eq!(region["pixels"], 1);
    // One pixel, error 0.3 in one channel of three: sqrt(0.09 / 3).
    let expected = (0.09f64 / 3.0).sqrt();
    let rmse = region["rmse"].as_f64().unwrap();
    assert!(close(rmse, expected, 1e-6), "{rmse} vs {expected}");
}

/// Sizes are compared from the headers before anything is decoded (issue 30): two large
/// pictures of different sizes are a size mismatch at once, in little memory (under a 1 GB
/// address-space cap; decoding both first needed 1.5 GB). Before, both were decoded first
/// (12.5 s and 2.1 GB at the probe's size).
#[cfg(unix)]
#[test]
fn sizes_are_compared_before_anything_is_decoded() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.png"), dir.path().join("b.png"));
    image::GrayImage::new(8192, 8192).save(&a).unwrap();
    image::GrayImage::new(8192, 8000).save(&b).unwrap();
    let o = shutter_capped(1_000_000, &["diff", &s(&a), &s(&b)]);
    let err = stderr(&o);
    // diff's exit for inputs it cannot compare (README, exit codes).
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("size mismatch") && err.contains("8192x8000 but"),
        "{err}"
    );
}

/// Two 40×30 RGB images: a copy of `pair`'s noise, and the same with `edit` applied to its
/// planes (R, G, B).
fn edited(dir: &std::path::Path, edit: impl Fn(&mut [Vec<f32>; 3])) -> (String, String) {
    let (w, h) = (40, 30);
    let planes = || {
        [
            noise(w * h, 1, 0.0, 1.0),
            noise(w * h, 2, 0.0, 1.0),
            noise(w * h, 3, 0.0, 1.0),
        ]
    };
    let write = |name: &str, [r, g, b]: [Vec<f32>; 3]| {
        let path = dir.join(name);
        write_exr(&path, w, h, vec![("R", r), ("G", g), ("B", b)]);
        s(&path)
    };
    let mut changed = planes();
    edit(&mut changed);
    (
        write("golden.exr", planes()),
        write("candidate.exr", changed),
    )
}

/// A NaN in the candidate fails the gate (issue 31): it was counted, shown, then treated as
/// 0, so `--fail 0.01` passed it. `--allow-nonfinite` lets through only a NaN the reference
/// holds alike: one the candidate gained fails all the same (an outside tester's finding: it
/// passed, and the every-channel figures said `psnr inf`).
#[test]
fn a_nan_fails_the_gate_unless_allowed() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = edited(dir.path(), |p| p[1][17] = f32::NAN);
    let o = shutter(&["diff", &a, &b, "--fail", "0.01"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("1 non-finite samples"),
        "{}",
        stderr(&o)
    );
    // No gate asked for: a NaN still fails. The largest difference names where it is (an
    // outside probe: it said 0 at (0, 0) in no channel).
    let o = shutter(&["diff", &a, &b]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stdout(&o).contains("at (17, 0) G"), "{}", stdout(&o));
    let o = shutter(&["diff", &a, &b, "--json"]);
    let largest = &json(&o)["frames"][0]["largest"];
    assert_eq!(
        (largest["x"].as_i64(), largest["channel"].as_str()),
        (Some(17), Some("G"))
    );
    let o = shutter(&["diff", &a, &b, "--fail", "0.01", "--allow-nonfinite"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o)
            .contains("1 samples became or stopped being NaN or infinite, the first at (17, 0) G"),
        "{}",
        stderr(&o)
    );
    assert!(
        stdout(&o).contains("1 non-finite samples counted as 0"),
        "{}",
        stdout(&o)
    );
    // The same NaN in both: let through.
    let o = shutter(&["diff", &b, &b, "--fail", "0.01", "--allow-nonfinite"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// Where a figure is `null` in JSON (an infinite PSNR), `identical` says which way; a frame
/// that differs passes with no gate given, and a warning says that nothing gated it; a
/// difference of 1e-7 prints as such, not as 0.000000 (an outside tester's findings).
#[test]
fn identical_no_gate_and_small_differences_are_said() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = edited(dir.path(), |p| p[0][3] += 1e-6);
    let o = shutter(&["diff", &a, &a, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let same = json(&o);
    assert_eq!(same["frames"][0]["identical"], true, "{same}");
    assert!(same["frames"][0]["whole"]["psnr"].is_null(), "{same}");
    assert_eq!(same["warnings"], serde_json::json!([]), "{same}");
    let o = shutter(&["diff", &a, &b, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let differ = json(&o);
    assert_eq!(differ["frames"][0]["identical"], false, "{differ}");
    assert!(
        differ["warnings"][0]
            .as_str()
            .unwrap()
            .contains("1 of 1 frames differ and pass: no gate"),
        "{differ}"
    );
    let o = shutter(&["diff", &a, &b, "--hard-fail", "0.5"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(!stderr(&o).contains("no gate"), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(!text.contains("0.000000"), "{text}");
    assert!(text.contains("largest difference 1.00e-6"), "{text}");
}

/// A 10×10 block brightened by 0.5 (issue 31): the whole-frame RMSE (0.144 on this 40×30
/// frame; 0.0095 on the probe's larger one) can stay under a gate set for noise, but 100
/// pixels are over a per-pixel threshold; the largest difference is reported where it is.
#[test]
fn a_small_bright_block_fails_a_per_pixel_gate() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = edited(dir.path(), |p| {
        for y in 5..15 {
            for x in 20..30 {
                for plane in p.iter_mut() {
                    plane[y * 40 + x] += 0.5;
                }
            }
        }
    });
    let o = shutter(&["diff", &a, &b, "--fail", "0.2"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "the aggregate gate: {}",
        stderr(&o)
    );
    let o = shutter(&["diff", &a, &b, "--fail", "0.2", "--fail-pixel", "0.1"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o)
            .contains("100 pixels over the per-pixel gate (allowed: 0; by layer: [beauty] 100)"),
        "{}",
        stderr(&o)
    );
    let text = stdout(&o);
    assert!(text.contains("largest difference 0.5"), "{text}");
    let at = text.split("largest difference").nth(1).unwrap();
    let (x, y): (usize, usize) = {
        let inside = &at[at.find('(').unwrap() + 1..at.find(')').unwrap()];
        let mut parts = inside.split(", ").map(|v| v.parse().unwrap());
        (parts.next().unwrap(), parts.next().unwrap())
    };
    assert!((20..30).contains(&x) && (5..15).contains(&y), "{text}");
    // Allowed by count, or by share (100 of 1,200 pixels is 8.3 %).
    for allow in [["--allow-pixels", "100"], ["--fail-percent", "8.4"]] {
        let mut args = vec!["diff", &a, &b, "--fail-pixel", "0.1"];
        args.extend(allow);
        let o = shutter(&args);
        assert_eq!(o.status.code(), Some(0), "{allow:?}: {}", stderr(&o));
    }
}

/// Alpha zeroed over part of the frame, colour untouched (issue 31): RMSE is 0, but alpha is
/// compared pixel by pixel, so `--fail-pixel` fails it and the largest difference names A.
#[test]
fn an_alpha_only_change_fails_a_per_pixel_gate() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40, 30);
    let rgb = || {
        vec![
            ("R", noise(w * h, 1, 0.0, 1.0)),
            ("G", noise(w * h, 2, 0.0, 1.0)),
            ("B", noise(w * h, 3, 0.0, 1.0)),
        ]
    };
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    let mut with_alpha = rgb();
    with_alpha.push(("A", vec![1.0; w * h]));
    write_exr(&a, w, h, with_alpha);
    let mut cut = rgb();
    cut.push((
        "A",
        (0..w * h)
            .map(|i| if i < 520 { 0.0 } else { 1.0 })
            .collect(),
    ));
    write_exr(&b, w, h, cut);
    let o = shutter(&["diff", &s(&a), &s(&b), "--fail", "0"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "RMSE is of colour: {}",
        stderr(&o)
    );
    let o = shutter(&["diff", &s(&a), &s(&b), "--fail-pixel", "0.01"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("520 pixels over the per-pixel gate"),
        "{}",
        stderr(&o)
    );
    assert!(stdout(&o).contains(") A: 1 against 0"), "{}", stdout(&o));
}

/// A frame as a renderer writes one: beauty RGBA, a light layer, depth and vectors; `edit`
/// changes the named channels' planes.
fn layered(path: &std::path::Path, edit: impl Fn(&str, &mut Vec<f32>)) {
    let (w, h) = (40, 30);
    let names = [
        "R",
        "G",
        "B",
        "A",
        "diffuse.R",
        "diffuse.G",
        "diffuse.B",
        "Z",
        "velocity.X",
        "velocity.Y",
    ];
    let channels = names
        .iter()
        .enumerate()
        .map(|(i, &name)| {
            let mut plane = match name {
                "A" => vec![1.0; w * h],
                "Z" => noise(w * h, 40, 1.0, 100.0),
                _ => noise(w * h, 10 + i as u32, 0.0, 1.0),
            };
            edit(name, &mut plane);
            (name, plane)
        })
        .collect();
    write_exr(path, w, h, channels);
}

fn json(o: &std::process::Output) -> serde_json::Value {
    serde_json::from_str(&stdout(o)).unwrap_or_else(|e| panic!("{e}: {}", stdout(o)))
}

/// Every layer is compared (issue 31): a change in a light layer alone fails --fail-pixel and
/// is named in the per-layer figures; depth is gated by --data-fail-pixel (0: exact), an
/// infinite depth written alike in both is no change, a lost layer fails and an added one
/// warns.
#[test]
fn every_layer_is_compared_with_its_own_gate() {
    let dir = tempfile::tempdir().unwrap();
    let golden = dir.path().join("golden.exr");
    layered(&golden, |_, _| {});
    let g = s(&golden);

    // An AOV-only change: the beauty's figures stay 0.
    let aov = dir.path().join("aov.exr");
    layered(&aov, |name, p| {
        if name == "diffuse.G" {
            p[7 * 40 + 9] += 0.25;
        }
    });
    let o = shutter(&["diff", &g, &s(&aov), "--fail-pixel", "0.1", "--json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let report = json(&o);
    let frame = &report["frames"][0];
    assert_eq!(frame["whole"]["rmse"], 0.0, "the beauty is untouched");
    let layers = frame["layers"].as_array().unwrap();
    let names: Vec<&str> = layers
        .iter()
        .map(|l| l["layer"].as_str().unwrap())
        .collect();
    // The beauty first, then the file's order (EXR sorts channels by name).
    assert_eq!(names, ["[beauty]", "Z", "diffuse", "velocity"]);
    let diffuse = &layers[2];
    assert_eq!(diffuse["class"], "colour");
    assert_eq!(diffuse["pixels_over_fail"], 1);
    assert_eq!(diffuse["largest"]["channel"], "diffuse.G");
    assert_eq!(
        (
            diffuse["largest"]["x"].clone(),
            diffuse["largest"]["y"].clone()
        ),
        (9.into(), 7.into())
    );
    // Its RMSE over its 3 channels of 1,200 pixels, and its mean absolute error.
    let rmse = diffuse["rmse"].as_f64().unwrap();
    let d = 0.25f64;
    assert!((rmse - (d * d / 3600.0).sqrt()).abs() < 1e-6, "{rmse}");
    assert!((diffuse["mae"].as_f64().unwrap() - d / 3600.0).abs() < 1e-7);
    assert_eq!(layers[1]["class"], "data");

    // Depth off by 1e-3 on one pixel: exact fails it, a tolerance of 0.01 lets it through,
    // --fail-pixel alone (colour) does not look at it.
    let depth = dir.path().join("depth.exr");
    layered(&depth, |name, p| {
        if name == "Z" {
            p[100] += 1e-3;
        }
    });
    for (flags, code) in [
        (vec!["--fail-pixel", "0.1"], 0),
        (vec!["--data-fail-pixel", "0"], 1),
        (vec!["--data-fail-pixel", "0.01"], 0),
    ] {
        let d = s(&depth);
        let mut args = vec!["diff", &g, &d];
        args.extend(flags.iter().copied());
        let o = shutter(&args);
        assert_eq!(o.status.code(), Some(code), "{flags:?}: {}", stderr(&o));
    }

    // An infinite depth in both is no change; in one only, it fails.
    let inf_a = dir.path().join("inf_a.exr");
    let inf_b = dir.path().join("inf_b.exr");
    layered(&inf_a, |name, p| {
        if name == "Z" {
            p[5] = f32::INFINITY;
        }
    });
    layered(&inf_b, |name, p| {
        if name == "Z" {
            p[5] = f32::INFINITY;
        }
    });
    let o = shutter(&["diff", &s(&inf_a), &s(&inf_b), "--data-fail-pixel", "0"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = shutter(&["diff", &g, &s(&inf_b)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("1 non-finite samples in Z"),
        "{}",
        stderr(&o)
    );

    // A lost layer fails; an added one warns.
    let fewer = dir.path().join("fewer.exr");
    let keep = ["R", "G", "B", "A", "diffuse.R", "diffuse.G", "diffuse.B"];
    let read = read_exr_reference(&golden);
    write_exr(
        &fewer,
        40,
        30,
        read.iter()
            .filter(|(n, _)| keep.contains(&n.as_str()))
            .map(|(n, p)| (n.as_str(), p.clone()))
            .collect(),
    );
    let o = shutter(&["diff", &g, &s(&fewer)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o)
            .contains("the candidate lacks 3 channels of the reference: Z, velocity.X, velocity.Y"),
        "{}",
        stderr(&o)
    );
    let o = shutter(&["diff", &s(&fewer), &g]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: the candidate has channels the reference lacks: Z"));
    // --warn-exit makes the warning an exit code of its own.
    let o = shutter(&["diff", &s(&fewer), &g, "--warn-exit"]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
}

/// idiff's relative threshold: a sample fails only when its difference is also over R times
/// the mean magnitude of the two values (0.5 against 0.6: 0.1 / 0.55 = 0.18).
#[test]
fn a_relative_threshold_and_a_hard_limit() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    let flat = |v: f32| vec![v; 16];
    write_exr(
        &a,
        4,
        4,
        vec![("R", flat(0.5)), ("G", flat(0.5)), ("B", flat(0.5))],
    );
    let mut r = flat(0.5);
    r[5] = 0.6;
    write_exr(&b, 4, 4, vec![("R", r), ("G", flat(0.5)), ("B", flat(0.5))]);
    let (a, b) = (s(&a), s(&b));
    let diff = |gates: &[&str]| {
        let mut args = vec!["diff", a.as_str(), b.as_str(), "--fail-pixel", "0.05"];
        args.extend(gates);
        shutter(&args)
    };
    for (relative, code) in [("0.17", 1), ("0.19", 0)] {
        let o = diff(&["--fail-relative", relative]);
        assert_eq!(o.status.code(), Some(code), "{relative}: {}", stderr(&o));
    }
    // Allowed by count, but over the hard limit.
    let o = diff(&["--allow-pixels", "1"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = diff(&["--allow-pixels", "1", "--hard-fail", "0.09"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--hard-fail 0.09"), "{}", stderr(&o));
}

/// A hole in the reference sequence is warned about; a pattern that matches nothing is an
/// input not there (could not compare: 3), not a bad command line (2).
#[test]
fn sequence_holes_are_warned_and_an_empty_pattern_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    for n in [1, 2, 4] {
        pair(dir.path(), &format!("a.{n:04}.exr"), 8, 8, n, 0.0);
        pair(dir.path(), &format!("b.{n:04}.exr"), 8, 8, n, 0.0);
    }
    let (a, b) = (
        s(&dir.path().join("a.####.exr")),
        s(&dir.path().join("b.####.exr")),
    );
    let o = shutter(&["diff", &a, &b]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("has no frame 3 between 1 and 4"),
        "{}",
        stderr(&o)
    );
    let o = shutter(&["diff", &s(&dir.path().join("c.####.exr")), &b]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("no files match"), "{}", stderr(&o));
}

/// Parts of a multi-part file are matched by their names, not their order: the same layers
/// written in another order are the same image; a changed layer is named by its part.
#[test]
fn parts_are_matched_by_name() {
    use crate::support::{write_parts, Part};
    let dir = tempfile::tempdir().unwrap();
    let n = 8 * 6;
    let part = |name: &'static str, seed: u32, bump: f32| Part {
        name: Some(name),
        view: None,
        multi_view: None,
        channels: ["R", "G", "B"]
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let mut p = noise(n, seed + i as u32, 0.0, 1.0);
                p[0] += bump;
                (c.to_string(), p)
            })
            .collect(),
    };
    let write = |name: &str, order: [(&'static str, u32, f32); 3]| {
        let path = dir.path().join(name);
        write_parts(
            &path,
            (8, 6),
            order.map(|(n, seed, bump)| part(n, seed, bump)).into(),
        );
        path
    };
    let a = write(
        "a.exr",
        [("rgba", 1, 0.0), ("diffuse", 5, 0.0), ("specular", 9, 0.0)],
    );
    let b = write(
        "b.exr",
        [("rgba", 1, 0.0), ("specular", 9, 0.0), ("diffuse", 5, 0.0)],
    );
    let c = write(
        "c.exr",
        [("rgba", 1, 0.0), ("diffuse", 5, 0.5), ("specular", 9, 0.0)],
    );
    let o = shutter(&["diff", &s(&a), &s(&b), "--fail-pixel", "0", "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let layers: Vec<String> = json(&o)["frames"][0]["layers"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["layer"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(layers, ["[beauty]", "diffuse", "specular"]);
    let o = shutter(&["diff", &s(&a), &s(&c), "--fail-pixel", "0.1"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("by layer: diffuse 1)"),
        "{}",
        stderr(&o)
    );
}

/// --allow-nonfinite lets through a NaN written alike in both images, past every gate (the
/// per-pixel and hard ones included), while it is still counted; a value that became NaN is a
/// difference larger than any gate, whatever the allowances, so it fails the per-pixel and
/// hard gates though the non-finite gate is off (it passed them all before: a NaN let
/// through).
#[test]
fn allowed_nonfinite_values_alike_pass_every_gate_and_a_changed_one_fails_them() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = edited(dir.path(), |p| p[0][10] = f32::NAN);
    let both = dir.path().join("both.exr");
    std::fs::copy(&b, &both).unwrap();
    let both = s(&both);
    for gate in [["--fail-pixel", "0.1"], ["--hard-fail", "1"]] {
        let mut args = vec!["diff", &b, &both, "--allow-nonfinite", "--json"];
        args.extend(gate);
        let o = shutter(&args);
        assert_eq!(o.status.code(), Some(0), "{gate:?}: {}", stderr(&o));
        assert_eq!(json(&o)["frames"][0]["whole"]["non_finite"], 1);
        let mut args = vec!["diff", &a, &b, "--allow-nonfinite", "--json"];
        args.extend(gate);
        let o = shutter(&args);
        assert_eq!(o.status.code(), Some(1), "{gate:?}: {}", stderr(&o));
        assert_eq!(json(&o)["frames"][0]["whole"]["non_finite"], 1);
    }
    // No value gate asked for: the non-finite one, let through for values alike in both,
    // fails the NaN the candidate gained.
    let o = shutter(&["diff", &a, &b, "--allow-nonfinite"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
}

/// A NaN fails a diff wherever it is: in a data channel though both images hold it alike
/// (an infinite depth written alike is no change, a NaN never is), and in a channel only
/// the candidate has (which is not compared, but is the candidate's). Both passed before.
#[test]
fn a_nan_in_a_data_channel_of_both_or_a_channel_only_the_candidate_has_fails() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (8, 6);
    let n = w * h;
    let write = |name: &str, extra: Vec<(&str, Vec<f32>)>| {
        let path = dir.path().join(name);
        let mut channels = vec![
            ("R", vec![0.5; n]),
            ("G", vec![0.5; n]),
            ("B", vec![0.5; n]),
        ];
        channels.extend(extra);
        write_exr(&path, w, h, channels);
        s(&path)
    };
    let mut z = vec![2.0f32; n];
    z[5] = f32::NAN;
    z[6] = f32::INFINITY;
    let (za, zb) = (
        write("za.exr", vec![("Z", z.clone())]),
        write("zb.exr", vec![("Z", z)]),
    );
    let o = shutter(&["diff", &za, &zb]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("1 non-finite samples"),
        "{}",
        stderr(&o)
    );
    // The infinity alone, alike in both, is no change.
    let mut z = vec![2.0f32; n];
    z[6] = f32::INFINITY;
    let (ia, ib) = (
        write("ia.exr", vec![("Z", z.clone())]),
        write("ib.exr", vec![("Z", z)]),
    );
    let o = shutter(&["diff", &ia, &ib]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // A light layer only the candidate has, with a NaN.
    let plain = write("plain.exr", vec![]);
    let mut spec = vec![0.1f32; n];
    spec[3] = f32::NAN;
    let more = write(
        "more.exr",
        vec![
            ("spec.R", spec),
            ("spec.G", vec![0.1; n]),
            ("spec.B", vec![0.1; n]),
        ],
    );
    let o = shutter(&["diff", &plain, &more]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("1 non-finite samples in spec.R"),
        "{}",
        stderr(&o)
    );
    // Let through, non-finite values must be alike in both: the reference has no spec.R to
    // be alike in (it passed, though the help said otherwise: a review's finding).
    let o = shutter(&["diff", &plain, &more, "--allow-nonfinite"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
}

/// A part the read cannot place (its data window is not the beauty's) is named as not
/// compared, so a change in it cannot pass unseen.
#[test]
fn a_part_of_another_data_window_is_named_as_not_compared() {
    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::math::Vec2;
    use exr::meta::attribute::{IntegerBounds, Text};
    use exr::meta::header::{ImageAttributes, LayerAttributes};
    use exr::prelude::WritableImage;
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, light: f32| {
        let layer = |part: &str, position: (i32, i32), value: f32| {
            let mut layer = Layer::new(
                (8, 6),
                LayerAttributes::named(Text::from(part)),
                Encoding::default(),
                AnyChannels::sort(
                    ["R", "G", "B"]
                        .iter()
                        .map(|c| AnyChannel::new(*c, FlatSamples::F32(vec![value; 48])))
                        .collect(),
                ),
            );
            layer.attributes.layer_position = Vec2(position.0, position.1);
            layer
        };
        let path = dir.path().join(name);
        Image::from_layers(
            ImageAttributes::new(IntegerBounds::new((0, 0), (8, 6))),
            vec![layer("rgba", (0, 0), 0.5), layer("light", (2, 1), light)],
        )
        .write()
        .to_file(&path)
        .unwrap();
        s(&path)
    };
    let (a, b) = (write("a.exr", 0.1), write("b.exr", 0.9));
    let o = shutter(&["diff", &a, &b, "--fail-pixel", "0.1"]);
    assert!(
        stderr(&o).contains("part light of") && stderr(&o).contains("not compared"),
        "{}",
        stderr(&o)
    );
    // Not compared is a warning (`--warn-exit`: 4, where it had exited 0), and a candidate
    // without the part lost it (exit 1, where it had passed). Found by an outside probe.
    let o = shutter(&["diff", &a, &b, "--warn-exit"]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    let alone = dir.path().join("alone.exr");
    let mut layer = Layer::new(
        (8, 6),
        LayerAttributes::named(Text::from("rgba")),
        Encoding::default(),
        AnyChannels::sort(
            ["R", "G", "B"]
                .iter()
                .map(|c| AnyChannel::new(*c, FlatSamples::F32(vec![0.5; 48])))
                .collect(),
        ),
    );
    layer.attributes.layer_position = Vec2(0, 0);
    Image::from_layers(
        ImageAttributes::new(IntegerBounds::new((0, 0), (8, 6))),
        vec![layer],
    )
    .write()
    .to_file(&alone)
    .unwrap();
    let o = shutter(&["diff", &a, &s(&alone), "--json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let missing = json(&o)["frames"][0]["missing_channels"].to_string();
    assert!(missing.contains("part light"), "{missing}");
}

/// The same pixels at another place are another picture: a data window moved by (5, 3) px, or
/// another display window, is a size mismatch (exit 3; idiff fails it too). Compared index by
/// index, a misplacement read as identical (rmse 0, exit 0).
#[test]
fn pictures_whose_windows_differ_do_not_pass() {
    use shutter::frame::{Window, Windows};
    use shutter::io::exr::{write_channels, ExrOptions};
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40usize, 30usize);
    let write = |name: &str, windows: Windows| {
        let path = dir.path().join(name);
        let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        let channels = ["R", "G", "B"]
            .iter()
            .map(|c| (c.to_string(), noise(w * h, 3, 0.0, 1.0)))
            .collect();
        write_channels(file, w, h, windows, channels, ExrOptions::default()).unwrap();
        s(&path)
    };
    let display = Window {
        x: 0,
        y: 0,
        width: w,
        height: h,
    };
    let a = write("a.exr", Windows::full(w, h));
    let same = write("same.exr", Windows::full(w, h));
    let moved = write(
        "moved.exr",
        Windows {
            data_origin: (5, 3),
            display,
        },
    );
    let wider = write(
        "wider.exr",
        Windows {
            data_origin: (0, 0),
            display: Window {
                width: 64,
                height: 48,
                ..display
            },
        },
    );
    let o = shutter(&["diff", &a, &same]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    for other in [&moved, &wider] {
        let o = shutter(&["diff", &a, other]);
        assert_eq!(o.status.code(), Some(3), "{other}: {}", stderr(&o));
        assert!(stderr(&o).contains("size mismatch"), "{}", stderr(&o));
        assert!(stderr(&o).contains("data window at"), "{}", stderr(&o));
    }
}

/// Negative frames on disk are compared, named as shutter writes them (`-002`); files numbered
/// beyond ±999999999 are not frames, and the warning names one (QA: `diff` compared frame 0
/// alone of frames -2 to 0, and took `a.1000000001.exr` as a frame).
#[test]
fn negative_frames_are_compared_and_numbers_beyond_the_limit_named() {
    let dir = tempfile::tempdir().unwrap();
    for n in [-2i64, -1, 0] {
        let seed = (n + 10) as u32;
        pair(dir.path(), &format!("a.{n:04}.exr"), 8, 8, seed, 0.0);
        pair(dir.path(), &format!("b.{n:04}.exr"), 8, 8, seed, 0.0);
    }
    pair(dir.path(), "a.1000000001.exr", 8, 8, 1, 0.0);
    let (a, b) = (
        s(&dir.path().join("a.####.exr")),
        s(&dir.path().join("b.####.exr")),
    );
    let o = shutter(&["diff", &a, &b, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let frames: Vec<i64> = report["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["frame"].as_i64().unwrap())
        .collect();
    assert_eq!(frames, [-2, -1, 0]);
    let err = stderr(&o);
    assert!(
        err.contains("a.1000000001.exr") && err.contains("999999999"),
        "{err}"
    );
}

/// A small 8-bit PNG of noise, as a candidate or reference frame.
fn png(path: &std::path::Path, seed: u32) {
    let values = noise(12 * 8 * 3, seed, 0.0, 255.0);
    let bytes: Vec<u8> = values.iter().map(|v| *v as u8).collect();
    image::RgbImage::from_raw(12, 8, bytes)
        .unwrap()
        .save(path)
        .unwrap();
}

/// `--heatmap` naming an input (QA): `--heatmap a.exr` replaced the reference with PNG bytes
/// and exited 0, and a heatmap pattern over the candidate's replaced every candidate frame.
/// Refused before anything is written, as blur refuses an `-o` that names an input (the same
/// check: the same path, another spelling, a symbolic or a hard link), with diff's code for
/// an output that cannot be written (3); a name that is not `.png` is a usage error (2).
#[test]
fn a_heatmap_that_names_an_input_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let a = pair(dir.path(), "a.exr", 12, 8, 1, 0.0);
    let b = pair(dir.path(), "b.exr", 12, 8, 2, 0.0);
    let before = std::fs::read(&a).unwrap();
    let o = shutter(&["diff", &a, &b, "--heatmap", &a]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains(".png"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&a).unwrap(), before);
    let elsewhere = s(&dir.path().join("heat.exr"));
    let o = shutter(&["diff", &a, &b, "--heatmap", &elsewhere]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!dir.path().join("heat.exr").exists());

    // PNG inputs, where the extension alone does not tell.
    let (pa, pb) = (dir.path().join("a.png"), dir.path().join("b.png"));
    png(&pa, 3);
    png(&pb, 4);
    #[cfg(unix)]
    {
        std::os::unix::fs::symlink(&pa, dir.path().join("soft.png")).unwrap();
        std::fs::hard_link(&pb, dir.path().join("hard.png")).unwrap();
    }
    let mut targets = vec![
        s(&pa),
        s(&pb),
        format!("{}/./b.png", dir.path().display()),
        format!("{}/sub/../a.png", dir.path().display()),
    ];
    std::fs::create_dir(dir.path().join("sub")).unwrap();
    if cfg!(unix) {
        targets.push(s(&dir.path().join("soft.png")));
        targets.push(s(&dir.path().join("hard.png")));
    }
    let originals = (std::fs::read(&pa).unwrap(), std::fs::read(&pb).unwrap());
    for target in &targets {
        for idiff in [false, true] {
            let mut args = vec!["diff", pa.to_str().unwrap(), pb.to_str().unwrap()];
            args.extend(["--heatmap", target]);
            if idiff {
                args.push("--idiff");
            }
            let o = shutter(&args);
            let code = if idiff { 4 } else { 3 };
            assert_eq!(o.status.code(), Some(code), "{target}: {}", stderr(&o));
            assert!(
                stderr(&o).contains("overwrite the input"),
                "{target}: {}",
                stderr(&o)
            );
            assert!(stderr(&o).contains("--heatmap"), "{}", stderr(&o));
            let now = (std::fs::read(&pa).unwrap(), std::fs::read(&pb).unwrap());
            assert!(now == originals, "{target} replaced an input");
        }
    }

    // Sequences: a heatmap pattern over the candidate's frames, or over the reference's
    // another way spelt; none of them is written.
    let seq = dir.path().join("seq");
    std::fs::create_dir(&seq).unwrap();
    for frame in 1..=3 {
        png(&seq.join(format!("r.{frame:04}.png")), 10 + frame);
        png(&seq.join(format!("t.{frame:04}.png")), 20 + frame);
    }
    let before = snapshot(&seq);
    let bytes: Vec<Vec<u8>> = (1..=3)
        .map(|f| std::fs::read(seq.join(format!("t.{f:04}.png"))).unwrap())
        .collect();
    let (r, t) = (
        format!("{}/r.####.png", seq.display()),
        format!("{}/t.####.png", seq.display()),
    );
    for heat in [t.clone(), format!("{}/./r.%04d.png", seq.display())] {
        let o = shutter(&["diff", &r, &t, "--heatmap", &heat, "--json"]);
        assert_eq!(o.status.code(), Some(3), "{heat}: {}", stderr(&o));
        assert!(stderr(&o).contains("overwrite the input"), "{}", stderr(&o));
        let error: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(error["error"]["problems"][0]["kind"], "output", "{error}");
        assert_eq!(snapshot(&seq), before, "{heat}");
    }
    for (f, expected) in (1..=3).zip(&bytes) {
        assert_eq!(
            &std::fs::read(seq.join(format!("t.{f:04}.png"))).unwrap(),
            expected
        );
    }
    // A heatmap elsewhere is written as before.
    let heat = format!("{}/h.####.png", dir.path().display());
    let o = shutter(&["diff", &r, &t, "--heatmap", &heat]);
    assert!(matches!(o.status.code(), Some(0 | 1)), "{}", stderr(&o));
    assert!(dir.path().join("h.0002.png").exists());
}

/// A FIFO where `--heatmap` or one of `--report`'s files would go (an outside probe: each
/// was replaced by a regular file, exit 0, where blur's `-o` refuses "something that is not
/// a file"): refused before anything is written, with diff's code for an output that cannot
/// be written (3), naming the file and the flag; the FIFO stays a FIFO.
#[cfg(unix)]
#[test]
fn a_fifo_where_a_heatmap_or_report_would_go_is_refused_before_anything_is_written() {
    use std::os::unix::fs::FileTypeExt;
    let dir = tempfile::tempdir().unwrap();
    let a = pair(dir.path(), "a.exr", 12, 8, 1, 0.0);
    let b = pair(dir.path(), "b.exr", 12, 8, 2, 0.0);
    let mkfifo = |path: &std::path::Path| {
        let status = std::process::Command::new("mkfifo").arg(path).status();
        assert!(status.unwrap().success(), "mkfifo {}", path.display());
    };
    let heat = dir.path().join("h.png");
    mkfifo(&heat);
    let report = dir.path().join("rep");
    std::fs::create_dir(&report).unwrap();
    let page = report.join("index.html");
    mkfifo(&page);
    let elsewhere = dir.path().join("ok.png");
    let (heat_s, report_s, elsewhere_s) = (s(&heat), s(&report), s(&elsewhere));
    let cases: [(Vec<&str>, &std::path::Path, &str); 2] = [
        (vec!["--heatmap", &heat_s], &heat, "--heatmap"),
        (
            vec!["--report", &report_s, "--heatmap", &elsewhere_s],
            &page,
            "--report",
        ),
    ];
    for (extra, fifo, flag) in cases {
        let o = shutter(&[&["diff", &a, &b][..], &extra].concat());
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(3), "{flag}: {err}");
        assert!(
            err.contains(&s(fifo)) && err.contains("not a file") && err.contains(flag),
            "{err}"
        );
        let kind = std::fs::symlink_metadata(fifo).unwrap().file_type();
        assert!(kind.is_fifo(), "{} was replaced", fifo.display());
        assert!(!elsewhere.exists(), "a heatmap was written");
        assert!(!report.join("thumbs").exists(), "thumbnails were written");
        assert!(
            !report.join("report.json").exists(),
            "report.json was written"
        );
    }
}

/// An EXR of grey R, G, B (f32) and an object ID `id` (u32) holding `ids`.
fn ids_exr(path: &std::path::Path, w: usize, h: usize, ids: Vec<u32>) {
    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::meta::header::LayerAttributes;
    use exr::prelude::WritableImage;
    let grey = |name: &str| AnyChannel::new(name, FlatSamples::F32(vec![0.5; w * h]));
    let channels = vec![
        grey("R"),
        grey("G"),
        grey("B"),
        AnyChannel::new("id", FlatSamples::U32(ids)),
    ];
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(channels.into()),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
}

#[test]
fn u32_ids_over_2_pow_24_are_compared_and_printed_as_integers() {
    // 16777217 and 16777216 are one f32 (2²⁴); as IDs they are two objects.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (8, 4);
    let mut ids = vec![1000u32; w * h];
    ids[w + 2] = 16_777_217;
    ids[2 * w + 3] = 4_000_000_001;
    let (a, b, c) = (
        dir.path().join("a.exr"),
        dir.path().join("b.exr"),
        dir.path().join("c.exr"),
    );
    ids_exr(&a, w, h, ids.clone());
    ids_exr(&c, w, h, ids.clone());
    ids[w + 2] = 16_777_216;
    ids_exr(&b, w, h, ids);
    let out = shutter(&["diff", &s(&a), &s(&b), "--data-fail-pixel", "0"]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stdout(&out)
            .contains("largest difference 1.000000 at (2, 1) id: 16777217 against 16777216"),
        "{}",
        stdout(&out)
    );
    let report = dir.path().join("report");
    shutter(&["diff", &s(&a), &s(&b), "--report", &s(&report)]);
    let page = std::fs::read_to_string(report.join("index.html")).unwrap();
    assert!(page.contains("id: 16777217 against 16777216"), "{page}");
    let same = shutter(&["diff", &s(&a), &s(&c), "--data-fail-pixel", "0"]);
    assert_eq!(same.status.code(), Some(0), "{}", stderr(&same));
}

/// Files as Blender writes them, a part a pass: two view layers (`Main`, `Second`), or two
/// views of one (`ViewLayer.Combined-left`, view `left`). `diff` compares them in the view
/// layer `--layer` names (QA: it had no `--layer`, and stopped at "choose one with
/// --layer"). A stereo file is compared in every view the reference holds, each an entry
/// of its own named by its view, so a change confined to the right eye fails the gate (it
/// had passed, with a warning, comparing the default view alone); `--view` compares one; a
/// candidate without a view of the reference is refused, one with a view more is warned.
#[test]
fn blender_files_of_view_layers_and_views_are_compared_in_the_one_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (w, h) = (24, 16);
    let n = w * h;
    let pass = |prefix: &str, seed: u32, offset: f32| -> Vec<(String, Vec<f32>)> {
        let mut channels = vec![(format!("{prefix}.Combined.A"), vec![1.0; n])];
        for (i, c) in ["R", "G", "B"].into_iter().enumerate() {
            let plane = noise(n, seed + i as u32, 0.0, 1.0);
            let plane = plane.iter().map(|v| v + offset).collect();
            channels.push((format!("{prefix}.Combined.{c}"), plane));
        }
        channels
    };
    let part = |name: &'static str, view, channels| Part {
        name: Some(name),
        view,
        multi_view: None,
        channels,
    };
    // Two view layers; in b, Main's beauty is brighter.
    for (file, offset) in [("layers_a.exr", 0.0), ("layers_b.exr", 0.25)] {
        let parts = vec![
            part("Main.Combined", None, pass("Main", 1, offset)),
            part("Second.Combined", None, pass("Second", 9, 0.0)),
        ];
        write_parts(&d.join(file), (w, h), parts);
    }
    let diff = |a: &str, b: &str, extra: &[&str]| {
        let (a, b) = (s(&d.join(a)), s(&d.join(b)));
        let mut args = vec!["diff", "--preset", "blender", "--fail", "0.01", &a, &b];
        args.extend(extra);
        shutter(&args)
    };
    let o = diff("layers_a.exr", "layers_b.exr", &[]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("--layer"), "{}", stderr(&o));
    let o = diff("layers_a.exr", "layers_b.exr", &["--layer", "Main"]);
    assert_eq!(o.status.code(), Some(1), "Main differs: {}", stderr(&o));
    let o = diff("layers_a.exr", "layers_a.exr", &["--layer", "Main"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // A file of no views: its entry names none (the JSON as it was).
    let o = diff(
        "layers_a.exr",
        "layers_b.exr",
        &["--layer", "Main", "--json"],
    );
    let report = json(&o);
    assert_eq!(report["frames"].as_array().unwrap().len(), 1, "{report}");
    assert!(report["frames"][0].get("view").is_none(), "{report}");
    assert!(report["frames"][0].get("extra_views").is_none(), "{report}");
    assert!(!stdout(&diff("layers_a.exr", "layers_b.exr", &["--layer", "Main"])).contains("view"));

    // Two views (a third in views_c); in b and c, the right view is brighter by 0.25.
    let stereo = |file: &str, offset: f32, views: &[&'static str]| {
        let parts = views
            .iter()
            .map(|&view| {
                let (name, seed, offset) = match view {
                    "left" => ("ViewLayer.Combined-left", 1, 0.0),
                    "right" => ("ViewLayer.Combined-right", 5, offset),
                    _ => ("ViewLayer.Combined-centre", 13, 0.0),
                };
                part(name, Some(view), pass("ViewLayer", seed, offset))
            })
            .collect();
        write_parts(&d.join(file), (w, h), parts);
    };
    stereo("views_a.exr", 0.0, &["left", "right"]);
    stereo("views_b.exr", 0.25, &["left", "right"]);
    stereo("views_c.exr", 0.25, &["left", "right", "centre"]);
    stereo("views_left.exr", 0.0, &["left"]);
    let o = diff("views_a.exr", "views_b.exr", &[]);
    assert_eq!(o.status.code(), Some(1), "right differs: {}", stderr(&o));
    let said = stderr(&o);
    assert!(!said.contains("holds the views"), "{said}");
    assert!(
        said.contains("FAIL") && said.contains("view right"),
        "{said}"
    );
    // Each line that names an entry names its view: left's figures are 0, right's are not.
    let text = stdout(&o);
    assert!(text.contains("view left: rmse 0.000000 "), "{text}");
    assert!(text.contains("view right: rmse 0.250000 "), "{text}");
    assert!(text.contains("worst rmse: 0.250000 over 2 views"), "{text}");
    let o = diff("views_a.exr", "views_b.exr", &["--json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let report = json(&o);
    let frames = report["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2, "{report}");
    assert_eq!(
        (&frames[0]["view"], &frames[0]["failed"]),
        (&serde_json::json!("left"), &serde_json::json!(false)),
        "{report}"
    );
    assert_eq!(
        (&frames[1]["view"], &frames[1]["failed"]),
        (&serde_json::json!("right"), &serde_json::json!(true)),
        "{report}"
    );
    assert!(
        (frames[1]["value"].as_f64().unwrap() - 0.25).abs() < 1e-5,
        "{report}"
    );
    assert!(
        (report["worst"].as_f64().unwrap() - 0.25).abs() < 1e-5,
        "{report}"
    );
    assert_eq!(report["failed"], true, "{report}");
    // One view asked for: that view alone, as before.
    let o = diff("views_a.exr", "views_b.exr", &["--view", "left"]);
    assert_eq!(o.status.code(), Some(0), "left is the same: {}", stderr(&o));
    assert!(!stderr(&o).contains("holds the views"), "{}", stderr(&o));
    let o = diff("views_a.exr", "views_b.exr", &["--view", "right", "--json"]);
    assert_eq!(o.status.code(), Some(1), "right differs: {}", stderr(&o));
    let report = json(&o);
    assert_eq!(report["frames"].as_array().unwrap().len(), 1, "{report}");
    assert_eq!(report["frames"][0]["view"], "right", "{report}");
    // Each view's heatmap and thumbnails under a name of its own: left's black (no
    // difference), right's not.
    let heat = d.join("heat.png");
    let page = d.join("page");
    let o = diff(
        "views_a.exr",
        "views_b.exr",
        &["--heatmap", &s(&heat), "--report", &s(&page)],
    );
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!heat.exists());
    let (left, right) = (
        std::fs::read(d.join("heat.left.png")).unwrap(),
        std::fs::read(d.join("heat.right.png")).unwrap(),
    );
    assert_ne!(left, right);
    for view in ["left", "right"] {
        for image in ["reference", "candidate", "heatmap"] {
            let thumb = page.join(format!("thumbs/still-{view}-{image}.png"));
            assert!(thumb.exists(), "{thumb:?}");
        }
    }
    let html = std::fs::read_to_string(page.join("index.html")).unwrap();
    assert!(html.contains("id=\"frame-still-right\""), "{html}");
    // A candidate without the right view is refused, naming it, the file and the frame.
    for frame in ["sa.0007.exr", "sb.0007.exr"] {
        let from = if frame.starts_with("sa") {
            "views_a.exr"
        } else {
            "views_left.exr"
        };
        std::fs::copy(d.join(from), d.join(frame)).unwrap();
    }
    let o = diff("sa.####.exr", "sb.####.exr", &[]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let said = stderr(&o);
    assert!(
        said.contains("sb.0007.exr") && said.contains("frame 7") && said.contains("right"),
        "{said}"
    );
    // A candidate of no views, its one picture the reference's left view.
    let mono = vec![part("ViewLayer.Combined", None, pass("ViewLayer", 1, 0.0))];
    write_parts(&d.join("mono.exr"), (w, h), mono);
    let o = diff("views_a.exr", "mono.exr", &[]);
    assert_eq!(o.status.code(), Some(3), "no views at all: {}", stderr(&o));
    assert!(stderr(&o).contains("mono.exr"), "{}", stderr(&o));
    // With --idiff: could not compare (idiff's 4).
    let o = diff("sa.####.exr", "sb.####.exr", &["--idiff"]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    // A candidate with a view more: compared in the reference's views, the third warned.
    let o = diff("views_b.exr", "views_c.exr", &["--warn-exit", "--json"]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    let report = json(&o);
    assert_eq!(report["frames"].as_array().unwrap().len(), 2, "{report}");
    assert_eq!(
        report["frames"][0]["extra_views"],
        serde_json::json!(["centre"])
    );
    assert!(stderr(&o).contains("centre"), "{}", stderr(&o));
    // With --idiff, as channels the candidate adds (idiff -a fails a count that differs).
    let o = diff("views_b.exr", "views_c.exr", &["--idiff"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let o = diff("views_b.exr", "views_b.exr", &["--idiff"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// The single-part scheme (a `multiView` list, the right view's channels `right.R`): every
/// view compared as in a multi-part file, and a candidate of the left view alone refused.
#[test]
fn single_part_multi_view_files_are_compared_in_every_view() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (w, h) = (20, 12);
    let n = w * h;
    let write = |file: &str, offset: f32, views: &'static [&'static str]| {
        let mut channels = Vec::new();
        for &view in views {
            let (seed, offset) = if view == "left" {
                (3, 0.0)
            } else {
                (7, offset)
            };
            for (i, c) in ["R", "G", "B"].into_iter().enumerate() {
                let plane = noise(n, seed + i as u32, 0.0, 1.0);
                let plane = plane.iter().map(|v| v + offset).collect();
                let name = if view == "left" {
                    c.to_string()
                } else {
                    format!("{view}.{c}")
                };
                channels.push((name, plane));
            }
        }
        let path = d.join(file);
        write_views(&path, (w, h), views, channels);
        s(&path)
    };
    let a = write("a.exr", 0.0, &["left", "right"]);
    let b = write("b.exr", 0.5, &["left", "right"]);
    let left = write("left.exr", 0.0, &["left"]);
    let o = shutter(&["diff", &a, &b, "--fail", "0.01", "--json"]);
    assert_eq!(o.status.code(), Some(1), "right differs: {}", stderr(&o));
    let report = json(&o);
    let frames = report["frames"].as_array().unwrap();
    let seen: Vec<(&str, bool)> = frames
        .iter()
        .map(|f| (f["view"].as_str().unwrap(), f["failed"].as_bool().unwrap()))
        .collect();
    assert_eq!(seen, [("left", false), ("right", true)], "{report}");
    // The right view's channels are compared as the view's R, G, B.
    assert!(
        (frames[1]["value"].as_f64().unwrap() - 0.5).abs() < 1e-5,
        "{report}"
    );
    let o = shutter(&["diff", &a, &a]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = shutter(&["diff", &a, &left]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("right"), "{}", stderr(&o));
    // A reference of no views against a stereo candidate: compared in the candidate's
    // default view and warned; under --idiff, channel sets that differ, as idiff fails them
    // (exit 2: an outside probe found it passing).
    let mono = d.join("mono.exr");
    let planes = ["R", "G", "B"]
        .into_iter()
        .enumerate()
        .map(|(i, c)| (c, noise(n, 3 + i as u32, 0.0, 1.0)))
        .collect();
    write_exr(&mono, w, h, planes);
    let o = shutter(&["diff", &s(&mono), &a]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = shutter(&["diff", "--idiff", &s(&mono), &a]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[test]
fn what_reading_a_file_took_for_granted_is_warned_once_naming_the_files() {
    // `blur` warns when it reads grey from a luminance channel, or is asked for a view of
    // files that hold none; `diff` read them the same way and said nothing, so a Y-only
    // golden "matched" an RGB candidate's grey and `--view right` of files of no views
    // compared their one image, both silently. Said once a run, not once a frame.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (w, h) = (16, 10);
    for frame in 1..=3 {
        let y = noise(w * h, 5 + frame, 0.0, 1.0);
        write_exr(
            &d.join(format!("luma.{frame:04}.exr")),
            w,
            h,
            vec![("Y", y.clone())],
        );
        let rgb = vec![("R", y.clone()), ("G", y.clone()), ("B", y)];
        write_exr(&d.join(format!("grey.{frame:04}.exr")), w, h, rgb.clone());
        write_exr(&d.join(format!("copy.{frame:04}.exr")), w, h, rgb);
    }
    let (luma, grey, copy) = (
        s(&d.join("luma.####.exr")),
        s(&d.join("grey.####.exr")),
        s(&d.join("copy.####.exr")),
    );
    let o = shutter(&["diff", &luma, &grey, "--json"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report = json(&o);
    let warnings: Vec<&str> = report["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap())
        .collect();
    assert_eq!(report["frames"].as_array().unwrap().len(), 3, "{report}");
    assert_eq!(
        warnings,
        [format!(
            "{luma}: colour read from the luminance channel Y as grey (R = G = B = Y): the \
             file holds no colour channels the preset names"
        )],
        "{report}"
    );

    let o = shutter(&["diff", &grey, &copy, "--view", "right"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains(&format!(
            "{grey} and {copy}: view right: no input file holds views"
        )),
        "{err}"
    );
    assert_eq!(err.matches("no input file holds views").count(), 1, "{err}");
}

/// A candidate that lost a channel of the reference's beauty fails (exit 1), as a lost `Z`
/// does: its alpha (it had passed, read as 1, exit 0), its B (it had stopped as "could not
/// compare", exit 3), its R, G and B read from a luminance `Y` (it had passed, warned as
/// grey). A reference without alpha against a candidate with one is warned (the candidate's
/// alpha is compared against 1). Found by an outside probe.
#[test]
fn a_candidate_that_lost_a_beauty_channel_fails() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (12, 8);
    let plane = |seed| noise(w * h, seed, 0.0, 1.0);
    let write = |name: &str, channels: &[&str]| {
        let path = dir.path().join(name);
        let planes = channels
            .iter()
            .enumerate()
            .map(|(k, &c)| (c, plane(k as u32 + 1)))
            .collect();
        write_exr(&path, w, h, planes);
        s(&path)
    };
    let rgba = write("rgba.exr", &["R", "G", "B", "A"]);
    let rgb = write("rgb.exr", &["R", "G", "B"]);
    let rga = write("rga.exr", &["R", "G", "A"]);
    let ya = write("ya.exr", &["Y", "A"]);
    for (candidate, lost) in [(&rgb, &["A"][..]), (&rga, &["B"]), (&ya, &["R", "G", "B"])] {
        let o = shutter(&["diff", &rgba, candidate, "--json"]);
        assert_eq!(o.status.code(), Some(1), "{candidate}: {}", stderr(&o));
        let report = json(&o);
        let missing = &report["frames"][0]["missing_channels"];
        for name in lost {
            assert!(
                missing.as_array().unwrap().iter().any(|m| m == name),
                "{candidate}: {missing} lacks {name}"
            );
        }
        assert_eq!(report["failed"], true);
    }
    let o = shutter(&["diff", &rgb, &rgba, "--json", "--warn-exit"]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    assert_eq!(json(&o)["frames"][0]["extra_channels"][0], "A");
}

/// A sequence whose candidate lacks a frame stops before anything is written (exit 3, no
/// heatmap, no report): it had written the other frames' heatmaps and thumbnails, then
/// stopped with no report. Found by an outside probe.
#[test]
fn a_frame_missing_from_the_candidate_stops_the_run_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    for n in 1..=3 {
        pair(dir.path(), &format!("a.{n:04}.exr"), 8, 6, n, 0.0);
        if n != 2 {
            pair(dir.path(), &format!("b.{n:04}.exr"), 8, 6, n, 0.0);
        }
    }
    let (a, b) = (
        format!("{}/a.####.exr", dir.path().display()),
        format!("{}/b.####.exr", dir.path().display()),
    );
    let heat = format!("{}/h.####.png", dir.path().display());
    let report = dir.path().join("report");
    let o = shutter(&[
        "diff",
        &a,
        &b,
        "--frames",
        "1-3",
        "--heatmap",
        &heat,
        "--report",
        &s(&report),
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    assert!(stderr(&o).contains("b.0002.exr"), "{}", stderr(&o));
    for n in 1..=3 {
        assert!(
            !dir.path().join(format!("h.{n:04}.png")).exists(),
            "h.{n:04}.png"
        );
    }
    assert!(!report.exists(), "a report folder was made");
}

/// The largest difference is named at its pixel in the file's coordinates (the data window's
/// origin added), as `idiff` names it: (−6, −2) in a data window from (−10, −5), where it had
/// said (4, 3). Found by an outside probe.
#[test]
fn the_largest_difference_is_named_in_the_file_s_coordinates() {
    use shutter::frame::{Window, Windows};
    use shutter::io::exr::{write_channels, ExrOptions};
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16usize, 10usize);
    let windows = Windows {
        data_origin: (-10, -5),
        display: Window {
            x: 0,
            y: 0,
            width: 8,
            height: 6,
        },
    };
    let write = |name: &str, bump: f32| {
        let path = dir.path().join(name);
        let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
        let mut g = vec![0.25; w * h];
        g[3 * w + 4] += bump;
        let channels = [("R", vec![0.5; w * h]), ("G", g), ("B", vec![0.1; w * h])]
            .into_iter()
            .map(|(c, p)| (c.to_string(), p))
            .collect();
        write_channels(file, w, h, windows, channels, ExrOptions::default()).unwrap();
        s(&path)
    };
    let (a, b) = (write("a.exr", 0.0), write("b.exr", 2.0));
    let o = shutter(&["diff", &a, &b, "--json"]);
    let report = json(&o);
    let largest = &report["frames"][0]["largest"];
    assert_eq!(
        (largest["x"].as_i64(), largest["y"].as_i64()),
        (Some(-6), Some(-2)),
        "{largest}"
    );
    let o = shutter(&["diff", &a, &b]);
    assert!(stdout(&o).contains("at (-6, -2) G"), "{}", stdout(&o));
}

/// An ID stored as u32 in the reference and as float in the candidate is compared as stored,
/// and the change of type is warned: 16777217 against 16777216 (one f32) fails
/// `--data-fail-pixel 0`, where it had passed, rounded through f32. Found by an outside
/// probe.
#[test]
fn a_u32_channel_against_a_float_one_is_compared_as_stored_and_warned() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (8, 4);
    let a = dir.path().join("a.exr");
    ids_exr(&a, w, h, vec![16_777_217; w * h]);
    let b = dir.path().join("b.exr");
    let grey = vec![0.5; w * h];
    let channels = vec![
        ("R", grey.clone()),
        ("G", grey.clone()),
        ("B", grey),
        ("id", vec![16_777_216.0; w * h]),
    ];
    write_exr(&b, w, h, channels);
    let o = shutter(&["diff", &s(&a), &s(&b), "--data-fail-pixel", "0", "--json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let report = json(&o);
    assert!(
        report["warnings"].to_string().contains("id stored as u32"),
        "{}",
        report["warnings"]
    );
    // Both values printed as they are (a review: both printed 16777216).
    let o = shutter(&["diff", &s(&a), &s(&b)]);
    assert!(
        stdout(&o).contains("16777217 against 16777216"),
        "{}",
        stdout(&o)
    );
}

/// Files that hold no colour image are compared channel by channel as data: a depth pass on
/// its own (it had stopped, "missing channel", exit 3, even against itself; `--idiff` 4), and
/// a vector pass of `X` and `Y`, whose `Y` had been read as a luminance beauty, so a change
/// to it passed `--data-fail-pixel 0` and the every-channel figures counted it three times
/// beside a made-up alpha. Their figures are idiff's: worked out here. Found by an outside
/// probe.
#[test]
fn files_of_no_colour_image_are_compared_as_data() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (12, 8);
    let z = noise(w * h, 3, 1.0, 50.0);
    let (za, zb) = (dir.path().join("za.exr"), dir.path().join("zb.exr"));
    write_exr(&za, w, h, vec![("Z", z.clone())]);
    let mut changed = z.clone();
    changed[5] += 0.001;
    write_exr(&zb, w, h, vec![("Z", changed)]);
    let o = shutter(&["diff", &s(&za), &s(&za)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = shutter(&["diff", "--idiff", &s(&za), &s(&za)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = shutter(&["diff", &s(&za), &s(&zb), "--data-fail-pixel", "0"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    // SSIM and FLIP cannot score it: their gates are not applied, and it says so (a
    // review: the file failed against itself, its unscored NaN "worse" than any gate).
    let o = shutter(&[
        "diff",
        &s(&za),
        &s(&za),
        "--metric",
        "ssim",
        "--fail",
        "0.9",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(stderr(&o).contains("not scored"), "{}", stderr(&o));
    // A Cryptomatte layer's R, G, B, A are IDs and coverage: such a file is data too.
    let crypto = dir.path().join("crypto.exr");
    let planes =
        ["R", "G", "B", "A"].map(|c| (format!("CryptoObject00.{c}"), noise(w * h, 7, 0.0, 1.0)));
    let planes = planes
        .iter()
        .map(|(n, p)| (n.as_str(), p.clone()))
        .collect();
    write_exr(&crypto, w, h, planes);
    let o = shutter(&["diff", &s(&crypto), &s(&crypto), "--data-fail-pixel", "0"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));

    let (x, y) = (noise(w * h, 4, -3.0, 3.0), noise(w * h, 5, -3.0, 3.0));
    let (va, vb) = (dir.path().join("va.exr"), dir.path().join("vb.exr"));
    write_exr(&va, w, h, vec![("X", x.clone()), ("Y", y.clone())]);
    let mut moved = y.clone();
    moved[10] += 0.5;
    write_exr(&vb, w, h, vec![("X", x), ("Y", moved)]);
    let o = shutter(&["diff", &s(&va), &s(&vb), "--data-fail-pixel", "0", "--json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let report = json(&o);
    let every = &report["frames"][0]["every_channel"];
    assert_eq!(every["channels"], 2, "{every}");
    // One sample of 2 · 96 off by 0.5.
    let samples = (2 * w * h) as f64;
    let mean = every["mean_error"].as_f64().unwrap();
    let rms = every["rms_error"].as_f64().unwrap();
    assert!((mean - 0.5 / samples).abs() < 1e-9, "{every}");
    assert!((rms - (0.25 / samples).sqrt()).abs() < 1e-9, "{every}");
    assert_eq!(report["frames"][0]["largest"]["channel"], "Y");
}

/// A file of no colour image whose parts have other data windows (a depth part, and an ID
/// part cropped to its objects): the parts at the first part's window are compared, the
/// other is named as not compared, a warning (a review: the file was refused as corrupt,
/// exit 3, even against itself).
#[test]
fn a_data_file_s_part_of_another_window_is_left_out_and_named() {
    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::math::Vec2;
    use exr::meta::attribute::{IntegerBounds, Text};
    use exr::meta::header::{ImageAttributes, LayerAttributes};
    use exr::prelude::WritableImage;
    let dir = tempfile::tempdir().unwrap();
    let layer = |part: &str, channel: &str, size: (usize, usize), at: (i32, i32)| {
        let n = size.0 * size.1;
        let samples = FlatSamples::F32(noise(n, 3, 1.0, 9.0));
        let mut layer = Layer::new(
            size,
            LayerAttributes::named(Text::from(part)),
            Encoding::default(),
            AnyChannels::sort(vec![AnyChannel::new(channel, samples)].into()),
        );
        layer.attributes.layer_position = Vec2(at.0, at.1);
        layer
    };
    let path = dir.path().join("data.exr");
    Image::from_layers(
        ImageAttributes::new(IntegerBounds::new((0, 0), (8, 6))),
        vec![
            layer("depth", "Z", (8, 6), (0, 0)),
            layer("ids", "id", (4, 2), (2, 1)),
        ],
    )
    .write()
    .to_file(&path)
    .unwrap();
    let o = shutter(&["diff", &s(&path), &s(&path), "--json", "--warn-exit"]);
    assert_eq!(o.status.code(), Some(4), "{}", stderr(&o));
    let report = json(&o);
    let warnings = report["warnings"].to_string();
    assert!(
        warnings.contains("not compared") && warnings.contains("id"),
        "{warnings}"
    );
    assert_eq!(
        report["frames"][0]["every_channel"]["channels"], 1,
        "{report}"
    );
}

/// diff's errors in diff's words (an outside tester): a file that could not be read was named
/// by blur's "color pass" (diff reads no passes), the summary said "nothing was written for
/// the frames concerned" (diff compares; it stopped before comparing anything), and one bad
/// file given as both inputs printed the same line twice.
#[test]
fn diff_s_errors_are_its_own_and_said_once() {
    let dir = tempfile::tempdir().unwrap();
    let good = pair(dir.path(), "good.exr", 12, 8, 1, 0.0);
    let bytes = std::fs::read(&good).unwrap();
    let (bad, other) = (dir.path().join("bad.exr"), dir.path().join("other.exr"));
    std::fs::write(&bad, &bytes[..40]).unwrap();
    std::fs::write(&other, &bytes[..60]).unwrap();
    let errors = |err: &str| {
        err.lines()
            .filter(|l| l.starts_with("shutter: error:"))
            .count()
    };
    let o = shutter(&["diff", &s(&bad), &s(&bad)]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let err = stderr(&o);
    assert_eq!(errors(&err), 1, "{err}");
    assert!(err.contains("bad.exr") && !err.contains("pass"), "{err}");
    assert!(!err.contains("problems found"), "{err}");
    let o = shutter(&["diff", &s(&bad), &s(&other)]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
    let err = stderr(&o);
    assert_eq!(errors(&err), 2, "{err}");
    assert!(!err.contains("pass") && !err.contains("written"), "{err}");
    assert!(
        err.contains("shutter: 2 problems found; nothing was compared"),
        "{err}"
    );
}

/// idiff's peak was printed as the f64 the f32 sample widens to ("peak 1.2999999523162842");
/// it is printed as short as reads back as the sample.
#[test]
fn the_psnr_peak_is_printed_as_the_sample_reads() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (4, 2);
    let colour = |r: f32| {
        vec![
            ("R", vec![r; w * h]),
            ("G", vec![0.5; w * h]),
            ("B", vec![0.5; w * h]),
        ]
    };
    let (a, b) = (dir.path().join("a.exr"), dir.path().join("b.exr"));
    write_exr(&a, w, h, colour(1.3));
    write_exr(&b, w, h, colour(1.2));
    let o = shutter(&["diff", &s(&a), &s(&b)]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(text.contains("(peak 1.3)"), "{text}");
    assert!(!text.contains("1.29999"), "{text}");
}

/// `--heatmap 'hm/one.####.png'` comparing two single files wrote a file named
/// `one.####.png`; as blur refuses a pattern `-o` for single inputs (and diff a heatmap that
/// is no pattern for sequences), it is refused, nothing written.
#[test]
fn a_heatmap_pattern_for_single_files_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let a = pair(dir.path(), "a.exr", 12, 8, 1, 0.0);
    let b = pair(dir.path(), "b.exr", 12, 8, 2, 0.0);
    let folder = dir.path().join("hm");
    for heatmap in ["one.####.png", "one.%04d.png"] {
        let o = shutter(&["diff", &a, &b, "--heatmap", &s(&folder.join(heatmap))]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains("--heatmap") && err.contains("single files"),
            "{err}"
        );
        assert!(!folder.exists(), "{heatmap}: something was written");
    }
    let o = shutter(&["diff", &a, &b, "--heatmap", &s(&folder.join("one.png"))]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(folder.join("one.png").exists());
}
