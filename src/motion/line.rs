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
    if !(a.iter().chain(&b).all(|v| v.is_finite())) {
        return;
    }
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    if dx == 0.0 && dy == 0.0 {
        return;
    }
    if dx.abs() >= dy.abs() {
        draw_major(a, b, (clip.x0, clip.x1), (clip.y0, clip.y1), span);
    } else {
        // The same walk with the axes swapped.
        draw_major(
            [a[1], a[0]],
            [b[1], b[0]],
            (clip.y0, clip.y1),
            (clip.x0, clip.x1),
            |s: Span| {
                span(Span {
                    first: (s.first.1, s.first.0),
                    second: (s.second.1, s.second.0),
                    ..s
                })
            },
        );
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

/// The walk along x (|dx| ≥ |dy| > 0 or dx ≠ 0).
#[inline(always)]
fn draw_major(
    a: [f64; 2],
    b: [f64; 2],
    (x0, x1): (i64, i64),
    (y0, y1): (i64, i64),
    mut span: impl FnMut(Span),
) {
    if x0 >= x1 || y0 >= y1 {
        return;
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
    // coverage only while the segment is within one pixel of its centre j + ½. With a margin
    // of a column each side, so the clip never changes a column's own coverage.
    if slope != 0.0 {
        let (ylo, yhi) = (y0 as f64 - 0.5, y1 as f64 + 0.5);
        let run = dx / dy;
        let xa = a[0] + (ylo - a[1]) * run;
        let xb = a[0] + (yhi - a[1]) * run;
        first = first.max(floor(xa.min(xb)) - 1.0);
        last = last.min(-floor(-xa.max(xb)) + 1.0);
    } else if a[1] < y0 as f64 - 0.5 || a[1] > y1 as f64 + 0.5 {
        return;
    }
    if first.is_nan() || last.is_nan() || first > last {
        return;
    }
    let (first, last) = (first as i64, last as i64);
    // One column: the segment's piece in it is [left, right] along x.
    let mut column_span = |column: i64, left: f64, right: f64| {
        let middle = 0.5 * (left + right);
        let along = middle - a[0];
        let u = along * inverse;
        let y = a[1] + slope * along;
        let coverage = (right - left) * stretch;
        // Split between the two rows whose centres bracket y. Within the walked columns
        // y is near the clip, so shifting by 2³¹ makes truncation a floor.
        let v = y - 0.5 + ROW_SHIFT;
        let shifted = v as i64;
        let f = v - shifted as f64;
        let row = shifted - ROW_SHIFT as i64;
        let c0 = if (y0..y1).contains(&row) {
            coverage * (1.0 - f)
        } else {
            0.0
        };
        let c1 = if (y0..y1).contains(&(row + 1)) {
            coverage * f
        } else {
            0.0
        };
        if c0 > 0.0 || c1 > 0.0 {
            span(Span {
                first: (column, row),
                second: (column, row + 1),
                c0,
                c1,
                u,
            });
        }
    };
    // Columns the segment crosses whole are [inner_first, inner_last]; the end columns hold
    // its fractional end points.
    let inner_first = (-floor(-lo)) as i64;
    let inner_last = floor(hi) as i64 - 1;
    for column in first..=last {
        let c = column as f64;
        if column >= inner_first && column <= inner_last {
            column_span(column, c, c + 1.0);
        } else {
            let (left, right) = (lo.max(c), hi.min(c + 1.0));
            if right > left {
                column_span(column, left, right);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::truth::sample::hash01;

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
                (sum - length).abs() <= 0.01 * length,
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
        assert!((sum - 64.0).abs() < 1e-6);
        // Entirely outside: nothing, quickly.
        assert_eq!(total([-1e9, -5e8], [1e9, -4e8], clip).1, 0);
        assert_eq!(total([1e12, 3.0], [1e12 + 5.0, 3.0], clip).1, 0);
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
