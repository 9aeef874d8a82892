//! From pass files to a canonical [`Frame`]: which channels of which file each pass reads
//! (planned from headers, so preflight can check every frame before anything is decoded),
//! then the decode and the conversion from the preset's convention to the canonical one.
//!
//! Motion can come from any of the three motion sections of a preset (velocity, prev, next),
//! whatever each stores; a needed pass is taken from its own section first, then from the
//! others, converting between them:
//!
//! | needed   | from a backward source (`p(-1)`) | from a forward source (`p(+1)`)      |
//! |----------|----------------------------------|--------------------------------------|
//! | velocity | `p0 - p(-1)`                     | `p(+1) - p0` (linear, warned)        |
//! | prev     | `p(-1)`                          | `2·p0 - p(+1)` (linear, warned)      |
//! | next     | `2·p0 - p(-1)` (linear, warned)  | `p(+1)`                              |

use std::path::{Path, PathBuf};

use crate::error::{Problem, ProblemKind};
use crate::frame::{pixel_centre, Color, Frame, Passes, Plane, Positions, Velocity};
use crate::io::file::FileInfo;
use crate::io::image::srgb_to_linear;
use crate::io::preset::{Meaning, Preset, Transfer, Units, VectorSpec};
use crate::io::sequence::PathPattern;

/// The pass files given by the user (patterns or plain paths).
#[derive(Clone, Debug)]
pub struct Inputs {
    pub color: PathPattern,
    pub depth: Option<PathPattern>,
    pub velocity: Option<PathPattern>,
    pub prev: Option<PathPattern>,
    pub next: Option<PathPattern>,
}

impl Inputs {
    /// Colour only (other passes, if any, are looked up in the colour file).
    pub fn color_only(color: PathPattern) -> Inputs {
        Inputs {
            color,
            depth: None,
            velocity: None,
            prev: None,
            next: None,
        }
    }

    /// Every pattern given, with the pass it was given for.
    pub fn all(&self) -> Vec<(&'static str, &PathPattern)> {
        let mut all = vec![("color", &self.color)];
        for (name, pattern) in [
            ("depth", &self.depth),
            ("velocity", &self.velocity),
            ("prev", &self.prev),
            ("next", &self.next),
        ] {
            if let Some(pattern) = pattern {
                all.push((name, pattern));
            }
        }
        all
    }

    pub fn is_sequence(&self) -> bool {
        self.all().iter().any(|(_, p)| p.is_sequence())
    }
}

/// A channel to read: which planned file, which entry of that file's read list.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Slot {
    file: usize,
    entry: usize,
}

#[derive(Clone, Debug)]
struct PlannedFile {
    info: FileInfo,
    /// Indices into `info.channels`, distinct.
    channels: Vec<usize>,
}

#[derive(Clone, Debug)]
struct ColorPlan {
    rgb: [Slot; 3],
    a: Option<Slot>,
    decode_srgb: bool,
    premultiply: bool,
}

#[derive(Clone, Debug)]
struct VectorPlan {
    x: Slot,
    y: Slot,
    z: Option<Slot>,
    spec: VectorSpec,
}

/// Which channels of which files one frame reads, and how they become canonical passes.
#[derive(Clone, Debug)]
pub struct FramePlan {
    pub frame: Option<i64>,
    pub width: usize,
    pub height: usize,
    files: Vec<PlannedFile>,
    color: Option<ColorPlan>,
    depth: Option<(Slot, crate::io::preset::DepthSpec)>,
    velocity: Option<VectorPlan>,
    prev: Option<VectorPlan>,
    next: Option<VectorPlan>,
    /// Conversions that are approximations (e.g. next positions extrapolated).
    pub warnings: Vec<String>,
}

impl FramePlan {
    /// The files this frame reads.
    pub fn paths(&self) -> Vec<&Path> {
        self.files.iter().map(|f| f.info.path.as_path()).collect()
    }
}

