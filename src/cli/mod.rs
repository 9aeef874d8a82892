//! The command line: parse (clap, in `args`), resolve to a job (preset merged, flags over
//! preset values, frames listed), run, and report. Only this module prints.

pub mod args;

use std::io::IsTerminal;

use clap::Parser;

use crate::dof::{CocSource, DofParams, Lens, Method};
use crate::error::{Error, Result};
use crate::io::exr::{parse_compression, ExrOptions, WRITABLE_COMPRESSIONS};
use crate::io::file::{FileInfo, FileKind};
use crate::io::output::{OutputFormat, OutputOptions};
use crate::io::passes::{passes_found, Inputs};
use crate::io::preset::{Preset, Transfer, BUILTIN};
use crate::io::sequence::{parse_frames, PathPattern};
use crate::motion::{
    scatter, Algorithm, Anchor, BlurParams, CurveKind, Normalize, ReconstructParams, ScatterParams,
    StretchParams, Variant, Weight,
};
use crate::pipeline::{run, Event, Job};

use args::{
    BenchArgs, BlurArgs, Cli, Command, DiffArgs, DofArgs, InfoArgs, PresetsArgs, PresetsCommand,
    SceneArgs,
};

/// Parses the command line, runs it and returns the process exit code.
pub fn main() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            let _ = e.print();
            return e.exit_code();
        }
    };
    let result = match cli.command {
        Command::Blur(args) => blur(*args, false),
        Command::Dof(args) => blur(*args, true),
        Command::Info(args) => info(args),
        Command::Presets(args) => presets(args),
        Command::Scene(args) => scene(args),
        Command::Bench(args) => bench(args),
        Command::Diff(args) => {
            return match diff(args) {
                Ok(code) => code,
                Err(error) => {
                    print_error(&error);
                    // For diff, an unreadable input is not a comparison result: exit 2.
                    2
                }
            };
        }
    };
    match result {
        Ok(()) => 0,
        Err(error) => {
            print_error(&error);
            error.exit_code()
        }
    }
}

/// The most problems printed one by one; the rest are counted.
const MAX_PRINTED_PROBLEMS: usize = 20;

fn print_error(error: &Error) {
    match error {
        Error::Usage(message) => eprintln!("shutter: error: {message}"),
        Error::Files(problems) => {
            for problem in problems.iter().take(MAX_PRINTED_PROBLEMS) {
                eprintln!("shutter: error: {problem}");
            }
            if problems.len() > MAX_PRINTED_PROBLEMS {
                eprintln!(
                    "shutter: error: ... and {} more problems",
                    problems.len() - MAX_PRINTED_PROBLEMS
                );
            }
            if problems.len() > 1 {
                eprintln!(
                    "shutter: {} problems found; nothing was written for the frames concerned",
                    problems.len()
                );
            }
        }
    }
}

