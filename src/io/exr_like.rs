//! An EXR output made like the colour file it came from (issue 29: what comes in goes out).
//!
//! In: the planes to write, part by part, each with the colour file's header of that part
//! (`None` when the colour came from a PNG, JPEG or TIFF), the output settings and the record
//! of what made the frame. Out: the file, written through the caller's writer, with as many
//! parts as the input had (those carried), and under DWA one more for the data.
//!
//! The output's header is the input's, minus what describes the file's layout: every
//! attribute the exr crate reads (chromaticities, whiteLuminance, framesPerSecond, timeCode,
//! owner, comments, capDate, utcOffset, the camera matrices, the views, custom attributes of
//! any type), the display window, the pixel aspect; the data window is the frame's. Not kept:
//! the preview (it shows the pixels before the blur), and the layout (channels, chunk count,
//! the tile levels: only the full-resolution level is read, so a mip-mapped input comes back
//! as one level; nor a custom attribute under a layout name (`is_layout`), such as the
//! stale `openexr:chunkCount` oiiotool leaves), and, where one view of a multi-view file is
//! written, its `multiView` list
//! and parts' `view` attributes (an output of every view keeps them). Its form follows the
//! input too: compression (unless `compression` is set), line order (RANDOM_Y for tiles
//! alone, where OpenEXR allows it, its tiles written in increasing order), scan lines or tiles of
//! the same size (a tiled plate stays tiled, so the tools that read it by tiles still can),
//! and each channel's pixel type (half stays half; `half` writes every float channel half,
//! u32 stays u32). Added: `shutter/version` and `shutter/settings` (the settings that differ
//! from the defaults, as flags, and the view layers read: `--layer X`, `--layers FG,BG`), as
//! Nuke records `nuke/node_hash`.
//!
//! The exr crate writes custom attributes in the order of a `HashMap`, which differs from
//! run to run; `exr_order::sort_attributes` then puts each header's attributes in name order (as
//! OpenEXR's own library writes them), in place, so the same frame gives the same bytes.

use std::io::{BufWriter, Read, Seek, Write};

use exr::compression::Compression;
use exr::image::{AnyChannels, Blocks, Encoding, Image, Layer};
use exr::math::Vec2;
use exr::meta::attribute::{AttributeValue, IntegerBounds, Text};
use exr::meta::header::{standard_names, Header, ImageAttributes, LayerAttributes};
use exr::meta::BlockDescription;
use exr::prelude::LineOrder;

use crate::frame::Window;
use crate::io::channels::{name_of, name_text};
pub use crate::io::exr_channels::OutChannel;
use crate::io::exr_channels::{channels_like, lossy_for};

/// How an EXR output is encoded where it does not follow its input.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExrOutput {
    /// The compression; `None`: the input's (ZIP when the input is not an EXR, or its
    /// compression is one the exr crate cannot write).
    pub compression: Option<Compression>,
    /// Every channel as 16-bit half; off: each channel as the input stored it (32-bit float
    /// when the input is not an EXR).
    pub half: bool,
    /// The `chromaticities` of an output not made like an EXR: a photo's primaries and white,
    /// from its ICC profile (`io::image::chromaticities`); set per frame.
    pub chromaticities: Option<exr::meta::attribute::Chromaticities>,
}

/// The compression when neither the settings nor the input say one: ZIP over 16 lines, what
/// compositors write by default.
pub const DEFAULT_COMPRESSION: Compression = Compression::ZIP16;

/// One part of the output: the input part it is made like (`None`: a new file's defaults),
/// its data window (in the file's coordinates) and its channels, each of the window's size.
pub struct OutPart<'a> {
    pub input: Option<&'a Header>,
    /// The part's name where it is not the input part's.
    pub name: Option<String>,
    /// The name of the part its channels of no view layer go to where it is split by view
    /// layer (a multi-part output from a part of no name), when not the usual `rgba`.
    pub bare: Option<&'static str>,
    pub data: Window,
    pub channels: Vec<OutChannel>,
}

/// A part as it is written: made like `input`, at `data`, with its channels; `view`: the
/// view it says, in a multi-part output of views (see `write_like`).
struct Written<'a> {
    attributes: LayerAttributes,
    encoding: Encoding,
    input: Option<&'a Header>,
    data: Window,
    channels: Vec<OutChannel>,
    view: Option<String>,
}

