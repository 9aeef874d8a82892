//! What the user typed, as clap parses it. Validated only for shape here; `cli::resolve`
//! turns it into a [`crate::pipeline::Job`].

use std::path::PathBuf;

use clap::{Arg, ArgAction, ArgMatches, Args, FromArgMatches, Parser, Subcommand};

use crate::settings::{Def, Given, Kind, Section, Value, DEFS};

#[derive(Debug, Parser)]
#[command(
    name = "shutter",
    version,
    about = "Adds motion blur and depth of field to rendered frame sequences",
    long_about = "Adds the camera effects a renderer left out - motion blur and depth of field - \
to rendered frame sequences, reading colour, depth, velocity and previous/next position passes \
from OpenEXR or 8/16-bit images.\n\nExit codes: 0 success; 1 a problem with an input or output \
file (missing, corrupt, too large; unwritable: permissions, a read-only file system, a folder \
in the way, a device error), found by the preflight, while decoding or while writing, or no \
GPU adapter for --backend wgpu: fix it, a retry fails the same way; 2 a usage error; 75 \
temporary (EX_TEMPFAIL): another job holds a frame's output lock, or a write failed with an \
error a retry may cure (a full disk or quota, an interrupted or timed-out write): retry, with \
--skip-existing; 128 + N stopped by signal N (130 SIGINT, 143 \
SIGTERM, 129 SIGHUP): frames written before are whole. shutter diff has codes of its own (see \
its --help)."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Blur frames: read passes, apply an algorithm, write colour. Lens flags (or a preset's
    /// [dof] section) add depth of field before the motion blur.
    Blur(Box<BlurArgs>),
    /// Depth of field from colour and depth (or a painted CoC map): the lens flags, or
    /// --coc-map. Takes every `blur` flag too: with --algorithm, motion blur runs after it.
    Dof(Box<BlurArgs>),
    /// Print what is in image files: size, windows, channels, compression, matching presets.
    Info(InfoArgs),
    /// List the built-in presets, or show one.
    Presets(PresetsArgs),
    /// Write a procedural test scene: its passes and brute-force references.
    Scene(SceneArgs),
    /// Compare two images or sequences, every channel: metrics, CI gates, a heatmap, an HTML
    /// report. Exit codes: 0 pass, 1 fail, 2 usage, 3 could not compare (an unreadable input,
    /// sizes that differ), 4 warned (with --warn-exit); --idiff gives idiff's.
    Diff(Box<DiffArgs>),
    /// Time and score every algorithm setting on the truth scenes: bench.json, bench.md,
    /// pareto.svg/.png and contact sheets.
    Bench(BenchArgs),
    /// Expand a frame spec and cut it into chunks, as a farm task runs them: prints each
    /// chunk's frames as a spec for --frames, one line per chunk (or chunk K alone).
    Frames(FramesArgs),
    /// Fit how a vector pass is stored from the frames themselves (meaning, x/y swap, y axis,
    /// zero, scale) and print the preset section that reads it.
    Vectors(VectorsArgs),
}

#[derive(Debug, Args)]
pub struct VectorsArgs {
    /// Colour: a #### / %04d pattern of a sequence (frame n and a neighbour at least).
    #[arg(long, value_name = "PATH")]
    pub color: String,

    /// The file(s) holding the vectors [default: the colour files].
    #[arg(long, value_name = "PATH")]
    pub velocity: Option<String>,

    /// The two stored channels, in the file's order [default: the first pair the preset's
    /// [velocity] section finds].
    #[arg(long, value_name = "X,Y")]
    pub channels: Option<String>,

    /// Presets for finding the colour and vector channels (see shutter presets).
    #[arg(long, value_name = "P")]
    pub preset: Vec<String>,

    /// The frame to fit at [default: the middle frame with neighbours on both sides].
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub frame: Option<i64>,

    /// Write the fitted reading as a preset file (use it after the presets given).
    #[arg(long, value_name = "FILE")]
    pub write_preset: Option<PathBuf>,

    /// Print JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct FramesArgs {
    /// A frame spec, as --frames takes it: 1001-1100, 1-100:5 (a step), 1,3,7-20:2, -10--1.
    #[arg(value_name = "SPEC", allow_hyphen_values = true)]
    pub spec: String,

