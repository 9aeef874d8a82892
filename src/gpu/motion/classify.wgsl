// reconstruct's tile classification on the GPU: the twin of `classify` and `summary` in
// src/motion/reconstruct/classify.rs, the CPU reference (read the two side by side: the
// names and the order of the operations are the CPU's). Concatenated after reconstruct.wgsl
// (its bindings, `texel8`, `near_blur`, `tile_length`); run as two dispatches of one
// invocation a tile: `classify_tiles` (each tile's `Summary`), then `classify_kinds` (each
// tile's kind from the summaries within its reach), which `gather_2014` reads.
//
// The kinds are decisions, so they must be the CPU's exactly: every quantity compared is a
// max (exact), a difference of two floats (correctly rounded in WGSL), a product or a sum
// (correctly rounded), or a whole number of tiles found by exact products (`tiles_across`),
// never a quotient or a square root of the shader's own (|M| comes from the host, as the
// gather's). What can still move a kind: a driver that fuses the reach's product into its
// sum (`m·reach_factor + 2m`), which changes nothing centred (the factor is 1, the product
// exact) and can move a tile whose reach lies within an ulp of a whole tile under an offset
// exposure; that tile then takes the full gather where the CPU boxes it, or the reverse, both
// estimates of the same pixels.

// Per tile, row by row: the gather its pixels take (FULL, PLAIN or UNIFORM, the CPU's
// `TileKind`), written by `classify_kinds` or uploaded from the host.
@group(0) @binding(7) var<storage, read_write> kinds: array<u32>;
// Per tile, SUMMARY_WORDS words (the CPU's `Summary`): its longest |V|, or -1 where a pixel
// fails; its steepest step of V, or -1 where no tile within one of it blurs; then its
// `Hollow`: its body's longest |V| (-1 where a pixel is still and not empty), steepest step,
// and least and greatest V (x, y).
@group(0) @binding(8) var<storage, read_write> summaries: array<f32>;
const SUMMARY_WORDS: u32 = 8u;

// `TileKind`'s numbers and `UNIFORM_SPREAD` (a unit test in src/gpu/motion/classify.rs checks
// each against the Rust value).
const FULL: u32 = 0u;
const PLAIN: u32 = 1u;
const UNIFORM: u32 = 2u;
const HOLLOW: u32 = 3u;
const UNIFORM_SPREAD: f32 = 0.125;

// Whether pixel i of tile (c, r) takes the box: its tile uniform, or hollow and the pixel
// neither still nor paired (`fails`).
fn boxed(c: u32, r: u32, i: u32) -> bool {
    let kind = kinds[r * columns() + c];
    return kind == UNIFORM || (kind == HOLLOW && !fails(i));
}

// The CPU's `empty`: still, colour and alpha 0 (the texel's first four words).
fn empty(j: u32) -> bool {
    let o = 8u * j;
    let colour = vec4<f32>(texels[o], texels[o + 1u], texels[o + 2u], texels[o + 3u]);
    return texel8(j).length < HALF_PIXEL && all(colour == vec4<f32>(0.0));
}

// f32::MAX: the least and greatest V start from it (f32::MIN is its negation).
const F32_MAX: f32 = 3.40282347e38;

// Whether pixel j fails a plain tile: still, or paired by its matte (the mattes are bound
// only under the exposure variant; otherwise one word).
fn fails(j: u32) -> bool {
    if texel8(j).length < HALF_PIXEL {
        return true;
    }
    if arrayLength(&mattes) < MATTE_WORDS * config.width * config.height {
        return false;
    }
    let o = MATTE_WORDS * j;
    return !(bitcast<u32>(mattes[o + 1u]) == j && bitcast<u32>(mattes[o + 2u]) == j);
}

// The CPU's `summary`: tile t's pixels read once, up to the first that fails; where one
// fails, its bodies read again for its `Hollow`.
@compute @workgroup_size(64)
fn classify_tiles(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = id.x;
    if t >= columns() * rows() {
        return;
    }
    let steep = !near_blur(t % columns(), t / columns(), 1u);
    let o = SUMMARY_WORDS * t;
    var h = scan(t, false, steep);
    if h.read {
        summaries[o] = h.own;
        summaries[o + 1u] = select(h.step, -1.0, steep);
        // (A tile none of whose pixels fails blurs, so its `Hollow` is the same reading.)
        summaries[o + 2u] = select(h.own, -1.0, steep);
    } else {
        summaries[o] = -1.0;
        summaries[o + 1u] = -1.0;
        h = scan(t, true, false);
        summaries[o + 2u] = select(-1.0, h.own, h.read);
    }
    summaries[o + 3u] = h.step;
    summaries[o + 4u] = h.low.x;
    summaries[o + 5u] = h.low.y;
    summaries[o + 6u] = h.high.x;
    summaries[o + 7u] = h.high.y;
}

// What the CPU's `scan` finds: `read` false where it returns `None`.
struct Scanned {
    read: bool,
    own: f32,
    step: f32,
    low: vec2<f32>,
    high: vec2<f32>,
}

