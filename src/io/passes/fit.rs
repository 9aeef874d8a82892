//! How a vector pass is stored, fitted from the frames themselves (issue 32, `shutter
//! vectors`): frame n−1's colour, moved by the true motion, is frame n. The motion between
//! frame n and its neighbours is measured at textured points by block matching (a pyramid,
//! coarse to fine, sub-pixel at the end, only where the match is unique), and the stored
//! values at those points are fitted to it under every reading a preset can state: the four
//! offset meanings and the two absolute positions, x and y swapped or not, y up or down, the
//! value meaning "still" (zero, 0 or 0.5), one scale (in pixels, or in screen-normalised
//! units, which scale x by the width and y by the height; a render's shutter is a scale too).
//!
//! In: the luma of frame n and of n−1 and/or n+1, and the two stored components at n. Out:
//! every reading's fit (its residual in pixels over the points, robust to occlusion: a point
//! off by more than a pixel counts as a pixel), the residual of no motion by that same
//! measure, and a verdict: a reading chosen, or why none is (nothing fits better than no
//! motion; two readings fit alike; an axis never moves, so its sign and scale are not seen).
//!
//! No motion is scored like a reading (F5): as an uncapped RMS, the few points a tracker
//! gets wrong (a point covered in the neighbour, matched to a look-alike tens of pixels
//! away) made it several pixels, and any reading, even one of scale 0.02 that moves nothing,
//! passed for "clearly better". A reading whose own motion is under the floor below which
//! measured motion counts as none ([`verdict::STILL`]) is no motion, whatever it scores.

use serde::Serialize;

use crate::io::preset::{Meaning, Units};

/// What the fit reads.
pub struct FitInput<'a> {
    pub width: usize,
    pub height: usize,
    /// Luma of frame n, and of n−1 and n+1 where they exist.
    pub current: &'a [f32],
    pub prev: Option<&'a [f32]>,
    pub next: Option<&'a [f32]>,
    /// The two stored components at frame n, in the file's order.
    pub stored: [&'a [f32]; 2],
    /// Points sampled at most, on a grid ([`FIT_POINTS`] for `shutter vectors`; fewer for
    /// the check before a blur, which only has to tell a clearly wrong reading).
    pub max_points: usize,
}

/// The outcome.
#[derive(Clone, Debug, Serialize)]
pub struct Fit {
    /// Every reading, best first.
    pub readings: Vec<Reading>,
    /// The residual of reading no motion at all, by the readings' measure (each point's
    /// motion capped at [`TRUNCATE`]), toward the neighbour the best reading looks to (of
    /// all the points where there is no reading).
    pub no_motion: f64,
    /// Points where motion was measured.
    pub points: usize,
    /// Whether each stored component varies over those points (else its axis is not seen).
    pub varying: [bool; 2],
    /// The reading chosen, or `None` with `why`.
    pub chosen: Option<Reading>,
    pub why: Option<String>,
    /// The samples fitted, per neighbour: (forward, stored, measured, centres).
    #[serde(skip)]
    samples: Vec<Samples>,
    #[serde(skip)]
    size: (usize, usize),
}

/// The points of one neighbour: stored values, measured motion and pixel centres per axis.
#[derive(Clone, Debug)]
struct Samples {
    forward: bool,
    s: [Vec<f64>; 2],
    m: [Vec<f64>; 2],
    c: [Vec<f64>; 2],
}

/// The largest motion looked for, in pixels per frame at full size.
const SEARCH: f32 = 192.0;
/// Half the side of a matched patch.
const PATCH: isize = 4;
/// Points `shutter vectors` samples at most (on a grid, before the flat ones are dropped).
pub const FIT_POINTS: usize = 4096;

