// stretch on the GPU: the twin of src/motion/stretch/ (texture_blur → move_vertices →
// rasterise → cover), read side by side with it. src/gpu/motion/stretch.rs says how the stages are run and
// why rasterise is a render pipeline.
//
// Compute bindings (group 0), the CPU stages' arguments in order: config, planes (R, G, B, A
// one after the other), z, v (interleaved x, y: the CPU's [[f32; 2]]), then the outputs:
// blurred (four planes), vertices (shift x, shift y, alpha per pixel: the CPU's
// ([f32; 2], f32)), keys (one per triangle) and range (the frame's range per channel).
// Render bindings (group 0, read-only): config, planes, z, v, blurred, vertices, order.
// Cover bindings (group 0): config, planes, z, the three render targets (read), covered.

// Keep in sync with StretchConfig in src/motion/stretch/config.rs (twelve 4-byte words; a test
// in src/gpu/motion/stretch.rs compares the fields).
struct StretchConfig {
    width: u32,
    height: u32,
    shutter: f32,
    t0: f32,
    t1: f32,
    tear: f32,
    extent: f32,
    min_alpha: f32,
    depth_limit: f32,
    texture_blur: u32,
    // 0: what `mul` ORs into its products (`apart` in the prelude).
    zero: u32,
    _pad: u32,
}

// The CPU's constants (a test checks they match).
const STILL: f32 = 0.5;
const MOST_SAMPLES: u32 = 64u;
const MAX_SHIFT: f32 = 128.0;
// A triangle that is not drawn (the ordered form of a NaN no depth can be).
const NOT_DRAWN: u32 = 0u;
// Invocations per workgroup of the 1-D stages; rows of 65535 workgroups beyond that.
const GROUP: u32 = 256u;

// ---- compute stages -------------------------------------------------------------------------

@group(0) @binding(0) var<uniform> config: StretchConfig;
@group(0) @binding(1) var<storage, read> planes: array<f32>;
@group(0) @binding(2) var<storage, read> z: array<f32>;
@group(0) @binding(3) var<storage, read> v: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read_write> blurred: array<f32>;
@group(0) @binding(5) var<storage, read_write> vertices: array<f32>;
@group(0) @binding(6) var<storage, read_write> keys: array<u32>;
// Per channel c: [2c] the ordered max, [2c + 1] the complement of the ordered min; both taken
// with atomicMax on a cleared buffer (min and max commute: the result does not depend on the
// order the invocations run in).
@group(0) @binding(7) var<storage, read_write> range: array<atomic<u32>, 8>;

fn pixels() -> u32 {
    return config.width * config.height;
}


// `a · b` rounded by itself, as the CPU's is: never fused into the add it feeds (NVIDIA's
// driver fuses `x·x + y·y`, and a sample count or a vertex's move follows the sum's last bit).
fn mul(a: f32, b: f32) -> f32 {
    return apart(a, b, config.zero);
}

// |w|, rounded as the CPU's `(x * x + y * y).sqrt()`.
fn norm(w: vec2<f32>) -> f32 {
    return sqrt(mul(w.x, w.x) + mul(w.y, w.y));
}

fn moving(w: vec2<f32>) -> bool {
    return norm(w) * config.shutter >= STILL;
}

// The offset −v·t of a sample at time t from its pixel: the whole part (x, y) and the
// fraction (z, w), each taken of −v·t alone, so every pixel of one motion reads the same
// offsets with the same weights (the CPU's for_each_offset).
fn sample_offset(v: vec2<f32>, t: f32) -> vec4<f32> {
    let o = vec2<f32>(-mul(v.x, t), -mul(v.y, t));
    let whole = floor(o);
    return vec4<f32>(whole, o - whole);
}

// One of a sample's four bilinear taps.
struct Tap {
    j: u32,
    w: f32,
}

