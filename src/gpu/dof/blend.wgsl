// Depth of field's blend, the pyramid form: the twin of `blend` in src/dof/blend/pyramid/. Keep
// in sync with it: the same texels (colour offset by the reference and premultiplied by
// w = max(T, 1/64), w, T_near), the same [1 3 3 1]/8 halvings (across, then down, the same
// sums in the same order, indices clamped to the level), the same ladder and bracket, the
// same bilinear read of a level (down first, colour divided by w, then across) and the same
// mix, and the same discs below level 3's CoC. What the host decides is the CPU's own: E,
// the number of levels, the ladder's CoCs, whether and where T_near is read (`blend::Plan`).
//
// Three entry points, dispatched in order over the same bindings:
// - `first_level`: level 1 from the frame, one invocation per texel; its z slice 1 makes the
//   plain level 1 (every pixel weighing 1: `Source::plain`), which a near pixel's level disc
//   reads (dispatched where any pixel is in front of the focus plane, the plan's `near`; the
//   CPU makes it only if such a pixel reads level 1's disc: the same texels where read);
// - `halve`: level L from level L − 1, one invocation per texel; L rides in the dispatch's
//   z count (the host dispatches z = L − 1 groups deep and only the last slice works), since
//   a stage has one uniform for all its dispatches;
// - `compose`: one invocation per pixel.

// Keep in sync with `BlendConfig` in src/dof/blend/pyramid/mod.rs (a test holds the layouts).
struct BlendConfig {
    width: u32,
    height: u32,
    // Levels of the pyramid (1 ..= levels).
    levels: u32,
    has_alpha: u32,
    reference: vec4<f32>,
    epsilon: f32,
    // 1 / (E − ε).
    inverse_span: f32,
    // E.
    largest: f32,
    // 1 where T_near is read (some pixel is in front of the focus plane).
    near: u32,
    // The ladder's bracket of E: T_near is read at levels near_k and near_k + 1,
    // mixed by near_f.
    near_k: u32,
    near_f: f32,
    // Levels 2 and 3's CoCs, where the discs end (`disc_bounds`).
    disc_level_2: f32,
    disc_level_3: f32,
}

@group(0) @binding(0) var<uniform> config: BlendConfig;
// r, g, b, a planes one after the other (a zero without alpha).
@group(0) @binding(1) var<storage, read> color: array<f32>;
// The signed CoC plane (diameter, px).
@group(0) @binding(2) var<storage, read> coc: array<f32>;
// Per level L = 1 ..= levels: width, height, first texel, at 3 (L − 1); then the plain
// level 1's, at 3 levels.
@group(0) @binding(3) var<storage, read> geometry: array<u32>;
// The ladder: levels + 1 CoCs (the sharp frame's, 0, then each level's), then levels
// inverse gaps.
@group(0) @binding(4) var<storage, read> ladder: array<f32>;
// r, g, b, a planes one after the other.
@group(0) @binding(5) var<storage, read_write> out: array<f32>;
// Every level's texels, two vec4 each: (r, g, b, a) and (w, T_near, 0, 0).
@group(0) @binding(6) var<storage, read_write> texels: array<vec4<f32>>;

const IN_FOCUS_WEIGHT: f32 = 0.015625;
const MIN_POSITIVE: f32 = 1.17549435e-38;
// SPREAD_MARGIN in src/dof/blend/pyramid/compose.rs.
const SPREAD_MARGIN: f32 = 1e-3;
// FRAME_UNTIL, LEVEL_UNTIL and LEVEL_1_VARIANCE in src/dof/blend/pyramid/disc.rs.
const FRAME_UNTIL: f32 = 0.75;
const LEVEL_UNTIL: f32 = 0.9;
const LEVEL_1_VARIANCE: f32 = 0.75;

struct Texel {
    c: vec4<f32>,
    e: vec4<f32>,
}

fn interpolator(c: f32) -> f32 {
    return clamp((abs(c) - config.epsilon) * config.inverse_span, 0.0, 1.0);
}

