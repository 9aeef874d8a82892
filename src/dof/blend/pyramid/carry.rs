//! Planes the pyramid carries beside the beauty (light layers' R, G and B): each blurred with
//! the beauty's weights, as it would be alone in the beauty's place, bit for bit.
//!
//! In: the carried planes, the beauty's [`Source`] (its CoC and constants) and what the
//! beauty's compose stage made for the frame row (its [`Scratch`]: each pixel's blurriness,
//! the levels' rows with their w). Out: each plane blurred, written in place like the
//! beauty. It runs inside the pyramid's compose bands ([`super::blend_carrying`]), after the
//! beauty's row.
//!
//! Everything that depends on the CoC alone is the beauty's, made once: the plan (E, the
//! levels, the ladders, where T_near is read), each texel's w and T_near, each pixel's
//! blurriness and the near field's spread, the levels a row needs, each pixel's bracket,
//! disc and mix, and the divisor of each level row and of each level disc. A plane adds only its own
//! lanes: premultiplied by w and halved into its levels, divided by the beauty's w, and
//! mixed. The planes go eight to a texel (a [`Group`]), so every level of theirs is made by
//! the beauty's own halving code, lane for lane. Each lane sees the operations it would see
//! as a colour channel of the beauty in the same order (offset by its own reference, the
//! plane's first sample, as a layer alone would be), so the bits are the same: the tests
//! hold each layer to `blend` run on it alone.

use rayon::prelude::*;

use super::compose::{lerp, Sampler, Scratch};
use super::disc::{frame_disc, kernel, level_disc, DiscRows, Kernel};
use super::levels::{halve_levels, halve_plane_row, Ladder, Level, Source, Texel, BAND, ZERO};

/// Carried planes a texel holds.
pub(super) const GROUP: usize = 8;

/// Up to [`GROUP`] carried planes: their references (each plane's first sample; 0 in the
/// lanes no plane fills) and their levels 1 ..= L, whose texels hold a lane a plane.
pub(super) struct Group {
    pub(super) lanes: usize,
    reference: Texel,
    levels: Vec<Level>,
}

impl Group {
    /// Each plane's reference (its first sample), a lane each.
    pub(super) fn reference(&self) -> &Texel {
        &self.reference
    }

    /// The group of `planes` (at most [`GROUP`]), its `count` levels made.
    pub(super) fn new(
        source: &Source,
        planes: &[Vec<f32>],
        width: usize,
        height: usize,
        count: usize,
    ) -> Self {
        assert!(!planes.is_empty() && planes.len() <= GROUP);
        let mut reference = ZERO;
        for (r, p) in reference.iter_mut().zip(planes) {
            *r = p[0];
        }
        let planes: Vec<&[f32]> = planes.iter().map(Vec::as_slice).collect();
        let (w2, h2) = (width.div_ceil(2), height.div_ceil(2));
        let mut texels = vec![ZERO; w2 * h2];
        texels.par_chunks_mut(w2 * BAND).enumerate().for_each_init(
            FirstScratch::default,
            |s, (band, out)| {
                let rows = Rows {
                    source,
                    planes: &planes,
                    reference: &reference,
                    width,
                };
                first_level_band(&rows, height, band, out, s)
            },
        );
        let mut levels = vec![Level {
            width: w2,
            height: h2,
            texels,
        }];
        halve_levels(&mut levels, count);
        Group {
            lanes: planes.len(),
            reference,
            levels,
        }
    }
}

/// What a level-1 row of a group is made from.
struct Rows<'a> {
    source: &'a Source<'a>,
    planes: &'a [&'a [f32]],
    reference: &'a Texel,
    width: usize,
}

/// A level-1 task's buffers, as the beauty's (`levels::FirstScratch`).
#[derive(Default)]
struct FirstScratch {
    w: Vec<f32>,
    channel: Vec<f32>,
    rows: Vec<f32>,
    down: Vec<f32>,
}

/// Frame row y of the group premultiplied by w and halved across, as [`GROUP`] planes of
/// `out.len() / GROUP` texels: the beauty's colour lanes' sums (`levels::first_row`).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn first_row(rows: &Rows, y: usize, out: &mut [f32], s: &mut FirstScratch) {
    let width = rows.width;
    let w2 = out.len() / GROUP;
    let span = y * width..(y + 1) * width;
    let coc = &rows.source.coc[span.clone()];
    s.w.resize(width, 0.0);
    s.channel.resize(width, 0.0);
    for (w, &c) in s.w.iter_mut().zip(coc) {
        *w = rows.source.weight(c);
    }
    for (lane, out) in out.chunks_mut(w2).enumerate() {
        match rows.planes.get(lane) {
            Some(plane) => {
                let reference = rows.reference[lane];
                for ((o, v), w) in s.channel.iter_mut().zip(&plane[span.clone()]).zip(&s.w) {
                    *o = (v - reference) * w;
                }
                halve_plane_row(&s.channel, out);
            }
            None => out.fill(0.0),
        }
    }
}

