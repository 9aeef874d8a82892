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
//! In: the frame's depth (smaller is nearer), its motion (the velocity, p(0) − p(−1), or the
//! previous and next positions, a streak bending at the frame's instant) and the exposure.
//! Out: for every pixel, the index of the pixel whose value it takes. Each moving surface
//! marks the pixels its streak crosses (points a pixel or less apart along it, each followed
//! at most [`MOST_REACH`] px from its pixel) with its depth and index, keeping the least:
//! the same answer in any order, so for any thread count. Still frames cost one pass over
//! the pixels. Runs on the CPU for every backend (the data is never on the GPU).

use std::sync::atomic::{AtomicU64, Ordering};

use rayon::prelude::*;

use super::shutter::Shutter;
use crate::frame::{Frame, Positions, Velocity};

/// How far a streak is followed from its pixel, each way, in pixels: reconstruct's largest
/// blur by default (`max_blur`, 128) twice over, so every streak a pass draws is covered and a
/// frame's cost stays bounded (a 1080p frame of huge vectors marks at most 2 × 256 points a
/// pixel).
pub const MOST_REACH: f32 = 256.0;

/// A depth as a key whose unsigned order is the depth's order (negative depths before
/// positive ones; NaN, which the numeric policy leaves no depth holding, last).
fn depth_key(z: f32) -> u32 {
    if z.is_nan() {
        return u32::MAX;
    }
    let bits = z.to_bits();
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

impl Motion<'_> {
    /// Where pixel i's surface (at `centre` at the frame's instant) is at time t, as a
    /// displacement from `centre`, before and after the instant.
    fn displacement(&self, i: usize, centre: (f32, f32), t: f32) -> (f32, f32) {
        match self {
            Motion::Velocity(v) => (v.x[i] * t, v.y[i] * t),
            Motion::Positions(prev, next) => {
                // p(t) = p(0) + t·(p(0) − p(−1)) before the instant, p(0) + t·(p(1) − p(0))
                // after it.
                let (x, y) = if t < 0.0 {
                    (centre.0 - prev.x[i], centre.1 - prev.y[i])
                } else {
                    (next.x[i] - centre.0, next.y[i] - centre.1)
                };
                (x * t, y * t)
            }
        }
    }
}

/// For every pixel, the index of the pixel whose value a `motion` layer takes there: the
/// nearest surface (least depth; the lower index on a tie) among those whose streak over
/// the exposure `shutter` covers it, its own among them. `None` when the frame has no depth
/// or no motion (the layer then comes back unchanged).
pub fn nearest_surfaces(frame: &Frame, shutter: Shutter) -> Option<Vec<u32>> {
    let depth = frame.depth.as_ref()?;
    let motion = match (&frame.velocity, &frame.prev, &frame.next) {
        (Some(v), _, _) => Motion::Velocity(v),
        (None, Some(prev), Some(next)) => Motion::Positions(prev, next),
        _ => return None,
    };
    let (width, height) = (frame.width, frame.height);
    let key = |i: usize| (u64::from(depth_key(depth[i])) << 32) | i as u64;
    let nearest: Vec<AtomicU64> = (0..width * height)
        .into_par_iter()
        .map(|i| AtomicU64::new(key(i)))
        .collect();
    let (t0, t1) = shutter.interval();
    // The streak's pieces: before the instant and after it (positions bend there).
    let pieces: Vec<(f32, f32)> = [(t0, t1.min(0.0)), (t0.max(0.0), t1)]
        .into_iter()
        .filter(|(a, b)| a < b)
        .collect();
    (0..height).into_par_iter().for_each(|y| {
        for x in 0..width {
            let i = y * width + x;
            let centre = (x as f32 + 0.5, y as f32 + 0.5);
            let mine = key(i);
            for &(a, b) in &pieces {
                let from = reached(motion.displacement(i, centre, a));
                let to = reached(motion.displacement(i, centre, b));
                let (dx, dy) = (to.0 - from.0, to.1 - from.1);
                // Points at most a pixel apart along the piece, its two ends included.
                let steps = dx.abs().max(dy.abs()).ceil() as usize;
                for s in 0..=steps {
                    let f = if steps == 0 {
                        0.0
                    } else {
                        s as f32 / steps as f32
                    };
                    let px = (centre.0 + from.0 + dx * f).floor();
                    let py = (centre.1 + from.1 + dy * f).floor();
                    if px < 0.0 || py < 0.0 || px >= width as f32 || py >= height as f32 {
                        continue;
                    }
                    let j = py as usize * width + px as usize;
                    if j != i {
                        nearest[j].fetch_min(mine, Ordering::Relaxed);
                    }
                }
            }
        }
    });
    Some(nearest.into_iter().map(|k| k.into_inner() as u32).collect())
}

