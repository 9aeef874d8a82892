//! stretch: the invariants of docs/DESIGN.md, numerics, determinism, and accuracy on the truth
//! scenes.

use shutter::frame::{Frame, Velocity};
use shutter::motion::{Algorithm, Anchor, StretchParams};
use shutter::process::Params;

use crate::support::*;

/// Noise colour over two depth layers (so silhouettes are everywhere) with noise velocity.
pub fn frame(w: usize, h: usize, seed: u32, speed: f32) -> Frame {
    let n = w * h;
    let mut f = noise_frame(w, h, seed);
    f.velocity = Some(Velocity {
        x: noise(n, seed + 5, -speed, speed),
        y: noise(n, seed + 6, -speed, speed),
    });
    f
}

pub fn variants() -> Vec<Params> {
    let default = StretchParams::default();
    [
        default,
        StretchParams {
            anchor: Anchor::Rear,
            texture_blur: false,
            extent: 40.0,
            ..default
        },
        StretchParams {
            min_alpha: 0.5,
            tear: 0.0,
            ..default
        },
    ]
    .into_iter()
    .map(|stretch| Params {
        shutter: 0.75,
        stretch,
        ..Params::default()
    })
    .collect()
}

/// A `w`×`h` frame the pass must leave unchanged (the invariants table, tests/invariants.rs).
pub fn still(w: usize, h: usize) -> Frame {
    let mut f = frame(w, h, 1, 0.0);
    // A streak under half a pixel is no motion too (0.6 px per frame, shutter 0.75; at the
    // right edge, far from any strip of motion the table adds at the left).
    f.velocity.as_mut().unwrap().x[h / 2 * w + w - 3] = 0.6;
    f
}

/// A frame poisoned with NaN, infinite, huge and degenerate values in every pass the pass
/// reads (the invariants table, tests/invariants.rs).
pub fn poisoned() -> Frame {
    let mut f = frame(50, 40, 4, 15.0);
    invariants::poison_color_and_depth(&mut f);
    let v = f.velocity.as_mut().unwrap();
    v.x[10] = f32::NAN;
    v.y[20] = f32::INFINITY;
    v.x[30] = -1e38;
    v.y[40] = 1e20;
    f
}

#[test]
fn output_is_identical_for_one_and_two_threads() {
    invariants::same_bytes_for_any_thread_count(
        "stretch",
        "crossing",
        &["color", "depth", "velocity"],
        &[],
    );
}

