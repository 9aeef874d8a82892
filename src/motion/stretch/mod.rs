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
//! Beyond the talk, for frames with transparency (a view layer of a stack, premultiplied,
//! alpha 0 and infinitely far where empty): the talk's translucency is a look over a
//! background, and where a pixel is not wholly covered (alpha below 1) there is (partly) no
//! background, so it would be the output's alpha. There a fragment is not blended; the
//! fourth stage, [`cover`], gives the pixel the coverage and colour the exposure gives it,
//! the sharp frame averaged along the nearest smear's motion (cover.rs says what the talk's
//! blend did on a Cycles render's FG layer). An opaque frame has no such pixel: it is drawn
//! as the talk draws it, bit for bit.
//!
//! Beyond the talk, and from its own list of cons ("per-vertex operation: no texture
//! blurring … pre-process textures in motion-directions"): with `texture_blur`, each moving
//! pixel's colour is first averaged along its own motion over the exposure (bilinear
//! samples), leaving out samples of nearer surfaces: a moving surface smears over itself and
//! reveals what lies behind it, but never pulls a nearer surface over itself. Without it, a
//! textured surface moving as a whole (a camera pan) is not blurred at all, only silhouettes
//! are. With it, a smear is not drawn over its own surface (the pixels within the tear of a
//! fragment's depth): the pre-blur has averaged those along their motion, and redrawing them
//! with the sharp colour at up to alpha 1 put a sharp line inside every moving silhouette.
//!
//! Numerics: inputs obey the numeric policy ([`crate::numeric`]: finite colour, velocity
//! within ±[`VELOCITY_LIMIT`](crate::numeric::VELOCITY_LIMIT), depth in [0, +∞]). Every
//! output value is a convex combination of input colours, clamped against rounding (to the
//! frame's range for the pre-blur, to what it combines for interpolation, blending and
//! cover's averages), so
//! it is finite and within the input range; a uniform colour stays exactly uniform
//! (averages, interpolation and blending all work on differences).
//!
//! Determinism: triangles are ordered by depth with their index as the tie-break, and drawn
//! into fixed bands of rows, each band taking every triangle that reaches it in that order;
//! of the fragments that sweep a pixel, the last drawn stays.

mod config;
mod cover;
mod mesh;
mod texture_blur;

use rayon::prelude::*;

use crate::frame::{Color, Frame};
use crate::motion::shutter::Shutter;
use crate::stages::Cpu;
pub use config::{Anchor, StretchConfig, StretchParams, MAX_SHIFT, MOST_SAMPLES, STILL};
pub use cover::{cover, cover_carrying, partly_covered, sweep_at};
pub use mesh::{move_vertices, rasterise, rasterise_carrying, swept_motion, triangle_corners};
pub use texture_blur::{texture_blur, texture_blur_carrying};

/// Applies the filter: [`texture_blur`] → [`move_vertices`] → [`rasterise`] → [`cover`]. The frame must
/// hold colour, depth and velocity; the output holds colour alone. A frame in which nothing
/// moves keeps its colour untouched.
pub fn stretch(frame: Frame, params: &StretchParams, shutter: impl Into<Shutter>) -> Frame {
    stretch_with(frame, params, shutter, &Cpu)
}

/// Stretch's stages that a backend may run elsewhere: texture_blur → move_vertices →
/// rasterise → cover, as one (the GPU keeps the vertices, the drawn frame and what the
/// fragments swept on the device between them). The default is the CPU's [`stages`], the reference; [`Cpu`] takes it, and the GPU
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

    /// [`stages`] with the R, G and B planes of `layers` (light layers beside the beauty)
    /// blurred in place with the beauty's weights: on the CPU carried through the same taps
    /// and fragments ([`stages_carrying`]).
    fn stages_carrying(
        &self,
        config: &StretchConfig,
        planes: &[Vec<f32>; 4],
        z: &[f32],
        v: &[[f32; 2]],
        layers: &mut [Color],
    ) -> [Vec<f32>; 4] {
        stages_carrying(config, planes, z, v, layers)
    }
}

impl Stages for Cpu {}

