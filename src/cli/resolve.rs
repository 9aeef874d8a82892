//! The second phase of argument handling: what the user typed (clap's `BlurArgs`) and the
//! presets it names, resolved into a [`Job`] (settings through `crate::settings`, the
//! inputs, output and frames listed).

use crate::error::{Error, Result};
use crate::io::image::ImageFormat;
use crate::io::output::{OutputFormat, OutputOptions};
use crate::io::passes::Inputs;
use crate::io::preset::{Encoding, Preset, Transfer};
use crate::io::sequence::{parse_frames, PathPattern};
use crate::pipeline::{Job, StackLayer};
use crate::process::Params;
use crate::settings::{self};

use super::args::BlurArgs;

/// Why a pattern found no frames on disk: none match, or those that do are numbered beyond
/// the limit (`note`, from [`crate::io::sequence::Discovered::beyond_note`]).
pub(super) fn no_match(note: Option<String>) -> String {
    let none = "no files match the pattern; check it, or pass --frames";
    match note {
        Some(note) => format!("{none} ({note})"),
        None => none.to_string(),
    }
}

/// Every pass a pattern when the colour is one, and a file when it is a file (README,
/// "Sequences": inputs and output are all patterns or all files): a single file beside a
/// colour pattern would be read for every frame of it, and a colour file beside a pass
/// pattern for every frame of that. `coc_map`: the depth given is `--coc-map`.
fn one_form(inputs: &Inputs, coc_map: bool) -> Result<()> {
    let sequence = inputs.color.is_sequence();
    let Some((pass, mixed)) = inputs
        .all()
        .into_iter()
        .find(|(_, p)| p.is_sequence() != sequence)
    else {
        return Ok(());
    };
    let flag = if pass == "depth" && coc_map {
        "coc-map"
    } else {
        pass
    };
    Err(Error::usage(if sequence {
        format!(
            "--{flag} '{}' is one file but --color '{}' is a sequence, and one file is not \
             read for every frame: give --{flag} as a pattern too, {}",
            mixed.raw,
            inputs.color.raw,
            as_pattern(&mixed.raw)
        )
    } else {
        format!(
            "--color '{}' is one file but --{flag} '{}' is a sequence: give --color as a \
             pattern too, {} (or --{flag} as one file)",
            inputs.color.raw,
            mixed.raw,
            as_pattern(&inputs.color.raw)
        )
    }))
}

/// A pattern to suggest for the file `path`: the last run of digits in its file name as `#`s
/// (`seq/depth.0001.exr` → `seq/depth.####.exr`).
fn as_pattern(path: &str) -> String {
    let name = crate::io::sequence::name_start(path);
    match path[name..].rfind(|c: char| c.is_ascii_digit()) {
        Some(last) => {
            let end = name + last + 1;
            let start = path[..end]
                .trim_end_matches(|c: char| c.is_ascii_digit())
                .len();
            format!(
                "e.g. '{}{}{}'",
                &path[..start],
                "#".repeat(end - start),
                &path[end..]
            )
        }
        None => "with #### or %04d for the frame number".to_string(),
    }
}

/// Turns the blur arguments into a job: the second phase of argument handling.
/// Warnings for output flags the chosen format cannot use (given on the command line; a
/// preset's output section serves every format, so its keys are not warned about).
fn output_warnings(given: &settings::Given, format: OutputFormat) -> Vec<String> {
    let typed = |name: &str| given.get(name).is_some();
    let mut warnings = Vec::new();
    for flag in ["half", "compression", "jpeg-quality", "bit-depth"] {
        if !typed(flag) || applies(flag, format) {
            continue;
        }
        warnings.push(match (flag, format) {
            ("half" | "compression", _) => {
                format!("--{flag} applies to EXR output, not this -o: it has no effect")
            }
            ("jpeg-quality", _) => {
                "--jpeg-quality applies to JPEG output, not this -o: it has no effect".into()
            }
            (_, OutputFormat::Exr) => "--bit-depth applies to PNG and TIFF output, not EXR (use \
                                      --half): it has no effect"
                .into(),
            _ => "--bit-depth applies to PNG and TIFF output; JPEG is always 8-bit: it has no \
                  effect"
                .into(),
        });
    }
    warnings
}

