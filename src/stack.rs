//! Layer stacks (issue 33): a shot rendered in view layers, front to back. Each layer is
//! blurred alone, premultiplied, with its own depth and motion, so what a nearer layer
//! uncovers is what the layer behind holds rather than a guess; then the layers are merged
//! front over back.
//!
//! A layer's alpha is its coverage. A pixel it does not cover (alpha 0) is empty, not a
//! surface: whatever its passes say, it is still and as far as can be, so it neither moves
//! nor hides anything ([`prepare_for_motion`]). A covered pixel whose passes say nothing is
//! there (a renderer samples depth and vectors at one point: at a layer's edge that point can
//! miss the surface the colour's samples saw; Blender writes depth 10¹⁰ and no motion there)
//! takes the passes of the nearest pixel of a surface within [`EDGE_REACH`] px. For depth of
//! field an empty pixel takes the depth of the nearest surface, so the gathers, which
//! normalise by the weights they meet, meet a field whose circles of confusion are those of
//! the layer's own surfaces and spread nothing from the empty space
//! ([`prepare_for_dof`]).

use crate::error::{Problem, ProblemKind};
use crate::frame::{pixel_centre, CarriedChannel, Color, Frame, LayerClass, Plane};
use crate::gpu::Gpu;
use crate::io::sequence::PathPattern;
use crate::motion::Algorithm;
use crate::numeric::DepthKind;
use crate::process::{depth_kind, process_on, Params};

/// Depth at or beyond this says no surface is there: Blender writes 10¹⁰ (and no motion) at
/// a pixel whose depth sample hits nothing of the layer; a real surface 10⁹ scene units away
/// is, for a lens and for motion, at infinity.
pub const NO_SURFACE: f32 = 1e9;

/// How far (px) a covered pixel with no surface of its own looks for the surface it covers:
/// the reach of a renderer's pixel filter (Blackman–Harris 1.5 px wide, Gaussian, box), two
/// pixels with room.
pub const EDGE_REACH: f32 = 2.0;

/// The names the merged beauty goes out under (an EXR output): a file's main RGBA layer.
pub const MERGED: [&str; 4] = ["R", "G", "B", "A"];

/// Why a stack does not read `path`, a file of several `views` (the default first), when its
/// output would hold every view (an EXR without `--view`): a stack is read from one view, so
/// such a run wrote the default view alone and left the others out with no word of them.
/// Carrying each view through the stack is for later; one run per view does it now.
pub fn views_problem(path: &std::path::Path, views: &[Option<String>]) -> Problem {
    let names: Vec<&str> = views.iter().flatten().map(String::as_str).collect();
    Problem::new(
        ProblemKind::View,
        path,
        format!(
            "the colour file holds views {}, and a stack of view layers is read from one \
             view: an EXR output without --view would hold one of them and lose the others; \
             give --view {} (one run per view, each to its own output, e.g. --view {} -o \
             {}/…), or --layer NAME to blur one view layer in every view",
            names.join(", "),
            names.join(" or --view "),
            names.first().unwrap_or(&"NAME"),
            names.first().unwrap_or(&"NAME"),
        ),
    )
}

