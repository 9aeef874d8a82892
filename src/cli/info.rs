//! `shutter info`: what is in image files, and which presets match them.

use crate::error::{Error, Result};
use crate::io::file::{FileInfo, FileKind};
use crate::io::passes::passes_found;
use crate::io::preset::{Preset, BUILTIN};

use super::args::InfoArgs;
use super::out;

pub fn info(args: InfoArgs) -> Result<()> {
    let presets: Vec<Preset> = BUILTIN
        .iter()
        .filter(|(name, _)| crate::io::preset::is_convention(name))
        .map(|(name, _)| Preset::builtin(name))
        .collect::<Result<_>>()?;
    let mut problems = Vec::new();
    let mut documents = Vec::new();
    for path in &args.files {
        let info = match FileInfo::probe(path) {
            Ok(info) => info,
            Err(problem) => {
                problems.push(problem);
                continue;
            }
        };
        let mut matches: Vec<(String, Vec<&'static str>)> = presets
            .iter()
            .map(|p| (p.name.clone(), passes_found(&info, p)))
            .filter(|(_, found)| !found.is_empty())
            .collect();
        // Best match first: most passes found; ties keep the built-in order.
        matches.sort_by_key(|(_, found)| std::cmp::Reverse(found.len()));
        if args.json {
            documents.push(info_json(&info, &matches));
        } else {
            out(&info_text(&info, &matches));
        }
    }
    if args.json {
        out(&(serde_json::to_string_pretty(&documents).unwrap_or_default() + "\n"));
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(Error::Files(problems))
    }
}

fn describe_kind(info: &FileInfo) -> String {
    match &info.kind {
        FileKind::Exr {
            compression,
            tiled,
            multipart,
        } => {
            let mut compression = compression.clone();
            compression.dedup();
            format!(
                "OpenEXR, {}, {}, {} compression",
                if *tiled { "tiled" } else { "scan lines" },
                if *multipart {
                    "multi-part"
                } else {
                    "single part"
                },
                compression.join("/")
            )
        }
        FileKind::Image {
            format,
            bits,
            float,
        } => format!(
            "{}, {bits}-bit {}",
            format.to_uppercase(),
            if *float { "float" } else { "integer" }
        ),
    }
}

fn info_text(info: &FileInfo, matches: &[(String, Vec<&'static str>)]) -> String {
    let w = &info.windows;
    let mut text = format!("{}\n", info.path.display());
    text.push_str(&format!("  format:         {}\n", describe_kind(info)));
    text.push_str(&format!(
        "  size:           {}x{}\n",
        info.width, info.height
    ));
    text.push_str(&format!(
        "  data window:    ({}, {}) - ({}, {})\n",
        w.data_origin.0,
        w.data_origin.1,
        w.data_origin.0 + info.width as i32 - 1,
        w.data_origin.1 + info.height as i32 - 1
    ));
    text.push_str(&format!(
        "  display window: ({}, {}) - ({}, {})\n",
        w.display.x,
        w.display.y,
        w.display.max().0,
        w.display.max().1
    ));
    text.push_str("  channels:\n");
    for c in &info.channels {
        let name = c.alias.clone().unwrap_or_else(|| c.name.clone());
        text.push_str(&format!("    {name:<28} {}\n", c.sample_type));
    }
    if matches.is_empty() {
        text.push_str("  presets:        none match; write one (see README, Presets)\n");
    } else {
        for (i, (name, found)) in matches.iter().enumerate() {
            let label = if i == 0 { "  presets:" } else { "" };
            text.push_str(&format!("{label:<18}{name} ({})\n", found.join(", ")));
        }
    }
    text
}

fn info_json(info: &FileInfo, matches: &[(String, Vec<&'static str>)]) -> serde_json::Value {
    let w = &info.windows;
    serde_json::json!({
        "path": info.path.display().to_string(),
        "format": describe_kind(info),
        "width": info.width,
        "height": info.height,
        "data_window": [w.data_origin.0, w.data_origin.1,
            w.data_origin.0 + info.width as i32 - 1, w.data_origin.1 + info.height as i32 - 1],
        "display_window": [w.display.x, w.display.y, w.display.max().0, w.display.max().1],
        "compression": match &info.kind { FileKind::Exr { compression, .. } => compression.clone(), _ => vec![] },
        "channels": info.channels.iter().map(|c| serde_json::json!({
            "name": c.alias.clone().unwrap_or_else(|| c.name.clone()),
            "type": c.sample_type,
            "part": c.part,
        })).collect::<Vec<_>>(),
        "presets": matches.iter().map(|(name, found)| serde_json::json!({
            "name": name, "passes": found,
        })).collect::<Vec<_>>(),
    })
}
