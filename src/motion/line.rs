//! Line rasterisation with sub-pixel coverage, for `scatter`.
//!
//! Method (Wu-style, with exact fractional end points): walk the segment's major axis one
//! pixel column (or row) at a time. Each column receives the exact length of the segment
//! inside it — the column's share of the major extent, clipped at the segment's fractional end
//! points, times `√(1 + m²)` — and that length is split between the two pixels whose centres
//! are nearest the segment at the middle of that share, linearly (a tent one pixel each side
//! of the line). So the coverages of a segment sum exactly to its length, a segment moved by a
//! fraction of a pixel moves its coverage smoothly, and a pixel-wide patch sliding along the
//! segment is what is drawn (box along the motion, tent across it).
//!
//! Clipping: only pixels in the clip rectangle receive coverage, and only columns whose
//! segment piece can reach it are visited, so a segment millions of pixels long costs the
//! columns it crosses inside the rectangle. Each column's coverage is computed from the whole
//! segment, never from a clipped copy, so drawing a segment into two adjacent rectangles gives
//! exactly the coverages of drawing it into their union. Non-finite end points draw nothing.
//!
//! [`draw_spans`] hands each column to a callback; `scatter`'s hot loop instead takes the
//! [`Walk`] itself: it computes the end columns (the segment's fractional end points) exactly
//! and steps the columns crossed whole in 32-bit fixed point ([`Whole`]: a row and its split
//! from an integer add, a shift and a mask, to 2⁻³² px), and leaves the rows unclipped (they
//! overhang the clip by at most [`OVERHANG`]), so the caller pads its cells instead of testing
//! every row.

/// `v.floor()` without the library call (baseline x86-64 has no rounding instruction):
/// truncation corrected for negatives; values this large are integers already.
#[inline]
pub fn floor(v: f64) -> f64 {
    if v.abs() < 4.0e15 {
        let t = v as i64 as f64;
        if t > v {
            t - 1.0
        } else {
            t
        }
    } else {
        v
    }
}

/// Added before truncating a row coordinate so truncation is a floor (rows of any image are
/// far inside ±2³¹).
const ROW_SHIFT: f64 = 2147483648.0;

/// The pixels that may receive coverage: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Clip {
    pub x0: i64,
    pub y0: i64,
    pub x1: i64,
    pub y1: i64,
}

/// One column (or row) of a segment: pixel `first` gets coverage `c0` and `second` gets
/// `c1` (a coverage is 0 where its pixel is outside the clip, and then the pixel may be too);
/// `u` is where along the segment (0 at `a`, 1 at `b`) they were measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Span {
    pub first: (i64, i64),
    pub second: (i64, i64),
    pub c0: f64,
    pub c1: f64,
    pub u: f64,
}

/// Draws the segment from `a` to `b` (pixel coordinates: pixel (i, j) covers
/// [i, i+1) × [j, j+1)), one [`Span`] per column (row) it crosses near `clip`.
#[inline(always)]
pub fn draw_spans(a: [f64; 2], b: [f64; 2], clip: Clip, mut span: impl FnMut(Span)) {
    let Some(walk) = Walk::new(a, b, clip) else {
        return;
    };
    let (rows, pixel) = (walk.rows.0..walk.rows.1, |major: i64, minor: i64| {
        if walk.swapped {
            (minor, major)
        } else {
            (major, minor)
        }
    });
    for column in walk.first..=walk.last {
        let c = walk.column(column);
        let c0 = if rows.contains(&c.row) { c.c0 } else { 0.0 };
        let c1 = if rows.contains(&(c.row + 1)) {
            c.c1
        } else {
            0.0
        };
        if c0 > 0.0 || c1 > 0.0 {
            span(Span {
                first: pixel(column, c.row),
                second: pixel(column, c.row + 1),
                c0,
                c1,
                u: c.u,
            });
        }
    }
}

