// Motion blur's `scatter` pass on the GPU: the twin of src/motion/scatter/ (the CPU reference;
// Guertin & Nowrouzezahrai, *High Performance Non-linear Motion Blur*, §3), stage for stage:
// `reach` (which pixels move; a list of them) → `prepare` (the accumulate dispatch's size) →
// `accumulate` (each moving pixel draws its curve into fixed-point sums) → `resolve` (each
// pixel's output by the normalisation), with `scales` between reach and accumulate (each
// tile's fixed-point scale, from the curves that can reach it: fixed.wgsl). Why a compute
// rasteriser with integer atomics, and the f32 form of the geometry:
// src/gpu/motion/scatter/mod.rs.
//
// Bindings, in order: the ScatterConfig uniform; colour (R, G, B, A planes), depth, prev and
// next (x, y, z planes each) — the CPU's inputs; then `state` (the moving count, the
// accumulate dispatch, the farthest reach, the host's flags; then each block's curves, reach
// and colour bounds: fixed.wgsl), `moving` (the list of moving pixels, two words an entry:
// the pixel, and how far its curve reaches; then each tile's scales: fixed.wgsl), the five
// sums (R, G, B, A, weight; two words per pixel), the output colour (four planes), and the
// fringe (src/motion/scatter/fringe.rs, found on the CPU: three words an entry, the
// still pixel, its moving partner and the partner's coverage of it; `reach_fringe` lists
// them after the moving pixels and `accumulate` draws each as its partner's curve from the
// pixel's own centre, its weights times the coverage).
//
// Light layers: this file goes into two modules. Its stages call hooks (`carried_layers`,
// `carried_magnitude`, `carry_pen`, `carry_deposit`, `carry_resolve`) at the points where
// the CPU handles its carried planes (`Scatter::extra`): alone.wgsl defines them empty (the
// beauty alone, whose compiled code is then what it was without them), carrying.wgsl
// carries light layers through the same dispatches with bindings of their own (group 1).

// Keep in sync with `ScatterConfig` in src/motion/scatter/config.rs (its size test and the test
// in src/gpu/motion/scatter/mod.rs guard the layout: thirteen 4-byte fields).
struct ScatterConfig {
    width: u32,
    height: u32,
    shutter: f32,
    offset: f32,
    segments: u32,
    sigma: f32,
    gaussian: u32,
    background_weight: f32,
    exposure: u32,
    arc: u32,
    max_curve: f32,
    flatness: f32,
    depth_tolerance: f32,
}

@group(0) @binding(0) var<uniform> config: ScatterConfig;
@group(0) @binding(1) var<storage, read> color: array<f32>;
@group(0) @binding(2) var<storage, read> depth: array<f32>;
@group(0) @binding(3) var<storage, read> prev: array<f32>;
@group(0) @binding(4) var<storage, read> next: array<f32>;
@group(0) @binding(5) var<storage, read_write> state: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> moving: array<u32>;
@group(0) @binding(7) var<storage, read_write> sum_r: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> sum_g: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> sum_b: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> sum_a: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> sum_w: array<atomic<u32>>;
@group(0) @binding(12) var<storage, read_write> out: array<f32>;
@group(0) @binding(13) var<storage, read_write> fringe: array<u32>;

// Invocations per workgroup of every stage but `prepare`, and whether `accumulate` walks the
// moving list backwards: test hooks (the output must not depend on either).
override WORKGROUP: u32 = 64u;
override REVERSED: bool = false;

// `state`'s words (keep in sync with src/gpu/motion/scatter/pass.rs).
const COUNT: u32 = 0u;
const DISPATCH: u32 = 1u;
// The farthest any block's curves reach (px), which bounds the blocks `scales` looks at.
const MOST_REACH: u32 = 4u;
const FLAGS: u32 = 8u;
// The light layers carried (the host's; 0 for the beauty alone).
const LAYERS: u32 = 9u;
// The fringe's entries (the host's).
const FRINGES: u32 = 10u;
// A fringe entry in the moving list: its index with this bit set.
const FRINGE: u32 = 0x80000000u;
// Each block's words, then FAR's (fixed.wgsl).
const BLOCKS: u32 = 16u;
// Flags the host sets: every alpha is 1 (alpha sums are the weight sums), and the positions
// carry depth (z planes).
const OPAQUE: u32 = 1u;
const HAS_Z: u32 = 2u;