/// Whether the output setting `flag` changes what a `format` output holds: EXR's --half,
/// --compression and --beauty-only, JPEG's --jpeg-quality, PNG's and TIFF's --bit-depth. One
/// that does not is warned about when given, and left out of the settings record.
fn applies(flag: &str, format: OutputFormat) -> bool {
    let exr = format == OutputFormat::Exr;
    let jpeg = format == OutputFormat::Image(ImageFormat::Jpeg);
    match flag {
        "half" | "compression" | "beauty-only" => exr,
        "jpeg-quality" => jpeg,
        "bit-depth" => !exr && !jpeg,
        _ => true,
    }
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
    let (settings, mut warnings) = settings::resolve(&args.settings.0, &preset)?;
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

    if args.coc_map.is_some() && !args.depth.is_empty() {
        return Err(Error::usage(
            "--coc-map is read in place of depth: give --coc-map or --depth, not both",
        ));
    }
    // A painted map is the blur: a lens given beside it would not be read (a preset's lens
    // may stay, unread, under a map given for one shot).
    let given = &args.settings.0;
    let lens: Vec<String> = ["focal-length", "f-stop", "focus-distance", "sensor-width"]
        .iter()
        .filter(|name| given.get(name).is_some())
        .map(|name| format!("--{name}"))
        .collect();
    if args.coc_map.is_some() && !lens.is_empty() {
        return Err(Error::usage(format!(
            "--coc-map paints each pixel's blur in place of a lens and depth: {} would not be \
             read; give the lens (with depth) or --coc-map, not both",
            lens.join(", ")
        )));
    }
    if args.coc_map.is_none() && given.get("coc-scale").is_some() {
        warnings.push(
            "--coc-scale applies to a painted map (--coc-map), not a lens: it has no effect".into(),
        );
    }
    // One colour file, or one a layer (a stack rendered one file per layer): each other pass
    // given not at all (found in the colour file), or once per colour file.
    let count = args.color.len();
    for (flag, given) in [
        ("depth", &args.depth),
        ("velocity", &args.velocity),
        ("prev", &args.prev),
        ("next", &args.next),
    ] {
        if !given.is_empty() && given.len() != count {
            return Err(Error::usage(format!(
                "--{flag} is given {} times and --color {count}: give it once per colour file \
                 (a stack of one file per layer, front first), or not at all to find it in \
                 each colour file",
                given.len()
            )));
        }
    }
    if count > 1 && args.coc_map.is_some() {
        return Err(Error::usage(
            "--coc-map paints one picture's blur: it does not go with a stack of one colour \
             file per layer (give each layer's depth with --depth)",
        ));
    }
    let pattern = |p: Option<&String>| p.map(|p| PathPattern::parse(p)).transpose();
    let mut layer_inputs = Vec::with_capacity(count);
    for k in 0..count {
        layer_inputs.push(Inputs {
            color: PathPattern::parse(&args.color[k])?,
            depth: pattern(args.depth.get(k).or(args.coc_map.as_ref()))?,
            velocity: pattern(args.velocity.get(k))?,
            prev: pattern(args.prev.get(k))?,
            next: pattern(args.next.get(k))?,
        });
    }
    for inputs in &layer_inputs {
        one_form(inputs, args.coc_map.is_some())?;
    }
    if layer_inputs
        .iter()
        .any(|i| i.is_sequence() != layer_inputs[0].is_sequence())
    {
        return Err(Error::usage(
            "the colour files of a stack are all sequences (#### or %04d) or all single files",
        ));
    }
    let inputs = layer_inputs[0].clone();
    let output = PathPattern::parse(&args.output)?;
    let Some(format) = OutputFormat::from_path(&output.path(None)) else {
        return Err(Error::usage(format!(
            "-o {}: unknown output format; use .exr, .png, .tif, .tiff, .jpg or .jpeg",
            args.output
        )));
    };
    // (JPEG and EXR outputs ignore a bit depth, with a warning: `output_warnings`.)
    if settings.output.bit_depth == Some(32) && format == OutputFormat::Image(ImageFormat::Png) {
        return Err(Error::usage(format!(
            "bit depth 32 (float) is for TIFF output: -o {} is a PNG, which holds no float \
             samples; write a .tif or .exr, or use --bit-depth 16",
            args.output
        )));
    }
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

    let stack = stack_of(args, &preset, &layer_inputs, &mut warnings)?;
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
            let discovered = source.discover()?;
            let beyond = discovered.beyond_note(source);
            let padding = discovered.padding_note(source);
            let found = discovered.frames;
            if found.is_empty() {
                // Bad input (exit 1), not a bad command: the files are not there.
                return Err(Error::Files(vec![crate::error::Problem::new(
                    crate::error::ProblemKind::MissingFile,
                    std::path::Path::new(&source.raw),
                    no_match(beyond.or(padding)),
                )]));
            }
            warnings.extend(beyond);
            // Holes in a sequence found on disk: a render that left frames out.
            let holes = crate::io::holes::holes(&found);
            if !holes.is_empty() {
                warnings.push(format!(
                    "'{}' has no frame{} {}: {} frame{} missing between {} and {}{} (they are \
                     not written; --frames names every frame wanted and makes a missing one \
                     an error)",
                    source.raw,
                    if holes.len() == 1 { "" } else { "s" },
                    crate::io::sequence::format_frames(&holes),
                    holes.len(),
                    if holes.len() == 1 { " is" } else { "s are" },
                    found[0],
                    found[found.len() - 1],
                    crate::io::holes::mixed_steps(&found)
                        .map_or(String::new(), |m| format!("; {m}"))
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
    // Nor an output setting this -o cannot use (a JPEG's quality on a PNG, --half on a
    // TIFF), which changes nothing: recorded, dropping it would redo every frame.
    let mut record = vec![format!("--preset {}", preset.name)];
    let defaults = settings::Settings::default();
    let mut made = settings::Settings {
        backend: defaults.backend,
        max_pixels: defaults.max_pixels,
        max_memory: defaults.max_memory,
        ..settings.clone()
    };
    if !applies("half", format) {
        made.output.exr = defaults.output.exr;
    }
    if !applies("beauty-only", format) {
        made.output.beauty_only = defaults.output.beauty_only;
    }
    if !applies("jpeg-quality", format) {
        made.output.jpeg_quality = defaults.output.jpeg_quality;
    }
    if !applies("bit-depth", format) {
        made.output.bit_depth = defaults.output.bit_depth;
    }
    record.extend(settings::flags(&made));
    // The transfer 8/16-bit colour is read and written with (--linear, or a preset's
    // [color] transfer, which its name alone does not say), where an 8/16-bit file has one.
    // (Every colour file a stack's layers read included: one PNG layer among EXRs is enough.)
    let picture_in = (stack.iter().filter_map(|l| l.inputs.as_ref()))
        .chain([&inputs])
        .any(|i| OutputFormat::from_path(&i.color.path(None)) != Some(OutputFormat::Exr));
    if preset.color.transfer == Transfer::Linear && (picture_in || format != OutputFormat::Exr) {
        record.push("--linear".into());
    }
    // Which view layers made it: one read alone, or a stack, front first (a name with a
    // space quoted, as a shell would need it: Blender's "View Layer").
    let quoted = |v: String| {
        if v.contains(char::is_whitespace) {
            format!("'{v}'")
        } else {
            v
        }
    };
    if let Some(layer) = &args.layer {
        record.push(format!("--layer {}", quoted(layer.clone())));
    }
    if stack.len() > 1 {
        let names: Vec<&str> = stack.iter().map(|l| l.name.as_str()).collect();
        record.push(format!("--layers {}", quoted(names.join(","))));
    }
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

/// The stack of view layers a job blurs and merges (`crate::stack`), front first: one file a
/// layer (`--color` repeated; `--layers` names them, else each file's name does), or the view
/// layers `--layers` names in one file. Empty: no stack.
fn stack_of(
    args: &BlurArgs,
    preset: &Preset,
    inputs: &[Inputs],
    warnings: &mut Vec<String>,
) -> Result<Vec<StackLayer>> {
    let by_layer = preset.channel_names().any(|n| n.contains("{layer}"));
    let names = &args.layers;
    if let Some(name) = (0..names.len())
        .find_map(|i| (names[..i].contains(&names[i]) || names[i].is_empty()).then(|| &names[i]))
    {
        return Err(Error::usage(format!(
            "--layers names each view layer once, front first (FG,BG); '{name}' is not"
        )));
    }
    if inputs.len() > 1 {
        if !names.is_empty() && names.len() != inputs.len() {
            return Err(Error::usage(format!(
                "--layers names {} layers and --color gives {} files: one name a file, front \
                 first",
                names.len(),
                inputs.len()
            )));
        }
        // Named by their files where --layers does not name them (`stack::file_layer_names`).
        let colours: Vec<&PathPattern> = inputs.iter().map(|i| &i.color).collect();
        let (stems, warning) = crate::stack::file_layer_names(&colours);
        if names.is_empty() {
            warnings.extend(warning);
        }
        return Ok((inputs.iter().enumerate())
            .map(|(k, inputs)| StackLayer {
                name: names.get(k).unwrap_or(&stems[k]).clone(),
                inputs: Some(inputs.clone()),
                layer: names.get(k).filter(|_| by_layer).cloned(),
            })
            .collect());
    }
    if !names.is_empty() && !by_layer {
        return Err(Error::usage(format!(
            "--layers: preset {} names no channel by view layer, so every layer would read \
             the same channels (the blender preset names them, or a preset of your own with \
             {{layer}} in its channel names; or give one --color a layer)",
            preset.name
        )));
    }
    Ok((names.iter())
        .map(|name| StackLayer {
            name: name.clone(),
            inputs: None,
            layer: Some(name.clone()),
        })
        .collect())
}
