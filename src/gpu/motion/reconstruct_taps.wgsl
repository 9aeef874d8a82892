// How the 2014 gather (reconstruct.wgsl, `gather_pixel_2014`) reads one tap between pixels:
// the twin of src/motion/reconstruct/taps.rs (`around_index`, `bilinear`, `split`,
// `split_by_cover`) and of `matte::surfaces_of`. Each reads depth and motion from the texels
// and mixes the pipeline's `colours()` colours through `colour(g, j)`; every weight is a
// function of the geometry and of the mattes (fitted on the beauty), never of the colours.
// Concatenated after reconstruct.wgsl, whose bindings and constants it uses.

// `around`: the indices of the four texels around pixel (x, y) + offset (clamped to the
// frame) and their bilinear weights.
struct Around {
    index: array<u32, 4>,
    weight: array<f32, 4>,
}

fn around(x: u32, y: u32, offset: vec2<f32>) -> Around {
    let width = config.width;
    let height = config.height;
    let fx = max(f32(x) + offset.x, 0.0);
    let fy = max(f32(y) + offset.y, 0.0);
    let x0u = u32(fx);
    let y0u = u32(fy);
    let wx = fx - f32(x0u);
    let wy = fy - f32(y0u);
    let x0 = min(x0u, width - 1u);
    let x1 = min(x0u + 1u, width - 1u);
    let y0 = min(y0u, height - 1u);
    let y1 = min(y0u + 1u, height - 1u);
    return Around(
        array<u32, 4>(y0 * width + x0, y0 * width + x1, y1 * width + x0, y1 * width + x1),
        array<f32, 4>((1.0 - wx) * (1.0 - wy), wx * (1.0 - wy), (1.0 - wx) * wy, wx * wy),
    );
}

// `bilinear`: the colours at the tap's point, read between pixels over the corners that move
// or share the nearest pixel's surface (depth and motion stay the nearest's).
fn bilinear(nearest: u32, scale: f32, x: u32, y: u32, offset: vec2<f32>) -> Colours {
    let corners = around(x, y, offset);
    let z = texel8(nearest).z;
    var w: array<f32, 4>;
    for (var q = 0u; q < 4u; q++) {
        let t = texel8(corners.index[q]);
        let mixes = abs(t.z - z) * scale < 1.0 || t.length >= HALF_PIXEL;
        w[q] = corners.weight[q] * select(0.0, 1.0, mixes);
    }
    let total = w[0] + w[1] + w[2] + w[3];
    if total > 0.0 {
        let inverse = 1.0 / total;
        var out: Colours;
        for (var g = 0u; g < colours(); g++) {
            out.c[g] = (w[0] * colour(g, corners.index[0]) + w[1] * colour(g, corners.index[1])
                + w[2] * colour(g, corners.index[2]) + w[3] * colour(g, corners.index[3]))
                * inverse;
        }
        return out;
    }
    return colours_of(nearest);
}

// A tap's part (the CPU's `Part`): the depth and motion of its surface, its colours summed
// with their weights, and its share of the tap.
struct Part {
    texel: Texel2014,
    colour: Colours,
    share: f32,
}

// `split`'s result: the tap's two parts.
struct Split {
    a: Part,
    b: Part,
}

// `split`: the exposure variant's tap read between pixels and split by surface.
fn split(nearest: u32, scale: f32, x: u32, y: u32, offset: vec2<f32>) -> Split {
    let corners = around(x, y, offset);
    let near = texel8(nearest);
    let moves = near.length >= HALF_PIXEL;
    var out: Split;
    out.a.texel = near;
    var heaviest = 0.0;
    // The heaviest pixel of part B, if any.
    var heaviest_pixel = 0u;
    var have_heaviest = false;
    for (var q = 0u; q < 4u; q++) {
        let j = corners.index[q];
        let texel = texel8(j);
        let w = corners.weight[q];
        let same = abs(texel.z - near.z) * scale < 1.0;
        let texel_moves = texel.length >= HALF_PIXEL;
        var on_surface = same && !texel_moves;
        if moves {
            on_surface = same || texel_moves;
        }
        if on_surface {
            for (var g = 0u; g < colours(); g++) {
                out.a.colour.c[g] += w * colour(g, j);
            }
            out.a.share += w;
        } else {
            for (var g = 0u; g < colours(); g++) {
                out.b.colour.c[g] += w * colour(g, j);
            }
            out.b.share += w;
            if w > heaviest {
                heaviest = w;
                out.b.texel = texel;
                heaviest_pixel = j;
                have_heaviest = true;
            }
        }
    }
    if !moves {
        for (var g = 0u; g < colours(); g++) {
            out.a.colour.c[g] = out.a.share * colour(g, nearest);
        }
    }
    if out.b.texel.length < HALF_PIXEL {
        for (var g = 0u; g < colours(); g++) {
            var heaviest_colour = vec4<f32>(0.0);
            if have_heaviest {
                heaviest_colour = colour(g, heaviest_pixel);
            }
            out.b.colour.c[g] = out.b.share * heaviest_colour;
        }
    }
    return out;
}

