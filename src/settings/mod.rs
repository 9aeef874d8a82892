//! Every setting of a blur job, defined once (ripgrep's flag definitions are the model): its
//! name, flag, preset key, kind, range, unit and help, and where it lives in the parameter
//! structs, which own the defaults. From [`DEFS`] come the clap arguments of `shutter blur`
//! and `shutter dof` (`cli::args`), the reading and validation of preset keys, `shutter
//! presets keys`, the bench's flags, and the README's tables (checked by a test).
//!
//! A value is resolved as: the flag if given, else the preset key if a preset sets it, else
//! the default of the parameter struct. An invalid value is reported as the flag, or as the
//! preset and key, depending on where it came from.

use std::fmt;

use crate::dof::{BlendForm, DofParams, Lens, Method};
use crate::error::{Error, Result};
use crate::gpu::Backend;
use crate::io::exr::{compression_name, parse_compression, WRITABLE_COMPRESSIONS};
use crate::io::output::OutputOptions;
use crate::io::preset::Preset;
use crate::motion::{scatter, Algorithm, Anchor, CurveKind, Normalize, Shutter, Variant, Weight};
use crate::process::Params;

pub use crate::io::preset::Section;

/// A rule of a number setting's own, and the words that say what it allows.
pub type Rule = (fn(f64) -> bool, &'static str);

/// What values a setting takes.
#[derive(Clone, Copy)]
pub enum Kind {
    /// A number from `min` to `max` (above `min` when `above`); `whole` for integers.
    /// `valid` adds a rule of its own, and `expect` then says what is allowed. `names` are
    /// numbers by name, accepted beside the numbers (`--shutter-offset start`).
    Number {
        min: f64,
        max: f64,
        above: bool,
        whole: bool,
        valid: Option<Rule>,
        names: &'static [(&'static str, f32)],
    },
    /// One of these names.
    Choice(fn() -> Vec<&'static str>),
    /// On or off; the flag turns the default over (`--no-jitter`, `--half`).
    Switch,
}

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

/// A setting's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    Number(f64),
    Name(&'static str),
    Switch(bool),
    /// No value: the setting is off or chosen by the pass (see the definition's `unset`).
    Unset,
}

impl Value {
    fn number(self) -> f64 {
        match self {
            Value::Number(v) => v,
            _ => f64::NAN,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Value::Name(n) => n,
            _ => "",
        }
    }

    fn switch(self) -> bool {
        matches!(self, Value::Switch(true))
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Number(v) => write!(f, "{v}"),
            Value::Name(n) => f.write_str(n),
            Value::Switch(on) => f.write_str(if *on { "on" } else { "off" }),
            Value::Unset => f.write_str("unset"),
        }
    }
}

/// An f32 field as a value, printed as it was written (0.1, not 0.10000000149).
fn short(v: f32) -> Value {
    Value::Number(v.to_string().parse().unwrap_or(v as f64))
}

/// Everything a blur job's settings resolve to.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    pub algorithm: Algorithm,
    /// The motion blur's parameters (its `dof` stays `None` here; see [`Settings::dof`]).
    pub params: Params,
    /// Depth of field's parameters, used when a lens or a CoC map is given.
    pub dof: DofParams,
    pub lens: LensSettings,
    pub output: OutputOptions,
    /// Where the stages that have a GPU twin run.
    pub backend: Backend,
    /// The largest input frame, in pixels, checked from each file's header.
    pub max_pixels: usize,
}

/// The lens as settings: the three that turn depth of field on have no default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LensSettings {
    pub focal_length: Option<f64>,
    pub f_stop: Option<f64>,
    pub focus_distance: Option<f64>,
    pub sensor_width: f64,
    /// CoC diameter (px) of a painted map's value 1.
    pub coc_scale: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            algorithm: Algorithm::None,
            params: Params::default(),
            dof: DofParams::default(),
            lens: LensSettings {
                focal_length: None,
                f_stop: None,
                focus_distance: None,
                sensor_width: Lens::DEFAULT_SENSOR_MM,
                coc_scale: crate::dof::DEFAULT_COC_SCALE,
            },
            output: OutputOptions::default(),
            backend: Backend::default(),
            max_pixels: crate::io::file::DEFAULT_MAX_PIXELS,
        }
    }
}

