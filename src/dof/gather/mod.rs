//! `gather`: depth of field as a flat bokeh gather with near and far fields, in the spirit of
//! Sousa's CryENGINE 3 filter (seed 003, "far + near field processing", "tile min/max CoC").
//!
//! Inputs: colour, the signed CoC plane of [`super::coc_plane`] (negative in front of the
//! focus plane) and its tile min/max ([`super::tiles`]). Output: the colour with depth of
//! field. It sits before motion blur. Its GPU twin is `crate::gpu::dof::gather`, which runs
//! the per-pixel loop over the tile [`plan`] made here ([`OffsetTap`], [`TileTaps`]) with a
//! [`GatherConfig`].
//!
//! The physics it approximates: each pixel spreads its light evenly over its bokeh — the
//! aperture's shape at the pixel's CoC — so a point of radiance L with bokeh area a gives
//! L/a to each pixel it covers, and nearer surfaces hide farther ones. Per output pixel p:
//!
//! 1. **Tiles** ([`super::tiles`]). Tiles of 16×16 keep their largest |CoC| and their
//!    smallest and largest signed CoC. A tile gathers over the largest radius of any tile
//!    whose bokeh can reach it (the near field's tile max of Sousa); a tile nothing out of
//!    focus can reach is copied; a tile whose neighbourhood's min is not a layer below its
//!    own max has no near field and skips that half of the work.
//! 2. **Taps.** For R up to `rings` px, every pixel of the neighbourhood; beyond, the
//!    [`super::bokeh`] rings scaled to R and snapped to whole pixels (merged where two land
//!    on one). A tap's distance is the aperture's norm of its whole-pixel offset, so an
//!    n-blade diaphragm shapes the bokeh. A tile's taps are the same for all its pixels, so
//!    the loop runs taps outside and the tile's 16 pixels of a row inside, on padded planes
//!    (structure of arrays, no bounds checks): one AVX-512 vector per tap where the CPU has
//!    it. What lies beyond the frame is unknown, and the gather does not make it up: a tap
//!    outside the frame weighs nothing (its 1 / bokeh area is 0 in the padding), so the far
//!    field is the average of the in-frame taps, renormalised, and the near field counts
//!    the near pixels the frame holds ([`Padded`] says what was measured against mirroring).
//!
//!    Ring taps are a ring step (R / rings) apart, so each reads a prefilter level: the
//!    planes box-averaged over that step ([`level_side`], `levels::Level`), colour weighted by
//!    1 / bokeh area. Single-pixel taps left a lone highlight under a 21 px bokeh as dotted
//!    rings (pixels inside its disc from 0 to 9.4× its level) and kept 0.13 of a 1 px
//!    checker's contrast; with the levels, 0.6× to 1.8× and 0.001 (BENCH-NOTE of the rings
//!    branch: a box of two steps erred less on the truth scenes but widened every bokeh's
//!    rim by a step).
//!
//!    Where a larger bokeh than the tile's own sets its radius (a near field reaching over
//!    it), the far field is gathered apart over the taps of the tile's own largest radius:
//!    a far sample counts only within the pixel's own bokeh, and the large radius's rings
//!    are too sparse there (a fine far texture would come out as a grid of marks). Where
//!    the tile's far taps are rings still (a strongly defocused near object's rim inside
//!    the tile, over fine far detail), a pixel whose own bokeh fits the whole-pixel grid
//!    (radius up to `rings` px) gathers its far field over that grid instead
//!    ([`TileTaps::dense_start`]): the rings of the near object's radius left a 5 px far
//!    bokeh a few dozen scattered taps, and on `border` the fine checker under the disc's
//!    tiles erred 2.5× the references' noise up to a tile from its rim.
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

mod carry;
mod levels;
mod run;

use rayon::prelude::*;

use super::bokeh::{grid, taps, Aperture, Norms, Tap};
use super::tiles::{Tiles, LAYER, TILE};
use super::DofConfig;
use crate::frame::Color;
use carry::{carry_tile, fold, Folded, TileCopy};
pub use run::inverse_area;
use run::{gather_run, Fields, Padded, PixelTap, Row, RowWeights, SMALLEST_RADIUS};

