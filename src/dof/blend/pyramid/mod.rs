//! blend's pyramid form, the default (seed 004, "Depth of Field: Technique Overview" to
//! "Render to Backbuffer", with the talk's "resolution reduction" variation taken all the
//! way): the blurred images are the levels of a binomial pyramid, and each pixel mixes the
//! two whose blur brackets its CoC; below level 3's CoC (18.1 px), where the pyramid cannot
//! show a disc, a pixel blurred by its own CoC takes the lens's disc directly (`disc`).
//!
//! Inputs: colour and the signed CoC plane (px, diameter). Output: the colour with depth of
//! field, written in place. Its GPU twin is `crate::gpu::dof::blend`, which runs the same
//! `plan` and reads a [`BlendConfig`].
//!
//! - **What a frame decides first** (`plan`, the twin's too): E; how many levels it needs
//!   (the last at least as blurred as E); the ladder that places each image at the CoC it
//!   shows; where T_near is read (at the blur of E); and the reference colour the texels are
//!   offset by (a uniform frame stays exact).
//! - **The levels** (`levels`): each halving filters with [1 3 3 1]/8 across and down;
//!   level L stands for a CoC of [`level_coc`]`(L)`, about twice the one before (4.3 px for
//!   level 1).
//! - **The discs** (`disc`): below level 2's CoC (9.0 px) the disc of the pixel's CoC over
//!   the sharp frame, up to level 3's over level 1's texels, each tap weighed by its coverage
//!   and its w, with short mixes between the three (which the pyramid's Gaussian-like images
//!   cannot: a disc passes a texture near its size inverted, and the fine levels alias).
//! - **Compose** (`compose`): per row, each pixel its disc, or mixed from the two images
//!   that bracket its CoC, linearly in CoC. The near field's spread (the blend's second ghosting fix) takes
//!   over only where it exceeds the pixel's own T by `SPREAD_MARGIN`: inside a uniform
//!   foreground the two are equal but for rounding.
//! - **Skip**: the levels a row needs are made for it and no others, and pixels with T = 0
//!   and no near blur reaching them are not touched.
//! - **Light layers** (`carry`, [`blend_carrying`]): planes carried beside the colour get
//!   its plan, w, T_near, blurriness, brackets and the discs' w, made once; each adds only
//!   its lanes of the levels, the discs and the mixes, eight planes a texel, with the bits it gets
//!   alone in the colour's place. At 1080p with six RGB layers the pass took 0.18–0.20 s
//!   where each layer run alone took 0.28–0.29 s, the beauty alone 0.04 s (BENCHMARKS.md,
//!   "Light layers"): the pyramid's per-pixel work is mostly each layer's own.
//!
//! Against the talk's two copies (BENCHMARKS.md, issue 14): on `layers` at 640×360 it errs
//! less (region RMSE 0.0296 against 0.0478 in one run, before the discs), and at 1080p it was
//! 14–22× faster before them (BENCHMARKS.md has the discs' cost).

mod carry;
mod compose;
mod disc;
mod levels;

use rayon::prelude::*;

use super::largest_coc;
use crate::dof::DofConfig;
use crate::frame::Color;
use carry::{compose_carried_row, CarriedRows, CarriedScratch, Group, Shared, GROUP};
use compose::{compose_row, Pyramid, Sampler, Scratch, Window};
pub use disc::{disc_bounds, FRAME_UNTIL, LEVEL_UNTIL};
use levels::{build, Ladder, Source, Texel, BAND, MAX_LEVELS, ZERO};
pub use levels::{level_coc, level_variance, COC_PER_SIGMA};

/// The pyramid's uniform, as its GPU twin reads it (`BlendConfig` in
/// src/gpu/dof/blend.wgsl; a test there holds the two layouts together): sixteen 4-byte
/// fields, `reference` (a vec4) on a 16-byte boundary, the whole a multiple of 16 as uniforms
/// need. Made from the frame's `Plan`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct BlendConfig {
    pub width: u32,
    pub height: u32,
    /// Levels 1 ..= `levels` are made.
    pub levels: u32,
    /// 1 where the frame has alpha.
    pub has_alpha: u32,
    /// The colour the texels are offset by (0 for a missing alpha).
    pub reference: [f32; 4],
    pub epsilon: f32,
    /// 1 / (E − ε).
    pub inverse_span: f32,
    /// E.
    pub largest: f32,
    /// 1 where T_near is read.
    pub near: u32,
    /// T_near is read at levels `near_k` and `near_k` + 1, mixed by `near_f`.
    pub near_k: u32,
    pub near_f: f32,
    /// Levels 2 and 3's CoCs, where the discs end ([`disc_bounds`]).
    pub disc_level_2: f32,
    pub disc_level_3: f32,
}

