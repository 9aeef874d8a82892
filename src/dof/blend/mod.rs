//! `blend`: Wloka's depth-of-field blend (Arce & Wloka, "In-Game Special Effects and
//! Lighting", seed 004, "Depth of Field: Technique Overview" to "Render to Backbuffer"): the
//! sharp frame and progressively blurred images of it, mixed per pixel by the blurriness
//! interpolator.
//!
//! Inputs: colour and the signed CoC plane of [`super::coc_plane`] (px, diameter). Output:
//! the colour with depth of field. It is the stage after `coc` in `--method blend`
//! ([`super::apply`]) and sits before motion blur. Its GPU twin (`crate::gpu::dof::blend`)
//! runs the pyramid; the talk's form runs on the CPU on either backend. Light layers beside
//! the beauty ([`blend_carrying`]) ride on the beauty's weights: on the CPU the pyramid makes
//! everything that depends on the CoC once and each layer adds only its own lanes
//! (`pyramid::carry`); the talk's form and the GPU twin run each layer in the beauty's place.
//!
//! - **Blurriness interpolator** `T = clamp((|CoC| − ε)/(E − ε), 0, 1)` per pixel (the talk's
//!   `T.r(d)`), with E the frame's largest CoC (`largest_coc`): the sharp frame stands for
//!   CoCs of ε or less, the most blurred image for E.
//! - **The blurred images**, in one of two forms ([`BlendForm`]):
//!   1. [`pyramid`], the default: the levels of a binomial pyramid, each half the size of the
//!      one before (the talk's "resolution reduction" variation), as many as E needs. Each
//!      image is placed at the CoC it actually shows, and a pixel mixes the two that bracket
//!      its CoC, linearly in CoC; below level 3's CoC (18 px) a pixel blurred by its own CoC
//!      takes the lens's disc over the sharp frame or level 1 instead (`pyramid::disc`).
//!   2. [`talk`]: the talk's own form, the sharp frame and two copies made by n and 2n
//!      passes of its 3×3 filter blit ("Render to Backbuffer": texture 0, n and 2n), each
//!      placed at the CoC it shows, mixed along CoC = ε + T·(E − ε).
//! - **Ghosting at transitions.** The talk lists "blurriness interpolator interpolation" and
//!   names the problem ("visibility on blurred edges potentially wrong") without giving the
//!   fix, so this is ours, in two parts shared by both forms:
//!   1. The blurred images blur colour premultiplied by `w = max(T, 1/64)`
//!      (`IN_FOCUS_WEIGHT`) and divide by the blurred w, so sharp pixels lend almost
//!      nothing to them: an in-focus subject does not leave a ghost halo on the blurred
//!      background around it.
//!   2. They also blur `T_near` (T of pixels in front of the focus plane, 0 behind), and a
//!      pixel blends with `max(T, blurred T_near)`: a blurred foreground spreads over the
//!      sharp background behind its edge instead of stopping hard at its silhouette.
//! - **Skip**: a frame whose CoC stays below ε is returned as it is ([`super::apply`]), and
//!   pixels with T = 0 and no near blur reaching them keep their sharp value; each form makes
//!   its images only where some output reads them.
//!
//! Output is a convex mix of weighted averages of input pixels, computed in a fixed order.

pub mod pyramid;
pub mod talk;

use rayon::prelude::*;

use super::{BlendForm, DofConfig};
use crate::frame::Color;

/// Weight of an in-focus pixel in the blurred images (relative to 1 for a fully blurred one).
const IN_FOCUS_WEIGHT: f32 = 1.0 / 64.0;

/// E: the frame's largest CoC (the plane is already clamped to --max-coc), at least a pixel
/// above ε, so the blur is spent on what the frame has.
fn largest_coc(coc: &[f32], epsilon: f32) -> f32 {
    coc.par_iter()
        .map(|c| c.abs())
        .reduce(|| 0.0, f32::max)
        .max(epsilon + 1.0)
}

