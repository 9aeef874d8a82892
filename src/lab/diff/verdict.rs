//! Each frame's verdict: why it fails (the non-finite gate, channels lost, the hard, metric
//! and per-pixel gates, in that order), and whether it warns by its pixels.

use super::{channels, DiffJob};

/// Why a frame fails, in words, or `None`.
pub(super) fn failure(
    job: &DiffJob,
    compared: &channels::Compared,
    value: f64,
    pixels: usize,
) -> Option<String> {
    if compared.non_finite > 0 && !job.allow_nonfinite {
        let layers: Vec<&str> = compared
            .layers
            .iter()
            .filter(|l| l.non_finite > 0)
            .map(|l| l.layer.as_str())
            .chain(compared.extra_non_finite.iter().map(|(c, _)| c.as_str()))
            .collect();
        return Some(format!(
            "{} non-finite samples in {} (NaN or infinite; --allow-nonfinite lets them through)",
            compared.non_finite,
            layers.join(", ")
        ));
    }
    // Let through, the non-finite values must be alike in both: one that became NaN or
    // infinite (or stopped being so) is a change no allowance covers.
    if compared.non_finite_changed > 0 && job.allow_nonfinite {
        let m = &compared.every.max_error;
        // The first compared sample that changed, else a channel only the candidate has.
        let first = match compared.extra_non_finite.first() {
            Some((channel, _)) if !m.error.is_infinite() => {
                format!(
                    "in {}, which the reference lacks",
                    crate::error::printable(channel)
                )
            }
            _ => format!(
                "the first at ({}, {}) {}: {} against {}",
                m.x,
                m.y,
                crate::error::printable(&m.channel),
                m.value_text(m.a),
                m.value_text(m.b)
            ),
        };
        return Some(format!(
            "{} samples became or stopped being NaN or infinite, {first} (--allow-nonfinite \
             lets through only values alike in both)",
            compared.non_finite_changed,
        ));
    }
    if !compared.missing.is_empty() {
        return Some(format!(
            "the candidate lacks {} channel{} of the reference: {}",
            compared.missing.len(),
            if compared.missing.len() == 1 { "" } else { "s" },
            compared.missing.join(", ")
        ));
    }
    if let Some(hard) = job.gates.hard_fail {
        if compared.over_hard > 0 {
            let m = &compared.every.max_error;
            return Some(format!(
                "{} samples differ by more than --hard-fail {hard} (largest {:.6} at ({}, {}) {})",
                compared.over_hard, m.error, m.x, m.y, m.channel
            ));
        }
    }
    if let Some(limit) = job.fail {
        if job.metric.exceeds(value, limit) {
            return Some(format!(
                "{} {value:.6} worse than --fail {limit}",
                job.metric.name()
            ));
        }
    }
    if job.gates.fail.is_some() || job.gates.data_fail.is_some() {
        let allowed = allowed_pixels(job, pixels);
        let over = compared.pixels_over_fail;
        if over > allowed {
            let layers: Vec<String> = compared
                .layers
                .iter()
                .filter(|l| l.pixels_over_fail > 0)
                .map(|l| format!("{} {}", l.layer, l.pixels_over_fail))
                .collect();
            return Some(format!(
                "{over} pixels over the per-pixel gate (allowed: {allowed}; by layer: {})",
                layers.join(", ")
            ));
        }
    }
    None
}

/// Whether `over` pixels of `pixels` over the per-pixel warning thresholds warn: more than
/// `warn_percent` of them, as idiff's `-warnpercent` (none by default).
pub(super) fn warns_by_pixels(job: &DiffJob, over: usize, pixels: usize) -> bool {
    over > (job.warn_percent / 100.0 * pixels as f64).floor() as usize
}

/// How many pixels of `pixels` may fail the per-pixel gate.
fn allowed_pixels(job: &DiffJob, pixels: usize) -> usize {
    job.allow_pixels
        .max((job.fail_percent / 100.0 * pixels as f64).floor() as usize)
}