/// The names of a stack's layers read from files of their own (`--color` given once a layer,
/// no `--layers`), from their colour files' names: the file's name without its frame
/// number's placeholder, up to its first period, without separators (`_`, `-`, `.`, space)
/// at either end: `fg.####.exr`, `fg_####.exr` and `####-fg.exr` are all `fg`. (Up to the
/// first period alone named `fg_####.exr`'s layer `fg_####`, the frame's placeholder and
/// all.) Where two files give one name, or one gives none, every layer is named by its place
/// (`layer1`, …), and the warning returned says so: that fallback was silent.
pub fn file_layer_names(patterns: &[&PathPattern]) -> (Vec<String>, Option<String>) {
    let stems: Vec<String> = (patterns.iter())
        .map(|pattern| {
            let raw = if pattern.is_sequence() {
                pattern.with_hashes()
            } else {
                pattern.raw.clone()
            };
            let path = std::path::Path::new(&raw);
            let name = path.file_name().map_or(String::new(), |n| {
                let name = n.to_string_lossy();
                match pattern.is_sequence() {
                    // The placeholder, as `with_hashes` writes it: the first run of `#`.
                    true => match name.find('#') {
                        Some(at) => {
                            let end = name[at..].find(|c| c != '#').map_or(name.len(), |e| at + e);
                            format!("{}{}", &name[..at], &name[end..])
                        }
                        None => name.to_string(),
                    },
                    false => name.to_string(),
                }
            });
            let separator = |c: char| matches!(c, '_' | '-' | '.' | ' ');
            let name = name.trim_start_matches(separator);
            let stem = name.split('.').next().unwrap_or_default();
            stem.trim_matches(separator).to_string()
        })
        .collect();
    let clash = (0..stems.len()).find(|&i| stems[i].is_empty() || stems[..i].contains(&stems[i]));
    let Some(i) = clash else {
        return (stems, None);
    };
    let names: Vec<String> = (1..=stems.len()).map(|k| format!("layer{k}")).collect();
    let why = if stems[i].is_empty() {
        format!("{} gives no name", patterns[i].raw)
    } else {
        format!("{} and another give the name {}", patterns[i].raw, stems[i])
    };
    let warning = format!(
        "the stack's layers are named {} by their place: {why}; name them with --layers \
         (front first, one name a --color)",
        names.join(", ")
    );
    (names, Some(warning))
}

/// Blurs each layer of `layers` (front first) with `algorithm` and `params` and merges them
/// front over back ([`merge`]).
pub fn process_stack(
    algorithm: Algorithm,
    params: &Params,
    layers: Vec<Frame>,
    frame_number: i64,
    gpu: Option<&Gpu>,
) -> Frame {
    let blurred = layers
        .into_iter()
        .map(|layer| blur_layer(algorithm, params, layer, frame_number, gpu))
        .collect();
    merge(blurred)
}

/// A note when the stack's order looks reversed: a layer that is nearer than a layer given
/// before it (any pair, not only neighbours) over most of the pixels both cover wholly (at
/// least [`ORDER_PIXELS`] of them; nearer by more than [`ORDER_MARGIN`] of the depth, so a
/// surface rendered into both layers is no reversal). The stack merges in the order given,
/// whatever the depths say (README, View layers), so a reversed order hides the foreground;
/// interpenetration over a few pixels (a ground plane under a figure's feet) says nothing.
/// Layers without depth (an algorithm that reads none) are not judged.
pub fn order_note(layers: &[Frame], names: &[String]) -> Option<String> {
    let solid = |f: &Frame, i: usize| {
        let a = f
            .color
            .as_ref()
            .and_then(|c| c.a.as_ref())
            .map_or(1.0, |a| a[i]);
        let z = f.depth.as_ref().map_or(f32::NAN, |d| d[i]);
        (a >= SOLID && z.is_finite() && z < NO_SURFACE).then_some(z)
    };
    let name = |j: usize| names.get(j).map_or("?", String::as_str);
    for (k, front) in layers.iter().enumerate() {
        for (j, back) in layers.iter().enumerate().skip(k + 1) {
            if front.pixel_count() != back.pixel_count() {
                continue;
            }
            let (mut both, mut nearer) = (0usize, 0usize);
            for i in 0..front.pixel_count() {
                if let (Some(zf), Some(zb)) = (solid(front, i), solid(back, i)) {
                    both += 1;
                    nearer += usize::from(zb < zf * (1.0 - ORDER_MARGIN));
                }
            }
            if both >= ORDER_PIXELS && 2 * nearer > both {
                return Some(format!(
                    "view layer {} is nearer than {} in {nearer} of the {both} pixels both \
                     cover, but the stack (front first) merges it behind; is the order \
                     reversed?",
                    name(j),
                    name(k),
                ));
            }
        }
    }
    None
}

/// The fewest pixels two layers must both cover for [`order_note`] to judge their order.
pub const ORDER_PIXELS: usize = 64;

