//! Layer stacks (`--layers`, issue 33): a shot rendered in view layers, each blurred alone
//! with its own depth and motion and merged front over back. The frames are Blender's
//! multi-layer EXRs (`<layer>.Combined.RGBA`, `.Depth.Z`, `.Vector.XYZW`, pixels with y up,
//! X, Y = p(−1) − p(0)), written here.

use std::path::{Path, PathBuf};

use crate::dof::lens_flags;
use crate::support::*;

const W: usize = 96;
const H: usize = 16;
/// The still box of the foreground layer: columns [BOX.0, BOX.1).
const BOX: (usize, usize) = (40, 56);
const BOX_RGB: [f32; 3] = [0.9, 0.3, 0.1];
/// The background pans right this many pixels a frame (the default shutter, 0.5 of the
/// frame centred on it, streaks it over 10 px).
const PAN: f32 = 20.0;
const STRIPE_PERIOD: f32 = 12.0;

/// The background's texture at screen x (a pixel's centre is i + 0.5) at the frame's time.
fn stripes(x: f32) -> f32 {
    0.5 + 0.4 * (std::f32::consts::TAU * x / STRIPE_PERIOD).sin()
}

/// The background at pixel i over the exposure, worked out by hand: the texture moves right
/// by PAN a frame, the shutter is open over t ∈ [−¼, ¼], so the pixel sees the texture over
/// [x − PAN/4, x + PAN/4] evenly; the mean of a sinusoid over a window of width L is its
/// value at the centre times sin(πL/P)/(πL/P).
fn streaked(i: usize) -> f32 {
    let x = i as f32 + 0.5;
    let l = PAN / 2.0;
    let k = std::f32::consts::PI * l / STRIPE_PERIOD;
    0.5 + 0.4 * (std::f32::consts::TAU * x / STRIPE_PERIOD).sin() * k.sin() / k
}

fn in_box(i: usize) -> bool {
    (BOX.0..BOX.1).contains(&(i % W))
}

/// The channels of layer `name`: colour (premultiplied), alpha, depth, vector (X, Y, Z, W).
fn layer_channels(
    name: &str,
    rgb: [Vec<f32>; 3],
    alpha: Vec<f32>,
    depth: Vec<f32>,
    motion: Vec<f32>,
) -> Vec<(String, Vec<f32>)> {
    let [r, g, b] = rgb;
    let n = W * H;
    vec![
        (format!("{name}.Combined.R"), r),
        (format!("{name}.Combined.G"), g),
        (format!("{name}.Combined.B"), b),
        (format!("{name}.Combined.A"), alpha),
        (format!("{name}.Depth.Z"), depth),
        // Blender's X, Y = p(−1) − p(0) and Z, W = p(0) − p(+1), y up: a pixel moving
        // right by m has X = Z = −m.
        (
            format!("{name}.Vector.X"),
            motion.iter().map(|m| -m).collect(),
        ),
        (format!("{name}.Vector.Y"), vec![0.0; n]),
        (
            format!("{name}.Vector.Z"),
            motion.iter().map(|m| -m).collect(),
        ),
        (format!("{name}.Vector.W"), vec![0.0; n]),
    ]
}

/// The panning background layer `BG` (every pixel covered, depth 30).
fn background() -> Vec<(String, Vec<f32>)> {
    let n = W * H;
    let value: Vec<f32> = (0..n).map(|i| stripes((i % W) as f32 + 0.5)).collect();
    layer_channels(
        "BG",
        [value.clone(), value.clone(), value],
        vec![1.0; n],
        vec![30.0; n],
        vec![PAN; n],
    )
}

/// The foreground layer `FG`: a still box at depth 3; its empty pixels hold `empty_depth`
/// and move by `empty_motion` (what they say must not matter).
fn foreground(empty_depth: f32, empty_motion: f32) -> Vec<(String, Vec<f32>)> {
    foreground_moving(0.0, empty_depth, empty_motion)
}

/// [`foreground`] with the box moving right by `motion` px a frame.
fn foreground_moving(motion: f32, empty_depth: f32, empty_motion: f32) -> Vec<(String, Vec<f32>)> {
    let n = W * H;
    let plane = |inside: f32, outside: f32| -> Vec<f32> {
        (0..n)
            .map(|i| if in_box(i) { inside } else { outside })
            .collect()
    };
    layer_channels(
        "FG",
        BOX_RGB.map(|c| plane(c, 0.0)),
        plane(1.0, 0.0),
        plane(3.0, empty_depth),
        plane(motion, empty_motion),
    )
}

fn write(path: &Path, layers: Vec<Vec<(String, Vec<f32>)>>) {
    let channels: Vec<(String, Vec<f32>)> = layers.into_iter().flatten().collect();
    write_exr(
        path,
        W,
        H,
        channels
            .iter()
            .map(|(n, p)| (n.as_str(), p.clone()))
            .collect(),
    );
}

/// Runs `shutter <command> --preset blender --color <input> -o <out> <args…>`, checks it
/// succeeded, and returns the output's channels.
fn run(command: &str, input: &Path, out: PathBuf, args: &[&str]) -> Vec<(String, Vec<f32>)> {
    run_json(command, input, out, args).0
}

/// [`run`] with `--json`: the output's channels and the run's JSON summary.
fn run_json(
    command: &str,
    input: &Path,
    out: PathBuf,
    args: &[&str],
) -> (Vec<(String, Vec<f32>)>, serde_json::Value) {
    let mut all = vec![
        command,
        "--preset",
        "blender",
        "--color",
        input.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
    ];
    all.extend(args);
    let o = shutter(&all);
    assert!(o.status.success(), "{all:?}: {}", stderr(&o));
    let json = serde_json::from_str(&stdout(&o)).unwrap();
    (read_exr_reference(&out), json)
}

/// An empty pixel of a layer (alpha 0) neither moves nor hides anything, whatever its
/// passes say: here the foreground's empty pixels claim to be nearer than its box and to
/// move 30 px a frame (or, for depth of field, to lie far out of focus in front of it). The
/// box stays exactly as it is and every pixel it does not cover is exactly what the
/// background alone gives.
#[test]
fn an_empty_layer_pixel_neither_moves_nor_darkens_what_is_behind_it() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("layers.exr");
    write(&input, vec![foreground(0.5, -30.0), background()]);
    let cases: Vec<(&str, Vec<&str>)> = vec![
        ("blur", vec!["--algorithm", "reconstruct"]),
        ("blur", vec!["--algorithm", "scatter"]),
        ("blur", vec!["--algorithm", "stretch"]),
        ("dof", [&["--method", "gather"][..], &lens_flags()].concat()),
        ("dof", [&["--method", "blend"][..], &lens_flags()].concat()),
    ];
    for (command, args) in cases {
        let what = format!("{command} {}", args[1]);
        let stacked = run(
            command,
            &input,
            dir.path().join(format!("stack-{}.exr", args[1])),
            &[&args[..], &["--layers", "FG,BG"]].concat(),
        );
        let alone = run(
            command,
            &input,
            dir.path().join(format!("bg-{}.exr", args[1])),
            &[&args[..], &["--layer", "BG"]].concat(),
        );
        for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
            let merged = channel(&stacked, name);
            let behind = channel(&alone, &format!("BG.Combined.{name}"));
            for i in 0..W * H {
                let expected = if in_box(i) { BOX_RGB[c] } else { behind[i] };
                assert!(
                    (merged[i] - expected).abs() <= 1e-6,
                    "{what} {name} at ({}, {}): {} where {expected} (in the box: {})",
                    i % W,
                    i / W,
                    merged[i],
                    in_box(i)
                );
            }
        }
        let alpha = channel(&stacked, "A");
        assert!(alpha.iter().all(|&a| (a - 1.0).abs() <= 1e-6), "{what}: A");
        // The layers go out beside the merged beauty, each blurred with its own weights.
        let fg = channel(&stacked, "FG.Combined.A");
        assert!(
            (0..W * H).all(|i| fg[i] == if in_box(i) { 1.0 } else { 0.0 }),
            "{what}: the still box's layer is as it was"
        );
        assert_same_bits(
            channel(&stacked, "BG.Combined.R"),
            channel(&alone, "BG.Combined.R"),
            &format!("{what}: BG.Combined.R"),
        );
    }
}