// Corner `corner` (dx its bit 0, dy its bit 1) of the sample `offset` (sample_offset's) from
// pixel (x, y): the pixel there and its bilinear weight; weight 0 where the weight is not
// above 0 or the pixel lies outside the frame (the CPU leaves those taps out).
fn corner_tap(offset: vec4<f32>, corner: u32, x: u32, y: u32) -> Tap {
    let dx = corner & 1u;
    let dy = corner >> 1u;
    let wx = select(1.0 - offset.z, offset.z, dx == 1u);
    let wy = select(1.0 - offset.w, offset.w, dy == 1u);
    let w = wx * wy;
    let sx = i32(x) + i32(offset.x) + i32(dx);
    let sy = i32(y) + i32(offset.y) + i32(dy);
    if !(w > 0.0 && sx >= 0 && sy >= 0 && sx < i32(config.width) && sy < i32(config.height)) {
        return Tap(0u, 0.0);
    }
    return Tap(u32(sy) * config.width + u32(sx), w);
}

// The flat index of a 1-D invocation dispatched as rows of workgroups.
fn flat(id: vec3<u32>, groups: vec3<u32>) -> u32 {
    return id.x + id.y * groups.x * GROUP;
}

var<workgroup> lows: array<array<f32, 4>, 256>;
var<workgroup> highs: array<array<f32, 4>, 256>;

// The frame's range per channel, the CPU's fold in texture_blur: a tree per workgroup, then
// one atomic per channel and end.
@compute @workgroup_size(256)
fn frame_range(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let i = flat(id, groups);
    let n = pixels();
    for (var c = 0u; c < 4u; c++) {
        if i < n {
            lows[local][c] = planes[c * n + i];
            highs[local][c] = planes[c * n + i];
        } else {
            lows[local][c] = infinity();
            highs[local][c] = -infinity();
        }
    }
    workgroupBarrier();
    for (var half = GROUP / 2u; half > 0u; half /= 2u) {
        if local < half {
            for (var c = 0u; c < 4u; c++) {
                lows[local][c] = min(lows[local][c], lows[local + half][c]);
                highs[local][c] = max(highs[local][c], highs[local + half][c]);
            }
        }
        workgroupBarrier();
    }
    if local == 0u {
        for (var c = 0u; c < 4u; c++) {
            atomicMax(&range[2u * c], ordered(highs[0][c]));
            atomicMax(&range[2u * c + 1u], ~ordered(lows[0][c]));
        }
    }
}

// Stage 1: each moving pixel's colour averaged along its own motion over the exposure
// (bilinear samples, leaving out nearer surfaces), clamped to the frame's range per channel;
// still pixels keep theirs.
@compute @workgroup_size(8, 8)
fn texture_blur(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = config.width;
    let height = config.height;
    if id.x >= width || id.y >= height {
        return;
    }
    let n = pixels();
    let x = id.x;
    let y = id.y;
    let i = y * width + x;
    var own: array<f32, 4>;
    for (var c = 0u; c < 4u; c++) {
        own[c] = planes[c * n + i];
        blurred[c * n + i] = own[c];
    }
    if !moving(v[i]) {
        return;
    }
    let t0 = config.t0;
    let t1 = config.t1;
    // Along the motion the mesh gives its fragments, cut as theirs is (the CPU's).
    let cut = swept_motion(v[i]);
    let vx = cut.x;
    let vy = cut.y;
    let length = norm(vec2<f32>(vx, vy)) * (t1 - t0);
    let samples = clamp(u32(min(ceil(length), 1.0e6)) + 1u, 2u, MOST_SAMPLES);
    var sum = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
    var total = 0.0;
    for (var k = 0u; k < samples; k++) {
        let t = t0 + (t1 - t0) * (f32(k) + 0.5) / f32(samples);
        // At time t the pixel shows what was at x − v·t at the frame (as the CPU reads).
        let offset = sample_offset(vec2<f32>(vx, vy), t);
        for (var corner = 0u; corner < 4u; corner++) {
            let tap = corner_tap(offset, corner, x, y);
            if tap.w == 0.0 {
                continue;
            }
            let j = tap.j;
            let w = tap.w;
            if z[j] * config.tear < z[i] {
                continue;
            }
            for (var c = 0u; c < 4u; c++) {
                sum[c] += w * (planes[c * n + j] - own[c]);
            }
            total += w;
        }
    }
    if total > 0.0 {
        for (var c = 0u; c < 4u; c++) {
            let lo = unordered(~atomicLoad(&range[2u * c + 1u]));
            let hi = unordered(atomicLoad(&range[2u * c]));
            blurred[c * n + i] = clamp(own[c] + sum[c] / total, lo, hi);
        }
    }
}