/// How much nearer, as a share of the depth, a later layer must be to count as in front.
pub const ORDER_MARGIN: f32 = 1e-3;

/// One layer through the effects: depth of field with its empty pixels at their nearest
/// surface's depth, then the motion blur with them still and far.
pub fn blur_layer(
    algorithm: Algorithm,
    params: &Params,
    mut layer: Frame,
    frame_number: i64,
    gpu: Option<&Gpu>,
) -> Frame {
    let Some(coverage) = layer.color.as_ref().and_then(|c| c.a.clone()) else {
        // No alpha: the layer covers every pixel, and is a frame like any other.
        return process_on(algorithm, params, layer, frame_number, gpu);
    };
    let surface = surface_pixels(&layer, &coverage, depth_kind(params));
    let nearest = nearest_surface(layer.width, layer.height, &surface);
    let Some(dof) = params.dof else {
        prepare_for_motion(&mut layer, &coverage, (&surface, &nearest), algorithm);
        return process_on(algorithm, params, layer, frame_number, gpu);
    };
    if algorithm == Algorithm::None {
        prepare_for_dof(&mut layer, &coverage, &surface, &nearest);
        return process_on(algorithm, params, layer, frame_number, gpu);
    }
    // Both: the motion's passes wait while depth of field runs on a depth of its own.
    let motion = (
        layer.depth.clone(),
        layer.velocity.take(),
        layer.prev.take(),
        layer.next.take(),
    );
    prepare_for_dof(&mut layer, &coverage, &surface, &nearest);
    let dof_only = Params {
        dof: Some(dof),
        ..*params
    };
    let mut defocused = process_on(Algorithm::None, &dof_only, layer, frame_number, gpu);
    (
        defocused.depth,
        defocused.velocity,
        defocused.prev,
        defocused.next,
    ) = motion;
    prepare_for_motion(&mut defocused, &coverage, (&surface, &nearest), algorithm);
    let motion_only = Params {
        dof: None,
        ..*params
    };
    process_on(algorithm, &motion_only, defocused, frame_number, gpu)
}

/// Which pixels hold a surface of the layer: covered (alpha above 0) and, where there is a
/// depth, one nearer than [`NO_SURFACE`] (a painted CoC map says nothing of that: covered
/// is enough).
pub fn surface_pixels(layer: &Frame, coverage: &[f32], kind: DepthKind) -> Vec<bool> {
    match (&layer.depth, kind) {
        (Some(depth), DepthKind::Depth) => coverage
            .iter()
            .zip(depth)
            .map(|(&a, &z)| a > 0.0 && z < NO_SURFACE)
            .collect(),
        _ => coverage.iter().map(|&a| a > 0.0).collect(),
    }
}

/// For every pixel, the index of the nearest pixel of a surface (Euclidean, to within the
/// propagation's rounding: two raster sweeps over the 8-neighbourhood, each pixel offered
/// its neighbours' nearest), `u32::MAX` where the layer has none.
pub fn nearest_surface(width: usize, height: usize, surface: &[bool]) -> Vec<u32> {
    const NONE: u32 = u32::MAX;
    let mut nearest: Vec<u32> = (0..surface.len())
        .map(|i| if surface[i] { i as u32 } else { NONE })
        .collect();
    let distance = |i: usize, s: u32| -> u64 {
        let (x, y) = ((i % width) as i64, (i / width) as i64);
        let (sx, sy) = ((s as usize % width) as i64, (s as usize / width) as i64);
        ((x - sx).pow(2) + (y - sy).pow(2)) as u64
    };
    let offer = |nearest: &mut Vec<u32>, i: usize, from: usize| {
        let s = nearest[from];
        if s != NONE && (nearest[i] == NONE || distance(i, s) < distance(i, nearest[i])) {
            nearest[i] = s;
        }
    };
    let (w, h) = (width as i64, height as i64);
    for pass in 0..2 {
        // Forward: from the left and the row above; backward: from the right and below.
        let (rows, step): (Vec<i64>, i64) = if pass == 0 {
            ((0..h).collect(), 1)
        } else {
            ((0..h).rev().collect(), -1)
        };
        for y in rows {
            let xs: Vec<i64> = if step == 1 {
                (0..w).collect()
            } else {
                (0..w).rev().collect()
            };
            for &x in &xs {
                let i = (y * w + x) as usize;
                for (dx, dy) in [(-step, 0), (-step, -step), (0, -step), (step, -step)] {
                    let (nx, ny) = (x + dx, y + dy);
                    if (0..w).contains(&nx) && (0..h).contains(&ny) {
                        offer(&mut nearest, i, (ny * w + nx) as usize);
                    }
                }
            }
            // And back along the row, so a surface to the other side reaches this row now.
            for &x in xs.iter().rev() {
                let i = (y * w + x) as usize;
                let nx = x + step;
                if (0..w).contains(&nx) {
                    offer(&mut nearest, i, (y * w + nx) as usize);
                }
            }
        }
    }
    nearest
}