    /// Frames per chunk [default: all in one].
    #[arg(long, value_name = "N")]
    pub chunk_size: Option<usize>,

    /// Print chunk K alone (counted from 0, as a Slurm array's task ids can be).
    #[arg(long, value_name = "K")]
    pub chunk: Option<usize>,

    /// Print the number of chunks instead (an array's size).
    #[arg(long, conflicts_with = "chunk")]
    pub count: bool,
}

#[derive(Debug, Args)]
pub struct BlurArgs {
    /// Preset name (shutter, blender, nuke, painted, rsmb, vray, unreal, arnold, preview, final)
    /// or path to a .toml file; repeat to merge several, later ones winning.
    #[arg(long, value_name = "P")]
    pub preset: Vec<String>,

    /// Colour pass: a file, or a sequence pattern with #### or %04d. With a multi-layer EXR
    /// the preset finds the other passes in it. Repeat it for a stack of view layers rendered
    /// one file per layer, front first (see --layers).
    #[arg(long, value_name = "PATH", required = true)]
    pub color: Vec<String>,

    /// Depth pass file or pattern (default: looked up in the colour file); once per --color.
    #[arg(long, value_name = "PATH")]
    pub depth: Vec<String>,

    /// Velocity pass file or pattern (default: looked up in the colour file); once per
    /// --color.
    #[arg(long, value_name = "PATH")]
    pub velocity: Vec<String>,

    /// Previous-position pass file or pattern (default: looked up in the colour file); once
    /// per --color.
    #[arg(long, value_name = "PATH")]
    pub prev: Vec<String>,

    /// Next-position pass file or pattern (default: looked up in the colour file); once per
    /// --color.
    #[arg(long, value_name = "PATH")]
    pub next: Vec<String>,

    /// View layer substituted for {layer} in preset channel names (default: found in the file).
    #[arg(long, value_name = "NAME")]
    pub layer: Option<String>,

    /// A stack of view layers, front first (FG,BG): each read with its name for {layer},
    /// blurred alone with its own depth and motion, and merged front over back, so what a
    /// nearer layer uncovers is what the layer behind holds. An EXR output holds the merged
    /// beauty as R, G, B, A and every layer's channels, each blurred with its own layer.
    /// With --color repeated (one file per layer), it names the files' layers [default: each
    /// file's name up to its first period].
    #[arg(
        long,
        value_name = "NAME,NAME",
        value_delimiter = ',',
        conflicts_with = "layer"
    )]
    pub layers: Vec<String>,

    /// View of multi-view (stereo) EXRs to read and write alone, e.g. right [default: an EXR
    /// output holds every view; a picture output reads each file's default view].
    #[arg(long, value_name = "NAME")]
    pub view: Option<String>,

    /// Max Displace (px) the vectors were encoded with, for presets that read RE:Vision's
    /// normalised 8/16-bit vectors (rsmb): sets max_displace on each such section.
    #[arg(long, value_name = "PX")]
    pub max_displace: Option<f32>,

    #[command(flatten)]
    pub settings: SettingArgs,

    /// A painted blurriness map (grey image or one-channel EXR, a file or pattern) instead of
    /// a lens and depth: CoC diameter = value × --coc-scale. Read in place of depth.
    #[arg(long, value_name = "PATH", help_heading = "Depth of field")]
    pub coc_map: Option<String>,

    /// Frames to process: 1001-1100, 1-100:5 (a step), 1,5,9-12, -10--1 (Open Job
    /// Description's range expressions; 1-99x2 too) [default: every frame found on disk for
    /// the colour pattern].
    #[arg(long, value_name = "SPEC", allow_hyphen_values = true)]
    pub frames: Option<String>,

    /// Output file or pattern (.exr, .png, .tif, .tiff, .jpg, .jpeg).
    #[arg(short, long, value_name = "PATH")]
    pub output: String,

    /// Integer images (8/16-bit input colour and output) hold linear values, not sRGB.
    #[arg(long)]
    pub linear: bool,

    /// Skip frames whose output already exists as a whole frame of the right size and
    /// format (an EXR also made with this run's settings), so a rerun resumes; anything else
    /// is written again, with a warning.
    #[arg(long)]
    pub skip_existing: bool,

    /// Check every input's header and list what each frame would do (write, overwrite, skip,
    /// redo) and read; read no pixels, write nothing, take no lock.
    #[arg(long)]
    pub dry_run: bool,

    /// As it blurs, fit the stored vectors of one frame it reads against its neighbours (as
    /// shutter vectors does) and warn when another reading fits clearly better than the
    /// preset's: on or off (for farms that have checked once).
    #[arg(long, value_name = "on|off", default_value = "on")]
    pub check_vectors: String,

    /// Print a JSON summary on stdout (frames, per-stage seconds, warnings).
    #[arg(long)]
    pub json: bool,

    /// Report each frame on stderr even when it is not a terminal.
    #[arg(short, long)]
    pub verbose: bool,

    /// Print no warnings on stderr (they are still in --json). Without it every warning is
    /// one line on stderr, on a terminal or a pipe (a farm's log).
    #[arg(short, long, conflicts_with = "verbose")]
    pub quiet: bool,

    /// Worker threads, at most the larger of 256 and the cores [default: RAYON_NUM_THREADS,
    /// else one per core].
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

