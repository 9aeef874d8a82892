//! Which preset a file most likely needs, and why (`shutter info`), from its header alone.
//!
//! The rule, deterministic:
//!
//! 1. Each convention preset (in the fixed order of `io::preset::BUILTIN`: shutter,
//!    blender, nuke, painted, rsmb) reads what it finds in the file on its own, as
//!    [`passes_found`](super::passes_found) lists it: colour first, then depth and the motion
//!    sections among the channels colour did not take; a motion section whose encoding
//!    cannot read the file's samples (RSMB's codes in a float file) finds nothing.
//! 2. Its score is the number of the file's stored channels those passes read (a grey
//!    image's `Y`, `R`, `G`, `B` are one stored channel).
//! 3. The highest score wins; ties go to the first in the fixed order, and the message
//!    names the presets it tied with. No score: no preset names the file's channels.
//!
//! When the winner reads colour alone, nothing in the header says more, and the suggestion
//! says so ("colour only") rather than name a renderer. An 8/16-bit integer image is the one
//! case where the header cannot tell what the file is: an RGB(A) image may be a photo or
//! motion vectors in R, G, and a grey one a painted depth map. For those, the presets that
//! could read it as vectors or depth are listed as candidates, each with its reason:
//! - as vectors: presets whose motion section stores still as a code inside the range
//!   (painted's `zero = 0.5`, rsmb's 127 / 32767), since unsigned codes with zero at 0 cannot
//!   hold motion to the left or up, and whose channels the image has (R, G);
//! - as depth (grey images only, which cannot hold vectors): presets that map grey to depth
//!   between `near` and `far`.
//!
//! Pixels are never read: telling a photo from vectors by their values would be a guess
//! dressed as a fact.

use serde::Serialize;

use crate::io::file::{FileInfo, FileKind};
use crate::io::preset::{Encoding, Meaning, Preset, Units, VectorSpec};

use super::found::{decodes, passes_read_in, PassesRead};
use super::plan::{find_channels, find_layers};

/// A pass a preset finds, and the channels it reads (as `shutter info` names them).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Found {
    pub pass: &'static str,
    pub channels: Vec<String>,
}

/// Another reading of an integer image that its header cannot rule out.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Candidate {
    pub preset: String,
    /// `vectors` (given as `--velocity`, `--prev` or `--next`) or `depth` (as `--depth`).
    pub role: &'static str,
    pub channels: Vec<String>,
    pub reason: String,
}

/// The preset a file most likely needs, and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Suggestion {
    /// The preset; `None` when no preset names any of the file's channels.
    pub preset: Option<String>,
    /// What it reads.
    pub found: Vec<Found>,
    /// The stored channels it reads, of `channels` in the file.
    pub matched: usize,
    pub channels: usize,
    /// Presets that read as many channels; the fixed order chose `preset` among them.
    pub tied: Vec<String>,
    /// One line: the rule's outcome in words.
    pub reason: String,
    /// For integer images the header cannot tell apart: other readings, with their reasons.
    pub candidates: Vec<Candidate>,
    /// The view layers the preset found (two or more: a run reads one with `--layer`, or
    /// stacks them with `--layers`); empty otherwise.
    pub view_layers: Vec<String>,
}

/// A file of several view layers ([`view_layers`]) is read layer by layer, as `--layers`
/// reads it, and each pass lists every layer's channels; a file whose one view layer stands
/// beside colour-only ones (Blender's `Composite`) is read in that layer.
pub(super) fn passes_read(info: &FileInfo, preset: &Preset) -> PassesRead {
    let layers = view_layers(info, preset);
    match layers.len() {
        0 => return passes_read_in(info, preset, None),
        1 => return passes_read_in(info, preset, Some(&layers[0])),
        _ => {}
    }
    let mut all: PassesRead = Vec::new();
    for layer in &layers {
        for (pass, channels) in passes_read_in(info, preset, Some(layer)) {
            match all.iter_mut().find(|(p, _)| *p == pass) {
                Some((_, seen)) => seen.extend(channels),
                None => all.push((pass, channels)),
            }
        }
    }
    all
}

