// The prelude of every shader (each module's SHADER is this file followed by its own): the
// bit patterns and bit-level tests of f32 that the twins share, defined once. WGSL lets an
// implementation assume that float arithmetic meets no NaN or infinity, so a float
// comparison with one proves nothing: the numeric policy's values are recognised by their
// bits. Shaders that use none of it are unchanged by it (unused declarations compile to
// nothing).

// The bits of +∞ (and the exponent field of every f32): a magnitude above them is a NaN.
const INFINITY_BITS: u32 = 0x7f800000u;
// The bits of −∞.
const NEG_INFINITY_BITS: u32 = 0xff800000u;
// Every bit but the sign: `bits & MAGNITUDE` is |v|'s bits.
const MAGNITUDE: u32 = 0x7fffffffu;
// The sign bit.
const SIGN: u32 = 0x80000000u;

fn is_nan(v: f32) -> bool {
    return (bitcast<u32>(v) & MAGNITUDE) > INFINITY_BITS;
}

fn is_finite(v: f32) -> bool {
    return (bitcast<u32>(v) & MAGNITUDE) < INFINITY_BITS;
}

// +∞ (WGSL has no literal for it).
fn infinity() -> f32 {
    return bitcast<f32>(INFINITY_BITS);
}

// An f32 as a u32 of the same order (total order: −0 below +0), for atomic min and max.
fn ordered(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | SIGN, ~b, (b & SIGN) != 0u);
}

// The inverse of `ordered`.
fn unordered(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & MAGNITUDE, (u & SIGN) != 0u));
}

// `a · b` rounded to f32 by itself, never fused into an add; `zero` must be a 0 the compiler
// cannot see (a word of a uniform the host writes 0). WGSL lets a driver contract `a·b + c`
// into one fused multiply-add (NVIDIA's does, lavapipe's does not), which rounds once where
// the CPU rounds twice: where a decision follows the sum (a sample count's ceil, whether a
// centre lies on an edge), one ulp moves it. The OR on the product's bits stands between the
// multiply and the add, so no compiler can fuse them.
fn apart(a: f32, b: f32, zero: u32) -> f32 {
    return bitcast<f32>(bitcast<u32>(a * b) | zero);
}

// ---- the shader ----------------------------------------------------------------------------
