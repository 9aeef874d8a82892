//! reconstruct — the gather filter of McGuire, Hennessy, Bukowski & Osman 2012, *A
//! Reconstruction Filter for Plausible Motion Blur* (Listing 1, Fig. 4).
//!
//! Pipeline: half-spread velocity V (clamped to [0.5, k] px) → [`super::tile_max`] →
//! [`super::neighbor_max`] → [`pack`] (texels) → [`gather`]. Inputs: colour (RGBA, premultiplied), depth,
//! velocity; prev/next are never read. Each output pixel is a weighted average of input
//! colours with non-negative weights (the centre's weight is at least 1/k), so it lies in the
//! per-channel range of the inputs and a uniform colour stays uniform.
//!
//! Conventions: positive depth, so "Y in front of X" is `Z[Y] < Z[X]` (the paper's z is
//! negative camera-space z). Shutter φ: the half-spread is `q = ½·v·φ`.
//!
//! Numerics the paper leaves open, handled here (see the constants):
//! - a pixel with zero velocity inside a moving neighbourhood: its own weight `1/|V|` uses
//!   `max(|V|, 0.5 px)` (the paper's clamp), while its cones and cylinders use the true
//!   |V| = 0 and so vanish at any distance: it stays sharp unless something in front blurs
//!   over it (1/0 is +∞ there, and every distance is positive, so no NaN arises);
//! - velocities far above k are clamped to k (direction kept; the numeric policy bounds the
//!   inputs by [`VELOCITY_LIMIT`](crate::numeric::VELOCITY_LIMIT) first, so |q|² cannot overflow);
//! - inputs obey the numeric policy ([`crate::numeric`]: finite colour and velocity, depth
//!   in [0, +∞]); far depth (+∞) is packed as [`HUGE`] so depth differences stay finite —
//!   output is always finite;
//! - taps outside the image are clamped to the border; tiles at the right and bottom edges
//!   may be partial.
//!
//! Skips: when no pixel's V exceeds half a pixel the frame is returned as it came (no copy);
//! pixels whose tile NeighborMax is below half a pixel keep their input colour.

use rayon::prelude::*;

use super::neighbor_max::neighbor_max;
use super::tile_max::{tile_max, TileGrid};
use crate::frame::{Color, Frame, Velocity};
use crate::numeric::{unit, HUGE};

/// Half a pixel: velocities at or below it do not blur (the paper's 0.5 px).
pub const HALF_PIXEL: f32 = 0.5;
/// The paper's ε: guards `|q| + ε` and the early-out test.
pub const EPSILON: f32 = 0.01;

/// Which taps the gather takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    /// Listing 1: every tap along ±NeighborMax.
    Paper,
    /// Every other tap along the pixel's own velocity instead (McGuire's later G3D code and
    /// Jimenez 2014 sample both directions), so a pixel moving across its neighbourhood's
    /// dominant motion still blurs along its own.
    Dual,
}

impl Variant {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, Variant)] =
        &[("paper", Variant::Paper), ("dual", Variant::Dual)];
}

/// Parameters, with the paper's defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReconstructParams {
    /// k: the largest blur radius in pixels, also the tile size. Paper: 20.
    pub max_blur: usize,
    /// S: filter taps, odd. Paper: 15.
    pub taps: usize,
    /// SOFT_Z_EXTENT in scene units (the paper used 1 mm to 10 cm).
    pub soft_z: f32,
    /// Jitter the taps per pixel (a hash of frame and pixel) to trade ghosting for noise.
    pub jitter: bool,
    pub variant: Variant,
}

impl Default for ReconstructParams {
    fn default() -> Self {
        ReconstructParams {
            max_blur: 20,
            taps: 15,
            soft_z: 0.1,
            jitter: true,
            variant: Variant::Paper,
        }
    }
}

/// Far depth (+∞ under the numeric policy) as a finite number, so that the soft depth
/// comparison's differences stay finite.
fn finite_depth(z: f32) -> f32 {
    z.min(HUGE)
}