// Stage 2: per vertex (pixel centre), its move over the exposure and its alpha. A moving
// silhouette vertex (one with a farther neighbour beyond the tear ratio) moves to t0 where
// its motion faces away from the nearer surface's normal, to t1 where it faces along it;
// the others stay, opaque.
@compute @workgroup_size(256)
fn move_vertices(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let i = flat(id, groups);
    if i >= pixels() {
        return;
    }
    let width = i32(config.width);
    let height = i32(config.height);
    var shift = vec2<f32>(0.0, 0.0);
    var alpha = 1.0;
    let w = v[i];
    if moving(w) {
        let x = i32(i % config.width);
        let y = i32(i / config.width);
        var normal = vec2<f32>(0.0, 0.0);
        let steps = array<vec2<i32>, 4>(
            vec2<i32>(-1, 0),
            vec2<i32>(1, 0),
            vec2<i32>(0, -1),
            vec2<i32>(0, 1),
        );
        for (var k = 0u; k < 4u; k++) {
            let nx = x + steps[k].x;
            let ny = y + steps[k].y;
            if nx < 0 || ny < 0 || nx >= width || ny >= height {
                continue;
            }
            let j = u32(ny) * config.width + u32(nx);
            if z[j] > z[i] * config.tear {
                normal += vec2<f32>(steps[k]);
            }
        }
        let facing = w.x * normal.x + w.y * normal.y;
        var t = 0.0;
        if facing < 0.0 {
            t = config.t0;
        } else if facing > 0.0 {
            t = config.t1;
        }
        if t != 0.0 {
            shift = vec2<f32>(w.x * t, w.y * t);
            var length = norm(shift);
            if length > MAX_SHIFT {
                let cut = MAX_SHIFT / length;
                shift = vec2<f32>(shift.x * cut, shift.y * cut);
                length = MAX_SHIFT;
            }
            alpha = min(max(1.0 - length / config.extent, config.min_alpha), 1.0);
        }
    }
    vertices[3u * i] = shift.x;
    vertices[3u * i + 1u] = shift.y;
    vertices[3u * i + 2u] = alpha;
}

// The pixel indices of triangle t: quad (qx, qy) has corners 00, 10, 01, 11 (pixel centres);
// its first triangle is 00-10-11, its second 00-11-01 (triangle_corners on the CPU).
fn triangle_corners(t: u32) -> vec3<u32> {
    let across = config.width - 1u;
    let quad = t / 2u;
    let i = (quad / across) * config.width + quad % across;
    if t % 2u == 0u {
        return vec3<u32>(i, i + 1u, i + config.width + 1u);
    }
    return vec3<u32>(i, i + config.width + 1u, i + config.width);
}