/// A whole-pixel offset with the area it stands for, as a tap of a tile's pattern: its index
/// step in the padded planes and the aperture norms of the offset (of −offset for the far
/// field, whose bokeh is the aperture; of the offset for the near field, turned over).
fn pixel_tap((dx, dy): (isize, isize), area: f32, norms: &Norms, stride: isize) -> PixelTap {
    PixelTap {
        step: dy * stride + dx,
        offset: (dx as i32, dy as i32),
        norm_far: norms.of(-dx, -dy),
        norm_near: norms.of(dx, dy),
        area,
    }
}

/// The largest offset of `taps` in either direction (px).
fn extent(taps: &[PixelTap]) -> usize {
    taps.iter().fold(0, |m, t| {
        m.max(t.offset.0.unsigned_abs() as usize)
            .max(t.offset.1.unsigned_abs() as usize)
    })
}

/// The largest of `tiles`' reaches (px).
fn largest_reach(tiles: &Tiles) -> f32 {
    tiles.reach.iter().fold(0.0f32, |m, &r| m.max(r))
}

/// [`Norms`] for taps of tiles reaching at most `largest` px: a ring scaled to it and snapped
/// lands within a pixel of it, so the table goes a pixel further, up to [`MOST_TABULATED`]
/// (a quarter of a MiB).
fn norms_for(aperture: Aperture, largest: f32) -> Norms {
    let half = (largest.min(MOST_TABULATED as f32).ceil() as usize + 1).min(MOST_TABULATED);
    Norms::new(aperture, half)
}

/// The largest offset [`Norms`] tabulates; taps farther out are normed as they come.
const MOST_TABULATED: usize = 128;

/// The whole-pixel neighbourhood of radius `radius` px as taps, the centre left out (p counts
/// itself). The same for every tile with that whole radius, so made once per radius.
fn grid_taps(radius: usize, norms: &Norms, stride: isize) -> Vec<PixelTap> {
    grid(radius, &norms.aperture)[1..]
        .iter()
        .map(|t| pixel_tap((t.dx as isize, t.dy as isize), t.area, norms, stride))
        .collect()
}

/// The side (px) of the prefilter box ([`levels::Level`]) the rings of gather radius `radius`
/// read: the ring step, R / rings, rounded, at most [`MOST_SIDE`]; 1 (no prefilter) where the
/// grids go.
pub fn level_side(radius: f32, rings: usize) -> usize {
    if radius.ceil() as usize <= rings {
        return 1;
    }
    ((radius / rings as f32).round() as usize).clamp(1, MOST_SIDE)
}

/// The largest prefilter box (px): a level costs its side in additions a pixel and plane on
/// the CPU and its square on the GPU (which sums each box whole), so a bokeh far larger than
/// the rings can fill keeps the work bounded (a 16 px box under the default six rings: a
/// 96 px bokeh radius; beyond it the taps' boxes leave gaps again).
const MOST_SIDE: usize = 16;

/// The taps of a tile whose gather radius is `radius`, larger than the grids go: the rings
/// scaled to the radius and snapped to whole pixels, taps landing on the same pixel merged
/// (their areas summed). Norms are those of the whole-pixel offset, so distances are exact.
/// The centre is left out (p counts itself). With a prefilter box of even `side` the taps
/// snap to the box's centre, half a pixel up and left of its pixel.
fn ring_taps(
    radius: f32,
    rings: &[Tap],
    norms: &Norms,
    stride: isize,
    side: usize,
) -> Vec<PixelTap> {
    let whole = radius.ceil() as usize;
    let shift = if side.is_multiple_of(2) { 0.5 } else { 0.0 };
    let mut offsets: Vec<((isize, isize), f32)> = Vec::new();
    // Which entry of `offsets` each whole-pixel offset went to, on a square a pixel wider
    // than the radius each way (a lookup instead of a search; the same entries in the same
    // order, their areas summed in tap order).
    let half = whole as isize + 2;
    let side_len = (2 * half + 1) as usize;
    let mut entry = vec![usize::MAX; side_len * side_len];
    for tap in &rings[1..] {
        let key = (
            (tap.dx * radius + 0.5 + shift).floor() as isize,
            (tap.dy * radius + 0.5 + shift).floor() as isize,
        );
        let area = tap.area * radius * radius;
        let slot = &mut entry[((key.1 + half) as usize) * side_len + (key.0 + half) as usize];
        match offsets.get_mut(*slot) {
            Some((_, a)) => *a += area,
            None => {
                *slot = offsets.len();
                offsets.push((key, area));
            }
        }
    }
    offsets
        .into_iter()
        .filter(|(key, _)| *key != (0, 0))
        .map(|(key, area)| {
            let mut t = pixel_tap(key, area, norms, stride);
            if shift > 0.0 {
                let (cx, cy) = (key.0 as f32 - shift, key.1 as f32 - shift);
                t.norm_far = norms.aperture.norm(-cx, -cy);
                t.norm_near = norms.aperture.norm(cx, cy);
            }
            t
        })
        .collect()
}