impl Settings {
    /// The settings that run `algorithm` with `params` (depth of field included).
    pub fn of(algorithm: Algorithm, params: &Params) -> Settings {
        use crate::dof::CocSource;
        let mut settings = Settings {
            algorithm,
            params: Params {
                dof: None,
                ..*params
            },
            ..Settings::default()
        };
        if let Some(dof) = params.dof {
            settings.dof = DofParams {
                source: settings.dof.source,
                ..dof
            };
            match dof.source {
                CocSource::Lens(lens) => {
                    settings.lens.focal_length = Some(lens.focal_mm);
                    settings.lens.f_stop = Some(lens.f_number);
                    settings.lens.focus_distance = Some(lens.focus);
                    settings.lens.sensor_width = lens.sensor_mm;
                }
                CocSource::Map { scale } => settings.lens.coc_scale = scale,
            }
        }
        settings
    }
}

/// One setting.
pub struct Def {
    /// The long flag without dashes; the preset key is the same with `_` for `-`.
    pub name: &'static str,
    /// The flag when it differs from the name (switches on by default: `no-jitter`).
    pub flag: Option<&'static str>,
    pub section: Section,
    /// The algorithms (blur section) or depth-of-field methods it applies to; empty: all.
    pub applies: &'static [&'static str],
    pub value_name: &'static str,
    pub help: &'static str,
    pub kind: Kind,
    /// What an unset value means, for help texts.
    pub unset: &'static str,
    pub get: fn(&Settings) -> Value,
    pub set: fn(&mut Settings, Value),
}

