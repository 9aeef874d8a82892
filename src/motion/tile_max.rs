//! TileMax (McGuire et al. 2012, eq. 1): the dominant velocity of each k×k tile — the vector
//! of largest magnitude, not a per-component maximum. Input: a velocity field (reconstruct
//! passes the input velocity and maps each tile's winner to the clamped half-spread V, which
//! is monotonic in |v|); output: a `ceil(w/k) × ceil(h/k)` grid (tiles at the right and
//! bottom edges may be partial). Next: [`super::neighbor_max`].

use rayon::prelude::*;

/// A grid of vectors, one per tile.
#[derive(Clone, Debug, PartialEq)]
pub struct TileGrid {
    pub columns: usize,
    pub rows: usize,
    /// Tile size in pixels (k).
    pub size: usize,
    pub x: Vec<f32>,
    pub y: Vec<f32>,
}

impl TileGrid {
    pub fn get(&self, column: usize, row: usize) -> (f32, f32) {
        let i = row * self.columns + column;
        (self.x[i], self.y[i])
    }

    /// |M| of tile (column, row), `sqrt(x·x + y·y)` in f32: what reconstruct's 2014 gather
    /// compares and counts taps by, on the CPU and (made on the host, the shader's own
    /// would differ in its last bits) on the GPU.
    pub fn length(&self, column: usize, row: usize) -> f32 {
        let (x, y) = self.get(column, row);
        (x * x + y * y).sqrt()
    }

    /// The tile holding pixel (x, y).
    pub fn at_pixel(&self, x: usize, y: usize) -> (f32, f32) {
        self.get(x / self.size, y / self.size)
    }
}

/// The vector of larger magnitude (the first on ties; a NaN vector never wins, an infinite
/// one always does).
#[inline]
pub fn vmax(a: (f32, f32), b: (f32, f32)) -> (f32, f32) {
    if b.0 * b.0 + b.1 * b.1 > a.0 * a.0 + a.1 * a.1 {
        b
    } else {
        a
    }
}

/// TileMax of the velocity planes `vx`, `vy` (`width × height`) with tiles of `size` px.
pub fn tile_max(vx: &[f32], vy: &[f32], width: usize, height: usize, size: usize) -> TileGrid {
    let size = size.max(1);
    let columns = width.div_ceil(size);
    let rows = height.div_ceil(size);
    let tiles: Vec<(f32, f32)> = (0..rows)
        .into_par_iter()
        .flat_map_iter(|row| {
            // (x, y, |v|²) of the best so far; `m > best` is false for NaN, true for ∞.
            let mut best = vec![(0.0f32, 0.0f32, 0.0f32); columns];
            for y in row * size..((row + 1) * size).min(height) {
                let line = y * width;
                for (column, slot) in best.iter_mut().enumerate() {
                    let start = line + column * size;
                    let end = line + ((column + 1) * size).min(width);
                    for (&x, &y) in vx[start..end].iter().zip(&vy[start..end]) {
                        let m = x * x + y * y;
                        if m > slot.2 {
                            *slot = (x, y, m);
                        }
                    }
                }
            }
            best.into_iter().map(|(x, y, _)| (x, y))
        })
        .collect();
    TileGrid {
        columns,
        rows,
        size,
        x: tiles.iter().map(|t| t.0).collect(),
        y: tiles.iter().map(|t| t.1).collect(),
    }
}

/// The stage's uniform on the GPU, uploaded as it is: `TileMaxConfig` in
/// src/gpu/motion/tile_max.wgsl (held to it by a layout test there). Eight 4-byte fields, a
/// multiple of 16 bytes as uniforms need.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct TileMaxConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// Tile edge k, pixels.
    pub size: u32,
    /// The grid: ⌈width/size⌉ × ⌈height/size⌉ tiles.
    pub columns: u32,
    pub rows: u32,
    pub _pad: [u32; 3],
}

impl TileMaxConfig {
    /// The uniform for `tile_max(vx, vy, width, height, size)` (a size of 0 is 1, as there).
    pub fn new(width: usize, height: usize, size: usize) -> Self {
        let size = size.max(1);
        TileMaxConfig {
            width: width as u32,
            height: height as u32,
            size: size as u32,
            columns: width.div_ceil(size) as u32,
            rows: height.div_ceil(size) as u32,
            _pad: [0; 3],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dominant_vector_per_tile_with_partial_edge_tiles() {
        // 5×3 image, tiles of 2: columns 3, rows 2.
        let mut vx = vec![0.0; 15];
        let mut vy = vec![0.0; 15];
        vx[1] = 3.0; // tile (0, 0)
        vy[6] = -4.0; // pixel (1, 1) → tile (0, 0), larger
        vx[14] = -1.0; // pixel (4, 2) → tile (2, 1), partial tile
        let grid = tile_max(&vx, &vy, 5, 3, 2);
        assert_eq!((grid.columns, grid.rows), (3, 2));
        assert_eq!(grid.get(0, 0), (0.0, -4.0));
        assert_eq!(grid.get(1, 0), (0.0, 0.0));
        assert_eq!(grid.get(2, 1), (-1.0, 0.0));
        assert_eq!(grid.at_pixel(4, 2), (-1.0, 0.0));
    }
}
