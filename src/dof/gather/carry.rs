//! The carried planes of the bokeh gather ([`super::gather_carrying`]: light layers beside
//! the beauty): each tile row's weights, kept by the beauty's loop ([`super::run::gather_run`]),
//! folded into one weight a tap and lane ([`fold`]), and applied to every carried plane a
//! tile at a time ([`carry_tile`]), a fused multiply-add a tap, lane and plane.
//!
//! Measured (the `dof` bench frame at 1080p with six RGB light layers, BENCHMARKS.md "Light
//! layers"): the carried loop waits on its reads, 18 planes' samples a tap, not on its
//! arithmetic. One weight a tap instead of a far and a near sum and a composite, a tile's
//! rows at a time in groups of three planes (so that a group's neighbourhood of the tile
//! stays in L1), and the frame's own planes read instead of padded copies took six layers
//! from about 3.5× the beauty to 2.7× (the bench row's medians); the bound asked, 1.5×, is
//! not reached: the carried loop alone still costs about the beauty's whole gather.

use super::run::{counts, Fields, Padded, Row, RowWeights};
use crate::dof::tiles::TILE;

/// A tile row's lanes.
type Lanes = [f32; TILE];

/// A tile row's weights as the carried planes apply them ([`fold`]): each pixel's output is
/// `centre × c + Σ w × s` over the taps, in order, `c` the pixel's own sample and `s` each
/// tap's (each tap its step in the planes [`carry_tile`] reads, [`TileCopy::origin`]).
#[derive(Default)]
pub(super) struct Folded {
    pub(super) centre: Lanes,
    pub(super) taps: Vec<(isize, Lanes)>,
    /// The taps that read the far taps' prefilter level and those that read the taps' level
    /// ([`super::run::Level`]; empty where they read the planes themselves).
    pub(super) far_level: Vec<(isize, Lanes)>,
    pub(super) level: Vec<(isize, Lanes)>,
}

/// Folds the weights [`super::run::gather_run`] kept for a tile row into one weight a tap and lane, the
/// composite's scales taken into them: the beauty's `c + near_scale × Σ wn (s − c) +
/// far_scale × Σ wf (s − c)`, with the dense grid's far field in its lanes instead of the
/// rings', is `far_scale × ia_c × c + Σ near_scale × wn × s + Σ far_scale × wf × s` (the
/// pixel's own weight is `1 − Σ` of the others: `far_scale × ia_c`, its 1 / bokeh area
/// scaled). Each carried plane then takes a multiply-add a tap, on its raw samples. The same
/// weights as the beauty's, summed in another form: a plane comes out within rounding of what
/// it gets in the beauty's place, not with the same bits. Lanes past `span` weigh nothing, and
/// so does a tap outside the frame (its 1 / bokeh area is 0). Steps are in planes of row length
/// `stride`.
pub(super) fn fold(
    padded: &Padded,
    row: &Row,
    weights: &RowWeights,
    stride: usize,
    folded: &mut Folded,
) {
    let (start, span) = (row.start, row.span);
    let ia = &padded.planes[5];
    let radius = &padded.planes[4];
    let mut near = [0.0f32; TILE];
    let mut ring = [0.0f32; TILE];
    let mut dense = [0.0f32; TILE];
    let mut centre = [0.0f32; TILE];
    // Lanes whose own sample is the far level's box (as in `gather_run`), its weight.
    let mut boxed = [0.0f32; TILE];
    for x in 0..span {
        let far = weights.far_scale[x];
        near[x] = weights.near_scale[x];
        if weights.dense_lanes[x] {
            dense[x] = far;
        } else {
            ring[x] = far;
        }
        if row.far_level && radius[start + x].abs() > row.small {
            boxed[x] = far * row.far_planes[5][start + x];
        } else {
            centre[x] = far * ia[start + x];
        }
    }
    folded.centre = centre;
    folded.taps.clear();
    folded.far_level.clear();
    folded.level.clear();
    let stride = stride as isize;
    // Where a tap's weight goes: 0 the planes themselves, 1 the far level, 2 the taps' level.
    let mut push = |to: usize, (dx, dy): (i32, i32), w: Lanes| {
        if counts(&w) {
            let list = match to {
                1 => &mut folded.far_level,
                2 => &mut folded.level,
                _ => &mut folded.taps,
            };
            list.push((dy as isize * stride + dx as isize, w));
        }
    };
    let far_to = if row.far_level { 1 } else { 0 };
    let main_to = if row.level { 2 } else { 0 };
    push(far_to, (0, 0), boxed);
    let scaled = |scale: &Lanes, w: &Lanes| -> Lanes { std::array::from_fn(|x| scale[x] * w[x]) };
    if row.fields == Fields::Both {
        // One list of taps, each lane's weight far or near (the other 0).
        for ((offset, wf), (_, wn)) in weights.far.iter().zip(&weights.near) {
            push(
                main_to,
                *offset,
                std::array::from_fn(|x| ring[x] * wf[x] + near[x] * wn[x]),
            );
        }
    } else {
        for (offset, wf) in &weights.far {
            push(far_to, *offset, scaled(&ring, wf));
        }
        for (offset, wn) in &weights.near {
            push(main_to, *offset, scaled(&near, wn));
        }
    }
    for (offset, wf) in &weights.dense {
        push(0, *offset, scaled(&dense, wf));
    }
}

