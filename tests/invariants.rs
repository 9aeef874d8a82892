//! The invariants every pass keeps (docs/DESIGN.md "Algorithms"), as one table over every motion
//! blur algorithm and depth-of-field method: each is a weighted average of input colours
//! with non-negative weights, so a still (or in-focus) frame comes back unchanged, a uniform
//! colour stays uniform, every output channel stays within its input range, and hostile
//! values give finite output; and every pass returns colour alone, on every path. Each area
//! module gives its frames (`frame`, `still`, `poisoned`) and its settings (`variants`).

use shutter::frame::Frame;
use shutter::motion::Algorithm;
use shutter::process::{apply, Params};

use crate::support::invariants::{self, Make};

/// One row of the table.
struct Pass {
    name: &'static str,
    algorithm: Algorithm,
    make: Make,
    variants: fn() -> Vec<Params>,
    /// A `w`×`h` frame in which nothing moves (or is out of focus), sub-half-pixel motion
    /// (or blur) at its right edge included.
    still: fn(usize, usize) -> Frame,
    poisoned: fn() -> Frame,
    /// How far right of a moving (or defocused) strip still pixels must come out unchanged:
    /// beyond the pass's reach from it on the 384 px wide frames of that check (the reaches
    /// below were measured on them).
    far: usize,
    /// Relative slack of the range and uniform checks (float rounding of the weights'
    /// normalisation: reconstruct's 2014 variants give a uniform 0.7 back as 0.70000005).
    slack: f32,
}

fn table() -> [Pass; 4] {
    [
        Pass {
            name: "reconstruct",
            algorithm: Algorithm::Reconstruct,
            make: crate::reconstruct::frame,
            variants: crate::reconstruct::variants,
            still: crate::reconstruct::still,
            poisoned: crate::reconstruct::poisoned,
            // Streaks of up to 11 px each way (up to 20 px per frame on each axis, under a
            // 0.75 shutter), gathered over tiles of up to 20 px and their neighbours (2012)
            // or 8 px tiles dilated by a tile (2014). Changes reach 10 px past the strip.
            far: 64,
            slack: 1e-6,
        },
        Pass {
            name: "scatter",
            algorithm: Algorithm::Scatter,
            make: crate::scatter::frame,
            variants: crate::scatter::variants,
            still: crate::scatter::still,
            poisoned: crate::scatter::poisoned,
            // Curves through p(∓1) up to 38 px away, exposed over ±0.375 of a frame. Changes
            // reach 9 px past the strip.
            far: 64,
            slack: 0.0,
        },
        Pass {
            name: "stretch",
            algorithm: Algorithm::Stretch,
            make: crate::stretch::frame,
            variants: crate::stretch::variants,
            still: crate::stretch::still,
            poisoned: crate::stretch::poisoned,
            // Streaks of up to 11 px each way. Changes reach 10 px past the strip.
            far: 64,
            slack: 0.0,
        },
        Pass {
            // Depth of field alone (gather and blend, in `variants`).
            name: "depth of field",
            algorithm: Algorithm::None,
            make: crate::dof::frame,
            variants: crate::dof::variants,
            still: crate::dof::still,
            poisoned: crate::dof::poisoned,
            // At 384 px wide the strong lens's CoCs (10–13 px at 64 px wide) reach the 48 px
            // cap: the gather spreads them 24 px, blend's copies about twice the cap (each
            // binomial blur reaches about the cap, and the second copy is blurred from the
            // first). Changes reach 24 px past the strip (gather), 54 (blend) and 94 (the
            // talk's form).
            far: 112,
            slack: 1e-6,
        },
    ]
}

/// Where nothing moves (or nothing is out of focus), each pass returns the frame before its
/// first stage: this guards that early return.
#[test]
fn every_pass_returns_a_frame_where_nothing_moves_unchanged() {
    for pass in table() {
        eprintln!("{}", pass.name);
        let still = (pass.still)(57, 31);
        invariants::zero_motion_is_identity(pass.algorithm, &still, &(pass.variants)());
    }
}

/// The stages themselves: with motion (or defocus) in a strip at the left edge, the whole
/// pass runs, and the still (in-focus) pixels far from the strip, sub-half-pixel motion
/// included, come out bit for bit unchanged, for every variant of every pass.
#[test]
fn every_pass_leaves_still_pixels_far_from_motion_unchanged() {
    // Wider than scatter's tiles (256 px), so that still pixels are checked both in a tile
    // the strip's curves reach and in one they do not; wider than a few of every other
    // pass's tiles too.
    let (w, h) = (384, 32);
    for pass in table() {
        eprintln!("{}", pass.name);
        invariants::still_far_from_motion_is_identity(
            pass.algorithm,
            &(pass.still)(w, h),
            &(pass.make)(w, h, 1, 20.0),
            &(pass.variants)(),
            pass.far,
        );
    }
}

#[test]
fn every_pass_keeps_a_uniform_colour_uniform() {
    for pass in table() {
        eprintln!("{}", pass.name);
        invariants::uniform_stays_uniform(
            pass.algorithm,
            pass.make,
            &(pass.variants)(),
            pass.slack,
        );
    }
}

#[test]
fn every_pass_stays_within_the_input_range_per_channel() {
    for pass in table() {
        eprintln!("{}", pass.name);
        invariants::within_input_range(pass.algorithm, pass.make, &(pass.variants)(), pass.slack);
    }
}

#[test]
fn every_pass_gives_finite_output_for_nan_inf_and_huge_input() {
    for pass in table() {
        eprintln!("{}", pass.name);
        invariants::finite_output(pass.algorithm, &(pass.poisoned)(), &(pass.variants)());
    }
}

#[test]
fn every_pass_returns_colour_alone_on_every_path() {
    // The same shape whether the pass blurs or returns early: colour with alpha where the
    // input had it, and no other pass.
    for pass in table() {
        for frame in [(pass.still)(57, 31), (pass.make)(40, 30, 7, 20.0)] {
            for params in (pass.variants)() {
                let out = apply(pass.algorithm, &params, frame.clone(), 1);
                let what = pass.name;
                assert!(out.color.as_ref().is_some_and(|c| c.a.is_some()), "{what}");
                assert!(out.depth.is_none() && out.velocity.is_none(), "{what}");
                assert!(out.prev.is_none() && out.next.is_none(), "{what}");
                assert_eq!(
                    (out.width, out.height),
                    (frame.width, frame.height),
                    "{what}"
                );
            }
        }
    }
}
