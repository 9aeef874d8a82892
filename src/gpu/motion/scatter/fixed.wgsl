// scatter's fixed point (concatenated after scatter.wgsl, whose stages call it): the scale of
// each 16×16 tile's sums, found from the curves that can reach the tile, and the 64-bit
// integer sums themselves (deposit, carry, decode). Why integer sums at all, the rule for G
// and the proof that the sums cannot overflow: src/gpu/motion/scatter/mod.rs, "The fixed
// point".
//
// `reach` counts each curve into the block of the pixel it is drawn from (`count_curve`):
// the block's curves, the farthest any of them reaches, and per colour (the beauty's R, G
// and B; its alpha; each carried layer's R, G and B) the largest |value| and the sum of the
// values' exponents. `scales` gathers, for each tile (a block's square), the blocks whose
// reach touches it: N, the curves that can deposit in the tile, and per colour 2^e, the power
// of two above the largest |value| among them, and 2^l, the least of their blocks' typical
// (mean) magnitudes. The tile's sums of that colour count units of 2^(e − G), with
// G = min(62 − ⌈log₂ N⌉ − w, 32 + e − l): 32 fractional bits where the colours landing are of
// one magnitude, more where a firefly lands among ordinary colours, never so many that the
// sums can overflow. A firefly raises e only in the tiles its own curve can reach.
//
// A curve's reach is a bound on how far from p(0) it goes: the Bézier's extent (`extent`,
// which the scaling to the longest curve only shrinks), and where that is farther than the
// longest curve, or the curve may be an arc, the farthest point of its path as `accumulate`
// builds it. It is kept beside the curve's entry in the moving list, and `accumulate` clips
// the curve's walks to it, so no deposit lands in a tile that did not count the curve, by
// construction. The rare curve that reaches farther than the longest curve can (one cut
// short far from p(0)), or whose path `reach` found empty, is counted into every tile
// instead (FAR, the block after the last), which keeps the blocks `scales` visits within
// the longest curve's reach.

// Blocks (and tiles) are BLOCK pixels square: the CPU's `BLOCK` (src/motion/scatter/config.rs),
// over which its own reach is kept.
const BLOCK: u32 = 16u;
// Colours with a scale of their own: the beauty's R, G and B (one scale, so a deposit scales
// its weight once for all three), its alpha (whose values are of another kind, at most 1,
// where a colour may be huge), then each carried layer's R, G and B, at most MOST_LAYERS of
// them (carrying.wgsl); the weight's scale is the frame's (`weight_shift`).
const COLOURS: u32 = 10u;
const ALPHA: u32 = 1u;
const FIRST_CARRIED: u32 = 2u;
// A block's words in `state` (from BLOCKS; FAR's follow the last block's): its curves, the
// farthest they reach (px), then per colour the largest |value| of its channels (a
// non-negative float's bits) and the sum of the exponents its curves bring
// (`exponent_above`, plus 126), whose mean is the block's typical magnitude.
const CURVES: u32 = 0u;
const REACH: u32 = 1u;
const BOUNDS: u32 = 2u;
const LOGS: u32 = 12u;
const BLOCK_WORDS: u32 = 22u;
// A tile's words (`tile_at`): N, the curves that can deposit in it, then per colour
// k = G − e, a signed byte (four to a word, the beauty's first: a deposit reads one word),
// and per colour G and e (its sums count units of 2^(e − G)).
const TILE_CURVES: u32 = 0u;
const FACTORS: u32 = 1u;
const SHIFTS: u32 = 4u;
const EXPONENTS: u32 = 14u;
const TILE_WORDS: u32 = 24u;
// 2⁶²: the sums' magnitude stays below it and the rounding (the proof in mod.rs).
const TOP_BITS: i32 = 62;
// log₂ of a bound on what one curve deposits in one pixel, in weight: at most 64 segments,
// each at most one deposit a pixel of coverage ≤ √2 times a weight ≤ 1 (the paper's weights:
// 64·√2 ≈ 90.5 < 2⁷); under the exposure normalisation a curve's deposits sum to its
// coverage, ≤ 1 (< 2¹).
const WIDE_PAPER: u32 = 7u;
const WIDE_EXPOSURE: u32 = 1u;
// Fractional bits of a sum in a tile whose colours are all of one magnitude (as one frame-wide
// scale had): a typical deposit, a weight below 1 times a value below 2^e, is then below 2³²
// units (one atomic word; the carry seldom reaches the high one) and keeps every bit of its
// f32; more bits would cost the high word's atomic at most deposits.
const FRACTION: i32 = 32;
// 2³²: a word.
const WORD: f32 = 4294967296.0;

