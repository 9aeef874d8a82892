//! What comes in goes out (issue 29): an EXR's attributes and form come back from shutter as
//! they went in, read by our reader and by a client nobody here wrote (OpenImageIO's
//! `oiiotool`, Debian's `openimageio-tools`; required where `SHUTTER_REQUIRE_TOOLS=1`, as in
//! CI, else skipped with a note).

use std::path::Path;

use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
use exr::math::Vec2;
use exr::meta::attribute::{AttributeValue, Chromaticities, IntegerBounds, Text};
use exr::meta::header::{ImageAttributes, LayerAttributes};
use exr::meta::{BlockDescription, MetaData};
use exr::prelude::{f16, Blocks, Compression, LineOrder, WritableImage};

use crate::support::{noise, oiiotool_info, s, shutter, stderr, write_exr, LENS_ARGS};

const W: usize = 40;
const H: usize = 24;

/// ACEScg's primaries and white (AP1, D60), as a renderer writes them.
fn acescg() -> Chromaticities {
    Chromaticities {
        red: Vec2(0.713, 0.293),
        green: Vec2(0.165, 0.830),
        blue: Vec2(0.128, 0.044),
        white: Vec2(0.32168, 0.33767),
    }
}

/// The custom attributes the plate carries, of several types.
fn custom() -> Vec<(&'static str, AttributeValue)> {
    vec![
        (
            "pipeline/shot",
            AttributeValue::Text(Text::from("sq010_sh020")),
        ),
        ("pipeline/take", AttributeValue::I32(7)),
        ("pipeline/gain", AttributeValue::F32(1.5)),
        ("renderer/samples", AttributeValue::I32(512)),
        ("renderer/name", AttributeValue::Text(Text::from("cycles"))),
    ]
}

/// A colour plate as a renderer writes one: RGBA half, PIZ, ACEScg chromaticities, 24 fps,
/// owner, comments, pixel aspect 2 and custom attributes; `blocks` and `line_order` as given.
fn write_plate(path: &Path, blocks: Blocks, line_order: LineOrder) {
    let n = W * H;
    let channel = |name: &str, seed: u32| {
        let plane: Vec<f16> = noise(n, seed, 0.0, 1.0)
            .into_iter()
            .map(f16::from_f32)
            .collect();
        AnyChannel::new(Text::from(name), FlatSamples::F16(plane))
    };
    let mut layer_attributes = LayerAttributes {
        owner: Some(Text::from("Studio X")),
        comments: Some(Text::from("test plate")),
        frames_per_second: Some((24, 1)),
        ..LayerAttributes::default()
    };
    for (name, value) in custom() {
        layer_attributes.other.insert(Text::from(name), value);
    }
    let mut image_attributes = ImageAttributes::new(IntegerBounds::from_dimensions((W, H)));
    image_attributes.pixel_aspect = 2.0;
    image_attributes.chromaticities = Some(acescg());
    let layer = Layer::new(
        (W, H),
        layer_attributes,
        Encoding {
            compression: Compression::PIZ,
            blocks,
            line_order,
        },
        AnyChannels::sort(
            vec![
                channel("R", 1),
                channel("G", 2),
                channel("B", 3),
                channel("A", 4),
            ]
            .into(),
        ),
    );
    let image = Image {
        attributes: image_attributes,
        layer_data: layer,
    };
    image.write().to_file(path).unwrap();
}

/// A folder holding the plate (`color.exr`, see [`write_plate`]) and its passes.
fn plate_frame(blocks: Blocks, line_order: LineOrder) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    write_plate(&dir.path().join("color.exr"), blocks, line_order);
    write_passes(dir.path());
    dir
}

/// Depth and a uniform motion of 6 px a frame to the right for the plate (as velocity and as
/// previous and next positions), so every algorithm blurs it.
fn write_passes(dir: &Path) {
    let n = W * H;
    write_exr(&dir.join("depth.exr"), W, H, vec![("Z", vec![5.0; n])]);
    write_exr(
        &dir.join("velocity.exr"),
        W,
        H,
        vec![("X", vec![6.0; n]), ("Y", vec![0.0; n])],
    );
    let x = |shift: f32| (0..n).map(|i| (i % W) as f32 + 0.5 + shift).collect();
    let y: Vec<f32> = (0..n).map(|i| (i / W) as f32 + 0.5).collect();
    for (role, shift) in [("prev", -6.0), ("next", 6.0)] {
        write_exr(
            &dir.join(format!("{role}.exr")),
            W,
            H,
            vec![("X", x(shift)), ("Y", y.clone())],
        );
    }
}

fn blur(dir: &Path, out: &str, extra: &[&str]) {
    blur_with(dir, out, extra, &[]);
}

/// [`blur`] with the environment variables `env` set; what it printed.
fn blur_with(dir: &Path, out: &str, extra: &[&str], env: &[(&str, &str)]) -> Vec<u8> {
    // `dof` first in `extra` runs `shutter dof` (depth of field alone).
    let (command, extra) = match extra.split_first() {
        Some((&"dof", rest)) => ("dof", rest),
        _ => ("blur", extra),
    };
    let mut args = vec![command.to_string()];
    if command == "blur" && !extra.contains(&"--algorithm") {
        args.extend(["--algorithm".to_string(), "reconstruct".into()]);
    }
    args.extend([
        "--color".to_string(),
        s(&dir.join("color.exr")),
        "--depth".into(),
        s(&dir.join("depth.exr")),
        "--velocity".into(),
        s(&dir.join("velocity.exr")),
        "--prev".into(),
        s(&dir.join("prev.exr")),
        "--next".into(),
        s(&dir.join("next.exr")),
        "-o".into(),
        s(&dir.join(out)),
    ]);
    args.extend(extra.iter().map(|a| a.to_string()));
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_shutter"))
        .args(&args)
        .envs(env.iter().copied())
        .output()
        .expect("run shutter");
    assert!(run.status.success(), "{}", stderr(&run));
    run.stdout
}

#[test]
fn a_plates_attributes_pixel_types_and_compression_come_back() {
    let dir = plate_frame(Blocks::ScanLines, LineOrder::Increasing);
    blur(dir.path(), "out.exr", &[]);
    let out = dir.path().join("out.exr");

    let meta = MetaData::read_from_file(&out, false).unwrap();
    let header = &meta.headers[0];
    assert_eq!(header.compression, Compression::PIZ);
    assert!(header
        .channels
        .list
        .iter()
        .all(|c| c.sample_type == exr::meta::attribute::SampleType::F16));
    assert_eq!(header.shared_attributes.pixel_aspect, 2.0);
    assert_eq!(header.shared_attributes.chromaticities, Some(acescg()));
    assert_eq!(header.own_attributes.frames_per_second, Some((24, 1)));
    assert_eq!(
        header.own_attributes.owner,
        Some(Text::from("Studio X")),
        "owner"
    );
    assert_eq!(
        header.own_attributes.comments,
        Some(Text::from("test plate"))
    );
    for (name, value) in custom() {
        assert_eq!(
            header.own_attributes.other.get(&Text::from(name)),
            Some(&value),
            "{name}"
        );
    }
    let settings = header
        .own_attributes
        .other
        .get(&Text::from("shutter/settings"));
    assert!(
        matches!(settings, Some(AttributeValue::Text(t)) if t.to_string().contains("--algorithm reconstruct")),
        "{settings:?}"
    );

    if let Some(info) = oiiotool_info(&out) {
        for line in [
            "4 channel, half openexr",
            "compression: \"piz\"",
            "PixelAspectRatio: 2",
            "chromaticities: 0.713, 0.293, 0.165, 0.83, 0.128, 0.044, 0.32168, 0.33767",
            "framesPerSecond: 24/1",
            "Copyright: \"Studio X\"",
            "ImageDescription: \"test plate\"",
            "pipeline/shot: \"sq010_sh020\"",
            "pipeline/take: 7",
            "pipeline/gain: 1.5",
            "shutter/version: \"",
        ] {
            assert!(
                info.contains(line),
                "oiiotool does not show {line:?}:\n{info}"
            );
        }
    }
}

#[test]
fn settings_override_the_plates_compression_and_pixel_type() {
    let dir = plate_frame(Blocks::ScanLines, LineOrder::Increasing);
    blur(dir.path(), "out.exr", &["--compression", "zips"]);
    let meta = MetaData::read_from_file(dir.path().join("out.exr"), false).unwrap();
    assert_eq!(meta.headers[0].compression, Compression::ZIP1);
    assert!(meta.headers[0]
        .channels
        .list
        .iter()
        .all(|c| c.sample_type == exr::meta::attribute::SampleType::F16));

    // A float plate stays float, and --half makes it half.
    let n = W * H;
    write_exr(
        &dir.path().join("color.exr"),
        W,
        H,
        vec![
            ("R", vec![0.5; n]),
            ("G", vec![0.5; n]),
            ("B", vec![0.5; n]),
        ],
    );
    blur(dir.path(), "float.exr", &[]);
    blur(dir.path(), "half.exr", &["--half"]);
    let types = |file: &str| {
        let meta = MetaData::read_from_file(dir.path().join(file), false).unwrap();
        let list = &meta.headers[0].channels.list;
        list.iter().map(|c| c.sample_type).collect::<Vec<_>>()
    };
    use exr::meta::attribute::SampleType::{F16, F32};
    assert_eq!(types("float.exr"), vec![F32; 3]);
    assert_eq!(types("half.exr"), vec![F16; 3]);
}

#[test]
fn a_tiled_plate_in_decreasing_line_order_comes_back_tiled_in_that_order() {
    let dir = plate_frame(Blocks::Tiles(Vec2(16, 8)), LineOrder::Decreasing);
    blur(dir.path(), "out.exr", &[]);
    let out = dir.path().join("out.exr");
    let meta = MetaData::read_from_file(&out, false).unwrap();
    let header = &meta.headers[0];
    assert!(
        matches!(header.blocks, BlockDescription::Tiles(t) if t.tile_size == Vec2(16, 8)),
        "{:?}",
        header.blocks
    );
    assert_eq!(header.line_order, LineOrder::Decreasing);
    if let Some(info) = oiiotool_info(&out) {
        assert!(info.contains("tile size: 16 x 8"), "{info}");
    }
}

#[test]
fn a_tiled_plate_in_random_line_order_comes_back_declaring_random_order() {
    // RANDOM_Y (valid for tiles alone) is the plate's; it came back INCREASING_Y (QA).
    let dir = plate_frame(Blocks::Tiles(Vec2(16, 8)), LineOrder::Unspecified);
    let plate = MetaData::read_from_file(dir.path().join("color.exr"), false).unwrap();
    assert_eq!(plate.headers[0].line_order, LineOrder::Unspecified);
    blur(dir.path(), "a.exr", &[]);
    blur(dir.path(), "b.exr", &[]);
    let out = dir.path().join("a.exr");
    let meta = MetaData::read_from_file(&out, false).unwrap();
    let header = &meta.headers[0];
    assert!(
        matches!(header.blocks, BlockDescription::Tiles(t) if t.tile_size == Vec2(16, 8)),
        "{:?}",
        header.blocks
    );
    assert_eq!(header.line_order, LineOrder::Unspecified);
    // Its tiles still go out in one order: the same frame gives the same bytes.
    let b = std::fs::read(dir.path().join("b.exr")).unwrap();
    assert!(std::fs::read(&out).unwrap() == b, "two runs differ");
    if let Some(info) = oiiotool_info(&out) {
        assert!(info.contains("tile size: 16 x 8"), "{info}");
    }
}

#[test]
fn the_same_frame_gives_the_same_bytes_whatever_order_the_attributes_were_held_in() {
    // The exr crate writes custom attributes in the order of a HashMap, which differs from
    // process to process; with seven custom attributes (five of the plate's, shutter's two)
    // two runs agree by chance once in 5,040.
    let dir = plate_frame(Blocks::ScanLines, LineOrder::Increasing);
    blur(dir.path(), "a.exr", &[]);
    blur(dir.path(), "b.exr", &[]);
    let a = std::fs::read(dir.path().join("a.exr")).unwrap();
    let b = std::fs::read(dir.path().join("b.exr")).unwrap();
    assert!(a == b, "two runs of one frame wrote different bytes");
}

/// A multi-layer frame as renderers write them: a beauty RGBA that is the sum of its light
/// layers `diffuse` and `specular` (stored `kind`), with `Z`, `velocity.X/Y` and an object
/// ID (u32, values over 2²⁴ among them, where an f32 rounds) beside them.
fn write_layered(path: &Path, kind: exr::meta::attribute::SampleType) {
    use exr::meta::attribute::SampleType;
    let n = W * H;
    let stored = |plane: Vec<f32>| match kind {
        SampleType::F16 => plane
            .into_iter()
            .map(|v| f16::from_f32(v).to_f32())
            .collect(),
        _ => plane,
    };
    let samples = |plane: &[f32]| match kind {
        SampleType::F16 => FlatSamples::F16(plane.iter().map(|&v| f16::from_f32(v)).collect()),
        _ => FlatSamples::F32(plane.to_vec()),
    };
    let diffuse: Vec<Vec<f32>> = (0..3).map(|c| stored(noise(n, 10 + c, 0.0, 2.0))).collect();
    let specular: Vec<Vec<f32>> = (0..3).map(|c| stored(noise(n, 20 + c, 0.0, 0.5))).collect();
    let mut list = Vec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let beauty: Vec<f32> = (0..n).map(|i| diffuse[c][i] + specular[c][i]).collect();
        list.push(AnyChannel::new(Text::from(name), FlatSamples::F32(beauty)));
        let layer = |l: &str| Text::from(format!("{l}.{name}").as_str());
        list.push(AnyChannel::new(layer("diffuse"), samples(&diffuse[c])));
        list.push(AnyChannel::new(layer("specular"), samples(&specular[c])));
    }
    let data =
        |name: &str, plane: Vec<f32>| AnyChannel::new(Text::from(name), FlatSamples::F32(plane));
    list.push(data("A", vec![1.0; n]));
    list.push(data("Z", noise(n, 30, 1.0, 9.0)));
    list.push(data("velocity.X", noise(n, 31, -5.0, 5.0)));
    list.push(data("velocity.Y", noise(n, 32, -5.0, 5.0)));
    list.push(AnyChannel::new(
        Text::from("id"),
        FlatSamples::U32((0..n).map(|i| IDS[i % IDS.len()]).collect()),
    ));
    let layer = Layer::new(
        (W, H),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    let image = Image::from_layer(layer);
    image.write().to_file(path).unwrap();
}

