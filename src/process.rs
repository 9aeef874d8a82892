//! One frame's processing, above the effects: the numeric policy ([`crate::numeric`]) applied
//! once as the frame enters (by the pipeline's read stage, or by [`process`]), then depth of field ([`crate::dof`]), then motion blur
//! ([`crate::motion`]) — "DoF before MB" (Sousa). `dof` and `motion` are siblings that never
//! import each other; this module is where they meet, and where each stage's backend is chosen.

use crate::dof::{self, CocSource, DofParams};
use crate::frame::{Color, Frame, LayerClass, Passes};
use crate::gpu::Gpu;
use crate::motion::{self, reconstruct, scatter, stretch, Algorithm, Shutter};
use crate::motion::{ReconstructParams, ScatterParams, StretchParams};
use crate::numeric::{self, DepthKind, Replaced};
use crate::stages::Cpu;

/// The default shutter: 0.5 of the frame interval (180°), centred on the frame.
pub const DEFAULT_SHUTTER: f32 = 0.5;

/// Everything one frame's processing reads besides the frame: the motion blur's parameters
/// for each algorithm, and the lens when depth of field runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params {
    /// Fraction of the frame interval the shutter is open (0.5 = 180°).
    pub shutter: f32,
    /// Where the exposure sits about the frame, in exposures: 0 centred, +½ opening at the
    /// frame, −½ closing at it ([`crate::motion::shutter::Shutter`]).
    pub shutter_offset: f32,
    pub reconstruct: ReconstructParams,
    pub scatter: ScatterParams,
    pub stretch: StretchParams,
    /// Depth of field, run before the motion blur when set ("DoF before MB", Sousa).
    pub dof: Option<DofParams>,
}

impl Default for Params {
    fn default() -> Self {
        Params {
            shutter: DEFAULT_SHUTTER,
            shutter_offset: 0.0,
            reconstruct: ReconstructParams::default(),
            scatter: ScatterParams::default(),
            stretch: StretchParams::default(),
            dof: None,
        }
    }
}

/// The passes a job reads: the algorithm's, and colour and depth for depth of field.
pub fn needs(algorithm: Algorithm, params: &Params) -> Passes {
    let mut passes = algorithm.needs();
    if let Some(dof) = &params.dof {
        passes = passes.union(dof.needs());
    }
    passes
}

/// What the depth plane holds under these parameters (a painted CoC map is read as depth).
pub fn depth_kind(params: &Params) -> DepthKind {
    match params.dof.map(|d| d.source) {
        Some(CocSource::Map { .. }) => DepthKind::CocMap,
        _ => DepthKind::Depth,
    }
}

/// Processes frame number `frame_number` (it seeds the per-pixel jitter, so the output depends
/// on nothing else): the numeric policy, then [`process_clean`]. Returns the output frame,
/// which holds the new colour (other passes are dropped: only colour is written), and what
/// the policy replaced.
pub fn process(
    algorithm: Algorithm,
    params: &Params,
    mut frame: Frame,
    frame_number: i64,
) -> (Frame, Replaced) {
    let replaced = numeric::sanitize(&mut frame, depth_kind(params));
    (
        process_clean(algorithm, params, frame, frame_number),
        replaced,
    )
}

/// Processes a frame that already obeys the numeric policy (the pipeline applies it in its
/// read stage, so the scan overlaps the processing of the frame before): depth of field when
/// asked for, then the algorithm.
pub fn process_clean(
    algorithm: Algorithm,
    params: &Params,
    frame: Frame,
    frame_number: i64,
) -> Frame {
    process_on(algorithm, params, frame, frame_number, None)
}

