//! `shutter info`: what is in image files, and which presets match them.

use std::collections::BTreeMap;

use crate::error::{Error, Problem, ProblemKind, Result};
use crate::io::channels::{self, LayerClass};
use crate::io::file::{ChannelInfo, FileInfo, FileKind};
use crate::io::passes::{pass_layers, passes_found, suggest, Suggestion};
use crate::io::preset::{Preset, BUILTIN};

use super::args::InfoArgs;
use super::attributes::shown_name;
use super::out_text;

pub fn info(args: InfoArgs) -> Result<()> {
    let presets: Vec<Preset> = BUILTIN
        .iter()
        .filter(|(name, _)| crate::io::preset::is_convention(name))
        .map(|(name, _)| Preset::builtin(name))
        .collect::<Result<_>>()?;
    // The channels classed as a run with the preset classes them: by its `[layers]` table,
    // the layers its passes are read from, then the name rule (`shutter` without --preset).
    let preset = Preset::load(&args.preset)?;
    let layers: BTreeMap<String, LayerClass> = (preset.layers.iter())
        .map(|(layer, class)| (layer.clone(), class.class()))
        .collect();
    let mut problems = Vec::new();
    let mut documents = Vec::new();
    for path in &args.files {
        let info = match FileInfo::probe(path) {
            Ok(info) => info,
            Err(mut problem) => {
                // A sequence's pattern is no file: say which to give.
                let pattern = crate::io::sequence::PathPattern::parse(&path.to_string_lossy());
                if pattern.is_ok_and(|p| p.is_sequence()) && !path.exists() {
                    problem.detail.push_str(
                        "; shutter info reads files, not patterns: give one frame's file \
                         (shot.0001.exr for shot.####.exr)",
                    );
                }
                problems.push(problem);
                continue;
            }
        };
        // Presets are matched in the view a run would read: --view, else the default. A
        // view the file does not hold is an error; a file that names no default is described,
        // with no match until a view is chosen.
        if let (Some(view), None) = (&args.view, &info.views) {
            // As blur warns it: a file of no views reads the same in any.
            say!(
                "shutter: warning: view {view}: {} holds no views: --view has no effect",
                path.display()
            );
        }
        let seen = match info.in_view(args.view.as_deref()) {
            Ok(seen) => Some(seen),
            Err(detail) if args.view.is_some() => {
                problems.push(Problem::new(ProblemKind::View, path, detail));
                continue;
            }
            Err(_) => None,
        };
        let (matches, suggestion) = match &seen {
            Some(seen) => {
                let mut matches: Vec<(String, Vec<&'static str>)> = presets
                    .iter()
                    .map(|p| (p.name.clone(), passes_found(seen, p)))
                    .filter(|(_, found)| !found.is_empty())
                    .collect();
                // Best match first: most passes found; ties keep the built-in order.
                matches.sort_by_key(|(_, found)| std::cmp::Reverse(found.len()));
                (matches, Some(suggest(seen, &presets)))
            }
            None => (Vec::new(), None),
        };
        let pass_layers = pass_layers(seen.as_ref().unwrap_or(&info), &preset);
        let shown = Shown {
            layers: &layers,
            pass_layers: &pass_layers,
            info: &info,
            view: seen.as_ref().and_then(|s| s.view.as_deref()),
            matches: &matches,
            suggestion: suggestion.as_ref(),
        };
        if args.json {
            documents.push(info_json(&shown));
        } else {
            out_text(&info_text(&shown))?;
        }
    }
    if args.json {
        // One document: the files described and, when some could not be, the error object
        // a failed run's --json carries (README: "JSON").
        let document = if problems.is_empty() {
            serde_json::json!({
                "schema": crate::JSON_SCHEMA,
                "command": "info",
                "ok": true,
                "files": documents,
            })
        } else {
            let error = Error::Files(problems.clone());
            let mut document = super::error_json("info", &error, error.exit_code());
            document["files"] = serde_json::Value::Array(documents);
            document
        };
        super::out_json(&document)?;
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(Error::Files(problems))
    }
}

/// What `info` shows of one file.
struct Shown<'a> {
    /// A preset's classes of layers by name, over the name rule.
    layers: &'a BTreeMap<String, LayerClass>,
    /// The layers the preset reads passes from in the file: data (`passes::pass_layers`).
    pass_layers: &'a std::collections::BTreeSet<String>,
    info: &'a FileInfo,
    /// The view presets were matched in (multi-view files).
    view: Option<&'a str>,
    matches: &'a [(String, Vec<&'static str>)],
    /// `None` for a multi-view file that names no default view, when none was chosen.
    suggestion: Option<&'a Suggestion>,
}

fn describe_kind(info: &FileInfo) -> String {
    match &info.kind {
        FileKind::Exr {
            compression,
            tiled,
            multipart,
            ..
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
            ..
        } => format!(
            "{}, {bits}-bit {}",
            format.to_uppercase(),
            if *float { "float" } else { "integer" }
        ),
    }
}

