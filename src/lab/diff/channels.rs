//! Every channel of two frames compared (issue 31): the beauty's R, G, B and alpha, every
//! light layer and every data layer the colour file holds, matched by name.
//!
//! In: the two frames as read with every channel ([`crate::io::passes::FramePlan::read_every_channel`])
//! and the per-pixel gates. Out: per layer figures (RMSE, mean absolute error, the largest
//! difference with its pixel, channel and both values, pixels over the gates), the figures
//! over every channel as `idiff` gives them (mean error, RMS error, PSNR with its peak, max
//! error), the pixels over each gate, and the channels only one side holds.
//!
//! Colour channels (the beauty and light layers) are gated by `--fail-pixel`/`--warn-pixel`;
//! data channels (depth, vectors, normals, IDs) by `--data-fail-pixel`/`--data-warn-pixel`,
//! whose 0 means exact. A sample fails a gate when its absolute difference is over the
//! threshold and over the relative threshold times the mean of the two magnitudes (idiff's
//! `-failrelative`). A non-finite sample in a colour channel fails every gate; in a data
//! channel only where the two sides differ (an infinite depth behind everything, written
//! alike in both, is not a change).

use serde::Serialize;

use crate::frame::{Frame, LayerClass};

/// The largest difference in one channel between two images, where it is and both values.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct Largest {
    pub error: f64,
    /// The pixel, in the file's coordinates (the data window's origin added, as `idiff`
    /// gives it).
    pub x: i64,
    pub y: i64,
    /// The channel's name as the file stores it.
    pub channel: String,
    /// The reference's value there, and the tested image's.
    pub a: f64,
    pub b: f64,
    /// Whether `a` or `b` is a u32 channel's value, compared as stored: printed exactly (an
    /// f32 rounds them over 2²⁴: 16777217 would print 16777216).
    #[serde(skip)]
    pub integer: bool,
}

impl Largest {
    /// `a` or `b` as text: beside a u32 channel's value, each as the number it is (an integer
    /// prints as one); a float channel's as the shortest text that reads back as its f32.
    pub fn value_text(&self, value: f64) -> String {
        if self.integer {
            format!("{value}")
        } else {
            format!("{}", value as f32)
        }
    }
}

/// The per-pixel gates.
#[derive(Clone, Copy, Debug, Default)]
pub struct Gates {
    pub fail: Option<f64>,
    pub warn: Option<f64>,
    pub data_fail: Option<f64>,
    pub data_warn: Option<f64>,
    /// Relative thresholds (a fraction of the mean magnitude of the two values); 0: none.
    pub fail_relative: f64,
    pub warn_relative: f64,
    /// No sample may differ by more than this, whatever the allowances.
    pub hard_fail: Option<f64>,
    /// Non-finite samples fail no gate (they are still counted).
    pub allow_nonfinite: bool,
}

impl Gates {
    fn of(&self, class: LayerClass) -> (Option<f64>, Option<f64>) {
        match class {
            LayerClass::Colour => (self.fail, self.warn),
            LayerClass::Data | LayerClass::Motion => (self.data_fail, self.data_warn),
        }
    }
}

/// One layer's figures (the beauty's is named `beauty`; a channel of no layer, such as `Z`,
/// is its own layer).
#[derive(Clone, Debug, Serialize)]
pub struct LayerDiff {
    pub layer: String,
    pub class: &'static str,
    pub channels: Vec<String>,
    pub rmse: f64,
    pub mae: f64,
    /// The largest difference of one sample, where and what (infinite at the first sample
    /// that became NaN or infinite, or stopped being so, where one counts).
    pub largest: Largest,
    /// Samples non-finite in either side (for data layers: where the two differ).
    pub non_finite: usize,
    pub pixels_over_fail: usize,
    pub pixels_over_warn: usize,
}

/// The figures over every channel compared, defined as OpenImageIO's `idiff` defines them.
#[derive(Clone, Debug, Default, Serialize)]
pub struct EveryChannel {
    pub channels: usize,
    /// Mean absolute difference over every sample.
    pub mean_error: f64,
    pub rms_error: f64,
    /// `20 log10(peak / rms_error)`; the peak is the largest magnitude in either image, and
    /// at least 1.0 (idiff's).
    pub psnr: f64,
    pub psnr_peak: f64,
    pub max_error: Largest,
}