// Only the twin builds it (the CPU reads the plan itself).
#[cfg(feature = "gpu")]
impl BlendConfig {
    /// The uniform for a frame of `config` with alpha or without, whose plan is `plan`.
    pub(crate) fn new(config: &DofConfig, plan: &Plan, has_alpha: bool) -> Self {
        let (near_k, near_f) = plan.near.unwrap_or((0, 0.0));
        BlendConfig {
            width: config.width as u32,
            height: config.height as u32,
            levels: plan.levels as u32,
            has_alpha: has_alpha as u32,
            reference: plan.reference,
            epsilon: config.epsilon,
            inverse_span: plan.inverse_span,
            largest: plan.largest,
            near: plan.near.is_some() as u32,
            near_k: near_k as u32,
            near_f,
            disc_level_2: disc_bounds()[0],
            disc_level_3: disc_bounds()[1],
        }
    }
}

/// What the pyramid form decides for a frame before it blurs a pixel, the GPU twin's too.
pub(crate) struct Plan {
    /// E.
    pub largest: f32,
    /// Levels 1 ..= `levels` are made.
    pub levels: usize,
    /// Where each image of the pyramid stands in CoC.
    pub ladder: Ladder,
    /// Where T_near is read: the ladder's bracket of E, if any pixel is in front of the focus
    /// plane.
    pub near: Option<(usize, f32)>,
    /// The colour the texels are offset by: each plane's first sample (0 without alpha).
    pub reference: [f32; 4],
    /// 1 / (E − ε).
    pub inverse_span: f32,
}

/// The pyramid's [`Plan`] for a frame.
pub(crate) fn plan(config: &DofConfig, color: &Color, coc: &[f32]) -> Plan {
    let epsilon = config.epsilon;
    let largest = largest_coc(coc, epsilon);
    let mut reference = [0.0; 4];
    for (r, p) in reference.iter_mut().zip(color.planes()) {
        *r = p[0];
    }
    let inverse_span = 1.0 / (largest - epsilon);
    // Enough levels that the last one is at least as blurred as E, so every CoC (and
    // T_near, spread at E) is bracketed.
    let mut levels = 1;
    while levels < MAX_LEVELS && level_coc(levels) < largest {
        levels += 1;
    }
    let ladder = Ladder::new(levels);
    let interpolator = |c: f32| ((c.abs() - epsilon) * inverse_span).clamp(0.0, 1.0);
    // T_near is read at the blur of E, where any pixel is in front of the focus plane.
    let near = coc
        .par_iter()
        .any(|&c| c < 0.0 && interpolator(c) > 0.0)
        .then(|| ladder.bracket(largest));
    Plan {
        largest,
        levels,
        ladder,
        near,
        reference,
        inverse_span,
    }
}

/// The pyramid form: the blurred images are the levels of a binomial pyramid, and each
/// pixel mixes the two whose blur brackets its CoC; `coc` is the signed CoC plane (px,
/// diameter).
pub fn blend(config: &DofConfig, color: Color, coc: &[f32]) -> Color {
    blend_carrying(config, color, coc, Vec::new()).0
}