/// The settings of [`crate::settings::DEFS`] as flags: one argument per definition, its help
/// text, default and preset key generated from it.
#[derive(Clone, Debug, Default)]
pub struct SettingArgs(pub Given);

impl FromArgMatches for SettingArgs {
    fn from_arg_matches(matches: &ArgMatches) -> Result<Self, clap::Error> {
        let mut given = Given::default();
        for def in DEFS {
            let value = match def.kind {
                Kind::Switch => matches.get_flag(def.name).then(|| "true".to_string()),
                _ => matches.get_one::<String>(def.name).cloned(),
            };
            if let Some(value) = value {
                given.values.push((def.name, value));
            }
        }
        Ok(SettingArgs(given))
    }

    fn update_from_arg_matches(&mut self, matches: &ArgMatches) -> Result<(), clap::Error> {
        *self = SettingArgs::from_arg_matches(matches)?;
        Ok(())
    }
}

impl Args for SettingArgs {
    fn augment_args(command: clap::Command) -> clap::Command {
        DEFS.iter()
            .fold(command, |command, def| command.arg(setting_arg(def)))
    }

    fn augment_args_for_update(command: clap::Command) -> clap::Command {
        SettingArgs::augment_args(command)
    }
}

/// The clap argument of one setting.
fn setting_arg(def: &'static Def) -> Arg {
    let heading = match def.section {
        Section::Blur => "Motion blur",
        Section::Dof => "Depth of field",
        Section::Output => "Output",
    };
    let key = format!("{}.{}", def.section.table(), def.key());
    let describe = def.describe();
    // Help lines start with a capital, as clap's own do.
    let mut chars = describe.chars();
    let describe: String = chars
        .next()
        .map(|c| c.to_uppercase().chain(chars).collect())
        .unwrap_or_default();
    let arg = Arg::new(def.name).long(def.flag()).help_heading(heading);
    match def.kind {
        Kind::Switch => {
            let turns = if def.default_value() == Value::Switch(true) {
                "off"
            } else {
                "on"
            };
            arg.action(ArgAction::SetTrue).help(format!(
                "{describe}; this flag turns it {turns} [default: {}; preset key {key}]",
                def.default_text()
            ))
        }
        _ => arg
            .value_name(def.value_name)
            .allow_negative_numbers(true)
            .help(format!(
                "{describe} [default: {}; preset key {key}]",
                def.default_text()
            )),
    }
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Files to describe.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,

    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,

    /// View of multi-view (stereo) EXRs to describe and match presets in [default: each
    /// file's default view].
    #[arg(long, value_name = "NAME")]
    pub view: Option<String>,

    /// Presets whose `[layers]` tables class the channels as a run with them would (the
    /// classes shown are otherwise the name rule's).
    #[arg(long, value_name = "P")]
    pub preset: Vec<String>,
}

#[derive(Debug, Args)]
pub struct PresetsArgs {
    #[command(subcommand)]
    pub command: Option<PresetsCommand>,
}

#[derive(Debug, Subcommand)]
pub enum PresetsCommand {
    /// Print a preset's TOML (a built-in name or a path).
    Show {
        /// Preset name or .toml path.
        name: String,
    },
    /// List every settings key a preset may set ([blur], [dof], [output]): its flag, default,
    /// and what it does.
    Keys,
}

