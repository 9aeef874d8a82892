//! Depth of field: the invariants, near and far fields, bokeh energy and shape, determinism,
//! the CLI, and accuracy on `layers` against the lens reference.

use shutter::dof::{BlendForm, CocSource, DofParams, Lens, Method};
use shutter::frame::{Color, Frame};
use shutter::lab::truth::render::Reference;
use shutter::motion::Algorithm;
use shutter::process::{apply, Params};

use crate::support::*;

/// f/1.4 50 mm focused at 3 m on a 36 mm sensor (the `layers` lens).
const LENS: Lens = Lens {
    focal_mm: 50.0,
    f_number: 1.4,
    focus: 3.0,
    sensor_mm: 36.0,
};

fn params(method: Method) -> DofParams {
    DofParams {
        method,
        ..DofParams::new(CocSource::Lens(LENS))
    }
}

fn with(dof: DofParams) -> Params {
    Params {
        dof: Some(dof),
        ..Params::default()
    }
}

/// A lens with CoCs of 10–13 px on the 64 px wide noise frames (100 mm f/1.4 on an 8 mm
/// sensor, focused at 3 m: depth 2 is in front, depth 9 behind).
const STRONG: Lens = Lens {
    focal_mm: 100.0,
    f_number: 1.4,
    focus: 3.0,
    sensor_mm: 8.0,
};

/// Both methods, with non-default settings too.
pub fn variants() -> Vec<Params> {
    let strong = |method| DofParams {
        method,
        ..DofParams::new(CocSource::Lens(STRONG))
    };
    vec![
        with(strong(Method::Gather)),
        with(DofParams {
            blades: 5,
            blade_rotation: 20.0,
            rings: 2,
            ..strong(Method::Gather)
        }),
        with(DofParams {
            max_coc: 6.0,
            ..strong(Method::Gather)
        }),
        with(strong(Method::Blend)),
        with(DofParams {
            epsilon: 2.0,
            max_coc: 6.0,
            ..strong(Method::Blend)
        }),
        with(DofParams {
            blend_form: BlendForm::Talk,
            ..strong(Method::Blend)
        }),
        with(DofParams {
            blend_form: BlendForm::Talk,
            passes: Some(3),
            epsilon: 2.0,
            ..strong(Method::Blend)
        }),
    ]
}

/// Noise colour over depths 2 and 9 (both out of focus for [`LENS`], on either side of it).
pub fn frame(w: usize, h: usize, seed: u32, _speed: f32) -> Frame {
    noise_frame(w, h, seed)
}

/// The frame the `split` tests use: left half colour `left` at depth `left_depth`, right half
/// `right` at `right_depth`.
fn split(
    w: usize,
    h: usize,
    left: [f32; 3],
    left_depth: f32,
    right: [f32; 3],
    right_depth: f32,
) -> Frame {
    let n = w * h;
    let mut f = Frame::new(w, h);
    let pick = |i: usize, k: usize| if i % w < w / 2 { left[k] } else { right[k] };
    f.color = Some(Color {
        r: (0..n).map(|i| pick(i, 0)).collect(),
        g: (0..n).map(|i| pick(i, 1)).collect(),
        b: (0..n).map(|i| pick(i, 2)).collect(),
        a: None,
    });
    f.depth = Some(
        (0..n)
            .map(|i| {
                if i % w < w / 2 {
                    left_depth
                } else {
                    right_depth
                }
            })
            .collect(),
    );
    f
}

fn run(frame: &Frame, dof: DofParams) -> Color {
    apply(Algorithm::None, &with(dof), frame.clone(), 1)
        .color
        .unwrap()
}

/// A `w`×`h` frame the pass must leave unchanged (the invariants table, tests/invariants.rs).
pub fn still(w: usize, h: usize) -> Frame {
    let mut f = frame(w, h, 1, 0.0);
    // Depth at the focus distance, give or take less than ε of blur.
    let depth = f.depth.as_mut().unwrap();
    for (i, d) in depth.iter_mut().enumerate() {
        *d = 3.0 + 0.001 * (i % 7) as f32;
    }
    f
}

/// A frame poisoned with NaN, infinite, huge and degenerate values in every pass the pass
/// reads (the invariants table, tests/invariants.rs).
pub fn poisoned() -> Frame {
    let mut f = frame(64, 48, 5, 0.0);
    invariants::poison_color_and_depth(&mut f);
    f
}

#[test]
fn a_poisoned_painted_map_gives_finite_output() {
    let map = with(DofParams::new(CocSource::Map { scale: 40.0 }));
    invariants::finite_output(Algorithm::None, &poisoned(), &[map]);
}