fn blocks_across() -> u32 {
    return (config.width + BLOCK - 1u) / BLOCK;
}

fn blocks() -> u32 {
    return blocks_across() * ((config.height + BLOCK - 1u) / BLOCK);
}

// The first word of block b's entry (b = blocks(): FAR's), and of tile t's.
fn block_at(b: u32) -> u32 {
    return BLOCKS + b * BLOCK_WORDS;
}

fn tile_at(t: u32) -> u32 {
    return 2u * pixels() + t * TILE_WORDS;
}

// The block (and the tile) holding pixel p.
fn block_of(p: u32) -> u32 {
    return (p / config.width) / BLOCK * blocks_across() + (p % config.width) / BLOCK;
}

// How far (px, along each axis) from the pixel it is drawn from a curve that goes at most r
// px from p(0) may deposit: r, the pixel beside it, and one more (for the f32 rounding of
// the path, which `accumulate` builds alike but need not round alike), as a whole number.
fn reach_of(r: f32) -> u32 {
    var at = r;
    if !(at >= 0.0) {
        at = 0.0;
    }
    // No frame is 2³⁰ px across.
    return u32(ceil(min(at, UNCLIPPED))) + 2u;
}

// The farthest point from p(0) of the path of `segments` just built (`path`).
fn farthest(segments: u32) -> f32 {
    let now = vec2<f32>(0.5, 0.5);
    var r = 0.0;
    for (var k = 0u; k <= segments; k++) {
        r = max(r, length2(points[k] - now));
    }
    return r;
}

// The reach of a curve counted into FAR: no clip.
const UNCLIPPED: f32 = 1073741824.0;

// Past this reach a curve is counted into every tile (FAR): the longest curve's, and the
// pixels beside it.
fn far() -> u32 {
    return u32(ceil(min(max(config.max_curve, 1.0), UNCLIPPED))) + 3u;
}

// e of a bound's bits (a non-negative float's): 2^e is the power of two above it (1 where
// it is 0), so colours times 2^−e lie in (−1, 1), exactly.
fn exponent_above(bits: u32) -> i32 {
    if bits == 0u {
        return 0;
    }
    return max(i32(bits >> 23u), 1) - 126;
}