/// The view layers of the file for a preset that names channels by `{layer}`, sorted: the
/// values `{layer}` takes where the preset finds the whole colour and a pass besides
/// (depth or motion). A name with colour alone, as Blender's `Composite` result beside the
/// render's view layer, or with part of a colour, is not a layer to blur; empty when the
/// preset names no channel by layer.
pub fn view_layers(info: &FileInfo, preset: &Preset) -> Vec<String> {
    let mut layers: Vec<String> = (preset.color.channels.iter())
        .filter_map(|alternative| alternative.first())
        .flat_map(|template| find_layers(info, template))
        .collect();
    layers.sort();
    layers.dedup();
    layers.retain(|layer| {
        let read = passes_read_in(info, preset, Some(layer));
        read.iter().any(|(pass, _)| *pass == "color") && read.len() > 1
    });
    layers
}

/// The passes a preset finds in one file on its own (for `shutter info`): colour first, then
/// the other passes among the channels colour did not take; every view layer's.
pub fn passes_found(info: &FileInfo, preset: &Preset) -> Vec<&'static str> {
    passes_read(info, preset)
        .into_iter()
        .map(|(pass, _)| pass)
        .collect()
}

/// The ways besides `--depth FILE` to give the depth a colour file (`info`, read with
/// `preset`) does not hold, as a missing depth pass's problem ends with them: with depth of
/// field (`dof`), `--coc-map FILE`; the convention presets that find depth in the file, each
/// with the channel it reads; else a preset of one's own whose `[depth] channels` name it.
pub fn other_ways_to_depth(info: &FileInfo, preset: &Preset, dof: bool) -> String {
    let mut ways = String::new();
    if dof {
        ways.push_str(
            ", or --coc-map FILE (a painted map of each pixel's blur, read in place of depth)",
        );
    }
    let finding = presets_finding(info, preset, &["depth"]);
    if finding.is_empty() {
        ways.push_str(
            ", or a preset whose [depth] channels name the file's depth channel \
             (--preset FILE)",
        );
    } else {
        ways.push_str(&format!(
            ", or a preset that finds depth in it: {}",
            finding.join(" or ")
        ));
    }
    ways
}

/// The ways besides `--velocity FILE` (`--prev`, `--next`) to give the motion a colour file
/// (`info`, read with `preset`) does not hold, as a missing motion pass's problem ends with
/// them: the convention presets that find vectors in the file (a velocity, or previous or
/// next positions: each pass is derived from whichever a preset finds), each with the
/// channels it reads and as what (`--preset vray (VRayVelocity.R, VRayVelocity.G as
/// velocity)`);
/// else a preset of one's own whose channels name them.
pub fn other_ways_to_motion(info: &FileInfo, preset: &Preset) -> String {
    let finding = presets_finding(info, preset, &["velocity", "prev", "next"]);
    if finding.is_empty() {
        ", or a preset whose [velocity] channels name the file's vector channels \
         (--preset FILE)"
            .to_string()
    } else {
        format!(
            ", or a preset that finds vectors in it: {}",
            finding.join(" or ")
        )
    }
}

/// The convention presets besides `preset` that find one of `passes` in the file on its
/// own, in the fixed order, each as the flag that chooses it with the channels it reads for
/// the first of them it finds (`--preset shutter (depth.Z)`; where `passes` are several,
/// which one: `--preset vray (VRayVelocity.R, VRayVelocity.G as velocity)`).
fn presets_finding(info: &FileInfo, preset: &Preset, passes: &[&str]) -> Vec<String> {
    (crate::io::preset::BUILTIN.iter())
        .filter(|(name, _)| crate::io::preset::is_convention(name) && *name != preset.name)
        .filter_map(|(name, _)| Preset::builtin(name).ok())
        .filter_map(|other| {
            let read = passes_read(info, &other);
            let (pass, channels) = read.into_iter().find(|(pass, _)| passes.contains(pass))?;
            // A preset that reads the pass as a picture's codes (grey 0..1 as near..far,
            // vectors about 0.5: `painted`) is no way to read a float file's.
            if codes(&other, pass) && !info.is_integer_image() {
                return None;
            }
            let channels: Vec<String> = channels.iter().map(|&c| shown(info, c)).collect();
            let what = if passes.len() > 1 {
                format!(" as {pass}")
            } else {
                String::new()
            };
            let channels = channels.join(", ");
            Some(format!("--preset {} ({channels}{what})", other.name))
        })
        .collect()
}