impl Def {
    pub fn flag(&self) -> &'static str {
        self.flag.unwrap_or(self.name)
    }

    pub fn key(&self) -> String {
        self.name.replace('-', "_")
    }

    /// The default, from the parameter structs.
    pub fn default_value(&self) -> Value {
        (self.get)(&Settings::default())
    }

    /// The default as help texts print it.
    pub fn default_text(&self) -> String {
        match self.default_value() {
            Value::Unset => self.unset.to_string(),
            value => value.to_string(),
        }
    }

    /// The help line: what it applies to, what it does, and its choices.
    pub fn describe(&self) -> String {
        let mut text = String::new();
        if !self.applies.is_empty() {
            text += &format!("{}: ", self.applies.join(", "));
        }
        text += self.help;
        if let Kind::Choice(names) = self.kind {
            text += &format!(" ({})", names().join(", "));
        }
        text
    }

    /// What values are allowed, for messages.
    pub fn expect(&self) -> String {
        let text = self.expect_number();
        match self.kind {
            Kind::Number { names, .. } if !names.is_empty() => {
                let names: Vec<&str> = names.iter().map(|(n, _)| *n).collect();
                format!("{}, or {text}", names.join(", "))
            }
            _ => text,
        }
    }

    fn expect_number(&self) -> String {
        match self.kind {
            Kind::Number {
                valid: Some((_, expect)),
                ..
            } => expect.to_string(),
            Kind::Number {
                min,
                max,
                above,
                whole,
                ..
            } => {
                let what = if whole { "a whole number" } else { "a number" };
                match (above, max.is_finite()) {
                    (true, true) => format!("{what} above {min} and at most {max}"),
                    (true, false) => format!("{what} above {min}"),
                    (false, true) => format!("{what} from {min} to {max}"),
                    (false, false) => format!("{what} of {min} or more"),
                }
            }
            Kind::Choice(names) => {
                let names = names();
                match names.split_last() {
                    Some((last, [])) => last.to_string(),
                    Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
                    None => String::new(),
                }
            }
            Kind::Switch => "true or false".to_string(),
        }
    }

    /// Parses and checks a value typed as text (a flag).
    pub fn parse(&self, raw: &str) -> std::result::Result<Value, String> {
        match self.kind {
            Kind::Switch => match raw {
                "true" => Ok(Value::Switch(true)),
                "false" => Ok(Value::Switch(false)),
                _ => Err(self.expect()),
            },
            Kind::Choice(names) => names()
                .into_iter()
                .find(|n| n.eq_ignore_ascii_case(raw.trim()))
                .map(Value::Name)
                .ok_or_else(|| self.expect()),
            Kind::Number { names, .. } => {
                if let Some((_, v)) = names
                    .iter()
                    .find(|(n, _)| n.eq_ignore_ascii_case(raw.trim()))
                {
                    return Ok(Value::Number(*v as f64));
                }
                match raw.trim().parse::<f64>() {
                    Ok(v) => self.check(v),
                    Err(_) => Err(self.expect()),
                }
            }
        }
    }

    /// Checks a number against the setting's range.
    fn check(&self, v: f64) -> std::result::Result<Value, String> {
        let Kind::Number {
            min,
            max,
            above,
            whole,
            valid,
            ..
        } = self.kind
        else {
            return Err(self.expect());
        };
        let in_range = v.is_finite()
            && if above { v > min } else { v >= min }
            && v <= max
            && (!whole || v.fract() == 0.0)
            && valid.is_none_or(|(rule, _)| rule(v));
        if in_range {
            Ok(Value::Number(v))
        } else {
            Err(self.expect())
        }
    }

    /// Reads and checks a preset's TOML value.
    fn read_toml(&self, value: &toml::Value) -> std::result::Result<Value, String> {
        match (self.kind, value) {
            (Kind::Switch, toml::Value::Boolean(b)) => Ok(Value::Switch(*b)),
            (Kind::Choice(_), toml::Value::String(s)) => self.parse(s),
            (Kind::Number { .. }, toml::Value::Integer(i)) => self.check(*i as f64),
            (Kind::Number { .. }, toml::Value::Float(f)) => self.check(*f),
            (Kind::Number { names, .. }, toml::Value::String(s)) if !names.is_empty() => {
                self.parse(s)
            }
            _ => Err(self.expect()),
        }
    }
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
        unset: "",
        get: |s| Value::Name(compression_name(s.output.exr.compression)),
        set: |s, v| {
            if let Some(c) = parse_compression(v.name()) {
                s.output.exr.compression = c;
            }
        },
    },
    Def {
        name: "half",
        flag: None,
        section: Section::Output,
        applies: &[],
        value_name: "",
        help: "write EXR as 16-bit half floats (off: 32-bit float)",
        kind: Kind::Switch,
        unset: "",
        get: |s| Value::Switch(s.output.exr.half),
        set: |s, v| s.output.exr.half = v.switch(),
    },
    Def {
        name: "bit-depth",
        flag: None,
        section: Section::Output,
        applies: &[],
        value_name: "BITS",
        help: "bits per channel of PNG and TIFF output (JPEG is always 8)",
        kind: Kind::Number {
            min: 8.0,
            max: 16.0,
            above: false,
            whole: true,
            valid: Some((|v| v == 8.0 || v == 16.0, "8 or 16")),
            names: &[],
        },
        unset: "",
        get: |s| Value::Number(if s.output.sixteen_bit { 16.0 } else { 8.0 }),
        set: |s, v| s.output.sixteen_bit = v.number() == 16.0,
    },
];

/// The definition of a setting by name.
pub fn def(name: &str) -> Option<&'static Def> {
    DEFS.iter().find(|d| d.name == name)
}

/// Settings given as flags: (setting, the text typed; "true" for a switch's flag).
#[derive(Clone, Debug, Default)]
pub struct Given {
    pub values: Vec<(&'static str, String)>,
}

impl Given {
    pub fn get(&self, name: &str) -> Option<&str> {
        self.values
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, v)| v.as_str())
    }
}