/// Options for planning.
#[derive(Clone, Debug)]
pub struct PlanOptions<'a> {
    pub preset: &'a Preset,
    /// The view layer substituted for `{layer}` in channel names; found when `None`.
    pub layer: Option<&'a str>,
    pub needs: Passes,
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
    };
    let color_path = inputs.color.path(frame);
    let color_info = planner.probe(&color_path, "color");
    let mut plan = FramePlan {
        frame,
        width: color_info.as_ref().map_or(0, |i| i.width),
        height: color_info.as_ref().map_or(0, |i| i.height),
        files: Vec::new(),
        color: None,
        depth: None,
        velocity: None,
        prev: None,
        next: None,
        warnings: Vec::new(),
    };
    let preset = options.preset;
    let needs = options.needs;

    // Colour is always located: it gives the frame size and claims its channels, so that
    // passes looked up in the same file never take R, G, B for vectors.
    let mut claimed: Vec<usize> = Vec::new();
    if let Some(info) = &color_info {
        match resolve(info, &preset.color.channels, 3, &[], options.layer) {
            Ok(Some(found)) => {
                claimed = found.iter().flatten().copied().collect();
                if needs.color {
                    let file = planner.add_file(info.clone());
                    let integer = info.is_integer_image();
                    let slots: Vec<Option<Slot>> = found
                        .iter()
                        .map(|c| c.map(|c| planner.slot(file, c)))
                        .collect();
                    plan.color = Some(ColorPlan {
                        rgb: [
                            slots[0].expect("required"),
                            slots[1].expect("required"),
                            slots[2].expect("required"),
                        ],
                        a: slots.get(3).copied().flatten(),
                        decode_srgb: integer && preset.color.transfer == Transfer::Srgb,
                        premultiply: integer,
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
            planner.check_size(&info, plan.width, plan.height, "depth");
            let alts: Vec<Vec<String>> = preset
                .depth
                .channels
                .iter()
                .map(|c| vec![c.clone()])
                .collect();
            let skip = if own.is_some() { &[][..] } else { &claimed[..] };
            match resolve(&info, &alts, 1, skip, options.layer) {
                Ok(Some(found)) => {
                    let file = planner.add_file(info.clone());
                    let slot = planner.slot(file, found[0].expect("required"));
                    plan.depth = Some((slot, preset.depth.clone()));
                }
                Ok(None) if own.is_some() && info.channels.len() == 1 => {
                    // A file given for depth with one channel: that channel is depth.
                    let file = planner.add_file(info.clone());
                    let slot = planner.slot(file, 0);
                    plan.depth = Some((slot, preset.depth.clone()));
                }
                Ok(None) => planner.missing(&info, "depth", &preset.depth.channels.join(" or ")),
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
            match resolve(&info, &spec.channels, 2, skip, options.layer) {
                Ok(Some(found)) => {
                    if !planner.check_size(&info, plan.width, plan.height, name) {
                        fatal = true;
                        break;
                    }
                    let file = planner.add_file(info.clone());
                    let x = planner.slot(file, found[0].expect("required"));
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
                    chosen = Some(VectorPlan {
                        x,
                        y,
                        z,
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
        if chosen.is_none() && !fatal {
            let (name, spec, _) = sections[target];
            if let Some(info) = &color_info {
                let mut problem =
                    planner.missing_problem(info, name, &alternatives(&spec.channels));
                problem.detail.push_str(&format!("; or give --{name} FILE"));
                planner.problem(problem);
            }
        }
        match target {
            0 => plan.velocity = chosen,
            1 => plan.prev = chosen,
            _ => plan.next = chosen,
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
}

impl Planner<'_> {
    fn probe(&mut self, path: &Path, pass: &'static str) -> Option<FileInfo> {
        if let Some((_, info)) = self.probed.iter().find(|(p, _)| p == path) {
            return info.clone();
        }
        let info = match FileInfo::probe(path) {
            Ok(info) => Some(info),
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
        Problem::new(
            ProblemKind::MissingChannel,
            &info.path,
            format!(
                "not in the file with preset {}; the file has {}",
                self.options.preset.name,
                info.channel_list()
            ),
        )
        .pass(pass)
        .channel(wanted.to_string())
    }

    fn missing(&mut self, info: &FileInfo, pass: &'static str, wanted: &str) {
        let problem = self.missing_problem(info, pass, wanted);
        self.problem(problem);
    }

    /// Reports a size different from the colour's; returns whether sizes agree.
    fn check_size(
        &mut self,
        info: &FileInfo,
        width: usize,
        height: usize,
        pass: &'static str,
    ) -> bool {
        if (info.width, info.height) != (width, height) {
            self.problem(
                Problem::new(
                    ProblemKind::SizeMismatch,
                    &info.path,
                    format!(
                        "{}x{} but the color pass is {width}x{height}",
                        info.width, info.height
                    ),
                )
                .pass(pass),
            );
            return false;
        }
        true
    }

    fn add_file(&mut self, info: FileInfo) -> usize {
        if let Some(i) = self.files.iter().position(|f| f.info.path == info.path) {
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
fn resolve(
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
            1 => return Ok(Some(matches.remove(0).1)),
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

/// The values `{layer}` can take in `template` for the channels of this file.
fn find_layers(info: &FileInfo, template: &str) -> Vec<String> {
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

/// Decodes the planned files and converts them to canonical passes.
pub fn read_frame(plan: &FramePlan) -> Result<Frame, Problem> {
    let mut decoded: Vec<Vec<Plane>> = Vec::with_capacity(plan.files.len());
    for file in &plan.files {
        let planes = file
            .info
            .read(&file.channels)
            .map_err(|p| p.frame(plan.frame))?;
        decoded.push(planes);
    }
    let (width, height) = (plan.width, plan.height);
    let mut frame = Frame::new(width, height);
    if let Some(first) = plan.files.first() {
        frame.windows = first.info.windows;
    }
    // Takes a plane out of `decoded` (cloning when a channel serves two passes).
    let mut uses = vec![Vec::new(); decoded.len()];
    for slot in plan_slots(plan) {
        uses[slot.file].push(slot.entry);
    }
    let mut take = |slot: Slot, decoded: &mut Vec<Vec<Plane>>| -> Plane {
        let remaining = &mut uses[slot.file];
        let position = remaining.iter().position(|&e| e == slot.entry);
        if let Some(position) = position {
            remaining.swap_remove(position);
        }
        if remaining.contains(&slot.entry) {
            decoded[slot.file][slot.entry].clone()
        } else {
            std::mem::take(&mut decoded[slot.file][slot.entry])
        }
    };

    if let Some(plan_color) = &plan.color {
        let mut r = take(plan_color.rgb[0], &mut decoded);
        let mut g = take(plan_color.rgb[1], &mut decoded);
        let mut b = take(plan_color.rgb[2], &mut decoded);
        let a = plan_color.a.map(|slot| take(slot, &mut decoded));
        if plan_color.decode_srgb {
            for plane in [&mut r, &mut g, &mut b] {
                plane.iter_mut().for_each(|v| *v = srgb_to_linear(*v));
            }
        }
        if let (true, Some(a)) = (plan_color.premultiply, &a) {
            for plane in [&mut r, &mut g, &mut b] {
                plane.iter_mut().zip(a).for_each(|(v, a)| *v *= a);
            }
        }
        frame.color = Some(Color { r, g, b, a });
    }
    if let Some((slot, spec)) = &plan.depth {
        let mut depth = take(*slot, &mut decoded);
        if let (Some(near), Some(far)) = (spec.near, spec.far) {
            depth.iter_mut().for_each(|d| *d = near + *d * (far - near));
        }
        if spec.scale != 1.0 {
            depth.iter_mut().for_each(|d| *d *= spec.scale);
        }
        frame.depth = Some(depth);
    }
    for target in 0..3 {
        let source = match target {
            0 => &plan.velocity,
            1 => &plan.prev,
            _ => &plan.next,
        };
        let Some(source) = source else { continue };
        let x = take(source.x, &mut decoded);
        let y = take(source.y, &mut decoded);
        let z = source.z.map(|slot| take(slot, &mut decoded));
        let motion = Motion::decode(&source.spec, x, y, z, width, height);
        match target {
            0 => frame.velocity = Some(motion.velocity(width)),
            1 => frame.prev = Some(motion.position(width, true)),
            _ => frame.next = Some(motion.position(width, false)),
        }
    }
    Ok(frame)
}

fn plan_slots(plan: &FramePlan) -> Vec<Slot> {
    let mut slots = Vec::new();
    if let Some(c) = &plan.color {
        slots.extend(c.rgb);
        slots.extend(c.a);
    }
    if let Some((slot, _)) = &plan.depth {
        slots.push(*slot);
    }
    for v in [&plan.velocity, &plan.prev, &plan.next]
        .into_iter()
        .flatten()
    {
        slots.push(v.x);
        slots.push(v.y);
        slots.extend(v.z);
    }
    slots
}

/// A decoded motion source in canonical units (pixels, y down): either offsets from the pixel
/// centre or absolute positions, pointing backward (to p(-1)) or forward (to p(+1)).
struct Motion {
    x: Plane,
    y: Plane,
    z: Option<Plane>,
    absolute: bool,
    backward: bool,
}

impl Motion {
    fn decode(
        spec: &VectorSpec,
        mut x: Plane,
        mut y: Plane,
        z: Option<Plane>,
        width: usize,
        height: usize,
    ) -> Motion {
        let absolute = spec.meaning.is_position();
        let (sx, sy) = match spec.units {
            Units::Pixels => (spec.scale, spec.scale),
            Units::Normalized => (spec.scale * width as f32, spec.scale * height as f32),
        };
        // Canonical offsets point to the *other* time; velocity and from_next point back to
        // the current frame, so they change sign.
        let sign = match spec.meaning {
            Meaning::Velocity | Meaning::FromNext => -1.0,
            _ => 1.0,
        };
        let map = |v: f32, s: f32| {
            let d = v - spec.zero;
            if d.abs() <= spec.dead_zone {
                0.0
            } else {
                d * s * sign
            }
        };
        x.iter_mut().for_each(|v| *v = map(*v, sx));
        y.iter_mut().for_each(|v| *v = map(*v, sy));
        if spec.y_up {
            if absolute {
                let h = height as f32;
                y.iter_mut().for_each(|v| *v = h - *v);
            } else {
                y.iter_mut().for_each(|v| *v = -*v);
            }
        }
        Motion {
            x,
            y,
            z,
            absolute,
            backward: spec.meaning.is_backward(),
        }
    }

    /// Canonical velocity p(0) - p(-1).
    fn velocity(self, width: usize) -> Velocity {
        let Motion {
            mut x,
            mut y,
            absolute,
            backward,
            ..
        } = self;
        for (i, (vx, vy)) in x.iter_mut().zip(y.iter_mut()).enumerate() {
            let (cx, cy) = pixel_centre(i, width);
            let (dx, dy) = if absolute {
                (*vx - cx, *vy - cy)
            } else {
                (*vx, *vy)
            };
            // Backward offset d = p(-1) - p0, velocity -d; forward offset approximates it.
            if backward {
                *vx = -dx;
                *vy = -dy;
            } else {
                *vx = dx;
                *vy = dy;
            }
        }
        Velocity { x, y }
    }

    /// Absolute p(-1) (`want_prev`) or p(+1).
    fn position(self, width: usize, want_prev: bool) -> Positions {
        let Motion {
            mut x,
            mut y,
            z,
            absolute,
            backward,
        } = self;
        let same_direction = backward == want_prev;
        for (i, (px, py)) in x.iter_mut().zip(y.iter_mut()).enumerate() {
            let (cx, cy) = pixel_centre(i, width);
            match (absolute, same_direction) {
                (true, true) => {}
                (true, false) => {
                    *px = 2.0 * cx - *px;
                    *py = 2.0 * cy - *py;
                }
                (false, true) => {
                    *px += cx;
                    *py += cy;
                }
                (false, false) => {
                    *px = cx - *px;
                    *py = cy - *py;
                }
            }
        }
        Positions {
            x,
            y,
            z: if same_direction { z } else { None },
        }
    }
}

/// Reads the colour of one file (or one frame of a pattern) alone: the other passes are not
/// planned. Used by `diff` and `bench` to load images to compare.
pub fn read_color(
    pattern: &PathPattern,
    frame: Option<i64>,
    preset: &Preset,
) -> Result<Frame, Vec<Problem>> {
    let options = PlanOptions {
        preset,
        layer: None,
        needs: Passes::COLOR,
    };
    let plan = plan_frame(&Inputs::color_only(pattern.clone()), frame, &options)?;
    read_frame(&plan).map_err(|problem| vec![problem])
}

/// The passes a preset finds in one file on its own (for `shutter info`): colour first, then
/// the other passes among the channels colour did not take.
pub fn passes_found(info: &FileInfo, preset: &Preset) -> Vec<&'static str> {
    let mut found = Vec::new();
    let mut claimed = Vec::new();
    if let Ok(Some(color)) = resolve(info, &preset.color.channels, 3, &[], None) {
        claimed = color.iter().flatten().copied().collect();
        found.push("color");
    }
    let depth: Vec<Vec<String>> = preset
        .depth
        .channels
        .iter()
        .map(|c| vec![c.clone()])
        .collect();
    if let Ok(Some(_)) = resolve(info, &depth, 1, &claimed, None) {
        found.push("depth");
    }
    for (name, spec) in [
        ("velocity", &preset.velocity),
        ("prev", &preset.prev),
        ("next", &preset.next),
    ] {
        if let Ok(Some(_)) = resolve(info, &spec.channels, 2, &claimed, None) {
            found.push(name);
        }
    }
    found
}
