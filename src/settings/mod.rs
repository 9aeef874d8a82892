//! Every setting of a blur job, defined once (ripgrep's flag definitions are the model): its
//! name, flag, preset key, kind, range, unit and help, and where it lives in the parameter
//! structs, which own the defaults. From [`DEFS`] come the clap arguments of `shutter blur`
//! and `shutter dof` (`cli::args`), the reading and validation of preset keys, `shutter
//! presets keys`, the bench's flags, and the README's tables (checked by a test).
//!
//! A value is resolved as: the flag if given, else the preset key if a preset sets it, else
//! the default of the parameter struct. An invalid value is reported as the flag, or as the
//! preset and key, depending on where it came from.
//!
//! The machinery is split as ripgrep splits `crates/core/flags/`:
//!
//! - this file: what a setting is ([`Def`], its [`Kind`] and [`Value`]), what they resolve
//!   to ([`Settings`]), the flags as typed ([`Given`]), and the public names callers import;
//! - `defs`: the table, [`DEFS`], one entry per setting, and the helpers its entries use;
//! - `parse`: text and preset values read into [`Settings`] and checked against their
//!   ranges, the errors that name the flag or preset key, and the way back to flags;
//! - `doc`: the words users read, from the same table: help lines, printed defaults, what
//!   values are allowed, and the README's tables.

mod defs;
mod doc;
mod parse;

use std::fmt;

use crate::dof::{DofParams, Lens};
use crate::gpu::Backend;
use crate::io::output::OutputOptions;
use crate::motion::Algorithm;
use crate::process::Params;

pub use defs::DEFS;
pub use doc::{markdown_table, readme_with_tables};
pub use parse::{check_preset, dof_params, flags, resolve};

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
    /// The most memory a run may need, in MiB (`None`: [`crate::pipeline::memory_limit`]'s
    /// share of the machine), checked from the headers before anything is decoded.
    pub max_memory: Option<u64>,
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
            max_memory: None,
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
}

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
