//! The passes a preset finds in one file on its own, from its header: what `shutter info`
//! and the preset suggestion ([`super::suggest`]) read a file with, by the planner's own
//! rules ([`find_channels`], colour first and claiming its channels).

use super::convert::Decode;
use super::plan::{find_channels, luminance};
use crate::io::file::FileInfo;
use crate::io::preset::{Preset, VectorSpec};

/// Passes found, each with the channels (indices into a file's channels) it reads.
pub(super) type PassesRead = Vec<(&'static str, Vec<usize>)>;

/// The passes a preset finds in one file on its own, each with the channels (indices into
/// `info.channels`) it reads: colour first, then depth, velocity, prev and next among the
/// channels colour did not take. A motion section whose encoding cannot read the file's
/// sample type (RSMB's codes in a float file) finds nothing.
///
/// A file with no colour channel the preset names but a `Y` is read both ways, `Y` as grey
/// colour and not, and the reading that takes more of the file's channels is kept: a
/// luminance image is colour, a file of `X`, `Y` vectors is not.
/// In view layer `layer` (`None`: the one the file holds, if any); a file of several is read
/// layer by layer by `suggest::passes_read`.
pub(super) fn passes_read_in(info: &FileInfo, preset: &Preset, layer: Option<&str>) -> PassesRead {
    match find_channels(info, &preset.color.channels, 3, &[], layer) {
        Ok(None) => {
            let without = passes_after(info, preset, None, layer);
            match luminance(info) {
                Some(grey) => {
                    let with = passes_after(info, preset, Some(grey), layer);
                    let count = |read: &[(&str, Vec<usize>)]| {
                        let mut all: Vec<usize> =
                            read.iter().flat_map(|(_, c)| c.iter().copied()).collect();
                        all.sort_unstable();
                        all.dedup();
                        all.len()
                    };
                    if count(&with) > count(&without) {
                        with
                    } else {
                        without
                    }
                }
                None => without,
            }
        }
        color => passes_after(info, preset, color.ok().flatten(), layer),
    }
}

/// The passes a preset finds once colour has taken `color`'s channels (see [`passes_read_in`]).
fn passes_after(
    info: &FileInfo,
    preset: &Preset,
    color: Option<Vec<Option<usize>>>,
    layer: Option<&str>,
) -> PassesRead {
    let mut found = Vec::new();
    let mut claimed: Vec<usize> = Vec::new();
    if let Some(color) = color {
        for c in color.into_iter().flatten() {
            if !claimed.contains(&c) {
                claimed.push(c);
            }
        }
        found.push(("color", claimed.clone()));
    }
    let depth: Vec<Vec<String>> = preset
        .depth
        .channels
        .iter()
        .map(|c| vec![c.clone()])
        .collect();
    if let Ok(Some(channels)) = find_channels(info, &depth, 1, &claimed, layer) {
        found.push(("depth", channels.into_iter().flatten().collect()));
    }
    for (name, spec) in [
        ("velocity", &preset.velocity),
        ("prev", &preset.prev),
        ("next", &preset.next),
    ] {
        if let Ok(Some(channels)) = find_channels(info, &spec.channels, 2, &claimed, layer) {
            let read = if spec.meaning.is_position() { 3 } else { 2 };
            let channels: Vec<usize> = channels.into_iter().take(read).flatten().collect();
            if decodes(spec, name, info.channels[channels[0]].sample_type) {
                found.push((name, channels));
            }
        }
    }
    found
}

/// The layers a preset reads depth and motion from in one file on its own (each by its
/// [`layer_key`](crate::io::channels::layer_key)): data whatever their names say, as a run
/// with that preset classes them (`FramePlan::pass_layers`); what `shutter info --preset`
/// shows.
pub fn pass_layers(info: &FileInfo, preset: &Preset) -> std::collections::BTreeSet<String> {
    (passes_read_in(info, preset, None).into_iter())
        .filter(|(pass, _)| *pass != "color")
        .flat_map(|(_, channels)| channels)
        .map(|c| {
            let channel = &info.channels[c];
            let name = channel.alias.as_ref().unwrap_or(&channel.name);
            crate::io::channels::layer_key(name).to_string()
        })
        .collect()
}

/// Whether a motion section's encoding reads samples of this type, whatever the values only
/// the user knows (RSMB's Max Displace, which a built-in preset leaves out).
pub(super) fn decodes(spec: &VectorSpec, pass: &str, sample_type: &str) -> bool {
    let mut spec = spec.clone();
    spec.max_displace.get_or_insert(1.0);
    Decode::resolve(&spec, pass, sample_type).is_ok()
}
