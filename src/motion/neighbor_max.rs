//! NeighborMax (McGuire et al. 2012, eq. 2): for each tile, the dominant vector of TileMax
//! over the 3×3 tiles around it (tiles outside the grid are skipped). Since |V| ≤ k, it bounds
//! every velocity that can reach a pixel of the tile. Input: [`super::tile_max`]'s grid;
//! output: a grid of the same size, read by [`super::reconstruct`].

use super::tile_max::{vmax, TileGrid};

pub fn neighbor_max(tiles: &TileGrid) -> TileGrid {
    let (columns, rows) = (tiles.columns, tiles.rows);
    let mut x = vec![0.0; columns * rows];
    let mut y = vec![0.0; columns * rows];
    for row in 0..rows {
        for column in 0..columns {
            let mut best = (0.0f32, 0.0f32);
            for r in row.saturating_sub(1)..(row + 2).min(rows) {
                for c in column.saturating_sub(1)..(column + 2).min(columns) {
                    best = vmax(best, tiles.get(c, r));
                }
            }
            x[row * columns + column] = best.0;
            y[row * columns + column] = best.1;
        }
    }
    TileGrid {
        columns,
        rows,
        size: tiles.size,
        x,
        y,
    }
}

/// The stage's uniform on the GPU, uploaded as it is: `NeighborMaxConfig` in
/// src/gpu/motion/neighbor_max.wgsl (held to it by a layout test there): the grid's size,
/// which the CPU stage reads from the grid itself. Four 4-byte fields, 16 bytes as uniforms
/// need.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct NeighborMaxConfig {
    /// The grid, tiles.
    pub columns: u32,
    pub rows: u32,
    pub _pad: [u32; 2],
}

impl NeighborMaxConfig {
    /// The uniform for `neighbor_max(tiles)`.
    pub fn of(tiles: &TileGrid) -> Self {
        NeighborMaxConfig {
            columns: tiles.columns as u32,
            rows: tiles.rows as u32,
            _pad: [0; 2],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spreads_the_dominant_vector_to_the_eight_neighbours_only() {
        let mut tiles = TileGrid {
            columns: 4,
            rows: 3,
            size: 8,
            x: vec![0.0; 12],
            y: vec![0.0; 12],
        };
        tiles.x[5] = 2.0; // tile (1, 1)
        tiles.y[0] = 1.0; // tile (0, 0), smaller
        let n = neighbor_max(&tiles);
        for (c, r) in [(0, 0), (1, 0), (2, 0), (0, 2), (2, 2)] {
            assert_eq!(n.get(c, r), (2.0, 0.0), "({c}, {r})");
        }
        assert_eq!(n.get(3, 1), (0.0, 0.0));
    }
}