/// [`draw_spans`] one pixel at a time: `deposit(x, y, coverage, u)` for each pixel in `clip`
/// with coverage.
#[inline(always)]
pub fn draw(a: [f64; 2], b: [f64; 2], clip: Clip, mut deposit: impl FnMut(i64, i64, f64, f64)) {
    draw_spans(a, b, clip, |s| {
        if s.c0 > 0.0 {
            deposit(s.first.0, s.first.1, s.c0, s.u);
        }
        if s.c1 > 0.0 {
            deposit(s.second.0, s.second.1, s.c1, s.u);
        }
    });
}

/// How far outside a clip's rows (columns, for a walk along y) a [`Walk`]'s rows can fall:
/// row and row + 1 of every walked column lie in `y0 − OVERHANG .. y1 + OVERHANG`.
pub const OVERHANG: i64 = 4;

/// A segment's walk along its major axis, for callers that deposit coverage themselves (the
/// hot loop of `scatter`): columns `first..=last` (rows where `swapped`, the walk along y),
/// each split by [`Walk::column`] between two rows. Unlike [`draw_spans`] it leaves the
/// minor axis unclipped: rows may overhang the clip by up to [`OVERHANG`] pixels.
#[derive(Clone, Copy, Debug)]
pub struct Walk {
    /// The walk runs along y: a column is a pixel row and its "rows" are pixel columns.
    pub swapped: bool,
    pub first: i64,
    pub last: i64,
    /// The clip along the minor axis: rows `rows.0..rows.1`.
    pub rows: (i64, i64),
    a: [f64; 2],
    lo: f64,
    hi: f64,
    inverse: f64,
    slope: f64,
    stretch: f64,
}

/// The columns a [`Walk`] crosses whole, `first..=last` (empty where `last < first`), with
/// the walk's rows in fixed point, so stepping a column costs a few integer operations: at
/// column `first + k`, the segment is at row coordinate `(y + k·step) / 2³²` (the rows'
/// centres at integers) and at `u + k·du` along it, and the column's coverage is `coverage`.
/// `first` is in `walk.first..=walk.last + 1` and `last` in `first − 1..=walk.last`, so the
/// walk's other columns are `walk.first..first` and `last + 1..=walk.last`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Whole {
    pub first: i64,
    pub last: i64,
    pub y: i64,
    pub step: i64,
    pub u: f64,
    pub du: f64,
    pub coverage: f64,
}

/// One in 2³² of a pixel: the resolution of [`Whole`]'s fixed point.
const FIXED: f64 = 4294967296.0;

impl Whole {
    /// The column `k` steps after `first`, as [`Walk::column`] gives it (to fixed-point
    /// rounding).
    #[inline(always)]
    pub fn column(&self, k: i64) -> Column {
        let y = self.y.wrapping_add(self.step.wrapping_mul(k));
        let f = (y as u32) as f64 * (1.0 / FIXED);
        Column {
            row: y >> 32,
            c0: self.coverage * (1.0 - f),
            c1: self.coverage * f,
            u: self.u + k as f64 * self.du,
        }
    }
}

/// One column of a [`Walk`]: rows `row` and `row + 1` get coverages `c0` and `c1` (neither
/// negative), measured at `u` along the segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Column {
    pub row: i64,
    pub c0: f64,
    pub c1: f64,
    pub u: f64,
}

impl Walk {
    /// The walk of the segment from `a` to `b` over the columns near `clip`; `None` where it
    /// covers nothing there (or is degenerate or not finite).
    #[inline(always)]
    pub fn new(a: [f64; 2], b: [f64; 2], clip: Clip) -> Option<Walk> {
        if !(a.iter().chain(&b).all(|v| v.is_finite())) {
            return None;
        }
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        if dx == 0.0 && dy == 0.0 {
            return None;
        }
        if dx.abs() >= dy.abs() {
            Walk::major(a, b, (clip.x0, clip.x1), (clip.y0, clip.y1), false)
        } else {
            // The same walk with the axes swapped.
            Walk::major(
                [a[1], a[0]],
                [b[1], b[0]],
                (clip.y0, clip.y1),
                (clip.x0, clip.x1),
                true,
            )
        }
    }

