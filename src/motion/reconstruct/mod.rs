//! reconstruct — the gather filter of McGuire, Hennessy, Bukowski & Osman 2012, *A
//! Reconstruction Filter for Plausible Motion Blur* (Listing 1, Fig. 4).
//!
//! Pipeline: half-spread velocity V (clamped to [0.5, k] px) → [`crate::motion::tile_max`] →
//! [`crate::motion::neighbor_max`] → [`pack`] (texels) → [`gather`]; the 2014 variants dilate the
//! tiles instead of NeighborMax ([`crate::motion::dilate`]), and the exposure variant mattes the
//! silhouettes ([`matte`]) before its gather. Inputs: colour (RGBA, premultiplied), depth,
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

pub mod matte;

use crate::frame::{Color, Frame, Velocity};
use crate::motion::tile_max::TileGrid;
use crate::motion::Shutter;
use crate::numeric::{unit, HUGE};
use matte::Matte;

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
    /// Guertin, McGuire & Nowrouzezahrai 2014 with Jimenez 2014's changes, as Blender's EEVEE
    /// and compositor Vector Blur run it: tiles dilated along their motion ([`dilate`]), taps
    /// along both the tile's and the pixel's own vector on each side, foreground and
    /// background accumulated apart (see [`gather_pixel_2014`]).
    Stable,
    /// The 2014 filter with the box shutter's weights (ours, measured in BENCHMARKS.md): a
    /// tap reaches the centre within half a pixel of its spread (not a whole one), the tap
    /// count alone normalises (the centre holds no slot of its own), a tap counts whichever
    /// way it moves along its line (the shutter is centred: a tap moving against the line
    /// reaches the centre in the other half), and what the taps leave uncovered is filled
    /// with the centre's own surface for the share of the shutter it covers the pixel
    /// (1/(2|V|)) and the background behind it for the rest. Each tap is read between
    /// pixels and split by surface ([`split`]), by each pixel's coverage where a moving
    /// surface's edge crosses it ([`split_by_cover`], [`matte`]), and the taps along
    /// the pixel's own vector sit half a step from those along the tile's.
    Exposure,
}

impl Variant {
    /// Every choice, by the name flags and presets use.
    pub const ALL: &'static [(&'static str, Variant)] = &[
        ("paper", Variant::Paper),
        ("dual", Variant::Dual),
        ("2014", Variant::Stable),
        ("exposure", Variant::Exposure),
    ];

    /// The number the config carries.
    pub fn code(self) -> u32 {
        match self {
            Variant::Paper => 0,
            Variant::Dual => 1,
            Variant::Stable => 2,
            Variant::Exposure => 3,
        }
    }

    /// Whether this variant is the 2014 filter's (dilated tiles, split accumulation).
    pub fn is_2014(self) -> bool {
        matches!(self, Variant::Stable | Variant::Exposure)
    }
}

/// Parameters. The defaults are the exposure variant's, the lowest error of the variants on
/// every truth scene (BENCHMARKS.md); the paper's were k 20, S 15.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReconstructParams {
    /// k: the largest blur radius in pixels. paper and dual: also the tile size (paper: 20);
    /// the 2014 variants' tiles stay at 8 px and their dilation carries longer vectors.
    pub max_blur: usize,
    /// S: filter taps, odd. paper and dual: taps along the line; the 2014 variants: ⌈S/4⌉ per
    /// side of the centre along each of the tile's and the pixel's own vector (S + 1 in all
    /// when the pixel moves).
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
            max_blur: 128,
            taps: 31,
            soft_z: 0.1,
            jitter: true,
            variant: Variant::Exposure,
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
pub type Texel = [f32; 6];
const Z: usize = 4;
const INV_LENGTH: usize = 5;
/// The 2014 filters' tile size at most (px), whatever k: the dilation carries longer vectors
/// across as many tiles as they reach. Smaller tiles keep the dominant vector local: on the
/// truth scenes at k 128, S 31, tiles of 8 px err 5–13 % less than 20 px on rotor, orbit,
/// figure and gears (BENCHMARKS.md), at no cost worth measuring.
const TILE_2014: usize = 8;

/// Taps evaluated together in the gather.
const LANES: usize = 8;

/// |V|² above which a pixel blurs: (0.5 px + ε)².
pub(crate) const MOVING_SQUARED: f32 = (HALF_PIXEL + EPSILON) * (HALF_PIXEL + EPSILON);

/// Everything reconstruct's stages read besides their buffers, as plain numbers: the uniform
/// of its GPU twin, `ReconstructConfig` in src/gpu/reconstruct.wgsl (keep the two in sync; the
/// size test below guards the layout).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
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
    /// Where the exposure sits about the frame, in exposures ([`Shutter::offset`]): 0 centred,
    /// +½ opening at the frame, −½ closing at it. A surface's streak is its centred one
    /// moved by 2·offset·V along its own half-spread V.
    pub offset: f32,
    /// S: taps per pixel, odd.
    pub taps: u32,
    /// 1 / SOFT_Z_EXTENT, per scene unit.
    pub inv_soft_z: f32,
    /// 1 to jitter the taps per pixel, else 0.
    pub jitter: u32,
    /// The variant: 0 paper, 1 dual (every other tap along the pixel's own velocity), 2 the
    /// 2014 filter, 3 the 2014 filter with exposure weights ([`Variant::code`]).
    pub variant: u32,
    /// The jitter's seed: the frame number modulo 2³².
    pub seed: u32,
}

