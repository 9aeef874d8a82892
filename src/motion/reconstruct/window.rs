//! window — the kinds of a block of pixels at a silhouette, a bit a pixel, for
//! [`super::matte`]: which pixels are read (in the frame and in a tile the pass picked), which
//! move, and which have a 3×3 all of one kind.
//!
//! The matte tests each pixel's candidates against these (each pixel is a candidate of up to
//! 24 others, and a candidate's purity is its own 3×3), so they are found once a block. They
//! are kept a block at a time, a u64 a row, so a frame's silhouettes cost their tiles alone:
//! no frame-sized buffer is written (two of them, a byte a pixel, were most of the fringe's
//! bookkeeping at 1080p, their pages faulted in frame by frame; BENCHMARKS.md), and the
//! pixels at a silhouette are found a row at a time, a bit each.

use super::config::ReconstructConfig;

/// Calls `each(window, (x, y))` for every pixel of the selected tiles of tile row `r` at a
/// silhouette as read (its 3×3 holds read pixels of both kinds), block by block, with the
/// block's [`Window`]; with `near_pure_still`, only those with a pure still pixel in their 5×5
/// (the fringe's pairs need one: on a frame of noise, a twentieth of its pixels). Every other
/// pixel's matte is its label.
pub(super) fn silhouettes(
    config: &ReconstructConfig,
    moves: &impl Fn(usize) -> bool,
    selected: &impl Fn(usize, usize) -> bool,
    (r, near_pure_still): (usize, bool),
    mut each: impl FnMut(&Window, (usize, usize)),
) {
    let (width, height) = (config.width as usize, config.height as usize);
    let size = config.tile as usize;
    let mut window = Window::default();
    let rows = r * size..((r + 1) * size).min(height);
    for c in (0..width.div_ceil(size)).filter(|&c| selected(c, r)) {
        let columns = c * size..((c + 1) * size).min(width);
        for y0 in rows.clone().step_by(BLOCK) {
            for x0 in columns.clone().step_by(BLOCK) {
                let (x1, y1) = ((x0 + BLOCK).min(columns.end), (y0 + BLOCK).min(rows.end));
                window.fill(config, moves, selected, (x0, y0), (x1, y1));
                // The block's own columns, as bits of the window's rows.
                let own = ((1u64 << (x1 - x0)) - 1) << APRON;
                for y in y0..y1 {
                    let j = y - y0 + APRON;
                    let mixed = window.read[j] & !(window.pure_moving[j] | window.pure_still[j]);
                    let mut mixed = mixed & own;
                    if near_pure_still {
                        let pure = window.pure_still[j - 2..j + 3]
                            .iter()
                            .fold(0, |m, &p| m | p);
                        mixed &= pure | pure << 1 | pure << 2 | pure >> 1 | pure >> 2;
                    }
                    while mixed != 0 {
                        let bit = mixed.trailing_zeros() as usize;
                        mixed &= mixed - 1;
                        each(&window, (x0 + bit - APRON, y));
                    }
                }
            }
        }
    }
}

/// How far past its block a [`Window`] reaches: a pixel's candidates lie in its 5×5, and a
/// candidate's purity is its own 3×3.
const APRON: usize = 3;
/// The side of a [`Window`]'s block at most (a larger tile is read in blocks): the block and
/// its apron fit the bits of a u64.
const BLOCK: usize = 32;
/// A [`Window`]'s rows.
pub(super) const ROWS: usize = BLOCK + 2 * APRON;

/// The kinds of one block of a selected tile's pixels and of those within [`APRON`] of it, a
/// bit a pixel, row by row (bit `k` of row `j`: the frame's pixel (x0 + k, y0 + j)): read (in
/// the frame and in a selected tile), moves, its 3×3 all moving, its 3×3 all still (pixels not
/// read count as either).
pub(super) struct Window {
    pub(super) x0: i64,
    pub(super) y0: i64,
    pub(super) read: [u64; ROWS],
    pub(super) moves: [u64; ROWS],
    /// Purity, of the read pixels not on the window's edge.
    pub(super) pure_moving: [u64; ROWS],
    pub(super) pure_still: [u64; ROWS],
}

impl Default for Window {
    fn default() -> Window {
        Window {
            x0: 0,
            y0: 0,
            read: [0; ROWS],
            moves: [0; ROWS],
            pure_moving: [0; ROWS],
            pure_still: [0; ROWS],
        }
    }
}

impl Window {
    /// The window of the block from (x0, y0) up to (x1, y1), within one tile.
    fn fill(
        &mut self,
        config: &ReconstructConfig,
        moves: &impl Fn(usize) -> bool,
        selected: &impl Fn(usize, usize) -> bool,
        (x0, y0): (usize, usize),
        (x1, y1): (usize, usize),
    ) {
        let (width, height) = (config.width as i64, config.height as i64);
        let size = config.tile as usize;
        (self.x0, self.y0) = (x0 as i64 - APRON as i64, y0 as i64 - APRON as i64);
        let (columns, rows) = (x1 - x0 + 2 * APRON, y1 - y0 + 2 * APRON);
        // Read and moves: a test per pixel of the selected tiles the window meets.
        let (left, right) = (self.x0.max(0), (self.x0 + columns as i64).min(width));
        for j in 0..ROWS {
            let y = self.y0 + j as i64;
            let (mut read, mut moving) = (0u64, 0u64);
            if j < rows && y >= 0 && y < height {
                let ty = y as usize / size;
                let mut x = left;
                while x < right {
                    let tx = x as usize / size;
                    let end = (((tx + 1) * size) as i64).min(right);
                    if selected(tx, ty) {
                        for x in x..end {
                            let bit = 1u64 << (x - self.x0);
                            read |= bit;
                            if moves((y * width + x) as usize) {
                                moving |= bit;
                            }
                        }
                    }
                    x = end;
                }
            }
            (self.read[j], self.moves[j]) = (read, moving);
        }
        // Purity: a 3×3 with no read still pixel is all moving, one with no read moving pixel
        // all still: each kind's bits dilated by the 3×3 (three rows ORed, then shifted).
        let inner = ((1u64 << (columns - 1)) - 1) & !1;
        let still = |j: usize| self.read[j] & !self.moves[j];
        let moving = |j: usize| self.read[j] & self.moves[j];
        let dilate = |m: u64| m | m << 1 | m >> 1;
        let (mut pure_moving, mut pure_still) = ([0u64; ROWS], [0u64; ROWS]);
        for j in 1..rows - 1 {
            let still = dilate(still(j - 1) | still(j) | still(j + 1));
            let moving = dilate(moving(j - 1) | moving(j) | moving(j + 1));
            pure_moving[j] = self.read[j] & !still & inner;
            pure_still[j] = self.read[j] & !moving & inner;
        }
        (self.pure_moving, self.pure_still) = (pure_moving, pure_still);
    }

    /// Whether `mask` holds pixel (x, y), which must lie in the window.
    #[inline(always)]
    pub(super) fn get(&self, mask: &[u64; ROWS], x: i64, y: i64) -> bool {
        (mask[(y - self.y0) as usize] >> (x - self.x0)) & 1 != 0
    }
}
