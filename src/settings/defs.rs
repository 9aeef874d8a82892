//! The table of settings, [`DEFS`]: one [`Def`] per setting, in the order help texts list
//! them, each saying where its value lives in [`Settings`](super::Settings) (the parameter
//! structs own the defaults) and what values it takes. A new setting is one entry here; its
//! flag, preset key, help, README row and checks all come from it (`parse`, `doc`,
//! `cli::args`).

use super::{Def, Kind, Section, Value};
use crate::dof::{BlendForm, Method};
use crate::gpu::Backend;
use crate::io::exr::{compression_name, parse_compression, WRITABLE_COMPRESSIONS};
use crate::motion::{scatter, Algorithm, Anchor, CurveKind, Normalize, Shutter, Variant, Weight};

/// A number from `min` to `max`.
const fn number(min: f64, max: f64) -> Kind {
    Kind::Number {
        min,
        max,
        above: false,
        whole: false,
        valid: None,
        names: &[],
    }
}

/// A number above `min`, with no upper bound.
const fn above(min: f64) -> Kind {
    Kind::Number {
        min,
        max: f64::INFINITY,
        above: true,
        whole: false,
        valid: None,
        names: &[],
    }
}

/// A whole number from `min` to `max`.
const fn whole(min: f64, max: f64) -> Kind {
    Kind::Number {
        min,
        max,
        above: false,
        whole: true,
        valid: None,
        names: &[],
    }
}

/// An f32 field as a value, printed as it was written (0.1, not 0.10000000149).
fn short(v: f32) -> Value {
    Value::Number(v.to_string().parse().unwrap_or(v as f64))
}

