//! Multi-view (stereo) EXRs: an EXR output holds every view, each blurred as that view
//! alone, `--view` reads and writes one (a picture output the default), and a view that
//! cannot be settled stops the run before anything is written, listing the views.
//! Both of OpenEXR's schemes (MultiViewOpenEXR.html): one part with a `multiView` attribute
//! and view-named channels, and parts with a `view` attribute each.

use std::path::{Path, PathBuf};

use crate::support::{
    noise, read_exr_reference, s, shutter, snapshot, stderr, stdout, write_exr, write_parts,
    write_views, Part,
};

const W: usize = 32;
const H: usize = 24;

/// One view's canonical passes: colour, depth and a velocity that blurs.
fn view_passes(seed: u32) -> Vec<(&'static str, Vec<f32>)> {
    let n = W * H;
    vec![
        ("R", noise(n, seed, 0.0, 1.0)),
        ("G", noise(n, seed + 1, 0.0, 1.0)),
        ("B", noise(n, seed + 2, 0.0, 1.0)),
        ("A", vec![1.0; n]),
        ("Z", noise(n, seed + 3, 1.0, 5.0)),
        ("velocity.X", noise(n, seed + 4, -6.0, 6.0)),
        ("velocity.Y", noise(n, seed + 5, -3.0, 3.0)),
    ]
}

const LEFT: u32 = 10;
const RIGHT: u32 = 50;

fn named(
    passes: Vec<(&str, Vec<f32>)>,
    rename: impl Fn(&str) -> String,
) -> Vec<(String, Vec<f32>)> {
    passes.into_iter().map(|(n, p)| (rename(n), p)).collect()
}

/// `R` → `right.R`, `velocity.X` → `velocity.right.X`: the view as the penultimate component.
fn in_view(view: &str) -> impl Fn(&str) -> String + '_ {
    move |name: &str| match name.rsplit_once('.') {
        Some((layer, channel)) => format!("{layer}.{view}.{channel}"),
        None => format!("{view}.{name}"),
    }
}

/// The single-part scheme: `multiView = [left, right]`, left's channels plain (the default
/// view), right's named `right.R`, `velocity.right.X`, ...
fn single_part_stereo(path: &Path) {
    let mut channels = named(view_passes(LEFT), |n| n.to_string());
    channels.extend(named(view_passes(RIGHT), in_view("right")));
    write_views(path, (W, H), &["left", "right"], channels);
}

/// Each view as a plain file of one view, to compare with.
fn mono(dir: &Path) -> (String, String) {
    let left = dir.join("left.exr");
    let right = dir.join("right.exr");
    write_exr(&left, W, H, view_passes(LEFT));
    write_exr(&right, W, H, view_passes(RIGHT));
    (s(&left), s(&right))
}

/// Runs `shutter blur` (reconstruct) on `color` with `extra` flags into `out`.
fn blur(color: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    let out = s(out);
    let mut args = vec![
        "blur",
        "--algorithm",
        "reconstruct",
        "--color",
        color,
        "-o",
        &out,
    ];
    args.extend(extra);
    shutter(&args)
}

/// The beauty of an output's first part holding one (R, G, B, A): an output of every view
/// has the default view's first.
fn beauty(path: &Path) -> Vec<(String, Vec<f32>)> {
    let layers = crate::support::read_exr_layers(path);
    let has_red = |l: &&exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>>| {
        l.channel_data
            .list
            .iter()
            .any(|c| c.name.to_string() == "R")
    };
    let first = layers.iter().find(has_red).expect("a beauty").clone();
    let mut channels: Vec<(String, Vec<f32>)> = first
        .channel_data
        .list
        .into_iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    channels.retain(|(name, _)| ["R", "G", "B", "A"].contains(&name.as_str()));
    assert_eq!(channels.len(), 4, "{path:?}");
    channels
}

fn assert_same_image(a: &Path, b: &Path) {
    assert_eq!(beauty(a), beauty(b), "{a:?} and {b:?} differ");
}

fn assert_different_images(a: &Path, b: &Path) {
    assert_ne!(beauty(a), beauty(b), "{a:?} and {b:?} are the same");
}

#[test]
fn single_part_stereo_reads_the_default_view_and_view_right_the_other() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let stereo = d.join("stereo.exr");
    single_part_stereo(&stereo);
    let (left, right) = mono(d);
    for (input, out, extra) in [
        (s(&stereo), "default.exr", &[][..]),
        (s(&stereo), "right.exr", &["--view", "right"][..]),
        (s(&stereo), "left.exr", &["--view", "left"][..]),
        (left, "mono-left.exr", &[][..]),
        (right, "mono-right.exr", &[][..]),
    ] {
        let o = blur(&input, &d.join("out").join(out), extra);
        assert!(o.status.success(), "{out}: {}", stderr(&o));
    }
    let out = |name: &str| d.join("out").join(name);
    assert_same_image(&out("default.exr"), &out("mono-left.exr"));
    assert_same_image(&out("left.exr"), &out("mono-left.exr"));
    assert_same_image(&out("right.exr"), &out("mono-right.exr"));
    assert_different_images(&out("right.exr"), &out("left.exr"));
    // One view is written: no multiView list naming views the file does not hold.
    let meta = exr::meta::MetaData::read_from_file(out("right.exr"), false).unwrap();
    assert_eq!(meta.headers[0].own_attributes.multi_view_names, None);
    // Without --view, both, with the list.
    let meta = exr::meta::MetaData::read_from_file(out("default.exr"), false).unwrap();
    let list = meta.headers[0].own_attributes.multi_view_names.as_ref();
    let list: Vec<String> = list.unwrap().iter().map(|t| t.to_string()).collect();
    assert_eq!(list, ["left", "right"]);
}

#[test]
fn multi_part_stereo_reads_the_first_parts_view_and_view_left_the_other() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let stereo = d.join("stereo.exr");
    // The document's "simple stereo EXR, with default view right": right's part first.
    write_parts(
        &stereo,
        (W, H),
        vec![
            Part {
                name: Some("rgb-right"),
                view: Some("right"),
                multi_view: None,
                channels: named(view_passes(RIGHT), |n| n.to_string()),
            },
            Part {
                name: Some("rgb-left"),
                view: Some("left"),
                multi_view: None,
                channels: named(view_passes(LEFT), |n| n.to_string()),
            },
        ],
    );
    let (left, right) = mono(d);
    for (input, out, extra) in [
        (s(&stereo), "default.exr", &[][..]),
        (s(&stereo), "left.exr", &["--view", "left"][..]),
        (left, "mono-left.exr", &[][..]),
        (right, "mono-right.exr", &[][..]),
    ] {
        let o = blur(&input, &d.join("out").join(out), extra);
        assert!(o.status.success(), "{out}: {}", stderr(&o));
    }
    let out = |name: &str| d.join("out").join(name);
    assert_same_image(&out("default.exr"), &out("mono-right.exr"));
    assert_same_image(&out("left.exr"), &out("mono-left.exr"));
    assert_different_images(&out("default.exr"), &out("left.exr"));
    // Without --view, both views' parts, the default's first.
    let meta = exr::meta::MetaData::read_from_file(out("default.exr"), false).unwrap();
    let views: Vec<Option<String>> = (meta.headers.iter())
        .map(|h| h.own_attributes.view_name.as_ref().map(|t| t.to_string()))
        .collect();
    assert_eq!(views, [Some("right".into()), Some("left".into())]);
}

