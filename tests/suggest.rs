//! `shutter info` names the preset a file most likely needs, with the channels that matched:
//! each built-in convention preset for a synthetic file in its own convention, and no motion
//! preset for plain colour beyond the readings its header cannot rule out.

use std::path::Path;

use crate::support::{s, shutter, stderr, stdout, write_exr, write_parts, write_views, Part};

const W: usize = 8;
const H: usize = 6;

fn plane(value: f32) -> Vec<f32> {
    vec![value; W * H]
}

fn exr(path: &Path, names: &[&str]) {
    write_exr(path, W, H, names.iter().map(|n| (*n, plane(0.5))).collect());
}

/// `shutter info --json` on one file: its document.
fn info(path: &Path) -> serde_json::Value {
    let o = shutter(&["info", "--json", &s(path)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    json["files"][0].clone()
}

fn info_text(path: &Path) -> String {
    let o = shutter(&["info", &s(path)]);
    assert!(o.status.success(), "{}", stderr(&o));
    stdout(&o)
}

/// The suggestion's passes, as (pass, channels).
fn found(suggestion: &serde_json::Value) -> Vec<(String, Vec<String>)> {
    suggestion["found"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let channels = f["channels"].as_array().unwrap();
            (
                f["pass"].as_str().unwrap().to_string(),
                channels
                    .iter()
                    .map(|c| c.as_str().unwrap().to_string())
                    .collect(),
            )
        })
        .collect()
}

fn candidates(suggestion: &serde_json::Value) -> Vec<(String, String)> {
    suggestion["candidates"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (
                c["preset"].as_str().unwrap().to_string(),
                c["role"].as_str().unwrap().to_string(),
            )
        })
        .collect()
}

fn pair(pass: &str, channels: &[&str]) -> (String, Vec<String>) {
    (
        pass.to_string(),
        channels.iter().map(|c| c.to_string()).collect(),
    )
}

#[test]
fn the_canonical_convention_suggests_shutter() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("canonical.exr");
    exr(
        &path,
        &[
            "R",
            "G",
            "B",
            "A",
            "Z",
            "velocity.X",
            "velocity.Y",
            "prev.X",
            "prev.Y",
            "prev.Z",
            "next.X",
            "next.Y",
            "next.Z",
        ],
    );
    let doc = info(&path);
    let suggestion = &doc["suggestion"];
    assert_eq!(suggestion["preset"], "shutter");
    assert_eq!(suggestion["matched"], 13);
    assert_eq!(suggestion["channels"], 13);
    assert!(found(suggestion).contains(&pair("velocity", &["velocity.X", "velocity.Y"])));
    assert!(found(suggestion).contains(&pair("next", &["next.X", "next.Y", "next.Z"])));
    assert!(candidates(suggestion).is_empty());
    let text = info_text(&path);
    assert!(
        text.contains("suggested:      shutter: R, G, B, A as color; Z as depth; velocity.X"),
        "{text}"
    );
}

#[test]
fn a_blender_multilayer_file_suggests_blender() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("blender.exr");
    let l = "RenderLayer";
    let names: Vec<String> = ["Combined.R", "Combined.G", "Combined.B", "Combined.A"]
        .iter()
        .chain(&["Depth.Z", "Vector.X", "Vector.Y", "Vector.Z", "Vector.W"])
        .map(|n| format!("{l}.{n}"))
        .collect();
    exr(&path, &names.iter().map(String::as_str).collect::<Vec<_>>());
    let suggestion = &info(&path)["suggestion"];
    assert_eq!(suggestion["preset"], "blender");
    assert_eq!(suggestion["matched"], 9);
    assert!(found(suggestion).contains(&pair(
        "next",
        &["RenderLayer.Vector.Z", "RenderLayer.Vector.W"]
    )));
}

/// A render of two view layers is what `--layers FG,BG` reads: info names the preset, the
/// layers and the two ways to read them (it said "none match" before).
#[test]
fn a_blender_file_of_two_view_layers_suggests_blender_and_names_the_layers() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("layers.exr");
    let names: Vec<String> = ["FG", "BG"]
        .iter()
        .flat_map(|l| {
            [
                "Combined.R",
                "Combined.G",
                "Combined.B",
                "Combined.A",
                "Depth.Z",
            ]
            .iter()
            .chain(&["Vector.X", "Vector.Y", "Vector.Z", "Vector.W"])
            .map(move |n| format!("{l}.{n}"))
        })
        .collect();
    exr(&path, &names.iter().map(String::as_str).collect::<Vec<_>>());
    let suggestion = &info(&path)["suggestion"];
    assert_eq!(suggestion["preset"], "blender");
    assert_eq!(suggestion["matched"], 18);
    assert_eq!(suggestion["view_layers"], serde_json::json!(["BG", "FG"]));
    assert!(found(suggestion).contains(&pair("depth", &["BG.Depth.Z", "FG.Depth.Z"])));
    let text = info_text(&path);
    assert!(
        text.contains("presets:        blender (color, depth"),
        "{text}"
    );
    assert!(
        text.contains("view layers BG, FG: --layer NAME reads one, --layers"),
        "{text}"
    );
}