/// The four stages on the CPU: the colour planes (R, G, B, A) drawn over the sharp frame.
pub fn stages(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
) -> [Vec<f32>; 4] {
    stages_carrying(config, planes, z, v, &mut [])
}

/// [`stages`], carrying the R, G and B planes of `layers` (light layers) through the same
/// work: every weight stretch gives a colour is a function of depth, motion, the beauty's
/// alpha and the vertices alone (the pre-blur's taps, each fragment's depth test,
/// barycentric weights and alpha, cover's taps), so they are found once, with the beauty's, and applied to each layer's channels
/// in the order they are applied to the beauty's. A layer comes out with the bits it would
/// get in the beauty's place (its alpha is the beauty's, which is left as it came), and the
/// triangles are chosen, sorted and walked once. The layers travel pixel-major (a pixel's
/// channels side by side), so a tap or a corner reads them from one place.
pub fn stages_carrying(
    config: &StretchConfig,
    planes: &[Vec<f32>; 4],
    z: &[f32],
    v: &[[f32; 2]],
    layers: &mut [Color],
) -> [Vec<f32>; 4] {
    let n = config.width as usize * config.height as usize;
    let channels = 3 * layers.len();
    let carried = pack(layers, n);
    // The sharp frame to draw first: pre-blurred along each pixel's motion if asked.
    let (mut out, mut carried_out) = if config.texture_blur() {
        texture_blur_carrying(config, planes, z, v, &carried, channels)
    } else {
        (planes.clone(), carried.clone())
    };
    let vertices = move_vertices(config, z, v);
    let mut swept = vec![[0.0f32; 4]; n];
    rasterise_carrying(
        config,
        planes,
        z,
        v,
        &vertices,
        &mut out,
        &mut swept,
        &carried,
        &mut carried_out,
        channels,
    );
    drop(vertices);
    cover_carrying(
        config,
        planes,
        (z, v),
        &swept,
        &mut out,
        &carried,
        &mut carried_out,
        channels,
    );
    drop(carried);
    unpack(&carried_out, layers, n);
    out
}

/// Pixels a block of [`pack`] and [`unpack`] (its carried values stay in the cache).
const BLOCK: usize = 4096;

/// The R, G and B planes of `layers` taken out and laid pixel-major: pixel i's values at
/// `i·3·layers..`, layer by layer, R, G, B.
fn pack(layers: &mut [Color], n: usize) -> Vec<f32> {
    let channels = 3 * layers.len();
    let planes: Vec<Vec<f32>> = layers
        .iter_mut()
        .flat_map(|l| [&mut l.r, &mut l.g, &mut l.b])
        .map(std::mem::take)
        .collect();
    let mut packed = vec![0.0; n * channels];
    if channels == 0 {
        return packed;
    }
    packed
        .par_chunks_mut(BLOCK * channels)
        .enumerate()
        .for_each(|(block, values)| {
            let base = block * BLOCK;
            for (c, plane) in planes.iter().enumerate() {
                for (k, pixel) in values.chunks_mut(channels).enumerate() {
                    pixel[c] = plane[base + k];
                }
            }
        });
    packed
}

/// [`pack`] undone: `packed`'s planes put back into `layers`.
fn unpack(packed: &[f32], layers: &mut [Color], n: usize) {
    let channels = 3 * layers.len();
    let mut planes: Vec<&mut Vec<f32>> = layers
        .iter_mut()
        .flat_map(|l| [&mut l.r, &mut l.g, &mut l.b])
        .collect();
    for plane in planes.iter_mut() {
        **plane = vec![0.0; n];
    }
    // Each block's piece of every plane.
    let mut blocks: Vec<Vec<&mut [f32]>> = (0..n.div_ceil(BLOCK))
        .map(|_| Vec::with_capacity(channels))
        .collect();
    for plane in planes {
        for (block, piece) in blocks.iter_mut().zip(plane.chunks_mut(BLOCK)) {
            block.push(piece);
        }
    }
    blocks
        .into_par_iter()
        .zip(packed.par_chunks(BLOCK * channels.max(1)))
        .for_each(|(pieces, values)| {
            for (c, piece) in pieces.into_iter().enumerate() {
                for (value, pixel) in piece.iter_mut().zip(values.chunks(channels)) {
                    *value = pixel[c];
                }
            }
        });
}

