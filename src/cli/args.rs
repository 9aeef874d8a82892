//! What the user typed, as clap parses it. Validated only for shape here; `cli::resolve`
//! turns it into a [`crate::pipeline::Job`].

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(
    name = "shutter",
    version,
    about = "Adds motion blur and depth of field to rendered frame sequences",
    long_about = "Adds the camera effects a renderer left out - motion blur and depth of field - \
to rendered frame sequences, reading colour, depth, velocity and previous/next position passes \
from OpenEXR or 8/16-bit images.\n\nExit codes: 0 success, 1 a problem with input or output \
files, 2 a usage error."
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
    /// Compare two images or sequences: metrics, a CI gate, a heatmap. Exit codes: 0 within
    /// --fail, 1 over it, 2 an unreadable input or a size mismatch.
    Diff(DiffArgs),
    /// Time and score every algorithm setting on the truth scenes: bench.json, bench.md,
    /// pareto.svg/.png and contact sheets.
    Bench(BenchArgs),
}

#[derive(Debug, Args)]
pub struct BlurArgs {
    /// Preset name (shutter, blender, nuke, painted, preview, final) or path to a .toml file;
    /// repeat to merge several, later ones winning.
    #[arg(long, value_name = "P")]
    pub preset: Vec<String>,

    /// Blur algorithm [default: from the preset, else none]. none copies colour through.
    #[arg(long, value_name = "NAME")]
    pub algorithm: Option<String>,

    /// Colour pass: a file, or a sequence pattern with #### or %04d. With a multi-layer EXR
    /// the preset finds the other passes in it.
    #[arg(long, value_name = "PATH")]
    pub color: String,

    /// Depth pass file or pattern (default: looked up in the colour file).
    #[arg(long, value_name = "PATH")]
    pub depth: Option<String>,

    /// Velocity pass file or pattern (default: looked up in the colour file).
    #[arg(long, value_name = "PATH")]
    pub velocity: Option<String>,

    /// Previous-position pass file or pattern (default: looked up in the colour file).
    #[arg(long, value_name = "PATH")]
    pub prev: Option<String>,

    /// Next-position pass file or pattern (default: looked up in the colour file).
    #[arg(long, value_name = "PATH")]
    pub next: Option<String>,

    /// View layer substituted for {layer} in preset channel names (default: found in the file).
    #[arg(long, value_name = "NAME")]
    pub layer: Option<String>,

    /// Fraction of the frame interval the shutter is open, centred on the frame (0.5 = 180°)
    /// [default: from the preset, else 0.5].
    #[arg(long, value_name = "F")]
    pub shutter: Option<f32>,

    /// Largest blur radius in pixels. reconstruct: k, also the tile size [default: preset,
    /// else 20]; scatter: a curve is at most twice this long [default: preset, else 128].
    #[arg(long, value_name = "PX")]
    pub max_blur: Option<usize>,

    /// reconstruct: filter taps S, odd [default: preset, else 15].
    #[arg(long, value_name = "S")]
    pub samples: Option<usize>,

    /// reconstruct: soft depth extent in scene units [default: preset, else 0.1].
    #[arg(long, value_name = "Z")]
    pub soft_z: Option<f32>,

    /// reconstruct: no per-pixel jitter of the taps (ghosting instead of noise).
    #[arg(long)]
    pub no_jitter: bool,

    /// reconstruct: paper (every tap along the neighbourhood's velocity) or dual (every
    /// other tap along the pixel's own) [default: preset, else paper].
    #[arg(long, value_name = "V")]
    pub variant: Option<String>,

    /// scatter: line segments per curve, at most (the paper's Δ = 11 points is 10)
    /// [default: preset, else 10].
    #[arg(long, value_name = "N")]
    pub segments: Option<usize>,

    /// scatter: σ of the Gaussian weight along the curve, in units of s (0..1 over the frame
    /// interval) [default: preset, else 2].
    #[arg(long, value_name = "S")]
    pub sigma: Option<f32>,

    /// scatter: weight along the curve, gaussian (the paper) or box (the ideal shutter)
    /// [default: preset, else gaussian].
    #[arg(long, value_name = "W")]
    pub weight: Option<String>,

    /// scatter: background weight w_b of the paper's normalisation [default: preset, else 5].
    #[arg(long, value_name = "WB")]
    pub background_weight: Option<f32>,

    /// scatter: paper (eq. 4 with w_b) or exposure (deposits as shares of the exposure, the
    /// rest filled with what lies behind) [default: preset, else paper].
    #[arg(long, value_name = "N")]
    pub normalize: Option<String>,

