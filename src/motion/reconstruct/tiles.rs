//! Which tiles each of reconstruct's later stages works on, and the loop that runs a gather
//! over them: the paper's gather over the tiles whose NeighborMax blurs, the 2014 gather over
//! those within one tile of a blurring one, and the 2014 pack over those within its taps'
//! reach ([`packed_2014`]). Every other pixel keeps its colour, so still tiles cost nothing.
//! And which of the 2014 gather's tiles are plain ([`plain_tiles`]: every tap one surface).

use rayon::prelude::*;

use super::config::{
    reach_factor, ReconstructConfig, Texel2014, HALF_PIXEL, LENGTH, MOVING_SQUARED,
};
use super::matte::{self, Matte};
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
    gather_tiles_of(config, columns, &mut [color], selected, |tile, x, y| {
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
    pixel: impl Fn((usize, usize), usize, usize) -> [[f32; 4]; G] + Sync,
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
            for c in (0..columns).filter(|&c| selected(c, row)) {
                for local_y in 0..planes[0].len() / width {
                    let y = row * size + local_y;
                    for x in c * size..((c + 1) * size).min(width) {
                        let o = local_y * width + x;
                        let value = pixel((c, row), x, y);
                        for (k, plane) in planes.iter_mut().enumerate() {
                            plane[o] = value[k / 4][k % 4];
                        }
                    }
                }
            }
        });
    for ((color, alpha), has) in colours.iter_mut().zip(alphas).zip(has_alpha) {
        color.a = has.then_some(alpha);
    }
}

/// Which tiles are plain: every texel a tap of any of their pixels can read moves and has no
/// matte pair, so [`split_by_cover`](super::taps::split_by_cover) finds no matte there and
/// [`split`](super::taps::split) puts all four of a tap's pixels in one part, the nearest's
/// (part B empty): the gather then reads each tap as that part alone, without the tests, and
/// weighs no second part, with the same bits (most of a camera pan: the 1080p `pan`'s whole
/// process 1.21–1.23 → 0.94–0.96 s). A tap of a pixel of tile (c, r) reads within
/// `reach_factor · |M|` of the pixel along the vector it looks up (|M| at most the largest of
/// the 3×3 dilated tiles around, which the jittered lookup reaches, or the pixel's own |V|,
/// at most its tile's largest), a slid tap `2·|V|` further, and a bilinear read one pixel
/// more: the tile is plain where no tile within that reach, plus one pixel, holds a pixel
/// that fails. Each tile is read once, in parallel, up to its first failing pixel (a tile
/// the pack left out fails at its first: its texels are zero), and the reach is counted in
/// whole tiles on a summed-area table of the failing ones, so a sparse frame pays a read a
/// tile (a table of pixels, made on one thread, had cost the 1080p `sparse` 5 to 20 ms of 45).
pub(crate) fn plain_tiles(
    config: &ReconstructConfig,
    texels: &[Texel2014],
    mattes: &[Matte],
    tiles: &TileGrid,
) -> Vec<bool> {
    let (width, height) = (config.width as usize, config.height as usize);
    let size = config.tile as usize;
    let (columns, rows) = (tiles.columns, tiles.rows);
    // Pixels a plain tile's taps must not read: still ones, and any with a matte pair.
    let fails = |j: usize| {
        texels[j][LENGTH] < HALF_PIXEL || (!mattes.is_empty() && !matte::unpaired(&mattes[j], j))
    };
    // Per tile: whether a pixel of it fails, else its largest own |V|.
    let per_tile: Vec<Option<f32>> = (0..columns * rows)
        .into_par_iter()
        .map(|t| {
            let (c, r) = (t % columns, t / columns);
            let mut own = 0.0f32;
            for y in r * size..((r + 1) * size).min(height) {
                for x in c * size..((c + 1) * size).min(width) {
                    let j = y * width + x;
                    if fails(j) {
                        return None;
                    }
                    own = own.max(texels[j][LENGTH]);
                }
            }
            Some(own)
        })
        .collect();
    // table[r·(columns + 1) + c]: the failing tiles above and left of tile (c, r).
    let stride = columns + 1;
    let mut table = vec![0u32; stride * (rows + 1)];
    for r in 0..rows {
        let mut row = 0u32;
        for c in 0..columns {
            row += per_tile[r * columns + c].is_none() as u32;
            table[(r + 1) * stride + c + 1] = table[r * stride + c + 1] + row;
        }
    }
    (0..columns * rows)
        .map(|t| {
            let (c, r) = (t % columns, t / columns);
            let Some(mut m) = per_tile[t] else {
                return false;
            };
            for rr in r.saturating_sub(1)..(r + 2).min(rows) {
                for cc in c.saturating_sub(1)..(c + 2).min(columns) {
                    m = m.max(tiles.length(cc, rr));
                }
            }
            let reach = m * reach_factor(config) + 2.0 * m + 2.0;
            if !reach.is_finite() || reach > (width + height) as f32 {
                return false;
            }
            // The reach in whole tiles beyond the tile's own.
            let across = (reach / size as f32).ceil() as usize;
            let (c0, r0) = (c.saturating_sub(across), r.saturating_sub(across));
            let (c1, r1) = ((c + across + 1).min(columns), (r + across + 1).min(rows));
            let count = table[r1 * stride + c1] + table[r0 * stride + c0]
                - table[r0 * stride + c1]
                - table[r1 * stride + c0];
            count == 0
        })
        .collect()
}