/// [`stretch`] with its [`Stages`] run by `stages` (the CPU's, [`Cpu`], or a backend's twin),
/// given the config, the colour planes (R, G, B, A: an opaque alpha where the frame has
/// none), depth and velocity; they return the four planes. Only frames in which something
/// moves reach them; the config is made here from the frame's size, so it always matches.
pub fn stretch_with(
    frame: Frame,
    params: &StretchParams,
    shutter: impl Into<Shutter>,
    stages: &impl Stages,
) -> Frame {
    stretch_layers_with(frame, &mut [], params, shutter, stages)
}

/// [`stretch_with`], and `layers` (light layers beside the beauty) blurred in place with
/// exactly the beauty's weights ([`Stages::stages_carrying`]); their alpha is the beauty's
/// and is left as it came. Where nothing moves they are left as they came too.
pub fn stretch_layers_with(
    mut frame: Frame,
    layers: &mut [Color],
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
    let [r, g, b, a] = if layers.is_empty() {
        stages.stages(&config, &planes, &z, &v)
    } else {
        stages.stages_carrying(&config, &planes, &z, &v, layers)
    };
    frame.color = Some(Color {
        r,
        g,
        b,
        a: has_alpha.then_some(a),
    });
    frame
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Velocity;
    use crate::numeric::close;

    /// A deterministic value in [0, 1) for (seed, i).
    fn hash(seed: u32, i: usize) -> f32 {
        let mut x = (i as u32).wrapping_mul(0x9E37_79B9) ^ seed.wrapping_mul(0x85EB_CA6B);
        x ^= x >> 15;
        x = x.wrapping_mul(0x2C1B_3C6D);
        x ^= x >> 12;
        x = x.wrapping_mul(0x297A_2D39);
        x ^= x >> 15;
        (x >> 8) as f32 / (1u32 << 24) as f32
    }

    /// A `w`×`h` frame of noise colour over blocks at two depths (silhouettes everywhere)
    /// and a third of its pixels still, the others moving up to 20 px a frame, some 500
    /// (cut to MAX_SHIFT); with a noise alpha or none.
    fn moving_frame(w: usize, h: usize, alpha: bool) -> Frame {
        let n = w * h;
        let mut f = Frame::new(w, h);
        f.color = Some(Color {
            r: (0..n).map(|i| hash(1, i)).collect(),
            g: (0..n).map(|i| 4.0 * hash(2, i) - 1.0).collect(),
            b: (0..n).map(|i| hash(3, i) * hash(4, i)).collect(),
            a: alpha.then(|| (0..n).map(|i| hash(5, i)).collect()),
        });
        f.depth = Some(
            (0..n)
                .map(|i| {
                    if (i % w / 5 + i / w / 4).is_multiple_of(3) {
                        2.0
                    } else {
                        9.0
                    }
                })
                .collect(),
        );
        let speed = |i: usize| match i % 3 {
            0 => 0.0,
            _ if i % 97 == 1 => 500.0,
            _ => 20.0,
        };
        f.velocity = Some(Velocity {
            x: (0..n).map(|i| speed(i) * (hash(6, i) - 0.5)).collect(),
            y: (0..n).map(|i| speed(i) * (hash(7, i) - 0.5)).collect(),
        });
        f
    }

    /// Light layer `k` of `f`: noise of its own, with the beauty's alpha (as process.rs
    /// builds them).
    fn layer(f: &Frame, k: u32) -> Color {
        let n = f.pixel_count();
        let noise = |c: u32| (0..n).map(|i| 3.0 * hash(10 * k + c, i) - 1.0).collect();
        Color {
            r: noise(1),
            g: noise(2),
            b: noise(3),
            a: f.color.as_ref().unwrap().a.clone(),
        }
    }

    fn bits(plane: &[f32]) -> Vec<u32> {
        plane.iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn carried_layers_get_the_bits_they_get_in_the_beautys_place() {
        // Each layer carried through the beauty's taps and fragments must come out bit for
        // bit as it does blurred alone in the beauty's place (process.rs's in_place: its
        // colour with the beauty's alpha, depth and motion), and the beauty as it does with
        // no layer: sizes of one band and one block and of several, with and without alpha,
        // one to three layers, both anchors, with and without the pre-blur.
        let default = StretchParams::default();
        let every = [
            default,
            StretchParams {
                anchor: Anchor::Rear,
                texture_blur: false,
                extent: 40.0,
                ..default
            },
            StretchParams {
                min_alpha: 0.5,
                tear: 0.0,
                ..default
            },
        ];
        for (w, h, count) in [(9, 7, 2), (67, 41, 1), (130, 70, 3), (1, 5, 2)] {
            for alpha in [false, true] {
                let f = moving_frame(w, h, alpha);
                for params in &every {
                    let what = format!("{w}x{h} alpha {alpha} {params:?}");
                    let mut layers: Vec<Color> = (0..count).map(|k| layer(&f, k)).collect();
                    let carried = stretch_layers_with(f.clone(), &mut layers, params, 0.75, &Cpu);
                    let beauty = stretch(f.clone(), params, 0.75).color.unwrap();
                    let got = carried.color.unwrap();
                    assert_eq!(bits(&got.r), bits(&beauty.r), "{what}");
                    assert_eq!(bits(&got.g), bits(&beauty.g), "{what}");
                    assert_eq!(bits(&got.b), bits(&beauty.b), "{what}");
                    assert_eq!(got.a.as_deref().map(bits), beauty.a.as_deref().map(bits));
                    for (k, carried) in (0..count).zip(&layers) {
                        let mut alone = f.clone();
                        alone.color = Some(layer(&f, k));
                        let want = stretch(alone, params, 0.75).color.unwrap();
                        // The layer moved (but where the frame is one pixel wide: no
                        // triangle, nothing to blur along): the comparison is not of a copy.
                        if w > 1 {
                            assert_ne!(bits(&want.r), bits(&layer(&f, k).r), "{what}");
                        }
                        assert_eq!(bits(&carried.r), bits(&want.r), "{what} {k}");
                        assert_eq!(bits(&carried.g), bits(&want.g), "{what} {k}");
                        assert_eq!(bits(&carried.b), bits(&want.b), "{what} {k}");
                        // Their alpha is the beauty's, as it came.
                        assert_eq!(carried.a, f.color.as_ref().unwrap().a);
                    }
                }
            }
        }
    }

    #[test]
    fn carried_layers_are_left_as_they_came_where_nothing_moves() {
        let mut f = moving_frame(20, 10, true);
        f.velocity = Some(Velocity {
            x: vec![0.1; 200],
            y: vec![0.0; 200],
        });
        let mut layers = [layer(&f, 0), layer(&f, 1)];
        let out = stretch_layers_with(f.clone(), &mut layers, &StretchParams::default(), 1.0, &Cpu);
        assert_eq!(out.color, f.color);
        assert_eq!(layers, [layer(&f, 0), layer(&f, 1)]);
    }

    #[test]
    fn packing_the_layers_and_unpacking_them_gives_them_back() {
        // Over a block of pixels and a part of one.
        let f = moving_frame(71, 60, false);
        let mut layers: Vec<Color> = (0..3).map(|k| layer(&f, k)).collect();
        let packed = pack(&mut layers, 71 * 60);
        assert!(layers.iter().all(|l| l.r.is_empty()));
        assert_eq!(packed[3 * 3 * 100 + 3 + 2], layer(&f, 1).b[100]);
        unpack(&packed, &mut layers, 71 * 60);
        let want: Vec<Color> = (0..3).map(|k| layer(&f, k)).collect();
        assert_eq!(layers, want);
    }

    #[test]
    fn the_config_is_twelve_plain_words() {
        // Uploaded as one uniform by the GPU twin: twelve 4-byte fields, no padding.
        assert_eq!(std::mem::size_of::<StretchConfig>(), 48);
        let c = StretchConfig::new(4, 3, &StretchParams::default(), 0.5);
        assert_eq!((c.zero, c._pad), (0, 0));
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
