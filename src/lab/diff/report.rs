//! `shutter diff --report DIR`: one HTML page a person reads for a whole sequence — per
//! frame its verdict (pass, warn, fail), its figures, each layer's, and thumbnails of the
//! reference, the candidate and the heatmap, the worst frames first — beside `report.json`
//! (the `--json` document) in the same folder.
//!
//! In: the diff's report and, per frame, the two images (thumbnails are made while each
//! frame is compared, so nothing is read twice). Out: `DIR/index.html`, `DIR/report.json`,
//! `DIR/thumbs/*.png`, each written atomically. The page is self-contained: no script, no
//! network, relative image links, so it opens from a CI's artefacts as it is.

use std::io::Write;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::error::{Problem, ProblemKind, Result};
use crate::lab::metrics::{self, Metric, Rgb};

use super::DiffReport;

/// The widest a thumbnail is, in pixels.
const THUMB_WIDTH: usize = 320;

/// The thumbnails of one frame, relative to the report's folder.
#[derive(Clone, Debug, Serialize)]
pub struct Thumbnails {
    pub reference: PathBuf,
    pub candidate: PathBuf,
    pub heatmap: PathBuf,
}

impl Thumbnails {
    /// The names of a frame's (and view's) thumbnails.
    pub fn of(frame: Option<i64>, view: Option<&str>) -> Thumbnails {
        let stem = frame.map_or("still".to_string(), |n| format!("{n:06}"));
        let stem = match view {
            Some(view) => format!("{stem}-{view}"),
            None => stem,
        };
        Thumbnails {
            reference: PathBuf::from(format!("thumbs/{stem}-reference.png")),
            candidate: PathBuf::from(format!("thumbs/{stem}-candidate.png")),
            heatmap: PathBuf::from(format!("thumbs/{stem}-heatmap.png")),
        }
    }

    pub fn all(&self) -> [&Path; 3] {
        [&self.reference, &self.candidate, &self.heatmap]
    }
}

/// The files [`write`] writes in the report's folder, beside the thumbnails.
pub const PAGES: [&str; 2] = ["report.json", "index.html"];

/// An interleaved 8-bit RGB image shrunk by a box filter to at most [`THUMB_WIDTH`] wide.
fn shrink(rgb: &[u8], width: usize, height: usize) -> (Vec<u8>, usize, usize) {
    let step = width.div_ceil(THUMB_WIDTH).max(1);
    let (w, h) = (width.div_ceil(step).max(1), height.div_ceil(step).max(1));
    let mut out = Vec::with_capacity(w * h * 3);
    for ty in 0..h {
        for tx in 0..w {
            let mut sum = [0u32; 3];
            let mut count = 0u32;
            for y in ty * step..((ty + 1) * step).min(height) {
                for x in tx * step..((tx + 1) * step).min(width) {
                    for (c, s) in sum.iter_mut().enumerate() {
                        *s += rgb[(y * width + x) * 3 + c] as u32;
                    }
                    count += 1;
                }
            }
            for s in sum {
                out.push((s / count.max(1)) as u8);
            }
        }
    }
    (out, w, h)
}

fn create_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir)
        .map_err(|e| Problem::new(ProblemKind::Output, dir, format!("cannot create: {e}")).into())
}

/// Writes one frame's thumbnails under `dir/thumbs`: the two images as a display shows them
/// (exposure 0, clamped, sRGB) and the heatmap of `errors`, each pixel's largest difference
/// over every channel (an AOV-only change shows), scaled to the frame's largest. Each view
/// of a multi-view frame, `view` (as in file names), has its own
/// (`thumbs/000012-left-reference.png`).
pub fn thumbnails(
    dir: &Path,
    frame: Option<i64>,
    view: Option<&str>,
    a: &Rgb,
    b: &Rgb,
    errors: &[f32],
) -> std::result::Result<Thumbnails, Problem> {
    let thumbs = dir.join("thumbs");
    create_dir(&thumbs).map_err(|e| e.problems()[0].clone())?;
    let (w, h) = (a.width, a.height);
    let max = errors
        .iter()
        .copied()
        .filter(|e| e.is_finite())
        .fold(0.0f32, f32::max)
        .max(1e-12);
    let map: Vec<f32> = errors
        .iter()
        .map(|&e| if e.is_finite() { e / max } else { 1.0 })
        .collect();
    let heat = super::magma(&map);
    let names = Thumbnails::of(frame, view);
    for (name, rgb) in [
        (&names.reference, metrics::display_rgb8(a)),
        (&names.candidate, metrics::display_rgb8(b)),
        (&names.heatmap, heat),
    ] {
        let (small, sw, sh) = shrink(&rgb, w, h);
        crate::lab::bench::plot::write_png(&dir.join(name), sw, sh, &small)
            .map_err(|e| e.problems()[0].clone())?;
    }
    Ok(names)
}