/// The taps of a gather radius: the whole-pixel grid up to `rings` px, the snapped rings
/// beyond (made into `made`), and the side of the prefilter box they read.
fn taps_for<'a>(
    radius: f32,
    grids: &'a [Vec<PixelTap>],
    rings: &[Tap],
    norms: &Norms,
    stride: isize,
    made: &'a mut Vec<PixelTap>,
) -> (&'a [PixelTap], usize) {
    match grids.get(radius.ceil() as usize) {
        Some(grid) => (grid, 1),
        None => {
            let side = level_side(radius, grids.len() - 1);
            *made = ring_taps(radius, rings, norms, stride, side);
            (made, side)
        }
    }
}

/// What a tile that gathers gathers: its fields, the radius of its taps, and the radius of
/// its far field's own taps where they differ (0: none, the tile's own pixels are in focus).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Choice {
    fields: Fields,
    radius: f32,
    far_radius: Option<f32>,
}

/// Whether a tile's far taps are the rings (its far radius beyond the `rings` px the grids
/// go to): then its pixels whose own bokeh fits the grid gather their far field over it.
fn far_rings(choice: &Choice, rings: usize) -> bool {
    choice.far_radius.unwrap_or(choice.radius).ceil() as usize > rings
}

/// How a tile with gather radius `reach`, own largest radius `own` and no near field
/// (`far_only`) gathers; `None` where nothing out of focus reaches it (it is copied).
fn choose(reach: f32, own: f32, far_only: bool, half_focus: f32) -> Option<Choice> {
    if reach < half_focus {
        return None;
    }
    let near = !far_only;
    // Where the tile's radius is set by a larger bokeh than its own (a near field reaching
    // over it), the far field is gathered apart at the tile's own radius: the large radius's
    // rings are too sparse for a small far bokeh, which would keep only the few taps inside
    // it (a grid of marks on a fine far texture).
    let split = near && own.ceil() < reach.ceil();
    let far_radius = split.then_some(if own < half_focus { 0.0 } else { own });
    let fields = match (near, split) {
        (false, _) => Fields::Far,
        (true, false) => Fields::Both,
        (true, true) => Fields::Apart,
    };
    Some(Choice {
        fields,
        radius: reach,
        far_radius,
    })
}

/// The gather's uniform, as its GPU twin reads it (`GatherConfig` in
/// src/gpu/dof/gather.wgsl; a test there holds the two layouts together): eight 4-byte
/// fields, a multiple of 16 bytes as uniforms need. The rest of the gather's parameters
/// (rings, blades, ε) are spent on the host, in [`plan`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct GatherConfig {
    pub width: u32,
    pub height: u32,
    /// Tiles per row.
    pub columns: u32,
    /// 1 where the frame has alpha.
    pub has_alpha: u32,
    /// [`LAYER`].
    pub layer: f32,
    /// The colours the twin's buffers hold, RGBA each (its `gather_carrying`: the beauty and
    /// light layers; 1 for `gather`).
    pub colours: u32,
    /// The largest bokeh radius (px) that gathers its far field over a tile's dense grid
    /// ([`TileTaps::dense_start`]): `rings`, the grid's radius.
    pub small: f32,
    /// The prefilter levels the tiles' taps read ([`TilePlan::sides`]).
    pub levels: u32,
}

impl GatherConfig {
    /// The uniform for gathering a frame of `config` with alpha or without (no levels: the
    /// plan's count goes in `levels`).
    pub fn new(config: &DofConfig, has_alpha: bool) -> Self {
        GatherConfig {
            width: config.width as u32,
            height: config.height as u32,
            columns: config.width.div_ceil(TILE) as u32,
            has_alpha: has_alpha as u32,
            layer: LAYER,
            colours: 1,
            small: config.rings as f32,
            levels: 0,
        }
    }
}