impl ReconstructConfig {
    pub fn new(
        width: usize,
        height: usize,
        params: &ReconstructParams,
        shutter: impl Into<Shutter>,
        seed: u32,
    ) -> Self {
        let shutter = shutter.into();
        let size = params.max_blur.max(1);
        ReconstructConfig {
            width: width as u32,
            height: height as u32,
            // The 2014 filter's tiles stay at most 32 px (Blender's size) whatever k: its
            // dilation carries longer vectors across as many tiles as they reach.
            tile: if params.variant.is_2014() {
                size.min(TILE_2014)
            } else {
                size
            } as u32,
            k: size as f32,
            shutter: shutter.open,
            offset: shutter.offset,
            taps: (params.taps.max(1) | 1) as u32,
            inv_soft_z: 1.0 / params.soft_z.max(1e-6),
            jitter: params.jitter as u32,
            variant: params.variant.code(),
            seed,
        }
    }
}

/// Applies the filter: [`tile_max`] (mapped to V) → [`neighbor_max`] → [`pack`] → [`gather`].
/// The frame must hold colour, depth and velocity; the output holds colour alone. A frame in
/// which nothing moves more than half a pixel keeps its colour untouched.
pub fn reconstruct(
    frame: Frame,
    params: &ReconstructParams,
    shutter: impl Into<Shutter>,
    seed: u32,
) -> Frame {
    reconstruct_with(
        frame,
        params,
        shutter,
        seed,
        &crate::motion::Cpu,
        |config, inputs, color| inputs.gather(config, color),
    )
}

/// What the gather stage reads besides the config and the colour it writes in place, as
/// [`reconstruct_with`] hands it over: [`gather`]'s arguments or [`gather_2014`]'s.
pub enum GatherInputs<'a> {
    /// paper and dual.
    Paper {
        texels: &'a [Texel],
        velocity: &'a Velocity,
        neighbors: &'a TileGrid,
    },
    /// 2014 and exposure: the dilated tiles, and the exposure variant's mattes (empty for
    /// the 2014 filter).
    Stable {
        texels: &'a [Texel2014],
        mattes: &'a [Matte],
        tiles: &'a TileGrid,
    },
}

impl GatherInputs<'_> {
    /// The CPU gather of these inputs: [`gather`] or [`gather_2014`].
    pub fn gather(&self, config: &ReconstructConfig, color: &mut Color) {
        match *self {
            GatherInputs::Paper {
                texels,
                velocity,
                neighbors,
            } => gather(config, texels, velocity, neighbors, color),
            GatherInputs::Stable {
                texels,
                mattes,
                tiles,
            } => gather_2014(config, texels, mattes, tiles, color),
        }
    }
}