/// A band of level 1 of the group: rows halved across, halved down, gathered into texels
/// (`levels::first_level_band`'s sums, over [`GROUP`] lanes).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn first_level_band(
    source: &Rows,
    height: usize,
    band: usize,
    out: &mut [Texel],
    s: &mut FirstScratch,
) {
    let w2 = source.width.div_ceil(2);
    let count = out.len() / w2;
    let last = height as isize - 1;
    let first = (2 * band * BAND) as isize - 1;
    let needed = 2 * count + 2;
    let stride = GROUP * w2;
    let mut rows = std::mem::take(&mut s.rows);
    rows.resize(needed * stride, 0.0);
    for (r, row) in rows.chunks_mut(stride).enumerate() {
        let y = (first + r as isize).clamp(0, last) as usize;
        first_row(source, y, row, s);
    }
    s.down.resize(stride, 0.0);
    let lanes = source.planes.len();
    for (j, o) in out.chunks_mut(w2).enumerate() {
        let r = |k: usize, lane: usize| {
            let start = (2 * j + k) * stride + lane * w2;
            &rows[start..start + w2]
        };
        for lane in 0..lanes {
            let (a, b, d, e) = (r(0, lane), r(1, lane), r(2, lane), r(3, lane));
            let down = &mut s.down[lane * w2..(lane + 1) * w2];
            for i in 0..w2 {
                down[i] = 0.125 * (a[i] + e[i]) + 0.375 * (b[i] + d[i]);
            }
        }
        for (i, t) in o.iter_mut().enumerate() {
            for (lane, v) in t.iter_mut().enumerate().take(lanes) {
                *v = s.down[lane * w2 + i];
            }
        }
    }
    s.rows = rows;
}

/// A compose task's buffers for the carried planes: each group's level rows, each pixel's
/// images and the discs' rows.
#[derive(Default)]
pub(super) struct CarriedScratch {
    /// Group g's row of level l at [g][l − 1].
    made: Vec<Vec<Vec<Texel>>>,
    /// Per pixel: the lower image of its mix and f (the image is u8::MAX where the pixel is
    /// left sharp), and where its blur comes from.
    picks: Vec<(u8, f32, Kernel)>,
    /// The last discs' rows, as the beauty's (`compose::Scratch`).
    frame_rows: DiscRows,
    level_rows: [DiscRows; 2],
}

/// Copies of frame rows y − 1, y and y + 1 (clamped to the frame), as they were before the
/// compose stage wrote them: every plane of the row, one after another, the carried planes
/// from `first` on.
pub(super) struct CarriedRows<'a> {
    pub(super) rows: [&'a [f32]; 3],
    pub(super) first: usize,
}

/// What the beauty's compose shares with the carried planes.
pub(super) struct Shared<'a> {
    pub(super) source: &'a Source<'a>,
    pub(super) samplers: &'a [Sampler<'a>],
    pub(super) ladder: &'a Ladder,
    /// Each group's frame as texels (`super::disc::frame_texels`; empty where no pixel
    /// reads the frame's disc).
    pub(super) frames: &'a [Vec<Texel>],
    /// The beauty's frame as texels (their 1/w weighs a near pixel's taps).
    pub(super) frame: &'a [Texel],
    /// Each group's plain level 1 (`levels::Source::plain`; empty where no near pixel
    /// reads level 1's disc).
    pub(super) plain: &'a [Group],
    /// Levels 2 and 3's CoCs (`super::disc::disc_bounds`).
    pub(super) bounds: [f32; 2],
}

