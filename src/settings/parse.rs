//! Settings read and checked: a flag's text or a preset's TOML value turned into a [`Value`]
//! and held to its definition's range ([`Def::parse`]), every setting resolved into
//! [`Settings`] (flag over preset key over default, [`resolve`]), the errors that name the
//! flag or the preset and key the bad value came from, depth of field's parameters from the
//! lens settings ([`dof_params`]), and the way back: the flags that set given settings
//! ([`flags`], what the bench runs `shutter blur` with).

use super::{Def, Given, Kind, Section, Settings, Value, DEFS};
use crate::dof::{DofParams, Lens};
use crate::error::{Error, Result};
use crate::io::preset::Preset;

impl Def {
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

/// Where a value came from, for messages.
fn flag_error(def: &Def, raw: &str, expect: String) -> Error {
    match def.kind {
        Kind::Switch => Error::usage(format!("--{}: {expect}", def.flag())),
        _ => Error::usage(format!(
            "--{} {raw}: use {expect}{}",
            def.flag(),
            // Focus at infinity, a photographer's setting: what to give instead.
            match def.name == "focus-distance"
                && raw.parse::<f64>().is_ok_and(|v| v == f64::INFINITY)
            {
                true => " (to focus at infinity, give a distance far beyond the scene's, as 1e6)",
                false => "",
            }
        )),
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
        } else if def.name == "passes" && settings.dof.blend_form != crate::dof::BlendForm::Talk {
            // The pyramid's levels follow the CoC; only the talk's copies take passes.
            warnings.push(
                "--passes applies to blend's talk form (--blend-form talk), not the pyramid: \
                 it has no effect"
                    .into(),
            );
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
        let raw = match raw {
            toml::Value::Float(v) => crate::numeric::shown(*v),
            other => other.to_string(),
        };
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
    use super::super::def;
    use super::*;
    use crate::motion::{Algorithm, Weight};

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
