//! Planning one frame's reads from the file headers: which file and channel each pass takes,
//! every problem found named by file, frame and channel.

use std::path::{Path, PathBuf};

use crate::error::{Problem, ProblemKind};
use crate::frame::Passes;
use crate::io::exr as exr_io;
use crate::io::file::{FileInfo, FileKind};
use crate::io::preset::{Preset, Transfer, VectorSpec};
use crate::io::sequence::PathPattern;

use super::convert::Decode;
use super::parts::{other_channels, PartApart};
use super::window::{display_warning, part_view, DataWindow};
use super::Inputs;

/// A channel to read: which planned file, which entry of that file's read list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Slot {
    pub(super) file: usize,
    pub(super) entry: usize,
}

#[derive(Clone, Debug)]
pub(super) struct PlannedFile {
    pub(super) info: FileInfo,
    /// Indices into `info.channels`, distinct.
    pub(super) channels: Vec<usize>,
}

#[derive(Clone, Debug)]
pub(super) struct ColorPlan {
    pub(super) rgb: [Slot; 3],
    pub(super) a: Option<Slot>,
    pub(super) decode_srgb: bool,
    pub(super) premultiply: bool,
    /// The other channels of the colour's part (indices into the file's `channels`), read
    /// only when [`FramePlan::read_every_channel`] asks, with their slots then.
    pub(super) others: Vec<usize>,
    /// The parts of the colour file whose data window is not the beauty's (indices into
    /// its headers), read apart only when [`FramePlan::read_parts_apart`] asks, with each
    /// part's channels (indices into the file's `channels`) and classes then.
    pub(super) apart: Vec<usize>,
    pub(super) apart_read: Vec<PartApart>,
    pub(super) other_slots: Vec<Slot>,
    /// Each other channel's class, and whether it is read exactly (a u32 data channel no
    /// pass reads: its bits, so IDs over 2²⁴ come back as they were), beside `other_slots`.
    pub(super) other_classes: Vec<crate::frame::LayerClass>,
    pub(super) other_exact: Vec<bool>,
    /// The preset's classes of layers by name (`[layers]`), over `io::channels`' rule.
    pub(super) layer_classes: std::collections::BTreeMap<String, crate::frame::LayerClass>,
}

#[derive(Clone, Debug)]
pub(super) struct VectorPlan {
    pub(super) x: Slot,
    pub(super) y: Slot,
    pub(super) z: Option<Slot>,
    /// The channel whose value below full-on marks a vector invalid (`validity_alpha`).
    pub(super) alpha: Option<Slot>,
    /// How the stored values decode, for this file's sample type.
    pub(super) decode: Decode,
    pub(super) spec: VectorSpec,
}

/// Which channels of which files one frame reads, and how they become canonical passes.
#[derive(Clone, Debug)]
pub struct FramePlan {
    pub frame: Option<i64>,
    pub width: usize,
    pub height: usize,
    pub(super) files: Vec<PlannedFile>,
    pub(super) color: Option<ColorPlan>,
    pub(super) depth: Option<(Slot, crate::io::preset::DepthSpec)>,
    pub(super) velocity: Option<VectorPlan>,
    pub(super) prev: Option<VectorPlan>,
    pub(super) next: Option<VectorPlan>,
    /// Conversions that are approximations (e.g. next positions extrapolated).
    pub warnings: Vec<String>,
    /// Parts of the colour file its other channels are not read from (another data window,
    /// deep data), by name: named by `diff` as not compared.
    pub parts_left_out: Vec<String>,
    /// Those of them that cannot be read at all (deep data, or data shutter does not
    /// decode), each with why: `blur` warns of them ([`FramePlan::unread_warnings`]).
    pub parts_unread: Vec<(String, String)>,
    /// The colour file's windows: the frame's (every pass is cut to its data window).
    pub(super) color_windows: Option<crate::frame::Windows>,
}

impl FramePlan {
    /// The files this frame reads.
    pub fn paths(&self) -> Vec<&Path> {
        self.files.iter().map(|f| f.info.path.as_path()).collect()
    }