    /// scatter: bezier (the paper's quadratic) or arc (circular where the motion turns)
    /// [default: preset, else bezier].
    #[arg(long, value_name = "C")]
    pub curve: Option<String>,

    /// scatter: cut a curve into fewer segments where they stray at most this many pixels
    /// from it; 0 always uses --segments [default: preset, else 0.1].
    #[arg(long, value_name = "PX")]
    pub flatness: Option<f32>,

    /// scatter, stretch: relative depth tolerance of the depth test [default: preset, else
    /// 0.02].
    #[arg(long, value_name = "F")]
    pub depth_tolerance: Option<f32>,

    /// stretch: `extent` of alpha = max(min_alpha, 1 − |M|/extent), pixels [default: preset,
    /// else 2].
    #[arg(long, value_name = "PX")]
    pub extent: Option<f32>,

    /// stretch: the alpha floor of moved vertices [default: preset, else 0.1].
    #[arg(long, value_name = "A")]
    pub min_alpha: Option<f32>,

    /// stretch: relative depth step that tears the mesh [default: preset, else 0.05].
    #[arg(long, value_name = "F")]
    pub tear: Option<f32>,

    /// stretch: centre (trailing vertices back and leading ones forward by half the
    /// exposure) or rear (the talk's rear curtain) [default: preset, else centre].
    #[arg(long, value_name = "A")]
    pub anchor: Option<String>,

    /// stretch: no averaging of moving pixels along their motion before stretching (the
    /// talk's plain form: only silhouettes blur).
    #[arg(long)]
    pub no_texture_blur: bool,

    #[command(flatten)]
    pub dof: DofArgs,

    /// Frames to process: 1001-1100, 1-99x2, 1,5,9-12 [default: every frame found on disk
    /// for the colour pattern].
    #[arg(long, value_name = "SPEC")]
    pub frames: Option<String>,

    /// Output file or pattern (.exr, .png, .tif, .tiff, .jpg, .jpeg).
    #[arg(short, long, value_name = "PATH")]
    pub output: String,

    /// Write EXR as 16-bit half floats (default: 32-bit float).
    #[arg(long)]
    pub half: bool,

    /// EXR compression: none, rle, zips, zip, piz, pxr24, b44, b44a, dwaa, dwab
    /// [default: from the preset, else zip].
    #[arg(long, value_name = "NAME")]
    pub compression: Option<String>,

    /// Bits per channel of PNG and TIFF output: 8 or 16 [default: from the preset, else 8].
    #[arg(long, value_name = "BITS")]
    pub bit_depth: Option<u8>,

    /// Integer images (8/16-bit input colour and output) hold linear values, not sRGB.
    #[arg(long)]
    pub linear: bool,

    /// Skip frames whose output already exists, so a rerun resumes.
    #[arg(long)]
    pub skip_existing: bool,

    /// Print a JSON summary on stdout (frames, per-stage seconds, warnings).
    #[arg(long)]
    pub json: bool,

    /// Report each frame on stderr even when it is not a terminal.
    #[arg(short, long)]
    pub verbose: bool,

    /// Worker threads [default: RAYON_NUM_THREADS, else one per core].
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

/// Depth-of-field flags, shared by `shutter dof` and `shutter blur`.
#[derive(Debug, Args, Default)]
pub struct DofArgs {
    /// Depth of field: gather (bokeh gather with near and far fields) or blend (Wloka's
    /// blurriness blend) [default: preset, else gather].
    #[arg(long, value_name = "M", help_heading = "Depth of field")]
    pub method: Option<String>,

    /// Lens focal length in mm.
    #[arg(long, value_name = "MM", help_heading = "Depth of field")]
    pub focal_length: Option<f64>,

    /// Lens f-number (aperture = focal length / f-stop).
    #[arg(long, value_name = "N", help_heading = "Depth of field")]
    pub f_stop: Option<f64>,

    /// Focus distance in metres. Depth is read as metres too: a depth pass in other units
    /// needs a preset's [depth] scale (0.01 for centimetres).
    #[arg(long, value_name = "D", help_heading = "Depth of field")]
    pub focus_distance: Option<f64>,

    /// Sensor (film) width in mm: the image's width spans it [default: preset, else 36].
    #[arg(long, value_name = "MM", help_heading = "Depth of field")]
    pub sensor_width: Option<f64>,

