//! Decoding a planned frame and converting its passes to the canonical convention.

use crate::error::{Problem, ProblemKind};
use crate::frame::{CarriedChannel, Color, Frame, Passes, Plane};
use crate::io::file::FileKind;
use crate::io::image::read_photo_colour;
use crate::io::preset::{Preset, VectorSpec};
use crate::io::sequence::PathPattern;

use super::convert::MotionSource;
use super::plan::{plan_frame, FramePlan, PlanOptions, Slot};
use super::window::DataWindow;
use super::Inputs;

/// Decodes the planned files and converts them to canonical passes.
pub fn read_frame(plan: &FramePlan) -> Result<Frame, Problem> {
    read_frame_noted(plan).map(|(frame, _)| frame)
}

/// [`read_frame`], with notes on what the read did to this frame's values that the plan
/// could not foresee (vectors marked invalid, filled or read as still). A note's text does
/// not name the frame, so a sequence reports each kind once.
pub fn read_frame_noted(plan: &FramePlan) -> Result<(Frame, Vec<String>), Problem> {
    read_frame_keeping(plan, false, &mut false).map(|(frame, notes, _)| (frame, notes))
}

/// The stored values of a frame's first motion pass ([velocity], else [prev], else [next]),
/// x and y as the file holds them under the section's reading, before that reading converts
/// them: what the vector check fits (`io::passes::check`).
pub struct StoredVectors {
    /// The section that reads them, as the plan resolved it.
    pub spec: VectorSpec,
    pub planes: [Plane; 2],
}

