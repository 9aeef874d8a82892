//! How the 2014 gather ([`super::gather_2014`]) reads one tap between pixels: bilinearly over
//! a surface ([`bilinear`]), split by surface ([`split`]) or by the matte's coverage
//! ([`split_by_cover`]).
//!
//! Each reads the geometry (depth, motion) from the packed [`Texel2014`]s and mixes the
//! colours of `G` sets at once through `colour(j)`, pixel j's [`Colours`]: the beauty's alone
//! (G = 1, read from the texels), or the beauty's and light layers' carried beside it. Every
//! weight is a function of the geometry and of the matte (fitted once, on the beauty), never of
//! the colours mixed, and each set is mixed channel by channel in the same order: so a layer
//! comes out with the bits it gets in the beauty's place.

use super::config::{Texel2014, HALF_PIXEL, LENGTH, Z};
use super::matte::{self, Matte};

/// How much [`split_by_cover`] steepens the coverage it reads for a centre whose own point
/// lies off the moving surface (a still one, or a moving one covered under half), about its
/// half level. A pixel's coverage by an edge ramps from 0 to 1 over one pixel as the edge
/// crosses it; read between pixel centres (bilinearly), the ramp spreads over two, so a still
/// pixel just outside a moving surface's rim counted the surface as reaching it. Measured on
/// the truth scenes (BENCHMARKS.md, "The matte"): 1.25 at still centres takes sparse from
/// 0.0171 to 0.0150 and gears from 0.0174 to 0.0160 at 320×180 (sparse 0.0128 → 0.0122 and
/// gears 0.0154 → 0.0145 at 640×360), the others within 0.7 %; 1.5 and 2, or steepening at
/// moving centres too, cost crossing up to 10 %.
pub const COVER_SLOPE: f32 = 1.25;

/// `G` colours of one pixel, RGBA each (premultiplied): the beauty's and carried layers'.
pub type Colours<const G: usize> = [[f32; 4]; G];

/// A tap's part: its geometry (a texel whose depth and motion are the part's; its colour
/// words unused), its colours summed with their weights, and its share of the tap.
pub(crate) type Part<const G: usize> = (Texel2014, Colours<G>, f32);

/// Where a tap is read: the frame's size, the pixel nearest to the tap's point (an index),
/// 1 / SOFT_Z_EXTENT (`scale`), the gathering pixel (x, y) and the point's offset from it.
#[derive(Clone, Copy)]
pub(crate) struct At {
    pub(crate) size: (usize, usize),
    pub(crate) nearest: usize,
    pub(crate) scale: f32,
    pub(crate) pixel: (usize, usize),
    pub(crate) offset: (f32, f32),
}

impl At {
    /// The four pixels around the tap's point, with their bilinear weights.
    fn corners(&self) -> [(usize, f32); 4] {
        around_index(self.size, self.pixel.0, self.pixel.1, self.offset)
    }
}

/// The four pixels around pixel (x, y) + `offset` (clamped to the frame), as indices, each
/// with its bilinear weight.
#[inline(always)]
pub(crate) fn around_index(
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

/// The colours at the tap's point `at` (its nearest pixel a moving one) read bilinearly, over
/// the four pixels around it that move or share the nearest's surface (within the soft depth
/// extent), so a tap never takes colour across a silhouette from a still surface. Depth and
/// motion stay the nearest's.
#[inline(always)]
pub(crate) fn bilinear<const G: usize>(
    texels: &[Texel2014],
    colour: &impl Fn(usize) -> Colours<G>,
    at: &At,
) -> Colours<G> {
    let At { nearest, scale, .. } = *at;
    let [c0, c1, c2, c3] = at.corners();
    let corners = [&texels[c0.0], &texels[c1.0], &texels[c2.0], &texels[c3.0]];
    let z = texels[nearest][Z];
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
        let colours = [colour(c0.0), colour(c1.0), colour(c2.0), colour(c3.0)];
        let mut out = [[0.0f32; 4]; G];
        for g in 0..G {
            for ch in 0..4 {
                out[g][ch] = (w[0] * colours[0][g][ch]
                    + w[1] * colours[1][g][ch]
                    + w[2] * colours[2][g][ch]
                    + w[3] * colours[3][g][ch])
                    * inverse;
            }
        }
        out
    } else {
        colour(nearest)
    }
}

