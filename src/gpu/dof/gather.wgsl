// Depth of field's bokeh gather: the twin of `gather` (src/dof/gather/mod.rs), one workgroup per
// 16×16 tile, one invocation per pixel. Keep in sync with `gather_run` there: the same taps
// in the same order, the same weights, the same sums (offset by the centre) and the same
// composite. The tile plan (which fields, which taps) is the CPU's own (`dof::gather::plan`).

// Keep in sync with `GatherConfig` in src/dof/gather/mod.rs (a test holds the layouts together).
struct GatherConfig {
    width: u32,
    height: u32,
    // Tiles per row.
    columns: u32,
    // 1 where the frame has alpha.
    has_alpha: u32,
    // gather::LAYER.
    layer: f32,
    // The colours in `color` and `out` (`gather_carrying`): the beauty's, light layers'.
    colours: u32,
    // The largest bokeh radius (px) that gathers its far field over a tile's dense grid.
    small: f32,
    // The prefilter levels in `sides`.
    levels: u32,
}

// Keep in sync with `OffsetTap` in src/dof/gather/mod.rs.
struct Tap {
    dx: i32,
    dy: i32,
    norm_far: f32,
    norm_near: f32,
    area: f32,
}

// Keep in sync with `TileTaps` in src/dof/gather/mod.rs: fields 0 copy, 1 far, 2 both, 3 apart;
// where the far taps are rings, the dense grid (count 0 elsewhere).
struct Tile {
    fields: u32,
    taps_start: u32,
    taps_count: u32,
    far_start: u32,
    far_count: u32,
    dense_start: u32,
    dense_count: u32,
    // The prefilter level the taps read and the one the far taps read (0: the planes
    // themselves; k: level k - 1, in `level_planes`).
    level: u32,
    far_level: u32,
}

// The far taps of a pixel of radius rp in `tile` (start, count, level): the dense grid where
// the tile's far taps are rings and the pixel's own bokeh fits the grid (the CPU's lanes that
// take it: a tap beyond the bokeh weighs 0, so the CPU's smaller grid sums the same), else
// the tile's far taps (its main taps when both fields share them) and their level.
fn far_list(tile: Tile, rp: f32) -> vec3<u32> {
    if (tile.dense_count > 0u && rp <= config.small) {
        return vec3<u32>(tile.dense_start, tile.dense_count, 0u);
    }
    if (tile.fields == 2u) {
        return vec3<u32>(tile.taps_start, tile.taps_count, tile.far_level);
    }
    return vec3<u32>(tile.far_start, tile.far_count, tile.far_level);
}

@group(0) @binding(0) var<uniform> config: GatherConfig;
// r, g, b, a planes one after the other (a zero without alpha); `gather_carrying`: those of
// each colour in turn.
@group(0) @binding(1) var<storage, read> color: array<f32>;
// The signed CoC plane (diameter, px), then 1 / bokeh area per pixel (the CPU's
// `inverse_area`: WGSL's division is not correctly rounded).
@group(0) @binding(2) var<storage, read> coc: array<f32>;
@group(0) @binding(3) var<storage, read> taps: array<Tap>;
@group(0) @binding(4) var<storage, read> tiles: array<Tile>;
// The prefilter levels' box sides (px).
@group(0) @binding(5) var<storage, read> sides: array<u32>;
// r, g, b, a planes one after the other (of each colour in turn).
@group(0) @binding(6) var<storage, read_write> out: array<f32>;
// The prefilter levels (`prefilter`), level after level: the box's mean 1 / bokeh area, then
// each colour's r, g, b, a box averages weighted by 1 / bokeh area.
@group(0) @binding(7) var<storage, read_write> level_planes: array<f32>;

const TILE: u32 = 16u;

// Index i of a row or column of n pixels reflected into it about its edges, the edge pixel
// repeated (`mirror` in gather/mod.rs): where a tap outside the frame reads, with weight 0.

// Whether the tap at offset (dx, dy) from pixel (x, y) lies inside the frame: outside it, its
// 1 / bokeh area is 0 (the CPU's padding), so it weighs nothing in either field.
fn inside(x: u32, y: u32, dx: i32, dy: i32) -> bool {
    let sx = i32(x) + dx;
    let sy = i32(y) + dy;
    return sx >= 0 && sx < i32(config.width) && sy >= 0 && sy < i32(config.height);
}
fn mirror(i: i32, n: u32) -> u32 {
    let period = 2 * i32(n);
    var m = i % period;
    if (m < 0) {
        m += period;
    }
    if (m >= i32(n)) {
        return u32(period - 1 - m);
    }
    return u32(m);
}

struct Sample {
    d: vec4<f32>,
    c: f32,
    ia: f32,
}