#[test]
fn gather_spreads_a_blurred_foreground_over_the_sharp_background() {
    // Red foreground at 1.2 m (CoC −8.07 px at 320 px wide), blue background in focus.
    let f = split(320, 40, [1.0, 0.0, 0.0], 1.2, [0.0, 0.0, 1.0], 3.0);
    let coc = LENS.coc(1.2, 320.0);
    assert!(close(coc, 8.07, 0.01), "{coc}");
    for method in [Method::Gather, Method::Blend] {
        let out = run(&f, params(method));
        let row = 20 * 320;
        // Just right of the edge the foreground covers part of the background…
        let edge = out.r[row + 161];
        assert!(edge > 0.15 && edge < 0.85, "{method:?}: {edge}");
        // …and farther than its bokeh radius it does not (the blend's Gaussian-like copies
        // have longer tails).
        let beyond = out.r[row + 160 + 8];
        match method {
            Method::Gather => assert_eq!(beyond, 0.0),
            Method::Blend => assert!(beyond < 0.02, "{beyond}"),
        }
    }
}

#[test]
fn an_in_focus_subject_does_not_bleed_onto_the_blurred_background() {
    // Red subject in focus, blue background at 40 m (CoC 5 px at 320 wide) behind it.
    let f = split(320, 40, [1.0, 0.0, 0.0], 3.0, [0.0, 0.0, 1.0], 40.0);
    let gather = run(&f, params(Method::Gather));
    for x in 160..320 {
        assert_eq!(
            gather.r[20 * 320 + x],
            0.0,
            "red on the background at x = {x}"
        );
    }
    // The subject stays sharp: nothing behind it shows through.
    for x in 0..160 {
        assert_eq!(
            gather.b[20 * 320 + x],
            0.0,
            "blue on the subject at x = {x}"
        );
    }
    // The blend's weighting keeps the ghost small (it would be ~50% next to the edge
    // without it).
    let blend = run(&f, params(Method::Blend));
    let ghost = blend.r[20 * 320 + 160];
    assert!(ghost < 0.05, "{ghost}");
}

#[test]
fn a_bright_highlight_keeps_its_energy_and_takes_the_aperture_shape() {
    // One pixel of 1000 in the middle of a black plane at 40 m: its CoC is
    // 0.0357·0.05·37/(40·2.95) m = 0.560 mm on the sensor, 15.93 px on a 1024 px wide image.
    let (w, h) = (1024, 64);
    let n = w * h;
    let centre = 32 * w + 512;
    let mut f = Frame::new(w, h);
    let mut r = vec![0.0; n];
    r[centre] = 1000.0;
    f.color = Some(Color {
        r,
        g: vec![0.0; n],
        b: vec![0.0; n],
        a: None,
    });
    f.depth = Some(vec![40.0; n]);
    let radius = 0.5 * LENS.coc(40.0, w as f64) as f32;
    assert!(close(radius, 7.96, 0.01), "{radius}");
    let hexagon = shutter::dof::bokeh::Aperture::new(6, 0.0);
    let mut outside_hexagon = [0usize; 2];
    for (k, blades) in [0u32, 6].into_iter().enumerate() {
        let out = run(
            &f,
            DofParams {
                blades,
                ..params(Method::Gather)
            },
        );
        let total: f32 = out.r.iter().sum();
        assert!(
            close(total, 1000.0, 20.0),
            "{blades} blades: energy {total}"
        );
        for (i, &v) in out.r.iter().enumerate() {
            if v > 0.0 {
                let dx = (i % w) as f32 - 512.0;
                let dy = (i / w) as f32 - 32.0;
                assert!(
                    (dx * dx + dy * dy).sqrt() <= radius + 1.5,
                    "lit at ({dx}, {dy})"
                );
                if hexagon.norm(dx, dy) > radius + 1.0 {
                    outside_hexagon[k] += 1;
                }
            }
        }
    }
    assert!(
        outside_hexagon[0] > 0,
        "a round bokeh reaches past the hexagon"
    );
    assert_eq!(outside_hexagon[1], 0, "a six-blade bokeh stays inside it");
}

/// A lens that blurs a 128 px wide frame strongly (100 mm f/1.4 focused at 3 m on an 8 mm
/// sensor): a CoC of 28 px at 10.4 m behind the focus plane and at 1.753 m in front of it.
const BOKEH: Lens = Lens {
    focal_mm: 100.0,
    f_number: 1.4,
    focus: 3.0,
    sensor_mm: 8.0,
};

/// The side of [`highlight`]'s frame (px).
const HIGHLIGHT_FRAME: usize = 128;

/// What a point's bokeh looks like, from the pixels lit by at least half of a flat bokeh of
/// the expected shape and radius (their centres inside the shape: the gather's coverage ramp
/// is ½ at the shape's edge): the area its light is spread over and how far those pixels
/// reach from the point each way (px).
#[derive(Debug)]
struct Bokeh {
    /// The expected circumradius (px): half the lens's CoC at the point's depth.
    radius: f32,
    /// The point's light over the bokeh's level (the median of the lit pixels), as a share
    /// of the area of the aperture's shape at `radius`.
    area: f32,
    left: f32,
    right: f32,
    up: f32,
    down: f32,
}

