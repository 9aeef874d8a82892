//! On a farm (issue 18): frame ranges as farms write them, and chunks of them.

use shutter::io::sequence::{parse_frames, PathPattern};

use crate::support::*;

#[test]
fn shutter_frames_cuts_a_spec_into_chunks_for_a_farm() {
    let o = shutter(&["frames", "1-100:5", "--chunk-size", "7"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let lines: Vec<String> = stdout(&o).lines().map(String::from).collect();
    assert_eq!(lines, ["1-31:5", "36-66:5", "71-96:5"]);
    let mut all = Vec::new();
    for line in &lines {
        all.extend(parse_frames(line).unwrap());
    }
    assert_eq!(all, (1..=100).step_by(5).collect::<Vec<i64>>());
    let o = shutter(&["frames", "1-100:5", "--chunk-size", "7", "--count"]);
    assert_eq!(stdout(&o).trim(), "3");
    let o = shutter(&["frames", "-10--1", "--chunk-size", "4", "--chunk", "2"]);
    assert_eq!(stdout(&o).trim(), "-2,-1");
    // A chunk past the end is a usage error naming how many there are.
    let o = shutter(&["frames", "1-10", "--chunk-size", "5", "--chunk", "2"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("2 chunks"), "{}", stderr(&o));
}

#[test]
fn stepped_and_negative_frames_run_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let colour = PathPattern::parse(&format!("{}/C.####.exr", dir.path().display())).unwrap();
    let (w, h) = (8, 4);
    for frame in -3..=3 {
        let value = vec![frame as f32; w * h];
        write_exr(
            &colour.path(Some(frame)),
            w,
            h,
            vec![("R", value.clone()), ("G", value.clone()), ("B", value)],
        );
    }
    let out = PathPattern::parse(&format!("{}/out/o.####.exr", dir.path().display())).unwrap();
    let o = shutter(&[
        "blur",
        "--color",
        &colour.raw,
        "--frames",
        "-3-3:3",
        "-o",
        &out.raw,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut written: Vec<String> = std::fs::read_dir(dir.path().join("out"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    written.sort();
    assert_eq!(written, ["o.-003.exr", "o.0000.exr", "o.0003.exr"]);
    // Each output holds its own frame's colour.
    for frame in [-3i64, 0, 3] {
        let channels = read_exr_reference(&out.path(Some(frame)));
        assert!(channel(&channels, "R").iter().all(|&v| v == frame as f32));
    }
}

#[test]
fn dry_run_lists_what_each_frame_would_do_and_touches_nothing() {
    let dir = tempfile::tempdir().unwrap();
    for frame in 1..=3 {
        write_canonical_frame(dir.path(), Some(frame), 16, 8);
    }
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    // Frame 2 done (a whole frame), frame 3 cut short (empty).
    let done = shutter(&[
        "blur",
        "--color",
        &s(&dir.path().join("C.0002.exr")),
        "-o",
        &s(&out.join("o.0002.exr")),
    ]);
    assert!(done.status.success(), "{}", stderr(&done));
    std::fs::write(out.join("o.0003.exr"), b"").unwrap();
    let before = snapshot(dir.path());
    let colour = format!("{}/C.####.exr", dir.path().display());
    let pattern = format!("{}/o.####.exr", out.display());
    let dry_run = |extra: &str| {
        let o = shutter(&[
            "blur",
            "--color",
            &colour,
            "-o",
            &pattern,
            "--dry-run",
            extra,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        o
    };
    let o = dry_run("--skip-existing");
    let lines: Vec<String> = stdout(&o).lines().map(String::from).collect();
    let at = |f: u32| out.join(format!("o.{f:04}.exr")).display().to_string();
    assert_eq!(
        lines,
        [
            format!("frame 1: write {}", at(1)),
            format!("frame 2: skip {}", at(2)),
            format!("frame 3: redo {} (it is empty)", at(3)),
        ]
    );
    // The JSON form names each frame's inputs.
    let o = dry_run("--json");
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let planned = report["planned"].as_array().unwrap();
    assert_eq!(planned.len(), 3);
    assert_eq!(planned[1]["action"], "overwrite");
    assert_eq!(
        planned[0]["inputs"][0],
        dir.path().join("C.0001.exr").display().to_string()
    );
    assert_eq!(report["frames_written"], 0);
    // Nothing was written, locked or removed.
    assert_eq!(snapshot(dir.path()), before);
}

/// What a farm relies on: a frame's output depends on its own inputs and settings alone, so
/// a sequence cut into chunks (one process each, with different thread counts, run in any
/// order) writes the same bytes as one run over every frame. Every motion blur algorithm,
/// and depth of field before it.
#[test]
fn chunked_runs_write_the_bytes_of_one_run() {
    let scene = small_scene("rotor", 64, 36, 5, 2);
    let inputs = [
        ("--color", role_pattern(scene.path(), "color")),
        ("--depth", role_pattern(scene.path(), "depth")),
        ("--velocity", role_pattern(scene.path(), "velocity")),
        ("--prev", role_pattern(scene.path(), "prev")),
        ("--next", role_pattern(scene.path(), "next")),
    ];
    // Depth of field then scatter: a lens that blurs at 64 px (a 4 mm sensor).
    let dof_then_scatter = "--algorithm scatter --sensor-width 4 --focal-length 50 --f-stop 1.4 \
                            --focus-distance 2";
    let settings: Vec<Vec<&str>> = [
        "--algorithm none",
        "--algorithm reconstruct",
        "--algorithm scatter",
        "--algorithm stretch",
        dof_then_scatter,
    ]
    .iter()
    .map(|s| s.split_whitespace().collect())
    .collect();
    let mut third_frames: Vec<Vec<u8>> = Vec::new();
    let out = tempfile::tempdir().unwrap();
    for (i, setting) in settings.iter().enumerate() {
        let run = |name: &str, frames: &str, threads: &str| {
            let pattern = format!("{}/{i}/{name}/o.####.exr", out.path().display());
            let mut args = vec![
                "blur",
                "--frames",
                frames,
                "--threads",
                threads,
                "-o",
                &pattern,
            ];
            for (flag, path) in &inputs {
                args.extend([*flag, path.as_str()]);
            }
            args.extend_from_slice(setting);
            let o = shutter(&args);
            assert!(o.status.success(), "{setting:?} {frames}: {}", stderr(&o));
        };
        run("one", "1-5", "2");
        // Chunks of 2 (5 is not a multiple), the last first, one thread and three.
        for (frames, threads) in [("5", "1"), ("3,4", "3"), ("1-2", "1")] {
            run("chunks", frames, threads);
        }
        for frame in 1..=5 {
            let name = format!("o.{frame:04}.exr");
            let one = std::fs::read(out.path().join(format!("{i}/one/{name}"))).unwrap();
            let chunked = std::fs::read(out.path().join(format!("{i}/chunks/{name}"))).unwrap();
            assert!(
                one == chunked,
                "{setting:?}: frame {frame} differs between one run and chunks"
            );
        }
        let mut names: Vec<String> = std::fs::read_dir(out.path().join(format!("{i}/chunks")))
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(
            names.len(),
            5,
            "{setting:?}: stray files beside the outputs: {names:?}"
        );
        third_frames.push(std::fs::read(out.path().join(format!("{i}/one/o.0003.exr"))).unwrap());
    }
    // Each setting changes the frame (else the comparison above would prove little).
    for (i, frame) in third_frames.iter().enumerate() {
        for (j, other) in third_frames.iter().enumerate().take(i) {
            assert!(
                frame != other,
                "{:?} and {:?} wrote the same frame 3",
                settings[j],
                settings[i]
            );
        }
    }
}