// Where level `level` (1-based) starts in `level_planes`.
fn level_base(level: u32, n: u32) -> u32 {
    return (level - 1u) * (1u + 4u * config.colours) * n;
}

// Colour g's RGBA at pixel i of level `level` (0: the colour itself).
fn level_colour(level: u32, g: u32, i: u32, n: u32) -> vec4<f32> {
    if (level == 0u) {
        let base = 4u * g * n;
        return vec4<f32>(color[base + i], color[base + n + i], color[base + 2u * n + i], color[base + 3u * n + i]);
    }
    let base = level_base(level, n) + (1u + 4u * g) * n;
    return vec4<f32>(level_planes[base + i], level_planes[base + n + i], level_planes[base + 2u * n + i], level_planes[base + 3u * n + i]);
}

// 1 / bokeh area at pixel i of level `level` (0: the pixel's own).
fn level_weight(level: u32, i: u32, n: u32) -> f32 {
    if (level == 0u) {
        return coc[n + i];
    }
    return level_planes[level_base(level, n) + i];
}

// The sample at offset (dx, dy) from pixel (x, y) of level `level`: its colour minus the
// centre's, its signed radius and 1 / bokeh area.
fn sample(x: u32, y: u32, dx: i32, dy: i32, centre: vec4<f32>, level: u32) -> Sample {
    let n = config.width * config.height;
    let sx = mirror(i32(x) + dx, config.width);
    let sy = mirror(i32(y) + dy, config.height);
    let i = sy * config.width + sx;
    var s: Sample;
    s.d = level_colour(level, 0u, i, n) - centre;
    s.c = 0.5 * coc[i];
    s.ia = select(0.0, level_weight(level, i, n), inside(x, y, dx, dy));
    return s;
}

// a / b within rounding of the CPU's correctly rounded quotient: WGSL's division may be off
// by 2.5 ulps (lavapipe's is), which put the light layers' mean difference over the parity
// tests' 1e-7 of the range; one correction by the exact residual (an fma) brings it back.
fn divide(a: f32, b: f32) -> f32 {
    let q = a / b;
    return q + fma(-q, b, a) / b;
}

// The prefilter (`Padded::level` in src/dof/gather/run.rs): level group.z's box of its side
// about each pixel (offsets -side/2 ..= side - 1 - side/2), summed across then down as the
// CPU does: 1 / bokeh area's mean, and each colour's average weighted by it.
@compute @workgroup_size(16, 16)
fn prefilter(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let x = group.x * TILE + local.x;
    let y = group.y * TILE + local.y;
    if (x >= config.width || y >= config.height) {
        return;
    }
    let n = config.width * config.height;
    let p = y * config.width + x;
    let level = group.z + 1u;
    let side = sides[group.z];
    let lo = i32(side / 2u);
    let hi = i32(side) - 1 - lo;
    let colours = min(config.colours, MOST_COLOURS);
    let base = level_base(level, n);
    var sum = 0.0;
    for (var oy = -lo; oy <= hi; oy++) {
        let sy = i32(y) + oy;
        if (sy < 0 || sy >= i32(config.height)) {
            continue;
        }
        var across = 0.0;
        for (var ox = -lo; ox <= hi; ox++) {
            let sx = i32(x) + ox;
            if (sx >= 0 && sx < i32(config.width)) {
                across += coc[n + u32(sy) * config.width + u32(sx)];
            }
        }
        sum += across;
    }
    level_planes[base + p] = divide(sum, f32(side * side));
    for (var g = 0u; g < colours; g++) {
        var weighted = vec4<f32>(0.0);
        for (var oy = -lo; oy <= hi; oy++) {
            let sy = i32(y) + oy;
            if (sy < 0 || sy >= i32(config.height)) {
                continue;
            }
            var across = vec4<f32>(0.0);
            for (var ox = -lo; ox <= hi; ox++) {
                let sx = i32(x) + ox;
                if (sx >= 0 && sx < i32(config.width)) {
                    let i = u32(sy) * config.width + u32(sx);
                    across += coc[n + i] * level_colour(0u, g, i, n);
                }
            }
            weighted += across;
        }
        var average = level_colour(0u, g, p, n);
        if (sum > 0.0) {
            average = vec4<f32>(divide(weighted.x, sum), divide(weighted.y, sum), divide(weighted.z, sum), divide(weighted.w, sum));
        }
        let at = base + (1u + 4u * g) * n;
        level_planes[at + p] = average.x;
        level_planes[at + n + p] = average.y;
        level_planes[at + 2u * n + p] = average.z;
        level_planes[at + 3u * n + p] = average.w;
    }
}

