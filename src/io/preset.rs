//! Presets: how a renderer names and encodes its passes, converted on read to the canonical
//! convention of DESIGN.md, plus optional algorithm and output settings.
//!
//! Presets are TOML. The built-in ones live in `presets/` and are embedded in the binary;
//! `--preset FILE.toml` loads one from disk. Every preset is merged over `shutter` (the
//! canonical convention), and several `--preset` flags merge left to right, so a preset holds
//! only what it changes. Command-line flags override preset values.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The presets compiled into the binary: (name, TOML text).
pub const BUILTIN: &[(&str, &str)] = &[
    ("shutter", include_str!("../../presets/shutter.toml")),
    ("blender", include_str!("../../presets/blender.toml")),
    ("nuke", include_str!("../../presets/nuke.toml")),
    ("painted", include_str!("../../presets/painted.toml")),
    ("preview", include_str!("../../presets/preview.toml")),
    ("final", include_str!("../../presets/final.toml")),
];

/// The tables of settings a preset may carry ([blur], [dof], [output]); their keys are defined
/// in [`crate::settings`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Section {
    Blur,
    Dof,
    Output,
}

impl Section {
    pub const ALL: [Section; 3] = [Section::Blur, Section::Dof, Section::Output];

    /// The table's name in TOML.
    pub fn table(self) -> &'static str {
        match self {
            Section::Blur => "blur",
            Section::Dof => "dof",
            Section::Output => "output",
        }
    }
}

/// How 8/16-bit colour values are encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Transfer {
    #[default]
    Srgb,
    Linear,
}

/// What a stored two-component vector means, once scaled and flipped to pixels, y down.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Meaning {
    /// `p(0) - p(-1)`: canonical velocity.
    Velocity,
    /// `p(-1) - p(0)`: offset to where the surface was one frame earlier.
    ToPrev,
    /// `p(+1) - p(0)`: offset to where it will be one frame later.
    ToNext,
    /// `p(0) - p(+1)`.
    FromNext,
    /// Absolute `p(-1)`.
    PrevPosition,
    /// Absolute `p(+1)`.
    NextPosition,
}

impl Meaning {
    /// True when the vector tells where the surface was (backward in time).
    pub fn is_backward(self) -> bool {
        matches!(
            self,
            Meaning::Velocity | Meaning::ToPrev | Meaning::PrevPosition
        )
    }

    pub fn is_position(self) -> bool {
        matches!(self, Meaning::PrevPosition | Meaning::NextPosition)
    }
}

/// Units of stored vectors.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Units {
    /// Pixels of the data window.
    #[default]
    Pixels,
    /// Fractions of the image width (x) and height (y).
    Normalized,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ColorSpec {
    /// Alternatives, each `[R, G, B]` or `[R, G, B, A]` (alpha optional in the file).
    pub channels: Vec<Vec<String>>,
    #[serde(default)]
    pub transfer: Transfer,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DepthSpec {
    /// Alternative channel names.
    pub channels: Vec<String>,
    /// When both are set, depth = near + value * (far - near) (painted grey maps).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub near: Option<f32>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub far: Option<f32>,
    /// Multiplies stored depth (e.g. to convert centimetres to the scene unit).
    #[serde(default = "one")]
    pub scale: f32,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VectorSpec {
    /// Alternatives, each `[x, y]` or `[x, y, z]` (z optional, read for positions only).
    pub channels: Vec<Vec<String>>,
    pub meaning: Meaning,
    /// Stored value meaning "no motion" (e.g. 0.5 for maps stored 0..1).
    #[serde(default)]
    pub zero: f32,
    /// Multiplies `stored - zero`.
    #[serde(default = "one")]
    pub scale: f32,
    /// |stored - zero| at or below this reads as exactly zero (quantised painted maps).
    #[serde(default)]
    pub dead_zone: f32,
    #[serde(default)]
    pub units: Units,
    /// Stored y grows upward: vectors have their y negated, positions are mirrored.
    #[serde(default)]
    pub y_up: bool,
}

fn one() -> f32 {
    1.0
}

/// A resolved preset: every pass described.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preset {
    #[serde(default)]
    pub description: String,
    pub color: ColorSpec,
    pub depth: DepthSpec,
    pub velocity: VectorSpec,
    pub prev: VectorSpec,
    pub next: VectorSpec,
    /// Settings of the motion blur, depth of field and output: keys are checked against their
    /// one definition in [`crate::settings`] when a job is resolved.
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    pub blur: toml::Table,
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    pub dof: toml::Table,
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    pub output: toml::Table,
    /// The names (or paths) this preset was built from, for messages.
    #[serde(skip)]
    pub name: String,
    /// Which of those set each settings key ("blur.max_blur" → "final"), for messages.
    #[serde(skip)]
    pub origins: std::collections::BTreeMap<String, String>,
}

/// True when the built-in preset describes how passes are stored (it has a colour, depth or
/// motion section), as opposed to carrying settings only (preview, final).
pub fn is_convention(name: &str) -> bool {
    name == "shutter"
        || builtin_text(name)
            .and_then(|text| text.parse::<toml::Table>().ok())
            .is_some_and(|table| {
                ["color", "depth", "velocity", "prev", "next"]
                    .iter()
                    .any(|key| table.contains_key(*key))
            })
}

/// The TOML text of a built-in preset.
pub fn builtin_text(name: &str) -> Option<&'static str> {
    BUILTIN
        .iter()
        .find(|(builtin, _)| *builtin == name)
        .map(|(_, text)| *text)
}