// The CPU's `scan`: tile t's every pixel, none failing (`bodies` false; no steps where
// `steep`), or its bodies alone (`bodies`: no still pixel that is not empty; steps between
// bodies only).
fn scan(t: u32, bodies: bool, steep: bool) -> Scanned {
    let c = t % columns();
    let r = t / columns();
    let width = config.width;
    let height = config.height;
    var h = Scanned(true, 0.0, 0.0, vec2<f32>(F32_MAX), vec2<f32>(-F32_MAX));
    let x_end = min((c + 1u) * config.tile, width);
    let y_end = min((r + 1u) * config.tile, height);
    for (var y = r * config.tile; y < y_end; y++) {
        for (var x = c * config.tile; x < x_end; x++) {
            let j = y * width + x;
            let texel = texel8(j);
            if bodies && texel.length < HALF_PIXEL && !empty(j) {
                h.read = false;
                return h;
            }
            if fails(j) {
                if bodies {
                    continue;
                }
                h.read = false;
                return h;
            }
            h.own = max(h.own, texel.length);
            h.low = min(h.low, vec2<f32>(texel.vx, texel.vy));
            h.high = max(h.high, vec2<f32>(texel.vx, texel.vy));
            if steep {
                continue;
            }
            if x + 1u < width && !(bodies && fails(j + 1u)) {
                let other = texel8(j + 1u);
                h.step = max(max(h.step, abs(other.vx - texel.vx)), abs(other.vy - texel.vy));
            }
            if y + 1u < height && !(bodies && fails(j + width)) {
                let other = texel8(j + width);
                h.step = max(max(h.step, abs(other.vx - texel.vx)), abs(other.vy - texel.vy));
            }
        }
    }
    return h;
}

// The CPU's `longest`: the longest |M| a tap of tile (c, r) can be taken along, its own
// (`own`) or a dilated tile's within one.
fn longest(c: u32, r: u32, own: f32) -> f32 {
    var m = own;
    for (var rr = select(r - 1u, 0u, r < 1u); rr < min(r + 2u, rows()); rr++) {
        for (var cc = select(c - 1u, 0u, c < 1u); cc < min(c + 2u, columns()); cc++) {
            m = max(m, tile_length(cc, rr));
        }
    }
    return m;
}

// The CPU's `tiles_across`: ⌈reach / tile⌉, the quotient's rounding corrected by exact
// products.
fn tiles_across(reach: f32) -> u32 {
    let size = f32(config.tile);
    var across = max(ceil(reach / size), 0.0);
    if across > 0.0 && (across - 1.0) * size >= reach {
        across -= 1.0;
    }
    if across * size < reach {
        across += 1.0;
    }
    return u32(across);
}

// The CPU's `classify`, tile t's kind: plain where no tile within its tap reach fails,
// uniform where, too, every step within its streaks' reach times that reach is at most
// UNIFORM_SPREAD.
@compute @workgroup_size(64)
fn classify_kinds(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = id.x;
    if t >= columns() * rows() {
        return;
    }
    kinds[t] = kind_of(t);
}

fn kind_of(t: u32) -> u32 {
    // Ours only (`Form::OURS`: the exposure variant).
    if config.variant != EXPOSURE {
        return FULL;
    }
    let own = summaries[SUMMARY_WORDS * t];
    if own < 0.0 {
        return hollow_kind(t);
    }
    let c = t % columns();
    let r = t / columns();
    let m = longest(c, r, own);
    let streak = m * (1.0 + 2.0 * abs(config.offset));
    let reach = streak + 2.0 * m + 2.0;
    if reach > f32(config.width + config.height) {
        return FULL;
    }
    let a = tiles_across(reach);
    for (var rr = select(r - a, 0u, r < a); rr < min(r + a + 1u, rows()); rr++) {
        for (var cc = select(c - a, 0u, c < a); cc < min(c + a + 1u, columns()); cc++) {
            if summaries[SUMMARY_WORDS * (rr * columns() + cc)] < 0.0 {
                return hollow_kind(t);
            }
        }
    }
    let near = streak + 2.0;
    let b = tiles_across(near);
    var step = 0.0;
    for (var rr = select(r - b, 0u, r < b); rr < min(r + b + 1u, rows()); rr++) {
        for (var cc = select(c - b, 0u, c < b); cc < min(c + b + 1u, columns()); cc++) {
            let s = summaries[SUMMARY_WORDS * (rr * columns() + cc) + 1u];
            if s < 0.0 {
                return PLAIN;
            }
            step = max(step, s);
        }
    }
    return select(PLAIN, UNIFORM, step * near <= UNIFORM_SPREAD);
}

// The CPU's `hollow_kind`: a tile with a failing tile in its plain reach is hollow where no
// tile within its uniform reach holds a still surface, and the steps and the range of its
// bodies' motions there are within UNIFORM_SPREAD of one smooth flow.
fn hollow_kind(t: u32) -> u32 {
    let own = summaries[SUMMARY_WORDS * t + 2u];
    if own < 0.0 {
        return FULL;
    }
    let c = t % columns();
    let r = t / columns();
    let m = longest(c, r, own);
    let reach = m * (1.0 + 2.0 * abs(config.offset)) + 2.0;
    if reach > f32(config.width + config.height) {
        return FULL;
    }
    let a = tiles_across(reach);
    var step = 0.0;
    var low = vec2<f32>(F32_MAX);
    var high = vec2<f32>(-F32_MAX);
    for (var rr = select(r - a, 0u, r < a); rr < min(r + a + 1u, rows()); rr++) {
        for (var cc = select(c - a, 0u, c < a); cc < min(c + a + 1u, columns()); cc++) {
            let o = SUMMARY_WORDS * (rr * columns() + cc);
            if summaries[o + 2u] < 0.0 {
                return FULL;
            }
            step = max(step, summaries[o + 3u]);
            low = min(low, vec2<f32>(summaries[o + 4u], summaries[o + 5u]));
            high = max(high, vec2<f32>(summaries[o + 6u], summaries[o + 7u]));
        }
    }
    let span = f32((2u * a + 1u) * config.tile);
    // (No body within reach: no range, and no sentinels subtracted, which would overflow.)
    var range = 0.0;
    if high.x >= low.x {
        range = max(high.x - low.x, high.y - low.y);
    }
    if step * reach <= UNIFORM_SPREAD && range * reach <= UNIFORM_SPREAD * span {
        return HOLLOW;
    }
    return FULL;
}