/// A still foreground over a panning background: the box stays sharp, and the background
/// streaks right up to its edge with what the background layer holds behind it (worked out
/// by hand above), where a single layer can only guess what the box hides.
#[test]
fn a_still_foreground_over_a_panning_background_stays_sharp_with_the_background_streaking_to_its_edge(
) {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("layers.exr");
    // Blender's empty pixels: depth 10¹⁰, no motion.
    write(&input, vec![foreground(1e10, 0.0), background()]);
    // The same frame as one layer: the box where it is, the background elsewhere.
    let single = dir.path().join("single.exr");
    let n = W * H;
    let pick = |inside: f32, outside: &[f32]| -> Vec<f32> {
        (0..n)
            .map(|i| if in_box(i) { inside } else { outside[i] })
            .collect()
    };
    let bg = background();
    let value = &bg[0].1;
    write(
        &single,
        vec![layer_channels(
            "ViewLayer",
            BOX_RGB.map(|c| pick(c, value)),
            vec![1.0; n],
            pick(3.0, &vec![30.0; n]),
            pick(0.0, &vec![PAN; n]),
        )],
    );
    for algorithm in ["reconstruct", "scatter", "stretch"] {
        let args = ["--algorithm", algorithm];
        let stacked = run(
            "blur",
            &input,
            dir.path().join(format!("stack-{algorithm}.exr")),
            &[&args[..], &["--layers", "FG,BG"]].concat(),
        );
        let one = run(
            "blur",
            &single,
            dir.path().join(format!("one-{algorithm}.exr")),
            &args,
        );
        let r = channel(&stacked, "R");
        for i in (0..n).filter(|&i| in_box(i)) {
            assert!(
                (r[i] - BOX_RGB[0]).abs() <= 1e-6,
                "{algorithm}: the box at ({}, {}) is {}, not sharp",
                i % W,
                i / W,
                r[i]
            );
        }
        // The three pixels each side of the box: what the background holds behind it.
        let beside: Vec<usize> = (0..n)
            .filter(|&i| {
                let x = i % W;
                (BOX.0 - 3..BOX.0).contains(&x) || (BOX.1..BOX.1 + 3).contains(&x)
            })
            .collect();
        // And the pixels away from the box and from the frame's edges: the algorithm's own
        // error on a pan.
        let away: Vec<usize> = (0..n)
            .filter(|&i| {
                let x = i % W;
                (10..BOX.0 - 10).contains(&x) || (BOX.1 + 10..W - 10).contains(&x)
            })
            .collect();
        let worst = |plane: &[f32], at: &[usize]| {
            (at.iter())
                .map(|&i| (plane[i] - streaked(i % W)).abs())
                .fold(0.0f32, f32::max)
        };
        let one = channel(&one, "ViewLayer.Combined.R");
        let (stack_error, single_error, own) =
            (worst(r, &beside), worst(one, &beside), worst(r, &away));
        eprintln!(
            "{algorithm}: beside the box, stack {stack_error}, single layer {single_error}; \
             away from it {own}"
        );
        assert!(
            own <= 0.03 && stack_error <= own + 0.002,
            "{algorithm}: beside the box the stack errs {stack_error}, away from it {own}"
        );
        assert!(
            single_error >= 4.0 * stack_error.max(0.005),
            "{algorithm}: the single layer errs {single_error} beside the box, the stack \
             {stack_error}: the case does not show what layers fix"
        );
    }
}

/// Three layers merge in their order, front over back: premultiplied halves of red and green
/// over opaque blue give R ½, G ¼, B ¼, A 1 (still layers: the blur leaves them as they are);
/// given back to front, blue covers everything.
#[test]
fn three_layers_merge_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("three.exr");
    let n = W * H;
    let flat = |v: f32| vec![v; n];
    let layer = |name: &str, rgb: [f32; 3], a: f32, depth: f32| {
        layer_channels(name, rgb.map(flat), flat(a), flat(depth), flat(0.0))
    };
    write(
        &input,
        vec![
            layer("Red", [0.5, 0.0, 0.0], 0.5, 1.0),
            layer("Green", [0.0, 0.5, 0.0], 0.5, 2.0),
            layer("Blue", [0.0, 0.0, 1.0], 1.0, 3.0),
        ],
    );
    for (order, expected) in [
        ("Red,Green,Blue", [0.5, 0.25, 0.25, 1.0]),
        ("Blue,Green,Red", [0.0, 0.0, 1.0, 1.0]),
        ("Green,Red,Blue", [0.25, 0.5, 0.25, 1.0]),
    ] {
        let out = run(
            "blur",
            &input,
            dir.path().join("o.exr"),
            &["--algorithm", "reconstruct", "--layers", order],
        );
        for (name, want) in ["R", "G", "B", "A"].into_iter().zip(expected) {
            let got = channel(&out, name);
            assert!(
                got.iter().all(|&v| (v - want).abs() <= 1e-6),
                "{order}: {name} is {} where {want}",
                got[0]
            );
        }
        // Each layer goes out beside the merge, as it was (nothing moves).
        assert!(channel(&out, "Green.Combined.G").iter().all(|&v| v == 0.5));
        // What made it says which layers, in which order.
        let meta = exr::meta::MetaData::read_from_file(dir.path().join("o.exr"), false).unwrap();
        let record = meta.headers[0]
            .own_attributes
            .other
            .get(&exr::prelude::Text::from("shutter/settings"));
        assert!(
            matches!(record, Some(exr::prelude::AttributeValue::Text(t))
                if t.to_string().ends_with(&format!("--layers {order}"))),
            "{record:?}"
        );
    }
}