fn info_text(shown: &Shown) -> String {
    let Shown {
        layers,
        pass_layers,
        info,
        view,
        matches,
        suggestion,
    } = *shown;
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
    if let Some(views) = &info.views {
        let read = match view {
            Some(view) => format!("; presets matched in view {}", shown_name(view)),
            None => format!(
                "; no default view ({}): choose one with --view",
                shown_name(views.no_default.as_deref().unwrap_or("none named"))
            ),
        };
        let list = shown_name(&views.list());
        text.push_str(&format!("  views:          {list}{read}\n"));
    }
    text.push_str("  channels:\n");
    for c in &info.channels {
        let name = shown_name(c.alias.as_ref().unwrap_or(&c.name));
        let in_view = match (&info.views, &c.view) {
            (Some(_), Some(v)) => format!("  view {}", shown_name(v)),
            (Some(_), None) => "  no view".to_string(),
            _ => String::new(),
        };
        // A part shutter cannot read (deep data) is left out of a run, with a warning.
        let class = match info.unreadable(c) {
            Some(_) => "not read",
            None => class_of(info, c, layers, pass_layers).name(),
        };
        let line = format!("    {name:<28} {:<4} {class:<6}{in_view}", c.sample_type);
        text.push_str(line.trim_end());
        text.push('\n');
    }
    for (part, rows) in attribute_rows(info) {
        text.push_str(&match part {
            Some(name) => format!("  attributes ({}):\n", shown_name(&name)),
            None => "  attributes:\n".to_string(),
        });
        for row in rows {
            text.push_str(&format!(
                "    {:<28} {:<15} {}\n",
                shown_name(&row.name),
                row.kind,
                row.text
            ));
        }
    }
    let Some(suggestion) = suggestion else {
        text.push_str("  presets:        choose a view with --view to match presets\n");
        return text;
    };
    if matches.is_empty() {
        text.push_str("  presets:        none match; write one (see README, Presets)\n");
    } else {
        for (i, (name, found)) in matches.iter().enumerate() {
            let label = if i == 0 { "  presets:" } else { "" };
            text.push_str(&format!("{label:<18}{name} ({})\n", found.join(", ")));
        }
    }
    text.push_str(&format!(
        "  suggested:      {}: {}\n",
        suggestion.preset.as_deref().unwrap_or("none"),
        suggestion.reason
    ));
    for role in ["vectors", "depth"] {
        let label = format!("  if {role}:");
        for (i, c) in suggestion
            .candidates
            .iter()
            .filter(|c| c.role == role)
            .enumerate()
        {
            let label = if i == 0 { label.as_str() } else { "" };
            text.push_str(&format!("{label:<18}{}: {}\n", c.preset, c.reason));
        }
    }
    text
}

/// The header attributes of each part of an EXR (named by its part's name, or `part N` in a
/// multi-part file), or a photo's metadata blocks.
fn attribute_rows(info: &FileInfo) -> Vec<(Option<String>, Vec<super::attributes::Shown>)> {
    match &info.kind {
        FileKind::Exr { headers, .. } => headers
            .iter()
            .enumerate()
            .map(|(i, h)| {
                let name = (headers.len() > 1).then(|| {
                    h.own_attributes
                        .layer_name
                        .as_ref()
                        .map_or(format!("part {i}"), |n| format!("part {i}, {n}"))
                });
                (name, super::attributes::of_header(h))
            })
            .collect(),
        FileKind::Image { .. } => match crate::io::image::read_photo(&info.path) {
            Ok(photo) => vec![(None, super::attributes::of_photo(&photo))],
            Err(_) => Vec::new(),
        },
    }
}

fn info_json(shown: &Shown) -> serde_json::Value {
    let Shown {
        layers,
        pass_layers,
        info,
        view,
        matches,
        suggestion,
    } = *shown;
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
        "views": info.views.as_ref().map(|v| serde_json::json!({
            "names": v.names,
            "default": v.default,
            "read": view,
        })),
        "channels": info.channels.iter().map(|c| serde_json::json!({
            "name": c.alias.as_ref().unwrap_or(&c.name),
            "type": c.sample_type,
            "class": class_of(info, c, layers, pass_layers).name(),
            "part": c.part,
            "unread": info.unreadable(c),
            "view": c.view,
        })).collect::<Vec<_>>(),
        "attributes": attribute_rows(info).into_iter().map(|(part, rows)| serde_json::json!({
            "part": part,
            "attributes": rows.into_iter().map(|r| serde_json::json!({
                "name": r.name, "type": r.kind, "value": r.json,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "presets": matches.iter().map(|(name, found)| serde_json::json!({
            "name": name, "passes": found,
        })).collect::<Vec<_>>(),
        "suggestion": suggestion,
    })
}

/// The class a channel has in an output (`io::channels`): how shutter treats it when the
/// file is the colour file.
fn class_of(
    info: &FileInfo,
    channel: &ChannelInfo,
    layers: &BTreeMap<String, LayerClass>,
    pass_layers: &std::collections::BTreeSet<String>,
) -> LayerClass {
    // As the read classes it: by `part.channel` where the part has a name (`diffuse.R`).
    let qualified = channel.alias.as_ref().unwrap_or(&channel.name);
    if let Some(class) = channels::preset_class(layers, qualified) {
        return class;
    }
    if pass_layers.contains(channels::layer_key(qualified)) {
        return LayerClass::Data;
    }
    let crypto = match &info.kind {
        FileKind::Exr { headers, .. } => headers
            .get(channel.part)
            .map(channels::crypto_layers)
            .unwrap_or_default(),
        FileKind::Image { .. } => Vec::new(),
    };
    channels::class_of(qualified, &crypto)
}