fn within(i: usize, s: u32, width: usize, reach: f32) -> bool {
    let (x, y) = pixel_centre(i, width);
    let (sx, sy) = pixel_centre(s as usize, width);
    (x - sx).powi(2) + (y - sy).powi(2) <= reach * reach
}

/// The motion passes of an empty pixel (still, infinitely far); of a covered pixel with no
/// surface of its own (its nearest surface's within [`EDGE_REACH`], an opaque one's first,
/// else still); and of a pixel at a layer's edge, partly covered, those of the nearest pixel
/// the layer covers wholly within [`EDGE_REACH`], where there is one: a renderer's vectors at
/// an edge are an average over the pixel's samples, the misses' (no motion, or a hidden
/// surface's) among them (Cycles: X, Y of a layer rendered without the background are alpha
/// times the surface's), and a surface moves as its inside next to it does.
///
/// For an algorithm that moves each pixel's colour along that pixel's own motion and nothing
/// else ([`Algorithm::moves_each_pixel_alone`]: scatter) an edge pixel keeps its own motion
/// unless it reads as diluted ([`diluted`]): the colour of an edge pixel whose vector was
/// sampled on the surface (at its centre) moves as that vector says, which on a rotating or
/// zooming surface is not its neighbour's.
/// reconstruct and stretch keep the rule for every edge pixel, because one motion for a
/// surface's pixels measured better, vectors sampled on the surface or not (BENCHMARKS.md,
/// "Edge vectors"). In reconstruct the whole difference comes through the tile grid: an edge
/// pixel's own vector at a rotating blade's tip is the longest of its tile by a hundredth of
/// a pixel, so it flips near-ties of the tiles' longest vectors, and the dilation spreads the
/// new direction over the tiles around, where every pixel's first taps run a few degrees off
/// its own motion, across the blade's stripes (the rotor's stack 0.0812 → 0.0919; with the
/// grid held, the own vectors are neutral). In stretch, an edge pixel's motion decides which
/// vertices move and how far its triangles reach.
pub fn prepare_for_motion(
    layer: &mut Frame,
    coverage: &[f32],
    (surface, nearest): (&[bool], &[u32]),
    algorithm: Algorithm,
) {
    let own_edges = algorithm.moves_each_pixel_alone();
    let (width, n) = (layer.width, coverage.len());
    let solid: Vec<bool> = (0..n).map(|i| surface[i] && coverage[i] >= SOLID).collect();
    let nearest_solid = nearest_surface(width, layer.height, &solid);
    let near =
        |i: usize, s: u32| (s != u32::MAX && within(i, s, width, EDGE_REACH)).then_some(s as usize);
    // The edges first, from pixels nothing changes; then the rest, from those.
    for i in (0..n).filter(|&i| surface[i] && !solid[i]) {
        let edge = near(i, nearest_solid[i]);
        if let Some(s) = edge.filter(|&s| !own_edges || diluted(layer, i, s, coverage[i])) {
            copy_motion(layer, i, Some(s), false);
        }
    }
    for i in (0..n).filter(|&i| !surface[i]) {
        let from = (coverage[i] > 0.0)
            .then(|| near(i, nearest_solid[i]).or_else(|| near(i, nearest[i])))
            .flatten();
        copy_motion(layer, i, from, true);
    }
}

