//! unmix — the colour-line model the matte ([`super::matte`]) fits and unmixes with: where a
//! pixel's colour projects on the line between a moving and a still colour ([`fit`], and
//! [`fits`] against several still colours at once), and how far its own surface's colour is
//! extrapolated from its partner's ([`extrapolation`]); [`over_empty`] says where alpha
//! measures coverage itself.

use super::config::Texel2014;

/// The most candidates of each kind a pixel's pairs are taken from (so at most 64 pairs a
/// pixel, whatever the frame: a frame of noise, every pixel a silhouette, costs a bounded
/// multiple of a clean one).
pub const CANDIDATES: usize = 8;

/// Whether a pair's still colour `b` is empty space (colour and alpha 0: a view layer's pixels
/// beside its surface) and its moving colour `f` is not: there a pixel's alpha is its
/// coverage, measured where the frame was rendered, and the fit's α is that coverage (alpha is
/// a channel of the fit), so the label's half bounds neither α nor the unmixing. A pixel of
/// alpha 0 that holds light (an additive glow, written with no coverage) is not empty: its
/// alpha says nothing of coverage.
#[inline]
pub fn over_empty(f: &Texel2014, b: &Texel2014) -> bool {
    transparent(b) && f[3] > 0.0
}

/// Whether a texel's colour and alpha are all 0: what a view layer does not cover (with no
/// motion, empty space: [`over_empty`]'s still partner, `classify::empty`).
#[inline]
pub fn transparent(t: &Texel2014) -> bool {
    t[..4].iter().all(|&v| v == 0.0)
}

/// How far a pixel of colour `c` with coverage α by the moving surface (pair `f` moving, `b`
/// still) extrapolates its own surface's colour from its partner's through its own, channel
/// by channel (R, G, B and A): a moving pixel's surface is `c + e·(c − b)`, a still one's
/// `c + e·(c − f)`, with `e` the unmixing's (1 − α)/α or α/(1 − α) (at most 1: α ≥ ½ on a
/// moving pixel, ≤ ½ on a still one; over empty space, [`over_empty`], α is not bounded by
/// the label and neither is `e`). A pair explains the colour only within its residual,
/// so each channel's `e` is cut to the most that keeps it within the three colours' range
/// (the clamp of the unmixed colour, as a factor): every output stays within its inputs'
/// range, as the gather's convex weights promise, and the same factors applied to a light
/// layer's colours are linear in them. Finite and not negative whatever the colours (at most 1
/// but over empty space).
pub fn extrapolation(
    c: &Texel2014,
    f: &Texel2014,
    b: &Texel2014,
    alpha: f32,
    moving: bool,
) -> [f32; 4] {
    let (partner, most) = if moving {
        (b, (1.0 - alpha) / alpha)
    } else {
        (f, alpha / (1.0 - alpha))
    };
    let cap = if over_empty(f, b) { f32::MAX } else { 1.0 };
    [0, 1, 2, 3].map(|ch| {
        let low = c[ch].min(f[ch]).min(b[ch]);
        let high = c[ch].max(f[ch]).max(b[ch]);
        let d = c[ch] - partner[ch];
        let room = if d > 0.0 {
            (high - c[ch]) / d
        } else if d < 0.0 {
            (low - c[ch]) / d
        } else {
            most
        };
        // (A NaN room, from colours near the numeric policy's bound, gives no extrapolation.)
        let e = if room.is_nan() { 0.0 } else { most.min(room) };
        if e.is_finite() {
            e.clamp(0.0, cap)
        } else {
            0.0
        }
    })
}

