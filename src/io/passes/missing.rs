//! A needed pass's channels not found in a file, said so that the user can act on it: a
//! preset that lists none, a part shutter cannot read, a channel the colour pass already
//! reads, or what the file has and what the preset expects.

use crate::error::{Problem, ProblemKind};
use crate::io::file::FileInfo;
use crate::io::preset::Preset;

/// The problem of pass `pass` of `info`, whose channels `wanted` (alternatives joined by " or ",
/// a set's names by ",") the preset names and the planner did not find. `colour_took`: the
/// channels of `info` the colour pass reads (a channel is read as one pass only), empty where
/// `info` is not the colour file.
pub(super) fn missing_problem(
    (preset, layer): (&Preset, Option<&str>),
    info: &FileInfo,
    pass: &'static str,
    wanted: &str,
    colour_took: &[usize],
) -> Problem {
    // A preset listing no channel for the pass (`channels = []`) looks for nothing.
    if wanted.trim().is_empty() {
        let (name, list) = (&preset.name, info.channel_list());
        let why = format!(
            "preset {name} lists no channels for this pass ([{pass}] channels is empty); the \
             file has {list}"
        );
        return Problem::new(ProblemKind::MissingChannel, &info.path, why).pass(pass);
    }
    // In a part shutter cannot read (HTJ2K, ZSTD, deep data): not missing, unsupported.
    let names: Vec<&str> = wanted.split(" or ").flat_map(|a| a.split(',')).collect();
    if let Some(detail) = info.unread_among(&names) {
        return Problem::new(ProblemKind::Unsupported, &info.path, detail)
            .pass(pass)
            .channel(wanted.to_string());
    }
    // In the file, but read as colour: a preset whose [color] channels take this pass's
    // (`[color] channels = [["Z", "Z", "Z"]]` to see a depth pass) would otherwise hear that
    // Z is not in a file whose channel list names it.
    let resolved = |n: &str| match layer {
        Some(l) => n.replace("{layer}", l),
        None => n.to_string(),
    };
    let mut taken: Vec<String> = (names.iter().map(|n| resolved(n)))
        .filter(|n| info.find(n).is_some_and(|c| colour_took.contains(&c)))
        .collect();
    taken.dedup();
    if !taken.is_empty() {
        let (is, them) = if taken.len() == 1 {
            ("is", "it")
        } else {
            ("are", "them")
        };
        let why = format!(
            "{} {is} in the file, but preset {}'s [color] channels read {them} as colour, and a \
             channel is read as one pass only: use a preset whose [color] channels are others",
            crate::error::printable(&taken.join(", ")),
            preset.name,
        );
        return Problem::new(ProblemKind::MissingChannel, &info.path, why)
            .pass(pass)
            .channel(wanted.to_string());
    }
    Problem::new(
        ProblemKind::MissingChannel,
        &info.path,
        format!(
            "not in the file with preset {}{}; the file has {}{}",
            preset.name,
            layer
                .filter(|_| wanted.contains("{layer}"))
                .map_or(String::new(), |l| format!(" for view layer {l}")),
            info.channel_list(),
            // What the renderer must write for the preset (F8: MRQ's depth pass).
            Some(&preset.expects)
                .filter(|e| !e.is_empty())
                .map_or(String::new(), |e| format!(
                    "; preset {} expects {e}",
                    preset.name
                )),
        ),
    )
    .pass(pass)
    .channel(wanted.to_string())
}