// `matte::surfaces_of` for colour g: pixel i's coverage by the moving surface, and the RGBA
// of its moving and still surfaces, unmixed with the beauty's matte.
struct Surfaces {
    alpha: f32,
    moving: vec4<f32>,
    still: vec4<f32>,
}

fn surfaces(g: u32, i: u32) -> Surfaces {
    let m = MATTE_WORDS * i;
    let alpha = mattes[m];
    let c = colour(g, i);
    let fi = bitcast<u32>(mattes[m + 1u]);
    let bi = bitcast<u32>(mattes[m + 2u]);
    if fi == i && bi == i {
        // No pair: α is the label, and both surfaces are the colour itself.
        return Surfaces(alpha, c, c);
    }
    let f = colour(g, fi);
    let b = colour(g, bi);
    let e = vec4<f32>(mattes[m + 3u], mattes[m + 4u], mattes[m + 5u], mattes[m + 6u]);
    if texel8(i).length >= HALF_PIXEL {
        return Surfaces(alpha, c + e * (c - b), b);
    }
    return Surfaces(alpha, f, c + e * (c - f));
}

// `split_by_cover`: the exposure variant's tap split by the mattes' coverage; `valid` false
// where the CPU returns `None` (then `split` reads the tap).
struct Cover {
    parts: Split,
    valid: bool,
}

fn split_by_cover(nearest: u32, scale: f32, x: u32, y: u32, offset: vec2<f32>, steepen: bool) -> Cover {
    var out: Cover;
    out.valid = false;
    let corners = around(x, y, offset);
    // Away from every silhouette (no pixel of the four has a pair): `split` reads the tap.
    var plain = true;
    for (var q = 0u; q < 4u; q++) {
        let j = corners.index[q];
        let m = MATTE_WORDS * j;
        if bitcast<u32>(mattes[m + 1u]) != j || bitcast<u32>(mattes[m + 2u]) != j {
            plain = false;
        }
    }
    if plain {
        return out;
    }
    let near = texel8(nearest);
    let moves = near.length >= HALF_PIXEL;
    var still_z = near.z;
    var have_still = !moves;
    for (var q = 0u; q < 4u; q++) {
        let t = texel8(corners.index[q]);
        if t.length < HALF_PIXEL {
            if !have_still {
                still_z = t.z;
                have_still = true;
            } else if abs(t.z - still_z) * scale >= 1.0 {
                return out;
            }
        }
    }
    var moving: Part;
    var still: Part;
    var share_m = 0.0;
    var share_s = 0.0;
    var heavy_m = 0.0;
    var heavy_s = -1.0;
    // The still part's colours (RGBA of each), from the heaviest still contributor, as the
    // loop meets it (the CPU's `still_colour`).
    var still_colour: Colours;
    // The least and greatest coverage of the pixels the tap weighs.
    var least = 1.0;
    var most = 0.0;
    for (var q = 0u; q < 4u; q++) {
        let j = corners.index[q];
        let w = corners.weight[q];
        let t = texel8(j);
        let m = MATTE_WORDS * j;
        let alpha = mattes[m];
        if w > 0.0 {
            least = min(least, alpha);
            most = max(most, alpha);
        }
        let w_m = w * alpha;
        let w_s = w * (1.0 - alpha);
        let t_moves = t.length >= HALF_PIXEL;
        var fg_texel = t;
        var bg_index = j;
        if t_moves {
            bg_index = bitcast<u32>(mattes[m + 2u]);
        } else {
            fg_texel = texel8(bitcast<u32>(mattes[m + 1u]));
        }
        let heavier = w_s > heavy_s;
        for (var g = 0u; g < colours(); g++) {
            let s = surfaces(g, j);
            moving.colour.c[g] += w_m * s.moving;
            if heavier {
                still_colour.c[g] = s.still;
            }
        }
        share_m += w_m;
        share_s += w_s;
        if w_m > heavy_m && fg_texel.length >= HALF_PIXEL {
            heavy_m = w_m;
            moving.texel = fg_texel;
        }
        if heavier {
            heavy_s = w_s;
            still.texel = texel8(bg_index);
        }
    }
    // A centre off the moving surface (still, or covered under half): the coverage
    // steepened about its half level, never past the coverages the tap reads (see the CPU
    // twin).
    let total = share_m + share_s;
    if steepen && share_m > 0.0 && share_s > 0.0 {
        let cover = share_m / total;
        let steeper = min(max((cover - 0.5) * COVER_SLOPE + 0.5, least), most);
        let factor = steeper / cover;
        for (var g = 0u; g < colours(); g++) {
            moving.colour.c[g] *= factor;
        }
        share_m = steeper * total;
        share_s = (1.0 - steeper) * total;
    }
    if heavy_m == 0.0 {
        share_s += share_m;
        share_m = 0.0;
        moving = Part();
    }
    if !moves {
        for (var g = 0u; g < colours(); g++) {
            still_colour.c[g] = surfaces(g, nearest).still;
        }
        still.texel = near;
    }
    for (var g = 0u; g < colours(); g++) {
        still.colour.c[g] = share_s * still_colour.c[g];
    }
    moving.share = share_m;
    still.share = share_s;
    out.valid = true;
    if moves {
        out.parts = Split(moving, still);
    } else {
        out.parts = Split(still, moving);
    }
    return out;
}
