//! Each preset reads a synthetic frame written in its renderer's convention back as the
//! canonical values. Positions sit on pixel centres plus whole-pixel motion, so every
//! canonical value is exactly representable and the EXR cases compare bit for bit.

use std::path::Path;

use shutter::frame::Frame;
use shutter::io::passes::{plan_frame, read_frame, Inputs, PlanOptions};
use shutter::io::preset::Preset;
use shutter::io::sequence::PathPattern;
use shutter::Passes;

use crate::support::*;

const W: usize = 11;
const H: usize = 7;

/// The canonical truth: per pixel, where the surface was one frame ago and will be one
/// frame later (pixel centre plus whole-pixel offsets that vary across the image).
struct Truth {
    rgba: [Vec<f32>; 4],
    depth: Vec<f32>,
    prev: [Vec<f32>; 2],
    next: [Vec<f32>; 2],
}

impl Truth {
    /// The colour channels (RGB, with `alpha` A) followed by `rest`, as `write_exr` takes
    /// them.
    fn with_colour<'a>(
        &self,
        alpha: bool,
        rest: Vec<(&'a str, Vec<f32>)>,
    ) -> Vec<(&'a str, Vec<f32>)> {
        let mut channels = vec![
            ("R", self.rgba[0].clone()),
            ("G", self.rgba[1].clone()),
            ("B", self.rgba[2].clone()),
        ];
        if alpha {
            channels.push(("A", self.rgba[3].clone()));
        }
        channels.extend(rest);
        channels
    }

    fn new() -> Truth {
        let n = W * H;
        let mut prev = [vec![0.0; n], vec![0.0; n]];
        let mut next = [vec![0.0; n], vec![0.0; n]];
        for k in 0..n {
            let (x, y) = ((k % W) as f32 + 0.5, (k / W) as f32 + 0.5);
            let (i, j) = ((k % W) as f32, (k / W) as f32);
            prev[0][k] = x - (i - 5.0);
            prev[1][k] = y - (2.0 * j - 6.0);
            next[0][k] = x + (3.0 - j);
            next[1][k] = y + (i - 4.0);
        }
        Truth {
            rgba: [
                noise(n, 11, 0.0, 3.0),
                noise(n, 12, 0.0, 1.0),
                noise(n, 13, 0.0, 1.0),
                noise(n, 14, 0.0, 1.0),
            ],
            depth: noise(n, 15, 0.5, 50.0),
            prev,
            next,
        }
    }

    fn velocity(&self) -> [Vec<f32>; 2] {
        let n = W * H;
        let mut v = [vec![0.0; n], vec![0.0; n]];
        for k in 0..n {
            let (x, y) = ((k % W) as f32 + 0.5, (k / W) as f32 + 0.5);
            v[0][k] = x - self.prev[0][k];
            v[1][k] = y - self.prev[1][k];
        }
        v
    }

    fn check(&self, frame: &Frame, tolerance: f32, what: &str) {
        let color = frame.color.as_ref().unwrap();
        assert_close(&color.r, &self.rgba[0], tolerance, &format!("{what} R"));
        assert_close(&color.g, &self.rgba[1], tolerance, &format!("{what} G"));
        assert_close(&color.b, &self.rgba[2], tolerance, &format!("{what} B"));
        let depth = frame.depth.as_ref().unwrap();
        assert_close(
            depth,
            &self.depth,
            tolerance * 100.0,
            &format!("{what} depth"),
        );
        let v = self.velocity();
        let velocity = frame.velocity.as_ref().unwrap();
        assert_close(
            &velocity.x,
            &v[0],
            tolerance * 64.0,
            &format!("{what} velocity x"),
        );
        assert_close(
            &velocity.y,
            &v[1],
            tolerance * 64.0,
            &format!("{what} velocity y"),
        );
        let prev = frame.prev.as_ref().unwrap();
        assert_close(
            &prev.x,
            &self.prev[0],
            tolerance * 64.0,
            &format!("{what} prev x"),
        );
        assert_close(
            &prev.y,
            &self.prev[1],
            tolerance * 64.0,
            &format!("{what} prev y"),
        );
        let next = frame.next.as_ref().unwrap();
        assert_close(
            &next.x,
            &self.next[0],
            tolerance * 64.0,
            &format!("{what} next x"),
        );
        assert_close(
            &next.y,
            &self.next[1],
            tolerance * 64.0,
            &format!("{what} next y"),
        );
    }
}