// The CPU's constants (src/motion/scatter/mod.rs, src/motion/curve.rs; a test compares).
const STILL: f32 = 0.25;
const MOST_SEGMENTS: u32 = 64u;
const COVERED: f32 = 0.001;
const COLLINEAR: f32 = 0.0001;
const LARGEST_RADIUS: f32 = 10000000.0;
const TAU: f32 = 6.2831855;
const PI: f32 = 3.1415927;
// Most workgroups along one dispatch dimension (WebGPU's limit); more go to the second.
const MOST_GROUPS: u32 = 65535u;

fn pixels() -> u32 {
    return config.width * config.height;
}

// The invocation's index in a dispatch of x × y workgroups.
fn flat(group: vec3<u32>, groups: vec3<u32>, lane: u32) -> u32 {
    return (group.y * groups.x + group.x) * WORKGROUP + lane;
}

// NaN and infinity are tested on the bits (`is_nan`, `is_finite`: the prelude).

// ---- The f32 form of the geometry -------------------------------------------------------
//
// Positions are relative to the corner of the moving pixel (x, y): its centre p(0) is
// (0.5, 0.5), pixel boundaries stay at integers, and after the scaling to `max_curve`
// every point is within that many pixels of p(0), so f32 keeps ~2⁻¹⁵ px where the CPU's f64
// keeps its absolute coordinates exactly.

// A moving pixel's p(−1) and p(+1), relative to its corner.
struct Motion {
    prev: vec2<f32>,
    next: vec2<f32>,
}

fn motion_of(i: u32) -> Motion {
    let n = pixels();
    let corner = vec2<f32>(f32(i % config.width), f32(i / config.width));
    return Motion(
        vec2<f32>(prev[i], prev[n + i]) - corner,
        vec2<f32>(next[i], next[n + i]) - corner,
    );
}

// The exposure [t0, t1] (`Shutter::interval`).
fn interval() -> vec2<f32> {
    return vec2<f32>((config.offset - 0.5) * config.shutter, (config.offset + 0.5) * config.shutter);
}

// The farthest the exposure gets from the frame's instant.
fn half() -> f32 {
    let t = interval();
    return max(abs(t.x), abs(t.y));
}

// `Scatter::extent`: a bound on how far the curve strays from p(0) during the exposure.
fn extent(m: Motion) -> f32 {
    let now = vec2<f32>(0.5, 0.5);
    let v = 0.5 * (m.next - m.prev);
    let a = 0.5 * (m.next + m.prev) - now;
    let h = half();
    return h * length2(v) + h * h * length2(a);
}

// |p| as the CPU computes it (no hypot): sqrt(x² + y²).
fn length2(p: vec2<f32>) -> f32 {
    return sqrt(p.x * p.x + p.y * p.y);
}

fn cross2(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return a.x * b.y - a.y * b.x;
}

// The weight along the curve at time t (`Scatter::weight`).
fn weight(t: f32) -> f32 {
    if config.gaussian == 0u {
        return 1.0;
    }
    let t01 = interval();
    let d = 0.5 * (t - 0.5 * (t01.x + t01.y));
    let sigma = config.sigma;
    return exp(-d * d / (2.0 * sigma * sigma));
}

// ---- reach -------------------------------------------------------------------------------

// Stage 1: each pixel's motion test (`Scatter::motion`); a moving pixel joins the list (in
// whatever order the invocations arrive: the sums are integers, so the order is immaterial)
// and counts its curve into its block (`count_curve`: its reach and per-channel |colour|,
// from which `scales` sets the fixed point of the tiles it reaches).
@compute @workgroup_size(WORKGROUP)
fn reach(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let i = flat(group, groups, lane);
    let n = pixels();
    if i >= n {
        return;
    }
    let m = motion_of(i);
    if !(extent(m) >= STILL) {
        return;
    }
    let slot = atomicAdd(&state[COUNT], 1u);
    moving[2u * slot] = i;
    moving[2u * slot + 1u] = count_curve(i, i, m);
}

