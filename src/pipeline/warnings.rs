//! What the numeric policy replaced in a pass, in words: named by the pass's kind (a painted
//! CoC map is not depth), its file and the first frame it was found in.

use crate::io::passes::Inputs;
use crate::io::sequence::PathPattern;
use crate::numeric::{DepthKind, Replaced, HUGE, POSITION_LIMIT, VELOCITY_LIMIT};

/// The warnings, the first time each pass has values replaced by the numeric policy, of what
/// they became, in which file and from which frame. `each`: what each frame read replaced (a
/// frame's views summed as one; a stack's layers each apart, named with the file they were
/// read from, `layers` giving each its name and inputs); `seen`: what earlier frames replaced,
/// each layer's apart, updated here.
pub(super) fn replaced_warnings(
    each: &[Replaced],
    seen: &mut Vec<Replaced>,
    frame: Option<i64>,
    inputs: &Inputs,
    layers: &[(&str, &Inputs)],
    kind: DepthKind,
) -> Vec<String> {
    let mut whole = Replaced::default();
    let reads: Vec<(Replaced, Option<&str>, &Inputs)> = if layers.is_empty() {
        each.iter().for_each(|r| whole.add(*r));
        vec![(whole, None, inputs)]
    } else {
        (each.iter().zip(layers))
            .map(|(r, (name, inputs))| (*r, Some(*name), *inputs))
            .collect()
    };
    seen.resize(reads.len().max(seen.len()), Replaced::default());
    let mut warnings = Vec::new();
    for ((replaced, layer, inputs), seen) in reads.into_iter().zip(seen.iter_mut()) {
        warnings.extend(replaced_in(&replaced, seen, frame, inputs, layer, kind));
        seen.add(replaced);
    }
    warnings
}

/// [`replaced_warnings`] of one read: the job's frame, or the stack's view layer `layer`.
fn replaced_in(
    replaced: &Replaced,
    seen: &Replaced,
    frame: Option<i64>,
    inputs: &Inputs,
    layer: Option<&str>,
    kind: DepthKind,
) -> Vec<String> {
    let file = |pattern: Option<&PathPattern>| {
        let pattern = pattern.unwrap_or(&inputs.color);
        let layer = layer.map_or(String::new(), |l| format!(" (view layer {l})"));
        format!(" in {}{layer}", pattern.path(frame).display())
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