/// One pixel of light at the centre of a black [`HIGHLIGHT_FRAME`]² frame, at `depth` m over
/// a background at `background` m, through the gather with `blades` turned by `rotation`
/// degrees and rings enough (16, the most) that every bokeh here (radius 16 px at most)
/// gathers over its whole-pixel grid: the bokeh it makes.
fn highlight(blades: u32, rotation: f32, depth: f32, background: f32) -> Bokeh {
    const LIGHT: f32 = 1000.0;
    let w = HIGHLIGHT_FRAME;
    let n = w * w;
    let (cx, cy) = (w / 2, w / 2);
    let mut f = Frame::new(w, w);
    let mut r = vec![0.0; n];
    r[cy * w + cx] = LIGHT;
    f.color = Some(Color {
        r,
        g: vec![0.0; n],
        b: vec![0.0; n],
        a: None,
    });
    let mut z = vec![background; n];
    z[cy * w + cx] = depth;
    f.depth = Some(z);
    let out = run(
        &f,
        DofParams {
            blades,
            blade_rotation: rotation,
            rings: 16,
            ..DofParams::new(CocSource::Lens(BOKEH))
        },
    );
    let radius = 0.5 * BOKEH.coc(depth as f64, w as f64) as f32;
    let aperture = shutter::dof::bokeh::Aperture::new(blades, rotation);
    let shape = aperture.unit_area() * radius * radius;
    let half = 0.5 * LIGHT / shape;
    let mut bokeh = Bokeh {
        radius,
        area: 0.0,
        left: 0.0,
        right: 0.0,
        up: 0.0,
        down: 0.0,
    };
    let mut lit = Vec::new();
    for (i, &v) in out.r.iter().enumerate() {
        if v < half {
            continue;
        }
        let dx = (i % w) as f32 - cx as f32;
        let dy = (i / w) as f32 - cy as f32;
        lit.push(v);
        bokeh.left = bokeh.left.max(-dx);
        bokeh.right = bokeh.right.max(dx);
        bokeh.up = bokeh.up.max(-dy);
        bokeh.down = bokeh.down.max(dy);
    }
    lit.sort_by(f32::total_cmp);
    bokeh.area = LIGHT / lit[lit.len() / 2] / shape;
    bokeh
}

/// Whether `bokeh`'s area is its shape's within `tolerance`, and it reaches `expected`
/// (left, right, up, down, in units of its radius) each way within 1.5 px: the farthest
/// pixel centre inside a polygon's vertex lies up to a pixel short of it, and the shape cut
/// by its reflection (the bug this guards) falls 2 px short of a pentagon's vertex and 7 px
/// of a triangle's at this radius.
fn bokeh_is(bokeh: &Bokeh, tolerance: f32, expected: [f32; 4], what: &str) {
    assert!(
        (bokeh.area - 1.0).abs() <= tolerance,
        "{what}: area {} of the shape's ({bokeh:?})",
        bokeh.area
    );
    let got = [bokeh.left, bokeh.right, bokeh.up, bokeh.down];
    for (g, e) in got.iter().zip(expected) {
        assert!(
            (g - e * bokeh.radius).abs() <= 1.5,
            "{what}: reaches {got:?}, expected {:?} ({bokeh:?})",
            expected.map(|e| e * bokeh.radius)
        );
    }
}

/// How far a regular polygon of circumradius 1 reaches along its axis of symmetry: to the
/// vertex one way, to the middle of an edge (cos(π/n)) the other.
fn apothem(blades: u32) -> f32 {
    (std::f32::consts::PI / blades as f32).cos()
}

// Tolerance of the bokeh's area. Where the point and its background are one layer, the far
// field spreads its light evenly over the sum of its taps' coverage, whose ½-pixel ramp at
// the edge makes that sum the shape's area within a fraction of a percent at a radius of 14
// px (measured 0.996–1.005 for 0, 3, 4, 5 and 6 blades); in the near field the level is the
// point's light over the exact area. 2 % leaves room for that and tells the shape cut by its
// own reflection at the grid's margin (the bug this guards) apart: 0.73 of a triangle's
// area (a hexagon) and 0.968 of a pentagon's (a decagon).
const BOKEH_AREA: f32 = 0.02;

