//! stretch — the vertex-stretch motion blur of Wloka & Zeleznik as presented by Arce & Wloka
//! (*In-Game Special Effects and Lighting*, "Motion Blur: The Technique"), brought from
//! meshes to images (docs/DESIGN.md "stretch").
//!
//! The image becomes a mesh: a vertex at every pixel centre carrying its colour, depth and
//! velocity; two triangles per 2×2 quad of centres; no triangle where the depths of its
//! vertices differ by more than the tear ratio (`depth_max > depth_min · (1 + tear)`), so a
//! moving object tears away from its background instead of dragging it like a rubber sheet.
//!
//! Per vertex, the screen-space normal N points out of the nearer surface: the sum of the
//! directions to those of its four neighbours that lie beyond the tear ratio (so only
//! silhouette vertices of the nearer side have one). With motion M = v (px per frame):
//! - [`Anchor::Rear`] (the talk's version, rear-curtain: the object sharp at the end of the
//!   exposure): where M·N < 0 the vertex moves back to the start of the exposure, by −v·φ, and
//!   becomes translucent, `alpha = max(min_alpha, 1 − |v·φ|/extent)`; other vertices stay.
//! - [`Anchor::Centre`] (for shutter centred on the frame, docs/DESIGN.md): trailing vertices
//!   move back by v·φ/2, leading ones (M·N > 0) forward by v·φ/2, both translucent by the
//!   same formula with that displacement.
//!
//! The sharp frame is drawn first, then every triangle with a moved vertex, back to front
//! (farthest vertex first), alpha blended, each fragment depth-tested against the frame
//! (`z ≤ depth · (1 + depth_tolerance)`) so nearer still surfaces stay in front.
//!
//! Beyond the talk, and from its own list of cons ("per-vertex operation: no texture
//! blurring … pre-process textures in motion-directions"): with `texture_blur`, each moving
//! pixel's colour is first averaged along its own motion over the exposure (bilinear
//! samples), leaving out samples of nearer surfaces: a moving surface smears over itself and
//! reveals what lies behind it, but never pulls a nearer surface over itself. Without it, a
//! textured surface moving as a whole (a camera pan) is not blurred at all, only silhouettes
//! are.
//!
//! Numerics: inputs obey the numeric policy ([`crate::numeric`]: finite colour, velocity
//! within ±[`VELOCITY_LIMIT`](crate::numeric::VELOCITY_LIMIT), depth in [0, +∞]). Every
//! output value is a convex combination of input colours, clamped against rounding (to the
//! frame's range for the pre-blur, to what it combines for interpolation and blending), so
//! it is finite and within the input range; a uniform colour stays exactly uniform
//! (averages, interpolation and blending all work on differences).
//!
//! Determinism: triangles are ordered by depth with their index as the tie-break, and drawn
//! into fixed bands of rows, each band taking every triangle that reaches it in that order.

use rayon::prelude::*;

use super::triangle::{draw, Rect};
use crate::frame::{Color, Frame};
use crate::motion::shutter::Shutter;
use crate::stages::Cpu;

/// A pixel whose streak over the exposure is shorter than this many pixels is still.
pub const STILL: f32 = 0.5;
/// Rows per drawing band.
const BAND: usize = 32;
/// At most this many samples along a pixel's motion in the texture pre-blur.
pub const MOST_SAMPLES: usize = 64;
/// A vertex moves at most this many pixels over the exposure (its move is cut to this
/// length, direction kept), as reconstruct's blur radius k is 128 px by default. A triangle's
/// cost grows with its moved vertex's distance, and velocities up to the numeric policy's
/// 1e7 px would otherwise make sliver triangles across the whole frame: with 10% of pixels
/// at 1e9 px and 30% at depth 0 (tearing the mesh everywhere), 640×360 took 1.2 s against
/// 0.2 s without those velocities and 1280×720 12.6 s against 0.75 s, growing with the
/// square of the pixel count (issue 17). By then such a smear is at the alpha floor.
pub const MAX_SHIFT: f32 = 128.0;

/// Where the sharp object sits within its streak.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Anchor {
    /// At the end of the exposure (the talk's rear-curtain form): trailing vertices move
    /// back by the whole exposure.
    Rear,
    /// In the middle (our shutter is centred on the frame): trailing vertices back, leading
    /// ones forward, by half the exposure each.
    Centre,
}

