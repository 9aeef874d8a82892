// reconstruct's `gather` stage on the GPU: the twin of `gather` / `gather_pixel` (paper and
// dual) and `gather_2014` / `gather_pixel_2014` with `around`, `bilinear` and `split` (2014
// and exposure) in src/motion/reconstruct/, the CPU reference. Read the two side by side:
// the names, the order of the operations and the order of the sums are the CPU's. One
// invocation per pixel; a pixel outside the tiles the CPU gathers is left as it came.
//
// In (built on the CPU: tile_max → neighbor_max or dilate → pack): the packed texels, the
// pixel velocity (paper and dual only), the tile grid (NeighborMax, or the dilated tiles of
// the 2014 filter). In and out: the premultiplied colour, written in place.
//
// Bindings, in the CPU functions' argument order: 0 the config, 1 texels, 2 velocity, 3
// tiles, 4 colour, 5 the exposure variant's mattes (`gather_2014`'s third argument;
// MATTE_WORDS a pixel, src/motion/reconstruct/matte.rs; one unread word otherwise), and 6
// the colours the 2014 gather carries beside the beauty (`gather_2014_carrying`'s; one
// unread word otherwise); 7 and 8, the tiles' kinds and the classification's summaries, are
// declared in classify.wgsl, concatenated after this file and reconstruct_taps.wgsl. Planar
// buffers hold their planes one after the other, as the CPU's structs do: velocity x then
// y, tiles x then y (then each tile's |M|, made on the host), colour r, g, b, a (of each
// colour in turn when the gather carries several).
//
// The 2014 gather's tap reading (`around`, `bilinear`, `split`, `split_by_cover`,
// `surfaces`) is in reconstruct_taps.wgsl, concatenated after this file.
//
// Numerics: the inputs obey the numeric policy (finite colour and velocity, packed depth at
// most 1e30), so everything but one quantity stays finite. That one is the paper texel's
// 1/|V|, +∞ for a still pixel, on which the CPU relies (∞·d is ∞, and its cone and cylinder
// are 0). WGSL lets an implementation assume that no infinity occurs, so the shader does not
// compute with it: `scaled` recognises a huge 1/|V| by its bits and gives a distance past
// every filter's support, which is what the CPU's arithmetic gives.

// Keep in sync with `ReconstructConfig` in src/motion/reconstruct/ (a size test guards
// the layout: eleven 4-byte fields).
struct ReconstructConfig {
    // Frame size, pixels.
    width: u32,
    height: u32,
    // The tile size, pixels.
    tile: u32,
    // k as the largest half-spread, pixels.
    k: f32,
    // Fraction of the frame interval the shutter is open.
    shutter: f32,
    // Where the exposure sits about the frame, in exposures: 0 centred, +0.5 opening at the
    // frame, -0.5 closing at it (a streak is its centred one moved by 2·offset·V).
    offset: f32,
    // S: taps per pixel, odd.
    taps: u32,
    // 1 / SOFT_Z_EXTENT, per scene unit.
    inv_soft_z: f32,
    // 1 to jitter the taps per pixel, else 0.
    jitter: u32,
    // 0 paper, 1 dual, 2 the 2014 filter, 3 exposure.
    variant: u32,
    // The jitter's seed: the frame number modulo 2³².
    seed: u32,
}

@group(0) @binding(0) var<uniform> config: ReconstructConfig;
// paper and dual: 6 floats per pixel (`Texel`); 2014 and exposure: 8 (`Texel2014`).
@group(0) @binding(1) var<storage, read> texels: array<f32>;
@group(0) @binding(2) var<storage, read> velocity: array<f32>;
@group(0) @binding(3) var<storage, read> tiles: array<f32>;
@group(0) @binding(4) var<storage, read_write> color: array<f32>;
// Per pixel (MATTE_WORDS apart): α, then the indices (as the bits of a float) of the pixels
// whose colours are its moving and still partners, then its unmixing's extrapolation in R, G,
// B and A (`Matte`).
@group(0) @binding(5) var<storage, read> mattes: array<f32>;
// The 2014 gather's colours when it carries several (COLOURS ≥ 1), packed as the CPU packs
// them (zero off the packed tiles): colour g of pixel j at g·width·height + j. One unread
// word otherwise.
@group(0) @binding(6) var<storage, read> carried: array<vec4<f32>>;