#[test]
fn odd_blades_give_a_far_point_the_aperture_s_own_shape_pointing_as_documented() {
    // A point 10.4 m away (7.4 m behind the focus plane, CoC 28 px) over a background as far
    // (one layer):
    // its bokeh is the aperture as it stands (src/dof/bokeh.rs): at rotation 0 a triangle's
    // flat edge is on the right and it points left; a pentagon points left too (an edge's
    // middle at 0°, a vertex at 180°). Turned 90° (clockwise on screen: y grows down), the
    // triangle stands on its flat edge and points up. Before the fix the taps covered only
    // the shape at +offset while a far source counts where −offset lies inside it: a
    // triangle came out a hexagon (its level that of 0.73 of its area, 7 or 8 px of the
    // 14 each way), a pentagon a decagon (0.968 of its area, 12 px to the left).
    let (d, bg) = (10.4, 10.4);
    let t = highlight(3, 0.0, d, bg);
    bokeh_is(
        &t,
        BOKEH_AREA,
        [1.0, 0.5, apothem(6), apothem(6)],
        "triangle",
    );
    let p = highlight(5, 0.0, d, bg);
    let side = (0.4 * std::f32::consts::PI).sin();
    bokeh_is(&p, BOKEH_AREA, [1.0, apothem(5), side, side], "pentagon");
    let turned = highlight(3, 90.0, d, bg);
    bokeh_is(
        &turned,
        BOKEH_AREA,
        [apothem(6), apothem(6), 1.0, 0.5],
        "triangle turned 90°",
    );
    // A round and a square aperture are their own reflections: the same either way.
    bokeh_is(&highlight(0, 0.0, d, bg), BOKEH_AREA, [1.0; 4], "round");
    bokeh_is(
        &highlight(4, 0.0, d, bg),
        BOKEH_AREA,
        [apothem(4); 4],
        "square",
    );
}

#[test]
fn odd_blades_turn_the_bokeh_over_in_the_near_field() {
    // Light from a point in front of the focus plane meets the sensor before it converges:
    // its bokeh is the aperture turned 180° (a triangle pointing right where a point behind
    // focus makes one pointing left). The gather turns it over by field: a source counted in
    // the near field (in front of a sharp background) is turned, one in the far field (behind
    // focus) is not (`dof::bokeh`, "Orientation"). Before, the triangle came out a hexagon in
    // both.
    let front = 1.753;
    let turned = [0.5, 1.0, apothem(6), apothem(6)];
    let upright = [1.0, 0.5, apothem(6), apothem(6)];
    for (depth, background, expected, what) in [
        (front, 3.0, turned, "in front, over a sharp background"),
        (10.4, 10.4, upright, "behind focus, one layer"),
    ] {
        let t = highlight(3, 0.0, depth, background);
        bokeh_is(&t, BOKEH_AREA, expected, what);
    }
}

#[test]
fn same_bytes_for_one_and_two_threads() {
    for method in [
        &["--method", "gather"][..],
        &["--method", "blend"],
        &["--method", "blend", "--blend-form", "talk"],
    ] {
        let mut flags = lens_flags();
        flags.extend(method);
        invariants::same_bytes_for_any_thread_count("none", "layers", &["color", "depth"], &flags);
    }
}

#[test]
fn both_methods_beat_the_sharp_frame_on_layers_and_gather_beats_blend() {
    let talk = DofParams {
        blend_form: BlendForm::Talk,
        ..params(Method::Blend)
    };
    let (none, errors, _, _) = scene_errors_against(
        "layers",
        (240, 135),
        Reference::DepthOfField,
        &[
            (Algorithm::None, with(params(Method::Gather))),
            (Algorithm::None, with(params(Method::Blend))),
            (Algorithm::None, with(talk)),
        ],
    );
    let (gather, blend, talk) = (errors[0], errors[1], errors[2]);
    assert!(gather < 0.4 * none, "gather {gather} vs none {none}");
    assert!(blend < 0.5 * none, "blend {blend} vs none {none}");
    assert!(gather < blend, "gather {gather} vs blend {blend}");
    // The pyramid's continuous mix of levels beats the talk's three images (here, where
    // CoCs reach 6 px, by 6 %; at 640×360, up to 16 px, by half: BENCHMARKS.md).
    assert!(blend < talk, "blend {blend} vs the talk's form {talk}");
}

#[test]
fn depth_of_field_then_motion_blur_beats_either_alone_on_layers() {
    let dof = with(params(Method::Gather));
    let scatter = Params::default();
    let (none, errors, _, _) = scene_errors_against(
        "layers",
        (240, 135),
        Reference::Both,
        &[
            (Algorithm::Scatter, dof),
            (Algorithm::None, dof),
            (Algorithm::Scatter, scatter),
        ],
    );
    let (both, dof_only, motion_only) = (errors[0], errors[1], errors[2]);
    assert!(
        both < dof_only,
        "both {both} vs depth of field only {dof_only}"
    );
    assert!(
        both < motion_only,
        "both {both} vs motion blur only {motion_only}"
    );
    assert!(both < 0.5 * none, "both {both} vs none {none}");
}

pub(crate) fn lens_flags() -> Vec<&'static str> {
    vec![
        "--focal-length",
        "50",
        "--f-stop",
        "1.4",
        "--focus-distance",
        "3",
    ]
}

