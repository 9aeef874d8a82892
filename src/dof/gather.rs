//! `gather`: depth of field as a flat bokeh gather with near and far fields, in the spirit of
//! Sousa's CryENGINE 3 filter (seed 003, "far + near field processing", "tile min/max CoC").
//!
//! Inputs: colour and the signed CoC plane of [`super::coc_plane`] (negative in front of the
//! focus plane). Output: the colour with depth of field. It sits before motion blur.
//!
//! The physics it approximates: each pixel spreads its light evenly over its bokeh — the
//! aperture's shape at the pixel's CoC — so a point of radiance L with bokeh area a gives
//! L/a to each pixel it covers, and nearer surfaces hide farther ones. Per output pixel p:
//!
//! 1. **Reach.** Tiles of 16×16 keep their largest |CoC|; a tile gathers over the largest
//!    radius of any tile whose bokeh can reach it (the near field's tile max of Sousa). A
//!    tile nothing out of focus can reach is copied.
//! 2. **Taps.** The [`super::bokeh`] rings, scaled to that radius R (fewer rings when R is
//!    small), read the nearest pixel s. The tap's distance is the aperture's norm, so an
//!    n-blade diaphragm shapes the bokeh.
//! 3. **Far field** (s no nearer than p, within 1 px of CoC): s counts where its bokeh and
//!    p's both cover the tap, `min(r_s, r_p)` — so an in-focus pixel takes nothing from the
//!    blurred background behind it, and a blurred background takes nothing from an in-focus
//!    subject in front of it (that subject is near field with a tiny bokeh). Weights are
//!    coverage / bokeh area, the far field's colour their normalised average ("pre-multiply
//!    with far CoC", Gotanda via Sousa). p itself always counts.
//! 4. **Near field** (s nearer than p by more than 1 px of CoC): s covers p where its own
//!    bokeh reaches, whatever p's — an out-of-focus foreground spreads over an in-focus
//!    background. Each tap adds coverage × tap area / bokeh area: an estimate of how much of
//!    p's light the near field blocks (its opacity α) and of the light it gives.
//! 5. **Composite**: `near + (1 − α)·far`, with α clamped to 1.
//!
//! Every weight is a share of one pixel's light, so HDR highlights keep their energy: a
//! bright pixel's light is spread over its bokeh, not averaged away. Output is a convex
//! combination of input pixels (within their range), computed per pixel in a fixed order
//! (the same bits for any thread count).

use rayon::prelude::*;

use super::bokeh::{grid, taps, Aperture, Tap};
use super::DofParams;
use crate::frame::Color;
use crate::motion::sanitize_color;

/// Tile edge (px) of the reach pass.
pub const TILE: usize = 16;

/// Two pixels whose signed CoC differ by less than this (px) are the same layer.
const LAYER: f32 = 1.0;

/// Smallest bokeh radius a weight divides by (px): a pixel's own footprint.
const SMALLEST_RADIUS: f32 = 0.5;

