//! The 2014 filter's gather (Guertin, McGuire & Nowrouzezahrai, *A Fast and Stable
//! Feature-Aware Motion Blur Filter*, HPG 2014, with Jimenez's changes, SIGGRAPH 2014), in
//! both its forms: Blender's (`2014`, as its compositor's Vector Blur and EEVEE run it) and
//! ours with the box shutter's weights (`exposure`, the default).
//!
//! In: the config, the packed [`Texel2014`]s, the exposure variant's mattes (empty for the
//! 2014 filter), the dilated tile grid. Out: the colour of the tiles near a blurring one, in
//! place. Twin: `gather_2014` in src/gpu/motion/reconstruct.wgsl.

use super::classify::{fails, TileKind};
use super::config::{
    Form, ReconstructConfig, Texel2014, HALF_PIXEL, LANES, LENGTH, MAX_TAPS_PER_SIDE, VX, VY, Z,
};
use super::matte::{self, Matte};
use super::pack::pack_tiles;
use super::taps::{
    bilinear, split, split_by_cover, whole_colour, whole_share, At, Colours, Recipe,
};
use super::tiles::{gather_tiles_of, near_blur, Gather, TileMask};
use super::uniform::box_pixel;
use crate::frame::Color;
use crate::motion::tile_max::TileGrid;
use crate::numeric::unit;

pub use super::taps::COVER_SLOPE;

/// Jitter salts of the 2014 gather: the tile lookup and the taps' offset.
pub const SALT_TILE: u32 = 0x5449_4c45;
pub const SALT_TAPS: u32 = 0x5441_5053;

/// The dilated tiles and each one's kind ([`super::classify::classify`]'s), as the gather
/// reads them.
pub type Tiles<'a> = (&'a TileGrid, &'a [TileKind]);

/// Most colours [`gather_2014_carrying`] gathers in one pass (the GPU twin: in one dispatch).
pub const MOST_COLOURS: usize = 8;

/// The 2014 filter's gather, in place, over the tiles within one tile of a blurring one,
/// each tile's pixels by the copy its kind names (`kinds`, [`super::classify::classify`]'s).
pub fn gather_2014(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    mattes: &[Matte],
    (tiles, kinds): Tiles<'_>,
    color: &mut Color,
) {
    let beauty = |j: usize| {
        let t = &texels[j];
        [[t[0], t[1], t[2], t[3]]]
    };
    gather_2014_of(
        config,
        texels,
        (&beauty, &matte::RGBA),
        mattes,
        (tiles, kinds),
        &mut [color],
    );
}