/// Whether the output holds one view of a multi-view input, or all of them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Views {
    /// One view, or a file of no views: a plain file, without the input's `multiView` list
    /// or parts' `view` attributes (they would name views it does not hold).
    One,
    /// Every view: the input's view attributes are kept.
    Every,
}

/// Writes `parts` as one EXR over the display window `display`, each part made like its
/// input part (see the module doc), then puts the attributes in name order. `record` is
/// `shutter/settings`' text.
///
/// Under DWAA or DWAB, which compress every channel whose name ends in R, G, B or Y as
/// colour (`velocity.Y`, `N.R`), a part's data channels go to a part of their own, with ZIP:
/// data is never written lossily, and a layer's channels stay together. That part is named
/// `data` beside the main part (see [`data_part_name`]); a part that holds data alone stays
/// itself, under its own name, with ZIP. Returns what DWA capped, as
/// [`crate::io::exr_zip::write`] does.
pub fn write_like(
    writer: &mut BufWriter<impl Read + Write + Seek>,
    display: Window,
    parts: Vec<OutPart>,
    output: &ExrOutput,
    record: &str,
    views: Views,
) -> Result<Option<(usize, f32)>, String> {
    let display = IntegerBounds::new((display.x, display.y), (display.width, display.height));
    let image_attributes = match parts.first().and_then(|p| p.input) {
        Some(h) => {
            let mut shared = ImageAttributes {
                display_window: display,
                ..h.shared_attributes.clone()
            };
            shared.other.retain(|name, _| !is_layout(name));
            // The time code among the rest, written as it was read (see `as_read`).
            if let Some(time) = shared.time_code.take() {
                shared
                    .other
                    .insert(Text::from("timeCode"), AttributeValue::TimeCode(time));
            }
            for value in shared.other.values_mut() {
                as_read(value);
            }
            shared
        }
        None => ImageAttributes {
            chromaticities: output.chromaticities,
            ..ImageAttributes::new(display)
        },
    };
    // Each part, and the lossless part its data needs under a lossy compression.
    let goes_apart = |part: &OutPart, c: &OutChannel| {
        let compression = encoding_like(part.input, output).compression;
        lossy_for(compression, c, part.input, output.half)
    };
    // Whether the file will have several parts: then a part that has no name of its own and
    // holds channels of several view layers is split by layer, so each part can be named by
    // what its channels begin with (see `common_prefix`).
    let multi_part = parts.len() > 1
        || parts.iter().any(|p| {
            p.channels.iter().any(|c| goes_apart(p, c))
                && p.channels.iter().any(|c| !goes_apart(p, c))
        });
    // Several parts of every view of a file whose channel names say their views are written
    // in OpenEXR's multi-part scheme (MultiViewOpenEXR.html), not as a `multiView` on every
    // part, which the document says not to write: each part holds one view's channels,
    // named without the view, and says it in its `view` attribute; the channels of no view
    // go to parts of no view, none of them first. Each part is split by view, each view's
    // channels named as a file of that view alone names them (their data in a lossless
    // part of the view's), its parts' names followed by `-view`, as Blender names a view's
    // part (`io::view::part_name_without_view`).
    let by_view = multi_part && (parts.iter()).any(|p| p.channels.iter().any(|c| c.view.is_some()));
    let units: Vec<(OutPart, Option<String>)> = if by_view {
        parts.into_iter().flat_map(split_by_view).collect()
    } else {
        parts.into_iter().map(|p| (p, None)).collect()
    };
    // The parts' own names, which a data part's name may not take (in its view).
    let mut taken: Vec<(Option<String>, String)> = units
        .iter()
        .filter_map(|(p, view)| {
            let name = (p.name.clone())
                .or_else(|| Some(name_of(p.input?.own_attributes.layer_name.as_ref()?)))?;
            Some((view.clone(), name))
        })
        .collect();
    let in_view = |taken: &[(Option<String>, String)], view: &Option<String>| -> Vec<String> {
        (taken.iter().filter(|(v, _)| v == view))
            .map(|(_, name)| name.clone())
            .collect()
    };
    let mut layers = Vec::new();
    for (part, view) in units {
        let encoding = encoding_like(part.input, output);
        let (kept, apart): (Vec<_>, Vec<_>) = part
            .channels
            .into_iter()
            .partition(|c| !lossy_for(encoding.compression, c, part.input, output.half));
        let mut attributes = attributes_like(part.input, part.data, record, views);
        if let Some(name) = &part.name {
            attributes.layer_name = Some(name_text(name));
        }
        let data_encoding = Encoding {
            compression: DEFAULT_COMPRESSION,
            ..encoding
        };
        if kept.is_empty() {
            // Data alone: the part itself, lossless (named, as every part of a view is).
            if by_view && attributes.layer_name.is_none() {
                let name = data_part_name(None, &in_view(&taken, &view));
                taken.push((view.clone(), name.clone()));
                attributes.layer_name = Some(name_text(&name));
            }
            if !apart.is_empty() {
                layers.push(Written {
                    attributes,
                    encoding: data_encoding,
                    input: part.input,
                    data: part.data,
                    channels: apart,
                    view,
                });
            }
            continue;
        }
        // The kept channels' parts are named first (a colour group `FG` before a data part of
        // the same name), each by what its channels begin with where the file will have
        // several parts.
        if multi_part && attributes.layer_name.is_none() {
            for (layer, group) in by_view_layer(kept) {
                let usual = match part.bare {
                    Some(bare) if layer.is_none() => bare,
                    _ if !layers.iter().any(|l| l.view == view) => "rgba",
                    _ => "part",
                };
                let prefix = common_prefix(&group);
                let name = fresh(prefix.as_deref().unwrap_or(usual), &in_view(&taken, &view));
                taken.push((view.clone(), name.clone()));
                let mut attributes = attributes.clone();
                attributes.layer_name = Some(name_text(&name));
                layers.push(Written {
                    attributes,
                    encoding,
                    input: part.input,
                    data: part.data,
                    channels: group,
                    view: view.clone(),
                });
            }
        } else {
            layers.push(Written {
                attributes: attributes.clone(),
                encoding,
                input: part.input,
                data: part.data,
                channels: kept,
                view: view.clone(),
            });
        }
        for (layer, group) in by_view_layer(apart) {
            let mut data_attributes = attributes.clone();
            let prefix = layer.and_then(|_| common_prefix(&group));
            let names = in_view(&taken, &view);
            let name = match prefix {
                Some(prefix) if !names.contains(&prefix) => prefix,
                _ => data_part_name(attributes.layer_name.as_ref(), &names),
            };
            taken.push((view.clone(), name.clone()));
            data_attributes.layer_name = Some(name_text(&name));
            layers.push(Written {
                attributes: data_attributes,
                encoding: data_encoding,
                input: part.input,
                data: part.data,
                channels: group,
                view: view.clone(),
            });
        }
    }
    if by_view {
        say_views(&mut layers);
    }
    let several = layers.len() > 1;
    // A part in random order (RANDOM_Y) is written in increasing order, and then declared
    // random: the exr crate writes a random-order part's blocks as its threads finish them,
    // which would make the same frame give other bytes on each run.
    let random_y: Vec<bool> = layers
        .iter()
        .map(|l| l.encoding.line_order == LineOrder::Unspecified)
        .collect();
    let layers: Vec<_> = layers
        .into_iter()
        .enumerate()
        .map(|(i, layer)| {
            let Written {
                mut attributes,
                mut encoding,
                input,
                data,
                channels,
                ..
            } = layer;
            if random_y[i] {
                encoding.line_order = LineOrder::Increasing;
            }
            // Every part of a multi-part file has a name (given above to every part that
            // had none, but a file's one part of data alone under DWA).
            if several && attributes.layer_name.is_none() {
                attributes.layer_name = Some(Text::from(if i == 0 { "rgba" } else { "part" }));
            }
            Layer::new(
                (data.width, data.height),
                attributes,
                encoding,
                AnyChannels::sort(channels_like(channels, input, output.half).into()),
            )
        })
        .collect();
    let image = Image::from_layers(image_attributes, layers);
    // An attribute under a standard name but of another type than the standard's (`isoSpeed`
    // an int, `owner` an int, `multiView` a string), as other writers leave them, is read as
    // a custom attribute; the exr crate's checks refuse to write a custom attribute under a
    // reserved name. OpenEXR reads such a file (the attribute keeps its own type), and
    // `oiiotool` writes it back as it was: so does shutter, with the checks left out for
    // such a frame alone.
    let reserved = |other: &std::collections::HashMap<Text, AttributeValue>| {
        other
            .keys()
            .any(|name| standard_names::ALL.contains(&name.bytes()))
    };
    let keeps_odd_types = reserved(&image.attributes.other)
        || image
            .layer_data
            .iter()
            .any(|layer| reserved(&layer.attributes.other));
    let capped = crate::io::exr_zip::write(&image, &mut *writer, !keeps_odd_types)
        .map_err(|e| e.to_string())?;
    writer.flush().map_err(|e| e.to_string())?;
    crate::io::exr_order::sort_attributes(writer.get_mut(), &random_y)
        .map_err(|e| format!("sorting its attributes: {e}"))?;
    Ok(capped)
}

