//! `shutter vectors`: fits how a sequence's vector pass is stored from its own frames
//! (`io::passes::fit`), prints the best reading, how it compares with the next best and with
//! no motion, and the preset section that reads it; `--write-preset FILE` writes that
//! section as a preset file.

use crate::error::{Error, Problem, ProblemKind, Result};
use crate::io::file::FileInfo;
use crate::io::passes::{fit, read_color, FitInput, Reading};
use crate::io::preset::{Preset, Units};
use crate::io::sequence::PathPattern;

use super::args::VectorsArgs;

/// Linear luma of a frame's colour.
fn luma(pattern: &PathPattern, frame: i64, preset: &Preset) -> Result<(Vec<f32>, usize, usize)> {
    let f = read_color(pattern, Some(frame), preset).map_err(Error::Files)?;
    let c = f.color.as_ref().expect("colour read");
    let y = (0..f.width * f.height)
        .map(|i| 0.2126 * c.r[i] + 0.7152 * c.g[i] + 0.0722 * c.b[i])
        .map(|v| if v.is_finite() { v } else { 0.0 })
        .collect();
    Ok((y, f.width, f.height))
}

/// The middle one of `frames` with a neighbour on both sides (`exists`), else with one.
fn middle_with_neighbours(frames: &[i64], exists: impl Fn(i64) -> bool) -> Option<i64> {
    let both: Vec<i64> = frames
        .iter()
        .copied()
        .filter(|&f| exists(f - 1) && exists(f + 1))
        .collect();
    let any: Vec<i64> = frames
        .iter()
        .copied()
        .filter(|&f| exists(f - 1) || exists(f + 1))
        .collect();
    let pick = if both.is_empty() { any } else { both };
    pick.get(pick.len() / 2).copied()
}

/// The fit of one frame's stored planes against its neighbours' luma.
fn fit_frames(
    (width, height): (usize, usize),
    current: &[f32],
    [prev, next]: [&Option<Vec<f32>>; 2],
    planes: &[Vec<f32>],
) -> crate::io::passes::Fit {
    fit(&FitInput {
        width,
        height,
        current,
        prev: prev.as_deref(),
        next: next.as_deref(),
        stored: [&planes[0], &planes[1]],
    })
}

/// The two stored channels' names: `--channels`, else the first pair of the preset's
/// [velocity] alternatives the file holds (not the colour's own channels, in a shared file).
fn channel_names(
    args: &VectorsArgs,
    info: &FileInfo,
    preset: &Preset,
    shared: bool,
) -> Result<[String; 2]> {
    if let Some(list) = &args.channels {
        let names: Vec<&str> = list.split(',').map(str::trim).collect();
        return match names.as_slice() {
            [x, y] => Ok([x.to_string(), y.to_string()]),
            _ => Err(Error::usage("--channels takes two names: X,Y")),
        };
    }
    if let Some([x, y]) = crate::io::passes::vector_channels(info, preset, &preset.velocity, shared)
    {
        let name = |i: usize| {
            info.channels[i]
                .alias
                .clone()
                .unwrap_or_else(|| info.channels[i].name.clone())
        };
        return Ok([name(x), name(y)]);
    }
    Err(Problem::new(
        ProblemKind::MissingChannel,
        &info.path,
        format!(
            "none of the preset's [velocity] channel pairs is in the file (it holds {}): name \
             them with --channels X,Y",
            info.channel_list()
        ),
    )
    .into())
}

/// The preset file for a reading.
fn preset_text(r: &Reading, names: &[String; 2], source: &str, others: &str) -> String {
    let (x, y) = if r.swap {
        (&names[1], &names[0])
    } else {
        (&names[0], &names[1])
    };
    let section = |name: &str| {
        format!(
            "[{name}]\nchannels = [[\"{x}\", \"{y}\"]]\nmeaning = \"{}\"\nencoding = \"plain\"\nzero = {:?}\nscale = {:?}\ndead_zone = 0.0\nunits = \"{}\"\ny_up = {}\n",
            serde_json::to_value(r.meaning)
                .ok()
                .and_then(|v| v.as_str().map(String::from))
                .unwrap_or_default(),
            r.zero,
            r.scale,
            match r.units {
                Units::Pixels => "pixels",
                Units::Normalized => "normalized",
            },
            r.y_up
        )
    };
    // The sections these vectors answer for: [velocity], and [prev] or [next] by the
    // direction they point; the other direction stays the preset's (Blender's Z,W).
    let other = if r.meaning.is_backward() {
        "prev"
    } else {
        "next"
    };
    format!(
        "# Written by shutter vectors from {source}: the stored vectors fitted to the motion \
         measured\n# between the frames ({} px RMS; {others}).\n# Use it after the presets the \
         fit was run with, e.g. --preset blender --preset this.toml.\n\n{}\n{}",
        round(r.residual),
        section("velocity"),
        section(other)
    )
}