fn parse_table(text: &str, origin: &str) -> Result<toml::Table> {
    text.parse::<toml::Table>()
        .map_err(|e| Error::usage(format!("preset {origin}: {e}")))
}

/// Loads the TOML of one preset: a built-in name, or a path to a `.toml` file.
fn load_table(name_or_path: &str) -> Result<toml::Table> {
    if let Some(text) = builtin_text(name_or_path) {
        return parse_table(text, name_or_path);
    }
    let path = std::path::Path::new(name_or_path);
    if path.extension().is_some_and(|e| e == "toml") || path.exists() {
        let text = std::fs::read_to_string(path).map_err(|e| {
            Error::usage(format!("cannot read preset file {}: {e}", path.display()))
        })?;
        return parse_table(&text, name_or_path);
    }
    let names: Vec<&str> = BUILTIN.iter().map(|(n, _)| *n).collect();
    Err(Error::usage(format!(
        "unknown preset '{name_or_path}': built-in presets are {}; or give a path to a .toml file",
        names.join(", ")
    )))
}

/// Records `name` as the origin of every settings key in `table`.
fn note_origins(
    table: &toml::Table,
    name: &str,
    origins: &mut std::collections::BTreeMap<String, String>,
) {
    for section in Section::ALL {
        if let Some(toml::Value::Table(keys)) = table.get(section.table()) {
            for key in keys.keys() {
                origins.insert(format!("{}.{key}", section.table()), name.to_string());
            }
        }
    }
}

/// Merges `over` into `base`: tables merge key by key, everything else is replaced.
fn merge(base: &mut toml::Table, over: toml::Table) {
    for (key, value) in over {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(base_table)), toml::Value::Table(over_table)) => {
                merge(base_table, over_table)
            }
            (_, value) => {
                base.insert(key, value);
            }
        }
    }
}

impl Preset {
    /// Builds the preset from `shutter` with the named presets merged over it in order.
    pub fn load(names: &[String]) -> Result<Preset> {
        let mut table = parse_table(builtin_text("shutter").unwrap_or_default(), "shutter")?;
        let mut origins = std::collections::BTreeMap::new();
        note_origins(&table, "shutter", &mut origins);
        for name in names {
            if name != "shutter" {
                let over = load_table(name)?;
                note_origins(&over, name, &mut origins);
                merge(&mut table, over);
            }
        }
        let mut preset: Preset = table.try_into().map_err(|e: toml::de::Error| {
            Error::usage(format!("preset {}: {e}", names.join(" + ")))
        })?;
        preset.name = if names.is_empty() {
            "shutter".to_string()
        } else {
            names.join("+")
        };
        preset.origins = origins;
        preset.validate()?;
        Ok(preset)
    }

