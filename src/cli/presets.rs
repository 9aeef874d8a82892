//! `shutter presets`: the built-in presets, one preset's TOML, and every settings key.

use crate::error::{Error, Result};
use crate::io::preset::{Preset, BUILTIN};
use crate::settings::{self, Section};

use super::args::{PresetsArgs, PresetsCommand};
use super::out;

pub fn presets(args: PresetsArgs) -> Result<()> {
    match args.command {
        None => {
            let mut text = String::new();
            for (name, _) in BUILTIN {
                let preset = Preset::builtin(name)?;
                text += &format!("{name:<10} {}\n", preset.description);
                if !preset.expects.is_empty() {
                    text += &format!("{:<10} expects: {}\n", "", preset.expects);
                }
            }
            out(&text)?;
            Ok(())
        }
        Some(PresetsCommand::Show { name }) => {
            if let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name) {
                out(text)?;
                return Ok(());
            }
            // A file: check it loads and its settings are valid, then print it as written.
            let preset = Preset::load(std::slice::from_ref(&name))?;
            settings::resolve(&settings::Given::default(), &preset)?;
            let text = crate::io::input::read_small_text(
                std::path::Path::new(&name),
                crate::io::preset::PRESET_CAP,
            )
            .map_err(|e| Error::usage(format!("cannot read {name}: {e}")))?;
            out(&text)?;
            Ok(())
        }
        Some(PresetsCommand::Keys) => {
            for (section, what) in [
                (Section::Blur, "motion blur"),
                (Section::Dof, "depth of field"),
                (Section::Output, "output"),
            ] {
                let mut text = format!("[{}]  {what}\n", section.table());
                for def in settings::DEFS.iter().filter(|d| d.section == section) {
                    text += &format!(
                        "  {:<18} --{:<18} default {:<8} {}\n",
                        def.key(),
                        def.flag(),
                        def.default_text(),
                        def.describe()
                    );
                }
                out(&(text + "\n"))?;
            }
            Ok(())
        }
    }
}
