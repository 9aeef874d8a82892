//! `shutter vectors` (issue 32): sequences with known motion — a textured background and a
//! foreground square, each moving on its own accelerating path, so that every component is
//! observable and backward and forward motion differ — written with their vectors in
//! disguised conventions; the fit recovers each, and the preset it writes makes `shutter
//! blur` give the frames the canonical vectors give.

use std::path::Path;

use crate::support::{read_exr_reference, s, shutter, snapshot, stderr, stdout, write_exr};

const W: usize = 96;
const H: usize = 64;

/// Value noise on a 3-pixel lattice, bilinear between lattice values: a texture defined at
/// every real position, so a shifted copy is exact.
fn texture(x: f32, y: f32, seed: u32) -> f32 {
    let lattice = |i: i64, j: i64| {
        let mut h = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ (seed as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
        h ^= h >> 29;
        h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h ^= h >> 32;
        (h % 1000) as f32 / 1000.0
    };
    let (u, v) = (x / 3.0, y / 3.0);
    let (i, j) = (u.floor() as i64, v.floor() as i64);
    let (fu, fv) = (u - u.floor(), v - v.floor());
    let top = lattice(i, j) * (1.0 - fu) + lattice(i + 1, j) * fu;
    let bottom = lattice(i, j + 1) * (1.0 - fu) + lattice(i + 1, j + 1) * fu;
    top * (1.0 - fv) + bottom * fv
}

/// Where each layer has moved by frame t (pixels): accelerating, so the motion before a frame
/// and after it differ.
fn background(t: f32) -> (f32, f32) {
    (4.0 * t + 1.0 * t * t, -3.0 * t + 0.8 * t * t)
}

fn foreground(t: f32) -> (f32, f32) {
    (-5.0 * t + 0.5 * t * t, 2.0 * t + 0.6 * t * t)
}

/// Whether pixel centre (x, y) of frame t is on the foreground square.
fn on_square(x: f32, y: f32, t: f32) -> bool {
    let (dx, dy) = foreground(t);
    let (x, y) = (x - dx, y - dy);
    (26.0..78.0).contains(&x) && (14.0..50.0).contains(&y)
}

/// Frame t's colour and depth, and per pixel the layer's motion p(t) − p(t−1) and
/// p(t+1) − p(t).
#[allow(clippy::type_complexity)]
fn frame(t: i64) -> ([Vec<f32>; 4], Vec<(f32, f32)>, Vec<(f32, f32)>) {
    let t = t as f32;
    let mut rgb = [
        vec![0.0; W * H],
        vec![0.0; W * H],
        vec![0.0; W * H],
        vec![10.0; W * H],
    ];
    let mut back = vec![(0.0, 0.0); W * H];
    let mut forward = vec![(0.0, 0.0); W * H];
    for y in 0..H {
        for x in 0..W {
            let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
            let i = y * W + x;
            let (path, seed): (fn(f32) -> (f32, f32), u32) = if on_square(cx, cy, t) {
                rgb[3][i] = 2.0;
                (foreground, 7)
            } else {
                (background, 3)
            };
            let (px, py) = path(t);
            for (c, plane) in rgb.iter_mut().take(3).enumerate() {
                plane[i] = texture(cx - px, cy - py, seed + c as u32);
            }
            let (a, b, c) = (path(t - 1.0), path(t), path(t + 1.0));
            back[i] = (b.0 - a.0, b.1 - a.1);
            forward[i] = (c.0 - b.0, c.1 - b.1);
        }
    }
    (rgb, back, forward)
}

/// How the vectors are disguised in a sequence.
#[derive(Clone, Copy)]
enum Disguise {
    /// Canonical: velocity p(0) − p(−1), pixels, y down.
    Canonical,
    /// Forward offsets p(+1) − p(0), y up (Nuke's forward).
    ForwardYUp,
    /// Velocity scaled by a half-open shutter (stored = 0.5 · velocity).
    HalfShutter,
    /// Backward offsets p(−1) − p(0), normalised to the frame, stored around 0.5.
    BackwardNormalised,
}

fn write_sequence(dir: &Path, disguise: Disguise) {
    for t in 1..=3 {
        write_frame(dir, t, t, false, disguise);
    }
}

/// File `number` of a sequence: frame t of the motion, or with `still` its picture with no
/// motion stored (the vectors of a frame whose neighbour is the same picture).
fn write_frame(dir: &Path, number: i64, t: i64, still: bool, disguise: Disguise) {
    let (rgb, mut back, mut forward) = frame(t);
    if still {
        back.fill((0.0, 0.0));
        forward.fill((0.0, 0.0));
    }
    let [r, g, b, z] = rgb;
    let (vx, vy): (Vec<f32>, Vec<f32>) = (0..W * H)
        .map(|i| match disguise {
            Disguise::Canonical => back[i],
            Disguise::ForwardYUp => (forward[i].0, -forward[i].1),
            Disguise::HalfShutter => (0.5 * back[i].0, 0.5 * back[i].1),
            Disguise::BackwardNormalised => {
                (0.5 - back[i].0 / W as f32, 0.5 - back[i].1 / H as f32)
            }
        })
        .unzip();
    write_exr(
        &dir.join(format!("c.{number:04}.exr")),
        W,
        H,
        vec![
            ("R", r),
            ("G", g),
            ("B", b),
            ("Z", z),
            ("mv.x", vx),
            ("mv.y", vy),
        ],
    );
}

fn fit(dir: &Path, preset: &Path) -> std::process::Output {
    shutter(&[
        "vectors",
        "--color",
        &s(&dir.join("c.####.exr")),
        "--channels",
        "mv.x,mv.y",
        "--write-preset",
        &s(preset),
    ])
}

fn blur(dir: &Path, presets: &[&Path], out: &str) -> Vec<(String, Vec<f32>)> {
    let mut args = vec![
        "blur".to_string(),
        "--algorithm".into(),
        "reconstruct".into(),
        "--color".into(),
        s(&dir.join("c.####.exr")),
        "--frames".into(),
        "2".into(),
        "-o".into(),
        s(&dir.join(out)),
        "-q".into(),
    ];
    for p in presets {
        args.push("--preset".into());
        args.push(s(p));
    }
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = shutter(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    read_exr_reference(&dir.join(out.replace("####", "0002")))
}

#[test]
fn three_disguised_conventions_are_recovered_and_blur_as_the_canonical() {
    let root = tempfile::tempdir().unwrap();
    // The canonical sequence's blur, through a preset naming the vector channels.
    let canonical = root.path().join("canonical");
    std::fs::create_dir_all(&canonical).unwrap();
    write_sequence(&canonical, Disguise::Canonical);
    let plain = root.path().join("plain.toml");
    std::fs::write(
        &plain,
        "[velocity]\nchannels = [[\"mv.x\", \"mv.y\"]]\nmeaning = \"velocity\"\n\
         [prev]\nchannels = [[\"mv.x\", \"mv.y\"]]\nmeaning = \"velocity\"\n\
         [next]\nchannels = [[\"mv.x\", \"mv.y\"]]\nmeaning = \"velocity\"\n",
    )
    .unwrap();
    let reference = blur(&canonical, &[&plain], "o.####.exr");
    // The canonical sequence fits as itself.
    let fitted = root.path().join("canonical.toml");
    let o = fit(&canonical, &fitted);
    assert_eq!(o.status.code(), Some(0), "{}\n{}", stdout(&o), stderr(&o));
    let text = std::fs::read_to_string(&fitted).unwrap();
    assert!(text.contains("meaning = \"velocity\""), "{text}");
    // Backward vectors answer for [velocity] and [prev]; [next] stays the preset's.
    assert!(
        text.contains("[prev]") && !text.contains("[next]"),
        "{text}"
    );
    assert!(text.contains("encoding = \"plain\""), "{text}");

    // The presets that state each disguise as it was written.
    let truth = |meaning: &str, extra: &str| {
        ["velocity", "prev", "next"]
            .map(|section| {
                format!("[{section}]\nchannels = [[\"mv.x\", \"mv.y\"]]\nmeaning = \"{meaning}\"\n{extra}")
            })
            .join("")
    };
    for (name, disguise, expect, truth) in [
        (
            "forward",
            Disguise::ForwardYUp,
            [
                "meaning = \"to_next\"",
                "y_up = true",
                "scale = 1.0",
                "zero = 0.0",
            ],
            truth("to_next", "y_up = true\n"),
        ),
        (
            "half",
            Disguise::HalfShutter,
            [
                "meaning = \"velocity\"",
                "y_up = false",
                "scale = 2.0",
                "zero = 0.0",
            ],
            truth("velocity", "scale = 2.0\n"),
        ),
        (
            "normalised",
            Disguise::BackwardNormalised,
            [
                "meaning = \"to_prev\"",
                "units = \"normalized\"",
                "scale = 1.0",
                "zero = 0.5",
            ],
            truth("to_prev", "units = \"normalized\"\nzero = 0.5\n"),
        ),
    ] {
        let dir = root.path().join(name);
        std::fs::create_dir_all(&dir).unwrap();
        write_sequence(&dir, disguise);
        let preset = root.path().join(format!("{name}.toml"));
        let o = fit(&dir, &preset);
        assert_eq!(
            o.status.code(),
            Some(0),
            "{name}: {}\n{}",
            stdout(&o),
            stderr(&o)
        );
        let text = std::fs::read_to_string(&preset).unwrap();
        for needle in expect {
            assert!(text.contains(needle), "{name}: {needle:?} not in\n{text}");
        }
        // Blurred through the preset written, the frame is the one the true reading gives
        // (for the backward disguises, the canonical sequence's).
        let got = blur(&dir, &[&preset], "o.####.exr");
        let stated = root.path().join(format!("{name}-truth.toml"));
        std::fs::write(&stated, truth).unwrap();
        let expected = blur(&dir, &[&stated], "t.####.exr");
        for ((n, a), (_, b)) in got.iter().zip(&expected) {
            let worst = a
                .iter()
                .zip(b)
                .map(|(x, y)| (x - y).abs())
                .fold(0.0f32, f32::max);
            assert!(worst < 1e-3, "{name}: channel {n} differs by {worst}");
        }
        if !matches!(disguise, Disguise::ForwardYUp) {
            // The colour (the vectors themselves come back as stored: they differ).
            for ((n, a), (_, b)) in got
                .iter()
                .zip(&reference)
                .filter(|((n, _), _)| n.len() == 1)
            {
                let worst = a
                    .iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0f32, f32::max);
                assert!(
                    worst < 1e-3,
                    "{name} against canonical: {n} differs by {worst}"
                );
            }
        }
    }
}

/// A sequence whose motion never changes vertically (a horizontal pan) says nothing about y:
/// the fit says so and writes no preset (exit 1); a still sequence fits nothing better than
/// no motion.
#[test]
fn what_the_frames_cannot_tell_is_reported_not_chosen() {
    let dir = tempfile::tempdir().unwrap();
    for t in 1..=3i64 {
        let shift = 3.0 * t as f32;
        let (mut r, mut g, mut b) = (vec![0.0; W * H], vec![0.0; W * H], vec![0.0; W * H]);
        for y in 0..H {
            for x in 0..W {
                let (cx, cy) = (x as f32 + 0.5 - shift, y as f32 + 0.5);
                let i = y * W + x;
                r[i] = texture(cx, cy, 1);
                g[i] = texture(cx, cy, 2);
                b[i] = texture(cx, cy, 3);
            }
        }
        write_exr(
            &dir.path().join(format!("c.{t:04}.exr")),
            W,
            H,
            vec![
                ("R", r),
                ("G", g),
                ("B", b),
                ("mv.x", vec![3.0; W * H]),
                ("mv.y", vec![0.0; W * H]),
            ],
        );
    }
    let preset = dir.path().join("p.toml");
    let o = fit(dir.path(), &preset);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    assert!(stdout(&o).contains("undecided"), "{}", stdout(&o));
    assert!(!preset.exists());
}

/// F5, a real Cycles render in small (160×90): a flat grey square moving 35 px a frame before
/// a still checker wall of 22-pixel squares, its vectors stored as Blender stores them. The
/// square has nothing to follow, so nothing fits better than no motion, and no motion is
/// printed by the readings' own measure (each point's error capped at a pixel). Before, the
/// wall's covered and uncovered points matched the checker a period away and no motion
/// printed as an uncapped 7 px, beside "readings" of scale 0.02 that moved nothing.
#[test]
fn a_flat_square_before_a_checker_wall_is_reported_as_no_motion() {
    let (cw, ch) = (160, 90);
    let dir = tempfile::tempdir().unwrap();
    for t in 1..=3i64 {
        let corner = (25.0 + 35.0 * (t - 1) as f32, 24.0 + (t - 1) as f32);
        let mut grey = vec![0.0; cw * ch];
        let mut stored = (vec![0.0; cw * ch], vec![0.0; cw * ch]);
        for y in 0..ch {
            for x in 0..cw {
                let (cx, cy) = (x as f32 + 0.5, y as f32 + 0.5);
                let i = y * cw + x;
                let on_square = (corner.0..corner.0 + 40.0).contains(&cx)
                    && (corner.1..corner.1 + 40.0).contains(&cy);
                grey[i] = if on_square {
                    // to_prev, y up: where the square was a frame before, relative to now.
                    stored.0[i] = -35.0;
                    stored.1[i] = 1.0;
                    0.45
                } else if ((cx / 22.0).floor() as i64 + (cy / 22.0).floor() as i64) % 2 == 0 {
                    0.8
                } else {
                    0.2
                };
            }
        }
        write_exr(
            &dir.path().join(format!("c.{t:04}.exr")),
            cw,
            ch,
            vec![
                ("R", grey.clone()),
                ("G", grey.clone()),
                ("B", grey),
                ("mv.x", stored.0),
                ("mv.y", stored.1),
            ],
        );
    }
    let preset = dir.path().join("p.toml");
    let o = fit(dir.path(), &preset);
    let out = stdout(&o);
    assert_eq!(o.status.code(), Some(1), "{out}");
    assert!(
        out.contains("undecided: nothing fits clearly better than no motion"),
        "{out}"
    );
    let no_motion: f64 = out
        .split("no motion fits to ")
        .nth(1)
        .and_then(|rest| rest.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no motion's figure: {out}"));
    assert!(no_motion <= 1.0, "{out}");
    assert!(!preset.exists());
}

/// `blur` checks the preset's reading before it blurs: a wrong y axis is warned about, naming
/// the reading that fits; the right one is not; `--check-vectors off` skips the check.
#[test]
fn blur_warns_when_another_reading_fits_clearly_better() {
    let dir = tempfile::tempdir().unwrap();
    write_sequence(dir.path(), Disguise::Canonical);
    let preset = |y_up: bool| {
        let path = dir.path().join(format!("y{y_up}.toml"));
        std::fs::write(
            &path,
            ["velocity", "prev"]
                .map(|section| {
                    format!("[{section}]\nchannels = [[\"mv.x\", \"mv.y\"]]\nmeaning = \"velocity\"\ny_up = {y_up}\n")
                })
                .join(""),
        )
        .unwrap();
        s(&path)
    };
    let run = |preset: &str, extra: &[&str]| {
        let algorithm = if extra.contains(&"scatter") {
            "scatter"
        } else {
            "reconstruct"
        };
        let mut args = vec!["blur", "--algorithm", algorithm, "--color"];
        let color = s(&dir.path().join("c.####.exr"));
        let out = s(&dir.path().join("out/o.####.exr"));
        args.extend([color.as_str(), "-o", out.as_str(), "--preset", preset]);
        args.extend(extra.iter().filter(|a| **a != "scatter"));
        let o = shutter(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    let wrong = run(&preset(true), &[]);
    assert!(
        wrong.contains("fit another reading better than the preset's")
            && wrong.contains("velocity, y down"),
        "{wrong}"
    );
    assert!(!run(&preset(false), &[]).contains("another reading"));
    assert!(!run(&preset(true), &["--check-vectors", "off"]).contains("another reading"));
    // Scatter reads [prev]: that section is checked.
    let scatter = run(&preset(true), &["scatter"]);
    assert!(scatter.contains("another reading"), "{scatter}");
}

/// The check fits frames the run reads: a still start (three frames of one picture, no
/// motion stored) says nothing, and the check goes on to the first frame that moves; a farm
/// chunk of one frame reads the neighbour its reading looks toward (the previous) from disk;
/// a chunk of two fits its second frame against its first, read by the run. `--json` says
/// which frames it fitted and what it found; the frames written are the same without it.
#[test]
fn blur_checks_past_a_still_start_and_in_chunks_of_one_and_two_frames() {
    let dir = tempfile::tempdir().unwrap();
    // Files 1-3 hold frame 1's picture, still; files 4 and 5 move on from it.
    for number in 1..=5 {
        write_frame(
            dir.path(),
            number,
            (number - 2).max(1),
            number <= 3,
            Disguise::Canonical,
        );
    }
    let preset = |y_up: bool| {
        let path = dir.path().join(format!("y{y_up}.toml"));
        std::fs::write(
            &path,
            format!("[velocity]\nchannels = [[\"mv.x\", \"mv.y\"]]\nmeaning = \"velocity\"\ny_up = {y_up}\n"),
        )
        .unwrap();
        s(&path)
    };
    let run = |preset: &str, frames: &str, check: &str| {
        let color = s(&dir.path().join("c.####.exr"));
        let out = s(&dir.path().join(format!("out{frames}{check}/o.####.exr")));
        let o = shutter(&[
            "blur",
            "--algorithm",
            "reconstruct",
            "--color",
            &color,
            "--frames",
            frames,
            "-o",
            &out,
            "--preset",
            preset,
            "--json",
            "--check-vectors",
            check,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (stderr(&o), report["vector_check"].clone())
    };
    let fitted = |check: &serde_json::Value| -> (Vec<i64>, String) {
        let frames = check["frames"].as_array().unwrap();
        (
            frames.iter().map(|f| f.as_i64().unwrap()).collect(),
            check["outcome"].as_str().unwrap().to_string(),
        )
    };
    let (wrong, check) = run(&preset(true), "1-5", "on");
    assert!(
        wrong.contains("measured on frame 4 against frames 3 and 5"),
        "{wrong}"
    );
    assert_eq!(fitted(&check), (vec![2, 3, 4], "warned".into()));
    assert!(check["seconds"].as_f64().unwrap() > 0.0);
    let (right, check) = run(&preset(false), "1-5", "on");
    assert!(!right.contains("another reading"), "{right}");
    assert_eq!(fitted(&check), (vec![2, 3, 4], "fits".into()));
    // Off: no report, and the same frames.
    let (_, off) = run(&preset(false), "1-5", "off");
    assert!(off.is_null(), "{off}");
    for f in 1..=5 {
        let frame = |check: &str| {
            read_exr_reference(&dir.path().join(format!("out1-5{check}/o.{f:04}.exr")))
        };
        assert!(
            frame("on") == frame("off"),
            "frame {f} differs with the check"
        );
    }
    // Chunks: one frame reads frame 3 from disk; two fit frame 5 against frame 4.
    let (chunk, check) = run(&preset(true), "4", "on");
    assert!(
        chunk.contains("measured on frame 4 against frame 3:"),
        "{chunk}"
    );
    assert_eq!(fitted(&check), (vec![4], "warned".into()));
    let (pair, check) = run(&preset(true), "4-5", "on");
    assert!(
        pair.contains("measured on frame 5 against frame 4:"),
        "{pair}"
    );
    assert_eq!(fitted(&check), (vec![5], "warned".into()));
    let (still, check) = run(&preset(true), "2", "on");
    assert!(!still.contains("another reading"), "{still}");
    assert_eq!(fitted(&check), (vec![2], "nothing to judge".into()));
}

/// A real Cycles render (fixtures/cycles, Blender 5.2.3): the fit finds exactly what the
/// `blender` preset states, for X,Y (backward offsets, y up) and for Z,W (forward, y up);
/// `blur`'s check passes the preset and warns about it with y flipped.
#[test]
fn a_real_cycles_render_fits_the_blender_preset() {
    let root = env!("CARGO_MANIFEST_DIR");
    let color = format!("{root}/fixtures/cycles/shot.####.exr");
    let fit = |channels: &str| {
        let o = shutter(&[
            "vectors",
            "--preset",
            "blender",
            "--color",
            &color,
            "--channels",
            channels,
            "--json",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        report["chosen"].clone()
    };
    let xy = fit("ViewLayer.Vector.X,ViewLayer.Vector.Y");
    assert_eq!(xy["meaning"], "to_prev", "{xy}");
    let zw = fit("ViewLayer.Vector.Z,ViewLayer.Vector.W");
    assert_eq!(zw["meaning"], "from_next", "{zw}");
    for chosen in [&xy, &zw] {
        assert_eq!(chosen["y_up"], true, "{chosen}");
        assert_eq!(chosen["swap"], false, "{chosen}");
        assert_eq!(chosen["zero"], 0.0, "{chosen}");
        assert_eq!(chosen["scale"], 1.0, "{chosen}");
        assert_eq!(chosen["units"], "pixels", "{chosen}");
        assert!(chosen["residual"].as_f64().unwrap() < 0.3, "{chosen}");
    }
    let dir = tempfile::tempdir().unwrap();
    let y_down = dir.path().join("y_down.toml");
    std::fs::write(&y_down, "[velocity]\ny_up = false\n").unwrap();
    let blur = |presets: &[&str]| {
        let out = s(&dir.path().join("o.####.exr"));
        let mut args = vec![
            "blur",
            "--algorithm",
            "reconstruct",
            "--color",
            &color,
            "-o",
            &out,
            "--json",
        ];
        for p in presets {
            args.extend(["--preset", p]);
        }
        let o = shutter(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        (stderr(&o), report["vector_check"]["outcome"].clone())
    };
    let (right, outcome) = blur(&["blender"]);
    assert!(!right.contains("another reading"), "{right}");
    assert_eq!(outcome, "fits");
    let (wrong, outcome) = blur(&["blender", &s(&y_down)]);
    assert!(
        wrong.contains("another reading") && wrong.contains("to_prev, y up"),
        "{wrong}"
    );
    assert_eq!(outcome, "warned");
}

/// `--write-preset` naming an input (QA): `--write-preset cyc/shot.0003.exr` replaced frame 3
/// of the colour with TOML and exited 0. Any input is refused before anything is written, as
/// blur refuses an `-o` that names one: every frame of the colour pattern (read or not), and
/// the vector pass, however the name is spelt or linked.
#[test]
fn a_preset_written_over_an_input_is_refused() {
    let root = env!("CARGO_MANIFEST_DIR");
    let dir = tempfile::tempdir().unwrap();
    let cyc = dir.path().join("cyc");
    std::fs::create_dir(&cyc).unwrap();
    for f in 1..=3 {
        let name = format!("shot.{f:04}.exr");
        std::fs::copy(format!("{root}/fixtures/cycles/{name}"), cyc.join(&name)).unwrap();
        std::fs::copy(cyc.join(&name), cyc.join(format!("vec.{f:04}.exr"))).unwrap();
    }
    #[cfg(unix)]
    std::os::unix::fs::symlink(cyc.join("shot.0001.exr"), dir.path().join("link.exr")).unwrap();
    let color = s(&cyc.join("shot.####.exr"));
    let velocity = s(&cyc.join("vec.####.exr"));
    let before = snapshot(&cyc);
    let mut targets = vec![
        (s(&cyc.join("shot.0003.exr")), false),
        (s(&cyc.join("shot.0001.exr")), false),
        (format!("{}/./shot.0002.exr", cyc.display()), false),
        (s(&cyc.join("vec.0002.exr")), true),
    ];
    if cfg!(unix) {
        targets.push((s(&dir.path().join("link.exr")), false));
    }
    for (target, separate) in &targets {
        let mut args = vec!["vectors", "--preset", "blender", "--color", &color];
        if *separate {
            args.extend(["--velocity", &velocity]);
        }
        args.extend(["--write-preset", target]);
        let o = shutter(&args);
        assert_eq!(o.status.code(), Some(1), "{target}: {}", stderr(&o));
        assert!(stderr(&o).contains("overwrite the input"), "{}", stderr(&o));
        assert!(stderr(&o).contains("--write-preset"), "{}", stderr(&o));
        assert_eq!(snapshot(&cyc), before, "{target}");
        // Refused before the fit: nothing printed.
        assert!(o.stdout.is_empty(), "{}", stdout(&o));
    }
    // A preset file the fit reads is an input too.
    let given = dir.path().join("given.toml");
    std::fs::write(&given, "[velocity]\n").unwrap();
    let o = shutter(&[
        "vectors",
        "--preset",
        "blender",
        "--preset",
        &s(&given),
        "--color",
        &color,
        "--write-preset",
        &format!("{}/./given.toml", dir.path().display()),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("overwrite the input"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&given).unwrap(), "[velocity]\n");
    // Elsewhere it is written.
    let preset = dir.path().join("fit.toml");
    let o = shutter(&[
        "vectors",
        "--preset",
        "blender",
        "--color",
        &color,
        "--write-preset",
        &s(&preset),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(std::fs::read_to_string(&preset)
        .unwrap()
        .contains("[velocity]"));
}