/// Whether the motion of edge pixel `i` (covered `alpha`) reads as diluted by its misses:
/// nearer `alpha` times the motion of the wholly covered pixel `s` beside it than that motion
/// itself, summed over the passes it has (velocity, previous and next positions). A renderer
/// that averages its samples' vectors with the misses' zero writes the former (Cycles'
/// transparent film); one that samples the surface at the pixel centre (the truth scenes, a
/// depth-sampled vector pass) writes the pixel's own motion. A still neighbour, or a tie,
/// says the pixel's own.
fn diluted(layer: &Frame, i: usize, s: usize, alpha: f32) -> bool {
    let ((x, y), (sx, sy)) = (pixel_centre(i, layer.width), pixel_centre(s, layer.width));
    let velocity = layer
        .velocity
        .as_ref()
        .map(|v| [(v.x[i], v.y[i]), (v.x[s], v.y[s])]);
    let positions = [layer.prev.as_ref(), layer.next.as_ref()]
        .into_iter()
        .flatten()
        .map(|p| [(p.x[i] - x, p.y[i] - y), (p.x[s] - sx, p.y[s] - sy)]);
    let (mut to_diluted, mut to_own) = (0.0f64, 0.0f64);
    for [(vx, vy), (ux, uy)] in velocity.into_iter().chain(positions) {
        let off = |k: f32| {
            let (ex, ey) = (
                f64::from(vx) - f64::from(k * ux),
                f64::from(vy) - f64::from(k * uy),
            );
            ex * ex + ey * ey
        };
        to_diluted += off(alpha);
        to_own += off(1.0);
    }
    to_diluted < to_own
}

/// Pixels a layer covers at least this much are wholly its surface (alpha 1 to rounding).
const SOLID: f32 = 0.999;

/// Gives pixel `i` the motion of pixel `from` (its displacement, from `i`), and its depth
/// when `depth`; `None`: still and infinitely far.
fn copy_motion(layer: &mut Frame, i: usize, from: Option<usize>, depth: bool) {
    let width = layer.width;
    if let (true, Some(plane)) = (depth, layer.depth.as_mut()) {
        plane[i] = from.map_or(f32::INFINITY, |s| plane[s]);
    }
    if let Some(v) = layer.velocity.as_mut() {
        (v.x[i], v.y[i]) = from.map_or((0.0, 0.0), |s| (v.x[s], v.y[s]));
    }
    let (x, y) = pixel_centre(i, width);
    for positions in [layer.prev.as_mut(), layer.next.as_mut()]
        .into_iter()
        .flatten()
    {
        match from {
            Some(s) => {
                let (sx, sy) = pixel_centre(s, width);
                positions.x[i] = positions.x[s] - sx + x;
                positions.y[i] = positions.y[s] - sy + y;
                if let Some(z) = positions.z.as_mut() {
                    z[i] = z[s];
                }
            }
            None => {
                positions.x[i] = x;
                positions.y[i] = y;
                if let Some(z) = positions.z.as_mut() {
                    z[i] = f32::INFINITY;
                }
            }
        }
    }
}

/// The depth depth of field reads: every pixel that is not a surface takes its nearest
/// surface's (infinitely far where the layer has none).
pub fn prepare_for_dof(layer: &mut Frame, _coverage: &[f32], surface: &[bool], nearest: &[u32]) {
    if let Some(depth) = layer.depth.as_mut() {
        for i in 0..surface.len() {
            if !surface[i] {
                depth[i] = match nearest[i] {
                    u32::MAX => f32::INFINITY,
                    s => depth[s as usize],
                };
            }
        }
    }
}