/// [`reconstruct`] with the tile stages (`tile_max`, `neighbor_max`, `dilate`) run by
/// `stages` and the gather stage given by the caller: the dispatch hooks of a backend whose
/// twins run elsewhere (the GPU). `gather_stage` must write into the colour what
/// [`GatherInputs::gather`] does; it runs only when something moves.
pub fn reconstruct_with(
    mut frame: Frame,
    params: &ReconstructParams,
    shutter: impl Into<Shutter>,
    seed: u32,
    stages: &impl crate::motion::TileStages,
    gather_stage: impl FnOnce(&ReconstructConfig, GatherInputs<'_>, &mut Color),
) -> Frame {
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
    let mut tiles = stages.tile_max(&velocity.x, &velocity.y, width, height, size);
    let stable = config.variant >= Variant::Stable.code();
    for (x, y) in tiles.x.iter_mut().zip(tiles.y.iter_mut()) {
        (*x, *y) = if stable {
            spread_2014(*x, *y, &config)
        } else {
            half_spread(*x, *y, config.shutter, config.k)
        };
    }
    let moving = |v: (f32, f32)| v.0 * v.0 + v.1 * v.1 > MOVING_SQUARED;
    if width * height == 0
        || !(0..tiles.rows).any(|r| (0..tiles.columns).any(|c| moving(tiles.get(c, r))))
    {
        frame.color = Some(color);
        return frame;
    }
    // How far a streak reaches from its pixel, in half-spreads: 1 centred, up to 2 when the
    // exposure is offset (the centred streak ±V moved by 2·offset·V).
    let reach = reach_factor(&config);
    if stable {
        // An offset streak reaches (1 + 2|offset|)·|V| ahead of its surface (on one side): the
        // dilation carries the tile vectors that far when given them scaled so (its reach is
        // ⌈|M|/tile⌉ tiles each way, and scaling keeps the order of lengths it picks by), and
        // the gather gets them back at their true length. Centred, the factor is 1: nothing
        // changes, bit for bit.
        let dilated = if reach != 1.0 {
            let mut scaled = tiles.clone();
            scale_tiles(&mut scaled, reach);
            let mut dilated = stages.dilate(&scaled);
            scale_tiles(&mut dilated, 1.0 / reach);
            dilated
        } else {
            stages.dilate(&tiles)
        };
        let packed = packed_2014(&config, &dilated);
        let texels = pack_2014(&config, &color, &depth, &velocity, &dilated, &packed);
        drop(depth);
        let mattes = if config.variant == Variant::Exposure.code() {
            matte::mattes(&config, &texels, |c, row| packed.get(c, row))
        } else {
            Vec::new()
        };
        let inputs = GatherInputs::Stable {
            texels: &texels,
            mattes: &mattes,
            tiles: &dilated,
        };
        gather_stage(&config, inputs, &mut color);
    } else {
        // An offset streak reaches up to 2k, two tiles of k: NeighborMax over 5×5 tiles then
        // (the 3×3 stage twice).
        let neighbors = if reach != 1.0 {
            stages.neighbor_max(&stages.neighbor_max(&tiles))
        } else {
            stages.neighbor_max(&tiles)
        };
        let texels = pack(&config, &color, &depth, &velocity, &neighbors);
        drop(depth);
        let inputs = GatherInputs::Paper {
            texels: &texels,
            velocity: &velocity,
            neighbors: &neighbors,
        };
        gather_stage(&config, inputs, &mut color);
    }
    frame.color = Some(color);
    frame
}

/// How far a streak reaches from its pixel, in half-spreads |V|: `1 + 2·|offset|` (1 for the
/// centred shutter, 2 when it opens or closes at the frame).
#[inline]
pub fn reach_factor(config: &ReconstructConfig) -> f32 {
    1.0 + 2.0 * config.offset.abs()
}

/// Every vector of `tiles` times `factor`.
fn scale_tiles(tiles: &mut TileGrid, factor: f32) {
    for (x, y) in tiles.x.iter_mut().zip(tiles.y.iter_mut()) {
        *x *= factor;
        *y *= factor;
    }
}

/// Whether any tile within `radius` tiles of (c, r) blurs.
fn near_blur(tiles: &TileGrid, c: usize, r: usize, radius: usize) -> bool {
    (r.saturating_sub(radius)..(r + radius + 1).min(tiles.rows)).any(|rr| {
        (c.saturating_sub(radius)..(c + radius + 1).min(tiles.columns))
            .any(|cc| blurs(tiles, cc, rr))
    })
}

/// One pixel's data for the 2014 gather: premultiplied R, G, B, A, depth, the half-spread
/// vector V (clamped to k, not raised to half a pixel) and |V|.
pub type Texel2014 = [f32; 8];
const VX: usize = 5;
const VY: usize = 6;
const LENGTH: usize = 7;

/// The 2014 filter's pack: pixels within two tiles of a blurring tile (a pixel gathers when
/// a tile of its 3×3 neighbourhood blurs, since its tile lookup is jittered by up to a
/// quarter tile; its taps reach at most k = one tile further).
pub fn pack_2014(
    config: &ReconstructConfig,
    color: &Color,
    depth: &[f32],
    velocity: &Velocity,
    tiles: &TileGrid,
    packed: &TileMask,
) -> Vec<Texel2014> {
    pack_tiles(
        config,
        tiles.columns,
        [0.0; 8],
        |c, row| packed.get(c, row),
        |i| {
            let v = spread_2014(velocity.x[i], velocity.y[i], config);
            [
                color.r[i],
                color.g[i],
                color.b[i],
                color.a.as_ref().map_or(1.0, |a| a[i]),
                finite_depth(depth[i]),
                v.0,
                v.1,
                (v.0 * v.0 + v.1 * v.1).sqrt(),
            ]
        },
    )
}

/// Which tiles of a grid a stage works on.
pub struct TileMask {
    columns: usize,
    on: Vec<bool>,
}

impl TileMask {
    /// Whether tile (column, row) is on.
    #[inline]
    pub fn get(&self, column: usize, row: usize) -> bool {
        self.on[row * self.columns + column]
    }
}

/// The tiles [`pack_2014`] packs: those within `reach + 1` tiles (Chebyshev) of a blurring
/// one, where taps reach k px (up to 2k when the exposure is offset), `reach` tiles beyond
/// the tile a pixel looks up. [`near_blur`] over every tile, computed as a square dilation in
/// two passes of running counts, so its cost does not grow with the reach.
pub fn packed_2014(config: &ReconstructConfig, tiles: &TileGrid) -> TileMask {
    let reach = (config.k * reach_factor(config) / config.tile as f32).ceil() as usize + 1;
    let (columns, rows) = (tiles.columns, tiles.rows);
    // Within `reach` along one axis of a marked cell: a running count over a window.
    let dilate = |marked: &dyn Fn(usize) -> bool, n: usize| -> Vec<bool> {
        let mut prefix = vec![0u32; n + 1];
        for i in 0..n {
            prefix[i + 1] = prefix[i] + marked(i) as u32;
        }
        (0..n)
            .map(|i| prefix[(i + reach + 1).min(n)] > prefix[i.saturating_sub(reach)])
            .collect()
    };
    let mut across = vec![false; columns * rows];
    for r in 0..rows {
        let row = dilate(&|c| blurs(tiles, c, r), columns);
        across[r * columns..(r + 1) * columns].copy_from_slice(&row);
    }
    let mut on = vec![false; columns * rows];
    for c in 0..columns {
        let column = dilate(&|r| across[r * columns + c], rows);
        for (r, v) in column.into_iter().enumerate() {
            on[r * columns + c] = v;
        }
    }
    TileMask { columns, on }
}

/// The 2014 filter's half-spread: `q = ½·v·φ`, its length clamped to k (not raised to half a
/// pixel: the filter treats vectors under half a pixel as still).
#[inline]
pub fn spread_2014(vx: f32, vy: f32, config: &ReconstructConfig) -> (f32, f32) {
    let (qx, qy) = (0.5 * vx * config.shutter, 0.5 * vy * config.shutter);
    let length = (qx * qx + qy * qy).sqrt();
    if length > config.k {
        let scale = config.k / length;
        (qx * scale, qy * scale)
    } else {
        (qx, qy)
    }
}

/// The 2014 filter's gather, in place, over the tiles within one tile of a blurring one.
pub fn gather_2014(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    mattes: &[Matte],
    tiles: &TileGrid,
    color: &mut Color,
) {
    gather_tiles(
        config,
        tiles.columns,
        color,
        |c, row| near_blur(tiles, c, row, 1),
        |_, x, y| gather_pixel_2014(config, texels, mattes, tiles, x, y),
    );
}

/// How much [`split_by_cover`] steepens the coverage it reads for a still centre, about its
/// half level. A pixel's coverage by an edge ramps from 0 to 1 over one pixel as the edge
/// crosses it; read between pixel centres (bilinearly), the ramp spreads over two, so a still
/// pixel just outside a moving surface's rim counted the surface as reaching it. Measured on
/// the truth scenes (BENCHMARKS.md, "The matte"): 1.25 at still centres takes sparse from
/// 0.0171 to 0.0150 and gears from 0.0174 to 0.0160 at 320×180 (sparse 0.0128 → 0.0122 and
/// gears 0.0154 → 0.0145 at 640×360), the others within 0.7 %; 1.5 and 2, or steepening at
/// moving centres too, cost crossing up to 10 %.
pub(crate) const COVER_SLOPE: f32 = 1.25;

/// The most taps the exposure variant takes per side and direction however long the streak.
pub(crate) const MAX_TAPS_PER_SIDE: usize = 64;
/// The exposure variant's widest spacing of taps along a streak (px).
pub(crate) const TAP_SPACING: f32 = 2.0;

/// Jitter salts of the 2014 gather: the tile lookup and the taps' offset.
pub(crate) const SALT_TILE: u32 = 0x5449_4c45;
pub(crate) const SALT_TAPS: u32 = 0x5441_5053;
/// Jitter salt of the paper and dual gather's taps.
pub(crate) const SALT_PAPER: u32 = 0x5245_434f;

/// The four texels around pixel (x, y) + `offset` (clamped to the frame), each with its
/// bilinear weight: [`bilinear`] and [`split`] read a tap through this.
#[inline(always)]
fn around(
    texels: &[Texel2014],
    (width, height): (usize, usize),
    x: usize,
    y: usize,
    offset: (f32, f32),
) -> [(&Texel2014, f32); 4] {
    around_index((width, height), x, y, offset).map(|(i, w)| (&texels[i], w))
}

/// [`around`]'s pixels, as indices.
#[inline(always)]
fn around_index(
    (width, height): (usize, usize),
    x: usize,
    y: usize,
    offset: (f32, f32),
) -> [(usize, f32); 4] {
    let fx = (x as f32 + offset.0).max(0.0);
    let fy = (y as f32 + offset.1).max(0.0);
    let (x0, y0) = (fx as usize, fy as usize);
    let (wx, wy) = (fx - x0 as f32, fy - y0 as f32);
    let (x0, x1) = (x0.min(width - 1), (x0 + 1).min(width - 1));
    let (y0, y1) = (y0.min(height - 1), (y0 + 1).min(height - 1));
    [
        (y0 * width + x0, (1.0 - wx) * (1.0 - wy)),
        (y0 * width + x1, wx * (1.0 - wy)),
        (y1 * width + x0, (1.0 - wx) * wy),
        (y1 * width + x1, wx * wy),
    ]
}

/// The colour of `nearest` (the texel nearest to pixel (x, y) + `offset`, a moving one)
/// read bilinearly at that point, over the four texels around it that move or share its
/// surface (within the soft depth extent, `scale` = 1 / SOFT_Z_EXTENT), so a tap never takes
/// colour across a silhouette from a still surface. Depth and motion stay the nearest's.
#[inline(always)]
fn bilinear(
    texels: &[Texel2014],
    (width, height): (usize, usize),
    mut nearest: Texel2014,
    scale: f32,
    x: usize,
    y: usize,
    offset: (f32, f32),
) -> Texel2014 {
    let [c0, c1, c2, c3] = around(texels, (width, height), x, y, offset);
    let corners = [c0.0, c1.0, c2.0, c3.0];
    let z = nearest[Z];
    let mixes =
        |t: &Texel2014| ((t[Z] - z).abs() * scale < 1.0 || t[LENGTH] >= HALF_PIXEL) as u32 as f32;
    let w = [
        c0.1 * mixes(corners[0]),
        c1.1 * mixes(corners[1]),
        c2.1 * mixes(corners[2]),
        c3.1 * mixes(corners[3]),
    ];
    let total = w[0] + w[1] + w[2] + w[3];
    if total > 0.0 {
        let inverse = 1.0 / total;
        for ch in 0..4 {
            nearest[ch] = (w[0] * corners[0][ch]
                + w[1] * corners[1][ch]
                + w[2] * corners[2][ch]
                + w[3] * corners[3][ch])
                * inverse;
        }
    }
    nearest
}

/// The exposure variant's tap at pixel (x, y) + `offset`, read between pixels and split by
/// surface: the four texels around the point with their bilinear weights, in two parts. Part
/// A is what lies on the surface of `nearest` (the texels that share its depth within the
/// soft extent, `scale` = 1 / SOFT_Z_EXTENT, and, when it moves, any that move); part B is
/// the rest, with the depth and motion of its heaviest texel. Each part's colour is its
/// texels' colour summed with their weights (a still part's, one texel's colour times its
/// share: a still surface does not blur), so its mean is the colour over its share; the two
/// shares add up to one. The gather weighs each part as a tap of its own surface.
///
/// Why: at a silhouette the point falls partly on the moving surface and partly beside it,
/// and over the shutter a box integrates the surface's coverage of the pixel as it slides a
/// fraction of a pixel across it. Read whole, as its nearest texel's surface ([`bilinear`]
/// renormalises over that surface's texels), a tap counts the moving surface as covering
/// the point wherever the nearest texel is the surface's, and still neighbours as not
/// covered at all: the silhouette moves in whole-pixel steps, too far out in every
/// direction the motion has a component across it (the top and bottom rims of a disc
/// moving sideways, the ends of its streak). Split, the coverage ramps over the pixel
/// between the two texel centres, where the pixel-centre classification of depth and motion
/// puts the edge. On `sparse` at 320×180 (a disc of 8 px moving 7.4 px a frame) this takes
/// the default's error from 0.0255 to 0.0206, and no truth scene gets worse. Where any of
/// the four pixels has a matte, [`split_by_cover`] reads the tap instead, with the edge
/// where the pixels' colours put it.
#[inline(always)]
fn split(
    texels: &[Texel2014],
    (width, height): (usize, usize),
    nearest: &Texel2014,
    scale: f32,
    x: usize,
    y: usize,
    offset: (f32, f32),
) -> (Texel2014, f32, Texel2014, f32) {
    let corners = around(texels, (width, height), x, y, offset);
    let moves = nearest[LENGTH] >= HALF_PIXEL;
    let mut a = *nearest;
    let mut b = [0.0f32; 8];
    a[..4].fill(0.0);
    let (mut share_a, mut share_b, mut heaviest) = (0.0f32, 0.0f32, 0.0f32);
    let mut heaviest_color = [0.0f32; 4];
    for (texel, w) in corners {
        let same = (texel[Z] - nearest[Z]).abs() * scale < 1.0;
        let texel_moves = texel[LENGTH] >= HALF_PIXEL;
        let on_surface = if moves {
            same || texel_moves
        } else {
            same && !texel_moves
        };
        if on_surface {
            for ch in 0..4 {
                a[ch] += w * texel[ch];
            }
            share_a += w;
        } else {
            for ch in 0..4 {
                b[ch] += w * texel[ch];
            }
            share_b += w;
            if w > heaviest {
                heaviest = w;
                b[4..].copy_from_slice(&texel[4..]);
                heaviest_color.copy_from_slice(&texel[..4]);
            }
        }
    }
    // A still surface does not blur: its part takes one texel's colour (the nearest's, or
    // the heaviest of part B), not a mix of its neighbours'.
    if !moves {
        for ch in 0..4 {
            a[ch] = share_a * nearest[ch];
        }
    }
    if b[LENGTH] < HALF_PIXEL {
        for ch in 0..4 {
            b[ch] = share_b * heaviest_color[ch];
        }
    }
    (a, share_a, b, share_b)
}

/// The exposure variant's tap at pixel (x, y) + `offset`, split by coverage ([`matte`]):
/// each of the four pixels around the point gives its bilinear weight times its coverage α to
/// the moving surface, in that surface's colour, and the rest to the still surface behind;
/// part A is the surface of the nearest pixel (`nearest`, an index), part B the other, each
/// with the depth and motion of its heaviest contributor (a still pixel's moving partner for
/// the moving part). A still part takes one colour, as in [`split`]: the nearest's own still
/// surface, or its heaviest contributor's. Each part's colour is summed with its share, as in
/// [`split`]. `None` where the still pixels among the four lie on more than one surface (or
/// not on the nearest's, when it is still): [`split`] reads the tap then.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn split_by_cover(
    texels: &[Texel2014],
    mattes: &[Matte],
    (width, height): (usize, usize),
    nearest: usize,
    scale: f32,
    (x, y): (usize, usize),
    offset: (f32, f32),
    steepen: bool,
) -> Option<(Texel2014, f32, Texel2014, f32)> {
    if mattes.is_empty() {
        return None;
    }
    let corners = around_index((width, height), x, y, offset);
    // Away from every silhouette (no pixel of the four has a pair) coverage is the labels':
    // [`split`] reads the tap.
    if corners.iter().all(|&(j, _)| {
        let m = &mattes[j];
        m[1].to_bits() as usize == j && m[2].to_bits() as usize == j
    }) {
        return None;
    }
    let near = &texels[nearest];
    let moves = near[LENGTH] >= HALF_PIXEL;
    let mut still_z = (!moves).then_some(near[Z]);
    for (j, _) in corners {
        let t = &texels[j];
        if t[LENGTH] < HALF_PIXEL {
            match still_z {
                None => still_z = Some(t[Z]),
                Some(z) if (t[Z] - z).abs() * scale >= 1.0 => return None,
                Some(_) => {}
            }
        }
    }
    let mut moving = [0.0f32; 8];
    let mut still = [0.0f32; 8];
    let (mut share_m, mut share_s) = (0.0f32, 0.0f32);
    let (mut heavy_m, mut heavy_s) = (0.0f32, -1.0f32);
    let mut still_colour = [0.0f32; 4];
    for (j, w) in corners {
        let t = &texels[j];
        let (alpha, fg, bg) = matte::surfaces(texels, mattes, j);
        let (w_m, w_s) = (w * alpha, w * (1.0 - alpha));
        for ch in 0..3 {
            moving[ch] += w_m * fg[ch];
        }
        moving[3] += w_m * t[3];
        share_m += w_m;
        share_s += w_s;
        let t_moves = t[LENGTH] >= HALF_PIXEL;
        let fg_texel = if t_moves {
            t
        } else {
            &texels[mattes[j][1].to_bits() as usize]
        };
        let bg_texel = if t_moves {
            &texels[mattes[j][2].to_bits() as usize]
        } else {
            t
        };
        if w_m > heavy_m && fg_texel[LENGTH] >= HALF_PIXEL {
            heavy_m = w_m;
            moving[4..].copy_from_slice(&fg_texel[4..]);
        }
        if w_s > heavy_s {
            heavy_s = w_s;
            still[4..].copy_from_slice(&bg_texel[4..]);
            still_colour = [bg[0], bg[1], bg[2], bg_texel[3]];
        }
    }
    // At a still centre, the coverage read between pixels is steepened about its half level:
    // interpolated between pixel centres, coverages ramp over two pixels where an edge's
    // coverage of a pixel ramps over one (see COVER_SLOPE).
    let total = share_m + share_s;
    if steepen && share_m > 0.0 && share_s > 0.0 {
        let cover = share_m / total;
        let steeper = ((cover - 0.5) * COVER_SLOPE + 0.5).clamp(0.0, 1.0);
        let factor = steeper / cover;
        for v in moving.iter_mut().take(4) {
            *v *= factor;
        }
        share_m = steeper * total;
        share_s = (1.0 - steeper) * total;
    }
    if heavy_m == 0.0 {
        // No moving surface here after all: all of it is the still one.
        share_s += share_m;
        share_m = 0.0;
        moving = [0.0; 8];
    }
    if !moves {
        let (_, _, bg) = matte::surfaces(texels, mattes, nearest);
        still_colour = [bg[0], bg[1], bg[2], near[3]];
        still[4..].copy_from_slice(&near[4..]);
    }
    for ch in 0..4 {
        still[ch] = share_s * still_colour[ch];
    }
    Some(if moves {
        (moving, share_m, still, share_s)
    } else {
        (still, share_s, moving, share_m)
    })
}