/// [`process_clean`] on a backend: the stages that have a GPU twin run on `gpu` when it is
/// given (depth of field's `coc`, tile min/max, gather and blend's pyramid; reconstruct's
/// tile stages and gather; scatter's and stretch's three stages), every other stage on the
/// CPU in the same run.
pub fn process_on(
    algorithm: Algorithm,
    params: &Params,
    frame: Frame,
    frame_number: i64,
    gpu: Option<&Gpu>,
) -> Frame {
    match gpu {
        Some(gpu) => process_with(algorithm, params, frame, frame_number, gpu),
        None => process_with(algorithm, params, frame, frame_number, &Cpu),
    }
}

/// [`process_clean`] with every pass's stages run by `stages` ([`crate::stages`]): the CPU's,
/// or a backend's twins.
///
/// The colour layers the frame carries beside its beauty (`diffuse.R`, `specular.A`, …;
/// [`crate::io::channels`]) are blurred with exactly the weights the beauty gets: three at
/// a time in the beauty's place, with the beauty's alpha, depth and motion, through the same
/// passes. Every weight of every pass is a function of those alone, but for reconstruct's
/// mattes (the exposure variant's coverage at silhouettes, fitted on colour), which are made
/// once from the beauty and read by every layer ([`reconstruct::reconstruct_layers_with`]);
/// so the blur is linear in the colour and a beauty that is the sum of its light layers still
/// is after it, to float rounding. On the CPU, scatter, the bokeh gather, reconstruct's
/// 2014 variants and stretch carry the layers through the beauty's own work (its curves,
/// its taps' weights, its fragments: [`scatter::stages_carrying`],
/// [`dof::gather::gather_carrying`], [`reconstruct::gather_2014::gather_2014_carrying`],
/// [`stretch::stages_carrying`]), so a layer costs its share of the sums alone, and the
/// GPU's bokeh gather, scatter and reconstruct's 2014 gather carry them through their
/// dispatches likewise; the other passes (and stretch on the GPU) run each group of three in
/// the beauty's place, which costs about what the beauty does (issue 29, point 6).
///
/// Data layers a preset classes `motion` take, after a motion blur, the value of the nearest
/// surface whose streak covers each pixel ([`motion::carry`]), found from the frame's depth
/// and motion before the passes; other data layers come back as they were read.
pub fn process_with(
    algorithm: Algorithm,
    params: &Params,
    frame: Frame,
    frame_number: i64,
    stages: &(impl dof::Stages + motion::Stages),
) -> Frame {
    let carried: Vec<usize> = (0..frame.carried.channels.len())
        .filter(|&i| frame.carried.channels[i].class == LayerClass::Motion)
        .collect();
    let nearest = match streak_of(algorithm, params) {
        Some(streak) if !carried.is_empty() => motion::carry::nearest_surfaces(&frame, &streak),
        _ => None,
    };
    let mut frame = process_layers(algorithm, params, frame, frame_number, stages);
    if let Some(nearest) = nearest {
        for &i in &carried {
            let channel = &mut frame.carried.channels[i];
            channel.plane = motion::carry::carried(&channel.plane, &nearest);
            if let Some(exact) = &channel.exact {
                channel.exact = Some(motion::carry::carried(exact, &nearest));
            }
        }
    }
    frame
}

/// The streaks `algorithm` draws, as [`motion::carry`] follows them: its exposure, its path,
/// its longest streak and its depth tolerance. `None` for no motion blur.
fn streak_of(algorithm: Algorithm, params: &Params) -> Option<motion::carry::Streak> {
    use motion::carry::{Nearer, Path, Streak};
    let shutter = shutter_of(params);
    Some(match algorithm {
        Algorithm::None => return None,
        // The half-spread is at most k a side ([`reconstruct::spread_2014`]).
        Algorithm::Reconstruct => Streak {
            interval: shutter.interval(),
            path: Path::Straight,
            longest: 2.0 * params.reconstruct.max_blur as f32,
            nearer: Nearer::By(params.reconstruct.soft_z.max(0.0)),
        },
        Algorithm::Stretch => {
            // Each side's shift is at most MAX_SHIFT.
            let config = stretch::StretchConfig::new(1, 1, &params.stretch, shutter);
            let sides = u8::from(config.t0 < 0.0) + u8::from(config.t1 > 0.0);
            Streak {
                interval: (config.t0, config.t1),
                path: Path::Straight,
                longest: stretch::MAX_SHIFT * f32::from(sides),
                nearer: Nearer::ByFraction(params.stretch.depth_tolerance.max(0.0)),
            }
        }
        Algorithm::Scatter => Streak {
            interval: shutter.interval(),
            path: Path::Curve {
                arc: params.scatter.curve == motion::CurveKind::Arc,
            },
            longest: params.scatter.max_curve.max(1.0),
            nearer: Nearer::ByFraction(params.scatter.depth_tolerance.max(0.0)),
        },
    })
}