/// One tap as the GPU twin of [`gather`] reads it (`Tap` in src/gpu/dof/gather.wgsl; a test
/// there holds the layouts together): a whole-pixel offset, the aperture norms of it for the
/// far and the near field, and the area it stands for (px²). Five 4-byte fields, the array
/// stride in a storage buffer.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct OffsetTap {
    pub dx: i32,
    pub dy: i32,
    pub norm_far: f32,
    pub norm_near: f32,
    pub area: f32,
}

/// How one tile gathers, as the GPU twin reads it (`Tile` in src/gpu/dof/gather.wgsl; a test
/// there holds the layouts together): `fields` 0 copy, 1 the far field alone, 2 both fields
/// over the same taps, 3 the far field over its own taps then the near field; the taps (start
/// and count in [`TilePlan::taps`]), the far field's own taps, and the dense grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct TileTaps {
    pub fields: u32,
    pub taps_start: u32,
    pub taps_count: u32,
    pub far_start: u32,
    pub far_count: u32,
    /// Where the far taps are rings (a radius beyond `rings` px): the whole-pixel grid of
    /// radius `rings`, over which a pixel whose own bokeh radius is at most
    /// [`GatherConfig::small`] gathers its far field instead (count 0 elsewhere).
    pub dense_start: u32,
    pub dense_count: u32,
    /// The prefilter level the taps read and the one the far taps read: 0 the planes
    /// themselves, k level k − 1 of [`TilePlan::sides`] (the far taps' own where both fields
    /// share the taps). Where the far taps read a level, a pixel that gathers them takes its
    /// own sample from it too.
    pub level: u32,
    pub far_level: u32,
}

/// What [`gather`] decides per tile, as the GPU twin reads it: every tile's choice and the
/// tap lists they point into (each list once, shared by the tiles of one radius).
#[derive(Clone, Debug, PartialEq)]
pub struct TilePlan {
    pub taps: Vec<OffsetTap>,
    pub tiles: Vec<TileTaps>,
    /// The prefilter levels' box sides (px), in the order [`TileTaps::level`] counts them.
    pub sides: Vec<u32>,
}

/// The prefilter levels' box sides ([`level_side`]) the tiles' ring taps read, each once, in
/// the order the tiles first need them.
fn level_sides(config: &DofConfig, tiles: &Tiles) -> Vec<usize> {
    let half_focus = (0.5 * config.epsilon).max(SMALLEST_RADIUS);
    let mut sides: Vec<usize> = Vec::new();
    for t in 0..tiles.reach.len() {
        if let Some(choice) = choose(tiles.reach[t], tiles.own[t], tiles.far_only[t], half_focus) {
            for radius in [Some(choice.radius), choice.far_radius]
                .into_iter()
                .flatten()
            {
                let side = level_side(radius, config.rings);
                if side > 1 && !sides.contains(&side) {
                    sides.push(side);
                }
            }
        }
    }
    sides
}