/// Whether `preset` reads `pass` as a picture's codes: depth as grey mapped onto near..far,
/// vectors quantised to codes (a dead zone about their zero: `painted`'s 8-bit steps). A
/// zero of 0.5 alone says nothing of it: Unreal's float vectors are stored about 0.5.
fn codes(preset: &Preset, pass: &str) -> bool {
    match pass {
        "depth" => preset.depth.grey_range().is_some(),
        "velocity" => preset.velocity.dead_zone > 0.0,
        "prev" => preset.prev.dead_zone > 0.0,
        "next" => preset.next.dead_zone > 0.0,
        _ => false,
    }
}

/// The name `shutter info` shows for a channel.
fn shown(info: &FileInfo, channel: usize) -> String {
    let c = &info.channels[channel];
    c.alias.clone().unwrap_or_else(|| c.name.clone())
}

/// Distinct stored channels (part, index) among `channels`.
fn stored(info: &FileInfo, channels: impl IntoIterator<Item = usize>) -> usize {
    let mut seen: Vec<(usize, usize)> = channels
        .into_iter()
        .map(|c| (info.channels[c].part, info.channels[c].index))
        .collect();
    seen.sort_unstable();
    seen.dedup();
    seen.len()
}

/// Suggests one of `presets` (convention presets, in their fixed order) for the file.
pub fn suggest(info: &FileInfo, presets: &[Preset]) -> Suggestion {
    let total = stored(info, 0..info.channels.len());
    let scored: Vec<(usize, PassesRead)> = presets
        .iter()
        .map(|p| {
            let read = passes_read(info, p);
            let score = stored(info, read.iter().flat_map(|(_, c)| c.iter().copied()));
            (score, read)
        })
        .collect();
    // The first of the highest scores: ties go to the fixed order.
    let best = scored
        .iter()
        .enumerate()
        .fold(None, |best: Option<usize>, (i, (score, _))| match best {
            Some(b) if scored[b].0 >= *score => Some(b),
            _ if *score > 0 => Some(i),
            _ => best,
        });
    let candidates = candidates(info, presets);
    let Some(best) = best else {
        return Suggestion {
            preset: None,
            found: Vec::new(),
            matched: 0,
            channels: total,
            tied: Vec::new(),
            reason: format!(
                "no preset names any of the file's channels ({}); write one (README, \
                 Presets)",
                info.channel_list()
            ),
            candidates,
            view_layers: Vec::new(),
        };
    };
    let (score, read) = &scored[best];
    let name = presets[best].name.clone();
    let tied: Vec<String> = scored
        .iter()
        .enumerate()
        .filter(|(i, (s, _))| *i != best && s == score)
        .map(|(i, _)| presets[i].name.clone())
        .collect();
    let found: Vec<Found> = read
        .iter()
        .map(|(pass, channels)| Found {
            pass,
            channels: channels.iter().map(|&c| shown(info, c)).collect(),
        })
        .collect();
    let colour_only = found.iter().all(|f| f.pass == "color");
    let mut reason = if colour_only {
        format!(
            "colour only ({} as color, alike in every preset that names them): no preset \
             finds depth or motion channels in this file",
            found[0].channels.join(", ")
        )
    } else {
        format!(
            "{}: {score} of the file's {total} channels",
            describe_found(&found)
        )
    };
    if !tied.is_empty() && !colour_only {
        let order: Vec<&str> = presets.iter().map(|p| p.name.as_str()).collect();
        reason.push_str(&format!(
            "; {} read as many, and ties go to the first of {}",
            tied.join(", "),
            order.join(", ")
        ));
    }
    let view_layers = view_layers(info, &presets[best]);
    // Names with colour alone beside the view layers (Blender's Composite result).
    let mut colour_alone: Vec<String> = (presets[best].color.channels.iter())
        .filter_map(|alternative| alternative.first())
        .flat_map(|template| find_layers(info, template))
        .filter(|l| !view_layers.contains(l))
        .collect();
    colour_alone.sort();
    colour_alone.dedup();
    match view_layers.as_slice() {
        [] => {}
        [_] if colour_alone.is_empty() => {}
        [one] => reason.push_str(&format!(
            "; view layer {one} ({} hold no passes to blur): --layer {one} reads it",
            colour_alone.join(", ")
        )),
        _ => reason.push_str(&format!(
            "; view layers {}: --layer NAME reads one, --layers NAME,NAME,... stacks them \
             front first",
            view_layers.join(", ")
        )),
    }
    let view_layers = if view_layers.len() > 1 || !colour_alone.is_empty() {
        view_layers
    } else {
        Vec::new()
    };
    Suggestion {
        view_layers,
        preset: Some(name),
        found,
        matched: *score,
        channels: total,
        tied,
        reason,
        // Other readings only where the winner's reading leaves the question open.
        candidates: if colour_only { candidates } else { Vec::new() },
    }
}