/// The exposure `params` ask for, through the numeric policy.
fn shutter_of(params: &Params) -> Shutter {
    Shutter {
        open: numeric::shutter(params.shutter),
        offset: numeric::shutter_offset(params.shutter_offset),
    }
}

/// [`process_with`] but for the data layers: the beauty and its colour layers.
fn process_layers(
    algorithm: Algorithm,
    params: &Params,
    mut frame: Frame,
    frame_number: i64,
    stages: &(impl dof::Stages + motion::Stages),
) -> Frame {
    let colour: Vec<usize> = (0..frame.carried.channels.len())
        .filter(|&i| frame.carried.channels[i].class == LayerClass::Colour)
        .collect();
    // With nothing to do to the beauty there is nothing to do to its layers.
    let idle = algorithm == Algorithm::None && params.dof.is_none();
    let Some(beauty) = frame.color.as_ref().filter(|_| !idle && !colour.is_empty()) else {
        return process_beauty(algorithm, params, frame, &mut [], frame_number, stages);
    };
    let n = frame.pixel_count();
    let alpha = beauty.a.clone();
    let names: Vec<&str> = colour
        .iter()
        .map(|&i| frame.carried.channels[i].name.as_str())
        .collect();
    let groups = slots(&names);
    let mut layers: Vec<Color> = groups
        .iter()
        .map(|group| {
            let [r, g, b] = group.map(|slot| match slot {
                Some(k) => std::mem::take(&mut frame.carried.channels[colour[k]].plane),
                None => vec![0.0; n],
            });
            Color {
                r,
                g,
                b,
                a: alpha.clone(),
            }
        })
        .collect();
    let mut frame = process_beauty(algorithm, params, frame, &mut layers, frame_number, stages);
    for (group, layer) in groups.iter().zip(layers) {
        for (slot, plane) in group.iter().zip([layer.r, layer.g, layer.b]) {
            if let Some(k) = slot {
                frame.carried.channels[colour[*k]].plane = plane;
            }
        }
    }
    frame
}

/// Colour channels (by name) placed three at a time in the beauty's R, G and B: each
/// channel named for red (`diffuse.R`, `R`, `specular.red`) in R, green in G and blue in B,
/// any other (a layer's alpha, `emission.X`) where there is room, in order. Returns the
/// groups, each slot the index in `names` of the channel it holds (`None`: empty). Where a
/// pass fits a number to colour (reconstruct's mattes, per channel), a layer's R then gets
/// the beauty's R's, so layers that add up to the beauty channel by channel still do.
fn slots(names: &[&str]) -> Vec<[Option<usize>; 3]> {
    let mut queues: [Vec<usize>; 3] = Default::default();
    let mut others = Vec::new();
    for (k, name) in names.iter().enumerate() {
        let component = name.rsplit('.').next().unwrap_or(name).to_ascii_lowercase();
        match component.as_str() {
            "r" | "red" => queues[0].push(k),
            "g" | "green" => queues[1].push(k),
            "b" | "blue" => queues[2].push(k),
            _ => others.push(k),
        }
    }
    let mut groups = vec![[None; 3]; queues.iter().map(Vec::len).max().unwrap_or(0)];
    for (slot, queue) in queues.iter().enumerate() {
        for (group, &k) in queue.iter().enumerate() {
            groups[group][slot] = Some(k);
        }
    }
    // The others fill the empty slots first, then groups of their own.
    let mut others = others.into_iter();
    for group in groups.iter_mut() {
        for slot in group.iter_mut().filter(|s| s.is_none()) {
            *slot = others.next();
        }
    }
    let rest: Vec<usize> = others.collect();
    for chunk in rest.chunks(3) {
        let mut group = [None; 3];
        for (slot, &k) in group.iter_mut().zip(chunk) {
            *slot = Some(k);
        }
        groups.push(group);
    }
    groups
}

