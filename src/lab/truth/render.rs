//! Rendering a scene: the passes a renderer writes (colour antialiased at the frame time,
//! and the depth, velocity, previous and next positions of the surface seen at each pixel
//! centre) and the brute-force references (motion blur: many time samples over the shutter,
//! [(o − ½)·φ, (o + ½)·φ] about the frame for offset o, `motion::Shutter`;
//! depth of field: many aperture samples; and both together).
//!
//! Reference samples follow a randomly shifted Kronecker sequence in five dimensions
//! (sub-pixel x and y, time, aperture u and v; `sample::kronecker`), shifted per pixel by a
//! hash. The colour pass uses the same sub-pixel positions. Time is snapped
//! to a grid of `TIME_STEPS` instants across the shutter, whose scene poses are computed once
//! per frame; at 4096 steps the snap moves a sample by φ/4096 of a frame, below a hundredth of
//! a pixel for motion under 80 px per frame.

use glam::DVec2;
use rayon::prelude::*;

use super::model::{Hit, Posed, Scene};
use super::sample::{concentric_disk, kronecker, pixel_shift, DIMENSIONS};
use crate::frame::{Color, Frame, Plane, Positions, Velocity};

/// Instants across the shutter at which scene poses are tabulated.
pub const TIME_STEPS: usize = 4096;

/// What to render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    /// Reference samples per pixel.
    pub samples: usize,
    /// Shutter fraction φ.
    pub shutter: f64,
    /// Where the exposure sits about the frame, in exposures (`motion::Shutter::offset`):
    /// the references integrate t ∈ [(o − ½)·φ, (o + ½)·φ] about the frame's time.
    pub shutter_offset: f64,
    pub seed: u64,
}

/// Which reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reference {
    /// Time samples over the shutter, pinhole.
    MotionBlur,
    /// Aperture samples at the frame time.
    DepthOfField,
    /// Both.
    Both,
}

/// Evaluates `pixel(i, j)` for every pixel, rows in parallel, and returns the `K` values as
/// `K` planes.
pub(super) fn render_planes<const K: usize>(
    width: usize,
    height: usize,
    pixel: impl Fn(usize, usize) -> [f32; K] + Sync,
) -> Vec<Plane> {
    let rows: Vec<Vec<[f32; K]>> = (0..height)
        .into_par_iter()
        .map(|j| (0..width).map(|i| pixel(i, j)).collect())
        .collect();
    let mut planes: Vec<Plane> = (0..K).map(|_| Vec::with_capacity(width * height)).collect();
    for value in rows.into_iter().flatten() {
        for (plane, v) in planes.iter_mut().zip(value) {
            plane.push(v);
        }
    }
    planes
}

/// The mean of `samples` rays through pixel (i, j), `K` values each (a colour, or a layer's
/// colour and coverage): sample k uses point k of the pixel's shifted Kronecker sequence,
/// `trace(u, p)` gets it and its sub-pixel position.
pub(super) fn pixel_mean<const K: usize>(
    i: usize,
    j: usize,
    width: usize,
    samples: usize,
    seed: u64,
    trace: impl Fn(&[f64; DIMENSIONS], DVec2) -> [f32; K],
) -> [f32; K] {
    let shift = pixel_shift(seed, (j * width + i) as u64);
    let mut sum = [0.0f64; K];
    for k in 0..samples {
        let u = kronecker(k, &shift);
        let value = trace(&u, DVec2::new(i as f64 + u[0], j as f64 + u[1]));
        for (s, c) in sum.iter_mut().zip(value) {
            *s += c as f64;
        }
    }
    sum.map(|s| (s / samples as f64) as f32)
}

/// Offsets below this many pixels are rounding in the closed-form transforms, not motion:
/// they are written as exactly zero so that still surfaces are exactly still.
const STILL: f64 = 1e-6;

/// Where the surface `hit` at the pixel centre `centre` at frame time `t` is one frame
/// earlier and one frame later, p(−1) and p(+1), screen pixels y down; offsets below
/// [`STILL`] are snapped to the centre.
pub(super) fn prev_next(scene: &Scene, hit: &Hit, centre: DVec2, t: f64) -> (DVec2, DVec2) {
    let settle = |p: DVec2| {
        if (p - centre).length() < STILL {
            centre
        } else {
            p
        }
    };
    (
        settle(scene.screen_position(hit, t - 1.0)),
        settle(scene.screen_position(hit, t + 1.0)),
    )
}

