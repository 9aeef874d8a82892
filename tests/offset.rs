//! The shutter offset (issue 19, point 3): an exposure that opens at the frame (`start`),
//! closes at it (`end`) or sits anywhere between, `motion::Shutter`. Every algorithm smears
//! a moving point over p(0) + v·[(o − ½)φ, (o + ½)φ], and on the truth scenes, scored
//! against references rendered over the same offset exposure, errs like the centred shutter.

use shutter::frame::{Color, Frame, Positions, Velocity};
use shutter::motion::{Algorithm, CurveKind, ReconstructParams, ScatterParams, Variant};
use shutter::process::Params;

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