// The CPU's constants (src/motion/reconstruct/); a unit test in src/gpu/motion/reconstruct.rs
// checks each against the Rust value.
const HALF_PIXEL: f32 = 0.5;
const EPSILON: f32 = 0.01;
// (HALF_PIXEL + EPSILON)², as the CPU rounds it, by its bits.
const MOVING_SQUARED_BITS: u32 = 0x3e852bd3u;
const MAX_TAPS_PER_SIDE: u32 = 64u;
const TAP_SPACING: f32 = 2.0;
const COVER_SLOPE: f32 = 1.25;
const MATTE_WORDS: u32 = 7u;
const SALT_TILE: u32 = 0x54494c45u;
const SALT_TAPS: u32 = 0x54415053u;
const SALT_PAPER: u32 = 0x5245434fu;
const PAPER: u32 = 0u;
const DUAL: u32 = 1u;
const EXPOSURE: u32 = 3u;

// The hash of every jitter: `pcg` and `hash` and `unit` in src/numeric.rs, bit for bit (u32
// arithmetic wraps in WGSL as `wrapping_*` does in Rust).
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn hash(seed: u32, stream: u32, index: u32) -> u32 {
    return pcg(index ^ pcg(stream ^ pcg(seed)));
}

// A uniform number in [0, 1): the hash's top 24 bits, exact in f32.
fn unit(seed: u32, stream: u32, index: u32) -> f32 {
    return f32(hash(seed, stream, index) >> 8u) * (1.0 / 16777216.0);
}

fn columns() -> u32 {
    return (config.width + config.tile - 1u) / config.tile;
}

fn rows() -> u32 {
    return (config.height + config.tile - 1u) / config.tile;
}

// The vector of tile (c, r).
fn tile_at(c: u32, r: u32) -> vec2<f32> {
    let n = columns() * rows();
    let i = r * columns() + c;
    return vec2<f32>(tiles[i], tiles[n + i]);
}

// |M| of tile (c, r), made on the host as the CPU's gather makes it (the shader's own would
// differ in its last bits, and the 2014 gather's decisions read it).
fn tile_length(c: u32, r: u32) -> f32 {
    let n = columns() * rows();
    return tiles[2u * n + r * columns() + c];
}

// Whether a tile blurs: |V|² above (0.5 px + ε)².
fn blurs(c: u32, r: u32) -> bool {
    let v = tile_at(c, r);
    return v.x * v.x + v.y * v.y > bitcast<f32>(MOVING_SQUARED_BITS);
}

// Whether any tile within `radius` tiles of (c, r) blurs.
fn near_blur(c: u32, r: u32, radius: u32) -> bool {
    let r_end = min(r + radius + 1u, rows());
    let c_end = min(c + radius + 1u, columns());
    for (var rr = select(r - radius, 0u, r < radius); rr < r_end; rr++) {
        for (var cc = select(c - radius, 0u, c < radius); cc < c_end; cc++) {
            if blurs(cc, rr) {
                return true;
            }
        }
    }
    return false;
}

fn write_color(i: u32, out: vec4<f32>) {
    let n = config.width * config.height;
    color[i] = out.x;
    color[n + i] = out.y;
    color[2u * n + i] = out.z;
    color[3u * n + i] = out.w;
}

// ---- paper and dual ----

// `Texel`: premultiplied RGBA, depth, 1/|V| (+∞ where still).
struct Texel {
    color: vec4<f32>,
    z: f32,
    inv_length: f32,
}

fn texel6(i: u32) -> Texel {
    let o = 6u * i;
    return Texel(
        vec4<f32>(texels[o], texels[o + 1u], texels[o + 2u], texels[o + 3u]),
        texels[o + 4u],
        texels[o + 5u],
    );
}