impl Anchor {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, Anchor)] =
        &[("centre", Anchor::Centre), ("rear", Anchor::Rear)];
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StretchParams {
    /// `extent` of `alpha = max(min_alpha, 1 − |M|/extent)`, pixels. Default 2, chosen on the
    /// bench: larger extents leave the smears too opaque (BENCHMARKS.md).
    pub extent: f32,
    /// The alpha floor (the talk's 0.1).
    pub min_alpha: f32,
    /// Relative depth step that tears the mesh.
    pub tear: f32,
    pub anchor: Anchor,
    /// Average each moving pixel's colour along its own motion first.
    pub texture_blur: bool,
    /// A fragment is drawn over a pixel whose depth is at least its own / (1 + this).
    pub depth_tolerance: f32,
}

impl Default for StretchParams {
    fn default() -> Self {
        StretchParams {
            extent: 2.0,
            min_alpha: 0.1,
            tear: 0.05,
            anchor: Anchor::Centre,
            texture_blur: true,
            depth_tolerance: 0.02,
        }
    }
}

/// Everything stretch's stages read besides their buffers, as plain numbers: the uniform of
/// its GPU twin (keep in sync with `struct StretchConfig` in src/gpu/motion/stretch.wgsl; a test
/// there compares the fields).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct StretchConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// Fraction of the frame interval the shutter is open.
    pub shutter: f32,
    /// The exposure, in frames relative to the frame's own time: [t0, t1].
    pub t0: f32,
    pub t1: f32,
    /// 1 + the tear ratio: neighbours whose depths differ by more are not joined.
    pub tear: f32,
    /// `extent` of a moved vertex's alpha, pixels (at least 1e-6).
    pub extent: f32,
    /// The alpha floor, in [0, 1].
    pub min_alpha: f32,
    /// 1 + the depth tolerance: a fragment is drawn where its depth ≤ the pixel's × this.
    pub depth_limit: f32,
    /// 1 where colour is averaged along the motion first ([`texture_blur`]), else 0.
    pub texture_blur: u32,
}

impl StretchConfig {
    /// Whether colour is averaged along the motion first, typed (the GPU reads the word).
    pub fn texture_blur(&self) -> bool {
        self.texture_blur != 0
    }

    pub fn new(
        width: usize,
        height: usize,
        params: &StretchParams,
        shutter: impl Into<Shutter>,
    ) -> Self {
        let shutter = shutter.into();
        // Rear is the talk's rear curtain: the frame closes the exposure whatever the offset
        // (it is the centre anchor of `--shutter-offset end`). Centre follows the exposure
        // wherever the offset puts it.
        let (t0, t1) = match params.anchor {
            Anchor::Rear => (-shutter.open, 0.0),
            Anchor::Centre => shutter.interval(),
        };
        let shutter = shutter.open;
        StretchConfig {
            width: width as u32,
            height: height as u32,
            shutter,
            t0,
            t1,
            tear: 1.0 + params.tear.max(0.0),
            extent: params.extent.max(1e-6),
            min_alpha: params.min_alpha.clamp(0.0, 1.0),
            depth_limit: 1.0 + params.depth_tolerance.max(0.0),
            texture_blur: params.texture_blur as u32,
        }
    }

    /// Whether a pixel of velocity `v` streaks far enough over the exposure to move.
    #[inline]
    pub fn moving(&self, [x, y]: [f32; 2]) -> bool {
        (x * x + y * y).sqrt() * self.shutter >= STILL
    }

    /// Whether two depths lie on different surfaces.
    #[inline]
    fn torn(&self, a: f32, b: f32) -> bool {
        a.max(b) > a.min(b) * self.tear
    }
}

/// `a + t·(b − a)`, kept between a and b.
fn mix(a: f32, b: f32, t: f32) -> f32 {
    (a + t * (b - a)).clamp(a.min(b), a.max(b))
}

/// Applies the filter: [`texture_blur`] → [`move_vertices`] → [`rasterise`]. The frame must
/// hold colour, depth and velocity; the output holds colour alone. A frame in which nothing
/// moves keeps its colour untouched.
pub fn stretch(frame: Frame, params: &StretchParams, shutter: impl Into<Shutter>) -> Frame {
    stretch_with(frame, params, shutter, &Cpu)
}

/// Stretch's stages that a backend may run elsewhere: texture_blur → move_vertices →
/// rasterise, as one (the GPU keeps the vertices and the drawn frame on the device between
/// them). The default is the CPU's [`stages`], the reference; [`Cpu`] takes it, and the GPU
/// (`crate::gpu::motion`) overrides it with its twin, which must return the same planes
/// within the tolerance its parity test states (tests/gpu_stretch.rs).
pub trait Stages {
    /// [`stages`].
    fn stages(
        &self,
        config: &StretchConfig,
        planes: &[Vec<f32>; 4],
        z: &[f32],
        v: &[[f32; 2]],
    ) -> [Vec<f32>; 4] {
        stages(config, planes, z, v)
    }
}