/// Where a value came from, for messages.
fn flag_error(def: &Def, raw: &str, expect: String) -> Error {
    match def.kind {
        Kind::Switch => Error::usage(format!("--{}: {expect}", def.flag())),
        _ => Error::usage(format!("--{} {raw}: use {expect}", def.flag())),
    }
}

/// Resolves every setting: flags over preset keys over the parameter structs' defaults.
/// Also returns warnings for flags that do not apply to the chosen algorithm or method.
pub fn resolve(given: &Given, preset: &Preset) -> Result<(Settings, Vec<String>)> {
    check_preset(preset)?;
    let mut settings = Settings::default();
    for def in DEFS {
        let value = match given.get(def.name) {
            Some(raw) => match def.kind {
                // A switch's flag turns its default over.
                Kind::Switch => Value::Switch(!def.default_value().switch()),
                _ => def
                    .parse(raw)
                    .map_err(|expect| flag_error(def, raw, expect))?,
            },
            None => match preset_value(def, preset)? {
                Some(value) => value,
                None => continue,
            },
        };
        (def.set)(&mut settings, value);
    }
    let mut warnings = Vec::new();
    for def in DEFS.iter().filter(|d| given.get(d.name).is_some()) {
        let chosen = match def.section {
            Section::Blur => settings.algorithm.name(),
            Section::Dof => settings.dof.method.name(),
            Section::Output => continue,
        };
        if !def.applies.is_empty() && !def.applies.contains(&chosen) {
            warnings.push(format!(
                "--{} applies to {}, not {chosen}: it has no effect",
                def.flag(),
                def.applies.join(" and ")
            ));
        }
    }
    Ok((settings, warnings))
}

/// A preset's value of the setting, checked; `None` when the preset does not set it.
fn preset_value(def: &Def, preset: &Preset) -> Result<Option<Value>> {
    let key = def.key();
    let Some(raw) = preset.settings(def.section).get(&key) else {
        return Ok(None);
    };
    def.read_toml(raw).map(Some).map_err(|expect| {
        Error::usage(format!(
            "preset {}: [{}] {key} = {raw}: use {expect}",
            preset.origin(def.section, &key),
            def.section.table()
        ))
    })
}

/// Refuses keys that name no setting, listing the section's keys.
pub fn check_preset(preset: &Preset) -> Result<()> {
    for section in Section::ALL {
        for key in preset.settings(section).keys() {
            let known = DEFS.iter().any(|d| d.section == section && d.key() == *key);
            if !known {
                let keys: Vec<String> = DEFS
                    .iter()
                    .filter(|d| d.section == section)
                    .map(|d| d.key())
                    .collect();
                return Err(Error::usage(format!(
                    "preset {}: unknown key [{}] {key}; the keys are {}",
                    preset.origin(section, key),
                    section.table(),
                    keys.join(", ")
                )));
            }
        }
    }
    Ok(())
}

/// The flags that set `settings` where they differ from the defaults, in definition order
/// (`--algorithm` first): what `shutter blur` needs to run them, as the bench does.
pub fn flags(settings: &Settings) -> Vec<String> {
    let defaults = Settings::default();
    let mut flags = Vec::new();
    for def in DEFS {
        let value = (def.get)(settings);
        if value == (def.get)(&defaults) {
            continue;
        }
        match value {
            Value::Switch(_) => flags.push(format!("--{}", def.flag())),
            Value::Unset => {}
            value => {
                flags.push(format!("--{}", def.flag()));
                flags.push(value.to_string());
            }
        }
    }
    flags
}

/// The README's table of a section's settings: flag, preset key, default, what it does.
pub fn markdown_table(section: Section) -> String {
    let mut text = String::from("| flag | preset key | default | what |\n|---|---|---|---|\n");
    for def in DEFS.iter().filter(|d| d.section == section) {
        let flag = if def.value_name.is_empty() {
            format!("`--{}`", def.flag())
        } else {
            format!("`--{} {}`", def.flag(), def.value_name)
        };
        let default = match def.default_value() {
            Value::Unset => def.unset.to_string(),
            value => format!("`{value}`"),
        };
        text += &format!(
            "| {flag} | `{}` | {default} | {} |\n",
            def.key(),
            def.describe().replace('|', "\\|")
        );
    }
    text
}

