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