/// Blender adds its compositor's result, `Composite.Combined.RGBA`, beside the view layers:
/// colour alone, not a layer to blur or stack; nor is a name with part of a colour.
#[test]
fn blenders_composite_result_is_no_view_layer() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("render.exr");
    let mut names: Vec<String> = ["Combined.R", "Combined.G", "Combined.B", "Combined.A"]
        .iter()
        .chain(&["Depth.Z", "Vector.X", "Vector.Y", "Vector.Z", "Vector.W"])
        .map(|n| format!("ViewLayer.{n}"))
        .collect();
    names.extend(["R", "G", "B", "A"].map(|c| format!("Composite.Combined.{c}")));
    names.push("Junk.Combined.R".to_string());
    exr(&path, &names.iter().map(String::as_str).collect::<Vec<_>>());
    let suggestion = &info(&path)["suggestion"];
    assert_eq!(suggestion["preset"], "blender");
    assert_eq!(suggestion["matched"], 9);
    assert_eq!(suggestion["view_layers"], serde_json::json!(["ViewLayer"]));
    let text = info_text(&path);
    let hint = "; view layer ViewLayer (Composite, Junk hold no passes to blur): --layer \
                ViewLayer reads it";
    assert!(text.contains(hint), "{text}");
}

#[test]
fn nuke_files_suggest_nuke_single_and_multi_part() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nuke.exr");
    exr(
        &path,
        &[
            "R",
            "G",
            "B",
            "A",
            "depth.Z",
            "forward.u",
            "forward.v",
            "backward.u",
            "backward.v",
        ],
    );
    let suggestion = &info(&path)["suggestion"];
    assert_eq!(suggestion["preset"], "nuke");
    assert_eq!(suggestion["matched"], 9);
    assert!(found(suggestion).contains(&pair("next", &["forward.u", "forward.v"])));
    // shutter reads colour and depth.Z alike, but not the vectors.
    assert!(suggestion["tied"].as_array().unwrap().is_empty());

    // Parts named after Nuke's layers, channels u, v in each: shutter's plain `u`, `v`
    // alternative finds one of the two vector parts, nuke both.
    let path = dir.path().join("nuke-parts.exr");
    let part = |name: &'static str, channels: &[&str]| Part {
        name: Some(name),
        view: None,
        multi_view: None,
        channels: channels
            .iter()
            .map(|c| (c.to_string(), plane(0.5)))
            .collect(),
    };
    write_parts(
        &path,
        (W, H),
        vec![
            part("rgba", &["R", "G", "B", "A"]),
            part("depth", &["Z"]),
            part("forward", &["u", "v"]),
            part("backward", &["u", "v"]),
        ],
    );
    let suggestion = &info(&path)["suggestion"];
    assert_eq!(suggestion["preset"], "nuke", "{suggestion}");
    assert_eq!(suggestion["matched"], 9);
}

/// An 8-bit RGB(A) PNG or a 16-bit TIFF of the given channel count.
fn image(path: &Path, channels: usize, sixteen: bool) {
    let color = match (channels, sixteen) {
        (1, false) => image::ColorType::L8,
        (3, false) => image::ColorType::Rgb8,
        (4, false) => image::ColorType::Rgba8,
        (1, true) => image::ColorType::L16,
        (3, true) => image::ColorType::Rgb16,
        _ => image::ColorType::Rgba16,
    };
    let bytes = vec![127u8; W * H * channels * if sixteen { 2 } else { 1 }];
    image::save_buffer(path, &bytes, W as u32, H as u32, color).unwrap();
}