/// [`gather_2014`] of several colours at once, each in place: the beauty (first) and light
/// layers beside it (R, G, B in the beauty's places, with its alpha), every one blurred with
/// exactly the weights the beauty gets. The weights read only the texels' depth and motion
/// and the mattes, so they are computed once for up to eight colours, whose values ride along
/// each tap ([`super::taps`]): each colour comes out with the bits it gets alone in the
/// beauty's place. `packed` is the tiles the texels were packed on ([`super::packed_2014`]),
/// where the colours are packed beside them.
///
/// Up to eight at a time, in chunks as even as they can be, each gathered by a copy of the
/// gather for its count (eight copies of the default form cost 4 s of a 77 s release build).
/// With six light layers at 1080p (the bench's `moving` frame), one pass of seven took
/// 2.5–2.8 s where passes of four and three took 3.8–4.2 s, and a pass of eight with one
/// colour repeated 3.2 s (the beauty alone: 1.2 s): each colour's share of a tap costs far
/// less than the tap's weights, but a colour carried for nothing costs its share. On
/// `sparse`, where few pixels move, seven in one pass took 0.25–0.28 s and four and three
/// 0.33–0.35 s.
///
/// Where every layer's alpha is the beauty's (as `process_with` gives them), the layers'
/// alphas are not gathered again: their R, G and B go four to a colour beside the beauty
/// (six layers: five colours and the beauty, not seven; nine: one pass of eight, not two of
/// five), each value unmixed with the extrapolation of its own channel ([`matte::Kinds`]),
/// and each layer's alpha comes back as the beauty's gathered alpha, which is the bits its
/// own would get. Layers with alphas of their own go one to a colour.
pub fn gather_2014_carrying(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    mattes: &[Matte],
    (tiles, kinds): Tiles<'_>,
    packed: &TileMask,
    colours: &mut [&mut Color],
) {
    if colours.is_empty() {
        return;
    }
    let inputs = (texels, mattes, (tiles, kinds), packed);
    let (beauty, layers) = colours.split_at_mut(1);
    if layers.is_empty() || layers.iter().any(|layer| layer.a != beauty[0].a) {
        let rgba = vec![[0, 1, 2, 3]; colours.len()];
        return gather_chunks(config, inputs, colours, &rgba);
    }
    // The layers' alphas are the beauty's: their channels go four to a colour (kinds R, G,
    // B in turn), and each layer's alpha comes back as the beauty's.
    let n = texels.len();
    let mut stream: Vec<(Vec<f32>, u8)> = Vec::with_capacity(3 * layers.len() + 3);
    for layer in layers.iter_mut() {
        for (kind, plane) in [&mut layer.r, &mut layer.g, &mut layer.b]
            .into_iter()
            .enumerate()
        {
            stream.push((std::mem::take(plane), kind as u8));
        }
    }
    while !stream.len().is_multiple_of(4) {
        stream.push((vec![0.0; n], 0));
    }
    let mut kinds = vec![[0, 1, 2, 3]];
    let mut packed_colours = Vec::with_capacity(stream.len() / 4);
    let mut planes = stream.into_iter();
    while let (Some(r), Some(g), Some(b), Some(a)) =
        (planes.next(), planes.next(), planes.next(), planes.next())
    {
        kinds.push([r.1, g.1, b.1, a.1]);
        packed_colours.push(Color {
            r: r.0,
            g: g.0,
            b: b.0,
            a: Some(a.0),
        });
    }
    let mut all: Vec<&mut Color> = std::iter::once(&mut *beauty[0])
        .chain(packed_colours.iter_mut())
        .collect();
    gather_chunks(config, inputs, &mut all, &kinds);
    let mut planes = packed_colours.into_iter().flat_map(|c| {
        [
            c.r,
            c.g,
            c.b,
            c.a.expect("each packed colour holds four channels"),
        ]
    });
    for layer in layers.iter_mut() {
        for plane in [&mut layer.r, &mut layer.g, &mut layer.b] {
            *plane = planes.next().expect("three channels a layer");
        }
        layer.a.clone_from(&beauty[0].a);
    }
}