fn plane(ch: u32, i: u32) -> f32 {
    return color[ch * config.width * config.height + i];
}

// Frame pixel (x, y) as a texel: colour offset and premultiplied, w, T_near; `plain`: as if
// every pixel were fully blurred (T = 1, w = 1: `Source::plain`).
fn frame_texel(x: u32, y: u32, plain: bool) -> Texel {
    let i = y * config.width + x;
    let c = coc[i];
    var t = interpolator(c);
    if plain {
        t = 1.0;
    }
    let w = max(t, IN_FOCUS_WEIGHT);
    var near = 0.0;
    if c < 0.0 {
        near = t;
    }
    var colour = vec4<f32>(plane(0u, i), plane(1u, i), plane(2u, i), 0.0);
    if config.has_alpha == 1u {
        colour.w = plane(3u, i);
    }
    var t0: Texel;
    t0.c = (colour - config.reference) * w;
    if config.has_alpha == 0u {
        t0.c.w = 0.0;
    }
    t0.e = vec4<f32>(w, near, 0.0, 0.0);
    return t0;
}

// [1 3 3 1]/8 over four texels, as `halve_row` sums them.
fn taps4(a: Texel, b: Texel, d: Texel, e: Texel) -> Texel {
    var o: Texel;
    o.c = 0.125 * (a.c + e.c) + 0.375 * (b.c + d.c);
    o.e = 0.125 * (a.e + e.e) + 0.375 * (b.e + d.e);
    return o;
}

fn clamped(i: i32, n: u32) -> u32 {
    return u32(clamp(i, 0, i32(n) - 1));
}

// Frame row y halved across at texel i.
fn first_across(i: u32, y: u32, plain: bool) -> Texel {
    let c = 2 * i32(i);
    let w = config.width;
    return taps4(
        frame_texel(clamped(c - 1, w), y, plain),
        frame_texel(clamped(c, w), y, plain),
        frame_texel(clamped(c + 1, w), y, plain),
        frame_texel(clamped(c + 2, w), y, plain),
    );
}

fn store(level_first: u32, index: u32, t: Texel) {
    texels[2u * (level_first + index)] = t.c;
    texels[2u * (level_first + index) + 1u] = t.e;
}

fn load(level_first: u32, index: u32) -> Texel {
    var t: Texel;
    t.c = texels[2u * (level_first + index)];
    t.e = texels[2u * (level_first + index) + 1u];
    return t;
}

// Level 1 (z 0), and the plain level 1 (z 1: every pixel by the filter alone, read by a
// near pixel's level disc; its geometry follows the levels').
@compute @workgroup_size(8, 8, 1)
fn first_level(@builtin(global_invocation_id) id: vec3<u32>) {
    let plain = id.z == 1u;
    let g = select(0u, 3u * config.levels, plain);
    let w2 = geometry[g];
    let h2 = geometry[g + 1u];
    if id.x >= w2 || id.y >= h2 {
        return;
    }
    let r = 2 * i32(id.y);
    let h = config.height;
    let t = taps4(
        first_across(id.x, clamped(r - 1, h), plain),
        first_across(id.x, clamped(r, h), plain),
        first_across(id.x, clamped(r + 1, h), plain),
        first_across(id.x, clamped(r + 2, h), plain),
    );
    store(geometry[g + 2u], id.y * w2 + id.x, t);
}

// Texel row y of level `above` halved across at texel i.
fn level_across(above: u32, i: u32, y: u32) -> Texel {
    let w = geometry[3u * (above - 1u)];
    let first = geometry[3u * (above - 1u) + 2u];
    let c = 2 * i32(i);
    let row = first + y * w;
    return taps4(
        load(row, clamped(c - 1, w)),
        load(row, clamped(c, w)),
        load(row, clamped(c + 1, w)),
        load(row, clamped(c + 2, w)),
    );
}

