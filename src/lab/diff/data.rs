//! Files that hold no colour image (a depth, vector, ID or matte pass on its own): every
//! channel compared as data, by name, with the data gates; the figures over every channel
//! as `idiff` gives them stand for the beauty's (`--metric rmse` and `psnr` read them; SSIM
//! and FLIP, which need a picture, cannot score such a file).

use std::path::Path;

use crate::error::{Problem, ProblemKind};
use crate::frame::{CarriedChannel, Frame, LayerClass};
use crate::io::file::FileInfo;
use crate::lab::metrics::{Metric, Scores};

use super::{channels, failure, write_heatmap, DiffJob, Entry, FrameDiff};

/// Whether a reference whose colour read found `colour` (none: the read found no colour
/// channel) is such a file: it holds no channel named R, G, B or Y in any layer, or its `Y`
/// was read as a luminance beside an `X` (a vector pass, as `info` reads it).
pub(super) fn holds_no_colour(path: &Path, colour: Option<&[String]>) -> bool {
    let leaf = |name: &str| {
        name.rsplit('.')
            .next()
            .unwrap_or_default()
            .to_ascii_lowercase()
    };
    let Ok(info) = FileInfo::probe(path) else {
        return false;
    };
    match colour {
        None => !(info.channels.iter()).any(|c| ["r", "g", "b", "y"].contains(&&*leaf(&c.name))),
        Some(colour) => {
            colour
                .first()
                .is_some_and(|c| c.rsplit('.').next() == Some("Y"))
                && info.find("X").is_some()
        }
    }
}

/// One file of `entry` read whole, every channel as data (u32 channels exactly).
fn read(path: &Path, entry: &Entry) -> Result<Frame, Problem> {
    let frame = entry.frame;
    let info = FileInfo::probe(path).map_err(|p| p.frame(frame))?;
    let info = info
        .in_view(entry.view)
        .map_err(|d| Problem::new(ProblemKind::MissingChannel, path, d).frame(frame))?;
    let all: Vec<usize> = (0..info.channels.len()).collect();
    let bits: Vec<usize> = (all.iter().copied())
        .filter(|&i| info.channels[i].sample_type == "u32")
        .collect();
    let planes = info.read_bits(&all, &bits).map_err(|p| p.frame(frame))?;
    let mut out = Frame::new(info.width, info.height);
    out.windows = info.windows;
    for (i, plane) in planes.into_iter().enumerate() {
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
    Ok(out)
}

/// Compares an entry whose reference holds no colour image ([`holds_no_colour`]).
pub(super) fn compare(job: &DiffJob, entry: &Entry) -> Result<FrameDiff, Problem> {
    let frame = entry.frame;
    let (pa, pb) = (job.a.path(frame), job.b.path(frame));
    let (a, b) = (read(&pa, entry)?, read(&pb, entry)?);
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
    // PSNR for a peak of 1.0, as the beauty's is.
    let psnr = if every.rms_error == 0.0 {
        f64::INFINITY
    } else {
        -20.0 * every.rms_error.log10()
    };
    let value = match job.metric {
        Metric::Rmse => every.rms_error,
        Metric::Psnr => psnr,
        Metric::Ssim | Metric::Flip => {
            notes.push(format!(
                "--metric {} needs a colour image: not scored",
                job.metric.name()
            ));
            f64::NAN
        }
    };
    if let Some(heatmap) = &job.heatmap {
        let most = compared.errors.iter().copied().fold(1e-12f32, f32::max);
        let map: Vec<f32> = compared.errors.iter().map(|e| e / most).collect();
        let path = heatmap.path(frame);
        let path = entry
            .output
            .map_or_else(|| path.clone(), |v| super::views::output_path(&path, v));
        write_heatmap(&path, a.width, a.height, &map).map_err(|e| e.problems()[0].clone())?;
    }
    let why = failure(job, &compared, value, a.width * a.height);
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
        largest: every.max_error.clone(),
        pixels_over_fail: compared.pixels_over_fail,
        pixels_over_warn: compared.pixels_over_warn,
        samples_over_hard: compared.over_hard,
        warned: job.warn.is_some_and(|w| job.metric.exceeds(value, w))
            || compared.pixels_over_warn > 0
            || !compared.extra.is_empty(),
        every_channel: compared.every,
        layers: compared.layers,
        missing_channels: compared.missing,
        extra_channels: compared.extra,
        extra_views: entry.extra.to_vec(),
        thumbnails: None,
        notes,
        read_warnings: Vec::new(),
        failed: why.is_some(),
        why,
    })
}