// A 1/|V| of 1e30 or more (+∞ included, recognised by its bits): any distance it scales
// lies past the support of `cone` and `cylinder` (taps are at least a quarter step from the
// centre, so the CPU's product is ≥ 1e29 or ∞).
fn huge(inv_length: f32) -> bool {
    return (bitcast<u32>(inv_length) & MAGNITUDE) >= bitcast<u32>(1e30f);
}

// distance / |V|: the CPU's `distance * inv_length`, without computing with ∞.
fn scaled(distance: f32, inv_length: f32) -> f32 {
    if huge(inv_length) {
        return 2.0;
    }
    return distance * inv_length;
}

fn half_spread(vx: f32, vy: f32) -> vec2<f32> {
    let qx = 0.5 * vx * config.shutter;
    let qy = 0.5 * vy * config.shutter;
    let length = sqrt(qx * qx + qy * qy);
    if length == 0.0 {
        return vec2<f32>(0.0, 0.0);
    }
    let scale = max(HALF_PIXEL, min(length, config.k)) / (length + EPSILON);
    return vec2<f32>(qx * scale, qy * scale);
}

fn cone(scaled_distance: f32) -> f32 {
    return clamp(1.0 - scaled_distance, 0.0, 1.0);
}

fn cylinder(scaled_distance: f32) -> f32 {
    let t = clamp((scaled_distance - 0.95) * 10.0, 0.0, 1.0);
    return 1.0 - t * t * (3.0 - 2.0 * t);
}

fn soft_depth_compare(za: f32, zb: f32, inverse_extent: f32) -> f32 {
    return clamp(1.0 - (zb - za) * inverse_extent, 0.0, 1.0);
}

fn gather_pixel(x: u32, y: u32, v: vec2<f32>, n: vec2<f32>) -> vec4<f32> {
    let width = config.width;
    let height = config.height;
    let taps = config.taps;
    let centre_tap = (taps - 1u) / 2u;
    let inv_soft_z = config.inv_soft_z;
    let i = y * width + x;
    let centre = texel6(i);
    let n_length = sqrt(n.x * n.x + n.y * n.y);
    let own = half_spread(v.x, v.y);
    let own_length = sqrt(own.x * own.x + own.y * own.y);
    var j = 0.0;
    if config.jitter != 0u {
        j = unit(config.seed, SALT_PAPER, i) - 0.5;
    }
    var weight = 1.0 / HALF_PIXEL;
    if !huge(centre.inv_length) {
        weight = min(centre.inv_length, 1.0 / HALF_PIXEL);
    }
    var sum = vec4<f32>(0.0);
    let step = 2.0 / (f32(config.taps) + 1.0);
    let dual = config.variant == DUAL && own_length > HALF_PIXEL + EPSILON;
    // The offset exposure (see the CPU twin): the taps' line moved by −2·offset half-spreads,
    // and a tap's distance divided by its reach towards X, (1 − 2·offset) ahead and
    // (1 + 2·offset) behind (for its cones and X's alike).
    let shift = 2.0 * config.offset;
    let ahead = 1.0 / max(1.0 - shift, 1e-6);
    let behind = 1.0 / max(1.0 + shift, 1e-6);
    for (var index = 0u; index < taps; index++) {
        if index == centre_tap {
            continue;
        }
        let t = -1.0 + (f32(index) + j + 1.0) * step - shift;
        let tap_reach = select(behind, ahead, t > 0.0);
        var d = n;
        var len = n_length;
        if dual && index % 2u == 1u {
            d = own;
            len = own_length;
        }
        let px = u32(max(f32(x) + 0.5 + d.x * t, 0.0));
        let py = u32(max(f32(y) + 0.5 + d.y * t, 0.0));
        let sample = texel6(min(py, height - 1u) * width + min(px, width - 1u));
        let distance = max(abs(t) * len, 1e-6) * tap_reach;
        let z = sample.z;
        let front = soft_depth_compare(centre.z, z, inv_soft_z);
        let back = soft_depth_compare(z, centre.z, inv_soft_z);
        let ds = scaled(distance, sample.inv_length);
        let dc = scaled(distance, centre.inv_length);
        let alpha = front * cone(ds) + back * cone(dc) + cylinder(ds) * cylinder(dc) * 2.0;
        weight += alpha;
        sum += alpha * (sample.color - centre.color);
    }
    let inverse = 1.0 / weight;
    return centre.color + sum * inverse;
}