/// Object IDs as a renderer hashes them: small ones, and ones an f32 cannot hold (2²⁴ + 1,
/// a NaN's bit pattern, the largest).
const IDS: [u32; 7] = [
    1000,
    16_777_217,
    16_777_219,
    0x7FC0_0001,
    0x8000_0001,
    3_000_000_001,
    u32::MAX,
];

/// A u32 channel of an EXR, as stored.
fn read_u32(path: &Path, name: &str) -> Vec<u32> {
    for layer in crate::support::read_exr_layers(path) {
        for channel in layer.channel_data.list {
            if channel.name.to_string() == name {
                match channel.sample_data {
                    FlatSamples::U32(values) => return values,
                    other => panic!("{name} is not u32: {other:?}"),
                }
            }
        }
    }
    panic!("no channel {name}")
}

/// Every run of a multi-layer frame: the channels of the input, the data ones bit for bit
/// (the IDs as u32, every bit), and light layers that still add up to the beauty.
fn check_layers(input: &Path, output: &Path, tolerance: f32) {
    let ids = read_u32(output, "id");
    assert!(
        ids.iter()
            .enumerate()
            .all(|(i, &v)| v == IDS[i % IDS.len()]),
        "{}: the IDs changed: {:?}",
        output.display(),
        &ids[..IDS.len()]
    );
    use crate::support::{channel, read_exr_reference};
    let before = read_exr_reference(input);
    let after = read_exr_reference(output);
    let names = |c: &[(String, Vec<f32>)]| {
        let mut names: Vec<String> = c.iter().map(|(n, _)| n.clone()).collect();
        names.sort();
        names
    };
    assert_eq!(names(&after), names(&before), "the output's channels");
    for data in ["Z", "velocity.X", "velocity.Y", "id"] {
        let (b, a) = (channel(&before, data), channel(&after, data));
        assert!(
            a.iter().zip(b).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{data} changed"
        );
    }
    for c in ["R", "G", "B"] {
        let beauty = channel(&after, c);
        let diffuse = channel(&after, &format!("diffuse.{c}"));
        let specular = channel(&after, &format!("specular.{c}"));
        assert!(
            beauty != channel(&before, c) && diffuse != channel(&before, &format!("diffuse.{c}")),
            "{}: {c}: nothing was blurred",
            output.display()
        );
        let worst = (0..W * H)
            .map(|i| (beauty[i] - diffuse[i] - specular[i]).abs() / (1.0 + beauty[i].abs()))
            .fold(0.0f32, f32::max);
        assert!(
            worst <= tolerance,
            "{c}: diffuse + specular differs from the beauty by {worst:e} (relative)"
        );
    }
}

/// A circle of confusion about 7 px across on the 40 px frame (depth 5 m, focus 0.3 m).
const LENS: [&str; 6] = [
    "--focal-length",
    "50",
    "--f-stop",
    "1.4",
    "--focus-distance",
    "0.3",
];

/// A folder holding the float multi-layer frame (`color.exr`) and its passes.
fn layered_frame() -> (tempfile::TempDir, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let color = dir.path().join("color.exr");
    write_layered(&color, exr::meta::attribute::SampleType::F32);
    write_passes(dir.path());
    (dir, color)
}

#[test]
fn light_layers_blur_with_the_beautys_weights_and_data_layers_come_back_unchanged() {
    let (dir, color) = layered_frame();
    let lens = LENS;
    for (name, args) in [
        ("reconstruct", &[][..]),
        ("2012", &["--variant", "paper"][..]),
        ("stretch", &["--algorithm", "stretch"][..]),
        ("scatter", &["--algorithm", "scatter"][..]),
        ("dof", &lens[..]),
        ("dof-alone", &[&["dof"][..], &lens[..]].concat()[..]),
    ] {
        let out = format!("{name}.exr");
        blur(dir.path(), &out, args);
        // Float rounding: the beauty's sum and the layers' sums round apart.
        check_layers(&color, &dir.path().join(&out), 1e-5);
    }
}

#[test]
fn half_light_layers_stay_half_and_add_up_within_its_rounding() {
    use exr::meta::attribute::SampleType;
    let dir = tempfile::tempdir().unwrap();
    let color = dir.path().join("color.exr");
    write_layered(&color, SampleType::F16);
    write_passes(dir.path());
    blur(dir.path(), "out.exr", &[]);
    let out = dir.path().join("out.exr");
    // Two half roundings of values up to 2.5: 2 × 2⁻¹¹ relative.
    check_layers(&color, &out, 2.0 * 2f32.powi(-11));
    if let Some(info) = oiiotool_info(&out) {
        // OpenImageIO lists the beauty first, then the channels of no layer, then the
        // layers, each channel with its pixel type.
        let list = "channel list: R (float), G (float), B (float), A (float), Z (float), \
                    id (uint), diffuse.R (half), diffuse.G (half), diffuse.B (half), \
                    specular.R (half), specular.G (half), specular.B (half), \
                    velocity.X (float), velocity.Y (float)";
        assert!(info.contains("14 channel") && info.contains(list), "{info}");
    }
    let meta = MetaData::read_from_file(&out, false).unwrap();
    for c in &meta.headers[0].channels.list {
        let name = c.name.to_string();
        let expected = if name.starts_with("diffuse") || name.starts_with("specular") {
            SampleType::F16
        } else if name == "id" {
            SampleType::U32
        } else {
            SampleType::F32
        };
        assert_eq!(c.sample_type, expected, "{name}");
    }
}

/// The GPU twins give every light layer the beauty's weights too: the layers go through the
/// same dispatches, so they add up as on the CPU.
#[cfg(feature = "gpu")]
#[test]
fn light_layers_add_up_on_the_gpu_too() {
    if crate::gpu::with_gpu::gpu().is_none() {
        return;
    }
    let (dir, color) = layered_frame();
    let lens = LENS;
    for (name, args) in [
        ("reconstruct", &[][..]),
        ("stretch", &["--algorithm", "stretch"][..]),
        ("scatter", &["--algorithm", "scatter"][..]),
        ("dof-alone", &[&["dof"][..], &lens[..]].concat()[..]),
    ] {
        let out = format!("{name}.exr");
        blur(
            dir.path(),
            &out,
            &[args, &["--backend", "wgpu"][..]].concat(),
        );
        check_layers(&color, &dir.path().join(&out), 1e-5);
    }
    // reconstruct's carrying gather on a device whose binding holds two colours of this frame
    // (two dispatches: the beauty and diffuse, then specular), and on one that holds not even
    // the texels (every colour on the CPU, in one pass): the CPU's layers, within the
    // gather's parity, and bit for bit.
    use crate::support::{channel, read_exr_reference};
    blur(dir.path(), "cpu.exr", &[]);
    let cpu = read_exr_reference(&dir.path().join("cpu.exr"));
    for (limit, exact) in [("32768", false), ("4096", true)] {
        let out = format!("limit-{limit}.exr");
        let env = [("SHUTTER_GPU_MAX_BINDING", limit)];
        let printed = blur_with(dir.path(), &out, &["--backend", "wgpu", "--json"], &env);
        let report: serde_json::Value = serde_json::from_slice(&printed).unwrap();
        let on_cpu = report["backend"]["stages_on_cpu"].as_u64().unwrap();
        assert_eq!(on_cpu > 0, exact, "limit {limit}: {report}");
        let got = read_exr_reference(&dir.path().join(&out));
        for name in ["R", "diffuse.R", "specular.G", "specular.B"] {
            let (c, g) = (channel(&cpu, name), channel(&got, name));
            let worst = c
                .iter()
                .zip(g)
                .map(|(c, g)| (c - g).abs())
                .fold(0.0f32, f32::max);
            let bound = if exact { 0.0 } else { 1e-5 };
            assert!(worst <= bound, "limit {limit}: {name} differs by {worst:e}");
        }
    }
}

#[test]
fn beauty_only_writes_the_beauty_alone_and_blurs_no_layer() {
    use exr::meta::attribute::SampleType;
    let dir = tempfile::tempdir().unwrap();
    write_layered(&dir.path().join("color.exr"), SampleType::F32);
    write_passes(dir.path());
    blur(dir.path(), "out.exr", &["--beauty-only"]);
    let written = crate::support::read_exr_reference(&dir.path().join("out.exr"));
    let mut names: Vec<&str> = written.iter().map(|(n, _)| n.as_str()).collect();
    names.sort();
    assert_eq!(names, ["A", "B", "G", "R"]);
}

/// README.md's "What survives" table: every row names the tests that check it (or says it is
/// open), and every test it names exists.
#[test]
fn the_readme_what_survives_table_names_tests_that_exist() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let start = readme
        .find("<!-- survives -->")
        .expect("the table's start marker");
    let end = readme
        .find("<!-- end survives -->")
        .expect("the table's end marker");
    let rows: Vec<&str> = readme[start..end]
        .lines()
        .filter(|l| l.starts_with('|') && !l.starts_with("| input") && !l.starts_with("|---"))
        .collect();
    assert!(rows.len() >= 15, "{} rows", rows.len());
    for row in rows {
        let checked = row.trim_end_matches('|').rsplit('|').next().unwrap().trim();
        if checked == "open" {
            continue;
        }
        let names: Vec<&str> = checked.split(", ").map(|n| n.trim_matches('`')).collect();
        assert!(
            !names.is_empty() && !names[0].is_empty(),
            "no test named: {row}"
        );
        for name in names {
            let (module, test) = name.split_once("::").unwrap_or_else(|| panic!("{name}"));
            let source = std::fs::read_to_string(root.join("tests").join(format!("{module}.rs")))
                .unwrap_or_else(|_| panic!("{name}: no tests/{module}.rs"));
            assert!(
                source.contains(&format!("fn {test}()")),
                "{name}: no such test in tests/{module}.rs"
            );
        }
    }
}

#[test]
fn vectors_read_from_a_lossy_part_are_warned_about_by_channel() {
    // DWAA keeps `velocity.Y` (a name ending in Y, as luminance) only roughly and
    // `velocity.X` exactly: OpenEXR's rule is by name, whatever the pixel type.
    let dir = plate_frame(Blocks::ScanLines, LineOrder::Increasing);
    let n = W * H;
    let vectors = Layer::new(
        (W, H),
        LayerAttributes::default(),
        Encoding {
            compression: Compression::DWAA(None),
            blocks: Blocks::ScanLines,
            line_order: LineOrder::Increasing,
        },
        AnyChannels::sort(
            vec![
                AnyChannel::new("X", FlatSamples::F32(vec![6.0; n])),
                AnyChannel::new("Y", FlatSamples::F32(vec![0.0; n])),
            ]
            .into(),
        ),
    );
    Image::from_layer(vectors)
        .write()
        .to_file(dir.path().join("velocity.exr"))
        .unwrap();
    let run = shutter(&[
        "blur",
        "--algorithm",
        "reconstruct",
        "--color",
        &s(&dir.path().join("color.exr")),
        "--depth",
        &s(&dir.path().join("depth.exr")),
        "--velocity",
        &s(&dir.path().join("velocity.exr")),
        "-o",
        &s(&dir.path().join("out.exr")),
        "--json",
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let report: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
    let warnings = report["warnings"].to_string();
    assert!(
        warnings.contains("velocity: channel Y is compressed with dwaa"),
        "{warnings}"
    );
    assert!(!warnings.contains("channel X"), "{warnings}");
    assert!(!warnings.contains("depth:"), "{warnings}");
}

#[test]
fn a_picture_from_an_exr_is_its_display_window_not_its_overscan() {
    use shutter::frame::{Window, Windows};
    let dir = tempfile::tempdir().unwrap();
    // Overscan: 4 px beyond the 16×10 picture on the left and right, 2 above and below.
    let (dw, dh) = (24usize, 14usize);
    let windows = Windows {
        data_origin: (-4, -2),
        display: Window {
            x: 0,
            y: 0,
            width: 16,
            height: 10,
        },
    };
    // Each pixel holds its own file x coordinate over 32, so the picture's columns say where
    // they came from.
    let r: Vec<f32> = (0..dw * dh)
        .map(|i| ((i % dw) as f32 - 4.0 + 8.0) / 32.0)
        .collect();
    let file = std::io::BufWriter::new(std::fs::File::create(dir.path().join("c.exr")).unwrap());
    shutter::io::exr::write_channels(
        file,
        dw,
        dh,
        windows,
        vec![
            ("R".into(), r.clone()),
            ("G".into(), r.clone()),
            ("B".into(), r),
        ],
        shutter::io::exr::ExrOptions::default(),
    )
    .unwrap();
    let out = dir.path().join("out.png");
    let run = shutter(&[
        "blur",
        "--linear",
        "--color",
        &s(&dir.path().join("c.exr")),
        "-o",
        &s(&out),
    ]);
    assert!(run.status.success(), "{}", stderr(&run));
    let picture = image::open(&out).unwrap().to_rgb8();
    assert_eq!(picture.dimensions(), (16, 10));
    for x in 0..16u32 {
        let expected = ((x as f32 + 8.0) / 32.0 * 255.0).round() as u8;
        assert_eq!(picture.get_pixel(x, 5)[0], expected, "column {x}");
    }
}

/// `--skip-existing` finds a picture made from an EXR whole when its data window is not its
/// display window: overscan (data beyond the picture) and an auto bounding box (data inside
/// it, fewer pixels than the picture). The picture is the display window; it was held
/// against the data window's size, so every rerun wrote every frame again, saying it was
/// "16x10, the frame is 24x14" (or, for the box, that 160 pixels were above a pixel limit
/// nobody set). `--dry-run` says "skip" alike.
#[test]
fn skip_existing_finds_a_picture_of_an_overscan_or_bbox_exr_whole() {
    use shutter::frame::Window;
    let dir = tempfile::tempdir().unwrap();
    let display = Window {
        x: 0,
        y: 0,
        width: 16,
        height: 10,
    };
    // (name, data window origin, data window size)
    let cases = [
        ("overscan", (-4, -2), (24usize, 14usize)),
        ("bbox", (5, 3), (6usize, 4usize)),
    ];
    for (name, origin, (w, h)) in cases {
        let n = w * h;
        let channels = ["R", "G", "B", "A", "Z", "velocity.X", "velocity.Y"]
            .iter()
            .zip([
                noise(n, 3, 0.0, 1.0),
                noise(n, 4, 0.0, 1.0),
                noise(n, 5, 0.0, 1.0),
                vec![1.0; n],
                vec![5.0; n],
                vec![2.0; n],
                vec![0.0; n],
            ])
            .map(|(c, v)| (c.to_string(), v))
            .collect();
        let input = dir.path().join(format!("{name}.exr"));
        write_windowed(&input, origin, (w, h), display, channels);
        for ext in ["png", "tif", "jpg"] {
            let out = s(&dir.path().join(format!("{name}.{ext}")));
            let args = [
                "blur",
                "--algorithm",
                "reconstruct",
                "--color",
                &s(&input),
                "-o",
                &out,
            ];
            let first = shutter(&args);
            assert!(first.status.success(), "{name}.{ext}: {}", stderr(&first));
            let (w, h) = image::image_dimensions(&out).unwrap();
            assert_eq!((w, h), (16, 10), "{name}.{ext}: the display window");
            let before = std::fs::read(&out).unwrap();
            let again = [&args[..], &["--skip-existing", "--json"]].concat();
            let o = shutter(&again);
            assert!(o.status.success(), "{name}.{ext}: {}", stderr(&o));
            let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
            assert_eq!(report["frames_skipped"], 1, "{name}.{ext}: {report}");
            assert_eq!(report["frames_written"], 0, "{name}.{ext}: {report}");
            let warnings = report["warnings"].to_string();
            assert!(
                !warnings.contains("written again"),
                "{name}.{ext}: {warnings}"
            );
            assert_eq!(std::fs::read(&out).unwrap(), before, "{name}.{ext}");
            let dry = [&again[..], &["--dry-run"]].concat();
            let o = shutter(&dry);
            assert!(o.status.success(), "{name}.{ext}: {}", stderr(&o));
            let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
            assert_eq!(
                report["planned"][0]["action"], "skip",
                "{name}.{ext}: {report}"
            );
        }
    }
}

/// A multi-part frame as Nuke writes one: the beauty (`rgba`, PIZ half), a light layer as a
/// part of its own (`diffuse`, channels R, G, B, equal to the beauty), and the data in a ZIP
/// part (`data`: Z, velocity.X, velocity.Y).
fn write_multi_part(path: &Path) {
    let n = W * H;
    let light: Vec<Vec<f32>> = (0..3).map(|c| noise(n, 40 + c, 0.0, 1.0)).collect();
    let half = |p: &[f32]| FlatSamples::F16(p.iter().map(|&v| f16::from_f32(v)).collect());
    let part = |name: &str, compression, channels: Vec<AnyChannel<FlatSamples>>| {
        Layer::new(
            (W, H),
            LayerAttributes::named(name),
            Encoding {
                compression,
                blocks: Blocks::ScanLines,
                line_order: LineOrder::Increasing,
            },
            AnyChannels::sort(channels.into()),
        )
    };
    let rgb = |l: &[Vec<f32>]| {
        ["R", "G", "B"]
            .into_iter()
            .zip(l)
            .map(|(c, p)| AnyChannel::new(c, half(p)))
            .collect::<Vec<_>>()
    };
    let data = vec![
        AnyChannel::new("Z", FlatSamples::F32(noise(n, 50, 1.0, 9.0))),
        AnyChannel::new("velocity.X", FlatSamples::F32(noise(n, 51, -3.0, 3.0))),
        AnyChannel::new("velocity.Y", FlatSamples::F32(noise(n, 52, -3.0, 3.0))),
    ];
    let image = Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions((W, H))))
        .with_layer(part("rgba", Compression::PIZ, rgb(&light)))
        .with_layer(part("diffuse", Compression::PIZ, rgb(&light)))
        .with_layer(part("data", Compression::ZIP16, data));
    image.write().to_file(path).unwrap();
}