fn downsample(plane: &[f32], w: usize, h: usize) -> (Vec<f32>, usize, usize) {
    let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
    let mut out = vec![0.0; nw * nh];
    for (y, row) in out.chunks_exact_mut(nw).enumerate() {
        let (r0, r1) = ((2 * y).min(h - 1) * w, (2 * y + 1).min(h - 1) * w);
        let (top, bottom) = (&plane[r0..r0 + w], &plane[r1..r1 + w]);
        if w >= 2 {
            // Each output sample averages a 2×2 block (an odd last column or row is dropped).
            for (x, v) in row.iter_mut().enumerate() {
                *v = 0.25 * (top[2 * x] + top[2 * x + 1] + bottom[2 * x] + bottom[2 * x + 1]);
            }
        } else {
            row[0] = 0.5 * (top[0] + bottom[0]);
        }
    }
    (out, nw, nh)
}

struct Level<'a> {
    plane: std::borrow::Cow<'a, [f32]>,
    w: usize,
    h: usize,
}

/// The frame (borrowed, not copied) and its halvings.
fn pyramid(plane: &[f32], w: usize, h: usize, levels: usize) -> Vec<Level<'_>> {
    let mut out = vec![Level {
        plane: std::borrow::Cow::Borrowed(plane),
        w,
        h,
    }];
    for _ in 1..levels {
        let last = out.last().expect("one level");
        let (plane, w, h) = downsample(&last.plane, last.w, last.h);
        out.push(Level {
            plane: std::borrow::Cow::Owned(plane),
            w,
            h,
        });
    }
    out
}

fn sample(l: &Level, x: isize, y: isize) -> f32 {
    let x = x.clamp(0, l.w as isize - 1) as usize;
    let y = y.clamp(0, l.h as isize - 1) as usize;
    l.plane[y * l.w + x]
}

/// Sum of squared differences between the patch of `a` at (x, y) and of `b` at (x+dx, y+dy),
/// edges clamped; stops adding once the sum passes `limit` (a search's best so far), so a
/// search pays little for the displacements that lose.
fn ssd_below(
    a: &Level,
    b: &Level,
    (x, y): (isize, isize),
    (dx, dy): (isize, isize),
    limit: f32,
) -> f32 {
    let inside = |l: &Level, x: isize, y: isize| {
        x - PATCH >= 0 && y - PATCH >= 0 && x + PATCH < l.w as isize && y + PATCH < l.h as isize
    };
    let mut sum = 0.0;
    if inside(a, x, y) && inside(b, x + dx, y + dy) {
        // Both patches inside their frames: rows of contiguous samples, no clamping.
        let side = (2 * PATCH + 1) as usize;
        for py in -PATCH..=PATCH {
            let ra = ((y + py) as usize) * a.w + (x - PATCH) as usize;
            let rb = ((y + dy + py) as usize) * b.w + (x + dx - PATCH) as usize;
            let row: f32 = a.plane[ra..ra + side]
                .iter()
                .zip(&b.plane[rb..rb + side])
                .map(|(p, q)| (p - q) * (p - q))
                .sum();
            sum += row;
            if sum > limit {
                return sum;
            }
        }
        return sum;
    }
    for py in -PATCH..=PATCH {
        for px in -PATCH..=PATCH {
            let d = sample(a, x + px, y + py) - sample(b, x + dx + px, y + dy + py);
            sum += d * d;
        }
        if sum > limit {
            return sum;
        }
    }
    sum
}

/// The whole sum of squared differences (see [`ssd_below`]).
fn ssd(a: &Level, b: &Level, p: (isize, isize), d: (isize, isize)) -> f32 {
    ssd_below(a, b, p, d, f32::INFINITY)
}