#[test]
fn prev_and_next_are_never_read() {
    let dir = small_scene("crossing", 48, 27, 1, 2);
    let p = |role: &str| s(&dir.path().join(format!("{role}.0001.exr")));
    let o = shutter(&[
        "blur",
        "--algorithm",
        "stretch",
        "--color",
        &p("color"),
        "--depth",
        &p("depth"),
        "--velocity",
        &p("velocity"),
        "--prev",
        &s(&dir.path().join("missing.exr")),
        "--json",
        "-o",
        &s(&dir.path().join("out.exr")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    assert!(report["warnings"]
        .to_string()
        .contains("--prev is not read"));
}

/// At the bench's 320×180: at 160×90 the pan moves only 1.25 px over the exposure and
/// stretch gains 4 % there (0.0167 against 0.0174).
#[test]
fn beats_the_unblurred_frame_on_crossing_and_pan() {
    for name in ["crossing", "pan"] {
        let runs = [(Algorithm::Stretch, Params::default())];
        let (none, errors, _, _) = scene_errors(name, (320, 180), &runs);
        let ours = errors[0];
        assert!(ours < 0.9 * none, "{name}: stretch {ours} vs none {none}");
    }
}

/// A parallelogram of opaque colour over empty space (a view layer's FG: premultiplied,
/// alpha 0 and depth +∞ where empty, still there), 12 px wide on each of its 12 rows, each
/// row `row / 3` px right of the one three above (staircase silhouettes on both sides, whose
/// steps tear the mesh), moving right at 32 px a frame under a 0.5 shutter: a 16-px streak.
fn parallelogram_over_nothing() -> (Frame, impl Fn(usize) -> Option<usize>) {
    let (w, h) = (72, 24);
    let n = w * h;
    // The first column the shape covers on row y, if it covers the row.
    let left = |y: usize| (6..18).contains(&y).then(|| 20 + (y - 6) / 3);
    let mut f = Frame::new(w, h);
    let inside = |i: usize| left(i / w).is_some_and(|l| (l..l + 12).contains(&(i % w)));
    let plane = |value: f32| {
        (0..n)
            .map(|i| if inside(i) { value } else { 0.0 })
            .collect()
    };
    f.color = Some(shutter::frame::Color {
        r: plane(0.8),
        g: plane(0.4),
        b: plane(0.2),
        a: Some(plane(1.0)),
    });
    f.depth = Some(
        (0..n)
            .map(|i| if inside(i) { 5.0 } else { f32::INFINITY })
            .collect(),
    );
    f.velocity = Some(Velocity {
        x: plane(32.0),
        y: vec![0.0; n],
    });
    (f, left)
}

/// The alpha the exposure gives pixel x of a row whose pixels `l..l + 12` are covered, moving
/// at `v` px a frame over [t0, t1], worked out by hand: the mean over the exposure of the
/// row's alpha at x − v·t, read between pixel centres as stretch reads it (linearly: a tent
/// from centre l − 1 to centre l, 1 to centre l + 11, down to 0 at l + 12). Its integral from
/// −∞ to s is F(s) below (0 to l − 1; (s − l + 1)²/2 on the rising pixel; ½ plus the covered
/// length after; 12 beyond l + 12); the mean is the difference of F at the streak's two ends
/// over the streak's length.
fn coverage(x: usize, l: usize, v: f32, [t0, t1]: [f32; 2]) -> f32 {
    let l = l as f32;
    let f = |s: f32| {
        let s = s - (l - 1.0);
        match s {
            s if s <= 0.0 => 0.0,
            s if s <= 1.0 => s * s / 2.0,
            s if s <= 12.0 => 0.5 + (s - 1.0),
            s if s <= 13.0 => 12.0 - (13.0 - s) * (13.0 - s) / 2.0,
            _ => 12.0,
        }
    };
    let x = x as f32;
    (f(x - v * t0) - f(x - v * t1)) / (v * (t1 - t0))
}

/// The FG layer of a view-layer stack is blurred alone, over nothing: there, stretch's smears
/// are the output's alpha. Until the smears' pixels took the coverage the exposure gives
/// (src/motion/stretch/cover.rs) the talk's opacity made them: 0.92 beside the silhouette
/// (the exposure: 0.5), a cut at the 0.1 floor where the streak ends, and gaps a pixel high
/// at every step of a staircase silhouette (torn triangles), a comb. Inside the silhouette the
/// pre-blur gives the same ramp, which the smears redrew sharp (alpha 1 where the exposure
/// gives 0.56) until they left their own surface alone.
#[test]
fn a_shape_moving_over_nothing_leaves_the_exposure_s_alpha_ramp_without_seams() {
    let (f, left) = parallelogram_over_nothing();
    let w = f.width;
    for (anchor, exposure) in [(Anchor::Centre, [-0.25, 0.25]), (Anchor::Rear, [-0.5, 0.0])] {
        let params = StretchParams {
            anchor,
            ..StretchParams::default()
        };
        let out = shutter::motion::stretch::stretch(f.clone(), &params, 0.5);
        let color = out.color.unwrap();
        let alpha = color.a.unwrap();
        let mut worst = 0.0f32;
        for i in 0..f.pixel_count() {
            let (x, y) = (i % w, i / w);
            // Every pixel of every row the shape covers, inside it and out.
            let Some(l) = left(y) else {
                assert_eq!(
                    alpha[i], 0.0,
                    "{anchor:?} ({x}, {y}) above or below the shape"
                );
                continue;
            };
            let want = coverage(x, l, 32.0, exposure);
            let what = format!("{anchor:?} ({x}, {y})");
            // Midpoint samples (17 over the streak) against the integral: within 0.014.
            assert!(
                (alpha[i] - want).abs() <= 0.02,
                "{what}: alpha {} not {want}",
                alpha[i]
            );
            // Premultiplied: the colour with that coverage.
            assert!(
                (color.r[i] - 0.8 * alpha[i]).abs() <= 1e-6,
                "{what}: red {}",
                color.r[i]
            );
            worst = worst.max((alpha[i] - want).abs());
        }
        eprintln!("{anchor:?}: largest difference from the exposure's alpha {worst}");
    }
}

/// An opaque frame: the parallelogram over a far, still, opaque background. With the
/// pre-blur, each pixel of a moving surface is its surface averaged along its motion, what
/// lies behind it where the streak leaves it (the background's colour in proportion to the
/// exposure's coverage, worked out as above); the smears are drawn beside it, not over it.
/// They were drawn over it too, the sharp colour at the talk's opacity, up to 1 at the inner
/// vertex, so a line a pixel or two wide along the inside of every moving silhouette came out
/// sharp, with the pre-blur's partly revealed background beside it a dark seam.
#[test]
fn a_smear_is_not_drawn_over_its_own_pre_blurred_surface() {
    let (mut f, left) = parallelogram_over_nothing();
    let w = f.width;
    let background = [0.1f32, 0.3, 0.6];
    let c = f.color.as_mut().unwrap();
    let a = c.a.as_mut().unwrap();
    let covered: Vec<bool> = a.iter().map(|&a| a == 1.0).collect();
    for (plane, value) in [&mut c.r, &mut c.g, &mut c.b].into_iter().zip(background) {
        for (p, &inside) in plane.iter_mut().zip(&covered) {
            if !inside {
                *p = value;
            }
        }
    }
    a.fill(1.0);
    for (z, &inside) in f.depth.as_mut().unwrap().iter_mut().zip(&covered) {
        if !inside {
            *z = 100.0;
        }
    }
    for (anchor, exposure) in [(Anchor::Centre, [-0.25, 0.25]), (Anchor::Rear, [-0.5, 0.0])] {
        let params = StretchParams {
            anchor,
            ..StretchParams::default()
        };
        let out = shutter::motion::stretch::stretch(f.clone(), &params, 0.5);
        let color = out.color.unwrap();
        for i in (0..f.pixel_count()).filter(|&i| covered[i]) {
            let (x, y) = (i % w, i / w);
            let l = left(y).unwrap();
            let cover = coverage(x, l, 32.0, exposure);
            let what = format!("{anchor:?} ({x}, {y})");
            for (got, (fg, bg)) in [&color.r, &color.g, &color.b]
                .into_iter()
                .zip([0.8, 0.4, 0.2].into_iter().zip(background))
            {
                let want = bg + (fg - bg) * cover;
                assert!(
                    (got[i] - want).abs() <= 0.02,
                    "{what}: {} not {want}",
                    got[i]
                );
            }
        }
    }
}

/// Motion past the mesh's cut (MAX_SHIFT px over the longer side of the exposure) is cut the
/// same in every stage, so every speed beyond it gives one picture. The pre-blur read the
/// uncut motion (an outside tester's finding): a box moving 2,000 px a frame came out 0.84
/// red at its centre, 20,000 the background alone and 100,000 the box sharp, while the mesh
/// drew the same cut smear for all three.
#[test]
fn motion_beyond_the_cut_gives_one_picture_whatever_its_speed() {
    let (w, h) = (96, 40);
    let n = w * h;
    let boxed = |i: usize| (30..60).contains(&(i % w)) && (12..28).contains(&(i / w));
    let checker = |i: usize| {
        if (i % w / 4 + i / w / 4).is_multiple_of(2) {
            0.2
        } else {
            0.6
        }
    };
    let blurred = |speed: f32| {
        let mut f = Frame::new(w, h);
        f.color = Some(shutter::frame::Color {
            r: (0..n)
                .map(|i| if boxed(i) { 1.0 } else { checker(i) })
                .collect(),
            g: (0..n)
                .map(|i| if boxed(i) { 0.2 } else { checker(i) })
                .collect(),
            b: (0..n)
                .map(|i| if boxed(i) { 0.0 } else { checker(i) })
                .collect(),
            a: None,
        });
        f.depth = Some((0..n).map(|i| if boxed(i) { 2.0 } else { 10.0 }).collect());
        f.velocity = Some(Velocity {
            x: (0..n).map(|i| if boxed(i) { speed } else { 0.0 }).collect(),
            y: vec![0.0; n],
        });
        let out = shutter::motion::stretch::stretch(f, &StretchParams::default(), 0.5);
        out.color.unwrap()
    };
    let cut = blurred(1_000.0);
    let centre = 20 * w + 45;
    assert!(
        cut.r[centre] < 0.9,
        "the box's centre is blurred: {}",
        cut.r[centre]
    );
    for speed in [2_000.0, 20_000.0, 100_000.0] {
        let got = blurred(speed);
        assert!(
            got.r == cut.r && got.g == cut.g && got.b == cut.b,
            "{speed} px a frame: centre {} where 1000 px gives {}",
            got.r[centre],
            cut.r[centre]
        );
    }
}
