//! One frame's processing, above the effects: the numeric policy ([`crate::numeric`]) applied
//! once as the frame enters (by the pipeline's read stage, or by [`process`]), then depth of field ([`crate::dof`]), then motion blur
//! ([`crate::motion`]) — "DoF before MB" (Sousa). `dof` and `motion` are siblings that never
//! import each other; this module is where they meet, and where each stage's backend is chosen.

use crate::dof::{self, CocSource, DofParams};
use crate::frame::{Carried, Color, Frame, LayerClass, Passes, Plane};
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
/// passes. Every weight of every pass is a function of those alone, never of the colour, so
/// the blur is linear in the colour and a beauty that is the sum of its light layers still
/// is after it, to float rounding. Each group of three costs what the beauty does; sharing
/// one computation of the weights between them is the next step (issue 29, point 6).
pub fn process_with(
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
    if let (false, false, Some(beauty)) = (idle, colour.is_empty(), &frame.color) {
        let n = frame.pixel_count();
        for group in colour.chunks(3) {
            let mut planes: Vec<Plane> = group
                .iter()
                .map(|&i| std::mem::take(&mut frame.carried.channels[i].plane))
                .collect();
            planes.resize_with(3, || vec![0.0; n]);
            let [r, g, b]: [Plane; 3] = planes.try_into().expect("three planes");
            let layers = Frame {
                color: Some(Color {
                    r,
                    g,
                    b,
                    a: beauty.a.clone(),
                }),
                carried: Carried::default(),
                ..frame.clone_passes()
            };
            let out = process_beauty(algorithm, params, layers, frame_number, stages);
            let color = out.color.expect("the passes give colour back");
            for (&i, plane) in group.iter().zip([color.r, color.g, color.b]) {
                frame.carried.channels[i].plane = plane;
            }
        }
    }
    process_beauty(algorithm, params, frame, frame_number, stages)
}

/// The passes over the frame's beauty: depth of field when asked for, then the algorithm.
fn process_beauty(
    algorithm: Algorithm,
    params: &Params,
    frame: Frame,
    frame_number: i64,
    stages: &(impl dof::Stages + motion::Stages),
) -> Frame {
    let frame = match &params.dof {
        Some(dof) => dof::apply_with(frame, dof, stages),
        None => frame,
    };
    let shutter = Shutter {
        open: numeric::shutter(params.shutter),
        offset: numeric::shutter_offset(params.shutter_offset),
    };
    match algorithm {
        Algorithm::Reconstruct => {
            // Frame numbers seed the jitter modulo 2³² (the hash is 32-bit).
            let seed = frame_number as u32;
            reconstruct::reconstruct_with(frame, &params.reconstruct, shutter, seed, stages)
        }
        Algorithm::Scatter => scatter::scatter_with(frame, &params.scatter, shutter, stages),
        Algorithm::Stretch => stretch::stretch_with(frame, &params.stretch, shutter, stages),
        Algorithm::None => Frame {
            depth: None,
            velocity: None,
            prev: None,
            next: None,
            ..frame
        },
    }
}

/// [`process`] without the count of replaced values.
pub fn apply(algorithm: Algorithm, params: &Params, frame: Frame, frame_number: i64) -> Frame {
    process(algorithm, params, frame, frame_number).0
}