    /// The colour file's windows (its data window's corner and its display window), where
    /// it has them (an EXR).
    pub fn windows(&self) -> Option<crate::frame::Windows> {
        self.color_windows
    }

    /// The colour file's pixel aspect ratio (an EXR's `pixelAspectRatio`: a pixel's width
    /// over its height), where it says one.
    pub fn pixel_aspect(&self) -> Option<f32> {
        let color = self.color.as_ref()?;
        match &self.files[color.rgb[0].file].info.kind {
            FileKind::Exr { headers, .. } => {
                headers.first().map(|h| h.shared_attributes.pixel_aspect)
            }
            _ => None,
        }
    }
}

/// Options for planning.
#[derive(Clone, Debug)]
pub struct PlanOptions<'a> {
    pub preset: &'a Preset,
    /// The view layer substituted for `{layer}` in channel names; found when `None`.
    pub layer: Option<&'a str>,
    /// The view of multi-view EXRs to read (`io::view`); each file's default when `None`.
    pub view: Option<&'a str>,
    pub needs: Passes,
    /// The largest frame a file's header may declare, in pixels.
    pub max_pixels: usize,
}

/// Plans the reads of one frame from the file headers. Returns every problem found (missing
/// files, missing channels, size mismatches), each naming file, frame and channel.
pub fn plan_frame(
    inputs: &Inputs,
    frame: Option<i64>,
    options: &PlanOptions,
) -> Result<FramePlan, Vec<Problem>> {
    let mut planner = Planner {
        frame,
        options,
        files: Vec::new(),
        problems: Vec::new(),
        probed: Vec::new(),
        color_window: None,
        colour_took: (PathBuf::new(), Vec::new()),
        color_turned: false,
    };
    let color_path = inputs.color.path(frame);
    let color_info = planner.probe(&color_path, "color");
    planner.color_window = color_info.as_ref().map(DataWindow::of);
    planner.color_turned = color_info.as_ref().is_some_and(FileInfo::is_turned);
    let mut plan = FramePlan {
        frame,
        width: color_info.as_ref().map_or(0, |i| i.width),
        height: color_info.as_ref().map_or(0, |i| i.height),
        color_windows: color_info.as_ref().map(|i| i.windows),
        files: Vec::new(),
        color: None,
        depth: None,
        velocity: None,
        prev: None,
        next: None,
        warnings: Vec::new(),
        parts_left_out: Vec::new(),
        parts_unread: Vec::new(),
    };
    let preset = options.preset;
    let needs = options.needs;

    // Colour is always located: it gives the frame size and claims its channels, so that
    // passes looked up in the same file never take R, G, B for vectors.
    let mut claimed: Vec<usize> = Vec::new();
    if let Some(info) = &color_info {
        let mut found = find_channels(info, &preset.color.channels, 3, &[], options.layer);
        if let Ok(None) = found {
            if let Some(grey) = luminance(info) {
                plan.warnings.push(format!(
                    "colour read from the luminance channel {} as grey (R = G = B = Y): \
                     the file holds no colour channels the preset names",
                    info.channels[grey[0].expect("required")].name
                ));
                found = Ok(Some(grey));
            }
        }
        match found {
            Ok(Some(found)) => {
                claimed = found.iter().flatten().copied().collect();
                planner.colour_took = (info.path.clone(), claimed.clone());
                // The frame is the colour's part's: its size and window, which every pass
                // is placed against (a multi-part file's parts differ: the first part's, an
                // overscan depth or another layer's box, made the colour's read "changed").
                let info = &part_view(info, found[0].expect("required"));
                (plan.width, plan.height) = (info.width, info.height);
                plan.color_windows = Some(info.windows);
                planner.color_window = Some(DataWindow::of(info));
                if needs.color {
                    let file = planner.add_file(info.clone());
                    let integer = info.is_integer_image();
                    let slots: Vec<Option<Slot>> = found
                        .iter()
                        .map(|c| c.map(|c| planner.slot(file, c)))
                        .collect();
                    let (others, apart, left) = other_channels(info, &claimed);
                    plan.parts_unread = left
                        .iter()
                        .zip(&apart)
                        .filter_map(|(name, part)| Some((name.clone(), part.clone().err()?)))
                        .collect();
                    plan.parts_left_out = left;
                    plan.warnings.extend(layers_near_misses(info, preset));
                    plan.color = Some(ColorPlan {
                        rgb: [
                            slots[0].expect("required"),
                            slots[1].expect("required"),
                            slots[2].expect("required"),
                        ],
                        a: slots.get(3).copied().flatten(),
                        decode_srgb: integer && preset.color.transfer == Transfer::Srgb,
                        premultiply: integer,
                        others,
                        apart: apart.into_iter().flatten().collect(),
                        apart_read: Vec::new(),
                        other_slots: Vec::new(),
                        other_classes: Vec::new(),
                        other_exact: Vec::new(),
                        layer_classes: preset
                            .layers
                            .iter()
                            .map(|(layer, class)| (layer.clone(), class.class()))
                            .collect(),
                    });
                }
            }
            Ok(None) => {
                if needs.color {
                    planner.missing(info, "color", &alternatives(&preset.color.channels));
                }
            }
            Err(detail) => planner.problem(
                Problem::new(ProblemKind::MissingChannel, &info.path, detail).pass("color"),
            ),
        }
    }

    if needs.depth {
        let own = inputs.depth.as_ref().map(|p| p.path(frame));
        let info = match &own {
            Some(path) => planner.probe(path, "depth"),
            None => color_info.clone(),
        };
        if let Some(info) = info {
            // A file of its own: its size; the colour file's parts are each their own.
            if own.is_some() {
                planner.check_size(&info, "depth");
            }
            let alts: Vec<Vec<String>> = preset
                .depth
                .channels
                .iter()
                .map(|c| vec![c.clone()])
                .collect();
            let skip = if own.is_some() { &[][..] } else { &claimed[..] };
            match find_channels(&info, &alts, 1, skip, options.layer) {
                Ok(Some(found)) => {
                    let channel = found[0].expect("required");
                    let c = &info.channels[channel];
                    if let Some(layer) = options.layer.filter(|_| own.is_none()) {
                        let names = std::iter::once(&c.name).chain(&c.alias);
                        if names.clone().all(|n| !n.starts_with(&format!("{layer}."))) {
                            plan.warnings.push(not_the_layers(layer, "depth", &c.name));
                        }
                    }
                    let info = part_view(&info, channel);
                    planner.check_size(&info, "depth");
                    let file = planner.add_file(info);
                    let slot = planner.slot(file, channel);
                    plan.depth = Some((slot, preset.depth.clone()));
                }
                Ok(None) if own.is_some() && info.has_one_channel() => {
                    // A file given for depth with one channel (a grey map among them): that
                    // channel is depth. Without the file's name, so a sequence warns once.
                    if info.is_integer_image() {
                        plan.warnings.extend(preset.depth.grey_note(&preset.name));
                    }
                    let file = planner.add_file(info.clone());
                    let slot = planner.slot(file, 0);
                    plan.depth = Some((slot, preset.depth.clone()));
                }
                Ok(None) => {
                    let wanted = preset.depth.channels.join(" or ");
                    let mut problem = planner.missing_problem(&info, "depth", &wanted);
                    if own.is_none() {
                        // Looked up in the colour file: the flag that gives it apart.
                        problem.detail.push_str("; or give --depth FILE");
                    }
                    planner.problem(problem);
                }
                Err(detail) => planner.problem(
                    Problem::new(ProblemKind::MissingChannel, &info.path, detail).pass("depth"),
                ),
            }
        }
    }

    // Motion: each needed pass from its own section first, then from the others.
    let sections: [(&'static str, &VectorSpec, &Option<PathPattern>); 3] = [
        ("velocity", &preset.velocity, &inputs.velocity),
        ("prev", &preset.prev, &inputs.prev),
        ("next", &preset.next, &inputs.next),
    ];
    let wanted = [
        (needs.velocity, 0usize, [0usize, 1, 2]),
        (needs.prev, 1, [1, 0, 2]),
        (needs.next, 2, [2, 0, 1]),
    ];
    let mut no_motion = false;
    for (needed, target, order) in wanted {
        if !needed {
            continue;
        }
        let mut chosen = None;
        let mut fatal = false;
        for source in order {
            let (name, spec, own_pattern) = sections[source];
            let own = own_pattern.as_ref().map(|p| p.path(frame));
            let info = match &own {
                Some(path) => planner.probe(path, name),
                None => color_info.clone(),
            };
            let Some(info) = info else {
                fatal = own.is_some();
                if fatal {
                    break;
                }
                continue;
            };
            let skip = if own.is_some() { &[][..] } else { &claimed[..] };
            match find_channels(&info, &spec.channels, 2, skip, options.layer) {
                Ok(Some(found)) => {
                    let x_channel = found[0].expect("required");
                    let info = part_view(&info, x_channel);
                    if !planner.check_size(&info, name) {
                        fatal = true;
                        break;
                    }
                    let decode =
                        match Decode::resolve(spec, name, info.channels[x_channel].sample_type) {
                            Ok(decode) => decode,
                            Err(detail) => {
                                planner.problem(
                                    Problem::new(ProblemKind::Unsupported, &info.path, detail)
                                        .pass(name)
                                        .channel(info.channels[x_channel].name.clone()),
                                );
                                fatal = true;
                                break;
                            }
                        };
                    let file = planner.add_file(info.clone());
                    let x = planner.slot(file, x_channel);
                    let y = planner.slot(file, found[1].expect("required"));
                    let z = if spec.meaning.is_position() {
                        found
                            .get(2)
                            .copied()
                            .flatten()
                            .map(|c| planner.slot(file, c))
                    } else {
                        None
                    };
                    // The validity alpha lives in the vectors' own file, and is never the
                    // colour's alpha (a multi-layer file's `A` says coverage, not validity).
                    let alpha_channel = spec
                        .validity_alpha
                        .iter()
                        .filter_map(|n| info.find(n))
                        .find(|c| !skip.contains(c));
                    let alpha = alpha_channel.map(|c| planner.slot(file, c));
                    if !spec.validity_alpha.is_empty() && alpha.is_none() {
                        plan.warnings.push(format!(
                            "{name} vectors: the file has no validity alpha ({}), so every \
                             vector is read as valid",
                            spec.validity_alpha.join(" or ")
                        ));
                    }
                    chosen = Some(VectorPlan {
                        x,
                        y,
                        z,
                        alpha,
                        decode,
                        spec: spec.clone(),
                    });
                    let target_name = ["velocity", "prev", "next"][target];
                    let backward = spec.meaning.is_backward();
                    let extrapolated = (target == 2 && backward) || (target != 2 && !backward);
                    if extrapolated {
                        // Without the frame's file name, so a sequence warns once.
                        plan.warnings.push(format!(
                            "{target_name} pass derived from {} ({:?}) assuming linear motion",
                            name, spec.meaning,
                        ));
                    }
                    break;
                }
                Ok(None) if own.is_some() => {
                    planner.missing(&info, name, &alternatives(&spec.channels));
                    fatal = true;
                    break;
                }
                Ok(None) => continue,
                Err(detail) => {
                    planner.problem(
                        Problem::new(ProblemKind::MissingChannel, &info.path, detail).pass(name),
                    );
                    fatal = true;
                    break;
                }
            }
        }
        // No source holds motion. Every target tries the same three, so this is said once,
        // as the velocity the user gives (a painted map goes in --velocity; the previous and
        // next positions a pass reads are derived from it), not as the target the algorithm
        // happens to read first.
        if chosen.is_none() && !fatal && !no_motion {
            no_motion = true;
            let (name, spec, _) = sections[0];
            if let Some(info) = &color_info {
                // The colour's own channels are no vectors to offer.
                let offered = info.not_taken(&spec.channels, 2, &claimed);
                let mut problem = planner.missing_problem(info, name, &alternatives(&offered));
                problem.detail.push_str("; or give --velocity FILE");
                if target != 0 {
                    problem.detail.push_str(
                        " (the previous and next positions are derived from it), or --prev \
                         FILE or --next FILE",
                    );
                }
                planner.problem(problem);
            }
        }
        match target {
            0 => plan.velocity = chosen,
            1 => plan.prev = chosen,
            _ => plan.next = chosen,
        }
    }

    if let Some(view) = options.view {
        let any_views = planner
            .probed
            .iter()
            .any(|(_, info)| info.as_ref().is_some_and(|i| i.views.is_some()));
        if !any_views && planner.problems.is_empty() {
            // Without the frame's file name, so a sequence warns once.
            plan.warnings.push(format!(
                "view {view}: no input file holds views (a multiView attribute or parts \
                 with a view attribute), so the files are read as they are"
            ));
        }
    }

    // Depth and vectors are data: a lossy compression keeps them only roughly.
    let mut data: Vec<(&str, Slot)> = plan
        .depth
        .iter()
        .map(|(slot, _)| ("depth", *slot))
        .collect();
    for (pass, source) in [
        ("velocity", &plan.velocity),
        ("prev", &plan.prev),
        ("next", &plan.next),
    ] {
        if let Some(source) = source {
            data.extend(
                [source.x, source.y]
                    .into_iter()
                    .chain(source.z)
                    .map(|s| (pass, s)),
            );
        }
    }
    for (pass, slot) in data {
        let file = &planner.files[slot.file];
        let channel = &file.info.channels[file.channels[slot.entry]];
        let framed = plan.color_windows.as_ref();
        if let Some(warning) = framed.and_then(|c| display_warning(pass, &file.info, c)) {
            if !plan.warnings.contains(&warning) {
                plan.warnings.push(warning);
            }
        }
        if let Some(method) = stored_lossily(&file.info, channel) {
            let warning = format!(
                "{pass}: channel {} is compressed with {method}, which keeps a {} channel of \
                 that name only approximately; store depth and vectors losslessly (zip, piz)",
                channel.name, channel.sample_type
            );
            if !plan.warnings.contains(&warning) {
                plan.warnings.push(warning);
            }
        }
    }

    if planner.problems.is_empty() {
        plan.files = planner.files;
        Ok(plan)
    } else {
        let mut problems = planner.problems;
        for p in &mut problems {
            p.frame = frame;
        }
        problems.dedup();
        Err(problems)
    }
}

struct Planner<'a> {
    frame: Option<i64>,
    options: &'a PlanOptions<'a>,
    files: Vec<PlannedFile>,
    problems: Vec<Problem>,
    /// Files already probed in this frame (a path is probed once).
    probed: Vec<(PathBuf, Option<FileInfo>)>,
    /// The colour file's data window, once its header has been read.
    color_window: Option<DataWindow>,
    /// The colour file and the channels of it the colour pass reads.
    colour_took: (PathBuf, Vec<usize>),
    /// The colour file is a picture turned upright by its orientation to another shape.
    color_turned: bool,
}