#[derive(Debug, Args)]
pub struct SceneArgs {
    /// Scene name: rotor, orbit, figure, crossing, pan, zoom, gears, static, sparse, huge,
    /// layers, border, border-coarse, border-cut, follow, follow-wall.
    pub name: String,

    /// Output folder: color, depth, velocity, prev, next and reference(_dof, _both)
    /// .####.exr (and layers.####.exr with --layers), and scene.json.
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,

    /// Image size, each side 1 to 16384 pixels [default: 640x360].
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,

    /// The most memory the scene may need, in MiB, estimated from its size before anything
    /// is rendered [default: half the machine's memory, within the process's address-space
    /// and cgroup limits, as blur's].
    #[arg(long, value_name = "MIB")]
    pub max_memory: Option<u64>,

    /// Number of frames (frame f is scene time f - 1).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub frames: usize,

    /// Reference samples per pixel.
    #[arg(long, value_name = "N", default_value_t = crate::lab::truth::write::DEFAULT_SAMPLES)]
    pub samples: usize,

    /// Shutter fraction of the references (0.5 = 180°).
    #[arg(long, value_name = "F", default_value_t = 0.5)]
    pub shutter: f64,

    /// Where the references' exposure sits about the frame: centre, start (it opens at the
    /// frame), end (it closes at it) or a number from -0.5 to 0.5, as blur's --shutter-offset.
    #[arg(
        long,
        value_name = "O",
        default_value = "centre",
        allow_negative_numbers = true
    )]
    pub shutter_offset: String,

    /// Seed of the sample patterns (and of the layout of random scenes).
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,

    /// Also write layers.####.exr: the scene as a Blender multilayer render of two view
    /// layers, BG (the background, the farthest object) and FG (every shape, alpha =
    /// coverage), read with --preset blender --layer FG or --layer BG.
    #[arg(long)]
    pub layers: bool,
}

#[derive(Debug, Args)]
pub struct DiffArgs {
    /// First image (the reference), a file or a #### / %04d pattern.
    pub a: String,

    /// Second image (the one tested), a file or a pattern.
    pub b: String,

    /// The gating metric: rmse, psnr, ssim or flip (all four are printed).
    #[arg(long, value_name = "M", default_value = "rmse")]
    pub metric: String,

    /// Report every frame whose metric is worse than this (exit code unchanged).
    #[arg(long, value_name = "X")]
    pub warn: Option<f64>,

    /// Exit 1 when any frame's metric is worse than this.
    #[arg(long, value_name = "Y")]
    pub fail: Option<f64>,

    /// Fail a pixel with a colour channel (the beauty's R, G, B, A and every light layer)
    /// that differs by more than T; the frame fails when more pixels fail than
    /// --allow-pixels / --fail-percent allow (none by default).
    #[arg(long, value_name = "T")]
    pub fail_pixel: Option<f64>,

    /// Warn about pixels with a colour channel that differs by more than T.
    #[arg(long, value_name = "T")]
    pub warn_pixel: Option<f64>,

    /// Fail a pixel with a data channel (depth, vectors, normals, IDs) that differs by more
    /// than T (0: any difference), counted with --fail-pixel's.
    #[arg(long, value_name = "T")]
    pub data_fail_pixel: Option<f64>,

    /// Warn about pixels with a data channel that differs by more than T.
    #[arg(long, value_name = "T")]
    pub data_warn_pixel: Option<f64>,

    /// A sample fails only if its difference is also over R times the mean magnitude of its
    /// two values (idiff's -failrelative; 0: off).
    #[arg(long, value_name = "R", default_value_t = 0.0)]
    pub fail_relative: f64,

    /// The same for the warning thresholds (idiff's -warnrelative).
    #[arg(long, value_name = "R", default_value_t = 0.0)]
    pub warn_relative: f64,

    /// Fail the frame if any sample of any channel differs by more than H, whatever
    /// --allow-pixels and --fail-percent allow.
    #[arg(long, value_name = "H")]
    pub hard_fail: Option<f64>,

    /// How many pixels may fail the per-pixel gates in a frame.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub allow_pixels: usize,