/// The 2014 filter at pixel (x, y), as Blender's compositor runs it (Jimenez's version of
/// Guertin et al.):
///
/// - the tile's dilated vector M is looked up with the tile boundary jittered by up to a
///   quarter tile (diagonally), and replaced by the pixel's own V when that is longer;
/// - each half of the shutter is gathered apart: taps at `X + M·t` for the half before the
///   frame's time and `X − M·t` for the half after, t = (i + ξ)/K for i < K, then as many
///   along the pixel's own V when it moves;
/// - a tap counts (its direction weight) unless it moves, by more than half a pixel, against
///   the vector it was taken along; of those, its background weight is
///   `clamp(½ + s·(z_tap − z), 0, 1)·clamp(|V| − d + 1, 0, 1)` (behind the centre and within
///   the centre's own spread) and its foreground weight
///   `clamp(½ − s·(z_tap − z), 0, 1)·clamp(|V_tap| − d + 1, 0, 1)` (in front and reaching
///   the centre), d the tap's distance, s = 1 / SOFT_Z_EXTENT;
/// - the result is the sum of both accumulations over the tap count (the centre counts
///   once), plus the background's average in place of whatever weight the taps failed to
///   give: what a missing foreground leaves visible is background, not the centre pixel.
///
/// Returns premultiplied RGBA, a convex mix of taps and centre.
#[inline(always)]
fn gather_pixel_2014(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    mattes: &[Matte],
    tiles: &TileGrid,
    x: usize,
    y: usize,
) -> [f32; 4] {
    let (width, height) = (config.width as usize, config.height as usize);
    let size = config.tile as f32;
    let i = y * width + x;
    let centre = texels[i];
    let (tile_shift, offset) = if config.jitter != 0 {
        (
            (unit(config.seed, SALT_TILE, i as u32) * 2.0 - 1.0) * 0.25 * size,
            unit(config.seed, SALT_TAPS, i as u32),
        )
    } else {
        (0.0, 0.5)
    };
    let column =
        ((x as f32 + tile_shift).max(0.0) as usize / config.tile as usize).min(tiles.columns - 1);
    let row =
        ((y as f32 + tile_shift).max(0.0) as usize / config.tile as usize).min(tiles.rows - 1);
    let mut m = tiles.get(column, row);
    let mut m_length = (m.0 * m.0 + m.1 * m.1).sqrt();
    // The jittered lookup can land on a tile the dilation left still (it spreads a vector
    // along its line, not across it), beside a small moving object's corners: there the
    // pixel's own tile is looked up instead. Ours does so always; Blender's form (2014) only
    // under an offset exposure, which reaches twice as far on one side and so misses more.
    // (On an 8×8 textured square moving 10 px a frame under a 0.4 shutter, tests/offset.rs,
    // this takes the exposure variant's RMSE from 0.0174 to 0.0018 opening at the frame and
    // from 0.0085 to 0.0016 centred. On the truth scenes at 320×180 and 640×360 no region
    // RMSE rises and figure, zoom, huge and layers fall in the fifth digit.)
    let exposure = config.variant == Variant::Exposure.code();
    if (config.offset != 0.0 || exposure) && m_length < HALF_PIXEL {
        let (c, r) = (
            (x / config.tile as usize).min(tiles.columns - 1),
            (y / config.tile as usize).min(tiles.rows - 1),
        );
        m = tiles.get(c, r);
        m_length = (m.0 * m.0 + m.1 * m.1).sqrt();
    }
    let own = (centre[VX], centre[VY]);
    let own_length = centre[LENGTH];
    if m_length < own_length {
        m = own;
        m_length = own_length;
    }
    if m_length < HALF_PIXEL {
        return [centre[0], centre[1], centre[2], centre[3]];
    }
    let k = config.taps.div_ceil(4).max(1) as usize;
    // Ours takes at least one tap per TAP_SPACING px of the longer vector on each side (up to
    // MAX_TAPS_PER_SIDE), so a long streak is sampled as densely as a short one: on `huge`
    // at 640×360 this takes the error from 0.071 to 0.042 (one per pixel: 0.041).
    let k = if config.variant == Variant::Exposure.code() {
        k.max(((m_length / TAP_SPACING).ceil() as usize).min(MAX_TAPS_PER_SIDE))
    } else {
        k
    };
    let scale = config.inv_soft_z;
    // The offset exposure: a surface's streak runs over u ∈ [2o − 1, 2o + 1] half-spreads of
    // its motion, so what reaches X from ahead (along the line, moving away from X) lies
    // within (1 − 2o) of its spread and what reaches it from behind (moving towards X) within
    // (1 + 2o). Each side's taps cover that share of the line, at the same spacing (k taps
    // per spread: 2k in all whatever o), and a tap's reach towards X is its spread times the
    // share of its direction. The background's window (the centre's own spread) takes the
    // side's share too, so a tap of the centre's own surface, moving with it, weighs as much
    // at every distance its streak reaches (half foreground, half background, as centred),
    // and the background that an exposure opening at the frame uncovers behind a moving
    // edge (up to 2|V| back) is there to fill it. Centred, every factor is 1 and each side
    // takes k taps: the same numbers, bit for bit.
    let shift = 2.0 * config.offset;
    // How far past the centre's own spread a background tap still counts: a whole pixel in
    // Blender's form, half a pixel (the centre pixel's half-width) in ours, so that a still
    // pixel takes nothing from its neighbours behind it.
    let edge = if exposure { 0.5 } else { 1.0 };
    // How far past its own spread a foreground tap reaches: a whole pixel (Blender's), but
    // in ours half a pixel for a still tap, which does not spread at all.
    let reach = |length: f32| {
        if exposure && length < HALF_PIXEL {
            0.5
        } else {
            1.0
        }
    };
    let mut fg = [0.0f32; 4];
    let mut bg = [0.0f32; 4];
    let (mut w_fg, mut w_bg) = (0.0f32, 0.0f32);
    // The centre holds one slot of the count in Blender's form.
    let mut count = if exposure { 0.0f32 } else { 1.0 };
    // A still centre has no vector of its own: Blender's form gathers along the tile's alone,
    // with half the taps of a moving centre. Ours takes the second set along the tile's vector
    // too, half a step off the first, so a still pixel that a moving surface crosses samples
    // its exposure as finely as a moving one (on `sparse` at 320×180, 0.0193 → 0.0189; no
    // truth scene gets worse). The 1080p moving frame has no still centres: no time cost there.
    let directions = if exposure || own_length >= HALF_PIXEL {
        2
    } else {
        1
    };
    let centre_z = centre[Z];
    for side in [1.0f32, -1.0] {
        for d in 0..directions {
            let (dx, dy, length) = if d == 0 || own_length < HALF_PIXEL {
                (m.0, m.1, m_length)
            } else {
                (own.0, own.1, own_length)
            };
            let (sx, sy) = (side * dx, side * dy);
            // This side's share of the line: (1 − 2o) ahead, (1 + 2o) behind.
            let extent = 1.0 - shift * side;
            let k = (k as f32 * extent).ceil() as usize;
            if k == 0 {
                continue;
            }
            let step = extent / k as f32;
            // Ours offsets the taps along the pixel's own vector by half a step from those
            // along the tile's: where the two are the same vector (everywhere on a lone moving
            // object) the second set then halves the step instead of repeating the first
            // (on `sparse` at 320×180, 0.0206 → 0.0193; every truth scene gains).
            let offset = if exposure && d == 1 {
                (offset + 0.5).fract()
            } else {
                offset
            };
            // Taps eight at a time, so the weights' arithmetic runs on eight lanes (lanes
            // past the last tap are dead: zero weight, no count).
            let mut first = 0;
            while first < k {
                let mut t = [0.0f32; LANES];
                let mut live = [0.0f32; LANES];
                // Each tap as up to two surfaces (see [`split`]): `sample` with `share` of
                // the tap, `other` with the rest; colours are summed with their shares.
                let mut sample = [[0.0f32; 8]; LANES];
                let mut share = [0.0f32; LANES];
                let mut other = [[0.0f32; 8]; LANES];
                let mut other_share = [0.0f32; LANES];
                for l in 0..LANES.min(k - first) {
                    t[l] = ((first + l) as f32 + offset) * step;
                    let px = (x as f32 + 0.5 + sx * t[l]).max(0.0) as usize;
                    let py = (y as f32 + 0.5 + sy * t[l]).max(0.0) as usize;
                    let nearest_index = py.min(height - 1) * width + px.min(width - 1);
                    let nearest = texels[nearest_index];
                    let at = (sx * t[l], sy * t[l]);
                    if exposure {
                        (sample[l], share[l], other[l], other_share[l]) = split_by_cover(
                            texels,
                            mattes,
                            (width, height),
                            nearest_index,
                            scale,
                            (x, y),
                            at,
                            own_length < HALF_PIXEL,
                        )
                        .unwrap_or_else(|| {
                            split(texels, (width, height), &nearest, scale, x, y, at)
                        });
                    } else {
                        // Colour is read between pixels (bilinear, as a GPU's filtered
                        // texture read, which Blender's runs), depth and motion at the
                        // nearest: a streak of a pixel or two is then a box of its true
                        // length, not a few whole pixels (on `sparse` at 320×180 this halved
                        // the error, 0.042 → 0.021). A still surface is read at the nearest
                        // texel alone: it does not blur.
                        sample[l] = if nearest[LENGTH] >= HALF_PIXEL {
                            bilinear(texels, (width, height), nearest, scale, x, y, at)
                        } else {
                            nearest
                        };
                        share[l] = 1.0;
                    }
                    live[l] = 1.0;
                }
                // The foreground and background weights of one surface of a tap.
                // `share`: the tap's reach towards X in spreads (1 centred).
                let window = own_length * extent;
                let weights = |texel: &Texel2014, distance: f32, direction: f32, share: f32| {
                    let dz = texel[Z] - centre_z;
                    let behind = (0.5 + scale * dz).clamp(0.0, 1.0);
                    let front = (0.5 - scale * dz).clamp(0.0, 1.0);
                    (
                        direction
                            * front
                            * (texel[LENGTH] * share - distance + reach(texel[LENGTH]))
                                .clamp(0.0, 1.0),
                        direction * behind * (window - distance + edge).clamp(0.0, 1.0),
                    )
                };
                let mut f = [[0.0f32; 2]; LANES];
                let mut b = [[0.0f32; 2]; LANES];
                for l in 0..LANES {
                    let distance = length * t[l];
                    // Blender's form: the tap must move along the vector it was taken along
                    // (each half of the shutter is gathered on its own side). Ours: the
                    // shutter is centred, so a tap moving against the line reaches the centre
                    // in the other half; it counts either way.
                    let along = dx * sample[l][VX] + dy * sample[l][VY] > 0.0;
                    let counts = exposure || sample[l][LENGTH] < HALF_PIXEL || along;
                    let direction = if counts { live[l] } else { 0.0 };
                    // Moving along the line on this side, a tap moves away from X (+1).
                    let away = |texel: &Texel2014| {
                        let along = dx * texel[VX] + dy * texel[VY] > 0.0;
                        if along {
                            side
                        } else {
                            -side
                        }
                    };
                    let share = |texel: &Texel2014| 1.0 - shift * away(texel);
                    (f[l][0], b[l][0]) =
                        weights(&sample[l], distance, direction, share(&sample[l]));
                    (f[l][1], b[l][1]) = weights(&other[l], distance, direction, share(&other[l]));
                    count += direction;
                }
                for l in 0..LANES {
                    for ch in 0..4 {
                        fg[ch] += f[l][0] * sample[l][ch] + f[l][1] * other[l][ch];
                        bg[ch] += b[l][0] * sample[l][ch] + b[l][1] * other[l][ch];
                    }
                    w_fg += f[l][0] * share[l] + f[l][1] * other_share[l];
                    w_bg += b[l][0] * share[l] + b[l][1] * other_share[l];
                }
                first += LANES;
            }
        }
    }
    let mut out = [0.0f32; 4];
    if exposure {
        // What the taps leave uncovered shows the centre's own surface for the share of the
        // shutter it spends over the pixel, 1/(2|V|), and what lies behind it (the
        // background taps) for the rest; with no tap behind, the centre alone.
        let cover = (0.5 / own_length).min(1.0);

        let missing = if count > 0.0 {
            (1.0 - (w_fg + w_bg) / count).clamp(0.0, 1.0)
        } else {
            1.0
        };
        let inverse = if count > 0.0 { 1.0 / count } else { 0.0 };
        // A still centre's own surface is its colour less the moving surface's fringe in it
        // (the matte's; the taps bring the moving surface back for as long as it covers).
        let mut own_colour = [centre[0], centre[1], centre[2], centre[3]];
        if own_length < HALF_PIXEL && !mattes.is_empty() {
            let (_, _, still) = matte::surfaces(texels, mattes, i);
            own_colour[..3].copy_from_slice(&still);
        }
        for ch in 0..4 {
            let background = if w_bg > 0.0 {
                cover * own_colour[ch] + (1.0 - cover) * bg[ch] / w_bg
            } else {
                own_colour[ch]
            };
            out[ch] = (fg[ch] + bg[ch]) * inverse + background * missing;
        }
        return out;
    }
    // Blender's own addition: a little of the centre in the background, so that its
    // average exists when no tap is behind.
    let w = 1.0 / (50.0 * (4 * k) as f32);
    let w_bg = w_bg + w;
    let missing = (1.0 - (w_fg + w_bg) / count).clamp(0.0, 1.0);
    for ch in 0..4 {
        let background = (bg[ch] + w * centre[ch]) / w_bg;
        out[ch] = (fg[ch] + bg[ch] + w * centre[ch]) / count + background * missing;
    }
    out
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
    pack_tiles(
        config,
        neighbors.columns,
        [0.0; 6],
        |c, row| near_blur(neighbors, c, row, reach_factor(config).ceil() as usize),
        |i| {
            let length = spread_length(velocity.x[i], velocity.y[i], config.shutter, config.k);
            [
                color.r[i],
                color.g[i],
                color.b[i],
                color.a.as_ref().map_or(1.0, |a| a[i]),
                finite_depth(depth[i]),
                // 1/|V|: infinite for a still pixel, whose cones and cylinders are then 0 at
                // any distance (it spreads nowhere).
                1.0 / length,
            ]
        },
    )
}