#[test]
fn dof_needs_a_lens_or_a_map_and_says_so() {
    let dir = small_scene("layers", 32, 18, 1, 4);
    let color = role_pattern(dir.path(), "color");
    let depth = role_pattern(dir.path(), "depth");
    let out = format!("{}/o.####.exr", dir.path().display());
    let o = shutter(&["dof", "--color", &color, "--depth", &depth, "-o", &out]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--focal-length"), "{}", stderr(&o));
    // Half a lens is an error too, naming what is missing.
    let o = shutter(&[
        "dof", "--color", &color, "--depth", &depth, "--f-stop", "2", "-o", &out,
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--focus-distance"), "{}", stderr(&o));
    // A focus distance inside the focal length cannot be focused.
    let mut args = vec!["dof", "--color", &color, "--depth", &depth, "-o", &out];
    args.extend([
        "--focal-length",
        "50",
        "--f-stop",
        "2",
        "--focus-distance",
        "0.01",
    ]);
    let o = shutter(&args);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("focus distance"), "{}", stderr(&o));
    // Focus at infinity, refused, says what to give (an outside tester: it said only "use a
    // finite number above 0").
    *args.last_mut().unwrap() = "inf";
    let o = shutter(&args);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("to focus at infinity"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.path().join("o.0001.exr").exists());
}

#[test]
fn dof_reads_colour_and_depth_only() {
    let dir = small_scene("layers", 32, 18, 1, 4);
    // A velocity sequence that is not EXR at all (a pattern, as the colour is: a single file
    // beside a colour pattern is a usage error): never opened.
    for frame in 0..=2 {
        let broken = dir.path().join(format!("broken.{frame:04}.exr"));
        std::fs::write(&broken, b"not an exr at all").unwrap();
    }
    let broken = role_pattern(dir.path(), "broken");
    let out = format!("{}/o.####.exr", dir.path().display());
    let color = role_pattern(dir.path(), "color");
    let depth = role_pattern(dir.path(), "depth");
    let mut args = vec![
        "dof",
        "--color",
        &color,
        "--depth",
        &depth,
        "--velocity",
        &broken,
        "-o",
        &out,
        "--verbose",
    ];
    args.extend(lens_flags());
    let o = shutter(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("--velocity is not read"),
        "{}",
        stderr(&o)
    );
}

#[test]
fn a_preset_with_a_dof_section_blurs_the_lens_before_the_motion() {
    let dir = small_scene("layers", 64, 36, 1, 4);
    let preset = dir.path().join("both.toml");
    std::fs::write(
        &preset,
        "[blur]\nalgorithm = \"scatter\"\n\n[dof]\nmethod = \"blend\"\nfocal_length = 50\n\
         f_stop = 1.4\nfocus_distance = 3\n",
    )
    .unwrap();
    let color = role_pattern(dir.path(), "color");
    let depth = role_pattern(dir.path(), "depth");
    let prev = role_pattern(dir.path(), "prev");
    let next = role_pattern(dir.path(), "next");
    let run_with = |extra: &[&str], name: &str| {
        let out = format!("{}/{name}.####.exr", dir.path().display());
        let mut args = vec![
            "blur", "--color", &color, "--depth", &depth, "--prev", &prev, "--next", &next, "-o",
            &out,
        ];
        args.extend(extra);
        let o = shutter(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        read_exr_reference(&dir.path().join(format!("{name}.0001.exr")))
    };
    let from_preset = run_with(&["--preset", preset.to_str().unwrap()], "preset");
    let mut flags = vec!["--algorithm", "scatter", "--method", "blend"];
    flags.extend(lens_flags());
    let from_flags = run_with(&flags, "flags");
    let motion_only = run_with(&["--algorithm", "scatter"], "motion");
    for name in ["R", "G", "B"] {
        assert_exact(
            channel(&from_preset, name),
            channel(&from_flags, name),
            name,
        );
    }
    assert_ne!(channel(&from_preset, "R"), channel(&motion_only, "R"));
}

/// The README's photo walk-through, command for command.
#[test]
fn the_photo_walkthrough_runs_as_written() {
    let root = env!("CARGO_MANIFEST_DIR");
    let dir = tempfile::tempdir().unwrap();
    let photo = format!("{root}/fixtures/photo/photo.jpg");
    let painted = dir.path().join("photo-dof.jpg");
    let o = shutter(&[
        "dof",
        "--preset",
        "painted",
        "--color",
        &photo,
        "--depth",
        &format!("{root}/fixtures/photo/depth.png"),
        "--focal-length",
        "85",
        "--f-stop",
        "1.8",
        "--focus-distance",
        "3",
        "-o",
        &s(&painted),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let from_map = dir.path().join("photo-coc.png");
    let o = shutter(&[
        "dof",
        "--color",
        &photo,
        "--coc-map",
        &format!("{root}/fixtures/photo/coc.png"),
        "--coc-scale",
        "24",
        "--blades",
        "6",
        "-o",
        &s(&from_map),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The subject (the post, in focus in both) stays as it was; the wall behind it blurs.
    let read = |p: &std::path::Path| image::open(p).unwrap().to_rgb8();
    let input = read(std::path::Path::new(&photo));
    for out in [read(&painted), read(&from_map)] {
        assert_eq!(out.dimensions(), input.dimensions());
        let near = |a: u8, b: u8| (a as i32 - b as i32).abs() <= 12;
        // Inside the post (x 150–190), away from its edges: unchanged but for JPEG noise.
        for (x, y) in [(170, 120), (165, 150), (175, 90)] {
            let (a, b) = (input.get_pixel(x, y), out.get_pixel(x, y));
            assert!(
                (0..3).all(|k| near(a[k], b[k])),
                "post at ({x}, {y}): {a:?} vs {b:?}"
            );
        }
        // The wall's mortar lines wash out: the summed step between vertical neighbours down
        // a column of wall drops by a third or more (JPEG noise keeps some).
        let contrast = |img: &image::RgbImage| {
            (0..60)
                .map(|y| {
                    (img.get_pixel(260, y + 1)[0] as i32 - img.get_pixel(260, y)[0] as i32).abs()
                })
                .sum::<i32>()
        };
        assert!(
            3 * contrast(&out) <= 2 * contrast(&input),
            "{} vs {}",
            contrast(&out),
            contrast(&input)
        );
    }
}

#[test]
fn help_documents_every_dof_flag() {
    for command in ["dof", "blur"] {
        let text = stdout(&shutter(&[command, "--help"]));
        for flag in [
            "--method",
            "--focal-length",
            "--f-stop",
            "--focus-distance",
            "--sensor-width",
            "--coc-map",
            "--coc-scale",
            "--epsilon",
            "--max-coc",
            "--blades",
            "--blade-rotation",
            "--rings",
            "--passes",
        ] {
            assert!(text.contains(flag), "{flag} missing from {command} --help");
        }
    }
}

/// A fine checker of `cell` px cells, 0.1 and 0.9, whose first cell at the top-left corner
/// is `cell − shift` pixels wide and high: whole cells meet every edge for shift 0, cells cut
/// part-way otherwise (shift cell − 1 leaves a 1 px sliver along the top and left edges).
pub(crate) fn edge_checker(w: usize, h: usize, cell: usize, shift: usize) -> Color {
    let plane: Vec<f32> = (0..w * h)
        .map(|i| 0.1 + 0.8 * (((i % w + shift) / cell + (i / w + shift) / cell) % 2) as f32)
        .collect();
    Color {
        r: plane.clone(),
        g: plane.clone(),
        b: plane,
        a: None,
    }
}

/// Issue 34's edge case at 160×96: the frame's DoF settings, the checker of `cell` px cells
/// moved by `shift`, a uniform CoC plane of `coc` px and its tiles.
pub(crate) fn edge_case(
    cell: usize,
    coc: f32,
    shift: usize,
) -> (
    shutter::dof::DofConfig,
    Color,
    Vec<f32>,
    shutter::dof::tiles::Tiles,
) {
    use shutter::dof::tiles::{tiles, TilesConfig};
    let (w, h) = EDGE_FRAME;
    let coc_plane = vec![coc; w * h];
    let config = shutter::dof::DofConfig::new(w, h, &DofParams::default());
    let t = tiles(&TilesConfig::new(w, h, config.epsilon), &coc_plane);
    (config, edge_checker(w, h, cell, shift), coc_plane, t)
}

/// The size of the edge tests' frame.
pub(crate) const EDGE_FRAME: (usize, usize) = (160, 96);

/// The fine checkers and CoCs of issue 34's edge tests: 4 px cells under a 9 px CoC, 5 px
/// under 12, each meeting the edges whole, cut in half and as a 1 px sliver.
pub(crate) const EDGE_CHECKERS: [(usize, f32, [usize; 3]); 2] =
    [(4, 9.0, [0, 2, 3]), (5, 12.0, [0, 2, 4])];

/// Issue 34: a fine checker meeting the frame's edges (both orientations: its cells meet the
/// top and bottom rows and the first and last columns; whole, cut in half, or as a 1 px
/// sliver) keeps its blurred mean, 0.5, within 0.25 in the first CoC radius of every edge,
/// corners included, through both methods (the outside of the frame is unknown: neither
/// may invent structure there). Measured 160x96 (the largest distance from 0.5 in the
/// first radius): the gather 0.213 (cell 4, whole cells), 0.181 (cell 5); the blend 0.224
/// and 0.188 with its discs (0.188 and 0.217 with the pyramid alone); away from the edges
/// the disc itself leaves 0.07 (gather) and 0.04–0.06 (blend).
/// Mirroring the frame about its edge reached 0.304 and 0.260 in the gather. And each line
/// of that first radius along each edge (corners left out) keeps the mean within 0.01
/// (measured: within 0.003): the blend's pyramid padded with black outside the frame read
/// 0.469 on the first line.
#[test]
fn a_fine_checker_keeps_its_mean_at_the_frame_edge_through_both_methods() {
    use shutter::dof::blend::blend;
    use shutter::dof::gather::gather;
    let (w, h) = EDGE_FRAME;
    for (cell, coc, shifts) in EDGE_CHECKERS {
        for shift in shifts {
            let (config, color, coc_plane, t) = edge_case(cell, coc, shift);
            let outputs = [
                ("gather", gather(&config, &color, &coc_plane, &t)),
                ("blend", blend(&config, color.clone(), &coc_plane)),
            ];
            let radius = (0.5 * coc).ceil() as usize;
            for (method, out) in outputs {
                let what = format!("{method}, cell {cell} shift {shift}, CoC {coc}");
                // Each line of the first radius along each edge (corners left out): its mean.
                for k in 0..radius {
                    let (across, down) = (radius..w - radius, radius..h - radius);
                    let lines: [Vec<(usize, usize)>; 4] = [
                        across.clone().map(|x| (x, k)).collect(),
                        across.map(|x| (x, h - 1 - k)).collect(),
                        down.clone().map(|y| (k, y)).collect(),
                        down.map(|y| (w - 1 - k, y)).collect(),
                    ];
                    for line in lines {
                        let inner: Vec<f64> =
                            line.iter().map(|&(x, y)| out.r[y * w + x] as f64).collect();
                        let mean = inner.iter().sum::<f64>() / inner.len() as f64;
                        assert!(
                            (mean - 0.5).abs() <= 0.01,
                            "{what}: line {k} from an edge: mean {mean}"
                        );
                    }
                }
                for y in 0..h {
                    for x in 0..w {
                        if x.min(w - 1 - x).min(y).min(h - 1 - y) < radius {
                            let v = out.r[y * w + x];
                            assert!((v - 0.5).abs() <= 0.25, "{what}: ({x}, {y}): {v}");
                        }
                    }
                }
            }
        }
    }
}

/// Issue 34: a checker of 2 px cells under a CoC of 5 px (its period, 4 px, is where the
/// lens's disc passes a texture inverted: its first side lobe) comes out inverted through
/// both methods, as the lens renders it: away from the edges, the pixels that were dark
/// (0.1) come out brighter on average than those that were bright (0.9), by at least 0.05.
/// The exact disc of diameter 5 (its area over each pixel, NumPy) leaves 0.097; measured
/// here: the gather and the blend 0.093. blend's pyramid alone (before its disc below level
/// 3) kept the pattern upright, −0.043, and failed: no Gaussian-like kernel has a negative
/// lobe.
#[test]
fn a_checker_near_the_coc_s_size_comes_out_inverted_through_both_methods() {
    use shutter::dof::blend::blend;
    use shutter::dof::gather::gather;
    let (w, h) = EDGE_FRAME;
    for shift in [0, 1] {
        let (config, color, coc_plane, t) = edge_case(2, 5.0, shift);
        let outputs = [
            ("gather", gather(&config, &color, &coc_plane, &t)),
            ("blend", blend(&config, color.clone(), &coc_plane)),
        ];
        for (method, out) in outputs {
            let (mut dark, mut bright) = ((0.0f64, 0usize), (0.0f64, 0usize));
            for y in 8..h - 8 {
                for x in 8..w - 8 {
                    let i = y * w + x;
                    let into = if color.r[i] < 0.5 {
                        &mut dark
                    } else {
                        &mut bright
                    };
                    into.0 += out.r[i] as f64;
                    into.1 += 1;
                }
            }
            let inverted = dark.0 / dark.1 as f64 - bright.0 / bright.1 as f64;
            assert!(
                inverted >= 0.05,
                "{method}, shift {shift}: dark pixels minus bright ones {inverted}"
            );
        }
    }
}

/// blend's discs for a pixel in front of the focus plane take every tap alike: an object out
/// of focus before a sharp background shows that background through its blurred rim (the
/// pixels of its edge are part background, as a lens sees them), while a pixel behind the
/// focus plane still takes nearly nothing from a sharp neighbour (its disc weighs each tap by
/// w, 1/64 for a sharp one: a sharp pixel in front of a blurred background does not bleed
/// into it). The exact disc about the object's last column has 0.627 of its area over the
/// object at a CoC of 5 px (the frame's disc) and 0.553 at 12 px (level 1's); measured: 0.626
/// and 0.553 (0.991 and 0.988 when the taps were weighed by w, before: the fan of the real
/// Cycles frame, BENCHMARKS.md; each seen failing), behind the focus plane 0.991 and 0.988.
#[test]
fn a_near_pixel_s_disc_shows_the_sharp_background_behind_its_rim() {
    use shutter::dof::blend::blend;
    let (w, h) = (64, 32);
    let edge = 32;
    for (size, near) in [(5.0f32, 0.58..0.68), (12.0, 0.50..0.61)] {
        for (sign, within) in [(-1.0f32, near), (1.0, 0.95..1.01)] {
            // The object (colour 1) left of `edge`, the sharp background (0) right.
            let coc: Vec<f32> = (0..w * h)
                .map(|i| if i % w < edge { sign * size } else { 0.0 })
                .collect();
            let r: Vec<f32> = coc.iter().map(|&c| (c != 0.0) as u8 as f32).collect();
            let color = Color {
                r: r.clone(),
                g: r.clone(),
                b: r,
                a: None,
            };
            let params = DofParams {
                max_coc: size,
                ..DofParams::default()
            };
            let config = shutter::dof::DofConfig::new(w, h, &params);
            let out = blend(&config, color, &coc);
            let at = out.r[(h / 2) * w + edge - 1];
            assert!(
                within.contains(&at),
                "CoC {}: the object's last column {at}, not in {within:?}",
                sign * size
            );
        }
    }
}

/// A `side`² frame of grey `paint` under one CoC (px, diameter) everywhere, gathered with the
/// default 6 rings.
fn gathered_under(side: usize, coc: f32, paint: impl Fn(usize, usize) -> f32) -> Vec<f32> {
    use shutter::dof::gather::gather;
    use shutter::dof::tiles::{tiles, TilesConfig};
    use shutter::dof::DofConfig;
    let n = side * side;
    let plane: Vec<f32> = (0..n).map(|i| paint(i % side, i / side)).collect();
    let color = Color {
        r: plane.clone(),
        g: plane.clone(),
        b: plane,
        a: None,
    };
    let coc_plane = vec![coc; n];
    let config = DofConfig::new(side, side, &DofParams::default());
    let t = tiles(&TilesConfig::new(side, side, config.epsilon), &coc_plane);
    gather(&config, &color, &coc_plane, &t).r
}

/// A lone highlight (one pixel of 50 on a ground of 0.02) under a 42 px CoC: its bokeh is a
/// disc of radius 21 px holding its light evenly, (50 − 0.02) / (π·21²) = 0.0361 over the
/// ground. Six rings sample a 21 px bokeh 3.5 px apart, and each tap read one pixel: the
/// highlight came out as the taps' pattern, dotted rings (pixels inside the disc from 0 to
/// 9.4× that level). Each ring tap now reads a box of its tile's prefilter level: every
/// pixel within 17 px of the highlight must hold between 0.4× and 2× the disc's level
/// (measured 0.59× to 1.78×), and the light must still sum to the highlight's (within 1 %).
#[test]
fn a_lone_highlight_under_a_large_bokeh_fills_its_disc_not_the_taps_pattern() {
    let (side, centre) = (128, 64);
    let out = gathered_under(side, 42.0, |x, y| {
        if (x, y) == (centre, centre) {
            50.0
        } else {
            0.02
        }
    });
    let level = (50.0 - 0.02) / (std::f32::consts::PI * 21.0 * 21.0);
    let mut inside = 0;
    for y in 0..side {
        for x in 0..side {
            let (dx, dy) = (x as f32 - centre as f32, y as f32 - centre as f32);
            if (dx * dx + dy * dy).sqrt() <= 17.0 {
                let share = (out[y * side + x] - 0.02) / level;
                assert!(
                    (0.4..=2.0).contains(&share),
                    "({x}, {y}): {share} of the disc's level"
                );
                inside += 1;
            }
        }
    }
    assert!(inside > 900, "{inside}");
    let light: f32 = out.iter().map(|v| v - 0.02).sum();
    assert!(close(light, 50.0 - 0.02, 0.5), "light {light}");
}

/// The opposite case: a texture of one pixel under the same 42 px CoC, where a prefilter
/// could blur what it should not. A checker of 1 px cells (0 and 1) under a 21 px disc is its
/// mean everywhere, 0.5 within 0.003 (the exact disc's area over each pixel), up to the
/// frame's edge. The single-pixel taps sampled the checker at the ring pattern's offsets and
/// kept 0.13 of it; with the levels the gather stays within 0.02 of the mean (measured
/// 0.0009 off at most).
#[test]
fn a_one_pixel_checker_under_a_large_bokeh_is_its_mean_up_to_the_frame_edge() {
    let side = 128;
    let out = gathered_under(side, 42.0, |x, y| ((x + y) % 2) as f32);
    for (i, v) in out.iter().enumerate() {
        assert!((v - 0.5).abs() <= 0.02, "({}, {}): {v}", i % side, i / side);
    }
}