/// A tile's neighbourhood in the carried planes: `rows` tile rows of [`TILE`] lanes from
/// (x0, y0), and `reach` px around them, each plane copied into `reach`-padded rows of
/// `stride` = TILE + 2 × reach values (0 outside the frame, where every weight is 0): a
/// plane's taps over the tile then read a few KiB of a few pages, not a run of every
/// padded frame row they touch.
pub(super) struct TileCopy {
    pub(super) x0: usize,
    pub(super) y0: usize,
    pub(super) rows: usize,
    pub(super) reach: usize,
    /// Whether the taps read the frame's own planes (the tile's neighbourhood inside it).
    pub(super) direct: bool,
}

impl TileCopy {
    pub(super) fn stride(&self) -> usize {
        TILE + 2 * self.reach
    }

    /// Whether the tile's neighbourhood lies inside a frame of `width` × `height`: its taps
    /// can then read the frame's own planes (row length `width`), not a copy.
    pub(super) fn inside(&self, (width, height): (usize, usize)) -> bool {
        self.x0 >= self.reach
            && self.y0 >= self.reach
            && self.x0 + TILE + self.reach <= width
            && self.y0 + self.rows + self.reach <= height
    }

    /// Where the tile's first pixel is in the planes its taps read, and their row length: the
    /// frame's (of row length `width`) where [`TileCopy::direct`], its copy's elsewhere.
    pub(super) fn origin(&self, width: usize) -> (usize, usize) {
        if self.direct {
            (self.y0 * width + self.x0, width)
        } else {
            (self.reach * self.stride() + self.reach, self.stride())
        }
    }

    fn len(&self) -> usize {
        (self.rows + 2 * self.reach) * self.stride()
    }

    /// Copies the tile's neighbourhood of `plane` (a frame of `width` × `height`) into `out`.
    fn copy(&self, plane: &[f32], (width, height): (usize, usize), out: &mut [f32]) {
        let stride = self.stride();
        for (ly, row) in out.chunks_exact_mut(stride).enumerate() {
            let y = (self.y0 + ly) as isize - self.reach as isize;
            if y < 0 || y >= height as isize {
                row.fill(0.0);
                continue;
            }
            let x_first = self.x0 as isize - self.reach as isize;
            let from = x_first.max(0) as usize;
            let to = (self.x0 + TILE + self.reach).min(width);
            let lead = (from as isize - x_first) as usize;
            let source = &plane[y as usize * width..];
            row[..lead].fill(0.0);
            row[lead..lead + to - from].copy_from_slice(&source[from..to]);
            row[lead + to - from..].fill(0.0);
        }
    }
}