// rasterise's choice of triangles: each untorn triangle with a moved vertex gets the ordered
// depth of its farthest vertex as its key (the host sorts the drawn ones farthest first,
// index as the tie-break, as the CPU does); the others NOT_DRAWN.
@compute @workgroup_size(256)
fn select_triangles(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let t = flat(id, groups);
    let count = 2u * (config.width - 1u) * (config.height - 1u);
    if config.width < 2u || config.height < 2u || t >= count {
        return;
    }
    let corners = triangle_corners(t);
    var moved = false;
    var lo = infinity();
    var hi = 0.0;
    for (var k = 0u; k < 3u; k++) {
        let c = corners[k];
        moved = moved || vertices[3u * c] != 0.0 || vertices[3u * c + 1u] != 0.0;
        lo = min(lo, z[c]);
        hi = max(hi, z[c]);
    }
    let torn = max(lo, hi) > min(lo, hi) * config.tear;
    keys[t] = select(NOT_DRAWN, ordered(hi), moved && !torn);
}

// ---- rasterise: a render pipeline ----------------------------------------------------------

// What the draws read: the compute stages' outputs, read-only, and the order of triangles.
@group(0) @binding(11) var<storage, read> moves: array<f32>;
@group(0) @binding(12) var<storage, read> sharp: array<f32>;
@group(0) @binding(13) var<storage, read> order: array<u32>;

struct Corner {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) triangle: u32,
}

// What a fragment writes: R, G, B with the blend alpha into the first target, the alpha plane
// with the blend alpha into the second; both blend as `src·α + dst·(1 − α)` (the CPU's `mix`).
struct Drawn {
    @location(0) color: vec4<f32>,
    @location(1) alpha: vec4<f32>,
}

// A pixel position (pixels, y down) in clip space.
fn clip(p: vec2<f32>) -> vec4<f32> {
    return vec4<f32>(p.x / f32(config.width) * 2.0 - 1.0, 1.0 - p.y / f32(config.height) * 2.0, 0.0, 1.0);
}

// The pixel under a fragment.
fn pixel(position: vec4<f32>) -> u32 {
    return u32(position.y) * config.width + u32(position.x);
}

// The sharp frame first (texture_blur's output, or the colour itself), one triangle over the
// whole target, no blending.
@vertex
fn sharp_vertex(@builtin(vertex_index) k: u32) -> @builtin(position) vec4<f32> {
    let corner = vec2<f32>(f32((k & 1u) * 2u), f32((k >> 1u) * 2u));
    return clip(corner * vec2<f32>(f32(config.width), f32(config.height)));
}

@fragment
fn sharp_fragment(@builtin(position) position: vec4<f32>) -> Drawn {
    let i = pixel(position);
    let n = pixels();
    var c: array<f32, 4>;
    for (var k = 0u; k < 4u; k++) {
        c[k] = select(planes[k * n + i], sharp[k * n + i], config.texture_blur != 0u);
    }
    return Drawn(vec4<f32>(c[0], c[1], c[2], 0.0), vec4<f32>(c[3], 0.0, 0.0, 0.0));
}

// Stage 3: the triangles of `order`, in that order (the API blends in primitive order). Each
// is drawn as its bounding box (two triangles, six vertices) grown to whole pixels and one
// more, so the box holds every pixel centre the triangle can own with half a pixel to
// spare; the fragment shader then decides coverage by the CPU's own rule. The
// fixed-function rasteriser's sub-pixel snapping and tie rule never decide a pixel: the two
// halves of a box share a diagonal, and exactly one of them takes a centre on it.
@vertex
fn draw_vertex(@builtin(vertex_index) index: u32) -> Corner {
    let t = order[index / 6u];
    let corners = triangle_corners(t);
    var lo = vec2<f32>(infinity(), infinity());
    var hi = -lo;
    for (var k = 0u; k < 3u; k++) {
        let i = corners[k];
        let p = vec2<f32>(
            f32(i % config.width) + 0.5 + moves[3u * i],
            f32(i / config.width) + 0.5 + moves[3u * i + 1u],
        );
        lo = min(lo, p);
        hi = max(hi, p);
    }
    lo = floor(lo) - 1.0;
    hi = ceil(hi) + 1.0;
    let box = array<u32, 6>(0u, 1u, 2u, 2u, 1u, 3u);
    let b = box[index % 6u];
    var out: Corner;
    out.position = clip(vec2<f32>(select(lo.x, hi.x, (b & 1u) != 0u), select(lo.y, hi.y, (b & 2u) != 0u)));
    out.triangle = t;
    return out;
}