/// Text made safe inside HTML.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// One of the largest difference's values as the page shows it: a u32 channel's as the
/// integer it is, a float's as a [`figure`].
fn value(largest: &super::channels::Largest, v: f64) -> String {
    if largest.integer {
        largest.value_text(v)
    } else {
        figure(v)
    }
}

/// A figure as the page shows it: six significant places, `inf` for infinity.
fn figure(v: f64) -> String {
    if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.to_string()
    } else if v.is_nan() {
        "nan".to_string()
    } else {
        format!("{v:.6}")
    }
}

const STYLE: &str = "body{font:14px/1.4 sans-serif;margin:24px;color:#222;background:#fff}\
h1{font-size:20px}table{border-collapse:collapse;margin:8px 0}\
td,th{border:1px solid #ccc;padding:4px 8px;text-align:left;vertical-align:top}\
.verdict{font-weight:bold;color:#fff;padding:6px 12px;display:inline-block;min-width:48px;text-align:center}\
.pass{background:#2e7d32}.warn{background:#f9a825;color:#222}.fail{background:#c62828}\
.thumbs{white-space:nowrap}.thumbs img{width:200px;margin-right:6px;image-rendering:pixelated;border:1px solid #999}\
.layers td{font-size:12px}.why{color:#c62828}";

