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
//! run to run; [`sort_attributes`] then puts each header's attributes in name order (as
//! OpenEXR's own library writes them), in place, so the same frame gives the same bytes.

use std::io::{BufWriter, Read, Seek, SeekFrom, Write};

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
/// itself, under its own name, with ZIP.
pub fn write_like(
    writer: &mut BufWriter<impl Read + Write + Seek>,
    display: Window,
    parts: Vec<OutPart>,
    output: &ExrOutput,
    record: &str,
    views: Views,
) -> Result<(), String> {
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
    // The parts' own names, which a data part's name may not take.
    let mut taken: Vec<String> = parts
        .iter()
        .filter_map(|p| {
            (p.name.clone()).or_else(|| Some(name_of(p.input?.own_attributes.layer_name.as_ref()?)))
        })
        .collect();
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
    let mut layers = Vec::new();
    for part in parts {
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
            // Data alone: the part itself, lossless.
            if !apart.is_empty() {
                layers.push((attributes, data_encoding, part.input, part.data, apart));
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
                    _ if layers.is_empty() => "rgba",
                    _ => "part",
                };
                let name = fresh(common_prefix(&group).as_deref().unwrap_or(usual), &taken);
                taken.push(name.clone());
                let mut attributes = attributes.clone();
                attributes.layer_name = Some(name_text(&name));
                layers.push((attributes, encoding, part.input, part.data, group));
            }
        } else {
            layers.push((attributes.clone(), encoding, part.input, part.data, kept));
        }
        for (layer, group) in by_view_layer(apart) {
            let mut data_attributes = attributes.clone();
            let prefix = layer.and_then(|_| common_prefix(&group));
            let name = match prefix {
                Some(prefix) if !taken.contains(&prefix) => prefix,
                _ => data_part_name(attributes.layer_name.as_ref(), &taken),
            };
            taken.push(name.clone());
            data_attributes.layer_name = Some(name_text(&name));
            layers.push((data_attributes, data_encoding, part.input, part.data, group));
        }
    }
    let several = layers.len() > 1;
    // A part in random order (RANDOM_Y) is written in increasing order, and then declared
    // random: the exr crate writes a random-order part's blocks as its threads finish them,
    // which would make the same frame give other bytes on each run.
    let random_y: Vec<bool> = layers
        .iter()
        .map(|l| l.1.line_order == LineOrder::Unspecified)
        .collect();
    let layers: Vec<_> = layers
        .into_iter()
        .enumerate()
        .map(
            |(i, (mut attributes, mut encoding, input, data, channels))| {
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
            },
        )
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
    crate::io::exr_zip::write(&image, &mut *writer, !keeps_odd_types).map_err(|e| e.to_string())?;
    writer.flush().map_err(|e| e.to_string())?;
    sort_attributes(writer.get_mut(), &random_y).map_err(|e| format!("sorting its attributes: {e}"))
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

/// Puts the attributes of every header of the EXR in `file` in name order, in place, and
/// declares RANDOM_Y the line order of each part `random_y` marks (its blocks are in
/// increasing order, which a random order allows). Every attribute is a self-contained
/// record (name, type, size, value), so reordering them, or changing the one byte of a
/// `lineOrder`, leaves each header, and so the offset tables after them, the same length.
pub fn sort_attributes(
    file: &mut (impl Read + Write + Seek),
    random_y: &[bool],
) -> std::io::Result<()> {
    /// OpenEXR's `RANDOM_Y` in a `lineOrder` attribute.
    const RANDOM_Y: u8 = 2;
    const MULTIPART: u32 = 0x1000;
    let invalid = |what: &str| std::io::Error::new(std::io::ErrorKind::InvalidData, what);
    file.seek(SeekFrom::Start(0))?;
    let mut bytes = Vec::new();
    // Headers are small; read them in growing steps until the last one ends.
    let mut step = 1 << 16;
    loop {
        let have = bytes.len();
        Read::by_ref(file).take(step).read_to_end(&mut bytes)?;
        let complete = bytes.len() < have + step as usize;
        if let Some(end) = headers_end(&bytes)? {
            bytes.truncate(end);
            break;
        }
        if complete {
            return Err(invalid("the headers do not end"));
        }
        step *= 2;
    }
    let version = u32::from_le_bytes(bytes[4..8].try_into().expect("eight bytes"));
    let mut at = 8;
    let mut sorted = bytes[..8].to_vec();
    for part in 0.. {
        let records = header_records(&bytes, at)?;
        if random_y.get(part).copied().unwrap_or(false) {
            let line_order = records
                .iter()
                .find(|r| &bytes[r.start..r.name_end] == b"lineOrder")
                .ok_or_else(|| invalid("a part has no lineOrder"))?;
            // The value is the record's last byte (size 1).
            bytes[line_order.end - 1] = RANDOM_Y;
        }
        let end = records.last().map_or(at, |r| r.end);
        let mut order: Vec<_> = records.iter().collect();
        order.sort_by_key(|r| &bytes[r.start..r.name_end]);
        for r in order {
            sorted.extend_from_slice(&bytes[r.start..r.end]);
        }
        sorted.push(0);
        at = end + 1;
        if version & MULTIPART == 0 || bytes.get(at) == Some(&0) {
            break;
        }
    }
    sorted.extend_from_slice(&bytes[at..]);
    debug_assert_eq!(sorted.len(), bytes.len());
    file.seek(SeekFrom::Start(0))?;
    file.write_all(&sorted)?;
    file.seek(SeekFrom::End(0))?;
    Ok(())
}

