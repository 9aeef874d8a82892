//! Files that hold no colour image (a depth, vector, ID or matte pass on its own): every
//! channel compared as data, by name, with the data gates; the figures over every channel
//! as `idiff` gives them stand for the beauty's (`--metric rmse` and `psnr` read them; SSIM
//! and FLIP, which need a picture, cannot score such a file).

use std::path::Path;

use crate::error::{Problem, ProblemKind};
use crate::frame::{CarriedChannel, Frame, LayerClass};
use crate::io::file::FileInfo;
use crate::io::passes::{passes_found, FramePlan};
use crate::io::preset::Preset;
use crate::lab::metrics::{Metric, Scores};

use super::verdict::{failure, warns_by_pixels};
use super::{channels, write_heatmap, DiffJob, Entry, FrameDiff};

/// Whether the reference at `path` is such a file. Where the colour read found a luminance
/// `Y` (`luminance`), as `info` reads the file: `preset` finds no colour in it
/// (`passes_found`: a `Y` beside an `X` is a vector pass). Where the colour read found
/// nothing: no layer holds R, G and B (a Cryptomatte layer's are IDs and coverage; a file of
/// view layers with colour is refused as the read refuses it, asking for `--layer`).
pub(super) fn holds_no_colour(path: &Path, preset: &Preset, luminance: bool) -> bool {
    let Ok(info) = FileInfo::probe(path) else {
        return false;
    };
    if luminance {
        return !passes_found(&info, preset).contains(&"color");
    }
    let split = |name: &str| match name.rsplit_once('.') {
        Some((layer, leaf)) => (layer.to_string(), leaf.to_ascii_lowercase()),
        None => (String::new(), name.to_ascii_lowercase()),
    };
    let names: Vec<(String, String)> = info.channels.iter().map(|c| split(&c.name)).collect();
    let colour_layer = |layer: &str| {
        !layer.to_ascii_lowercase().contains("crypto")
            && ["r", "g", "b"]
                .iter()
                .all(|want| names.iter().any(|(l, leaf)| l == layer && leaf == want))
    };
    !names.iter().any(|(layer, _)| colour_layer(layer))
}

/// Whether the colour `plan` reads is a luminance `Y` read as grey.
pub(super) fn luminance(plan: &FramePlan) -> bool {
    (plan.colour_channel_names().first()).is_some_and(|c| c.rsplit('.').next() == Some("Y"))
}

/// One file of `entry` read whole, every channel as data (u32 channels exactly), and the
/// channels left out (of a part of another window, deep, or not decodable).
fn read(path: &Path, entry: &Entry) -> Result<(Frame, Vec<String>), Problem> {
    let frame = entry.frame;
    let info = FileInfo::probe(path).map_err(|p| p.frame(frame))?;
    let info = info
        .in_view(entry.view)
        .map_err(|d| Problem::new(ProblemKind::MissingChannel, path, d).frame(frame))?;
    // The channels of the parts that share the first part's window (another window, or a
    // deep part, is left out and named, as the colour read leaves such parts out).
    let window = |part: usize| match &info.kind {
        crate::io::file::FileKind::Exr { headers, .. } => headers
            .get(part)
            .map(|h| (h.layer_size, h.own_attributes.layer_position, h.deep)),
        _ => None,
    };
    let first = info.channels.first().map_or(0, |c| c.part);
    let mut left_out: Vec<String> = Vec::new();
    let all: Vec<usize> = (0..info.channels.len())
        .filter(|&i| {
            let channel = &info.channels[i];
            let same = window(channel.part) == window(first)
                && window(channel.part).is_none_or(|(_, _, deep)| !deep)
                && info.unreadable(channel).is_none();
            if !same && !left_out.contains(&channel.name) {
                left_out.push(channel.name.clone());
            }
            same
        })
        .collect();
    let bits: Vec<usize> = (all.iter().copied())
        .filter(|&i| info.channels[i].sample_type == "u32")
        .collect();
    let planes = info.read_bits(&all, &bits).map_err(|p| p.frame(frame))?;
    let mut out = Frame::new(info.width, info.height);
    out.windows = info.windows;
    for (&i, plane) in all.iter().zip(planes) {
        let channel = &info.channels[i];
        let exact: Option<Vec<u32>> = bits
            .contains(&i)
            .then(|| plane.iter().map(|v| v.to_bits()).collect());
        let plane = match &exact {
            Some(values) => values.iter().map(|&v| v as f32).collect(),
            None => plane,
        };
        out.carried.channels.push(CarriedChannel {
            name: channel.name.clone(),
            stored: channel.name.clone(),
            shared: false,
            part: channel.part,
            class: LayerClass::Data,
            plane,
            exact,
            window: None,
        });
    }
    Ok((out, left_out))
}