impl Planner<'_> {
    fn probe(&mut self, path: &Path, pass: &'static str) -> Option<FileInfo> {
        if let Some((_, info)) = self.probed.iter().find(|(p, _)| p == path) {
            return info.clone();
        }
        let info = match FileInfo::probe_within(path, self.options.max_pixels) {
            Ok(info) => match info.in_view(self.options.view) {
                Ok(info) => Some(info),
                Err(detail) => {
                    self.problem(Problem::new(ProblemKind::View, path, detail).pass(pass));
                    None
                }
            },
            Err(problem) => {
                self.problem(problem.pass(pass));
                None
            }
        };
        self.probed.push((path.to_path_buf(), info.clone()));
        info
    }

    fn problem(&mut self, problem: Problem) {
        self.problems.push(problem.frame(self.frame));
    }

    fn missing_problem(&self, info: &FileInfo, pass: &'static str, wanted: &str) -> Problem {
        let took = if info.path == self.colour_took.0 {
            &self.colour_took.1[..]
        } else {
            &[]
        };
        let preset = (self.options.preset, self.options.layer);
        super::missing::missing_problem(preset, info, pass, wanted, took)
    }

    fn missing(&mut self, info: &FileInfo, pass: &'static str, wanted: &str) {
        let problem = self.missing_problem(info, pass, wanted);
        self.problem(problem);
    }

    /// Reports a size different from the colour's; returns whether sizes agree. When the
    /// colour file could not be read, its problem is the one reported, not a mismatch with
    /// a size nobody knows.
    fn check_size(&mut self, info: &FileInfo, pass: &'static str) -> bool {
        let Some(colour) = self.color_window else {
            return true;
        };
        // A pass is placed by its data window in the file's coordinates: one that covers the
        // colour's is read and cropped to it (depth rendered with overscan); one that does not
        // is an error naming what it leaves out.
        let own = DataWindow::of(info);
        // Only an EXR has a data window to be placed by: an 8/16-bit map (a painted depth or
        // CoC map, a velocity map) is the picture it was painted on, so one of another size
        // is a mismatch, larger as well as smaller (cutting a depth map made at twice the
        // photo's size to its top-left corner would blur the wrong places without a word).
        let placed = matches!(info.kind, FileKind::Exr { .. });
        if if placed {
            own.covers(&colour)
        } else {
            own == colour
        } {
            return true;
        }
        let detail = if !placed || own.origin == colour.origin || (own.width, own.height) == (0, 0)
        {
            // Maps are matched to the upright picture: where either was turned by its
            // orientation, say so, or a map the size of the stored photo reads as nonsense.
            let turned = |yes: bool, (w, h): (usize, usize)| match yes {
                true => format!(" (upright by its EXIF orientation; stored {h}x{w})"),
                false => String::new(),
            };
            format!(
                "{}x{}{} but the color pass is {}x{}{}{}",
                info.width,
                info.height,
                turned(info.is_turned(), (info.width, info.height)),
                colour.width,
                colour.height,
                turned(self.color_turned, (colour.width, colour.height)),
                match info.is_turned() || self.color_turned {
                    true => ": a map is matched to the picture as it is shown, upright",
                    false => "",
                }
            )
        } else {
            format!(
                "its data window {} does not cover the color pass's {}: it has no pixel at {}",
                own.describe(),
                colour.describe(),
                own.uncovered_in(&colour)
            )
        };
        self.problem(Problem::new(ProblemKind::SizeMismatch, &info.path, detail).pass(pass));
        false
    }

    fn add_file(&mut self, info: FileInfo) -> usize {
        // A file is read once per data window: a multi-part file's parts of another window
        // ([`part_view`]) are read apart.
        let same = |f: &FileInfo| {
            f.path == info.path
                && (f.width, f.height, f.windows) == (info.width, info.height, info.windows)
        };
        if let Some(i) = self.files.iter().position(|f| same(&f.info)) {
            return i;
        }
        self.files.push(PlannedFile {
            info,
            channels: Vec::new(),
        });
        self.files.len() - 1
    }

    fn slot(&mut self, file: usize, channel: usize) -> Slot {
        let channels = &mut self.files[file].channels;
        let entry = channels
            .iter()
            .position(|&c| c == channel)
            .unwrap_or_else(|| {
                channels.push(channel);
                channels.len() - 1
            });
        Slot { file, entry }
    }
}

