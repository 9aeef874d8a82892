//! The shutter offset (issue 19, point 3): an exposure that opens at the frame (`start`),
//! closes at it (`end`) or sits anywhere between, `motion::Shutter`. Every algorithm smears
//! a moving point over p(0) + v·[(o − ½)φ, (o + ½)φ], and on the truth scenes, scored
//! against references rendered over the same offset exposure, errs like the centred shutter.

use shutter::frame::{Color, Frame, Positions, Velocity};
use shutter::motion::{Algorithm, CurveKind, ReconstructParams, ScatterParams, Variant};
use shutter::process::Params;

use crate::support::rgb;

/// A 4×4 white square at x ∈ [30, 34), y ∈ [8, 12) on black, moving +10 px a frame (every
/// pass: velocity and positions), nearer than the still background.
fn moving_square() -> Frame {
    let (w, h) = (72, 20);
    let n = w * h;
    let inside = |i: usize| (30..34).contains(&(i % w)) && (8..12).contains(&(i / w));
    let value = |f: &dyn Fn(usize) -> f32| (0..n).map(f).collect::<Vec<f32>>();
    let mut f = Frame::new(w, h);
    let white = value(&|i| inside(i) as u32 as f32);
    f.color = Some(Color {
        r: white.clone(),
        g: white.clone(),
        b: white,
        a: Some(vec![1.0; n]),
    });
    f.depth = Some(value(&|i| if inside(i) { 1.0 } else { 10.0 }));
    let vx = value(&|i| if inside(i) { 10.0 } else { 0.0 });
    f.velocity = Some(Velocity {
        x: vx.clone(),
        y: vec![0.0; n],
    });
    let centre_x = value(&|i| (i % w) as f32 + 0.5);
    let centre_y = value(&|i| (i / w) as f32 + 0.5);
    let shifted = |sign: f32| Positions {
        x: centre_x
            .iter()
            .zip(&vx)
            .map(|(x, v)| x + sign * v)
            .collect(),
        y: centre_y.clone(),
        z: None,
    };
    f.prev = Some(shifted(-1.0));
    f.next = Some(shifted(1.0));
    f
}

/// Every algorithm and variant with its own name, shutter 1 (a 10 px streak).
fn runs(offset: f32) -> Vec<(String, Algorithm, Params)> {
    let base = Params {
        shutter: 1.0,
        shutter_offset: offset,
        ..Params::default()
    };
    let mut runs = Vec::new();
    for (name, variant) in Variant::ALL {
        let reconstruct = ReconstructParams {
            variant: *variant,
            ..ReconstructParams::default()
        };
        runs.push((
            format!("reconstruct {name}"),
            Algorithm::Reconstruct,
            Params {
                reconstruct,
                ..base
            },
        ));
    }
    for (name, curve) in CurveKind::ALL {
        let scatter = ScatterParams {
            curve: *curve,
            ..ScatterParams::default()
        };
        runs.push((
            format!("scatter {name}"),
            Algorithm::Scatter,
            Params { scatter, ..base },
        ));
    }
    runs.push(("stretch".into(), Algorithm::Stretch, base));
    runs
}

/// How much each column of the square's rows changed, summed over the rows.
fn column_change(input: &Frame, output: &Frame) -> Vec<f32> {
    let w = input.width;
    let (a, b) = (
        &input.color.as_ref().unwrap().r,
        &output.color.as_ref().unwrap().r,
    );
    (0..w)
        .map(|x| (8..12).map(|y| (b[y * w + x] - a[y * w + x]).abs()).sum())
        .collect()
}

