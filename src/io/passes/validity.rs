//! Vectors a renderer marks invalid (RSMB: the vector image's alpha below full-on) take the
//! motion of the nearest valid vector.
//!
//! RE:Vision's "MV_Alpha" page (<http://help.revisionfx.com/resource/78/single/>) says areas
//! whose motion is unknown must have alpha other than full-on rather than a (0, 0) vector,
//! which it shows as the incorrect way, and that RSMB then blurs those areas as it should:
//! an object rendered over nothing still streaks past its silhouette into the pixels with no
//! vectors. So invalid pixels are neither read as zero motion nor as still; they take the
//! motion of the surface nearest to them, like a dilation of the valid vectors.
//!
//! Alternatives considered:
//! - *still* (zero motion): what the page calls wrong; it cuts every streak at the edge of
//!   the valid area.
//! - *normalised convolution* (a weighted average of the valid vectors around, or a
//!   push-pull pyramid): smooth, but at a motion boundary it averages two surfaces into a
//!   vector that neither has, and its reach depends on a kernel size.
//!
//! The nearest valid pixel is found exactly, in Euclidean distance between pixel centres,
//! with the separable distance transform of Felzenszwalb & Huttenlocher, *Distance
//! Transforms of Sampled Functions* (Theory of Computing 8, 2012), keeping the argument of
//! the minimum: a pass down the columns (nearest valid row in each column), then the lower
//! envelope of parabolas along each row. Time and memory are linear in the pixel count
//! whatever the mask, and the result is a pure function of the mask (ties go to the pixel
//! the envelope meets first, in a fixed scan order).

/// For every pixel of a `width × height` row-major mask, the index of the nearest pixel
/// where `valid` is true (itself where it is valid), or `None` when no pixel is valid.
pub(super) fn nearest_valid(valid: &[bool], width: usize, height: usize) -> Option<Vec<usize>> {
    debug_assert_eq!(valid.len(), width * height);
    if !valid.iter().any(|&v| v) {
        return None;
    }
    const NONE: usize = usize::MAX;
    // Pass 1, per column: the row of the nearest valid pixel in that column (ties upward).
    let mut row = vec![NONE; width * height];
    for x in 0..width {
        let mut last = NONE;
        for y in 0..height {
            if valid[y * width + x] {
                last = y;
            }
            row[y * width + x] = last;
        }
        let mut below = NONE;
        for y in (0..height).rev() {
            if valid[y * width + x] {
                below = y;
            }
            let above = row[y * width + x];
            if below != NONE && (above == NONE || below - y < y - above) {
                row[y * width + x] = below;
            }
        }
    }
    // Pass 2, per row: for each x the column x' minimising (x - x')² + g(x')², g the column
    // distance from pass 1, by the lower envelope of the parabolas rooted at each x'.
    let mut nearest = vec![0usize; width * height];
    let mut sites: Vec<usize> = Vec::with_capacity(width);
    let mut bounds: Vec<f64> = Vec::with_capacity(width + 1);
    for y in 0..height {
        let g2 = |x: usize| {
            let r = row[y * width + x];
            let d = r.abs_diff(y) as f64;
            d * d
        };
        sites.clear();
        bounds.clear();
        for q in (0..width).filter(|&q| row[y * width + q] != NONE) {
            let fq = g2(q) + (q * q) as f64;
            loop {
                let Some(&p) = sites.last() else {
                    sites.push(q);
                    bounds.push(f64::NEG_INFINITY);
                    break;
                };
                // Where the parabola of q overtakes the last one kept.
                let s = (fq - (g2(p) + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
                if s <= *bounds.last().expect("one per site") {
                    sites.pop();
                    bounds.pop();
                } else {
                    sites.push(q);
                    bounds.push(s);
                    break;
                }
            }
        }
        // Pass 1 left every column with a valid row: some pixel is valid, and pass 1 finds
        // it from every row of its column.
        let mut k = 0;
        for x in 0..width {
            while k + 1 < sites.len() && bounds[k + 1] < x as f64 {
                k += 1;
            }
            let column = sites[k];
            nearest[y * width + x] = row[y * width + column] * width + column;
        }
    }
    Some(nearest)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn distance2(a: usize, b: usize, width: usize) -> usize {
        let (ax, ay) = (a % width, a / width);
        let (bx, by) = (b % width, b / width);
        ax.abs_diff(bx).pow(2) + ay.abs_diff(by).pow(2)
    }

    #[test]
    fn every_pixel_gets_a_nearest_valid_pixel_at_the_least_distance() {
        // Pseudo-random masks of several densities and shapes against brute force.
        let mut state = 0x9e37_79b9u32;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            state
        };
        for (width, height, density) in [
            (1, 1, 2),
            (7, 1, 3),
            (1, 9, 3),
            (13, 11, 2),
            (17, 5, 20),
            (23, 19, 60),
            (31, 29, 200),
        ] {
            for _ in 0..4 {
                let mut valid: Vec<bool> =
                    (0..width * height).map(|_| next() % density == 0).collect();
                valid[(next() as usize) % (width * height)] = true;
                let nearest = nearest_valid(&valid, width, height).unwrap();
                for i in 0..width * height {
                    let j = nearest[i];
                    assert!(valid[j], "{width}x{height}: pixel {i} got invalid {j}");
                    let best = (0..width * height)
                        .filter(|&k| valid[k])
                        .map(|k| distance2(i, k, width))
                        .min()
                        .unwrap();
                    assert_eq!(distance2(i, j, width), best, "{width}x{height}: pixel {i}");
                    if valid[i] {
                        assert_eq!(j, i);
                    }
                }
            }
        }
    }

    #[test]
    fn no_valid_pixel_gives_none() {
        assert_eq!(nearest_valid(&[false; 6], 3, 2), None);
    }
}