fn read_all(preset: &Preset, inputs: &Inputs) -> Frame {
    let options = PlanOptions {
        preset,
        layer: None,
        view: None,
        needs: Passes::ALL,
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let plan = plan_frame(inputs, None, &options).unwrap_or_else(|p| panic!("{p:?}"));
    read_frame(&plan).unwrap()
}

fn inputs(color: &Path) -> Inputs {
    Inputs::color_only(PathPattern::parse(&s(color)).unwrap())
}

fn pixel_centres() -> [Vec<f32>; 2] {
    let n = W * H;
    [
        (0..n).map(|k| (k % W) as f32 + 0.5).collect(),
        (0..n).map(|k| (k / W) as f32 + 0.5).collect(),
    ]
}

#[test]
fn shutter_preset_separate_files() {
    let t = Truth::new();
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    write_exr(&p("C.exr"), W, H, t.with_colour(true, Vec::new()));
    write_exr(&p("Z.exr"), W, H, vec![("Z", t.depth.clone())]);
    let v = t.velocity();
    write_exr(
        &p("V.exr"),
        W,
        H,
        vec![("X", v[0].clone()), ("Y", v[1].clone())],
    );
    write_exr(
        &p("P.exr"),
        W,
        H,
        vec![("R", t.prev[0].clone()), ("G", t.prev[1].clone())],
    );
    write_exr(
        &p("N.exr"),
        W,
        H,
        vec![
            ("x", t.next[0].clone()),
            ("y", t.next[1].clone()),
            ("z", t.depth.clone()),
        ],
    );
    let mut i = inputs(&p("C.exr"));
    i.depth = Some(PathPattern::parse(&s(&p("Z.exr"))).unwrap());
    i.velocity = Some(PathPattern::parse(&s(&p("V.exr"))).unwrap());
    i.prev = Some(PathPattern::parse(&s(&p("P.exr"))).unwrap());
    i.next = Some(PathPattern::parse(&s(&p("N.exr"))).unwrap());
    let frame = read_all(&Preset::builtin("shutter").unwrap(), &i);
    t.check(&frame, 0.0, "shutter");
    assert_exact(
        frame.next.as_ref().unwrap().z.as_ref().unwrap(),
        &t.depth,
        "next z",
    );
}

#[test]
fn shutter_preset_one_multilayer_file() {
    let t = Truth::new();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("all.exr");
    let v = t.velocity();
    write_exr(
        &path,
        W,
        H,
        t.with_colour(
            true,
            vec![
                ("Z", t.depth.clone()),
                ("velocity.X", v[0].clone()),
                ("velocity.Y", v[1].clone()),
                ("prev.X", t.prev[0].clone()),
                ("prev.Y", t.prev[1].clone()),
                ("next.X", t.next[0].clone()),
                ("next.Y", t.next[1].clone()),
            ],
        ),
    );
    let frame = read_all(&Preset::builtin("shutter").unwrap(), &inputs(&path));
    t.check(&frame, 0.0, "shutter multi-layer");
}

#[test]
fn blender_preset() {
    let t = Truth::new();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("blender.exr");
    let c = pixel_centres();
    let n = W * H;
    // Blender: X,Y = p(-1) - p(0), Z,W = p(0) - p(+1), y up.
    let vx: Vec<f32> = (0..n).map(|k| t.prev[0][k] - c[0][k]).collect();
    let vy: Vec<f32> = (0..n).map(|k| -(t.prev[1][k] - c[1][k])).collect();
    let vz: Vec<f32> = (0..n).map(|k| c[0][k] - t.next[0][k]).collect();
    let vw: Vec<f32> = (0..n).map(|k| -(c[1][k] - t.next[1][k])).collect();
    let l = "My Layer";
    let name = |pass: &str| format!("{l}.{pass}");
    let names: Vec<String> = [
        "Combined.R",
        "Combined.G",
        "Combined.B",
        "Combined.A",
        "Depth.Z",
        "Vector.X",
        "Vector.Y",
        "Vector.Z",
        "Vector.W",
    ]
    .iter()
    .map(|p| name(p))
    .collect();
    let planes = vec![
        t.rgba[0].clone(),
        t.rgba[1].clone(),
        t.rgba[2].clone(),
        t.rgba[3].clone(),
        t.depth.clone(),
        vx,
        vy,
        vz,
        vw,
    ];
    write_exr(
        &path,
        W,
        H,
        names.iter().map(|n| n.as_str()).zip(planes).collect(),
    );
    let frame = read_all(&Preset::builtin("blender").unwrap(), &inputs(&path));
    t.check(&frame, 0.0, "blender");
}

#[test]
fn blender_preset_with_two_view_layers_asks_for_one() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.exr");
    let n = W * H;
    let mut channels = Vec::new();
    let names: Vec<String> = ["A", "B"]
        .iter()
        .flat_map(|l| ["R", "G", "B"].map(|c| format!("{l}.Combined.{c}")))
        .collect();
    for name in &names {
        channels.push((name.as_str(), vec![0.5; n]));
    }
    write_exr(&path, W, H, channels);
    let preset = Preset::builtin("blender").unwrap();
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: Passes::COLOR,
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let problems = plan_frame(&inputs(&path), None, &options).unwrap_err();
    assert!(problems[0]
        .to_string()
        .contains("several view layers (A, B)"));
    let options = PlanOptions {
        layer: Some("B"),
        ..options
    };
    assert!(plan_frame(&inputs(&path), None, &options).is_ok());
}

#[test]
fn nuke_preset() {
    let t = Truth::new();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("nuke.exr");
    let c = pixel_centres();
    let n = W * H;
    // Nuke: forward = p(+1) - p(0), backward = p(-1) - p(0), v up.
    let fu: Vec<f32> = (0..n).map(|k| t.next[0][k] - c[0][k]).collect();
    let fv: Vec<f32> = (0..n).map(|k| -(t.next[1][k] - c[1][k])).collect();
    let bu: Vec<f32> = (0..n).map(|k| t.prev[0][k] - c[0][k]).collect();
    let bv: Vec<f32> = (0..n).map(|k| -(t.prev[1][k] - c[1][k])).collect();
    write_exr(
        &path,
        W,
        H,
        t.with_colour(
            true,
            vec![
                ("depth.Z", t.depth.clone()),
                ("forward.u", fu),
                ("forward.v", fv),
                ("backward.u", bu),
                ("backward.v", bv),
            ],
        ),
    );
    let frame = read_all(&Preset::builtin("nuke").unwrap(), &inputs(&path));
    t.check(&frame, 0.0, "nuke");
}

/// Writes a 16-bit PNG from values in [0, 1].
fn write_png16(path: &Path, channels: &[&[f32]]) {
    use image::ImageEncoder;
    let n = W * H;
    let mut bytes = Vec::with_capacity(n * channels.len() * 2);
    for k in 0..n {
        for c in channels {
            let code = (c[k].clamp(0.0, 1.0) * 65535.0).round() as u16;
            bytes.extend(code.to_ne_bytes());
        }
    }
    let color = match channels.len() {
        1 => image::ExtendedColorType::L16,
        3 => image::ExtendedColorType::Rgb16,
        _ => image::ExtendedColorType::Rgba16,
    };
    let file = std::fs::File::create(path).unwrap();
    image::codecs::png::PngEncoder::new(file)
        .write_image(&bytes, W as u32, H as u32, color)
        .unwrap();
}