/// The tile row's lanes of `plane` from index `base`.
#[inline(always)]
fn lanes(plane: &[f32], base: usize) -> &Lanes {
    plane[base..]
        .first_chunk::<TILE>()
        .expect("the tile copy holds every tap of a tile row")
}

/// N carried planes' tile copies over the tile's rows with their [`Folded`] weights: a fused
/// multiply-add a tap and lane, the sums handed from tap to tap as values so that they stay
/// in registers. `out[k][row]` is plane k's row.
#[inline(always)]
fn carry_group<const N: usize>(
    planes: [[&[f32]; N]; 3],
    (origin, stride): (usize, usize),
    folded: &[Folded],
    out: &mut [Vec<Lanes>],
) {
    for (ly, row) in folded.iter().enumerate() {
        let start = origin + ly * stride;
        let mut acc = planes[0].map(|plane| {
            let c = lanes(plane, start);
            let v: Lanes = std::array::from_fn(|x| row.centre[x] * c[x]);
            v
        });
        // The taps over the planes themselves, then those over the levels.
        for (set, taps) in [&row.taps, &row.far_level, &row.level]
            .into_iter()
            .enumerate()
        {
            for (step, w) in taps {
                let base = (start as isize + step) as usize;
                for k in 0..N {
                    let s = lanes(planes[set][k], base);
                    let mut v = acc[k];
                    for x in 0..TILE {
                        v[x] = w[x].mul_add(s[x], v[x]);
                    }
                    acc[k] = v;
                }
            }
        }
        for (o, a) in out.iter_mut().zip(acc) {
            o[ly] = a;
        }
    }
}

/// Most carried planes [`carry_tile`] sums in one pass over a tile's taps. Fewer planes a
/// pass read a tile's weights more often but keep their samples nearer: on the `dof` bench
/// frame with six RGB light layers, passes of two, three, four, six and nine planes, three of
/// them was the fastest; and by the worst case over that frame, the same at f/5.6 (CoCs a
/// quarter as large) and one with a single column of blocks out of focus, three again
/// (worst 3.12× the beauty, against 3.22× for two and 3.75× for four; BENCHMARKS.md,
/// "Light layers").
const MOST_PLANES: usize = 3;

/// The carried planes (the frame's own, `width` × `height`) over one tile ([`TileCopy`]),
/// with the [`Folded`] weights of each of its rows, into `out` (a tile's rows a plane). The
/// planes go in groups of at most [`MOST_PLANES`], as even as they split, each group one
/// pass over the tile's rows and taps, read from the frame's planes where the tile's
/// neighbourhood lies inside the frame and from copies made in `scratch` elsewhere.
///
/// Compiled for AVX-512 and for AVX2 with FMA beside the baseline: `mul_add` is correctly
/// rounded on every one (the baseline calls libm's `fmaf`), so every machine and thread
/// count gives the same bits.
#[multiversion::multiversion(targets("x86_64+avx512f+avx512vl+fma", "x86_64+avx2+fma"))]
pub(super) fn carry_tile(
    planes: [&[Vec<f32>]; 3],
    size: (usize, usize),
    tile: &TileCopy,
    folded: &[Folded],
    scratch: &mut Vec<f32>,
    out: &mut [Vec<Lanes>],
) {
    let count = planes[0].len();
    let groups = count.div_ceil(MOST_PLANES);
    let len = tile.len();
    let at = tile.origin(size.0);
    // Which of the three sets the tile's taps read (a level's planes are empty where no tap
    // reads it: the planes themselves stand in).
    let used: [bool; 3] = std::array::from_fn(|set| {
        set == 0
            || folded
                .iter()
                .any(|row| !(if set == 1 { &row.far_level } else { &row.level }).is_empty())
    });
    let mut from = 0;
    for g in 0..groups {
        // The first `count % groups` groups take one plane more.
        let n = count / groups + usize::from(g < count % groups);
        if !tile.direct {
            scratch.resize(3 * n * len, 0.0);
            for set in 0..3 {
                if used[set] {
                    for k in 0..n {
                        let copy = &mut scratch[(set * n + k) * len..(set * n + k + 1) * len];
                        tile.copy(&planes[set][from + k], size, copy);
                    }
                }
            }
        }
        let read = |set: usize, k: usize| -> &[f32] {
            let set = if used[set] { set } else { 0 };
            if tile.direct {
                &planes[set][from + k]
            } else {
                &scratch[(set * n + k) * len..(set * n + k + 1) * len]
            }
        };
        let outs = &mut out[from..from + n];
        match n {
            1 => carry_group([0, 1, 2].map(|s| [read(s, 0)]), at, folded, outs),
            2 => carry_group(
                [0, 1, 2].map(|s| [read(s, 0), read(s, 1)]),
                at,
                folded,
                outs,
            ),
            _ => carry_group(
                [0, 1, 2].map(|s| [read(s, 0), read(s, 1), read(s, 2)]),
                at,
                folded,
                outs,
            ),
        }
        from += n;
    }
}

