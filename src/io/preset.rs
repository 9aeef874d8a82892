//! Presets: how a renderer names and encodes its passes, converted on read to the canonical
//! convention of docs/DESIGN.md, plus optional algorithm and output settings.
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
    ("rsmb", include_str!("../../presets/rsmb.toml")),
    ("vray", include_str!("../../presets/vray.toml")),
    ("unreal", include_str!("../../presets/unreal.toml")),
    ("arnold", include_str!("../../presets/arnold.toml")),
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

/// How stored vector values become offsets (before units, sign and y axis are applied).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Encoding {
    /// `(stored - zero) * scale`, whatever the file's sample type.
    #[default]
    Plain,
    /// RE:Vision Effects' normalised integer encoding (RSMB), which depends on the file's
    /// bit depth: an 8-bit code c reads as `(c - 127) / 127 * max_displace`, a 16-bit code
    /// as `(c - 32767) / 32767 * max_displace` (codes 0..254 and 0..65534 span
    /// -max_displace..+max_displace;
    /// <https://revisionfx.com/support/faqs/motion_vector_FAQs/motion_vector_math>).
    /// Float files are refused: RE:Vision's text on them was not found (presets/rsmb.toml).
    Rsmb,
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

impl DepthSpec {
    /// The `near` and `far` a grey map's codes (0 to 1) are mapped between, where both are
    /// given (a preset for painted maps).
    pub fn grey_range(&self) -> Option<(f32, f32)> {
        self.near.zip(self.far)
    }

    /// How a grey map's codes (0 to 1) are taken as depth under this preset, for the run's
    /// warnings: as they are, in scene units, where it gives no `near` and `far` (which a
    /// painted map rarely means); `None` where it maps them between the two.
    pub fn grey_note(&self, preset: &str) -> Option<String> {
        self.grey_range().is_none().then(|| {
            format!(
                "depth: the grey of an 8/16-bit map is read as depth 0 to 1 in scene units \
                 (metres for the lens) under preset {preset}; --preset painted reads black to \
                 white as 1 to 100 m (copy it to set near and far)"
            )
        })
    }
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
    /// How stored values become offsets: `plain` uses `zero` and `scale`; `rsmb` decodes
    /// RE:Vision's 8/16-bit codes with `max_displace` (and leaves `zero`, `scale` unset).
    #[serde(default, skip_serializing_if = "is_default")]
    pub encoding: Encoding,
    /// RSMB's Max Displace: the motion in pixels that the largest code stands for. The
    /// renderer's setting, not stored in the file, so the preset must give it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_displace: Option<f32>,
    /// Alternative names of a channel, in the file the vectors come from, whose value below
    /// full-on (1.0, the largest code of an integer file) marks the vector at that pixel
    /// invalid. Invalid vectors take the motion of the nearest valid one
    /// (`io::passes::validity`); empty: every vector is valid.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub validity_alpha: Vec<String>,
}

impl VectorSpec {
    /// What is missing for the section to be read, when something is: a message naming the
    /// key and what to do.
    pub fn incomplete(&self, pass: &str) -> Option<String> {
        match (self.encoding, self.max_displace) {
            (Encoding::Rsmb, None) => Some(format!(
                "[{pass}] encoding \"rsmb\" needs max_displace, the Max Displace (pixels) the \
                 vectors were written with (it is not stored in the file): give it with \
                 --max-displace PX, or in a preset file, e.g. [{pass}] max_displace = 32.0, \
                 after --preset rsmb"
            )),
            _ => None,
        }
    }
}

fn is_default<T: Default + PartialEq>(value: &T) -> bool {
    *value == T::default()
}

fn one() -> f32 {
    1.0
}

/// A layer's class as a preset names it (`[layers]`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum LayerClassName {
    Colour,
    Data,
    Motion,
}

impl LayerClassName {
    pub fn class(self) -> crate::frame::LayerClass {
        match self {
            LayerClassName::Colour => crate::frame::LayerClass::Colour,
            LayerClassName::Data => crate::frame::LayerClass::Data,
            LayerClassName::Motion => crate::frame::LayerClass::Motion,
        }
    }
}

/// A resolved preset: every pass described.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Preset {
    #[serde(default)]
    pub description: String,
    /// What the renderer must be set to for the preset to read its passes right (one line,
    /// shown by `shutter presets`).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub expects: String,
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
    /// The class of the colour file's layers by name, over the rule `io::channels` gives
    /// (`albedo = "data"` keeps a layer sharp, `"ViewLayer.Mist" = "colour"` blurs one,
    /// `Z = "motion"` carries depth with the motion: [`crate::motion::carry`]):
    /// `[layers]` in a preset file, merged key by key like the settings.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub layers: std::collections::BTreeMap<String, LayerClassName>,
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

/// The largest preset file read (1 MiB; the built-in ones are under 4 KiB).
pub const PRESET_CAP: u64 = 1 << 20;