/// [`read_frame_noted`], keeping a copy of the stored vectors with `keep` (the one frame the
/// vector check fits). `grey_noted` is a run's: once a frame's painted map has been found in
/// colour (and said so, naming its file), later frames' maps are not compared again, so a
/// sequence of such maps is noted once, not once a file.
pub fn read_frame_keeping(
    plan: &FramePlan,
    keep: bool,
    grey_noted: &mut bool,
) -> Result<(Frame, Vec<String>, Option<StoredVectors>), Problem> {
    let mut kept = None;
    let mut notes = Vec::new();
    let mut decoded: Vec<Vec<Plane>> = Vec::with_capacity(plan.files.len());
    let (width, height) = (plan.width, plan.height);
    let colour = plan.color_windows.map(|windows| DataWindow {
        origin: windows.data_origin,
        width,
        height,
    });
    // The u32 data channels carried to the output are read as their bits, exactly (the
    // plan says which: none a pass reads as a number).
    let exact: Vec<Slot> = plan
        .color
        .iter()
        .flat_map(|c| c.other_slots.iter().zip(&c.other_exact))
        .filter(|(_, &exact)| exact)
        .map(|(slot, _)| *slot)
        .collect();
    // A depth map in an RGB image: its G and B read too, to tell grey from colour.
    let grey = if *grey_noted {
        None
    } else {
        super::grey_map::check(plan)
    };
    for (index, file) in plan.files.iter().enumerate() {
        let bits: Vec<usize> = exact
            .iter()
            .filter(|slot| slot.file == index)
            .map(|slot| file.channels[slot.entry])
            .collect();
        let grey = grey.as_ref().filter(|c| c.file == index);
        let channels = grey.map_or(&file.channels, |c| &c.channels);
        let mut planes = file.info.read_bits(channels, &bits).map_err(|p| {
            match (p.pass, pass_of(plan, index)) {
                (None, Some(pass)) => p.frame(plan.frame).pass(pass),
                _ => p.frame(plan.frame),
            }
        })?;
        if let Some(grey) = grey {
            let note = grey.note(&mut planes, &file.info.path, file.info.width);
            *grey_noted |= note.is_some();
            notes.extend(note.map(|n| match plan.frame {
                Some(f) => format!("{n} (frame {f}; later frames' maps are not compared)"),
                None => n,
            }));
        }
        // A pass whose data window is larger than the colour's (overscan) is cut to it; the
        // plan made sure it covers it.
        let own = DataWindow::of(&file.info);
        if let Some(colour) = colour.filter(|c| *c != own) {
            for plane in &mut planes {
                *plane = own.crop(plane, &colour);
            }
        }
        decoded.push(planes);
    }
    let mut frame = Frame::new(width, height);
    if let Some(windows) = plan.color_windows {
        frame.windows = windows;
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
        // The other channels of the colour's part first: a channel the passes read too (a
        // depth in the colour file) is then cloned for them, not taken.
        let file = &plan.files[plan_color.rgb[0].file];
        let channel_of = |slot: Slot| &file.info.channels[file.channels[slot.entry]];
        if let FileKind::Exr { headers, .. } = &file.info.kind {
            let others = (plan_color.other_slots.iter())
                .zip(&plan_color.other_classes)
                .zip(&plan_color.other_exact);
            for ((&slot, &class), &read_exactly) in others {
                let channel = channel_of(slot);
                let mut plane = take(slot, &mut decoded);
                // Bits read exactly: the values as stored, and as numbers in the plane.
                let exact = read_exactly.then(|| {
                    let values: Vec<u32> = plane.iter().map(|v| v.to_bits()).collect();
                    plane = values.iter().map(|&v| v as f32).collect();
                    values
                });
                frame.carried.channels.push(CarriedChannel {
                    class,
                    name: channel.name.clone(),
                    stored: stored_name(headers, channel),
                    shared: file.info.views.is_some() && channel.view.is_none(),
                    part: channel.part,
                    plane,
                    exact,
                    window: None,
                });
            }
            // The parts of another data window, each read on its own.
            for apart in &plan_color.apart_read {
                let passed = apart.passed_through();
                // Its u32 data keeps its bits, passed through or placed.
                let bits: Vec<usize> = (apart.channels.iter().zip(&apart.classes))
                    .filter(|(&i, class)| {
                        class.is_data() && file.info.channels[i].sample_type == "u32"
                    })
                    .map(|(&i, _)| i)
                    .collect();
                let read = (file.info)
                    .read_exr(&apart.channels, &bits)
                    .map_err(|p| p.frame(plan.frame))?;
                let own = DataWindow {
                    origin: read.windows.data_origin,
                    width: read.width,
                    height: read.height,
                };
                let to = colour.unwrap_or(own);
                let planes = read.planes.into_iter();
                let channels = apart.channels.iter().zip(&apart.classes).zip(planes);
                for ((&i, &class), mut plane) in channels {
                    let channel = &file.info.channels[i];
                    let exact = bits.contains(&i).then(|| {
                        let values: Vec<u32> = plane.iter().map(|v| v.to_bits()).collect();
                        plane = values.iter().map(|&v| v as f32).collect();
                        values
                    });
                    let (plane, exact, window) = if passed {
                        (plane, exact, Some(own.as_window()))
                    } else {
                        let (own, to) = (own.as_window(), to.as_window());
                        let exact = exact.map(|values| own.place(&values, &to));
                        (own.place(&plane, &to), exact, None)
                    };
                    frame.carried.channels.push(CarriedChannel {
                        class,
                        name: channel.name.clone(),
                        stored: stored_name(headers, channel),
                        part: channel.part,
                        shared: file.info.views.is_some() && channel.view.is_none(),
                        plane,
                        exact,
                        window,
                    });
                }
            }
            frame.carried.headers = headers.clone();
            frame.carried.colour_part = channel_of(plan_color.rgb[0]).part;
            frame.carried.beauty = plan_color
                .rgb
                .iter()
                .chain(&plan_color.a)
                .map(|&slot| channel_of(slot).name.clone())
                .collect();
            frame.carried.beauty_stored = plan_color
                .rgb
                .iter()
                .chain(&plan_color.a)
                .map(|&slot| stored_name(headers, channel_of(slot)))
                .collect();
        }
        let mut r = take(plan_color.rgb[0], &mut decoded);
        let mut g = take(plan_color.rgb[1], &mut decoded);
        let mut b = take(plan_color.rgb[2], &mut decoded);
        let a = plan_color.a.map(|slot| take(slot, &mut decoded));
        // A photo: its profile's curves make its colour linear (`decode_srgb`: unless the
        // preset says the values are linear already), and its profile and metadata go with
        // the frame to the output.
        let colour_file = &plan.files[plan_color.rgb[0].file].info;
        if colour_file.is_integer_image() {
            let (photo, note) = read_photo_colour(
                &colour_file.path,
                [&mut r, &mut g, &mut b],
                a.as_deref(),
                plan_color.decode_srgb,
            )
            .map_err(|d| {
                let (kind, d) = match d.strip_prefix(crate::io::image::NOT_SUPPORTED) {
                    Some(what) => (ProblemKind::Unsupported, what.to_string()),
                    None => (ProblemKind::Corrupt, d),
                };
                Problem::new(kind, &colour_file.path, d).frame(plan.frame)
            })?;
            notes.extend(note);
            frame.carried.photo = Some(photo);
        } else if colour_file.is_image() {
            // A float TIFF: its values are linear light already; what it holds besides them
            // (profile, EXIF) and that it is float go with the frame to the output.
            let photo = crate::io::image::read_photo(&colour_file.path).map_err(|d| {
                Problem::new(ProblemKind::Corrupt, &colour_file.path, d).frame(plan.frame)
            })?;
            notes.extend(crate::io::image::more_images_note(&photo));
            // Straight alpha, as its ExtraSamples says: premultiplied here, as shutter works.
            if let (true, Some(a)) = (photo.straight, &a) {
                for plane in [&mut r, &mut g, &mut b] {
                    plane.iter_mut().zip(a).for_each(|(v, a)| *v *= a);
                }
            }
            frame.carried.photo = Some(photo);
        }
        if let (true, Some(a)) = (plan_color.premultiply, &a) {
            // What premultiplying loses: the straight colour under alpha 0, for the output.
            if let Some(photo) = frame.carried.photo.as_mut() {
                let pixels: Vec<(u32, [f32; 3])> = (a.iter().enumerate())
                    .filter(|&(i, &a)| a == 0.0 && (r[i] != 0.0 || g[i] != 0.0 || b[i] != 0.0))
                    .map(|(i, _)| (i as u32, [r[i], g[i], b[i]]))
                    .collect();
                photo.hidden = (!pixels.is_empty()).then_some(crate::frame::Hidden {
                    width: frame.width,
                    height: frame.height,
                    pixels,
                });
            }
            for plane in [&mut r, &mut g, &mut b] {
                plane.iter_mut().zip(a).for_each(|(v, a)| *v *= a);
            }
        }
        frame.color = Some(Color { r, g, b, a });
    }
    if let Some((slot, spec)) = &plan.depth {
        let mut depth = take(*slot, &mut decoded);
        if let Some((near, far)) = spec.grey_range() {
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
        if keep && kept.is_none() {
            kept = Some(StoredVectors {
                spec: source.spec.clone(),
                planes: [x.clone(), y.clone()],
            });
        }
        let z = source.z.map(|slot| take(slot, &mut decoded));
        let alpha = source.alpha.map(|slot| take(slot, &mut decoded));
        let mut motion = MotionSource::decode(&source.spec, source.decode, x, y, z, width, height);
        if let Some(alpha) = alpha {
            let filled = motion.fill_invalid(&alpha, width, height);
            let pass = ["velocity", "prev", "next"][target];
            if filled.none_valid {
                notes.push(format!(
                    "{pass}: every vector of a frame is marked invalid by its alpha (below \
                     full-on), so that frame's {pass} reads as still"
                ));
            } else if filled.filled > 0 {
                notes.push(format!(
                    "{pass}: vectors marked invalid by their alpha (below full-on) take the \
                     motion of the nearest valid vector"
                ));
            }
        }
        match target {
            0 => frame.velocity = Some(motion.velocity(width)),
            1 => frame.prev = Some(motion.position(width, true)),
            _ => frame.next = Some(motion.position(width, false)),
        }
    }
    Ok((frame, notes, kept))
}

/// The pass file `index` of the plan is read for, first of those it serves (a colour file
/// holding the depth and vectors is the colour's): what a decoding error names beside the
/// file and frame (an outside probe: a damaged depth file's error named neither).
fn pass_of(plan: &FramePlan, index: usize) -> Option<&'static str> {
    let vectors = [
        ("velocity", &plan.velocity),
        ("prev", &plan.prev),
        ("next", &plan.next),
    ];
    if plan.color.as_ref().is_some_and(|c| c.rgb[0].file == index) {
        Some("color")
    } else if plan
        .depth
        .as_ref()
        .is_some_and(|(slot, _)| slot.file == index)
    {
        Some("depth")
    } else {
        vectors
            .into_iter()
            .find(|(_, v)| v.as_ref().is_some_and(|v| v.x.file == index))
            .map(|(name, _)| name)
    }
}

