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
    pub(crate) fn corners(&self) -> [(usize, f32); 4] {
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
///
/// The parts' colours are not read here: [`Recipe`] says how each is made, and the gather
/// reads them once it knows what each part weighs, only for a part that weighs something
/// (at silhouettes, where taps split, four in ten parts weigh nothing).
#[inline(always)]
pub(crate) fn split(texels: &[Texel2014], at: &At) -> (Shape, Shape, Recipe) {
    let At { nearest, scale, .. } = *at;
    let corners = at.corners();
    let near = &texels[nearest];
    let moves = near[LENGTH] >= HALF_PIXEL;
    let mut a = *near;
    let mut b = [0.0f32; 8];
    let mut on_a = [false; 4];
    let (mut share_a, mut share_b, mut heaviest) = (0.0f32, 0.0f32, 0.0f32);
    let mut heaviest_index = NONE;
    for (k, &(j, w)) in corners.iter().enumerate() {
        let texel = &texels[j];
        let same = (texel[Z] - near[Z]).abs() * scale < 1.0;
        let texel_moves = texel[LENGTH] >= HALF_PIXEL;
        on_a[k] = if moves {
            same || texel_moves
        } else {
            same && !texel_moves
        };
        if on_a[k] {
            share_a += w;
        } else {
            share_b += w;
            if w > heaviest {
                heaviest = w;
                b[4..].copy_from_slice(&texel[4..]);
                heaviest_index = j;
            }
        }
    }
    a[..4].fill(0.0);
    let recipe = Recipe {
        corners,
        on_a,
        // A still surface does not blur: its part takes one pixel's colour (the nearest's,
        // or the heaviest of part B), not a mix of its neighbours'.
        a_from: if moves { NONE } else { nearest },
        b_from: if b[LENGTH] < HALF_PIXEL {
            heaviest_index
        } else {
            NONE
        },
        b_still: b[LENGTH] < HALF_PIXEL,
        shares: (share_a, share_b),
    };
    ((a, share_a), (b, share_b), recipe)
}

/// A part's geometry (a texel whose depth and motion are the part's; its colour words unused)
/// and its share of the tap.
pub(crate) type Shape = (Texel2014, f32);

/// No pixel.
const NONE: usize = usize::MAX;

/// How the colours of [`split`]'s two parts are made from the four pixels around the point.
#[derive(Clone, Copy)]
pub(crate) struct Recipe {
    corners: [(usize, f32); 4],
    /// Which corners lie on part A (the nearest's surface); the rest are part B's.
    on_a: [bool; 4],
    /// Part A's one pixel where it is still ([`NONE`]: its corners' colours summed).
    a_from: usize,
    /// Part B's one pixel (its heaviest) where it is still; [`NONE`] with `b_still`: no pixel
    /// of B weighs, and its colour is 0.
    b_from: usize,
    b_still: bool,
    shares: (f32, f32),
}

impl Recipe {
    /// Part A's colours, as [`split`] summed them before it left them to the caller: each
    /// corner's weight times its colour, in order, or a still part's share times one pixel's.
    #[inline(always)]
    pub(crate) fn part_a<const G: usize>(
        &self,
        colour: &impl Fn(usize) -> Colours<G>,
    ) -> Colours<G> {
        self.part(colour, true, self.a_from, false, self.shares.0)
    }

    /// Part B's colours (as [`Recipe::part_a`]).
    #[inline(always)]
    pub(crate) fn part_b<const G: usize>(
        &self,
        colour: &impl Fn(usize) -> Colours<G>,
    ) -> Colours<G> {
        self.part(colour, false, self.b_from, self.b_still, self.shares.1)
    }

    #[inline(always)]
    fn part<const G: usize>(
        &self,
        colour: &impl Fn(usize) -> Colours<G>,
        a: bool,
        from: usize,
        still: bool,
        share: f32,
    ) -> Colours<G> {
        let mut out = [[0.0f32; 4]; G];
        if from != NONE {
            let c = colour(from);
            for g in 0..G {
                for ch in 0..4 {
                    out[g][ch] = share * c[g][ch];
                }
            }
        } else if !still {
            out = summed(colour, &self.corners, |k| self.on_a[k] == a);
        }
        out
    }
}

/// Where all four pixels around the point move (so all lie on the nearest's surface), what
/// [`split`] gives is one part, the whole tap: its share the corners' weights summed
/// (this), its colours summed with their weights in the same order ([`whole_colour`]); part
/// B empty, so the caller weighs none. The gather reads taps so in its plain tiles
/// ([`super::tiles::plain_tiles`]), without the tests, and reads the colours only of a tap
/// that weighs.
#[inline(always)]
pub(crate) fn whole_share(corners: &[(usize, f32); 4]) -> f32 {
    let mut share_a = 0.0f32;
    for &(_, w) in corners {
        share_a += w;
    }
    share_a
}

/// The whole tap's colours ([`whole_share`]), from the corners it read ([`At::corners`]).
#[inline(always)]
pub(crate) fn whole_colour<const G: usize>(
    colour: &impl Fn(usize) -> Colours<G>,
    corners: &[(usize, f32); 4],
) -> Colours<G> {
    summed(colour, corners, |_| true)
}

/// The colours of the corners `keep` takes (by their place in `corners`), each times its
/// weight, summed in order.
#[inline(always)]
fn summed<const G: usize>(
    colour: &impl Fn(usize) -> Colours<G>,
    corners: &[(usize, f32); 4],
    keep: impl Fn(usize) -> bool,
) -> Colours<G> {
    let mut sum = [[0.0f32; 4]; G];
    for (k, &(j, w)) in corners.iter().enumerate() {
        if keep(k) {
            let c = colour(j);
            for g in 0..G {
                for ch in 0..4 {
                    sum[g][ch] += w * c[g][ch];
                }
            }
        }
    }
    sum
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
    (mattes, kinds): (&[Matte], &matte::Kinds<G>),
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
        let (alpha, fg, bg) = matte::surfaces_of(texels, mattes, j, colour, kinds);
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
        let (_, _, bg) = matte::surfaces_of(texels, mattes, nearest, colour, kinds);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A 4×4 frame: columns 0 and 1 a surface at depth 1 moving 5 px a frame, columns 2 and 3
    /// a still one at depth 9; pixel (x, y)'s colour x + 10y in every channel, and twice that
    /// in a second set.
    fn frame() -> (Vec<Texel2014>, impl Fn(usize) -> Colours<2>) {
        let texels = (0..16)
            .map(|i| {
                let c = (i % 4 + 10 * (i / 4)) as f32;
                let (z, v) = if i % 4 < 2 { (1.0, 5.0) } else { (9.0, 0.0) };
                let mut t: Texel2014 = [c, c, c, c, 0.0, 0.0, 0.0, 0.0];
                (t[Z], t[LENGTH]) = (z, v);
                t
            })
            .collect();
        let colour = |j: usize| {
            let c = (j % 4 + 10 * (j / 4)) as f32;
            [[c; 4], [2.0 * c; 4]]
        };
        (texels, colour)
    }

    #[test]
    fn a_split_tap_s_parts_take_their_colours_as_its_recipe_says() {
        // The point (1.25, 1.5): corners (1, 1), (2, 1), (1, 2), (2, 2) weighing 0.375, 0.125,
        // 0.375, 0.125; the nearest pixel (1, 2) moves. Part A: the moving corners summed,
        // 0.375 · 11 + 0.375 · 21 = 12; part B: still, so its heaviest pixel's colour (the
        // first of the two equal, (2, 1): 12) times its share, 0.25 · 12 = 3.
        let (texels, colour) = frame();
        let at = At {
            size: (4, 4),
            nearest: 9,
            scale: 1.0,
            pixel: (1, 1),
            offset: (0.25, 0.5),
        };
        let ((a, share_a), (b, share_b), parts) = split(&texels, &at);
        assert_eq!((share_a, share_b), (0.75, 0.25));
        assert_eq!((a[Z], a[LENGTH], b[Z], b[LENGTH]), (1.0, 5.0, 9.0, 0.0));
        assert_eq!(parts.part_a(&colour), [[12.0; 4], [24.0; 4]]);
        assert_eq!(parts.part_b(&colour), [[3.0; 4], [6.0; 4]]);
        // Seen from the still side, nearest (2, 2): part A is the still surface, one pixel's
        // colour (the nearest's, 22) times its share; part B the moving corners summed.
        let at = At { nearest: 10, ..at };
        let ((_, share_a), (_, share_b), parts) = split(&texels, &at);
        assert_eq!((share_a, share_b), (0.25, 0.75));
        assert_eq!(parts.part_a(&colour), [[5.5; 4], [11.0; 4]]);
        assert_eq!(parts.part_b(&colour), [[12.0; 4], [24.0; 4]]);
        // The whole tap: every corner summed, 0.375 · 11 + 0.125 · 12 + 0.375 · 21 + 0.125 · 22.
        let corners = at.corners();
        assert_eq!(whole_share(&corners), 1.0);
        assert_eq!(whole_colour(&colour, &corners), [[16.25; 4], [32.5; 4]]);
    }
}
