//! Data carried with the motion (issue 29): for a layer a preset's `[layers]` table classes
//! `motion` (`Z = "motion"`, `velocity = "motion"`), each pixel of the output takes the value
//! of the nearest surface whose streak covers it over the exposure, the pixel's own surface
//! included, instead of the value the sharp frame had there.
//!
//! Why a pipeline asks for it: after the blur, a foreground's streak lies over pixels whose
//! depth and vectors are still the background's. A depth merge (Z-combine, deep) downstream
//! then puts the streak behind what it covers, and a second vector pass (a retime, another
//! blur) moves it with the background. Carried, the streak holds the foreground's depth and
//! vectors where the foreground passed. Values are never mixed (a depth or an ID averaged
//! over an edge is a surface that does not exist): each pixel takes one surface's.
//!
//! In: the frame's depth (smaller is nearer), its motion and the streaks the pass draws
//! ([`Streak`]: its exposure, its path — along the velocity for reconstruct and stretch,
//! scatter's curve through the previous and next positions — and its longest streak). Out:
//! for every pixel, the index of the pixel whose value it takes. Each moving surface offers
//! its depth and index to the pixels its streak enters (points a pixel or less apart along
//! it), each pixel keeping the least: the same answer in any order, so for any thread count.
//! A pixel then takes the least unless it is no nearer than its own surface by the pass's
//! depth tolerance, so a surface moving over itself keeps its own values (an ID edge
//! between two touching objects does not shift). Still frames cost one pass over the
//! pixels. Runs on the CPU for every backend (the data is never on the GPU).

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use super::curve::{Arc, Bezier};
use crate::frame::{Frame, Positions, Velocity};

/// How far a streak is followed from its pixel, each way, in pixels, whatever the pass's own
/// bound: a frame's cost stays bounded (a 1080p frame of huge vectors marks at most 2 × 512
/// points a pixel).
pub const MOST_REACH: f32 = 512.0;

/// The streaks a pass draws, as the carry follows them: the exposure, the path, the longest a
/// streak is drawn, and when a surface counts as nearer than another.
#[derive(Clone, Copy, Debug)]
pub struct Streak {
    /// The exposure [t0, t1], frames about the frame's instant.
    pub interval: (f32, f32),
    pub path: Path,
    /// The longest streak the pass draws (pixels, end to end): a longer one is scaled about
    /// its pixel to this length.
    pub longest: f32,
    pub nearer: Nearer,
}

/// A streak's path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Path {
    /// Along the velocity, p(t) = p(0) + t·v (reconstruct, stretch).
    Straight,
    /// Through the previous, present and next positions (scatter): the quadratic, or the arc
    /// where `arc` and the three points make one.
    Curve { arc: bool },
}

/// When a streak's surface is nearer than a pixel's own: by more than the pass's depth
/// tolerance, so a surface moving over itself (or two touching at one depth) keeps its own
/// values rather than its neighbours'.
#[derive(Clone, Copy, Debug)]
pub enum Nearer {
    /// By more than this depth (reconstruct's soft depth extent).
    By(f32),
    /// By more than this fraction of the pixel's depth (scatter's and stretch's tolerance).
    ByFraction(f32),
}

impl Nearer {
    fn holds(self, z: f32, own: f32) -> bool {
        match self {
            Nearer::By(extent) => z < own - extent,
            Nearer::ByFraction(fraction) => z * (1.0 + fraction) < own,
        }
    }
}

/// A depth as a key whose unsigned order is the depth's order (negative depths before
/// positive ones, −0 as +0; NaN, which the numeric policy leaves no depth holding, last).
fn depth_key(z: f32) -> u32 {
    if z.is_nan() {
        return u32::MAX;
    }
    let bits = (z + 0.0).to_bits();
    if bits >> 31 == 1 {
        !bits
    } else {
        bits | 0x8000_0000
    }
}

/// How the frame's surfaces move.
enum Motion<'a> {
    Velocity(&'a Velocity),
    Positions(&'a Positions, &'a Positions),
}

/// Points along a streak's path over the exposure, before scaling: enough that no chord
/// strays far from a curve (the straight path needs its ends alone).
const CURVE_POINTS: usize = 17;