// `values[0] + w1·(values[1] − values[0]) + w2·(values[2] − values[0])`, kept within the
// three values (the CPU's interpolate).
fn interpolate(values: vec3<f32>, w1: f32, w2: f32) -> f32 {
    let v = values.x + w1 * (values.y - values.x) + w2 * (values.z - values.x);
    return clamp(v, min(values.x, min(values.y, values.z)), max(values.x, max(values.y, values.z)));
}

// Twice the signed area of (a, b, p) for p at the origin (the CPU rasteriser's `edge`, whose
// p is the pixel centre the corners here are relative to): a × b. Written about p, not about
// a as the CPU's, so that a centre at a corner (a or b the origin) gives exactly 0 however
// the products round: about a, the centre at b gives a.x·a.y − a.y·a.x, 0 when both products
// round alike and an ulp of either sign when a driver fuses one of them into the subtraction,
// and a centre the CPU puts exactly on the edge (where its two products are one product,
// rounded once) would fall inside or outside by the rounding (the stretch tests failed so
// on an NVIDIA GPU).
fn edge(a: vec2<f32>, b: vec2<f32>) -> f32 {
    return mul(a.x, b.y) - mul(a.y, b.x);
}

// Whether a centre exactly on edge a → b of a triangle of positive `edge` orientation
// belongs to it (the CPU rasteriser's `top_left`).
fn top_left(a: vec2<f32>, b: vec2<f32>) -> bool {
    let d = b - a;
    return (d.y == 0.0 && d.x < 0.0) || d.y > 0.0;
}

// What of `shift` survives the CPU's f64 sum `pos + shift` (pos = a pixel centre's
// coordinate, ≥ ½): f64 rounds the sum to its ulp at pos, 2^(e − 52) for pos in [2^e, 2^(e+1)),
// so a shift below pos·2^−29 is rounded to a multiple of that ulp here (exactly: dividing and
// multiplying by a power of two, and WGSL's round is half-to-even as f64's sum), and a larger
// one is kept (f32's 24 bits are exact in f64). Velocities of 1e−30 px next to 1e7 px (the
// stress frames) make such shifts; the CPU draws them as if unmoved.
fn absorbed(shift: f32, pos: f32) -> f32 {
    let e = i32((bitcast<u32>(pos) >> 23u) & 0xffu) - 127;
    let ulp = bitcast<f32>(u32(e - 52 + 127) << 23u);
    if abs(shift) < ulp * 8388608.0 {
        return round(shift / ulp) * ulp;
    }
    return shift;
}

// Corner i of a triangle, relative to the centre of pixel (x, y): the integer offset of the
// two centres, exact, plus the corner's shift as the CPU's position holds it. Small numbers,
// so the edge functions below keep nearly all of f32's precision where the CPU computes
// absolute positions in f64.
fn corner(i: u32, x: u32, y: u32) -> vec2<f32> {
    let cx = i % config.width;
    let cy = i / config.width;
    let sx = absorbed(moves[3u * i], f32(cx) + 0.5);
    let sy = absorbed(moves[3u * i + 1u], f32(cy) + 0.5);
    return vec2<f32>(f32(i32(cx) - i32(x)) + sx, f32(i32(cy) - i32(y)) + sy);
}

// A fragment the CPU draws: its pixel, barycentric weights and interpolated depth.
struct Fragment {
    i: u32,
    corners: vec3<u32>,
    w1: f32,
    w2: f32,
    depth: f32,
}