fn round(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

pub fn vectors(args: VectorsArgs) -> Result<i32> {
    let preset = Preset::load(&args.preset)?;
    let color = PathPattern::parse(&args.color)?;
    if !color.is_sequence() {
        return Err(Error::usage(
            "--color must be a pattern with #### or %04d: the fit compares neighbouring frames",
        ));
    }
    let vectors = match &args.velocity {
        Some(v) => PathPattern::parse(v)?,
        None => color.clone(),
    };
    let found = color.discover()?;
    let has = |f: i64| found.contains(&f);
    let frame = match args.frame {
        Some(f) => f,
        None => middle_with_neighbours(&found, has).ok_or_else(|| {
            Error::Files(vec![Problem::new(
                ProblemKind::MissingFile,
                std::path::Path::new(&color.raw),
                "no frame with a neighbouring frame: the fit needs two consecutive frames",
            )])
        })?,
    };
    let (current, w, h) = luma(&color, frame, &preset)?;
    let neighbour = |f: i64| -> Result<Option<Vec<f32>>> {
        if !has(f) {
            return Ok(None);
        }
        let (plane, nw, nh) = luma(&color, f, &preset)?;
        if (nw, nh) != (w, h) {
            return Err(Problem::new(
                ProblemKind::SizeMismatch,
                color.path(Some(f)),
                format!("{nw}x{nh} but frame {frame} is {w}x{h}"),
            )
            .into());
        }
        Ok(Some(plane))
    };
    let (prev, next) = (neighbour(frame - 1)?, neighbour(frame + 1)?);
    if prev.is_none() && next.is_none() {
        return Err(Problem::new(
            ProblemKind::MissingFile,
            color.path(Some(frame - 1)),
            format!(
                "frame {frame} has no neighbour (frames {} and {} are missing)",
                frame - 1,
                frame + 1
            ),
        )
        .into());
    }
    let path = vectors.path(Some(frame));
    let info = FileInfo::probe(&path)?;
    let shared = args.velocity.is_none();
    let names = channel_names(&args, &info, &preset, shared)?;
    let index = |name: &str| {
        info.find(name).ok_or_else(|| {
            Error::from(
                Problem::new(ProblemKind::MissingChannel, &path, "not in the file").channel(name),
            )
        })
    };
    let planes = info.read(&[index(&names[0])?, index(&names[1])?])?;
    if (info.width, info.height) != (w, h) {
        return Err(Problem::new(
            ProblemKind::SizeMismatch,
            &path,
            format!("{}x{} but the colour is {w}x{h}", info.width, info.height),
        )
        .into());
    }
    let start = std::time::Instant::now();
    let result = fit_frames((w, h), &current, [&prev, &next], &planes);
    let seconds = start.elapsed().as_secs_f64();
    let next_best = result
        .chosen
        .as_ref()
        .and_then(|c| result.readings.iter().find(|r| *r != c));
    let others = format!(
        "no motion {} px{}",
        round(result.no_motion),
        next_best.map_or(String::new(), |r| format!(
            ", next best {} px: {}",
            round(r.residual),
            crate::io::passes::describe_reading(r)
        ))
    );
    let source = format!(
        "{} frame {frame}, channels {}",
        vectors.raw,
        names.join(", ")
    );
    let text = result
        .chosen
        .as_ref()
        .map(|r| preset_text(r, &names, &source, &others));
    if args.json {
        super::out_json(&serde_json::json!({
            "schema": crate::JSON_SCHEMA,
            "command": "vectors",
            "ok": true,
            "frame": frame,
            "channels": names,
            "points": result.points,
            "seconds": seconds,
            "no_motion": result.no_motion,
            "chosen": result.chosen,
            "why": result.why,
            "readings": result.readings,
            "preset": text,
        }));
    } else {
        let mut out = format!(
            "frame {frame}: motion measured at {} points ({:.2} s); no motion fits to {} px\n",
            result.points,
            seconds,
            round(result.no_motion)
        );
        for (i, r) in result.readings.iter().take(4).enumerate() {
            out += &format!(
                "  {} {} px  {}\n",
                if i == 0 { "best" } else { "    " },
                round(r.residual),
                crate::io::passes::describe_reading(r)
            );
        }
        match (&text, &result.why) {
            (Some(text), _) => out += &format!("\n{text}"),
            (None, Some(why)) => out += &format!("undecided: {why}\n"),
            (None, None) => {}
        }
        super::out(&out);
    }
    match (&args.write_preset, &text) {
        (Some(file), Some(text)) => {
            crate::io::output::write_atomic(file, |w| {
                use std::io::Write;
                w.write_all(text.as_bytes()).map_err(|e| e.to_string())
            })
            .map_err(|detail| Problem::new(ProblemKind::Output, file, detail))?;
            Ok(0)
        }
        (Some(file), None) => {
            eprintln!(
                "shutter: no preset written to {}: {}",
                file.display(),
                result.why.as_deref().unwrap_or("no reading chosen")
            );
            Ok(1)
        }
        _ => Ok(0),
    }
}

/// The check `blur` runs before it blurs (issue 32, point 2): on the middle frame with
/// neighbours (as `shutter vectors` picks it), the stored vectors the run reads ([velocity],
/// or [prev]/[next] for scatter) are fitted against the motion measured in the colour, and
/// the preset's own reading is scored as it is. A warning when another reading fits clearly
/// better (more than twice as close, and by over a quarter pixel); `None` otherwise, and
/// whenever the check cannot be made (no vector file, no neighbour, a still sequence, RE:Vision
/// codes).
pub fn check(job: &crate::pipeline::Job) -> Option<String> {
    let needs = crate::process::needs(job.algorithm, &job.params);
    // The section the run reads motion from: [velocity] (reconstruct, stretch), else [prev]
    // or [next] (scatter), with its own file.
    let (spec, file) = if needs.velocity {
        (&job.preset.velocity, &job.inputs.velocity)
    } else if needs.prev {
        (&job.preset.prev, &job.inputs.prev)
    } else if needs.next {
        (&job.preset.next, &job.inputs.next)
    } else {
        return None;
    };
    if spec.encoding != crate::io::preset::Encoding::Plain {
        return None;
    }
    let color = &job.inputs.color;
    let frames: Vec<i64> = job.frames.iter().flatten().copied().collect();
    // Neighbours from the job's own frames (the preflight found them); only where none has
    // one (a farm chunk of one frame) is the disk asked, for the middle frame alone: no stat
    // per frame of a long sequence before the run starts.
    let listed: std::collections::HashSet<i64> = frames.iter().copied().collect();
    let on_disk = |f: i64| listed.contains(&f) || color.path(Some(f)).is_file();
    let frame = middle_with_neighbours(&frames, |f| listed.contains(&f))
        .or_else(|| frames.get(frames.len() / 2).copied())?;
    let vectors = file.as_ref().unwrap_or(color);
    let info = FileInfo::probe(&vectors.path(Some(frame))).ok()?;
    let [x, y] = crate::io::passes::vector_channels(&info, &job.preset, spec, file.is_none())?;
    let planes = info.read(&[x, y]).ok()?;
    let (current, w, h) = luma(color, frame, &job.preset).ok()?;
    if (info.width, info.height) != (w, h) {
        return None;
    }
    let side = |f: i64| {
        on_disk(f)
            .then(|| luma(color, f, &job.preset).ok())
            .flatten()
            .filter(|(_, nw, nh)| (*nw, *nh) == (w, h))
            .map(|(p, _, _)| p)
    };
    let (prev, next) = (side(frame - 1), side(frame + 1));
    let result = fit_frames((w, h), &current, [&prev, &next], &planes);
    let best = result.readings.first()?;
    if result.no_motion < 0.5 {
        return None;
    }
    let stated = Reading {
        meaning: spec.meaning,
        swap: false,
        y_up: spec.y_up,
        zero: spec.zero,
        scale: spec.scale,
        units: spec.units,
        residual: 0.0,
        fitted_scale: [0.0; 2],
        consistent: true,
    };
    let own = result.residual_of(&stated)?;
    (own > 2.0 * best.residual + 0.25).then(|| {
        format!(
            "the vectors fit another reading better than the preset's, measured on frame \
             {frame} against its neighbours: {} ({:.2} px) against the preset's {} ({:.2} px; \
             no motion {:.2} px); check with shutter vectors, or --check-vectors off",
            crate::io::passes::describe_reading(best),
            best.residual,
            crate::io::passes::describe_reading(&stated),
            own,
            result.no_motion
        )
    })
}