impl Motion<'_> {
    /// Pixel i's streak (its surface at `now` at the frame's instant) as points along it,
    /// scaled about `now` to `streak.longest`; empty where it is not finite.
    fn points(&self, i: usize, now: [f64; 2], streak: &Streak) -> Vec<[f64; 2]> {
        let (t0, t1) = (streak.interval.0 as f64, streak.interval.1 as f64);
        let mut points: Vec<[f64; 2]> = match self {
            Motion::Velocity(v) => {
                let (vx, vy) = (v.x[i] as f64, v.y[i] as f64);
                [t0, t1]
                    .iter()
                    .map(|&t| [now[0] + vx * t, now[1] + vy * t])
                    .collect()
            }
            Motion::Positions(prev, next) => {
                let prev = [prev.x[i] as f64, prev.y[i] as f64];
                let next = [next.x[i] as f64, next.y[i] as f64];
                let arc = match streak.path {
                    Path::Curve { arc: true } => Arc::fit(prev, now, next),
                    _ => None,
                };
                let bezier = Bezier::through(prev, now, next);
                (0..CURVE_POINTS)
                    .map(|k| {
                        let t = t0 + (t1 - t0) * k as f64 / (CURVE_POINTS - 1) as f64;
                        match (&arc, streak.path) {
                            (Some(arc), _) => arc.at_time(t),
                            (None, Path::Curve { .. }) => bezier.at(0.5 * (t + 1.0)),
                            // Straight through positions: the chord's velocity.
                            (None, Path::Straight) => [
                                now[0] + 0.5 * (next[0] - prev[0]) * t,
                                now[1] + 0.5 * (next[1] - prev[1]) * t,
                            ],
                        }
                    })
                    .collect()
            }
        };
        let total: f64 = points
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
            .sum();
        if !total.is_finite() {
            return Vec::new();
        }
        // The pass's own bound, then ours, scaled about the pixel (a similarity).
        let longest = (streak.longest as f64).min(2.0 * MOST_REACH as f64);
        if total > longest {
            let scale = longest / total;
            for q in &mut points {
                *q = [
                    now[0] + scale * (q[0] - now[0]),
                    now[1] + scale * (q[1] - now[1]),
                ];
            }
        }
        points
    }
}

/// For every pixel, the index of the pixel whose value a `motion` layer takes there: the
/// nearest surface (least depth; the lower index on a tie) among those whose streak over the
/// exposure covers it, where that surface is nearer than the pixel's own by the pass's
/// tolerance; else the pixel itself. `None` when the frame has no depth or not the motion
/// the path needs (the layer then comes back unchanged).
pub fn nearest_surfaces(frame: &Frame, streak: &Streak) -> Option<Vec<u32>> {
    let depth = frame.depth.as_ref()?;
    let motion = match (streak.path, &frame.velocity, &frame.prev, &frame.next) {
        (Path::Straight, Some(v), _, _) => Motion::Velocity(v),
        (_, _, Some(prev), Some(next)) => Motion::Positions(prev, next),
        _ => return None,
    };
    let (width, height) = (frame.width, frame.height);
    let key = |i: usize| (u64::from(depth_key(depth[i])) << 32) | i as u64;
    let nearest: Vec<AtomicU64> = (0..width * height)
        .into_par_iter()
        .map(|i| AtomicU64::new(key(i)))
        .collect();
    (0..height).into_par_iter().for_each(|y| {
        for x in 0..width {
            let i = y * width + x;
            let mine = key(i);
            let points = motion.points(i, [x as f64 + 0.5, y as f64 + 0.5], streak);
            for pair in points.windows(2) {
                mark(&nearest, (width, height), i, mine, pair[0], pair[1]);
            }
        }
    });
    Some(
        nearest
            .into_par_iter()
            .enumerate()
            .map(|(i, k)| {
                let j = k.into_inner() as u32;
                if j as usize != i && streak.nearer.holds(depth[j as usize], depth[i]) {
                    j
                } else {
                    i as u32
                }
            })
            .collect(),
    )
}

/// Offers `key` (pixel i's) to the pixels the segment from `a` to `b` enters: points at most
/// a pixel apart along it, its ends pulled in by a thousandth of a pixel so that an end on a
/// pixel's edge marks neither pixel (a streak from 9 to 12 marks 9, 10 and 11, as the beauty's
/// streak covers them).
fn mark(
    nearest: &[AtomicU64],
    (width, height): (usize, usize),
    i: usize,
    key: u64,
    a: [f64; 2],
    b: [f64; 2],
) {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let length = dx.hypot(dy);
    let inset = if length > 2e-3 { 1e-3 / length } else { 0.0 };
    let steps = dx.abs().max(dy.abs()).ceil().max(1.0) as usize;
    for s in 0..=steps {
        let f = (s as f64 / steps as f64).clamp(inset, 1.0 - inset);
        let (px, py) = ((a[0] + dx * f).floor(), (a[1] + dy * f).floor());
        if px < 0.0 || py < 0.0 || px >= width as f64 || py >= height as f64 {
            continue;
        }
        let j = py as usize * width + px as usize;
        // A load first: most pixels already hold a nearer key, and a load writes nothing.
        if j != i && nearest[j].load(Ordering::Relaxed) > key {
            nearest[j].fetch_min(key, Ordering::Relaxed);
        }
    }
}