/// (part name, compression, channel names) of each part of an EXR.
fn parts_of(path: &Path) -> Vec<(String, Compression, Vec<String>)> {
    let meta = MetaData::read_from_file(path, false).unwrap();
    meta.headers
        .iter()
        .map(|h| {
            (
                h.own_attributes
                    .layer_name
                    .as_ref()
                    .map_or(String::new(), |n| n.to_string()),
                h.compression,
                h.channels.list.iter().map(|c| c.name.to_string()).collect(),
            )
        })
        .collect()
}

#[test]
fn a_multi_part_frame_comes_back_part_for_part() {
    let dir = tempfile::tempdir().unwrap();
    let color = dir.path().join("color.exr");
    write_multi_part(&color);
    write_passes(dir.path());
    blur(dir.path(), "out.exr", &[]);
    let out = dir.path().join("out.exr");
    let rgb = vec!["B".to_string(), "G".into(), "R".into()];
    assert_eq!(
        parts_of(&out),
        vec![
            ("rgba".into(), Compression::PIZ, rgb.clone()),
            ("diffuse".into(), Compression::PIZ, rgb),
            (
                "data".into(),
                Compression::ZIP16,
                vec!["Z".into(), "velocity.X".into(), "velocity.Y".into()]
            ),
        ]
    );
    // Read part by part: the light part blurred as the beauty, the data part bit for bit.
    let read = |path: &Path| {
        let image = exr::prelude::read_all_flat_layers_from_file(path).unwrap();
        image
            .layer_data
            .into_iter()
            .map(|layer| {
                layer
                    .channel_data
                    .list
                    .into_iter()
                    .map(|c| c.sample_data.values_as_f32().collect::<Vec<f32>>())
                    .collect::<Vec<_>>()
            })
            .collect::<Vec<_>>()
    };
    let (before, after) = (read(&color), read(&out));
    assert_ne!(after[0], before[0], "the beauty was not blurred");
    assert_eq!(
        after[1], after[0],
        "the light part is blurred as the beauty"
    );
    for (a, b) in after[2].iter().zip(&before[2]) {
        assert!(a.iter().zip(b).all(|(a, b)| a.to_bits() == b.to_bits()));
    }
    if let Some(info) = oiiotool_info(&out) {
        assert!(info.contains("3 subimages"), "{info}");
    }
}

#[test]
fn a_part_of_data_alone_keeps_its_name_under_dwa() {
    // The multi-part frame's `data` part holds data alone: under DWAA it is that same part,
    // ZIP, not an empty part dropped and its channels moved to a new one (`data.data`).
    let dir = tempfile::tempdir().unwrap();
    let color = dir.path().join("color.exr");
    write_multi_part(&color);
    write_passes(dir.path());
    blur(dir.path(), "out.exr", &["--compression", "dwaa"]);
    let out = dir.path().join("out.exr");
    let names: Vec<(String, bool)> = parts_of(&out)
        .into_iter()
        .map(|(name, compression, _)| (name, matches!(compression, Compression::DWAA(_))))
        .collect();
    assert_eq!(
        names,
        [
            ("rgba".to_string(), true),
            ("diffuse".to_string(), true),
            ("data".to_string(), false)
        ]
    );
    let compared = shutter(&["diff", &s(&color), &s(&out), "--data-fail-pixel", "0"]);
    assert!(
        !stderr(&compared).contains("lacks"),
        "{}",
        stderr(&compared)
    );
}

#[test]
fn data_under_a_dwa_output_goes_to_a_lossless_part_of_its_own() {
    use exr::meta::attribute::SampleType;
    let dir = tempfile::tempdir().unwrap();
    let color = dir.path().join("color.exr");
    write_layered(&color, SampleType::F32);
    write_passes(dir.path());
    blur(dir.path(), "out.exr", &["--compression", "dwaa"]);
    let out = dir.path().join("out.exr");
    let parts = parts_of(&out);
    assert_eq!(parts.len(), 2, "{parts:?}");
    assert!(matches!(parts[0].1, Compression::DWAA(_)), "{parts:?}");
    // Named `data`, as a pipeline names a part of data channels, not `rgba.data` (a name
    // that reads as the channel `data` of the layer `rgba`).
    assert_eq!(parts[1].0, "data");
    assert_eq!(parts[1].1, Compression::ZIP16);
    assert_eq!(parts[1].2, ["Z", "id", "velocity.X", "velocity.Y"]);
    // `diff` finds each data channel in its new part: the round trip loses none, and they
    // come back exact (the light, blurred, is not gated here).
    let compared = shutter(&[
        "diff",
        &s(&color),
        &s(&out),
        "--data-fail-pixel",
        "0",
        "--fail-pixel",
        "1e30",
    ]);
    assert!(
        compared.status.success() && !stderr(&compared).contains("lacks"),
        "{}",
        stderr(&compared)
    );
    // And the other way round: the multi-part file as the reference.
    let reverse = shutter(&[
        "diff",
        &s(&out),
        &s(&color),
        "--data-fail-pixel",
        "0",
        "--fail-pixel",
        "1e30",
    ]);
    assert!(reverse.status.success(), "{}", stderr(&reverse));
    // The data comes back bit for bit.
    use crate::support::{channel, read_exr_reference};
    let (before, after) = (read_exr_reference(&color), read_exr_reference(&out));
    for data in ["Z", "velocity.X", "velocity.Y", "id"] {
        let (b, a) = (channel(&before, data), channel(&after, data));
        assert!(
            a.iter().zip(b).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{data}"
        );
    }
}

/// Under B44 and B44A (lossy for half channels) and PXR24 (float to 24 bits), the data those
/// would store lossily goes to a lossless part of its own, as under DWA (an outside probe:
/// `--compression b44` wrote half depth and vectors through B44, 15 px off, with no word);
/// data they keep exactly (float under B44, u32 IDs) stays in its part, and nothing moves
/// where nothing would be lossy.
#[test]
fn data_b44_or_pxr24_would_store_lossily_goes_to_a_lossless_part() {
    use crate::support::{assert_same_bits, channel, read_exr_reference};
    use exr::meta::attribute::SampleType;
    let dir = tempfile::tempdir().unwrap();
    let color = dir.path().join("color.exr");
    write_layered(&color, SampleType::F32);
    write_passes(dir.path());
    let before = read_exr_reference(&color);
    for (method, half, compression) in [
        ("b44", true, Compression::B44),
        ("b44a", true, Compression::B44A),
        ("pxr24", false, Compression::PXR24),
    ] {
        let name = format!("out-{method}.exr");
        let mut extra = vec!["--compression", method];
        if half {
            extra.push("--half");
        }
        blur(dir.path(), &name, &extra);
        let out = dir.path().join(&name);
        let parts = parts_of(&out);
        assert_eq!(parts.len(), 2, "{method}: {parts:?}");
        assert_eq!(parts[0].1, compression, "{method}: {parts:?}");
        assert!(
            parts[0].2.contains(&"id".to_string()),
            "{method}: {parts:?}"
        );
        assert_eq!(parts[1].0, "data", "{method}");
        assert_eq!(parts[1].1, Compression::ZIP16, "{method}");
        assert_eq!(parts[1].2, ["Z", "velocity.X", "velocity.Y"], "{method}");
        let after = read_exr_reference(&out);
        for data in ["Z", "velocity.X", "velocity.Y", "id"] {
            let expected: Vec<f32> = channel(&before, data)
                .iter()
                .map(|&v| match half && data != "id" {
                    true => f16::from_f32(v).to_f32(),
                    false => v,
                })
                .collect();
            assert_same_bits(
                channel(&after, data),
                &expected,
                &format!("{method} {data}"),
            );
        }
    }
    // Float data under B44 is kept exactly: one part, as before.
    blur(dir.path(), "out-float.exr", &["--compression", "b44"]);
    assert_eq!(parts_of(&dir.path().join("out-float.exr")).len(), 1);
}

#[test]
fn passes_are_placed_by_their_data_windows() {
    use shutter::frame::Window;
    let dir = tempfile::tempdir().unwrap();
    let display = Window {
        x: 0,
        y: 0,
        width: W,
        height: H,
    };
    let write = |name: &str, origin: (i32, i32), size: (usize, usize), channels| {
        write_windowed(&dir.path().join(name), origin, size, display, channels);
    };
    // The beauty: an auto-bbox from (4, 2), 20×10 of the 40×24 picture.
    let (cw, ch) = (20, 10);
    write(
        "color.exr",
        (4, 2),
        (cw, ch),
        ["R", "G", "B"]
            .map(|c| (c.to_string(), noise(cw * ch, 60, 0.0, 1.0)))
            .into(),
    );
    // Depth rendered with 8 px of overscan: each pixel holds its file coordinates, so the
    // depth the beauty's pixels were given says where it was read from.
    let (dw, dh) = (W + 16, H + 16);
    let coded: Vec<f32> = (0..dw * dh)
        .map(|i| {
            let (x, y) = ((i % dw) as f32 - 8.0, (i / dw) as f32 - 8.0);
            1000.0 + x + 100.0 * y
        })
        .collect();
    write("depth.exr", (-8, -8), (dw, dh), vec![("Z".into(), coded)]);
    let info = shutter::io::file::FileInfo::probe(&dir.path().join("color.exr")).unwrap();
    assert_eq!(info.windows.data_origin, (4, 2));
    let preset = shutter::io::preset::Preset::builtin("shutter").unwrap();
    let inputs = shutter::io::passes::Inputs {
        depth: Some(
            shutter::io::sequence::PathPattern::parse(&s(&dir.path().join("depth.exr"))).unwrap(),
        ),
        ..shutter::io::passes::Inputs::color_only(
            shutter::io::sequence::PathPattern::parse(&s(&dir.path().join("color.exr"))).unwrap(),
        )
    };
    let options = shutter::io::passes::PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: shutter::Passes {
            color: true,
            depth: true,
            ..shutter::Passes::default()
        },
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let plan = shutter::io::passes::plan_frame(&inputs, None, &options).unwrap();
    let frame = shutter::io::passes::read_frame(&plan).unwrap();
    let depth = frame.depth.unwrap();
    assert_eq!(depth.len(), cw * ch);
    for (i, &z) in depth.iter().enumerate() {
        let (x, y) = (4 + i % cw, 2 + i / cw);
        assert_eq!(z, 1000.0 + x as f32 + 100.0 * y as f32, "pixel ({x}, {y})");
    }

    // A depth that does not cover the beauty's window is refused, naming both windows:
    // (depth file, its origin and size, the words expected).
    let refused = |name: &str, origin: (i32, i32), (w, h): (usize, usize), expected: &str| {
        write(name, origin, (w, h), vec![("Z".into(), vec![5.0; w * h])]);
        let run = blur_with_depth(dir.path(), name, "out.exr");
        assert_eq!(run.status.code(), Some(1), "{name}: {}", stderr(&run));
        assert!(stderr(&run).contains(expected), "{name}: {}", stderr(&run));
    };
    // One that stops short of the beauty's bottom row.
    refused(
        "short.exr",
        (0, 0),
        (W, 11),
        "its data window (0, 0) - (39, 10) does not cover the color pass's (4, 2) - (23, 11)",
    );
    // One of the beauty's size, one pixel to the right (issue 30: it was read as if aligned).
    refused(
        "offset.exr",
        (5, 2),
        (cw, ch),
        "its data window (5, 2) - (24, 11) does not cover",
    );
}