// Paper and dual: pixels of the tiles whose NeighborMax blurs.
@compute @workgroup_size(8, 8)
fn gather(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= config.width || id.y >= config.height {
        return;
    }
    let c = id.x / config.tile;
    let r = id.y / config.tile;
    if !blurs(c, r) {
        return;
    }
    let n = config.width * config.height;
    let i = id.y * config.width + id.x;
    let v = vec2<f32>(velocity[i], velocity[n + i]);
    write_color(i, gather_pixel(id.x, id.y, v, tile_at(c, r)));
}

// ---- 2014 and exposure ----

// MOST_COLOURS, the most colours one pipeline of the 2014 gather mixes along the same taps,
// is declared by the module's last line: 1 in the beauty's module, so its colours are plain
// values (with arrays of eight, lavapipe's beauty gather took 7 % longer), 8 in the carrying
// module (the CPU's eight a pass).

// The colours the 2014 gather mixes along its taps and where it reads them, set per pipeline
// so that each count has its own specialised copy (as each count has on the CPU): 0, the
// beauty alone, read from the texels (the CPU's `gather_2014`); n from 1 to MOST_COLOURS, n
// colours read from `carried` (`gather_2014_carrying`: the beauty, then light layers with its
// alpha). Every weight reads only the texels' depth and motion and the mattes (fitted on the
// beauty), never the colours mixed, so each colour comes out as it does alone in the beauty's
// place.
override COLOURS: u32 = 0u;

// The depth and motion of a `Texel2014` (its words 4 to 7): depth, the half-spread V and |V|.
// Its colour words are read by `colour`.
struct Texel2014 {
    z: f32,
    vx: f32,
    vy: f32,
    length: f32,
}

fn texel8(i: u32) -> Texel2014 {
    let o = 8u * i;
    return Texel2014(texels[o + 4u], texels[o + 5u], texels[o + 6u], texels[o + 7u]);
}

// How many colours this pipeline mixes.
fn colours() -> u32 {
    return max(COLOURS, 1u);
}

// Colour g of pixel j, premultiplied RGBA (the CPU's `colour(j)[g]`).
fn colour(g: u32, j: u32) -> vec4<f32> {
    if COLOURS == 0u {
        let o = 8u * j;
        return vec4<f32>(texels[o], texels[o + 1u], texels[o + 2u], texels[o + 3u]);
    }
    return carried[g * config.width * config.height + j];
}

// The CPU's `Colours<G>`: an RGBA per colour, the first `colours()` of them used.
struct Colours {
    c: array<vec4<f32>, MOST_COLOURS>,
}

fn colours_of(j: u32) -> Colours {
    var out: Colours;
    for (var g = 0u; g < colours(); g++) {
        out.c[g] = colour(g, j);
    }
    return out;
}

// Pixel i of each colour's r, g, b, a planes (the colours' planes one after the other).
fn write_colours(i: u32, out: Colours) {
    let n = config.width * config.height;
    for (var g = 0u; g < colours(); g++) {
        let o = 4u * g * n + i;
        color[o] = out.c[g].x;
        color[o + n] = out.c[g].y;
        color[o + 2u * n] = out.c[g].z;
        color[o + 3u * n] = out.c[g].w;
    }
}

