//! `dilate`: the tile stage of the 2014 filter (Guertin, McGuire & Nowrouzezahrai 2014, with
//! Jimenez 2014's dilation as Blender's EEVEE and compositor run it): each tile's dominant
//! half-spread vector M is spread to the tiles its motion line crosses, forwards and
//! backwards (the shutter is open on both sides of the frame's time), and each tile keeps the
//! longest vector that reaches it.
//!
//! Unlike [`super::neighbor_max`], which hands every tile the largest vector of its 3×3
//! neighbourhood whichever way it points, a vector here reaches only the tiles along its own
//! line: a fast object beside a slow one no longer makes the slow one's tiles sample along the
//! fast direction.
//!
//! A tile is on a line when its centre is within √2 tiles of it (the tile's and the line's
//! bounding circles, as conservative as Jimenez's rasterisation); a vector of length |M|
//! reaches ⌈|M|/tile⌉ tiles each way. The scan is a gather over the tiles that can reach a
//! tile, in a fixed order, so ties (equal lengths) go to the first in row-major order and the
//! result does not depend on thread count.

use super::tile_max::TileGrid;

/// Distance (in tiles) from a motion line within which a tile counts as crossed.
pub const REACH: f32 = std::f32::consts::SQRT_2;

/// What the reach test needs of a source tile's vector M, worked out once per tile: |M|², the
/// tiles it spans each way along x and y (⌈|M_x|/tile⌉, ⌈|M_y|/tile⌉) and the unit normal of
/// its line. The GPU twin (src/gpu/motion/dilate.rs) takes these numbers from here too: WGSL's square
/// root and division are not correctly rounded, and for diagonal motion the reach test sits
/// exactly on its threshold (a tile beside the diagonal is √2 tiles from it).
///
/// The normal is cut to [`NORMAL_BITS`] significant bits, away from zero ([`short`]), so that
/// each product of the test's n·(dx, dy) is exact for offsets under 2^13 tiles (a frame under
/// 8192 tiles across: 65 536 px with 8 px tiles): the sum is then rounded once whether or not
/// a driver fuses a product into it (an fma). Before, with full normals,
/// NVIDIA's driver (H200, 580.159) fused them and 1.2 % of the tiles of a generated grid, on
/// the threshold, went the other way (tests/gpu.rs); lavapipe did not fuse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Source {
    /// |M|², px².
    pub length2: f32,
    /// ⌈|M_x|/tile⌉ and ⌈|M_y|/tile⌉, tiles.
    pub span_x: f32,
    pub span_y: f32,
    /// The unit normal of M's line, (−M_y, M_x)/|M|.
    pub nx: f32,
    pub ny: f32,
}

/// Significant bits kept of a source's normal: with an offset of under 2^13 tiles, n·d's
/// products are exact in f32 (11 + 13 = 24 bits).
pub const NORMAL_BITS: u32 = 11;

/// `v` rounded away from zero to [`NORMAL_BITS`] significant bits (a component of a unit
/// normal cannot overflow); not-finite values as they are. Away from zero, so that the cut
/// normal is never shorter than 1 and |n·d| never smaller than in exact arithmetic: a tile
/// exactly √2 from the line (beside a diagonal, or at (−1, 3) from a vector (10, 70)) stays
/// out, as it was with the full normal (rounded to nearest, 1/√2 became 0.70703125 and those
/// tiles came in).
#[inline]
pub fn short(v: f32) -> f32 {
    if !v.is_finite() {
        return v;
    }
    let dropped = 24 - NORMAL_BITS;
    let bits = v.to_bits() + ((1 << dropped) - 1);
    f32::from_bits(bits & !((1u32 << dropped) - 1))
}

impl Source {
    /// The source data of vector `m` with tiles of `size` px.
    #[inline]
    pub fn new(m: (f32, f32), size: f32) -> Source {
        let length2 = m.0 * m.0 + m.1 * m.1;
        let length = length2.sqrt();
        let span = |c: f32| (c.abs() / size).ceil();
        Source {
            length2,
            span_x: span(m.0),
            span_y: span(m.1),
            nx: short(-m.1 / length),
            ny: short(m.0 / length),
        }
    }

    /// Whether this source, `(dx, dy)` tiles from a tile, reaches it: within the rectangle
    /// of tiles it spans either way, and within [`REACH`] tiles of its line. (A source of
    /// zero length reaches nothing: [`dilate`] skips it.)
    #[inline]
    pub fn reaches(&self, dx: isize, dy: isize) -> bool {
        let (dx, dy) = (dx as f32, dy as f32);
        if dx.abs() > self.span_x || dy.abs() > self.span_y {
            return false;
        }
        (self.nx * dx + self.ny * dy).abs() < REACH
    }
}