    /// The built-in preset of that name.
    pub fn builtin(name: &str) -> Result<Preset> {
        Preset::load(&[name.to_string()])
    }

    /// The settings table of a section.
    pub fn settings(&self, section: Section) -> &toml::Table {
        match section {
            Section::Blur => &self.blur,
            Section::Dof => &self.dof,
            Section::Output => &self.output,
        }
    }

    /// The preset (name or path) that set a settings key of a section.
    pub fn origin(&self, section: Section, key: &str) -> &str {
        self.origins
            .get(&format!("{}.{key}", section.table()))
            .map_or(self.name.as_str(), String::as_str)
    }

    /// Every channel name the preset's passes list, alternatives included.
    pub fn channel_names(&self) -> impl Iterator<Item = &String> {
        self.color
            .channels
            .iter()
            .chain(&self.velocity.channels)
            .chain(&self.prev.channels)
            .chain(&self.next.channels)
            .flatten()
            .chain(&self.depth.channels)
    }

    fn validate(&self) -> Result<()> {
        let bad = |what: String| Err(Error::usage(format!("preset {}: {what}", self.name)));
        if self.color.channels.is_empty() {
            return bad(
                "[color] channels is empty: give at least one alternative, e.g. \
                 channels = [[\"R\", \"G\", \"B\"]]"
                    .into(),
            );
        }
        if self.channel_names().any(|n| n.trim().is_empty()) {
            return bad("a channel name is empty".into());
        }
        if self
            .color
            .channels
            .iter()
            .any(|c| !(3..=4).contains(&c.len()))
        {
            return bad("each color alternative needs 3 or 4 channel names".into());
        }
        for (pass, spec) in [
            ("velocity", &self.velocity),
            ("prev", &self.prev),
            ("next", &self.next),
        ] {
            if spec.channels.iter().any(|c| !(2..=3).contains(&c.len())) {
                return bad(format!(
                    "each {pass} alternative needs 2 or 3 channel names"
                ));
            }
            if !spec.scale.is_finite() || !spec.zero.is_finite() || spec.dead_zone < 0.0 {
                return bad(format!("{pass}: scale, zero and dead_zone must be finite"));
            }
        }
        if let (Some(near), Some(far)) = (self.depth.near, self.depth.far) {
            if !(near.is_finite() && far.is_finite()) {
                return bad("depth near and far must be finite".into());
            }
        }
        Ok(())
    }

    /// The preset as TOML (what `shutter presets show` prints for a resolved preset).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_preset_loads() {
        for (name, _) in BUILTIN {
            let preset = Preset::builtin(name).unwrap();
            assert!(!preset.description.is_empty(), "{name} has no description");
        }
    }

    #[test]
    fn later_presets_override_earlier_keys_only() {
        let preset = Preset::load(&["blender".into()]).unwrap();
        assert_eq!(preset.velocity.meaning, Meaning::ToPrev);
        assert!(preset.velocity.y_up);
        // Not set by blender: kept from shutter.
        assert_eq!(preset.color.transfer, Transfer::Srgb);
    }

    #[test]
    fn settings_presets_merge_over_a_renderer_preset() {
        let preset = Preset::load(&["blender".into(), "final".into()]).unwrap();
        assert_eq!(preset.velocity.meaning, Meaning::ToPrev);
        assert_eq!(preset.blur["algorithm"].as_str(), Some("scatter"));
        assert_eq!(preset.blur["segments"].as_integer(), Some(20));
        assert_eq!(preset.origin(Section::Blur, "segments"), "final");
    }

    #[test]
    fn unknown_preset_lists_the_builtins() {
        let err = Preset::load(&["maya".into()]).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err
            .to_string()
            .contains("blender, nuke, painted, preview, final"));
    }

    #[test]
    fn unknown_keys_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("typo.toml");
        std::fs::write(&path, "[velocity]\nmeanin = \"to_prev\"\n").unwrap();
        let err = Preset::load(&[path.display().to_string()]).unwrap_err();
        assert!(err.to_string().contains("meanin"), "{err}");
    }
}