/// The exposure variant's tap at `at`, read between pixels and split by surface: the four
/// pixels around the point with their bilinear weights, in two parts. Part A is what lies on
/// the surface of the nearest pixel (the pixels that share its depth within the soft
/// extent, and, when it moves, any that move); part B is
/// the rest, with the depth and motion of its heaviest pixel. Each part's colour is its
/// pixels' colour summed with their weights (a still part's, one pixel's colour times its
/// share: a still surface does not blur), so its mean is the colour over its share; the two
/// shares add up to one. The gather weighs each part as a tap of its own surface.
///
/// Why: at a silhouette the point falls partly on the moving surface and partly beside it,
/// and over the shutter a box integrates the surface's coverage of the pixel as it slides a
/// fraction of a pixel across it. Read whole, as its nearest pixel's surface ([`bilinear`]
/// renormalises over that surface's pixels), a tap counts the moving surface as covering
/// the point wherever the nearest pixel is the surface's, and still neighbours as not
/// covered at all: the silhouette moves in whole-pixel steps, too far out in every
/// direction the motion has a component across it (the top and bottom rims of a disc
/// moving sideways, the ends of its streak). Split, the coverage ramps over the pixel
/// between the two pixel centres, where the pixel-centre classification of depth and motion
/// puts the edge. On `sparse` at 320×180 (a disc of 8 px moving 7.4 px a frame) this takes
/// the default's error from 0.0255 to 0.0206, and no truth scene gets worse. Where any of
/// the four pixels has a matte, [`split_by_cover`] reads the tap instead, with the edge
/// where the pixels' colours put it.
#[inline(always)]
pub(crate) fn split<const G: usize>(
    texels: &[Texel2014],
    colour: &impl Fn(usize) -> Colours<G>,
    at: &At,
) -> (Part<G>, Part<G>) {
    let At { nearest, scale, .. } = *at;
    let corners = at.corners();
    let near = &texels[nearest];
    let moves = near[LENGTH] >= HALF_PIXEL;
    let mut a = *near;
    let mut b = [0.0f32; 8];
    let mut colour_a = [[0.0f32; 4]; G];
    let mut colour_b = [[0.0f32; 4]; G];
    let (mut share_a, mut share_b, mut heaviest) = (0.0f32, 0.0f32, 0.0f32);
    let mut heaviest_colour = [[0.0f32; 4]; G];
    for (j, w) in corners {
        let texel = &texels[j];
        let same = (texel[Z] - near[Z]).abs() * scale < 1.0;
        let texel_moves = texel[LENGTH] >= HALF_PIXEL;
        let on_surface = if moves {
            same || texel_moves
        } else {
            same && !texel_moves
        };
        let c = colour(j);
        if on_surface {
            for g in 0..G {
                for ch in 0..4 {
                    colour_a[g][ch] += w * c[g][ch];
                }
            }
            share_a += w;
        } else {
            for g in 0..G {
                for ch in 0..4 {
                    colour_b[g][ch] += w * c[g][ch];
                }
            }
            share_b += w;
            if w > heaviest {
                heaviest = w;
                b[4..].copy_from_slice(&texel[4..]);
                heaviest_colour = c;
            }
        }
    }
    // A still surface does not blur: its part takes one pixel's colour (the nearest's, or
    // the heaviest of part B), not a mix of its neighbours'.
    if !moves {
        let c = colour(nearest);
        for g in 0..G {
            for ch in 0..4 {
                colour_a[g][ch] = share_a * c[g][ch];
            }
        }
    }
    if b[LENGTH] < HALF_PIXEL {
        for g in 0..G {
            for ch in 0..4 {
                colour_b[g][ch] = share_b * heaviest_colour[g][ch];
            }
        }
    }
    a[..4].fill(0.0);
    ((a, colour_a, share_a), (b, colour_b, share_b))
}

/// What [`split`] gives where all four pixels around the point move (so all lie on the
/// nearest's surface): part A the whole tap, its colours summed with their weights in the
/// same order, its share the weights' sum; part B empty, so the caller weighs none. The
/// gather reads taps so in its plain tiles ([`super::tiles::plain_tiles`]), without the tests.
#[inline(always)]
pub(crate) fn whole<const G: usize>(
    near: &Texel2014,
    colour: &impl Fn(usize) -> Colours<G>,
    at: &At,
) -> Part<G> {
    let mut colour_a = [[0.0f32; 4]; G];
    let mut share_a = 0.0f32;
    for (j, w) in at.corners() {
        let c = colour(j);
        for g in 0..G {
            for ch in 0..4 {
                colour_a[g][ch] += w * c[g][ch];
            }
        }
        share_a += w;
    }
    (*near, colour_a, share_a)
}