/// The warnings that the preset's `[layers]` names a layer the colour file lacks, one typo
/// away from one it has ([`crate::io::channels::near_misses`]). Without the file's name, so a
/// sequence warns once.
fn layers_near_misses(info: &FileInfo, preset: &Preset) -> Vec<String> {
    let names: Vec<&str> = (info.channels.iter())
        .map(|c| c.alias.as_ref().unwrap_or(&c.name).as_str())
        .collect();
    crate::io::channels::near_misses(preset.layers.keys(), &names)
        .into_iter()
        .map(|(key, layer)| {
            format!(
                "preset {}: [layers] names {key}, which is no layer of the colour file: did \
                 you mean {layer}? {layer} keeps its default class",
                preset.name
            )
        })
        .collect()
}

/// The warning that view layer `layer` reads `pass` from `channel`, a channel not of its own
/// (the file's plain `Z`, a preset's fallback): that is where some other render's surfaces
/// are, not the layer's, and was read without a word. A warning, not a refusal: a file of one
/// layer beside its plain passes reads them rightly so.
fn not_the_layers(layer: &str, pass: &str, channel: &str) -> String {
    format!(
        "view layer {layer} has no {pass} of its own: it reads {channel}, which is not the \
         layer's; render the layer's own {pass} pass (Blender: the view layer's Z pass) if \
         the blur looks wrong"
    )
}