/// `readme` with the text between each `<!-- settings:SECTION -->` marker and the next
/// `<!-- end settings -->` replaced by that section's [`markdown_table`]; `None` when a
/// section's markers are missing.
pub fn readme_with_tables(readme: &str) -> Option<String> {
    let mut text = readme.to_string();
    for section in Section::ALL {
        let open = format!("<!-- settings:{} -->\n", section.table());
        let start = text.find(&open)? + open.len();
        let end = start + text[start..].find("<!-- end settings -->")?;
        text.replace_range(start..end, &markdown_table(section));
    }
    Some(text)
}

/// The depth-of-field parameters when a lens or a CoC map turns it on, else `None`.
pub fn dof_params(settings: &Settings, coc_map: bool) -> Result<Option<DofParams>> {
    use crate::dof::CocSource;
    let lens = &settings.lens;
    let source = if coc_map {
        CocSource::Map {
            scale: lens.coc_scale,
        }
    } else {
        match (lens.focal_length, lens.f_stop, lens.focus_distance) {
            (None, None, None) => return Ok(None),
            (Some(focal_mm), Some(f_number), Some(focus)) => CocSource::Lens(Lens {
                focal_mm,
                f_number,
                focus,
                sensor_mm: lens.sensor_width,
            }),
            _ => {
                return Err(Error::usage(
                    "depth of field needs all of --focal-length, --f-stop and \
                     --focus-distance (or the [dof] keys focal_length, f_stop and \
                     focus_distance), or --coc-map",
                ))
            }
        }
    };
    let params = DofParams {
        source,
        ..settings.dof
    };
    params.check().map_err(Error::usage)?;
    Ok(Some(params))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_default_is_valid_and_every_name_unique() {
        for (i, def) in DEFS.iter().enumerate() {
            match def.default_value() {
                Value::Number(v) => assert!(def.check(v).is_ok(), "{}", def.name),
                Value::Name(n) => assert!(def.parse(n).is_ok(), "{}", def.name),
                Value::Switch(_) => assert!(matches!(def.kind, Kind::Switch)),
                Value::Unset => assert!(!def.unset.is_empty(), "{}", def.name),
            }
            assert!(
                DEFS[..i]
                    .iter()
                    .all(|d| d.flag() != def.flag() && d.name != def.name),
                "{} twice",
                def.name
            );
        }
    }

    #[test]
    fn flags_of_the_defaults_are_empty_and_round_trip_otherwise() {
        assert!(flags(&Settings::default()).is_empty());
        let mut s = Settings {
            algorithm: Algorithm::Scatter,
            ..Settings::default()
        };
        s.params.scatter.weight = Weight::Gaussian;
        s.params.reconstruct.jitter = false;
        s.params.scatter.flatness = 0.05;
        assert_eq!(
            flags(&s),
            [
                "--algorithm",
                "scatter",
                "--no-jitter",
                "--weight",
                "gaussian",
                "--flatness",
                "0.05"
            ]
        );
    }

    #[test]
    fn values_are_checked_against_their_ranges() {
        let samples = def("samples").unwrap();
        assert!(samples.parse("15").is_ok());
        assert_eq!(
            samples.parse("16").unwrap_err(),
            "an odd whole number from 1 to 255"
        );
        assert!(def("shutter").unwrap().parse("1.5").is_err());
        assert!(def("shutter").unwrap().parse("nan").is_err());
        assert_eq!(
            def("weight").unwrap().parse("Box").unwrap(),
            Value::Name("box")
        );
        assert_eq!(
            def("blades").unwrap().parse("2").unwrap_err(),
            "0 (round) or 3 to 32"
        );
        assert_eq!(
            def("max-coc").unwrap().parse("0").unwrap_err(),
            "a number above 0 and at most 512"
        );
    }
}