/// The exposure variant's tap at `at`, split by coverage ([`matte`]):
/// each of the four pixels around the point gives its bilinear weight times its coverage α to
/// the moving surface, in that surface's colour, and the rest to the still surface behind;
/// part A is the surface of the nearest pixel, part B the other, each
/// with the depth and motion of its heaviest contributor (a still pixel's moving partner for
/// the moving part). A still part takes one colour, as in [`split`]: the nearest's own still
/// surface, or its heaviest contributor's. Each part's colour is summed with its share, as in
/// [`split`]. `None` where the still pixels among the four lie on more than one surface (or
/// not on the nearest's, when it is still): [`split`] reads the tap then.
#[inline(always)]
pub(crate) fn split_by_cover<const G: usize>(
    texels: &[Texel2014],
    colour: &impl Fn(usize) -> Colours<G>,
    mattes: &[Matte],
    at: &At,
    steepen: bool,
) -> Option<(Part<G>, Part<G>)> {
    if mattes.is_empty() {
        return None;
    }
    let At { nearest, scale, .. } = *at;
    let corners = at.corners();
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
    let mut moving_colour = [[0.0f32; 4]; G];
    let (mut share_m, mut share_s) = (0.0f32, 0.0f32);
    let (mut heavy_m, mut heavy_s) = (0.0f32, -1.0f32);
    let mut still_colour = [[0.0f32; 4]; G];
    // The least and greatest coverage of the pixels the tap reads (those it weighs).
    let (mut least, mut most) = (1.0f32, 0.0f32);
    for (j, w) in corners {
        let t = &texels[j];
        let (alpha, fg, bg) = matte::surfaces_of(texels, mattes, j, colour);
        if w > 0.0 {
            least = least.min(alpha);
            most = most.max(alpha);
        }
        let (w_m, w_s) = (w * alpha, w * (1.0 - alpha));
        for g in 0..G {
            for ch in 0..4 {
                moving_colour[g][ch] += w_m * fg[g][ch];
            }
        }
        share_m += w_m;
        share_s += w_s;
        let t_moves = t[LENGTH] >= HALF_PIXEL;
        let fg_texel = if t_moves {
            t
        } else {
            &texels[mattes[j][1].to_bits() as usize]
        };
        let bg_index = if t_moves {
            mattes[j][2].to_bits() as usize
        } else {
            j
        };
        if w_m > heavy_m && fg_texel[LENGTH] >= HALF_PIXEL {
            heavy_m = w_m;
            moving[4..].copy_from_slice(&fg_texel[4..]);
        }
        if w_s > heavy_s {
            heavy_s = w_s;
            still[4..].copy_from_slice(&texels[bg_index][4..]);
            still_colour = bg;
        }
    }
    // At a centre off the moving surface (`steepen`: a still one, or a moving one covered
    // under half), the coverage read between pixels is steepened about its half level:
    // interpolated between pixel centres, coverages ramp over two pixels where an edge's
    // coverage of a pixel ramps over one (see COVER_SLOPE). Never past the coverages the
    // tap reads: that corrects the interpolation across an edge, and a tap along a rim (a
    // row of pixels a tenth covered, moving along itself) reads the rim's own coverage.
    let total = share_m + share_s;
    if steepen && share_m > 0.0 && share_s > 0.0 {
        let cover = share_m / total;
        let steeper = ((cover - 0.5) * COVER_SLOPE + 0.5).max(least).min(most);
        let factor = steeper / cover;
        for c in moving_colour.iter_mut() {
            for v in c.iter_mut() {
                *v *= factor;
            }
        }
        share_m = steeper * total;
        share_s = (1.0 - steeper) * total;
    }
    if heavy_m == 0.0 {
        // No moving surface here after all: all of it is the still one.
        share_s += share_m;
        share_m = 0.0;
        moving = [0.0; 8];
        moving_colour = [[0.0; 4]; G];
    }
    if !moves {
        let (_, _, bg) = matte::surfaces_of(texels, mattes, nearest, colour);
        still_colour = bg;
        still[4..].copy_from_slice(&near[4..]);
    }
    let mut colour_s = [[0.0f32; 4]; G];
    for g in 0..G {
        for ch in 0..4 {
            colour_s[g][ch] = share_s * still_colour[g][ch];
        }
    }
    let moving = (moving, moving_colour, share_m);
    let still = (still, colour_s, share_s);
    Some(if moves {
        (moving, still)
    } else {
        (still, moving)
    })
}
