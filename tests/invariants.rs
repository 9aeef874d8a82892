//! The invariants every pass keeps (DESIGN.md "Algorithms"), as one table over every motion
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
    still: fn() -> Frame,
    poisoned: fn() -> Frame,
    /// Relative slack of the range check (float rounding of the weights' normalisation).
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
            slack: 1e-6,
        },
        Pass {
            name: "scatter",
            algorithm: Algorithm::Scatter,
            make: crate::scatter::frame,
            variants: crate::scatter::variants,
            still: crate::scatter::still,
            poisoned: crate::scatter::poisoned,
            slack: 0.0,
        },
        Pass {
            name: "stretch",
            algorithm: Algorithm::Stretch,
            make: crate::stretch::frame,
            variants: crate::stretch::variants,
            still: crate::stretch::still,
            poisoned: crate::stretch::poisoned,
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
            slack: 1e-6,
        },
    ]
}

#[test]
fn every_pass_returns_a_still_frame_unchanged() {
    for pass in table() {
        eprintln!("{}", pass.name);
        invariants::zero_motion_is_identity(pass.algorithm, &(pass.still)(), &(pass.variants)());
    }
}

#[test]
fn every_pass_keeps_a_uniform_colour_uniform() {
    for pass in table() {
        eprintln!("{}", pass.name);
        invariants::uniform_stays_uniform(pass.algorithm, pass.make, &(pass.variants)());
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
        for frame in [(pass.still)(), (pass.make)(40, 30, 7, 20.0)] {
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