/// Spreads each tile's vector along its own line (both ways) and keeps, per tile, the
/// longest that reaches it (a tile's own vector wins ties, then the first source in row-major
/// order). `tiles` holds half-spread vectors in pixels.
///
/// A scatter: each source visits only the tiles of the rectangle its vector spans, so the
/// cost grows with the vectors' lengths in tiles, not with the square of the largest one.
/// It runs in row-major order on one thread (a few million steps at most at 1080p), which
/// makes the tie rule, and so the result, independent of thread count.
pub fn dilate(tiles: &TileGrid) -> TileGrid {
    let (columns, rows) = (tiles.columns, tiles.rows);
    let size = tiles.size.max(1) as f32;
    let mut out = tiles.clone();
    let mut best: Vec<f32> = tiles
        .x
        .iter()
        .zip(&tiles.y)
        .map(|(x, y)| x * x + y * y)
        .collect();
    for r in 0..rows {
        for c in 0..columns {
            let m = tiles.get(c, r);
            let source = Source::new(m, size);
            let length = source.length2;
            if length == 0.0 {
                continue;
            }
            let (sx, sy) = (source.span_x as usize, source.span_y as usize);
            for tr in r.saturating_sub(sy)..(r + sy + 1).min(rows) {
                for tc in c.saturating_sub(sx)..(c + sx + 1).min(columns) {
                    let i = tr * columns + tc;
                    let (dx, dy) = (tc as isize - c as isize, tr as isize - r as isize);
                    if length > best[i] && source.reaches(dx, dy) {
                        best[i] = length;
                        out.x[i] = m.0;
                        out.y[i] = m.1;
                    }
                }
            }
        }
    }
    out
}

/// The stage's uniform on the GPU, uploaded as it is: `DilateConfig` in
/// src/gpu/motion/dilate.wgsl (held to it by a layout test there). The CPU stage scans each
/// source's own span instead of one radius. Four 4-byte fields, 16 bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct DilateConfig {
    /// The grid, tiles.
    pub columns: u32,
    pub rows: u32,
    /// The largest span of any live source, clamped to the grid, tiles: the scan's radius.
    pub radius: u32,
    pub _pad: u32,
}

/// One tile as a source: [`Source`] as the GPU reads it, `SourceTile` in
/// src/gpu/motion/dilate.wgsl (held to it by a layout test there): eight 4-byte fields, 32
/// bytes.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct SourceTile {
    /// |M|², px².
    pub length2: f32,
    /// ⌈|M_x|/tile⌉ and ⌈|M_y|/tile⌉ as the CPU's loop takes them (`as usize`: NaN is 0,
    /// larger values saturate), here to u32.
    pub span_x: u32,
    pub span_y: u32,
    /// The unit normal of M's line.
    pub nx: f32,
    pub ny: f32,
    /// 1 when M can reach another tile: |M|² > 0 (not NaN) and a finite normal. On the CPU a
    /// NaN |M|² never wins and a non-finite normal makes the reach test compare a NaN.
    pub live: u32,
    pub _pad: [u32; 2],
}

