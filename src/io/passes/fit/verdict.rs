//! The fit's verdict ([`super`]): its readings, which is chosen, or why none is, in words.

use serde::Serialize;

use crate::io::preset::{Meaning, Units};

/// One reading of the stored values and how well it fits.
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct Reading {
    pub meaning: Meaning,
    /// The file's second component is x.
    pub swap: bool,
    pub y_up: bool,
    pub zero: f32,
    pub scale: f32,
    pub units: Units,
    /// RMS distance in pixels between the motion this reading gives and the motion measured,
    /// each point's distance capped at [`TRUNCATE`].
    pub residual: f64,
    /// RMS in pixels of the motion this reading gives at the points (not capped): under
    /// [`STILL`] the reading says no motion.
    pub motion: f64,
    /// The scale fitted (one for both axes) in pixels per stored unit on each axis (the
    /// units' factor applied), before rounding.
    pub fitted_scale: [f64; 2],
    /// Whether the reading's scale is positive (else no preset can state it).
    pub consistent: bool,
}

/// A distance beyond which a point counts as not fitting at all (occlusion, a mismatch).
pub const TRUNCATE: f64 = 1.0;

/// Motion under this (pixels, RMS over the points, uncapped) is no motion: the sub-pixel
/// refinement's error on a real render, and what a reading of near-zero scale gives.
pub const STILL: f64 = 0.25;

impl Reading {
    /// Whether the reading moves the points by less than measured motion must to count
    /// ([`STILL`]): a scale near zero, no motion whatever it scores.
    pub fn is_still(&self) -> bool {
        self.motion < STILL
    }
}

/// The verdict: the best reading, unless nothing fits clearly better than no motion, a
/// different reading fits about as well, or an axis never moves. `no_motion` is no motion's
/// residual toward the best reading's neighbour, capped as the readings' are, and the plain
/// RMS of the motion measured there; `points` the points measured.
pub(super) fn decide(
    readings: &[Reading],
    [no_motion, moved]: [f64; 2],
    points: usize,
    varying: [bool; 2],
) -> (Option<Reading>, Option<String>) {
    let nothing = |best: &str| {
        Some(format!(
            "nothing fits clearly better than no motion ({best} against {no_motion:.2} px \
             without motion, each point's error capped at {TRUNCATE} px)"
        ))
    };
    let Some(best) = readings.first() else {
        if points >= 8 {
            // Points were followed, but every reading's scale came out negative or zero.
            return (None, nothing("no reading has a positive scale"));
        }
        return (
            None,
            Some("no textured point could be followed to a neighbouring frame: give frames with detail and a neighbour on each side".into()),
        );
    };
    if moved < STILL || best.residual > 0.5 * no_motion {
        return (None, nothing(&format!("best {:.2} px", best.residual)));
    }
    if best.is_still() {
        return (
            None,
            nothing(&format!(
                "the best reading fits to {:.2} px but moves the points by {:.2} px: it is no \
                 motion itself",
                best.residual, best.motion
            )),
        );
    }
    if !best.consistent {
        return (
            None,
            Some("the best reading has no positive scale: no preset states it".into()),
        );
    }
    if !varying[0] || !varying[1] {
        return (
            None,
            Some(
                "one stored component never changes: that axis's sign and scale cannot be seen \
                 (a pan along one axis says nothing of the other); give frames where both move"
                    .into(),
            ),
        );
    }
    let alike = readings.iter().skip(1).find(|r| {
        r.residual <= best.residual * 1.25 + 0.05
            && (r.meaning != best.meaning || r.swap != best.swap || r.y_up != best.y_up)
    });
    if let Some(other) = alike {
        let reason = if other.meaning.is_backward() != best.meaning.is_backward() {
            before_and_after(best, other)
        } else {
            String::new()
        };
        return (
            None,
            Some(format!(
                "two readings fit alike: {} ({:.3} px) and {} ({:.3} px){reason}",
                describe(best),
                best.residual,
                describe(other),
                other.residual
            )),
        );
    }
    (Some(best.clone()), None)
}