/// The choice of `all` named `name` (names are checked before they are set).
fn pick<T: Copy>(all: &[(&'static str, T)], name: &str) -> T {
    all.iter()
        .find(|(n, _)| *n == name)
        .or(all.first())
        .map(|(_, v)| *v)
        .expect("a choice table is never empty")
}

/// The name of `value` in `all`.
fn name_of<T: Copy + PartialEq>(all: &[(&'static str, T)], value: T) -> Value {
    all.iter()
        .find(|(_, v)| *v == value)
        .map_or(Value::Unset, |(n, _)| Value::Name(n))
}

/// The names of `all`, for a choice's list.
fn names<T>(all: &[(&'static str, T)]) -> Vec<&'static str> {
    all.iter().map(|(n, _)| *n).collect()
}

const RECONSTRUCT: &[&str] = &["reconstruct"];
const SCATTER: &[&str] = &["scatter"];
const STRETCH: &[&str] = &["stretch"];
const GATHER: &[&str] = &["gather"];
const BLEND: &[&str] = &["blend"];

/// Every setting, in the order help texts list them.
pub const DEFS: &[Def] = &[
    Def {
        name: "algorithm",
        flag: None,
        section: Section::Blur,
        applies: &[],
        value_name: "NAME",
        help: "the motion blur; none copies colour through",
        kind: Kind::Choice(|| names(Algorithm::ALL)),
        unset: "",
        get: |s| Value::Name(s.algorithm.name()),
        set: |s, v| s.algorithm = pick(Algorithm::ALL, v.name()),
    },
    Def {
        name: "backend",
        flag: None,
        section: Section::Blur,
        applies: &[],
        value_name: "B",
        help: "where the passes run: cpu (the reference, the default for now), wgpu (any \
               Vulkan, Metal or DX12 adapter, software ones included; an error if none) or \
               auto (a hardware GPU, else the CPU); stages without a GPU twin yet (blend's \
               talk form) run on the CPU",
        kind: Kind::Choice(|| names(Backend::ALL)),
        unset: "",
        get: |s| Value::Name(s.backend.name()),
        set: |s, v| s.backend = pick(Backend::ALL, v.name()),
    },
    Def {
        name: "max-pixels",
        flag: None,
        section: Section::Blur,
        applies: &[],
        value_name: "N",
        help: "the largest input frame in pixels (width × height), checked from each file's \
               header before anything is decoded; the default, 16384 × 16384, admits 16K \
               frames",
        kind: whole(1.0, 4_294_967_296.0),
        unset: "",
        get: |s| Value::Number(s.max_pixels as f64),
        set: |s, v| s.max_pixels = v.number() as usize,
    },
    Def {
        name: "max-memory",
        flag: None,
        section: Section::Blur,
        applies: &[],
        value_name: "MIB",
        help: "the most memory a run may need, in MiB, estimated from every input's header \
               before anything is decoded (a frame's decoded passes, five times over for the \
               frames in flight and the passes' buffers, 1.5 times more for the bokeh \
               gather, a decoder's own, and 3 MiB a thread); a run over it \
               stops in the preflight, naming the frame",
        kind: whole(64.0, 1_073_741_824.0),
        unset: "half the machine's memory, within the process's address-space and cgroup limits",
        get: |s| {
            s.max_memory
                .map_or(Value::Unset, |m| Value::Number(m as f64))
        },
        set: |s, v| s.max_memory = Some(v.number() as u64),
    },
    Def {
        name: "shutter",
        flag: None,
        section: Section::Blur,
        applies: &[],
        value_name: "F",
        help: "fraction of the frame interval the shutter is open (0.5 = 180°); \
               --shutter-offset places it",
        kind: number(0.0, 1.0),
        unset: "",
        get: |s| short(s.params.shutter),
        set: |s, v| s.params.shutter = v.number() as f32,
    },
    Def {
        name: "shutter-offset",
        flag: None,
        section: Section::Blur,
        applies: &[],
        value_name: "O",
        help: "where the exposure sits about the frame: its middle after the frame's instant, \
               in exposures, so it spans [(O − 0.5)·φ, (O + 0.5)·φ] frames; centre (0, the \
               shutter centred on the frame), start (0.5, it opens at the frame), end (−0.5, \
               it closes at the frame) or a number between (Nuke's custom offset c, the time \
               it opens, is c/φ + 0.5)",
        kind: Kind::Number {
            min: -0.5,
            max: 0.5,
            above: false,
            whole: false,
            valid: None,
            names: Shutter::OFFSETS,
        },
        unset: "",
        get: |s| {
            let o = s.params.shutter_offset;
            Shutter::OFFSETS
                .iter()
                .find(|(_, v)| *v == o)
                .map_or_else(|| short(o), |(n, _)| Value::Name(n))
        },
        set: |s, v| {
            s.params.shutter_offset = match v {
                Value::Name(n) => pick(Shutter::OFFSETS, n),
                v => v.number() as f32,
            }
        },
    },
    Def {
        name: "max-blur",
        flag: None,
        section: Section::Blur,
        applies: RECONSTRUCT,
        value_name: "PX",
        help: "k, the largest blur radius in pixels (paper, dual: also the tile size; the \
               paper used 20)",
        kind: whole(1.0, 512.0),
        unset: "",
        get: |s| Value::Number(s.params.reconstruct.max_blur as f64),
        set: |s, v| s.params.reconstruct.max_blur = v.number() as usize,
    },
    Def {
        name: "samples",
        flag: None,
        section: Section::Blur,
        applies: RECONSTRUCT,
        value_name: "S",
        help: "filter taps S, odd (paper, dual: along the line; 2014, exposure: S + 1 in \
               all, a quarter on each side along the tile's and the pixel's own motion; \
               exposure: at least one per 2 px of the streak, up to 64 a side)",
        kind: Kind::Number {
            min: 1.0,
            max: 255.0,
            above: false,
            whole: true,
            valid: Some((|v| v % 2.0 == 1.0, "an odd whole number from 1 to 255")),
            names: &[],
        },
        unset: "",
        get: |s| Value::Number(s.params.reconstruct.taps as f64),
        set: |s, v| s.params.reconstruct.taps = v.number() as usize,
    },
    Def {
        name: "soft-z",
        flag: None,
        section: Section::Blur,
        applies: RECONSTRUCT,
        value_name: "Z",
        help: "soft depth extent, scene units",
        kind: above(0.0),
        unset: "",
        get: |s| short(s.params.reconstruct.soft_z),
        set: |s, v| s.params.reconstruct.soft_z = v.number() as f32,
    },
    Def {
        name: "jitter",
        flag: Some("no-jitter"),
        section: Section::Blur,
        applies: RECONSTRUCT,
        value_name: "",
        help: "jitter the taps per pixel (off: ghosting instead of noise)",
        kind: Kind::Switch,
        unset: "",
        get: |s| Value::Switch(s.params.reconstruct.jitter),
        set: |s, v| s.params.reconstruct.jitter = v.switch(),
    },
    Def {
        name: "variant",
        flag: None,
        section: Section::Blur,
        applies: RECONSTRUCT,
        value_name: "V",
        help: "paper: McGuire 2012, every tap along the neighbourhood's velocity; dual: \
               every other tap along the pixel's own; 2014: Guertin 2014 as Blender's Vector \
               Blur runs it (Jimenez's form); exposure: 2014 with the box shutter's weights",
        kind: Kind::Choice(|| names(Variant::ALL)),
        unset: "",
        get: |s| name_of(Variant::ALL, s.params.reconstruct.variant),
        set: |s, v| s.params.reconstruct.variant = pick(Variant::ALL, v.name()),
    },
    Def {
        name: "normalize",
        flag: None,
        section: Section::Blur,
        applies: SCATTER,
        value_name: "N",
        help: "exposure: deposits as shares of the exposure, the rest filled with what lies \
               behind; paper: eq. 4 with the background weight",
        kind: Kind::Choice(|| names(Normalize::ALL)),
        unset: "",
        get: |s| name_of(Normalize::ALL, s.params.scatter.normalize),
        set: |s, v| s.params.scatter.normalize = pick(Normalize::ALL, v.name()),
    },
    Def {
        name: "weight",
        flag: None,
        section: Section::Blur,
        applies: SCATTER,
        value_name: "W",
        help: "weight along the curve: box (the ideal shutter) or the paper's gaussian",
        kind: Kind::Choice(|| names(Weight::ALL)),
        unset: "",
        get: |s| name_of(Weight::ALL, s.params.scatter.weight),
        set: |s, v| s.params.scatter.weight = pick(Weight::ALL, v.name()),
    },
    Def {
        name: "sigma",
        flag: None,
        section: Section::Blur,
        applies: SCATTER,
        value_name: "S",
        help: "σ of the gaussian weight, in units of s (0..1 over the frame interval)",
        kind: number(0.01, f64::INFINITY),
        unset: "",
        get: |s| short(s.params.scatter.sigma),
        set: |s, v| s.params.scatter.sigma = v.number() as f32,
    },
    Def {
        name: "background-weight",
        flag: None,
        section: Section::Blur,
        applies: SCATTER,
        value_name: "WB",
        help: "w_b of the paper's normalisation",
        kind: number(0.0, f64::INFINITY),
        unset: "",
        get: |s| short(s.params.scatter.background_weight),
        set: |s, v| s.params.scatter.background_weight = v.number() as f32,
    },
    Def {
        name: "curve",
        flag: None,
        section: Section::Blur,
        applies: SCATTER,
        value_name: "C",
        help: "bezier: the paper's quadratic; arc: circular where the motion turns",
        kind: Kind::Choice(|| names(CurveKind::ALL)),
        unset: "",
        get: |s| name_of(CurveKind::ALL, s.params.scatter.curve),
        set: |s, v| s.params.scatter.curve = pick(CurveKind::ALL, v.name()),
    },
    Def {
        name: "segments",
        flag: None,
        section: Section::Blur,
        applies: SCATTER,
        value_name: "N",
        help: "line segments per curve, at most (the paper's Δ = 11 points is 10)",
        kind: whole(1.0, scatter::MOST_SEGMENTS as f64),
        unset: "",
        get: |s| Value::Number(s.params.scatter.segments as f64),
        set: |s, v| s.params.scatter.segments = v.number() as usize,
    },
    Def {
        name: "flatness",
        flag: None,
        section: Section::Blur,
        applies: SCATTER,
        value_name: "PX",
        help: "fewer segments where every chord stays this close to the curve, pixels; 0 \
               always uses --segments",
        kind: number(0.0, f64::INFINITY),
        unset: "",
        get: |s| short(s.params.scatter.flatness),
        set: |s, v| s.params.scatter.flatness = v.number() as f32,
    },
    Def {
        name: "max-curve",
        flag: None,
        section: Section::Blur,
        applies: SCATTER,
        value_name: "PX",
        help: "the longest a curve may be, pixels; longer ones are scaled about p(0)",
        kind: number(1.0, 1e6),
        unset: "",
        get: |s| short(s.params.scatter.max_curve),
        set: |s, v| s.params.scatter.max_curve = v.number() as f32,
    },
    Def {
        name: "depth-tolerance",
        flag: None,
        section: Section::Blur,
        applies: &["scatter", "stretch"],
        value_name: "F",
        help: "a curve or fragment is drawn over a pixel whose depth is at least its own / \
               (1 + F)",
        kind: number(0.0, f64::INFINITY),
        unset: "",
        get: |s| short(s.params.scatter.depth_tolerance),
        set: |s, v| {
            let f = v.number() as f32;
            s.params.scatter.depth_tolerance = f;
            s.params.stretch.depth_tolerance = f;
        },
    },
    Def {
        name: "anchor",
        flag: None,
        section: Section::Blur,
        applies: STRETCH,
        value_name: "A",
        help: "centre: trailing vertices back and leading ones forward by half the exposure; \
               rear: the talk's rear curtain",
        kind: Kind::Choice(|| names(Anchor::ALL)),
        unset: "",
        get: |s| name_of(Anchor::ALL, s.params.stretch.anchor),
        set: |s, v| s.params.stretch.anchor = pick(Anchor::ALL, v.name()),
    },
    Def {
        name: "extent",
        flag: None,
        section: Section::Blur,
        applies: STRETCH,
        value_name: "PX",
        help: "extent of the moved vertices' alpha max(min_alpha, 1 − |M|/extent), pixels",
        kind: above(0.0),
        unset: "",
        get: |s| short(s.params.stretch.extent),
        set: |s, v| s.params.stretch.extent = v.number() as f32,
    },
    Def {
        name: "min-alpha",
        flag: None,
        section: Section::Blur,
        applies: STRETCH,
        value_name: "A",
        help: "the alpha floor of moved vertices (the talk's 0.1)",
        kind: number(0.0, 1.0),
        unset: "",
        get: |s| short(s.params.stretch.min_alpha),
        set: |s, v| s.params.stretch.min_alpha = v.number() as f32,
    },
    Def {
        name: "tear",
        flag: None,
        section: Section::Blur,
        applies: STRETCH,
        value_name: "F",
        help: "relative depth step that tears the mesh",
        kind: number(0.0, f64::INFINITY),
        unset: "",
        get: |s| short(s.params.stretch.tear),
        set: |s, v| s.params.stretch.tear = v.number() as f32,
    },
    Def {
        name: "texture-blur",
        flag: Some("no-texture-blur"),
        section: Section::Blur,
        applies: STRETCH,
        value_name: "",
        help: "average moving pixels along their motion before stretching (off: only \
               silhouettes blur)",
        kind: Kind::Switch,
        unset: "",
        get: |s| Value::Switch(s.params.stretch.texture_blur),
        set: |s, v| s.params.stretch.texture_blur = v.switch(),
    },
    Def {
        name: "method",
        flag: None,
        section: Section::Dof,
        applies: &[],
        value_name: "M",
        help: "depth of field: the bokeh gather with near and far fields, or Wloka's \
               blurriness blend",
        kind: Kind::Choice(|| names(Method::ALL)),
        unset: "",
        get: |s| name_of(Method::ALL, s.dof.method),
        set: |s, v| s.dof.method = pick(Method::ALL, v.name()),
    },
    Def {
        name: "focal-length",
        flag: None,
        section: Section::Dof,
        applies: &[],
        value_name: "MM",
        help: "lens focal length, mm; with --f-stop and --focus-distance it turns depth of \
               field on",
        kind: above(0.0),
        unset: "none",
        get: |s| s.lens.focal_length.map_or(Value::Unset, Value::Number),
        set: |s, v| s.lens.focal_length = Some(v.number()),
    },
    Def {
        name: "f-stop",
        flag: None,
        section: Section::Dof,
        applies: &[],
        value_name: "N",
        help: "lens f-number (aperture = focal length / f-stop)",
        kind: above(0.0),
        unset: "none",
        get: |s| s.lens.f_stop.map_or(Value::Unset, Value::Number),
        set: |s, v| s.lens.f_stop = Some(v.number()),
    },
    Def {
        name: "focus-distance",
        flag: None,
        section: Section::Dof,
        applies: &[],
        value_name: "D",
        help: "focus distance, metres; depth is read as metres too (a preset's [depth] scale \
               converts other units)",
        kind: above(0.0),
        unset: "none",
        get: |s| s.lens.focus_distance.map_or(Value::Unset, Value::Number),
        set: |s, v| s.lens.focus_distance = Some(v.number()),
    },
    Def {
        name: "sensor-width",
        flag: None,
        section: Section::Dof,
        applies: &[],
        value_name: "MM",
        help: "sensor (film) width in mm: the image's width spans it",
        kind: above(0.0),
        unset: "",
        get: |s| Value::Number(s.lens.sensor_width),
        set: |s, v| s.lens.sensor_width = v.number(),
    },
    Def {
        name: "coc-scale",
        flag: None,
        section: Section::Dof,
        applies: &[],
        value_name: "PX",
        help: "CoC diameter in pixels of a painted map's value 1 (white)",
        kind: number(0.0, 512.0),
        unset: "",
        get: |s| short(s.lens.coc_scale),
        set: |s, v| s.lens.coc_scale = v.number() as f32,
    },
    Def {
        name: "epsilon",
        flag: None,
        section: Section::Dof,
        applies: &[],
        value_name: "PX",
        help: "ε: circles of confusion smaller than this diameter (px) are in focus",
        kind: number(0.0, 512.0),
        unset: "",
        get: |s| short(s.dof.epsilon),
        set: |s, v| s.dof.epsilon = v.number() as f32,
    },
    Def {
        name: "max-coc",
        flag: None,
        section: Section::Dof,
        applies: &[],
        value_name: "PX",
        help: "largest CoC diameter (px), larger ones are clamped; blend: E, the CoC of its \
               most blurred copy, is the frame's largest CoC, at most this",
        kind: Kind::Number {
            min: 0.0,
            max: 512.0,
            above: true,
            whole: false,
            valid: None,
            names: &[],
        },
        unset: "",
        get: |s| short(s.dof.max_coc),
        set: |s, v| s.dof.max_coc = v.number() as f32,
    },
    Def {
        name: "blades",
        flag: None,
        section: Section::Dof,
        applies: GATHER,
        value_name: "N",
        help: "diaphragm blades, 0 for a round aperture",
        kind: Kind::Number {
            min: 0.0,
            max: 32.0,
            above: false,
            whole: true,
            valid: Some((|v| v != 1.0 && v != 2.0, "0 (round) or 3 to 32")),
            names: &[],
        },
        unset: "",
        get: |s| Value::Number(s.dof.blades as f64),
        set: |s, v| s.dof.blades = v.number() as u32,
    },
    Def {
        name: "blade-rotation",
        flag: None,
        section: Section::Dof,
        applies: GATHER,
        value_name: "DEG",
        help: "diaphragm rotation, degrees",
        kind: number(-360.0, 360.0),
        unset: "",
        get: |s| short(s.dof.blade_rotation),
        set: |s, v| s.dof.blade_rotation = v.number() as f32,
    },
    Def {
        name: "rings",
        flag: None,
        section: Section::Dof,
        applies: GATHER,
        value_name: "N",
        help: "rings of taps; ring k has 8k taps (6 rings: 169 taps)",
        kind: whole(1.0, 16.0),
        unset: "",
        get: |s| Value::Number(s.dof.rings as f64),
        set: |s, v| s.dof.rings = v.number() as usize,
    },
    Def {
        name: "passes",
        flag: None,
        section: Section::Dof,
        applies: BLEND,
        value_name: "N",
        help: "the talk's form: passes n of the 3×3 filter for the first blurred copy (the \
               second has 2n)",
        kind: whole(1.0, 4096.0),
        unset: "chosen so the 2n copy looks like E",
        get: |s| {
            s.dof
                .passes
                .map_or(Value::Unset, |n| Value::Number(n as f64))
        },
        set: |s, v| s.dof.passes = Some(v.number() as usize),
    },
    Def {
        name: "blend-form",
        flag: None,
        section: Section::Dof,
        applies: BLEND,
        value_name: "F",
        help: "the blurred images: a binomial pyramid mixed continuously by CoC, or the \
               talk's two copies (n and 2n passes) mixed by T",
        kind: Kind::Choice(|| names(BlendForm::ALL)),
        unset: "",
        get: |s| name_of(BlendForm::ALL, s.dof.blend_form),
        set: |s, v| s.dof.blend_form = pick(BlendForm::ALL, v.name()),
    },
    Def {
        name: "compression",
        flag: None,
        section: Section::Output,
        applies: &[],
        value_name: "NAME",
        help: "EXR compression",
        kind: Kind::Choice(|| WRITABLE_COMPRESSIONS.to_vec()),
        unset: "as the colour file's (zip when it is not an EXR)",
        get: |s| {
            s.output
                .exr
                .compression
                .map_or(Value::Unset, |c| Value::Name(compression_name(c)))
        },
        set: |s, v| s.output.exr.compression = parse_compression(v.name()),
    },
    Def {
        name: "half",
        flag: None,
        section: Section::Output,
        applies: &[],
        value_name: "",
        help: "write every float EXR channel as 16-bit half float, u32 channels (IDs) as \
               they are, and as float a data channel holding values half cannot (a depth \
               of 1e10, a position of −7e4, an object index over 2048) and Cryptomatte's \
               IDs (hashes in a float's bits) (off: each as the colour file stores it; \
               32-bit float when it is not an EXR)",
        kind: Kind::Switch,
        unset: "",
        get: |s| Value::Switch(s.output.exr.half),
        set: |s, v| s.output.exr.half = v.switch(),
    },
    Def {
        name: "beauty-only",
        flag: None,
        section: Section::Output,
        applies: &[],
        value_name: "",
        help: "write the beauty alone to an EXR (off: every channel of the colour file too, \
               light layers blurred with the beauty's weights, data layers unchanged)",
        kind: Kind::Switch,
        unset: "",
        get: |s| Value::Switch(s.output.beauty_only),
        set: |s, v| s.output.beauty_only = v.switch(),
    },
    Def {
        name: "bit-depth",
        flag: None,
        section: Section::Output,
        applies: &[],
        value_name: "BITS",
        help: "bits per channel of PNG and TIFF output: 8, 16, or 32 (float, TIFF only; \
               JPEG is always 8)",
        kind: Kind::Number {
            min: 8.0,
            max: 32.0,
            above: false,
            whole: true,
            valid: Some((|v| v == 8.0 || v == 16.0 || v == 32.0, "8, 16 or 32")),
            names: &[],
        },
        unset: "as the input (a float TIFF: float in a TIFF, 16 in a PNG); 8 for an EXR input",
        get: |s| {
            s.output
                .bit_depth
                .map_or(Value::Unset, |bits| Value::Number(bits as f64))
        },
        set: |s, v| s.output.bit_depth = Some(v.number() as u8),
    },
    Def {
        name: "jpeg-quality",
        flag: None,
        section: Section::Output,
        applies: &[],
        value_name: "Q",
        help: "JPEG output quality, 1 to 100 (the chroma subsampling is the input's)",
        // 95, as before: visually lossless for photos at 4:4:4 and 4:2:0 alike, where 90
        // and below leave ringing a second generation of a blurred edge makes visible.
        kind: whole(1.0, 100.0),
        unset: "",
        get: |s| Value::Number(s.output.jpeg_quality as f64),
        set: |s, v| s.output.jpeg_quality = v.number() as u8,
    },
];