/// Merges blurred layers, front first, front over back (premultiplied: what a layer lets
/// through is 1 − its alpha, clamped to 0..1). The merged frame is the first layer's frame
/// with the merged colour as its beauty (an EXR output names it [`MERGED`]); each layer's own
/// blurred beauty and the channels it carried go out beside it, under their names.
pub fn merge(layers: Vec<Frame>) -> Frame {
    let like = merged_like(&layers);
    let mut layers = layers.into_iter();
    let Some(mut merged) = layers.next() else {
        return Frame::new(0, 0);
    };
    let mut channels = Vec::new();
    let Some(front) = merged.color.take() else {
        return merged;
    };
    channels.extend(beauty_channels(&merged, &front));
    let mut color = front;
    let n = merged.width * merged.height;
    let mut alpha = color.a.take().unwrap_or_else(|| vec![1.0; n]);
    channels.append(&mut merged.carried.channels);
    for mut layer in layers {
        let Some(behind) = layer.color.take() else {
            continue;
        };
        channels.extend(beauty_channels(&layer, &behind));
        channels.append(&mut layer.carried.channels);
        over(&mut color, &mut alpha, &behind);
    }
    color.a = Some(alpha);
    merged.color = Some(color);
    merged.carried.beauty = MERGED.map(String::from).to_vec();
    merged.carried.beauty_stored = merged.carried.beauty.clone();
    merged.carried.merged = true;
    merged.carried.merged_like = like;
    // A channel of the file under the merged beauty's names is the one it replaces.
    channels.retain(|c| !MERGED.contains(&c.name.as_str()));
    merged.carried.channels = channels;
    merged
}

/// For each channel of the merged beauty (R, G, B, A), the first layer's name for it, where
/// every layer stores that channel of its beauty in one pixel type (as its colour part's header
/// says): the merged beauty is written in it, so layers all in half make a half merge. It went
/// out in float whatever the layers were, named as no channel of the part it is made like.
fn merged_like(layers: &[Frame]) -> Vec<Option<String>> {
    let type_of = |layer: &Frame, k: usize| {
        let carried = &layer.carried;
        let name = carried.beauty_stored.get(k)?;
        let header = carried.headers.get(carried.colour_part)?;
        // A layer of a file of its own is named by the stack (`name_layer`: `fg.R` of `R`).
        let unnamed = name.split_once('.').map_or(name.as_str(), |(_, rest)| rest);
        let found = [name.as_str(), unnamed].into_iter().find_map(|n| {
            (header.channels.list.iter()).find(|c| crate::io::channels::name_of(&c.name) == n)
        })?;
        Some((crate::io::channels::name_of(&found.name), found.sample_type))
    };
    (0..MERGED.len())
        .map(|k| {
            let (name, kind) = type_of(layers.first()?, k)?;
            (layers.iter().skip(1))
                .all(|l| type_of(l, k).is_some_and(|(_, t)| t == kind))
                .then_some(name)
        })
        .collect()
}

/// `behind` under what is merged so far (`color`, `alpha`).
fn over(color: &mut Color, alpha: &mut Plane, behind: &Color) {
    let through: Vec<f32> = alpha.iter().map(|&a| 1.0 - a.clamp(0.0, 1.0)).collect();
    for (front, back) in [
        (&mut color.r, &behind.r),
        (&mut color.g, &behind.g),
        (&mut color.b, &behind.b),
    ] {
        for ((f, &b), &t) in front.iter_mut().zip(back).zip(&through) {
            *f += t * b;
        }
    }
    for (i, (a, &t)) in alpha.iter_mut().zip(&through).enumerate() {
        *a += t * behind.a.as_ref().map_or(1.0, |b| b[i]);
    }
}

/// Names a layer read from a file of its own `name` in the output: its beauty (`name.R`,
/// unless the file names it under `name.` already: `FG.Combined.R`) and every channel it
/// carries (`name.diffuse.R`).
pub fn name_layer(layer: &mut Frame, name: &str) {
    let prefix = format!("{name}.");
    let named = |n: &String| {
        if n.starts_with(&prefix) {
            n.clone()
        } else {
            format!("{prefix}{n}")
        }
    };
    let planes = layer.color.as_ref().map_or(0, |c| c.planes().len());
    let carried = &mut layer.carried;
    if carried.beauty.len() != planes {
        carried.beauty = MERGED[..planes].iter().map(|n| n.to_string()).collect();
        carried.beauty_stored = carried.beauty.clone();
    }
    carried.beauty = carried.beauty.iter().map(named).collect();
    carried.beauty_stored = carried.beauty_stored.iter().map(named).collect();
    for channel in &mut carried.channels {
        channel.name = named(&channel.name);
        channel.stored = named(&channel.stored);
    }
}

