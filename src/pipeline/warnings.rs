//! What the numeric policy replaced in a pass, in words: named by the pass's kind (a painted
//! CoC map is not depth), its file and the first frame it was found in.

use crate::io::passes::Inputs;
use crate::io::sequence::PathPattern;
use crate::numeric::{DepthKind, Replaced, HUGE, POSITION_LIMIT, VELOCITY_LIMIT};

/// The warnings, the first time each pass has values replaced by the numeric policy, of what
/// they became, in which file (where the job reads one file a pass: a stack's layers each
/// have their own, `layered`) and from which frame. `seen`: what earlier frames replaced.
pub(super) fn replaced_warnings(
    replaced: &Replaced,
    seen: &Replaced,
    frame: Option<i64>,
    inputs: &Inputs,
    layered: bool,
    kind: DepthKind,
) -> Vec<String> {
    let file = |pattern: Option<&PathPattern>| {
        let pattern = pattern.unwrap_or(&inputs.color);
        match layered {
            true => String::new(),
            false => format!(" in {}", pattern.path(frame).display()),
        }
    };
    let at = frame.map_or(String::new(), |f| format!(", first in frame {f}"));
    let depth = match kind {
        // A painted map: NaN is in focus, a negative blur none (`numeric::coc_map`).
        DepthKind::CocMap => "CoC map values NaN or negative read as 0 (in focus)".to_string(),
        DepthKind::Depth => "depth values NaN read as far, negative as 0".to_string(),
    };
    let positions = file(inputs.prev.as_ref().or(inputs.next.as_ref()));
    let cases = [
        (
            replaced.color,
            seen.color,
            format!("colour values NaN or beyond ±{HUGE:e} read as 0 or clamped"),
            file(None),
        ),
        (
            replaced.depth,
            seen.depth,
            depth,
            file(inputs.depth.as_ref()),
        ),
        (
            replaced.velocity,
            seen.velocity,
            format!(
                "velocity values NaN or beyond ±{VELOCITY_LIMIT:e} px read as still or clamped"
            ),
            file(inputs.velocity.as_ref()),
        ),
        (
            replaced.positions,
            seen.positions,
            format!("positions NaN or beyond ±{POSITION_LIMIT:e} px read as still or clamped"),
            positions,
        ),
    ];
    (cases.into_iter())
        .filter(|(now, before, _, _)| *now > 0 && *before == 0)
        .map(|(_, _, what, file)| format!("{what}{file}{at}; the JSON summary counts them"))
        .collect()
}
