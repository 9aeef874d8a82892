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
//!
//! The files, in the order a frame meets them:
//! - [`config`]: the parameters, the variants, the config every stage reads (the GPU
//!   twin's uniform), the half-spread and the texel layouts;
//! - `crate::motion::{tile_max, neighbor_max, dilate}`: the tile stages, shared with no other
//!   pass but kept beside their twins' names;
//! - [`tiles`]: which tiles each later stage works on, and the loop over them;
//! - [`pack`]: each pixel's texel, for the tiles that blur;
//! - [`matte`]: the exposure variant's coverage at silhouettes;
//! - [`classify`]: which form of the gather each tile takes (the full one, its plain copy,
//!   or the uniform tiles' box, [`uniform`]);
//! - [`gather_2014`]: the 2014 filter's gather, in both its forms (Blender's and ours, told
//!   apart by the numbers of [`config::Form`]), of the beauty and any light layers carried
//!   beside it; [`taps`]: how it reads a tap between pixels;
//! - [`gather_2012`]: the 2012 paper's gather (paper and dual).
//!
//! This file holds the pass: [`reconstruct`], and [`reconstruct_with`] with the stages a
//! backend may run elsewhere ([`Stages`]: the tile stages, the classification and the
//! gather; the GPU's twins are `crate::gpu::motion`).

pub mod classify;
pub mod config;
pub mod gather_2012;
pub mod gather_2014;
pub mod matte;
pub mod pack;
pub mod taps;
pub mod tiles;
pub mod uniform;
pub mod unmix;
mod window;

pub use config::{
    half_spread, reach_factor, spread_2014, Form, ReconstructConfig, ReconstructParams, Texel,
    Texel2014, Variant, EPSILON, HALF_PIXEL,
};
pub use gather_2012::gather;
pub use gather_2014::gather_2014;
pub use pack::{pack, pack_2014};
pub use tiles::{packed_2014, TileMask};

use crate::frame::{Color, Frame, Velocity};
use crate::motion::shutter::Shutter;
use crate::motion::tile_max::{self, TileGrid};
use crate::motion::{dilate, neighbor_max};
use crate::stages::Cpu;
use classify::TileKind;
use config::MOVING_SQUARED;
use matte::Matte;

/// Applies the filter: [`tile_max`] (mapped to V) → [`neighbor_max`] → [`pack`] → [`gather`].
/// The frame must hold colour, depth and velocity; the output holds colour alone. A frame in
/// which nothing moves more than half a pixel keeps its colour untouched.
pub fn reconstruct(
    frame: Frame,
    params: &ReconstructParams,
    shutter: impl Into<Shutter>,
    seed: u32,
) -> Frame {
    reconstruct_with(frame, params, shutter, seed, &Cpu)
}

/// Reconstruct's stages that a backend may run elsewhere: the tile stages (`tile_max`, then
/// `neighbor_max` for paper and dual or `dilate` for the 2014 variants), the 2014 variants'
/// classification of the tiles (`classify`) and the gather. Each
/// default method is the CPU stage, the reference; [`Cpu`] takes them all, and the GPU
/// (`crate::gpu::motion`) overrides each with its twin, which must return what the CPU stage
/// returns within the tolerance its parity test states (tests/gpu.rs,
/// tests/gpu_reconstruct.rs). The pack and the matte run on the CPU for every backend.
pub trait Stages {
    /// [`tile_max::tile_max`].
    fn tile_max(
        &self,
        vx: &[f32],
        vy: &[f32],
        width: usize,
        height: usize,
        size: usize,
    ) -> TileGrid {
        tile_max::tile_max(vx, vy, width, height, size)
    }

    /// [`neighbor_max::neighbor_max`].
    fn neighbor_max(&self, tiles: &TileGrid) -> TileGrid {
        neighbor_max::neighbor_max(tiles)
    }

    /// [`dilate::dilate`].
    fn dilate(&self, tiles: &TileGrid) -> TileGrid {
        dilate::dilate(tiles)
    }

    /// [`classify::classify`]: each dilated tile's [`TileKind`], once a frame, for the 2014
    /// gather of the beauty and of every colour carried beside it.
    fn classify(
        &self,
        config: &ReconstructConfig,
        texels: &[Texel2014],
        mattes: &[Matte],
        tiles: &TileGrid,
    ) -> Vec<TileKind> {
        classify::classify(config, texels, mattes, tiles)
    }

    /// The gather, in place: [`GatherInputs::gather`] ([`gather`] or [`gather_2014`]). Runs
    /// only when something moves.
    fn gather(&self, config: &ReconstructConfig, inputs: GatherInputs<'_>, color: &mut Color) {
        inputs.gather(config, color)
    }

    /// The 2014 gather of the beauty and light layers beside it (`colours`, the beauty
    /// first), each in place with the beauty's weights: on the CPU, computed once for up to
    /// eight colours at a time ([`gather_2014::gather_2014_carrying`]). `texels` are the
    /// beauty's, packed on `packed`; `kinds` the tiles' ([`Stages::classify`]).
    fn gather_2014_carrying(
        &self,
        config: &ReconstructConfig,
        (texels, mattes, tiles, kinds): (&[Texel2014], &[Matte], &TileGrid, &[TileKind]),
        packed: &TileMask,
        colours: &mut [&mut Color],
    ) {
        gather_2014::gather_2014_carrying(config, texels, mattes, (tiles, kinds), packed, colours)
    }
}