impl SourceTile {
    pub fn new(m: (f32, f32), size: f32) -> SourceTile {
        let s = Source::new(m, size);
        let live = s.length2 > 0.0 && s.nx.is_finite() && s.ny.is_finite();
        SourceTile {
            length2: s.length2,
            span_x: s.span_x as u32,
            span_y: s.span_y as u32,
            nx: s.nx,
            ny: s.ny,
            live: live as u32,
            _pad: [0; 2],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(columns: usize, rows: usize, size: usize) -> TileGrid {
        TileGrid {
            columns,
            rows,
            size,
            x: vec![0.0; columns * rows],
            y: vec![0.0; columns * rows],
        }
    }

    #[test]
    fn a_vector_reaches_the_tiles_along_its_line_only() {
        // 5×5 tiles of 10 px; the centre tile moves 10 px to the right.
        let mut tiles = grid(5, 5, 10);
        tiles.x[2 * 5 + 2] = 10.0;
        let out = dilate(&tiles);
        // Left and right neighbours get it (both ways: the shutter is centred)...
        assert_eq!(out.get(1, 2), (10.0, 0.0));
        assert_eq!(out.get(3, 2), (10.0, 0.0));
        assert_eq!(out.get(2, 2), (10.0, 0.0));
        // ...but not tiles beyond its reach along the line, nor the rows above and below: a
        // horizontal vector spans no tile vertically.
        assert_eq!(out.get(0, 2), (0.0, 0.0));
        assert_eq!(out.get(2, 1), (0.0, 0.0));
        assert_eq!(out.get(1, 3), (0.0, 0.0));
    }

    #[test]
    fn a_diagonal_vector_misses_the_off_diagonal_corner_tiles() {
        // 20 px down-right in 10 px tiles: reaches two tiles each way along the diagonal.
        let mut tiles = grid(5, 5, 10);
        tiles.x[2 * 5 + 2] = 14.0;
        tiles.y[2 * 5 + 2] = 14.0;
        let out = dilate(&tiles);
        assert_eq!(out.get(4, 4), (14.0, 14.0));
        assert_eq!(out.get(0, 0), (14.0, 14.0));
        // (4, 0) is 2·√2 tiles from the line: not crossed.
        assert_eq!(out.get(4, 0), (0.0, 0.0));
        assert_eq!(out.get(0, 4), (0.0, 0.0));
        // (3, 1) and (1, 3) are exactly √2 from it: not within, with the normal cut
        // (`short`) as with the full one.
        assert_eq!(out.get(3, 1), (0.0, 0.0));
        assert_eq!(out.get(1, 3), (0.0, 0.0));
        // The same with a line that is not diagonal: (10, 70) px in 10 px tiles reaches
        // (−1, 3) tiles from its source only if within √2 of its line, and that tile is
        // exactly √2 from it, as is (1, −3).
        let mut tiles = grid(9, 9, 10);
        tiles.x[4 * 9 + 4] = 10.0;
        tiles.y[4 * 9 + 4] = 70.0;
        let out = dilate(&tiles);
        assert_eq!(out.get(4, 8), (10.0, 70.0));
        assert_eq!(out.get(3, 7), (0.0, 0.0));
        assert_eq!(out.get(5, 1), (0.0, 0.0));
    }

    #[test]
    fn the_longest_vector_wins_and_a_tile_keeps_its_own_when_longer() {
        let mut tiles = grid(3, 1, 10);
        tiles.x[0] = 8.0;
        tiles.x[1] = 3.0;
        tiles.x[2] = -9.0;
        let out = dilate(&tiles);
        assert_eq!(out.get(1, 0), (-9.0, 0.0));
        assert_eq!(out.get(0, 0), (8.0, 0.0));
        assert_eq!(out.get(2, 0), (-9.0, 0.0));
    }

    #[test]
    fn sources_that_reach_nothing_are_not_live() {
        assert_eq!(SourceTile::new((0.0, 0.0), 8.0).live, 0);
        assert_eq!(SourceTile::new((f32::NAN, 1.0), 8.0).live, 0);
        // |M| = ∞ with infinite components: the normal is NaN.
        assert_eq!(SourceTile::new((f32::INFINITY, 0.0), 8.0).live, 0);
        // |M|² overflows with finite components: the normal is 0, and it reaches its span.
        let huge = SourceTile::new((1e20, 0.0), 8.0);
        assert_eq!((huge.live, huge.span_x), (1, u32::MAX));
        let s = SourceTile::new((10.0, -3.0), 8.0);
        assert_eq!((s.live, s.span_x, s.span_y), (1, 2, 1));
    }

    #[test]
    fn the_reach_test_rounds_alike_fused_or_not() {
        // n·d with the normal cut to NORMAL_BITS: each product exact, so fusing either into
        // the sum (what a GPU driver may do) gives the same bits. With full normals, some of
        // these differ (checked below, so the cut is what makes them agree).
        use crate::lab::truth::sample::hash01;
        let (mut cut_differ, mut full_differ) = (0, 0);
        for k in 0..20_000u64 {
            let next = |stream: u64| hash01(7, stream, k, 0) as f32;
            let m = (400.0 * next(0) - 200.0, 400.0 * next(1) - 200.0);
            let (dx, dy) = (
                (16383.0 * next(2)).floor() - 8191.0,
                (16383.0 * next(3)).floor() - 8191.0,
            );
            let fused = |nx: f32, ny: f32| {
                let plain = nx * dx + ny * dy;
                (plain != nx.mul_add(dx, ny * dy) || plain != ny.mul_add(dy, nx * dx)) as u32
            };
            let s = Source::new(m, 8.0);
            cut_differ += fused(s.nx, s.ny);
            let length = (m.0 * m.0 + m.1 * m.1).sqrt();
            full_differ += fused(-m.1 / length, m.0 / length);
            // The cut lengthens the normal by under 2^-10 of itself, never shortens it.
            let full = (m.1 / length).abs();
            assert!(s.nx.abs() >= full && s.nx.abs() - full <= full / 1024.0);
        }
        assert_eq!(cut_differ, 0);
        assert!(full_differ > 1000, "{full_differ}");
    }
}