/// The outcome of comparing every channel of one frame.
#[derive(Clone, Debug, Default)]
pub struct Compared {
    /// The beauty first, then the other layers in the reference's order.
    pub layers: Vec<LayerDiff>,
    pub every: EveryChannel,
    /// Pixels where any channel fails (warns): over its class's threshold.
    pub pixels_over_fail: usize,
    pub pixels_over_warn: usize,
    /// Samples over `--hard-fail` (non-finite ones included).
    pub over_hard: usize,
    /// Non-finite samples that count (every layer's).
    pub non_finite: usize,
    /// Of those, the ones not alike in both images (a value that became or stopped being NaN
    /// or infinite, or an infinity of the other sign): what `--allow-nonfinite` still fails.
    pub non_finite_changed: usize,
    /// Per pixel, the largest difference of any channel (+∞ where a counted sample is
    /// non-finite).
    pub errors: Vec<f32>,
    /// Channels of the reference the candidate lacks, and the reverse.
    pub missing: Vec<String>,
    pub extra: Vec<String>,
    /// The channels only the candidate has that hold a NaN (or, in a colour channel, an
    /// infinity), with how many: counted in `non_finite`.
    pub extra_non_finite: Vec<(String, usize)>,
    /// Channels stored as u32 on one side and as float on the other (compared all the same).
    pub retyped: Vec<String>,
}

impl Compared {
    /// Whether every channel both frames hold is the same (NaN and infinities alike in
    /// both) and neither holds a channel the other lacks.
    pub fn identical(&self) -> bool {
        self.every.rms_error == 0.0
            && self.non_finite_changed == 0
            && self.missing.is_empty()
            && self.extra.is_empty()
    }
}

/// The beauty's layer name in the figures: no channel's layer is named so (a channel name
/// holds no brackets in any renderer's output; a layer named `beauty` stays its own).
pub const BEAUTY: &str = "[beauty]";

/// One channel of both sides.
struct Pair<'a> {
    name: String,
    layer: String,
    class: LayerClass,
    a: &'a [f32],
    b: &'a [f32],
    /// Each side's u32 values as stored, where it reads them exactly (IDs): compared as they
    /// are, not through f32, which rounds over 2²⁴ (against the other side's float where
    /// only one is u32).
    exact: (Option<&'a [u32]>, Option<&'a [u32]>),
}

/// The channels only one side holds: the reference's (lost: a failure), the candidate's
/// with their index among its carried channels (none for the beauty's), and the beauty's
/// the candidate gained.
type OneSided = (Vec<String>, Vec<(String, usize)>, Vec<String>);

