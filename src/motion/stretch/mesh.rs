//! stretch's mesh: its second and third stages, the vertices' moves and the triangles drawn
//! over the sharp frame, for the beauty and, with the same fragments and alphas, the light
//! layers carried beside it; where the frame is not wholly covered, what the fragments leave
//! for the fourth stage, [`cover`](super::cover).

use rayon::prelude::*;

use super::config::{StretchConfig, MAX_SHIFT};
use crate::motion::triangle::{draw, Rect};

/// Rows per drawing band.
const BAND: usize = 32;

/// `a + t·(b − a)`, kept between a and b.
fn mix(a: f32, b: f32, t: f32) -> f32 {
    (a + t * (b - a)).clamp(a.min(b), a.max(b))
}

/// Stage 2: per vertex (pixel centre), its move over the exposure and its alpha. A moving
/// silhouette vertex (one with a farther neighbour beyond the tear ratio) moves to t0 where
/// its motion faces away from the nearer surface's normal, to t1 where it faces along it;
/// the others stay, opaque.
pub fn move_vertices(config: &StretchConfig, z: &[f32], v: &[[f32; 2]]) -> Vec<([f32; 2], f32)> {
    let (width, height) = (config.width as usize, config.height as usize);
    let move_of = |i: usize| -> ([f32; 2], f32) {
        let [vx, vy] = v[i];
        if !config.moving(v[i]) {
            return ([0.0; 2], 1.0);
        }
        let (x, y) = (i % width, i / width);
        let mut normal = [0.0f32; 2];
        for (dx, dy) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
            let (nx, ny) = (x as i64 + dx, y as i64 + dy);
            if nx < 0 || ny < 0 || nx >= width as i64 || ny >= height as i64 {
                continue;
            }
            let j = ny as usize * width + nx as usize;
            if z[j] > z[i] * config.tear {
                normal[0] += dx as f32;
                normal[1] += dy as f32;
            }
        }
        let facing = vx * normal[0] + vy * normal[1];
        let t = if facing < 0.0 {
            config.t0
        } else if facing > 0.0 {
            config.t1
        } else {
            0.0
        };
        if t == 0.0 {
            return ([0.0; 2], 1.0);
        }
        let mut shift = [vx * t, vy * t];
        let mut length = (shift[0] * shift[0] + shift[1] * shift[1]).sqrt();
        if length > MAX_SHIFT {
            let cut = MAX_SHIFT / length;
            shift = [shift[0] * cut, shift[1] * cut];
            length = MAX_SHIFT;
        }
        let alpha = (1.0 - length / config.extent).max(config.min_alpha);
        (shift, alpha.min(1.0))
    };
    (0..width * height).into_par_iter().map(move_of).collect()
}

/// The motion a vertex gives the fragments that sweep a pixel (px per frame): its velocity,
/// cut as its move is, so that over the longer part of the exposure on either side of the
/// frame it covers at most [`MAX_SHIFT`] px, direction kept. A smear reaches no farther, and
/// the fragments interpolate the motion between corners: a corner at the numeric policy's
/// 1e7 px beside one at 9 px made the motion of a fragment near the slow corner hang on the
/// last bits of its weights (f64 here, f32 in the GPU twin: 1 px apart).
pub fn swept_motion(config: &StretchConfig, [vx, vy]: [f32; 2]) -> [f32; 2] {
    let reach = (vx * vx + vy * vy).sqrt() * config.t0.abs().max(config.t1.abs());
    if reach > MAX_SHIFT {
        let cut = MAX_SHIFT / reach;
        [vx * cut, vy * cut]
    } else {
        [vx, vy]
    }
}

/// Stage 3: every untorn triangle with a moved vertex drawn over `out`, farthest first, alpha
/// blended, each fragment depth-tested against the frame. With the pre-blur, a fragment over
/// a pixel of its own surface (a depth within the tear of its own) is not drawn: the pre-blur
/// has averaged that pixel along its motion already, and the talk's interpolated sharp colour
/// at up to alpha 1 hid that (a sharp line along the inside of every silhouette, beside a seam
/// where the pre-blur had shown what lies behind). A fragment over a pixel the frame
/// does not wholly cover (alpha below 1) is not blended: it writes its motion and depth into
/// `swept` (per pixel: velocity x, y, depth, and 1 where a fragment came; the nearest
/// fragment's, as it is drawn last), for [`cover`](super::cover) to turn into the smear's
/// coverage.
pub fn rasterise(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
    vertices: &[([f32; 2], f32)],
    out: &mut [Vec<f32>; 4],
    swept: &mut [[f32; 4]],
) {
    draw_all::<false>(config, planes, z, v, vertices, out, swept, &[], &mut [], 0);
}

/// [`rasterise`], and the light layers' `channels` carried planes (`carried`, pixel-major, as
/// [`texture_blur_carrying`](super::texture_blur_carrying) takes them) drawn over
/// `carried_out` by the same fragments: each fragment's depth test, barycentric weights and
/// alpha are found once and blend every carried channel as they blend the beauty's. So a
/// carried channel comes out with the bits it gets in the beauty's place.
#[allow(clippy::too_many_arguments)] // the beauty's buffers, then the carried ones
pub fn rasterise_carrying(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
    vertices: &[([f32; 2], f32)],
    out: &mut [Vec<f32>; 4],
    swept: &mut [[f32; 4]],
    carried: &[f32],
    carried_out: &mut [f32],
    channels: usize,
) {
    if channels == 0 {
        draw_all::<false>(config, planes, z, v, vertices, out, swept, &[], &mut [], 0);
    } else {
        draw_all::<true>(
            config,
            planes,
            z,
            v,
            vertices,
            out,
            swept,
            carried,
            carried_out,
            channels,
        );
    }
}