fn plan_slots(plan: &FramePlan) -> Vec<Slot> {
    let mut slots = Vec::new();
    if let Some(c) = &plan.color {
        slots.extend(c.rgb);
        slots.extend(c.a);
        slots.extend(&c.other_slots);
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
        slots.extend(v.alpha);
    }
    slots
}

/// Reads the colour of one file (or one frame of a pattern) alone: the other passes are not
/// planned. Used by `diff` and `bench` to load images to compare.
pub fn read_color(
    pattern: &PathPattern,
    frame: Option<i64>,
    preset: &Preset,
) -> Result<Frame, Vec<Problem>> {
    let plan = plan_color(pattern, frame, preset)?;
    read_frame(&plan).map_err(|problem| vec![problem])
}

/// [`read_color`]'s plan, from the file's header alone (its size is the plan's): what to
/// check before anything is decoded.
pub fn plan_color(
    pattern: &PathPattern,
    frame: Option<i64>,
    preset: &Preset,
) -> Result<FramePlan, Vec<Problem>> {
    plan_color_in(pattern, frame, preset, (None, None))
}

/// [`plan_color`] in the view layer and the view asked for (each found in the file where
/// `None`, as `blur --layer` and `--view` choose them).
pub fn plan_color_in(
    pattern: &PathPattern,
    frame: Option<i64>,
    preset: &Preset,
    (layer, view): (Option<&str>, Option<&str>),
) -> Result<FramePlan, Vec<Problem>> {
    let options = PlanOptions {
        preset,
        layer,
        view,
        needs: Passes::COLOR,
        max_pixels: crate::io::file::DEFAULT_MAX_PIXELS,
    };
    plan_frame(&Inputs::color_only(pattern.clone()), frame, &options)
}

