//! A small triangle rasteriser, for `stretch`.
//!
//! Pixels are sampled at their centres (i + ½, j + ½). A pixel belongs to a triangle when its
//! centre is inside, by edge functions in f64; a centre exactly on an edge belongs to the
//! triangle only if that edge is a *top* or *left* edge (the top-left rule of Direct3D and
//! OpenGL), so two triangles sharing an edge never both take a pixel on it and never both
//! miss it. Attributes are interpolated with the barycentric weights (screen space, no
//! perspective: the vertices are image pixels).
//!
//! Work is bounded by the triangle's bounding box clipped to the clip rectangle, so a huge
//! triangle costs at most the rectangle. Degenerate triangles (zero area) and non-finite
//! vertices draw nothing.

/// Pixels that may be drawn: columns `x0..x1`, rows `y0..y1`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x0: usize,
    pub y0: usize,
    pub x1: usize,
    pub y1: usize,
}

/// Twice the signed area of (a, b, p): positive when p is left of a→b in y-down pixel
/// coordinates seen as a math frame (counter-clockwise in x-right, y-up).
fn edge(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
}

/// The tie-break for centres exactly on edge a → b of a triangle with positive [`edge`]
/// orientation: the edge owns them when it runs down the screen, or exactly leftwards. For
/// this orientation those are the left and top edges. A shared edge is a → b in one
/// triangle and b → a in the other, and exactly one of the two directions passes, so a
/// centre on it goes to exactly one triangle.
fn top_left(a: [f64; 2], b: [f64; 2]) -> bool {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    (dy == 0.0 && dx < 0.0) || dy > 0.0
}

