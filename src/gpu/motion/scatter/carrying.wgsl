
// ---- light layers carried ----------------------------------------------------------------
//
// scatter.wgsl's hooks for light layers (RGB colours beside the beauty, sharing its alpha),
// the twin of the CPU's carried planes (`Scatter::extra`, src/motion/scatter/): the curves
// are drawn once, by the same dispatches, and every deposit adds each layer channel's value
// at the curve's pixel, with the weight it gives the beauty, into sums of its own; each
// pixel is resolved once (`Resolution`) and that applied to every layer channel. Each
// channel has its own colour bound and fixed-point scale, as each of the beauty's has, so a
// layer's sums are the bits it would get alone in the beauty's place.
//
// Bindings, group 1 (group 0 is the beauty's, as scatter.wgsl lists them): the layers'
// input planes (R, G, B of each layer in turn), their sums (two words per pixel, plane after
// plane in the same order) and their output planes (the same order). `state[LAYERS]` says
// how many layers the run carries (at most MOST_LAYERS), `state[CARRIED_BOUND + c]` holds
// channel c's bound.

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

// The power of two above every |value| of a moving pixel in carried channel c.
fn carried_exponent(c: u32) -> i32 {
    return exponent_above(atomicLoad(&state[CARRIED_BOUND + c]));
}

// reach: moving pixel i raises each carried channel's bound, as it raises the beauty's.
fn carry_bound(i: u32) {
    let n = pixels();
    let channels = carried_channels();
    for (var c = 0u; c < channels; c++) {
        atomicMax(&state[CARRIED_BOUND + c], bitcast<u32>(abs(carried[c * n + i])));
    }
}

// The curve's layer values, times 2^−e per channel (the pen's colour for the layers), and
// how many (read once a curve, not at every deposit).
var<private> carried_pen: array<f32, MOST_CARRIED>;
var<private> pen_channels: u32;

// accumulate: the values of moving pixel i, the curve being drawn.
fn carry_pen(i: u32) {
    let n = pixels();
    pen_channels = carried_channels();
    for (var c = 0u; c < pen_channels; c++) {
        carried_pen[c] = ldexp(carried[c * n + i], -carried_exponent(c));
    }
}

// accumulate: a deposit of weight d at pixel p that passed the depth test: each carried
// channel's value times d into its sum (`add` of scatter.wgsl, on the carried sums).
fn carry_deposit(p: u32, d: f32) {
    let n = pixels();
    for (var c = 0u; c < pen_channels; c++) {
        let f = fixed(d * carried_pen[c]);
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

// resolve: pixel p's carried channels by its resolution, the beauty's.
fn carry_resolve(p: u32, r: Resolution) {
    let n = pixels();
    let channels = carried_channels();
    for (var c = 0u; c < channels; c++) {
        let plane = c * n;
        let own = carried[plane + p];
        var value = own;
        if r.kind != OWN {
            let lo = atomicLoad(&carried_sums[2u * (plane + p)]);
            let sum = fixed_value(lo, atomicLoad(&carried_sums[2u * (plane + p) + 1u]));
            // What lies behind, as `behind_color` finds the beauty's.
            var back = own;
            if r.kind == REST && r.behind.count > 0u {
                var s = 0.0;
                for (var k = 0u; k < r.behind.count; k++) {
                    s += carried[plane + r.behind.pixels[k]];
                }
                back = s / f32(r.behind.count);
            }
            value = resolved(r, sum, carried_exponent(c), own, back);
        }
        carried_out[plane + p] = value;
    }
}