/// The clamped half-spread velocity of the paper: `V = q·max(0.5, min(|q|, k)) / (|q| + ε)`
/// with `q = ½·v·φ`.
pub fn half_spread(vx: f32, vy: f32, shutter: f32, k: f32) -> (f32, f32) {
    let (qx, qy) = (0.5 * vx * shutter, 0.5 * vy * shutter);
    let length = (qx * qx + qy * qy).sqrt();
    if length == 0.0 {
        return (0.0, 0.0);
    }
    let scale = HALF_PIXEL.max(length.min(k)) / (length + EPSILON);
    (qx * scale, qy * scale)
}

/// |V| of [`half_spread`] without forming V.
#[inline]
fn spread_length(vx: f32, vy: f32, shutter: f32, k: f32) -> f32 {
    let (qx, qy) = (0.5 * vx * shutter, 0.5 * vy * shutter);
    let length = (qx * qx + qy * qy).sqrt();
    if length == 0.0 {
        return 0.0;
    }
    HALF_PIXEL.max(length.min(k)) * length / (length + EPSILON)
}

/// `cone(X, Y, v) = clamp(1 − |X − Y| / |v|, 0, 1)`: is X within Y's point-spread function?
/// Takes the distance already divided by |v| (the gather keeps 1/|v| per pixel).
#[inline]
fn cone(scaled_distance: f32) -> f32 {
    (1.0 - scaled_distance).clamp(0.0, 1.0)
}

/// `cylinder(X, Y, v) = 1 − smoothstep(0.95|v|, 1.05|v|, |X − Y|)`, with the distance
/// already divided by |v|.
#[inline]
fn cylinder(scaled_distance: f32) -> f32 {
    let t = ((scaled_distance - 0.95) * 10.0).clamp(0.0, 1.0);
    1.0 - t * t * (3.0 - 2.0 * t)
}

/// `softDepthCompare(za, zb)` for positive depth: 1 when zb is in front of za; takes
/// 1 / SOFT_Z_EXTENT.
#[inline]
fn soft_depth_compare(za: f32, zb: f32, inverse_extent: f32) -> f32 {
    (1.0 - (zb - za) * inverse_extent).clamp(0.0, 1.0)
}

/// One pixel's data for the gather, packed so a tap reads one cache line:
/// premultiplied R, G, B, A, depth, and 1 / |V| (infinite where still).
type Texel = [f32; 6];
const Z: usize = 4;
const INV_LENGTH: usize = 5;
/// Taps evaluated together in the gather.
const LANES: usize = 8;

/// |V|² above which a pixel blurs: (0.5 px + ε)².
const MOVING_SQUARED: f32 = (HALF_PIXEL + EPSILON) * (HALF_PIXEL + EPSILON);

/// Everything reconstruct's stages read besides their buffers, as plain numbers: the shape of
/// the uniform its GPU twin will take (keep the two in sync).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct ReconstructConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// k: the tile size, pixels (the paper's tiles are k×k).
    pub tile: u32,
    /// k as the largest half-spread, pixels.
    pub k: f32,
    /// Fraction of the frame interval the shutter is open.
    pub shutter: f32,
    /// S: taps per pixel, odd.
    pub taps: u32,
    /// 1 / SOFT_Z_EXTENT, per scene unit.
    pub inv_soft_z: f32,
    /// 1 to jitter the taps per pixel, else 0.
    pub jitter: u32,
    /// 1 for the dual variant (every other tap along the pixel's own velocity), else 0.
    pub dual: u32,
    /// The jitter's seed: the frame number modulo 2³².
    pub seed: u32,
}

impl ReconstructConfig {
    pub fn new(
        width: usize,
        height: usize,
        params: &ReconstructParams,
        shutter: f32,
        seed: u32,
    ) -> Self {
        let size = params.max_blur.max(1);
        ReconstructConfig {
            width: width as u32,
            height: height as u32,
            tile: size as u32,
            k: size as f32,
            shutter,
            taps: (params.taps.max(1) | 1) as u32,
            inv_soft_z: 1.0 / params.soft_z.max(1e-6),
            jitter: params.jitter as u32,
            dual: (params.variant == Variant::Dual) as u32,
            seed,
        }
    }
}