// Stage 1, the fringe: each entry joins the moving list, marked, and counts its partner's
// curve into the block of its own pixel, from which it is drawn.
@compute @workgroup_size(WORKGROUP)
fn reach_fringe(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let k = flat(group, groups, lane);
    if k >= atomicLoad(&state[FRINGES]) {
        return;
    }
    // The fringe's pixels are still, so the list holds them and the moving ones; but where
    // the f32 motion test calls one moving that the CPU's called still, a full list drops
    // the entry (`prepare` and `accumulate` read at most a pixel's worth).
    let slot = atomicAdd(&state[COUNT], 1u);
    let partner = fringe[3u * k + 1u];
    let reach = count_curve(fringe[3u * k], partner, motion_of(partner));
    if slot < pixels() {
        moving[2u * slot] = FRINGE | k;
        moving[2u * slot + 1u] = reach;
    }
}

// Between reach and accumulate: one workgroup of `WORKGROUP` invocations per moving pixel, in
// rows of at most MOST_GROUPS.
@compute @workgroup_size(1)
fn prepare() {
    let count = min(atomicLoad(&state[COUNT]), pixels());
    let groups = (count + WORKGROUP - 1u) / WORKGROUP;
    let x = min(groups, MOST_GROUPS);
    var y = 0u;
    if x > 0u {
        y = (groups + x - 1u) / x;
    }
    atomicStore(&state[DISPATCH], x);
    atomicStore(&state[DISPATCH + 1u], y);
    atomicStore(&state[DISPATCH + 2u], 1u);
}

// ---- curves: curve.wgsl (src/motion/curve.rs) ---------------------------------------------

// ---- accumulate --------------------------------------------------------------------------

// One curve cut into segments (`Path`), points relative to the moving pixel's corner.
var<private> points: array<vec2<f32>, 65>;
var<private> weights: array<f32, 65>;
var<private> depths: array<f32, 65>;
var<private> lengths: array<f32, 64>;

// `Scatter::path` for moving pixel i (its depths; a fringe entry's, its partner's), its
// weights times `cover` (1, or a fringe's coverage): its segment count, 0 if it has no curve.
fn path(i: u32, m: Motion, cover: f32) -> u32 {
    let now = vec2<f32>(0.5, 0.5);
    let t01 = interval();
    let t0 = t01.x;
    let t1 = t01.y;
    let most = config.segments;
    let tolerance = config.flatness;
    var arc = Arc(false, vec2<f32>(0.0), 0.0, 0.0, 0.0, 0.0);
    if config.arc != 0u {
        arc = arc_fit(m.prev, now, m.next);
    }
    let bezier = bezier_through(m.prev, now, m.next);
    var segments: u32;
    if arc.ok {
        segments = arc_segments(arc, t0, t1, tolerance, most);
    } else {
        segments = bezier_segments(bezier, 0.5 * (t1 - t0), tolerance, most);
    }
    let n = pixels();
    let z0 = depth[i];
    let zp = prev[2u * n + i];
    let zn = next[2u * n + i];
    let has_z = (atomicLoad(&state[FLAGS]) & HAS_Z) != 0u && is_finite(zp) && is_finite(zn)
        && is_finite(z0);
    var total = 0.0;
    let step = (t1 - t0) / f32(segments);
    for (var k = 0u; k <= segments; k++) {
        let t = t0 + step * f32(k);
        if arc.ok {
            points[k] = now + arc_at(arc, t);
        } else {
            points[k] = bezier_at(bezier, 0.5 * (t + 1.0));
        }
        weights[k] = weight(t);
        if has_z {
            depths[k] = max(z0 + t * 0.5 * (zn - zp) + t * t * (0.5 * (zn + zp) - z0), 0.0);
        } else {
            depths[k] = z0;
        }
        if k > 0u {
            lengths[k - 1u] = length2(points[k] - points[k - 1u]);
            total += lengths[k - 1u];
        }
    }
    if is_nan(total) || total <= 1e-9 {
        return 0u;
    }
    let longest = max(config.max_curve, 1.0);
    var scale = 1.0;
    if total > longest {
        // Scaled about p(0): a similarity, so every length scales the same.
        scale = longest / total;
        for (var k = 0u; k <= segments; k++) {
            points[k] = now + scale * (points[k] - now);
        }
    }
    if config.exposure != 0u {
        var sum = total;
        if config.gaussian != 0u {
            sum = 0.0;
            for (var k = 0u; k < segments; k++) {
                sum += lengths[k] * 0.5 * (weights[k] + weights[k + 1u]);
            }
        }
        sum *= scale;
        if !(sum > 0.0 && is_finite(sum)) {
            return 0u;
        }
        let inverse = cover / sum;
        for (var k = 0u; k <= segments; k++) {
            weights[k] *= inverse;
        }
    }
    return segments;
}