impl Stages for Cpu {}

/// The three stages on the CPU: the colour planes (R, G, B, A) drawn over the sharp frame.
pub fn stages(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
) -> [Vec<f32>; 4] {
    // The sharp frame to draw first: pre-blurred along each pixel's motion if asked.
    let mut out = if config.texture_blur() {
        texture_blur(config, planes, z, v)
    } else {
        planes.clone()
    };
    let vertices = move_vertices(config, z, v);
    rasterise(config, planes, z, &vertices, &mut out);
    out
}

/// [`stretch`] with its [`Stages`] run by `stages` (the CPU's, [`Cpu`], or a backend's twin),
/// given the config, the colour planes (R, G, B, A: an opaque alpha where the frame has
/// none), depth and velocity; they return the four planes. Only frames in which something
/// moves reach them; the config is made here from the frame's size, so it always matches.
pub fn stretch_with(
    mut frame: Frame,
    params: &StretchParams,
    shutter: impl Into<Shutter>,
    stages: &impl Stages,
) -> Frame {
    let (width, height) = (frame.width, frame.height);
    frame.prev = None;
    frame.next = None;
    let (Some(color), Some(depth), Some(velocity)) = (
        frame.color.take(),
        frame.depth.take(),
        frame.velocity.take(),
    ) else {
        return frame;
    };
    let config = StretchConfig::new(width, height, params, shutter);
    let n = width * height;
    let v: Vec<[f32; 2]> = velocity
        .x
        .par_iter()
        .zip(&velocity.y)
        .map(|(&x, &y)| [x, y])
        .collect();
    if n == 0 || !v.par_iter().any(|&v| config.moving(v)) {
        // Colour alone, as on every path.
        frame.color = Some(color);
        return frame;
    }
    drop(velocity);
    let z = depth;
    let has_alpha = color.a.is_some();
    let planes: [Vec<f32>; 4] = [
        color.r,
        color.g,
        color.b,
        color.a.unwrap_or_else(|| vec![1.0; n]),
    ];
    let [r, g, b, a] = stages.stages(&config, &planes, &z, &v);
    frame.color = Some(Color {
        r,
        g,
        b,
        a: has_alpha.then_some(a),
    });
    frame
}