/// Turns the blur arguments into a job: the second phase of argument handling.
pub fn resolve(args: &BlurArgs) -> Result<Job> {
    let mut preset = Preset::load(&args.preset)?;
    let dof = dof_params(&args.dof, &mut preset)?;
    let algorithm_name = args
        .algorithm
        .clone()
        .or_else(|| preset.blur.algorithm.clone())
        .unwrap_or_else(|| "none".into());
    let algorithm = Algorithm::parse(&algorithm_name).ok_or_else(|| {
        let names: Vec<&str> = Algorithm::ALL.iter().map(|(n, _)| *n).collect();
        Error::usage(format!(
            "unknown algorithm '{algorithm_name}'; available: {}",
            names.join(", ")
        ))
    })?;
    let shutter = args.shutter.or(preset.blur.shutter).unwrap_or(0.5);
    if !(0.0..=1.0).contains(&shutter) {
        return Err(Error::usage(format!(
            "--shutter {shutter} is outside 0..1 (the fraction of the frame the shutter is open)"
        )));
    }

    let pattern = |p: &Option<String>| p.as_deref().map(PathPattern::parse).transpose();
    if args.dof.coc_map.is_some() && args.depth.is_some() {
        return Err(Error::usage(
            "--coc-map is read in place of depth: give --coc-map or --depth, not both",
        ));
    }
    let inputs = Inputs {
        color: PathPattern::parse(&args.color)?,
        depth: pattern(&args.depth.clone().or_else(|| args.dof.coc_map.clone()))?,
        velocity: pattern(&args.velocity)?,
        prev: pattern(&args.prev)?,
        next: pattern(&args.next)?,
    };
    let output = PathPattern::parse(&args.output)?;
    if OutputFormat::from_path(&output.path(None)).is_none() {
        return Err(Error::usage(format!(
            "-o {}: unknown output format; use .exr, .png, .tif, .tiff, .jpg or .jpeg",
            args.output
        )));
    }

    let frames: Vec<Option<i64>> = match (&args.frames, inputs.is_sequence()) {
        (Some(_), false) => {
            return Err(Error::usage(
                "--frames needs a sequence: give the inputs as patterns with #### or %04d",
            ))
        }
        (Some(spec), true) => parse_frames(spec)?.into_iter().map(Some).collect(),
        (None, true) => {
            let source = inputs
                .all()
                .into_iter()
                .map(|(_, p)| p)
                .find(|p| p.is_sequence())
                .expect("is_sequence");
            let found = source.discover()?;
            if found.is_empty() {
                return Err(Error::usage(format!(
                    "no files match '{}'; check the pattern or pass --frames",
                    source.raw
                )));
            }
            found.into_iter().map(Some).collect()
        }
        (None, false) => vec![None],
    };
    if inputs.is_sequence() && !output.is_sequence() {
        return Err(Error::usage(
            "-o must be a pattern with #### or %04d when the inputs are a sequence",
        ));
    }
    if !inputs.is_sequence() && output.is_sequence() {
        return Err(Error::usage(
            "-o is a frame pattern but the inputs are single files; give input patterns and --frames",
        ));
    }

    let compression_name = args
        .compression
        .clone()
        .or_else(|| preset.output.compression.clone())
        .unwrap_or_else(|| "zip".into());
    let compression = parse_compression(&compression_name).ok_or_else(|| {
        Error::usage(format!(
            "unknown compression '{compression_name}'; use one of {}",
            WRITABLE_COMPRESSIONS.join(", ")
        ))
    })?;
    let bit_depth = args.bit_depth.or(preset.output.bit_depth).unwrap_or(8);
    if bit_depth != 8 && bit_depth != 16 {
        return Err(Error::usage(format!(
            "--bit-depth {bit_depth}: use 8 or 16"
        )));
    }
    let reconstruct = reconstruct_params(args, &preset)?;
    let scatter = scatter_params(args, &preset)?;
    let stretch = stretch_params(args, &preset, scatter.depth_tolerance)?;
    if args.linear {
        preset.color.transfer = Transfer::Linear;
    }
    let output_options = OutputOptions {
        exr: ExrOptions {
            compression,
            half: args.half || preset.output.half.unwrap_or(false),
        },
        sixteen_bit: bit_depth == 16,
        srgb: preset.color.transfer == Transfer::Srgb,
    };

    Ok(Job {
        inputs,
        output,
        frames,
        preset,
        layer: args.layer.clone(),
        algorithm,
        params: BlurParams {
            shutter,
            reconstruct,
            scatter,
            stretch,
            dof,
        },
        output_options,
        skip_existing: args.skip_existing,
    })
}

fn reconstruct_params(args: &BlurArgs, preset: &Preset) -> Result<ReconstructParams> {
    let defaults = ReconstructParams::default();
    let blur = &preset.blur;
    let max_blur = args.max_blur.or(blur.max_blur).unwrap_or(defaults.max_blur);
    if !(1..=512).contains(&max_blur) {
        return Err(Error::usage(format!(
            "--max-blur {max_blur}: use 1 to 512 pixels"
        )));
    }
    let taps = args.samples.or(blur.samples).unwrap_or(defaults.taps);
    if taps.is_multiple_of(2) || !(1..=255).contains(&taps) {
        return Err(Error::usage(format!(
            "--samples {taps}: use an odd number from 1 to 255"
        )));
    }
    let soft_z = args.soft_z.or(blur.soft_z).unwrap_or(defaults.soft_z);
    if !(soft_z.is_finite() && soft_z > 0.0) {
        return Err(Error::usage(format!(
            "--soft-z {soft_z}: use a positive depth extent in scene units"
        )));
    }
    let variant_name = args
        .variant
        .clone()
        .or_else(|| blur.variant.clone())
        .unwrap_or_else(|| "paper".into());
    let variant = match variant_name.as_str() {
        "paper" => Variant::Paper,
        "dual" => Variant::Dual,
        other => {
            return Err(Error::usage(format!(
                "--variant {other}: use paper or dual"
            )))
        }
    };
    Ok(ReconstructParams {
        max_blur,
        taps,
        soft_z,
        jitter: !args.no_jitter && blur.jitter.unwrap_or(defaults.jitter),
        variant,
    })
}