/// The triangles drawn over the beauty, and where `CARRY` over the carried planes too (one
/// copy of the loop each way, so the beauty's alone is as it was).
#[allow(clippy::too_many_arguments)]
fn draw_all<const CARRY: bool>(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
    vertices: &[([f32; 2], f32)],
    out: &mut [Vec<f32>; 4],
    swept: &mut [[f32; 4]],
    carried: &[f32],
    carried_out: &mut [f32],
    channels: usize,
) {
    let (width, height) = (config.width as usize, config.height as usize);
    // Triangles with a moved vertex, farthest first.
    let quads_across = width.saturating_sub(1);
    let position = |i: usize| {
        let (shift, _) = vertices[i];
        [
            (i % width) as f64 + 0.5 + shift[0] as f64,
            (i / width) as f64 + 0.5 + shift[1] as f64,
        ]
    };
    // Each with its depth key and its rows on screen (so a band skips it without
    // rebuilding it).
    let mut triangles: Vec<(f32, u32, [f64; 2])> = (0..quads_across * height.saturating_sub(1) * 2)
        .into_par_iter()
        .filter_map(|t| {
            let corners = triangle_corners(t, quads_across, width);
            let moved = corners.iter().any(|&i| vertices[i].0 != [0.0; 2]);
            let zs = corners.map(|i| z[i]);
            let (lo, hi) = (
                zs.iter().copied().fold(f32::INFINITY, f32::min),
                zs.iter().copied().fold(0.0, f32::max),
            );
            if !moved || config.torn(lo, hi) {
                return None;
            }
            let ys = corners.map(|i| position(i)[1]);
            let rows = [
                ys.iter().copied().fold(f64::INFINITY, f64::min),
                ys.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ];
            Some((hi, t as u32, rows))
        })
        .collect();
    triangles.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));

    let [r, g, b, a] = out;
    let strip = BAND * width;
    // Each band's carried values (none for the beauty alone).
    let carried_bands: Vec<&mut [f32]> = if CARRY {
        carried_out.chunks_mut(strip * channels).collect()
    } else {
        (0..height.div_ceil(BAND))
            .map(|_| Default::default())
            .collect()
    };
    r.par_chunks_mut(strip)
        .zip(g.par_chunks_mut(strip))
        .zip(b.par_chunks_mut(strip))
        .zip(a.par_chunks_mut(strip))
        .zip(carried_bands)
        .zip(swept.par_chunks_mut(strip))
        .enumerate()
        .for_each(|(band, (((((r, g), b), a), carried_band), swept_band))| {
            let mut rows = [r, g, b, a];
            let rect = Rect {
                x0: 0,
                y0: band * BAND,
                x1: width,
                y1: ((band + 1) * BAND).min(height),
            };
            for &(_, t, [lo, hi]) in &triangles {
                if hi < rect.y0 as f64 - 0.5 || lo > rect.y1 as f64 + 0.5 {
                    continue;
                }
                let corners = triangle_corners(t as usize, quads_across, width);
                let p = corners.map(position);
                draw(p, rect, |x, y, w| {
                    let i = y * width + x;
                    let (w1, w2) = (w[1] as f32, w[2] as f32);
                    let interpolate = |values: [f32; 3]| {
                        let v =
                            values[0] + w1 * (values[1] - values[0]) + w2 * (values[2] - values[0]);
                        let lo = values.iter().copied().fold(f32::INFINITY, f32::min);
                        let hi = values.iter().copied().fold(f32::NEG_INFINITY, f32::max);
                        v.clamp(lo, hi)
                    };
                    let depth = interpolate(corners.map(|k| z[k]));
                    if depth > z[i] * config.depth_limit {
                        return;
                    }
                    let o = i - band * strip;
                    if planes[3][i] < 1.0 {
                        // (cover's test, `alpha >= 1`, turned round.) What shows behind the smear here is (partly) nothing: cover gives
                        // the pixel the smear's coverage, along the nearest one's motion.
                        let motions = corners.map(|k| swept_motion(config, v[k]));
                        let motion = [0, 1].map(|d| interpolate(motions.map(|m| m[d])));
                        swept_band[o] = [motion[0], motion[1], depth, 1.0];
                        return;
                    }
                    if config.texture_blur() && !config.torn(z[i], depth) {
                        // The smear's own surface, which the pre-blur has averaged already.
                        return;
                    }
                    let alpha = interpolate(corners.map(|k| vertices[k].1));
                    for c in 0..4 {
                        let source = interpolate(corners.map(|k| planes[c][k]));
                        rows[c][o] = mix(rows[c][o], source, alpha);
                    }
                    if CARRY {
                        let row = &mut carried_band[o * channels..][..channels];
                        for (c, value) in row.iter_mut().enumerate() {
                            let source = interpolate(corners.map(|k| carried[k * channels + c]));
                            *value = mix(*value, source, alpha);
                        }
                    }
                });
            }
        });
}

/// The pixel indices of triangle `t`: quad (qx, qy) has corners 00, 10, 01, 11 (pixel
/// centres); its first triangle is 00-10-11, its second 00-11-01.
pub fn triangle_corners(t: usize, quads_across: usize, width: usize) -> [usize; 3] {
    let quad = t / 2;
    let (qx, qy) = (quad % quads_across, quad / quads_across);
    let i = qy * width + qx;
    if t.is_multiple_of(2) {
        [i, i + 1, i + width + 1]
    } else {
        [i, i + width + 1, i + width]
    }
}
