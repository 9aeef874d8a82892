//! Unit tests of the fit ([`super`]): scenes of three frames built in memory, with outliers
//! of the kinds a render gives (occluded points, a periodic wall's false matches).
use super::*;

/// Value noise on a 3-pixel lattice, bilinear between lattice values (a texture defined at
/// every real position, so a shifted copy is exact).
fn noise(x: f32, y: f32, seed: u64) -> f32 {
    let lattice = |i: i64, j: i64| {
        let mut h = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (j as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ seed.wrapping_mul(0x1656_67B1_9E37_79F9);
        h ^= h >> 29;
        h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h ^= h >> 32;
        (h % 1000) as f32 / 1000.0
    };
    let (u, v) = (x / 3.0, y / 3.0);
    let (i, j) = (u.floor() as i64, v.floor() as i64);
    let (fu, fv) = (u - u.floor(), v - v.floor());
    let top = lattice(i, j) * (1.0 - fu) + lattice(i + 1, j) * fu;
    let bottom = lattice(i, j + 1) * (1.0 - fu) + lattice(i + 1, j + 1) * fu;
    top * (1.0 - fv) + bottom * fv
}

/// A still wall and a square of side `side` whose top-left corner is at `corner[t]` in frame
/// t (0: previous, 1: current, 2: next), painted by `wall` and `square` (each given the
/// position relative to its own origin).
struct Scene {
    w: usize,
    h: usize,
    side: f32,
    corner: [(f32, f32); 3],
    wall: fn(f32, f32) -> f32,
    square: fn(f32, f32) -> f32,
}

impl Scene {
    /// Whether pixel centre (x, y) of frame t is on the square.
    fn on_square(&self, t: usize, x: f32, y: f32) -> bool {
        let (cx, cy) = self.corner[t];
        (cx..cx + self.side).contains(&x) && (cy..cy + self.side).contains(&y)
    }

    /// Frame t's luma.
    fn frame(&self, t: usize) -> Vec<f32> {
        let (cx, cy) = self.corner[t];
        (0..self.w * self.h)
            .map(|i| {
                let (x, y) = ((i % self.w) as f32 + 0.5, (i / self.w) as f32 + 0.5);
                if self.on_square(t, x, y) {
                    (self.square)(x - cx, y - cy)
                } else {
                    (self.wall)(x, y)
                }
            })
            .collect()
    }

    /// The stored components at the current frame: `on` on the square, `off` elsewhere
    /// (each given the pixel's index).
    fn stored(
        &self,
        on: impl Fn(usize) -> [f32; 2],
        off: impl Fn(usize) -> [f32; 2],
    ) -> [Vec<f32>; 2] {
        let values: Vec<[f32; 2]> = (0..self.w * self.h)
            .map(|i| {
                let (x, y) = ((i % self.w) as f32 + 0.5, (i / self.w) as f32 + 0.5);
                if self.on_square(1, x, y) {
                    on(i)
                } else {
                    off(i)
                }
            })
            .collect();
        [0, 1].map(|axis| values.iter().map(|v| v[axis]).collect())
    }

    /// The fit of the current frame against both neighbours.
    fn fit(&self, stored: &[Vec<f32>; 2]) -> Fit {
        let frames = [self.frame(0), self.frame(1), self.frame(2)];
        fit(&FitInput {
            width: self.w,
            height: self.h,
            current: &frames[1],
            prev: Some(&frames[0]),
            next: Some(&frames[2]),
            stored: [&stored[0], &stored[1]],
            max_points: FIT_POINTS,
        })
    }
}

/// A stored value that is a renderer's float noise: under ±0.01, different at every pixel.
fn dust(i: usize, seed: u64) -> f32 {
    (noise(i as f32 * 3.0, 0.0, seed) - 0.5) * 0.02
}

/// Asserts the verdict's own test, like with like: no reading fits clearly better (half
/// the residual) than no motion, and none is chosen.
fn assert_nothing_beats_no_motion(f: &Fit) {
    for r in &f.readings {
        assert!(
            r.residual > 0.5 * f.no_motion,
            "{} fits to {} px against no motion's {} px",
            describe(r),
            r.residual,
            f.no_motion
        );
    }
    assert!(f.chosen.is_none(), "{:?}", f.chosen.as_ref().map(describe));
    let why = f.why.as_deref().unwrap_or_default();
    assert!(why.contains("no motion"), "{why}");
}

/// F5: a vector pass that holds nothing of a textured square's motion (float dust on every
/// pixel): every reading fits with a scale near zero, and no motion, scored by the same
/// capped measure, fits as well. Before, no motion was an uncapped RMS that the square's
/// points (off by ~12 px) blew up to several pixels, so any near-zero reading passed for
/// twice as good as no motion; only the tie rule kept one from being chosen.
#[test]
fn a_reading_of_scale_near_zero_does_not_beat_no_motion() {
    let scene = Scene {
        w: 96,
        h: 64,
        side: 24.0,
        corner: [(20.0, 14.0), (30.0, 20.0), (42.0, 27.0)],
        wall: |x, y| noise(x, y, 3),
        square: |x, y| noise(x, y, 7),
    };
    let stored = scene.stored(|i| [dust(i, 1), dust(i, 2)], |i| [dust(i, 1), dust(i, 2)]);
    let f = scene.fit(&stored);
    assert!(f.no_motion <= TRUNCATE, "no motion {} px", f.no_motion);
    assert!(f.readings[0].is_still(), "{}", describe(&f.readings[0]));
    assert_nothing_beats_no_motion(&f);
}

/// F5's real render, in small: a flat square moving 35 px a frame before a still checker
/// wall of 22-pixel squares (so shifting it 22 px on both axes gives it back). The square
/// has nothing to follow, and the wall it uncovers and covers matched the checker one
/// period away, on the rim of the search (22 px at this size): points that moved nowhere
/// read as 31 px of motion. Such rim matches are not taken, and what is left is no motion.
#[test]
fn a_flat_square_before_a_periodic_wall_fits_nothing() {
    let scene = Scene {
        w: 160,
        h: 90,
        side: 40.0,
        corner: [(25.0, 24.0), (60.0, 25.0), (95.0, 26.0)],
        wall: |x, y| {
            let (i, j) = ((x / 22.0).floor() as i64, (y / 22.0).floor() as i64);
            if (i + j) % 2 == 0 {
                0.8
            } else {
                0.2
            }
        },
        square: |_, _| 0.45,
    };
    // The blender preset's reading: to_prev, y up, pixels.
    let stored = scene.stored(|_| [-35.0, 1.0], |_| [0.0, 0.0]);
    let f = scene.fit(&stored);
    let toward_prev = f
        .motion_toward(false)
        .expect("the previous frame was measured");
    assert!(
        toward_prev[0].hypot(toward_prev[1]) < 1.0,
        "motion measured toward the previous frame: {toward_prev:?}"
    );
    assert!(f.no_motion <= TRUNCATE, "no motion {} px", f.no_motion);
    assert_nothing_beats_no_motion(&f);
}

/// What the capped comparison must keep: a small textured square (a few per cent of the
/// points) over a still wall, its motion stored as velocity in pixels, y down, is chosen,
/// though no motion misses only the square's points and the points it uncovers.
#[test]
fn a_small_moving_square_is_still_fitted() {
    let scene = Scene {
        w: 96,
        h: 72,
        side: 24.0,
        corner: [(26.0, 18.0), (35.0, 23.0), (47.0, 30.0)],
        wall: |x, y| noise(x, y, 3),
        square: |x, y| noise(x, y, 7),
    };
    let stored = scene.stored(|_| [9.0, 5.0], |_| [0.0, 0.0]);
    let f = scene.fit(&stored);
    let chosen = f.chosen.as_ref().unwrap_or_else(|| {
        panic!(
            "{:?}; {:?}",
            f.why,
            f.readings.iter().take(3).map(describe).collect::<Vec<_>>()
        )
    });
    assert_eq!(
        (
            chosen.meaning,
            chosen.swap,
            chosen.y_up,
            chosen.zero,
            chosen.scale
        ),
        (Meaning::Velocity, false, false, 0.0, 1.0),
        "{}",
        describe(chosen)
    );
}

/// A reading as the fit gives it: velocity in pixels, y down, with this residual and motion.
fn reading(residual: f64, motion: f64) -> Reading {
    Reading {
        meaning: Meaning::Velocity,
        swap: false,
        y_up: false,
        zero: 0.0,
        scale: 1.0,
        units: Units::Pixels,
        residual,
        motion,
        fitted_scale: [1.0; 2],
        consistent: true,
    }
}

/// A reading that fits to under half no motion's residual but moves the points by less
/// than measured motion must ([`STILL`]) is no motion itself, not chosen; the same fit with
/// motion to speak of is chosen.
#[test]
fn a_reading_that_moves_nothing_is_no_motion() {
    let (chosen, why) = decide(&[reading(0.1, 0.1)], [0.3, 5.0], 500, [true; 2]);
    assert!(chosen.is_none());
    assert!(why.unwrap().contains("no motion itself"));
    let (chosen, why) = decide(&[reading(0.1, 2.0)], [0.3, 5.0], 500, [true; 2]);
    assert_eq!(chosen, Some(reading(0.1, 2.0)), "{why:?}");
}

/// Points followed with no reading of positive scale is no motion fitting best, not "no
/// point could be followed" (which is for no points).
#[test]
fn no_reading_of_positive_scale_is_no_motion_fitting_best() {
    let (chosen, why) = decide(&[], [0.3, 5.0], 500, [true; 2]);
    assert!(chosen.is_none());
    assert!(why
        .unwrap()
        .contains("nothing fits clearly better than no motion"));
    let (_, why) = decide(&[], [0.0, 0.0], 0, [true; 2]);
    assert!(why.unwrap().contains("no textured point"));
}

/// The tester's L15: one textured square speeding up over a still wall (12 px then 20 px a
/// frame, stored as to_next): velocity read off the previous frame with scale 0.6 fits as
/// well as to_next with scale 1, so the fit is rightly undecided; but its reason said the
/// motion was the same before and after the frame, which is false here. It now says how
/// the motion changed (20 / 12 = 1.667), as it does for a square turning back, one turning a
/// quarter (its x and y swapped, the new x the old y reversed, stored y down or y up: the
/// swapped readings' y axes decide which is reversed) and one bouncing off a floor (its y
/// reversed), and keeps the old reason for a steady square.
#[test]
fn a_square_changing_its_motion_is_undecided_for_the_change_it_makes() {
    let scene = |corner| Scene {
        w: 128,
        h: 96,
        side: 40.0,
        corner,
        wall: |x, y| noise(x, y, 3),
        square: |x, y| noise(x, y, 7),
    };
    // The square's corner in each frame, its motion to the next frame, the reason.
    type Case = ([(f32, f32); 3], [f32; 2], &'static str);
    let cases: [Case; 6] = [
        (
            [(20.0, 14.0), (32.0, 20.0), (52.0, 30.0)],
            [20.0, 10.0],
            "times 1.667",
        ),
        // A quarter turn: (12, 4) then (−4, 12), stored y down and y up.
        (
            [(40.0, 30.0), (52.0, 34.0), (48.0, 46.0)],
            [-4.0, 12.0],
            "with x and y swapped, with its x reversed",
        ),
        (
            [(40.0, 30.0), (52.0, 34.0), (48.0, 46.0)],
            [-4.0, -12.0],
            "with x and y swapped, with its x reversed",
        ),
        (
            [(30.0, 20.0), (42.0, 26.0), (30.0, 20.0)],
            [-12.0, -6.0],
            "before it reversed",
        ),
        (
            [(30.0, 20.0), (42.0, 26.0), (54.0, 20.0)],
            [12.0, -6.0],
            "with its y reversed",
        ),
        (
            [(20.0, 14.0), (32.0, 20.0), (44.0, 26.0)],
            [12.0, 6.0],
            "the same before and after",
        ),
    ];
    for (corner, next, reason) in cases {
        let square = scene(corner);
        let f = square.fit(&square.stored(|_| next, |_| [0.0, 0.0]));
        assert!(f.chosen.is_none(), "{:?}", f.chosen.as_ref().map(describe));
        let why = f.why.as_deref().unwrap_or_default();
        assert!(why.contains(reason), "{corner:?}: {why}");
        let steady = reason.contains("the same");
        assert_eq!(why.contains("the same before and after"), steady, "{why}");
    }
}