/// The name of the part that takes the data channels of the part named `part` under DWA,
/// none of `taken`: `data` beside the main part (unnamed, or OpenEXR's and Nuke's `rgba`, or
/// `beauty`), as a pipeline names a part of data channels (OpenEXR's part helper and Nuke
/// name a part by what it holds, and a channel keeps its full name in any part); beside
/// another part `<part>.data`, so each part's data stays told apart (two views' parts, say);
/// a number after it where even that name is taken. Readers find a channel by its own
/// name, whatever its part (`shutter diff` and the passes' lookup among them).
fn data_part_name(part: Option<&Text>, taken: &[String]) -> String {
    let part = part.map(name_of);
    let main = part
        .as_deref()
        .is_none_or(|n| crate::io::file::FileInfo::MAIN_PARTS.contains(&n));
    let fallback = format!("{}.data", part.as_deref().unwrap_or("rgba"));
    if main && !taken.iter().any(|n| n == "data") {
        return "data".to_string();
    }
    fresh(&fallback, taken)
}

/// Channels in groups, one for those of no view layer (first), then one a view layer in
/// the order of its first channel: Blender names a channel `layer.pass.channel`, so a name
/// of three parts or more is of the layer its first part names.
fn by_view_layer(channels: Vec<OutChannel>) -> Vec<(Option<String>, Vec<OutChannel>)> {
    let mut groups: Vec<(Option<String>, Vec<OutChannel>)> = Vec::new();
    for channel in channels {
        let parts: Vec<&str> = channel.name.split('.').collect();
        let layer = (parts.len() >= 3).then(|| parts[0].to_string());
        match groups.iter_mut().find(|(l, _)| *l == layer) {
            Some((_, group)) => group.push(channel),
            None if layer.is_none() => groups.insert(0, (None, vec![channel])),
            None => groups.push((layer, vec![channel])),
        }
    }
    groups
}

