//! `blend`: Wloka's depth-of-field blend (Arce & Wloka, "In-Game Special Effects and
//! Lighting", seed 004, "Depth of Field: Technique Overview" to "Render to Backbuffer"): the
//! sharp frame and progressively blurred images of it, mixed per pixel by the blurriness
//! interpolator.
//!
//! Inputs: colour and the signed CoC plane of [`super::coc_plane`] (px, diameter). Output:
//! the colour with depth of field. It is the stage after `coc` in `--method blend`
//! ([`super::apply`]) and sits before motion blur. Its GPU twin (`crate::gpu::dof::blend`)
//! runs the pyramid; the talk's form runs on the CPU on either backend.
//!
//! - **Blurriness interpolator** `T = clamp((|CoC| − ε)/(E − ε), 0, 1)` per pixel (the talk's
//!   `T.r(d)`), with E the frame's largest CoC (`largest_coc`): the sharp frame stands for
//!   CoCs of ε or less, the most blurred image for E.
//! - **The blurred images**, in one of two forms ([`BlendForm`]):
//!   1. [`pyramid`], the default: the levels of a binomial pyramid, each half the size of the
//!      one before (the talk's "resolution reduction" variation), as many as E needs, and a
//!      half step at full resolution between the sharp frame and level 1. Each image is
//!      placed at the CoC it actually shows, and a pixel mixes the two that bracket its CoC,
//!      linearly in CoC.
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