    /// The walk along x (|dx| ≥ |dy| > 0 or dx ≠ 0).
    #[inline(always)]
    fn major(
        a: [f64; 2],
        b: [f64; 2],
        (x0, x1): (i64, i64),
        (y0, y1): (i64, i64),
        swapped: bool,
    ) -> Option<Walk> {
        if x0 >= x1 || y0 >= y1 {
            return None;
        }
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let inverse = 1.0 / dx;
        let slope = dy * inverse;
        let stretch = (1.0 + slope * slope).sqrt();
        let (lo, hi) = (a[0].min(b[0]), a[0].max(b[0]));
        // Columns the segment covers, inside the clip.
        let mut first = floor(lo).max(x0 as f64);
        let mut last = (-floor(-hi) - 1.0).min((x1 - 1) as f64);
        // Columns where the segment is within reach of the clip's rows: a row j receives
        // coverage only while the segment is within one pixel of its centre j + ½. With a
        // margin of a column each side, so the clip never changes a column's own coverage.
        // (In those columns the middle of the segment's piece is within 2.5 columns, so, as
        // |slope| ≤ 1, 2.5 rows, of [y0 − ½, y1 + ½]: rows y0 − 3 to y1 + 3 at most.)
        let (ylo, yhi) = (y0 as f64 - 0.5, y1 as f64 + 0.5);
        let inside = a[1].min(b[1]) >= ylo && a[1].max(b[1]) <= yhi;
        // A segment inside that band is within reach of the rows all along: nothing to cut.
        if !inside {
            if slope == 0.0 {
                return None;
            }
            let run = dx / dy;
            let xa = a[0] + (ylo - a[1]) * run;
            let xb = a[0] + (yhi - a[1]) * run;
            first = first.max(floor(xa.min(xb)) - 1.0);
            last = last.min(-floor(-xa.max(xb)) + 1.0);
        }
        if first.is_nan() || last.is_nan() || first > last {
            return None;
        }
        Some(Walk {
            swapped,
            first: first as i64,
            last: last as i64,
            rows: (y0, y1),
            a,
            lo,
            hi,
            inverse,
            slope,
            stretch,
        })
    }

    /// The columns in `first..=last` that the segment crosses whole.
    #[inline(always)]
    pub fn whole(&self) -> Whole {
        let (first, last) = (self.first as f64, self.last as f64);
        // ⌈lo⌉ and ⌊hi⌋ − 1, clamped first (they may be far off-screen).
        let start = (-floor(-self.lo)).clamp(first, last + 1.0);
        let end = (floor(self.hi) - 1.0).clamp(start - 1.0, last);
        let along = start + 0.5 - self.a[0];
        // Row coordinate of the segment at the column's middle, rows' centres at integers;
        // near the clip, so far inside the fixed point's ±2³¹ pixels.
        let y = self.a[1] + self.slope * along - 0.5;
        Whole {
            first: start as i64,
            last: end as i64,
            y: (y * FIXED) as i64,
            step: (self.slope * FIXED) as i64,
            u: along * self.inverse,
            du: self.inverse,
            coverage: self.stretch,
        }
    }