@compute @workgroup_size(8, 8, 1)
fn halve(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    // Level L = groups.z + 1, made by the last slice only.
    if group.z + 1u != groups.z {
        return;
    }
    let level = groups.z + 1u;
    let above = level - 1u;
    let g = 3u * (level - 1u);
    let w2 = geometry[g];
    let h2 = geometry[g + 1u];
    if id.x >= w2 || id.y >= h2 {
        return;
    }
    let h = geometry[3u * (above - 1u) + 1u];
    let r = 2 * i32(id.y);
    let t = taps4(
        level_across(above, id.x, clamped(r - 1, h)),
        level_across(above, id.x, clamped(r, h)),
        level_across(above, id.x, clamped(r + 1, h)),
        level_across(above, id.x, clamped(r + 2, h)),
    );
    store(geometry[g + 2u], id.y * w2 + id.x, t);
}

// ---------------------------------------------------------------------------------------
// compose

struct Tap {
    before: u32,
    after: u32,
    f: f32,
}

// Where pixel centre x of a frame axis lands in level L (`axis_taps`): the texel before it,
// the one after (clamped to the level's n texels) and the weight of the one after. The
// products are exact in f32 (a power of two), as the CPU's f64 ones rounded to f32.
fn axis_tap(x: u32, level: u32, n: u32) -> Tap {
    let p = ldexp(f32(x) + 0.5, -i32(level)) - 0.5;
    let before = floor(p);
    var t: Tap;
    t.f = p - before;
    t.before = clamped(i32(before), n);
    t.after = clamped(i32(before) + 1, n);
    return t;
}

fn mix_texel(a: Texel, b: Texel, f: f32) -> Texel {
    var o: Texel;
    o.c = a.c + f * (b.c - a.c);
    o.e = a.e + f * (b.e - a.e);
    return o;
}

// Level L at texel column c, mixed down between its rows by `down`, colour divided by w
// (`normalised_row`).
fn level_column(first: u32, w: u32, c: u32, down: Tap) -> Texel {
    var t = mix_texel(load(first, down.before * w + c), load(first, down.after * w + c), down.f);
    var weight = MIN_POSITIVE;
    if t.e.x > MIN_POSITIVE {
        weight = t.e.x;
    }
    t.c = t.c / weight;
    return t;
}

// Level L at frame pixel (x, y) (`Sampler::row`, then `Sampler::at`).
fn level_at(level: u32, x: u32, y: u32) -> Texel {
    let g = 3u * (level - 1u);
    let w = geometry[g];
    let h = geometry[g + 1u];
    let first = geometry[g + 2u];
    let across = axis_tap(x, level, w);
    let down = axis_tap(y, level, h);
    return mix_texel(
        level_column(first, w, across.before, down),
        level_column(first, w, across.after, down),
        across.f,
    );
}

// T_near of level L at frame pixel (x, y): mixed down, then across, not divided.
fn near_at(level: u32, x: u32, y: u32) -> f32 {
    let g = 3u * (level - 1u);
    let w = geometry[g];
    let h = geometry[g + 1u];
    let first = geometry[g + 2u];
    let across = axis_tap(x, level, w);
    let down = axis_tap(y, level, h);
    let a0 = texels[2u * (first + down.before * w + across.before) + 1u].y;
    let a1 = texels[2u * (first + down.after * w + across.before) + 1u].y;
    let b0 = texels[2u * (first + down.before * w + across.after) + 1u].y;
    let b1 = texels[2u * (first + down.after * w + across.after) + 1u].y;
    let a = a0 + down.f * (a1 - a0);
    let b = b0 + down.f * (b1 - b0);
    return a + across.f * (b - a);
}

fn sharp(i: u32) -> vec4<f32> {
    var s = vec4<f32>(plane(0u, i), plane(1u, i), plane(2u, i), 0.0);
    if config.has_alpha == 1u {
        s.w = plane(3u, i);
    }
    return s;
}

struct Bracket {
    k: u32,
    f: f32,
}

// Where c sits in the ladder (`Ladder::bracket`): k counts the CoCs of images
// 1 ..= levels − 1 that c reaches.
fn bracket(c: f32) -> Bracket {
    let count = config.levels + 1u;
    var k = 0u;
    for (var i = 1u; i + 1u < count; i++) {
        if c >= ladder[i] {
            k += 1u;
        }
    }
    var b: Bracket;
    b.k = k;
    b.f = clamp((c - ladder[k]) * ladder[count + k], 0.0, 1.0);
    return b;
}