/// One of `choices` (name, value) by name, or a usage error naming the flag.
fn choose<T: Copy>(flag: &str, name: &str, choices: &[(&str, T)]) -> Result<T> {
    choices
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, v)| *v)
        .ok_or_else(|| {
            let names: Vec<&str> = choices.iter().map(|(n, _)| *n).collect();
            Error::usage(format!("--{flag} {name}: use {}", names.join(" or ")))
        })
}

fn scatter_params(args: &BlurArgs, preset: &Preset) -> Result<ScatterParams> {
    let defaults = ScatterParams::default();
    let blur = &preset.blur;
    let max_blur = args
        .max_blur
        .or(blur.max_blur)
        .map_or(defaults.max_blur, |m| m as f32);
    let segments = args.segments.or(blur.segments).unwrap_or(defaults.segments);
    if !(1..=scatter::MOST_SEGMENTS).contains(&segments) {
        return Err(Error::usage(format!(
            "--segments {segments}: use 1 to {}",
            scatter::MOST_SEGMENTS
        )));
    }
    let sigma = args.sigma.or(blur.sigma).unwrap_or(defaults.sigma);
    if !(sigma.is_finite() && sigma >= 0.01) {
        return Err(Error::usage(format!(
            "--sigma {sigma}: use at least 0.01 (units of the frame interval, 0..1)"
        )));
    }
    let background_weight = args
        .background_weight
        .or(blur.background_weight)
        .unwrap_or(defaults.background_weight);
    if !(background_weight.is_finite() && background_weight >= 0.0) {
        return Err(Error::usage(format!(
            "--background-weight {background_weight}: use a finite weight of 0 or more"
        )));
    }
    let flatness = args.flatness.or(blur.flatness).unwrap_or(defaults.flatness);
    if !(flatness.is_finite() && flatness >= 0.0) {
        return Err(Error::usage(format!(
            "--flatness {flatness}: use 0 or more pixels"
        )));
    }
    let depth_tolerance = args
        .depth_tolerance
        .or(blur.depth_tolerance)
        .unwrap_or(defaults.depth_tolerance);
    if !(depth_tolerance.is_finite() && depth_tolerance >= 0.0) {
        return Err(Error::usage(format!(
            "--depth-tolerance {depth_tolerance}: use 0 or more (relative)"
        )));
    }
    let pick = |arg: &Option<String>, key: &Option<String>| arg.clone().or_else(|| key.clone());
    let weight = match pick(&args.weight, &blur.weight) {
        Some(name) => choose(
            "weight",
            &name,
            &[("gaussian", Weight::Gaussian), ("box", Weight::Box)],
        )?,
        None => defaults.weight,
    };
    let normalize = match pick(&args.normalize, &blur.normalize) {
        Some(name) => choose(
            "normalize",
            &name,
            &[
                ("paper", Normalize::Paper),
                ("exposure", Normalize::Exposure),
            ],
        )?,
        None => defaults.normalize,
    };
    let curve = match pick(&args.curve, &blur.curve) {
        Some(name) => choose(
            "curve",
            &name,
            &[("bezier", CurveKind::Bezier), ("arc", CurveKind::Arc)],
        )?,
        None => defaults.curve,
    };
    Ok(ScatterParams {
        segments,
        sigma,
        weight,
        background_weight,
        normalize,
        curve,
        max_blur,
        flatness,
        depth_tolerance,
    })
}

