// Motion blur's `neighbor_max` stage on the GPU: the twin of `neighbor_max` in
// src/motion/neighbor_max.rs (the CPU reference; McGuire et al. 2012, eq. 2). One invocation
// per tile.
//
// In: TileMax's grid x, y (columns × rows). Out: the grid of the same size holding, per tile,
// the dominant vector of the 3×3 tiles around it (tiles outside the grid skipped), visited in
// the CPU's order (rows, then columns), starting from (0, 0) and keeping a vector only when
// its |v|² is strictly larger: the first on ties.
//
// NaN, infinity and rounding as in tile_max.wgsl: |v|² is compared by its bits (NaN never
// wins, +∞ wins over anything finite); a driver that fuses x·x + y·y into an fma, or flushes
// subnormals, can only swap two vectors whose |v|² are within a rounding of each other.

// Keep in sync with `NeighborMaxConfig` in src/gpu/motion/neighbor_max.rs (a size test guards the
// layout).
struct NeighborMaxConfig {
    // The grid, tiles.
    columns: u32,
    rows: u32,
    _pad0: u32,
    _pad1: u32,
}

@group(0) @binding(0) var<uniform> config: NeighborMaxConfig;
@group(0) @binding(1) var<storage, read> tiles_x: array<f32>;
@group(0) @binding(2) var<storage, read> tiles_y: array<f32>;
@group(0) @binding(3) var<storage, read_write> x: array<f32>;
@group(0) @binding(4) var<storage, read_write> y: array<f32>;


@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let column = id.x;
    let row = id.y;
    if column >= config.columns || row >= config.rows {
        return;
    }
    var m = 0u;
    var bx = 0.0;
    var by = 0.0;
    for (var r = max(row, 1u) - 1u; r < min(row + 2u, config.rows); r++) {
        for (var c = max(column, 1u) - 1u; c < min(column + 2u, config.columns); c++) {
            let t = r * config.columns + c;
            let tx = tiles_x[t];
            let ty = tiles_y[t];
            let mt = bitcast<u32>(tx * tx + ty * ty);
            if mt <= INFINITY_BITS && mt > m {
                m = mt;
                bx = tx;
                by = ty;
            }
        }
    }
    let t = row * config.columns + column;
    x[t] = bx;
    y[t] = by;
}
