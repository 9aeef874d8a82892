//! reconstruct: the invariants of DESIGN.md, numerics, determinism, and accuracy on the truth
//! scenes.

use shutter::frame::{Frame, Velocity};
use shutter::motion::{Algorithm, ReconstructParams, Variant};
use shutter::process::{apply, Params};

use crate::support::*;

pub fn frame(w: usize, h: usize, seed: u32, speed: f32) -> Frame {
    let mut f = noise_frame(w, h, seed);
    f.velocity = Some(Velocity {
        x: noise(w * h, seed + 5, -speed, speed),
        y: noise(w * h, seed + 6, -speed, speed),
    });
    f
}

pub fn variants() -> Vec<Params> {
    let mut all = Vec::new();
    for (taps, max_blur, jitter, variant) in [
        (15, 20, true, Variant::Paper),
        (5, 7, false, Variant::Paper),
        (9, 13, true, Variant::Dual),
    ] {
        all.push(Params {
            shutter: 0.75,
            reconstruct: ReconstructParams {
                max_blur,
                taps,
                jitter,
                variant,
                ..ReconstructParams::default()
            },
            ..Params::default()
        });
    }
    all
}

/// A frame the pass must leave unchanged (the invariants table, tests/invariants.rs).
pub fn still() -> Frame {
    let mut f = frame(57, 31, 1, 0.0);
    // Sub-half-pixel motion is no motion too.
    f.velocity.as_mut().unwrap().x[7] = 0.9;
    f
}

/// A frame poisoned with NaN, infinite, huge and degenerate values in every pass the pass
/// reads (the invariants table, tests/invariants.rs).
pub fn poisoned() -> Frame {
    let mut f = frame(50, 40, 4, 30.0);
    invariants::poison_color_and_depth(&mut f);
    let v = f.velocity.as_mut().unwrap();
    v.x[10] = f32::NAN;
    v.y[20] = f32::INFINITY;
    v.x[30] = -1e38;
    v.y[40] = 1e20;
    f
}

#[test]
fn zero_velocity_pixel_inside_a_moving_neighbourhood() {
    // A still pixel surrounded by motion: its weight 1/|V| must not divide by zero.
    let mut f = frame(40, 40, 5, 25.0);
    let v = f.velocity.as_mut().unwrap();
    v.x[20 * 40 + 20] = 0.0;
    v.y[20 * 40 + 20] = 0.0;
    let out = apply(Algorithm::Reconstruct, &Params::default(), f, 1);
    assert!(planes(&out).iter().all(|p| p.iter().all(|v| v.is_finite())));
}

#[test]
fn tile_grid_that_does_not_divide_the_image() {
    // 23×17 with k = 20: one full-width partial tile row and column.
    let f = frame(23, 17, 6, 30.0);
    let out = apply(Algorithm::Reconstruct, &Params::default(), f.clone(), 1);
    assert_eq!(planes(&out)[0].len(), 23 * 17);
    assert!(planes(&out)[0] != planes(&f)[0]);
}

#[test]
fn output_is_identical_for_one_and_two_threads() {
    invariants::same_bytes_for_any_thread_count(
        "reconstruct",
        "gears",
        &["color", "depth", "velocity"],
        &[],
    );
}

/// Region errors of `none` and `reconstruct` against the reference, at 160×90.
fn scene_errors(name: &str) -> (f64, f64, Frame, Frame) {
    let runs = [(Algorithm::Reconstruct, Params::default())];
    let (none, errors, passes, mut outputs) = crate::support::scene_errors(name, (160, 90), &runs);
    (none, errors[0], passes, outputs.remove(0))
}

#[test]
fn beats_the_unblurred_frame_on_rotor_and_pan() {
    for name in ["rotor", "pan"] {
        let (none, ours, _, _) = scene_errors(name);
        assert!(
            ours < 0.8 * none,
            "{name}: reconstruct {ours} vs none {none}"
        );
    }
}

#[test]
fn the_tracked_object_in_pan_stays_sharp() {
    let (_, _, passes, out) = scene_errors("pan");
    let worst = tracked_disc_change(&passes, &out);
    assert!(worst < 1e-4, "tracked object changed by {worst}");
}

#[test]
fn prev_and_next_are_never_read() {
    let dir = small_scene("crossing", 48, 27, 1, 2);
    let broken = dir.path().join("broken.exr");
    std::fs::write(&broken, b"not an exr").unwrap();
    let p = |role: &str| s(&dir.path().join(format!("{role}.0001.exr")));
    let o = shutter(&[
        "blur",
        "--algorithm",
        "reconstruct",
        "--color",
        &p("color"),
        "--depth",
        &p("depth"),
        "--velocity",
        &p("velocity"),
        "--prev",
        &s(&broken),
        "--next",
        &s(&dir.path().join("missing.exr")),
        "--json",
        "-o",
        &s(&dir.path().join("out.exr")),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let warnings = report["warnings"].to_string();
    assert!(warnings.contains("--prev is not read") && warnings.contains("--next is not read"));
}