    /// What share of a frame's pixels (percent) may fail the per-pixel gates.
    #[arg(long, value_name = "P", default_value_t = 0.0)]
    pub fail_percent: f64,

    /// What share of a frame's pixels (percent) may be over the per-pixel warning thresholds
    /// (--warn-pixel, --data-warn-pixel) before the frame warns (idiff's -warnpercent).
    #[arg(long, value_name = "P", default_value_t = 0.0)]
    pub warn_percent: f64,

    /// Let NaN and infinite values alike in both images through (by default any in either
    /// image fails the frame); one that became or stopped being NaN or infinite still fails.
    #[arg(long)]
    pub allow_nonfinite: bool,

    /// Exit 4 when a frame warns and none fails (by default a warning exits 0).
    #[arg(long)]
    pub warn_exit: bool,

    /// Behave as OpenImageIO's idiff for drop-in use: its exit codes as Debian's idiff 2.4
    /// answers them (0 pass, 1 warn, 2 fail, sizes or channel sets that differ, 4 an input
    /// unreadable or an output unwritable) and, unless given, its thresholds
    /// (--fail-pixel 1e-6 --warn-pixel 1e-6, on data channels too).
    #[arg(long)]
    pub idiff: bool,

    /// Write an HTML report of the comparison (index.html, report.json, thumbs/) in DIR.
    #[arg(long, value_name = "DIR")]
    pub report: Option<PathBuf>,

    /// Write the per-pixel error of the metric as a PNG (a pattern for sequences).
    #[arg(long, value_name = "OUT.png")]
    pub heatmap: Option<String>,

    /// The sharp (unblurred) frame(s): also score the region blur changes.
    #[arg(long, value_name = "PATH")]
    pub sharp: Option<String>,

    /// Frames to compare (as blur's --frames) [default: every frame found on disk for A].
    #[arg(long, value_name = "SPEC", allow_hyphen_values = true)]
    pub frames: Option<String>,

    /// Preset for finding colour channels (see shutter presets).
    #[arg(long, value_name = "P")]
    pub preset: Vec<String>,

    /// View layer whose beauty is scored, substituted for {layer} in preset channel names
    /// (default: found in the file; every channel is compared either way).
    #[arg(long, value_name = "NAME")]
    pub layer: Option<String>,

    /// View of multi-view (stereo) EXRs to compare alone, e.g. right [default: every view
    /// of the reference, each apart].
    #[arg(long, value_name = "NAME")]
    pub view: Option<String>,

    /// 8/16-bit inputs hold linear values, not sRGB.
    #[arg(long)]
    pub linear: bool,

    /// Print JSON on stdout.
    #[arg(long)]
    pub json: bool,

    /// Print no warnings on stderr (they stay in --json).
    #[arg(short, long)]
    pub quiet: bool,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Comma-separated scenes [default: all].
    #[arg(long, value_name = "LIST")]
    pub scenes: Option<String>,

    /// Frame size, each side 1 to 16384 pixels [default: 320x180].
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,

    /// Output folder (scenes are cached under it and reused when their settings match).
    #[arg(long, value_name = "DIR", default_value = "target/bench")]
    pub out: PathBuf,

    /// Reference samples per pixel.
    #[arg(long, value_name = "N", default_value_t = crate::lab::truth::write::DEFAULT_SAMPLES)]
    pub samples: usize,

    /// The shutter offset of the scenes' references and of every setting run on them
    /// (centre, start, end or a number from -0.5 to 0.5, as blur's --shutter-offset).
    #[arg(
        long,
        value_name = "O",
        default_value = "centre",
        allow_negative_numbers = true
    )]
    pub shutter_offset: String,

    /// Timed runs per measurement (median kept), at least 5.
    #[arg(long, value_name = "N", default_value_t = 5)]
    pub runs: usize,

    /// A folder with a peers.json (scripts/peers/run.sh writes one): other programs' outputs
    /// on the bench's scene files, scored beside shutter's settings.
    #[arg(long, value_name = "DIR")]
    pub peers: Option<PathBuf>,

    /// Also run each CPU setting on the scenes' view layers (FG: every shape, BG: the
    /// background), as `--layers FG,BG` ([layers] rows) and as each layer blurred alone and
    /// merged by hand ([hand merge] rows), against the same references.
    #[arg(long)]
    pub layers: bool,
}