#[test]
fn an_exposure_opening_at_the_frame_streaks_ahead_only() {
    // The square covers x ∈ [30, 34) at the frame and moves 10 px over the exposure: opening
    // at the frame, the streak is [30, 44): nothing changes behind (x < 30) and the square
    // reaches x ∈ [36, 42]; closing at the frame, [20, 34): nothing ahead (x ≥ 34), x ∈
    // [22, 28] reached; centred, [25, 39): both sides.
    let input = moving_square();
    for (offset, behind, ahead) in [(0.5f32, 0..30, 36..43), (-0.5, 34..72, 22..29)] {
        for (name, algorithm, params) in runs(offset) {
            let out = shutter::process::apply(algorithm, &params, input.clone(), 1);
            let change = column_change(&input, &out);
            let leak = behind.clone().map(|x| change[x]).fold(0.0f32, f32::max);
            assert!(
                leak <= 1e-5,
                "{name}, offset {offset}: x {behind:?} (outside the streak) changed by {leak}"
            );
            let reached = ahead.clone().filter(|&x| change[x] > 0.05).count();
            assert_eq!(
                reached,
                ahead.len(),
                "{name}, offset {offset}: the streak does not reach x {ahead:?}: {change:?}"
            );
        }
    }
    // Centred, both sides move (so the test would see an offset that is ignored).
    for (name, algorithm, params) in runs(0.0) {
        let out = shutter::process::apply(algorithm, &params, input.clone(), 1);
        let change = column_change(&input, &out);
        assert!(
            change[27] > 0.05 && change[36] > 0.05,
            "{name} centred: {change:?}"
        );
    }
}

/// Each setting's whole-frame RMSE against the motion reference of `scene` at 160×90 over
/// the exposure with offset `offset` (shutter 0.5, 256 samples), from the passes at the
/// frame run with that offset; and, for comparison, from the passes rendered at the
/// exposure's middle (t = offset·φ) run centred: the same exposure under the centred
/// shutter. Returns (setting, offset error, centred error on the same exposure).
fn offset_errors(name: &str, offset: f32) -> Vec<(String, f64, f64)> {
    use shutter::lab::metrics::rmse;
    use shutter::lab::truth::render::{render_passes, render_reference, Reference, RenderSettings};
    let (w, h) = (160, 90);
    let scene = shutter::lab::truth::scenes::build(name, w, h, 1).unwrap();
    let settings = RenderSettings {
        samples: 256,
        shutter: 0.5,
        shutter_offset: offset as f64,
        seed: 1,
    };
    let reference = render_reference(&scene, 0.0, Reference::MotionBlur, &settings);
    let at_frame = render_passes(&scene, 0.0, 256, 1);
    let at_middle = render_passes(&scene, 0.5 * offset as f64, 256, 1);
    let score = |frame: &Frame| {
        let c = frame.color.clone().unwrap();
        rmse(&rgb(&[c.r, c.g, c.b], w, h), &rgb(&reference, w, h), None)
    };
    let mut rows = vec![("none".to_string(), score(&at_frame), score(&at_middle))];
    for (label, algorithm, params) in runs(offset) {
        let params = Params {
            shutter: 0.5,
            ..params
        };
        let centred = Params {
            shutter_offset: 0.0,
            ..params
        };
        let offset_out = shutter::process::apply(algorithm, &params, at_frame.clone(), 1);
        let centred_out = shutter::process::apply(algorithm, &centred, at_middle.clone(), 1);
        rows.push((label, score(&offset_out), score(&centred_out)));
    }
    rows
}

#[test]
fn offset_exposures_err_like_the_centred_shutter_on_truth_scenes() {
    // An offset exposure asks for more than the centred one from the same frame: the image
    // must move half a streak as well as blur (the unblurred frame errs twice as much), and
    // what the exposure uncovers behind a moving edge, hidden in the frame, is a whole streak
    // wide on one side instead of half a streak on each (scatter, which follows the offset
    // exactly, ratio 1.00 where nothing is hidden, errs 1.6–2.6× its centred error here).
    // So the level compared is each error as a share of the unblurred frame's, the offset
    // run from the passes at the frame against the centred run on the same exposure (the
    // passes rendered at its middle). Measured at 160×90 (BENCHMARKS.md, "Shutter offset"):
    // scatter 0.89–1.08; reconstruct 0.64–1.53, the highest on `rotor` opening at the frame
    // (its velocity, p(0) − p(−1), is the motion of the frame before: extrapolated over the
    // frame after, a turning blade's streak bends away from it; closing at the frame, 0.87–
    // 1.30); stretch 0.64–1.04 (2.0–2.97 before its texture blur read the frame where the
    // surface was during the exposure, x − v·t, instead of x + v·t: the same when centred,
    // the streak's mirror image when offset).
    let mut worse = Vec::new();
    for name in ["crossing", "sparse", "pan", "rotor"] {
        for offset in [0.5f32, -0.5] {
            let rows = offset_errors(name, offset);
            let (none, none_centred) = (rows[0].1, rows[0].2);
            for (label, err, centred) in &rows[1..] {
                let ratio = (err / none) / (centred / none_centred);
                eprintln!(
                    "offset: {name} {offset:+} {label}: {err:.5} of none {none:.5}; centred on \
                     the same exposure {centred:.5} of none {none_centred:.5}; level ratio \
                     {ratio:.2}"
                );
                if ratio > LEVEL_TOLERANCE {
                    worse.push(format!("{name} {offset} {label}: level ratio {ratio:.2}"));
                }
            }
        }
    }
    assert!(worse.is_empty(), "{worse:#?}");
}