#[test]
fn painted_preset() {
    let t = Truth::new();
    let preset = Preset::builtin("painted").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let n = W * H;
    // Colour: opaque, sRGB-encoded.
    let srgb: Vec<Vec<f32>> = (0..3)
        .map(|c| {
            t.rgba[c]
                .iter()
                .map(|&v| shutter::io::image::linear_to_srgb(v.min(1.0)))
                .collect()
        })
        .collect();
    write_png16(&p("photo.png"), &[&srgb[0], &srgb[1], &srgb[2]]);
    // Depth: grey 0..1 = near..far.
    let (near, far) = (preset.depth.near.unwrap(), preset.depth.far.unwrap());
    let grey: Vec<f32> = t.depth.iter().map(|d| (d - near) / (far - near)).collect();
    write_png16(&p("depth.png"), &[&grey]);
    // Velocity: (r, g) = v / scale + 0.5, y down.
    let scale = preset.velocity.scale;
    let v = t.velocity();
    let r: Vec<f32> = v[0].iter().map(|v| v / scale + 0.5).collect();
    let g: Vec<f32> = v[1].iter().map(|v| v / scale + 0.5).collect();
    write_png16(&p("velocity.png"), &[&r, &g, &vec![0.0; n]]);

    let mut i = inputs(&p("photo.png"));
    i.depth = Some(PathPattern::parse(&s(&p("depth.png"))).unwrap());
    i.velocity = Some(PathPattern::parse(&s(&p("velocity.png"))).unwrap());
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: Passes {
            next: false,
            ..Passes::ALL
        },
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let plan = plan_frame(&i, None, &options).unwrap();
    let frame = read_frame(&plan).unwrap();
    // 16-bit quantisation: half a code step of 1/65535, times the scale for vectors.
    let step = 0.5 / 65535.0;
    let color = frame.color.as_ref().unwrap();
    let expected_r: Vec<f32> = t.rgba[0].iter().map(|v| v.min(1.0)).collect();
    assert_close(&color.r, &expected_r, 2e-5, "painted R");
    assert_close(
        frame.depth.as_ref().unwrap(),
        &t.depth,
        step * (far - near) * 1.01,
        "painted depth",
    );
    let velocity = frame.velocity.as_ref().unwrap();
    assert_close(
        &velocity.x,
        &v[0],
        step * scale * 1.01,
        "painted velocity x",
    );
    assert_close(
        &velocity.y,
        &v[1],
        step * scale * 1.01,
        "painted velocity y",
    );
    let prev = frame.prev.as_ref().unwrap();
    assert_close(&prev.x, &t.prev[0], step * scale * 1.01, "painted prev x");
}

#[test]
fn painted_mid_grey_is_exactly_still_at_8_bits() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("v.png");
    image::save_buffer(
        &path,
        &[127, 128, 0, 128, 127, 0],
        2,
        1,
        image::ColorType::Rgb8,
    )
    .unwrap();
    let preset = Preset::builtin("painted").unwrap();
    let color = dir.path().join("c.png");
    image::save_buffer(&color, &[0; 6], 2, 1, image::ColorType::Rgb8).unwrap();
    let mut i = inputs(&color);
    i.velocity = Some(PathPattern::parse(&s(&path)).unwrap());
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: Passes {
            velocity: true,
            ..Passes::default()
        },
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let frame = read_frame(&plan_frame(&i, None, &options).unwrap()).unwrap();
    let v = frame.velocity.unwrap();
    assert_eq!(v.x, [0.0, 0.0]);
    assert_eq!(v.y, [0.0, 0.0]);
}

#[test]
fn a_custom_preset_expresses_normalised_forward_vectors_with_y_up() {
    // A renderer storing forward motion 0..1 with 0.5 = still, in fractions of the screen,
    // y up, in channels mv.r / mv.g: written as a preset file, as the README shows.
    let dir = tempfile::tempdir().unwrap();
    let preset_path = dir.path().join("engine.toml");
    std::fs::write(
        &preset_path,
        r#"
description = "test engine: forward vectors, 0.5 = still, normalised, y up"
[next]
channels = [["mv.r", "mv.g"]]
meaning = "to_next"
zero = 0.5
scale = 0.5
units = "normalized"
y_up = true
"#,
    )
    .unwrap();
    let preset = Preset::load(&[s(&preset_path)]).unwrap();
    let t = Truth::new();
    let c = pixel_centres();
    let n = W * H;
    // stored = (p(+1) - p0) / (scale * size) + zero, y negated. Chosen so values are exact:
    // offsets are whole pixels, W = 11 and H = 7 make fractions inexact, so compare closely.
    let r: Vec<f32> = (0..n)
        .map(|k| (t.next[0][k] - c[0][k]) / (0.5 * W as f32) + 0.5)
        .collect();
    let g: Vec<f32> = (0..n)
        .map(|k| -(t.next[1][k] - c[1][k]) / (0.5 * H as f32) + 0.5)
        .collect();
    let path = dir.path().join("f.exr");
    write_exr(
        &path,
        W,
        H,
        t.with_colour(false, vec![("mv.r", r), ("mv.g", g)]),
    );
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: Passes {
            color: true,
            next: true,
            velocity: true,
            ..Passes::default()
        },
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let plan = plan_frame(&inputs(&path), None, &options).unwrap();
    assert!(
        plan.warnings.iter().any(|w| w.contains("linear motion")),
        "velocity from forward vectors is flagged: {:?}",
        plan.warnings
    );
    let frame = read_frame(&plan).unwrap();
    let next = frame.next.unwrap();
    assert_close(&next.x, &t.next[0], 1e-5, "next x");
    assert_close(&next.y, &t.next[1], 1e-5, "next y");
    // Velocity approximated as p(+1) - p0.
    let velocity = frame.velocity.unwrap();
    let expected: Vec<f32> = (0..n).map(|k| t.next[0][k] - c[0][k]).collect();
    assert_close(&velocity.x, &expected, 1e-5, "velocity x");
}