// A tap surface's foreground (x) and background (y) weights; `share`: the tap's reach
// towards the centre in spreads (1 centred); `window`: the centre's own spread times its
// side's share of the line (the CPU's `own_length * extent`).
fn weights(
    texel: Texel2014,
    distance: f32,
    direction: f32,
    share: f32,
    centre_z: f32,
    window: f32,
    scale: f32,
    edge: f32,
    still_reach: f32,
) -> vec2<f32> {
    let dz = texel.z - centre_z;
    let behind = clamp(0.5 + scale * dz, 0.0, 1.0);
    let front = clamp(0.5 - scale * dz, 0.0, 1.0);
    var reach = 1.0;
    if texel.length < HALF_PIXEL {
        reach = still_reach;
    }
    return vec2<f32>(
        direction * front * clamp(texel.length * share - distance + reach, 0.0, 1.0),
        direction * behind * clamp(window - distance + edge, 0.0, 1.0),
    );
}

// The numbers that tell the 2014 filter's two forms apart (Blender's and ours, the exposure
// variant), computed once from the config: the twin of `Form::of`
// (src/motion/reconstruct/config.rs), whose fields say what each does and why.
struct Form {
    own_tile: bool,
    tap_spacing: f32,
    edge: f32,
    still_reach: f32,
    centre_count: f32,
    still_second_set: bool,
    half_step: bool,
    split_taps: bool,
    either_way: bool,
    exposure_fill: bool,
    slide_hidden: bool,
}

fn form() -> Form {
    let ours = config.variant == EXPOSURE;
    return Form(
        ours || config.offset != 0.0,
        select(0.0, TAP_SPACING, ours),
        select(1.0, 0.5, ours),
        select(1.0, 0.5, ours),
        select(1.0, 0.0, ours),
        ours,
        ours,
        ours,
        ours,
        ours,
        ours,
    );
}

// The pixel nearest to the point `offset` from pixel (x, y), clamped to the frame (the CPU's
// `nearest_to`).
fn nearest_to(x: u32, y: u32, offset: vec2<f32>) -> u32 {
    let px = u32(max(f32(x) + 0.5 + offset.x, 0.0));
    let py = u32(max(f32(y) + 0.5 + offset.y, 0.0));
    return min(py, config.height - 1u) * config.width + min(px, config.width - 1u);
}

// Whether the point `offset` from pixel (x, y) lies in the frame (the CPU's `inside`).
fn inside(x: u32, y: u32, offset: vec2<f32>) -> bool {
    let px = f32(x) + 0.5 + offset.x;
    let py = f32(y) + 0.5 + offset.y;
    return px >= 0.0 && py >= 0.0 && px < f32(config.width) && py < f32(config.height);
}

// Whether texel j is still and nearer than depth z by the soft extent's half.
fn nearer_still(j: u32, z: f32) -> bool {
    let t = texel8(j);
    return t.length < HALF_PIXEL && 0.5 + config.inv_soft_z * (t.z - z) <= 0.0;
}

// Whether pixel (x, y) lies beside (a 4-neighbour of) a still surface nearer than it: the
// rim of a still subject (the CPU's `beside_nearer`).
fn beside_nearer(x: u32, y: u32) -> bool {
    let width = config.width;
    let i = y * width + x;
    let z = texel8(i).z;
    return (x > 0u && nearer_still(i - 1u, z))
        || (x + 1u < width && nearer_still(i + 1u, z))
        || (y > 0u && nearer_still(i - width, z))
        || (y + 1u < config.height && nearer_still(i + width, z));
}