#[test]
fn rsmb_vectors_are_an_rsmb_candidate_with_its_reason() {
    let dir = tempfile::tempdir().unwrap();
    for (name, sixteen) in [("mv.png", false), ("mv.tif", true)] {
        let path = dir.path().join(name);
        image(&path, 4, sixteen);
        let suggestion = &info(&path)["suggestion"];
        let candidates = candidates(suggestion);
        assert!(
            candidates.contains(&("rsmb".into(), "vectors".into())),
            "{name}: {suggestion}"
        );
        let rsmb = suggestion["candidates"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["preset"] == "rsmb")
            .unwrap();
        let reason = rsmb["reason"].as_str().unwrap();
        for needle in ["R, G", "RE:Vision", "max_displace", "A below full-on"] {
            assert!(reason.contains(needle), "'{needle}' not in {reason}");
        }
        assert_eq!(rsmb["channels"], serde_json::json!(["R", "G"]));
        let text = info_text(&path);
        assert!(text.contains("  if vectors:"), "{text}");
    }
}

#[test]
fn painted_maps_are_painted_candidates() {
    let dir = tempfile::tempdir().unwrap();
    // A painted velocity map: RGB, mid-grey still.
    let path = dir.path().join("velocity.png");
    image(&path, 3, false);
    let suggestion = &info(&path)["suggestion"];
    assert!(
        candidates(suggestion).contains(&("painted".into(), "vectors".into())),
        "{suggestion}"
    );
    // A painted depth map: grey, near..far. It cannot hold vectors.
    let path = dir.path().join("depth.png");
    image(&path, 1, true);
    let suggestion = &info(&path)["suggestion"];
    assert_eq!(
        candidates(suggestion),
        [("painted".to_string(), "depth".to_string())],
        "{suggestion}"
    );
    let text = info_text(&path);
    assert!(
        text.contains("  if depth:       painted: Y as depth: grey 0..1 = 1..100"),
        "{text}"
    );
}

#[test]
fn plain_colour_gets_no_motion_preset() {
    let dir = tempfile::tempdir().unwrap();
    // Float RGB: colour and nothing else; no reading as vectors is offered.
    let path = dir.path().join("rgb.exr");
    exr(&path, &["R", "G", "B"]);
    let suggestion = &info(&path)["suggestion"];
    assert_eq!(suggestion["preset"], "shutter");
    assert_eq!(found(suggestion), [pair("color", &["R", "G", "B"])]);
    assert!(candidates(suggestion).is_empty(), "{suggestion}");
    let text = info_text(&path);
    assert!(text.contains("colour only (R, G, B as color"), "{text}");
    assert!(!text.contains("if vectors"), "{text}");

    // An 8-bit RGB image: its suggestion is colour only too; vector readings are offered
    // only as what they are, readings the header cannot rule out.
    let path = dir.path().join("rgb.png");
    image(&path, 3, false);
    let suggestion = &info(&path)["suggestion"];
    assert_eq!(suggestion["preset"], "shutter");
    assert_eq!(found(suggestion), [pair("color", &["R", "G", "B"])]);
    assert!(candidates(suggestion)
        .iter()
        .all(|(_, role)| role == "vectors"));
}

#[test]
fn ties_go_to_the_fixed_order_and_say_so() {
    let dir = tempfile::tempdir().unwrap();
    // R, G, B, A and Z: shutter, blender's and nuke's fallbacks read the same five.
    let path = dir.path().join("rgbaz.exr");
    exr(&path, &["R", "G", "B", "A", "Z"]);
    let suggestion = &info(&path)["suggestion"];
    assert_eq!(suggestion["preset"], "shutter");
    let tied = suggestion["tied"].to_string();
    for name in ["blender", "nuke"] {
        assert!(tied.contains(name), "{tied}");
    }
    assert!(suggestion["reason"]
        .as_str()
        .unwrap()
        .contains("ties go to the first of shutter, blender, nuke"));

    // Channels no preset names: no suggestion, and the reason lists them.
    let path = dir.path().join("other.exr");
    exr(&path, &["diffuse.r", "diffuse.g"]);
    let suggestion = &info(&path)["suggestion"];
    assert!(suggestion["preset"].is_null());
    assert!(suggestion["reason"].as_str().unwrap().contains("diffuse.r"));
}