/// `--layers` asks for a preset that names channels by view layer, and for each layer once.
/// Layer files of different sizes in every frame: the preflight names every frame's mismatch
/// (it named frame 1's alone) and writes nothing.
#[test]
fn a_stack_whose_layers_differ_in_size_names_every_frame() {
    let dir = tempfile::tempdir().unwrap();
    for frame in 1..=2 {
        for (name, width) in [("fg", 8usize), ("bg", 10)] {
            let n = width * 4;
            let path = dir.path().join(format!("{name}.{frame:04}.exr"));
            let channels = ["R", "G", "B", "A", "Z", "velocity.X", "velocity.Y"]
                .into_iter()
                .map(|c| (c, vec![if c == "velocity.Y" { 0.0 } else { 1.0 }; n]))
                .collect();
            write_exr(&path, width, 4, channels);
        }
    }
    let (fg, bg) = (
        dir.path().join("fg.####.exr"),
        dir.path().join("bg.####.exr"),
    );
    let out = dir.path().join("out");
    let o = shutter(&[
        "blur",
        "--algorithm",
        "reconstruct",
        "--color",
        &s(&fg),
        "--color",
        &s(&bg),
        "-o",
        &s(&out.join("o.####.exr")),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    for frame in ["bg.0001.exr, frame 1", "bg.0002.exr, frame 2"] {
        assert!(
            err.contains(&format!(
                "size mismatch: {}",
                dir.path().join(frame).display()
            )),
            "{err}"
        );
    }
    assert!(err.contains("2 problems found"), "{err}");
    assert!(!out.exists() || std::fs::read_dir(&out).unwrap().next().is_none());
}

#[test]
fn layers_need_a_preset_of_view_layers_and_each_layer_once() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("layers.exr");
    write(&input, vec![foreground(1e10, 0.0), background()]);
    let out = s(&dir.path().join("o.exr"));
    let o = shutter(&[
        "blur",
        "--color",
        &s(&input),
        "-o",
        &out,
        "--layers",
        "FG,BG",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("names no channel by view layer"),
        "{}",
        stderr(&o)
    );
    let o = shutter(&[
        "blur",
        "--preset",
        "blender",
        "--color",
        &s(&input),
        "-o",
        &out,
        "--layers",
        "FG,FG",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("each view layer once"),
        "{}",
        stderr(&o)
    );
    let o = shutter(&[
        "blur",
        "--preset",
        "blender",
        "--color",
        &s(&input),
        "-o",
        &out,
        "--layers",
        "FG,Nope",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("Nope"), "{}", stderr(&o));
    assert!(!Path::new(&out).exists());
}

/// Runs `shutter <command> --preset blender --color <input> -o <out> --layers FG,BG --backend
/// <backend> <args…>` ([`run_json`]), checks that it ran on that backend (on wgpu with no
/// stage left to the CPU), and returns the output's channels.
#[cfg(feature = "gpu")]
fn stack_on(
    command: &str,
    input: &Path,
    out: PathBuf,
    backend: &str,
    args: &[&str],
) -> Vec<(String, Vec<f32>)> {
    let all = [&["--layers", "FG,BG", "--backend", backend][..], args].concat();
    let (channels, json) = run_json(command, input, out, &all);
    assert_eq!(json["backend"]["used"], backend, "{all:?}: {json}");
    if backend == "wgpu" {
        assert_eq!(json["backend"]["stages_on_cpu"], 0, "{all:?}: {json}");
    }
    channels
}

/// A stack on `--backend wgpu` gives the CPU's stack within each pass's own parity bound
/// (tests/gpu_reconstruct.rs, gpu_scatter.rs, gpu_stretch.rs for the motion blurs, 1e-3 of
/// the range as tests/gpu_dof.rs for depth of field): each layer runs through the pass's
/// twins, and the merge is the same arithmetic on both. A box moving 8 px a frame over the
/// panning background, and in focus before it.
#[cfg(feature = "gpu")]
#[test]
fn a_stack_on_wgpu_equals_the_cpu_within_each_pass_s_tolerance() {
    if crate::gpu::with_gpu::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("layers.exr");
    write(
        &input,
        vec![foreground_moving(-8.0, 1e10, 0.0), background()],
    );
    let cases: Vec<(&str, Vec<&str>, ParityBound)> = vec![
        (
            "blur",
            vec!["--algorithm", "reconstruct"],
            crate::gpu_reconstruct::BOUND,
        ),
        (
            "blur",
            vec!["--algorithm", "scatter"],
            crate::gpu_scatter::BOUND,
        ),
        (
            "blur",
            vec!["--algorithm", "stretch"],
            crate::gpu_stretch::BOUND,
        ),
        (
            "dof",
            [&["--method", "gather"][..], &lens_flags()].concat(),
            (1e-3, 1e-3, 0.0, 1e-3),
        ),
        (
            "dof",
            [&["--method", "blend"][..], &lens_flags()].concat(),
            (1e-3, 1e-3, 0.0, 1e-3),
        ),
    ];
    for (command, args, bound) in cases {
        let what = format!("{command} {}", args[1]);
        let outputs: Vec<_> = ["cpu", "wgpu"]
            .into_iter()
            .map(|backend| {
                let out = dir.path().join(format!("{}-{backend}.exr", args[1]));
                stack_on(command, &input, out, backend, &args)
            })
            .collect();
        let input = read_exr_reference(&input);
        for name in ["R", "G", "B", "A"] {
            let (cpu, got) = (channel(&outputs[0], name), channel(&outputs[1], name));
            assert_twin_within(&format!("stack {what} {name}"), got, cpu, bound);
        }
        assert_ne!(
            channel(&outputs[0], "R"),
            channel(&input, "BG.Combined.R"),
            "{what}: nothing was blurred"
        );
    }
}

/// A stack rendered one file per layer (`--color` repeated, front first, each pass once per
/// file) merges as the same layers in one file do, bit for bit, and each layer goes out
/// under its file's name (`fg.R`).
#[test]
fn a_stack_of_one_file_per_layer_merges_as_one_file_of_view_layers_does() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("layers.exr");
    let (fg, bg) = (foreground_moving(-8.0, 1e10, 0.0), background());
    write(&input, vec![fg.clone(), bg.clone()]);
    // Each layer as canonical pass files: colour, depth, and velocity p(0) − p(−1), y down
    // (Blender's X is p(−1) − p(0): its negation).
    let mut flags: Vec<String> = Vec::new();
    for (stem, layer) in [("fg", &fg), ("bg", &bg)] {
        let get = |suffix: &str| {
            layer
                .iter()
                .find(|(n, _)| n.ends_with(suffix))
                .unwrap()
                .1
                .clone()
        };
        let path = |what: &str| dir.path().join(format!("{stem}.{what}.exr"));
        write_exr(
            &path("color"),
            W,
            H,
            vec![
                ("R", get("Combined.R")),
                ("G", get("Combined.G")),
                ("B", get("Combined.B")),
                ("A", get("Combined.A")),
            ],
        );
        write_exr(&path("depth"), W, H, vec![("Z", get("Depth.Z"))]);
        let x: Vec<f32> = get("Vector.X").iter().map(|v| -v).collect();
        write_exr(
            &path("velocity"),
            W,
            H,
            vec![("X", x), ("Y", vec![0.0; W * H])],
        );
        for what in ["color", "depth", "velocity"] {
            flags.push(format!("--{what}"));
            flags.push(s(&path(what)));
        }
    }
    let stacked = run(
        "blur",
        &input,
        dir.path().join("one-file.exr"),
        &["--algorithm", "reconstruct", "--layers", "FG,BG"],
    );
    let out = dir.path().join("files.exr");
    let mut args = vec![
        "blur",
        "--algorithm",
        "reconstruct",
        "-o",
        out.to_str().unwrap(),
    ];
    args.extend(flags.iter().map(String::as_str));
    let o = shutter(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let files = read_exr_reference(&out);
    for name in ["R", "G", "B", "A"] {
        assert_same_bits(channel(&files, name), channel(&stacked, name), name);
        assert_same_bits(
            channel(&files, &format!("fg.{name}")),
            channel(&stacked, &format!("FG.Combined.{name}")),
            name,
        );
    }
    // A pass given for some layers and not others says what it wants.
    let o = shutter(&[
        "blur",
        "--color",
        &flags[1],
        "--color",
        &flags[7],
        "--depth",
        &flags[3],
        "-o",
        &s(&dir.path().join("x.exr")),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("once per colour file"),
        "{}",
        stderr(&o)
    );
}

/// `--layer FG` on a file of two view layers blurs FG alone: the other layer's channels come
/// back as they came, not blurred with FG's weights as if they were light of FG.
#[test]
fn one_view_layer_of_several_leaves_the_others_as_they_came() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("layers.exr");
    write(
        &input,
        vec![foreground_moving(-8.0, 1e10, 0.0), background()],
    );
    let out = run(
        "blur",
        &input,
        dir.path().join("fg.exr"),
        &["--algorithm", "reconstruct", "--layer", "FG"],
    );
    let stored = read_exr_reference(&input);
    for name in [
        "BG.Combined.R",
        "BG.Combined.A",
        "BG.Depth.Z",
        "BG.Vector.X",
    ] {
        assert_same_bits(channel(&out, name), channel(&stored, name), name);
    }
    assert_ne!(
        channel(&out, "FG.Combined.R"),
        channel(&stored, "FG.Combined.R"),
        "FG is blurred"
    );
}

/// Each part of an EXR: its name (empty where it has none) and its channels' names.
fn parts_of(path: &Path) -> Vec<(String, Vec<String>)> {
    (read_exr_layers(path).iter())
        .map(|l| {
            let part = l.attributes.layer_name.as_ref().map(|t| t.to_string());
            let channels = (l.channel_data.list.iter())
                .map(|c| c.name.to_string())
                .collect();
            (part.unwrap_or_default(), channels)
        })
        .collect()
}

/// The parts Blender 5 writes for `layers` (named `names`): a part a pass, `FG.Combined`
/// holding `FG.Combined.R`, ….
fn blender5_parts(layers: Vec<Vec<(String, Vec<f32>)>>, names: &[&str]) -> Vec<Part> {
    let mut parts = Vec::new();
    for (layer, name) in layers.into_iter().zip(names) {
        for pass in ["Combined", "Depth", "Vector"] {
            let prefix = format!("{name}.{pass}.");
            let channels: Vec<_> = (layer.iter())
                .filter(|(n, _)| n.starts_with(&prefix))
                .cloned()
                .collect();
            let part = format!("{name}.{pass}");
            parts.push(Part {
                name: Some(Box::leak(part.into_boxed_str())),
                view: None,
                multi_view: None,
                channels,
            });
        }
    }
    parts
}

/// A file's own composite (Blender's `Composite.Combined` part, under either naming of its
/// channels) was made before the blur: a stack's merged beauty replaces it, in its part and
/// under its name, with a warning. It was kept beside the merged beauty, which went out as
/// `Composite.Combined2` (bare R, G, B, A in it were dropped), and a chain of passes
/// alternated the name and dropped a composite at each step.
#[test]
fn a_stack_s_merged_beauty_replaces_the_file_s_composite_under_its_name() {
    let dir = tempfile::tempdir().unwrap();
    let layers = vec![foreground_moving(-8.0, 1e10, 0.0), background()];
    let single = dir.path().join("single.exr");
    write(&single, layers.clone());
    let args = ["--algorithm", "reconstruct", "--layers", "FG,BG"];
    let from_single = run("blur", &single, dir.path().join("s.exr"), &args);
    let stale = vec![7.0; W * H];
    for (k, names) in [
        ["R", "G", "B", "A"],
        [
            "Composite.Combined.R",
            "Composite.Combined.G",
            "Composite.Combined.B",
            "Composite.Combined.A",
        ],
    ]
    .into_iter()
    .enumerate()
    {
        let input = dir.path().join(format!("composite{k}.exr"));
        let mut parts = blender5_parts(layers.clone(), &["FG", "BG"]);
        parts.push(Part {
            name: Some("Composite.Combined"),
            view: None,
            multi_view: None,
            channels: names
                .iter()
                .map(|n| (n.to_string(), stale.clone()))
                .collect(),
        });
        write_parts(&input, (W, H), parts);
        let mut input = input;
        // The output of one pass is the input of the next: the name holds.
        for pass in 0..2 {
            let out = dir.path().join(format!("out{k}_{pass}.exr"));
            let mut all = vec![
                "blur",
                "--preset",
                "blender",
                "--color",
                input.to_str().unwrap(),
            ];
            let o_str = out.to_str().unwrap().to_string();
            all.extend(["-o", &o_str]);
            all.extend(args);
            let o = shutter(&all);
            assert!(o.status.success(), "{all:?}: {}", stderr(&o));
            let stored = parts_of(&out);
            let names: Vec<&str> = stored.iter().map(|(p, _)| p.as_str()).collect();
            assert_eq!(names[0], "Composite.Combined", "{names:?}");
            assert_eq!(stored[0].1, ["A", "B", "G", "R"]);
            assert_eq!(stored.len(), 7, "{names:?}");
            assert!(
                stderr(&o).contains("Composite.Combined (its composite, made before the blur)"),
                "{}",
                stderr(&o)
            );
            if pass == 0 {
                let merged = read_exr_reference(&out);
                for c in ["R", "G", "B", "A"] {
                    assert_same_bits(channel(&merged, c), channel(&from_single, c), c);
                }
            }
            input = out;
        }
    }
}

/// Blender 5 writes view layers as a multi-part file, a part a pass (`FG.Combined` holding
/// `FG.Combined.R`, …), and reads a part's channels that lack a layer name as the part's
/// (its reader puts the part's name before them). The merged beauty (`R`, `G`, `B`, `A`) in the
/// `FG.Combined` part made Blender 5.2 see an eight-channel Combined pass in FG and lose FG's
/// Combined altogether; it goes out in a part of its own, first, under Blender's name for the
/// composite (`Composite.Combined`), and comes out the same as from the single-part file.
#[test]
fn a_multi_part_stack_gives_the_merged_beauty_a_part_of_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let single = dir.path().join("single.exr");
    let layers = vec![foreground_moving(-8.0, 1e10, 0.0), background()];
    write(&single, layers.clone());
    let multi = dir.path().join("multi.exr");
    write_parts(&multi, (W, H), blender5_parts(layers, &["FG", "BG"]));
    let args = ["--algorithm", "reconstruct", "--layers", "FG,BG"];
    let from_single = run("blur", &single, dir.path().join("s.exr"), &args);
    let out = dir.path().join("m.exr");
    run("blur", &multi, out.clone(), &args);
    let stored = parts_of(&out);
    let (first, channels) = &stored[0];
    assert_eq!(first, "Composite.Combined");
    assert_eq!(channels, &["A", "B", "G", "R"]);
    let fg = stored.iter().find(|(p, _)| p == "FG.Combined").unwrap();
    assert_eq!(
        fg.1,
        [
            "FG.Combined.A",
            "FG.Combined.B",
            "FG.Combined.G",
            "FG.Combined.R"
        ]
    );
    // Every other part as it came: a part a pass, each named as its channels are.
    for (part, channels) in &stored[1..] {
        assert!(
            channels.iter().all(|c| c.starts_with(&format!("{part}."))),
            "{part}: {channels:?}"
        );
    }
    assert_eq!(stored.len(), 7);
    let merged = read_exr_reference(&out);
    for c in ["R", "G", "B", "A", "FG.Combined.R", "BG.Combined.G"] {
        assert_same_bits(channel(&merged, c), channel(&from_single, c), c);
    }
}

/// Under DWA the data goes to lossless parts of its own. Blender reads a part's channels as
/// named by the part unless their names begin with it (`rgba` + `FG.Combined.R` is its layer
/// `rgba.FG`), so from a one-part file of view layers (Blender 4 and before) each part is
/// named by what its channels' names begin with: the beauty's `FG.Combined`, and a data part a
/// view layer (`FG`: its depth and vectors; `BG`, another layer as it came) — not `rgba` and
/// `data`, which made Blender 5.2 list the layers `rgba.FG`, `data.FG` and `data.BG`.
#[test]
fn a_dwa_output_of_view_layers_names_each_part_as_its_channels_begin() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("layers.exr");
    write(
        &input,
        vec![foreground_moving(-8.0, 1e10, 0.0), background()],
    );
    let out = dir.path().join("dwa.exr");
    let args = ["--layer", "FG", "--compression", "dwaa"];
    run("blur", &input, out.clone(), &args);
    let parts = parts_of(&out);
    let names: Vec<&str> = parts.iter().map(|(p, _)| p.as_str()).collect();
    // The data parts in the order of their first channels in the file (sorted by name).
    assert_eq!(names, ["FG.Combined", "BG", "FG"], "{parts:?}");
    for (part, channels) in &parts {
        assert!(
            channels.iter().all(|c| c.starts_with(&format!("{part}."))),
            "{part}: {channels:?}"
        );
    }
    // The data as it came, bit for bit.
    let (came, went) = (read_exr_reference(&input), read_exr_reference(&out));
    for c in ["FG.Depth.Z", "FG.Vector.X", "BG.Combined.R", "BG.Vector.W"] {
        assert_same_bits(channel(&went, c), channel(&came, c), c);
    }
    // A stack: the merged beauty in a part of its own, named as from a multi-part file, then
    // each layer's beauty, then each layer's data.
    let out = dir.path().join("stack.exr");
    let args = ["--layers", "FG,BG", "--compression", "dwaa"];
    run("blur", &input, out.clone(), &args);
    let names: Vec<String> = parts_of(&out).into_iter().map(|(p, _)| p).collect();
    assert_eq!(
        names,
        [
            "Composite.Combined",
            "FG.Combined",
            "BG.Combined",
            "FG",
            "BG"
        ]
    );
}

/// Each layer's light AOVs are blurred with that layer's own weights (issue 29 per layer): an
/// AOV equal to its layer's colour comes out equal to its layer's blurred colour, for each
/// layer, and the merge is made of the layers' colours alone.
#[test]
fn each_layers_light_aovs_blur_with_its_own_weights() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("aovs.exr");
    let mut layers = vec![foreground_moving(-8.0, 1e10, 0.0), background()];
    for layer in &mut layers {
        let copies: Vec<(String, Vec<f32>)> = (layer.iter())
            .filter(|(n, _)| n.contains(".Combined.") && !n.ends_with(".A"))
            .map(|(n, p)| (n.replace(".Combined.", ".DiffCol."), p.clone()))
            .collect();
        layer.extend(copies);
    }
    write(&input, layers);
    for algorithm in ["reconstruct", "scatter", "stretch"] {
        let out = run(
            "blur",
            &input,
            dir.path().join(format!("{algorithm}.exr")),
            &["--algorithm", algorithm, "--layers", "FG,BG"],
        );
        for layer in ["FG", "BG"] {
            for c in ["R", "G", "B"] {
                assert_close(
                    channel(&out, &format!("{layer}.DiffCol.{c}")),
                    channel(&out, &format!("{layer}.Combined.{c}")),
                    1e-6,
                    &format!("{algorithm} {layer}.DiffCol.{c}"),
                );
            }
        }
    }
}

/// Where layers interpenetrate (a later layer's surface nearer than an earlier one's), the
/// stack's order decides, not the depths: FG, at depth 3, stays over BG's nearer square at
/// depth 1 wherever FG covers it. (Render interpenetrating objects in one layer, or each
/// held out of the other's.)
#[test]
fn interpenetrating_layers_merge_in_the_stacks_order() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("through.exr");
    let n = W * H;
    // BG: a square at depth 1 (nearer than FG's box at 3) over columns 30..50, the rest
    // at 30; nothing moves.
    let near = |i: usize| (30..50).contains(&(i % W));
    let bg = layer_channels(
        "BG",
        [0.0, 1.0, 0.0].map(|v| vec![v; n]),
        vec![1.0; n],
        (0..n).map(|i| if near(i) { 1.0 } else { 30.0 }).collect(),
        vec![0.0; n],
    );
    write(&input, vec![foreground(1e10, 0.0), bg]);
    let out = run(
        "blur",
        &input,
        dir.path().join("o.exr"),
        &["--algorithm", "reconstruct", "--layers", "FG,BG"],
    );
    let r = channel(&out, "R");
    let g = channel(&out, "G");
    for i in 0..n {
        let (want_r, want_g) = if in_box(i) {
            (BOX_RGB[0], BOX_RGB[1])
        } else {
            (0.0, 1.0)
        };
        assert!(
            (r[i] - want_r).abs() <= 1e-6 && (g[i] - want_g).abs() <= 1e-6,
            "({}, {}): R {} G {} where {want_r} {want_g}",
            i % W,
            i / W,
            r[i],
            g[i]
        );
    }
}