fn gather_pixel_2014(x: u32, y: u32) -> Colours {
    let f = form();
    let width = config.width;
    let height = config.height;
    let size = f32(config.tile);
    let i = y * width + x;
    let centre = texel8(i);
    var tile_shift = 0.0;
    var offset = 0.5;
    if config.jitter != 0u {
        tile_shift = (unit(config.seed, SALT_TILE, i) * 2.0 - 1.0) * 0.25 * size;
        offset = unit(config.seed, SALT_TAPS, i);
    }
    let column = min(u32(max(f32(x) + tile_shift, 0.0)) / config.tile, columns() - 1u);
    let row = min(u32(max(f32(y) + tile_shift, 0.0)) / config.tile, rows() - 1u);
    var m = tile_at(column, row);
    var m_length = tile_length(column, row);
    // Where the jittered lookup lands on a still tile, the pixel's own tile instead: always
    // in the exposure variant, under an offset exposure in the 2014 one (`Form::own_tile`).
    if f.own_tile && m_length < HALF_PIXEL {
        let c = min(x / config.tile, columns() - 1u);
        let r = min(y / config.tile, rows() - 1u);
        m = tile_at(c, r);
        m_length = tile_length(c, r);
    }
    let own = vec2<f32>(centre.vx, centre.vy);
    let own_length = centre.length;
    if m_length < own_length {
        m = own;
        m_length = own_length;
    }
    if m_length < HALF_PIXEL {
        return colours_of(i);
    }
    var k = max((config.taps + 3u) / 4u, 1u);
    if f.tap_spacing > 0.0 {
        k = max(k, min(u32(ceil(m_length / f.tap_spacing)), MAX_TAPS_PER_SIDE));
    }
    let scale = config.inv_soft_z;
    // The offset exposure (see the CPU twin): each side covers its share of the line,
    // (1 − 2·offset) ahead and (1 + 2·offset) behind, at k taps per spread.
    let shift = 2.0 * config.offset;
    let edge = f.edge;
    var fg: Colours;
    var bg: Colours;
    var w_fg = 0.0;
    var w_bg = 0.0;
    var count = f.centre_count;
    // A still centre: the 2014 form gathers along the tile's vector alone; exposure takes its
    // second set along the tile's vector too, half a step off (see the CPU twin).
    var directions = 2u;
    if own_length < HALF_PIXEL && !f.still_second_set {
        directions = 1u;
    }
    let centre_z = centre.z;
    // A streak that runs behind a nearer surface is slid back a streak's length where it is
    // hidden (`Form::slide_hidden`; the CPU twin says why and where not).
    let slides = f.slide_hidden && own_length >= HALF_PIXEL && !beside_nearer(x, y);
    // The coverage a tap reads is steepened where the centre's own point lies off the moving
    // surface: a still centre, or a moving one covered less than half (see the CPU twin).
    var steepen = own_length < HALF_PIXEL;
    if f.split_taps && !steepen {
        steepen = mattes[MATTE_WORDS * i] < 0.5;
    }
    for (var s = 0u; s < 2u; s++) {
        let side = select(1.0, -1.0, s == 1u);
        for (var d = 0u; d < directions; d++) {
            var dv = m;
            var length = m_length;
            if d == 1u && own_length >= HALF_PIXEL {
                dv = own;
                length = own_length;
            }
            let sx = side * dv.x;
            let sy = side * dv.y;
            var tap_offset = offset;
            if f.half_step && d == 1u {
                tap_offset = fract(offset + 0.5);
            }
            let extent = 1.0 - shift * side;
            let k_side = u32(ceil(f32(k) * extent));
            let step = extent / f32(k_side);
            for (var tap = 0u; tap < k_side; tap++) {
                let t = (f32(tap) + tap_offset) * step;
                var at = vec2<f32>(sx * t, sy * t);
                var nearest_index = nearest_to(x, y, at);
                if slides && length * t < own_length * extent + edge {
                    let near = texel8(nearest_index);
                    let dz = near.z - centre_z;
                    let away = select(-side, side, dv.x * near.vx + dv.y * near.vy > 0.0);
                    let share = 1.0 - shift * away;
                    var reach = 1.0;
                    if near.length < HALF_PIXEL {
                        reach = f.still_reach;
                    }
                    let reaches = near.length * share - length * t + reach > 0.0;
                    if 0.5 + scale * dz <= 0.0 && !reaches && inside(x, y, at) {
                        let back = 2.0 * own_length / length;
                        let slid = vec2<f32>(at.x - sx * back, at.y - sy * back);
                        let j = nearest_to(x, y, slid);
                        let tj = texel8(j);
                        if inside(x, y, slid) && tj.length >= HALF_PIXEL
                            && abs((tj.z - centre_z) * scale) < 1.0 {
                            at = slid;
                            nearest_index = j;
                        }
                    }
                }
                var parts: Split;
                if f.split_taps {
                    let cover = split_by_cover(nearest_index, scale, x, y, at, steepen);
                    if cover.valid {
                        parts = cover.parts;
                    } else {
                        parts = split(nearest_index, scale, x, y, at);
                    }
                } else {
                    let nearest = texel8(nearest_index);
                    parts.a.texel = nearest;
                    if nearest.length >= HALF_PIXEL {
                        parts.a.colour = bilinear(nearest_index, scale, x, y, at);
                    } else {
                        parts.a.colour = colours_of(nearest_index);
                    }
                    parts.a.share = 1.0;
                }
                let sample = parts.a.texel;
                let other = parts.b.texel;
                let distance = length * t;
                let along = dv.x * sample.vx + dv.y * sample.vy > 0.0;
                let counts = f.either_way || sample.length < HALF_PIXEL || along;
                let direction = select(0.0, 1.0, counts);
                // Moving along the line on this side, a tap moves away from the centre.
                let away0 = select(-side, side, along);
                let away1 = select(-side, side, dv.x * other.vx + dv.y * other.vy > 0.0);
                let window = own_length * extent;
                let w0 = weights(sample, distance, direction, 1.0 - shift * away0, centre_z, window, scale, edge, f.still_reach);
                let w1 = weights(other, distance, direction, 1.0 - shift * away1, centre_z, window, scale, edge, f.still_reach);
                count += direction;
                for (var g = 0u; g < colours(); g++) {
                    fg.c[g] += w0.x * parts.a.colour.c[g] + w1.x * parts.b.colour.c[g];
                    bg.c[g] += w0.y * parts.a.colour.c[g] + w1.y * parts.b.colour.c[g];
                }
                w_fg += w0.x * parts.a.share + w1.x * parts.b.share;
                w_bg += w0.y * parts.a.share + w1.y * parts.b.share;
            }
        }
    }
    var out: Colours;
    if f.exposure_fill {
        // 0.5/|V| is at least 1 for |V| ≤ half a pixel (0 included): no division there.
        var cover = 1.0;
        if own_length > HALF_PIXEL {
            cover = min(0.5 / own_length, 1.0);
        }
        var missing = 1.0;
        var inverse = 0.0;
        if count > 0.0 {
            missing = clamp(1.0 - (w_fg + w_bg) / count, 0.0, 1.0);
            inverse = 1.0 / count;
        }
        for (var g = 0u; g < colours(); g++) {
            // A still centre's own surface: its colour less the moving surface's fringe.
            var own_colour = colour(g, i);
            if own_length < HALF_PIXEL {
                own_colour = surfaces(g, i).still;
            }
            var background = own_colour;
            if w_bg > 0.0 {
                background = cover * own_colour + (1.0 - cover) * bg.c[g] / w_bg;
            }
            out.c[g] = (fg.c[g] + bg.c[g]) * inverse + background * missing;
        }
        return out;
    }
    // Blender's own addition: a little of the centre in the background.
    let w = 1.0 / (50.0 * f32(4u * k));
    let w_bg_all = w_bg + w;
    let missing = clamp(1.0 - (w_fg + w_bg_all) / count, 0.0, 1.0);
    for (var g = 0u; g < colours(); g++) {
        let centre_colour = colour(g, i);
        let background = (bg.c[g] + w * centre_colour) / w_bg_all;
        out.c[g] = (fg.c[g] + bg.c[g] + w * centre_colour) / count + background * missing;
    }
    return out;
}