    /// Column `column` (in `first..=last`): the exact length of the segment inside it, split
    /// between the two rows whose centres bracket the segment at the middle of that piece.
    #[inline(always)]
    pub fn column(&self, column: i64) -> Column {
        let c = column as f64;
        // The segment's piece in the column, [left, right] along x: the whole column inside
        // the segment, else clipped at its fractional end points (never empty in
        // first..=last, where lo < c + 1 and c < hi).
        let (left, right) = (self.lo.max(c), self.hi.min(c + 1.0));
        let middle = 0.5 * (left + right);
        let along = middle - self.a[0];
        let u = along * self.inverse;
        let y = self.a[1] + self.slope * along;
        let coverage = (right - left) * self.stretch;
        // Split between the two rows whose centres bracket y. Within the walked columns
        // y is near the clip, so shifting by 2³¹ makes truncation a floor.
        let v = y - 0.5 + ROW_SHIFT;
        let shifted = v as i64;
        let f = v - shifted as f64;
        Column {
            row: shifted - ROW_SHIFT as i64,
            c0: coverage * (1.0 - f),
            c1: coverage * f,
            u,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::truth::sample::hash01;
    use crate::numeric::close;

    const BIG: Clip = Clip {
        x0: -1000,
        y0: -1000,
        x1: 1000,
        y1: 1000,
    };

    fn total(a: [f64; 2], b: [f64; 2], clip: Clip) -> (f64, usize) {
        let (mut sum, mut count) = (0.0, 0);
        draw(a, b, clip, |x, y, c, u| {
            assert!((clip.x0..clip.x1).contains(&x) && (clip.y0..clip.y1).contains(&y));
            assert!(c >= 0.0 && (-1e-9..=1.0 + 1e-9).contains(&u));
            sum += c;
            count += 1;
        });
        (sum, count)
    }

    #[test]
    fn coverage_sums_to_the_length_for_random_lines() {
        for k in 0..2000u64 {
            let r = |i: u64| hash01(7, k, i, 0) * 200.0 - 100.0;
            let (a, b) = ([r(0), r(1)], [r(2), r(3)]);
            let length = (b[0] - a[0]).hypot(b[1] - a[1]);
            let (sum, _) = total(a, b, BIG);
            assert!(
                close(sum, length, 0.01 * length),
                "{a:?} → {b:?}: {sum} vs {length}"
            );
        }
    }

    #[test]
    fn splitting_the_clip_splits_the_coverage_exactly() {
        for k in 0..500u64 {
            let r = |i: u64| hash01(8, k, i, 0) * 60.0 - 10.0;
            let (a, b) = ([r(0), r(1)], [r(2), r(3)]);
            let whole = Clip {
                x0: 0,
                y0: 0,
                x1: 40,
                y1: 40,
            };
            let mut full = vec![0.0; 1600];
            draw(a, b, whole, |x, y, c, _| full[(y * 40 + x) as usize] += c);
            let mut parts = vec![0.0; 1600];
            for (x0, y0) in [(0, 0), (17, 0), (0, 23), (17, 23)] {
                let clip = Clip {
                    x0,
                    y0,
                    x1: if x0 == 0 { 17 } else { 40 },
                    y1: if y0 == 0 { 23 } else { 40 },
                };
                draw(a, b, clip, |x, y, c, _| parts[(y * 40 + x) as usize] += c);
            }
            assert_eq!(full, parts, "{a:?} → {b:?}");
        }
    }

    #[test]
    fn a_horizontal_line_through_centres_covers_its_row_only() {
        let mut got = Vec::new();
        draw([2.25, 5.5], [6.0, 5.5], BIG, |x, y, c, _| {
            got.push((x, y, c))
        });
        assert_eq!(
            got,
            vec![(2, 5, 0.75), (3, 5, 1.0), (4, 5, 1.0), (5, 5, 1.0)]
        );
        // Half a pixel down, it splits evenly between two rows.
        let (sum, count) = total([0.0, 6.0], [4.0, 6.0], BIG);
        assert_eq!((sum, count), (4.0, 8));
    }

    #[test]
    fn far_off_screen_segments_cost_only_what_they_cross() {
        let clip = Clip {
            x0: 0,
            y0: 0,
            x1: 64,
            y1: 64,
        };
        // Crossing the clip diagonally from a million pixels away.
        let mut visits = 0;
        draw([-1e6, -1e6], [1e6, 1e6 + 3.0], clip, |_, _, _, _| {
            visits += 1
        });
        assert!((64..=130).contains(&visits), "{visits}");
        let (sum, _) = total([-1e6, 10.5], [1e6, 10.5], clip);
        assert!(close(sum, 64.0, 1e-6));
        // Entirely outside: nothing, quickly.
        assert_eq!(total([-1e9, -5e8], [1e9, -4e8], clip).1, 0);
        assert_eq!(total([1e12, 3.0], [1e12 + 5.0, 3.0], clip).1, 0);
    }

    /// The walks over `clip` of `count` random segments with end points in
    /// [lo, lo + span)² (those that cover anything there).
    fn random_walks(seed: u64, count: u64, lo: f64, span: f64, clip: Clip) -> Vec<Walk> {
        (0..count)
            .filter_map(|k| {
                let r = |i: u64| lo + hash01(seed, k, i, 0) * span;
                Walk::new([r(0), r(1)], [r(2), r(3)], clip)
            })
            .collect()
    }

    #[test]
    fn a_walk_overhangs_its_clip_by_at_most_overhang() {
        let clip = Clip {
            x0: 10,
            y0: 20,
            x1: 30,
            y1: 25,
        };
        let mut columns = 0;
        for walk in random_walks(10, 20_000, -10.0, 60.0, clip) {
            let (major, minor) = if walk.swapped {
                ((clip.y0, clip.y1), (clip.x0, clip.x1))
            } else {
                ((clip.x0, clip.x1), (clip.y0, clip.y1))
            };
            assert_eq!(walk.rows, minor);
            assert!(walk.first >= major.0 && walk.last < major.1);
            for column in walk.first..=walk.last {
                let c = walk.column(column);
                assert!(c.row >= minor.0 - OVERHANG && c.row + 1 < minor.1 + OVERHANG);
                assert!(c.c0 >= 0.0 && c.c1 >= 0.0);
                columns += 1;
            }
        }
        assert!(columns > 10_000, "{columns}");
    }

    #[test]
    fn whole_columns_step_like_the_walk() {
        let clip = Clip {
            x0: -5,
            y0: 3,
            x1: 70,
            y1: 50,
        };
        let mut whole_columns = 0;
        for (k, walk) in random_walks(11, 5_000, -20.0, 100.0, clip)
            .iter()
            .enumerate()
        {
            let whole = walk.whole();
            assert!((walk.first..=walk.last + 1).contains(&whole.first));
            assert!((whole.first - 1..=walk.last).contains(&whole.last));
            for column in walk.first..=walk.last {
                let exact = walk.column(column);
                let is_whole = (whole.first..=whole.last).contains(&column);
                // A column is whole exactly where its coverage is the full stretch.
                let full = close(exact.c0 + exact.c1, walk.stretch, 1e-12);
                assert_eq!(is_whole, full, "{k}: column {column}");
                if is_whole {
                    let stepped = whole.column(column - whole.first);
                    let at = |c: &Column| c.row as f64 + c.c1 / (c.c0 + c.c1);
                    assert!(close(at(&stepped), at(&exact), 1e-6), "{k}: {column}");
                    assert!(close(stepped.c0 + stepped.c1, walk.stretch, 1e-12));
                    assert!(close(stepped.u, exact.u, 1e-9));
                    whole_columns += 1;
                }
            }
        }
        assert!(whole_columns > 20_000, "{whole_columns}");
    }

    #[test]
    fn floor_matches_the_library() {
        for v in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.7,
            -2.7,
            1e15 + 0.5,
            -1e15 - 0.5,
            5e15,
            -7e300,
        ] {
            assert_eq!(floor(v), v.floor(), "{v}");
        }
        for k in 0..10_000u64 {
            let v = (hash01(9, k, 0, 0) - 0.5) * 1e4;
            assert_eq!(floor(v), v.floor(), "{v}");
        }
    }

    #[test]
    fn degenerate_segments_draw_nothing() {
        assert_eq!(total([3.3, 4.4], [3.3, 4.4], BIG).1, 0);
        assert_eq!(total([f64::NAN, 1.0], [5.0, 5.0], BIG).1, 0);
        assert_eq!(total([1.0, 1.0], [f64::INFINITY, 5.0], BIG).1, 0);
        assert_eq!(total([1.0, f64::NEG_INFINITY], [2.0, 5.0], BIG).1, 0);
        let empty = Clip {
            x0: 5,
            y0: 5,
            x1: 5,
            y1: 9,
        };
        assert_eq!(total([0.0, 0.0], [9.0, 9.0], empty).1, 0);
    }
}