/// Applies the filter: [`tile_max`] (mapped to V) → [`neighbor_max`] → [`pack`] → [`gather`].
/// The frame must hold colour, depth and velocity; the output holds colour alone. A frame in
/// which nothing moves more than half a pixel keeps its colour untouched.
pub fn reconstruct(mut frame: Frame, params: &ReconstructParams, shutter: f32, seed: u32) -> Frame {
    let (width, height) = (frame.width, frame.height);
    let (Some(mut color), Some(depth), Some(velocity)) = (
        frame.color.take(),
        frame.depth.take(),
        frame.velocity.take(),
    ) else {
        return frame;
    };
    frame.prev = None;
    frame.next = None;
    let config = ReconstructConfig::new(width, height, params, shutter, seed);
    let size = config.tile as usize;

    // TileMax of the input velocity, then V of each tile's dominant vector: V is monotonic
    // in |v|, so this equals TileMax of V without storing a full-size V plane.
    let mut tiles = tile_max(&velocity.x, &velocity.y, width, height, size);
    for (x, y) in tiles.x.iter_mut().zip(tiles.y.iter_mut()) {
        (*x, *y) = half_spread(*x, *y, config.shutter, config.k);
    }
    let moving = |v: (f32, f32)| v.0 * v.0 + v.1 * v.1 > MOVING_SQUARED;
    if width * height == 0
        || !(0..tiles.rows).any(|r| (0..tiles.columns).any(|c| moving(tiles.get(c, r))))
    {
        frame.color = Some(color);
        return frame;
    }
    let neighbors = neighbor_max(&tiles);
    let texels = pack(&config, &color, &depth, &velocity, &neighbors);
    drop(depth);
    gather(&config, &texels, &velocity, &neighbors, &mut color);
    frame.color = Some(color);
    frame
}

/// Whether a tile's NeighborMax blurs: |V|² above (0.5 px + ε)².
#[inline]
fn blurs(neighbors: &TileGrid, c: usize, r: usize) -> bool {
    let (x, y) = neighbors.get(c, r);
    x * x + y * y > MOVING_SQUARED
}

/// Stage 3: each pixel of the tiles that blur and their neighbours (taps reach at most k px,
/// one tile) packed as a [`Texel`]: colour, depth made finite, and 1/|V|. The buffer is
/// zero-allocated, so untouched pages cost nothing.
pub fn pack(
    config: &ReconstructConfig,
    color: &Color,
    depth: &[f32],
    velocity: &Velocity,
    neighbors: &TileGrid,
) -> Vec<Texel> {
    let (width, height) = (config.width as usize, config.height as usize);
    let size = config.tile as usize;
    let columns = neighbors.columns;
    let n = width * height;
    let needed = |c: usize, r: usize| {
        (r.saturating_sub(1)..(r + 2).min(neighbors.rows)).any(|rr| {
            (c.saturating_sub(1)..(c + 2).min(columns)).any(|cc| blurs(neighbors, cc, rr))
        })
    };
    let mut texels: Vec<Texel> = vec![[0.0; 6]; n];
    texels
        .par_chunks_mut(size * width)
        .enumerate()
        .for_each(|(row, chunk)| {
            for c in (0..columns).filter(|&c| needed(c, row)) {
                for local_y in 0..chunk.len() / width {
                    let y = row * size + local_y;
                    for x in c * size..((c + 1) * size).min(width) {
                        let i = y * width + x;
                        let length =
                            spread_length(velocity.x[i], velocity.y[i], config.shutter, config.k);
                        chunk[local_y * width + x] = [
                            color.r[i],
                            color.g[i],
                            color.b[i],
                            color.a.as_ref().map_or(1.0, |a| a[i]),
                            finite_depth(depth[i]),
                            // 1/|V|: infinite for a still pixel, whose cones and
                            // cylinders are then 0 at any distance (it spreads nowhere).
                            1.0 / length,
                        ];
                    }
                }
            }
        });
    texels
}