/// A part of a file `write_parts` writes.
fn part(
    name: Option<&'static str>,
    view: Option<&'static str>,
    multi_view: Option<&'static [&'static str]>,
    channels: Vec<(String, Vec<f32>)>,
) -> Part {
    Part {
        name,
        view,
        multi_view,
        channels,
    }
}

/// One view's passes with a light layer and an object-ID layer beside them, as a renderer
/// writes each eye.
fn view_with_layers(seed: u32) -> Vec<(&'static str, Vec<f32>)> {
    let n = W * H;
    let mut passes = view_passes(seed);
    passes.extend([
        ("diffuse.R", noise(n, seed + 6, 0.0, 0.5)),
        ("diffuse.G", noise(n, seed + 7, 0.0, 0.5)),
        ("diffuse.B", noise(n, seed + 8, 0.0, 0.5)),
        ("crypto.id", noise(n, seed + 9, 0.0, 100.0)),
    ]);
    passes
}

/// Stereo files of [`view_with_layers`] in both schemes, `names.exr` (one part, `multiView`)
/// and `parts.exr` (a part a view), with `shared`, a channel of no view, beside them (in the
/// one part, or in a part of its own named `notes`).
fn stereo_with_layers(d: &Path, shared: Option<(String, Vec<f32>)>) -> (PathBuf, PathBuf) {
    let names = d.join("names.exr");
    let mut channels = named(view_with_layers(LEFT), |n| n.to_string());
    channels.extend(named(view_with_layers(RIGHT), in_view("right")));
    channels.extend(shared.clone());
    write_parts(
        &names,
        (W, H),
        vec![part(None, None, Some(&["left", "right"][..]), channels)],
    );
    let parts = d.join("parts.exr");
    let mut list = vec![
        part(
            Some("left"),
            Some("left"),
            None,
            named(view_with_layers(LEFT), |n| n.to_string()),
        ),
        part(
            Some("right"),
            Some("right"),
            None,
            named(view_with_layers(RIGHT), |n| n.to_string()),
        ),
    ];
    if let Some(channel) = shared {
        list.push(part(Some("notes"), None, None, vec![channel]));
    }
    write_parts(&parts, (W, H), list);
    (names, parts)
}