#[cfg(test)]
mod tests {
    use crate::dof::gather::{gather, gather_carrying, plan};
    use crate::dof::tiles::{tiles, Tiles, TilesConfig};
    use crate::dof::{DofConfig, DofParams};
    use crate::frame::Color;
    use crate::numeric::close;

    /// A frame with tiles of every kind (far field alone, both fields, fields apart, copied):
    /// a near disc over a far texture with a band in focus. Its colour (alpha included), its
    /// signed CoC, its tiles, its config, and a wave of frequency `k` as a plane.
    fn every_kind() -> (DofConfig, Color, Vec<f32>, Tiles, impl Fn(f32) -> Vec<f32>) {
        let (w, h) = (192, 96);
        let disc = |x: usize, y: usize| {
            let (dx, dy) = (x as f32 - 40.0, y as f32 - 48.0);
            dx * dx + dy * dy < 18.0 * 18.0
        };
        let coc: Vec<f32> = (0..w * h)
            .map(|i| match (i % w, i / w) {
                (x, y) if disc(x, y) => -40.0,
                (x, _) if x > 150 => 0.2,
                _ => 9.0,
            })
            .collect();
        let wave = move |k: f32| -> Vec<f32> { (0..w * h).map(|i| (i as f32 * k).sin()).collect() };
        let color = Color {
            r: wave(0.37),
            g: wave(0.21),
            b: wave(0.05),
            a: Some(wave(0.013)),
        };
        let config = DofConfig::new(w, h, &DofParams::default());
        let t = tiles(&TilesConfig::new(w, h, config.epsilon), &coc);
        let kinds: std::collections::BTreeSet<u32> =
            plan(&config, &t).tiles.iter().map(|t| t.fields).collect();
        assert_eq!(kinds, [0, 1, 2, 3].into());
        (config, color, coc, t, wave)
    }

    /// How far a carried plane may lie from what it gets gathered alone in the beauty's place,
    /// as a share of the plane's largest magnitude. Both are the same weighted average (the
    /// weights are the beauty's, ≥ 0, summing to 1), summed in two forms: the beauty's
    /// `c + near_scale × Σ wn (s − c) + far_scale × Σ wf (s − c)`, and the carried planes'
    /// `Σ W s` with each tap's weight scaled first and fused multiply-adds ([`super::fold`]).
    /// Each form rounds once or twice a tap, and the errors of up to a few hundred taps, each
    /// under half an ulp of the largest term, mostly cancel: measured here at most 6.9 ulps
    /// of 1 (8.2e-7; every group size, the weights of 20 px bokehs), and on the `dof` bench
    /// frame at 1080p (16 px bokehs, values up to 1) 2.2e-6, RMS 3.3e-7. 32 ulps (3.8e-6)
    /// still fails a wrong weight or sample (adding 1e-3 to the samples of the copied tiles
    /// fails it, as does reading a pixel to the side).
    const CARRIED_TOLERANCE: f32 = 32.0 * f32::EPSILON;