/// The plan [`gather`] follows for `tiles`: the same choices and the same taps, in order.
pub fn plan(config: &DofConfig, tiles: &Tiles) -> TilePlan {
    let rings_count = config.rings;
    let aperture = Aperture::new(config.blades, config.blade_rotation);
    let rings = taps(rings_count, &aperture);
    // Taps made on a stride wider than any offset, so that each step holds its offset:
    // dy = round(step / STRIDE), dx = step − dy·STRIDE.
    const STRIDE: isize = 1 << 24;
    let offset = |step: isize| {
        let dy = (step + STRIDE / 2).div_euclid(STRIDE);
        ((step - dy * STRIDE) as i32, dy as i32)
    };
    let norms = norms_for(aperture, largest_reach(tiles));
    let grids: Vec<Vec<PixelTap>> = (0..=rings_count)
        .map(|r| grid_taps(r, &norms, STRIDE))
        .collect();
    let half_focus = (0.5 * config.epsilon).max(SMALLEST_RADIUS);
    let sides = level_sides(config, tiles);
    let level = |radius: f32| {
        let side = level_side(radius, rings_count);
        sides
            .iter()
            .position(|&s| s == side)
            .map_or(0, |l| l as u32 + 1)
    };
    let mut plan = TilePlan {
        taps: Vec::new(),
        tiles: Vec::with_capacity(tiles.reach.len()),
        sides: sides.iter().map(|&s| s as u32).collect(),
    };
    // Tap lists already in `plan.taps`, by the radius that made them (a grid's whole radius,
    // or a ring radius's bits).
    let mut lists: std::collections::HashMap<(bool, u32), [u32; 2]> = Default::default();
    let mut list = |radius: f32, plan: &mut TilePlan| -> [u32; 2] {
        let key = match grids.get(radius.ceil() as usize) {
            Some(_) => (true, radius.ceil() as u32),
            None => (false, radius.to_bits()),
        };
        *lists.entry(key).or_insert_with(|| {
            let mut made = Vec::new();
            let (found, _) = taps_for(radius, &grids, &rings, &norms, STRIDE, &mut made);
            let start = plan.taps.len() as u32;
            plan.taps.extend(found.iter().map(|t| {
                let (dx, dy) = offset(t.step);
                OffsetTap {
                    dx,
                    dy,
                    norm_far: t.norm_far,
                    norm_near: t.norm_near,
                    area: t.area,
                }
            }));
            [start, found.len() as u32]
        })
    };
    for t in 0..tiles.reach.len() {
        let tile = match choose(tiles.reach[t], tiles.own[t], tiles.far_only[t], half_focus) {
            None => TileTaps {
                fields: 0,
                taps_start: 0,
                taps_count: 0,
                far_start: 0,
                far_count: 0,
                dense_start: 0,
                dense_count: 0,
                level: 0,
                far_level: 0,
            },
            Some(choice) => {
                let main = list(choice.radius, &mut plan);
                let far = match choice.far_radius {
                    None => main,
                    Some(0.0) => [0, 0],
                    Some(own) => list(own, &mut plan),
                };
                let fields = match choice.fields {
                    Fields::Far => 1,
                    Fields::Both => 2,
                    Fields::Apart => 3,
                };
                let dense = if far_rings(&choice, rings_count) {
                    list(rings_count as f32, &mut plan)
                } else {
                    [0, 0]
                };
                TileTaps {
                    fields,
                    taps_start: main[0],
                    taps_count: main[1],
                    far_start: far[0],
                    far_count: far[1],
                    dense_start: dense[0],
                    dense_count: dense[1],
                    level: level(choice.radius),
                    far_level: match choice.far_radius {
                        None => level(choice.radius),
                        Some(0.0) => 0,
                        Some(own) => level(own),
                    },
                }
            }
        };
        plan.tiles.push(tile);
    }
    plan
}

/// Where the tiles' taps read each prefilter level of `sides` ([`levels::Reads`]): around each
/// tile that reads one, as far as its taps that read it reach (the ring taps' extent, found
/// once a radius); with `everywhere`, over the whole padded frame.
fn level_reads(
    config: &DofConfig,
    tiles: &Tiles,
    padded: &Padded,
    sides: &[usize],
    rings: &[Tap],
    norms: &Norms,
    everywhere: bool,
) -> Vec<levels::Reads> {
    let (width, height) = (config.width, config.height);
    let mut reads: Vec<levels::Reads> = sides
        .iter()
        .map(|_| levels::Reads::new(padded, height))
        .collect();
    if everywhere {
        let all = |w: usize| (-(padded.pad as isize), (w + padded.pad + TILE) as isize);
        for r in &mut reads {
            r.mark(all(width), all(height));
        }
        return reads;
    }
    let tiles_x = width.div_ceil(TILE);
    let half_focus = (0.5 * config.epsilon).max(SMALLEST_RADIUS);
    let mut extents: std::collections::HashMap<u32, isize> = Default::default();
    for t in 0..tiles.reach.len() {
        let Some(choice) = choose(tiles.reach[t], tiles.own[t], tiles.far_only[t], half_focus)
        else {
            continue;
        };
        let (x0, y0) = (t % tiles_x * TILE, t / tiles_x * TILE);
        let rows = TILE.min(height - y0);
        for radius in [Some(choice.radius), choice.far_radius]
            .into_iter()
            .flatten()
        {
            let side = level_side(radius, config.rings);
            if let Some(l) = sides.iter().position(|&s| s == side && side > 1) {
                let e = *extents.entry(radius.to_bits()).or_insert_with(|| {
                    let taps = ring_taps(radius, rings, norms, padded.stride as isize, side);
                    extent(&taps) as isize
                });
                let (x0, y0) = (x0 as isize, y0 as isize);
                reads[l].mark(
                    (x0 - e, x0 + (TILE as isize) + e),
                    (y0 - e, y0 + rows as isize + e),
                );
            }
        }
    }
    reads
}

