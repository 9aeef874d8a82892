// Depth of field's `coc` stage on the GPU: the twin of `coc_plane` in src/dof/coc.rs (the
// CPU reference) and of `Lens::signed_coc` in src/dof/coc.rs. One invocation per pixel.
//
// In: the depth plane (scene units; or a painted map's stored values). Out: the signed CoC
// diameter of every pixel in pixels, clamped to ±limit: negative in front of the focus
// plane, positive behind it. NaN never comes out: NaN and +∞ depth are far, zero and
// negative depth (−∞ included) are nearest.
//
// The CPU evaluates the thin lens in f64; WGSL has no f64, so the host folds the lens into
// two f32 numbers (src/dof/coc.rs, `CocConfig::new`):
//     signed CoC = K · (1 − P/D),   K = A·F/(P − F) · width/sensor  (the far limit, px)
// which is the CPU's `−A·F·(P/D − 1)/(P − F) · width/sensor` rearranged. Its f32 error is
// stated in tests/gpu_dof.rs.
//
// Non-finite inputs are recognised by their bits, not by comparisons: WGSL lets an
// implementation assume that no NaN or infinity occurs in floating-point arithmetic.

// Keep in sync with `CocConfig` in src/dof/coc.rs (a test holds the layouts together).
struct CocConfig {
    // Frame size, pixels.
    width: u32,
    height: u32,
    // 0: the thin lens and the depth pass; 1: a painted map.
    source: u32,
    // The largest |CoC| (px).
    limit: f32,
    // lens: K, the far-limit CoC (px). map: the CoC of a stored 1 (px).
    scale: f32,
    // lens: the focus distance P (scene units).
    focus: f32,
    // map: the largest stored value that can come out below the limit, limit/scale.
    cap: f32,
    _pad: u32,
}

@group(0) @binding(0) var<uniform> config: CocConfig;
@group(0) @binding(1) var<storage, read> depth: array<f32>;
@group(0) @binding(2) var<storage, read_write> coc: array<f32>;


// P/D is floored at P·1e-20 (a depth 1e20 times nearer than the focus): with K at most 1e15
// (the host clamps it) the product stays finite, and the CoC is −limit there anyway.
const NEAREST_RATIO: f32 = 1e-20;

fn lens_coc(d: f32) -> f32 {
    let bits = bitcast<u32>(d);
    let magnitude = bits & MAGNITUDE;
    // NaN and +∞: far, P/D = 0.
    if magnitude > INFINITY_BITS || bits == INFINITY_BITS {
        return clamp(config.scale, -config.limit, config.limit);
    }
    // Zero, negative, −∞: nearest (the CPU's −LARGEST, clamped).
    if (bits & SIGN) != 0u || magnitude == 0u {
        return -config.limit;
    }
    let ratio = config.focus / max(d, config.focus * NEAREST_RATIO);
    return clamp(config.scale * (1.0 - ratio), -config.limit, config.limit);
}

fn map_coc(v: f32) -> f32 {
    let bits = bitcast<u32>(v);
    let magnitude = bits & MAGNITUDE;
    // NaN: in focus.
    if magnitude > INFINITY_BITS {
        return 0.0;
    }
    // +∞ is the largest value, −∞ the smallest; finite values are clamped to [0, cap] so the
    // product stays finite (the CPU clamps the product, to the same result).
    var stored = clamp(v, 0.0, config.cap);
    if magnitude == INFINITY_BITS {
        stored = select(config.cap, 0.0, (bits & SIGN) != 0u);
    }
    return clamp(stored * config.scale, 0.0, config.limit);
}

@compute @workgroup_size(16, 16)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= config.width || id.y >= config.height {
        return;
    }
    let i = id.y * config.width + id.x;
    let d = depth[i];
    if config.source == 0u {
        coc[i] = lens_coc(d);
    } else {
        coc[i] = map_coc(d);
    }
}