/// The texel `texel(i)` of every pixel of the tiles `selected(column, row)` picks, in a
/// buffer of `zero`s elsewhere; zero-allocated, so untouched pages cost nothing.
fn pack_tiles<T: Copy + Send + Sync>(
    config: &ReconstructConfig,
    columns: usize,
    zero: T,
    selected: impl Fn(usize, usize) -> bool + Sync,
    texel: impl Fn(usize) -> T + Sync,
) -> Vec<T> {
    let width = config.width as usize;
    let size = config.tile as usize;
    let mut texels = vec![zero; width * config.height as usize];
    texels
        .par_chunks_mut(size * width)
        .enumerate()
        .for_each(|(row, chunk)| {
            for c in (0..columns).filter(|&c| selected(c, row)) {
                for local_y in 0..chunk.len() / width {
                    let y = row * size + local_y;
                    for x in c * size..((c + 1) * size).min(width) {
                        chunk[local_y * width + x] = texel(y * width + x);
                    }
                }
            }
        });
    texels
}

/// Runs `pixel((column, row), x, y)` over every pixel of the tiles `selected(column, row)`
/// picks, a band of tile rows per task, and writes its premultiplied RGBA in place; other
/// pixels keep their colour.
fn gather_tiles(
    config: &ReconstructConfig,
    columns: usize,
    color: &mut Color,
    selected: impl Fn(usize, usize) -> bool + Sync,
    pixel: impl Fn((usize, usize), usize, usize) -> [f32; 4] + Sync,
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
            for c in (0..columns).filter(|&c| selected(c, row)) {
                for local_y in 0..r.len() / width {
                    let y = row * size + local_y;
                    for x in c * size..((c + 1) * size).min(width) {
                        let o = local_y * width + x;
                        [r[o], g[o], b[o], a[o]] = pixel((c, row), x, y);
                    }
                }
            }
        });
    color.a = has_alpha.then_some(alpha);
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
    let j = if config.jitter != 0 {
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
    let dual = config.variant == Variant::Dual.code() && own_length > HALF_PIXEL + EPSILON;
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
    fn the_config_is_eleven_plain_words() {
        // Uploaded as one uniform by the GPU twin: eleven 4-byte fields, no padding.
        assert_eq!(std::mem::size_of::<ReconstructConfig>(), 44);
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