// Image j of the ladder (level j, the sharp frame for 0) at pixel (x, y), offset by the
// reference.
fn image(j: u32, x: u32, y: u32) -> vec4<f32> {
    if j >= 1u {
        return level_at(j, x, y).c;
    }
    var s = sharp(y * config.width + x) - config.reference;
    if config.has_alpha == 0u {
        s.w = 0.0;
    }
    return s;
}

// A disc's texels of a row at dy² from its centre cx + fx (cx whole), as offsets from cx
// (`DiscRows`): those covered, [first, last], and those wholly inside (d ≤ reach − 1,
// weighing 1), [inner_first, inner_last], empty where inner_first > inner_last.
struct Span {
    first: i32,
    last: i32,
    inner_first: i32,
    inner_last: i32,
}

fn span(fx: f32, dy2: f32, reach: f32) -> Span {
    var s: Span;
    let across = sqrt(max(reach * reach - dy2, 0.0));
    s.first = i32(ceil(fx - across));
    s.last = i32(floor(fx + across));
    let inner = reach - 1.0;
    if inner > 0.0 && inner * inner > dy2 {
        let half = sqrt(inner * inner - dy2);
        s.inner_first = max(i32(ceil(fx - half)), s.first);
        s.inner_last = min(i32(floor(fx + half)), s.last);
    } else {
        s.inner_first = s.last + 1;
        s.inner_last = s.last;
    }
    return s;
}

// The sum of a grid's texels over a disc about (cx + fx, cy + fy) (`disc_sum`): rows top to
// bottom, each left to right, texels outside the grid left out; colour, then w. The grid is
// the frame (`level` 0: texels made from the colour and CoC as `frame_texels` makes them) or
// level 1. `plain` (the discs of a pixel in front of the focus plane): over the frame, each
// tap also weighed by its 1/w; over level 1, the plain level 1 (every tap alike either way).
struct DiscSum {
    c: vec4<f32>,
    w: f32,
}

fn disc_sum(level: u32, cx: i32, cy: i32, fx: f32, fy: f32, reach: f32, plain: bool) -> DiscSum {
    var n = vec2<i32>(i32(config.width), i32(config.height));
    // Level 1's geometry, or the plain level 1's (after the levels') where `plain`.
    let g = select(0u, 3u * config.levels, plain);
    if level == 1u {
        n = vec2<i32>(i32(geometry[g]), i32(geometry[g + 1u]));
    }
    var out: DiscSum;
    out.c = vec4<f32>(0.0);
    out.w = 0.0;
    let top = i32(ceil(fy - reach));
    let bottom = i32(floor(fy + reach));
    for (var dy = top; dy <= bottom; dy++) {
        let j = cy + dy;
        let d = f32(dy) - fy;
        let dy2 = d * d;
        let s = span(fx, dy2, reach);
        if j < 0 || j >= n.y || s.last < s.first {
            continue;
        }
        let first = max(cx + s.first, 0);
        let last = min(cx + s.last, n.x - 1);
        let inner_first = max(cx + s.inner_first, first);
        let inner_last = min(cx + s.inner_last, last);
        let inside = s.inner_first <= s.inner_last && inner_first <= inner_last;
        for (var i = first; i <= last; i++) {
            var k = 1.0;
            if !(inside && i >= inner_first && i <= inner_last) {
                let dx = f32(i - cx) - fx;
                k = clamp(reach - sqrt(dx * dx + dy2), 0.0, 1.0);
            }
            var c: vec4<f32>;
            var w: f32;
            if level == 0u {
                let index = u32(j) * config.width + u32(i);
                w = max(interpolator(coc[index]), IN_FOCUS_WEIGHT);
                var e = sharp(index) - config.reference;
                if config.has_alpha == 0u {
                    e.w = 0.0;
                }
                c = e * w;
                if plain {
                    k = k * (1.0 / w);
                }
            } else {
                let t = load(geometry[g + 2u], u32(j) * geometry[g] + u32(i));
                c = t.c;
                w = t.e.x;
            }
            out.c += k * c;
            out.w += k * w;
        }
    }
    return out;
}