/// The carried planes' compose stage for frame row y, after the beauty's ([`Scratch`] holds
/// what it made of the row): each group's level rows, then each pixel the beauty blurred
/// mixed from the same two images by the same f. `out` holds the row of each carried plane,
/// sharp, written in place.
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub(super) fn compose_carried_row(
    shared: &Shared,
    groups: &[Group],
    y: usize,
    rows: &CarriedRows,
    beauty: &Scratch,
    scratch: &mut CarriedScratch,
    out: &mut [&mut [f32]],
) {
    let Some((lo, hi)) = beauty.mixing else {
        return;
    };
    let Shared {
        source,
        samplers,
        ladder,
        frames,
        frame,
        plain: plain_groups,
        bounds,
    } = shared;
    let width = out[0].len();
    let height = source.coc.len() / width;
    let coc = &source.coc[y * width..(y + 1) * width];
    let CarriedScratch {
        made,
        picks,
        frame_rows,
        level_rows,
    } = scratch;
    made.resize_with(groups.len(), Vec::new);
    for (group, made) in groups.iter().zip(made.iter_mut()) {
        made.resize_with(group.levels.len(), Vec::new);
        for l in lo..=hi {
            samplers[l - 1].carried_row(
                &group.levels[l - 1],
                y,
                &beauty.made[l - 1],
                &mut made[l - 1],
            );
        }
    }

    // Each pixel's images and mix, as the beauty's (`compose::compose_row`).
    let (epsilon, largest) = (source.epsilon, source.largest);
    let to_coc = |t: f32| epsilon + t * (largest - epsilon);
    picks.clear();
    for &t in beauty.blur.iter() {
        if t == 0.0 {
            picks.push((u8::MAX, 0.0, Kernel::Pyramid));
            continue;
        }
        let c = to_coc(t.abs());
        let kernel = if t > 0.0 {
            kernel(c, *bounds)
        } else {
            Kernel::Pyramid
        };
        let (k, f) = ladder.bracket(c);
        picks.push((k as u8, f, kernel));
    }

    let mut planes = out.iter_mut();
    for (g, group) in groups.iter().enumerate() {
        let images = Images {
            rows,
            base: rows.first + g * GROUP,
            group,
            samplers,
            made: &made[g],
            width,
        };
        // Each blurred pixel mixed, into the planes (a pixel left sharp is not touched).
        let mut lanes: Vec<&mut [f32]> = planes
            .by_ref()
            .take(group.lanes)
            .map(|p| &mut p[..width])
            .collect();
        let texels = frames.get(g).map_or(&[][..], Vec::as_slice);

        for (x, &(k, f, kernel)) in picks.iter().enumerate() {
            if k == u8::MAX {
                continue;
            }
            let k = k as usize;
            let c = to_coc(beauty.blur[x].abs());
            // A near pixel's frame disc weighs each tap by the beauty's 1/w, and its level
            // disc reads the group's plain level 1, as the beauty's did
            // (`super::disc::frame_disc`; values, not closures: `multiversion`).
            let near = coc[x] < 0.0;
            let plain = near.then_some(*frame);
            let level_1 = match plain_groups.get(g) {
                Some(p) if near => &p.levels[0],
                _ => &group.levels[0],
            };
            // Each disc of the group divided by the beauty's w for the same disc (no
            // closures: `multiversion`, as in `compose::compose_row`).
            let m = match kernel {
                Kernel::Frame => divided(
                    frame_disc(texels, width, height, x, y, c, frame_rows, plain),
                    beauty.frame_w[x],
                ),
                Kernel::FrameToLevel(f) => lerp(
                    &divided(
                        frame_disc(texels, width, height, x, y, c, frame_rows, plain),
                        beauty.frame_w[x],
                    ),
                    &divided(level_disc(level_1, x, y, c, level_rows), beauty.level_w[x]),
                    f,
                ),
                Kernel::Level => {
                    divided(level_disc(level_1, x, y, c, level_rows), beauty.level_w[x])
                }
                Kernel::LevelToPyramid(g) => lerp(
                    &divided(level_disc(level_1, x, y, c, level_rows), beauty.level_w[x]),
                    &lerp(&images.at(k, x), &images.at(k + 1, x), f),
                    g,
                ),
                Kernel::Pyramid => lerp(&images.at(k, x), &images.at(k + 1, x), f),
            };
            for ((plane, m), reference) in lanes.iter_mut().zip(m).zip(&group.reference) {
                plane[x] = reference + m;
            }
        }
    }
}

/// Every lane of a disc's sum divided by `w`.
#[inline(always)]
fn divided(mut sum: Texel, w: f32) -> Texel {
    for v in sum.iter_mut() {
        *v /= w;
    }
    sum
}

/// What a group's mix reads for frame row y: the sharp rows and the levels' rows made for
/// the row.
struct Images<'a> {
    rows: &'a CarriedRows<'a>,
    /// The group's first plane among the copied rows' planes.
    base: usize,
    group: &'a Group,
    samplers: &'a [Sampler<'a>],
    made: &'a [Vec<Texel>],
    width: usize,
}