/// Depth of field: each layer gets its own circle of confusion. A near box (depth 0.5, about
/// 8 px across at f/1.4 focused at 3) spreads over the in-focus layer behind it, which stays
/// sharp beyond the box's reach: the merge is the spread box over the background exactly.
#[test]
fn a_defocused_near_layer_spreads_over_a_sharp_one_behind() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("near.exr");
    let n = W * H;
    let mut fg = foreground(1e10, 0.0);
    for (name, plane) in &mut fg {
        if name == "FG.Depth.Z" {
            for (i, z) in plane.iter_mut().enumerate() {
                if in_box(i) {
                    *z = 0.5;
                }
            }
        }
    }
    let mut bg = background();
    for (name, plane) in &mut bg {
        if name == "BG.Depth.Z" {
            *plane = vec![3.0; n];
        }
    }
    let stored = [fg.clone(), bg.clone()].concat();
    write(&input, vec![fg, bg]);
    for method in ["gather", "blend"] {
        let out = run(
            "dof",
            &input,
            dir.path().join(format!("{method}.exr")),
            &[
                &["--method", method][..],
                &lens_flags(),
                &["--layers", "FG,BG"],
            ]
            .concat(),
        );
        let fg_a = channel(&out, "FG.Combined.A");
        // Two pixels outside the box's left edge: the box's blur reaches there.
        let beside = 2 * W + BOX.0 - 2;
        assert!(
            fg_a[beside] > 0.05,
            "{method}: FG alpha {} beside the box",
            fg_a[beside]
        );
        for c in ["R", "G", "B"] {
            let (merged, front) = (channel(&out, c), channel(&out, &format!("FG.Combined.{c}")));
            let sharp = channel(&stored, &format!("BG.Combined.{c}"));
            let behind = channel(&out, &format!("BG.Combined.{c}"));
            for i in 0..n {
                // Beyond the box's reach the background is as it was: in focus.
                let x = i % W;
                if x + 8 < BOX.0 || x >= BOX.1 + 8 {
                    assert!(
                        (merged[i] - sharp[i]).abs() <= 1e-5,
                        "{method} {c} at ({x}, {}): {} where the sharp {}",
                        i / W,
                        merged[i],
                        sharp[i]
                    );
                }
                let over = front[i] + (1.0 - fg_a[i].clamp(0.0, 1.0)) * behind[i];
                assert!(
                    (merged[i] - over).abs() <= 1e-6,
                    "{method} {c} at {i}: not FG over BG"
                );
            }
        }
    }
}