/// [`blend`], and each of `carried` (planes beside the colour: light layers' R, G and B)
/// blurred with the colour's weights, bit for bit as [`blend`] blurs it in a colour channel's
/// place: the plan, the weights, each pixel's blurriness and mix are made once, and the
/// planes only add their own lanes to the levels and the mixes (`carry`).
pub fn blend_carrying(
    config: &DofConfig,
    mut color: Color,
    coc: &[f32],
    mut carried: Vec<Vec<f32>>,
) -> (Color, Vec<Vec<f32>>) {
    let (width, height) = (config.width, config.height);
    let Plan {
        largest,
        levels: count,
        ladder,
        near,
        reference,
        inverse_span,
    } = plan(config, &color, coc);
    let source = Source {
        planes: color.planes(),
        coc,
        reference,
        epsilon: config.epsilon,
        largest,
        inverse_span,
        plain: false,
    };
    let epsilon = config.epsilon;
    let levels = build(&source, width, height, count);
    let groups: Vec<Group> = carried
        .chunks(GROUP)
        .map(|planes| Group::new(&source, planes, width, height, count))
        .collect();
    let samplers: Vec<Sampler> = levels
        .iter()
        .enumerate()
        .map(|(l, level)| Sampler::new(level, l + 1, width, height))
        .collect();

    // The compose stage writes the frame in place, a band of rows per task, and reads each
    // row as it was (the sharp image; the discs read texels made before it): each task keeps
    // copies of the rows around the one it writes, and the rows just outside each band are
    // copied before any task starts. (Only the row itself is read since the half step went;
    // the copies of the rows above and below are left for a later change.)
    let bands = height.div_ceil(BAND);
    // The colour's planes, then the carried ones.
    let channels = source.planes.len();
    // The frame as texels (premultiplied by w, as the levels' are), where some pixel reads
    // the frame's disc: the beauty's with w, each carried group's (the compose stage writes
    // the planes in place, and the discs read them as they were).
    let bounds = disc_bounds();
    let to_coc = |t: f32| epsilon + t * (largest - epsilon);
    // And the plain level 1 (every pixel by the filter alone, w = 1), beauty's and each
    // carried group's, where some pixel in front of the focus plane reads level 1's disc.
    // One pass over the CoC says whether each is needed.
    let (frame_disc, plain_disc) = coc
        .par_iter()
        .map(|&c| {
            let t = source.interpolator(c);
            let own = to_coc(t);
            let level_disc = own > disc::FRAME_UNTIL * bounds[0] && own < bounds[1];
            (
                t > 0.0 && own <= bounds[0],
                c < 0.0 && t > 0.0 && level_disc,
            )
        })
        .reduce(|| (false, false), |a, b| (a.0 || b.0, a.1 || b.1));
    let (plain, plain_groups) = if plain_disc {
        let plain_source = source.plain();
        let groups: Vec<Group> = carried
            .chunks(GROUP)
            .map(|planes| Group::new(&plain_source, planes, width, height, 1))
            .collect();
        (
            Some(levels::first_level(&plain_source, width, height)),
            groups,
        )
    } else {
        (None, Vec::new())
    };
    let (frame, carried_frames) = if frame_disc {
        let mut beauty = ZERO;
        beauty[..4].copy_from_slice(&reference);
        let groups: Vec<Vec<Texel>> = carried
            .chunks(GROUP)
            .zip(&groups)
            .map(|(planes, group)| {
                let planes: Vec<&[f32]> = planes.iter().map(Vec::as_slice).collect();
                disc::frame_texels(&source, &planes, group.reference(), false)
            })
            .collect();
        (
            disc::frame_texels(&source, &source.planes, &beauty, true),
            groups,
        )
    } else {
        (Vec::new(), Vec::new())
    };
    let copy = |y: usize| -> Vec<f32> {
        source
            .planes
            .iter()
            .copied()
            .chain(carried.iter().map(Vec::as_slice))
            .flat_map(|p| &p[y * width..(y + 1) * width])
            .copied()
            .collect()
    };
    // The row above and the row below each band (clamped to the frame).
    let edges: Vec<[Vec<f32>; 2]> = (0..bands)
        .map(|b| {
            let above = (b * BAND).saturating_sub(1);
            let below = ((b + 1) * BAND).min(height - 1);
            [copy(above), copy(below)]
        })
        .collect();
    let source = Source {
        planes: Vec::new(),
        coc,
        reference,
        epsilon,
        largest,
        inverse_span: source.inverse_span,
        plain: false,
    };
    let mut chunks: Vec<_> = [
        Some(&mut color.r),
        Some(&mut color.g),
        Some(&mut color.b),
        color.a.as_mut(),
    ]
    .into_iter()
    .flatten()
    .chain(carried.iter_mut())
    .map(|p| p.chunks_mut(width * BAND))
    .collect();
    let band_planes: Vec<Vec<&mut [f32]>> = (0..bands)
        .map(|_| {
            chunks
                .iter_mut()
                .map(|c| c.next().expect("a band per plane"))
                .collect()
        })
        .collect();
    let pyramid = Pyramid {
        source: &source,
        samplers: &samplers,
        ladder: &ladder,
        near,
        frame: &frame,
        plain: plain.as_ref(),
        bounds,
    };
    let shared = Shared {
        source: &source,
        samplers: &samplers,
        ladder: &ladder,
        frames: &carried_frames,
        frame: &frame,
        plain: &plain_groups,
        bounds,
    };
    band_planes
        .into_par_iter()
        .zip(edges.par_iter())
        .enumerate()
        .for_each_init(
            || {
                let ring = [Vec::new(), Vec::new(), Vec::new()];
                (Scratch::default(), ring, CarriedScratch::default())
            },
            |(scratch, ring, carried), (band, (mut planes, edge))| {
                let rows = planes[0].len() / width;
                // ring[0], ring[1], ring[2]: copies of rows j − 1, j and j + 1 of the band.
                let load = |buffer: &mut Vec<f32>, planes: &[&mut [f32]], j: usize| {
                    buffer.clear();
                    for p in planes {
                        buffer.extend_from_slice(&p[j * width..(j + 1) * width]);
                    }
                };
                load(&mut ring[1], &planes, 0);
                for j in 0..rows {
                    let y = band * BAND + j;
                    if j + 1 < rows {
                        load(&mut ring[2], &planes, j + 1);
                    }
                    let above: &[f32] = match (j, y) {
                        (_, 0) => &ring[1],
                        (0, _) => &edge[0],
                        _ => &ring[0],
                    };
                    let below: &[f32] = if y + 1 == height {
                        &ring[1]
                    } else if j + 1 == rows {
                        &edge[1]
                    } else {
                        &ring[2]
                    };
                    // Channel ch of a copied row (empty past the frame's channels).
                    fn plane(rows: &[f32], ch: usize, width: usize) -> &[f32] {
                        rows.get(ch * width..(ch + 1) * width).unwrap_or(&[])
                    }
                    let window: Window = std::array::from_fn(|ch| {
                        if ch < channels {
                            [
                                plane(above, ch, width),
                                plane(&ring[1], ch, width),
                                plane(below, ch, width),
                            ]
                        } else {
                            [&[] as &[f32]; 3]
                        }
                    });
                    let mut out: Vec<&mut [f32]> = planes
                        .iter_mut()
                        .map(|p| &mut p[j * width..(j + 1) * width])
                        .collect();
                    let (out, out_carried) = out.split_at_mut(channels);
                    compose_row(&pyramid, y, &window, scratch, out);
                    if !groups.is_empty() {
                        let rows = CarriedRows {
                            rows: [above, &ring[1], below],
                            first: channels,
                        };
                        compose_carried_row(
                            &shared,
                            &groups,
                            y,
                            &rows,
                            scratch,
                            carried,
                            out_carried,
                        );
                    }
                    ring.rotate_left(1);
                }
            },
        );
    (color, carried)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn the_disc_reads_the_frame_as_it_was_across_bands() {
        // Every pixel at CoC 3 (E = 3, so T = 1 and w = 1 everywhere): each output is the
        // disc of diameter 3 over the input, each tap weighted by the share of it inside the
        // disc, clamp(2 − d, 0, 1) (d its distance: the 5 × 5 neighbourhood but its corners
        // and the taps at d = 2), renormalised over the taps inside the frame. The frame is
        // taller than two bands, so rows next to a band's edge read rows another task writes
        // in place.
        let (width, height) = (7, 2 * BAND + 5);
        let n = width * height;
        let value = |i: usize, k: usize| ((i * 7919 + k * 104_729) % 1000) as f32 / 1000.0;
        let planes: Vec<Vec<f32>> = (0..4)
            .map(|k| (0..n).map(|i| value(i, k)).collect())
            .collect();
        let color = Color {
            r: planes[0].clone(),
            g: planes[1].clone(),
            b: planes[2].clone(),
            a: Some(planes[3].clone()),
        };
        let coc = vec![3.0f32; n];
        let config = DofConfig::new(width, height, &crate::dof::DofParams::default());
        let out = blend(&config, color, &coc);
        for (k, got) in out.planes().iter().enumerate() {
            for y in 0..height as i64 {
                for x in 0..width as i64 {
                    let (mut sum, mut weights) = (0.0f64, 0.0f64);
                    for sy in (y - 2).max(0)..=(y + 2).min(height as i64 - 1) {
                        for sx in (x - 2).max(0)..=(x + 2).min(width as i64 - 1) {
                            let d = (((sx - x).pow(2) + (sy - y).pow(2)) as f64).sqrt();
                            let cover = (2.0 - d).clamp(0.0, 1.0);
                            sum += cover * planes[k][sy as usize * width + sx as usize] as f64;
                            weights += cover;
                        }
                    }
                    let expected = sum / weights;
                    let got = got[y as usize * width + x as usize] as f64;
                    assert!(
                        close(got, expected, 1e-5),
                        "plane {k} ({x}, {y}): {got} against {expected}"
                    );
                }
            }
        }
    }
}