/// Compares an entry whose reference holds no colour image ([`holds_no_colour`]).
pub(super) fn compare(job: &DiffJob, entry: &Entry) -> Result<FrameDiff, Problem> {
    let frame = entry.frame;
    let (pa, pb) = (job.a.path(frame), job.b.path(frame));
    let ((a, out_a), (b, out_b)) = (read(&pa, entry)?, read(&pb, entry)?);
    if (a.width, a.height, a.windows) != (b.width, b.height, b.windows) {
        let w = &b.windows;
        return Err(Problem::new(
            ProblemKind::SizeMismatch,
            &pb,
            format!(
                "{}x{}, data window at ({}, {}), but {} is {}x{} at ({}, {})",
                b.width,
                b.height,
                w.data_origin.0,
                w.data_origin.1,
                pa.display(),
                a.width,
                a.height,
                a.windows.data_origin.0,
                a.windows.data_origin.1
            ),
        )
        .frame(frame));
    }
    let compared = channels::compare(&a, &b, &job.gates);
    let every = &compared.every;
    let mut notes = vec![format!(
        "{} holds no colour image: every channel compared as data",
        pa.display()
    )];
    // What a warning is made of (`--warn-exit`): channels not compared, types that differ.
    let mut doubts = Vec::new();
    for (left, path) in [(&out_a, &pa), (&out_b, &pb)] {
        if !left.is_empty() {
            doubts.push(format!(
                "{} of {}: another data window, deep data, or data shutter does not decode: \
                 not compared",
                left.join(", "),
                path.display()
            ));
        }
    }
    if !compared.retyped.is_empty() {
        doubts.push(format!(
            "{} stored as u32 in one file and as float in the other: compared as stored",
            compared.retyped.join(", ")
        ));
    }
    if job.sharp.is_some() {
        notes.push("--sharp scores a colour image: not used".to_string());
    }
    // PSNR for a peak of 1.0, as the beauty's is.
    let psnr = if every.rms_error == 0.0 {
        f64::INFINITY
    } else {
        -20.0 * every.rms_error.log10()
    };
    let (value, scored) = match job.metric {
        Metric::Rmse => (every.rms_error, true),
        Metric::Psnr => (psnr, true),
        Metric::Ssim | Metric::Flip => {
            notes.push(format!(
                "--metric {} needs a colour image: not scored, --fail and --warn not applied",
                job.metric.name()
            ));
            (f64::NAN, false)
        }
    };
    // Unscored, the metric's gates do not apply (the per-pixel and channel gates do).
    let gated = DiffJob {
        fail: job.fail.filter(|_| scored),
        warn: job.warn.filter(|_| scored),
        ..job.clone()
    };
    if let Some(heatmap) = &job.heatmap {
        // Scaled to the largest finite error; a non-finite one is the top of the scale.
        let finite = compared.errors.iter().copied().filter(|e| e.is_finite());
        let most = finite.fold(1e-12f32, f32::max);
        let map: Vec<f32> = (compared.errors.iter())
            .map(|e| if e.is_finite() { e / most } else { 1.0 })
            .collect();
        let path = heatmap.path(frame);
        let path = entry
            .output
            .map_or_else(|| path.clone(), |v| super::views::output_path(&path, v));
        write_heatmap(&path, a.width, a.height, &map).map_err(|e| e.problems()[0].clone())?;
    }
    let why = failure(&gated, &compared, value, a.width * a.height);
    let whole = Scores {
        rmse: every.rms_error,
        mae: every.mean_error,
        psnr,
        ssim: f64::NAN,
        flip: f64::NAN,
        pixels: a.width * a.height,
        non_finite: compared.non_finite,
    };
    Ok(FrameDiff {
        frame,
        view: entry.view.map(str::to_string),
        a: pa,
        b: pb,
        whole,
        region: None,
        value,
        identical: compared.identical(),
        largest: every.max_error.clone(),
        pixels_over_fail: compared.pixels_over_fail,
        pixels_over_warn: compared.pixels_over_warn,
        samples_over_hard: compared.over_hard,
        warned: gated.warn.is_some_and(|w| job.metric.exceeds(value, w))
            || warns_by_pixels(job, compared.pixels_over_warn, a.width * a.height)
            || !compared.extra.is_empty()
            || !doubts.is_empty(),
        every_channel: compared.every,
        layers: compared.layers,
        missing_channels: compared.missing,
        extra_channels: compared.extra,
        extra_views: entry.extra.to_vec(),
        candidate_views: false,
        thumbnails: None,
        notes: notes.into_iter().chain(doubts).collect(),
        read_warnings: Vec::new(),
        failed: why.is_some(),
        why,
    })
}