/// `--layers` merges in the order given, whatever the depths say; a stack whose later layer
/// is nearer over most of what both cover (the box at depth 3 given behind the background at
/// 30) is named in a warning, once a run, also when another layer stands between them; the
/// right order, and a surface rendered at the same depth into two layers, say nothing.
#[test]
fn a_reversed_stack_is_named_in_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let rename = |layer: Vec<(String, Vec<f32>)>, to: &str| -> Vec<(String, Vec<f32>)> {
        (layer.into_iter())
            .map(|(n, p)| (n.replacen("FG", to, 1), p))
            .collect()
    };
    let n = W * H;
    // A layer that covers nothing, and the box again under another name.
    let empty = layer_channels(
        "X",
        [0.0; 3].map(|v| vec![v; n]),
        vec![0.0; n],
        vec![1e10; n],
        vec![0.0; n],
    );
    let same = rename(foreground(1e10, 0.0), "Same");
    for frame in 1..=3 {
        write(
            &dir.path().join(format!("layers.{frame:04}.exr")),
            vec![
                foreground(1e10, 0.0),
                background(),
                empty.clone(),
                same.clone(),
            ],
        );
    }
    let run = |order: &str| {
        let o = shutter(&[
            "blur",
            "--preset",
            "blender",
            "--algorithm",
            "reconstruct",
            "--layers",
            order,
            "--color",
            &format!("{}/layers.####.exr", dir.path().display()),
            "-o",
            &format!("{}/o.####.exr", dir.path().display()),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        stderr(&o)
    };
    let pixels = (BOX.1 - BOX.0) * H;
    for order in ["BG,FG", "BG,X,FG"] {
        let reversed = run(order);
        let named = format!("view layer FG is nearer than BG in {pixels} of the {pixels} pixels");
        assert_eq!(reversed.matches(&named).count(), 1, "{order}: {reversed}");
        assert!(
            reversed.contains("is the order reversed? (first in frame 1)"),
            "{reversed}"
        );
    }
    for order in ["FG,BG", "FG,X,BG", "FG,Same,BG"] {
        assert!(!run(order).contains("reversed"), "{order}");
    }
}

/// A NaN in one view layer of a stack is warned of naming that layer (and its file), the
/// first time each layer has one: BG's colour in frame 2, FG's in frame 3, BG's again in 3.
#[test]
fn a_stack_s_replaced_values_are_named_by_their_layer() {
    let dir = tempfile::tempdir().unwrap();
    let with_nan = |mut layer: Vec<(String, Vec<f32>)>| {
        layer[0].1[W + 3] = f32::NAN;
        layer
    };
    for frame in 1..=3 {
        let fg = foreground(1e10, 0.0);
        let (fg, bg) = match frame {
            1 => (fg, background()),
            2 => (fg, with_nan(background())),
            _ => (with_nan(fg), with_nan(background())),
        };
        write(
            &dir.path().join(format!("layers.{frame:04}.exr")),
            vec![fg, bg],
        );
    }
    let o = shutter(&[
        "blur",
        "--preset",
        "blender",
        "--algorithm",
        "reconstruct",
        "--layers",
        "FG,BG",
        "--color",
        &format!("{}/layers.####.exr", dir.path().display()),
        "-o",
        &format!("{}/o.####.exr", dir.path().display()),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let said = stderr(&o);
    let named = |layer: &str, frame: i64| {
        format!(
            "colour values NaN or beyond ±1e30 read as 0 or clamped in {}/layers.{frame:04}.exr \
             (view layer {layer}), first in frame {frame}",
            dir.path().display()
        )
    };
    assert_eq!(said.matches(&named("BG", 2)).count(), 1, "{said}");
    assert_eq!(said.matches(&named("FG", 3)).count(), 1, "{said}");
    assert_eq!(said.matches("colour values NaN").count(), 2, "{said}");
}

/// A disc of radius 8 moving (7, 2.5) px a frame (image axes, y down) in a layer `FG` over
/// empty space, before a still grey `BG`: its pixels' alpha their coverage (8×8 points a
/// pixel), depth and motion sampled at their centres, as Blender writes them. Returns the
/// input, each pixel's exact alpha over the exposure (worked out here: the mean over 32
/// instants of the centred shutter, t in [−¼, ¼] of the frame, of the displaced disc's
/// coverage), and the rim pixels whose centre missed the disc (alpha under one half, no depth
/// or motion of their own).
fn moving_disc(dir: &Path) -> (PathBuf, Vec<f32>, Vec<usize>) {
    let (w, h) = (48usize, 32usize);
    let (cx, cy, radius) = (24.3f32, 16.2f32, 8.0f32);
    let motion = (7.0f32, 2.5f32);
    let points = 8;
    let cover = |dx: f32, dy: f32, x: usize, y: usize| -> f32 {
        let mut inside = 0;
        for v in 0..points {
            for u in 0..points {
                let px = x as f32 + (u as f32 + 0.5) / points as f32 - cx - dx;
                let py = y as f32 + (v as f32 + 0.5) / points as f32 - cy - dy;
                inside += (px * px + py * py < radius * radius) as usize;
            }
        }
        inside as f32 / (points * points) as f32
    };
    let n = w * h;
    let sharp: Vec<f32> = (0..n).map(|i| cover(0.0, 0.0, i % w, i / w)).collect();
    let instants = 32;
    let exact: Vec<f32> = (0..n)
        .map(|i| {
            (0..instants)
                .map(|k| {
                    let t = ((k as f32 + 0.5) / instants as f32 - 0.5) * 0.5;
                    cover(motion.0 * t, motion.1 * t, i % w, i / w)
                })
                .sum::<f32>()
                / instants as f32
        })
        .collect();
    let hit = |i: usize| {
        let (px, py) = ((i % w) as f32 + 0.5 - cx, (i / w) as f32 + 0.5 - cy);
        px * px + py * py < radius * radius
    };
    let hits: Vec<bool> = (0..n).map(hit).collect();
    let input = dir.join("disc.exr");
    write_fg_over_grey(&input, (w, h), &sharp, &hits, motion);
    let missed: Vec<usize> = (0..n)
        .filter(|&i| sharp[i] > 0.0 && sharp[i] < 0.5 && !hit(i))
        .collect();
    assert!(missed.len() >= 20, "{} rim pixels", missed.len());
    (input, exact, missed)
}

/// Writes a two-layer file as Blender writes one: FG, of coverage `alpha` (its colour
/// (0.9, 0.8, 0.1) times that), depth 3 and the motion `motion` (px a frame) where `hit` (its
/// depth sample hit the surface), no depth (10¹⁰) and no motion elsewhere; BG grey (0.5),
/// opaque, still, at depth 30. Blender's vectors: X, Y = p(−1) − p(0) (and Z, W = p(0) −
/// p(+1)), y up.
fn write_fg_over_grey(
    path: &Path,
    (w, h): (usize, usize),
    alpha: &[f32],
    hit: &[bool],
    motion: (f32, f32),
) {
    let n = w * h;
    let on = |inside: f32, outside: f32| -> Vec<f32> {
        (0..n)
            .map(|i| if hit[i] { inside } else { outside })
            .collect()
    };
    let mut channels: Vec<(String, Vec<f32>)> = vec![
        ("FG.Combined.A".into(), alpha.to_vec()),
        ("FG.Depth.Z".into(), on(3.0, 1e10)),
        ("FG.Vector.X".into(), on(-motion.0, 0.0)),
        ("FG.Vector.Y".into(), on(motion.1, 0.0)),
        ("FG.Vector.Z".into(), on(-motion.0, 0.0)),
        ("FG.Vector.W".into(), on(motion.1, 0.0)),
        ("BG.Combined.A".into(), vec![1.0; n]),
        ("BG.Depth.Z".into(), vec![30.0; n]),
    ];
    for (c, value) in ["R", "G", "B"].into_iter().zip([0.9f32, 0.8, 0.1]) {
        channels.push((
            format!("FG.Combined.{c}"),
            alpha.iter().map(|a| a * value).collect(),
        ));
        channels.push((format!("BG.Combined.{c}"), vec![0.5; n]));
    }
    for c in ["X", "Y", "Z", "W"] {
        channels.push((format!("BG.Vector.{c}"), vec![0.0; n]));
    }
    write_exr(
        path,
        w,
        h,
        channels
            .iter()
            .map(|(name, plane)| (name.as_str(), plane.clone()))
            .collect(),
    );
}

/// The RMS and the largest error of `alpha` against `exact` over the pixels `missed`.
fn rim_errors(alpha: &[f32], exact: &[f32], missed: &[usize]) -> (f32, f32) {
    let errors: Vec<f32> = missed.iter().map(|&i| alpha[i] - exact[i]).collect();
    let rms = (errors.iter().map(|e| e * e).sum::<f32>() / errors.len() as f32).sqrt();
    (rms, errors.iter().fold(0.0f32, |m, e| m.max(e.abs())))
}

/// [`moving_disc`]'s rim pixels whose centre missed the disc come out of reconstruct's stack
/// near their exact exposure. The stack gives those pixels the disc's motion; read as covered
/// at least half (the matte's bound on a moving pixel) or with the coverage their taps
/// interpolate between pixel centres unsteepened, they came out 0.044 RMS and up to 0.13 off
/// (0.028 and 0.064 now).
#[test]
fn a_moving_disc_s_rim_pixels_whose_centre_missed_it_keep_near_their_exposure() {
    let dir = tempfile::tempdir().unwrap();
    let (input, exact, missed) = moving_disc(dir.path());
    let args = ["--algorithm", "reconstruct", "--layers", "FG,BG"];
    let out = run("blur", &input, dir.path().join("out.exr"), &args);
    let (rms, worst) = rim_errors(channel(&out, "FG.Combined.A"), &exact, &missed);
    assert!(
        rms < 0.035 && worst < 0.09,
        "the rim pixels whose centre missed the disc: RMS {rms}, worst {worst}"
    );
}

/// A rim moving along itself keeps its coverage: a band in a view layer over empty space
/// moving 8 px a frame along its length, its bottom row a tenth covered (the centre missed
/// it: no depth or motion of its own, which the stack gives it from the band). Over the
/// exposure that row is a tenth covered wherever the band stays over it, so its alpha away
/// from the band's ends is 0.1. The coverage a tap reads there is steepened (a moving pixel
/// covered under half), but never past the coverages of the pixels the tap reads, all 0.1
/// along the row: steepened about one half alone, it was driven to 0.
#[test]
fn a_rim_moving_along_itself_keeps_its_coverage() {
    let (w, h) = (64usize, 24usize);
    let n = w * h;
    let (left, right, top, rim) = (12usize, 52usize, 8usize, 16usize);
    let cover = |i: usize| {
        let (x, y) = (i % w, i / w);
        match (left <= x && x < right, y) {
            (true, y) if top <= y && y < rim => 1.0f32,
            (true, y) if y == rim => 0.1,
            _ => 0.0,
        }
    };
    let alpha: Vec<f32> = (0..n).map(cover).collect();
    let solid: Vec<bool> = alpha.iter().map(|&a| a == 1.0).collect();
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("band.exr");
    write_fg_over_grey(&input, (w, h), &alpha, &solid, (8.0, 0.0));
    let args = ["--algorithm", "reconstruct", "--layers", "FG,BG"];
    let out = run("blur", &input, dir.path().join("out.exr"), &args);
    let fg = channel(&out, "FG.Combined.A");
    // Away from the band's ends by more than its streak (8 px a frame, half a frame open).
    for x in left + 6..right - 6 {
        let got = fg[rim * w + x];
        assert!(
            (got - 0.1).abs() < 0.02,
            "the rim row at x = {x}: alpha {got}, the exposure 0.1"
        );
    }
}

/// The same disc on `--backend wgpu`: the twin steepens those pixels' coverage as the CPU
/// does (its rim within the same bounds of the exposure), and each channel of the FG layer
/// agrees with the CPU's within reconstruct's parity bound.
#[cfg(feature = "gpu")]
#[test]
fn a_moving_disc_s_rim_on_wgpu_is_the_cpu_s() {
    if crate::gpu::with_gpu::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (input, exact, missed) = moving_disc(dir.path());
    let outputs: Vec<_> = ["cpu", "wgpu"]
        .into_iter()
        .map(|backend| {
            let out = dir.path().join(format!("{backend}.exr"));
            stack_on(
                "blur",
                &input,
                out,
                backend,
                &["--algorithm", "reconstruct"],
            )
        })
        .collect();
    let (rms, worst) = rim_errors(channel(&outputs[1], "FG.Combined.A"), &exact, &missed);
    assert!(
        rms < 0.035 && worst < 0.09,
        "wgpu: RMS {rms}, worst {worst}"
    );
    for name in ["R", "G", "B", "A"].map(|c| format!("FG.Combined.{c}")) {
        let (cpu, got) = (channel(&outputs[0], &name), channel(&outputs[1], &name));
        assert_twin_within(
            &format!("disc {name}"),
            got,
            cpu,
            crate::gpu_reconstruct::BOUND,
        );
    }
}

/// A band in a view layer over empty space, its left edge on a pixel boundary (x = 24),
/// moving `speed` px a frame to the right, so that over the exposure (half a frame, centred,
/// as the blender preset's) the edge sweeps ±`speed`/4 px about it: the band's input, and
/// each pixel's exact coverage over the exposure (32 instants, the edge's position exact).
fn sliding_band(dir: &Path, speed: f32) -> (PathBuf, Vec<f32>, usize) {
    let (w, h) = (48usize, 24usize);
    let (left, right, top, bottom) = (24usize, 40usize, 4usize, 20usize);
    let n = w * h;
    let inside = |i: usize| {
        let (x, y) = (i % w, i / w);
        left <= x && x < right && top <= y && y < bottom
    };
    let alpha: Vec<f32> = (0..n).map(|i| inside(i) as u8 as f32).collect();
    let hits: Vec<bool> = (0..n).map(inside).collect();
    let instants = 32;
    let exact: Vec<f32> = (0..n)
        .map(|i| {
            let (x, y) = ((i % w) as f32, i / w);
            if y < top || y >= bottom {
                return 0.0;
            }
            (0..instants)
                .map(|k| {
                    let shift = speed * ((k as f32 + 0.5) / instants as f32 - 0.5) * 0.5;
                    let (l, r) = (left as f32 + shift, right as f32 + shift);
                    ((x + 1.0).min(r) - x.max(l)).max(0.0)
                })
                .sum::<f32>()
                / instants as f32
        })
        .collect();
    let input = dir.join("band.exr");
    write_fg_over_grey(&input, (w, h), &alpha, &hits, (speed, 0.0));
    (input, exact, w)
}

/// stretch leaves no hole beside a moving rim: [`sliding_band`] at 3.8 px a frame, whose
/// edges move 0.95 px each way over the exposure, so the pixel just beyond each edge is
/// covered about a quarter of it. The smear's triangles reach out from the moved silhouette
/// vertices less than a pixel, short of that pixel's centre, and its neighbours are empty
/// space no fragment reaches or the band's own pixels, which keep no sweep: it kept its sharp
/// alpha, 0 (the right edge's, ahead of the motion, alike). It now takes its moving
/// neighbour's motion (src/motion/stretch/cover.rs, `sweep_at`). Blurred as the hand-made
/// merge blurs a layer (`--layer FG`) and in the stack, every pixel of the band's rows comes
/// out within 0.03 of its exact exposure (it was 0.24 off beside each edge).
#[test]
fn stretch_leaves_no_hole_beside_a_moving_rim() {
    let dir = tempfile::tempdir().unwrap();
    let (input, exact, w) = sliding_band(dir.path(), 3.8);
    for (what, args) in [
        ("--layer FG", ["--layer", "FG"]),
        ("--layers FG,BG", ["--layers", "FG,BG"]),
    ] {
        let all = [&["--algorithm", "stretch"][..], &args].concat();
        let out = run("blur", &input, dir.path().join("out.exr"), &all);
        band_within_its_exposure(what, channel(&out, "FG.Combined.A"), &exact, w);
    }
}

/// Every pixel of [`sliding_band`]'s rows away from its top and bottom edges (a corner's
/// streak is 2-D) within 0.03 of its exact exposure.
fn band_within_its_exposure(what: &str, alpha: &[f32], exact: &[f32], w: usize) {
    for y in 6..18 {
        for x in 0..w {
            let i = y * w + x;
            assert!(
                (alpha[i] - exact[i]).abs() < 0.03,
                "{what}: ({x}, {y}) alpha {}, the exposure {}",
                alpha[i],
                exact[i]
            );
        }
    }
}

/// [`stretch_leaves_no_hole_beside_a_moving_rim`] on `--backend wgpu`: the twin's cover
/// takes the same motions in the same order (src/gpu/motion/stretch.wgsl, `sweep_at`).
#[cfg(feature = "gpu")]
#[test]
fn stretch_leaves_no_hole_beside_a_moving_rim_on_wgpu() {
    if crate::gpu::with_gpu::gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let (input, exact, w) = sliding_band(dir.path(), 3.8);
    let out = dir.path().join("out.exr");
    let out = stack_on("blur", &input, out, "wgpu", &["--algorithm", "stretch"]);
    band_within_its_exposure("wgpu", channel(&out, "FG.Combined.A"), &exact, w);
}

/// A part of a multi-part EXR at a data window of its own: its name, the window's corner
/// and size, and its channels (planes of that size).
type WindowedPart = (
    &'static str,
    (i32, i32),
    (usize, usize),
    Vec<(String, Vec<f32>)>,
);

/// Writes `parts` as one multi-part EXR whose display window is W×H at (0, 0).
fn write_windowed_parts(path: &Path, parts: Vec<WindowedPart>) {
    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::math::Vec2;
    use exr::meta::attribute::{IntegerBounds, Text};
    use exr::meta::header::{ImageAttributes, LayerAttributes};
    use exr::prelude::{Blocks, LineOrder, WritableImage};
    let layers: Vec<_> = (parts.into_iter())
        .map(|(name, (x, y), size, channels)| {
            let attributes = LayerAttributes {
                layer_name: Some(Text::from(name)),
                layer_position: Vec2(x, y),
                ..LayerAttributes::default()
            };
            let channels = (channels.into_iter())
                .map(|(n, p)| AnyChannel::new(n.as_str(), FlatSamples::F32(p)))
                .collect();
            let encoding = Encoding {
                blocks: Blocks::ScanLines,
                line_order: LineOrder::Increasing,
                ..Encoding::default()
            };
            Layer::new(size, attributes, encoding, AnyChannels::sort(channels))
        })
        .collect();
    let attributes = ImageAttributes::new(IntegerBounds::new((0, 0), (W, H)));
    Image::from_layers(attributes, layers)
        .write()
        .to_file(path)
        .unwrap();
}

/// The overscan of [`overscanned`]: this many pixels beyond each side (x, y).
const OVERSCAN: (usize, usize) = (4, 2);

/// `channels` (W×H planes) at the overscan's window, the pixels beyond the frame filled with
/// a value no pixel of the frame holds.
fn overscanned(channels: &[(String, Vec<f32>)]) -> Vec<(String, Vec<f32>)> {
    let (ox, oy) = OVERSCAN;
    let w = W + 2 * ox;
    (channels.iter())
        .map(|(n, p)| {
            let mut plane = vec![-77.0; w * (H + 2 * oy)];
            for y in 0..H {
                plane[(y + oy) * w + ox..][..W].copy_from_slice(&p[y * W..][..W]);
            }
            (n.clone(), plane)
        })
        .collect()
}

/// A multi-part file's parts may have data windows of their own: each pass is placed by its
/// part's window in the file's coordinates and the frame is the colour's part's. The frame's
/// size and window were the first part's, so a depth part with overscan before the colour
/// (`depth` then `rgba`) stopped the run ("the parts holding the wanted channels differ in
/// size", or "the file changed after the preflight checked it", rerun as often as one
/// liked); the same parts the other way round were read. Either order now gives the same
/// frame, bit for bit, as a one-part file of the colour's window; the output's data window is
/// the colour's.
#[test]
fn a_pass_part_with_overscan_before_the_colour_s_part_is_placed_by_its_own_window() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let named = |names: &[&str], planes: Vec<Vec<f32>>| -> Vec<(String, Vec<f32>)> {
        names.iter().map(|s| s.to_string()).zip(planes).collect()
    };
    let rgba = named(
        &["R", "G", "B", "A"],
        vec![
            noise(n, 1, 0.0, 1.0),
            noise(n, 2, 0.0, 1.0),
            noise(n, 3, 0.0, 1.0),
            vec![1.0; n],
        ],
    );
    let data = named(
        &["Z", "velocity.X", "velocity.Y"],
        vec![
            noise(n, 4, 1.0, 9.0),
            noise(n, 5, -6.0, 6.0),
            noise(n, 6, -2.0, 2.0),
        ],
    );
    let one_part = dir.path().join("one.exr");
    write(&one_part, vec![rgba.clone(), data.clone()]);
    let over = (-(OVERSCAN.0 as i32), -(OVERSCAN.1 as i32));
    let over_size = (W + 2 * OVERSCAN.0, H + 2 * OVERSCAN.1);
    let depth_part = ("depth", over, over_size, overscanned(&data));
    let rgba_part = ("rgba", (0, 0), (W, H), rgba);
    let depth_first = dir.path().join("depth_first.exr");
    write_windowed_parts(&depth_first, vec![depth_part.clone(), rgba_part.clone()]);
    let rgba_first = dir.path().join("rgba_first.exr");
    write_windowed_parts(&rgba_first, vec![rgba_part, depth_part]);
    let blur = |input: &Path, out: &str| {
        let out = dir.path().join(out);
        let o = shutter(&[
            "blur",
            "--algorithm",
            "reconstruct",
            "--color",
            &s(input),
            "-o",
            &s(&out),
        ]);
        assert!(o.status.success(), "{}: {}", input.display(), stderr(&o));
        out
    };
    let expected = read_exr_reference(&blur(&one_part, "one_out.exr"));
    for input in [&depth_first, &rgba_first] {
        let out = blur(input, "out.exr");
        let got = read_exr_reference(&out);
        for c in ["R", "G", "B", "A"] {
            assert_same_bits(channel(&got, c), channel(&expected, c), c);
        }
        let beauty = (read_exr_layers(&out).into_iter())
            .find(|l| {
                l.channel_data
                    .list
                    .iter()
                    .any(|c| c.name.to_string() == "R")
            })
            .unwrap();
        assert_eq!(beauty.attributes.layer_position, exr::math::Vec2(0, 0));
        assert_eq!(beauty.size, exr::math::Vec2(W, H));
    }
}

/// In a stack of view layers from one multi-part file, a layer's depth and vector parts with
/// overscan come first (the file's first part): the frame was that part's size and the read
/// of the colour stopped as "changed". Each layer now reads its colour at its part's window
/// and the merge is that of the one-part file, bit for bit. Layers whose colours lie at
/// different windows are refused by name, each window given.
#[test]
fn a_stack_reads_each_part_at_its_own_window() {
    let dir = tempfile::tempdir().unwrap();
    let layers = vec![foreground_moving(-8.0, 1e10, 0.0), background()];
    let single = dir.path().join("single.exr");
    write(&single, layers.clone());
    let args = ["--algorithm", "reconstruct", "--layers", "FG,BG"];
    let from_single = run("blur", &single, dir.path().join("s.exr"), &args);
    let over = (-(OVERSCAN.0 as i32), -(OVERSCAN.1 as i32));
    let over_size = (W + 2 * OVERSCAN.0, H + 2 * OVERSCAN.1);
    let mut parts: Vec<WindowedPart> = Vec::new();
    for part in blender5_parts(layers.clone(), &["FG", "BG"]) {
        let name = part.name.unwrap();
        if name.starts_with("BG.") && !name.ends_with("Combined") {
            parts.insert(0, (name, over, over_size, overscanned(&part.channels)));
        } else {
            parts.push((name, (0, 0), (W, H), part.channels));
        }
    }
    let input = dir.path().join("overscan.exr");
    write_windowed_parts(&input, parts.clone());
    let merged = run("blur", &input, dir.path().join("o.exr"), &args);
    for c in ["R", "G", "B", "A", "FG.Combined.R", "BG.Combined.G"] {
        assert_same_bits(channel(&merged, c), channel(&from_single, c), c);
    }
    // BG's colour at the overscan's window too: not the foreground's picture.
    for part in &mut parts {
        if part.0 == "BG.Combined" {
            *part = (part.0, over, over_size, overscanned(&part.3));
        }
    }
    write_windowed_parts(&input, parts);
    let out = dir.path().join("x.exr");
    let mut all = vec!["blur", "--preset", "blender", "--color"];
    let (i, o) = (s(&input), s(&out));
    all.extend([i.as_str(), "-o", o.as_str()]);
    all.extend(args);
    let o = shutter(&all);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    for needle in [
        "layer BG's colour is",
        "(-4, -2) - (99, 17)",
        "(0, 0) - (95, 15)",
    ] {
        assert!(err.contains(needle), "'{needle}' not in: {err}");
    }
    assert!(!out.exists());
}

/// A view layer without a depth of its own read the file's plain `Z` (the preset's
/// fallback) without a word: where some other render's surfaces are, not the layer's. The
/// run still reads it (a file of one layer beside its plain passes means it so) and warns,
/// naming the layer and the channel; a layer with its own depth is not named.
#[test]
fn a_layer_reading_a_depth_not_its_own_is_named_in_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let mut fg = foreground_moving(-8.0, 1e10, 0.0);
    let depth = fg.iter().position(|(n, _)| n == "FG.Depth.Z").unwrap();
    let (_, plane) = fg.remove(depth);
    fg.push(("Z".to_string(), plane));
    let input = dir.path().join("plain_z.exr");
    write(&input, vec![fg, background()]);
    let out = dir.path().join("o.exr");
    let mut all = vec!["blur", "--preset", "blender", "--color"];
    let (i, o) = (s(&input), s(&out));
    all.extend([i.as_str(), "-o", o.as_str(), "--layers", "FG,BG"]);
    all.extend(["--algorithm", "reconstruct"]);
    let o = shutter(&all);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("view layer FG has no depth of its own: it reads Z"),
        "{err}"
    );
    assert!(!err.contains("view layer BG has no depth"), "{err}");
}