/// How `channel`'s part compresses it lossily, if it does ([`exr_io::keeps_exactly`]).
fn stored_lossily(info: &FileInfo, channel: &crate::io::file::ChannelInfo) -> Option<&'static str> {
    let crate::io::file::FileKind::Exr { compression, .. } = &info.kind else {
        return None;
    };
    let method = *compression.get(channel.part)?;
    (!exr_io::keeps_exactly(method, &channel.name, channel.sample_type)).then_some(method)
}

fn alternatives(alts: &[Vec<String>]) -> String {
    alts.iter()
        .map(|a| a.join(","))
        .collect::<Vec<_>>()
        .join(" or ")
}

/// Finds the first alternative whose first `required` channels are all in the file (and none
/// of them in `skip`). Returns, per name of the alternative, the channel index if present.
/// `{layer}` in names stands for a view layer found in the file (or `layer` when given);
/// several candidate layers are an error naming them.
pub(super) fn find_channels(
    info: &FileInfo,
    alternatives: &[Vec<String>],
    required: usize,
    skip: &[usize],
    layer: Option<&str>,
) -> Result<Option<Vec<Option<usize>>>, String> {
    for alternative in alternatives {
        let layers: Vec<Option<String>> = if alternative.iter().any(|n| n.contains("{layer}")) {
            match layer {
                Some(layer) => vec![Some(layer.to_string())],
                None => find_layers(info, &alternative[0])
                    .into_iter()
                    .map(Some)
                    .collect(),
            }
        } else {
            vec![None]
        };
        let mut matches = Vec::new();
        for candidate in &layers {
            let names: Vec<String> = alternative
                .iter()
                .map(|n| match candidate {
                    Some(layer) => n.replace("{layer}", layer),
                    None => n.clone(),
                })
                .collect();
            let found: Vec<Option<usize>> = names.iter().map(|n| info.find(n)).collect();
            let complete = found[..required.min(found.len())]
                .iter()
                .all(|c| c.is_some_and(|c| !skip.contains(&c)));
            if complete {
                matches.push((candidate.clone(), found));
            }
        }
        match matches.len() {
            0 => continue,
            1 => {
                let (_, mut found) = matches.remove(0);
                info.one_part(alternative, &mut found)?;
                return Ok(Some(found));
            }
            _ => {
                let names: Vec<String> = matches.into_iter().filter_map(|(l, _)| l).collect();
                return Err(format!(
                    "the file holds several view layers ({}); choose one with --layer",
                    names.join(", ")
                ));
            }
        }
    }
    Ok(None)
}