fn stretch_params(args: &BlurArgs, preset: &Preset, depth_tolerance: f32) -> Result<StretchParams> {
    let defaults = StretchParams::default();
    let blur = &preset.blur;
    let extent = args.extent.or(blur.extent).unwrap_or(defaults.extent);
    if !(extent.is_finite() && extent > 0.0) {
        return Err(Error::usage(format!(
            "--extent {extent}: use a positive length in pixels"
        )));
    }
    let min_alpha = args
        .min_alpha
        .or(blur.min_alpha)
        .unwrap_or(defaults.min_alpha);
    if !(0.0..=1.0).contains(&min_alpha) {
        return Err(Error::usage(format!("--min-alpha {min_alpha}: use 0 to 1")));
    }
    let tear = args.tear.or(blur.tear).unwrap_or(defaults.tear);
    if !(tear.is_finite() && tear >= 0.0) {
        return Err(Error::usage(format!(
            "--tear {tear}: use 0 or more (relative depth step)"
        )));
    }
    let anchor = match args.anchor.clone().or_else(|| blur.anchor.clone()) {
        Some(name) => choose(
            "anchor",
            &name,
            &[("centre", Anchor::Centre), ("rear", Anchor::Rear)],
        )?,
        None => defaults.anchor,
    };
    Ok(StretchParams {
        extent,
        min_alpha,
        tear,
        anchor,
        texture_blur: !args.no_texture_blur && blur.texture_blur.unwrap_or(defaults.texture_blur),
        depth_tolerance,
    })
}

/// Depth of field from the flags over the preset's [dof] section: `None` when neither a lens
/// nor a CoC map is given. A CoC map is read through the depth pass with its stored values
/// kept as they are.
fn dof_params(args: &DofArgs, preset: &mut Preset) -> Result<Option<DofParams>> {
    let settings = preset.dof.clone();
    let focal = args.focal_length.or(settings.focal_length);
    let f_stop = args.f_stop.or(settings.f_stop);
    let focus = args.focus_distance.or(settings.focus_distance);
    let source =
        if args.coc_map.is_some() {
            let scale = args.coc_scale.or(settings.coc_scale).unwrap_or(32.0);
            preset.depth.near = Some(0.0);
            preset.depth.far = Some(1.0);
            preset.depth.scale = 1.0;
            for name in ["Y", "R", "Z"] {
                if !preset.depth.channels.iter().any(|c| c == name) {
                    preset.depth.channels.push(name.into());
                }
            }
            CocSource::Map { scale }
        } else {
            match (focal, f_stop, focus) {
                (None, None, None) => return Ok(None),
                (Some(focal_mm), Some(f_number), Some(focus)) => CocSource::Lens(Lens {
                    focal_mm,
                    f_number,
                    focus,
                    sensor_mm: args.sensor_width.or(settings.sensor_width).unwrap_or(36.0),
                }),
                _ => return Err(Error::usage(
                    "depth of field needs all of --focal-length, --f-stop and --focus-distance \
                     (or --coc-map)",
                )),
            }
        };
    let defaults = DofParams::new(source);
    let method_name = args.method.clone().or(settings.method);
    let method = match method_name {
        Some(name) => choose("--method", &name, Method::ALL)?,
        None => defaults.method,
    };
    let params = DofParams {
        method,
        source,
        epsilon: args
            .epsilon
            .or(settings.epsilon)
            .unwrap_or(defaults.epsilon),
        max_coc: args
            .max_coc
            .or(settings.max_coc)
            .unwrap_or(defaults.max_coc),
        blades: args.blades.or(settings.blades).unwrap_or(defaults.blades),
        blade_rotation: args
            .blade_rotation
            .or(settings.blade_rotation)
            .unwrap_or(defaults.blade_rotation),
        rings: args.rings.or(settings.rings).unwrap_or(defaults.rings),
        passes: args.passes.or(settings.passes),
    };
    params.check().map_err(Error::usage)?;
    Ok(Some(params))
}