/// A run that finds no motion names the presets that would find it in the file, as
/// `shutter info` suggests them (QA L7: V-Ray's `VRayVelocity.R/G` under the default preset
/// got no hint of `--preset vray`, as a missing depth gets one), and does not offer the
/// colour's own `R,G` as the vectors it looked for.
#[test]
fn missing_motion_names_the_presets_that_find_vectors_and_not_the_colours_channels() {
    let dir = tempfile::tempdir().unwrap();
    for (vectors, channels) in [
        ("VRayVelocity", "VRayVelocity.R, VRayVelocity.G"),
        ("velocity", "velocity.R, velocity.G"),
    ] {
        let color = dir.path().join(format!("{vectors}.exr"));
        let names: Vec<String> = ["R", "G", "B", "A", "Z"]
            .into_iter()
            .map(String::from)
            .chain(["R", "G", "B"].map(|c| format!("{vectors}.{c}")))
            .collect();
        exr(
            &color,
            &names.iter().map(String::as_str).collect::<Vec<_>>(),
        );
        let out = dir.path().join("out.exr");
        for algorithm in ["reconstruct", "scatter"] {
            let o = shutter(&[
                "blur",
                "--algorithm",
                algorithm,
                "--color",
                &s(&color),
                "-o",
                &s(&out),
            ]);
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(1), "{err}");
            assert!(!out.exists());
            let hint = format!("--preset vray ({channels} as velocity)");
            assert!(err.contains(&hint), "{algorithm}: no {hint}: {err}");
            assert!(
                !err.contains("R,G"),
                "{algorithm}: offers the colour's R,G: {err}"
            );
            // The preset that did not find it is not offered again.
            assert!(!err.contains("--preset shutter"), "{err}");
        }
    }
}

/// The presets a missing pass's problem offers are those that find it in the view being
/// read, not anywhere in the file (review: with `--view right` of a stereo file whose
/// `velocity.X/Y` are the default view's alone, the hint offered `--preset shutter`, which
/// fails the same way; likewise a `Z` of the default view alone, as every preset's depth
/// for `right`); and a preset that reads picture codes (`painted`: vectors about 0.5,
/// depth as grey) is not offered for a float file's `X`, `Y`.
#[test]
fn missing_pass_hints_look_in_the_view_read_and_skip_picture_code_presets() {
    let dir = tempfile::tempdir().unwrap();
    let stereo = dir.path().join("stereo.exr");
    let mut channels: Vec<(String, Vec<f32>)> = ["R", "G", "B", "A", "Z", "velocity.X"]
        .into_iter()
        .chain(["velocity.Y"])
        .map(|c| (c.to_string(), plane(0.5)))
        .collect();
    // right writes the velocity layer as its own (its Z alone), so left's velocity.X/Y are
    // the default view's, not right's (OpenEXR's one-part scheme, as `io::view` reads it).
    for c in [
        "right.R",
        "right.G",
        "right.B",
        "right.A",
        "velocity.right.Z",
    ] {
        channels.push((c.to_string(), plane(0.5)));
    }
    write_views(&stereo, (W, H), &["left", "right"], channels);
    let out = dir.path().join("out.exr");
    let run = |color: &Path, extra: &[&str]| {
        let mut args = vec!["blur", "--algorithm", "reconstruct", "--color"];
        let color = s(color);
        args.push(&color);
        let out = s(&out);
        args.extend(["-o", &out]);
        args.extend(extra);
        let o = shutter(&args);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        stderr(&o)
    };
    // right has neither depth nor vectors: no preset finds them there.
    let err = run(&stereo, &["--view", "right", "--preset", "vray"]);
    assert!(!err.contains("--preset shutter"), "{err}");
    assert!(!err.contains("--preset blender (Z)"), "{err}");
    assert!(err.contains("(--preset FILE)"), "{err}");
    // A float file's X, Y: the shutter preset reads them, painted would decode them as codes.
    let xy = dir.path().join("xy.exr");
    exr(&xy, &["R", "G", "B", "A", "Z", "X", "Y"]);
    let err = run(&xy, &["--preset", "vray"]);
    assert!(err.contains("--preset shutter (X, Y as velocity)"), "{err}");
    assert!(!err.contains("painted"), "{err}");
    // Unreal's float vectors are stored about 0.5 too, but are no picture's codes: its
    // preset is still offered (second review: it had been left out with painted).
    let mrq = dir.path().join("mrq.exr");
    let vectors = "FinalImageMovieRenderQueue_MotionVectors";
    let names: Vec<String> = ["R", "G", "B", "A"]
        .into_iter()
        .map(String::from)
        .chain(["R", "G", "B", "A"].map(|c| format!("{vectors}.{c}")))
        .chain(["FinalImageMovieRenderQueue_WorldDepth.R".to_string()])
        .collect();
    exr(&mrq, &names.iter().map(String::as_str).collect::<Vec<_>>());
    let err = run(&mrq, &["--preset", "vray"]);
    let hint = format!("--preset unreal ({vectors}.R, {vectors}.G as velocity)");
    assert!(err.contains(&hint), "{err}");
}