/// The passes of frame time `t` (colour, depth, velocity, prev, next). Colour is
/// antialiased with `samples` sub-pixel samples at the same positions as the references use,
/// so pixels that nothing crosses during the exposure are identical in colour and reference.
pub fn render_passes(scene: &Scene, t: f64, samples: usize, seed: u64) -> Frame {
    let (width, height) = (scene.width, scene.height);
    let n = width * height;
    let samples = samples.max(1);
    let posed = scene.pose(t);
    let order = scene.front_to_back();
    let planes = render_planes(width, height, |i, j| {
        let [r, g, b] = pixel_mean(i, j, width, samples, seed, |_, p| {
            scene.trace(&posed, &order, p, DVec2::ZERO).color
        });
        let centre = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
        let hit = scene.trace(&posed, &order, centre, DVec2::ZERO);
        let (prev, next) = prev_next(scene, &hit, centre, t);
        [
            r,
            g,
            b,
            hit.depth as f32,
            (centre.x - prev.x) as f32,
            (centre.y - prev.y) as f32,
            prev.x as f32,
            prev.y as f32,
            next.x as f32,
            next.y as f32,
        ]
    });
    let mut it = planes.into_iter();
    let mut take = || it.next().expect("ten planes");
    let (r, g, b, depth) = (take(), take(), take(), take());
    let velocity = Velocity {
        x: take(),
        y: take(),
    };
    let (px, py, nx, ny) = (take(), take(), take(), take());
    let mut frame = Frame::new(width, height);
    frame.color = Some(Color {
        r,
        g,
        b,
        a: Some(vec![1.0; n]),
    });
    frame.prev = Some(Positions {
        x: px,
        y: py,
        z: Some(depth.clone()),
    });
    frame.next = Some(Positions {
        x: nx,
        y: ny,
        z: Some(depth.clone()),
    });
    frame.depth = Some(depth);
    frame.velocity = Some(velocity);
    frame
}

/// The scene posed at [`TIME_STEPS`] times over the shutter about frame time `t` (the
/// midpoints of equal steps), which a sample's time coordinate picks among.
fn shutter_poses(scene: &Scene, t: f64, settings: &RenderSettings) -> Vec<Posed> {
    (0..TIME_STEPS)
        .into_par_iter()
        .map(|s| {
            let phase = (s as f64 + 0.5) / TIME_STEPS as f64 - 0.5 + settings.shutter_offset;
            scene.pose(t + settings.shutter * phase)
        })
        .collect()
}

/// A brute-force reference of frame time `t`: RGB planes.
pub fn render_reference(
    scene: &Scene,
    t: f64,
    kind: Reference,
    settings: &RenderSettings,
) -> [Plane; 3] {
    let (width, height) = (scene.width, scene.height);
    let samples = settings.samples.max(1);
    let moving = kind != Reference::DepthOfField;
    let poses = if moving {
        shutter_poses(scene, t, settings)
    } else {
        vec![scene.pose(t)]
    };
    let steps = poses.len();
    let order = scene.front_to_back();
    let lens = kind != Reference::MotionBlur && scene.lens.is_some();
    let planes = render_planes(width, height, |i, j| {
        pixel_mean(i, j, width, samples, settings.seed, |u, p| {
            let posed = &poses[((u[2] * steps as f64) as usize).min(steps - 1)];
            let aperture = if lens {
                concentric_disk(u[3], u[4])
            } else {
                DVec2::ZERO
            };
            scene.trace(posed, &order, p, aperture).color
        })
    });
    let mut it = planes.into_iter();
    let mut take = || it.next().expect("three planes");
    [take(), take(), take()]
}

/// The motion-blur references of the two view layers alone ([`super::layers`]): `FG`, every
/// shape over a transparent film, premultiplied RGBA (a sample that reaches the background
/// adds nothing, alpha the share of samples that hit a shape), and `BG`, the background
/// plane with no shape before it, RGB; over the same shutter, with the same samples as
/// [`render_reference`]. What each layer blurred alone should come out as; `FG over BG` of
/// the two is the best a merge of separately blurred layers can do.
pub fn render_layer_references(scene: &Scene, t: f64, settings: &RenderSettings) -> [Plane; 7] {
    let (width, height) = (scene.width, scene.height);
    let samples = settings.samples.max(1);
    let poses = shutter_poses(scene, t, settings);
    let order = scene.front_to_back();
    let nothing: [usize; 0] = [];
    let planes = render_planes(width, height, |i, j| {
        pixel_mean(i, j, width, samples, settings.seed, |u, p| {
            let posed = &poses[((u[2] * poses.len() as f64) as usize).min(poses.len() - 1)];
            let hit = scene.trace(posed, &order, p, DVec2::ZERO);
            let [r, g, b, a] = match hit.shape {
                Some(_) => [hit.color[0], hit.color[1], hit.color[2], 1.0],
                None => [0.0; 4],
            };
            let [br, bg, bb] = scene.trace(posed, &nothing, p, DVec2::ZERO).color;
            [r, g, b, a, br, bg, bb]
        })
    });
    let mut it = planes.into_iter();
    let mut take = || it.next().expect("seven planes");
    [take(), take(), take(), take(), take(), take(), take()]
}
