//! The channels of the colour file besides the passes, carried to the output (issue 29):
//! which they are, each one's class (light blurred with the beauty, or data passed through),
//! which are read exactly (u32 data no pass reads), which parts are read apart (another data
//! window), decided once per frame's plan so the read only follows it; and which views of a
//! multi-view colour file a run leaves out.

use super::parts::PartApart;
use super::plan::{FramePlan, PlannedFile, Slot};
use crate::io::exr_parts::MERGED_PART;

/// The index into the file's channels of `slot`.
fn file_channel(files: &[PlannedFile], slot: Slot) -> usize {
    files[slot.file].channels[slot.entry]
}

impl FramePlan {
    /// The warning that a multi-view colour file's other views are not written, when one view
    /// of it is (`--view`, or a picture output).
    pub fn unwritten_views(&self) -> Option<String> {
        let color = self.color.as_ref()?;
        let info = &self.files[color.rgb[0].file].info;
        let (views, view) = (info.views.as_ref()?, info.view.as_ref()?);
        let others: Vec<&str> = views
            .names
            .iter()
            .filter(|v| *v != view)
            .map(String::as_str)
            .collect();
        (!others.is_empty()).then(|| {
            format!(
                "view {view} of the colour file is written, as a file of one view; its other \
                 views ({}) are not: --view reads one view, a picture holds one",
                others.join(", ")
            )
        })
    }