    #[test]
    fn carried_planes_get_the_beautys_weights() {
        // Carried planes, from one to thirteen (one group to two), must come out as each does
        // gathered alone as the beauty's red within rounding (`CARRIED_TOLERANCE` of the
        // plane's largest magnitude), and the beauty as it does with nothing carried, bit for
        // bit.
        let (config, color, coc, t, wave) = every_kind();
        let extra: Vec<Vec<f32>> = [
            0.11, 0.07, 0.5, 0.9, 0.003, 0.23, 0.61, 0.019, 0.33, 0.8, 0.041, 0.17, 0.29,
        ]
        .map(wave)
        .into();
        let bits = |plane: &[f32]| plane.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        let alone: Vec<Vec<f32>> = extra
            .iter()
            .map(|plane| {
                let alone = Color {
                    r: plane.clone(),
                    ..color.clone()
                };
                let want = gather(&config, &alone, &coc, &t).r;
                assert_ne!(bits(&want), bits(plane));
                want
            })
            .collect();
        let beauty_alone = gather(&config, &color, &coc, &t);
        // Every group size `carry_tile` has a loop for (one to three planes), and counts that
        // split into several groups: four (two and two), seven (three, two and two), thirteen
        // (three, three, three, two and two).
        for count in [1, 2, 3, 4, 5, 7, 13] {
            let planes = extra[..count].to_vec();
            let (beauty, carried) = gather_carrying(&config, &color, &coc, &t, planes);
            assert_eq!(beauty, beauty_alone);
            assert_eq!(carried.len(), count);
            for (k, (got, want)) in carried.iter().zip(&alone).enumerate() {
                let largest = extra[k].iter().fold(0.0f32, |m, v| m.max(v.abs()));
                for (i, (g, w)) in got.iter().zip(want).enumerate() {
                    assert!(
                        close(*g, *w, CARRIED_TOLERANCE * largest),
                        "{count} planes: plane {k}, pixel {i}: {g} carried, {w} alone"
                    );
                }
            }
        }
    }

    #[test]
    fn a_beauty_that_is_the_sum_of_its_light_layers_still_is_after_the_blur() {
        // Issue 29: the beauty's red is the sum of three layers' reds, and after the gather
        // the carried layers still add up to the beauty's red, within rounding: the layers
        // take the beauty's weights, and the gather is linear in its colours.
        let (config, mut color, coc, t, wave) = every_kind();
        let layers: Vec<Vec<f32>> = [0.11, 0.07, 0.5].map(wave).into();
        let scaled: Vec<Vec<f32>> = layers
            .iter()
            .zip([0.2f32, 3.0, 0.05])
            .map(|(l, s)| l.iter().map(|v| v * s + 1.0).collect())
            .collect();
        color.r = (0..color.r.len())
            .map(|i| scaled[0][i] + scaled[1][i] + scaled[2][i])
            .collect();
        let (beauty, carried) = gather_carrying(&config, &color, &coc, &t, scaled.clone());
        let largest = color.r.iter().fold(0.0f32, |m, v| m.max(v.abs()));
        for (i, &r) in beauty.r.iter().enumerate() {
            let sum = carried[0][i] + carried[1][i] + carried[2][i];
            assert!(
                close(sum, r, CARRIED_TOLERANCE * largest),
                "pixel {i}: the layers add up to {sum}, the beauty is {r}"
            );
        }
    }

    #[test]
    fn carried_planes_are_the_same_bits_on_one_thread_and_two() {
        // The determinism rule: the carried planes' fused multiply-adds are correctly rounded
        // on every machine, and each tile row is summed by one thread in a fixed order.
        let (config, color, coc, t, wave) = every_kind();
        let extra: Vec<Vec<f32>> = [0.11, 0.07, 0.5, 0.9, 0.003, 0.23, 0.61].map(wave).into();
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("a thread pool");
            pool.install(|| gather_carrying(&config, &color, &coc, &t, extra.clone()))
        };
        let bits = |(beauty, carried): (Color, Vec<Vec<f32>>)| {
            let mut all = vec![beauty.r, beauty.g, beauty.b, beauty.a.unwrap_or_default()];
            all.extend(carried);
            all.iter()
                .map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(run(1)), bits(run(2)));
    }
}