// Each fragment of the box is tested by the CPU's rule (edge functions at the pixel centre,
// ties to the CPU's top-left edges), which also gives the barycentric weights as the CPU
// computes them; then it is depth-tested against the frame (`z ≤ depth · (1 + tolerance)`).
// Whether the CPU draws it, and the fragment in `fragment`.
fn drawn(in: Corner, fragment: ptr<function, Fragment>) -> bool {
    let i = pixel(in.position);
    let x = i % config.width;
    let y = i / config.width;
    let corners = triangle_corners(in.triangle);
    var points = array<vec2<f32>, 3>(corner(corners.x, x, y), corner(corners.y, x, y), corner(corners.z, x, y));
    // Positive orientation, as the CPU swaps corners 1 and 2 (the weights follow).
    var swapped = false;
    if edge(points[1] - points[0], points[2] - points[0]) < 0.0 {
        let t = points[1];
        points[1] = points[2];
        points[2] = t;
        swapped = true;
    }
    let e = vec3<f32>(edge(points[1], points[2]), edge(points[2], points[0]), edge(points[0], points[1]));
    // The area as the sum of the three: at a corner two of them are exactly 0 and the third
    // is the area, so its weight is exactly 1 (as the CPU's f64 weights are), and the depth
    // interpolated there is the corner's own, bit for bit (the depth test with no tolerance).
    let area = e.x + e.y + e.z;
    let bias = vec3<bool>(top_left(points[1], points[2]), top_left(points[2], points[0]), top_left(points[0], points[1]));
    let inside = (e > vec3<f32>(0.0)) | ((e == vec3<f32>(0.0)) & bias);
    if !all(inside) || !(area > 0.0) {
        return false;
    }
    var w1 = e.y / area;
    var w2 = e.z / area;
    if swapped {
        let t = w1;
        w1 = w2;
        w2 = t;
    }
    let depth = interpolate(vec3<f32>(z[corners.x], z[corners.y], z[corners.z]), w1, w2);
    if depth > z[i] * config.depth_limit {
        return false;
    }
    *fragment = Fragment(i, corners, w1, w2, depth);
    return true;
}

// Whether pixel i is wholly covered (alpha 1 or more): fragments blend there; elsewhere they
// leave their motion and depth to cover (the CPU's test in rasterise).
fn wholly_covered(i: u32) -> bool {
    return planes[3u * pixels() + i] >= 1.0;
}

// Whether, with the pre-blur, a fragment lies over its own surface (a depth within the tear
// of its own), which the pre-blur has averaged along its motion already: not drawn (the CPU's
// test in rasterise).
fn own_surface(f: Fragment) -> bool {
    let a = z[f.i];
    let b = f.depth;
    return config.texture_blur != 0u && !(max(a, b) > min(a, b) * config.tear);
}

// A drawn fragment over a wholly covered pixel, not of its own surface: its colour and alpha interpolated from the
// corners' input colour and alpha.
@fragment
fn draw_fragment(in: Corner) -> Drawn {
    var f: Fragment;
    if !drawn(in, &f) || !wholly_covered(f.i) || own_surface(f) {
        discard;
    }
    let n = pixels();
    let corners = f.corners;
    let alpha = interpolate(
        vec3<f32>(moves[3u * corners.x + 2u], moves[3u * corners.y + 2u], moves[3u * corners.z + 2u]),
        f.w1,
        f.w2,
    );
    var c: array<f32, 4>;
    for (var k = 0u; k < 4u; k++) {
        c[k] = interpolate(
            vec3<f32>(planes[k * n + corners.x], planes[k * n + corners.y], planes[k * n + corners.z]),
            f.w1,
            f.w2,
        );
    }
    return Drawn(vec4<f32>(c[0], c[1], c[2], alpha), vec4<f32>(c[3], 0.0, 0.0, alpha));
}