/// The passes over the frame's beauty and `layers` (colour beside it, each with its alpha):
/// depth of field when asked for, then the algorithm. Depth of field and every motion pass
/// take the layers into their passes (they share the CoC and tiles, the mattes, the curves,
/// stretch's taps and fragments).
fn process_beauty(
    algorithm: Algorithm,
    params: &Params,
    frame: Frame,
    layers: &mut [Color],
    frame_number: i64,
    stages: &(impl dof::Stages + motion::Stages),
) -> Frame {
    let frame = match &params.dof {
        Some(dof) => dof::apply_layers_with(frame, layers, dof, stages),
        None => frame,
    };
    let shutter = shutter_of(params);
    let pass = |f: Frame| match algorithm {
        Algorithm::Reconstruct | Algorithm::Scatter | Algorithm::Stretch => {
            unreachable!("they take their layers")
        }
        Algorithm::None => Frame {
            depth: None,
            velocity: None,
            prev: None,
            next: None,
            ..f
        },
    };
    match algorithm {
        Algorithm::Scatter => {
            scatter::scatter_layers_with(frame, layers, &params.scatter, shutter, stages)
        }
        Algorithm::Stretch => {
            stretch::stretch_layers_with(frame, layers, &params.stretch, shutter, stages)
        }
        Algorithm::Reconstruct => {
            // Frame numbers seed the jitter modulo 2³² (the hash is 32-bit).
            let seed = frame_number as u32;
            reconstruct::reconstruct_layers_with(
                frame,
                layers,
                &params.reconstruct,
                shutter,
                seed,
                stages,
            )
        }
        _ => {
            for layer in layers.iter_mut() {
                in_place(&frame, layer, &pass);
            }
            pass(frame)
        }
    }
}

/// `pass` run on `layer` in the beauty's place: a frame of `passes`' passes with its colour.
fn in_place(passes: &Frame, layer: &mut Color, pass: &dyn Fn(Frame) -> Frame) {
    let alone = Frame {
        color: Some(std::mem::replace(layer, Color::empty())),
        ..passes.clone_passes()
    };
    *layer = pass(alone).color.expect("the passes give colour back");
}

/// [`process`] without the count of replaced values.
pub fn apply(algorithm: Algorithm, params: &Params, frame: Frame, frame_number: i64) -> Frame {
    process(algorithm, params, frame, frame_number).0
}

#[cfg(test)]
mod tests {
    use super::slots;

    #[test]
    fn a_layer_s_red_green_and_blue_take_the_beauty_s_slots() {
        // As an EXR stores them: sorted by name, B before G before R.
        let names = [
            "diffuse.A",
            "diffuse.B",
            "diffuse.G",
            "diffuse.R",
            "emission.X",
            "specular.B",
            "specular.G",
            "specular.R",
            "sss.red",
        ];
        assert_eq!(
            slots(&names),
            [
                [Some(3), Some(2), Some(1)],
                [Some(7), Some(6), Some(5)],
                [Some(8), Some(0), Some(4)],
            ]
        );
        assert_eq!(
            slots(&["u", "v", "w", "x"]),
            [[Some(0), Some(1), Some(2)], [Some(3), None, None]]
        );
        assert!(slots(&[]).is_empty());
    }
}