#[test]
fn a_view_comes_out_with_every_channel_its_mono_file_gives_and_the_others_are_named() {
    // Both schemes: each view's output holds every channel the same view written as a file
    // of its own gives (light layers blurred with its beauty, depth, vectors and IDs as they
    // came), and the run says which views it did not write.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (names, parts) = stereo_with_layers(d, None);
    let mono = |seed: u32, name: &str| {
        let path = d.join(name);
        write_exr(&path, W, H, view_with_layers(seed));
        let out = d.join("out").join(name);
        let o = blur(&s(&path), &out, &[]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let mut channels = read_exr_reference(&out);
        channels.sort_by(|a, b| a.0.cmp(&b.0));
        channels
    };
    let (left, right) = (mono(LEFT, "left.exr"), mono(RIGHT, "right.exr"));
    assert_eq!(left.len(), 11);
    for (stereo, view, other, want) in [
        (&names, "left", "right", &left),
        (&names, "right", "left", &right),
        (&parts, "left", "right", &left),
        (&parts, "right", "left", &right),
    ] {
        let out = d.join("out").join(format!(
            "{view}-{}",
            stereo.file_name().unwrap().to_string_lossy()
        ));
        let o = blur(&s(stereo), &out, &["--view", view, "--json"]);
        assert!(o.status.success(), "{view}: {}", stderr(&o));
        let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        let warnings = report["warnings"].to_string();
        assert!(
            warnings.contains(&format!("other views ({other})")),
            "{warnings}"
        );
        let mut got = read_exr_reference(&out);
        got.sort_by(|a, b| a.0.cmp(&b.0));
        assert_eq!(&got, want, "{view} of {stereo:?}");
        // Run again with --skip-existing, it writes nothing and leaves no view out: nothing
        // to say (an outside tester found it said it all the same).
        let o = blur(
            &s(stereo),
            &out,
            &["--view", view, "--json", "--skip-existing"],
        );
        let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        assert_eq!(report["frames_skipped"], 1, "{report}");
        let warnings = report["warnings"].to_string();
        assert!(!warnings.contains("other views"), "{warnings}");
    }
}

/// The channels of an output, sorted by name, each with its part's view.
fn channels_by_view(path: &Path) -> Vec<(Option<String>, String, Vec<f32>)> {
    let mut all = Vec::new();
    for layer in crate::support::read_exr_layers(path) {
        let view = layer.attributes.view_name.as_ref().map(|t| t.to_string());
        for c in layer.channel_data.list {
            let values = c.sample_data.values_as_f32().collect();
            all.push((view.clone(), c.name.to_string(), values));
        }
    }
    all.sort_by(|a, b| (&a.0, &a.1).cmp(&(&b.0, &b.1)));
    all
}

#[test]
fn an_exr_output_holds_every_view_each_as_that_view_alone_gives() {
    // Both schemes, with a light layer, IDs and a channel of no view: without --view, one
    // output holds each view's channels under the names (and in the parts) they are stored
    // in, with the bits that view gives written alone (--view), the channels of no view
    // once, and the views attribute; nothing warns of views left out.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let extra = ("notes.N".to_string(), noise(W * H, 99, 0.0, 1.0));
    let (names, parts) = stereo_with_layers(d, Some(extra));
    for (stereo, one_part) in [(&names, true), (&parts, false)] {
        let file = stereo.file_name().unwrap().to_string_lossy().to_string();
        let run = |out: &str, extra: &[&str]| {
            let out = d.join("out").join(format!("{out}-{file}"));
            let o = blur(&s(stereo), &out, &[extra, &["--json"]].concat());
            assert!(o.status.success(), "{out:?}: {}", stderr(&o));
            let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
            (out, report["warnings"].to_string())
        };
        let (every, warnings) = run("every", &[]);
        assert!(!warnings.contains("other views"), "{warnings}");
        let (left, _) = run("left", &["--view", "left"]);
        let (right, _) = run("right", &["--view", "right"]);
        // What each view written alone gives, named and placed as the input stores it.
        let mut want = Vec::new();
        for (view, path) in [("left", &left), ("right", &right)] {
            for (_, name, values) in channels_by_view(path) {
                let shared = name == "notes.N";
                if shared && view == "right" {
                    continue;
                }
                if one_part {
                    let stored = if view == "right" && !shared {
                        in_view("right")(&name)
                    } else {
                        name
                    };
                    want.push((None, stored, values));
                } else {
                    let part_view = (!shared).then(|| view.to_string());
                    want.push((part_view, name, values));
                }
            }
        }
        want.sort_by(|a, b| (&a.0, &a.1).cmp(&(&b.0, &b.1)));
        let got = channels_by_view(&every);
        assert_eq!(
            got.iter().map(|c| (&c.0, &c.1)).collect::<Vec<_>>(),
            want.iter().map(|c| (&c.0, &c.1)).collect::<Vec<_>>(),
            "{file}"
        );
        assert!(got == want, "{file}: the values differ");
        // The views blurred apart: the right beauty is not the left's.
        assert_different_images(&left, &right);
        // OpenImageIO, which nobody here wrote, reads the views.
        if let Some(info) = crate::support::oiiotool_info(&every) {
            if one_part {
                assert!(info.contains("multiView: \"left\", \"right\""), "{info}");
            } else {
                // (It details the first subimage, the default view's.)
                assert!(info.contains("view: \"left\""), "{info}");
                assert!(info.contains("3 subimages"), "{info}");
            }
        }
    }
}

#[test]
fn a_part_of_no_view_comes_out_and_the_default_views_own_layers_stay_its_own() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let n = W * H;
    // Parts: each view's passes, then a part of no view whose channels share the views'
    // names (R, G, B): it is a part of its own, not a view's, and must come out.
    let parts = d.join("parts.exr");
    let shared = vec![
        ("R".to_string(), noise(n, 70, 0.0, 1.0)),
        ("G".to_string(), noise(n, 71, 0.0, 1.0)),
        ("B".to_string(), noise(n, 72, 0.0, 1.0)),
    ];
    write_parts(
        &parts,
        (W, H),
        vec![
            part(
                Some("left"),
                Some("left"),
                None,
                named(view_passes(LEFT), |n| n.to_string()),
            ),
            part(
                Some("right"),
                Some("right"),
                None,
                named(view_passes(RIGHT), |n| n.to_string()),
            ),
            part(Some("shared"), None, None, shared),
        ],
    );
    let out = d.join("out").join("parts.exr");
    let o = blur(&s(&parts), &out, &["--view", "right"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let layers: Vec<(Option<String>, Vec<String>)> = crate::support::read_exr_layers(&out)
        .iter()
        .map(|l| {
            let name = l.attributes.layer_name.as_ref().map(|t| t.to_string());
            let channels = l
                .channel_data
                .list
                .iter()
                .map(|c| c.name.to_string())
                .collect();
            (name, channels)
        })
        .collect();
    assert!(
        layers.contains(&(
            Some("shared".into()),
            vec!["B".into(), "G".into(), "R".into()]
        )),
        "{layers:?}"
    );
    // A plain file of one view: no part says it is a view's (a part of no view may then
    // come first).
    let meta = exr::meta::MetaData::read_from_file(&out, false).unwrap();
    assert!(meta
        .headers
        .iter()
        .all(|h| h.own_attributes.view_name.is_none()));
    // And OpenImageIO, which nobody here wrote, reads both parts, as plain parts.
    if let Some(info) = crate::support::oiiotool_info(&out) {
        // The view's seven channels, then the shared part's three.
        assert!(
            info.contains("2 subimages: 32x24 [f,f,f,f,f,f,f], 32x24 [f,f,f]"),
            "{info}"
        );
        assert!(!info.contains("multiView"), "{info}");
    }
    // One part: the default view (left) writes its layers without its name, the other view
    // with it. Right has `diffuse.right.R,G,B` but no alpha: left's `diffuse.A` is left's,
    // and must not come out as right's; `spec`, which no view writes as its own, is of no
    // view and comes out with either.
    let names = d.join("names.exr");
    let mut channels = named(view_passes(LEFT), |n| n.to_string());
    for (k, name) in [
        "diffuse.R",
        "diffuse.G",
        "diffuse.B",
        "diffuse.A",
        "spec.R",
        "spec.G",
        "spec.B",
    ]
    .into_iter()
    .enumerate()
    {
        channels.push((name.to_string(), noise(n, 80 + k as u32, 0.0, 1.0)));
    }
    channels.extend(named(view_passes(RIGHT), in_view("right")));
    for (k, name) in ["diffuse.right.R", "diffuse.right.G", "diffuse.right.B"]
        .into_iter()
        .enumerate()
    {
        channels.push((name.to_string(), noise(n, 90 + k as u32, 0.0, 1.0)));
    }
    write_views(&names, (W, H), &["left", "right"], channels);
    let written = |view: &str| {
        let out = d.join("out").join(format!("names-{view}.exr"));
        let o = blur(&s(&names), &out, &["--view", view]);
        assert!(o.status.success(), "{view}: {}", stderr(&o));
        let mut names: Vec<String> = read_exr_reference(&out)
            .into_iter()
            .map(|(n, _)| n)
            .collect();
        names.sort();
        names
    };
    let base = ["A", "B", "G", "R", "Z", "velocity.X", "velocity.Y"];
    let with = |extra: &[&str]| {
        let mut all: Vec<String> = base.iter().chain(extra).map(|n| n.to_string()).collect();
        all.sort();
        all
    };
    let spec = ["spec.B", "spec.G", "spec.R"];
    let diffuse = ["diffuse.B", "diffuse.G", "diffuse.R"];
    assert_eq!(written("right"), with(&[&diffuse[..], &spec[..]].concat()));
    assert_eq!(
        written("left"),
        with(&[&diffuse[..], &["diffuse.A"], &spec[..]].concat())
    );
}

#[test]
fn an_unknown_view_stops_the_run_listing_the_views_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let stereo = d.join("stereo.exr");
    single_part_stereo(&stereo);
    let out = d.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("keep.txt"), "already here").unwrap();
    let before = snapshot(&out);
    let o = blur(&s(&stereo), &out.join("o.exr"), &["--view", "centre"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    for needle in [
        s(&stereo).as_str(),
        "'centre'",
        "left (default), right",
        "--view",
    ] {
        assert!(err.contains(needle), "'{needle}' not in: {err}");
    }
    assert_eq!(snapshot(&out), before);
}

#[test]
fn a_multi_part_file_whose_first_part_has_no_view_needs_view() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let stereo = d.join("stereo.exr");
    // Against the document's advice, a part of no view comes first: no default view.
    write_parts(
        &stereo,
        (W, H),
        vec![
            Part {
                name: Some("notes"),
                view: None,
                multi_view: None,
                channels: vec![("notes.N".to_string(), vec![0.5; W * H])],
            },
            Part {
                name: Some("rgb-left"),
                view: Some("left"),
                multi_view: None,
                channels: named(view_passes(LEFT), |n| n.to_string()),
            },
            Part {
                name: Some("rgb-right"),
                view: Some("right"),
                multi_view: None,
                channels: named(view_passes(RIGHT), |n| n.to_string()),
            },
        ],
    );
    let out = d.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let before = snapshot(&out);
    // A picture holds one view: which one, the file does not say.
    let o = blur(&s(&stereo), &out.join("o.png"), &[]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    for needle in [s(&stereo).as_str(), "left, right", "no default", "--view"] {
        assert!(err.contains(needle), "'{needle}' not in: {err}");
    }
    assert_eq!(snapshot(&out), before);

    // info describes the file, and matches presets only once a view is chosen.
    let o = shutter(&["info", &s(&stereo)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    assert!(
        text.contains("no default view (its first part has no view attribute)"),
        "{text}"
    );
    assert!(text.contains("choose a view with --view"), "{text}");
    let o = shutter(&["info", "--json", &s(&stereo)]);
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(json["files"][0]["suggestion"].is_null());
    assert!(json["files"][0]["views"]["default"].is_null());

    let (left, right) = mono(d);
    let o = blur(&left, &out.join("mono-left.exr"), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = blur(&s(&stereo), &out.join("o.exr"), &["--view", "right"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = blur(&right, &out.join("mono.exr"), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_same_image(&out.join("o.exr"), &out.join("mono.exr"));

    // An EXR of every view needs no default: it is written with a view's part first, as
    // OpenEXR asks (a part of no view may not come first), the part of no view after.
    let o = blur(&s(&stereo), &out.join("every.exr"), &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let layers = crate::support::read_exr_layers(&out.join("every.exr"));
    let parts: Vec<(Option<String>, Option<String>)> = (layers.iter())
        .map(|l| {
            let text = |t: &Option<exr::meta::attribute::Text>| t.as_ref().map(|t| t.to_string());
            (
                text(&l.attributes.layer_name),
                text(&l.attributes.view_name),
            )
        })
        .collect();
    let named = |n: &str, v: Option<&str>| (Some(n.to_string()), v.map(String::from));
    assert_eq!(
        parts,
        [
            named("rgb-left", Some("left")),
            named("notes", None),
            named("rgb-right", Some("right"))
        ]
    );
    assert_same_image(&out.join("every.exr"), &out.join("mono-left.exr"));
}

#[test]
fn dof_reads_the_view_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let stereo = d.join("stereo.exr");
    single_part_stereo(&stereo);
    let (_, right) = mono(d);
    let lens = [
        "--focal-length",
        "200",
        "--f-stop",
        "1",
        "--focus-distance",
        "1",
    ];
    for (input, out, view) in [(s(&stereo), "right.exr", true), (right, "mono.exr", false)] {
        let out = s(&d.join("out").join(out));
        let mut args = vec!["dof", "--color", &input, "-o", &out];
        args.extend(lens);
        if view {
            args.extend(["--view", "right"]);
        }
        let o = shutter(&args);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let out = d.join("out");
    assert_same_image(&out.join("right.exr"), &out.join("mono.exr"));
    // Depth of field changed the frame: the comparison is not of two copies of the input.
    assert_ne!(
        read_exr_reference(&out.join("mono.exr")),
        read_exr_reference(&d.join("right.exr"))
            .into_iter()
            .filter(|(n, _)| ["A", "B", "G", "R"].contains(&n.as_str()))
            .collect::<Vec<_>>()
    );
}

#[test]
fn view_on_files_without_views_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (left, _) = mono(d);
    let o = blur(&left, &d.join("o.exr"), &["--view", "right", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let warnings = report["warnings"].to_string();
    assert!(warnings.contains("no input file holds views"), "{warnings}");
}

#[test]
fn info_shows_the_views_and_matches_presets_in_the_view_asked_for() {
    let dir = tempfile::tempdir().unwrap();
    let stereo = dir.path().join("stereo.exr");
    single_part_stereo(&stereo);
    let o = shutter(&["info", &s(&stereo)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for needle in [
        "views:          left (default), right; presets matched in view left",
        "right.R",
        "view right",
        "suggested:      shutter",
    ] {
        assert!(text.contains(needle), "'{needle}' not in:\n{text}");
    }
    let o = shutter(&["info", "--json", "--view", "right", &s(&stereo)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(
        json["files"][0]["views"]["names"],
        serde_json::json!(["left", "right"])
    );
    assert_eq!(json["files"][0]["views"]["default"], "left");
    assert_eq!(json["files"][0]["views"]["read"], "right");
    assert_eq!(json["files"][0]["suggestion"]["preset"], "shutter");
    // In view right, shutter reads right's colour, depth and velocity: 7 channels.
    assert_eq!(json["files"][0]["suggestion"]["matched"], 7);

    let o = shutter(&["info", "--view", "centre", &s(&stereo)]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("left (default), right"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn views_of_other_windows_and_a_part_of_no_view_first_come_out_each_at_its_window() {
    // Parts: IDs of no view first (overscan, u32 over 2²⁴), the left view at the frame, the
    // right view on a window of its own, and a left part of light and IDs on another window.
    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::math::Vec2;
    use exr::meta::attribute::{IntegerBounds, Text};
    use exr::meta::header::{ImageAttributes, LayerAttributes};
    use exr::prelude::WritableImage;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ids = |n: usize| {
        (0..n as u32)
            .map(|i| 0x8000_0001 + 7 * i)
            .collect::<Vec<u32>>()
    };
    let layer = |name: &str, view: Option<&str>, (x, y), (w, h), channels: Vec<AnyChannel<_>>| {
        let mut attributes = LayerAttributes::named(name);
        attributes.view_name = view.map(Text::from);
        attributes.layer_position = Vec2(x, y);
        Layer::new(
            (w, h),
            attributes,
            Encoding::FAST_LOSSLESS,
            AnyChannels::sort(channels.into()),
        )
    };
    let passes = |(w, h): (usize, usize), seed: u32| -> Vec<AnyChannel<FlatSamples>> {
        let n = w * h;
        let mut list: Vec<(&str, Vec<f32>)> = vec![
            ("R", noise(n, seed, 0.0, 1.0)),
            ("G", noise(n, seed + 1, 0.0, 1.0)),
            ("B", noise(n, seed + 2, 0.0, 1.0)),
            ("Z", noise(n, seed + 3, 1.0, 5.0)),
            ("velocity.X", noise(n, seed + 4, -6.0, 6.0)),
            ("velocity.Y", noise(n, seed + 5, -3.0, 3.0)),
        ];
        list.push(("A", vec![1.0; n]));
        (list.into_iter())
            .map(|(c, p)| AnyChannel::new(c, FlatSamples::F32(p)))
            .collect()
    };
    let (sw, sh) = (20, 12);
    let mut spec: Vec<AnyChannel<FlatSamples>> = ["spec.R", "spec.G", "spec.B"]
        .into_iter()
        .enumerate()
        .map(|(k, c)| AnyChannel::new(c, FlatSamples::F32(noise(sw * sh, 30 + k as u32, 0.0, 1.0))))
        .collect();
    spec.push(AnyChannel::new("id2", FlatSamples::U32(ids(sw * sh))));
    let image = Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions((W, H))))
        .with_layer(layer(
            "ids",
            None,
            (-4, -4),
            (W + 8, H + 8),
            vec![AnyChannel::new(
                "id",
                FlatSamples::U32(ids((W + 8) * (H + 8))),
            )],
        ))
        .with_layer(layer(
            "left",
            Some("left"),
            (0, 0),
            (W, H),
            passes((W, H), LEFT),
        ))
        .with_layer(layer(
            "right",
            Some("right"),
            (4, 3),
            (20, 16),
            passes((20, 16), RIGHT),
        ))
        .with_layer(layer("spec_left", Some("left"), (-10, -6), (sw, sh), spec));
    let stereo = d.join("stereo.exr");
    image.write().to_file(&stereo).unwrap();
    let out = d.join("out.exr");
    let o = blur(&s(&stereo), &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let layers = crate::support::read_exr_layers(&out);
    let part = |name: &str| crate::support::part_named(&layers, name);
    let u32s = |l: &Layer<AnyChannels<FlatSamples>>, c: &str| match &(l.channel_data.list.iter())
        .find(|ch| ch.name.to_string() == c)
        .unwrap()
        .sample_data
    {
        FlatSamples::U32(v) => v.clone(),
        other => panic!("{c} is not u32: {other:?}"),
    };
    // A view's part first; each part at its window.
    let first = layers[0]
        .attributes
        .view_name
        .as_ref()
        .map(|t| t.to_string());
    assert_eq!(first.as_deref(), Some("left"));
    let right = part("right");
    assert_eq!(
        (right.attributes.layer_position, right.size),
        (Vec2(4, 3), Vec2(20, 16))
    );
    let id = part("ids");
    assert_eq!(
        (id.attributes.layer_position, id.size),
        (Vec2(-4, -4), Vec2(W + 8, H + 8))
    );
    assert_eq!(u32s(id, "id"), ids((W + 8) * (H + 8)));
    // The left part of light is placed on left's window, its IDs placed to the bit.
    let spec = part("spec_left");
    assert_eq!(
        (spec.attributes.layer_position, spec.size),
        (Vec2(0, 0), Vec2(W, H))
    );
    let placed = u32s(spec, "id2");
    let stored = ids(sw * sh);
    for y in 0..H {
        for x in 0..W {
            let want = if x < sw - 10 && y < sh - 6 {
                stored[(y + 6) * sw + x + 10]
            } else {
                0
            };
            assert_eq!(placed[y * W + x], want, "id2 at ({x}, {y})");
        }
    }
    // The right view alone gives the same beauty as the right part of every view.
    let alone = d.join("right.exr");
    let o = blur(&s(&stereo), &alone, &["--view", "right"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let beauty_of = |l: &Layer<AnyChannels<FlatSamples>>| -> Vec<Vec<f32>> {
        (l.channel_data.list.iter())
            .filter(|c| ["R", "G", "B"].contains(&c.name.to_string().as_str()))
            .map(|c| c.sample_data.values_as_f32().collect())
            .collect()
    };
    let alone_layers = crate::support::read_exr_layers(&alone);
    let alone_right = (alone_layers.iter())
        .find(|l| {
            l.channel_data
                .list
                .iter()
                .any(|c| c.name.to_string() == "R")
        })
        .unwrap();
    assert_eq!(beauty_of(alone_right), beauty_of(right));
    // A rerun with --skip-existing finds it whole; an output of one view is not.
    let o = blur(&s(&stereo), &out, &["--skip-existing", "--json"]);
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(report["frames_skipped"], 1, "{report}");
    let o = blur(&s(&stereo), &alone, &["--skip-existing", "--json"]);
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert_eq!(report["frames_skipped"], 0, "{report}");
    assert!(
        report["warnings"]
            .to_string()
            .contains("does not hold the view"),
        "{report}"
    );
}

/// One view's passes as Blender names them in a multilayer EXR: `ViewLayer.Combined.R`, ...
fn blender_view(seed: u32) -> Vec<(String, Vec<f32>)> {
    let n = W * H;
    let vector = |v: f32| vec![v; n];
    let mut passes = vec![("ViewLayer.Combined.A".to_string(), vec![1.0; n])];
    for (i, c) in ["R", "G", "B"].into_iter().enumerate() {
        let plane = noise(n, seed + i as u32, 0.0, 1.0);
        passes.push((format!("ViewLayer.Combined.{c}"), plane));
    }
    passes.push(("ViewLayer.Depth.Z".into(), noise(n, seed + 3, 1.0, 5.0)));
    // Blender's Vector: to the previous frame in X, Y and to the next in Z, W (a steady
    // sideways motion).
    for (c, v) in [("X", -4.0), ("Y", 1.0), ("Z", 4.0), ("W", -1.0)] {
        passes.push((format!("ViewLayer.Vector.{c}"), vector(v)));
    }
    passes
}

/// The channels of `passes` whose names begin with `prefix`.
fn of_pass(passes: &[(String, Vec<f32>)], prefix: &str) -> Vec<(String, Vec<f32>)> {
    let prefix = format!("{prefix}.");
    passes
        .iter()
        .filter(|(n, _)| n.starts_with(&prefix))
        .cloned()
        .collect()
}

/// A part of an EXR output: its name, its view and its channels.
type OutPart = (Option<String>, Option<String>, Vec<(String, Vec<f32>)>);

/// A part's channels, names and values, in its order.
fn channels_of(
    layer: exr::image::Layer<exr::image::AnyChannels<exr::image::FlatSamples>>,
) -> Vec<(String, Vec<f32>)> {
    (layer.channel_data.list.into_iter())
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect()
}

/// The parts of an EXR output, in order.
fn parts_of(path: &Path) -> Vec<OutPart> {
    crate::support::read_exr_layers(path)
        .into_iter()
        .map(|l| {
            let a = &l.attributes;
            let name = a.layer_name.as_ref().map(|t| t.to_string());
            let view = a.view_name.as_ref().map(|t| t.to_string());
            (name, view, channels_of(l))
        })
        .collect()
}

/// A stereo render as Blender 5 writes it (a multilayer EXR of views): a part a pass a view,
/// named `ViewLayer.Combined-left`, its `view` attribute `left`, its channels
/// `ViewLayer.Combined.R` (which do not begin with the part's name). Read with the `blender`
/// preset, each view blurs as the same passes in a file of one view do (QA: the part's name
/// made each channel also `ViewLayer.Combined-left.ViewLayer.Combined.R`, a second view
/// layer, and the run stopped asking for `--layer`); `--view right` writes a file of one
/// view whose parts are named as Blender names a mono render's (`ViewLayer.Combined`), so
/// Blender finds the view layer `ViewLayer` in it again.
#[test]
fn blenders_stereo_render_reads_by_view_and_one_view_comes_out_named_as_a_mono_render() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (left, right) = (blender_view(LEFT), blender_view(RIGHT));
    let stereo = d.join("stereo.exr");
    let mut parts = Vec::new();
    for (pass, name_left, name_right) in [
        (
            "ViewLayer.Combined",
            "ViewLayer.Combined-left",
            "ViewLayer.Combined-right",
        ),
        (
            "ViewLayer.Depth",
            "ViewLayer.Depth-left",
            "ViewLayer.Depth-right",
        ),
        (
            "ViewLayer.Vector",
            "ViewLayer.Vector-left",
            "ViewLayer.Vector-right",
        ),
    ] {
        parts.push(part(
            Some(name_left),
            Some("left"),
            None,
            of_pass(&left, pass),
        ));
        parts.push(part(
            Some(name_right),
            Some("right"),
            None,
            of_pass(&right, pass),
        ));
    }
    write_parts(&stereo, (W, H), parts);
    let (mono_left, mono_right) = (d.join("mono-left.exr"), d.join("mono-right.exr"));
    write_parts(&mono_left, (W, H), vec![part(None, None, None, left)]);
    write_parts(&mono_right, (W, H), vec![part(None, None, None, right)]);
    let run = |input: &Path, out: &str, extra: &[&str]| {
        let out = d.join("out").join(out);
        let mut args = vec!["--preset", "blender"];
        args.extend(extra);
        let o = blur(&s(input), &out, &args);
        assert!(o.status.success(), "{}: {}", out.display(), stderr(&o));
        parts_of(&out)
    };
    let both = run(&stereo, "both.exr", &[]);
    let one = run(&stereo, "right.exr", &["--view", "right"]);
    let alone_left = run(&mono_left, "mono-left.exr", &[]);
    let alone_right = run(&mono_right, "mono-right.exr", &[]);
    let combined = |parts: &[OutPart], name: Option<&str>| {
        let found = parts.iter().find(|(n, _, _)| n.as_deref() == name);
        let (_, _, channels) = found.unwrap_or_else(|| panic!("no part {name:?} in {parts:?}"));
        of_pass(channels, "ViewLayer.Combined")
    };
    // Each view of the stereo output, and the one view, as that view alone gives it.
    let mono_beauty = |parts: &[OutPart]| of_pass(&parts[0].2, "ViewLayer.Combined");
    assert_eq!(
        combined(&both, Some("ViewLayer.Combined-left")),
        mono_beauty(&alone_left)
    );
    assert_eq!(
        combined(&both, Some("ViewLayer.Combined-right")),
        mono_beauty(&alone_right)
    );
    assert_ne!(
        mono_beauty(&alone_left),
        of_pass(&blender_view(LEFT), "ViewLayer.Combined")
    );
    let views: Vec<_> = both
        .iter()
        .map(|(n, v, _)| (n.clone(), v.clone()))
        .collect();
    assert_eq!(views.len(), 6, "{views:?}");
    assert!(views.iter().all(|(n, v)| n
        .as_ref()
        .unwrap()
        .ends_with(&format!("-{}", v.as_ref().unwrap()))));
    // One view: a file of one view, its parts named as a mono render's.
    let names: Vec<_> = one.iter().map(|(n, v, _)| (n.clone(), v.clone())).collect();
    let plain = |n: &str| (Some(n.to_string()), None);
    assert_eq!(
        names,
        [
            plain("ViewLayer.Combined"),
            plain("ViewLayer.Depth"),
            plain("ViewLayer.Vector")
        ]
    );
    assert_eq!(
        combined(&one, Some("ViewLayer.Combined")),
        mono_beauty(&alone_right)
    );
}

/// A view written as a file of one view (`--view right`) keeps each of its channels' pixel
/// types as stored in that view: `right.Z` half (the default view's `Z` is float), and
/// `id.right.v` u32 with every ID exact. Each output channel's type was looked up by its output
/// name (`Z`, `id.v`) in the input header: `Z` came out float as the other view's, and the
/// IDs, a name no input channel has, as float, every ID over 2²⁴ rounded.
#[test]
fn a_view_written_alone_keeps_its_own_channels_pixel_types() {
    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::meta::attribute::{IntegerBounds, Text};
    use exr::meta::header::{ImageAttributes, LayerAttributes};
    use exr::prelude::{f16, WritableImage};
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let ids: Vec<u32> = (0..n as u32).map(|i| (1 << 24) + 1 + i).collect();
    let f32s = |name: &str, seed: u32, lo: f32, hi: f32| {
        AnyChannel::new(Text::from(name), FlatSamples::F32(noise(n, seed, lo, hi)))
    };
    let halves = |name: &str, seed: u32, lo: f32, hi: f32| {
        let values = noise(n, seed, lo, hi)
            .into_iter()
            .map(f16::from_f32)
            .collect();
        AnyChannel::new(Text::from(name), FlatSamples::F16(values))
    };
    let channels = vec![
        f32s("R", 1, 0.0, 1.0),
        f32s("G", 2, 0.0, 1.0),
        f32s("B", 3, 0.0, 1.0),
        f32s("Z", 4, 1.0, 5.0),
        f32s("right.R", 5, 0.0, 1.0),
        f32s("right.G", 6, 0.0, 1.0),
        f32s("right.B", 7, 0.0, 1.0),
        halves("right.Z", 8, 1.0, 5.0),
        AnyChannel::new(Text::from("id.right.v"), FlatSamples::U32(ids.clone())),
    ];
    let attributes = LayerAttributes {
        multi_view_names: Some(vec![Text::from("left"), Text::from("right")]),
        ..LayerAttributes::default()
    };
    let image = Image {
        attributes: ImageAttributes::new(IntegerBounds::from_dimensions((W, H))),
        layer_data: Layer::new(
            (W, H),
            attributes,
            Encoding::SMALL_LOSSLESS,
            AnyChannels::sort(channels.into()),
        ),
    };
    let stereo = dir.path().join("stereo.exr");
    image.write().to_file(&stereo).unwrap();
    let out = dir.path().join("right.exr");
    let o = shutter(&[
        "blur",
        "--algorithm",
        "none",
        "--color",
        &s(&stereo),
        "--view",
        "right",
        "-o",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let layers = crate::support::read_exr_layers(&out);
    let channel = |name: &str| {
        layers
            .iter()
            .flat_map(|l| l.channel_data.list.iter())
            .find(|c| c.name.to_string() == name)
            .unwrap_or_else(|| panic!("{name} in the output"))
            .sample_data
            .clone()
    };
    assert!(matches!(channel("Z"), FlatSamples::F16(_)), "Z stays half");
    match channel("id.v") {
        FlatSamples::U32(values) => assert_eq!(values, ids, "every ID exact"),
        other => panic!("id.v is not u32: {other:?}"),
    }
}

/// A stereo render of two view layers (`FG`, `BG`), as Blender 5 writes it: a part a pass a
/// view layer a view (`FG.Combined-left`).
fn stereo_of_two_layers(path: &Path) {
    let mut parts = Vec::new();
    for (view, seed) in [("left", LEFT), ("right", RIGHT)] {
        for (layer, offset) in [("FG", 0), ("BG", 7)] {
            let passes: Vec<(String, Vec<f32>)> = (blender_view(seed + offset).into_iter())
                .map(|(n, p)| (n.replacen("ViewLayer", layer, 1), p))
                .collect();
            for pass in ["Combined", "Depth", "Vector"] {
                let pass = format!("{layer}.{pass}");
                let name = Box::leak(format!("{pass}-{view}").into_boxed_str());
                let view: &'static str = if view == "left" { "left" } else { "right" };
                parts.push(part(Some(name), Some(view), None, of_pass(&passes, &pass)));
            }
        }
    }
    write_parts(path, (W, H), parts);
}

/// A stack of view layers is read from one view. From a stereo file, an EXR output (which
/// without `--view` holds every view) held the default view alone, with a warning that blamed
/// a `--view` not given: the run now stops before anything is written, naming the file and
/// its views and the `--view` that writes each. `--view right` writes that view's stack.
#[test]
fn a_stack_of_a_stereo_file_needs_view_and_writes_nothing_without_it() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let stereo = d.join("stereo.exr");
    stereo_of_two_layers(&stereo);
    let out = d.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let before = snapshot(&out);
    let stack = ["--preset", "blender", "--layers", "FG,BG"];
    let o = blur(&s(&stereo), &out.join("o.exr"), &stack);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    for needle in [
        s(&stereo).as_str(),
        "left, right",
        "--view left",
        "--view right",
    ] {
        assert!(err.contains(needle), "'{needle}' not in: {err}");
    }
    assert_eq!(snapshot(&out), before);
    let mut one = stack.to_vec();
    one.extend(["--view", "right"]);
    let o = blur(&s(&stereo), &out.join("right.exr"), &one);
    assert!(o.status.success(), "{}", stderr(&o));
    let parts = parts_of(&out.join("right.exr"));
    assert_eq!(
        parts[0].0.as_deref(),
        Some("Composite.Combined"),
        "{parts:?}"
    );
}

/// The parts of an EXR output as (view, lossy, channels sorted: name and values), the
/// file's order.
type ViewPart = (Option<String>, bool, Vec<(String, Vec<f32>)>);

fn view_parts(path: &Path) -> Vec<ViewPart> {
    use exr::compression::Compression;
    (crate::support::read_exr_layers(path).into_iter())
        .map(|l| {
            let view = l.attributes.view_name.as_ref().map(|t| t.to_string());
            let lossy = matches!(
                l.encoding.compression,
                Compression::DWAA(_) | Compression::DWAB(_)
            );
            let mut channels = channels_of(l);
            channels.sort_by(|a, b| a.0.cmp(&b.0));
            (view, lossy, channels)
        })
        .collect()
}

/// Blurs `stereo` into `out` with `--compression dwaa` and `extra`, which must succeed.
fn blur_dwaa(stereo: &Path, out: &Path, extra: &[&str]) {
    let o = blur(
        &s(stereo),
        out,
        &[&["--compression", "dwaa"], extra].concat(),
    );
    assert!(o.status.success(), "{out:?}: {}", stderr(&o));
}

/// DWA keeps data in lossless parts of its own, so a single-part stereo file comes out in
/// several parts: then in OpenEXR's multi-part scheme (MultiViewOpenEXR.html), each part
/// holding one view's channels, named without the view, and saying the view in its `view`
/// attribute, none a `multiView`; each view's colour in a DWA part, its depth and vectors in
/// a lossless part of its own, just as that view written alone has them; the default
/// view's part first, the part names unique. (QA L14: every part had `multiView` and none
/// `view`, right's depth in a part `data` beside left's and its vectors in one named
/// `velocity.right`.)
#[test]
fn dwa_writes_a_single_part_stereo_file_in_parts_of_one_view_each() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let stereo = d.join("stereo.exr");
    single_part_stereo(&stereo);
    let run = |out: &Path, extra: &[&str]| blur_dwaa(&stereo, out, extra);
    let every = d.join("every.exr");
    run(&every, &[]);
    let layers = crate::support::read_exr_layers(&every);
    let mut names = Vec::new();
    for layer in &layers {
        let a = &layer.attributes;
        let name = a.layer_name.as_ref().map(|t| t.to_string());
        assert!(a.multi_view_names.is_none(), "{name:?} has multiView");
        assert!(a.view_name.is_some(), "{name:?} has no view");
        assert!(!names.contains(&name), "two parts named {name:?}");
        names.push(name);
    }
    let parts = view_parts(&every);
    assert_eq!(
        parts[0].0.as_deref(),
        Some("left"),
        "the default view first"
    );
    // Each view's parts: what the view written alone holds, bit for bit.
    let channels = |parts: &[ViewPart]| {
        let mut names: Vec<(bool, Vec<String>)> = (parts.iter())
            .map(|(_, lossy, c)| (*lossy, c.iter().map(|c| c.0.clone()).collect()))
            .collect();
        names.sort();
        names
    };
    for view in ["left", "right"] {
        let alone = d.join(format!("{view}.exr"));
        run(&alone, &["--view", view]);
        let mut want = view_parts(&alone);
        for part in &mut want {
            part.0 = Some(view.to_string());
        }
        let mut got: Vec<ViewPart> = (parts.iter())
            .filter(|p| p.0.as_deref() == Some(view))
            .cloned()
            .collect();
        let colour = ["A", "B", "G", "R"].map(String::from).to_vec();
        let data = ["Z", "velocity.X", "velocity.Y"].map(String::from).to_vec();
        assert_eq!(channels(&got), [(false, data), (true, colour)], "{view}");
        got.sort_by_key(|p| p.1);
        want.sort_by_key(|p| p.1);
        assert!(
            got == want,
            "{view}: the values differ from the view written alone"
        );
    }
    // Read back as the same two views, by shutter and by OpenImageIO.
    let o = shutter(&["info", &s(&every)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("left (default), right"),
        "{}",
        stdout(&o)
    );
    if let Some(o) = crate::support::run_tool("oiiotool", &["--info", "-v", "-a", &s(&every)]) {
        let info = String::from_utf8_lossy(&o.stdout);
        assert!(o.status.success(), "{info}");
        assert!(!info.contains("multiView"), "{info}");
        assert_eq!(info.matches("view: \"left\"").count(), 2, "{info}");
        assert_eq!(info.matches("view: \"right\"").count(), 2, "{info}");
    }
}

/// The same layout where the views' channel sets differ: a default view with a layer
/// `diffuse` (R, G, B, A), another view writing that layer as its own but without A
/// (`diffuse.right.R`, G, B), a third with no `diffuse` at all. As the reader reads them,
/// `diffuse.A` is the default view's alone (its layer is one `right` writes as its own)
/// and `diffuse.R`, G, B are no view's but the default's too (no other view reads them):
/// each view's parts, with the parts of no view, hold what that view written alone holds.
/// (Review: `diffuse.A` went to a part of no view, which `right` then read as its own,
/// and `center` gained `diffuse.R`, G, B.)
#[test]
fn dwa_splits_views_whose_channels_differ_as_each_view_reads_them() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let n = W * H;
    let mut channels = named(view_passes(LEFT), |n| n.to_string());
    channels.extend(named(view_passes(RIGHT), in_view("right")));
    channels.extend(named(view_passes(RIGHT + 20), in_view("center")));
    for (k, channel) in ["R", "G", "B", "A"].into_iter().enumerate() {
        channels.push((
            format!("diffuse.{channel}"),
            noise(n, 90 + k as u32, 0.0, 1.0),
        ));
        if channel != "A" {
            let name = format!("diffuse.right.{channel}");
            channels.push((name, noise(n, 95 + k as u32, 0.0, 1.0)));
        }
    }
    let counts =
        dwa_split_as_each_view_reads(d, channels, &["left", "right", "center"], "diffuse.");
    assert_eq!(
        counts,
        [4, 3, 0],
        "diffuse's channels in left, right, center written alone"
    );
}

/// Writes `channels` as one part of `views` (the first the default), blurs it into an EXR
/// with DWA (every view, split into parts by view) and each view alone (`--view V`), and
/// asserts each view's parts with the parts of no view hold what that view alone holds,
/// name for name and bit for bit. Returns, per view, how many channels of the view alone
/// begin with `prefix`.
fn dwa_split_as_each_view_reads(
    d: &Path,
    channels: Vec<(String, Vec<f32>)>,
    views: &'static [&'static str],
    prefix: &str,
) -> Vec<usize> {
    let stereo = d.join("views.exr");
    write_views(&stereo, (W, H), views, channels);
    let run = |out: &Path, extra: &[&str]| blur_dwaa(&stereo, out, extra);
    let every = d.join("every.exr");
    run(&every, &[]);
    let parts = view_parts(&every);
    let sorted = |mut c: Vec<(String, Vec<f32>)>| {
        c.sort_by(|a, b| a.0.cmp(&b.0));
        c
    };
    let names = |c: &[(String, Vec<f32>)]| c.iter().map(|c| c.0.clone()).collect::<Vec<_>>();
    let mut counts = Vec::new();
    for &view in views {
        let alone = d.join(format!("{view}.exr"));
        run(&alone, &["--view", view]);
        let want = sorted(view_parts(&alone).into_iter().flat_map(|p| p.2).collect());
        let got = sorted(
            (parts.iter())
                .filter(|p| p.0.is_none() || p.0.as_deref() == Some(view))
                .flat_map(|p| p.2.clone())
                .collect(),
        );
        assert_eq!(names(&got), names(&want), "{view}");
        assert!(
            got == want,
            "{view}: the values differ from the view written alone"
        );
        counts.push(
            names(&want)
                .iter()
                .filter(|n| n.starts_with(prefix))
                .count(),
        );
    }
    counts
}

/// The same where the layer is the beauty's: `rgba.R`, G, B, A in every view and a `rgba.Z`
/// of no view. `right` writes the `rgba` layer as its own (its beauty), so `rgba.Z` is the
/// default view's alone, as the reader reads it (second review: the writer counted each
/// view's other channels but not its beauty, and put `rgba.Z` in a part of no view).
#[test]
fn dwa_split_counts_each_view_s_beauty_among_its_own_layers() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let n = W * H;
    let mut channels = Vec::new();
    for (view, seed) in [("", LEFT), ("right.", RIGHT)] {
        for (k, c) in ["R", "G", "B", "A"].into_iter().enumerate() {
            let value = if c == "A" {
                vec![1.0; n]
            } else {
                noise(n, seed + k as u32, 0.0, 1.0)
            };
            let name = match view {
                "" => format!("rgba.{c}"),
                _ => format!("rgba.right.{c}"),
            };
            channels.push((name, value));
        }
    }
    channels.push(("rgba.Z".to_string(), noise(n, 70, 1.0, 5.0)));
    // Each view's depth and motion, the passes a blur reads.
    let passes = |seed| view_passes(seed).into_iter().skip(4);
    channels.extend(named(passes(LEFT).collect(), |n| n.to_string()));
    channels.extend(named(passes(RIGHT).collect(), in_view("right")));
    let counts = dwa_split_as_each_view_reads(d, channels, &["left", "right"], "rgba.Z");
    assert_eq!(counts, [1, 0], "rgba.Z in left, right written alone");
}