/// A displacement followed at most [`MOST_REACH`] px (its direction kept); none where it is
/// not finite.
fn reached((x, y): (f32, f32)) -> (f32, f32) {
    let length = x.hypot(y);
    if !length.is_finite() {
        return (0.0, 0.0);
    }
    if length > MOST_REACH {
        let scale = MOST_REACH / length;
        (x * scale, y * scale)
    } else {
        (x, y)
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

    #[test]
    fn a_near_streak_takes_the_pixels_it_crosses_and_no_others() {
        // Pixel 10 (depth 1) moves 8 px a frame; a centred shutter of 0.5 smears it over
        // ±2 px: pixels 8 to 12 take its value, the rest keep their own.
        let frame = row(24, &[(10, 1.0, 8.0)]);
        let nearest = nearest_surfaces(&frame, Shutter::centred(0.5)).unwrap();
        let want: Vec<u32> = (0..24)
            .map(|x| if (8..=12).contains(&x) { 10 } else { x })
            .collect();
        assert_eq!(nearest, want);
        // Opening at the frame ([0, 0.5]): only ahead of it, pixels 10 to 14.
        let start = Shutter {
            open: 0.5,
            offset: 0.5,
        };
        let nearest = nearest_surfaces(&frame, start).unwrap();
        let want: Vec<u32> = (0..24)
            .map(|x| if (10..=14).contains(&x) { 10 } else { x })
            .collect();
        assert_eq!(nearest, want);
    }

    #[test]
    fn a_far_streak_does_not_cover_a_nearer_still_surface() {
        // Pixel 10 (depth 50, behind everything) moves across its still neighbours (depth
        // 10): they keep their own values. Pixel 12 (depth 1, still) keeps its own too.
        let frame = row(24, &[(10, 50.0, 8.0), (12, 1.0, 0.0)]);
        let nearest = nearest_surfaces(&frame, Shutter::centred(0.5)).unwrap();
        assert_eq!(nearest, (0..24).collect::<Vec<u32>>());
    }

    #[test]
    fn of_two_streaks_over_a_pixel_the_nearer_wins_in_any_order() {
        // Pixels 6 (depth 3) and 14 (depth 2) both reach pixel 10 (6 + 4, 14 − 4).
        let frame = row(24, &[(6, 3.0, 16.0), (14, 2.0, -16.0)]);
        let nearest = nearest_surfaces(&frame, Shutter::centred(0.5)).unwrap();
        assert_eq!(nearest[10], 14);
        assert_eq!(nearest[7], 6);
        assert_eq!(nearest[13], 14);
        // The same on one thread and on many.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| nearest_surfaces(&frame, Shutter::centred(0.5)).unwrap());
        assert_eq!(one, nearest);
    }

    #[test]
    fn positions_bend_the_streak_at_the_frame_s_instant() {
        // Pixel (4, 4) of a 9×9 frame came from the left (prev 2 px left) and goes down
        // (next 2 px down): a centred full shutter covers (3..=4, 4) and (4, 4..=5).
        let (w, h) = (9, 9);
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
        next.y[i] += 2.0;
        frame.depth = Some(depth);
        frame.prev = Some(prev);
        frame.next = Some(next);
        let nearest = nearest_surfaces(&frame, Shutter::centred(1.0)).unwrap();
        let taken: Vec<(usize, usize)> = (0..w * h)
            .filter(|&j| nearest[j] as usize == i)
            .map(|j| (j % w, j / w))
            .collect();
        assert_eq!(taken, vec![(3, 4), (4, 4), (4, 5)]);
    }

    #[test]
    fn huge_and_non_finite_motion_is_followed_a_bounded_way() {
        let frame = row(1000, &[(500, 1.0, 1e30), (20, 1.0, f32::NAN)]);
        let nearest = nearest_surfaces(&frame, Shutter::centred(1.0)).unwrap();
        let taken = nearest.iter().filter(|&&j| j == 500).count();
        assert_eq!(taken, 2 * MOST_REACH as usize + 1);
        assert_eq!(nearest[20], 20);
        assert_eq!(nearest[21], 21);
    }

    #[test]
    fn without_depth_or_motion_nothing_is_carried() {
        let mut frame = row(8, &[]);
        frame.velocity = None;
        assert!(nearest_surfaces(&frame, Shutter::centred(0.5)).is_none());
        let mut frame = row(8, &[]);
        frame.depth = None;
        assert!(nearest_surfaces(&frame, Shutter::centred(0.5)).is_none());
    }

    #[test]
    fn carried_takes_each_pixel_s_value_from_its_nearest() {
        assert_eq!(carried(&[1u32, 2, 3, 4], &[0, 0, 3, 2]), vec![1, 1, 4, 3]);
    }
}