/// Stage 4: the gather, in place: pixels of blurring tiles get their filtered colour, the
/// others keep theirs.
pub fn gather(
    config: &ReconstructConfig,
    texels: &[Texel],
    velocity: &Velocity,
    neighbors: &TileGrid,
    color: &mut Color,
) {
    let width = config.width as usize;
    let size = config.tile as usize;
    let n = width * config.height as usize;
    let has_alpha = color.a.is_some();
    let mut alpha = color.a.take().unwrap_or_else(|| vec![0.0; n]);
    let band = size * width;
    color
        .r
        .par_chunks_mut(band)
        .zip(color.g.par_chunks_mut(band))
        .zip(color.b.par_chunks_mut(band))
        .zip(alpha.par_chunks_mut(band))
        .enumerate()
        .for_each(|(row, (((r, g), b), a))| {
            for c in 0..neighbors.columns {
                if !blurs(neighbors, c, row) {
                    continue;
                }
                let dominant = neighbors.get(c, row);
                for local_y in 0..r.len() / width {
                    let y = row * size + local_y;
                    for x in c * size..((c + 1) * size).min(width) {
                        let o = local_y * width + x;
                        let i = y * width + x;
                        let [cr, cg, cb, ca] = gather_pixel(
                            config,
                            texels,
                            (velocity.x[i], velocity.y[i]),
                            x,
                            y,
                            dominant,
                        );
                        r[o] = cr;
                        g[o] = cg;
                        b[o] = cb;
                        a[o] = ca;
                    }
                }
            }
        });
    color.a = has_alpha.then_some(alpha);
}