// The CPU's `shortened` (src/motion/reconstruct/uniform.rs): the factor the box shortens a
// half-spread of `length` by, to sqrt(|V|² − 1/4), at least |V|/2.
fn shortened(length: f32) -> f32 {
    return sqrt(max(length * length - 0.25, 0.25 * length * length)) / length;
}

// The four pixels around (x, y) + offset with their bilinear weights, the point clamped into
// the frame first (the CPU's `corners` in uniform.rs; `around` clamps the pixels instead).
fn box_corners(x: u32, y: u32, offset: vec2<f32>) -> Around {
    let width = config.width;
    let height = config.height;
    let fx = clamp(f32(x) + offset.x, 0.0, f32(width - 1u));
    let fy = clamp(f32(y) + offset.y, 0.0, f32(height - 1u));
    let x0 = u32(fx);
    let y0 = u32(fy);
    let wx = fx - f32(x0);
    let wy = fy - f32(y0);
    let x1 = min(x0 + 1u, width - 1u);
    let y1 = min(y0 + 1u, height - 1u);
    return Around(
        array<u32, 4>(y0 * width + x0, y0 * width + x1, y1 * width + x0, y1 * width + x1),
        array<f32, 4>((1.0 - wx) * (1.0 - wy), wx * (1.0 - wy), (1.0 - wx) * wy, wx * wy),
    );
}