// The motion a vertex gives the fragments that sweep a pixel: its velocity, cut so that it
// moves at most MAX_SHIFT px over the longer part of the exposure (the CPU's swept_motion).
fn swept_motion(w: vec2<f32>) -> vec2<f32> {
    let reach = norm(w) * max(abs(config.t0), abs(config.t1));
    if reach > MAX_SHIFT {
        let cut = MAX_SHIFT / reach;
        return vec2<f32>(w.x * cut, w.y * cut);
    }
    return w;
}

// A drawn fragment over a pixel not wholly covered: what shows behind the smear there is
// (partly) nothing, and cover gives the pixel the smear's coverage, along the nearest
// fragment's motion. Into `swept` (velocity x, y, depth, 1), unblended: the triangles are
// drawn in the same order a second time, into that target alone, and the last fragment of a
// pixel, the nearest, is what stays (WebGPU's least limit on a pass's target bytes per
// sample, 32, holds the two drawn targets and not a third).
@fragment
fn sweep_fragment(in: Corner) -> @location(0) vec4<f32> {
    var f: Fragment;
    if !drawn(in, &f) || wholly_covered(f.i) {
        discard;
    }
    let a = swept_motion(v[f.corners.x]);
    let b = swept_motion(v[f.corners.y]);
    let c = swept_motion(v[f.corners.z]);
    let motion = vec2<f32>(
        interpolate(vec3<f32>(a.x, b.x, c.x), f.w1, f.w2),
        interpolate(vec3<f32>(a.y, b.y, c.y), f.w1, f.w2),
    );
    return vec4<f32>(motion, f.depth, 1.0);
}

// ---- cover: a compute stage over the drawn targets ------------------------------------------

@group(0) @binding(20) var drawn_color: texture_2d<f32>;
@group(0) @binding(21) var drawn_alpha: texture_2d<f32>;
@group(0) @binding(22) var swept: texture_2d<f32>;
// The result: R, G, B, A one after the other (the CPU's `out` after cover).
@group(0) @binding(23) var<storage, read_write> covered: array<f32>;

fn swept_at(x: i32, y: i32) -> vec4<f32> {
    return textureLoad(swept, vec2<i32>(x, y), 0);
}

// The sweep pixel (x, y) takes (the CPU's sweep_at, in its order): its own where a fragment
// came; else of its eight neighbours' sweeps, the nearest in depth that passes the pixel's
// depth test; else of its eight neighbours that move, the nearest so, with its own motion (cut
// as a fragment's) and depth; else of the sweeps two away, the nearest so; each time the first
// of equals in the order of RINGS. w = 0 where none.
fn sweep_at(x: i32, y: i32, i: u32) -> vec4<f32> {
    let own = swept_at(x, y);
    if own.w != 0.0 {
        return own;
    }
    let swept_near = nearest_sweep(x, y, i, 0, 8, false);
    if swept_near.w != 0.0 {
        return swept_near;
    }
    let moving_near = nearest_sweep(x, y, i, 0, 8, true);
    if moving_near.w != 0.0 {
        return moving_near;
    }
    return nearest_sweep(x, y, i, 8, 24, false);
}

// The offsets sweep_at looks at: the eight neighbours (the four beside, then the four
// diagonal), then the sixteen two away (the four straight out, the eight beside them, the
// four corners), each group in reading order (the CPU's NEIGHBOURS and SECOND_RING).
const RINGS = array<vec2<i32>, 24>(
    vec2(0, -1), vec2(-1, 0), vec2(1, 0), vec2(0, 1),
    vec2(-1, -1), vec2(1, -1), vec2(-1, 1), vec2(1, 1),
    vec2(0, -2), vec2(-2, 0), vec2(2, 0), vec2(0, 2),
    vec2(-1, -2), vec2(1, -2), vec2(-2, -1), vec2(2, -1), vec2(-2, 1), vec2(2, 1), vec2(-1, 2), vec2(1, 2),
    vec2(-2, -2), vec2(2, -2), vec2(-2, 2), vec2(2, 2),
);