/// Why a backward and a forward reading fit alike. Each fits its own scale and axes, so
/// wherever the motion before the frame is the motion after it changed the same way at
/// every point followed (not at all; scaled, as one object speeding up or slowing down
/// over a still background; reversed, one object turning back; one axis reversed, a
/// bounce), the readings' scales and axes take the change up. The change is read off the
/// two readings: the ratio of their scales signed by their directions, and which of the
/// y axis and the x/y swap they differ in, where both are offsets in the same units from
/// the same zero (a position's scale says nothing of it); otherwise it is left unsaid.
fn before_and_after(best: &Reading, other: &Reading) -> String {
    let (backward, forward) = match best.meaning.is_backward() {
        true => (best, other),
        false => (other, best),
    };
    // Normalised units scale x by the width and y by the height, so where one reading swaps
    // and the other does not, no one factor relates them.
    let comparable = backward.units == forward.units
        && (backward.units == Units::Pixels || backward.swap == forward.swap)
        && backward.zero == forward.zero
        && !backward.meaning.is_position()
        && !forward.meaning.is_position()
        && forward.scale > 0.0;
    if !comparable {
        return String::new();
    }
    // Each as the displacement over its frame step (p − p_prev, p_next − p) per stored unit:
    // velocity and to_next are those, to_prev and from_next their negatives.
    let signed = |r: &Reading| match r.meaning {
        Meaning::ToPrev | Meaning::FromNext => -r.scale,
        _ => r.scale,
    };
    let factor = signed(backward) / signed(forward);
    // A reading swaps, then mirrors y. Where both or neither swap, the motion after is the
    // motion before times 1/factor on x and, where their y axes differ, mirrored on y;
    // where one swaps, the after's x is the before's y mirrored by the backward reading's
    // y axis, its y the before's x mirrored by the forward reading's.
    let swapped = backward.swap != forward.swap;
    let (x_reversed, y_reversed) = match swapped {
        false => (
            factor < 0.0,
            (factor < 0.0) != (backward.y_up != forward.y_up),
        ),
        true => (
            (factor < 0.0) != backward.y_up,
            (factor < 0.0) != forward.y_up,
        ),
    };
    let mut change = Vec::new();
    if (factor.abs() - 1.0).abs() > 0.05 {
        change.push(format!("times {:.3}", 1.0 / factor.abs()));
    }
    if swapped {
        change.push("with x and y swapped".to_string());
    }
    change.push(
        match (x_reversed, y_reversed) {
            (true, true) => "reversed",
            (true, false) => "with its x reversed",
            (false, true) => "with its y reversed",
            (false, false) => "",
        }
        .to_string(),
    );
    change.retain(|c| !c.is_empty());
    if change.is_empty() {
        return " (the motion is the same before and after this frame, so backward and \
                 forward readings fit alike: a frame whose motion changes tells them apart)"
            .into();
    }
    format!(
        " (the motion after this frame is the motion before it {} at every point followed, \
         which the readings' scales and axes take up, so backward and forward readings fit \
         alike: a frame where things change their motion unlike one another, two objects \
         moving differently, tells them apart)",
        change.join(", ")
    )
}

/// A reading in words.
pub fn describe(r: &Reading) -> String {
    format!(
        "{:?}{}{}, zero {}, scale {} ({})",
        r.meaning,
        if r.swap { ", x/y swapped" } else { "" },
        if r.y_up { ", y up" } else { ", y down" },
        r.zero,
        r.scale,
        match r.units {
            Units::Pixels => "pixels",
            Units::Normalized => "normalised",
        }
    )
    .replace("ToPrev", "to_prev")
    .replace("ToNext", "to_next")
    .replace("FromNext", "from_next")
    .replace("Velocity", "velocity")
    .replace("PrevPosition", "prev_position")
    .replace("NextPosition", "next_position")
}