/// `plane` as the pixels `nearest` names see it: each pixel takes its nearest surface's value.
pub fn carried<T: Copy + Send + Sync>(plane: &[T], nearest: &[u32]) -> Vec<T> {
    nearest.par_iter().map(|&j| plane[j as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w`×1 frame: depth 10 and still everywhere, with the given pixels overriding.
    fn row(w: usize, movers: &[(usize, f32, f32)]) -> Frame {
        let mut frame = Frame::new(w, 1);
        let mut depth = vec![10.0; w];
        let mut vx = vec![0.0; w];
        for &(x, z, v) in movers {
            depth[x] = z;
            vx[x] = v;
        }
        frame.depth = Some(depth);
        frame.velocity = Some(Velocity {
            x: vx,
            y: vec![0.0; w],
        });
        frame
    }

    /// reconstruct's streak for a shutter `open` of the frame, offset `offset`.
    fn straight(open: f32, offset: f32) -> Streak {
        Streak {
            interval: ((offset - 0.5) * open, (offset + 0.5) * open),
            path: Path::Straight,
            longest: f32::INFINITY,
            nearer: Nearer::By(0.1),
        }
    }

    /// The pixels that take pixel `i`'s value.
    fn taken(nearest: &[u32], i: u32) -> Vec<usize> {
        (0..nearest.len()).filter(|&j| nearest[j] == i).collect()
    }

    #[test]
    fn a_near_streak_takes_the_pixels_it_crosses_and_no_others() {
        // Pixel 10 (depth 1) moves 8 px a frame; a centred shutter of 0.5 smears it over
        // 8.5..12.5: pixels 8 to 12 take its value, the rest keep their own.
        let frame = row(24, &[(10, 1.0, 8.0)]);
        let nearest = nearest_surfaces(&frame, &straight(0.5, 0.0)).unwrap();
        assert_eq!(taken(&nearest, 10), vec![8, 9, 10, 11, 12]);
        assert!((0..24)
            .filter(|x| !(8..=12).contains(x))
            .all(|x| nearest[x] == x as u32));
        // Opening at the frame ([0, 0.5]): only ahead of it, 10.5..14.5.
        let nearest = nearest_surfaces(&frame, &straight(0.5, 0.5)).unwrap();
        assert_eq!(taken(&nearest, 10), vec![10, 11, 12, 13, 14]);
        // A streak ending on pixels' edges (6 px a frame: 9.0..12.0) marks the pixels it
        // enters, 9 to 11, as the beauty's streak covers them: neither edge pixel.
        let frame = row(24, &[(10, 1.0, 6.0)]);
        let nearest = nearest_surfaces(&frame, &straight(0.5, 0.0)).unwrap();
        assert_eq!(taken(&nearest, 10), vec![9, 10, 11]);
    }

    #[test]
    fn the_pass_s_longest_streak_bounds_the_carried_one() {
        // reconstruct's k = 2 px a side: 4 px end to end, 8.5..12.5 whatever the speed.
        let frame = row(40, &[(10, 1.0, 60.0)]);
        let streak = Streak {
            longest: 4.0,
            ..straight(0.5, 0.0)
        };
        let nearest = nearest_surfaces(&frame, &streak).unwrap();
        assert_eq!(taken(&nearest, 10), vec![8, 9, 10, 11, 12]);
    }

    #[test]
    fn a_far_streak_does_not_cover_a_nearer_still_surface() {
        // Pixel 10 (depth 50, behind everything) moves across its still neighbours (depth
        // 10): they keep their own values. Pixel 12 (depth 1, still) keeps its own too.
        let frame = row(24, &[(10, 50.0, 8.0), (12, 1.0, 0.0)]);
        let nearest = nearest_surfaces(&frame, &straight(0.5, 0.0)).unwrap();
        assert_eq!(nearest, (0..24).collect::<Vec<u32>>());
    }

    #[test]
    fn a_surface_moving_over_itself_keeps_its_own_values() {
        // Pixels 4 to 15 one surface (depth 2, within the tolerance of each other), moving 8
        // px a frame: inside it nothing shifts (an ID edge between two touching objects at
        // one depth stays put); past its ends, its streak covers the background.
        let movers: Vec<(usize, f32, f32)> =
            (4..16).map(|x| (x, 2.0 + 0.001 * x as f32, 8.0)).collect();
        let frame = row(24, &movers);
        let nearest = nearest_surfaces(&frame, &straight(0.5, 0.0)).unwrap();
        assert_eq!(nearest[4..16], (4..16).collect::<Vec<u32>>()[..]);
        assert_eq!(nearest[2], 4);
        assert_eq!(nearest[17], 15);
        assert_eq!(nearest[1], 1);
    }

    #[test]
    fn of_two_streaks_over_a_pixel_the_nearer_wins_in_any_order() {
        // Pixels 6 (depth 3) and 14 (depth 2) both reach pixel 10 (6 + 4, 14 − 4).
        let frame = row(24, &[(6, 3.0, 16.0), (14, 2.0, -16.0)]);
        let nearest = nearest_surfaces(&frame, &straight(0.5, 0.0)).unwrap();
        assert_eq!(nearest[10], 14);
        assert_eq!(nearest[7], 6);
        assert_eq!(nearest[13], 14);
        // The same on one thread and on many.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| nearest_surfaces(&frame, &straight(0.5, 0.0)).unwrap());
        assert_eq!(one, nearest);
    }

    #[test]
    fn positions_follow_scatter_s_curve() {
        // Pixel (4, 4) of a 12×9 frame came from 2 px to the left and goes 6 px to the right:
        // scatter's quadratic p(t) = p(0) + 4t + 2t² over a centred full shutter runs from
        // x 3.0 to 7.0 (pixels 3 to 6), where two lines bent at the instant would reach 7.5.
        let (w, h) = (12, 9);
        let mut frame = Frame::new(w, h);
        let mut depth = vec![10.0; w * h];
        let centres = |axis: usize| -> Vec<f32> {
            (0..w * h)
                .map(|i| [(i % w) as f32 + 0.5, (i / w) as f32 + 0.5][axis])
                .collect()
        };
        let i = 4 * w + 4;
        depth[i] = 1.0;
        let mut prev = Positions {
            x: centres(0),
            y: centres(1),
            z: None,
        };
        let mut next = prev.clone();
        prev.x[i] -= 2.0;
        next.x[i] += 6.0;
        frame.depth = Some(depth);
        frame.prev = Some(prev);
        frame.next = Some(next);
        let streak = Streak {
            interval: (-0.5, 0.5),
            path: Path::Curve { arc: false },
            longest: f32::INFINITY,
            nearer: Nearer::ByFraction(0.02),
        };
        let nearest = nearest_surfaces(&frame, &streak).unwrap();
        let row_of = |j: usize| (j % w, j / w);
        let taken: Vec<(usize, usize)> =
            taken(&nearest, i as u32).into_iter().map(row_of).collect();
        assert_eq!(taken, vec![(3, 4), (4, 4), (5, 4), (6, 4)]);
    }

    #[test]
    fn huge_and_non_finite_motion_is_followed_a_bounded_way() {
        let frame = row(2000, &[(1000, 1.0, 1e30), (20, 1.0, f32::NAN)]);
        let nearest = nearest_surfaces(&frame, &straight(1.0, 0.0)).unwrap();
        assert_eq!(taken(&nearest, 1000).len(), 2 * MOST_REACH as usize + 1);
        assert_eq!(nearest[20], 20);
        assert_eq!(nearest[21], 21);
    }

    #[test]
    fn without_depth_or_motion_nothing_is_carried() {
        let mut frame = row(8, &[]);
        frame.velocity = None;
        assert!(nearest_surfaces(&frame, &straight(0.5, 0.0)).is_none());
        let mut frame = row(8, &[]);
        frame.depth = None;
        assert!(nearest_surfaces(&frame, &straight(0.5, 0.0)).is_none());
    }

    #[test]
    fn depth_keys_order_depths_and_take_minus_zero_as_zero() {
        let keys: Vec<u32> = [-5.0f32, -0.5, 0.0, 0.5, 7.0, f32::NAN]
            .map(depth_key)
            .to_vec();
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "{keys:?}");
        assert_eq!(depth_key(-0.0), depth_key(0.0));
    }

    #[test]
    fn carried_takes_each_pixel_s_value_from_its_nearest() {
        assert_eq!(carried(&[1u32, 2, 3, 4], &[0, 0, 3, 2]), vec![1, 1, 4, 3]);
    }
}