/// `shutter blur --algorithm reconstruct` of `dir`'s color.exr with the depth file `depth`
/// of `dir`, to `out` in `dir`.
fn blur_with_depth(dir: &Path, depth: &str, out: &str) -> std::process::Output {
    let [color, depth, out] = ["color.exr", depth, out].map(|n| s(&dir.join(n)));
    let args = ["blur", "--algorithm", "reconstruct", "--color", &color];
    shutter(&[&args[..], &["--depth", &depth, "-o", &out]].concat())
}

/// An EXR of `channels` (each w × h) at data window origin `origin` in a picture `display`.
fn write_windowed(
    path: &Path,
    origin: (i32, i32),
    (w, h): (usize, usize),
    display: shutter::frame::Window,
    channels: Vec<(String, Vec<f32>)>,
) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let windows = shutter::frame::Windows {
        data_origin: origin,
        display,
    };
    let options = shutter::io::exr::ExrOptions::default();
    shutter::io::exr::write_channels(file, w, h, windows, channels, options).unwrap();
}

/// A pass whose display window is not the colour's was framed for another picture (rendered
/// at another resolution): placed by its data window, it is read without error, so the run
/// says so. An overscan pass (the same display window, a wider data window) is not warned of.
#[test]
fn a_pass_framed_for_another_picture_is_warned_of() {
    use shutter::frame::Window;
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, origin, (w, h): (usize, usize), display, names: Vec<&str>| {
        let channels = Vec::from_iter(
            (names.into_iter()).map(|c| (c.to_string(), noise(w * h, 61, 1.0, 5.0))),
        );
        write_windowed(&dir.path().join(name), origin, (w, h), display, channels);
    };
    let picture = |width, height| Window {
        x: 0,
        y: 0,
        width,
        height,
    };
    write(
        "color.exr",
        (0, 0),
        (W, H),
        picture(W, H),
        vec!["R", "G", "B", "velocity.X", "velocity.Y"],
    );
    // Depth with 8 px of overscan each side; depth rendered at twice the resolution.
    write(
        "over.exr",
        (-8, -8),
        (W + 16, H + 16),
        picture(W, H),
        vec!["Z"],
    );
    write(
        "twice.exr",
        (0, 0),
        (2 * W, 2 * H),
        picture(2 * W, 2 * H),
        vec!["Z"],
    );
    let run = |depth: &str| {
        let o = blur_with_depth(dir.path(), depth, &format!("out-{depth}"));
        assert!(o.status.success(), "{depth}: {}", stderr(&o));
        stderr(&o)
    };
    let warned = "display window";
    let over = run("over.exr");
    assert!(!over.contains(warned), "{over}");
    let twice = run("twice.exr");
    assert!(
        twice.contains("depth: the file's display window (0, 0) - (79, 47) is not the color pass's (0, 0) - (39, 23)"),
        "{twice}"
    );
}

