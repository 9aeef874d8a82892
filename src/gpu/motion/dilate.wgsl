// Motion blur's `dilate` stage on the GPU: the twin of `dilate` in src/motion/dilate.rs (the
// CPU reference: the 2014 filter's tile dilation, Guertin et al. 2014 with Jimenez 2014's
// changes). One invocation per tile.
//
// In: the tile grid x, y (columns × rows, half-spread vectors in px) and, per tile, what the
// reach test needs of its vector as a source (`SourceTile`, made on the host by the CPU's own
// `Source::new`: WGSL's sqrt and division are not correctly rounded, and a tile beside a
// diagonal line sits exactly √2 tiles from it, on the test's threshold). Out: the dilated
// grid: each tile keeps the longest vector whose line reaches it.
//
// The CPU scatters each source, in row-major order, to the tiles of the rectangle it spans;
// a tile takes a source's vector when it reaches the tile and is strictly longer than the
// best so far (the tile's own to begin with). A tile's result depends only on the sources
// that reach it, in that order, so this gathers: each tile visits the sources within `radius`
// tiles (the largest span of any source) in row-major order, with the same test.
//
// Lengths |M|² are compared by their bits, as in tile_max.wgsl: NaN never wins (and a tile
// whose own |M|² is NaN keeps its vector), +∞ wins over anything finite. A source whose
// normal is not finite (|M| infinite) reaches nothing on the CPU (its test compares a NaN);
// the host marks it not `live`.
//
// Rounding: the test's n·(dx, dy) is two products and a sum. The host's normal is cut to 11
// significant bits, away from zero (`short` in src/motion/dilate.rs), so each product is
// exact for offsets under 2^13 tiles and the sum is rounded once, whether or not a driver
// fuses a product into it (NVIDIA's does; lavapipe's does not): the result is the CPU's, bit
// for bit.

// Keep in sync with `DilateConfig` in src/gpu/motion/dilate.rs (a size test guards the layout).
struct DilateConfig {
    // The grid, tiles.
    columns: u32,
    rows: u32,
    // The largest span of any live source, clamped to the grid, tiles.
    radius: u32,
    _pad: u32,
}

// Keep in sync with `SourceTile` in src/gpu/motion/dilate.rs: `Source` of src/motion/dilate.rs.
struct SourceTile {
    // |M|², px².
    length2: f32,
    // ⌈|M_x|/tile⌉, ⌈|M_y|/tile⌉, saturated to whole tiles.
    span_x: u32,
    span_y: u32,
    // The unit normal of M's line.
    nx: f32,
    ny: f32,
    // 1 when M can reach another tile: |M|² > 0 and not NaN, and its normal finite.
    live: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> config: DilateConfig;
@group(0) @binding(1) var<storage, read> tiles_x: array<f32>;
@group(0) @binding(2) var<storage, read> tiles_y: array<f32>;
@group(0) @binding(3) var<storage, read> sources: array<SourceTile>;
@group(0) @binding(4) var<storage, read_write> x: array<f32>;
@group(0) @binding(5) var<storage, read_write> y: array<f32>;

// √2 in f32, `std::f32::consts::SQRT_2` (0x3fb504f3), by its bits so no literal rounding
// is involved.
const REACH_BITS: u32 = 0x3fb504f3u;

// a > b for two |M|² (non-negative, or NaN), false when either is NaN.
fn longer(a: u32, b: u32) -> bool {
    return a <= INFINITY_BITS && b <= INFINITY_BITS && a > b;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let column = id.x;
    let row = id.y;
    if column >= config.columns || row >= config.rows {
        return;
    }
    let t = row * config.columns + column;
    var best = bitcast<u32>(sources[t].length2);
    var bx = tiles_x[t];
    var by = tiles_y[t];
    let reach = bitcast<f32>(REACH_BITS);
    let r0 = max(row, config.radius) - config.radius;
    let r1 = min(row + config.radius + 1u, config.rows);
    let c0 = max(column, config.radius) - config.radius;
    let c1 = min(column + config.radius + 1u, config.columns);
    for (var r = r0; r < r1; r++) {
        for (var c = c0; c < c1; c++) {
            let s = sources[r * config.columns + c];
            if s.live == 0u {
                continue;
            }
            // From the source to this tile, in tiles.
            let dx = i32(column) - i32(c);
            let dy = i32(row) - i32(r);
            if u32(abs(dx)) > s.span_x || u32(abs(dy)) > s.span_y {
                continue;
            }
            let length = bitcast<u32>(s.length2);
            if longer(length, best) && abs(s.nx * f32(dx) + s.ny * f32(dy)) < reach {
                best = length;
                bx = tiles_x[r * config.columns + c];
                by = tiles_y[r * config.columns + c];
            }
        }
    }
    x[t] = bx;
    y[t] = by;
}