    /// Reads, besides the passes, every other channel of the part of the colour file that
    /// holds the colour, so the output can hold them again (an EXR output asks; the others
    /// do not, and `diff` and `bench` read colour alone).
    pub fn read_every_channel(&mut self) {
        let passes = self.pass_slots();
        let pass_layers = self.pass_layers();
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
            .map(|slot| {
                carried_class(
                    &color.layer_classes,
                    &pass_layers,
                    headers,
                    channel_of(slot),
                )
            })
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

    /// The names, as stored, of the channels the beauty is read from (R, G, B, then alpha).
    pub fn colour_names(&self) -> Vec<String> {
        let Some(color) = &self.color else {
            return Vec::new();
        };
        (color.rgb.iter().chain(&color.a))
            .map(|slot| {
                let file = &self.files[slot.file];
                file.info.channels[file.channels[slot.entry]].name.clone()
            })
            .collect()
    }

    /// Leaves out of a stack's output the colour file's composite, its part named
    /// [`MERGED_PART`] (Blender's): composited before the blur, it is stale, and the stack's
    /// merged beauty takes its place and its name. Keeping it beside the merged beauty gave
    /// the file two composites and the merged one a name of its own (`Composite.Combined2`),
    /// which the next pass of a chain then dropped. Says so in a warning. Call before
    /// [`FramePlan::read_layer_channels`].
    pub fn leave_out_composite(&mut self) {
        let Some(color) = &mut self.color else {
            return;
        };
        let info = &self.files[color.rgb[0].file].info;
        let crate::io::file::FileKind::Exr { headers, .. } = &info.kind else {
            return;
        };
        let composite: Vec<usize> = (0..headers.len())
            .filter(|&p| {
                headers.len() > 1
                    && p != info.channels[file_channel(&self.files, color.rgb[0])].part
                    && (headers[p].own_attributes.layer_name.as_ref())
                        .is_some_and(|n| n.as_slice() == MERGED_PART.as_bytes())
            })
            .collect();
        if composite.is_empty() {
            return;
        }
        color
            .others
            .retain(|&c| !composite.contains(&info.channels[c].part));
        color.apart.retain(|p| !composite.contains(p));
        self.warnings.push(format!(
            "the colour file's part {MERGED_PART} (its composite, made before the blur) is \
             not written: the stack's merged beauty replaces it, under its name"
        ));
    }

    /// [`FramePlan::read_every_channel`] and [`FramePlan::read_parts_apart`] for layer `own`
    /// of a stack of view layers (`--layers`, `stack` naming them all): it carries the
    /// channels of its own layer (`own.…`), blurred with its own weights; the stack's
    /// first layer (`rest`) carries besides the channels of no layer of the stack (another
    /// view layer, a composite, the parts of another data window) as data, which go out as
    /// they came. No layer reads another's.
    pub fn read_layer_channels(&mut self, own: &str, stack: &[String], rest: bool) {
        let layer_of = |name: &str| {
            stack
                .iter()
                .find(|l| {
                    name.strip_prefix(l.as_str())
                        .is_some_and(|r| r.starts_with('.'))
                })
                .cloned()
        };
        if let Some(color) = &mut self.color {
            let info = &self.files[color.rgb[0].file].info;
            color
                .others
                .retain(|&c| match layer_of(&info.channels[c].name) {
                    Some(layer) => layer == own,
                    None => rest,
                });
            if !rest {
                color.apart.clear();
            }
        }
        self.read_every_channel();
        self.read_parts_apart();
        let Some(color) = &mut self.color else {
            return;
        };
        let info = &self.files[color.rgb[0].file].info;
        let data = crate::frame::LayerClass::Data;
        for (k, &c) in color.others.iter().enumerate() {
            if layer_of(&info.channels[c].name).is_none() {
                color.other_classes[k] = data;
            }
        }
        for part in &mut color.apart_read {
            for (class, &c) in part.classes.iter_mut().zip(&part.channels) {
                if layer_of(&info.channels[c].name).as_deref() != Some(own) {
                    *class = data;
                }
            }
        }
    }

    /// The most pixels a part of the colour file holds (0 for a picture): what a part of its
    /// output passed through at its own window may hold.
    pub fn largest_part(&self) -> usize {
        let Some(color) = &self.color else {
            return 0;
        };
        match &self.files[color.rgb[0].file].info.kind {
            crate::io::file::FileKind::Exr { headers, .. } => (headers.iter())
                .map(|h| h.layer_size.0.saturating_mul(h.layer_size.1))
                .max()
                .unwrap_or(0),
            _ => 0,
        }
    }

    /// Reads, besides, the parts of the colour file whose data window is not the beauty's
    /// (an EXR output asks, after [`FramePlan::read_every_channel`]): each part of data
    /// alone comes back as it was, at its own window; a part holding light (or data carried
    /// with the motion) is placed on the beauty's window, where the passes work, and
    /// written there.
    pub fn read_parts_apart(&mut self) {
        let pass_layers = self.pass_layers();
        let Some(color) = &mut self.color else {
            return;
        };
        let info = &self.files[color.rgb[0].file].info;
        let headers = match &info.kind {
            crate::io::file::FileKind::Exr { headers, .. } => &headers[..],
            _ => &[],
        };
        color.apart_read = color
            .apart
            .iter()
            .map(|&part| {
                let channels: Vec<usize> = (0..info.channels.len())
                    .filter(|&i| info.channels[i].part == part)
                    .collect();
                let classes = (channels.iter())
                    .map(|&i| {
                        carried_class(
                            &color.layer_classes,
                            &pass_layers,
                            headers,
                            &info.channels[i],
                        )
                    })
                    .collect();
                PartApart {
                    part,
                    channels,
                    classes,
                }
            })
            .collect();
    }

    /// The layers of the colour file that the passes read depth and motion from, each by its
    /// [`channels::layer_key`](crate::io::channels::layer_key) (`VRayVelocity` for
    /// `VRayVelocity.R`, `Z` for `Z`): data in this run whatever their names say, with
    /// every channel of theirs (a velocity layer's unread B too), so that a preset's own
    /// passes come back bit for bit and out of a lossy DWA part (F12: V-Ray's `VRayVelocity`
    /// and MRQ's `…_MotionVectors`, colour by their names' letters, were blurred like light).
    /// A validity alpha is left out: it may be a layer of light's alpha.
    fn pass_layers(&self) -> std::collections::BTreeSet<String> {
        let Some(color) = &self.color else {
            return Default::default();
        };
        let path = &self.files[color.rgb[0].file].info.path;
        let mut slots: Vec<Slot> = self.depth.iter().map(|(slot, _)| *slot).collect();
        for v in [&self.velocity, &self.prev, &self.next]
            .into_iter()
            .flatten()
        {
            slots.extend([v.x, v.y]);
            slots.extend(v.z);
        }
        (slots.into_iter())
            .map(|slot| (&self.files[slot.file], slot.entry))
            .filter(|(file, _)| file.info.path == *path)
            .map(|(file, entry)| {
                let channel = &file.info.channels[file.channels[entry]];
                let name = channel.alias.as_ref().unwrap_or(&channel.name);
                crate::io::channels::layer_key(name).to_string()
            })
            .collect()
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
/// (`[layers]`), else data for a layer a pass is read from (`pass_layers`,
/// [`FramePlan::pass_layers`]) or a u32 channel, else `io::channels`' rule; a channel of a
/// named part is classed as `part.channel` (`diffuse.R`).
fn carried_class(
    layer_classes: &std::collections::BTreeMap<String, crate::frame::LayerClass>,
    pass_layers: &std::collections::BTreeSet<String>,
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
        // What a pass reads is depth or motion, whatever its name says.
        None if pass_layers.contains(channels::layer_key(qualified)) => {
            crate::frame::LayerClass::Data
        }
        // Integers hold IDs and counts, never light (a u32 `obj.R` included).
        None if channel.sample_type == "u32" => crate::frame::LayerClass::Data,
        None => channels::class_of(qualified, &crypto),
    }
}

/// What is wrong with one frame's stack of view layers (`stack` naming them, `first` the
/// front layer's plan, `rest` the others'), if anything: in one file of view layers
/// (`shared`), each layer's colour must be its own (not a fallback of the preset's, R, G, B,
/// that every layer would read alike); and the layers are one picture, the same size.
pub fn stack_problem(
    first: &FramePlan,
    rest: &[FramePlan],
    stack: &[String],
    shared: bool,
) -> Option<crate::error::Problem> {
    use crate::error::{Problem, ProblemKind};
    let path = |plan: &FramePlan| {
        (plan.paths().first().copied())
            .unwrap_or(std::path::Path::new(""))
            .to_path_buf()
    };
    for (plan, name) in std::iter::once(first).chain(rest).zip(stack) {
        if !shared {
            break;
        }
        let names = plan.colour_names();
        if let Some(other) = names.iter().find(|n| !n.starts_with(&format!("{name}."))) {
            return Some(
                Problem::new(
                    ProblemKind::MissingChannel,
                    path(plan),
                    format!(
                        "view layer {name} of --layers has no colour of its own: the preset \
                         reads {other} for it; check the layer's name (`shutter info` lists \
                         the file's channels)"
                    ),
                )
                .pass("color")
                .frame(plan.frame),
            );
        }
    }
    // Merged pixel for pixel: each layer's colour at the same data window (its part's: a
    // multi-part file's parts may differ).
    let window = |plan: &FramePlan| {
        let origin = plan.windows().map_or((0, 0), |w| w.data_origin);
        super::window::DataWindow {
            origin,
            width: plan.width,
            height: plan.height,
        }
    };
    for (plan, name) in rest.iter().zip(&stack[1..]) {
        if window(plan) != window(first) {
            return Some(
                Problem::new(
                    ProblemKind::SizeMismatch,
                    path(plan),
                    format!(
                        "layer {name}'s colour is {}x{} at {}, layer {}'s {}x{} at {}: a \
                         stack's layers are one picture, merged pixel for pixel, so each \
                         layer's colour needs the same data window (render them without a \
                         crop to the bounding box)",
                        plan.width,
                        plan.height,
                        window(plan).describe(),
                        stack[0],
                        first.width,
                        first.height,
                        window(first).describe()
                    ),
                )
                .frame(plan.frame),
            );
        }
    }
    None
}