// Adds to `sum` the colours read bilinearly at (x, y) + offset, the four corners added in
// pairs (the CPU's `add_tap`, which leaves out the corners of weight 0 on a row's or a
// column's line: the same sums).
fn add_tap(sum: ptr<function, Colours>, x: u32, y: u32, offset: vec2<f32>) {
    let a = box_corners(x, y, offset);
    for (var g = 0u; g < colours(); g++) {
        (*sum).c[g] += (a.weight[0] * colour(g, a.index[0]) + a.weight[1] * colour(g, a.index[1]))
            + (a.weight[2] * colour(g, a.index[2]) + a.weight[3] * colour(g, a.index[3]));
    }
}

// The uniform tiles' box (the CPU's `box_pixel`): n = 4k taps at the midpoints of n equal
// parts of the line along the pixel's own V (shortened, centred 2·offset·V back), read
// bilinearly, the even and odd taps summed apart, then together over n.
fn box_pixel(x: u32, y: u32) -> Colours {
    let centre = texel8(y * config.width + x);
    let length = centre.length;
    let k = max(max((config.taps + 3u) / 4u, 1u), min(u32(ceil(length / TAP_SPACING)), MAX_TAPS_PER_SIDE));
    let n = 4u * k;
    let step = 2.0 / f32(n);
    let v = vec2<f32>(centre.vx, centre.vy) * shortened(length);
    // An offset exposure's line is centred 2·offset·V back along the motion.
    let middle = vec2<f32>(centre.vx, centre.vy) * (-2.0 * config.offset);
    var even: Colours;
    var odd: Colours;
    for (var pair = 0u; pair < n / 2u; pair++) {
        let u0 = (f32(2u * pair) + 0.5) * step - 1.0;
        add_tap(&even, x, y, middle + v * u0);
        let u1 = (f32(2u * pair + 1u) + 0.5) * step - 1.0;
        add_tap(&odd, x, y, middle + v * u1);
    }
    let count = f32(n);
    for (var g = 0u; g < colours(); g++) {
        even.c[g] = (even.c[g] + odd.c[g]) / count;
    }
    return even;
}

// 2014 and exposure: pixels of the tiles within one tile of a blurring (dilated) tile, the
// uniform ones (`kinds`, classify.wgsl) and the hollow ones' bodies by the box (`boxed`). Its pipelines set COLOURS: 0 for `gather_2014`, the count for
// `gather_2014_carrying`.
@compute @workgroup_size(8, 8)
fn gather_2014(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= config.width || id.y >= config.height {
        return;
    }
    let c = id.x / config.tile;
    let r = id.y / config.tile;
    if !near_blur(c, r, 1u) {
        return;
    }
    let i = id.y * config.width + id.x;
    if boxed(c, r, i) {
        write_colours(i, box_pixel(id.x, id.y));
        return;
    }
    write_colours(i, gather_pixel_2014(id.x, id.y));
}