// reach: the curve of pixel i (its colour and motion), drawn from pixel `own` (i itself, or
// a fringe entry's still pixel), counted into own's block, or FAR's where it reaches farther
// than a curve can unless cut short far from p(0), or its path is empty (then it draws
// nothing, unless `accumulate` rounds otherwise). Returns its reach, the clip of its walks.
fn count_curve(own: u32, i: u32, m: Motion) -> u32 {
    // The Bézier's bound, which holds whether `path` scales the curve or not.
    var reach = reach_of(extent(m));
    var segments = 1u;
    if reach > far() || config.arc != 0u {
        // Farther than the longest curve (so `path` cuts it short), or maybe an arc: the
        // path's own farthest point (and the Bézier's bound beside it, where that is near
        // enough, in case `accumulate` decides otherwise about the arc).
        segments = path(i, m, 1.0);
        let along = reach_of(farthest(segments));
        reach = select(max(reach, along), along, reach > far());
    }
    var b = block_at(block_of(own));
    let counted = reach <= far() && segments != 0u;
    if counted {
        atomicMax(&state[b + REACH], reach);
        if reach > atomicLoad(&state[MOST_REACH]) {
            atomicMax(&state[MOST_REACH], reach);
        }
    } else {
        b = block_at(blocks());
        reach = u32(UNCLIPPED);
    }
    atomicAdd(&state[b + CURVES], 1u);
    let c = own_color(i);
    for (var k = 0u; k < FIRST_CARRIED + carried_layers(); k++) {
        var v = max(max(abs(c.x), abs(c.y)), abs(c.z));
        if k == ALPHA {
            v = abs(c.w);
        } else if k >= FIRST_CARRIED {
            v = carried_magnitude(k - FIRST_CARRIED, i);
        }
        // Non-negative floats order as their bits do.
        let bits = bitcast<u32>(v);
        atomicMax(&state[b + BOUNDS + k], bits);
        // FAR's typical magnitude is its largest (its logs could overflow a word).
        if counted {
            atomicAdd(&state[b + LOGS + k], u32(exponent_above(bits) + 126));
        }
    }
    return reach;
}

// Stage 1b, one invocation per tile: the curves of every block whose reach touches the tile
// (the CPU's tiles ask the same of its blocks: `Reach`) and of FAR, N; per colour the
// largest |value| they bring (2^e above it) and the least typical magnitude among them
// (2^l: the smallest of the blocks' mean exponents); and from those the tile's fixed point:
// G = min(62 − ⌈log₂ N⌉ − w, 32 + e − l) fractional bits of 2^e. A tile whose colours are
// of one magnitude counts in units of 2⁻³² of it, as one frame-wide scale did; one that a
// firefly's curve reaches, beside ordinary colours, gets as many more bits as the firefly
// is brighter than they are, up to what cannot overflow (the proof in mod.rs).
@compute @workgroup_size(WORKGROUP)
fn scales(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let t = flat(group, groups, lane);
    if t >= blocks() {
        return;
    }
    let across = blocks_across();
    let down = blocks() / across;
    let tx = t % across;
    let ty = t / across;
    let colours = FIRST_CARRIED + carried_layers();
    var top: array<u32, COLOURS>;
    var low: array<i32, COLOURS>;
    // FAR's curves reach every tile; its typical magnitude is its largest.
    let far = block_at(blocks());
    var curves = atomicLoad(&state[far + CURVES]);
    for (var c = 0u; c < colours; c++) {
        top[c] = atomicLoad(&state[far + BOUNDS + c]);
        low[c] = select(1000, exponent_above(top[c]), curves > 0u);
    }
    // A block b·BLOCK … b·BLOCK + 15 whose curves reach r px touches the tile if
    // BLOCK·|t − b| − 15 ≤ r; the farthest any block reaches bounds the blocks to look at.
    let span = (atomicLoad(&state[MOST_REACH]) + BLOCK - 1u) / BLOCK;
    let bx0 = select(tx - span, 0u, span > tx);
    let by0 = select(ty - span, 0u, span > ty);
    let bx1 = min(tx + span, across - 1u);
    let by1 = min(ty + span, down - 1u);
    for (var by = by0; by <= by1; by++) {
        for (var bx = bx0; bx <= bx1; bx++) {
            let b = block_at(by * across + bx);
            let count = atomicLoad(&state[b + CURVES]);
            if count == 0u {
                continue;
            }
            let reach = atomicLoad(&state[b + REACH]) + BLOCK - 1u;
            let gap = BLOCK * max(max(tx, bx) - min(tx, bx), max(ty, by) - min(ty, by));
            if gap > reach {
                continue;
            }
            curves += count;
            for (var c = 0u; c < colours; c++) {
                top[c] = max(top[c], atomicLoad(&state[b + BOUNDS + c]));
                let mean = i32(atomicLoad(&state[b + LOGS + c]) / count) - 126;
                low[c] = min(low[c], mean);
            }
        }
    }
    let most = most_shift(curves);
    let tile = tile_at(t);
    moving[tile + TILE_CURVES] = curves;
    var factors = array<u32, 3>();
    for (var c = 0u; c < colours; c++) {
        let shift = min(most, FRACTION + max(exponent_above(top[c]) - low[c], 0));
        // e no lower than G − 125, so k = G − e is a signed byte and a weight (≤ 2) times
        // 2^k a finite float (e ≤ 128 and G ≥ 24 keep k above −128): a colour below
        // 2^(G − 125) ≤ 2⁻⁶⁴ is below a unit there anyway.
        let e = max(exponent_above(top[c]), shift - 125);
        factors[c / 4u] |= (u32(shift - e) & 0xffu) << (8u * (c % 4u));
        moving[tile + SHIFTS + c] = bitcast<u32>(shift);
        moving[tile + EXPONENTS + c] = bitcast<u32>(e);
    }
    for (var w = 0u; w < 3u; w++) {
        moving[tile + FACTORS + w] = factors[w];
    }
}