/// Stage 1: each moving pixel's colour averaged along its own motion over the exposure
/// (bilinear samples, leaving out nearer surfaces), clamped to the frame's range per channel;
/// still pixels keep theirs. Returns the frame to draw first.
///
/// At time t the pixel at x shows the point of its surface that was at x − v·t at the frame,
/// so the samples read x − v·t for t over [t0, t1]. (Centred, [t0, t1] is symmetric and the
/// sign does not matter; until issue 19 this read x + v·t, which mirrored the streak about
/// the pixel for the rear anchor and for an offset shutter.)
pub fn texture_blur(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
) -> [Vec<f32>; 4] {
    let (width, height) = (config.width as usize, config.height as usize);
    let n = width * height;
    let (t0, t1) = (config.t0, config.t1);
    // Colour and depth together, so a tap reads one cache line.
    let texels: Vec<[f32; 5]> = (0..n)
        .into_par_iter()
        .map(|i| [planes[0][i], planes[1][i], planes[2][i], planes[3][i], z[i]])
        .collect();
    // The frame's range per channel: averages are clamped to it against rounding.
    let range: [(f32, f32); 4] = std::array::from_fn(|c| {
        planes[c]
            .par_iter()
            .fold(
                || (f32::INFINITY, f32::NEG_INFINITY),
                |(lo, hi), &v| (lo.min(v), hi.max(v)),
            )
            .reduce(
                || (f32::INFINITY, f32::NEG_INFINITY),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            )
    });
    let mut blurred = planes.clone();
    let [r, g, b, a] = &mut blurred;
    r.par_chunks_mut(width)
        .zip(g.par_chunks_mut(width))
        .zip(b.par_chunks_mut(width))
        .zip(a.par_chunks_mut(width))
        .enumerate()
        .for_each(|(y, (((r, g), b), a))| {
            let rows = [r, g, b, a];
            #[allow(clippy::needless_range_loop)] // x indexes four rows and the frame
            for x in 0..width {
                let i = y * width + x;
                if !config.moving(v[i]) {
                    continue;
                }
                let [vx, vy] = v[i];
                let length = (vx * vx + vy * vy).sqrt() * (t1 - t0);
                let samples = (length.ceil() as usize + 1).clamp(2, MOST_SAMPLES);
                // Sample points are pixel-centre coordinates: pixel (x, y) sits at (x, y).
                let own: [f32; 4] = std::array::from_fn(|c| planes[c][i]);
                let mut sum = [0.0f32; 4];
                let mut total = 0.0f32;
                for k in 0..samples {
                    let t = t0 + (t1 - t0) * (k as f32 + 0.5) / samples as f32;
                    // Bilinear between the four nearest centres, over those of the same
                    // surface (so a sub-pixel streak still blurs).
                    let (px, py) = (x as f32 - vx * t, y as f32 - vy * t);
                    let (fx, fy) = (px.floor(), py.floor());
                    let (ax, ay) = (px - fx, py - fy);
                    for (dx, dy, w) in [
                        (0, 0, (1.0 - ax) * (1.0 - ay)),
                        (1, 0, ax * (1.0 - ay)),
                        (0, 1, (1.0 - ax) * ay),
                        (1, 1, ax * ay),
                    ] {
                        let (sx, sy) = (fx + dx as f32, fy + dy as f32);
                        if !(w > 0.0
                            && sx >= 0.0
                            && sy >= 0.0
                            && sx < width as f32
                            && sy < height as f32)
                        {
                            continue;
                        }
                        let texel = &texels[sy as usize * width + sx as usize];
                        if texel[4] * config.tear < z[i] {
                            continue;
                        }
                        for c in 0..4 {
                            sum[c] += w * (texel[c] - own[c]);
                        }
                        total += w;
                    }
                }
                if total > 0.0 {
                    for c in 0..4 {
                        let value = own[c] + sum[c] / total;
                        rows[c][x] = value.clamp(range[c].0, range[c].1);
                    }
                }
            }
        });
    blurred
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

/// Stage 3: every untorn triangle with a moved vertex drawn over `out`, farthest first, alpha
/// blended, each fragment depth-tested against the frame.
pub fn rasterise(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    vertices: &[([f32; 2], f32)],
    out: &mut [Vec<f32>; 4],
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
    r.par_chunks_mut(strip)
        .zip(g.par_chunks_mut(strip))
        .zip(b.par_chunks_mut(strip))
        .zip(a.par_chunks_mut(strip))
        .enumerate()
        .for_each(|(band, (((r, g), b), a))| {
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
                    let alpha = interpolate(corners.map(|k| vertices[k].1));
                    let o = i - band * strip;
                    for c in 0..4 {
                        let source = interpolate(corners.map(|k| planes[c][k]));
                        rows[c][o] = mix(rows[c][o], source, alpha);
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn the_config_is_ten_plain_words() {
        // Uploaded as one uniform by the GPU twin: ten 4-byte fields, no padding.
        assert_eq!(std::mem::size_of::<StretchConfig>(), 40);
        let c = StretchConfig::new(4, 3, &StretchParams::default(), 0.5);
        // The centred anchor splits the exposure about the frame.
        assert_eq!((c.t0, c.t1), (-0.25, 0.25));
        let rear = StretchParams {
            anchor: Anchor::Rear,
            ..StretchParams::default()
        };
        let c = StretchConfig::new(4, 3, &rear, 0.5);
        assert_eq!((c.t0, c.t1), (-0.5, 0.0));
    }

    #[test]
    fn a_vertex_moves_at_most_max_shift_whatever_its_velocity() {
        // A 2×1 strip: a near pixel beside a far one, so the near vertex is a silhouette
        // whose normal points at the far one (+x). Before the cut, a velocity at the numeric
        // policy's limit moved it 2.5e6 px and its triangles crossed the whole frame.
        let c = StretchConfig::new(2, 1, &StretchParams::default(), 0.5);
        let z = [1.0, 10.0];
        for (vx, expected) in [(8.0f32, 2.0f32), (1e7, MAX_SHIFT), (-1e7, MAX_SHIFT)] {
            let v = [[vx, 0.0], [0.0; 2]];
            let moved = move_vertices(&c, &z, &v);
            let [sx, sy] = moved[0].0;
            let length = (sx * sx + sy * sy).sqrt();
            assert!(close(length, expected, 1e-3), "{vx}: {length}");
            // The direction is kept: moving along its normal (+x) it goes forward to t1,
            // moving against it back to t0, so +x either way; the far vertex stays.
            assert!(sy == 0.0 && sx > 0.0);
            assert!(moved[0].1 >= c.min_alpha && moved[0].1 <= 1.0);
            assert_eq!(moved[1], ([0.0; 2], 1.0));
        }
    }
}