/// The displacement from frame n's point (x, y) to where its patch is in `other`, in full
/// size pixels, or `None` where the match is not clear.
fn track(a: &[Level], b: &[Level], (x, y): (usize, usize), texture: f32) -> Option<(f32, f32)> {
    let top = a.len() - 1;
    let mut d = (0isize, 0isize);
    for level in (0..=top).rev() {
        let (la, lb) = (&a[level], &b[level]);
        let p = ((x >> level) as isize, (y >> level) as isize);
        let radius = if level == top {
            // The search at the coarsest level spans the motion looked for, and at most a
            // quarter of that level's frame.
            let cap = (la.w.min(la.h) / 4).max(2) as isize;
            ((SEARCH / (1 << level) as f32).ceil() as isize).min(cap)
        } else {
            2
        };
        let centre = if level == top {
            (0, 0)
        } else {
            (d.0 * 2, d.1 * 2)
        };
        let mut best = (f32::INFINITY, centre);
        for dy in -radius..=radius {
            for dx in -radius..=radius {
                let c = (centre.0 + dx, centre.1 + dy);
                let s = ssd_below(la, lb, p, c, best.0);
                // Ties to the smaller displacement, so a flat patch reads as still.
                if s < best.0
                    || (s == best.0 && c.0.abs() + c.1.abs() < best.1 .0.abs() + best.1 .1.abs())
                {
                    best = (s, c);
                }
            }
        }
        // A best on the rim of the coarsest search is no match: the true one may lie beyond
        // it, or be hidden (a point uncovered or covered by the motion), and what the rim
        // offers is a look-alike (on a periodic wall, the pattern one period away: F5's
        // checker, whose 22-pixel squares matched at (±22, ±22), the rim at 160×90).
        if level == top && (best.1 .0.abs() == radius || best.1 .1.abs() == radius) {
            return None;
        }
        d = best.1;
    }
    let (la, lb) = (&a[0], &b[0]);
    let p = (x as isize, y as isize);
    let here = ssd(la, lb, p, d);
    // A clear match: the patch found is closer than the patch shifted by a pixel is to
    // itself (a motion of half a pixel off the grid costs about a quarter of that).
    if here > 0.35 * texture + 1e-9 {
        return None;
    }
    // And a unique one: every displacement two or three pixels away matches clearly worse
    // (on an edge or a stripe the patch slides along it at little cost: the aperture
    // problem, which would give any reading's motion along the edge).
    let mut ring = f32::INFINITY;
    for dy in -3isize..=3 {
        for dx in -3isize..=3 {
            if dx.abs().max(dy.abs()) >= 2 {
                ring = ring.min(ssd(la, lb, p, (d.0 + dx, d.1 + dy)));
            }
        }
    }
    if ring < 2.0 * here + 0.25 * texture {
        return None;
    }
    let refine = |minus: f32, plus: f32| {
        let denominator = minus - 2.0 * here + plus;
        if denominator > 1e-12 {
            (0.5 * (minus - plus) / denominator).clamp(-0.5, 0.5)
        } else {
            0.0
        }
    };
    let fx = refine(
        ssd(la, lb, p, (d.0 - 1, d.1)),
        ssd(la, lb, p, (d.0 + 1, d.1)),
    );
    let fy = refine(
        ssd(la, lb, p, (d.0, d.1 - 1)),
        ssd(la, lb, p, (d.0, d.1 + 1)),
    );
    Some((d.0 as f32 + fx, d.1 as f32 + fy))
}

/// Textured points of frame n on a grid, with their patch's variation (sum of squared
/// differences to its one-pixel shifts).
fn points(l: &Level, max_points: usize) -> Vec<((usize, usize), f32)> {
    let margin = PATCH as usize + 1;
    if l.w <= 2 * margin || l.h <= 2 * margin {
        return Vec::new();
    }
    let area = (l.w - 2 * margin) * (l.h - 2 * margin);
    let stride = ((area as f64 / max_points.max(1) as f64).sqrt().ceil() as usize).max(2);
    let mut out = Vec::new();
    for y in (margin..l.h - margin).step_by(stride) {
        for x in (margin..l.w - margin).step_by(stride) {
            let p = (x as isize, y as isize);
            let texture = ssd(l, l, p, (1, 0)).min(ssd(l, l, p, (0, 1)));
            out.push(((x, y), texture));
        }
    }
    // The better textured half, and none that is flat.
    let mut energies: Vec<f32> = out.iter().map(|p| p.1).collect();
    energies.sort_by(f32::total_cmp);
    let floor = energies[energies.len() / 2].max(1e-6);
    out.retain(|p| p.1 >= floor);
    out
}