// The disc of diameter c about pixel (x, y) over the frame, normalised (`frame_disc`, then
// `normalised`); every tap alike where the pixel is in front of the focus plane.
fn frame_disc(x: u32, y: u32, c: f32) -> vec4<f32> {
    let plain = coc[y * config.width + x] < 0.0;
    let s = disc_sum(0u, i32(x), i32(y), 0.0, 0.0, 0.5 * c + 0.5, plain);
    return s.c / max(s.w, MIN_POSITIVE);
}

// The disc of diameter c about pixel (x, y) over level 1, normalised (`level_disc`, then
// `normalised`); over the plain level 1 where the pixel is in front of the focus plane.
fn level_disc(x: u32, y: u32, c: f32) -> vec4<f32> {
    let plain = coc[y * config.width + x] < 0.0;
    let diameter = sqrt(max(c * c - 16.0 * LEVEL_1_VARIANCE, 0.0));
    let px = (f32(x) + 0.5) * 0.5 - 0.5;
    let py = (f32(y) + 0.5) * 0.5 - 0.5;
    let cx = floor(px);
    let cy = floor(py);
    let s = disc_sum(1u, i32(cx), i32(cy), px - cx, py - cy, 0.25 * diameter + 0.5, plain);
    return s.c / max(s.w, MIN_POSITIVE);
}

@compute @workgroup_size(8, 8, 1)
fn compose(@builtin(global_invocation_id) id: vec3<u32>) {
    let x = id.x;
    let y = id.y;
    if x >= config.width || y >= config.height {
        return;
    }
    let n = config.width * config.height;
    let i = y * config.width + x;
    let c = coc[i];
    var t = interpolator(c);
    if config.near == 1u {
        let k = config.near_k;
        var lower = 0.0;
        if k == 0u {
            if c < 0.0 {
                lower = t;
            }
        } else {
            lower = near_at(k, x, y);
        }
        let spread = lower + config.near_f * (near_at(k + 1u, x, y) - lower);
        if spread > t + SPREAD_MARGIN {
            t = -spread;
        }
    }
    if t == 0.0 {
        out[i] = color[i];
        out[n + i] = color[n + i];
        out[2u * n + i] = color[2u * n + i];
        out[3u * n + i] = color[3u * n + i];
        return;
    }
    let cc = config.epsilon + abs(t) * (config.largest - config.epsilon);
    // Below level 3's CoC a pixel's own blur is the lens's disc (`disc::kernel`); the near
    // field's spread mixes levels only.
    let level_2 = config.disc_level_2;
    let level_3 = config.disc_level_3;
    let frame_until = FRAME_UNTIL * level_2;
    let level_until = LEVEL_UNTIL * level_3;
    var blurred: vec4<f32>;
    if t > 0.0 && cc <= frame_until {
        blurred = frame_disc(x, y, cc);
    } else if t > 0.0 && cc <= level_2 {
        let a = frame_disc(x, y, cc);
        let f = (cc - frame_until) / (level_2 - frame_until);
        blurred = a + f * (level_disc(x, y, cc) - a);
    } else if t > 0.0 && cc <= level_until {
        blurred = level_disc(x, y, cc);
    } else {
        let b = bracket(cc);
        let lower = image(b.k, x, y);
        let upper = image(b.k + 1u, x, y);
        blurred = lower + b.f * (upper - lower);
        if t > 0.0 && cc < level_3 {
            let a = level_disc(x, y, cc);
            let f = (cc - level_until) / (level_3 - level_until);
            blurred = a + f * (blurred - a);
        }
    }
    let mixed = config.reference + blurred;
    out[i] = mixed.x;
    out[n + i] = mixed.y;
    out[2u * n + i] = mixed.z;
    out[3u * n + i] = mixed.w;
}