#[test]
fn a_presets_layers_table_overrides_a_layers_class() {
    use crate::support::{channel, read_exr_reference};
    let (dir, color) = layered_frame();
    let preset = dir.path().join("layers.toml");
    std::fs::write(
        &preset,
        "[layers]\nspecular = \"data\"\nvelocity = \"colour\"\n",
    )
    .unwrap();
    blur(dir.path(), "out.exr", &["--preset", &s(&preset)]);
    let (before, after) = (
        read_exr_reference(&color),
        read_exr_reference(&dir.path().join("out.exr")),
    );
    // specular, light by its name, kept as data: bit for bit; velocity, data by its name,
    // blurred as light; diffuse as the rule says.
    assert_eq!(
        channel(&after, "specular.R"),
        channel(&before, "specular.R")
    );
    assert_ne!(
        channel(&after, "velocity.X"),
        channel(&before, "velocity.X")
    );
    assert_ne!(channel(&after, "diffuse.R"), channel(&before, "diffuse.R"));
    // A key one typo from a layer of the file is warned of, naming the layer it meant;
    // a key naming a layer the file lacks (one preset for shots of other AOVs) is not.
    let typo = dir.path().join("typo.toml");
    std::fs::write(&typo, "[layers]\nspecualr = \"data\"\nnormal = \"data\"\n").unwrap();
    let passes = ["depth", "velocity", "prev", "next"]
        .map(|p| [format!("--{p}"), s(&dir.path().join(format!("{p}.exr")))]);
    let mut args = vec!["blur".to_string(), "--color".into(), s(&color)];
    args.extend(passes.into_iter().flatten());
    args.extend(
        [
            "-o",
            &s(&dir.path().join("typo.exr")),
            "--preset",
            &s(&typo),
        ]
        .map(String::from),
    );
    let o = shutter(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", stderr(&o));
    let said = stderr(&o);
    assert!(
        said.contains(
            "[layers] names specualr, which is no layer of the colour file: did you mean specular?"
        ),
        "{said}"
    );
    assert!(!said.contains("names normal"), "{said}");
    // `shutter info --preset` shows the classes the run gave them.
    let o = shutter(&["info", &s(&color), "--json", "--preset", &s(&preset)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let class = |name: &str| {
        doc["files"][0]["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["name"] == name)
            .map(|c| c["class"].as_str().unwrap().to_string())
            .unwrap()
    };
    assert_eq!(class("specular.R"), "data");
    assert_eq!(class("velocity.X"), "colour");
    assert_eq!(class("diffuse.R"), "colour");
}

/// A frame whose beauty is the sum of two light layers, at a moving silhouette with the
/// fringe a renderer leaves: a square 6 px a frame in front (z 1) over a still background
/// (z 10), its edges covering their pixels by fractions, each layer with its own colours
/// on each surface (so each layer's colour line at the edge is its own).
fn silhouette() -> shutter::frame::Frame {
    use shutter::frame::{Carried, CarriedChannel, Color, Frame, LayerClass, Velocity};
    let (w, h) = (48usize, 32usize);
    let n = w * h;
    // The square's edges, at fractions of a pixel.
    let (x0, x1, y0, y1) = (12.3f32, 29.6f32, 8.7f32, 22.4f32);
    let overlap = |a: f32, b: f32, lo: f32, hi: f32| (b.min(hi) - a.max(lo)).clamp(0.0, 1.0);
    let cover: Vec<f32> = (0..n)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            overlap(x, x + 1.0, x0, x1) * overlap(y, y + 1.0, y0, y1)
        })
        .collect();
    // Each surface textured, a layer's texture its own: the pair of colours that explains a
    // fringe pixel best differs from layer to layer.
    let texture = |seed: u32| noise(n, seed, 0.0, 0.3);
    let layer = |fg: [f32; 3], bg: [f32; 3], seed: u32| -> [Vec<f32>; 3] {
        let (tf, tb) = (texture(seed), texture(seed + 1));
        [0, 1, 2].map(|c| {
            (0..n)
                .map(|i| {
                    let a = cover[i];
                    a * (fg[c] + tf[i]) + (1.0 - a) * (bg[c] + tb[i])
                })
                .collect()
        })
    };
    let diffuse = layer([0.8, 0.1, 0.05], [0.05, 0.3, 0.6], 40);
    let specular = layer([0.1, 0.6, 0.2], [0.4, 0.05, 0.1], 50);
    let beauty: [Vec<f32>; 3] =
        [0, 1, 2].map(|c| (0..n).map(|i| diffuse[c][i] + specular[c][i]).collect());
    let moving: Vec<bool> = cover.iter().map(|&a| a >= 0.5).collect();
    let mut frame = Frame::new(w, h);
    let [r, g, b] = beauty;
    frame.color = Some(Color {
        r,
        g,
        b,
        a: Some(vec![1.0; n]),
    });
    frame.depth = Some(moving.iter().map(|&m| if m { 1.0 } else { 10.0 }).collect());
    frame.velocity = Some(Velocity {
        x: moving.iter().map(|&m| if m { 6.0 } else { 0.0 }).collect(),
        y: moving.iter().map(|&m| if m { 2.0 } else { 0.0 }).collect(),
    });
    // Straight-line motion: p(±1) = p ± v.
    let positions = |sign: f32| {
        let v = frame.velocity.as_ref().expect("velocity");
        shutter::frame::Positions {
            x: (0..n)
                .map(|i| (i % w) as f32 + 0.5 + sign * v.x[i])
                .collect(),
            y: (0..n)
                .map(|i| (i / w) as f32 + 0.5 + sign * v.y[i])
                .collect(),
            z: None,
        }
    };
    frame.prev = Some(positions(-1.0));
    frame.next = Some(positions(1.0));
    let mut channels = Vec::new();
    for (name, planes) in [("diffuse", diffuse), ("specular", specular)] {
        // As an EXR holds them, sorted by name: B, G, R.
        for (c, plane) in ["R", "G", "B"].into_iter().zip(planes).rev() {
            channels.push(CarriedChannel {
                exact: None,
                name: format!("{name}.{c}"),
                stored: format!("{name}.{c}"),
                shared: false,
                window: None,
                part: 0,
                class: LayerClass::Colour,
                plane,
            });
        }
    }
    frame.carried = Carried {
        channels,
        ..Carried::default()
    };
    frame
}

/// The worst relative difference between the blurred beauty and the sum of its blurred
/// light layers.
fn sum_error(out: &shutter::frame::Frame) -> f32 {
    let color = out.color.as_ref().expect("colour");
    let plane = |name: &str| {
        &out.carried
            .channels
            .iter()
            .find(|c| c.name == name)
            .expect("a layer")
            .plane
    };
    let mut worst = 0.0f32;
    for (c, beauty) in ["R", "G", "B"]
        .into_iter()
        .zip([&color.r, &color.g, &color.b])
    {
        let (d, s) = (
            plane(&format!("diffuse.{c}")),
            plane(&format!("specular.{c}")),
        );
        for i in 0..beauty.len() {
            worst = worst.max((beauty[i] - d[i] - s[i]).abs() / (1.0 + beauty[i].abs()));
        }
    }
    worst
}

/// The matte at a silhouette (the default variant's coverage and unmixing) is the beauty's,
/// given to every light layer: fitted on each layer's own colours, a layer's coverage and
/// unmixed colours differ from the beauty's and the sum no longer holds there (it was off by
/// 7 % before the mattes were shared). On the CPU, and on the GPU's twins where there is one.
#[test]
fn light_layers_add_up_at_a_moving_silhouette() {
    use shutter::motion::{Algorithm, Variant};
    use shutter::numeric;
    use shutter::process::{process_on, Params};
    #[cfg(feature = "gpu")]
    let gpu = crate::gpu::with_gpu::gpu();
    #[cfg(not(feature = "gpu"))]
    let gpu: Option<&shutter::gpu::Gpu> = None;
    let mut params = Params::default();
    for variant in [Variant::Exposure, Variant::Stable, Variant::Paper] {
        params.reconstruct.variant = variant;
        for algorithm in [
            Algorithm::Reconstruct,
            Algorithm::Scatter,
            Algorithm::Stretch,
        ] {
            for backend in std::iter::once(None).chain(gpu.map(Some)) {
                let mut frame = silhouette();
                numeric::sanitize(&mut frame, numeric::DepthKind::Depth);
                let before = frame.color.as_ref().unwrap().r.clone();
                let out = process_on(algorithm, &params, frame, 3, backend);
                let on = if backend.is_some() { "GPU" } else { "CPU" };
                assert!(
                    out.color.as_ref().unwrap().r != before,
                    "{algorithm:?} {variant:?} on the {on}: nothing was blurred"
                );
                let worst = sum_error(&out);
                assert!(
                    worst <= 1e-5,
                    "{algorithm:?} {variant:?} on the {on}: the layers' sum differs from the \
                     beauty by {worst:e}"
                );
            }
        }
    }
}

/// A single-layer EXR of RGB noise (`seed`) and the channels given, as the exr crate
/// writes it.
fn write_rgb_with(path: &Path, seed: u32, extra: Vec<AnyChannel<FlatSamples>>) {
    let n = W * H;
    let mut list = extra;
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        list.push(AnyChannel::new(
            Text::from(name),
            FlatSamples::F32(noise(n, seed + c as u32, 0.0, 1.0)),
        ));
    }
    let layer = Layer::new(
        (W, H),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
}

/// `diff` compares u32 IDs as they are stored: two IDs over 2²⁴ that one f32 holds alike
/// (16777217 against 16777216) are a difference, and the data gate fails it.
#[test]
fn diff_tells_ids_apart_that_an_f32_rounds_alike() {
    let dir = tempfile::tempdir().unwrap();
    let write = |name: &str, changed: bool| {
        let n = W * H;
        let mut ids: Vec<u32> = (0..n).map(|i| IDS[i % IDS.len()]).collect();
        if changed {
            // IDS[1] is 2²⁴ + 1: its neighbour below rounds to the same f32.
            ids[1] = 16_777_216;
        }
        let path = dir.path().join(name);
        let id = AnyChannel::new(Text::from("id"), FlatSamples::U32(ids));
        write_rgb_with(&path, 40, vec![id]);
        s(&path)
    };
    let (a, b, same) = (
        write("a.exr", false),
        write("b.exr", true),
        write("c.exr", false),
    );
    let o = shutter(&["diff", &a, &b, "--data-fail-pixel", "0", "--json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let text = report.to_string();
    let largest = &report["frames"][0]["largest"];
    assert_eq!(largest["channel"], "id", "{text}");
    assert_eq!(largest["error"], 1.0, "{text}");
    let o = shutter(&["diff", &a, &same, "--data-fail-pixel", "0"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
}

/// A u32 channel a pass reads (a depth stored as integers) is read as its number, not as the
/// bits an ID layer is carried in: the frame blurs as with the same depth stored as float,
/// and the IDs beside it still come back bit for bit.
#[test]
fn a_u32_depth_is_read_as_a_number_beside_exact_ids() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let depth: Vec<u32> = (0..n).map(|i| if i % W < W / 2 { 1 } else { 20 }).collect();
    let write = |name: &str, integer: bool| {
        let id = AnyChannel::new(
            Text::from("id"),
            FlatSamples::U32((0..n).map(|i| IDS[i % IDS.len()]).collect()),
        );
        let z = AnyChannel::new(
            Text::from("Z"),
            if integer {
                FlatSamples::U32(depth.clone())
            } else {
                FlatSamples::F32(depth.iter().map(|&d| d as f32).collect())
            },
        );
        let path = dir.path().join(name);
        write_rgb_with(&path, 50, vec![id, z]);
        path
    };
    let dof = |input: &Path, out: &str, extra: &[&str]| {
        let out = dir.path().join(out);
        let mut args = vec![
            "dof".to_string(),
            "--focal-length".into(),
            "50".into(),
            "--f-stop".into(),
            "1.4".into(),
            "--focus-distance".into(),
            "1".into(),
            "--color".into(),
            s(input),
            "-o".into(),
            s(&out),
        ];
        args.extend(extra.iter().map(|a| a.to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = shutter(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };
    let u32_input = write("u32.exr", true);
    let integer = dof(&u32_input, "u32_out.exr", &[]);
    let float = dof(&write("f32.exr", false), "f32_out.exr", &[]);
    use crate::support::{channel, read_exr_reference};
    let (a, b) = (read_exr_reference(&integer), read_exr_reference(&float));
    for c in ["R", "G", "B"] {
        assert!(
            channel(&a, c) == channel(&b, c),
            "{c} differs with a u32 depth"
        );
    }
    assert!(
        channel(&a, "R") != noise(n, 50, 0.0, 1.0),
        "nothing was blurred"
    );
    let ids = read_u32(&integer, "id");
    assert!(ids
        .iter()
        .enumerate()
        .all(|(i, &v)| v == IDS[i % IDS.len()]));
    // --half makes the float channels half; the IDs stay u32, every bit.
    let half = dof(&u32_input, "half_out.exr", &["--half"]);
    let ids = read_u32(&half, "id");
    assert!(ids
        .iter()
        .enumerate()
        .all(|(i, &v)| v == IDS[i % IDS.len()]));
}

/// A square (x 10..16, y 8..16, depth 2, ID 3 000 000 001, over 2²⁴) moving 12 px a frame
/// to the right over a still background (depth 10, ID 7), as a colour file holding `Z`,
/// `velocity.X/Y`, `N.X` (data by name) and `id` (u32) beside the beauty, with the passes.
fn moving_square(dir: &Path) {
    let n = W * H;
    let inside = |i: usize| (10..16).contains(&(i % W)) && (8..16).contains(&(i / W));
    let plane = |fg: f32, bg: f32| -> Vec<f32> {
        (0..n).map(|i| if inside(i) { fg } else { bg }).collect()
    };
    let data =
        |name: &str, plane: Vec<f32>| AnyChannel::new(Text::from(name), FlatSamples::F32(plane));
    let list = vec![
        data("R", noise(n, 60, 0.0, 1.0)),
        data("G", plane(0.9, 0.1)),
        data("B", plane(0.2, 0.6)),
        data("Z", plane(2.0, 10.0)),
        data("velocity.X", plane(12.0, 0.0)),
        data("velocity.Y", vec![0.0; n]),
        data("N.X", noise(n, 61, -1.0, 1.0)),
        AnyChannel::new(
            Text::from("id"),
            FlatSamples::U32(
                (0..n)
                    .map(|i| if inside(i) { 3_000_000_001 } else { 7 })
                    .collect(),
            ),
        ),
    ];
    let layer = Layer::new(
        (W, H),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    Image::from_layer(layer)
        .write()
        .to_file(dir.join("color.exr"))
        .unwrap();
    write_exr(&dir.join("depth.exr"), W, H, vec![("Z", plane(2.0, 10.0))]);
    write_exr(
        &dir.join("velocity.exr"),
        W,
        H,
        vec![("X", plane(12.0, 0.0)), ("Y", vec![0.0; n])],
    );
    let y: Vec<f32> = (0..n).map(|i| (i / W) as f32 + 0.5).collect();
    for (role, step) in [("prev", -12.0), ("next", 12.0)] {
        let x = (0..n)
            .map(|i| (i % W) as f32 + 0.5 + if inside(i) { step } else { 0.0 })
            .collect();
        write_exr(
            &dir.join(format!("{role}.exr")),
            W,
            H,
            vec![("X", x), ("Y", y.clone())],
        );
    }
}

/// A preset's `[layers]` may carry data with the motion (`"motion"`): after a motion blur,
/// each pixel a nearer surface's streak covers takes that surface's depth, vectors and ID
/// (an ID over 2²⁴ exactly), and the rest keep theirs; a data layer not named (`N`) comes back
/// bit for bit, and depth of field, which moves nothing, leaves them all as they were.
#[test]
fn a_preset_carries_depth_vectors_and_ids_with_the_motion() {
    use crate::support::{channel, read_exr_reference};
    let dir = tempfile::tempdir().unwrap();
    moving_square(dir.path());
    let preset = dir.path().join("carry.toml");
    std::fs::write(
        &preset,
        "[layers]\nZ = \"motion\"\nvelocity = \"motion\"\nid = \"motion\"\n",
    )
    .unwrap();
    let before = read_exr_reference(&dir.path().join("color.exr"));
    // The square's streak under the default shutter (0.5, centred): ±3 px about it, so the
    // pixels x 7..=18 of its rows.
    // Stretch's rear curtain exposes [−0.5, 0]: 6 px behind it alone, x 4..=15.
    let runs = [
        ("reconstruct", "centre", 7..=18),
        ("scatter", "centre", 7..=18),
        ("stretch", "centre", 7..=18),
        ("stretch", "rear", 4..=15),
    ];
    for (algorithm, anchor, columns) in runs {
        let streaked = |i: usize| columns.contains(&(i % W)) && (8..16).contains(&(i / W));
        let out = format!("{algorithm}-{anchor}.exr");
        let mut args = vec![
            "--algorithm",
            algorithm,
            "--preset",
            preset.to_str().unwrap(),
        ];
        if algorithm == "stretch" {
            args.extend(["--anchor", anchor]);
        }
        let algorithm = format!("{algorithm} {anchor}");
        blur(dir.path(), &out, &args);
        let path = dir.path().join(&out);
        let after = read_exr_reference(&path);
        let (z, vx) = (channel(&after, "Z"), channel(&after, "velocity.X"));
        let ids = read_u32(&path, "id");
        for i in 0..W * H {
            let (want_z, want_v, want_id) = if streaked(i) {
                (2.0, 12.0, 3_000_000_001)
            } else {
                (10.0, 0.0, 7)
            };
            let at = (i % W, i / W);
            assert_eq!(z[i], want_z, "{algorithm}: Z at {at:?}");
            assert_eq!(vx[i], want_v, "{algorithm}: velocity.X at {at:?}");
            assert_eq!(ids[i], want_id, "{algorithm}: id at {at:?}");
        }
        assert_eq!(
            channel(&after, "N.X"),
            channel(&before, "N.X"),
            "{algorithm}"
        );
        assert_ne!(channel(&after, "R"), channel(&before, "R"), "{algorithm}");
    }
    blur(
        dir.path(),
        "dof.exr",
        &[&["dof", "--preset", &s(&preset)][..], &LENS[..]].concat(),
    );
    let after = read_exr_reference(&dir.path().join("dof.exr"));
    for name in ["Z", "velocity.X", "N.X"] {
        assert_eq!(channel(&after, name), channel(&before, name), "dof: {name}");
    }
    // `shutter info --preset` names the class.
    let o = shutter(&[
        "info",
        &s(&dir.path().join("color.exr")),
        "--json",
        "--preset",
        &s(&preset),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let classes: Vec<(String, String)> = doc["files"][0]["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (
                c["name"].as_str().unwrap().into(),
                c["class"].as_str().unwrap().into(),
            )
        })
        .collect();
    for (name, class) in [
        ("Z", "motion"),
        ("velocity.X", "motion"),
        ("id", "motion"),
        ("N.X", "data"),
    ] {
        assert!(
            classes.contains(&(name.to_string(), class.to_string())),
            "{name}: {classes:?}"
        );
    }
}

#[test]
fn parts_of_other_data_windows_come_out_data_as_it_was_and_light_on_the_beautys_window() {
    // A Nuke auto-bbox light layer (its own smaller window) and a depth part rendered with
    // overscan, beside a full-frame beauty: the depth part comes out as it went in, at its
    // own window; the light layer is placed on the beauty's window and blurred with the
    // beauty's weights. The light layer is the beauty inside its box and the beauty is black
    // outside it, so once placed it is the beauty, and must blur to the blurred beauty.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_passes(d);
    let (bx, by, bw, bh) = (8, 6, 16, 12);
    let inside = |i: usize| {
        let (x, y) = (i % W, i / W);
        (bx..bx + bw).contains(&x) && (by..by + bh).contains(&y)
    };
    let beauty: Vec<Vec<f32>> = (0..3)
        .map(|c| {
            let noise = noise(W * H, 80 + c, 0.0, 1.0);
            (0..W * H)
                .map(|i| if inside(i) { noise[i] } else { 0.0 })
                .collect()
        })
        .collect();
    let boxed: Vec<Vec<f32>> = beauty
        .iter()
        .map(|p| (0..W * H).filter(|&i| inside(i)).map(|i| p[i]).collect())
        .collect();
    let (ow, oh) = (W + 8, H + 8);
    let depth: Vec<f32> = (0..ow * oh).map(|i| 1000.0 + i as f32).collect();
    let part = |name: &str, (x, y): (i32, i32), size, channels: Vec<AnyChannel<FlatSamples>>| {
        let mut attributes = LayerAttributes::named(name);
        attributes.layer_position = Vec2(x, y);
        Layer::new(
            size,
            attributes,
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(channels.into()),
        )
    };
    let rgb = |planes: &[Vec<f32>]| {
        ["R", "G", "B"]
            .into_iter()
            .zip(planes)
            .map(|(c, p)| AnyChannel::new(c, FlatSamples::F32(p.clone())))
            .collect::<Vec<_>>()
    };
    let image = Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions((W, H))))
        .with_layer(part("rgba", (0, 0), (W, H), rgb(&beauty)))
        .with_layer(part(
            "diffuse",
            (bx as i32, by as i32),
            (bw, bh),
            rgb(&boxed),
        ))
        .with_layer(part(
            "depth",
            (-4, -4),
            (ow, oh),
            vec![AnyChannel::new("Z", FlatSamples::F32(depth.clone()))],
        ));
    image.write().to_file(d.join("color.exr")).unwrap();
    let printed = blur_with(d, "out.exr", &["--json"], &[]);
    let report: serde_json::Value = serde_json::from_slice(&printed).unwrap();
    let warnings = report["warnings"].to_string();
    assert!(!warnings.contains("not written"), "{warnings}");

    let layers = crate::support::read_exr_layers(&d.join("out.exr"));
    let find = |name: &str| crate::support::part_named(&layers, name);
    let channel = |name: &str, c: &str| -> Vec<f32> {
        let layer = find(name);
        let found = (layer.channel_data.list.iter())
            .find(|ch| ch.name.to_string() == c)
            .unwrap_or_else(|| panic!("no {name}.{c}"));
        found.sample_data.values_as_f32().collect()
    };
    // The depth part: its window and its values, as they came.
    let depth_part = find("depth");
    assert_eq!(depth_part.attributes.layer_position, Vec2(-4, -4));
    assert_eq!(depth_part.size, Vec2(ow, oh));
    assert_eq!(channel("depth", "Z"), depth);
    // The light layer: on the beauty's window, blurred as the beauty.
    let diffuse = find("diffuse");
    assert_eq!(diffuse.attributes.layer_position, Vec2(0, 0));
    assert_eq!(diffuse.size, Vec2(W, H));
    for c in ["R", "G", "B"] {
        let (got, want) = (channel("diffuse", c), channel("rgba", c));
        assert!(
            got.iter().zip(&want).all(|(a, b)| (a - b).abs() <= 1e-6),
            "diffuse.{c} is not the blurred beauty"
        );
        // And the blur moved it: light reached outside its box.
        assert!(
            (0..W * H).any(|i| !inside(i) && got[i] > 0.01),
            "{c} did not blur"
        );
    }
    // OpenImageIO, which nobody here wrote, reads the three parts.
    if let Some(info) = oiiotool_info(&d.join("out.exr")) {
        assert!(info.contains("3 subimages"), "{info}");
    }
    // A rerun finds the frame whole (its depth part larger than the beauty).
    let printed = blur_with(d, "out.exr", &["--json", "--skip-existing"], &[]);
    let report: serde_json::Value = serde_json::from_slice(&printed).unwrap();
    assert_eq!(report["frames_skipped"], 1, "{report}");
}

/// Each channel's pLinear flag comes back as the input stored it (here off, OpenEXR's
/// default). Rebuilt from the channel's name (the exr crate's guess: on for all but R, G, B,
/// L, Y, X and Z), it turned on for `A` and `velocity.X`, and a B44 output encoded them
/// through B44's perceptual curve: every negative vector came back 0.
#[test]
fn b44_keeps_each_channels_plinear_flag_and_negative_vectors() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let half = |v: Vec<f32>| FlatSamples::F16(v.into_iter().map(f16::from_f32).collect());
    let list = vec![
        AnyChannel::new("R", half(noise(n, 62, 0.0, 1.0))),
        AnyChannel::new("G", half(noise(n, 63, 0.0, 1.0))),
        AnyChannel::new("B", half(noise(n, 64, 0.0, 1.0))),
        AnyChannel::new("A", half(vec![1.0; n])),
        AnyChannel::new("Z", half(vec![5.0; n])),
        AnyChannel::new("velocity.X", half(noise(n, 61, -20.0, 20.0))),
        AnyChannel::new("velocity.Y", half(vec![0.0; n])),
    ]
    .into_iter()
    .map(|c| AnyChannel {
        quantize_linearly: false,
        ..c
    })
    .collect();
    let layer = Layer::new(
        (W, H),
        LayerAttributes::default(),
        Encoding {
            compression: Compression::B44,
            ..Encoding::FAST_LOSSLESS
        },
        AnyChannels::sort(list),
    );
    let input = dir.path().join("b44.exr");
    Image::from_layer(layer).write().to_file(&input).unwrap();
    let output = dir.path().join("out.exr");
    let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&output)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = MetaData::read_from_file(&output, false).unwrap();
    for channel in &meta.headers[0].channels.list {
        assert!(
            !channel.quantize_linearly,
            "{} written with pLinear on",
            channel.name
        );
    }
    // B44 is lossy: the vectors as the input file holds them.
    let (read, stored) = (
        crate::support::read_exr_reference(&output),
        crate::support::read_exr_reference(&input),
    );
    let written = crate::support::channel(&read, "velocity.X");
    let expected = crate::support::channel(&stored, "velocity.X");
    assert!(
        expected.iter().any(|&v| v < -1.0),
        "the input has negative vectors"
    );
    crate::support::assert_same_bits(written, expected, "velocity.X through B44");
}

/// A half plate with infinite pixels (read as ±1e30, the numeric policy's clamp) comes back
/// finite from every algorithm and from depth of field: colour written as half saturates at
/// half's largest value (65504) where f16 would overflow to ±Inf around the hot pixel.
#[test]
fn a_half_plate_with_infinite_pixels_comes_back_finite() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64usize, 48usize);
    let n = w * h;
    let half = |v: Vec<f32>| FlatSamples::F16(v.into_iter().map(f16::from_f32).collect());
    let mut red = vec![0.2f32; n];
    red[22 * w + 30] = f32::INFINITY;
    red[5 * w + 5] = f32::NEG_INFINITY;
    let square = |inside: f32, outside: f32| -> Vec<f32> {
        (0..n)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (20..36).contains(&x) && (16..32).contains(&y) {
                    inside
                } else {
                    outside
                }
            })
            .collect()
    };
    let list = vec![
        AnyChannel::new("R", half(red)),
        AnyChannel::new("G", half(vec![0.2; n])),
        AnyChannel::new("B", half(vec![0.2; n])),
        AnyChannel::new("A", half(vec![1.0; n])),
        AnyChannel::new("Z", half(square(2.0, 10.0))),
        AnyChannel::new("velocity.X", half(square(6.0, 0.0))),
        AnyChannel::new("velocity.Y", half(vec![0.0; n])),
    ];
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    let input = dir.path().join("inf.exr");
    Image::from_layer(layer).write().to_file(&input).unwrap();
    let lens = [
        "--focal-length",
        "50",
        "--f-stop",
        "1.4",
        "--focus-distance",
        "2",
    ];
    let runs: [Vec<&str>; 5] = [
        vec!["blur", "--algorithm", "reconstruct"],
        vec!["blur", "--algorithm", "scatter"],
        vec!["blur", "--algorithm", "stretch"],
        [&["dof"][..], &lens].concat(),
        [&["dof", "--method", "blend"][..], &lens].concat(),
    ];
    for (k, run) in runs.iter().enumerate() {
        let output = dir.path().join(format!("out{k}.exr"));
        let mut args = run.clone();
        let (input, output) = (s(&input), s(&output));
        args.extend(["--color", &input, "-o", &output]);
        let o = shutter(&args);
        assert!(o.status.success(), "{run:?}: {}", stderr(&o));
        for (name, plane) in crate::support::read_exr_reference(Path::new(&output)) {
            if ["R", "G", "B", "A"].contains(&name.as_str()) {
                let bad = plane.iter().filter(|v| !v.is_finite()).count();
                assert_eq!(bad, 0, "{run:?}: {bad} values of {name} not finite");
            }
        }
    }
}

/// A highlight past half's range through DWA: DWAA and DWAB compress colour lossily on a
/// log-like curve, and a block at half's largest value decoded past it to ±Inf (73 infinite
/// pixels of R from a finite 2·10⁵ highlight, read so by oiiotool too). The output is finite
/// to both readers, and the highlight still the frame's brightest part; an infinite pixel
/// (read as 10³⁰) does not stop the write; a lower-case `spec.r`, which DWA stores exactly,
/// keeps its 2·10⁵.
#[test]
fn a_highlight_past_half_s_range_through_dwa_comes_back_finite() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64usize, 64usize);
    let sun: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 - 32.0, (i / w) as f32 - 32.0);
            0.2 + 2e5 * (-(x * x + y * y) / 72.0).exp()
        })
        .collect();
    let mut red = sun.clone();
    red[3 * w + 3] = f32::INFINITY;
    let list = vec![
        AnyChannel::new("R", FlatSamples::F32(red)),
        AnyChannel::new("spec.r", FlatSamples::F32(sun.clone())),
        AnyChannel::new("G", FlatSamples::F32(sun.iter().map(|v| v * 0.9).collect())),
        AnyChannel::new("B", FlatSamples::F32(sun.iter().map(|v| v * 0.7).collect())),
        AnyChannel::new("A", FlatSamples::F32(vec![1.0; w * h])),
    ];
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    let input = dir.path().join("sun.exr");
    Image::from_layer(layer).write().to_file(&input).unwrap();
    for method in ["dwaa", "dwab"] {
        let output = dir.path().join(format!("{method}.exr"));
        let o = shutter(&[
            "blur",
            "--color",
            &s(&input),
            "--compression",
            method,
            "-o",
            &s(&output),
        ]);
        assert!(o.status.success(), "{method}: {}", stderr(&o));
        // The highlight comes back dimmer, and the run says so, naming the frame.
        let err = stderr(&o);
        assert!(
            err.contains(&format!("{method}.exr: "))
                && err.contains("DWA chunk")
                && err.contains("capped at"),
            "{method}: {err}"
        );
        for (name, plane) in crate::support::read_exr_reference(&output) {
            let bad = plane.iter().filter(|v| !v.is_finite()).count();
            assert_eq!(bad, 0, "{method}: {bad} values of {name} not finite");
            let brightest = plane.iter().copied().fold(0.0f32, f32::max);
            if name == "spec.r" {
                let peak = sun.iter().copied().fold(0.0f32, f32::max);
                assert_eq!(brightest, peak, "{method}: spec.r, stored exactly");
            } else if name != "A" {
                assert!(brightest > 1e4, "{method}: {name}'s highlight {brightest}");
            }
        }
        if let Some(out) = crate::support::run_tool("oiiotool", &["--stats", &s(&output)]) {
            let text = String::from_utf8_lossy(&out.stdout).to_string();
            let counts = text
                .lines()
                .find(|l| l.contains("InfCount"))
                .unwrap_or_else(|| panic!("{method}: no InfCount in oiiotool's stats: {text}"));
            assert!(
                counts
                    .split(':')
                    .nth(1)
                    .unwrap()
                    .split_whitespace()
                    .all(|c| c == "0"),
                "{method}: oiiotool reads infinities: {counts}"
            );
        }
    }
    // A bright frame DWA holds as it is (its brightest 2000, decoded again as it is written)
    // is written without a word.
    let list = vec![
        AnyChannel::new(
            "R",
            FlatSamples::F32(sun.iter().map(|v| v / 100.0).collect()),
        ),
        AnyChannel::new(
            "G",
            FlatSamples::F32(sun.iter().map(|v| v / 110.0).collect()),
        ),
        AnyChannel::new(
            "B",
            FlatSamples::F32(sun.iter().map(|v| v / 140.0).collect()),
        ),
    ];
    let layer = Layer::new(
        (w, h),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    let calm = dir.path().join("calm.exr");
    Image::from_layer(layer).write().to_file(&calm).unwrap();
    let output = dir.path().join("calm_dwaa.exr");
    let o = shutter(&[
        "blur",
        "--color",
        &s(&calm),
        "--compression",
        "dwaa",
        "-o",
        &s(&output),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("DWA chunk"), "{}", stderr(&o));
}

/// An attribute under a standard name but of another type (`isoSpeed` an int, `owner` an
/// int, `multiView` one string), as some writers leave them, comes back as it was, as from
/// `oiiotool`: the exr crate had refused to write it ("reserved and cannot be custom"), and
/// every run failed at its first write with exit 75, after the preflight said it would write.
#[test]
fn attributes_of_odd_types_under_standard_names_come_back() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let list = ["R", "G", "B"]
        .iter()
        .map(|c| AnyChannel::new(*c, FlatSamples::F32(noise(n, 70, 0.0, 1.0))))
        .collect();
    let odd = [
        ("isoSpeed", AttributeValue::I32(400)),
        ("owner", AttributeValue::I32(7)),
        ("multiView", AttributeValue::Text(Text::from("left"))),
    ];
    let mut attributes = LayerAttributes::default();
    for (name, value) in odd.clone() {
        attributes.other.insert(Text::from(name), value);
    }
    let layer = Layer::new(
        (W, H),
        attributes,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list),
    );
    let input = dir.path().join("odd.exr");
    Image::from_layer(layer)
        .write()
        .skip_compatibility_checks()
        .to_file(&input)
        .unwrap();
    let output = dir.path().join("out.exr");
    let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&output)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = MetaData::read_from_file(&output, false).unwrap();
    let header = &meta.headers[0];
    for (name, value) in odd {
        let found = header
            .own_attributes
            .other
            .get(&Text::from(name))
            .or(header.shared_attributes.other.get(&Text::from(name)));
        assert_eq!(found, Some(&value), "{name}");
    }
}