// Of the pixels at RINGS[first..last) from (x, y) in the frame, the nearest in depth whose
// depth passes pixel i's test, the first of equals: of their sweeps, or where `motion` of
// those that move, their own motion and depth as a sweep.
fn nearest_sweep(x: i32, y: i32, i: u32, first: i32, last: i32, motion: bool) -> vec4<f32> {
    var rings = RINGS;
    var best = vec4<f32>(0.0);
    for (var k = first; k < last; k++) {
        let nx = x + rings[k].x;
        let ny = y + rings[k].y;
        if nx < 0 || ny < 0 || nx >= i32(config.width) || ny >= i32(config.height) {
            continue;
        }
        var sweep = vec4<f32>(0.0);
        if motion {
            let j = u32(ny) * config.width + u32(nx);
            if moving(v[j]) {
                sweep = vec4<f32>(swept_motion(v[j]), z[j], 1.0);
            }
        } else {
            sweep = swept_at(nx, ny);
        }
        if sweep.w != 0.0 && sweep.z <= z[i] * config.depth_limit && (best.w == 0.0 || sweep.z < best.z) {
            best = sweep;
        }
    }
    return best;
}

// Stage 4: each pixel the frame does not wholly cover that a smear swept takes the average of
// the sharp frame along the sweep's motion over the exposure, over the samples not nearer than
// the sweep's depth (texture_blur's samples), clamped to the least and greatest tap; every
// other pixel what was drawn.
@compute @workgroup_size(8, 8)
fn cover(@builtin(global_invocation_id) id: vec3<u32>) {
    let width = config.width;
    let height = config.height;
    if id.x >= width || id.y >= height {
        return;
    }
    let n = pixels();
    let x = id.x;
    let y = id.y;
    let i = y * width + x;
    let color = textureLoad(drawn_color, vec2<i32>(i32(x), i32(y)), 0);
    var out = array<f32, 4>(color.x, color.y, color.z, textureLoad(drawn_alpha, vec2<i32>(i32(x), i32(y)), 0).x);
    let sweep = sweep_at(i32(x), i32(y), i);
    if !wholly_covered(i) && sweep.w != 0.0 {
        let t0 = config.t0;
        let t1 = config.t1;
        let vx = sweep.x;
        let vy = sweep.y;
        let length = norm(vec2<f32>(vx, vy)) * (t1 - t0);
        let samples = clamp(u32(min(ceil(length), 1.0e6)) + 1u, 2u, MOST_SAMPLES);
        var own: array<f32, 4>;
        var sum = array<f32, 4>(0.0, 0.0, 0.0, 0.0);
        var lo: array<f32, 4>;
        var hi: array<f32, 4>;
        for (var c = 0u; c < 4u; c++) {
            own[c] = planes[c * n + i];
            lo[c] = infinity();
            hi[c] = -infinity();
        }
        var total = 0.0;
        for (var k = 0u; k < samples; k++) {
            let t = t0 + (t1 - t0) * (f32(k) + 0.5) / f32(samples);
            let offset = sample_offset(vec2<f32>(vx, vy), t);
            for (var corner = 0u; corner < 4u; corner++) {
                let tap = corner_tap(offset, corner, x, y);
                if tap.w == 0.0 {
                    continue;
                }
                let j = tap.j;
                let w = tap.w;
                if z[j] * config.tear < sweep.z {
                    continue;
                }
                for (var c = 0u; c < 4u; c++) {
                    let value = planes[c * n + j];
                    sum[c] += w * (value - own[c]);
                    lo[c] = min(lo[c], value);
                    hi[c] = max(hi[c], value);
                }
                total += w;
            }
        }
        if total > 0.0 {
            for (var c = 0u; c < 4u; c++) {
                out[c] = clamp(own[c] + sum[c] / total, lo[c], hi[c]);
            }
        }
    }
    for (var c = 0u; c < 4u; c++) {
        covered[c * n + i] = out[c];
    }
}