/// The RMS of per-point distances, each at most [`TRUNCATE`]: robust to the few points
/// that match nothing, while a reading that misses a whole motion (a layer) pays for every
/// point of it.
fn robust_rms(distances: &[f64]) -> f64 {
    if distances.is_empty() {
        return 0.0;
    }
    let sum: f64 = distances.iter().map(|d| d.min(TRUNCATE).powi(2)).sum();
    (sum / distances.len() as f64).sqrt()
}

/// The plain RMS (not truncated): how much motion there is, not how well it fits.
fn rms(distances: &[f64]) -> f64 {
    if distances.is_empty() {
        return 0.0;
    }
    (distances.iter().map(|d| d * d).sum::<f64>() / distances.len() as f64).sqrt()
}

/// `v` rounded to a simple fraction (n/d, d ≤ 8) when it is within 1.5 % of one.
fn simple(v: f64) -> f64 {
    let mut best = v;
    let mut error = 0.015;
    for d in 1..=8 {
        let n = (v * d as f64).round();
        if n == 0.0 {
            continue;
        }
        let e = ((n / d as f64) - v).abs() / v.abs().max(1e-12);
        if e < error {
            error = e;
            best = n / d as f64;
        }
    }
    best
}

/// Fits every reading. `stored` components that never vary make their axis unseen.
pub fn fit(input: &FitInput) -> Fit {
    let (w, h) = (input.width, input.height);
    let levels = {
        let mut n = 1;
        while n < 6 && (w.min(h) >> n) >= 24 {
            n += 1;
        }
        n
    };
    let current = pyramid(input.current, w, h, levels);
    let sides: Vec<(bool, Vec<Level>)> = [(false, input.prev), (true, input.next)]
        .into_iter()
        .filter_map(|(forward, plane)| plane.map(|p| (forward, pyramid(p, w, h, levels))))
        .collect();
    let chosen_points = points(&current[0], input.max_points);
    // Motion measured to each neighbour at each point (None: not clear there).
    let measured: Vec<Vec<Option<(f32, f32)>>> = sides
        .iter()
        .map(|(_, other)| {
            use rayon::prelude::*;
            chosen_points
                .par_iter()
                .map(|&(p, texture)| track(&current, other, p, texture))
                .collect()
        })
        .collect();
    let mut readings = Vec::new();
    let mut samples = Vec::new();
    // Per neighbour measured (forward): each point's measured motion, all points' together.
    let mut still: Vec<(bool, Vec<f64>)> = Vec::new();
    let mut used = 0;
    for (side, (forward, _)) in sides.iter().enumerate() {
        let mut s = [Vec::new(), Vec::new()];
        let mut m = [Vec::new(), Vec::new()];
        let mut c = [Vec::new(), Vec::new()];
        let mut moved = Vec::new();
        for (k, &((x, y), _)) in chosen_points.iter().enumerate() {
            let Some((mx, my)) = measured[side][k] else {
                continue;
            };
            let (a, b) = (input.stored[0][y * w + x], input.stored[1][y * w + x]);
            if !a.is_finite() || !b.is_finite() {
                continue;
            }
            s[0].push(a as f64);
            s[1].push(b as f64);
            m[0].push(mx as f64);
            m[1].push(my as f64);
            c[0].push(x as f64 + 0.5);
            c[1].push(y as f64 + 0.5);
            moved.push((mx as f64).hypot(my as f64));
        }
        still.push((*forward, moved));
        used = used.max(s[0].len());
        if s[0].len() < 8 {
            continue;
        }
        samples.push(Samples {
            forward: *forward,
            s: s.clone(),
            m: m.clone(),
            c: c.clone(),
        });
        for absolute in [false, true] {
            for swap in [false, true] {
                for units in [Units::Pixels, Units::Normalized] {
                    // Offsets: x's sign picks the meaning; positions are not negated.
                    let x_signs: &[f64] = if absolute { &[1.0] } else { &[1.0, -1.0] };
                    for &sx in x_signs {
                        for sy in [1.0, -1.0] {
                            let candidate = Candidate {
                                forward: *forward,
                                absolute,
                                swap,
                                units,
                                signs: (sx, sy),
                            };
                            readings.push(candidate.fit(&s, &m, &c, (w, h)));
                        }
                    }
                }
            }
        }
    }
    // A negative scale is the opposite sign's reading, fitted there.
    readings.retain(|r| r.consistent);
    readings.sort_by(|a, b| a.residual.total_cmp(&b.residual));
    // No motion toward the best reading's neighbour, scored as the readings are; the plain
    // RMS there says whether anything moved at all.
    let moved: Vec<f64> = match readings.first() {
        Some(best) => still
            .iter()
            .find(|(forward, _)| *forward != best.meaning.is_backward())
            .map(|(_, moved)| moved.clone())
            .unwrap_or_default(),
        None => still
            .iter()
            .flat_map(|(_, moved)| moved.iter().copied())
            .collect(),
    };
    let no_motion = robust_rms(&moved);
    // Each stored component must vary where the motion was measured, or its axis's sign
    // and scale are not seen (the values are finite there: points with others are dropped).
    let varies = |axis: usize| {
        samples.iter().any(|side| {
            let (lo, hi) = side.s[axis]
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                });
            hi - lo > 1e-6
        })
    };
    let varying = [varies(0), varies(1)];
    let (chosen, why) = decide(&readings, [no_motion, rms(&moved)], used, varying);
    Fit {
        readings,
        no_motion,
        points: used,
        varying,
        chosen,
        why,
        samples,
        size: (w, h),
    }
}

