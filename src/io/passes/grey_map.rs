//! A painted map of one value a pixel (depth, or a CoC map read in its place) saved as an RGB
//! image: its R, G and B compared as it is read. A grey map saved as colour (as most editors
//! save a painting) has them equal, and is read without a word; where they differ (a map
//! painted in colour, a depth estimator's false-colour picture), one channel is read, the
//! first the preset's depth channels name (R for the built-in presets), and a note names the
//! file, the channel read and the first pixel where they differ.
//!
//! Why that channel and not the luminance: the preset says which channel holds depth, and a
//! map whose channels differ is not grey by any weighting (a false-colour ramp's luminance
//! rises and falls along it); the note says what was read and how to choose another, and
//! a map read before keeps its values.

use crate::frame::Plane;

use super::plan::FramePlan;

/// Channels of an 8-bit map within one code and a half of each other are equal: a grey map
/// saved as a JPEG (its chroma rounded) may differ by a code, a map painted in colour by more.
const GREY_TOLERANCE: f32 = 1.5 / 255.0;

/// What a frame reads from its depth file to compare R, G and B.
#[derive(Debug)]
pub(super) struct GreyCheck {
    /// The depth file (an index into the plan's files).
    pub(super) file: usize,
    /// The channels to decode (indices into the file's channels): those planned, then R, G
    /// or B where not among them.
    pub(super) channels: Vec<usize>,
    /// How many of `channels` the plan asked for.
    planned: usize,
    /// Where R, G and B are in `channels`.
    rgb: [usize; 3],
    /// The channel read as depth.
    read: String,
}

/// The check of `plan`'s depth, where it is read from one channel (R, G or B) of an 8/16-bit
/// RGB image that is not the colour's own file.
pub(super) fn check(plan: &FramePlan) -> Option<GreyCheck> {
    let (slot, _) = plan.depth.as_ref()?;
    let colour_files = plan.color.iter().flat_map(|c| c.rgb.iter().map(|s| s.file));
    if colour_files.clone().any(|f| f == slot.file) {
        return None;
    }
    let file = &plan.files[slot.file];
    let info = &file.info;
    let read = &info.channels[*file.channels.get(slot.entry)?];
    if !info.is_integer_image() || !["R", "G", "B"].contains(&read.name.as_str()) {
        return None;
    }
    let rgb = ["R", "G", "B"].map(|name| info.find(name));
    let [Some(r), Some(g), Some(b)] = rgb else {
        return None;
    };
    // A grey image answers to R, G and B from its one plane.
    let planes = [r, g, b].map(|c| info.channels[c].index);
    if planes[0] == planes[1] && planes[1] == planes[2] {
        return None;
    }
    let mut channels = file.channels.clone();
    let rgb = [r, g, b].map(|c| match channels.iter().position(|&k| k == c) {
        Some(at) => at,
        None => {
            channels.push(c);
            channels.len() - 1
        }
    });
    Some(GreyCheck {
        file: slot.file,
        planned: file.channels.len(),
        channels,
        rgb,
        read: read.name.clone(),
    })
}

impl GreyCheck {
    /// Compares R, G and B in `planes` (decoded as [`GreyCheck::channels`] lists them, an
    /// image `width` wide), drops those the plan did not ask for, and says, where they differ,
    /// what was read.
    pub(super) fn note(
        &self,
        planes: &mut Vec<Plane>,
        path: &std::path::Path,
        width: usize,
    ) -> Option<String> {
        let [r, g, b] = self.rgb.map(|k| planes.get(k));
        let first = match (r, g, b) {
            (Some(r), Some(g), Some(b)) => (0..r.len().min(g.len()).min(b.len())).find(|&i| {
                let (lo, hi) = (r[i].min(g[i]).min(b[i]), r[i].max(g[i]).max(b[i]));
                hi - lo > GREY_TOLERANCE
            }),
            _ => None,
        };
        let note = first.map(|i| {
            let [r, g, b] = self.rgb.map(|k| planes[k][i]);
            let (x, y) = (i % width.max(1), i / width.max(1));
            format!(
                "{}: a map of one value a pixel (depth, or a CoC map) saved in colour, its R, \
                 G and B differing (first at pixel ({x}, {y}): {r:.3}, {g:.3}, {b:.3}): its {} \
                 channel is read, the first of the preset's depth channels it holds; save the \
                 map as grey, or name the channel meant first in a preset's [depth] channels",
                path.display(),
                self.read
            )
        });
        planes.truncate(self.planned);
        note
    }
}
