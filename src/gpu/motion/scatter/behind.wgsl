// scatter's resolve stage, what lies behind a pixel not wholly covered (`Scatter::behind`
// and `Scatter::unseen` of src/motion/scatter/resolve.rs): concatenated after scatter.wgsl,
// whose resolve reads it.

// `OFF_FRAME_TAPS` and `BEHIND_PIXELS` of src/motion/scatter/resolve.rs.
const OFF_FRAME_TAPS: u32 = 4u;
// What lies behind a pixel not wholly covered (`Behind`): the pixels found (the first
// farther pixel along its motion either way, or what `unseen` reads), `count` of them (0:
// its own colour).
struct Behind {
    pixels: array<u32, 8>,
    count: u32,
}

// `Scatter::behind`: the nearest farther surface along the pixel's motion (either way; the
// average if both), else its own colour. (The CPU first asks its blocks' deepest depths
// whether the walk can find anything; that only skips walks that find nothing.)
fn behind(p: u32) -> Behind {
    var found = Behind(array<u32, 8>(), 0u);
    let m = motion_of(p);
    let e = extent(m);
    if !(e >= STILL) {
        return found;
    }
    let v = m.next - m.prev;
    let l = length2(v);
    if is_nan(l) || l <= 0.0 {
        return found;
    }
    let dir = v / l;
    let limit = depth[p] * (1.0 + config.depth_tolerance);
    let steps = u32(ceil(min(e, config.max_curve) + 2.0));
    let now = vec2<f32>(f32(p % config.width) + 0.5, f32(p / config.width) + 0.5);
    for (var s = 0; s < 2; s++) {
        let side = select(-1.0, 1.0, s == 0);
        for (var k = 1u; k <= steps; k++) {
            let x = now.x + side * f32(k) * dir.x;
            let y = now.y + side * f32(k) * dir.y;
            if !(x >= 0.0 && y >= 0.0 && x < f32(config.width) && y < f32(config.height)) {
                break;
            }
            let j = u32(y) * config.width + u32(x);
            if depth[j] > limit {
                found.pixels[found.count] = j;
                found.count += 1u;
                break;
            }
        }
    }
    if found.count == 0u {
        return unseen(p, now, dir, min(e, config.max_curve));
    }
    return found;
}

// The pixel at `d` px along `dir` from `now`; OFF_FRAME past the frame's edge.
const OFF_FRAME: u32 = 0xffffffffu;
fn along(now: vec2<f32>, dir: vec2<f32>, d: f32) -> u32 {
    let at = now + d * dir;
    if !(at.x >= 0.0 && at.y >= 0.0 && at.x < f32(config.width) && at.y < f32(config.height)) {
        return OFF_FRAME;
    }
    return u32(at.y) * config.width + u32(at.x);
}

// `Scatter::unseen`: for the part of moving pixel p's streak no curve brought (nothing
// farther along its motion), the part behind a nearer surface on one side read a streak's
// length back on the other, else the part past the frame's edge (on one side or both) read
// on its border.
fn unseen(p: u32, now: vec2<f32>, dir: vec2<f32>, q: f32) -> Behind {
    var found = Behind(array<u32, 8>(), 0u);
    let near = depth[p] / (1.0 + config.depth_tolerance);
    let far = depth[p] * (1.0 + config.depth_tolerance);
    // Per side (along dir, against it): where the streak goes behind a nearer surface, or
    // off the frame (-1: neither).
    var hidden = vec2<f32>(-1.0);
    var off = vec2<f32>(-1.0);
    for (var s = 0u; s < 2u; s++) {
        let side = select(-1.0, 1.0, s == 0u);
        for (var k = 1.0; k <= ceil(q); k += 1.0) {
            let j = along(now, dir, side * k);
            if j == OFF_FRAME {
                off[s] = k - 0.5;
                break;
            }
            if depth[j] < near {
                hidden[s] = k - 0.5;
                break;
            }
        }
    }
    if (hidden.x >= 0.0) != (hidden.y >= 0.0) {
        let side = select(-1.0, 1.0, hidden.x >= 0.0);
        let b = max(hidden.x, hidden.y);
        if b >= q || b < 1.0 {
            return found;
        }
        for (var f = 0.25; f < 1.0; f += 0.5) {
            let j = along(now, dir, -side * (q + (q - b) * f));
            if j != OFF_FRAME && depth[j] >= near && depth[j] <= far {
                found.pixels[found.count] = j;
                found.count += 1u;
            }
        }
    } else if hidden.x < 0.0 && hidden.y < 0.0 {
        // Each side that runs off the frame (both at a corner): OFF_FRAME_TAPS points spread
        // over the part past the edge, clamped to the frame.
        for (var s = 0u; s < 2u; s++) {
            if off[s] < 0.0 {
                continue;
            }
            let side = select(-1.0, 1.0, s == 0u);
            let b = off[s];
            for (var t = 0u; t < OFF_FRAME_TAPS; t++) {
                let f = (f32(t) + 0.5) / f32(OFF_FRAME_TAPS);
                let at = now + side * (b + (q - b) * f) * dir;
                let x = clamp(at.x, 0.0, f32(config.width) - 0.5);
                let y = clamp(at.y, 0.0, f32(config.height) - 0.5);
                found.pixels[found.count] = u32(y) * config.width + u32(x);
                found.count += 1u;
            }
        }
    }
    return found;
}

// The beauty's colour behind: the average of the pixels found, else `own`.
fn behind_color(b: Behind, own: vec4<f32>) -> vec4<f32> {
    if b.count == 0u {
        return own;
    }
    var sum = vec4<f32>(0.0);
    for (var k = 0u; k < b.count; k++) {
        sum += own_color(b.pixels[k]);
    }
    return sum / f32(b.count);
}
