// Motion blur's `tile_max` stage on the GPU: the twin of `tile_max` in src/motion/tile_max.rs
// (the CPU reference; McGuire et al. 2012, eq. 1). One workgroup per tile.
//
// In: the velocity planes vx, vy (width × height, px per frame). Out: the grid x, y
// (columns × rows, columns = ⌈width/size⌉, rows = ⌈height/size⌉): each tile's dominant
// vector, the one of largest |v|², the first in the tile's row-major order on ties; (0, 0)
// when no pixel has |v|² > 0. Tiles at the right and bottom edges may be partial.
//
// The CPU walks the tile in row-major order and keeps a vector when its |v|² is strictly
// larger; here 64 lanes each walk every 64th pixel of that order, then a tree reduction keeps
// the larger |v|², and on equal ones the earlier pixel: the same winner.
//
// NaN and infinity, as on the CPU (`m > best` is false for a NaN |v|², true for +∞ over
// anything finite): |v|² is compared by its bits. For non-negative floats the bits order as
// the values do, +∞ included, and NaN's bits lie above +∞'s, where they are refused. WGSL lets
// an implementation assume no NaN or infinity in floating-point arithmetic, so nothing here
// relies on a float comparison with one.
//
// Rounding: |v|² is x·x + y·y, each operation correctly rounded in WGSL as in Rust, but a
// driver may fuse the multiply and the add into an fma (WGSL cannot forbid it), and a GPU may
// flush subnormal results to zero. Either can change the winner only between two vectors
// whose |v|² are within a rounding of each other, or below 2⁻¹²⁶ px²; tests/gpu.rs states it.

// Keep in sync with `TileMaxConfig` in src/gpu/motion/tile_max.rs (a size test guards the layout).
struct TileMaxConfig {
    // Frame size, pixels.
    width: u32,
    height: u32,
    // Tile edge k, pixels.
    size: u32,
    // The grid: ⌈width/size⌉ × ⌈height/size⌉ tiles.
    columns: u32,
    rows: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> config: TileMaxConfig;
@group(0) @binding(1) var<storage, read> vx: array<f32>;
@group(0) @binding(2) var<storage, read> vy: array<f32>;
@group(0) @binding(3) var<storage, read_write> x: array<f32>;
@group(0) @binding(4) var<storage, read_write> y: array<f32>;

const LANES: u32 = 64u;
// No pixel yet: after every pixel in the tile's order.
const NONE: u32 = 0xffffffffu;

// Each lane's best so far: |v|² (bits), its index in the tile's row-major order, the vector.
var<workgroup> best_m: array<u32, LANES>;
var<workgroup> best_i: array<u32, LANES>;
var<workgroup> best_x: array<f32, LANES>;
var<workgroup> best_y: array<f32, LANES>;

// |v|² as bits, NaN included (refused by the caller).
fn magnitude_bits(vx: f32, vy: f32) -> u32 {
    return bitcast<u32>(vx * vx + vy * vy);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) tile: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    // Dispatched as columns × rows workgroups: every workgroup is a tile.
    let x0 = tile.x * config.size;
    let y0 = tile.y * config.size;
    let w = min(config.size, config.width - x0);
    let h = min(config.size, config.height - y0);
    var m = 0u;
    var index = NONE;
    var bx = 0.0;
    var by = 0.0;
    for (var k = lane; k < w * h; k += LANES) {
        let p = (y0 + k / w) * config.width + x0 + k % w;
        let px = vx[p];
        let py = vy[p];
        let mk = magnitude_bits(px, py);
        if mk <= INFINITY_BITS && mk > m {
            m = mk;
            index = k;
            bx = px;
            by = py;
        }
    }
    best_m[lane] = m;
    best_i[lane] = index;
    best_x[lane] = bx;
    best_y[lane] = by;
    workgroupBarrier();
    for (var half = LANES / 2u; half > 0u; half >>= 1u) {
        if lane < half {
            let o = lane + half;
            let later = best_m[o];
            let mine = best_m[lane];
            if later > mine || (later == mine && best_i[o] < best_i[lane]) {
                best_m[lane] = later;
                best_i[lane] = best_i[o];
                best_x[lane] = best_x[o];
                best_y[lane] = best_y[o];
            }
        }
        workgroupBarrier();
    }
    if lane == 0u {
        let t = tile.y * config.columns + tile.x;
        x[t] = best_x[0];
        y[t] = best_y[0];
    }
}