/// A layer's own blurred beauty as channels beside the merged one, under the names it had
/// (`FG.Combined.R`); none when it had no layer's names (a picture, or plain R, G, B: the
/// merged beauty takes those).
fn beauty_channels(layer: &Frame, color: &Color) -> Vec<CarriedChannel> {
    let carried = &layer.carried;
    let planes = color.planes();
    let names = &carried.beauty;
    let distinct = (1..names.len()).all(|i| !names[..i].contains(&names[i]));
    if names.len() != planes.len() || !distinct || names.iter().any(|n| !n.contains('.')) {
        return Vec::new();
    }
    (carried.beauty.iter().zip(&carried.beauty_stored))
        .zip(planes)
        .map(|((name, stored), plane)| CarriedChannel {
            name: name.clone(),
            stored: stored.clone(),
            shared: false,
            part: carried.colour_part,
            class: LayerClass::Colour,
            plane: plane.to_vec(),
            exact: None,
            window: None,
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Velocity;

    #[test]
    fn the_nearest_surface_is_found_across_the_frame_both_ways() {
        // 7×3, surfaces at (1, 0) and (6, 2).
        let (w, h) = (7, 3);
        let mut surface = vec![false; w * h];
        surface[1] = true;
        surface[2 * w + 6] = true;
        let nearest = nearest_surface(w, h, &surface);
        // (0, 2): (1, 0) is √5 away, (6, 2) 6.
        assert_eq!(nearest[2 * w], 1);
        // (5, 0): (6, 2) is √5 away, (1, 0) 4.
        assert_eq!(nearest[5], (2 * w + 6) as u32);
        // Each surface is its own.
        assert_eq!(nearest[1], 1);
        assert!(nearest_surface(2, 2, &[false; 4])
            .iter()
            .all(|&s| s == u32::MAX));
    }

    /// A 3×1 layer: a solid pixel moving (4, 0) px a frame, an edge pixel 0.6 covered with
    /// motion `edge`, an empty pixel. The edge pixel's motion after [`prepare_for_motion`].
    fn edge_motion_after(edge: (f32, f32), algorithm: Algorithm) -> (f32, f32) {
        let mut layer = Frame::new(3, 1);
        let coverage = vec![1.0, 0.6, 0.0];
        layer.depth = Some(vec![2.0, 2.0, NO_SURFACE * 10.0]);
        layer.velocity = Some(Velocity {
            x: vec![4.0, edge.0, 0.0],
            y: vec![0.0, edge.1, 0.0],
        });
        let surface = surface_pixels(&layer, &coverage, DepthKind::Depth);
        let nearest = nearest_surface(3, 1, &surface);
        prepare_for_motion(&mut layer, &coverage, (&surface, &nearest), algorithm);
        let v = layer.velocity.unwrap();
        (v.x[1], v.y[1])
    }

    #[test]
    fn scatter_keeps_an_edge_pixel_s_own_motion_unless_its_misses_diluted_it() {
        // Sampled on the surface (a rotating one: not quite the neighbour's): kept.
        assert_eq!(
            edge_motion_after((4.3, 0.5), Algorithm::Scatter),
            (4.3, 0.5)
        );
        // 0.6 of the neighbour's (Cycles' average with the misses' zero): the neighbour's.
        assert_eq!(
            edge_motion_after((2.4, 0.0), Algorithm::Scatter),
            (4.0, 0.0)
        );
        // reconstruct and stretch take the neighbour's either way.
        for algorithm in [Algorithm::Reconstruct, Algorithm::Stretch] {
            assert_eq!(edge_motion_after((4.3, 0.5), algorithm), (4.0, 0.0));
            assert_eq!(edge_motion_after((2.4, 0.0), algorithm), (4.0, 0.0));
        }
    }
}