/// Depth of field by gathering; `coc` is the signed CoC plane (px, diameter), `tiles` its
/// tile min/max ([`super::tiles::tiles`]).
pub fn gather(config: &DofConfig, color: &Color, coc: &[f32], tiles: &Tiles) -> Color {
    gather_carrying(config, color, coc, tiles, Vec::new()).0
}

/// [`gather`], carrying `extra` (colour planes beside the beauty: light layers) through the
/// beauty's taps: each tile row's weights are computed once, by the beauty's loop, folded into
/// one weight a tap and lane and applied to every carried plane ([`carry`]), so each gets the
/// beauty's weights at the cost of a multiply-add a tap. A carried plane comes out within
/// rounding of what it gets gathered in the beauty's place (the same weighted average, summed
/// in another form; a few ulps of the plane's magnitude), and the beauty with the same bits
/// as without planes carried. Returns the colour and the carried planes, in order (new
/// planes: the carried ones are read where they are, not padded, so they are held twice, as
/// when their padded copies replaced them).
pub fn gather_carrying(
    config: &DofConfig,
    color: &Color,
    coc: &[f32],
    tiles: &Tiles,
    extra: Vec<Vec<f32>>,
) -> (Color, Vec<Vec<f32>>) {
    gather_levels_where(config, color, coc, tiles, extra, false)
}