impl FramePlan {
    /// The warnings `blur` gives of the colour file's parts it cannot read: one for each
    /// reason, naming the parts, why and what to do (`exr::unsupported_reason`).
    pub fn unread_warnings(&self) -> Vec<String> {
        let mut reasons: Vec<&str> = self.parts_unread.iter().map(|(_, r)| &r[..]).collect();
        reasons.sort_unstable();
        reasons.dedup();
        reasons
            .into_iter()
            .map(|reason| {
                let parts: Vec<&str> = (self.parts_unread.iter())
                    .filter(|(_, r)| r == reason)
                    .map(|(name, _)| &name[..])
                    .collect();
                format!(
                    "{} of the colour file not read, nor written to the output: {reason}",
                    parts.join(", ")
                )
            })
            .collect()
    }

    /// The colour channels' names (R, G, B and, where read, A), as the colour file lists
    /// them.
    pub fn colour_channel_names(&self) -> Vec<String> {
        let Some(color) = &self.color else {
            return Vec::new();
        };
        let file = &self.files[color.rgb[0].file];
        (color.rgb.iter().chain(&color.a))
            .map(|slot| file.info.channels[file.channels[slot.entry]].name.clone())
            .collect()
    }

    /// The views of the colour file, where it is a multi-view EXR.
    pub fn colour_views(&self) -> Option<&crate::io::view::Views> {
        let file = self.color.as_ref()?.rgb[0].file;
        self.files.get(file)?.info.views.as_ref()
    }
}

/// A channel's name as its file stores it (a view's channel seen without its view,
/// [`crate::io::file::FileInfo::in_view`], has it in its header still).
fn stored_name(
    headers: &[exr::meta::header::Header],
    channel: &crate::io::file::ChannelInfo,
) -> String {
    headers
        .get(channel.part)
        .and_then(|h| h.channels.list.get(channel.index))
        .map_or_else(
            || channel.name.clone(),
            |c| crate::io::channels::name_of(&c.name),
        )
}