/// `R, G, B as color; backward.u, backward.v as velocity and prev; ...`: passes reading the
/// same channels are named together.
fn describe_found(found: &[Found]) -> String {
    let mut groups: Vec<(&[String], Vec<&str>)> = Vec::new();
    for f in found {
        match groups.iter_mut().find(|(c, _)| *c == f.channels.as_slice()) {
            Some((_, passes)) => passes.push(f.pass),
            None => groups.push((&f.channels, vec![f.pass])),
        }
    }
    groups
        .iter()
        .map(|(channels, passes)| format!("{} as {}", channels.join(", "), passes.join(" and ")))
        .collect::<Vec<_>>()
        .join("; ")
}

/// Readings of an 8/16-bit integer image as vectors or a depth map (see the module doc).
fn candidates(info: &FileInfo, presets: &[Preset]) -> Vec<Candidate> {
    if !matches!(info.kind, FileKind::Image { float: false, .. }) {
        return Vec::new();
    }
    // Grey: every channel but alpha reads one stored plane (R = G = B = Y), so it cannot
    // hold two components of motion.
    let grey = stored(
        info,
        (0..info.channels.len()).filter(|&c| info.channels[c].name != "A"),
    ) == 1;
    let mut out = Vec::new();
    for preset in presets.iter().filter(|_| !grey) {
        for (pass, spec) in [
            ("velocity", &preset.velocity),
            ("prev", &preset.prev),
            ("next", &preset.next),
        ] {
            let offset = spec.encoding == Encoding::Rsmb || spec.zero != 0.0;
            let Ok(Some(channels)) = find_channels(info, &spec.channels, 2, &[], None) else {
                continue;
            };
            let channels: Vec<usize> = channels.into_iter().take(2).flatten().collect();
            if offset && decodes(spec, pass, info.channels[channels[0]].sample_type) {
                let names: Vec<String> = channels.iter().map(|&c| shown(info, c)).collect();
                out.push(Candidate {
                    preset: preset.name.clone(),
                    role: "vectors",
                    reason: vector_reason(info, spec, &names),
                    channels: names,
                });
                break;
            }
        }
    }
    if grey {
        for preset in presets {
            let Some((near, far)) = preset.depth.grey_range() else {
                continue;
            };
            if let Some(c) = preset.depth.channels.iter().find_map(|n| info.find(n)) {
                let name = shown(info, c);
                out.push(Candidate {
                    preset: preset.name.clone(),
                    role: "depth",
                    reason: format!("{name} as depth: grey 0..1 = {near}..{far} scene units"),
                    channels: vec![name],
                });
            }
        }
    }
    out
}

fn vector_reason(info: &FileInfo, spec: &VectorSpec, names: &[String]) -> String {
    let meaning = match spec.meaning {
        Meaning::Velocity => "velocity p(0) - p(-1)",
        Meaning::ToPrev => "offsets to the previous frame",
        Meaning::ToNext => "offsets to the next frame",
        Meaning::FromNext => "p(0) - p(+1)",
        Meaning::PrevPosition => "previous positions",
        Meaning::NextPosition => "next positions",
    };
    let units = match spec.units {
        Units::Pixels => "pixels",
        Units::Normalized => "fractions of the frame",
    };
    let y = if spec.y_up { ", y up" } else { "" };
    let mut reason = match spec.encoding {
        Encoding::Plain => format!(
            "{} as {meaning}: (value - {}) x {} {units}{y}, {} is still",
            names.join(", "),
            spec.zero,
            spec.scale,
            spec.zero
        ),
        Encoding::Rsmb => format!(
            "{} as {meaning} in RE:Vision's codes (127 still at 8 bits, 32767 at 16; the top \
             code is +Max Displace){y}; needs max_displace, which the file does not store",
            names.join(", ")
        ),
    };
    if !spec.validity_alpha.is_empty() {
        match spec.validity_alpha.iter().find_map(|n| info.find(n)) {
            Some(c) => reason.push_str(&format!(
                "; {} below full-on marks a vector invalid",
                shown(info, c)
            )),
            None => reason.push_str(&format!(
                "; no {}, so every vector reads as valid",
                spec.validity_alpha.join(" or ")
            )),
        }
    }
    reason
}