/// Depth and vectors in a part of the colour file rendered with overscan (a data part whose
/// window reaches 4 px past the beauty's on every side) are placed by that part's window, as
/// passes in files of their own are: the frame blurs as with the same passes cut to the
/// beauty's window in a file beside it. They were refused as a "corrupt file" whose parts
/// holding the wanted channels differ in size.
#[test]
fn passes_in_an_overscan_part_of_the_colour_file_are_placed_by_its_window() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (ow, oh) = (W + 8, H + 8);
    // The passes at pixel (x, y) of the file's coordinates: a block moving 6 px right, near.
    let moving = |x: i64, y: i64| (10..26).contains(&x) && (6..18).contains(&y);
    let at = |w: usize, h: usize, origin: i64, f: &dyn Fn(i64, i64) -> f32| -> Vec<f32> {
        (0..w * h)
            .map(|i| f((i % w) as i64 + origin, (i / w) as i64 + origin))
            .collect()
    };
    let depth = |x, y| if moving(x, y) { 2.0 } else { 10.0 };
    let vx = |x, y| if moving(x, y) { 6.0 } else { 0.0 };
    let still = |_, _| 0.0;
    let beauty: Vec<Vec<f32>> = (0..3).map(|c| noise(W * H, 90 + c, 0.0, 1.0)).collect();
    let channels = |list: Vec<(&str, Vec<f32>)>| -> Vec<AnyChannel<FlatSamples>> {
        list.into_iter()
            .map(|(name, plane)| AnyChannel::new(name, FlatSamples::F32(plane)))
            .collect()
    };
    let part = |name: &str, origin: i32, size: (usize, usize), list| {
        let mut attributes = LayerAttributes::named(name);
        attributes.layer_position = Vec2(origin, origin);
        Layer::new(
            size,
            attributes,
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(channels(list).into()),
        )
    };
    let rgb = || {
        vec![
            ("R", beauty[0].clone()),
            ("G", beauty[1].clone()),
            ("B", beauty[2].clone()),
        ]
    };
    let passes = |w, h, origin| {
        vec![
            ("Z", at(w, h, origin, &depth)),
            ("velocity.X", at(w, h, origin, &vx)),
            ("velocity.Y", at(w, h, origin, &still)),
        ]
    };
    Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions((W, H))))
        .with_layer(part("rgba", 0, (W, H), rgb()))
        .with_layer(part("data", -4, (ow, oh), passes(ow, oh, -4)))
        .write()
        .to_file(d.join("parts.exr"))
        .unwrap();
    crate::support::write_exr(&d.join("beauty.exr"), W, H, rgb());
    crate::support::write_exr(&d.join("passes.exr"), W, H, passes(W, H, 0));
    let run = |args: &[&str], out: &str| {
        let out = s(&d.join(out));
        let mut all = vec!["blur", "--algorithm", "reconstruct", "-o", &out];
        all.extend(args);
        let o = shutter(&all);
        assert!(o.status.success(), "{args:?}: {}", stderr(&o));
        let read = crate::support::read_exr_reference(Path::new(&out));
        ["R", "G", "B"].map(|c| crate::support::channel(&read, c).to_vec())
    };
    let (parts, beside) = (s(&d.join("parts.exr")), s(&d.join("beauty.exr")));
    let passes = s(&d.join("passes.exr"));
    let from_parts = run(&["--color", &parts], "a.exr");
    let from_files = run(
        &[
            "--color",
            &beside,
            "--depth",
            &passes,
            "--velocity",
            &passes,
        ],
        "b.exr",
    );
    assert_ne!(from_files[0], beauty[0], "the block blurs");
    for (c, (a, b)) in from_parts.iter().zip(&from_files).enumerate() {
        crate::support::assert_same_bits(a, b, &format!("channel {c}"));
    }
}