// The most fractional bits sums that N curves deposit in can keep: 62 − ⌈log₂ N⌉ − w.
fn most_shift(curves: u32) -> i32 {
    // ⌈log₂ N⌉ (0 for one curve).
    let bits = i32(32u - countLeadingZeros(max(curves, 1u) - 1u));
    return TOP_BITS - bits - i32(select(WIDE_PAPER, WIDE_EXPOSURE, config.exposure != 0u));
}

// The weight's shift: one for the frame, its weights being bounded (at most 2^w a curve and
// pixel) where colours are not; N every curve of the frame (the list's count, which counts
// even a fringe entry a full list dropped), so the bound holds in every tile.
fn weight_shift() -> i32 {
    return min(most_shift(atomicLoad(&state[COUNT])), FRACTION);
}

// 2^k, for −126 ≤ k ≤ 127 (a normal float built from its bits: exact, and no libm call
// where a driver lowers `ldexp` to one, as llvmpipe does, lane by lane).
fn two_to(k: i32) -> f32 {
    return bitcast<f32>(u32(k + 127) << 23u);
}

// G and e of colour c (0 the beauty's R, G, B, ALPHA its A, FIRST_CARRIED… the carried
// layers') in the tile whose words start at `tile`: its sums count units of 2^(e − G).
fn shift_of(tile: u32, c: u32) -> i32 {
    return bitcast<i32>(moving[tile + SHIFTS + c]);
}

fn exponent_of(tile: u32, c: u32) -> i32 {
    return bitcast<i32>(moving[tile + EXPONENTS + c]);
}

// A deposit's weight d scaled for colour c in the tile whose words start at `tile`: d · 2^k,
// k = G − e, exactly (one product by a normal power of two, at most 2^125, and d ≤ 2); a
// channel's value times it is the deposit in units, below 2^G in magnitude. Looked up at
// every deposit, without a branch or `ldexp`: where a driver runs every side of a branch
// under a lane mask and lowers `ldexp` to a libm call, lane by lane (llvmpipe does both), a
// cache of the pen's scaled colour per tile cost more than reading the word.
fn weight_in(d: f32, tile: u32, c: u32) -> f32 {
    let factors = bitcast<i32>(moving[tile + FACTORS + c / 4u]);
    return d * two_to(extractBits(factors, 8u * (c % 4u), 8u));
}

// v (an integer number of units, |v| < 2⁶³) as a 64-bit two's-complement number (low word,
// high word), its fraction rounded to the nearest unit.
fn fixed(v: f32) -> vec2<u32> {
    let m = abs(v);
    let whole = floor(m * (1.0 / WORD));
    var hi = u32(whole);
    // Exact: the low part of m is bits of m's own (m is a multiple of its ulp, and so is
    // whole · 2³²), and 2³² is a power of two.
    let x = m - whole * WORD;
    var lo: u32;
    if x < 8388608.0 {
        lo = u32(x + 0.5);
    } else {
        lo = u32(x);
    }
    if v < 0.0 {
        // Negated: −(hi·2³² + lo) = (~hi + [lo = 0])·2³² + (~lo + 1), modulo 2⁶⁴.
        hi = ~hi + select(0u, 1u, lo == 0u);
        lo = ~lo + 1u;
    }
    return vec2<u32>(lo, hi);
}