/// A part's channels in groups by view (in the order their channels come, the channels of no
/// view last), each group a part of its own, its channels named as in their view (`right.R`
/// as `R`, `velocity.right.X` as `velocity.X`).
fn split_by_view(part: OutPart) -> Vec<(OutPart, Option<String>)> {
    let mut groups: Vec<(Option<String>, Vec<OutChannel>)> = Vec::new();
    for mut channel in part.channels {
        let view = channel.view.take().map(|(view, in_view)| {
            if in_view != channel.name {
                // Its pixel type and pLinear flag are still looked up under the stored name.
                let stored = std::mem::replace(&mut channel.name, in_view);
                channel.source.get_or_insert(stored);
            }
            view
        });
        match groups.iter_mut().find(|(v, _)| *v == view) {
            Some((_, group)) => group.push(channel),
            None => groups.push((view, vec![channel])),
        }
    }
    groups.sort_by_key(|(view, _)| view.is_none());
    (groups.into_iter())
        .map(|(view, channels)| {
            let part = OutPart {
                input: part.input,
                name: part.name.clone(),
                bare: part.bare,
                data: part.data,
                channels,
            };
            (part, view)
        })
        .collect()
}

/// The parts of a multi-part output of views (see `write_like`) made to say their views:
/// `view` on each part of a view, `multiView` on none, each name followed by `-view` (and
/// unique), and the first part of a view first (the default view's: its channels come
/// first; a part of no view may not be first).
fn say_views(layers: &mut Vec<Written>) {
    let mut names: Vec<String> = Vec::new();
    for Written {
        attributes, view, ..
    } in layers.iter_mut()
    {
        attributes.multi_view_names = None;
        attributes.view_name = view.as_deref().map(name_text);
        let name = (attributes.layer_name.as_ref()).map_or_else(|| "part".to_string(), name_of);
        let name = match view {
            Some(view) => format!("{name}-{view}"),
            None => name,
        };
        let name = fresh(&name, &names);
        attributes.layer_name = Some(name_text(&name));
        names.push(name);
    }
    if let Some(first) = layers.iter().position(|l| l.view.is_some()) {
        let layer = layers.remove(first);
        layers.insert(0, layer);
    }
}

