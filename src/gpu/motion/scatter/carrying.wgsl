
// ---- light layers carried ----------------------------------------------------------------
//
// scatter.wgsl's hooks for light layers (RGB colours beside the beauty, sharing its alpha),
// the twin of the CPU's carried planes (`Scatter::extra`, src/motion/scatter/): the curves
// are drawn once, by the same dispatches, and every deposit adds each layer channel's value
// at the curve's pixel, with the weight it gives the beauty, into sums of its own; each
// pixel is resolved once (`Resolution`) and that applied to every layer channel. Each
// layer's R, G and B have a colour bound and fixed-point scale of their own in each tile
// (fixed.wgsl), as the beauty's R, G and B have, so a layer's sums are the bits it would get
// alone in the beauty's place, and a firefly in one layer changes no other colour's scale.
//
// Bindings, group 1 (group 0 is the beauty's, as scatter.wgsl lists them): the layers'
// input planes (R, G, B of each layer in turn), their sums (two words per pixel, plane after
// plane in the same order) and their output planes (the same order). `state[LAYERS]` says
// how many layers the run carries (at most MOST_LAYERS); each block's and tile's words hold
// the layers' bounds and scales after the beauty's (from FIRST_CARRIED, fixed.wgsl).

@group(1) @binding(0) var<storage, read> carried: array<f32>;
@group(1) @binding(1) var<storage, read_write> carried_sums: array<atomic<u32>>;
@group(1) @binding(2) var<storage, read_write> carried_out: array<f32>;

// Most layers one run carries (keep in sync with src/gpu/motion/scatter/pass.rs), and their
// channels.
const MOST_LAYERS: u32 = 8u;
const MOST_CARRIED: u32 = 24u;

// The carried channels of this run: three a layer.
fn carried_channels() -> u32 {
    return 3u * min(atomicLoad(&state[LAYERS]), MOST_LAYERS);
}

// The layers carried in this run.
fn carried_layers() -> u32 {
    return min(atomicLoad(&state[LAYERS]), MOST_LAYERS);
}

// The largest |value| of layer l's channels at pixel i (`count_curve` bounds each layer's
// colour as it bounds the beauty's).
fn carried_magnitude(l: u32, i: u32) -> f32 {
    let n = pixels();
    let c = 3u * l;
    let r = abs(carried[c * n + i]);
    let g = abs(carried[(c + 1u) * n + i]);
    return max(max(r, g), abs(carried[(c + 2u) * n + i]));
}

// The curve's layer values (read once a curve, not at every deposit), and how many.
var<private> carried_pen: array<f32, MOST_CARRIED>;
var<private> pen_channels: u32;

// accumulate: the values of moving pixel i, the curve being drawn.
fn carry_pen(i: u32) {
    let n = pixels();
    pen_channels = carried_channels();
    for (var c = 0u; c < pen_channels; c++) {
        carried_pen[c] = carried[c * n + i];
    }
}

// accumulate: a deposit of weight d at pixel p, in the tile whose words start at `tile`,
// that passed the depth test: each carried channel's value times d, in the units of its
// layer's colour in the tile (which follow the beauty's), into its sum (`add` of
// fixed.wgsl, on the carried sums).
fn carry_deposit(p: u32, tile: u32, d: f32) {
    let n = pixels();
    var dc = d;
    for (var c = 0u; c < pen_channels; c++) {
        // Each layer's colour has its own scale in the tile, its channels share it.
        if c % 3u == 0u {
            dc = weight_in(d, tile, FIRST_CARRIED + c / 3u);
        }
        let f = fixed(dc * carried_pen[c]);
        if f.x == 0u && f.y == 0u {
            continue;
        }
        let low = 2u * (c * n + p);
        let high = carry(atomicAdd(&carried_sums[low], f.x), f.x, f.y);
        if high != 0u {
            atomicAdd(&carried_sums[low + 1u], high);
        }
    }
}

// resolve: pixel p's carried channels by its resolution, the beauty's, in the units of its
// tile (whose words start at `tile`).
fn carry_resolve(p: u32, tile: u32, r: Resolution) {
    let n = pixels();
    let channels = carried_channels();
    for (var c = 0u; c < channels; c++) {
        let plane = c * n;
        let own = carried[plane + p];
        var value = own;
        if r.kind != OWN {
            let lo = atomicLoad(&carried_sums[2u * (plane + p)]);
            let hi = atomicLoad(&carried_sums[2u * (plane + p) + 1u]);
            let sum = fixed_value(lo, hi, shift_of(tile, FIRST_CARRIED + c / 3u));
            // What lies behind, as `behind_color` finds the beauty's.
            var back = own;
            if r.kind == REST && r.behind.count > 0u {
                var s = 0.0;
                for (var k = 0u; k < r.behind.count; k++) {
                    s += carried[plane + r.behind.pixels[k]];
                }
                back = s / f32(r.behind.count);
            }
            value = resolved(r, sum, exponent_of(tile, FIRST_CARRIED + c / 3u), own, back);
        }
        carried_out[plane + p] = value;
    }
}