/// [`gather_carrying`], its prefilter levels made where the taps read them, or over the whole
/// frame with `everywhere` (the tests' reference: the same bits).
fn gather_levels_where(
    config: &DofConfig,
    color: &Color,
    coc: &[f32],
    tiles: &Tiles,
    extra: Vec<Vec<f32>>,
    everywhere: bool,
) -> (Color, Vec<Vec<f32>>) {
    let (width, height) = (config.width, config.height);
    let rings_count = config.rings;
    let aperture = Aperture::new(config.blades, config.blade_rotation);
    // Bokeh radii up to `rings` px gather every pixel of their neighbourhood (`grid`, in
    // pixels); larger ones the rings (in units of the radius), which are then at least a
    // pixel apart.
    let rings = taps(rings_count, &aperture);
    let unit_area = aperture.unit_area();
    let has_alpha = color.a.is_some();
    let reach = &tiles.reach;
    let largest = largest_reach(tiles);
    let pad = largest.ceil() as usize + 2;
    let padded = Padded::new(color, coc, (width, height), pad, unit_area);
    let stride = padded.stride as isize;
    let norms = norms_for(aperture, largest);
    let grids: Vec<Vec<PixelTap>> = (0..=rings_count)
        .map(|r| grid_taps(r, &norms, stride))
        .collect();
    let tiles_x = width.div_ceil(TILE);
    let half_focus = (0.5 * config.epsilon).max(SMALLEST_RADIUS);
    // The prefilter levels the tiles' rings read, each made once, where their taps read it.
    let sides = level_sides(config, tiles);
    let reads = level_reads(config, tiles, &padded, &sides, &rings, &norms, everywhere);
    let levels = levels::build(&padded, &sides, &reads, &extra, has_alpha, (width, height));
    let level_of = |side: usize| levels.iter().position(|l| l.side == side);

    // Output planes r, g, b, a, and the carried planes, filled a band of tile rows at a time.
    let mut out = [0, 1, 2, 3].map(|_| vec![0.0f32; width * height]);
    let mut out_extra: Vec<Vec<f32>> = extra.iter().map(|_| vec![0.0f32; width * height]).collect();
    let mut extra_bands: Vec<Vec<&mut [f32]>> = (0..height.div_ceil(TILE))
        .map(|_| Vec::with_capacity(out_extra.len()))
        .collect();
    for plane in out_extra.iter_mut() {
        for (bands, band) in extra_bands.iter_mut().zip(plane.chunks_mut(TILE * width)) {
            bands.push(band);
        }
    }
    let carrying = !extra.is_empty();
    let [out_r, out_g, out_b, out_a] = &mut out;
    out_r
        .par_chunks_mut(TILE * width)
        .zip(out_g.par_chunks_mut(TILE * width))
        .zip(out_b.par_chunks_mut(TILE * width))
        .zip(out_a.par_chunks_mut(TILE * width))
        .zip(extra_bands)
        .enumerate()
        .for_each(
            |(ty, ((((band_r, band_g), band_b), band_a), mut extra_bands))| {
                let mut bands = [band_r, band_g, band_b, band_a];
                let mut weights = RowWeights {
                    keep: carrying,
                    ..RowWeights::default()
                };
                // Each tile row's weights for the carried planes, their tile copies, and
                // their results (a tile a plane).
                let mut folded: Vec<Folded> = (0..TILE).map(|_| Folded::default()).collect();
                let mut scratch = Vec::new();
                let mut carried = vec![vec![[0.0f32; TILE]; TILE]; extra.len()];
                for tx in 0..tiles_x {
                    let t = ty * tiles_x + tx;
                    let x0 = tx * TILE;
                    let span = TILE.min(width - x0);
                    let rows = bands[0].len() / width;
                    let Some(choice) =
                        choose(reach[t], tiles.own[t], tiles.far_only[t], half_focus)
                    else {
                        for row in 0..rows {
                            let start = padded.index(x0, ty * TILE + row);
                            for (k, band) in bands.iter_mut().enumerate() {
                                band[row * width + x0..row * width + x0 + span]
                                    .copy_from_slice(&padded.planes[k][start..start + span]);
                            }
                            let from = (ty * TILE + row) * width + x0;
                            for (band, plane) in extra_bands.iter_mut().zip(&extra) {
                                band[row * width + x0..row * width + x0 + span]
                                    .copy_from_slice(&plane[from..from + span]);
                            }
                        }
                        continue;
                    };
                    let mut made = Vec::new();
                    let (taps, side) =
                        taps_for(choice.radius, &grids, &rings, &norms, stride, &mut made);
                    let mut made_far = Vec::new();
                    let (far_taps, far_side) = match choice.far_radius {
                        None => (taps, side),
                        Some(0.0) => (&[][..], 1),
                        Some(own) => taps_for(own, &grids, &rings, &norms, stride, &mut made_far),
                    };
                    let planes_of = |side: usize| match level_of(side) {
                        Some(l) => levels[l].planes(&padded),
                        None => padded.planes.each_ref().map(|p| p.as_slice()),
                    };
                    let carried_of = |side: usize| match level_of(side) {
                        Some(l) => &levels[l].carried[..],
                        None => &extra[..],
                    };
                    let mode = choice.fields;
                    let dense = far_rings(&choice, rings_count);
                    let mut copy = TileCopy {
                        x0,
                        y0: ty * TILE,
                        rows,
                        reach: extent(taps).max(extent(far_taps)).max(if dense {
                            rings_count
                        } else {
                            0
                        }),
                        direct: false,
                    };
                    copy.direct = copy.inside((width, height));
                    let copy_stride = copy.origin(width).1;
                    for row in 0..rows {
                        let start = padded.index(x0, ty * TILE + row);
                        let run = Row {
                            start,
                            span,
                            far_taps,
                            taps,
                            fields: mode,
                            grids: if dense { &grids } else { &[] },
                            small: rings_count as f32,
                            far_planes: planes_of(far_side),
                            planes: planes_of(side),
                            far_level: far_side > 1,
                            level: side > 1,
                        };
                        let mut result = [[0.0f32; TILE]; 4];
                        gather_run(&padded, &run, &mut result, &mut weights);
                        for (k, band) in bands.iter_mut().enumerate() {
                            band[row * width + x0..row * width + x0 + span]
                                .copy_from_slice(&result[k][..span]);
                        }
                        if carrying {
                            fold(&padded, &run, &weights, copy_stride, &mut folded[row]);
                        }
                    }
                    if carrying {
                        carry_tile(
                            [&extra[..], carried_of(far_side), carried_of(side)],
                            (width, height),
                            &copy,
                            &folded[..rows],
                            &mut scratch,
                            &mut carried,
                        );
                        for (band, plane) in extra_bands.iter_mut().zip(&carried) {
                            for row in 0..rows {
                                band[row * width + x0..row * width + x0 + span]
                                    .copy_from_slice(&plane[row][..span]);
                            }
                        }
                    }
                }
            },
        );
    let [r, g, b, a] = out;
    let color = Color {
        r,
        g,
        b,
        a: has_alpha.then_some(a),
    };
    (color, out_extra)
}

#[cfg(test)]
mod field_tests;