// The drawing of one curve: its colour (each deposit puts it in the units of its tile,
// fixed.wgsl), the weight's unit 2^G, where its pixel is, how far from it the curve may
// deposit (its reach as `reach` counted it: every walk is clipped to it, so no deposit lands
// in a tile whose scale did not count the curve), and whether alpha sums are kept. (The
// carried layers' colours: `carry_pen`.)
struct Pen {
    color: vec4<f32>,
    weight: f32,
    corner: vec2<i32>,
    reach: i32,
    opaque: bool,
    tolerance: f32,
}

// A deposit of weight d (coverage × weight) at pixel (px, py), absolute, inside the frame,
// where the curve's depth z passes the depth test (`Segment::deposit`).
fn deposit(pen: Pen, px: i32, py: i32, d: f32, z: f32) {
    if d == 0.0 {
        return;
    }
    let p = u32(py) * config.width + u32(px);
    // A curve passes a pixel whose depth is at least its own / (1 + tolerance).
    let limit = depth[p] * pen.tolerance;
    if !(z <= limit) {
        return;
    }
    // The colour and weight in the units of p's tile.
    let tile = tile_at((u32(py) / BLOCK) * blocks_across() + u32(px) / BLOCK);
    let dc = weight_in(d, tile, 0u);
    add(0u, p, dc * pen.color.x);
    add(1u, p, dc * pen.color.y);
    add(2u, p, dc * pen.color.z);
    if !pen.opaque {
        add(3u, p, weight_in(d, tile, ALPHA) * pen.color.w);
    }
    add(4u, p, d * pen.weight);
    // The carried layers' deposits, with the same weight (`Segment::carry`).
    carry_deposit(p, tile, d);
}