impl Stages for Cpu {}

/// What the gather stage reads besides the config and the colour it writes in place, as
/// [`reconstruct_with`] hands it over: [`gather`]'s arguments or [`gather_2014`]'s.
pub enum GatherInputs<'a> {
    /// paper and dual.
    Paper {
        texels: &'a [Texel],
        velocity: &'a Velocity,
        neighbors: &'a TileGrid,
    },
    /// 2014 and exposure: the dilated tiles and their kinds ([`Stages::classify`]), and the
    /// exposure variant's mattes (empty for the 2014 filter).
    Stable {
        texels: &'a [Texel2014],
        mattes: &'a [Matte],
        tiles: &'a TileGrid,
        kinds: &'a [TileKind],
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
                kinds,
            } => gather_2014(config, texels, mattes, (tiles, kinds), color),
        }
    }
}

/// [`reconstruct`] with its [`Stages`] run by `stages` (the CPU's, [`Cpu`], or a backend's
/// twins); the config is made here from the frame's size, so it always matches the frame.
pub fn reconstruct_with(
    frame: Frame,
    params: &ReconstructParams,
    shutter: impl Into<Shutter>,
    seed: u32,
    stages: &impl Stages,
) -> Frame {
    reconstruct_layers_with(frame, &mut [], params, shutter, seed, stages)
}

/// [`reconstruct_with`], and `layers` (light layers beside the beauty, each with the
/// beauty's alpha) blurred in place with exactly the beauty's weights: the tiles and the
/// exposure variant's mattes, the only numbers that depend on colour, are made once from
/// the beauty. The 2014 variants then gather the layers with the beauty, up to eight
/// colours a pass ([`Stages::gather_2014_carrying`]); paper and dual gather each layer in
/// the beauty's place.
pub fn reconstruct_layers_with(
    mut frame: Frame,
    layers: &mut [Color],
    params: &ReconstructParams,
    shutter: impl Into<Shutter>,
    seed: u32,
    stages: &impl Stages,
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
    let stable = config.variant().is_2014();
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
    // Which colours are opaque (every alpha 1): they come back exactly opaque ([`opaque`]).
    let opaque: Vec<bool> = std::iter::once(&color)
        .chain(layers.iter())
        .map(is_opaque)
        .collect();
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
        let mattes = if config.variant() == Variant::Exposure {
            matte::mattes(&config, &texels, |c, row| packed.get(c, row))
        } else {
            Vec::new()
        };
        drop(depth);
        let kinds = stages.classify(&config, &texels, &mattes, &dilated);
        if layers.is_empty() {
            let inputs = GatherInputs::Stable {
                texels: &texels,
                mattes: &mattes,
                tiles: &dilated,
                kinds: &kinds,
            };
            stages.gather(&config, inputs, &mut color);
        } else {
            let mut colours: Vec<&mut Color> = std::iter::once(&mut color)
                .chain(layers.iter_mut())
                .collect();
            let inputs = (&texels[..], &mattes[..], &dilated, &kinds[..]);
            stages.gather_2014_carrying(&config, inputs, &packed, &mut colours);
        }
    } else {
        // An offset streak reaches up to 2k, two tiles of k: NeighborMax over 5×5 tiles then
        // (the 3×3 stage twice).
        let neighbors = if reach != 1.0 {
            stages.neighbor_max(&stages.neighbor_max(&tiles))
        } else {
            stages.neighbor_max(&tiles)
        };
        for layer in layers.iter_mut() {
            let texels = pack(&config, layer, &depth, &velocity, &neighbors);
            let inputs = GatherInputs::Paper {
                texels: &texels,
                velocity: &velocity,
                neighbors: &neighbors,
            };
            stages.gather(&config, inputs, layer);
        }
        let texels = pack(&config, &color, &depth, &velocity, &neighbors);
        drop(depth);
        let inputs = GatherInputs::Paper {
            texels: &texels,
            velocity: &velocity,
            neighbors: &neighbors,
        };
        stages.gather(&config, inputs, &mut color);
    }
    for (colour, &was) in std::iter::once(&mut color)
        .chain(layers.iter_mut())
        .zip(&opaque)
    {
        if was {
            keep_opaque(colour);
        }
    }
    frame.color = Some(color);
    frame
}

/// Whether every alpha of `color` is 1 (a colour without alpha is not: it gets none).
fn is_opaque(color: &Color) -> bool {
    color
        .a
        .as_ref()
        .is_some_and(|a| a.iter().all(|&v| v == 1.0))
}

/// Sets every alpha of a colour that was opaque to exactly 1, after the gather. Every
/// alpha the gather reads is then 1, and every variant's alpha is a convex mix of them
/// (its weights normalised to sum to 1): exactly 1 in arithmetic, but the float sums round
/// to 0.99999994 or 1.0000001 at some pixels (on `gears` at 640×360, 44 of them), and an
/// opaque plate came back not quite opaque. Only alpha is set; the colour's bits are the
/// gather's, on either backend.
fn keep_opaque(color: &mut Color) {
    if let Some(a) = color.a.as_mut() {
        a.fill(1.0);
    }
}

/// Every vector of `tiles` times `factor`.
fn scale_tiles(tiles: &mut TileGrid, factor: f32) {
    for (x, y) in tiles.x.iter_mut().zip(tiles.y.iter_mut()) {
        *x *= factor;
        *y *= factor;
    }
}