/// Writes `dir/index.html` and `dir/report.json` for `report`.
pub fn write(dir: &Path, report: &DiffReport) -> Result<()> {
    create_dir(dir)?;
    let json = serde_json::to_string_pretty(report).unwrap_or_default() + "\n";
    let json_path = dir.join("report.json");
    crate::io::output::write_atomic(&json_path, |w| {
        w.write_all(json.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(|detail| Problem::new(ProblemKind::Output, &json_path, detail))?;
    let html = page(report);
    let html_path = dir.join("index.html");
    crate::io::output::write_atomic(&html_path, |w| {
        w.write_all(html.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(|detail| Problem::new(ProblemKind::Output, &html_path, detail))?;
    Ok(())
}

/// The page, the worst frames first: failures, then warnings, then by the gating metric.
fn page(report: &DiffReport) -> String {
    let metric = Metric::parse(report.metric).unwrap_or(Metric::Rmse);
    let mut order: Vec<usize> = (0..report.frames.len()).collect();
    let rank = |i: usize| {
        let f = &report.frames[i];
        (if f.failed {
            0
        } else if f.warned {
            1
        } else {
            2
        }) as u8
    };
    order.sort_by(|&i, &j| {
        let (fi, fj) = (&report.frames[i], &report.frames[j]);
        rank(i).cmp(&rank(j)).then_with(|| {
            let worse = |x: f64, y: f64| metric.exceeds(x, y) || (x.is_nan() && !y.is_nan());
            if worse(fi.value, fj.value) {
                std::cmp::Ordering::Less
            } else if worse(fj.value, fi.value) {
                std::cmp::Ordering::Greater
            } else {
                fi.frame.cmp(&fj.frame)
            }
        })
    });
    let failed = report.frames.iter().filter(|f| f.failed).count();
    let warned = report
        .frames
        .iter()
        .filter(|f| f.warned && !f.failed)
        .count();
    let (class, word) = if failed > 0 {
        ("fail", "FAIL")
    } else if warned > 0 {
        ("warn", "WARN")
    } else {
        ("pass", "PASS")
    };
    let noun = report.entries();
    let mut html = format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\
         <title>shutter diff: {word}</title><style>{STYLE}</style></head><body>\n\
         <h1><span class=\"verdict {class}\" id=\"verdict\">{word}</span> shutter diff</h1>\n\
         <p>{} {noun}: {failed} fail, {warned} warn, {} pass. Gating metric: {} (worst {}). \
         Worst {noun} first.</p>\n",
        report.frames.len(),
        report.frames.len() - failed - warned,
        escape(report.metric),
        figure(report.worst),
    );
    for warning in &report.warnings {
        html += &format!("<p class=\"why\">warning: {}</p>\n", escape(warning));
    }
    html += "<table>\n<tr><th>frame</th><th>verdict</th><th>figures</th><th>reference · candidate · heatmap</th></tr>\n";
    for &i in &order {
        let f = &report.frames[i];
        let (class, word) = if f.failed {
            ("fail", "FAIL")
        } else if f.warned {
            ("warn", "WARN")
        } else {
            ("pass", "PASS")
        };
        let label = f.frame.map_or("still".to_string(), |n| n.to_string());
        // A view's row: `12 right`, its id `frame-12-right`.
        let (label, id) = match &f.view {
            Some(view) => (
                format!("{label} {}", escape(view)),
                format!(
                    "{label}-{}",
                    escape(&view.replace(char::is_whitespace, "_"))
                ),
            ),
            None => (label.clone(), label),
        };
        let w = &f.whole;
        let m = &f.largest;
        let mut figures = format!(
            "RMSE {} · MAE {} · PSNR {} dB (peak 1) · SSIM {} · FLIP {}<br>\
             every channel ({}): mean {} · RMS {} · PSNR {} dB (peak {}) · max {}{}<br>\
             pixels over the fail gate {} · over the warning {}",
            figure(w.rmse),
            figure(w.mae),
            figure(w.psnr),
            figure(w.ssim),
            figure(w.flip),
            f.every_channel.channels,
            figure(f.every_channel.mean_error),
            figure(f.every_channel.rms_error),
            figure(f.every_channel.psnr),
            figure(f.every_channel.psnr_peak),
            figure(m.error),
            if m.error > 0.0 {
                format!(
                    " at ({}, {}) {}: {} against {}",
                    m.x,
                    m.y,
                    escape(&m.channel),
                    value(m, m.a),
                    value(m, m.b)
                )
            } else {
                String::new()
            },
            f.pixels_over_fail,
            f.pixels_over_warn,
        );
        if let Some(why) = &f.why {
            figures += &format!("<div class=\"why\">{}</div>", escape(why));
        }
        if !f.missing_channels.is_empty() {
            figures += &format!(
                "<div class=\"why\">missing: {}</div>",
                escape(&f.missing_channels.join(", "))
            );
        }
        figures += "<table class=\"layers\"><tr><th>layer</th><th>class</th><th>RMSE</th><th>MAE</th><th>max</th><th>over fail</th></tr>";
        for layer in &f.layers {
            figures += &format!(
                "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{} {}</td><td>{}</td></tr>",
                escape(&layer.layer),
                layer.class,
                figure(layer.rmse),
                figure(layer.mae),
                figure(layer.largest.error),
                escape(&layer.largest.channel),
                layer.pixels_over_fail
            );
        }
        figures += "</table>";
        let thumbs = f.thumbnails.as_ref().map_or(String::new(), |t| {
            [&t.reference, &t.candidate, &t.heatmap]
                .iter()
                .map(|p| {
                    let p = escape(&p.to_string_lossy());
                    format!("<img src=\"{p}\" alt=\"{p}\">")
                })
                .collect()
        });
        html += &format!(
            "<tr id=\"frame-{id}\"><td>{label}</td><td><span class=\"verdict {class}\">{word}</span></td>\
             <td>{figures}</td><td class=\"thumbs\">{thumbs}</td></tr>\n"
        );
    }
    html += "</table>\n</body></html>\n";
    html
}