    /// A painted blurriness map (grey image or one-channel EXR, a file or pattern) instead of
    /// a lens and depth: CoC diameter = value × --coc-scale. Read in place of depth.
    #[arg(long, value_name = "PATH", help_heading = "Depth of field")]
    pub coc_map: Option<String>,

    /// CoC diameter in pixels of a map value of 1 (white) [default: preset, else 32].
    #[arg(long, value_name = "PX", help_heading = "Depth of field")]
    pub coc_scale: Option<f32>,

    /// ε: circles of confusion smaller than this diameter (px) are in focus [default:
    /// preset, else 1].
    #[arg(long, value_name = "PX", help_heading = "Depth of field")]
    pub epsilon: Option<f32>,

    /// Largest CoC diameter (px); larger ones are clamped. blend: E (the CoC its most blurred
    /// copy stands for) is the frame's largest CoC, at most this [default: preset, else 48].
    #[arg(long, value_name = "PX", help_heading = "Depth of field")]
    pub max_coc: Option<f32>,

    /// gather: diaphragm blades, 0 for a round aperture [default: preset, else 0].
    #[arg(long, value_name = "N", help_heading = "Depth of field")]
    pub blades: Option<u32>,

    /// gather: diaphragm rotation in degrees [default: preset, else 0].
    #[arg(long, value_name = "DEG", help_heading = "Depth of field")]
    pub blade_rotation: Option<f32>,

    /// gather: rings of taps; ring k has 8k taps (6 rings: 169 taps) [default: preset, else 6].
    #[arg(long, value_name = "N", help_heading = "Depth of field")]
    pub rings: Option<usize>,

    /// blend: passes n of the 3×3 filter for the first blurred copy (the second has 2n)
    /// [default: preset, else chosen so the 2n copy looks like E].
    #[arg(long, value_name = "N", help_heading = "Depth of field")]
    pub passes: Option<usize>,
}

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Files to describe.
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,

    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
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
}

#[derive(Debug, Args)]
pub struct SceneArgs {
    /// Scene name: rotor, orbit, figure, crossing, pan, zoom, gears, static, sparse, huge,
    /// layers.
    pub name: String,

    /// Output folder: color, depth, velocity, prev, next and reference(_dof, _both)
    /// .####.exr, and scene.json.
    #[arg(short, long, value_name = "DIR")]
    pub output: PathBuf,

    /// Image size [default: 640x360].
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,

    /// Number of frames (frame f is scene time f - 1).
    #[arg(long, value_name = "N", default_value_t = 1)]
    pub frames: usize,

    /// Reference samples per pixel.
    #[arg(long, value_name = "N", default_value_t = crate::truth::write::DEFAULT_SAMPLES)]
    pub samples: usize,

    /// Shutter fraction of the references (0.5 = 180°).
    #[arg(long, value_name = "F", default_value_t = 0.5)]
    pub shutter: f64,

    /// Seed of the sample patterns (and of the layout of random scenes).
    #[arg(long, value_name = "S", default_value_t = 1)]
    pub seed: u64,
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

    /// Write the per-pixel error of the metric as a PNG (a pattern for sequences).
    #[arg(long, value_name = "OUT.png")]
    pub heatmap: Option<String>,

    /// The sharp (unblurred) frame(s): also score the region blur changes.
    #[arg(long, value_name = "PATH")]
    pub sharp: Option<String>,

    /// Frames to compare [default: every frame found on disk for A].
    #[arg(long, value_name = "SPEC")]
    pub frames: Option<String>,

    /// Preset for finding colour channels (see shutter presets).
    #[arg(long, value_name = "P")]
    pub preset: Vec<String>,

    /// 8/16-bit inputs hold linear values, not sRGB.
    #[arg(long)]
    pub linear: bool,

    /// Print JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Comma-separated scenes [default: all].
    #[arg(long, value_name = "LIST")]
    pub scenes: Option<String>,

    /// Frame size [default: 320x180].
    #[arg(long, value_name = "WxH")]
    pub size: Option<String>,

    /// Output folder (scenes are cached under it and reused when their settings match).
    #[arg(long, value_name = "DIR", default_value = "target/bench")]
    pub out: PathBuf,

    /// Reference samples per pixel.
    #[arg(long, value_name = "N", default_value_t = crate::truth::write::DEFAULT_SAMPLES)]
    pub samples: usize,

    /// Timed runs per measurement (median kept), at least 5.
    #[arg(long, value_name = "N", default_value_t = 5)]
    pub runs: usize,
}