/// Depth of field by blending progressively blurred images of the frame; `coc` is the signed
/// CoC plane (px, diameter). The form is `config.blend_form`: the pyramid or the talk's two
/// copies.
pub fn blend(config: &DofConfig, color: Color, coc: &[f32]) -> Color {
    match config.blend_form {
        BlendForm::Pyramid => pyramid::blend(config, color, coc),
        BlendForm::Talk => talk::blend(config, &color, coc),
    }
}

/// [`blend`], and the R, G and B of `layers` (light layers beside the colour) blurred in
/// place with its weights, each as [`blend`] blurs it in the colour's place, bit for bit:
/// the pyramid carries them through the colour's own plan, weights and mixes
/// ([`pyramid::blend_carrying`]); the talk's form runs on each layer. Their alpha is left as
/// it came.
pub fn blend_carrying(
    config: &DofConfig,
    color: Color,
    coc: &[f32],
    layers: &mut [Color],
) -> Color {
    match config.blend_form {
        BlendForm::Pyramid => {
            let planes: Vec<Vec<f32>> = layers
                .iter_mut()
                .flat_map(|l| [&mut l.r, &mut l.g, &mut l.b])
                .map(std::mem::take)
                .collect();
            let (out, carried) = pyramid::blend_carrying(config, color, coc, planes);
            let mut carried = carried.into_iter();
            for layer in layers.iter_mut() {
                for plane in [&mut layer.r, &mut layer.g, &mut layer.b] {
                    *plane = carried.next().expect("three planes a layer");
                }
            }
            out
        }
        BlendForm::Talk => {
            for layer in layers.iter_mut() {
                let blurred = talk::blend(config, layer, coc);
                (layer.r, layer.g, layer.b) = (blurred.r, blurred.g, blurred.b);
            }
            talk::blend(config, &color, coc)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dof::DofParams;

    #[test]
    fn both_forms_blur_each_layer_s_colour_as_blend_alone_and_leave_its_alpha() {
        // The pyramid carries the layers (its own tests vary sizes and counts); the talk's
        // form runs each alone. Either way a layer's R, G and B are the bits `blend` gives it
        // in the beauty's place, and its alpha is the one it came with.
        let (width, height) = (23, 19);
        let n = width * height;
        let value = |i: usize, k: usize| ((i * 7919 + k * 104_729) % 1000) as f32 / 250.0;
        let color = |k: usize| Color {
            r: (0..n).map(|i| value(i, 4 * k)).collect(),
            g: (0..n).map(|i| value(i, 4 * k + 1)).collect(),
            b: (0..n).map(|i| value(i, 4 * k + 2)).collect(),
            a: Some((0..n).map(|i| value(i, 4 * k + 3)).collect()),
        };
        let coc: Vec<f32> = (0..n)
            .map(|i| (i % width) as f32 * 1.5 - 12.0 + (i / width) as f32 * 0.3)
            .collect();
        for form in [BlendForm::Pyramid, BlendForm::Talk] {
            let params = DofParams {
                blend_form: form,
                passes: Some(2),
                ..DofParams::default()
            };
            let config = DofConfig::new(width, height, &params);
            let mut layers: Vec<Color> = (1..=3).map(color).collect();
            let out = blend_carrying(&config, color(0), &coc, &mut layers);
            let bits = |p: &[f32]| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            let alone = blend(&config, color(0), &coc);
            for (got, want) in out.planes().iter().zip(alone.planes()) {
                assert_eq!(bits(got), bits(want), "{form:?}: the beauty");
            }
            for (k, layer) in layers.iter().enumerate() {
                let came = color(k + 1);
                let alone = blend(&config, came.clone(), &coc);
                assert_ne!(bits(&alone.r), bits(&came.r), "{form:?}: blurred");
                for (got, want) in [
                    (&layer.r, &alone.r),
                    (&layer.g, &alone.g),
                    (&layer.b, &alone.b),
                ] {
                    assert_eq!(bits(got), bits(want), "{form:?}: layer {k}");
                }
                assert_eq!(layer.a, came.a, "{form:?}: layer {k}'s alpha");
            }
        }
    }
}