/// A luminance-only image's channels as colour (OpenEXR's `Y`, with `A` if present): Y for
/// each of R, G and B, so it reads as grey. Only for a file with no chroma: a luminance and
/// chroma image (`Y`, `RY`, `BY`) is not grey, and its subsampled chroma is refused when the
/// file is probed.
pub(super) fn luminance(info: &FileInfo) -> Option<Vec<Option<usize>>> {
    if info.find("RY").is_some() || info.find("BY").is_some() {
        return None;
    }
    let y = info.find("Y")?;
    Some(vec![Some(y), Some(y), Some(y), info.find("A")])
}

/// The values `{layer}` can take in `template` for the channels of this file.
pub(super) fn find_layers(info: &FileInfo, template: &str) -> Vec<String> {
    let Some((prefix, suffix)) = template.split_once("{layer}") else {
        return Vec::new();
    };
    let mut layers: Vec<String> = info
        .channels
        .iter()
        .flat_map(|c| std::iter::once(&c.name).chain(c.alias.as_ref()))
        .filter_map(|name| {
            let middle = name.strip_prefix(prefix)?.strip_suffix(suffix)?;
            (!middle.is_empty()).then(|| middle.to_string())
        })
        .collect();
    layers.sort();
    layers.dedup();
    layers
}