/// `info` shows an EXR's UTF-8 names and texts as the writer wrote them (`lumière.R`, owner
/// "Zoë 日本"), in text and in JSON; it showed each byte as a char (`lumiÃ¨re.R`), and a tool
/// reading `--json` got channel names the file does not have. The output still carries the
/// bytes as they came.
#[test]
fn info_shows_utf8_names_and_texts_as_written() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let mut list: Vec<AnyChannel<FlatSamples>> = ["R", "G", "B"]
        .iter()
        .map(|c| AnyChannel::new(*c, FlatSamples::F32(noise(n, 95, 0.0, 1.0))))
        .collect();
    let utf8 = |t: &str| Text::from_slice_unchecked(t.as_bytes());
    let name = utf8("lumière.R");
    list.push(AnyChannel::new(name, FlatSamples::F32(vec![0.5; n])));
    let attributes = LayerAttributes {
        owner: Some(utf8("Zoë 日本")),
        ..LayerAttributes::default()
    };
    let path = dir.path().join("utf8.exr");
    Image::from_layer(Layer::new(
        (W, H),
        attributes,
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list.into()),
    ))
    .write()
    .to_file(&path)
    .unwrap();
    let o = shutter(&["info", &s(&path)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = crate::support::stdout(&o);
    assert!(text.contains("lumière.R"), "{text}");
    assert!(text.contains("Zoë 日本"), "{text}");
    let o = shutter(&["info", &s(&path), "--json"]);
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let all = json.to_string();
    assert!(all.contains("\"lumière.R\""), "{all}");
    assert!(all.contains("Zoë 日本"), "{all}");
}

/// A luminance file (`Y` alone, read as grey: R = G = B = Y) comes back a luminance file: its
/// blurred `Y` under its name and no R, G, B it did not have; it came back as R, G and B with
/// no `Y`, and nothing said so.
#[test]
fn a_luminance_file_comes_back_with_its_y() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let moving = |i: usize| (8..20).contains(&(i % W)) && (6..16).contains(&(i / W));
    let plane = |f: &dyn Fn(usize) -> f32| -> Vec<f32> { (0..n).map(f).collect() };
    let y = noise(n, 97, 0.0, 1.0);
    let input = dir.path().join("y.exr");
    crate::support::write_exr(
        &input,
        W,
        H,
        vec![
            ("Y", y.clone()),
            ("Z", plane(&|i| if moving(i) { 2.0 } else { 10.0 })),
            ("velocity.X", plane(&|i| if moving(i) { 6.0 } else { 0.0 })),
            ("velocity.Y", vec![0.0; n]),
        ],
    );
    let output = dir.path().join("out.exr");
    let o = shutter(&[
        "blur",
        "--algorithm",
        "reconstruct",
        "--color",
        &s(&input),
        "-o",
        &s(&output),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let read = crate::support::read_exr_reference(&output);
    let mut names: Vec<&str> = read.iter().map(|(name, _)| name.as_str()).collect();
    names.sort();
    assert_eq!(names, ["Y", "Z", "velocity.X", "velocity.Y"]);
    let blurred = crate::support::channel(&read, "Y");
    assert!(blurred.iter().all(|v| v.is_finite()));
    assert_ne!(blurred, &y[..], "the square blurs");
}

/// A frame whose display window declares far more pixels than a picture may hold (200000²
/// around an 8×8 data window) is refused by the preflight when the output is a picture (exit
/// 1, `--dry-run` too, nothing written): it passed the dry run and failed at write time with
/// exit 75, which a farm retries for nothing.
#[test]
fn a_picture_larger_than_the_limit_is_refused_before_anything_is_written() {
    use shutter::frame::{Window, Windows};
    use shutter::io::exr::{write_channels, ExrOptions};
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("huge_display.exr");
    let windows = Windows {
        data_origin: (0, 0),
        display: Window {
            x: 0,
            y: 0,
            width: 200_000,
            height: 200_000,
        },
    };
    let channels = ["R", "G", "B"]
        .iter()
        .map(|c| (c.to_string(), vec![0.5f32; 64]))
        .collect();
    let file = std::io::BufWriter::new(std::fs::File::create(&path).unwrap());
    write_channels(file, 8, 8, windows, channels, ExrOptions::default()).unwrap();
    let (input, out) = (s(&path), s(&dir.path().join("out/o.png")));
    for extra in [&["--dry-run"][..], &[]] {
        let mut args = vec!["blur", "--color", input.as_str(), "-o", out.as_str()];
        args.extend(extra);
        let o = shutter(&args);
        assert_eq!(o.status.code(), Some(1), "{extra:?}: {}", stderr(&o));
        assert!(stderr(&o).contains("display window"), "{}", stderr(&o));
    }
    assert!(
        !dir.path().join("out").exists(),
        "the output folder was made"
    );
}

/// `info` names a tiled part's RANDOM_Y line order `random`, on the plate and on the output
/// that keeps it, in text and JSON (QA: it said `unspecified`, the exr crate's name for it,
/// which reads as "not given").
#[test]
fn info_names_a_random_line_order_random() {
    let dir = plate_frame(Blocks::Tiles(Vec2(16, 8)), LineOrder::Unspecified);
    blur(dir.path(), "out.exr", &[]);
    for file in ["color.exr", "out.exr"] {
        let path = s(&dir.path().join(file));
        let o = shutter(&["info", &path]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = crate::support::stdout(&o);
        let line = text
            .lines()
            .find(|l| l.trim_start().starts_with("lineOrder"))
            .unwrap_or_else(|| panic!("{file}: no lineOrder in:\n{text}"));
        assert_eq!(
            line.split_whitespace().collect::<Vec<_>>(),
            ["lineOrder", "lineOrder", "random"],
            "{file}"
        );
        let o = shutter(&["info", &path, "--json"]);
        let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let attributes = doc["files"][0]["attributes"][0]["attributes"]
            .as_array()
            .unwrap();
        let order = attributes
            .iter()
            .find(|a| a["name"] == "lineOrder")
            .unwrap();
        assert_eq!(order["value"], "random", "{file}");
    }
}

/// Each part's attributes as the file stores them, in file order: (name, type, value bytes).
/// Read from the bytes (OpenEXR's file layout), not through the exr crate, which keeps one
/// value per name and files the layout attributes away from the others.
fn raw_headers(bytes: &[u8]) -> Vec<Vec<(String, String, Vec<u8>)>> {
    let text = |at: usize| {
        let end = at + bytes[at..].iter().position(|&b| b == 0).unwrap();
        (
            String::from_utf8_lossy(&bytes[at..end]).into_owned(),
            end + 1,
        )
    };
    // The version field's bit 12: several parts, each header ended by a null byte and the
    // list of headers by another.
    let multi_part = bytes[5] & 0x10 != 0;
    let (mut at, mut parts) = (8, Vec::new());
    loop {
        let mut part = Vec::new();
        while bytes[at] != 0 {
            let (name, next) = text(at);
            let (kind, next) = text(next);
            let size = i32::from_le_bytes(bytes[next..next + 4].try_into().unwrap()) as usize;
            part.push((name, kind, bytes[next + 4..next + 4 + size].to_vec()));
            at = next + 4 + size;
        }
        at += 1;
        parts.push(part);
        if !multi_part || bytes[at] == 0 {
            return parts;
        }
    }
}

/// The attributes that say how a part is laid out in its file are the output's own, never
/// the input's: a custom attribute under one of their names, as OpenImageIO writes them
/// (`openexr:chunkCount`, a stale count from the file oiiotool read: QA found its 4 carried
/// into a part of 6 chunks, which `iinfo -v` then reports) or under the bare name with
/// another type than the standard's, is not carried; each standard one is written once, with
/// the output's value. A multi-part frame of a scan-line PIZ part and a tiled ZIP part.
#[test]
fn the_layout_attributes_of_every_part_are_the_outputs_own() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let stale = [
        ("openexr:chunkCount", AttributeValue::I32(99)),
        ("openexr:lineOrder", AttributeValue::I32(2)),
        ("chunkCount", AttributeValue::F32(99.0)),
        (
            "dataWindow",
            AttributeValue::Text(Text::from("(0, 0) - (1, 1)")),
        ),
        ("tiles", AttributeValue::Text(Text::from("64x64"))),
        ("type", AttributeValue::I32(3)),
    ];
    let part = |name: &str, compression, blocks, seed: u32| {
        let mut attributes = LayerAttributes::named(name);
        for (key, value) in stale.clone() {
            attributes.other.insert(Text::from(key), value);
        }
        attributes
            .other
            .insert(Text::from("pipeline/shot"), AttributeValue::I32(20));
        let channels = ["R", "G", "B"]
            .iter()
            .enumerate()
            .map(|(c, name)| {
                let plane = noise(n, seed + c as u32, 0.0, 1.0);
                AnyChannel::new(*name, FlatSamples::F32(plane))
            })
            .collect::<Vec<_>>();
        Layer::new(
            (W, H),
            attributes,
            Encoding {
                compression,
                blocks,
                line_order: LineOrder::Increasing,
            },
            AnyChannels::sort(channels.into()),
        )
    };
    let image = Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions((W, H))))
        .with_layer(part("rgba", Compression::PIZ, Blocks::ScanLines, 60))
        .with_layer(part(
            "diffuse",
            Compression::ZIP16,
            Blocks::Tiles(Vec2(16, 8)),
            63,
        ));
    image
        .write()
        .skip_compatibility_checks()
        .to_file(dir.path().join("color.exr"))
        .unwrap();
    write_passes(dir.path());
    blur(dir.path(), "out.exr", &[]);
    let out = dir.path().join("out.exr");
    let headers = raw_headers(&std::fs::read(&out).unwrap());
    assert_eq!(headers.len(), 2);
    // Chunks: PIZ holds 32 scan lines a chunk (24 lines, one chunk); 40×24 in 16×8 tiles is
    // 3 × 3 tiles.
    let expected = [
        ("rgba", 1, "scanlineimage", None),
        ("diffuse", 9, "tiledimage", Some((16, 8))),
    ];
    for (part, (name, chunks, kind, tiles)) in headers.iter().zip(expected) {
        let named = |key: &str| -> Vec<&(String, String, Vec<u8>)> {
            part.iter().filter(|(n, _, _)| n == key).collect()
        };
        // Nothing under OpenImageIO's names for the layout.
        for (key, _, _) in part {
            assert!(!key.starts_with("openexr:"), "{name}: {key} was carried");
        }
        assert_eq!(
            named("pipeline/shot").len(),
            1,
            "{name}: custom attributes stay"
        );
        let one = |key: &str, kind: &str| -> Vec<u8> {
            let found = named(key);
            assert_eq!(found.len(), 1, "{name}: {key} {found:?}");
            assert_eq!(found[0].1, kind, "{name}: {key}'s type");
            found[0].2.clone()
        };
        let int = |b: Vec<u8>| i32::from_le_bytes(b[..4].try_into().unwrap());
        assert_eq!(int(one("chunkCount", "int")), chunks, "{name}: chunkCount");
        assert_eq!(one("type", "string"), kind.as_bytes(), "{name}: type");
        assert_eq!(one("name", "string"), name.as_bytes(), "{name}: name");
        let window = one("dataWindow", "box2i");
        let corners: Vec<i32> = window.chunks(4).map(|c| int(c.to_vec())).collect();
        assert_eq!(corners, [0, 0, W as i32 - 1, H as i32 - 1], "{name}");
        one("displayWindow", "box2i");
        one("lineOrder", "lineOrder");
        one("compression", "compression");
        one("channels", "chlist");
        match tiles {
            Some((w, h)) => {
                let t = one("tiles", "tiledesc");
                assert_eq!((int(t[..4].to_vec()), int(t[4..8].to_vec())), (w, h));
            }
            None => assert!(named("tiles").is_empty(), "{name}: tiles"),
        }
    }
    // Our reader reads it, checking the chunk counts (pedantic), and so does OpenImageIO,
    // whose `openexr:chunkCount` is then the part's own.
    let meta = MetaData::read_from_file(&out, true).unwrap();
    assert!(matches!(meta.headers[1].blocks, BlockDescription::Tiles(_)));
    if let Some(info) = oiiotool_info(&out) {
        let counts: Vec<&str> = info
            .lines()
            .filter_map(|l| l.trim().strip_prefix("openexr:chunkCount: "))
            .collect();
        assert!(counts.iter().all(|c| *c != "99"), "{info}");
    }
}

/// Attributes the exr crate reads but would write otherwise than it read them come back as
/// they went in, readable by every client: a film scan's key code (the crate writes six of
/// its seven numbers, and every reader then refused the file, ours included), a time code of
/// frame 38 (48 or 60 fps: the crate's writer refuses frames over 29; OpenEXR reads and
/// writes it) and an empty string vector (OpenEXR reads `[]`; the crate refuses to write it).
/// The input is written with them as raw custom values, as OpenEXR stores them.
#[test]
fn a_key_code_a_time_code_of_frame_38_and_an_empty_string_vector_come_back() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let raw = |kind: &str, bytes: Vec<u8>| AttributeValue::Custom {
        kind: Text::from(kind),
        bytes: bytes.into(),
    };
    let le = |v: &[u32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    // 12:34:56:38 in TV60 packing, each field binary-coded decimal; no user data.
    let time = 0x38 | 0x56 << 8 | 0x34 << 16 | 0x12 << 24;
    let mut layer_attributes = LayerAttributes::default();
    for (name, value) in [
        // Under stand-in names of the same length (the crate refuses to write a standard
        // name as a custom value), renamed in the file's bytes below.
        ("keyCodX", raw("keycode", le(&[1, 2, 3, 4, 5, 4, 64]))),
        ("timeCodX", raw("timecode", le(&[time, 0]))),
        ("pipeline/tags", raw("stringvector", Vec::new())),
    ] {
        layer_attributes.other.insert(Text::from(name), value);
    }
    let channel = |name: &str, seed: u32| {
        AnyChannel::new(Text::from(name), FlatSamples::F32(noise(n, seed, 0.0, 1.0)))
    };
    let image = Image {
        attributes: ImageAttributes::new(IntegerBounds::from_dimensions((W, H))),
        layer_data: Layer::new(
            (W, H),
            layer_attributes,
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(vec![channel("R", 1), channel("G", 2), channel("B", 3)].into()),
        ),
    };
    let color = dir.path().join("color.exr");
    image.write().to_file(&color).unwrap();
    let mut bytes = std::fs::read(&color).unwrap();
    for (from, to) in [
        (&b"keyCodX\0keycode\0"[..], &b"keyCode\0keycode\0"[..]),
        (b"timeCodX\0timecode\0", b"timeCode\0timecode\0"),
    ] {
        let at = bytes.windows(from.len()).position(|w| w == from).unwrap();
        bytes[at..at + to.len()].copy_from_slice(to);
    }
    std::fs::write(&color, bytes).unwrap();
    write_passes(dir.path());
    blur(dir.path(), "out.exr", &[]);
    let out = dir.path().join("out.exr");
    let meta = MetaData::read_from_file(&out, false).unwrap();
    let header = &meta.headers[0];
    let key = header.own_attributes.film_key_code.expect("the key code");
    assert_eq!(
        [
            key.film_manufacturer_code,
            key.film_type,
            key.film_roll_prefix,
            key.count,
            key.perforation_offset,
            key.perforations_per_frame,
            key.perforations_per_count
        ],
        [1, 2, 3, 4, 5, 4, 64]
    );
    let code = header.shared_attributes.time_code.expect("the time code");
    assert_eq!(
        (code.hours, code.minutes, code.seconds, code.frame),
        (12, 34, 56, 38)
    );
    assert_eq!(
        header
            .own_attributes
            .other
            .get(&Text::from("pipeline/tags")),
        Some(&AttributeValue::TextVector(Vec::new()))
    );
    if let Some(info) = oiiotool_info(&out) {
        for line in [
            "smpte:KeyCode: 1, 2, 3, 4, 5, 4, 64",
            "smpte:TimeCode: 12:34:56:38",
        ] {
            assert!(
                info.contains(line),
                "oiiotool does not show {line:?}:\n{info}"
            );
        }
    }
}