@compute @workgroup_size(16, 16)
fn gather(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let x = group.x * TILE + local.x;
    let y = group.y * TILE + local.y;
    if (x >= config.width || y >= config.height) {
        return;
    }
    let n = config.width * config.height;
    let p = y * config.width + x;
    let tile = tiles[group.y * config.columns + group.x];
    let centre = vec4<f32>(color[p], color[n + p], color[2u * n + p], color[3u * n + p]);
    if (tile.fields == 0u) {
        out[p] = centre.x;
        out[n + p] = centre.y;
        out[2u * n + p] = centre.z;
        out[3u * n + p] = centre.w;
        return;
    }
    let cc = 0.5 * coc[p];
    let rp = abs(cc);
    let split = cc - 0.5 * config.layer;
    // Sums of weight × (sample − centre); p's own weight starts the far sum (the far level's
    // box where the far taps read one and p gathers them).
    var far = vec4<f32>(0.0);
    var far_weight = coc[n + p];
    let far_taps = far_list(tile, rp);
    if (tile.far_level > 0u && rp > config.small) {
        far_weight = level_weight(tile.far_level, p, n);
        far = far_weight * (level_colour(tile.far_level, 0u, p, n) - centre);
    }
    var near = vec4<f32>(0.0);
    var opacity = 0.0;
    // Both fields over the same taps in one loop, unless the far field reads the dense grid:
    // then as apart (the same sums in the same order).
    let fused = tile.fields == 2u && !(tile.dense_count > 0u && rp <= config.small);
    if (!fused) {
        for (var k = 0u; k < far_taps.y; k++) {
            let tap = taps[far_taps.x + k];
            let s = sample(x, y, tap.dx, tap.dy, centre, far_taps.z);
            let rs = abs(s.c);
            let is_far = tile.fields == 1u || s.c > split;
            let cover_far = clamp(min(rs, rp) - tap.norm_far + 0.5, 0.0, 1.0);
            var wf = 0.0;
            if (is_far) {
                wf = cover_far * s.ia;
            }
            far += wf * s.d;
            far_weight += wf;
        }
    }
    if (tile.fields == 3u || (tile.fields == 2u && !fused)) {
        for (var k = 0u; k < tile.taps_count; k++) {
            let tap = taps[tile.taps_start + k];
            let s = sample(x, y, tap.dx, tap.dy, centre, tile.level);
            let rs = abs(s.c);
            let cover_near = clamp(rs - tap.norm_near + 0.5, 0.0, 1.0);
            var wn = 0.0;
            if (!(s.c > split)) {
                wn = cover_near * tap.area * s.ia;
            }
            near += wn * s.d;
            opacity += wn;
        }
    }
    if (fused) {
        for (var k = 0u; k < tile.taps_count; k++) {
            let tap = taps[tile.taps_start + k];
            let s = sample(x, y, tap.dx, tap.dy, centre, tile.level);
            let rs = abs(s.c);
            let is_far = s.c > split;
            let cover_far = clamp(min(rs, rp) - tap.norm_far + 0.5, 0.0, 1.0);
            let cover_near = clamp(rs - tap.norm_near + 0.5, 0.0, 1.0);
            var wf = 0.0;
            var wn = 0.0;
            if (is_far) {
                wf = cover_far * s.ia;
            } else {
                wn = cover_near * tap.area * s.ia;
            }
            far += wf * s.d;
            near += wn * s.d;
            far_weight += wf;
            opacity += wn;
        }
    }
    var near_scale = 1.0;
    var rest = 1.0 - opacity;
    if (opacity > 1.0) {
        near_scale = 1.0 / opacity;
        rest = 0.0;
    }
    let far_scale = rest / far_weight;
    let o = centre + near * near_scale + far * far_scale;
    out[p] = o.x;
    out[n + p] = o.y;
    out[2u * n + p] = o.z;
    out[3u * n + p] = o.w;
}

// Most colours `gather_carrying` gathers in one dispatch.
const MOST_COLOURS: u32 = 8u;

// Colour g's RGBA at pixel i (its planes the g-th four in `color`).
fn colour_at(g: u32, i: u32, n: u32) -> vec4<f32> {
    let base = 4u * g * n;
    return vec4<f32>(color[base + i], color[base + n + i], color[base + 2u * n + i], color[base + 3u * n + i]);
}

// The pixel at offset (dx, dy) from pixel (x, y), mirrored into the frame.
fn tap_index(x: u32, y: u32, dx: i32, dy: i32) -> u32 {
    return mirror(i32(y) + dy, config.height) * config.width + mirror(i32(x) + dx, config.width);
}