// Draws the segment a → b (relative to the pixel's corner) with weights w0 → w1 and depths
// z0 → z1: `Walk` over the frame's columns (rows where the walk runs along y), each column's
// exact length split between the two rows whose centres bracket the segment at its middle.
fn draw(pen: Pen, a_in: vec2<f32>, b_in: vec2<f32>, w0: f32, w1: f32, z0: f32, z1: f32) {
    if !(is_finite(a_in.x) && is_finite(a_in.y) && is_finite(b_in.x) && is_finite(b_in.y)) {
        return;
    }
    // A depth that is not finite at either end never passes on the CPU (its change along
    // the segment is NaN there): nothing to draw.
    if !(is_finite(z0) && is_finite(z1)) {
        return;
    }
    if a_in.x == b_in.x && a_in.y == b_in.y {
        return;
    }
    let swapped = abs(b_in.x - a_in.x) < abs(b_in.y - a_in.y);
    var a = a_in;
    var b = b_in;
    // The frame within the curve's reach, relative to the pixel's corner: columns x0..x1,
    // rows y0..y1.
    let r = pen.reach;
    var x0 = max(-pen.corner.x, -r);
    var x1 = min(i32(config.width) - pen.corner.x, r + 1);
    var y0 = max(-pen.corner.y, -r);
    var y1 = min(i32(config.height) - pen.corner.y, r + 1);
    if swapped {
        a = a_in.yx;
        b = b_in.yx;
        x0 = max(-pen.corner.y, -r);
        x1 = min(i32(config.height) - pen.corner.y, r + 1);
        y0 = max(-pen.corner.x, -r);
        y1 = min(i32(config.width) - pen.corner.x, r + 1);
    }
    let dx = b.x - a.x;
    let dy = b.y - a.y;
    let inverse = 1.0 / dx;
    let slope = dy * inverse;
    let stretch = sqrt(1.0 + slope * slope);
    let lo = min(a.x, b.x);
    let hi = max(a.x, b.x);
    var first = max(floor(lo), f32(x0));
    var last = min(ceil(hi) - 1.0, f32(x1 - 1));
    // Only the columns where the segment is within reach of the frame's rows (`Walk::major`).
    let ylo = f32(y0) - 0.5;
    let yhi = f32(y1) + 0.5;
    let inside = min(a.y, b.y) >= ylo && max(a.y, b.y) <= yhi;
    if !inside {
        if slope == 0.0 {
            return;
        }
        let run = dx / dy;
        let xa = a.x + (ylo - a.y) * run;
        let xb = a.x + (yhi - a.y) * run;
        first = max(first, floor(min(xa, xb)) - 1.0);
        last = min(last, ceil(max(xa, xb)) + 1.0);
    }
    if !(first <= last) {
        return;
    }
    let dz = z1 - z0;
    let dw = w1 - w0;
    for (var column = i32(first); column <= i32(last); column++) {
        let c = f32(column);
        // The segment's piece in the column (`Walk::column`).
        let left = max(lo, c);
        let right = min(hi, c + 1.0);
        let middle = 0.5 * (left + right);
        let along = middle - a.x;
        let u = along * inverse;
        let y = a.y + slope * along;
        let coverage = (right - left) * stretch;
        let v = y - 0.5;
        let rowf = floor(v);
        let f = v - rowf;
        let row = i32(rowf);
        let c0 = coverage * (1.0 - f);
        let c1 = coverage * f;
        let z = z0 + dz * u;
        let w = w0 + dw * u;
        for (var k = 0; k < 2; k++) {
            let r = row + k;
            if r < y0 || r >= y1 {
                continue;
            }
            var d = c0;
            if k == 1 {
                d = c1;
            }
            if swapped {
                deposit(pen, r + pen.corner.x, column + pen.corner.y, d * w, z);
            } else {
                deposit(pen, column + pen.corner.x, r + pen.corner.y, d * w, z);
            }
        }
    }
}

// Stage 2: one invocation per moving pixel builds its curve and draws it into the sums.
@compute @workgroup_size(WORKGROUP)
fn accumulate(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let k = flat(group, groups, lane);
    let count = min(atomicLoad(&state[COUNT]), pixels());
    if k >= count {
        return;
    }
    var item = k;
    if REVERSED {
        item = count - 1u - k;
    }
    // A moving pixel draws its own curve; a fringe entry its partner's (the motion relative
    // to the corner, so the same), from its own pixel, times its coverage.
    let entry = moving[2u * item];
    var i = entry;
    var own = entry;
    var cover = 1.0;
    if (entry & FRINGE) != 0u {
        let f = 3u * (entry & ~FRINGE);
        own = fringe[f];
        i = fringe[f + 1u];
        cover = bitcast<f32>(fringe[f + 2u]);
    }
    let segments = path(i, motion_of(i), cover);
    if segments == 0u {
        return;
    }
    let opaque = (atomicLoad(&state[FLAGS]) & OPAQUE) != 0u;
    let pen = Pen(
        own_color(i),
        two_to(weight_shift()),
        vec2<i32>(i32(own % config.width), i32(own / config.width)),
        i32(moving[2u * item + 1u]),
        opaque,
        1.0 + config.depth_tolerance,
    );
    carry_pen(i);
    for (var s = 0u; s < segments; s++) {
        draw(pen, points[s], points[s + 1u], weights[s], weights[s + 1u], depths[s], depths[s + 1u]);
    }
}

// ---- resolve -----------------------------------------------------------------------------