/// Where colour `c` projects on the line from `b` (α 0) to `f` (α 1), clamped to [0, 1]; the
/// squared distance from `c` to that point; and the squared distance between `f` and `b`, all
/// in RGBA, alpha's term added last. Where the three alphas are equal (an opaque frame) its
/// terms are zero and every number keeps the bits of R, G and B's alone: a zero added to a
/// sum of squares changes nothing, and alpha's term in the projection is added only where it
/// is not zero (+0 added to a −0 would flip its sign). Non-finite sums (colours near the
/// numeric policy's bound) give a NaN residual, which no test passes.
#[inline]
pub fn fit(c: &Texel2014, f: &Texel2014, b: &Texel2014) -> (f32, f32, f32) {
    let d = [f[0] - b[0], f[1] - b[1], f[2] - b[2], f[3] - b[3]];
    let e = [c[0] - b[0], c[1] - b[1], c[2] - b[2], c[3] - b[3]];
    let spread = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3];
    let mut along = e[0] * d[0] + e[1] * d[1] + e[2] * d[2];
    if e[3] * d[3] != 0.0 {
        along += e[3] * d[3];
    }
    let alpha = (along / spread).clamp(0.0, 1.0);
    let r = [
        e[0] - alpha * d[0],
        e[1] - alpha * d[1],
        e[2] - alpha * d[2],
        e[3] - alpha * d[3],
    ];
    let residual = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3];
    (alpha, residual, spread)
}

/// [`fit`] of colour `c` between the moving colour `f` and each of [`CANDIDATES`] still colours
/// at once (`b[channel][candidate]`): each candidate's α, residual and spread, the same
/// operations in the same order as [`fit`]'s, so the same bits, in lanes (on a frame of noise,
/// every pixel a silhouette, the pairs' fits were most of the matte).
#[multiversion::multiversion(targets("x86_64+avx2"))]
pub(crate) fn fits(
    c: &[f32; 4],
    f: &[f32; 4],
    b: &[[f32; CANDIDATES]; 4],
) -> [[f32; CANDIDATES]; 3] {
    let mut out = [[0.0f32; CANDIDATES]; 3];
    for l in 0..CANDIDATES {
        let d = [
            f[0] - b[0][l],
            f[1] - b[1][l],
            f[2] - b[2][l],
            f[3] - b[3][l],
        ];
        let e = [
            c[0] - b[0][l],
            c[1] - b[1][l],
            c[2] - b[2][l],
            c[3] - b[3][l],
        ];
        let spread = d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + d[3] * d[3];
        let along = e[0] * d[0] + e[1] * d[1] + e[2] * d[2];
        let last = e[3] * d[3];
        let along = if last != 0.0 { along + last } else { along };
        let alpha = (along / spread).clamp(0.0, 1.0);
        let r = [
            e[0] - alpha * d[0],
            e[1] - alpha * d[1],
            e[2] - alpha * d[2],
            e[3] - alpha * d[3],
        ];
        out[0][l] = alpha;
        out[1][l] = r[0] * r[0] + r[1] * r[1] + r[2] * r[2] + r[3] * r[3];
        out[2][l] = spread;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fits_in_lanes_are_fit_s_bits() {
        // Colours of every sign and scale, alphas equal (an opaque frame: alpha's term zero,
        // not added) and not, signed zeros, and values past the numeric policy's bound (NaN
        // residuals): each lane the bits `fit` gives its pair.
        let values = [
            0.0, -0.0, 1.0, 0.25, -0.7, 3.5, 1e-20, 2e19, 0.333, 1.0, 0.5, -2.0, 7e-3, 1e30,
        ];
        let colour = |k: usize| -> Texel2014 {
            let v = |n: usize| values[(k * 7 + n * 3) % values.len()];
            [
                v(0),
                v(1),
                v(2),
                if k.is_multiple_of(3) { 1.0 } else { v(3) },
                1.0,
                0.0,
                0.0,
                0.0,
            ]
        };
        let mut checked = 0;
        for ci in 0..40 {
            for fi in 0..40 {
                let (c, f) = (colour(ci), colour(fi + 5));
                let mut lanes = [[0.0f32; CANDIDATES]; 4];
                let stills: Vec<Texel2014> = (0..CANDIDATES).map(|l| colour(ci + fi + l)).collect();
                for (l, b) in stills.iter().enumerate() {
                    for ch in 0..4 {
                        lanes[ch][l] = b[ch];
                    }
                }
                let got = fits(&[c[0], c[1], c[2], c[3]], &[f[0], f[1], f[2], f[3]], &lanes);
                for (l, b) in stills.iter().enumerate() {
                    let (alpha, residual, spread) = fit(&c, &f, b);
                    let want = [alpha, residual, spread].map(f32::to_bits);
                    assert_eq!([got[0][l], got[1][l], got[2][l]].map(f32::to_bits), want);
                    checked += 1;
                }
            }
        }
        assert_eq!(checked, 40 * 40 * CANDIDATES);
    }
}