/// A stack whose layers' colours are all half writes its merged beauty in half, as a plain
/// run keeps a half beauty half; it went out in float whatever the layers were (named as no
/// channel of the part it is made like). Each layer's own beauty keeps its type too.
#[test]
fn a_stack_of_half_layers_writes_a_half_merged_beauty() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("half.exr");
    let channels: Vec<(String, Vec<f32>)> = vec![foreground_moving(-8.0, 1e10, 0.0), background()]
        .into_iter()
        .flatten()
        .collect();
    let options = shutter::io::exr::ExrOptions {
        half: true,
        ..Default::default()
    };
    let channels = channels
        .iter()
        .map(|(n, p)| (n.as_str(), p.clone()))
        .collect();
    write_exr_with(&input, W, H, channels, options);
    let out = dir.path().join("o.exr");
    run("blur", &input, out.clone(), &["--layers", "FG,BG"]);
    let half = |name: &str| {
        (read_exr_layers(&out).iter())
            .flat_map(|l| l.channel_data.list.iter())
            .find(|c| c.name.to_string() == name)
            .map(|c| matches!(c.sample_data, exr::image::FlatSamples::F16(_)))
            .unwrap_or_else(|| panic!("no channel {name}"))
    };
    for c in ["R", "G", "B", "A", "FG.Combined.R", "BG.Combined.A"] {
        assert!(half(c), "{c} is not half");
    }
}