/// One attribute's bytes: `start..end`, its name `start..name_end`.
struct Record {
    start: usize,
    name_end: usize,
    end: usize,
}

/// The attributes of the header that starts at `at` (up to its terminating zero byte).
fn header_records(bytes: &[u8], mut at: usize) -> std::io::Result<Vec<Record>> {
    let short = || std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "a header is cut off");
    let mut records = Vec::new();
    while *bytes.get(at).ok_or_else(short)? != 0 {
        let start = at;
        let zero = |from: usize| {
            bytes[from.min(bytes.len())..]
                .iter()
                .position(|&b| b == 0)
                .map(|p| from + p)
                .ok_or_else(short)
        };
        let name_end = zero(start)?;
        let type_end = zero(name_end + 1)?;
        let size_at = type_end + 1;
        let size = bytes.get(size_at..size_at + 4).ok_or_else(short)?;
        let size = i32::from_le_bytes(size.try_into().expect("four bytes"));
        let size = usize::try_from(size).map_err(|_| short())?;
        let end = size_at + 4 + size;
        if end > bytes.len() {
            return Err(short());
        }
        records.push(Record {
            start,
            name_end,
            end,
        });
        at = end;
    }
    Ok(records)
}

/// Where the headers of the file whose first bytes are `bytes` end (after the last header's
/// terminator, and the empty header that ends a multi-part file's list), or `None` when
/// `bytes` stops before that.
fn headers_end(bytes: &[u8]) -> std::io::Result<Option<usize>> {
    if bytes.len() < 8 {
        return Ok(None);
    }
    let multipart = u32::from_le_bytes(bytes[4..8].try_into().expect("eight bytes")) & 0x1000 != 0;
    let mut at = 8;
    loop {
        let records = match header_records(bytes, at) {
            Ok(records) => records,
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
            Err(e) => return Err(e),
        };
        at = records.last().map_or(at, |r| r.end) + 1;
        if !multipart {
            return Ok(Some(at));
        }
        match bytes.get(at) {
            None => return Ok(None),
            Some(0) => return Ok(Some(at + 1)),
            Some(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::meta::MetaData;
    use exr::prelude::WritableImage;
    use std::fs::File;

    /// A two-part file whose parts carry custom attributes, written by the exr crate.
    fn two_parts(path: &std::path::Path) {
        use exr::image::{AnyChannel, AnyChannels, FlatSamples, Image, Layer};
        let layer = |name: &str, attributes: &[(&str, i32)]| {
            let mut own = LayerAttributes::named(name);
            for &(key, value) in attributes {
                own.other
                    .insert(Text::from(key), AttributeValue::I32(value));
            }
            Layer::new(
                (3, 2),
                own,
                Encoding::FAST_LOSSLESS,
                AnyChannels::sort(
                    vec![AnyChannel::new(
                        Text::from("Y"),
                        FlatSamples::F32(vec![0.5; 6]),
                    )]
                    .into(),
                ),
            )
        };
        let image = Image::from_layers(
            ImageAttributes::new(IntegerBounds::from_dimensions((3, 2))),
            vec![
                layer("beauty", &[("zeta", 1), ("alpha", 2), ("mid", 3)]),
                layer("data", &[("b", 4), ("a", 5)]),
            ],
        );
        image.write().to_file(path).unwrap();
    }

    /// The attribute names of each header, in the order the file holds them.
    fn names_in_order(bytes: &[u8]) -> Vec<Vec<String>> {
        let mut at = 8;
        let mut headers = Vec::new();
        loop {
            let records = header_records(bytes, at).unwrap();
            headers.push(
                records
                    .iter()
                    .map(|r| String::from_utf8_lossy(&bytes[r.start..r.name_end]).into_owned())
                    .collect(),
            );
            at = records.last().unwrap().end + 1;
            if bytes[at] == 0 {
                return headers;
            }
        }
    }

    #[test]
    fn a_multi_part_files_attributes_are_put_in_name_order_and_read_the_same() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.exr");
        two_parts(&path);
        let before = MetaData::read_from_file(&path, false).unwrap();
        let length = std::fs::metadata(&path).unwrap().len();
        let mut file = File::options().read(true).write(true).open(&path).unwrap();
        sort_attributes(&mut file, &[]).unwrap();
        drop(file);
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len() as u64, length);
        let headers = names_in_order(&bytes);
        assert_eq!(headers.len(), 2);
        for names in &headers {
            let mut sorted = names.clone();
            sorted.sort();
            assert_eq!(names, &sorted);
        }
        assert!(headers[0].contains(&"zeta".to_string()) && headers[1].contains(&"a".to_string()));
        // The same headers, and the pixels still where the offset tables say.
        let after = MetaData::read_from_file(&path, false).unwrap();
        assert_eq!(before.headers, after.headers);
        let image = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
        assert_eq!(image.layer_data.len(), 2);
    }
}