impl Fit {
    /// The RMS of the motion measured toward one neighbour (the next with `forward`), per
    /// axis, in pixels; `None` when that neighbour was not measured.
    pub fn motion_toward(&self, forward: bool) -> Option<[f64; 2]> {
        let side = self.samples.iter().find(|s| s.forward == forward)?;
        Some([rms(&side.m[0]), rms(&side.m[1])])
    }

    /// The residual of a reading as given (its own scale and zero, not refitted), against
    /// the neighbour its meaning looks to; `None` when that neighbour was not measured.
    pub fn residual_of(&self, r: &Reading) -> Option<f64> {
        let forward = !r.meaning.is_backward();
        let side = self.samples.iter().find(|s| s.forward == forward)?;
        let sx = match r.meaning {
            Meaning::Velocity | Meaning::FromNext => -1.0,
            _ => 1.0,
        };
        let candidate = Candidate {
            forward,
            absolute: r.meaning.is_position(),
            swap: r.swap,
            units: r.units,
            signs: (sx, if r.y_up { -sx } else { sx }),
        };
        let d = candidate.distances(
            &side.s,
            &side.m,
            &side.c,
            self.size,
            (r.scale as f64, r.zero as f64),
        );
        Some(robust_rms(&d))
    }
}

/// One reading to fit: which neighbour and form (offset or position), the components'
/// order, the units, and the signs of x and y.
struct Candidate {
    forward: bool,
    absolute: bool,
    swap: bool,
    units: Units,
    signs: (f64, f64),
}