/// `colours` (each value's kind in `kinds`, colour by colour) in chunks of at most
/// [`MOST_COLOURS`], as even as they can be.
fn gather_chunks(
    config: &ReconstructConfig,
    inputs: (&[Texel2014], &[Matte], Tiles<'_>, &TileMask),
    colours: &mut [&mut Color],
    kinds: &[[u8; 4]],
) {
    let size = colours.len().div_ceil(colours.len().div_ceil(MOST_COLOURS));
    for (chunk, kinds) in colours.chunks_mut(size).zip(kinds.chunks(size)) {
        match chunk.len() {
            1 => gather_packed::<1>(config, inputs, chunk, kinds),
            2 => gather_packed::<2>(config, inputs, chunk, kinds),
            3 => gather_packed::<3>(config, inputs, chunk, kinds),
            4 => gather_packed::<4>(config, inputs, chunk, kinds),
            5 => gather_packed::<5>(config, inputs, chunk, kinds),
            6 => gather_packed::<6>(config, inputs, chunk, kinds),
            7 => gather_packed::<7>(config, inputs, chunk, kinds),
            _ => gather_packed::<8>(config, inputs, chunk, kinds),
        }
    }
}

/// `G` `colours` packed pixel by pixel on the packed tiles, then gathered together.
fn gather_packed<const G: usize>(
    config: &ReconstructConfig,
    (texels, mattes, (tiles, kinds), packed): (&[Texel2014], &[Matte], Tiles<'_>, &TileMask),
    colours: &mut [&mut Color],
    channels: &[[u8; 4]],
) {
    let channels: matte::Kinds<G> = channels.try_into().expect("a kind for each colour");
    let values: Vec<Colours<G>> = {
        let sources: [&Color; G] = std::array::from_fn(|g| &*colours[g]);
        pack_tiles(
            config,
            tiles.columns,
            [[0.0; 4]; G],
            |c, row| packed.get(c, row),
            |i| sources.map(|c| [c.r[i], c.g[i], c.b[i], c.a.as_ref().map_or(1.0, |a| a[i])]),
        )
    };
    let colour = |j: usize| values[j];
    gather_2014_of(
        config,
        texels,
        (&colour, &channels),
        mattes,
        (tiles, kinds),
        colours,
    );
}

/// The gather of `G` colours, `colour(j)` those of pixel j, written into `out` (the first
/// `out.len()` of them).
fn gather_2014_of<const G: usize>(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    colour: (&(impl Fn(usize) -> Colours<G> + Sync), &matte::Kinds<G>),
    mattes: &[Matte],
    (tiles, kinds): Tiles<'_>,
    out: &mut [&mut Color],
) {
    // Each of the two forms a run meets almost always (ours, and Blender's centred) is given
    // to the gather as a constant, chosen once per frame, so the compiler specialises a whole
    // gather for it: with the form read at run time, the ten choices kept the lanes'
    // arithmetic from being specialised, and the default took 6 % more instructions at 1080p
    // (callgrind, one thread, the bench's moving frame); chosen per pixel, the three copies
    // shared one loop and it ran 4 % slower than before issue 28 (perf, same frame). Any other
    // form (Blender's offset) runs as read. Carrying layers (G > 1), only ours, the default, has
    // its own copy.
    let form = config.form();
    let inputs = (texels, colour, mattes, (tiles, kinds));
    if form == Form::OURS {
        gather_2014_as(config, || Form::OURS, inputs, out);
    } else if G == 1 && form == Form::BLENDER {
        gather_2014_as(config, || Form::BLENDER, inputs, out);
    } else {
        gather_2014_as(config, || form, inputs, out);
    }
}

/// [`gather_2014`] in the form `form` gives: a constant for the usual two, so each has its own
/// specialised copy.
#[inline(always)]
fn gather_2014_as<const G: usize>(
    config: &ReconstructConfig,
    form: impl Fn() -> Form + Sync,
    (texels, (colour, channels), mattes, (tiles, kinds)): (
        &[Texel2014],
        (&(impl Fn(usize) -> Colours<G> + Sync), &matte::Kinds<G>),
        &[Matte],
        Tiles<'_>,
    ),
    out: &mut [&mut Color],
) {
    let pixel = Pixel2014 {
        config,
        form,
        sources: Sources {
            texels,
            colour,
            mattes,
            channels,
        },
        tiles: (tiles, kinds),
    };
    gather_tiles_of(
        config,
        tiles.columns,
        out,
        |c, row| near_blur(tiles, c, row, 1),
        &pixel,
    );
}

/// The 2014 gather at a pixel, as [`gather_tiles_of`] runs it: a type, not a closure, so its
/// body is inlined into the band loop's copy for the CPU at hand (AVX2 where there is one:
/// [`super::tiles::Gather`]).
struct Pixel2014<'a, F, C, const G: usize> {
    config: &'a ReconstructConfig,
    form: F,
    sources: Sources<'a, C, G>,
    tiles: Tiles<'a>,
}

impl<const G: usize, F, C> Gather<G> for Pixel2014<'_, F, C, G>
where
    F: Fn() -> Form + Sync,
    C: Fn(usize) -> Colours<G> + Sync,
{
    #[inline(always)]
    fn pixel(&self, (c, row): (usize, usize), x: usize, y: usize) -> Colours<G> {
        let Self {
            config,
            form,
            sources,
            tiles: (tiles, kinds),
        } = self;
        // A copy of the gather for each kind of tile, so neither pays for the other's
        // branches (one copy with the flag read per tap ran the noise frame 10 % slower).
        match kinds[row * tiles.columns + c] {
            TileKind::Uniform => box_pixel(config, sources.texels, sources.colour, x, y),
            TileKind::Plain => {
                gather_pixel_2014::<G, _, true>(config, &form(), sources, tiles, x, y)
            }
            TileKind::Full => {
                gather_pixel_2014::<G, _, false>(config, &form(), sources, tiles, x, y)
            }
            TileKind::Hollow => {
                let j = y * config.width as usize + x;
                if fails(sources.texels, sources.mattes, j) {
                    gather_pixel_2014::<G, _, false>(config, &form(), sources, tiles, x, y)
                } else {
                    box_pixel(config, sources.texels, sources.colour, x, y)
                }
            }
        }
    }
}

/// What a pixel's gather reads: the texels (depth and motion), the colours carried
/// (`colour(j)`, pixel j's) and the mattes.
struct Sources<'a, C, const G: usize> {
    texels: &'a [Texel2014],
    colour: &'a C,
    mattes: &'a [Matte],
    /// Which of the beauty's channels each colour value is ([`matte::surfaces_of`]).
    channels: &'a matte::Kinds<G>,
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
fn gather_pixel_2014<const G: usize, C: Fn(usize) -> Colours<G>, const PLAIN: bool>(
    config: &ReconstructConfig,
    form: &Form,
    sources: &Sources<C, G>,
    tiles: &TileGrid,
    x: usize,
    y: usize,
) -> Colours<G> {
    let Sources {
        texels,
        colour,
        mattes,
        channels,
    } = *sources;
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
    let mut m_length = tiles.length(column, row);
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
        m_length = tiles.length(c, r);
    }
    let own = (centre[VX], centre[VY]);
    let own_length = centre[LENGTH];
    if m_length < own_length {
        m = own;
        m_length = own_length;
    }
    if m_length < HALF_PIXEL {
        return colour(i);
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
    // The pixel nearest to the point `offset` from the centre (clamped to the frame), and
    // whether the point lies in the frame.
    let nearest_to = |offset: (f32, f32)| {
        let px = (x as f32 + 0.5 + offset.0).max(0.0) as usize;
        let py = (y as f32 + 0.5 + offset.1).max(0.0) as usize;
        py.min(height - 1) * width + px.min(width - 1)
    };
    let inside = |offset: (f32, f32)| {
        let (px, py) = (x as f32 + 0.5 + offset.0, y as f32 + 0.5 + offset.1);
        px >= 0.0 && py >= 0.0 && px < width as f32 && py < height as f32
    };
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
    let mut fg = [[0.0f32; 4]; G];
    let mut bg = [[0.0f32; 4]; G];
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
    // A streak that runs behind a nearer surface: where the centre moves, a tap that falls on
    // a nearer surface whose own streak does not reach the centre (a still subject the
    // background streams behind, at the frame's instant hiding what the centre integrates
    // over the exposure) is read a whole streak's length (2|V|) back along its line, where
    // the centre's own surface is visible (the slid point must lie on it: within the soft
    // depth extent, moving), and weighed as at its own distance. The streak is thus slid
    // back until it is all visible. The taps left uncovered were filled with the background
    // taps' average, as Blender fills them: on `follow` at 320×180 (stripes of 9 px
    // streaming 18 px a frame behind a still card) that left the three pixels beside each
    // side 0.03 too dark, the visible part of the streak being less than a stripe period.
    // Not at a pixel beside such a surface (its rim): its colour holds part of that surface,
    // and where the surface is round (`follow-wall`, `pan`) the slid streak made those
    // pixels worse (region RMSE 0.0111 → 0.0114, 0.0076 → 0.0081). Not past the frame's
    // edge either: there the clamped read (the border extended) measured better on
    // `follow-wall` and `pan` (BENCHMARKS.md, "A still subject before a pan").
    let slides =
        form.slide_hidden && own_length >= HALF_PIXEL && !beside_nearer(texels, config, x, y);
    // Where the centre's own point lies off the moving surface, the coverage a tap reads
    // between pixel centres is steepened ([`COVER_SLOPE`]): at a still centre, and at a moving
    // one covered less than half, a view layer's edge pixel whose centre missed its surface
    // and which the stack gives the surface's motion (over empty space the matte keeps its
    // alpha, [`matte::over_empty`]; in an opaque frame a moving pixel is at least half
    // covered). On sparse's stack at 320×180 this takes the error from 0.01444 to 0.01332
    // (BENCHMARKS.md, "A layer's edge over empty space").
    let steepen = own_length < HALF_PIXEL || mattes.get(i).is_some_and(|m| m[0] < 0.5);
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
                // (Depth and motion in the texels, colours beside them.)
                let mut sample = [[0.0f32; 8]; LANES];
                let mut share = [0.0f32; LANES];
                let mut other = [[0.0f32; 8]; LANES];
                let mut other_share = [0.0f32; LANES];
                let mut sample_colour = [[[0.0f32; 4]; G]; LANES];
                let mut other_colour = [[[0.0f32; 4]; G]; LANES];
                // A plain tile's taps keep their corners; with layers carried, their colours
                // are read once the weights are known, and only where a weight is not 0
                // (`whole_colour`). The beauty alone reads its one colour with the tap: the
                // deferred read took 8.6 % more instructions there (cachegrind, one thread, a
                // 480×270 cut of the bench's moving frame), where its colour is 4 floats.
                let mut corners = [[(0usize, 0.0f32); 4]; LANES];
                // A tap [`split`] read keeps how its parts' colours are made, read likewise.
                let mut recipes: [Option<Recipe>; LANES] = [None; LANES];
                for l in 0..LANES.min(k - first) {
                    t[l] = ((first + l) as f32 + offset) * step;
                    let mut point = (sx * t[l], sy * t[l]);
                    let mut nearest_index = nearest_to(point);
                    let mut nearest = texels[nearest_index];
                    if slides && length * t[l] < own_length * extent + edge {
                        let dz = nearest[Z] - centre_z;
                        let away = if dx * nearest[VX] + dy * nearest[VY] > 0.0 {
                            side
                        } else {
                            -side
                        };
                        let share = 1.0 - shift * away;
                        let reaches =
                            nearest[LENGTH] * share - length * t[l] + reach(nearest[LENGTH]) > 0.0;
                        if 0.5 + scale * dz <= 0.0 && !reaches && inside(point) {
                            let back = 2.0 * own_length / length;
                            let slid = (point.0 - sx * back, point.1 - sy * back);
                            let j = nearest_to(slid);
                            let tj = &texels[j];
                            if inside(slid)
                                && tj[LENGTH] >= HALF_PIXEL
                                && ((tj[Z] - centre_z) * scale).abs() < 1.0
                            {
                                (point, nearest_index, nearest) = (slid, j, *tj);
                            }
                        }
                    }
                    let at = At {
                        size: (width, height),
                        nearest: nearest_index,
                        scale,
                        pixel: (x, y),
                        offset: point,
                    };
                    if form.split_taps && PLAIN {
                        // A plain tile ([`TileKind::Plain`]): every split is one part.
                        corners[l] = at.corners();
                        (sample[l], share[l]) = (nearest, whole_share(&corners[l]));
                        if G == 1 {
                            sample_colour[l] = whole_colour(colour, &corners[l]);
                        }
                    } else if form.split_taps {
                        match split_by_cover(texels, colour, (mattes, channels), &at, steepen) {
                            Some(parts) => {
                                (sample[l], sample_colour[l], share[l]) = parts.0;
                                (other[l], other_colour[l], other_share[l]) = parts.1;
                            }
                            None => {
                                let parts;
                                ((sample[l], share[l]), (other[l], other_share[l]), parts) =
                                    split(texels, &at);
                                recipes[l] = Some(parts);
                            }
                        }
                    } else {
                        // Colour is read between pixels (bilinear, as a GPU's filtered
                        // texture read, which Blender's runs), depth and motion at the
                        // nearest: a streak of a pixel or two is then a box of its true
                        // length, not a few whole pixels (on `sparse` at 320×180 this halved
                        // the error, 0.042 → 0.021). A still surface is read at the nearest
                        // texel alone: it does not blur.
                        sample[l] = nearest;
                        sample_colour[l] = if nearest[LENGTH] >= HALF_PIXEL {
                            bilinear(texels, colour, &at)
                        } else {
                            colour(nearest_index)
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
                    // (Part B is empty in a plain tile: nothing to weigh.)
                    if !PLAIN {
                        (f[l][1], b[l][1]) =
                            weights(&other[l], distance, direction, share(&other[l]));
                    }
                    count += direction;
                }
                for l in 0..LANES {
                    if form.split_taps && PLAIN && G > 1 {
                        // One part: its colour only where it weighs. A weight of 0 adds
                        // 0 × colour, ±0, to a sum that is never −0 (it starts at +0, and
                        // x + (−x) rounds to +0): skipping it leaves the same bits, as does
                        // leaving out part B's 0 × 0.
                        if f[l][0] != 0.0 || b[l][0] != 0.0 {
                            let s = whole_colour(colour, &corners[l]);
                            for g in 0..G {
                                for ch in 0..4 {
                                    fg[g][ch] += f[l][0] * s[g][ch];
                                    bg[g][ch] += b[l][0] * s[g][ch];
                                }
                            }
                        }
                    } else {
                        // As above, a part that weighs nothing adds ±0 whatever its colour.
                        let none = [[0.0f32; 4]; G];
                        // (A plain tile's taps are never split.)
                        let recipe = if PLAIN { None } else { recipes[l].as_ref() };
                        let (s, o) = match recipe {
                            Some(parts) => (
                                if f[l][0] != 0.0 || b[l][0] != 0.0 {
                                    parts.part_a(colour)
                                } else {
                                    none
                                },
                                if f[l][1] != 0.0 || b[l][1] != 0.0 {
                                    parts.part_b(colour)
                                } else {
                                    none
                                },
                            ),
                            None => (sample_colour[l], other_colour[l]),
                        };
                        for g in 0..G {
                            for ch in 0..4 {
                                fg[g][ch] += f[l][0] * s[g][ch] + f[l][1] * o[g][ch];
                                bg[g][ch] += b[l][0] * s[g][ch] + b[l][1] * o[g][ch];
                            }
                        }
                    }
                    w_fg += f[l][0] * share[l] + f[l][1] * other_share[l];
                    w_bg += b[l][0] * share[l] + b[l][1] * other_share[l];
                }
                first += LANES;
            }
        }
    }
    let mut out = [[0.0f32; 4]; G];
    let centre_colour = colour(i);
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
        let mut own_colour = centre_colour;
        if own_length < HALF_PIXEL && !mattes.is_empty() {
            own_colour = matte::surfaces_of(texels, mattes, i, colour, channels).2;
        }
        for g in 0..G {
            for ch in 0..4 {
                let background = if w_bg > 0.0 {
                    cover * own_colour[g][ch] + (1.0 - cover) * bg[g][ch] / w_bg
                } else {
                    own_colour[g][ch]
                };
                out[g][ch] = (fg[g][ch] + bg[g][ch]) * inverse + background * missing;
            }
        }
        return out;
    }
    // Blender's own addition: a little of the centre in the background, so that its
    // average exists when no tap is behind.
    let w = 1.0 / (50.0 * (4 * k) as f32);
    let w_bg = w_bg + w;
    let missing = (1.0 - (w_fg + w_bg) / count).clamp(0.0, 1.0);
    for g in 0..G {
        let (fg, bg, centre) = (&fg[g], &bg[g], &centre_colour[g]);
        for ch in 0..4 {
            let background = (bg[ch] + w * centre[ch]) / w_bg;
            out[g][ch] = (fg[ch] + bg[ch] + w * centre[ch]) / count + background * missing;
        }
    }
    out
}

/// Whether pixel (x, y) lies beside (a 4-neighbour of) a still surface nearer than it by the
/// soft depth extent's half: the rim of a still subject, whose colour holds part of it.
#[inline]
fn beside_nearer(texels: &[Texel2014], config: &ReconstructConfig, x: usize, y: usize) -> bool {
    let (width, height) = (config.width as usize, config.height as usize);
    let z = texels[y * width + x][Z];
    let nearer = |j: usize| {
        let t = &texels[j];
        t[LENGTH] < HALF_PIXEL && 0.5 + config.inv_soft_z * (t[Z] - z) <= 0.0
    };
    (x > 0 && nearer(y * width + x - 1))
        || (x + 1 < width && nearer(y * width + x + 1))
        || (y > 0 && nearer((y - 1) * width + x))
        || (y + 1 < height && nearer((y + 1) * width + x))
}

#[cfg(test)]
mod tests;
