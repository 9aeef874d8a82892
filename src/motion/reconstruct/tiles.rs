//! Which tiles each of reconstruct's later stages works on, and the loop that runs a gather
//! over them: the paper's gather over the tiles whose NeighborMax blurs, the 2014 gather over
//! those within one tile of a blurring one, and the 2014 pack over those within its taps'
//! reach ([`packed_2014`]). Every other pixel keeps its colour, so still tiles cost nothing.

use rayon::prelude::*;

use super::config::{reach_factor, ReconstructConfig, MOVING_SQUARED};
use crate::frame::Color;
use crate::motion::tile_max::TileGrid;

/// Whether a tile's NeighborMax blurs: |V|² above (0.5 px + ε)².
#[inline]
pub(crate) fn blurs(neighbors: &TileGrid, c: usize, r: usize) -> bool {
    let (x, y) = neighbors.get(c, r);
    x * x + y * y > MOVING_SQUARED
}

/// Whether any tile within `radius` tiles of (c, r) blurs.
pub(crate) fn near_blur(tiles: &TileGrid, c: usize, r: usize, radius: usize) -> bool {
    (r.saturating_sub(radius)..(r + radius + 1).min(tiles.rows)).any(|rr| {
        (c.saturating_sub(radius)..(c + radius + 1).min(tiles.columns))
            .any(|cc| blurs(tiles, cc, rr))
    })
}

/// Which tiles of a grid a stage works on.
pub struct TileMask {
    columns: usize,
    on: Vec<bool>,
}

impl TileMask {
    /// Whether tile (column, row) is on.
    #[inline]
    pub fn get(&self, column: usize, row: usize) -> bool {
        self.on[row * self.columns + column]
    }
}

/// The tiles [`pack_2014`] packs: those within `reach + 1` tiles (Chebyshev) of a blurring
/// one, where taps reach k px (up to 2k when the exposure is offset), `reach` tiles beyond
/// the tile a pixel looks up. [`near_blur`] over every tile, computed as a square dilation in
/// two passes of running counts, so its cost does not grow with the reach.
pub fn packed_2014(config: &ReconstructConfig, tiles: &TileGrid) -> TileMask {
    let reach = (config.k * reach_factor(config) / config.tile as f32).ceil() as usize + 1;
    let (columns, rows) = (tiles.columns, tiles.rows);
    // Within `reach` along one axis of a marked cell: a running count over a window.
    let dilate = |marked: &dyn Fn(usize) -> bool, n: usize| -> Vec<bool> {
        let mut prefix = vec![0u32; n + 1];
        for i in 0..n {
            prefix[i + 1] = prefix[i] + marked(i) as u32;
        }
        (0..n)
            .map(|i| prefix[(i + reach + 1).min(n)] > prefix[i.saturating_sub(reach)])
            .collect()
    };
    let mut across = vec![false; columns * rows];
    for r in 0..rows {
        let row = dilate(&|c| blurs(tiles, c, r), columns);
        across[r * columns..(r + 1) * columns].copy_from_slice(&row);
    }
    let mut on = vec![false; columns * rows];
    for c in 0..columns {
        let column = dilate(&|r| across[r * columns + c], rows);
        for (r, v) in column.into_iter().enumerate() {
            on[r * columns + c] = v;
        }
    }
    TileMask { columns, on }
}

/// Runs `pixel((column, row), x, y)` over every pixel of the tiles `selected(column, row)`
/// picks, a band of tile rows per task, and writes its premultiplied RGBA in place; other
/// pixels keep their colour.
pub(crate) fn gather_tiles(
    config: &ReconstructConfig,
    columns: usize,
    color: &mut Color,
    selected: impl Fn(usize, usize) -> bool + Sync,
    pixel: impl Fn((usize, usize), usize, usize) -> [f32; 4] + Sync,
) {
    gather_tiles_of(config, columns, &mut [color], selected, &|tile, x, y| {
        [pixel(tile, x, y)]
    });
}