fn blur(args: BlurArgs, dof: bool) -> Result<()> {
    if let Some(threads) = args.threads {
        if threads == 0 {
            return Err(Error::usage("--threads must be at least 1"));
        }
        // The exr crate builds its own pool for each parallel write and sizes it from this
        // variable: set it so --threads bounds every pool. Nothing else runs yet.
        std::env::set_var("RAYON_NUM_THREADS", threads.to_string());
        // Fails only if the pool was already built, which cannot happen this early.
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build_global();
    }
    let job = resolve(&args)?;
    if dof && job.params.dof.is_none() {
        return Err(Error::usage(
            "shutter dof needs a lens (--focal-length, --f-stop and --focus-distance) or a \
             painted map (--coc-map PATH)",
        ));
    }
    let terminal = std::io::stderr().is_terminal();
    let verbose = args.verbose;
    let mut bar: Option<indicatif::ProgressBar> = None;
    let mut on_event = |event: Event| match event {
        Event::Started { frames } => {
            if terminal && !verbose {
                let b = indicatif::ProgressBar::new(frames as u64);
                b.set_style(
                    indicatif::ProgressStyle::with_template(
                        "{bar:40} {pos}/{len} frames  {msg}  eta {eta}",
                    )
                    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
                );
                bar = Some(b);
            } else if verbose {
                eprintln!("shutter: {frames} frames to write");
            }
        }
        Event::Written { path, .. } => match &bar {
            Some(b) => {
                b.inc(1);
                let seconds = b.elapsed().as_secs_f64().max(1e-9);
                b.set_message(format!("{:.2} frames/s", b.position() as f64 / seconds));
            }
            None if verbose => eprintln!("shutter: wrote {}", path.display()),
            None => {}
        },
        Event::Skipped { path, .. } => {
            if verbose || terminal {
                eprintln!("shutter: skipped {} (exists)", path.display());
            }
        }
        Event::Warning(message) => match &bar {
            Some(b) => b.println(format!("shutter: warning: {message}")),
            None if verbose || terminal => eprintln!("shutter: warning: {message}"),
            None => {}
        },
    };
    let result = run(&job, &mut on_event);
    if let Some(b) = bar.take() {
        b.finish_and_clear();
    }
    let report = result?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).unwrap_or_default()
        );
    } else if verbose || terminal {
        eprintln!(
            "shutter: {} frames written, {} skipped in {:.2} s (read {:.2} s, process {:.2} s, write {:.2} s)",
            report.frames_written,
            report.frames_skipped,
            report.wall_seconds,
            report.read_seconds,
            report.process_seconds,
            report.write_seconds
        );
    }
    Ok(())
}

fn info(args: InfoArgs) -> Result<()> {
    let presets: Vec<Preset> = BUILTIN
        .iter()
        .filter(|(name, _)| crate::io::preset::is_convention(name))
        .map(|(name, _)| Preset::builtin(name))
        .collect::<Result<_>>()?;
    let mut problems = Vec::new();
    let mut documents = Vec::new();
    for path in &args.files {
        let info = match FileInfo::probe(path) {
            Ok(info) => info,
            Err(problem) => {
                problems.push(problem);
                continue;
            }
        };
        let mut matches: Vec<(String, Vec<&'static str>)> = presets
            .iter()
            .map(|p| (p.name.clone(), passes_found(&info, p)))
            .filter(|(_, found)| !found.is_empty())
            .collect();
        // Best match first: most passes found; ties keep the built-in order.
        matches.sort_by_key(|(_, found)| std::cmp::Reverse(found.len()));
        if args.json {
            documents.push(info_json(&info, &matches));
        } else {
            print!("{}", info_text(&info, &matches));
        }
    }
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&documents).unwrap_or_default()
        );
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(Error::Files(problems))
    }
}

fn describe_kind(info: &FileInfo) -> String {
    match &info.kind {
        FileKind::Exr {
            compression,
            tiled,
            multipart,
        } => {
            let mut compression = compression.clone();
            compression.dedup();
            format!(
                "OpenEXR, {}, {}, {} compression",
                if *tiled { "tiled" } else { "scan lines" },
                if *multipart {
                    "multi-part"
                } else {
                    "single part"
                },
                compression.join("/")
            )
        }
        FileKind::Image {
            format,
            bits,
            float,
        } => format!(
            "{}, {bits}-bit {}",
            format.to_uppercase(),
            if *float { "float" } else { "integer" }
        ),
    }
}

