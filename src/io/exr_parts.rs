//! Which part of an EXR output each channel of a frame goes to (`output` writes them through
//! [`exr_like`]): a part for each part of the colour file, holding what came from it, the
//! beauty in the colour's part. A stack's merged beauty (`Carried::merged`) in a multi-part
//! file goes in a part of its own, first, named `Composite.Combined` (Blender's name for the
//! composite): Blender 5 writes a view layer's passes a part each (`FG.Combined` holding
//! `FG.Combined.R`, …) and reads a part's channels that lack a layer name as the part's, so
//! `R`, `G`, `B`, `A` beside `FG.Combined.R` made it see an eight-channel Combined pass in FG
//! (and drop FG's Combined). A one-part output keeps them beside the layers, as before: there
//! Blender reads the bare channels as no layer's; where DWA's lossless data parts make that
//! output multi-part, `exr_like` splits its one part by view layer and the merged beauty's
//! part is named the same (`OutPart::bare`).

use crate::frame::{Frame, LayerClass, Window};
use crate::io::channels::name_of;
use crate::io::exr_like;
use crate::io::view::{layer_of, Scheme, Views as View};

/// The name of a stack's merged beauty's own part.
pub const MERGED_PART: &str = "Composite.Combined";

/// The parts of an EXR output of `views` (see `output::write_views`), made like `headers`, the
/// colour file's (one part when it is not an EXR); a part none of whose channels were
/// carried is left out.
pub fn exr_parts(
    views: Vec<Frame>,
    headers: &[exr::meta::header::Header],
) -> Vec<exr_like::OutPart<'_>> {
    let every = views.len() > 1;
    let count = headers.len().max(1);
    // A stack's merged beauty in a multi-part file: a part of its own, kept at `count` until
    // it is put first.
    let merged_beauty = views.first().is_some_and(|f| f.carried.merged);
    let own_part = count > 1 && merged_beauty;
    let colour_part = views
        .first()
        .map_or(0, |f| f.carried.colour_part.min(count - 1));
    let mut parts: Vec<Vec<exr_like::OutChannel>> = vec![Vec::new(); count + own_part as usize];
    let mut windows: Vec<Option<Window>> = vec![None; count + own_part as usize];
    // Where the file says its views in its channels' names (OpenEXR's single-part scheme),
    // each channel's view and its name in that view, in case the output is multi-part
    // (`exr_like::write_like` then writes it in the multi-part scheme). The frames come in
    // the order the run read the views (`Views::in_order`). A channel of no view is the
    // default view's alone where no other view reads it, as the reader decides (`FileInfo`):
    // every other view has one of its own in its place (`velocity.X` beside
    // `velocity.right.X`), or its layer is one another view writes as its own (`diffuse.A`
    // beside `diffuse.right.R`, `view::layer_of`).
    let by_names = every
        .then(|| View::of(headers))
        .flatten()
        .filter(|v| v.scheme == Scheme::Names);
    let order = by_names.as_ref().map(View::in_order).unwrap_or_default();
    // Each other view's own channels, its beauty's among them (`rgba.R` beside the default
    // view's `rgba.Z` makes `rgba` a layer of each view, as the reader counts every channel).
    let own: Vec<Vec<String>> = (views.iter().skip(1))
        .map(|f| {
            let beauty = match f.carried.beauty.is_empty() {
                true => ["R", "G", "B", "A"].map(String::from).to_vec(),
                false => f.carried.beauty.clone(),
            };
            (f.carried.channels.iter())
                .filter(|c| !c.shared)
                .map(|c| c.name.clone())
                .chain(beauty)
                .collect()
        })
        .collect();
    let own_layers: std::collections::BTreeSet<&str> =
        own.iter().flatten().filter_map(|n| layer_of(n)).collect();
    let view_of = |v: usize, shared: bool, name: &str| {
        let file = by_names.as_ref()?;
        let view = order.get(if shared { 0 } else { v })?;
        let layered = layer_of(name).is_some_and(|l| own_layers.contains(l));
        let defaults = shared
            && v == 0
            && (layered || own.iter().all(|names| names.iter().any(|n| n == name)));
        (!shared || defaults).then(|| (view.clone(), file.strip(name, view)))
    };
    for (v, frame) in views.into_iter().enumerate() {
        let carried = frame.carried;
        let color = frame.color.expect("checked");
        let data = Window {
            x: frame.windows.data_origin.0,
            y: frame.windows.data_origin.1,
            width: frame.width,
            height: frame.height,
        };
        // The beauty under the names it came with (as stored, view and all, beside other
        // views), then every channel carried beside it.
        let came_as = if every {
            &carried.beauty_stored
        } else {
            &carried.beauty
        };
        // Grey read as colour (a luminance file's `Y`, R = G = B = Y) names one channel three
        // times: it goes out as that one channel, so a luminance file comes back a luminance
        // file, where R, G and B are still equal (the blur, channel by channel in the same
        // order, keeps them so; were they not, R, G and B go out, as a picture's grey does).
        let distinct = |names: &[String]| (1..names.len()).all(|i| !names[..i].contains(&names[i]));
        let grey = came_as.len() >= 3
            && came_as[1] == came_as[0]
            && came_as[2] == came_as[0]
            && color.g == color.r
            && color.b == color.r;
        let mut names = match came_as.len() {
            _ if grey => vec![came_as[0].clone()],
            3 | 4 if distinct(came_as) => came_as.clone(),
            _ => ["R", "G", "B"].map(String::from).to_vec(),
        };
        // An alpha the colour file had not goes under the usual name, beside a view's
        // beauty in its layer (`right.A` beside `right.R`).
        if names.len() == 3 || grey {
            let alpha = match names[0].rsplit_once('.') {
                Some((layer, _)) if every => format!("{layer}.A"),
                _ => "A".to_string(),
            };
            names.push(alpha);
        }
        let mut planes = if grey {
            vec![color.r]
        } else {
            vec![color.r, color.g, color.b]
        };
        planes.extend(color.a);
        let part = if own_part {
            count
        } else {
            carried.colour_part.min(count - 1)
        };
        windows[part].get_or_insert(data);
        // A merged beauty takes its layers' pixel type where they agree (`stack::merge`).
        let like = |k: usize| carried.merged_like.get(k).cloned().flatten();
        parts[part].extend(
            names
                .into_iter()
                .zip(planes)
                .enumerate()
                .map(|(k, (name, plane))| exr_like::OutChannel {
                    view: view_of(v, false, &name),
                    name,
                    plane,
                    class: LayerClass::Colour,
                    exact: None,
                    source: like(k),
                }),
        );
        for c in carried.channels {
            // The channels of no view are each view's: written once.
            if every && c.shared && v > 0 {
                continue;
            }
            let part = c.part.min(count - 1);
            // (A part passed through at its own window holds no channel of the frame's.)
            windows[part].get_or_insert(c.window.unwrap_or(data));
            let (name, source) = if every || c.stored == c.name {
                (c.stored, None)
            } else {
                (c.name, Some(c.stored))
            };
            parts[part].push(exr_like::OutChannel {
                view: view_of(v, c.shared, &name),
                name,
                plane: c.plane,
                class: c.class,
                exact: c.exact,
                source,
            });
        }
    }
    // The parts of the file written again (a part none of whose channels were carried is not).
    let written: Vec<bool> = windows.iter().map(Option::is_some).collect();
    let mut out: Vec<exr_like::OutPart> = parts
        .into_iter()
        .zip(windows)
        .enumerate()
        .filter_map(|(p, (channels, data))| {
            let merged = p == count;
            Some(exr_like::OutPart {
                // The merged part is made like the beauty's, under a name of its own.
                input: headers.get(if merged { colour_part } else { p }),
                name: merged.then(|| merged_part_name(headers, &written)),
                // A merged beauty in a one-part file's one part: its own name should the part
                // be split (DWA, its data apart).
                bare: (count == 1 && merged_beauty).then_some(MERGED_PART),
                data: data?,
                channels,
            })
        })
        .collect();
    if own_part {
        if let Some(merged) = out.pop() {
            out.insert(0, merged);
        }
    }
    // A part of no view may not come first in a multi-view file: the first part of a view
    // goes first (its view is the default).
    if every {
        let viewed = |p: &exr_like::OutPart| {
            p.input
                .is_some_and(|h| h.own_attributes.view_name.is_some())
        };
        if let Some(first) = out.iter().position(viewed) {
            let part = out.remove(first);
            out.insert(0, part);
        }
    }
    out
}

/// [`MERGED_PART`], or where a part of the file `written` again has that name, the first of
/// `Composite.Combined2`, … none has (a stack's colour file's own composite is left out,
/// `FramePlan::leave_out_composite`, so the merged beauty takes its name).
fn merged_part_name(headers: &[exr::meta::header::Header], written: &[bool]) -> String {
    let taken: Vec<String> = (headers.iter().zip(written))
        .filter(|(_, &w)| w)
        .filter_map(|(h, _)| Some(name_of(h.own_attributes.layer_name.as_ref()?)))
        .collect();
    exr_like::fresh(MERGED_PART, &taken)
}