/// `name`, or where a part has it already, the first of `name2`, `name3`, … none has.
pub(crate) fn fresh(name: &str, taken: &[String]) -> String {
    std::iter::once(name.to_string())
        .chain((2..).map(|k| format!("{name}{k}")))
        .find(|n| !taken.contains(n))
        .expect("an endless list of names holds one not taken")
}

/// The longest run of whole leading name parts every channel's name begins with, before a
/// part of its own (`FG.Combined` of `FG.Combined.R` and `FG.Combined.A`; `FG` of those and
/// `FG.Depth.Z`); `None` where they share none.
fn common_prefix(channels: &[OutChannel]) -> Option<String> {
    let mut names = channels.iter().map(|c| c.name.as_str());
    let first = names.next()?;
    let mut prefix: Vec<&str> = first.split('.').collect();
    prefix.pop();
    for name in names {
        let parts: Vec<&str> = name.split('.').collect();
        let shared = (prefix.iter().zip(&parts[..parts.len() - 1]))
            .take_while(|(a, b)| a == b)
            .count();
        prefix.truncate(shared);
    }
    (!prefix.is_empty()).then(|| prefix.join("."))
}

/// The attributes that say how a part is laid out in its file, which the writer gives the
/// output's own values: OpenEXR's, and the DWA level that goes with the compression.
const LAYOUT: [&str; 12] = [
    "channels",
    "chunkCount",
    "compression",
    "dataWindow",
    "displayWindow",
    "dwaCompressionLevel",
    "lineOrder",
    "maxSamplesPerPixel",
    "name",
    "tiles",
    "type",
    "version",
];

/// Whether a custom attribute of the input names the layout, and so is not carried: under
/// a layout name but of another type than the standard's (which the exr crate reads as a
/// custom attribute and would write beside its own: OpenEXR 3.1 then refuses the file,
/// "Unexpected type for image attribute chunkCount"), or under OpenImageIO's name for it
/// (`openexr:chunkCount`, `openexr:lineOrder`, `openexr:roundingmode`: oiiotool 2.4 writes
/// the count of the file it read, stale in the file it writes, and `iinfo -v` reports it as
/// the part's).
fn is_layout(name: &Text) -> bool {
    let name = String::from_utf8_lossy(name.bytes());
    match name.strip_prefix("openexr:") {
        Some(oiio) => LAYOUT
            .iter()
            .chain(&["roundingmode", "levelmode"])
            .any(|l| l.eq_ignore_ascii_case(oiio)),
        None => LAYOUT.contains(&&*name),
    }
}

/// The input part's attributes, minus the preview (and the views where one is written), at
/// the part's data window, with shutter's record.
fn attributes_like(
    input: Option<&Header>,
    data: Window,
    record: &str,
    views: Views,
) -> LayerAttributes {
    let mut attributes = input.map_or_else(LayerAttributes::default, |h| {
        let mut kept = h.own_attributes.clone();
        kept.preview = None;
        kept.other.retain(|name, _| !is_layout(name));
        if views == Views::One {
            // One view is written (the one read): a multiView list would name views the
            // file does not hold, and make its channels the default view's.
            kept.multi_view_names = None;
            // Nor a part's `view`: the output is a file of one view, whose parts are plain
            // (a part of no view may come first in it, which a multi-view file may not
            // have). A part Blender named for its view (`layer.pass-view`) is named as a
            // file of one view names it (`layer.pass`): its channels (`layer.pass.X`) begin
            // with that, and Blender reads the channels of a part whose name they do not
            // begin with as of a view layer named by the whole part name.
            if let (Some(view), Some(name)) = (kept.view_name.take(), &kept.layer_name) {
                let view = name_of(&view);
                let plain = crate::io::view::part_name_without_view(&name_of(name), Some(&view));
                kept.layer_name = Some(name_text(&plain));
            }
        }
        kept
    });
    attributes.layer_position = Vec2(data.x, data.y);
    if let Some(key) = attributes.film_key_code.take() {
        attributes
            .other
            .insert(Text::from("keyCode"), AttributeValue::KeyCode(key));
    }
    for value in attributes.other.values_mut() {
        as_read(value);
    }
    // As UTF-8, as OpenEXR 3 reads its strings (it was Latin-1, `--layers Vordergrund_ü`
    // written as byte 0xFC: OpenEXR's Python module then refused to open the file).
    for (name, value) in [
        ("shutter/version", env!("CARGO_PKG_VERSION")),
        ("shutter/settings", record),
    ] {
        attributes
            .other
            .insert(Text::from(name), AttributeValue::Text(name_text(value)));
    }
    attributes
}