/// Loads the TOML of one preset: a built-in name, or a path to a `.toml` file.
fn load_table(name_or_path: &str) -> Result<toml::Table> {
    if let Some(text) = builtin_text(name_or_path) {
        return parse_table(text, name_or_path);
    }
    let path = std::path::Path::new(name_or_path);
    if path.extension().is_some_and(|e| e == "toml") || path.exists() {
        let text = crate::io::input::read_small_text(path, PRESET_CAP).map_err(|e| {
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

/// The tables of a preset that describe its passes, whose keys are checked when it loads.
const PASS_TABLES: [&str; 5] = ["color", "depth", "velocity", "prev", "next"];

/// Records `name` as the origin of every settings key in `table`, and of every key of its
/// pass tables (`depth.scale` → `cm.toml`), for messages.
fn note_origins(
    table: &toml::Table,
    name: &str,
    origins: &mut std::collections::BTreeMap<String, String>,
) {
    let tables = Section::ALL
        .map(Section::table)
        .into_iter()
        .chain(PASS_TABLES);
    for section in tables {
        if let Some(toml::Value::Table(keys)) = table.get(section) {
            for key in keys.keys() {
                origins.insert(format!("{section}.{key}"), name.to_string());
            }
        }
    }
}

/// The least and the largest `[depth] scale`: a conversion between any two units of length
/// a renderer writes depth in (micrometres to kilometres, 1e-6 to 1e3, with room either
/// side) lies within; beyond is a mistake, not a unit (1e-40 read every depth as 0, the
/// lens then blurring the whole frame without a word).
pub const DEPTH_SCALE: (f32, f32) = (1e-6, 1e6);

/// A preset's number as its message shows it: as written where that is short (`1e-40`, not
/// the f64 the f32 widens to), in exponent form beyond.
fn shown(v: f32) -> String {
    crate::numeric::shown_f32(v)
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
        self.origin_of(section.table(), key)
    }

    /// The preset (name or path) that set key `key` of table `table` (`depth`, `blur`).
    pub fn origin_of(&self, table: &str, key: &str) -> &str {
        self.origins
            .get(&format!("{table}.{key}"))
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
        if let Some(name) = self.channel_names().find(|n| miswritten_placeholder(n)) {
            return bad(format!(
                "channel name '{name}' has a placeholder written otherwise than {{layer}} \
                 (lower case, no spaces), so it would be looked for as written"
            ));
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
            for (key, value, allowed) in [
                ("scale", spec.scale, spec.scale.is_finite()),
                ("zero", spec.zero, spec.zero.is_finite()),
                // NaN compares false with everything: tested as what it must be.
                (
                    "dead_zone",
                    spec.dead_zone,
                    spec.dead_zone.is_finite() && spec.dead_zone >= 0.0,
                ),
            ] {
                if !allowed {
                    let expect = match key {
                        "dead_zone" => "a finite number of 0 or more",
                        _ => "a finite number",
                    };
                    return self.refused(pass, key, &shown(value), expect);
                }
            }
            if let Some(max) = spec.max_displace {
                if !(max.is_finite() && max > 0.0) {
                    return bad(format!(
                        "[{pass}] max_displace must be a positive number of pixels"
                    ));
                }
            }
            if spec.encoding == Encoding::Rsmb
                && (spec.zero != 0.0 || spec.scale != 1.0 || spec.dead_zone != 0.0)
            {
                return bad(format!(
                    "[{pass}] zero, scale and dead_zone do not apply to encoding \"rsmb\" \
                     (its codes fix them; max_displace scales it)"
                ));
            }
            if spec.validity_alpha.iter().any(|n| n.trim().is_empty()) {
                return bad(format!("[{pass}] a validity_alpha channel name is empty"));
            }
        }
        self.validate_depth()
    }

    /// Refuses `[depth]` mapping keys that would read no depth (F3: `scale = 0`, NaN, a
    /// negative or a subnormal scale, `near = far`, were read without a word, the lens then
    /// blurring everything, or a warning blaming the input file for NaN it does not hold).
    fn validate_depth(&self) -> Result<()> {
        let DepthSpec {
            near, far, scale, ..
        } = self.depth;
        let (least, most) = DEPTH_SCALE;
        if !(least..=most).contains(&scale) {
            return self.refused(
                "depth",
                "scale",
                &shown(scale),
                &format!(
                    "a number from {} to {} (what stored depth is multiplied by: 0.01 reads \
                     centimetres as metres)",
                    shown(least),
                    shown(most)
                ),
            );
        }
        let distance = |v: f32| v.is_finite() && v >= 0.0;
        match (near, far) {
            (None, None) => Ok(()),
            (Some(_), None) | (None, Some(_)) => {
                let (set, unset) = if near.is_some() {
                    ("near", "far")
                } else {
                    ("far", "near")
                };
                let value = near.or(far).unwrap_or_default();
                self.refused(
                    "depth",
                    set,
                    &shown(value),
                    &format!(
                        "it with {unset}, or neither: near and far map a grey map's black and \
                         white to depths, and one alone maps nothing"
                    ),
                )
            }
            (Some(near), Some(far)) => {
                let expect = "a finite distance of 0 or more, near and far different \
                              (the depths a grey map's black and white stand for)";
                if !distance(near) {
                    self.refused("depth", "near", &shown(near), expect)
                } else if !distance(far) || far == near {
                    self.refused("depth", "far", &shown(far), expect)
                } else {
                    Ok(())
                }
            }
        }
    }

    /// The error for key `key` of table `table` set to `shown`, naming the preset (file) that
    /// set it and what it takes, as a settings key's is (`settings::parse`).
    fn refused(&self, table: &str, key: &str, shown: &str, expect: &str) -> Result<()> {
        Err(Error::usage(format!(
            "preset {}: [{table}] {key} = {shown}: use {expect}",
            self.origin_of(table, key)
        )))
    }

    /// Refuses a preset that leaves out a value only the user knows (RSMB's Max Displace),
    /// before any file is looked at. Loading does not: a built-in preset such as `rsmb` is
    /// shown and merged without it.
    pub fn check_complete(&self) -> Result<()> {
        for (pass, spec) in [
            ("velocity", &self.velocity),
            ("prev", &self.prev),
            ("next", &self.next),
        ] {
            if let Some(missing) = spec.incomplete(pass) {
                return Err(Error::usage(format!("preset {}: {missing}", self.name)));
            }
        }
        Ok(())
    }

    /// The preset as TOML (what `shutter presets show` prints for a resolved preset).
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_default()
    }
}

/// Whether channel name `name` has `{layer}` written another way (`{LAYER}`, `{ Layer }`):
/// read as a literal name, it matches no channel, and the run would say the file lacks a pass
/// it has. Other braces are left alone (a channel may be named anything).
fn miswritten_placeholder(name: &str) -> bool {
    let mut rest = name;
    while let Some(open) = rest.find('{') {
        let Some(close) = rest[open..].find('}') else {
            break;
        };
        let inner = &rest[open + 1..open + close];
        if inner != "layer" && inner.trim().eq_ignore_ascii_case("layer") {
            return true;
        }
        rest = &rest[open + close + 1..];
    }
    false
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
            .contains("blender, nuke, painted, rsmb, vray, unreal, arnold, preview, final"));
    }

    #[test]
    fn rsmb_loads_but_a_run_needs_its_max_displace() {
        let preset = Preset::builtin("rsmb").unwrap();
        assert_eq!(preset.velocity.encoding, Encoding::Rsmb);
        assert_eq!(preset.next.meaning, Meaning::ToNext);
        assert_eq!(preset.prev.validity_alpha, ["A"]);
        assert!(!preset.expects.is_empty());
        let err = preset.check_complete().unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().contains("max_displace"), "{err}");

        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("md.toml");
        let text = "[velocity]\nmax_displace = 16.0\n[prev]\nmax_displace = 16.0\n\
                    [next]\nmax_displace = 16.0\n";
        std::fs::write(&path, text).unwrap();
        let preset = Preset::load(&["rsmb".into(), path.display().to_string()]).unwrap();
        preset.check_complete().unwrap();
        assert_eq!(preset.next.max_displace, Some(16.0));
        assert_eq!(preset.next.encoding, Encoding::Rsmb);
    }

    #[test]
    fn rsmb_refuses_zero_scale_and_bad_max_displace() {
        let dir = tempfile::tempdir().unwrap();
        for (text, wanted) in [
            ("[velocity]\nscale = 2.0\n", "do not apply"),
            ("[velocity]\nmax_displace = 0.0\n", "positive"),
            ("[velocity]\nmax_displace = -3.0\n", "positive"),
        ] {
            let path = dir.path().join("bad.toml");
            std::fs::write(&path, text).unwrap();
            let err = Preset::load(&["rsmb".into(), path.display().to_string()]).unwrap_err();
            assert!(err.to_string().contains(wanted), "{text}: {err}");
        }
    }

    #[test]
    fn unknown_keys_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("typo.toml");
        std::fs::write(&path, "[velocity]\nmeanin = \"to_prev\"\n").unwrap();
        let err = Preset::load(&[path.display().to_string()]).unwrap_err();
        assert!(err.to_string().contains("meanin"), "{err}");
    }

    #[test]
    fn a_placeholder_written_otherwise_than_layer_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let load = |names: &str| {
            let path = dir.path().join("layered.toml");
            let channels = ["R", "G", "B"]
                .map(|c| format!("\"{names}.{c}\""))
                .join(", ");
            std::fs::write(&path, format!("[color]\nchannels = [[{channels}]]\n")).unwrap();
            Preset::load(&[path.display().to_string()])
        };
        for miswritten in ["{LAYER}.Combined", "{ layer }.Combined", "x.{Layer}"] {
            let err = load(miswritten).unwrap_err().to_string();
            assert!(
                err.contains(&format!("'{miswritten}.R'")) && err.contains("{layer}"),
                "{miswritten}: {err}"
            );
        }
        // The placeholder itself, and braces around anything else, are channel names.
        for kept in ["{layer}.Combined", "{layers}.Combined", "{}", "{LAYER"] {
            assert!(load(kept).is_ok(), "{kept}");
        }
    }
}