// `gather` of `config.colours` colours at once, the twin of the CPU's `gather_carrying`: each
// tap's weights computed once, from the CoC, and every colour summed with them in `gather`'s
// order (sample minus centre), so each comes out as `gather` gives it in the beauty's place.
@compute @workgroup_size(16, 16)
fn gather_carrying(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_id) local: vec3<u32>) {
    let x = group.x * TILE + local.x;
    let y = group.y * TILE + local.y;
    if (x >= config.width || y >= config.height) {
        return;
    }
    let n = config.width * config.height;
    let p = y * config.width + x;
    let colours = min(config.colours, MOST_COLOURS);
    let tile = tiles[group.y * config.columns + group.x];
    var centre: array<vec4<f32>, MOST_COLOURS>;
    for (var g = 0u; g < colours; g++) {
        centre[g] = colour_at(g, p, n);
    }
    var far: array<vec4<f32>, MOST_COLOURS>;
    var near: array<vec4<f32>, MOST_COLOURS>;
    var far_weight = coc[n + p];
    var opacity = 0.0;
    if (tile.fields != 0u) {
        let cc = 0.5 * coc[p];
        let rp = abs(cc);
        let split = cc - 0.5 * config.layer;
        let far_taps = far_list(tile, rp);
        if (tile.far_level > 0u && rp > config.small) {
            far_weight = level_weight(tile.far_level, p, n);
            for (var g = 0u; g < colours; g++) {
                far[g] = far_weight * (level_colour(tile.far_level, g, p, n) - centre[g]);
            }
        }
        let fused = tile.fields == 2u && !(tile.dense_count > 0u && rp <= config.small);
        if (!fused) {
            for (var k = 0u; k < far_taps.y; k++) {
                let tap = taps[far_taps.x + k];
                let i = tap_index(x, y, tap.dx, tap.dy);
                let ia = select(0.0, level_weight(far_taps.z, i, n), inside(x, y, tap.dx, tap.dy));
                let sc = 0.5 * coc[i];
                let rs = abs(sc);
                let is_far = tile.fields == 1u || sc > split;
                let cover_far = clamp(min(rs, rp) - tap.norm_far + 0.5, 0.0, 1.0);
                var wf = 0.0;
                if (is_far) {
                    wf = cover_far * ia;
                }
                for (var g = 0u; g < colours; g++) {
                    far[g] += wf * (level_colour(far_taps.z, g, i, n) - centre[g]);
                }
                far_weight += wf;
            }
        }
        if (tile.fields == 3u || (tile.fields == 2u && !fused)) {
            for (var k = 0u; k < tile.taps_count; k++) {
                let tap = taps[tile.taps_start + k];
                let i = tap_index(x, y, tap.dx, tap.dy);
                let ia = select(0.0, level_weight(tile.level, i, n), inside(x, y, tap.dx, tap.dy));
                let sc = 0.5 * coc[i];
                let rs = abs(sc);
                let cover_near = clamp(rs - tap.norm_near + 0.5, 0.0, 1.0);
                var wn = 0.0;
                if (!(sc > split)) {
                    wn = cover_near * tap.area * ia;
                }
                for (var g = 0u; g < colours; g++) {
                    near[g] += wn * (level_colour(tile.level, g, i, n) - centre[g]);
                }
                opacity += wn;
            }
        }
        if (fused) {
            for (var k = 0u; k < tile.taps_count; k++) {
                let tap = taps[tile.taps_start + k];
                let i = tap_index(x, y, tap.dx, tap.dy);
                let ia = select(0.0, level_weight(tile.level, i, n), inside(x, y, tap.dx, tap.dy));
                let sc = 0.5 * coc[i];
                let rs = abs(sc);
                let is_far = sc > split;
                let cover_far = clamp(min(rs, rp) - tap.norm_far + 0.5, 0.0, 1.0);
                let cover_near = clamp(rs - tap.norm_near + 0.5, 0.0, 1.0);
                var wf = 0.0;
                var wn = 0.0;
                if (is_far) {
                    wf = cover_far * ia;
                } else {
                    wn = cover_near * tap.area * ia;
                }
                for (var g = 0u; g < colours; g++) {
                    let d = level_colour(tile.level, g, i, n) - centre[g];
                    far[g] += wf * d;
                    near[g] += wn * d;
                }
                far_weight += wf;
                opacity += wn;
            }
        }
    }
    var near_scale = 1.0;
    var rest = 1.0 - opacity;
    if (opacity > 1.0) {
        near_scale = 1.0 / opacity;
        rest = 0.0;
    }
    let far_scale = rest / far_weight;
    for (var g = 0u; g < colours; g++) {
        var o = centre[g];
        if (tile.fields != 0u) {
            o = centre[g] + near[g] * near_scale + far[g] * far_scale;
        }
        let base = 4u * g * n;
        out[base + p] = o.x;
        out[base + n + p] = o.y;
        out[base + 2u * n + p] = o.z;
        out[base + 3u * n + p] = o.w;
    }
}