/// The channels to compare, grouped by layer in the reference's order, and the names only
/// one side holds. The beauty's alpha the reference lacks reads as 1 (opaque) and is
/// compared so; the reference's alpha the candidate lacks is lost, as are its R, G and B
/// where the candidate's are read from a luminance Y.
fn pairs<'a>(a: &'a Frame, b: &'a Frame, ones: &'a [f32]) -> (Vec<Pair<'a>>, OneSided) {
    let mut out = Vec::new();
    let (mut lost, mut gained) = (Vec::new(), Vec::new());
    let names = |f: &Frame| -> Vec<String> {
        if f.carried.beauty.is_empty() {
            ["R", "G", "B", "A"].map(String::from).to_vec()
        } else {
            f.carried.beauty.clone()
        }
    };
    if let (Some(ca), Some(cb)) = (&a.color, &b.color) {
        let (pa, pb) = (ca.planes(), cb.planes());
        let (na, nb) = (names(a), names(b));
        let name_of = |names: &[String], c: usize| {
            names
                .get(c)
                .cloned()
                .unwrap_or_else(|| "RGBA"[c..c + 1].to_string())
        };
        // A channel's own name, past its layer's (`R` of `rgba.R`).
        let leaf = |name: String| name.rsplit('.').next().unwrap_or_default().to_string();
        for c in 0..4 {
            let (x, y) = (pa.get(c).copied(), pb.get(c).copied());
            if c == 3 && x.is_none() && y.is_none() {
                continue;
            }
            let name = name_of(&na, c);
            if c == 3 && y.is_none() {
                lost.push(name);
                continue;
            }
            if c == 3 && x.is_none() {
                gained.push(name_of(&nb, c));
            } else if leaf(name_of(&nb, c)) == "Y" && leaf(name.clone()) != "Y" {
                // The candidate's grey read from its luminance, where the reference has
                // colour (the reverse, a luminance golden of a grey candidate, is warned as
                // the read's own warning).
                lost.push(name.clone());
            }
            out.push(Pair {
                name,
                layer: BEAUTY.to_string(),
                class: LayerClass::Colour,
                a: x.unwrap_or(ones),
                b: y.unwrap_or(ones),
                exact: (None, None),
            });
        }
    }
    // A channel of a named part of a multi-part file is `part.channel`, as the read and
    // `shutter info` name it, so parts are matched by name, not by their order. A channel
    // found so on neither side is then matched by its own name (layer-qualified, as stored),
    // where that name is one channel's on each side: a channel keeps its full name in any
    // part (OpenEXR's part helper), so `Z` moved to a part of data (a DWA output's) or a
    // single-part file's `diffuse.R` written into a part `rgba` is the same channel.
    let key = |f: &Frame, i: usize| {
        let c = &f.carried.channels[i];
        let part = (f.carried.headers.len() > 1)
            .then(|| f.carried.headers.get(c.part))
            .flatten()
            .and_then(|h| h.own_attributes.layer_name.as_ref())
            .map(crate::io::channels::name_of);
        match part {
            Some(part) if !c.name.starts_with(&format!("{part}.")) => format!("{part}.{}", c.name),
            _ => c.name.clone(),
        }
    };
    let keys_a: Vec<String> = (0..a.carried.channels.len()).map(|i| key(a, i)).collect();
    let keys_b: Vec<String> = (0..b.carried.channels.len()).map(|i| key(b, i)).collect();
    let mut found: Vec<Option<usize>> = keys_a
        .iter()
        .map(|k| keys_b.iter().position(|kb| kb == k))
        .collect();
    let mut matched = vec![false; keys_b.len()];
    found.iter().flatten().for_each(|&j| matched[j] = true);
    let name_a = |i: usize| &a.carried.channels[i].name;
    let name_b = |j: usize| &b.carried.channels[j].name;
    for i in 0..keys_a.len() {
        if found[i].is_some() {
            continue;
        }
        let alone_in_a = (0..keys_a.len())
            .filter(|&k| found[k].is_none() && name_a(k) == name_a(i))
            .count()
            == 1;
        let mut in_b = (0..keys_b.len()).filter(|&j| !matched[j] && name_b(j) == name_a(i));
        if let (true, Some(j), None) = (alone_in_a, in_b.next(), in_b.next()) {
            found[i] = Some(j);
            matched[j] = true;
        }
    }
    let mut missing = lost;
    for (i, channel) in a.carried.channels.iter().enumerate() {
        let name = keys_a[i].clone();
        match found[i] {
            Some(j) => {
                let layer = crate::io::channels::split(&name).0;
                out.push(Pair {
                    layer: if layer.is_empty() {
                        name.clone()
                    } else {
                        layer.to_string()
                    },
                    name,
                    class: channel.class,
                    a: &channel.plane,
                    b: &b.carried.channels[j].plane,
                    exact: (
                        channel.exact.as_deref(),
                        b.carried.channels[j].exact.as_deref(),
                    ),
                });
            }
            None => missing.push(name),
        }
    }
    let extra = keys_b
        .into_iter()
        .zip(matched)
        .enumerate()
        .filter(|(_, (_, m))| !m)
        .map(|(j, (k, _))| (k, j))
        .collect();
    // Group by layer, keeping the order in which layers first appear.
    let mut order: Vec<String> = Vec::new();
    for p in &out {
        if !order.contains(&p.layer) {
            order.push(p.layer.clone());
        }
    }
    out.sort_by_key(|p| order.iter().position(|l| *l == p.layer));
    (out, (missing, extra, gained))
}

