//! The 2014 filter's gather (Guertin, McGuire & Nowrouzezahrai, *A Fast and Stable
//! Feature-Aware Motion Blur Filter*, HPG 2014, with Jimenez's changes, SIGGRAPH 2014), in
//! both its forms: Blender's (`2014`, as its compositor's Vector Blur and EEVEE run it) and
//! ours with the box shutter's weights (`exposure`, the default).
//!
//! In: the config, the packed [`Texel2014`]s, the exposure variant's mattes (empty for the
//! 2014 filter), the dilated tile grid. Out: the colour of the tiles near a blurring one, in
//! place. Twin: `gather_2014` in src/gpu/motion/reconstruct.wgsl.

use super::config::{
    Form, ReconstructConfig, Texel2014, HALF_PIXEL, LANES, LENGTH, MAX_TAPS_PER_SIDE, VX, VY, Z,
};
use super::matte::{self, Matte};
use super::tiles::{gather_tiles, near_blur};
use crate::frame::Color;
use crate::motion::tile_max::TileGrid;
use crate::numeric::unit;

/// How much [`split_by_cover`] steepens the coverage it reads for a still centre, about its
/// half level. A pixel's coverage by an edge ramps from 0 to 1 over one pixel as the edge
/// crosses it; read between pixel centres (bilinearly), the ramp spreads over two, so a still
/// pixel just outside a moving surface's rim counted the surface as reaching it. Measured on
/// the truth scenes (BENCHMARKS.md, "The matte"): 1.25 at still centres takes sparse from
/// 0.0171 to 0.0150 and gears from 0.0174 to 0.0160 at 320×180 (sparse 0.0128 → 0.0122 and
/// gears 0.0154 → 0.0145 at 640×360), the others within 0.7 %; 1.5 and 2, or steepening at
/// moving centres too, cost crossing up to 10 %.
pub const COVER_SLOPE: f32 = 1.25;

/// Jitter salts of the 2014 gather: the tile lookup and the taps' offset.
pub const SALT_TILE: u32 = 0x5449_4c45;
pub const SALT_TAPS: u32 = 0x5441_5053;

/// The 2014 filter's gather, in place, over the tiles within one tile of a blurring one.
pub fn gather_2014(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    mattes: &[Matte],
    tiles: &TileGrid,
    color: &mut Color,
) {
    // Each of the two forms a run meets almost always (ours, and Blender's centred) is given
    // to the gather as a constant, chosen once per frame, so the compiler specialises a whole
    // gather for it: with the form read at run time, the ten choices kept the lanes'
    // arithmetic from being specialised, and the default took 6 % more instructions at 1080p
    // (callgrind, one thread, the bench's moving frame); chosen per pixel, the three copies
    // shared one loop and it ran 4 % slower than before issue 28 (perf, same frame). Any other
    // form (Blender's offset) runs as read.
    let form = config.form();
    if form == Form::OURS {
        gather_2014_as(config, || Form::OURS, texels, mattes, tiles, color);
    } else if form == Form::BLENDER {
        gather_2014_as(config, || Form::BLENDER, texels, mattes, tiles, color);
    } else {
        gather_2014_as(config, || form, texels, mattes, tiles, color);
    }
}

/// [`gather_2014`] in the form `form` gives: a constant for the usual two, so each has its own
/// specialised copy.
#[inline(always)]
fn gather_2014_as(
    config: &ReconstructConfig,
    form: impl Fn() -> Form + Sync,
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
        |_, x, y| gather_pixel_2014(config, &form(), texels, mattes, tiles, x, y),
    );
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
/// Ours (the exposure variant) changes that recipe where `form` ([`Form`]) says, each field
/// with its reason. Returns premultiplied RGBA, a convex mix of taps and centre.
#[inline(always)]
fn gather_pixel_2014(
    config: &ReconstructConfig,
    form: &Form,
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
    let (tile_shift, offset) = if config.jitters() {
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
    if form.own_tile && m_length < HALF_PIXEL {
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
    let k = if form.tap_spacing > 0.0 {
        k.max(((m_length / form.tap_spacing).ceil() as usize).min(MAX_TAPS_PER_SIDE))
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
    let edge = form.edge;
    // How far past its own spread a foreground tap reaches: a whole pixel (Blender's), but
    // in ours half a pixel for a still tap, which does not spread at all.
    let reach = |length: f32| {
        if length < HALF_PIXEL {
            form.still_reach
        } else {
            1.0
        }
    };
    let mut fg = [0.0f32; 4];
    let mut bg = [0.0f32; 4];
    let (mut w_fg, mut w_bg) = (0.0f32, 0.0f32);
    // The centre holds one slot of the count in Blender's form.
    let mut count = form.centre_count;
    // A still centre has no vector of its own: Blender's form gathers along the tile's alone,
    // with half the taps of a moving centre. Ours takes the second set along the tile's vector
    // too, half a step off the first, so a still pixel that a moving surface crosses samples
    // its exposure as finely as a moving one (on `sparse` at 320×180, 0.0193 → 0.0189; no
    // truth scene gets worse). The 1080p moving frame has no still centres: no time cost there.
    let directions = if form.still_second_set || own_length >= HALF_PIXEL {
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
            let offset = if form.half_step && d == 1 {
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
                    if form.split_taps {
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
                    let counts = form.either_way || sample[l][LENGTH] < HALF_PIXEL || along;
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
    if form.exposure_fill {
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
    if corners.iter().all(|&(j, _)| matte::unpaired(&mattes[j], j)) {
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
