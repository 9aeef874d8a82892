//! The 2012 paper's gather (McGuire, Hennessy, Bukowski & Osman, *A Reconstruction Filter for
//! Plausible Motion Blur*, Listing 1 and Fig. 4), for the `paper` and `dual` variants: S taps
//! along ±NeighborMax (dual: every other one along the pixel's own velocity), each weighted by
//! the paper's three cases — blurry Y in front, blurry X seen through, both blurry — with
//! `cone`, `cylinder` and `softDepthCompare`.
//!
//! In: the config, the packed [`Texel`]s, the velocity, the NeighborMax grid. Out: the colour
//! of the tiles that blur, in place. Twin: `gather` in src/gpu/motion/reconstruct.wgsl.

use super::config::{
    half_spread, ReconstructConfig, Texel, Variant, EPSILON, HALF_PIXEL, INV_LENGTH, LANES, Z,
};
use super::tiles::{blurs, gather_tiles};
use crate::frame::{Color, Velocity};
use crate::motion::tile_max::TileGrid;
use crate::numeric::unit;

/// Jitter salt of the paper and dual gather's taps.
pub const SALT_PAPER: u32 = 0x5245_434f;

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
    gather_tiles(
        config,
        neighbors.columns,
        color,
        |c, row| blurs(neighbors, c, row),
        |(c, row), x, y| {
            let i = y * width + x;
            let v = (velocity.x[i], velocity.y[i]);
            gather_pixel(config, texels, v, x, y, neighbors.get(c, row))
        },
    );
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
    let j = if config.jitters() {
        unit(config.seed, SALT_PAPER, i as u32) - 0.5
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
    let dual = config.variant() == Variant::Dual && own_length > HALF_PIXEL + EPSILON;
    // The offset exposure: a surface Y's streak is Y + V_Y·u for u ∈ [2o − 1, 2o + 1], so
    // the surfaces that reach X lie around X − 2o·N: the taps' line is moved there (τ =
    // t − 2o, in half-spreads along the line), and a tap's own reach towards X is (1 − 2o)
    // of its spread ahead of X along N (it moves away from X) and (1 + 2o) behind (it moves
    // towards X): its distance is divided by that before the cones compare it with its
    // spread, and with X's (so a tap of X's own surface, moving with it, weighs the same at
    // every distance its streak reaches, as centred). Centred (o = 0) both factors are 1:
    // the same numbers, bit for bit.
    let shift = 2.0 * config.offset;
    let ahead = 1.0 / (1.0 - shift).max(1e-6);
    let behind = 1.0 / (1.0 + shift).max(1e-6);
    // Taps four at a time, so the classification arithmetic runs on four lanes
    // (lanes past the last tap get zero weight).
    let mut tap = 0;
    while tap < taps - 1 {
        // Dead lanes get a finite dummy distance (1 px) and zero weight.
        let mut t = [1.0f32; LANES];
        let mut tap_reach = [1.0f32; LANES];
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
            t[l] = -1.0 + (index as f32 + j + 1.0) * step - shift;
            tap_reach[l] = if t[l] > 0.0 { ahead } else { behind };
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
            // (At least 1e-6 px: a tap of the offset line may fall on X, where a still
            // tap's 0·∞ would be NaN; centred taps are never that near.)
            let distance = (t[l].abs() * length[l]).max(1e-6) * tap_reach[l];
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn classification_filters_of_figure_4() {
        // Distances in units of |v|.
        assert_eq!(cone(0.0), 1.0);
        assert_eq!(cone(0.5), 0.5);
        assert_eq!(cone(1.25), 0.0);
        assert_eq!(cylinder(0.9), 1.0);
        assert!(close(cylinder(1.0), 0.5, 1e-6));
        assert_eq!(cylinder(1.1), 0.0);
        // zb = 1 in front of za = 2: 1; behind: 0; within the soft extent (0.1): between.
        assert_eq!(soft_depth_compare(2.0, 1.0, 10.0), 1.0);
        assert_eq!(soft_depth_compare(1.0, 2.0, 10.0), 0.0);
        assert!(close(soft_depth_compare(1.0, 1.05, 10.0), 0.5, 1e-5));
        // A still pixel (1/|v| = ∞) spreads nowhere, without NaN.
        assert_eq!(cone(0.3 * f32::INFINITY), 0.0);
        assert_eq!(cylinder(0.3 * f32::INFINITY), 0.0);
    }
}