fn info_text(info: &FileInfo, matches: &[(String, Vec<&'static str>)]) -> String {
    let w = &info.windows;
    let mut text = format!("{}\n", info.path.display());
    text.push_str(&format!("  format:         {}\n", describe_kind(info)));
    text.push_str(&format!(
        "  size:           {}x{}\n",
        info.width, info.height
    ));
    text.push_str(&format!(
        "  data window:    ({}, {}) - ({}, {})\n",
        w.data_origin.0,
        w.data_origin.1,
        w.data_origin.0 + info.width as i32 - 1,
        w.data_origin.1 + info.height as i32 - 1
    ));
    text.push_str(&format!(
        "  display window: ({}, {}) - ({}, {})\n",
        w.display.0,
        w.display.1,
        w.display.0 + w.display.2 as i32 - 1,
        w.display.1 + w.display.3 as i32 - 1
    ));
    text.push_str("  channels:\n");
    for c in &info.channels {
        let name = c.alias.clone().unwrap_or_else(|| c.name.clone());
        text.push_str(&format!("    {name:<28} {}\n", c.sample_type));
    }
    if matches.is_empty() {
        text.push_str("  presets:        none match; write one (see README, Presets)\n");
    } else {
        for (i, (name, found)) in matches.iter().enumerate() {
            let label = if i == 0 { "  presets:" } else { "" };
            text.push_str(&format!("{label:<18}{name} ({})\n", found.join(", ")));
        }
    }
    text
}

fn info_json(info: &FileInfo, matches: &[(String, Vec<&'static str>)]) -> serde_json::Value {
    let w = &info.windows;
    serde_json::json!({
        "path": info.path.display().to_string(),
        "format": describe_kind(info),
        "width": info.width,
        "height": info.height,
        "data_window": [w.data_origin.0, w.data_origin.1,
            w.data_origin.0 + info.width as i32 - 1, w.data_origin.1 + info.height as i32 - 1],
        "display_window": [w.display.0, w.display.1,
            w.display.0 + w.display.2 as i32 - 1, w.display.1 + w.display.3 as i32 - 1],
        "compression": match &info.kind { FileKind::Exr { compression, .. } => compression.clone(), _ => vec![] },
        "channels": info.channels.iter().map(|c| serde_json::json!({
            "name": c.alias.clone().unwrap_or_else(|| c.name.clone()),
            "type": c.sample_type,
            "part": c.part,
        })).collect::<Vec<_>>(),
        "presets": matches.iter().map(|(name, found)| serde_json::json!({
            "name": name, "passes": found,
        })).collect::<Vec<_>>(),
    })
}

fn presets(args: PresetsArgs) -> Result<()> {
    match args.command {
        None => {
            for (name, _) in BUILTIN {
                let preset = Preset::builtin(name)?;
                println!("{name:<10} {}", preset.description);
            }
            Ok(())
        }
        Some(PresetsCommand::Show { name }) => {
            if let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name) {
                print!("{text}");
                return Ok(());
            }
            // A file: check it loads, then print it as written.
            Preset::load(std::slice::from_ref(&name))?;
            let text = std::fs::read_to_string(&name)
                .map_err(|e| Error::usage(format!("cannot read {name}: {e}")))?;
            print!("{text}");
            Ok(())
        }
    }
}

/// Parses `WxH`.
pub fn parse_size(text: &str) -> Result<(usize, usize)> {
    let bad = || Error::usage(format!("bad size '{text}': use WxH, e.g. 640x360"));
    let (w, h) = text.split_once(['x', 'X']).ok_or_else(bad)?;
    let w: usize = w.trim().parse().map_err(|_| bad())?;
    let h: usize = h.trim().parse().map_err(|_| bad())?;
    if w == 0 || h == 0 || w > 16384 || h > 16384 {
        return Err(bad());
    }
    Ok((w, h))
}

fn scene(args: SceneArgs) -> Result<()> {
    let (width, height) = match &args.size {
        Some(size) => parse_size(size)?,
        None => crate::truth::write::DEFAULT_SIZE,
    };
    let options = crate::truth::write::SceneOptions {
        width,
        height,
        frames: args.frames,
        samples: args.samples,
        shutter: args.shutter,
        seed: args.seed,
    };
    let verbose = std::io::stderr().is_terminal();
    let description =
        crate::truth::write::write_scene(&args.name, &args.output, &options, &mut |frame, _| {
            if verbose {
                eprintln!("shutter: scene {} frame {frame} written", args.name);
            }
        })?;
    if verbose {
        eprintln!(
            "shutter: {} frames of {} in {}",
            description.frames,
            description.scene,
            args.output.display()
        );
    }
    Ok(())
}

/// Frames for a pair of patterns: `--frames`, else those on disk for the first.
fn frames_for(
    first: &PathPattern,
    others: &[&PathPattern],
    spec: Option<&str>,
) -> Result<Vec<Option<i64>>> {
    let sequence = first.is_sequence();
    if others.iter().any(|p| p.is_sequence() != sequence) {
        return Err(Error::usage(
            "give all paths as patterns (#### or %04d) or all as single files",
        ));
    }
    match (spec, sequence) {
        (Some(_), false) => Err(Error::usage("--frames needs patterns with #### or %04d")),
        (Some(spec), true) => Ok(parse_frames(spec)?.into_iter().map(Some).collect()),
        (None, true) => {
            let found = first.discover()?;
            if found.is_empty() {
                return Err(Error::usage(format!(
                    "no files match '{}'; check the pattern or pass --frames",
                    first.raw
                )));
            }
            Ok(found.into_iter().map(Some).collect())
        }
        (None, false) => Ok(vec![None]),
    }
}

fn format_scores(s: &crate::metrics::Scores) -> String {
    format!(
        "rmse {:.6}  psnr {:.2} dB  ssim {:.5}  flip {:.5}  ({} px{})",
        s.rmse,
        s.psnr,
        s.ssim,
        s.flip,
        s.pixels,
        if s.non_finite > 0 {
            format!(", {} non-finite samples", s.non_finite)
        } else {
            String::new()
        }
    )
}

fn diff(args: DiffArgs) -> Result<i32> {
    let metric = crate::metrics::Metric::parse(&args.metric).ok_or_else(|| {
        Error::usage(format!(
            "unknown metric '{}'; use rmse, psnr, ssim or flip",
            args.metric
        ))
    })?;
    for (flag, value) in [("--warn", args.warn), ("--fail", args.fail)] {
        if value.is_some_and(|v| !v.is_finite()) {
            return Err(Error::usage(format!("{flag} must be a finite number")));
        }
    }
    let a = PathPattern::parse(&args.a)?;
    let b = PathPattern::parse(&args.b)?;
    let sharp = args.sharp.as_deref().map(PathPattern::parse).transpose()?;
    let heatmap = args
        .heatmap
        .as_deref()
        .map(PathPattern::parse)
        .transpose()?;
    let mut others = vec![&b];
    others.extend(sharp.as_ref());
    let frames = frames_for(&a, &others, args.frames.as_deref())?;
    if let Some(heatmap) = &heatmap {
        if frames.len() > 1 && !heatmap.is_sequence() {
            return Err(Error::usage(
                "--heatmap must be a pattern with #### or %04d when comparing sequences",
            ));
        }
    }
    let job = crate::diff::DiffJob {
        a,
        b,
        sharp,
        frames,
        metric,
        warn: args.warn,
        fail: args.fail,
        heatmap,
        preset: Preset::load(&args.preset)?,
        linear: args.linear,
    };
    let report = crate::diff::run(&job)?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&report).unwrap_or_default()
        );
    } else {
        for f in &report.frames {
            let label = f.frame.map_or(String::new(), |n| format!("frame {n}: "));
            println!("{label}{}", format_scores(&f.whole));
            if let Some(region) = &f.region {
                println!("{label}changed region: {}", format_scores(region));
            }
        }
        if report.frames.len() > 1 {
            println!(
                "worst {}: {:.6} over {} frames",
                report.metric,
                report.worst,
                report.frames.len()
            );
        }
    }
    for warning in &report.warnings {
        eprintln!("shutter: warning: {warning}");
    }
    if report.failed {
        let failed = report.frames.iter().filter(|f| f.failed).count();
        eprintln!(
            "shutter: FAIL: {failed} of {} frames have {} worse than --fail {}",
            report.frames.len(),
            report.metric,
            args.fail.unwrap_or_default()
        );
        return Ok(1);
    }
    Ok(0)
}

fn bench(args: BenchArgs) -> Result<()> {
    let (width, height) = match &args.size {
        Some(size) => parse_size(size)?,
        None => (320, 180),
    };
    let scenes = match &args.scenes {
        Some(list) => list.split(',').map(|s| s.trim().to_string()).collect(),
        None => crate::truth::scenes::SCENES
            .iter()
            .map(|(n, _)| n.to_string())
            .collect(),
    };
    let binary = std::env::current_exe()
        .map_err(|e| Error::usage(format!("cannot find the shutter binary: {e}")))?;
    let options = crate::bench::BenchOptions {
        scenes,
        width,
        height,
        out: args.out.clone(),
        samples: args.samples,
        runs: args.runs,
        binary,
    };
    let started = std::time::Instant::now();
    let report = crate::bench::run(&options, &mut |line| eprintln!("shutter: bench: {line}"))?;
    print!("{}", crate::bench::markdown(&report));
    eprintln!(
        "shutter: bench: {} rows in {:.1} s; wrote {}/bench.json, bench.md, pareto.svg, pareto.png, contact/",
        report.rows.len(),
        started.elapsed().as_secs_f64(),
        args.out.display()
    );
    Ok(())
}
