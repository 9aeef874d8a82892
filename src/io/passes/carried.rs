//! The channels of the colour file's part besides the passes, carried to the output (issue
//! 29): which they are, each one's class (light blurred with the beauty, or data passed
//! through), and which are read exactly (u32 data no pass reads), decided once per frame's
//! plan so the read only follows it.

use super::plan::{FramePlan, Slot};

impl FramePlan {
    /// Reads, besides the passes, every other channel of the part of the colour file that
    /// holds the colour, so the output can hold them again (an EXR output asks; the others
    /// do not, and `diff` and `bench` read colour alone).
    pub fn read_every_channel(&mut self) {
        let passes = self.pass_slots();
        let Some(color) = &mut self.color else {
            return;
        };
        let file = &mut self.files[color.rgb[0].file];
        color.other_slots = color
            .others
            .iter()
            .map(|&channel| {
                let entry = file
                    .channels
                    .iter()
                    .position(|&c| c == channel)
                    .unwrap_or_else(|| {
                        file.channels.push(channel);
                        file.channels.len() - 1
                    });
                Slot {
                    file: color.rgb[0].file,
                    entry,
                }
            })
            .collect();
        let headers = match &file.info.kind {
            crate::io::file::FileKind::Exr { headers, .. } => &headers[..],
            _ => &[],
        };
        let channel_of = |slot: &Slot| &file.info.channels[file.channels[slot.entry]];
        color.other_classes = color
            .other_slots
            .iter()
            .map(|slot| carried_class(&color.layer_classes, headers, channel_of(slot)))
            .collect();
        color.other_exact = color
            .other_slots
            .iter()
            .zip(&color.other_classes)
            .map(|(slot, &class)| {
                channel_of(slot).sample_type == "u32" && class.is_data() && !passes.contains(slot)
            })
            .collect();
    }

    /// The slots the passes read: colour, depth, motion (a u32 depth in the colour's part
    /// is among the other channels too, and is read as a number for the pass).
    fn pass_slots(&self) -> Vec<Slot> {
        let mut slots = Vec::new();
        if let Some(c) = &self.color {
            slots.extend(c.rgb);
            slots.extend(c.a);
        }
        slots.extend(self.depth.as_ref().map(|(slot, _)| *slot));
        for v in [&self.velocity, &self.prev, &self.next]
            .into_iter()
            .flatten()
        {
            slots.extend([v.x, v.y]);
            slots.extend(v.z);
            slots.extend(v.alpha);
        }
        slots
    }
}

/// The class of a channel carried beside the beauty: the preset's for its layer
/// (`[layers]`), else data for a u32 channel, else `io::channels`' rule; a channel of a
/// named part is classed as `part.channel` (`diffuse.R`).
fn carried_class(
    layer_classes: &std::collections::BTreeMap<String, crate::frame::LayerClass>,
    headers: &[exr::meta::header::Header],
    channel: &crate::io::file::ChannelInfo,
) -> crate::frame::LayerClass {
    use crate::io::channels;
    let crypto = headers
        .get(channel.part)
        .map(channels::crypto_layers)
        .unwrap_or_default();
    let qualified = channel.alias.as_ref().unwrap_or(&channel.name);
    match channels::preset_class(layer_classes, qualified) {
        Some(class) => class,
        // Integers hold IDs and counts, never light (a u32 `obj.R` included).
        None if channel.sample_type == "u32" => crate::frame::LayerClass::Data,
        None => channels::class_of(qualified, &crypto),
    }
}