fn own_color(p: u32) -> vec4<f32> {
    let n = pixels();
    return vec4<f32>(color[p], color[n + p], color[2u * n + p], color[3u * n + p]);
}

// How a pixel's output is made from its sums, the same for every channel (`Resolution`):
// found once per pixel from the weight sum, then applied to the beauty's channels and to
// every carried one (`carry_resolve`), so light layers get exactly the beauty's weights.
const OWN: u32 = 0u;
const PAPER: u32 = 1u;
const REST: u32 = 2u;
const MEAN: u32 = 3u;

struct Resolution {
    // OWN (no curve deposited: the input), PAPER (eq. 4), REST (covered for `total` < 1 of
    // the exposure: the deposits and what lies behind for the rest) or MEAN (covered at
    // least once over: the deposits averaged).
    kind: u32,
    // The weight sum.
    total: f32,
    // REST: the share not covered, and what lies behind.
    rest: f32,
    behind: Behind,
}

// `Scatter::resolution`: how pixel p, whose deposits weigh `total`, is resolved.
fn resolution(p: u32, total: f32) -> Resolution {
    var r = Resolution(OWN, total, 0.0, Behind(array<u32, 8>(), 0u));
    if !(total > 0.0) {
        return r;
    }
    if config.exposure == 0u {
        r.kind = PAPER;
    } else if total < 1.0 {
        r.kind = REST;
        r.rest = 1.0 - total;
        if r.rest > COVERED {
            r.behind = behind(p);
        }
    } else {
        r.kind = MEAN;
    }
    return r;
}

// `Scatter::channel`: one channel of a pixel by `r`, from `sum`, its deposits in units of
// the channel's scale 2^e in the pixel's tile, `own`, its input, and `back`, what lies
// behind (REST only), in the scaled units (so no sum of huge colours overflows f32) and
// scaled back at the end.
fn resolved(r: Resolution, sum: f32, e: i32, own: f32, back: f32) -> f32 {
    switch r.kind {
        case PAPER: {
            // The paper's eq. 4 (w_b is at least 0), its two terms apart: the deposits'
            // share (|sum| is at most the weight sum, so it stays below 2^e), and the pixel's
            // own colour's, which is not one of the tile's curves (a still pixel), so 2^−e
            // need not bound it and it is not scaled at all.
            let wb = config.background_weight;
            let total = r.total + wb;
            return ldexp(sum / total, e) + own * (wb / total);
        }
        case REST: {
            return ldexp(sum, e) + r.rest * back;
        }
        case MEAN: {
            return ldexp(sum / r.total, e);
        }
        default: {
            return own;
        }
    }
}

// Stage 3: each pixel's output from its sums (`Scatter::resolve`), resolved once and
// applied to the beauty's channels, then to the carried layers' (`carry_resolve`).
@compute @workgroup_size(WORKGROUP)
fn resolve(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let p = flat(group, groups, lane);
    let n = pixels();
    if p >= n {
        return;
    }
    let own = own_color(p);
    // p's tile, whose units its sums count.
    let tile = tile_at(block_of(p));
    let r = resolution(p, decode(p, 4u, weight_shift()));
    var result = own;
    if r.kind != OWN {
        let opaque = (atomicLoad(&state[FLAGS]) & OPAQUE) != 0u;
        var back = own;
        if r.kind == REST {
            back = behind_color(r.behind, own);
        }
        for (var ch = 0u; ch < 4u; ch++) {
            if ch == 3u && opaque {
                // An opaque frame's alpha sums are its weight sums.
                result[ch] = resolved(r, r.total, 0, own[ch], back[ch]);
            } else {
                // R, G and B share a scale; alpha has its own.
                let c = select(0u, ALPHA, ch == 3u);
                let sum = decode(p, ch, shift_of(tile, c));
                result[ch] = resolved(r, sum, exponent_of(tile, c), own[ch], back[ch]);
            }
        }
    }
    out[p] = result.x;
    out[n + p] = result.y;
    out[2u * n + p] = result.z;
    out[3u * n + p] = result.w;
    carry_resolve(p, tile, r);
}