impl Candidate {
    /// The stored components in the reading's x, y order.
    fn oriented<'a>(&self, s: &'a [Vec<f64>; 2]) -> [&'a [f64]; 2] {
        if self.swap {
            [&s[1], &s[0]]
        } else {
            [&s[0], &s[1]]
        }
    }

    /// The units' factor per axis: pixels, or the frame's width and height.
    fn factor(&self, (w, h): (usize, usize)) -> [f64; 2] {
        match self.units {
            Units::Pixels => [1.0, 1.0],
            Units::Normalized => [w as f64, h as f64],
        }
    }

    /// What point i's stored value on `axis` should give: the measured offset, or for a
    /// position the point's own centre plus it (mirrored about the height with y up).
    fn target(&self, m: &[Vec<f64>; 2], c: &[Vec<f64>; 2], h: usize, axis: usize, i: usize) -> f64 {
        let t = m[axis][i] + if self.absolute { c[axis][i] } else { 0.0 };
        if axis == 1 && self.absolute && self.signs.1 < 0.0 {
            t - h as f64
        } else {
            t
        }
    }

    /// Each point's distance between the motion measured and the motion this reading gives
    /// with scale k and zero z.
    fn distances(
        &self,
        s: &[Vec<f64>; 2],
        m: &[Vec<f64>; 2],
        c: &[Vec<f64>; 2],
        size: (usize, usize),
        (k, z): (f64, f64),
    ) -> Vec<f64> {
        let stored = self.oriented(s);
        let factor = self.factor(size);
        let sign = [self.signs.0, self.signs.1];
        (0..stored[0].len())
            .map(|i| {
                let d = |axis: usize| {
                    self.target(m, c, size.1, axis, i)
                        - sign[axis] * factor[axis] * k * (stored[axis][i] - z)
                };
                d(0).hypot(d(1))
            })
            .collect()
    }

    /// Fits the reading's scale k for each zero, 0 and 0.5 (one of each for both axes: the
    /// model t = σ·u·k·(s − z), u the units' factor per axis, a position with y up mirrored
    /// about h), by least squares refitted on the closest nine tenths of the points; keeps the
    /// zero that fits better and rounds k to a simple fraction where it is within 1.5 %.
    fn fit(
        &self,
        s: &[Vec<f64>; 2],
        m: &[Vec<f64>; 2],
        c: &[Vec<f64>; 2],
        size: (usize, usize),
    ) -> Reading {
        let stored = self.oriented(s);
        let factor = self.factor(size);
        let sign = [self.signs.0, self.signs.1];
        let n = stored[0].len();
        // Least squares for k with z fixed: rows (axis, point) a·k = t, a = σ·u·(s − z).
        let solve = |keep: &[usize], z: f64| -> (f64, f64) {
            let (mut aa, mut at) = (0.0, 0.0);
            for &i in keep {
                for axis in 0..2 {
                    let a = sign[axis] * factor[axis] * (stored[axis][i] - z);
                    aa += a * a;
                    at += a * self.target(m, c, size.1, axis, i);
                }
            }
            (if aa > 1e-18 { at / aa } else { 0.0 }, z)
        };
        // The zero is 0 or 0.5 (a free one, with one scale, fits a single motion under any
        // reading); the one that fits better is kept.
        let mut best: Option<((f64, f64), f64)> = None;
        for zero in [0.0, 0.5] {
            let mut kz = solve(&(0..n).collect::<Vec<_>>(), zero);
            for _ in 0..2 {
                let d = self.distances(s, m, c, size, kz);
                let mut order: Vec<usize> = (0..n).collect();
                order.sort_by(|&i, &j| d[i].total_cmp(&d[j]));
                kz = solve(&order[..(n * 9 / 10).max(2).min(n)], zero);
            }
            let r = robust_rms(&self.distances(s, m, c, size, kz));
            if best.is_none_or(|b| r < b.1) {
                best = Some((kz, r));
            }
        }
        let (kz, _) = best.expect("two zeros tried");
        let k = simple(kz.0);
        let distances = self.distances(s, m, c, size, (k, kz.1));
        // The reading's own motion: its distance from the motion of a still point.
        let zero = [vec![0.0; n], vec![0.0; n]];
        let motion = rms(&self.distances(s, &zero, c, size, (k, kz.1)));
        let meaning = match (self.forward, self.absolute, self.signs.0 > 0.0) {
            (false, false, true) => Meaning::ToPrev,
            (false, false, false) => Meaning::Velocity,
            (true, false, true) => Meaning::ToNext,
            (true, false, false) => Meaning::FromNext,
            (false, true, _) => Meaning::PrevPosition,
            (true, true, _) => Meaning::NextPosition,
        };
        Reading {
            meaning,
            swap: self.swap,
            y_up: self.signs.0 != self.signs.1,
            zero: kz.1 as f32,
            scale: k as f32,
            units: self.units,
            residual: robust_rms(&distances),
            motion,
            fitted_scale: [kz.0 * factor[0], kz.0 * factor[1]],
            consistent: k > 0.0,
        }
    }
}

mod verdict;
use verdict::decide;
pub use verdict::{describe, Reading, TRUNCATE};

#[cfg(test)]
mod tests;
