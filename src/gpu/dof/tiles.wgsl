// Depth of field's tile min/max stage on the GPU: the twin of `tiles` in src/dof/tiles.rs
// (the CPU reference; Sousa's "tile min/max CoC"). Two entry points, dispatched in order, one
// invocation per tile each:
//
// 1. `tile_min_max`: per tile, its largest bokeh radius |CoC|/2 of those at least ε/2 (`own`,
//    0 when none), and its smallest and largest signed radius (scratch, as bits: a tile with
//    no value yet holds +∞ and −∞ as the CPU's start does); the largest radius of the frame
//    (`overall`, an atomic max of non-negative floats' bits, which order as the values do).
// 2. `tile_reach`: per tile, the largest own radius of the tiles within span = ⌈(overall + 1)/tile⌉
//    tiles whose bokeh reaches it (the distance between the tiles' nearest pixels at most that
//    radius + 1 px), and whether no tile of that neighbourhood is nearer than its own largest
//    signed radius by half a layer (`far_only`, 1 or 0).
//
// In: the signed CoC plane (px, diameter) and the table of distances between tiles
// (`distance[dy·columns + dx]` for tiles dx, dy apart, made on the host by the CPU's own
// `gap_distance`: WGSL's sqrt is not correctly rounded). Out: reach, own, far_only.
//
// Every result is a maximum, a minimum or a comparison of values taken from the input, halved
// (exact) or plus one (correctly rounded in WGSL as in Rust), so it is the CPU's bit for bit;
// the one exception is a CoC below 2⁻¹²⁵ px, whose half is subnormal and may be flushed to zero
// by a GPU (tests/gpu_dof.rs states it). NaN is skipped by its bits, as the CPU's comparisons and
// f32::min/max skip it. The CPU's domain is a plane from `coc_plane` (finite, |CoC| ≤ 10⁶):
// beyond it the CPU's span arithmetic overflows; here the span is clamped to the grid.

// Keep in sync with `TilesConfig` in src/dof/tiles.rs (a test holds the layouts together).
struct TilesConfig {
    // Frame size, pixels.
    width: u32,
    height: u32,
    // Tile edge, pixels (tiles.rs's TILE), and its reciprocal (a power of two: exact).
    tile: u32,
    // The grid: ⌈width/tile⌉ × ⌈height/tile⌉ tiles.
    columns: u32,
    rows: u32,
    // ε: CoC diameters below it are in focus (px).
    epsilon: f32,
    // Two signed CoC radii closer than this are one layer (px; tiles.rs's LAYER).
    layer: f32,
    inv_tile: f32,
}

@group(0) @binding(0) var<uniform> config: TilesConfig;
@group(0) @binding(1) var<storage, read> coc: array<f32>;
@group(0) @binding(2) var<storage, read> distance: array<f32>;
@group(0) @binding(3) var<storage, read_write> reach: array<f32>;
@group(0) @binding(4) var<storage, read_write> own: array<f32>;
@group(0) @binding(5) var<storage, read_write> far_only: array<u32>;
// Scratch, from the first entry point to the second.
@group(0) @binding(6) var<storage, read_write> lowest: array<u32>;
@group(0) @binding(7) var<storage, read_write> highest: array<u32>;
@group(0) @binding(8) var<storage, read_write> overall: atomic<u32>;


@compute @workgroup_size(8, 8)
fn tile_min_max(@builtin(global_invocation_id) id: vec3<u32>) {
    let tx = id.x;
    let ty = id.y;
    if tx >= config.columns || ty >= config.rows {
        return;
    }
    let half_focus = 0.5 * config.epsilon;
    var largest = 0.0;
    var any = false;
    var low = 0.0;
    var high = 0.0;
    let x1 = min(tx * config.tile + config.tile, config.width);
    let y1 = min(ty * config.tile + config.tile, config.height);
    for (var y = ty * config.tile; y < y1; y++) {
        for (var x = tx * config.tile; x < x1; x++) {
            let c = coc[y * config.width + x];
            if (bitcast<u32>(c) & MAGNITUDE) > INFINITY_BITS {
                continue; // NaN
            }
            let r = 0.5 * abs(c);
            if r >= half_focus && r > largest {
                largest = r;
            }
            let signed = 0.5 * c;
            low = select(signed, min(low, signed), any);
            high = select(signed, max(high, signed), any);
            any = true;
        }
    }
    let t = ty * config.columns + tx;
    own[t] = largest;
    lowest[t] = select(INFINITY_BITS, bitcast<u32>(low), any);
    highest[t] = select(NEG_INFINITY_BITS, bitcast<u32>(high), any);
    atomicMax(&overall, bitcast<u32>(largest));
}

@compute @workgroup_size(8, 8)
fn tile_reach(@builtin(global_invocation_id) id: vec3<u32>) {
    let tx = id.x;
    let ty = id.y;
    if tx >= config.columns || ty >= config.rows {
        return;
    }
    let largest_radius = bitcast<f32>(atomicLoad(&overall));
    // ⌈(overall + 1)/tile⌉, clamped to the grid (the CPU clamps its loops to it).
    let extent = max(config.columns, config.rows);
    let span = u32(min(ceil((largest_radius + 1.0) * config.inv_tile), f32(extent)));
    var best = 0.0;
    var any_nearest = false;
    var nearest = 0.0;
    let y0 = max(ty, span) - span;
    let y1 = min(ty + span + 1u, config.rows);
    let x0 = max(tx, span) - span;
    let x1 = min(tx + span + 1u, config.columns);
    for (var oy = y0; oy < y1; oy++) {
        for (var ox = x0; ox < x1; ox++) {
            let other = oy * config.columns + ox;
            let low = lowest[other];
            if low != INFINITY_BITS {
                let v = bitcast<f32>(low);
                nearest = select(v, min(nearest, v), any_nearest);
                any_nearest = true;
            }
            let r = own[other];
            if r <= best {
                continue;
            }
            let dx = max(tx, ox) - min(tx, ox);
            let dy = max(ty, oy) - min(ty, oy);
            if distance[dy * config.columns + dx] <= r + 1.0 {
                best = r;
            }
        }
    }
    let t = ty * config.columns + tx;
    reach[t] = best;
    // The gather's test: a sample is far when its radius > the pixel's − layer/2. With no
    // value in the tile (highest −∞) or none in the neighbourhood (nearest +∞): far only.
    let high = highest[t];
    var far = true;
    if high != NEG_INFINITY_BITS && any_nearest {
        far = nearest > bitcast<f32>(high) - 0.5 * config.layer;
    }
    far_only[t] = select(0u, 1u, far);
}
