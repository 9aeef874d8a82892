// The curves scatter draws, the twin of src/motion/curve.rs: the quadratic Bézier through
// p(−1), p(0), p(+1) and the circular arc where the motion turns, with the segment counts that
// keep them within the flatness tolerance. Part of scatter's shader (`SHADER` in scatter.rs:
// the prelude, scatter.wgsl, then this).

struct Bezier {
    b0: vec2<f32>,
    b1: vec2<f32>,
    b2: vec2<f32>,
}

fn bezier_through(p: vec2<f32>, now: vec2<f32>, q: vec2<f32>) -> Bezier {
    return Bezier(p, 2.0 * now - 0.5 * (p + q), q);
}

fn bezier_at(b: Bezier, s: f32) -> vec2<f32> {
    let u = (1.0 - s) * (1.0 - s);
    let v = 2.0 * (1.0 - s) * s;
    let w = s * s;
    return vec2<f32>(
        u * b.b0.x + v * b.b1.x + w * b.b2.x,
        u * b.b0.y + v * b.b1.y + w * b.b2.y,
    );
}

fn bend_squared(b: Bezier) -> f32 {
    let x = b.b0.x - 2.0 * b.b1.x + b.b2.x;
    let y = b.b0.y - 2.0 * b.b1.y + b.b2.y;
    return 4.0 * (x * x + y * y);
}

// `Bezier::segments`.
fn bezier_segments(b: Bezier, span: f32, tolerance: f32, most: u32) -> u32 {
    if tolerance <= 0.0 {
        return max(most, 1u);
    }
    let limit = 8.0 * tolerance;
    let fourth = span * span * span * span * bend_squared(b);
    if fourth <= limit * limit {
        return 1u;
    }
    let needed = ceil(span * sqrt(sqrt(bend_squared(b)) / limit));
    if is_finite(needed) {
        return clamp(u32(needed), 1u, max(most, 1u));
    }
    return max(most, 1u);
}

// The circle through the three positions with the angle quadratic in time (`Arc`). Its
// points are kept relative to p(0) in chord form (see `arc_at`), so `centre` is relative to
// p(0) too.
struct Arc {
    ok: bool,
    centre: vec2<f32>,
    radius: f32,
    theta: f32,
    omega: f32,
    alpha: f32,
}

fn rem_euclid(x: f32, m: f32) -> f32 {
    let r = x - m * trunc(x / m);
    if r < 0.0 {
        return r + m;
    }
    return r;
}

// `Arc::fit`, with `now` = p(0) and the centre relative to it.
fn arc_fit(p: vec2<f32>, now: vec2<f32>, q: vec2<f32>) -> Arc {
    var arc = Arc(false, vec2<f32>(0.0), 0.0, 0.0, 0.0, 0.0);
    let a = now - p;
    let b = q - now;
    let turn = cross2(a, b);
    let la = length2(a);
    let lb = length2(b);
    if !(la > 0.0 && lb > 0.0 && abs(turn) > COLLINEAR * la * lb) {
        return arc;
    }
    let pr = p - now;
    let qr = q - now;
    let d = 2.0 * cross2(pr, qr);
    let pp = pr.x * pr.x + pr.y * pr.y;
    let qq = qr.x * qr.x + qr.y * qr.y;
    let offset = vec2<f32>((qr.y * pp - pr.y * qq) / d, (pr.x * qq - qr.x * pp) / d);
    let radius = length2(offset);
    if !(is_finite(radius) && radius < LARGEST_RADIUS) {
        return arc;
    }
    // The angle of p(0) about the centre, and the angles from it to p(+1) and p(−1): the
    // CPU's differences of absolute angles, each taken at once from the two vectors, u from
    // the centre to p(0) and w to the other point (atan2 of their cross and dot products,
    // formed without the cancellation of u × w for a radius of up to 10⁷ px).
    let theta = atan2(-offset.y, -offset.x);
    let radius2 = offset.x * offset.x + offset.y * offset.y;
    let to_next = atan2(cross2(qr, offset), radius2 - dot(offset, qr));
    let to_prev = atan2(cross2(pr, offset), radius2 - dot(offset, pr));
    var ahead: f32;
    var behind: f32;
    if turn > 0.0 {
        ahead = rem_euclid(to_next, TAU);
        behind = -rem_euclid(-to_prev, TAU);
    } else {
        ahead = -rem_euclid(-to_next, TAU);
        behind = rem_euclid(to_prev, TAU);
    }
    arc.ok = true;
    arc.centre = offset;
    arc.radius = radius;
    arc.theta = theta;
    arc.omega = 0.5 * (ahead - behind);
    arc.alpha = 0.5 * (ahead + behind);
    return arc;
}

// The angle turned since the frame's instant, t·(ω + t·α) (`Arc::angle` less θ).
fn arc_turn(arc: Arc, t: f32) -> f32 {
    return t * (arc.omega + t * arc.alpha);
}

// `Arc::at_time` less p(0), in chord form: the centre plus r·(cos, sin)(θ + δ) minus p(0)
// (which is the centre plus r·(cos, sin)θ) is 2r·sin(δ/2)·(−sin, cos)(θ + δ/2). The CPU's
// form subtracts two numbers of the radius's size (up to 10⁷ px): in f32 that would leave
// whole pixels of error, the chord form leaves a rounding of the chord.
fn arc_at(arc: Arc, t: f32) -> vec2<f32> {
    let delta = arc_turn(arc, t);
    let chord = 2.0 * arc.radius * sin(0.5 * delta);
    let middle = arc.theta + 0.5 * delta;
    return vec2<f32>(-chord * sin(middle), chord * cos(middle));
}

// `Arc::segments`, on the turn δ (the sweep does not depend on θ).
fn arc_segments(arc: Arc, t0: f32, t1: f32, tolerance: f32, most: u32) -> u32 {
    if tolerance <= 0.0 {
        return max(most, 1u);
    }
    var lo = min(arc_turn(arc, t0), arc_turn(arc, t1));
    var hi = max(arc_turn(arc, t0), arc_turn(arc, t1));
    if arc.alpha != 0.0 {
        let vertex = -arc.omega / (2.0 * arc.alpha);
        if vertex > t0 && vertex < t1 {
            lo = min(lo, arc_turn(arc, vertex));
            hi = max(hi, arc_turn(arc, vertex));
        }
    }
    let sweep = min(hi - lo, 2.0 * PI * 4.0);
    let needed = ceil(sweep * sqrt(arc.radius / (8.0 * tolerance)));
    if is_finite(needed) {
        return clamp(u32(needed), 1u, max(most, 1u));
    }
    return max(most, 1u);
}