/// Draws triangle `v` into `clip`: `fragment(x, y, [w0, w1, w2])` for each covered pixel,
/// with barycentric weights (summing to 1) of the three vertices.
pub fn draw(v: [[f64; 2]; 3], clip: Rect, mut fragment: impl FnMut(usize, usize, [f64; 3])) {
    if !v.iter().flatten().all(|c| c.is_finite()) {
        return;
    }
    let mut v = v;
    let mut order = [0usize, 1, 2];
    let area = edge(v[0], v[1], v[2]);
    if area == 0.0 || !area.is_finite() {
        return;
    }
    if area < 0.0 {
        v.swap(1, 2);
        order.swap(1, 2);
    }
    let area = area.abs();
    let lo_x = v.iter().map(|p| p[0]).fold(f64::INFINITY, f64::min);
    let hi_x = v.iter().map(|p| p[0]).fold(f64::NEG_INFINITY, f64::max);
    let lo_y = v.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    let hi_y = v.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max);
    // Pixel centres i + ½ within [lo, hi].
    let first = |lo: f64, min: usize| ((lo - 0.5).ceil().max(min as f64)) as usize;
    let last = |hi: f64, max: usize| (hi - 0.5).floor().min(max as f64 - 1.0);
    let (x0, y0) = (first(lo_x, clip.x0), first(lo_y, clip.y0));
    let (x1, y1) = (last(hi_x, clip.x1), last(hi_y, clip.y1));
    if x1 < x0 as f64 || y1 < y0 as f64 {
        return;
    }
    let (x1, y1) = (x1 as usize, y1 as usize);
    // Edge i is opposite vertex i.
    let edges = [(v[1], v[2]), (v[2], v[0]), (v[0], v[1])];
    let bias = edges.map(|(a, b)| top_left(a, b));
    for y in y0..=y1 {
        for x in x0..=x1 {
            let p = [x as f64 + 0.5, y as f64 + 0.5];
            let w = edges.map(|(a, b)| edge(a, b, p));
            let inside = (0..3).all(|k| w[k] > 0.0 || (w[k] == 0.0 && bias[k]));
            if inside {
                let mut weights = [0.0; 3];
                for k in 0..3 {
                    weights[order[k]] = w[k] / area;
                }
                fragment(x, y, weights);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::truth::sample::hash01;
    use crate::numeric::close;

    const CLIP: Rect = Rect {
        x0: 0,
        y0: 0,
        x1: 64,
        y1: 64,
    };

    fn coverage(tris: &[[[f64; 2]; 3]]) -> Vec<u32> {
        let mut count = vec![0u32; 64 * 64];
        for t in tris {
            draw(*t, CLIP, |x, y, w| {
                assert!(close(w.iter().sum::<f64>(), 1.0, 1e-9));
                assert!(w.iter().all(|&c| c >= -1e-12));
                count[y * 64 + x] += 1;
            });
        }
        count
    }

    #[test]
    fn two_triangles_sharing_an_edge_cover_each_pixel_once() {
        // A quad split along a diagonal through pixel centres, and random quads: every pixel
        // inside is drawn exactly once, whatever the winding.
        let quads = [
            [[10.5, 10.5], [30.5, 10.5], [30.5, 30.5], [10.5, 30.5]],
            [[2.0, 3.0], [40.25, 5.5], [50.0, 44.0], [6.5, 38.0]],
        ];
        let mut all: Vec<[[f64; 2]; 4]> = quads.to_vec();
        for k in 0..200u64 {
            let r = |i: u64| 4.0 + hash01(5, k, i, 0) * 56.0;
            // A convex quad: a square with jittered corners, snapped to quarter pixels so
            // many centres land on the edges.
            let (cx, cy, h) = (r(0).min(50.0), r(1).min(50.0), 2.0 + r(2) / 8.0);
            let snap = |v: f64| (v * 4.0).round() / 4.0;
            let q = [
                [snap(cx - h), snap(cy - h)],
                [snap(cx + h), snap(cy - h)],
                [snap(cx + h), snap(cy + h)],
                [snap(cx - h), snap(cy + h)],
            ];
            all.push(q);
        }
        for q in all {
            let a = [q[0], q[1], q[2]];
            let b = [q[0], q[2], q[3]];
            let b_reversed = [q[3], q[2], q[0]];
            for tris in [[a, b], [a, b_reversed]] {
                let count = coverage(&tris);
                assert!(count.iter().all(|&c| c <= 1), "{q:?}: a pixel drawn twice");
                // Every centre strictly inside the quad is drawn.
                for y in 0..64 {
                    for x in 0..64 {
                        let p = [x as f64 + 0.5, y as f64 + 0.5];
                        let inside = (0..4).all(|k| edge(q[k], q[(k + 1) % 4], p) > 0.0);
                        if inside {
                            assert_eq!(count[y * 64 + x], 1, "{q:?} at {x},{y}");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn covered_pixels_match_the_area_within_the_perimeter() {
        for k in 0..300u64 {
            let r = |i: u64| hash01(6, k, i, 0) * 64.0;
            let t = [[r(0), r(1)], [r(2), r(3)], [r(4), r(5)]];
            let area = 0.5 * edge(t[0], t[1], t[2]).abs();
            let perimeter: f64 = (0..3)
                .map(|i| {
                    let (a, b) = (t[i], t[(i + 1) % 3]);
                    (b[0] - a[0]).hypot(b[1] - a[1])
                })
                .sum();
            let count = coverage(&[t]).iter().sum::<u32>() as f64;
            assert!(
                close(count, area, perimeter),
                "{t:?}: {count} px vs area {area}"
            );
        }
    }

    #[test]
    fn degenerate_and_nan_triangles_draw_nothing() {
        let none = |t: [[f64; 2]; 3]| coverage(&[t]).iter().sum::<u32>();
        assert_eq!(none([[1.0, 1.0], [10.0, 10.0], [20.0, 20.0]]), 0);
        assert_eq!(none([[5.5, 5.5], [5.5, 5.5], [5.5, 5.5]]), 0);
        assert_eq!(none([[f64::NAN, 1.0], [10.0, 1.0], [5.0, 9.0]]), 0);
        assert_eq!(none([[f64::INFINITY, 1.0], [10.0, 1.0], [5.0, 9.0]]), 0);
        // Huge triangles cost the clip only and cover it.
        assert_eq!(none([[-1e12, -1e12], [1e12, -1e12], [0.0, 1e12]]), 64 * 64);
    }
}