/// A stack of files given by `--color` alone names each layer by its file: the name without
/// the frame's placeholder, up to its first period, without separators at its ends
/// (`fg_####.exr`: `fg`, where it was `fg_####`). Two files that give one name make layers
/// named by their place (`layer1`, `layer2`), now with a warning that says why.
#[test]
fn a_stack_of_files_is_named_by_them_without_the_frame_number() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let passes = |seed: u32, alpha: f32| {
        vec![
            ("R", noise(n, seed, 0.0, 1.0)),
            ("G", noise(n, seed + 1, 0.0, 1.0)),
            ("B", noise(n, seed + 2, 0.0, 1.0)),
            ("A", vec![alpha; n]),
            ("Z", vec![2.0 + seed as f32; n]),
            ("velocity.X", vec![3.0; n]),
            ("velocity.Y", vec![0.0; n]),
        ]
    };
    let files = [("fg_0001.exr", 1, 0.5), ("bg_0001.exr", 10, 1.0)];
    for (name, seed, alpha) in files {
        write_exr(&dir.path().join(name), W, H, passes(seed, alpha));
        let other = dir.path().join("other").join(name.replace("fg_", "bg_"));
        write_exr(&other, W, H, passes(seed, alpha));
    }
    let out_name =
        |out: &Path| (out.file_name().unwrap().to_string_lossy()).replace("####", "0001");
    let stack = |colors: [String; 2], out: &str| {
        let out = dir.path().join(out);
        let o = shutter(&[
            "blur",
            "--algorithm",
            "reconstruct",
            "--frames",
            "1",
            "--color",
            &colors[0],
            "--color",
            &colors[1],
            "-o",
            &s(&out),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let written = dir.path().join(out_name(&out));
        let names: Vec<String> = read_exr_reference(&written)
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        (names, stderr(&o))
    };
    let pattern =
        |folder: &str, stem: &str| s(&dir.path().join(folder).join(format!("{stem}_####.exr")));
    let (names, err) = stack([pattern("", "fg"), pattern("", "bg")], "o.####.exr");
    for c in ["fg.R", "fg.A", "bg.R", "bg.A", "R"] {
        assert!(names.iter().any(|n| n == c), "no {c} in {names:?}");
    }
    assert!(!err.contains("by their place"), "{err}");
    // `bg_####.exr` in two folders: one name twice.
    let (names, err) = stack([pattern("other", "bg"), pattern("", "bg")], "p.####.exr");
    for c in ["layer1.R", "layer2.R"] {
        assert!(names.iter().any(|n| n == c), "no {c} in {names:?}");
    }
    assert!(err.contains("named layer1, layer2 by their place"), "{err}");
    assert!(err.contains("give the name bg"), "{err}");
}