// The low word takes the low part; where it wraps (the value it returns, plus ours, is below
// it) the high word takes the carry with the high part. Every wrap carries exactly one, so
// the 64-bit sum is Σ values modulo 2⁶⁴ in any order.
fn carry(old: u32, lo: u32, hi: u32) -> u32 {
    return hi + select(0u, 1u, old + lo < old);
}

// Adds v (in units of its tile's scale) to sum `channel` (0–3 R, G, B, A; 4 the weight) of
// pixel p.
fn add(channel: u32, p: u32, v: f32) {
    let f = fixed(v);
    if f.x == 0u && f.y == 0u {
        return;
    }
    let low = 2u * p;
    var high = 0u;
    switch channel {
        case 0u: {
            high = carry(atomicAdd(&sum_r[low], f.x), f.x, f.y);
            if high != 0u {
                atomicAdd(&sum_r[low + 1u], high);
            }
        }
        case 1u: {
            high = carry(atomicAdd(&sum_g[low], f.x), f.x, f.y);
            if high != 0u {
                atomicAdd(&sum_g[low + 1u], high);
            }
        }
        case 2u: {
            high = carry(atomicAdd(&sum_b[low], f.x), f.x, f.y);
            if high != 0u {
                atomicAdd(&sum_b[low + 1u], high);
            }
        }
        case 3u: {
            high = carry(atomicAdd(&sum_a[low], f.x), f.x, f.y);
            if high != 0u {
                atomicAdd(&sum_a[low + 1u], high);
            }
        }
        default: {
            high = carry(atomicAdd(&sum_w[low], f.x), f.x, f.y);
            if high != 0u {
                atomicAdd(&sum_w[low + 1u], high);
            }
        }
    }
}

// A sum of pixel p (channel as `add` numbers them), in units of its channel's 2^e in p's
// tile (the weight's: 1), G its channel's shift there.
fn decode(p: u32, channel: u32, shift: i32) -> f32 {
    var lo: u32;
    var hi: u32;
    switch channel {
        case 0u: {
            lo = atomicLoad(&sum_r[2u * p]);
            hi = atomicLoad(&sum_r[2u * p + 1u]);
        }
        case 1u: {
            lo = atomicLoad(&sum_g[2u * p]);
            hi = atomicLoad(&sum_g[2u * p + 1u]);
        }
        case 2u: {
            lo = atomicLoad(&sum_b[2u * p]);
            hi = atomicLoad(&sum_b[2u * p + 1u]);
        }
        case 3u: {
            lo = atomicLoad(&sum_a[2u * p]);
            hi = atomicLoad(&sum_a[2u * p + 1u]);
        }
        default: {
            lo = atomicLoad(&sum_w[2u * p]);
            hi = atomicLoad(&sum_w[2u * p + 1u]);
        }
    }
    return fixed_value(lo, hi, shift);
}

// The value of a sum's two words (low, high) counted in units of 2^−shift. The magnitude is
// converted (a negative sum negated first), so a small negative sum keeps its digits rather
// than cancelling in −2³² + (2³² − s); each of the three roundings is within 2⁻²⁴ of it.
fn fixed_value(lo: u32, hi: u32, shift: i32) -> f32 {
    var l = lo;
    var h = hi;
    let negative = (hi & SIGN) != 0u;
    if negative {
        h = ~hi + select(0u, 1u, lo == 0u);
        l = ~lo + 1u;
    }
    let m = (f32(h) * WORD + f32(l)) * two_to(-shift);
    return select(m, -m, negative);
}