impl Images<'_> {
    /// Image j of the ladder (level j, the sharp frame for 0) at frame pixel x (a method,
    /// not a closure, as `compose::Images::at`).
    #[inline(always)]
    fn at(&self, j: usize, x: usize) -> Texel {
        if j >= 1 {
            self.samplers[j - 1].at(&self.made[j - 1], x)
        } else {
            let mut offset = ZERO;
            let row = self.rows.rows[1];
            for (lane, v) in offset.iter_mut().enumerate().take(self.group.lanes) {
                *v = row[(self.base + lane) * self.width + x] - self.group.reference[lane];
            }
            offset
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{blend, blend_carrying, plan};
    use super::BAND;
    use crate::dof::{DofConfig, DofParams};
    use crate::frame::Color;

    /// A plane of `width` × `height` of varied values (hashed from the pixel and `seed`),
    /// about `scale` around `offset`.
    fn plane(width: usize, height: usize, seed: u32, offset: f32, scale: f32) -> Vec<f32> {
        (0..width * height)
            .map(|i| {
                let h = (i as u32 ^ seed.wrapping_mul(0x9e37_79b9)).wrapping_mul(0x85eb_ca6b);
                let h = (h ^ (h >> 13)).wrapping_mul(0xc2b2_ae35);
                offset + scale * ((h >> 8) as f32 / (1 << 24) as f32)
            })
            .collect()
    }

    /// A signed CoC plane with a near field (left), an in-focus band, a far field rising to
    /// `largest` px (right), and pixels between that read each disc and each level.
    fn coc(width: usize, height: usize, largest: f32) -> Vec<f32> {
        let jitter = plane(width, height, 99, -0.5, 1.0);
        (0..width * height)
            .map(|i| {
                let (x, y) = ((i % width) as f32, (i / width) as f32);
                let u = (x + 0.5) / width as f32 + 0.1 * (y / height as f32);
                let c = if u < 0.3 {
                    -largest * 0.6 * (0.3 - u) / 0.3 - 1.0
                } else if u < 0.45 {
                    0.3
                } else {
                    largest * (u - 0.45) / 0.65
                };
                (c + 2.0 * jitter[i]).clamp(-largest, largest)
            })
            .collect()
    }

    /// A layer of the beauty's alpha (if any): R, G and B of its own, offset so each plane's
    /// reference differs.
    fn layer(width: usize, height: usize, k: u32, alpha: &Option<Vec<f32>>) -> Color {
        let n = k as f32;
        Color {
            r: plane(width, height, 10 * k + 1, 0.1 * n, 1.0 + n),
            g: plane(width, height, 10 * k + 2, -0.2 * n, 0.5),
            b: plane(width, height, 10 * k + 3, 3.0, 0.01 + n),
            a: alpha.clone(),
        }
    }

    fn bits(p: &[f32]) -> Vec<u32> {
        p.iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn carried_planes_come_out_as_each_layer_blended_alone_bit_for_bit() {
        // Sizes odd and even, one pixel to several bands, a row to a column; one layer (a
        // group with five empty lanes), three (two groups) and six (three groups, 18 planes,
        // the bench's count); with alpha and without.
        let sizes = [
            (1, 1),
            (1, 9),
            (13, 1),
            (2, 3),
            (7, 2 * BAND + 5),
            (33, 17),
            (64, 41),
            (101, 3 * BAND + 1),
        ];
        let (mut carried_pixels, mut near, mut deepest) = (0, 0, 0);
        for (s, &(width, height)) in sizes.iter().enumerate() {
            for (count, with_alpha) in [(1, true), (3, false), (6, true), (6, false)] {
                let largest = [6.0, 40.0][s % 2];
                let coc = coc(width, height, largest);
                let alpha = with_alpha.then(|| plane(width, height, 7, 0.0, 1.0));
                let beauty = layer(width, height, 0, &alpha);
                let layers: Vec<Color> = (1..=count)
                    .map(|k| layer(width, height, k, &alpha))
                    .collect();
                let config = DofConfig::new(width, height, &DofParams::default());
                let plan = plan(&config, &beauty, &coc);
                near += plan.near.is_some() as usize;
                deepest = deepest.max(plan.levels);
                let planes: Vec<Vec<f32>> = layers
                    .iter()
                    .flat_map(|l| [l.r.clone(), l.g.clone(), l.b.clone()])
                    .collect();
                let (out, carried) = blend_carrying(&config, beauty.clone(), &coc, planes);
                let alone = blend(&config, beauty.clone(), &coc);
                let what = format!("{width}×{height}, {count} layers, alpha {with_alpha}");
                for (got, want) in out.planes().iter().zip(alone.planes()) {
                    assert_eq!(bits(got), bits(want), "the beauty, {what}");
                }
                assert_eq!(carried.len(), 3 * count as usize, "{what}");
                for (k, layer) in layers.into_iter().enumerate() {
                    let alone = blend(&config, layer.clone(), &coc);
                    for (c, want) in [&alone.r, &alone.g, &alone.b].into_iter().enumerate() {
                        let got = &carried[3 * k + c];
                        assert_eq!(bits(got), bits(want), "layer {k} plane {c}, {what}");
                        let before = [&layer.r, &layer.g, &layer.b][c];
                        carried_pixels += got.iter().zip(before).filter(|(a, b)| a != b).count();
                    }
                }
            }
        }
        // The layers were blurred, not left as they came, with a near field's spread and
        // four levels among the frames.
        assert!(carried_pixels > 10_000, "{carried_pixels} pixels changed");
        assert!(
            near > 10 && deepest >= 4,
            "near fields {near}, levels {deepest}"
        );
    }
}