/// Whether a sample's difference `d` (of values `x`, `y`) is over `threshold` and over
/// `relative` times the mean of their magnitudes.
fn over(d: f64, x: f64, y: f64, threshold: f64, relative: f64) -> bool {
    d > threshold && d > relative * (x.abs() + y.abs()) / 2.0
}

/// Compares every channel the two frames share (same size: checked before).
pub fn compare(a: &Frame, b: &Frame, gates: &Gates) -> Compared {
    let n = a.width * a.height;
    let ones = vec![1.0f32; n];
    let (pairs, (missing, extra, gained)) = pairs(a, b, &ones);
    // A channel only the candidate has is not compared, but a NaN in it (or an infinity in
    // a colour channel: an infinite depth is a depth) is the candidate's fault all the same.
    let extra_non_finite: Vec<(String, usize)> = extra
        .iter()
        .filter_map(|(name, j)| {
            let c = &b.carried.channels[*j];
            let data = c.class.is_data();
            let bad = c
                .plane
                .iter()
                .filter(|v| v.is_nan() || (!data && v.is_infinite()))
                .count();
            (c.exact.is_none() && bad > 0).then(|| (name.clone(), bad))
        })
        .collect();
    let extra: Vec<String> = gained
        .into_iter()
        .chain(extra.into_iter().map(|(name, _)| name))
        .collect();
    // Channels stored as u32 on one side and as float on the other: compared, and named.
    let retyped: Vec<String> = pairs
        .iter()
        .filter(|p| p.exact.0.is_some() != p.exact.1.is_some())
        .map(|p| p.name.clone())
        .collect();
    let (ox, oy) = a.windows.data_origin;
    // Per pixel: bit 0 fails, bit 1 warns (any layer).
    let mut flags = vec![0u8; n];
    let mut errors = vec![0.0f32; n];
    let mut layer_flags = vec![0u8; n];
    let mut layers: Vec<LayerDiff> = Vec::new();
    let (mut sum_abs, mut sum_sq, mut peak, mut samples) = (0.0f64, 0.0f64, 1.0f64, 0usize);
    let mut every_largest = Largest::default();
    let mut over_hard = 0;
    let mut non_finite_total = 0;
    let mut non_finite_changed = 0;
    let mut start = 0;
    while start < pairs.len() {
        let layer = &pairs[start].layer;
        let end = start
            + pairs[start..]
                .iter()
                .take_while(|p| &p.layer == layer)
                .count();
        let group = &pairs[start..end];
        layer_flags.iter_mut().for_each(|f| *f = 0);
        let (mut l_abs, mut l_sq, mut l_non_finite) = (0.0f64, 0.0f64, 0usize);
        let mut l_largest = Largest::default();
        for pair in group {
            let (fail, warn) = gates.of(pair.class);
            let data = pair.class.is_data();
            for i in 0..n {
                let (x, y) = (pair.a[i], pair.b[i]);
                let (ea, eb) = (
                    pair.exact.0.map(|e| e[i] as f64),
                    pair.exact.1.map(|e| e[i] as f64),
                );
                let finite = (ea.is_some() || x.is_finite()) && (eb.is_some() || y.is_finite());
                let (px, py) = (
                    (i % a.width.max(1)) as i64 + ox as i64,
                    (i / a.width.max(1)) as i64 + oy as i64,
                );
                if !finite {
                    // An infinity written alike in both is no change in a data channel (a
                    // depth of the sky); a NaN never is, in either image.
                    let alike = x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
                    if data && alike && !x.is_nan() {
                        continue;
                    }
                    l_non_finite += 1;
                    // `--allow-nonfinite` lets through what is alike in both; a value that
                    // became NaN or infinite (or stopped being so) differs from it by more
                    // than any gate, whatever the allowances.
                    non_finite_changed += usize::from(!alike);
                    if !gates.allow_nonfinite || !alike {
                        // The first such sample is the largest difference (an infinite one:
                        // `null` in JSON), so the report names where a value went bad.
                        if l_largest.error.is_finite() {
                            l_largest = Largest {
                                error: f64::INFINITY,
                                x: px,
                                y: py,
                                channel: pair.name.clone(),
                                a: x as f64,
                                b: y as f64,
                                integer: false,
                            };
                        }
                        errors[i] = f32::INFINITY;
                        layer_flags[i] |=
                            u8::from(fail.is_some()) | (u8::from(warn.is_some()) << 1);
                        if gates.hard_fail.is_some() {
                            over_hard += 1;
                        }
                    }
                    continue;
                }
                let (x, y) = (ea.unwrap_or(x as f64), eb.unwrap_or(y as f64));
                let d = (x - y).abs();
                errors[i] = errors[i].max(d as f32);
                l_abs += d;
                l_sq += d * d;
                peak = peak.max(x.abs()).max(y.abs());
                if fail.is_some_and(|t| over(d, x, y, t, gates.fail_relative)) {
                    layer_flags[i] |= 1;
                }
                if warn.is_some_and(|t| over(d, x, y, t, gates.warn_relative)) {
                    layer_flags[i] |= 2;
                }
                if gates.hard_fail.is_some_and(|h| d > h) {
                    over_hard += 1;
                }
                // Ties go to the first pixel in reading order (then the first channel of
                // the layer in the file's order).
                let better = |best: &Largest| {
                    d > best.error || (d == best.error && d > 0.0 && (py, px) < (best.y, best.x))
                };
                if better(&l_largest) {
                    l_largest = Largest {
                        error: d,
                        x: px,
                        y: py,
                        channel: pair.name.clone(),
                        a: x,
                        b: y,
                        integer: pair.exact.0.is_some() || pair.exact.1.is_some(),
                    };
                }
            }
        }
        if l_largest.error > every_largest.error
            || (l_largest.error == every_largest.error
                && l_largest.error > 0.0
                && (l_largest.y, l_largest.x) < (every_largest.y, every_largest.x))
        {
            every_largest = l_largest.clone();
        }
        let count = (group.len() * n).max(1) as f64;
        sum_abs += l_abs;
        sum_sq += l_sq;
        samples += group.len() * n;
        non_finite_total += l_non_finite;
        let mut l_fail = 0;
        let mut l_warn = 0;
        for (f, l) in flags.iter_mut().zip(&layer_flags) {
            *f |= l;
            l_fail += usize::from(l & 1 != 0);
            l_warn += usize::from(l & 2 != 0);
        }
        layers.push(LayerDiff {
            layer: layer.clone(),
            class: group[0].class.name(),
            channels: group.iter().map(|p| p.name.clone()).collect(),
            rmse: (l_sq / count).sqrt(),
            mae: l_abs / count,
            largest: l_largest,
            non_finite: l_non_finite,
            pixels_over_fail: l_fail,
            pixels_over_warn: l_warn,
        });
        start = end;
    }
    let samples_f = samples.max(1) as f64;
    let rms_error = (sum_sq / samples_f).sqrt();
    Compared {
        every: EveryChannel {
            channels: pairs.len(),
            mean_error: sum_abs / samples_f,
            rms_error,
            psnr: if rms_error == 0.0 {
                f64::INFINITY
            } else {
                20.0 * (peak / rms_error).log10()
            },
            psnr_peak: peak,
            max_error: every_largest,
        },
        pixels_over_fail: flags.iter().filter(|&&f| f & 1 != 0).count(),
        pixels_over_warn: flags.iter().filter(|&&f| f & 2 != 0).count(),
        over_hard,
        non_finite: non_finite_total + extra_non_finite.iter().map(|(_, n)| n).sum::<usize>(),
        // A NaN in a channel the reference lacks is alike in nothing.
        non_finite_changed: non_finite_changed
            + extra_non_finite.iter().map(|(_, n)| n).sum::<usize>(),
        layers,
        errors,
        missing,
        extra,
        extra_non_finite,
        retyped,
    }
}