/// A luminance-only EXR (OpenEXR's `Y`, with `A`) reads as grey under any preset, with a
/// note; one with chroma (`RY`, `BY`) is not grey and is not read as if it were.
#[test]
fn a_luminance_only_exr_reads_as_grey_with_a_note() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    let y: Vec<f32> = (0..n).map(|k| k as f32 * 0.25 - 3.0).collect();
    let a: Vec<f32> = (0..n).map(|k| (k % 5) as f32 * 0.25).collect();
    let path = dir.path().join("grey.exr");
    write_exr(&path, W, H, vec![("A", a.clone()), ("Y", y.clone())]);
    for name in ["shutter", "blender", "nuke"] {
        let preset = Preset::builtin(name).unwrap();
        let options = PlanOptions {
            preset: &preset,
            layer: None,
            view: None,
            needs: Passes::COLOR,
            max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
        };
        let plan = plan_frame(&inputs(&path), None, &options).unwrap_or_else(|p| panic!("{p:?}"));
        assert!(
            plan.warnings
                .iter()
                .any(|w| w.contains("luminance channel Y as grey")),
            "{name}: {:?}",
            plan.warnings
        );
        let color = read_frame(&plan).unwrap().color.unwrap();
        assert_eq!(color.r, y, "{name}");
        assert_eq!(color.g, y, "{name}");
        assert_eq!(color.b, y, "{name}");
        assert_eq!(color.a.as_deref(), Some(&a[..]), "{name}");
    }

    // Through the CLI: the note among the run's warnings, and the output a luminance file
    // again: its Y as it was (nothing moves), no R, G, B it did not have.
    let out = dir.path().join("out.exr");
    let o = shutter(&["blur", "--color", &s(&path), "-o", &s(&out), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(
        report["warnings"].to_string().contains("as grey"),
        "{}",
        stdout(&o)
    );
    let written = read_exr_reference(&out);
    let plane = &written.iter().find(|(n, _)| n == "Y").unwrap().1;
    assert_eq!(plane, &y, "Y");
    for ch in ["R", "G", "B"] {
        assert!(written.iter().all(|(n, _)| n != ch), "{ch} written");
    }

    // Luminance with chroma is refused, not read as grey.
    let chroma = dir.path().join("yc.exr");
    let zero = vec![0.0; n];
    write_exr(
        &chroma,
        W,
        H,
        vec![("BY", zero.clone()), ("RY", zero), ("Y", y.clone())],
    );
    let o = shutter(&["blur", "--color", &s(&chroma), "-o", &s(&out)]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(!stderr(&o).contains("as grey"), "{}", stderr(&o));
}

/// RSMB's Max Displace in the tests, pixels: larger than every offset of [`Truth`].
const MAX_DISPLACE: f32 = 8.0;

/// A preset file giving the Max Displace for every section, as presets/rsmb.toml tells a
/// user to write; loaded after `rsmb`.
fn rsmb_preset(dir: &Path) -> Preset {
    let path = dir.join("max-displace.toml");
    let text: String = ["velocity", "prev", "next"]
        .iter()
        .map(|pass| format!("[{pass}]\nmax_displace = {MAX_DISPLACE:?}\n"))
        .collect();
    std::fs::write(&path, text).unwrap();
    Preset::load(&["rsmb".into(), s(&path)]).unwrap()
}

/// RE:Vision's encoder, verbatim from its maths page: `fred = ((x/MaxDisplace)+1)*0.5`,
/// clamped to [0, 1], `red = fred*254.0 + 0.5` (8-bit; `* 65534.0 + 0.5` at 16 bits),
/// truncated to an integer.
fn rsmb_code(offset: f32, top: f32) -> u16 {
    let f = ((offset / MAX_DISPLACE + 1.0) * 0.5).clamp(0.0, 1.0);
    (f * top + 0.5) as u16
}

/// Writes RSMB vectors (canonical offsets, y down) as an 8-bit PNG or a 16-bit TIFF, RGBA,
/// with y up and `alpha` given as codes out of the full scale (255 or 65535).
fn write_rsmb(path: &Path, bits: u8, dx: &[f32], dy: &[f32], alpha: &[u16]) {
    let (top, full) = if bits == 8 {
        (254.0, 255)
    } else {
        (65534.0, 65535)
    };
    let mut codes = Vec::with_capacity(W * H * 4);
    for k in 0..W * H {
        codes.extend([
            rsmb_code(dx[k], top),
            rsmb_code(-dy[k], top),
            full / 2, // blue: ignored
            alpha[k],
        ]);
    }
    if bits == 8 {
        let bytes: Vec<u8> = codes.iter().map(|&c| c as u8).collect();
        image::save_buffer(path, &bytes, W as u32, H as u32, image::ColorType::Rgba8).unwrap();
    } else {
        image::ImageBuffer::<image::Rgba<u16>, _>::from_raw(W as u32, H as u32, codes)
            .unwrap()
            .save(path)
            .unwrap();
    }
}

/// Offsets of positions from the pixel centres.
fn offsets(positions: &[Vec<f32>; 2]) -> [Vec<f32>; 2] {
    let c = pixel_centres();
    [0, 1].map(|a| (0..W * H).map(|k| positions[a][k] - c[a][k]).collect())
}

/// Reads colour, velocity, prev and next with the vector files given.
fn read_rsmb(
    preset: &Preset,
    color: &Path,
    velocity: &Path,
    prev: &Path,
    next: &Path,
) -> (Frame, Vec<String>) {
    let mut i = inputs(color);
    i.velocity = Some(PathPattern::parse(&s(velocity)).unwrap());
    i.prev = Some(PathPattern::parse(&s(prev)).unwrap());
    i.next = Some(PathPattern::parse(&s(next)).unwrap());
    let options = PlanOptions {
        preset,
        layer: None,
        view: None,
        needs: Passes {
            depth: false,
            ..Passes::ALL
        },
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let plan = plan_frame(&i, None, &options).unwrap_or_else(|p| panic!("{p:?}"));
    shutter::io::passes::read_frame_noted(&plan).unwrap()
}

/// RSMB's 8- and 16-bit encodings of known backward and forward motion read back as the
/// canonical p(-1), p(+1) and velocity, to the encoding's precision: the encoder rounds to
/// the nearest code (`+ 0.5` then truncation), and a code step is 2·MaxDisplace/254 =
/// MaxDisplace/127 px at 8 bits and MaxDisplace/32767 px at 16 bits, so every read offset
/// is within half a step of the truth (plus 1e-5 for the f32 sums with the pixel centre).
/// The still code (127, 32767) reads as exactly 0: a decode with 255 or 65535 in place of
/// 254 or 65534 fails that, and overshoots the bound near ±MaxDisplace.
#[test]
fn rsmb_preset_8_and_16_bit() {
    let t = Truth::new();
    let dir = tempfile::tempdir().unwrap();
    let preset = rsmb_preset(dir.path());
    let color = dir.path().join("C.exr");
    write_exr(&color, W, H, t.with_colour(false, Vec::new()));
    let backward = offsets(&t.prev);
    let forward = offsets(&t.next);
    for (bits, still, ext) in [(8u8, 127.0f32, "png"), (16, 32767.0, "tif")] {
        let full = vec![if bits == 8 { 255 } else { 65535 }; W * H];
        let b = dir.path().join(format!("backward{bits}.{ext}"));
        let f = dir.path().join(format!("forward{bits}.{ext}"));
        write_rsmb(&b, bits, &backward[0], &backward[1], &full);
        write_rsmb(&f, bits, &forward[0], &forward[1], &full);
        let (frame, notes) = read_rsmb(&preset, &color, &b, &b, &f);
        assert!(notes.is_empty(), "{bits}-bit: {notes:?}");
        let bound = 0.5 * MAX_DISPLACE / still + 1e-5;
        let what = |pass: &str| format!("rsmb {bits}-bit {pass}");
        let prev = frame.prev.as_ref().unwrap();
        let next = frame.next.as_ref().unwrap();
        let velocity = frame.velocity.as_ref().unwrap();
        let v = t.velocity();
        assert_close(&prev.x, &t.prev[0], bound, &what("prev x"));
        assert_close(&prev.y, &t.prev[1], bound, &what("prev y"));
        assert_close(&next.x, &t.next[0], bound, &what("next x"));
        assert_close(&next.y, &t.next[1], bound, &what("next y"));
        assert_close(&velocity.x, &v[0], bound, &what("velocity x"));
        assert_close(&velocity.y, &v[1], bound, &what("velocity y"));
        // Still where the truth is still, exactly.
        for k in 0..W * H {
            if v[0][k] == 0.0 {
                assert_eq!(velocity.x[k], 0.0, "{} at {k}", what("still x"));
            }
            if v[1][k] == 0.0 {
                assert_eq!(velocity.y[k], 0.0, "{} at {k}", what("still y"));
            }
        }
        assert!(v[0].contains(&0.0) && v[1].contains(&0.0));
    }
}

/// Pixels whose alpha is below full-on (0, or one code short of it) hold garbage vectors
/// (the most negative code); they read as the motion of the nearest pixel with full-on
/// alpha, never as their stored value or as zero. Without the preset's validity_alpha the
/// same file reads the garbage. With no valid pixel the frame reads as still, with a note.
#[test]
fn rsmb_invalid_alpha_takes_the_nearest_valid_motion() {
    let dir = tempfile::tempdir().unwrap();
    let preset = rsmb_preset(dir.path());
    let color = dir.path().join("C.exr");
    let n = W * H;
    write_exr(
        &color,
        W,
        H,
        vec![
            ("R", vec![0.5; n]),
            ("G", vec![0.5; n]),
            ("B", vec![0.5; n]),
            ("Z", vec![10.0; n]),
        ],
    );
    // Backward offsets: columns 0..=3 move by a, columns 6..=10 by b; columns 4 and 5 and
    // pixel (8, 3) are invalid. Column 4 is nearest to column 3 (a), column 5 to column 6
    // (b), pixel (8, 3) to its own region's neighbours (b).
    let (a, b) = ((3.0f32, -2.0f32), (-4.0f32, 1.0f32));
    let invalid = |k: usize| matches!(k % W, 4 | 5) || k == 3 * W + 8;
    let mut dx = vec![0.0; n];
    let mut dy = vec![0.0; n];
    let mut alpha = vec![255u16; n];
    let mut expected = [vec![0.0; n], vec![0.0; n]];
    for k in 0..n {
        let side = if k % W <= 4 { a } else { b };
        (expected[0][k], expected[1][k]) = side;
        if invalid(k) {
            // Garbage: code 0 in red and green (y is stored up).
            (dx[k], dy[k]) = (-MAX_DISPLACE, MAX_DISPLACE);
            alpha[k] = if k % 2 == 0 { 0 } else { 254 };
        } else {
            (dx[k], dy[k]) = side;
        }
    }
    let path = dir.path().join("backward.png");
    write_rsmb(&path, 8, &dx, &dy, &alpha);
    let bound = 0.5 * MAX_DISPLACE / 127.0 + 1e-5;

    let (frame, notes) = read_rsmb(&preset, &color, &path, &path, &path);
    assert!(
        notes.iter().any(|n| n.contains("nearest valid vector")),
        "{notes:?}"
    );
    let read = offsets(&{
        let prev = frame.prev.as_ref().unwrap();
        [prev.x.clone(), prev.y.clone()]
    });
    assert_close(&read[0], &expected[0], bound, "filled prev x");
    assert_close(&read[1], &expected[1], bound, "filled prev y");
    let velocity = frame.velocity.as_ref().unwrap();
    let minus = |p: &[f32]| p.iter().map(|v| -v).collect::<Vec<f32>>();
    assert_close(
        &velocity.x,
        &minus(&expected[0]),
        bound,
        "filled velocity x",
    );
    assert_close(
        &velocity.y,
        &minus(&expected[1]),
        bound,
        "filled velocity y",
    );

    // Through the CLI: the note is among the run's warnings.
    let out = dir.path().join("out.exr");
    let md = dir.path().join("max-displace.toml");
    let o = shutter(&[
        "blur",
        "--preset",
        "rsmb",
        "--preset",
        &s(&md),
        "--algorithm",
        "reconstruct",
        "--color",
        &s(&color),
        "--velocity",
        &s(&path),
        "-o",
        &s(&out),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("take the motion of the nearest valid vector"),
        "{}",
        stdout(&o)
    );

    // The key is what makes the difference: without it the garbage is read.
    let mut ignoring = preset.clone();
    for spec in [
        &mut ignoring.velocity,
        &mut ignoring.prev,
        &mut ignoring.next,
    ] {
        spec.validity_alpha.clear();
    }
    let (frame, _) = read_rsmb(&ignoring, &color, &path, &path, &path);
    let prev = frame.prev.as_ref().unwrap();
    let c = pixel_centres();
    for k in (0..n).filter(|&k| invalid(k)) {
        assert_eq!(prev.x[k] - c[0][k], -MAX_DISPLACE, "garbage x at {k}");
        assert_eq!(prev.y[k] - c[1][k], MAX_DISPLACE, "garbage y at {k}");
    }

    // Nothing valid: still, and said.
    write_rsmb(&path, 8, &dx, &dy, &vec![0; n]);
    let (frame, notes) = read_rsmb(&preset, &color, &path, &path, &path);
    assert!(
        notes.iter().any(|n| n.contains("reads as still")),
        "{notes:?}"
    );
    let prev = frame.prev.as_ref().unwrap();
    assert_eq!(prev.x, c[0]);
    assert_eq!(prev.y, c[1]);
    assert!(frame.velocity.as_ref().unwrap().x.iter().all(|&v| v == 0.0));
}

/// What RE:Vision does not document is refused, not guessed: a float vector file, and a
/// run without the Max Displace (a usage error before any file is read).
#[test]
fn rsmb_refuses_float_files_and_a_missing_max_displace() {
    let dir = tempfile::tempdir().unwrap();
    let preset = rsmb_preset(dir.path());
    let n = W * H;
    let color = dir.path().join("C.exr");
    write_exr(
        &color,
        W,
        H,
        vec![
            ("R", vec![0.5; n]),
            ("G", vec![0.5; n]),
            ("B", vec![0.5; n]),
        ],
    );
    let float = dir.path().join("V.exr");
    write_exr(
        &float,
        W,
        H,
        vec![
            ("R", vec![0.5; n]),
            ("G", vec![0.5; n]),
            ("A", vec![1.0; n]),
        ],
    );
    let mut i = inputs(&color);
    i.velocity = Some(PathPattern::parse(&s(&float)).unwrap());
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: Passes {
            velocity: true,
            ..Passes::COLOR
        },
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let problems = plan_frame(&i, None, &options).unwrap_err();
    assert_eq!(problems.len(), 1, "{problems:?}");
    assert_eq!(problems[0].kind, shutter::error::ProblemKind::Unsupported);
    assert!(
        problems[0].to_string().contains("8- and 16-bit"),
        "{}",
        problems[0]
    );

    let png = dir.path().join("V.png");
    write_rsmb(&png, 8, &vec![0.0; n], &vec![0.0; n], &vec![255; n]);
    let out = dir.path().join("out.exr");
    let o = shutter(&[
        "blur",
        "--preset",
        "rsmb",
        "--color",
        &s(&color),
        "--velocity",
        &s(&png),
        "-o",
        &s(&out),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("max_displace"), "{}", stderr(&o));
    assert!(!out.exists());
}

/// `--max-displace PX` gives an rsmb run its Max Displace: the output is the same bytes as
/// with the preset file of max_displace keys; 0 or a negative value is a usage error (exit
/// 2); with a preset that reads no RE:Vision vectors it has no effect and says so.
#[test]
fn max_displace_on_the_command_line_equals_the_preset_key() {
    let dir = tempfile::tempdir().unwrap();
    let _ = rsmb_preset(dir.path()); // writes max-displace.toml
    let n = W * H;
    let color = dir.path().join("C.exr");
    let shade: Vec<f32> = (0..n).map(|k| (k % 7) as f32 / 7.0).collect();
    write_exr(
        &color,
        W,
        H,
        vec![
            ("R", shade.clone()),
            ("G", shade.clone()),
            ("B", shade),
            ("Z", vec![10.0; n]),
        ],
    );
    let (dx, dy): (Vec<f32>, Vec<f32>) = (0..n)
        .map(|k| (if k % W < W / 2 { 3.0 } else { -2.0 }, 1.0))
        .unzip();
    let vectors = dir.path().join("backward.png");
    write_rsmb(&vectors, 8, &dx, &dy, &vec![255; n]);
    let run = |extra: &[&str], out: &str| {
        let out = dir.path().join(out);
        let mut args = vec![
            "blur".to_string(),
            "--algorithm".into(),
            "reconstruct".into(),
            "--color".into(),
            s(&color),
            "--velocity".into(),
            s(&vectors),
            "-o".into(),
            s(&out),
            "--json".into(),
        ];
        args.extend(extra.iter().map(|a| a.to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        (shutter(&args), out)
    };
    let md = s(&dir.path().join("max-displace.toml"));
    let (o, by_file) = run(&["--preset", "rsmb", "--preset", &md], "file.exr");
    assert!(o.status.success(), "{}", stderr(&o));
    let flag = format!("{MAX_DISPLACE}");
    let (o, by_flag) = run(&["--preset", "rsmb", "--max-displace", &flag], "flag.exr");
    assert!(o.status.success(), "{}", stderr(&o));
    // The pixels, not the bytes: each file records the presets that made it.
    assert!(
        read_exr_reference(&by_file) == read_exr_reference(&by_flag),
        "--max-displace gave other pixels than the preset key"
    );
    // Another Max Displace reads other motion: the flag is what set it.
    let (o, doubled) = run(&["--preset", "rsmb", "--max-displace", "16"], "doubled.exr");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        read_exr_reference(&by_flag) != read_exr_reference(&doubled),
        "--max-displace 16 read the same motion as 8"
    );
    for bad in ["--max-displace=0", "--max-displace=-3"] {
        let (o, out) = run(&["--preset", "rsmb", bad], "bad.exr");
        assert_eq!(o.status.code(), Some(2), "{bad}: {}", stderr(&o));
        assert!(stderr(&o).contains("--max-displace"), "{}", stderr(&o));
        assert!(!out.exists());
    }
    // Without rsmb the flag does nothing, and the run says so.
    let (o, _) = run(&["--max-displace", "8"], "plain.exr");
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("--max-displace 8"), "{}", stdout(&o));
}

/// The presets written from the documented facts (issue 32): V-Ray's velocity element
/// (p(+1) − p(0), pixels, y up), Unreal's MRQ pass (0.5 = still, normalised to the screen),
/// Arnold's raw motionvector (over a half-frame shutter: scale 2), each read back to the
/// motion written; and the depth each reads: `Z`, but MRQ's WorldDepth pass in centimetres,
/// read in metres (F8: the unreal preset named no depth MRQ writes).
#[test]
fn vray_unreal_and_arnold_presets() {
    let t = Truth::new();
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    // A motion per pixel, in pixels per frame, y down.
    let (vx, vy): (Vec<f32>, Vec<f32>) = (0..n)
        .map(|k| ((k % W) as f32 * 0.5 - 3.0, 2.0 - (k / W) as f32 * 0.25))
        .unzip();
    for (name, [x, y], stored, (depth, unit)) in [
        (
            "vray",
            ["VRayVelocity.R", "VRayVelocity.G"],
            (vx.clone(), vy.iter().map(|v| -v).collect::<Vec<f32>>()),
            ("Z", 1.0),
        ),
        (
            "unreal",
            [
                "FinalImageMovieRenderQueue_MotionVectors.R",
                "FinalImageMovieRenderQueue_MotionVectors.G",
            ],
            (
                vx.iter().map(|v| 0.5 + v / W as f32).collect(),
                vy.iter().map(|v| 0.5 + v / H as f32).collect(),
            ),
            ("FinalImageMovieRenderQueue_WorldDepth.R", 100.0),
        ),
        (
            "arnold",
            ["motionvector.R", "motionvector.G"],
            (
                vx.iter().map(|v| v / 2.0).collect(),
                vy.iter().map(|v| v / 2.0).collect(),
            ),
            ("Z", 1.0),
        ),
    ] {
        let path = dir.path().join(format!("{name}.exr"));
        let stored_depth = t.depth.iter().map(|d| d * unit).collect();
        write_exr(
            &path,
            W,
            H,
            t.with_colour(
                false,
                vec![(depth, stored_depth), (x, stored.0), (y, stored.1)],
            ),
        );
        let frame = read_all(&Preset::builtin(name).unwrap(), &inputs(&path));
        let metres = frame.depth.as_ref().unwrap();
        assert_close(metres, &t.depth, 1e-4, &format!("{name} depth"));
        let velocity = frame.velocity.as_ref().unwrap();
        assert_close(&velocity.x, &vx, 1e-4, &format!("{name} velocity x"));
        assert_close(&velocity.y, &vy, 1e-4, &format!("{name} velocity y"));
    }
}

/// A grey depth map given with `--depth` is read by its only channel under the default
/// `shutter` preset, as README's `--depth` says ("Z, or the file's only channel"): 8-bit and
/// 16-bit PNG, grey TIFF and JPEG, and a one-channel EXR alike (QA: a grey PNG was refused,
/// its aliases R, G, B counted as channels). The values are the grey's codes over their
/// range, as stored; the run warns that they are taken as depth in scene units, and
/// names the preset that maps grey to a range of distances. An RGB image is still refused.
#[test]
fn a_grey_depth_map_is_read_by_its_only_channel_under_the_shutter_preset() {
    let preset = Preset::builtin("shutter").unwrap();
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let n = W * H;
    write_png16(
        &p("photo.png"),
        &[&vec![0.5; n], &vec![0.5; n], &vec![0.5; n]],
    );
    let codes8: Vec<u8> = (0..n).map(|k| (k * 37 % 256) as u8).collect();
    let codes16: Vec<u16> = (0..n).map(|k| (k * 4099 % 65536) as u16).collect();
    let bytes16: Vec<u8> = codes16.iter().flat_map(|c| c.to_ne_bytes()).collect();
    let (w, h) = (W as u32, H as u32);
    let grey8 = image::ColorType::L8;
    image::save_buffer(p("d8.png"), &codes8, w, h, grey8).unwrap();
    image::save_buffer(p("d8.tif"), &codes8, w, h, grey8).unwrap();
    image::save_buffer(p("d16.png"), &bytes16, w, h, image::ColorType::L16).unwrap();
    let flat = vec![128u8; n];
    image::save_buffer(p("d8.jpg"), &flat, w, h, grey8).unwrap();
    let exr: Vec<f32> = (0..n).map(|k| k as f32 * 0.25).collect();
    write_exr(&p("d.exr"), W, H, vec![("depth", exr.clone())]);
    let eight: Vec<f32> = codes8.iter().map(|&c| c as f32 / 255.0).collect();
    let sixteen: Vec<f32> = codes16.iter().map(|&c| c as f32 / 65535.0).collect();
    let cases = [
        ("d8.png", eight.clone(), true),
        ("d8.tif", eight, true),
        ("d16.png", sixteen, true),
        ("d8.jpg", vec![128.0 / 255.0; n], true),
        ("d.exr", exr, false),
    ];
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: Passes {
            depth: true,
            ..Passes::COLOR
        },
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    for (name, expected, warned) in cases {
        let mut i = inputs(&p("photo.png"));
        i.depth = Some(PathPattern::parse(&s(&p(name))).unwrap());
        let plan = plan_frame(&i, None, &options).unwrap_or_else(|e| panic!("{name}: {e:?}"));
        let warning = plan
            .warnings
            .iter()
            .any(|w| w.contains("scene units") && w.contains("painted"));
        assert_eq!(warning, warned, "{name}: {:?}", plan.warnings);
        let frame = read_frame(&plan).unwrap();
        // The JPEG's flat grey decodes to its code within a step.
        let tolerance = if name.ends_with(".jpg") {
            1.01 / 255.0
        } else {
            0.0
        };
        assert_close(frame.depth.as_ref().unwrap(), &expected, tolerance, name);
    }
    // Three channels are not one: still refused, naming them.
    let mut i = inputs(&p("photo.png"));
    i.depth = Some(PathPattern::parse(&s(&p("photo.png"))).unwrap());
    let err = plan_frame(&i, None, &options).unwrap_err()[0].to_string();
    assert!(
        err.contains("depth pass") && err.contains("R, G, B"),
        "{err}"
    );
}

/// F3: a preset's depth mapping keys are checked when it loads, as every other numeric key
/// is: `[depth] scale = 0` (and NaN, negative, subnormal) read every depth as 0 or NaN and
/// blurred the whole frame without a word, `near = far` (a painted map's) likewise; and
/// `[velocity] dead_zone = nan` was taken while -1 was refused as "not finite". Each is
/// refused before any file is read (exit 2), naming the preset file, the key and what it
/// takes; nothing is written.
#[test]
fn a_presets_depth_mapping_and_dead_zone_are_checked_when_it_loads() {
    let dir = tempfile::tempdir().unwrap();
    let t = Truth::new();
    let color = dir.path().join("cm.exr");
    let in_cm = t.depth.iter().map(|d| d * 100.0).collect();
    write_exr(&color, W, H, t.with_colour(true, vec![("Z", in_cm)]));
    let out = dir.path().join("out.exr");
    let preset = dir.path().join("p.toml");
    let run = |text: &str, over: Option<&str>| {
        std::fs::write(&preset, text).unwrap();
        let mut args = vec!["dof"];
        if let Some(name) = over {
            args.extend(["--preset", name]);
        }
        let (color, preset, out) = (s(&color), s(&preset), s(&out));
        let tail = [
            "--preset",
            &preset,
            "--color",
            &color,
            "--focal-length",
            "50",
            "--f-stop",
            "1.4",
            "--focus-distance",
            "2",
            "-o",
            &out,
        ];
        args.extend(tail);
        shutter(&args)
    };
    for (text, over, said) in [
        (
            "[depth]\nscale = 0.0\n",
            None,
            "[depth] scale = 0: use a number from 1e-6 to 1000000",
        ),
        ("[depth]\nscale = nan\n", None, "[depth] scale = NaN"),
        ("[depth]\nscale = -0.01\n", None, "[depth] scale = -0.01"),
        ("[depth]\nscale = 1e-40\n", None, "[depth] scale = 1e-40"),
        (
            "[depth]\nnear = 0.0\nfar = 0.0\n",
            Some("painted"),
            "[depth] far = 0: use a finite distance",
        ),
        (
            "[depth]\nnear = -1.0\nfar = 10.0\n",
            None,
            "[depth] near = -1",
        ),
        (
            "[depth]\nnear = 2.0\n",
            None,
            "[depth] near = 2: use it with far",
        ),
        (
            "[velocity]\ndead_zone = nan\n",
            None,
            "[velocity] dead_zone = NaN: use a finite number of 0 or more",
        ),
        (
            "[velocity]\ndead_zone = -1.0\n",
            None,
            "[velocity] dead_zone = -1: use a finite number of 0 or more",
        ),
        (
            "[prev]\nzero = inf\n",
            None,
            "[prev] zero = inf: use a finite number",
        ),
    ] {
        let o = run(text, over);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{text}: {err}");
        assert!(
            err.contains(&format!("preset {}: {said}", s(&preset))),
            "{text}: {err}"
        );
        assert!(!out.exists(), "{text}: an output was written");
    }
    // What the keys are for is still taken: centimetres read as metres, a map whose white
    // is near (near above far), a dead zone of 0.
    for text in [
        "[depth]\nscale = 0.01\n",
        "[depth]\nscale = 0.01\nnear = 100.0\nfar = 1.0\n",
        "[velocity]\ndead_zone = 0.0\n",
    ] {
        let o = run(text, None);
        assert!(o.status.success(), "{text}: {}", stderr(&o));
    }
}