/// How much higher an offset error may be than the centred one, each as a share of the
/// unblurred frame's error (measured up to 1.53 for reconstruct, 1.08 for scatter, 1.29 for
/// stretch: rotor, whose centred error halved when its smears left their own surface alone).
const LEVEL_TOLERANCE: f64 = 1.65;

/// An 8×8 square at x ∈ [28, 36), y ∈ [8, 16) textured along x (a sine of 8 px period),
/// moving +10 px a frame over a still black background, and its exact exposure: each pixel
/// centre sampled at 4000 instants over [(o − ½)φ, (o + ½)φ]. Nothing the exposure shows is
/// hidden in the frame (the background is uniform), so a correct offset errs as the centred
/// shutter does.
fn textured_square(shutter: f32, offset: f32) -> (Frame, [Vec<f32>; 3]) {
    let (w, h) = (80, 24);
    let texture = |u: f32| {
        let r = 0.5 + 0.4 * (u * std::f32::consts::TAU / 8.0).sin();
        [r, 1.0 - 0.5 * r, 0.3]
    };
    let rows = 8..16;
    let mut f = moving_square();
    f.width = w;
    f.height = h;
    let n = w * h;
    let at = |i: usize| ((i % w) as f32 + 0.5, i / w);
    let inside = |i: usize| {
        let (x, y) = at(i);
        rows.contains(&y) && (28.0..36.0).contains(&x)
    };
    let color = |i: usize, ch: usize| {
        if inside(i) {
            texture(at(i).0 - 28.0)[ch]
        } else {
            0.0
        }
    };
    f.color = Some(Color {
        r: (0..n).map(|i| color(i, 0)).collect(),
        g: (0..n).map(|i| color(i, 1)).collect(),
        b: (0..n).map(|i| color(i, 2)).collect(),
        a: Some(vec![1.0; n]),
    });
    f.depth = Some((0..n).map(|i| if inside(i) { 1.0 } else { 10.0 }).collect());
    let vx: Vec<f32> = (0..n).map(|i| if inside(i) { 10.0 } else { 0.0 }).collect();
    f.velocity = Some(Velocity {
        x: vx.clone(),
        y: vec![0.0; n],
    });
    let shifted = |sign: f32| Positions {
        x: (0..n).map(|i| at(i).0 + sign * vx[i]).collect(),
        y: (0..n).map(|i| at(i).1 as f32 + 0.5).collect(),
        z: None,
    };
    f.prev = Some(shifted(-1.0));
    f.next = Some(shifted(1.0));
    let (t0, t1) = shutter::motion::Shutter {
        open: shutter,
        offset,
    }
    .interval();
    let steps = 4000;
    let mut reference = [vec![0.0f32; n], vec![0.0f32; n], vec![0.0f32; n]];
    for i in 0..n {
        let (x, y) = at(i);
        if !rows.contains(&y) {
            continue;
        }
        for s in 0..steps {
            let t = t0 + (t1 - t0) * (s as f32 + 0.5) / steps as f32;
            let u = x - 10.0 * t - 28.0;
            if (0.0..8.0).contains(&u) {
                let c = texture(u);
                for ch in 0..3 {
                    reference[ch][i] += c[ch] / steps as f32;
                }
            }
        }
    }
    (f, reference)
}

