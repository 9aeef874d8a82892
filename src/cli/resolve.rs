//! The second phase of argument handling: what the user typed (clap's `BlurArgs`) and the
//! presets it names, resolved into a [`Job`] (settings through `crate::settings`, the
//! inputs, output and frames listed).

use crate::error::{Error, Result};
use crate::io::output::{OutputFormat, OutputOptions};
use crate::io::passes::Inputs;
use crate::io::preset::{Encoding, Preset, Transfer};
use crate::io::sequence::{parse_frames, PathPattern};
use crate::pipeline::Job;
use crate::process::Params;
use crate::settings::{self};

use super::args::BlurArgs;

/// Turns the blur arguments into a job: the second phase of argument handling.
/// Warnings for output flags the chosen format cannot use (given on the command line; a
/// preset's output section serves every format, so its keys are not warned about).
fn output_warnings(given: &settings::Given, format: OutputFormat) -> Vec<String> {
    use crate::io::image::ImageFormat;
    let typed = |name: &str| given.get(name).is_some();
    let mut warnings = Vec::new();
    let exr = format == OutputFormat::Exr;
    for flag in ["half", "compression"] {
        if typed(flag) && !exr {
            warnings.push(format!(
                "--{flag} applies to EXR output, not this -o: it has no effect"
            ));
        }
    }
    if typed("jpeg-quality") && format != OutputFormat::Image(ImageFormat::Jpeg) {
        warnings
            .push("--jpeg-quality applies to JPEG output, not this -o: it has no effect".into());
    }
    if typed("bit-depth") {
        match format {
            OutputFormat::Exr => warnings.push(
                "--bit-depth applies to PNG and TIFF output, not EXR (use --half): it has no \
                 effect"
                    .into(),
            ),
            OutputFormat::Image(ImageFormat::Jpeg) => warnings.push(
                "--bit-depth applies to PNG and TIFF output; JPEG is always 8-bit: it has no \
                 effect"
                    .into(),
            ),
            OutputFormat::Image(_) => {}
        }
    }
    warnings
}