/// [`gather_tiles`] of up to `G` colours at once: `pixel` gives `G` colours' RGBA, the first
/// `colours.len()` written into `colours` in order.
pub(crate) fn gather_tiles_of<const G: usize>(
    config: &ReconstructConfig,
    columns: usize,
    colours: &mut [&mut Color],
    selected: impl Fn(usize, usize) -> bool + Sync,
    pixel: &impl Gather<G>,
) {
    let width = config.width as usize;
    let size = config.tile as usize;
    let n = width * config.height as usize;
    let band = (size * width).max(1);
    // Alpha planes taken out, zeros where a colour has none (written, then dropped).
    assert!(colours.len() <= G, "at most {G} colours");
    let has_alpha: Vec<bool> = colours.iter().map(|c| c.a.is_some()).collect();
    let mut alphas: Vec<Vec<f32>> = colours
        .iter_mut()
        .map(|c| c.a.take().unwrap_or_else(|| vec![0.0; n]))
        .collect();
    // Each band's planes: R, G, B and A of each colour in turn.
    let mut bands: Vec<Vec<&mut [f32]>> = (0..n.div_ceil(band))
        .map(|_| Vec::with_capacity(4 * colours.len()))
        .collect();
    for (color, alpha) in colours.iter_mut().zip(alphas.iter_mut()) {
        for plane in [&mut color.r, &mut color.g, &mut color.b, alpha] {
            for (planes, piece) in bands.iter_mut().zip(plane.chunks_mut(band)) {
                planes.push(piece);
            }
        }
    }
    bands
        .into_par_iter()
        .enumerate()
        .for_each(|(row, mut planes)| {
            let tiles: Vec<usize> = (0..columns).filter(|&c| selected(c, row)).collect();
            gather_band((size, width), (row, &tiles), &mut planes, pixel)
        });
    for ((color, alpha), has) in colours.iter_mut().zip(alphas).zip(has_alpha) {
        color.a = has.then_some(alpha);
    }
}

/// What [`gather_tiles_of`] runs at each pixel: `G` colours' premultiplied RGBA of pixel
/// (x, y) of tile (column, row). A closure is one; the 2014 gather is a type of its own
/// ([`super::gather_2014`]), whose body is inlined into [`gather_band`]'s copies.
pub(crate) trait Gather<const G: usize>: Sync {
    fn pixel(&self, tile: (usize, usize), x: usize, y: usize) -> [[f32; 4]; G];
}

impl<const G: usize, F> Gather<G> for F
where
    F: Fn((usize, usize), usize, usize) -> [[f32; 4]; G] + Sync,
{
    #[inline(always)]
    fn pixel(&self, tile: (usize, usize), x: usize, y: usize) -> [[f32; 4]; G] {
        self(tile, x, y)
    }
}

/// One band of tile rows of [`gather_tiles_of`] (`row`, and its `tiles` to gather): every
/// pixel of those tiles, written into the band's `planes`.
///
/// Compiled for the CPU at hand (`multiversion`): a [`Gather`] whose `pixel` is inlined
/// (the 2014 gather's) runs with AVX2 where there is one. (A closure's body is compiled for
/// the baseline CPU wherever it is called from, unless the compiler inlines it: the 2014
/// gather, passed as a closure, stayed a baseline call.) Only the instructions change, never
/// the operations or their order, and nothing is fused (Rust does not contract a multiply
/// and an add), so both copies give the same bits.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn gather_band<const G: usize, P: Gather<G>>(
    (size, width): (usize, usize),
    (row, tiles): (usize, &[usize]),
    planes: &mut [&mut [f32]],
    pixel: &P,
) {
    for &c in tiles {
        for local_y in 0..planes[0].len() / width {
            let y = row * size + local_y;
            for x in c * size..((c + 1) * size).min(width) {
                let o = local_y * width + x;
                let value = pixel.pixel((c, row), x, y);
                for (k, plane) in planes.iter_mut().enumerate() {
                    plane[o] = value[k / 4][k % 4];
                }
            }
        }
    }
}