#[test]
fn with_nothing_hidden_an_offset_errs_as_the_centred_shutter() {
    use shutter::lab::metrics::rmse;
    // Shutter 0.4 at 10 px a frame: a 4 px streak, moved 2 whole pixels by start or end.
    let score = |offset: f32, algorithm: Algorithm, params: &Params| {
        let (frame, reference) = textured_square(0.4, offset);
        let (w, h) = (frame.width, frame.height);
        let params = Params {
            shutter: 0.4,
            shutter_offset: offset,
            ..*params
        };
        let out = shutter::process::apply(algorithm, &params, frame, 1);
        let c = out.color.unwrap();
        rmse(&rgb(&[c.r, c.g, c.b], w, h), &rgb(&reference, w, h), None)
    };
    let mut worse = Vec::new();
    for (label, algorithm, params) in runs(0.0) {
        let centred = score(0.0, algorithm, &params);
        for offset in [0.5f32, -0.5] {
            let err = score(offset, algorithm, &params);
            eprintln!(
                "offset: square {offset:+} {label}: {err:.5} (centred {centred:.5}, ratio {:.2})",
                err / centred
            );
            let tolerance = match algorithm {
                Algorithm::Stretch => STRETCH_OFFSET_TOLERANCE,
                _ => OFFSET_TOLERANCE,
            };
            if err > tolerance * centred + 1e-4 {
                worse.push(format!(
                    "{label}, offset {offset}: {err} against {centred} centred"
                ));
            }
        }
    }
    assert!(worse.is_empty(), "{worse:#?}");
}

/// How much more an offset exposure may err than the centred one where nothing is hidden
/// (BENCHMARKS.md, "Shutter offset"): measured scatter 1.00 (the curve is cut at the
/// offset interval, so the output is the centred one moved 2 px, bit for bit but for the
/// border), reconstruct paper and dual 1.16–1.25, exposure 1.14–1.15, 2014 0.33–0.34 (an
/// offset gather looks up its own tile where the jittered lookup finds a still one; the
/// exposure variant does so centred too, Blender's 2014 form does not and misses the square's
/// corners), stretch: [`STRETCH_OFFSET_TOLERANCE`].
const OFFSET_TOLERANCE: f64 = 1.35;

/// [`OFFSET_TOLERANCE`] for stretch, measured 2.09–2.30 (0.0179 and 0.0196 against 0.0085
/// centred): with its texture blur the inside of the square is right either way (within 0.01
/// of the exposure on the rows measured), and what errs is the smears beside it, the talk's
/// opacity and the sharp colour of the silhouette stretched: one 4-px smear at the front (or
/// back) for an offset exposure against 2 px at each side centred. It was 1.05–1.30 while the
/// smears were drawn over the square's own pre-blurred pixels too, which cost the centred
/// exposure as much as the offset ones (0.0172 centred, 0.0181 and 0.0225 offset); 3.5–3.7
/// with its texture blur reading x + v·t, the fault this guards.
const STRETCH_OFFSET_TOLERANCE: f64 = 2.5;

#[test]
fn the_exposure_variant_keeps_a_small_fast_squares_corners_centred() {
    use shutter::lab::metrics::rmse;
    // Centred, the jittered tile lookup of Blender's form (2014) lands on tiles the dilation
    // left still beside the square's corners and leaves them sharp (measured RMSE 0.0085);
    // the exposure variant looks up the pixel's own tile there (0.0016; 0.0085 before it did).
    let score = |variant: Variant| {
        let (frame, reference) = textured_square(0.4, 0.0);
        let (w, h) = (frame.width, frame.height);
        let params = Params {
            shutter: 0.4,
            reconstruct: ReconstructParams {
                variant,
                ..ReconstructParams::default()
            },
            ..Params::default()
        };
        let out = shutter::process::apply(Algorithm::Reconstruct, &params, frame, 1);
        let c = out.color.unwrap();
        rmse(&rgb(&[c.r, c.g, c.b], w, h), &rgb(&reference, w, h), None)
    };
    let (exposure, stable) = (score(Variant::Exposure), score(Variant::Stable));
    eprintln!("offset: centred square, exposure {exposure:.5}, 2014 {stable:.5}");
    assert!(exposure < 0.003, "exposure {exposure}");
    assert!(
        exposure * 3.0 < stable,
        "exposure {exposure}, 2014 {stable}"
    );
}