/// Depth of field by gathering; `coc` is the signed CoC plane (px, diameter).
pub fn gather(
    color: &Color,
    coc: &[f32],
    width: usize,
    height: usize,
    params: &DofParams,
) -> Color {
    let aperture = Aperture::new(params.blades, params.blade_rotation);
    // Bokeh radii up to `rings` px gather every pixel of their neighbourhood (`grid`, in
    // pixels); larger ones the rings (in units of the radius), which are then at least a
    // pixel apart.
    let grids: Vec<Vec<Tap>> = (0..=params.rings).map(|r| grid(r, &aperture)).collect();
    let rings = taps(params.rings, &aperture);
    let unit_area = aperture.unit_area();
    let has_alpha = color.a.is_some();
    // Texels: r, g, b, signed CoC radius; alpha beside when present.
    let texels: Vec<[f32; 4]> = (0..width * height)
        .into_par_iter()
        .map(|i| {
            [
                sanitize_color(color.r[i]),
                sanitize_color(color.g[i]),
                sanitize_color(color.b[i]),
                0.5 * coc[i],
            ]
        })
        .collect();
    let alpha: Vec<f32> = match &color.a {
        Some(a) => a.iter().map(|&v| sanitize_color(v)).collect(),
        None => Vec::new(),
    };
    let reach = reach(coc, width, height, params.epsilon);
    let tiles_x = width.div_ceil(TILE);

    let mut out = vec![[0.0f32; 4]; width * height];
    // Alpha rows go along even without alpha (unused then), so rows zip one to one.
    let mut out_alpha = vec![0.0f32; width * height];
    let half_focus = 0.5 * params.epsilon;
    out.par_chunks_mut(width)
        .zip(out_alpha.par_chunks_mut(width))
        .enumerate()
        .for_each(|(y, (row, row_alpha))| {
            for (x, px) in row.iter_mut().enumerate() {
                let i = y * width + x;
                let radius = reach[(y / TILE) * tiles_x + x / TILE];
                let centre = texels[i];
                if radius < half_focus.max(SMALLEST_RADIUS) {
                    *px = centre;
                    if has_alpha {
                        row_alpha[x] = alpha[i];
                    }
                    continue;
                }
                let whole = radius.ceil() as usize;
                let (pattern, scale) = if whole <= params.rings {
                    (&grids[whole], 1.0)
                } else {
                    (&rings, radius)
                };
                let r_p = centre[3].abs();
                let c_p = centre[3];
                let own = 1.0 / (unit_area * r_p.max(SMALLEST_RADIUS).powi(2));
                let centre_alpha = if has_alpha { alpha[i] } else { 0.0 };
                // Sums of weight × (sample − centre): a uniform frame stays exact.
                let mut far = [0.0f32; 4];
                let mut far_weight = own;
                let mut near = [0.0f32; 4];
                let mut opacity = 0.0f32;
                let area_scale = scale * scale;
                for tap in &pattern[1..] {
                    let sx = (x as f32 + 0.5 + tap.dx * scale).floor();
                    let sy = (y as f32 + 0.5 + tap.dy * scale).floor();
                    let sx = (sx.max(0.0) as usize).min(width - 1);
                    let sy = (sy.max(0.0) as usize).min(height - 1);
                    let s = sy * width + sx;
                    let t = texels[s];
                    let r_s = t[3].abs();
                    let inverse_area = 1.0 / (unit_area * r_s.max(SMALLEST_RADIUS).powi(2));
                    let a = if has_alpha { alpha[s] } else { 0.0 };
                    let d = [
                        t[0] - centre[0],
                        t[1] - centre[1],
                        t[2] - centre[2],
                        a - centre_alpha,
                    ];
                    let (sum, total, w) = if t[3] > c_p - 0.5 * LAYER {
                        let distance = tap.norm_far * scale;
                        let cover = (r_s.min(r_p) - distance + 0.5).clamp(0.0, 1.0);
                        (&mut far, &mut far_weight, cover * inverse_area)
                    } else {
                        let distance = tap.norm_near * scale;
                        let cover = (r_s - distance + 0.5).clamp(0.0, 1.0);
                        (
                            &mut near,
                            &mut opacity,
                            cover * tap.area * area_scale * inverse_area,
                        )
                    };
                    if w > 0.0 {
                        for k in 0..4 {
                            sum[k] += w * d[k];
                        }
                        *total += w;
                    }
                }
                let (near_scale, rest) = if opacity > 1.0 {
                    (1.0 / opacity, 0.0)
                } else {
                    (1.0, 1.0 - opacity)
                };
                let far_scale = rest / far_weight;
                let base = [centre[0], centre[1], centre[2], centre_alpha];
                let mix = |k: usize| base[k] + near[k] * near_scale + far[k] * far_scale;
                *px = [mix(0), mix(1), mix(2), 0.0];
                if has_alpha {
                    row_alpha[x] = mix(3);
                }
            }
        });
    let mut r = Vec::with_capacity(width * height);
    let mut g = Vec::with_capacity(width * height);
    let mut b = Vec::with_capacity(width * height);
    for t in &out {
        r.push(t[0]);
        g.push(t[1]);
        b.push(t[2]);
    }
    Color {
        r,
        g,
        b,
        a: has_alpha.then_some(out_alpha),
    }
}

/// Per tile, the gather radius (px): the largest bokeh radius of any tile whose bokeh can
/// reach it (0 where none out of focus can). Radii below ε/2 count as in focus.
pub fn reach(coc: &[f32], width: usize, height: usize, epsilon: f32) -> Vec<f32> {
    let tiles_x = width.div_ceil(TILE);
    let tiles_y = height.div_ceil(TILE);
    let mut largest = vec![0.0f32; tiles_x * tiles_y];
    for (y, row) in coc.chunks(width).enumerate() {
        for (x, &c) in row.iter().enumerate() {
            let t = &mut largest[(y / TILE) * tiles_x + x / TILE];
            let r = 0.5 * c.abs();
            if r >= 0.5 * epsilon && r > *t {
                *t = r;
            }
        }
    }
    let overall = largest.iter().fold(0.0f32, |m, &r| m.max(r));
    let span = ((overall + 1.0) / TILE as f32).ceil() as isize;
    let mut reach = vec![0.0f32; tiles_x * tiles_y];
    for ty in 0..tiles_y as isize {
        for tx in 0..tiles_x as isize {
            let mut best = 0.0f32;
            for oy in (ty - span).max(0)..=(ty + span).min(tiles_y as isize - 1) {
                for ox in (tx - span).max(0)..=(tx + span).min(tiles_x as isize - 1) {
                    let r = largest[oy as usize * tiles_x + ox as usize];
                    if r <= best {
                        continue;
                    }
                    // Gap in pixels between the two tiles, per axis.
                    let gap = |a: isize, b: isize| ((a - b).abs() - 1).max(0) as f32 * TILE as f32;
                    let (gx, gy) = (gap(tx, ox), gap(ty, oy));
                    if (gx * gx + gy * gy).sqrt() <= r + 1.0 {
                        best = r;
                    }
                }
            }
            reach[ty as usize * tiles_x + tx as usize] = best;
        }
    }
    reach
}
