//! `shutter presets`: the built-in presets, one preset's TOML, and every settings key.

use crate::error::{Error, Result};
use crate::io::preset::{Preset, BUILTIN};
use crate::settings::{self, Section};

use super::args::{PresetsArgs, PresetsCommand};

pub fn presets(args: PresetsArgs) -> Result<()> {
    match args.command {
        None => {
            for (name, _) in BUILTIN {
                let preset = Preset::builtin(name)?;
                println!("{name:<10} {}", preset.description);
            }
            Ok(())
        }
        Some(PresetsCommand::Show { name }) => {
            if let Some((_, text)) = BUILTIN.iter().find(|(n, _)| *n == name) {
                print!("{text}");
                return Ok(());
            }
            // A file: check it loads and its settings are valid, then print it as written.
            let preset = Preset::load(std::slice::from_ref(&name))?;
            settings::resolve(&settings::Given::default(), &preset)?;
            let text = std::fs::read_to_string(&name)
                .map_err(|e| Error::usage(format!("cannot read {name}: {e}")))?;
            print!("{text}");
            Ok(())
        }
        Some(PresetsCommand::Keys) => {
            for (section, what) in [
                (Section::Blur, "motion blur"),
                (Section::Dof, "depth of field"),
                (Section::Output, "output"),
            ] {
                println!("[{}]  {what}", section.table());
                for def in settings::DEFS.iter().filter(|d| d.section == section) {
                    println!(
                        "  {:<18} --{:<18} default {:<8} {}",
                        def.key(),
                        def.flag(),
                        def.default_text(),
                        def.describe()
                    );
                }
                println!();
            }
            Ok(())
        }
    }
}