/// The gather of pixel (x, y) with velocity (vx, vy) along its tile's NeighborMax (nx, ny):
/// S taps weighted by the paper's three cases; returns premultiplied RGBA.
#[inline(always)]
fn gather_pixel(
    config: &ReconstructConfig,
    texels: &[Texel],
    (vx, vy): (f32, f32),
    x: usize,
    y: usize,
    (nx, ny): (f32, f32),
) -> [f32; 4] {
    let (width, height) = (config.width as usize, config.height as usize);
    let taps = config.taps as usize;
    let centre_tap = (taps - 1) / 2;
    let inv_soft_z = config.inv_soft_z;
    let i = y * width + x;
    let centre = texels[i];
    let n_length = (nx * nx + ny * ny).sqrt();
    let own = half_spread(vx, vy, config.shutter, config.k);
    let own_length = (own.0 * own.0 + own.1 * own.1).sqrt();
    let j = if config.jitter != 0 {
        unit(config.seed, 0x5245_434f, i as u32) - 0.5
    } else {
        0.0
    };
    // The average is accumulated as the centre colour plus weighted differences from
    // it: the same value, but a uniform neighbourhood gives back its colour exactly and
    // HDR values lose no precision to cancellation.
    // The paper's centre weight 1/|V[X]|, with |V| at least half a pixel as its clamp of
    // V intends, so a still pixel does not get an infinite weight.
    let mut weight = centre[INV_LENGTH].min(1.0 / HALF_PIXEL);
    let mut sum = [0.0f32; 4];
    let step = 2.0 / (config.taps as f32 + 1.0);
    let dual = config.dual != 0 && own_length > HALF_PIXEL + EPSILON;
    // Taps four at a time, so the classification arithmetic runs on four lanes
    // (lanes past the last tap get zero weight).
    let mut tap = 0;
    while tap < taps - 1 {
        // Dead lanes get a finite dummy distance (1 px) and zero weight.
        let mut t = [1.0f32; LANES];
        let mut length = [1.0f32; LANES];
        let mut live = [0.0f32; LANES];
        let mut sample = [centre; LANES];
        for l in 0..LANES {
            let mut index = tap + l;
            if index >= centre_tap {
                index += 1; // skip the centre tap
            }
            if index >= taps {
                continue;
            }
            t[l] = -1.0 + (index as f32 + j + 1.0) * step;
            let (dx, dy, len) = if dual && index % 2 == 1 {
                (own.0, own.1, own_length)
            } else {
                (nx, ny, n_length)
            };
            // Clamped at 0 first, so truncation is floor (and needs no libm call).
            let px = (x as f32 + 0.5 + dx * t[l]).max(0.0) as usize;
            let py = (y as f32 + 0.5 + dy * t[l]).max(0.0) as usize;
            sample[l] = texels[py.min(height - 1) * width + px.min(width - 1)];
            length[l] = len;
            live[l] = 1.0;
        }
        let mut alpha = [0.0f32; LANES];
        for l in 0..LANES {
            let distance = t[l].abs() * length[l];
            let z = sample[l][Z];
            let front = soft_depth_compare(centre[Z], z, inv_soft_z);
            let back = soft_depth_compare(z, centre[Z], inv_soft_z);
            let ds = distance * sample[l][INV_LENGTH];
            let dc = distance * centre[INV_LENGTH];
            alpha[l] =
                live[l] * (front * cone(ds) + back * cone(dc) + cylinder(ds) * cylinder(dc) * 2.0);
        }
        for l in 0..LANES {
            weight += alpha[l];
            for c in 0..4 {
                sum[c] += alpha[l] * (sample[l][c] - centre[c]);
            }
        }
        tap += LANES;
    }
    let inverse = 1.0 / weight;
    [
        centre[0] + sum[0] * inverse,
        centre[1] + sum[1] * inverse,
        centre[2] + sum[2] * inverse,
        centre[3] + sum[3] * inverse,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn half_spread_clamps_between_half_a_pixel_and_k() {
        // v = 10 px, φ = 0.5: q = 2.5 px, kept (up to ε).
        let (x, y) = half_spread(10.0, 0.0, 0.5, 20.0);
        assert!((x - 2.5 * 2.5 / 2.51).abs() < 1e-6 && y == 0.0);
        // Far above k: length k·|q|/(|q|+ε) ≈ k, direction kept.
        let (x, y) = half_spread(0.0, -1e6, 1.0, 20.0);
        assert!(x == 0.0 && (y + 20.0).abs() < 1e-3);
        // Tiny motion grows to half a pixel; none stays none.
        let (x, _) = half_spread(0.1, 0.0, 0.5, 20.0);
        assert!((x - 0.5 * 0.025 / 0.035).abs() < 1e-6);
        assert_eq!(half_spread(0.0, 0.0, 0.5, 20.0), (0.0, 0.0));
        // Through the numeric policy, NaN is still and infinity is clamped to k.
        let v = crate::numeric::velocity;
        assert_eq!(half_spread(v(f32::NAN), 0.0, 0.5, 20.0), (0.0, 0.0));
        let (x, _) = half_spread(v(f32::INFINITY), 0.0, 0.5, 20.0);
        assert!((x - 20.0).abs() < 1e-3);
    }

    #[test]
    fn the_config_is_ten_plain_words() {
        // Uploaded as one uniform by the GPU twin: ten 4-byte fields, no padding.
        assert_eq!(std::mem::size_of::<ReconstructConfig>(), 40);
        let even = ReconstructParams {
            taps: 14,
            ..ReconstructParams::default()
        };
        // S is made odd (the centre tap is the pixel itself).
        assert_eq!(ReconstructConfig::new(8, 8, &even, 0.5, 1).taps, 15);
    }

    #[test]
    fn classification_filters_of_figure_4() {
        // Distances in units of |v|.
        assert_eq!(cone(0.0), 1.0);
        assert_eq!(cone(0.5), 0.5);
        assert_eq!(cone(1.25), 0.0);
        assert_eq!(cylinder(0.9), 1.0);
        assert!((cylinder(1.0) - 0.5).abs() < 1e-6);
        assert_eq!(cylinder(1.1), 0.0);
        // zb = 1 in front of za = 2: 1; behind: 0; within the soft extent (0.1): between.
        assert_eq!(soft_depth_compare(2.0, 1.0, 10.0), 1.0);
        assert_eq!(soft_depth_compare(1.0, 2.0, 10.0), 0.0);
        assert!((soft_depth_compare(1.0, 1.05, 10.0) - 0.5).abs() < 1e-5);
        // A still pixel (1/|v| = ∞) spreads nowhere, without NaN.
        assert_eq!(cone(0.3 * f32::INFINITY), 0.0);
        assert_eq!(cylinder(0.3 * f32::INFINITY), 0.0);
    }
}
