//! The words users read about the settings, all from the one table ([`DEFS`]): a setting's
//! help line and its default as printed (used by `shutter blur --help`, `shutter dof --help`
//! and `shutter presets keys`, which `cli` lays out), what values it allows (in help texts and
//! in the errors of `parse`, so that both say the same), and the README's settings tables,
//! which a test holds to the README.

use super::{Def, Kind, Section, Value, DEFS};

impl Def {
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
                // An unbounded range still asks for a finite number (inf is refused).
                let what = match (whole, max.is_finite()) {
                    (true, _) => "a whole number",
                    (false, true) => "a number",
                    (false, false) => "a finite number",
                };
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