/// `--half` writes a data channel that half cannot hold as float, not as ±∞: Blender's depth
/// of 1e10 for empty pixels and a world position of −7e4 came back infinite (and `shutter
/// diff` then failed the frame on them); colour still goes half, and data within half's range
/// too.
#[test]
fn half_keeps_data_that_half_cannot_hold_as_float() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let mut z: Vec<f32> = noise(n, 5, 1.0, 9.0);
    z[3] = 1e10;
    write_exr(
        &dir.path().join("color.exr"),
        W,
        H,
        vec![
            ("R", noise(n, 1, 0.0, 1.0)),
            ("G", noise(n, 2, 0.0, 1.0)),
            ("B", noise(n, 3, 0.0, 1.0)),
            ("Z", z.clone()),
            ("P.X", vec![-7e4; n]),
            ("N.X", noise(n, 6, -1.0, 1.0)),
            // An object index past 2048 (Blender writes IndexOB as float): half would make
            // 3001 into 3000. Small indices fit half exactly and go half.
            ("IndexOB.X", (0..n).map(|i| (3000 + i % 3) as f32).collect()),
            ("IndexMA.X", (0..n).map(|i| (i % 7) as f32).collect()),
            // A Cryptomatte ID is a hash in a float's bits: half made 1.2e-20 into 0 (an
            // outside probe), and any other into another ID.
            ("CryptoObject00.R", vec![1.234_567_8e-20; n]),
            ("CryptoObject00.G", vec![0.5; n]),
        ],
    );
    write_passes(dir.path());
    blur(dir.path(), "out.exr", &["--half"]);
    let out = dir.path().join("out.exr");
    let meta = MetaData::read_from_file(&out, false).unwrap();
    let kind = |name: &str| {
        meta.headers
            .iter()
            .flat_map(|h| h.channels.list.iter())
            .find(|c| c.name.to_string() == name)
            .unwrap_or_else(|| panic!("{name}"))
            .sample_type
    };
    use exr::meta::attribute::SampleType;
    for (name, want) in [
        ("R", SampleType::F16),
        ("Z", SampleType::F32),
        ("P.X", SampleType::F32),
        ("N.X", SampleType::F16),
        ("IndexOB.X", SampleType::F32),
        ("IndexMA.X", SampleType::F16),
        ("CryptoObject00.R", SampleType::F32),
        ("CryptoObject00.G", SampleType::F32),
    ] {
        assert_eq!(kind(name), want, "{name}");
    }
    let read = crate::support::read_exr_reference(&out);
    let plane = |name: &str| &read.iter().find(|(n, _)| n == name).unwrap().1;
    assert_eq!(plane("Z")[3], 1e10);
    assert!(plane("P.X").iter().all(|&v| v == -7e4));
    assert_eq!(plane("IndexOB.X")[1], 3001.0);
    assert!(plane("CryptoObject00.R")
        .iter()
        .all(|&v| v == 1.234_567_8e-20));
}

/// Depth of field on a plate whose pixels are not square says that its bokeh is round in
/// pixels, so stretched once shown at the plate's aspect (an outside tester found it said
/// nothing); a motion blur, or square pixels, say nothing of it.
#[test]
fn depth_of_field_on_pixels_that_are_not_square_is_warned_of() {
    let dir = plate_frame(Blocks::ScanLines, LineOrder::Increasing);
    let lens = [&LENS_ARGS[..], &["--json"]].concat();
    let warned = |stdout: Vec<u8>| -> bool {
        let report: serde_json::Value = serde_json::from_slice(&stdout).unwrap();
        let warnings = report["warnings"].to_string();
        // One sentence, its lines joined by single spaces (a run of spaces was printed).
        assert!(!warnings.contains("  "), "{warnings}");
        warnings.contains("pixelAspectRatio")
    };
    let mut dof = vec!["dof"];
    dof.extend(&lens);
    assert!(warned(blur_with(dir.path(), "dof.exr", &dof, &[])));
    assert!(!warned(blur_with(dir.path(), "blur.exr", &["--json"], &[])));
    let n = W * H;
    let square = dir.path().join("square.exr");
    let grey = || noise(n, 9, 0.0, 1.0);
    write_exr(
        &square,
        W,
        H,
        vec![("R", grey()), ("G", grey()), ("B", grey())],
    );
    let (c, d, o) = (
        s(&square),
        s(&dir.path().join("depth.exr")),
        s(&dir.path().join("square.out.exr")),
    );
    let mut args = vec!["dof", "--color", &c, "--depth", &d, "-o", &o];
    args.extend(&lens);
    let run = shutter(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    assert!(!warned(run.stdout));
}

/// A renderer's frame of `W` x `H`: a bright box (columns `W/3` to `W/2`) at depth 2 before a
/// noisy wall at 10, moving `speed` px a frame to the right; `vectors` gives the box's
/// stored vector channels from that speed, `extra` more channels of data (normals, depth).
fn write_renderer_frame(
    path: &Path,
    vectors: &[(&str, f32, f32)],
    depth: (&str, f32),
    extra: &[&str],
) -> Vec<(String, Vec<f32>)> {
    let n = W * H;
    let boxed = |i: usize| (W / 3..W / 2).contains(&(i % W));
    let wall = noise(n, 7, 0.1, 0.4);
    let light = |k: usize| -> Vec<f32> {
        (0..n)
            .map(|i| {
                if boxed(i) {
                    1.0 - 0.2 * k as f32
                } else {
                    wall[i]
                }
            })
            .collect()
    };
    let mut channels: Vec<(String, Vec<f32>)> = vec![
        ("R".into(), light(0)),
        ("G".into(), light(1)),
        ("B".into(), light(2)),
        ("A".into(), vec![1.0; n]),
    ];
    let (depth_name, unit) = depth;
    let z = (0..n).map(|i| if boxed(i) { 2.0 } else { 10.0 } * unit);
    channels.push((depth_name.into(), z.collect()));
    for &(name, moving, still) in vectors {
        let v = (0..n).map(|i| if boxed(i) { moving } else { still });
        channels.push((name.into(), v.collect()));
    }
    for (k, name) in extra.iter().enumerate() {
        channels.push((name.to_string(), noise(n, 11 + k as u32, -1.0, 1.0)));
    }
    let refs = (channels.iter())
        .map(|(name, plane)| (name.as_str(), plane.clone()))
        .collect();
    write_exr(path, W, H, refs);
    channels
}

/// A V-Ray frame ([`write_vray`]) in `dir` blurred by reconstruct under `--preset vray` with
/// `extra`: the input's channels and the output's path.
fn blur_vray(dir: &Path, extra: &[&str]) -> (Vec<(String, Vec<f32>)>, std::path::PathBuf) {
    let color = dir.join("vray.exr");
    let input = write_vray(&color);
    let out = dir.join("out.exr");
    let (c, o) = (s(&color), s(&out));
    let mut args = vec!["blur", "--preset", "vray", "--algorithm", "reconstruct"];
    args.extend(extra);
    args.extend(["--color", &c, "-o", &o]);
    let run = shutter(&args);
    assert!(run.status.success(), "{}", stderr(&run));
    (input, out)
}

/// V-Ray's Velocity element (`VRayVelocity.R/G/B`, p(+1) − p(0), y up) and Z-depth and
/// Normals elements, beside the beauty.
fn write_vray(path: &Path) -> Vec<(String, Vec<f32>)> {
    write_renderer_frame(
        path,
        &[
            ("VRayVelocity.R", 8.0, 0.0),
            ("VRayVelocity.G", 0.0, 0.0),
            ("VRayVelocity.B", 0.25, 0.0),
        ],
        ("Z", 1.0),
        &[
            "VRayZDepth.R",
            "VRayZDepth.G",
            "VRayZDepth.B",
            "VRayNormals.R",
            "VRayNormals.G",
            "VRayNormals.B",
        ],
    )
}

/// The channels of `input` whose names start with one of `layers`, each as it came in the
/// output `out` (bit for bit) — what README's "What survives" promises of data layers.
fn assert_data_back(input: &[(String, Vec<f32>)], out: &Path, layers: &[&str]) {
    use crate::support::{assert_same_bits, channel, read_exr_reference};
    let after = read_exr_reference(out);
    let mut seen = 0;
    for (name, before) in input {
        if layers.iter().any(|l| name.starts_with(l)) {
            assert_same_bits(channel(&after, name), before, name);
            seen += 1;
        }
    }
    assert!(seen > 0, "no channel of {layers:?}");
    assert_ne!(channel(&after, "R"), channel(input, "R"), "nothing blurred");
}

/// F12: under `--preset vray` the preset's own vector pass, `VRayVelocity`, was classed as
/// light by its channels' letters (R, G, B) and blurred with the beauty's weights (476
/// pixels changed in a tester's frame); V-Ray's Z-depth and Normals elements too. A layer a
/// pass is read from is data whatever its name, and V-Ray's names are data by the name rule:
/// each comes back bit for bit.
#[test]
fn a_vray_frames_velocity_depth_and_normals_come_back_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let (input, out) = blur_vray(dir.path(), &[]);
    assert_data_back(
        &input,
        &out,
        &["VRayVelocity.", "VRayZDepth.", "VRayNormals."],
    );
}

/// F12: under DWAA (lossy for channels named R, G, B, float ones too) V-Ray's velocity
/// element stayed in the DWA part with the beauty, up to 0.17 px off; data goes to a
/// lossless part of its own, as `Z` did.
#[test]
fn a_vray_frames_velocity_leaves_a_dwa_part() {
    let dir = tempfile::tempdir().unwrap();
    let (input, out) = blur_vray(dir.path(), &["--compression", "dwaa"]);
    let parts = parts_of(&out);
    for (part, compression, channels) in &parts {
        let lossy = matches!(compression, Compression::DWAA(_) | Compression::DWAB(_));
        for name in channels {
            let data = !["R", "G", "B", "A"].contains(&name.as_str());
            assert!(
                !(lossy && data),
                "{name} is in the DWA part {part:?}: {parts:?}"
            );
        }
    }
    assert_data_back(
        &input,
        &out,
        &["VRayVelocity.", "VRayZDepth.", "VRayNormals.", "Z"],
    );
}

/// F12: `shutter info --preset vray` showed the element layers as colour; a run with the
/// preset treats them as data, and `info` says what the run does.
#[test]
fn info_with_a_renderers_preset_shows_its_passes_as_data() {
    let dir = tempfile::tempdir().unwrap();
    let color = dir.path().join("vray.exr");
    write_vray(&color);
    let o = shutter(&["info", "--preset", "vray", &s(&color)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = crate::support::stdout(&o);
    let class = |name: &str| -> String {
        (text.lines())
            .find(|l| l.split_whitespace().next() == Some(name))
            .and_then(|l| l.split_whitespace().last())
            .unwrap_or_else(|| panic!("no line for {name}: {text}"))
            .to_string()
    };
    for name in [
        "VRayVelocity.R",
        "VRayVelocity.B",
        "VRayZDepth.G",
        "VRayNormals.B",
        "Z",
    ] {
        assert_eq!(class(name), "data", "{name}: {text}");
    }
    assert_eq!(class("R"), "colour", "{text}");
}

/// F12 at its root: a layer a run's preset reads a pass from is data in that run whatever its
/// name (`smear`, which the name rule reads as light by its R, G), in the output and in
/// `info --preset`; unless the preset's `[layers]` says otherwise, explicitly.
#[test]
fn a_layer_a_preset_reads_a_pass_from_is_data_unless_its_layers_table_says_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let color = dir.path().join("smear.exr");
    let input = write_renderer_frame(
        &color,
        &[
            ("smear.R", 6.0, 0.0),
            ("smear.G", 0.0, 0.0),
            ("smear.B", 0.5, 0.0),
        ],
        ("Z", 1.0),
        &[],
    );
    let preset = dir.path().join("smear.toml");
    std::fs::write(
        &preset,
        "[velocity]\nchannels = [[\"smear.R\", \"smear.G\"]]\nmeaning = \"velocity\"\n",
    )
    .unwrap();
    let out = dir.path().join("out.exr");
    let blur = |presets: &[&Path]| {
        let mut args = vec![
            "blur".to_string(),
            "--algorithm".into(),
            "reconstruct".into(),
        ];
        for p in presets {
            args.extend(["--preset".to_string(), s(p)]);
        }
        args.extend(["--color".to_string(), s(&color), "-o".into(), s(&out)]);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = shutter(&args);
        assert!(o.status.success(), "{}", stderr(&o));
    };
    blur(&[&preset]);
    assert_data_back(&input, &out, &["smear."]);
    let info = |presets: &[&Path]| {
        let mut args = vec!["info".to_string()];
        for p in presets {
            args.extend(["--preset".to_string(), s(p)]);
        }
        args.push(s(&color));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let o = shutter(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = crate::support::stdout(&o);
        (text.lines())
            .find(|l| l.split_whitespace().next() == Some("smear.B"))
            .and_then(|l| l.split_whitespace().last())
            .unwrap_or_else(|| panic!("no smear.B: {text}"))
            .to_string()
    };
    assert_eq!(info(&[&preset]), "data");

    // Said otherwise: `[layers] smear = "colour"` blurs it with the beauty.
    let colour = dir.path().join("colour.toml");
    std::fs::write(&colour, "[layers]\nsmear = \"colour\"\n").unwrap();
    assert_eq!(info(&[&preset, &colour]), "colour");
    blur(&[&preset, &colour]);
    let after = crate::support::read_exr_reference(&out);
    let blurred = crate::support::channel(&after, "smear.R");
    assert_ne!(blurred, crate::support::channel(&input, "smear.R"));
}

/// F8 and F12 on Movie Render Queue's frame: the MotionVectors pass (0.5 = still, screen
/// fractions) and the WorldDepth pass (centimetres in R, G, B) beside the beauty. The unreal
/// preset read no depth (it named shutter's `Z`, which MRQ never writes), so no algorithm
/// ran; it reads WorldDepth now, and both passes come back bit for bit. Without the depth
/// pass the error says what to add in Unreal.
#[test]
fn a_movie_render_queue_frame_blurs_under_the_unreal_preset() {
    let dir = tempfile::tempdir().unwrap();
    let color = dir.path().join("mrq.exr");
    let mv = "FinalImageMovieRenderQueue_MotionVectors";
    let depth = "FinalImageMovieRenderQueue_WorldDepth";
    let names = |layer: &str| ["R", "G", "B", "A"].map(|c| format!("{layer}.{c}"));
    let [mr, mg, mb, ma] = names(mv);
    let [dg, db, da] = [1, 2, 3].map(|k| names(depth)[k].clone());
    let input = write_renderer_frame(
        &color,
        &[
            (&mr, 0.5 + 8.0 / W as f32, 0.5),
            (&mg, 0.5, 0.5),
            (&mb, 0.0, 0.0),
            (&ma, 1.0, 1.0),
        ],
        (&names(depth)[0], 100.0),
        &[dg.as_str(), db.as_str(), da.as_str()],
    );
    let out = dir.path().join("out.exr");
    let o = shutter(&[
        "blur",
        "--preset",
        "unreal",
        "--algorithm",
        "reconstruct",
        "--color",
        &s(&color),
        "-o",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_data_back(&input, &out, &[&format!("{mv}."), &format!("{depth}.")]);

    // Without WorldDepth: refused, naming the channel and the pass to add in Unreal.
    let bare = dir.path().join("bare.exr");
    let kept: Vec<(&str, Vec<f32>)> = (input.iter())
        .filter(|(name, _)| !name.starts_with(depth))
        .map(|(name, plane)| (name.as_str(), plane.clone()))
        .collect();
    write_exr(&bare, W, H, kept);
    let o = shutter(&[
        "blur",
        "--preset",
        "unreal",
        "--algorithm",
        "reconstruct",
        "--color",
        &s(&bare),
        "-o",
        &s(&dir.path().join("bare-out.exr")),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("FinalImageMovieRenderQueue_WorldDepth.R")
            && err.contains("MovieRenderQueue_WorldDepth, 32-bit"),
        "{err}"
    );
}
