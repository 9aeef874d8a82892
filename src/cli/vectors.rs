//! `shutter vectors`: fits how a sequence's vector pass is stored from its own frames
//! (`io::passes::fit`), prints the best reading, how it compares with the next best and with
//! no motion, and the preset section that reads it; `--write-preset FILE` writes that
//! section as a preset file.

use std::path::{Path, PathBuf};

use crate::error::{Error, Problem, ProblemKind, Result};
use crate::io::file::FileInfo;
use crate::io::passes::{fit, read_color, FitInput, Reading};
use crate::io::preset::{Preset, Units, BUILTIN};
use crate::io::sequence::PathPattern;

use super::args::VectorsArgs;

/// Linear luma of a frame's colour.
fn luma(pattern: &PathPattern, frame: i64, preset: &Preset) -> Result<(Vec<f32>, usize, usize)> {
    let f = read_color(pattern, Some(frame), preset).map_err(Error::Files)?;
    let c = f.color.as_ref().expect("colour read");
    Ok((crate::io::passes::luma(c), f.width, f.height))
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

/// Refuses, before anything is read or written, a `--write-preset` that would replace an
/// input: any frame of the colour pattern, the vector pass of any of them, or a preset file
/// given with `--preset`; the same check blur makes of `-o` (the same path, another spelling,
/// a symbolic or hard link).
fn refuse_overwriting_inputs(
    file: &Path,
    args: &VectorsArgs,
    color: &PathPattern,
    vectors: &PathPattern,
    found: &[i64],
) -> Result<()> {
    let mut inputs: Vec<PathBuf> = found.iter().map(|&f| color.path(Some(f))).collect();
    if args.velocity.is_some() {
        inputs.extend(found.iter().map(|&f| vectors.path(Some(f))));
    }
    let builtin = |name: &str| BUILTIN.iter().any(|(n, _)| *n == name);
    inputs.extend(
        args.preset
            .iter()
            .filter(|name| !builtin(name))
            .map(PathBuf::from),
    );
    match crate::io::passes::outputs_over_inputs(&[(file, inputs)]).first() {
        None => Ok(()),
        Some((_, input)) => Err(Problem::new(
            ProblemKind::Output,
            file,
            format!(
                "--write-preset would overwrite the input {}; choose another file",
                input.display()
            ),
        )
        .into()),
    }
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
    let found = color.discover()?.frames;
    if let Some(file) = &args.write_preset {
        refuse_overwriting_inputs(file, &args, &color, &vectors, &found)?;
    }
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
    let result = fit(&FitInput {
        width: w,
        height: h,
        current: &current,
        prev: prev.as_deref(),
        next: next.as_deref(),
        stored: [&planes[0], &planes[1]],
        max_points: crate::io::passes::FIT_POINTS,
    });
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
        }))?;
    } else {
        let mut out = format!(
            "frame {frame}: motion measured at {} points ({:.2} s); no motion fits to {} px \
             (each point's error capped at {} px, as the readings' are)\n",
            result.points,
            seconds,
            round(result.no_motion),
            crate::io::passes::FIT_TRUNCATE
        );
        for (i, r) in result.readings.iter().take(4).enumerate() {
            out += &format!(
                "  {} {} px  {}{}\n",
                if i == 0 { "best" } else { "    " },
                round(r.residual),
                crate::io::passes::describe_reading(r),
                if r.is_still() {
                    format!(" - moves the points {} px: no motion", round(r.motion))
                } else {
                    String::new()
                }
            );
        }
        match (&text, &result.why) {
            (Some(text), _) => out += &format!("\n{text}"),
            (None, Some(why)) => out += &format!("undecided: {why}\n"),
            (None, None) => {}
        }
        super::out_text(&out)?;
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
            say!(
                "shutter: no preset written to {}: {}",
                file.display(),
                result.why.as_deref().unwrap_or("no reading chosen")
            );
            Ok(1)
        }
        _ => Ok(0),
    }
}