pub fn resolve(args: &BlurArgs) -> Result<Job> {
    let mut preset = Preset::load(&args.preset)?;
    let mut displace_warning = None;
    if let Some(px) = args.max_displace {
        if !(px.is_finite() && px > 0.0) {
            return Err(Error::usage(format!(
                "--max-displace {px}: must be a positive number of pixels"
            )));
        }
        let mut any = false;
        for spec in [&mut preset.velocity, &mut preset.prev, &mut preset.next] {
            if spec.encoding == Encoding::Rsmb {
                spec.max_displace = Some(px);
                any = true;
            }
        }
        if !any {
            displace_warning = Some(format!(
                "--max-displace {px}: preset {} reads no RE:Vision-encoded vectors, so it has \
                 no effect (the rsmb preset does)",
                preset.name
            ));
        }
    }
    preset.check_complete()?;
    let (settings, warnings) = settings::resolve(&args.settings.0, &preset)?;
    let dof = settings::dof_params(&settings, args.coc_map.is_some())?;
    if args.coc_map.is_some() {
        // A CoC map is read through the depth pass with its stored values kept as they are.
        preset.depth.near = Some(0.0);
        preset.depth.far = Some(1.0);
        preset.depth.scale = 1.0;
        for name in ["Y", "R", "Z"] {
            if !preset.depth.channels.iter().any(|c| c == name) {
                preset.depth.channels.push(name.into());
            }
        }
    }

    let pattern = |p: &Option<String>| p.as_deref().map(PathPattern::parse).transpose();
    if args.coc_map.is_some() && args.depth.is_some() {
        return Err(Error::usage(
            "--coc-map is read in place of depth: give --coc-map or --depth, not both",
        ));
    }
    let inputs = Inputs {
        color: PathPattern::parse(&args.color)?,
        depth: pattern(&args.depth.clone().or_else(|| args.coc_map.clone()))?,
        velocity: pattern(&args.velocity)?,
        prev: pattern(&args.prev)?,
        next: pattern(&args.next)?,
    };
    let output = PathPattern::parse(&args.output)?;
    let Some(format) = OutputFormat::from_path(&output.path(None)) else {
        return Err(Error::usage(format!(
            "-o {}: unknown output format; use .exr, .png, .tif, .tiff, .jpg or .jpeg",
            args.output
        )));
    };
    let mut warnings = warnings;
    warnings.extend(displace_warning);
    warnings.extend(output_warnings(&args.settings.0, format));
    if let Some(layer) = &args.layer {
        if !preset.channel_names().any(|n| n.contains("{layer}")) {
            warnings.push(format!(
                "--layer {layer}: preset {} names no channel by view layer, so it has no \
                 effect (the blender preset does)",
                preset.name
            ));
        }
    }

    let stack = args.layers.clone();
    if !stack.is_empty() {
        if !preset.channel_names().any(|n| n.contains("{layer}")) {
            return Err(Error::usage(format!(
                "--layers: preset {} names no channel by view layer, so every layer would \
                 read the same channels (the blender preset names them, or a preset of \
                 your own with {{layer}} in its channel names)",
                preset.name
            )));
        }
        if let Some(name) = (0..stack.len()).find_map(|i| {
            (stack[..i].contains(&stack[i]) || stack[i].is_empty()).then(|| &stack[i])
        }) {
            return Err(Error::usage(format!(
                "--layers names each view layer once, front first (FG,BG); '{name}' is not"
            )));
        }
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
                // Bad input (exit 1), not a bad command: the files are not there.
                return Err(Error::Files(vec![crate::error::Problem::new(
                    crate::error::ProblemKind::MissingFile,
                    std::path::Path::new(&source.raw),
                    "no files match the pattern; check it, or pass --frames",
                )]));
            }
            // Holes in a sequence found on disk: a render that left frames out.
            let holes = crate::io::sequence::holes(&found);
            if !holes.is_empty() {
                warnings.push(format!(
                    "'{}' has no frame{} {}: {} frame{} missing between {} and {} (they are \
                     not written; --frames names every frame wanted and makes a missing one \
                     an error)",
                    source.raw,
                    if holes.len() == 1 { "" } else { "s" },
                    crate::io::sequence::format_frames(&holes),
                    holes.len(),
                    if holes.len() == 1 { " is" } else { "s are" },
                    found[0],
                    found[found.len() - 1]
                ));
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

    if args.linear {
        preset.color.transfer = Transfer::Linear;
    }
    // An EXR output records what made it (`shutter/settings`): the preset and every setting
    // that is not its default, as flags. Not how the job ran (threads, frame ranges, paths,
    // the backend, the pixel limit): a frame the GPU's fallback made on the CPU is the CPU's
    // frame, byte for byte.
    let mut record = vec![format!("--preset {}", preset.name)];
    let defaults = settings::Settings::default();
    record.extend(settings::flags(&settings::Settings {
        backend: defaults.backend,
        max_pixels: defaults.max_pixels,
        max_memory: defaults.max_memory,
        ..settings.clone()
    }));
    let output_options = OutputOptions {
        srgb: preset.color.transfer == Transfer::Srgb,
        record: record.join(" "),
        ..settings.output.clone()
    };

    Ok(Job {
        inputs,
        output,
        frames,
        preset,
        layer: args.layer.clone(),
        stack,
        view: args.view.clone(),
        algorithm: settings.algorithm,
        params: Params {
            dof,
            ..settings.params
        },
        output_options,
        skip_existing: args.skip_existing,
        dry_run: args.dry_run,
        backend: settings.backend,
        max_pixels: settings.max_pixels,
        max_memory: settings.max_memory.map(|mib| mib << 20),
        warnings,
        check_vectors: match args.check_vectors.as_str() {
            "on" => true,
            "off" => false,
            other => {
                return Err(Error::usage(format!(
                    "--check-vectors takes on or off, not '{other}'"
                )))
            }
        },
    })
}
