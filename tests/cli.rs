//! The command line as a user runs it: the "done when" cases, errors and exit codes.

use crate::support::*;

#[test]
fn none_on_separate_canonical_files_copies_rgb_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let rgba = write_canonical_frame(dir.path(), None, 37, 23);
    let out = dir.path().join("out/out.exr");
    let o = shutter(&[
        "blur",
        "--algorithm",
        "none",
        "--color",
        &s(&dir.path().join("C.exr")),
        "--depth",
        &s(&dir.path().join("Z.exr")),
        "--velocity",
        &s(&dir.path().join("V.exr")),
        "-o",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let written = read_exr_reference(&out);
    for (i, name) in ["R", "G", "B", "A"].iter().enumerate() {
        assert_exact(channel(&written, name), &rgba[i], name);
    }
    assert_eq!(written.len(), 4, "only colour is written");
}

#[test]
fn blender_multilayer_frame_with_preset_copies_rgb_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (20, 12);
    let n = w * h;
    let r = noise(n, 1, 0.0, 8.0);
    let g = noise(n, 2, 0.0, 1.0);
    let b = noise(n, 3, 0.0, 1.0);
    let path = dir.path().join("shot.exr");
    write_exr(
        &path,
        w,
        h,
        vec![
            ("RenderLayer.Combined.R", r.clone()),
            ("RenderLayer.Combined.G", g.clone()),
            ("RenderLayer.Combined.B", b.clone()),
            ("RenderLayer.Combined.A", vec![1.0; n]),
            ("RenderLayer.Depth.Z", vec![3.0; n]),
            ("RenderLayer.Vector.X", vec![0.0; n]),
            ("RenderLayer.Vector.Y", vec![0.0; n]),
            ("RenderLayer.Vector.Z", vec![0.0; n]),
            ("RenderLayer.Vector.W", vec![0.0; n]),
        ],
    );
    let out = dir.path().join("out.exr");
    let o = shutter(&[
        "blur",
        "--preset",
        "blender",
        "--color",
        &s(&path),
        "-o",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The beauty under the names it came with, and every other layer beside it.
    let written = read_exr_reference(&out);
    assert_exact(channel(&written, "RenderLayer.Combined.R"), &r, "R");
    assert_exact(channel(&written, "RenderLayer.Combined.G"), &g, "G");
    assert_exact(channel(&written, "RenderLayer.Combined.B"), &b, "B");
    assert_exact(channel(&written, "RenderLayer.Depth.Z"), &vec![3.0; n], "Z");
    assert_eq!(written.len(), 9, "every channel of the frame");
}

/// `--color`, `--depth` and `--velocity` of the shipped 3-frame canonical fixture.
fn canonical_fixture_passes() -> Vec<String> {
    let root = env!("CARGO_MANIFEST_DIR");
    ["color", "depth", "velocity"]
        .iter()
        .flat_map(|pass| {
            [
                format!("--{pass}"),
                format!("{root}/fixtures/canonical/{pass}.####.exr"),
            ]
        })
        .collect()
}

#[test]
fn shipped_fixtures_run_as_in_the_readme() {
    let dir = tempfile::tempdir().unwrap();
    let root = env!("CARGO_MANIFEST_DIR");
    // The README's first command: blurred by reconstruct, with no warning.
    let out = format!("{}/blur.####.exr", dir.path().display());
    let mut args = vec![
        "blur".to_string(),
        "--algorithm".into(),
        "reconstruct".into(),
    ];
    args.extend(canonical_fixture_passes());
    args.extend(["-o".to_string(), out]);
    let o = shutter(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    for frame in 1..=3 {
        let input = read_exr_reference(std::path::Path::new(&format!(
            "{root}/fixtures/canonical/color.{frame:04}.exr"
        )));
        let output = read_exr_reference(&dir.path().join(format!("blur.{frame:04}.exr")));
        assert!(
            channel(&output, "R") != channel(&input, "R"),
            "frame {frame} was not blurred"
        );
        assert!(channel(&output, "R").iter().all(|v| v.is_finite()));
    }
    // Without --algorithm: none, colour unchanged.
    let out = format!("{}/none.####.exr", dir.path().display());
    let mut args = vec!["blur".to_string()];
    args.extend(canonical_fixture_passes());
    args.extend(["-o".to_string(), out]);
    let o = shutter(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    for frame in 1..=3 {
        let input = read_exr_reference(std::path::Path::new(&format!(
            "{root}/fixtures/canonical/color.{frame:04}.exr"
        )));
        let output = read_exr_reference(&dir.path().join(format!("none.{frame:04}.exr")));
        for name in ["R", "G", "B", "A"] {
            assert_exact(channel(&output, name), channel(&input, name), name);
        }
    }
    let o = shutter(&[
        "blur",
        "--preset",
        "blender",
        "--color",
        &format!("{root}/fixtures/blender/shot.0001.exr"),
        "-o",
        &s(&dir.path().join("b.png")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn sequences_with_hashes_and_printf_patterns_and_frame_specs() {
    let dir = tempfile::tempdir().unwrap();
    let mut colours = Vec::new();
    for frame in 1..=5 {
        colours.push(write_canonical_frame(dir.path(), Some(frame), 9, 7));
    }
    let hashes = shutter(&[
        "blur",
        "--color",
        &format!("{}/C.####.exr", dir.path().display()),
        "--frames",
        "1-5x2",
        "-o",
        &format!("{}/a/out.####.exr", dir.path().display()),
    ]);
    assert!(hashes.status.success(), "{}", stderr(&hashes));
    let printf = shutter(&[
        "blur",
        "--color",
        &format!("{}/C.%04d.exr", dir.path().display()),
        "--frames",
        "2,4",
        "-o",
        &format!("{}/b/out.%04d.exr", dir.path().display()),
    ]);
    assert!(printf.status.success(), "{}", stderr(&printf));
    for (folder, frames) in [("a", vec![1, 3, 5]), ("b", vec![2, 4])] {
        let mut names: Vec<String> = std::fs::read_dir(dir.path().join(folder))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        let expected: Vec<String> = frames.iter().map(|f| format!("out.{f:04}.exr")).collect();
        assert_eq!(names, expected);
        for frame in frames {
            let written =
                read_exr_reference(&dir.path().join(format!("{folder}/out.{frame:04}.exr")));
            assert_exact(channel(&written, "R"), &colours[frame - 1][0], "R");
        }
    }
}

#[test]
fn frames_are_discovered_when_no_spec_is_given() {
    let dir = tempfile::tempdir().unwrap();
    for frame in [7, 8, 10] {
        write_canonical_frame(dir.path(), Some(frame), 4, 4);
    }
    let o = shutter(&[
        "blur",
        "--color",
        &format!("{}/C.####.exr", dir.path().display()),
        "-o",
        &format!("{}/out/o.####.exr", dir.path().display()),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(report["frames_written"], 3);
    assert!(dir.path().join("out/o.0010.exr").exists());
}

/// Runs a failing job into a fresh output folder (holding one older file) and checks the
/// failure: exit code 1, one line per problem naming what is given, folder untouched.
fn assert_fails_cleanly(args: &[&str], out_dir: &std::path::Path, expect: &[&str]) -> String {
    let before = snapshot(out_dir);
    let o = shutter(args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "stderr: {err}");
    for needle in expect {
        assert!(err.contains(needle), "'{needle}' not in: {err}");
    }
    assert_eq!(snapshot(out_dir), before, "the output folder changed");
    assert!(!err.contains("panicked"), "{err}");
    err
}

#[test]
fn missing_input_frame_fails_before_writing_anything() {
    let dir = tempfile::tempdir().unwrap();
    for frame in [1, 2, 4] {
        write_canonical_frame(dir.path(), Some(frame), 6, 5);
    }
    let out_dir = dir.path().join("out");
    std::fs::create_dir_all(&out_dir).unwrap();
    std::fs::write(out_dir.join("keep.txt"), "older work").unwrap();
    let err = assert_fails_cleanly(
        &[
            "blur",
            "--color",
            &format!("{}/C.####.exr", dir.path().display()),
            "--frames",
            "1-4",
            "-o",
            &format!("{}/o.####.exr", out_dir.display()),
        ],
        &out_dir,
        &["missing file", "C.0003.exr", "frame 3", "color"],
    );
    assert_eq!(err.lines().count(), 1, "one line: {err}");
}

#[test]
fn missing_channel_lists_the_channels_present_and_the_preset() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 6, 5);
    let only_z = dir.path().join("only_rg.exr");
    write_exr(
        &only_z,
        6,
        5,
        vec![("R", vec![0.0; 30]), ("G", vec![0.0; 30])],
    );
    let out_dir = dir.path().join("out");
    std::fs::create_dir_all(&out_dir).unwrap();
    let err = assert_fails_cleanly(
        &[
            "blur",
            "--color",
            &s(&only_z),
            "-o",
            &s(&out_dir.join("o.exr")),
        ],
        &out_dir,
        &[
            "missing channel",
            "only_rg.exr",
            "the file has G, R",
            "preset shutter",
            "color",
        ],
    );
    assert_eq!(err.lines().count(), 1, "one line: {err}");
}

#[test]
fn corrupt_and_truncated_exr_fail_before_writing_anything() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 64, 64);
    let good = std::fs::read(dir.path().join("C.exr")).unwrap();
    let out_dir = dir.path().join("out");
    std::fs::create_dir_all(&out_dir).unwrap();

    let truncated = dir.path().join("truncated.exr");
    std::fs::write(&truncated, &good[..good.len() * 2 / 3]).unwrap();
    let garbage = dir.path().join("garbage.exr");
    let mut bad = good.clone();
    bad[0] = b'x';
    std::fs::write(&garbage, &bad).unwrap();
    let header = dir.path().join("header.exr");
    std::fs::write(&header, &good[..40]).unwrap();

    for (path, name) in [
        (&truncated, "truncated.exr"),
        (&garbage, "garbage.exr"),
        (&header, "header.exr"),
    ] {
        let err = assert_fails_cleanly(
            &[
                "blur",
                "--color",
                &s(path),
                "-o",
                &s(&out_dir.join("o.exr")),
            ],
            &out_dir,
            &["corrupt file", name],
        );
        assert_eq!(err.lines().count(), 1, "one line: {err}");
    }
}

#[test]
fn all_problems_of_all_frames_are_reported_together() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), Some(1), 6, 5);
    write_canonical_frame(dir.path(), Some(3), 7, 5);
    let o = shutter(&[
        "blur",
        "--algorithm",
        "none",
        "--color",
        &format!("{}/C.####.exr", dir.path().display()),
        "--frames",
        "1-4",
        "-o",
        &format!("{}/out/o.####.exr", dir.path().display()),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(err.contains("C.0002.exr, frame 2"), "{err}");
    assert!(err.contains("C.0004.exr, frame 4"), "{err}");
    assert!(
        !dir.path().join("out").exists(),
        "no output folder is created"
    );
}

#[test]
fn size_mismatch_between_passes_is_an_error() {
    // `none` reads colour only, so the check runs through the planner with every pass needed.
    use shutter::io::passes::{plan_frame, Inputs, PlanOptions};
    use shutter::io::preset::Preset;
    use shutter::io::sequence::PathPattern;
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 6, 5);
    let small = dir.path().join("small_z.exr");
    write_exr(&small, 5, 5, vec![("Z", vec![1.0; 25])]);
    let preset = Preset::builtin("shutter").unwrap();
    let inputs = Inputs {
        color: PathPattern::parse(&s(&dir.path().join("C.exr"))).unwrap(),
        depth: Some(PathPattern::parse(&s(&small)).unwrap()),
        velocity: None,
        prev: None,
        next: None,
    };
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: shutter::Passes::ALL,
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let problems = plan_frame(&inputs, None, &options).unwrap_err();
    assert!(problems
        .iter()
        .any(|p| p.kind == shutter::ProblemKind::SizeMismatch
            && p.to_string().contains("5x5 but the color pass is 6x5")));
}

/// An argument that is not UTF-8 (a path from a Latin-1 share) is a usage error, said in one
/// line, with `--json`'s error object: it panicked (exit 101) once clap had refused it.
#[cfg(unix)]
#[test]
fn an_argument_that_is_not_utf8_is_a_usage_error_not_a_panic() {
    use std::os::unix::ffi::OsStrExt;
    let path = std::ffi::OsStr::from_bytes(b"nu\xff8/c.####.exr");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_shutter"))
        .args(["blur", "--json", "--color"])
        .arg(path)
        .args(["-o", "out.####.exr"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(report["ok"], false, "{report}");
}

/// `--json` with required arguments missing names them in the error object (an outside
/// probe: the message ended at "were not provided:"), as the line on stderr does.
#[test]
fn json_names_the_required_arguments_not_given() {
    let o = shutter(&["blur", "--json"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let message = report["error"]["message"].as_str().unwrap();
    assert!(
        message.contains("--color") && message.contains("--output"),
        "{message}"
    );
}

#[test]
fn output_equal_to_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 4, 4);
    let input = dir.path().join("C.exr");
    let before = std::fs::read(&input).unwrap();
    let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&input)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("overwrite the input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&input).unwrap(), before);
}

/// A second mount of the input folder (issue 30): the output's path differs from every
/// input's, but its folder is the input's folder (same device and inode), so writing it
/// would replace the input. Before, every colour input was replaced by its blurred frame.
/// Needs `mount --bind` (root, and a system that lets it mount): skipped with a note where
/// it cannot mount.
#[cfg(unix)]
#[test]
fn an_output_through_a_second_mount_of_the_input_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (inputs, mirror) = (dir.path().join("in"), dir.path().join("mirror"));
    std::fs::create_dir_all(&inputs).unwrap();
    std::fs::create_dir_all(&mirror).unwrap();
    for frame in 1..=2 {
        write_canonical_frame(&inputs, Some(frame), 4, 4);
    }
    let mounted = std::process::Command::new("mount")
        .args(["--bind", &s(&inputs), &s(&mirror)])
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|status| status.success());
    if !mounted {
        eprintln!("skipped: mount --bind is not allowed here (needs root)");
        return;
    }
    // Unmounted however the test ends.
    struct Unmount(std::path::PathBuf);
    impl Drop for Unmount {
        fn drop(&mut self) {
            let _ = std::process::Command::new("umount").arg(&self.0).status();
        }
    }
    let _unmount = Unmount(mirror.clone());
    let before = std::fs::read(inputs.join("C.0001.exr")).unwrap();
    let color = format!("{}/C.####.exr", inputs.display());
    let out = format!("{}/C.####.exr", mirror.display());
    let o = shutter(&["blur", "--color", &color, "-o", &out]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("overwrite the input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(inputs.join("C.0001.exr")).unwrap(), before);
}

/// An existing output that is the input under another name (a hard link) is the input.
#[cfg(unix)]
#[test]
fn an_output_that_is_a_hard_link_of_the_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 4, 4);
    let input = dir.path().join("C.exr");
    let link = dir.path().join("linked.exr");
    std::fs::hard_link(&input, &link).unwrap();
    let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&link)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("overwrite the input"), "{}", stderr(&o));
}

/// An output that is another frame's input: frame 3's colour is a link to the file frame 2
/// writes (an earlier run's output read back). Writing frame 2 would change what frame 3
/// reads, or has read (an outside probe: it did, with exit 0).
#[cfg(unix)]
#[test]
fn an_output_that_is_another_frames_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let (inputs, out_dir) = (dir.path().join("in"), dir.path().join("out"));
    std::fs::create_dir_all(&out_dir).unwrap();
    for frame in 1..=2 {
        write_canonical_frame(&inputs, Some(frame), 4, 4);
    }
    std::fs::copy(inputs.join("C.0001.exr"), out_dir.join("o.0002.exr")).unwrap();
    std::os::unix::fs::symlink(out_dir.join("o.0002.exr"), inputs.join("C.0003.exr")).unwrap();
    let before = std::fs::read(out_dir.join("o.0002.exr")).unwrap();
    let color = format!("{}/C.####.exr", inputs.display());
    let out = format!("{}/o.####.exr", out_dir.display());
    let o = shutter(&["blur", "--color", &color, "-o", &out]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("o.0002.exr, frame 2")
            && err.contains("overwrite the input")
            && err.contains("C.0003.exr"),
        "{err}"
    );
    assert_eq!(std::fs::read(out_dir.join("o.0002.exr")).unwrap(), before);
    assert!(!out_dir.join("o.0001.exr").exists(), "a frame was written");
}

#[test]
fn skip_existing_resumes_a_run() {
    let dir = tempfile::tempdir().unwrap();
    for frame in 1..=3 {
        write_canonical_frame(dir.path(), Some(frame), 4, 4);
    }
    let out = format!("{}/out/o.####.exr", dir.path().display());
    let color = format!("{}/C.####.exr", dir.path().display());
    // Frame 2 done before (a whole frame: anything else is written again, tests/lost.rs).
    let o = shutter(&["blur", "--color", &color, "-o", &out, "--frames", "2"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let done = dir.path().join("out/o.0002.exr");
    let before = std::fs::metadata(&done).unwrap().modified().unwrap();
    let o = shutter(&[
        "blur",
        "--color",
        &color,
        "-o",
        &out,
        "--skip-existing",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(report["frames_written"], 2);
    assert_eq!(report["frames_skipped"], 1);
    assert_eq!(
        std::fs::metadata(&done).unwrap().modified().unwrap(),
        before,
        "frame 2 was written again"
    );
}

/// A frame another run made with other settings is not this run's (a farm job resubmitted
/// with another algorithm over the same folder passes `--skip-existing` on every task): an
/// EXR whose `shutter/settings` differ from this run's is written again, said once a run
/// (naming both settings and how many frames), and `--dry-run` says "redo" with why. The
/// same settings again skip every frame. It skipped them all, silently, keeping the old
/// algorithm's frames.
#[test]
fn skip_existing_writes_again_frames_made_with_other_settings() {
    frames_made_with_other_settings_are_written_again("exr");
}

/// The same of pictures, which record their settings where each format keeps such text
/// (a PNG's text chunks, a TIFF's Software tag, a JPEG's comment): they recorded none, and
/// every picture another run made was kept (an outside tester's finding).
#[test]
fn skip_existing_writes_again_pictures_made_with_other_settings() {
    for ext in ["png", "tif", "jpg"] {
        frames_made_with_other_settings_are_written_again(ext);
    }
    // A PNG shutter made, blurred again: its record replaced, not carried beside the new.
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 6, 4);
    let (first, second) = (dir.path().join("a.png"), dir.path().join("b.png"));
    let color = dir.path().join("C.exr");
    let o = shutter(&["blur", "--color", &s(&color), "-o", &s(&first)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let args = [
        "blur",
        "--color",
        &s(&first),
        "--shutter",
        "0.25",
        "-o",
        &s(&second),
    ];
    let o = shutter(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    if let Some(info) = oiiotool_info(&second) {
        let records: Vec<&str> = info.lines().filter(|l| l.contains("shutter/")).collect();
        assert_eq!(records.len(), 2, "{info}");
        assert!(
            records.iter().any(|l| l.contains("--shutter 0.25")),
            "{info}"
        );
    }
}

/// The transfer 8/16-bit colour is read and written with is part of what made a picture: a
/// photo's frame made without --linear is made again by a run with it (an outside tester's
/// finding: it was kept, 74 codes off, as the record named the preset alone, whose file may
/// say `[color] transfer`). An output setting this -o cannot use (a JPEG's quality on a PNG)
/// is no part of it: a rerun giving one skips the frame.
#[test]
fn skip_existing_redoes_a_picture_made_with_the_other_transfer_alone() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 6, 4);
    let photo = dir.path().join("photo.png");
    let o = shutter(&[
        "blur",
        "--color",
        &s(&dir.path().join("C.exr")),
        "-o",
        &s(&photo),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.path().join("out.png");
    let run = |extra: &[&str]| {
        let args = ["blur", "--color", &s(&photo), "-o", &s(&out)];
        shutter(&[&args[..], extra].concat())
    };
    let o = run(&[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let action = |extra: &[&str]| {
        let dry = ["--skip-existing", "--dry-run", "--json"];
        let o = run(&[extra, &dry[..]].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        report["planned"][0].clone()
    };
    let planned = action(&["--linear"]);
    assert_eq!(planned["action"], "redo", "{planned}");
    assert!(
        planned["why"].as_str().unwrap().contains("--linear"),
        "{planned}"
    );
    // The same preset file, its transfer changed between the runs.
    let preset = dir.path().join("mine.toml");
    std::fs::write(&preset, "[color]\ntransfer = \"srgb\"\n").unwrap();
    let o = run(&["--preset", &s(&preset)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(action(&["--preset", &s(&preset)])["action"], "skip");
    std::fs::write(&preset, "[color]\ntransfer = \"linear\"\n").unwrap();
    let planned = action(&["--preset", &s(&preset)]);
    assert_eq!(planned["action"], "redo", "{planned}");
    let o = run(&[]);
    assert!(o.status.success(), "{}", stderr(&o));
    for unused in [
        &["--jpeg-quality", "50"][..],
        &["--half"],
        &["--compression", "piz"],
    ] {
        let planned = action(unused);
        assert_eq!(planned["action"], "skip", "{unused:?}: {planned}");
    }
}

/// Three frames written to `o.####.<ext>` by reconstruct, then by scatter at shutter 0.25
/// with `--skip-existing` (dry and not), then by scatter again.
fn frames_made_with_other_settings_are_written_again(ext: &str) {
    let dir = tempfile::tempdir().unwrap();
    for frame in 1..=3 {
        write_canonical_frame(dir.path(), Some(frame), 6, 4);
    }
    let d = dir.path().display();
    let (color, depth, velocity) = (
        format!("{d}/C.####.exr"),
        format!("{d}/Z.####.exr"),
        format!("{d}/V.####.exr"),
    );
    let out = format!("{d}/out/o.####.{ext}");
    let run = |extra: &[&str]| {
        let args = [
            "blur",
            "--color",
            &color,
            "--depth",
            &depth,
            "--velocity",
            &velocity,
            "-o",
            &out,
        ];
        shutter(&[&args[..], extra].concat())
    };
    let o = run(&["--algorithm", "reconstruct"]);
    assert!(o.status.success(), "{ext}: {}", stderr(&o));
    let first = dir.path().join(format!("out/o.0001.{ext}"));
    let before = std::fs::read(&first).unwrap();
    let other = [
        "--algorithm",
        "scatter",
        "--shutter",
        "0.25",
        "--skip-existing",
        "--json",
    ];
    let o = run(&[&other[..], &["--dry-run"]].concat());
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    for planned in report["planned"].as_array().unwrap() {
        assert_eq!(planned["action"], "redo", "{report}");
        let why = planned["why"].as_str().unwrap();
        assert!(
            why.contains("other settings") && why.contains("--algorithm reconstruct"),
            "{why}"
        );
    }
    assert_eq!(std::fs::read(&first).unwrap(), before, "a dry run wrote");
    let o = run(&other);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(report["frames_written"], 3, "{report}");
    assert_eq!(report["frames_skipped"], 0, "{report}");
    let said: Vec<&str> = (report["warnings"].as_array().unwrap().iter())
        .filter_map(|w| w.as_str())
        .filter(|w| w.contains("other settings"))
        .collect();
    assert_eq!(said.len(), 1, "once a run: {said:?}");
    assert!(
        said[0].contains(&format!("o.0001.{ext}"))
            && said[0].contains("--algorithm reconstruct")
            && said[0].contains("--shutter 0.25")
            && said[0].contains("2 more frames"),
        "{}",
        said[0]
    );
    assert_ne!(std::fs::read(&first).unwrap(), before, "frame 1 kept");
    // OpenImageIO, which nobody here wrote, reads what the new frame records.
    // (a PNG's `shutter/settings`, a TIFF's `Software`, a JPEG's comment as `ImageDescription`).
    if let Some(info) = oiiotool_info(&first) {
        let text = "--preset shutter --algorithm scatter --shutter 0.25";
        assert!(info.contains(text), "{ext}: {info}");
    }
    // The same settings again: every frame is this run's.
    let o = run(&other);
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(report["frames_skipped"], 3, "{ext}: {report}");
    assert!(
        !report["warnings"].to_string().contains("written again"),
        "{report}"
    );
}

#[test]
fn no_temporary_files_are_left_behind() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 4, 4);
    let out_dir = dir.path().join("o");
    for name in ["a.exr", "a.png", "a.tif", "a.jpg"] {
        let o = shutter(&[
            "blur",
            "--color",
            &s(&dir.path().join("C.exr")),
            "-o",
            &s(&out_dir.join(name)),
        ]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
    }
    let names: Vec<String> = std::fs::read_dir(&out_dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 4, "{names:?}");
    assert!(names.iter().all(|n| !n.starts_with('.')), "{names:?}");
}

#[test]
fn usage_errors_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), Some(1), 4, 4);
    let color = format!("{}/C.####.exr", dir.path().display());
    let out = format!("{}/o.####.exr", dir.path().display());
    for args in [
        vec!["blur", "--color", &color, "--frames", "9-1", "-o", &out],
        vec![
            "blur",
            "--color",
            &color,
            "--algorithm",
            "magic",
            "-o",
            &out,
        ],
        vec!["blur", "--color", &color, "--shutter", "1.5", "-o", &out],
        vec![
            "blur",
            "--color",
            &color,
            "--compression",
            "lzw",
            "-o",
            &out,
        ],
        vec!["blur", "--color", &color, "--preset", "maya", "-o", &out],
        vec!["blur", "--color", &color, "-o", "single.exr"],
        vec!["blur", "--color", &color, "-o", "out.####.gif"],
        vec!["blur", "--color", &color],
        vec!["frobnicate"],
    ] {
        let o = shutter(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    }
}

#[test]
fn json_summary_has_per_stage_times() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 8, 8);
    let o = shutter(&[
        "blur",
        "--color",
        &s(&dir.path().join("C.exr")),
        "--velocity",
        &s(&dir.path().join("V.exr")),
        "-o",
        &s(&dir.path().join("o.exr")),
        "--json",
    ]);
    assert!(o.status.success());
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    for key in [
        "read_seconds",
        "process_seconds",
        "write_seconds",
        "wall_seconds",
    ] {
        assert!(report[key].as_f64().unwrap() >= 0.0, "{key}");
    }
    assert_eq!(report["frames_written"], 1);
    let warnings = report["warnings"].as_array().unwrap();
    assert!(warnings
        .iter()
        .any(|w| w.as_str().unwrap().contains("--velocity is not read")));
    // On stderr too, one line, though it is not a terminal (issue 31: a farm's log).
    assert_eq!(
        stderr(&o),
        "shutter: warning: --velocity is not read: algorithm none does not need it\n"
    );
}

#[test]
fn passes_the_algorithm_does_not_use_are_never_opened() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 8, 8);
    let broken = dir.path().join("broken.exr");
    std::fs::write(&broken, b"not an exr at all").unwrap();
    let o = shutter(&[
        "blur",
        "--algorithm",
        "none",
        "--color",
        &s(&dir.path().join("C.exr")),
        "--velocity",
        &s(&broken),
        "--prev",
        &s(&dir.path().join("missing.exr")),
        "-o",
        &s(&dir.path().join("o.exr")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn info_prints_size_channels_compression_and_matching_preset() {
    let root = env!("CARGO_MANIFEST_DIR");
    let o = shutter(&["info", &format!("{root}/fixtures/blender/shot.0001.exr")]);
    assert!(o.status.success());
    let text = stdout(&o);
    for needle in [
        "96x64",
        "zip compression",
        "ViewLayer.Vector.W",
        "f32",
        "data window:    (0, 0) - (95, 63)",
        "blender (color, depth, velocity, prev, next)",
    ] {
        assert!(text.contains(needle), "'{needle}' not in:\n{text}");
    }
    let o = shutter(&[
        "info",
        "--json",
        &format!("{root}/fixtures/canonical/depth.0001.exr"),
    ]);
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(json["files"][0]["channels"][0]["type"], "f16");
    let o = shutter(&["info", "no/such/file.exr"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("missing file"));
    // --view of a file of no views is warned, as blur warns it (an outside probe: nothing
    // was said).
    let shot = format!("{root}/fixtures/blender/shot.0001.exr");
    let o = shutter(&["info", "--view", "left", &shot]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("holds no views"), "{}", stderr(&o));
}

#[test]
fn presets_list_and_show() {
    let o = shutter(&["presets"]);
    assert!(o.status.success());
    let text = stdout(&o);
    for name in ["shutter", "blender", "nuke", "painted", "rsmb"] {
        assert!(text.lines().any(|l| l.starts_with(name)), "{name}: {text}");
    }
    // A renderer preset says what the renderer must be set to.
    assert!(
        text.lines()
            .any(|l| l.contains("expects:") && l.contains("anti-aliasing off")),
        "{text}"
    );
    let o = shutter(&["presets", "show", "nuke"]);
    assert!(o.status.success());
    assert!(stdout(&o).contains("forward.u"));
    let o = shutter(&["presets", "show", "nope"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn help_documents_every_blur_flag() {
    let o = shutter(&["blur", "--help"]);
    let text = stdout(&o);
    for flag in [
        "--preset",
        "--algorithm",
        "--color",
        "--depth",
        "--velocity",
        "--prev",
        "--next",
        "--shutter",
        "--frames",
        "--output",
        "--half",
        "--compression",
        "--bit-depth",
        "--skip-existing",
        "--json",
        "--verbose",
        "--layer",
        "--linear",
        "--threads",
        "--dry-run",
    ] {
        assert!(text.contains(flag), "{flag} missing from help");
    }
}

/// Damage found decoding a pass file names the pass besides the file and frame (an outside
/// probe: a damaged depth file's error named only the file and frame).
#[test]
fn damage_found_decoding_a_pass_file_names_the_pass() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64, 64);
    let smooth: Vec<f32> = (0..w * h)
        .map(|k| 1.0 + (k % w) as f32 / w as f32)
        .collect();
    let plane = |name| (name, smooth.clone());
    write_exr(
        &dir.path().join("C.exr"),
        w,
        h,
        vec![plane("R"), plane("G"), plane("B")],
    );
    let depth = dir.path().join("D.exr");
    write_exr(&depth, w, h, vec![plane("Z")]);
    let mut bytes = std::fs::read(&depth).unwrap();
    let middle = bytes.len() / 2;
    for b in &mut bytes[middle..middle + 16] {
        *b ^= 0xFF;
    }
    std::fs::write(&depth, &bytes).unwrap();
    let o = shutter(&[
        "dof",
        "--color",
        &s(&dir.path().join("C.exr")),
        "--depth",
        &s(&depth),
        "--focal-length",
        "50",
        "--f-stop",
        "2",
        "--focus-distance",
        "1.5",
        "-o",
        &s(&dir.path().join("out.exr")),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("corrupt file") && err.contains("D.exr") && err.contains("depth pass"),
        "{err}"
    );
}

#[test]
fn damage_inside_compressed_data_stops_the_run_without_a_partial_frame() {
    let dir = tempfile::tempdir().unwrap();
    // Smooth pictures, so that ZIP really compresses: EXR stores a chunk raw when compression
    // would not shrink it, and damage to raw samples is undetectable by any reader.
    let (w, h) = (64, 64);
    let smooth: Vec<f32> = (0..w * h).map(|k| (k % w) as f32 / w as f32).collect();
    for frame in 1..=3 {
        write_exr(
            &dir.path().join(format!("C.{frame:04}.exr")),
            w,
            h,
            vec![
                ("R", smooth.clone()),
                ("G", smooth.clone()),
                ("B", smooth.clone()),
                ("A", vec![1.0; w * h]),
            ],
        );
    }
    // Damage the middle of frame 2's compressed pixels: headers and chunk table stay valid,
    // so only decoding can find it.
    let path = dir.path().join("C.0002.exr");
    let mut bytes = std::fs::read(&path).unwrap();
    let middle = bytes.len() / 2;
    for b in &mut bytes[middle..middle + 16] {
        *b ^= 0xFF;
    }
    std::fs::write(&path, &bytes).unwrap();
    let out_dir = dir.path().join("out");
    let o = shutter(&[
        "blur",
        "--color",
        &format!("{}/C.####.exr", dir.path().display()),
        "-o",
        &format!("{}/o.####.exr", out_dir.display()),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("corrupt file") && err.contains("C.0002.exr, frame 2"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    // Frame 1 may be whole; frame 2 is absent; no temporary file anywhere.
    let names: Vec<String> = std::fs::read_dir(&out_dir)
        .map(|d| {
            d.map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
                .collect()
        })
        .unwrap_or_default();
    assert!(
        !names
            .iter()
            .any(|n| n.contains("0002") || n.starts_with('.')),
        "{names:?}"
    );
    if names.contains(&"o.0001.exr".to_string()) {
        let written = read_exr_reference(&out_dir.join("o.0001.exr"));
        assert_eq!(written.len(), 4);
    }
}

#[test]
fn unwritable_output_is_a_file_error() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 4, 4);
    // The output's folder would have to be inside a regular file.
    let blocker = dir.path().join("blocker");
    std::fs::write(&blocker, b"a file, not a folder").unwrap();
    let o = shutter(&[
        "blur",
        "--color",
        &s(&dir.path().join("C.exr")),
        "-o",
        &s(&blocker.join("out.exr")),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = stderr(&o);
    assert!(
        err.contains("cannot write") && err.contains("blocker"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
}

#[test]
fn output_is_bit_identical_for_any_thread_count() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), Some(1), 190, 130);
    let mut outputs = Vec::new();
    for threads in ["1", "2", "3"] {
        let out = dir.path().join(format!("t{threads}/o.####.exr"));
        let o = shutter(&[
            "blur",
            "--threads",
            threads,
            "--color",
            &format!("{}/C.####.exr", dir.path().display()),
            "-o",
            &s(&out),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        outputs.push(std::fs::read(dir.path().join(format!("t{threads}/o.0001.exr"))).unwrap());
    }
    assert!(outputs.windows(2).all(|w| w[0] == w[1]), "outputs differ");
}

#[test]
fn a_sequence_warns_once_about_derived_motion() {
    let dir = tempfile::tempdir().unwrap();
    let mut args = vec!["blur".to_string(), "--algorithm".into(), "scatter".into()];
    args.extend(canonical_fixture_passes());
    args.extend([
        "-o".to_string(),
        format!("{}/o.####.exr", dir.path().display()),
        "--verbose".into(),
    ]);
    let o = shutter(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    // Three frames, next derived from velocity in each: one warning.
    assert_eq!(
        stderr(&o).matches("assuming linear motion").count(),
        1,
        "{}",
        stderr(&o)
    );
}

/// A render on ones that lost every other frame in a stretch (a farm's second worker failing:
/// 1, 2, 3, 5, 7, 9) is warned about by `blur` and by `diff`, the mixed steps said: the
/// commonest step, 2, had made it a complete sequence on twos, without a word (an outside
/// tester's finding).
#[test]
fn a_sequence_that_lost_every_other_frame_in_a_stretch_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    for frame in [1, 2, 3, 5, 7, 9] {
        write_canonical_frame(dir.path(), Some(frame), 4, 4);
    }
    let color = format!("{}/C.####.exr", dir.path().display());
    let out = format!("{}/out/o.####.exr", dir.path().display());
    let o = shutter(&["blur", "--color", &color, "-o", &out, "--dry-run", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let warnings = report["warnings"].to_string();
    assert!(
        warnings.contains("has no frames 4-8:2: 3 frames are missing between 1 and 9")
            && warnings.contains("step by 2 mostly, by 1 in places"),
        "{warnings}"
    );
    let o = shutter(&["diff", &color, &color]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("has no frames 4-8:2 between 1 and 9"),
        "{}",
        stderr(&o)
    );
}

/// A sequence on disk with a frame missing is warned about (issue 31: it was skipped without
/// a word); a pattern that matches nothing is bad input, exit 1 (it was a usage error, 2);
/// Houdini's `$F4` and `@@@@` name the frames as `####` does.
#[test]
fn holes_unmatched_patterns_and_houdini_tokens() {
    let dir = tempfile::tempdir().unwrap();
    for frame in [1, 2, 4] {
        write_canonical_frame(dir.path(), Some(frame), 4, 4);
    }
    let color = format!("{}/C.####.exr", dir.path().display());
    let out = format!("{}/out/o.####.exr", dir.path().display());
    let o = shutter(&["blur", "--color", &color, "-o", &out, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let warnings = report["warnings"].to_string();
    assert!(
        warnings.contains("has no frame 3: 1 frame is missing between 1 and 4"),
        "{warnings}"
    );
    let nothing = format!("{}/nothing.####.exr", dir.path().display());
    let o = shutter(&["blur", "--color", &nothing, "-o", &out]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("no files match the pattern"),
        "{}",
        stderr(&o)
    );
    // Frames padded otherwise than the pattern (`#` one digit, as Nuke reads it; four to
    // oiiotool and RV): the error names a file found and the pattern for it (an outside
    // tester: it said nothing of them).
    // Unpadded frames are all frames of one `#`, whatever their length.
    for name in ["U.7.exr", "U.12.exr"] {
        std::fs::copy(dir.path().join("C.0001.exr"), dir.path().join(name)).unwrap();
    }
    let color = format!("{}/U.####.exr", dir.path().display());
    let o = shutter(&["blur", "--color", &color, "-o", &out]);
    let err = stderr(&o);
    assert!(
        err.contains("'U.12.exr' is not padded")
            && err.contains("/U.#.exr'")
            && !err.contains("padded to"),
        "{err}"
    );
    for short in ["C.###.exr", "C.#####.exr", "C.%d.exr"] {
        let color = format!("{}/{short}", dir.path().display());
        let o = shutter(&["blur", "--color", &color, "-o", &out]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains("'C.0001.exr' is padded to 4 digits") && err.contains("/C.####.exr'"),
            "{short}: {err}"
        );
    }
    for (input, output) in [("C.$F4.exr", "h/o.$F4.exr"), ("C.@@@@.exr", "a/o.@@@@.exr")] {
        let input = format!("{}/{input}", dir.path().display());
        let output = format!("{}/{output}", dir.path().display());
        let o = shutter(&["blur", "--color", &input, "-o", &output, "--frames", "1,2"]);
        assert!(o.status.success(), "{input}: {}", stderr(&o));
        let folder = std::path::Path::new(&output)
            .parent()
            .unwrap()
            .to_path_buf();
        assert!(folder.join("o.0001.exr").exists() && folder.join("o.0002.exr").exists());
    }
}

/// Warnings reach a pipe (issue 31: a farm's log; they were dropped unless --verbose), one
/// line each, and `--quiet` silences them while `--json` keeps them.
#[test]
fn warnings_are_printed_on_a_pipe_unless_quiet() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 4, 4);
    let color = s(&dir.path().join("C.exr"));
    let depth = s(&dir.path().join("Z.exr"));
    let out = s(&dir.path().join("o.exr"));
    // Depth given to an algorithm that does not read it: a warning.
    let o = shutter(&["blur", "--color", &color, "--depth", &depth, "-o", &out]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.lines()
            .any(|l| l.starts_with("shutter: warning: --depth is not read")),
        "{err}"
    );
    let o = shutter(&[
        "blur", "--color", &color, "--depth", &depth, "-o", &out, "-q", "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    assert!(stdout(&o).contains("--depth is not read"), "{}", stdout(&o));
}

/// An RGB frame whose every sample is `value`, written at `path`.
fn flat_frame(path: &std::path::Path, value: f32) {
    let plane = vec![value; 8 * 4];
    write_exr(
        path,
        8,
        4,
        vec![("R", plane.clone()), ("G", plane.clone()), ("B", plane)],
    );
}

/// Negative frames on disk are frames of the sequence, named as shutter's own `####` writes
/// them (`-002`), so a sequence shutter wrote is found again (QA: discovery took digits only,
/// and `c.-002.exr` and `c.-001.exr` were left out without a word, frame 0 alone planned).
#[test]
fn negative_frames_on_disk_are_discovered_as_shutter_names_them() {
    let dir = tempfile::tempdir().unwrap();
    for frame in -2..=0 {
        flat_frame(
            &dir.path().join(format!("neg/c.{frame:04}.exr")),
            frame as f32,
        );
    }
    // Not as shutter writes any frame: left out, as a positive one padded wrongly is.
    flat_frame(&dir.path().join("neg/c.-02.exr"), 9.0);
    flat_frame(&dir.path().join("neg/c.-0002.exr"), 9.0);
    let color = format!("{}/neg/c.####.exr", dir.path().display());
    let out = format!("{}/out/o.####.exr", dir.path().display());
    let o = shutter(&["blur", "--color", &color, "-o", &out, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(report["frames_written"], 3, "{report}");
    let mut written: Vec<String> = std::fs::read_dir(dir.path().join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    assert_eq!(written, ["o.-001.exr", "o.-002.exr", "o.0000.exr"]);
    // And what it wrote is found again: a second run over its outputs plans all three.
    let again = format!("{}/again/o.####.exr", dir.path().display());
    let o = shutter(&["blur", "--dry-run", "--color", &out, "-o", &again, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let frames = planned_frames(&o);
    assert_eq!(frames, [-2, -1, 0]);
}

/// Files numbered beyond ±999999999 (what `--frames` refuses) are not frames of a sequence
/// found on disk, and the run says so, naming one and the limit (QA: they were found up to
/// i64::MAX, two jobs on them shared one lock byte, and the holes warning counted a billion).
#[test]
fn frame_numbers_beyond_the_limit_are_named_not_discovered() {
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "c.999999998.exr",
        "c.999999999.exr",
        "c.1000000001.exr",
        "c.9223372036854775807.exr",
    ] {
        flat_frame(&dir.path().join(name), 0.5);
    }
    let color = format!("{}/c.####.exr", dir.path().display());
    let out = format!("{}/out/o.####.exr", dir.path().display());
    let o = shutter(&["blur", "--dry-run", "--color", &color, "-o", &out, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let frames = planned_frames(&o);
    assert_eq!(frames, [999999998, 999999999]);
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let warnings = report["warnings"].to_string();
    assert!(
        warnings.contains("c.1000000001.exr") && warnings.contains("999999999"),
        "{warnings}"
    );
    assert!(!warnings.contains("missing"), "{warnings}");
    // The backend asked for is said, none used (an outside probe: both were empty).
    assert_eq!(report["backend"]["requested"], "cpu", "{report}");
    assert_eq!(report["backend"]["used"], "none", "{report}");
    // Nothing but such files: no frames, and the error says why.
    let far = tempfile::tempdir().unwrap();
    flat_frame(&far.path().join("c.-1000000000.exr"), 0.5);
    let color = format!("{}/c.####.exr", far.path().display());
    let o = shutter(&["blur", "--dry-run", "--color", &color, "-o", &out]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("no files match") && err.contains("c.-1000000000.exr"),
        "{err}"
    );
    assert!(err.contains("999999999"), "{err}");
}

/// A `#`, `%d`, `$F` or `@@` in a folder's name is part of the name: only the file name holds
/// a frame placeholder (QA: `take#2/color.0001.exr` was read as a pattern and matched no
/// file, and `take#2/color.####.exr` held "more than one frame placeholder").
#[test]
fn a_placeholder_is_only_looked_for_in_the_file_name() {
    let dir = tempfile::tempdir().unwrap();
    let take = dir.path().join("take#2 %d $F @@");
    for frame in [1, 2] {
        flat_frame(&take.join(format!("C.{frame:04}.exr")), frame as f32);
    }
    let one = s(&take.join("C.0001.exr"));
    let o = shutter(&["diff", &one, &one]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = shutter(&[
        "blur",
        "--color",
        &one,
        "-o",
        &s(&take.join("out/still.exr")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(take.join("out/still.exr").exists());
    for (input, output) in [
        ("C.####.exr", "a/o.####.exr"),
        ("C.%04d.exr", "b/o.%04d.exr"),
        ("C.$F4.exr", "c/o.$F4.exr"),
        ("C.@@@@.exr", "d/o.@@@@.exr"),
    ] {
        let input = s(&take.join(input));
        let output = s(&take.join(output));
        let o = shutter(&["blur", "--color", &input, "-o", &output, "--json"]);
        assert!(o.status.success(), "{input}: {}", stderr(&o));
        let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        assert_eq!(report["frames_written"], 2, "{input}: {report}");
        let folder = std::path::Path::new(&output).parent().unwrap();
        assert!(folder.join("o.0001.exr").exists() && folder.join("o.0002.exr").exists());
    }
}

/// A single file given for a pass while the colour is a pattern (or the other way round) is a
/// usage error naming the flag and the pattern to give (QA: frame 1's depth and velocity were
/// read for every frame of the sequence, without a word).
#[test]
fn a_single_file_pass_beside_a_pattern_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    for frame in [1, 2] {
        write_canonical_frame(dir.path(), Some(frame), 6, 4);
    }
    let at = |name: &str| s(&dir.path().join(name));
    let out_dir = dir.path().join("out");
    let out = s(&out_dir.join("o.####.exr"));
    let before = snapshot(dir.path());
    let cases: [(&[&str], &str, &str); 4] = [
        (
            &[
                "--depth",
                &at("Z.0001.exr"),
                "--velocity",
                &at("V.####.exr"),
            ],
            "--depth",
            "Z.####.exr",
        ),
        (
            &[
                "--depth",
                &at("Z.####.exr"),
                "--velocity",
                &at("V.0001.exr"),
            ],
            "--velocity",
            "V.####.exr",
        ),
        (&["--coc-map", &at("Z.0002.exr")], "--coc-map", "Z.####.exr"),
        (
            &[
                "--depth",
                &at("Z.0001.exr"),
                "--velocity",
                &at("V.0001.exr"),
            ],
            "--depth",
            "Z.####.exr",
        ),
    ];
    for (passes, flag, suggested) in cases {
        let color = at("C.####.exr");
        let mut args = vec!["blur", "--algorithm", "reconstruct", "--color", &color];
        args.extend_from_slice(passes);
        args.extend_from_slice(&["-o", &out]);
        let o = shutter(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{passes:?}: {err}");
        assert!(
            err.contains(flag) && err.contains(suggested),
            "{passes:?}: {err}"
        );
    }
    // A single colour file with a pattern for another pass: the same mix, named.
    let o = shutter(&[
        "blur",
        "--algorithm",
        "reconstruct",
        "--color",
        &at("C.0001.exr"),
        "--velocity",
        &at("V.####.exr"),
        "-o",
        &out,
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--color") && err.contains("C.####.exr"),
        "{err}"
    );
    assert_eq!(
        snapshot(dir.path()),
        before,
        "a refused run wrote something"
    );
}

/// A pattern in a folder that is not there is bad input (exit 1; `diff`: 3, could not
/// compare), as a pattern that matches no file is, not a usage error (exit 2, which a farm
/// reads as "fix the command": the command may be right and the folder gone or stale).
#[test]
fn a_pattern_in_a_missing_folder_is_bad_input_not_usage() {
    let dir = tempfile::tempdir().unwrap();
    let missing = s(&dir.path().join("nope/c.####.exr"));
    let out = s(&dir.path().join("o/o.####.exr"));
    let o = shutter(&["blur", "--color", &missing, "-o", &out]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("cannot list the folder"),
        "{}",
        stderr(&o)
    );
    let o = shutter(&["diff", &missing, &missing]);
    assert_eq!(o.status.code(), Some(3), "{}", stderr(&o));
}

/// The frames a `--dry-run --json` run planned, in its order.
fn planned_frames(o: &std::process::Output) -> Vec<i64> {
    let report: serde_json::Value = serde_json::from_str(&stdout(o)).unwrap();
    report["planned"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["frame"].as_i64().unwrap())
        .collect()
}

/// `--help` lists every preset shutter ships under `--preset` (vray, unreal and arnold were
/// missing from the list).
#[test]
fn help_names_every_builtin_preset() {
    for command in ["blur", "dof"] {
        let o = shutter(&[command, "--help"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let help = stdout(&o);
        let line = help
            .lines()
            .skip_while(|l| !l.contains("--preset"))
            .take(3)
            .collect::<Vec<_>>()
            .join(" ");
        for (name, _) in shutter::io::preset::BUILTIN {
            assert!(
                line.contains(name),
                "{command} --help: {name} not in {line}"
            );
        }
    }
}

/// A photo run that lacks a pass names the flag that gives it: `--velocity` for every motion
/// algorithm (scatter's previous and next positions are derived from velocity, so it is the
/// flag a painted map goes in; QA: scatter said "prev pass" and "give --prev FILE", twice),
/// `--depth` for depth; one line each, whichever pass the algorithm reads the motion as.
#[test]
fn a_missing_pass_names_the_flag_that_gives_it() {
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("photo.png");
    let depth = dir.path().join("depth.png");
    image::save_buffer(&photo, &[90u8; 8 * 6 * 3], 8, 6, image::ColorType::Rgb8).unwrap();
    image::save_buffer(&depth, &[128u8; 8 * 6], 8, 6, image::ColorType::L8).unwrap();
    let out_dir = dir.path().join("out");
    std::fs::create_dir_all(&out_dir).unwrap();
    let out = s(&out_dir.join("o.png"));
    let (photo, depth) = (s(&photo), s(&depth));
    for algorithm in ["reconstruct", "scatter", "stretch"] {
        let args = [
            "blur",
            "--preset",
            "painted",
            "--algorithm",
            algorithm,
            "--color",
            &photo,
            "--depth",
            &depth,
            "-o",
            &out,
        ];
        let err = assert_fails_cleanly(
            &args,
            &out_dir,
            &["photo.png", "velocity pass", "--velocity FILE"],
        );
        let problems = err
            .lines()
            .filter(|l| l.contains("missing channel"))
            .count();
        assert_eq!(problems, 1, "{algorithm}: one problem: {err}");
        assert!(
            !err.contains("prev pass") && !err.contains("next pass"),
            "{algorithm}: {err}"
        );
    }
    // Depth of field with no depth: the flag is --depth.
    let before = ["dof", "--preset", "painted", "--color", &photo];
    let args = [&before[..], &LENS_ARGS, &["-o", &out]].concat();
    assert_fails_cleanly(
        &args,
        &out_dir,
        &["photo.png", "depth pass", "--depth FILE"],
    );
}

/// The exit codes in the first table of README's usage (`Exit codes (what a farm's wrapper
/// acts on)`), as its first cells write them: `0`, `1`, …, `128 + N`.
fn readme_exit_codes() -> Vec<String> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("README.md");
    let text = std::fs::read_to_string(path).unwrap();
    let table = text
        .split("Exit codes (what a farm's wrapper acts on):")
        .nth(1)
        .expect("README has the exit-code table");
    table
        .lines()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .filter_map(|l| {
            let cell = l.split('|').nth(1)?.trim();
            let code = cell.strip_prefix('`')?.strip_suffix('`')?;
            Some(code.to_string())
        })
        .collect()
}

/// `shutter --help` lists every exit code README's table gives, and no other (75, retry,
/// and 128 + N, a signal, were missing from it).
#[test]
fn help_lists_the_exit_codes_of_the_readme() {
    let codes = readme_exit_codes();
    assert!(codes.len() >= 5, "{codes:?}");
    let o = shutter(&["--help"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let help = stdout(&o);
    let paragraph = help
        .split("Exit codes:")
        .nth(1)
        .and_then(|rest| rest.split("\n\n").next())
        .expect("--help has an exit-code paragraph")
        .replace('\n', " ");
    // Each entry of the paragraph starts with its code, after `Exit codes:` or a `;`.
    let listed: Vec<String> = paragraph
        .split(';')
        .map(|entry| {
            let words: Vec<&str> = entry.split_whitespace().collect();
            match words.as_slice() {
                ["128", "+", "N", ..] => "128 + N".to_string(),
                [code, ..] => code.to_string(),
                [] => String::new(),
            }
        })
        .filter(|code| code.starts_with(|c: char| c.is_ascii_digit()))
        .collect();
    assert_eq!(listed, codes, "--help's exit codes: {paragraph}");
}

/// `scene --size` over its limit says the limit, in the error and in `--help` (it said
/// only "use WxH").
#[test]
fn a_scene_size_over_the_limit_names_the_limit() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scene");
    let o = shutter(&["scene", "pan", "-o", &s(&out), "--size", "20000x10"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("16384"), "{}", stderr(&o));
    let help = stdout(&shutter(&["scene", "--help"]));
    let line = help.lines().find(|l| l.contains("--size")).unwrap();
    assert!(line.contains("16384"), "{line}");
}

/// A scene whose planes the memory cannot hold is refused before anything is allocated,
/// exit 1 with what to do, not aborted by the allocator (SIGABRT, exit 134 from a shell).
#[cfg(unix)]
#[test]
fn a_scene_too_large_for_the_memory_is_refused_not_aborted() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("scene");
    // 2 GB of address space; a 16384² scene's planes are 1 GiB each.
    let args = [
        "scene",
        "pan",
        "-o",
        &s(&out),
        "--size",
        "16384x16384",
        "--samples",
        "1",
    ];
    let o = shutter_capped(2_000_000, &args);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let message = stderr(&o);
    assert!(
        message.contains("too large") && message.contains("MiB") && message.contains("--size"),
        "{message}"
    );
    assert!(!out.join("color.0001.exr").exists());
    // And under a --max-memory of its own.
    let o = shutter(&[
        "scene",
        "gears",
        "-o",
        &s(&out),
        "--size",
        "2048x2048",
        "--max-memory",
        "64",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("--max-memory"), "{}", stderr(&o));
    assert!(!out.join("color.0001.exr").exists());
}

/// `shutter dof` with no depth names every way to give it (QA: it named `--depth` alone, as
/// blur's missing motion named `--velocity`): `--depth FILE`, `--coc-map FILE` (a painted
/// map of the blur, read in place of depth), and a preset: the built-in ones that find depth
/// in the file, by name and channel, or else one whose `[depth] channels` name it. A motion
/// blur, which cannot take a CoC map, does not offer one.
#[test]
fn dof_without_depth_names_every_way_to_give_it() {
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("photo.png");
    image::save_buffer(&photo, &[90u8; 8 * 6 * 3], 8, 6, image::ColorType::Rgb8).unwrap();
    // An EXR whose depth is `depth.Z`, which the painted preset does not name.
    let exr = dir.path().join("render.exr");
    let n = 8 * 6;
    write_exr(
        &exr,
        8,
        6,
        vec![
            ("R", vec![0.5; n]),
            ("G", vec![0.5; n]),
            ("B", vec![0.5; n]),
            ("depth.Z", vec![4.0; n]),
        ],
    );
    let out_dir = dir.path().join("out");
    std::fs::create_dir_all(&out_dir).unwrap();
    let out = s(&out_dir.join("o.exr"));
    let lens = LENS_ARGS;
    let run = |color: &std::path::Path, expect: &[&str]| {
        let color = s(color);
        let mut args = vec!["dof", "--preset", "painted", "--color", &color, "-o", &out];
        args.extend(lens);
        assert_fails_cleanly(&args, &out_dir, expect)
    };
    let err = run(
        &photo,
        &["photo.png", "depth pass", "--depth FILE", "--coc-map FILE"],
    );
    assert!(err.contains("[depth] channels"), "{err}");
    let err = run(&exr, &["render.exr", "--depth FILE", "--coc-map FILE"]);
    assert!(
        err.contains("--preset") && err.contains("shutter (depth.Z)"),
        "{err}"
    );
    // Motion blur needs depth too; a CoC map is no way to give it.
    let color = s(&photo);
    let args = [
        "blur",
        "--preset",
        "painted",
        "--algorithm",
        "reconstruct",
        "--color",
        &color,
        "--velocity",
        &color,
        "-o",
        &out,
    ];
    let err = assert_fails_cleanly(&args, &out_dir, &["depth pass", "--depth FILE"]);
    assert!(!err.contains("--coc-map"), "{err}");
}

/// `%%` in a path is one `%` as printf writes it: `-o 'b.%%d.exr'` for a single input wrote
/// `b.%1.exr` (the `%d` after the escape taken for a frame placeholder); a sequence's
/// `o.%%.%04d.exr` writes `o.%.0001.exr`.
#[test]
fn a_doubled_percent_in_a_path_is_one_percent_sign() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 8, 6);
    let copy = |color: &str, out: &str, extra: &[&str]| {
        let mut args = vec!["blur", "--algorithm", "none", "--color", color, "-o", out];
        args.extend(extra);
        shutter(&args)
    };
    let out = dir.path().join("b");
    let o = copy(
        &s(&dir.path().join("C.exr")),
        &s(&out.join("b.%%d.exr")),
        &[],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let written: Vec<String> = (std::fs::read_dir(&out).unwrap().flatten())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| !n.starts_with('.'))
        .collect();
    assert_eq!(written, ["b.%d.exr"]);
    for frame in [1, 2] {
        write_canonical_frame(dir.path(), Some(frame), 8, 6);
    }
    let seq = dir.path().join("s");
    let o = copy(
        &s(&dir.path().join("C.%04d.exr")),
        &s(&seq.join("o.%%.%04d.exr")),
        &["--frames", "1-2"],
    );
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(seq.join("o.%.0001.exr").exists() && seq.join("o.%.0002.exr").exists());
}

/// Four messages an outside tester found unclear: `info` given a pattern (it said only "no
/// such file"), `--frames` over the limit (the limit unnamed), a dry run's backend (`used`
/// was an empty string) and a failed preflight (it said "nothing was written for the frames
/// concerned", as if the others were).
#[test]
fn four_messages_say_what_they_mean() {
    let dir = tempfile::tempdir().unwrap();
    for frame in 1..=2 {
        write_canonical_frame(dir.path(), Some(frame), 4, 4);
    }
    let color = format!("{}/C.####.exr", dir.path().display());
    let o = shutter(&["info", &color]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("info reads files, not patterns"),
        "{}",
        stderr(&o)
    );
    let o = shutter(&["frames", "1-2000000"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("more than 1000000 frames"),
        "{}",
        stderr(&o)
    );
    let out = format!("{}/out/o.####.exr", dir.path().display());
    let o = shutter(&["blur", "--color", &color, "-o", &out, "--dry-run", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(report["backend"]["used"], "none", "{report}");
    // Depth and motion missing in both frames: four problems, and no frame is written.
    let depth = format!("{}/nothing.####.exr", dir.path().display());
    let args = [
        "blur",
        "--color",
        &color,
        "--depth",
        &depth,
        "--algorithm",
        "reconstruct",
    ];
    let o = shutter(&[&args[..], &["-o", &out]].concat());
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("4 problems found; nothing was written (every frame is checked"),
        "{}",
        stderr(&o)
    );
}