/// An attribute value the exr crate reads but would write otherwise, made the bytes it was
/// read from (a custom value of the same type name, written as it is): a key code (the crate
/// writes six of its seven numbers: every reader then refused the file), a time code its
/// writer refuses (frame 38 at 48 or 60 fps; OpenEXR writes it), an empty string vector.
fn as_read(value: &mut AttributeValue) {
    let custom = |kind: &str, bytes: Vec<u8>| AttributeValue::Custom {
        kind: Text::from(kind),
        bytes: bytes.into(),
    };
    let le = |values: &[u32]| values.iter().flat_map(|v| v.to_le_bytes()).collect();
    match value {
        AttributeValue::KeyCode(k) => {
            let numbers = [
                k.film_manufacturer_code,
                k.film_type,
                k.film_roll_prefix,
                k.count,
                k.perforation_offset,
                k.perforations_per_frame,
                k.perforations_per_count,
            ];
            *value = custom("keycode", le(&numbers.map(|n| n as u32)));
        }
        AttributeValue::TimeCode(t) => {
            // SMPTE 12M's TV60 packing (OpenEXR's ImfTimeCode), each field in binary-coded
            // decimal within its bits, as read.
            let bcd = |n: u8, bits: u32| {
                let v = u32::from(n % 10) | (u32::from(n / 10 % 10) << 4);
                v & ((1 << bits) - 1)
            };
            let flag = |b: bool, bit: u32| u32::from(b) << bit;
            let time = bcd(t.frame, 6)
                | flag(t.drop_frame, 6)
                | flag(t.color_frame, 7)
                | bcd(t.seconds, 7) << 8
                | flag(t.field_phase, 15)
                | bcd(t.minutes, 7) << 16
                | flag(t.binary_group_flags[0], 23)
                | bcd(t.hours, 6) << 24
                | flag(t.binary_group_flags[1], 30)
                | flag(t.binary_group_flags[2], 31);
            let user = t
                .binary_groups
                .iter()
                .enumerate()
                .fold(0u32, |u, (i, &g)| u | (u32::from(g) & 15) << (4 * i));
            *value = custom("timecode", le(&[time, user]));
        }
        AttributeValue::TextVector(texts) if texts.is_empty() => {
            *value = custom("stringvector", Vec::new());
        }
        _ => {}
    }
}

/// The input's compression, blocks and line order, where the exr crate can write them and
/// the settings do not say otherwise.
fn encoding_like(input: Option<&Header>, output: &ExrOutput) -> Encoding {
    let writable = |c: Compression| {
        crate::io::exr::WRITABLE_COMPRESSIONS.contains(&crate::io::exr::compression_name(c))
    };
    let compression = output
        .compression
        .or(input.map(|h| h.compression).filter(|&c| writable(c)))
        .unwrap_or(DEFAULT_COMPRESSION);
    let blocks = match input.map(|h| h.blocks) {
        Some(BlockDescription::Tiles(tiles)) => Blocks::Tiles(tiles.tile_size),
        _ => Blocks::ScanLines,
    };
    // RANDOM_Y is valid for tiles alone (a scan-line file declaring it reads as increasing).
    let line_order = match (input.map(|h| h.line_order), blocks) {
        (Some(LineOrder::Decreasing), _) => LineOrder::Decreasing,
        (Some(LineOrder::Unspecified), Blocks::Tiles(_)) => LineOrder::Unspecified,
        _ => LineOrder::Increasing,
    };
    Encoding {
        compression,
        blocks,
        line_order,
    }
}
