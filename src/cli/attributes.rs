//! `shutter info`'s header attributes (issue 31): every attribute an EXR part stores, as
//! `iinfo -v` lists them, with its type and value in text and JSON; for an 8/16-bit photo,
//! the metadata blocks it holds (ICC profile, EXIF, XMP, IPTC) and their sizes.

use exr::meta::attribute::AttributeValue;
use serde_json::{json, Value};

/// One attribute: its name, its type as the file names it, its value in text and in JSON.
pub struct Shown {
    pub name: String,
    pub kind: &'static str,
    pub text: String,
    pub json: Value,
}

fn floats(values: &[f32]) -> String {
    values
        .iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(", ")
}

/// An EXR text (bytes, which the exr crate shows one char a byte) as the UTF-8 that writers
/// put there (OpenEXR's strings are UTF-8 by convention: `owner` "Zoë" came out "ZoÃ«");
/// bytes that are not UTF-8 shown a char a byte, as before.
pub fn text_of(t: &exr::meta::attribute::Text) -> String {
    String::from_utf8(t.bytes().to_vec()).unwrap_or_else(|_| t.to_string())
}

/// A name as shutter holds it, shown in text: as it is, since [`crate::io::channels::name_of`]
/// reads names as UTF-8 already (`lumière.R`, not `lumiÃ¨re.R`; a byte that is not UTF-8
/// shows as its escape char), but for its control characters, escaped as values are
/// (`Z\u{1b}[31m\n`: a hostile name neither colours the terminal nor breaks the line).
/// JSON carries the name itself: its strings escape what they must.
pub fn shown_name(name: &str) -> String {
    crate::error::printable(name)
}

/// An attribute's type name, its value in text and in JSON.
fn value(value: &AttributeValue) -> (&'static str, String, Value) {
    use AttributeValue as A;
    match value {
        // One line in text: a newline shows as \n.
        A::Text(t) => ("string", format!("{:?}", text_of(t)), json!(text_of(t))),
        A::TextVector(list) => {
            let texts: Vec<String> = list.iter().map(text_of).collect();
            ("stringvector", format!("{texts:?}"), json!(texts))
        }
        A::F32(v) => ("float", v.to_string(), json!(v)),
        A::F64(v) => ("double", v.to_string(), json!(v)),
        A::I32(v) => ("int", v.to_string(), json!(v)),
        A::Rational((n, d)) => ("rational", format!("{n}/{d}"), json!([n, d])),
        A::IntVec2(v) => ("v2i", format!("{}, {}", v.0, v.1), json!([v.0, v.1])),
        A::FloatVec2(v) => ("v2f", format!("{}, {}", v.0, v.1), json!([v.0, v.1])),
        A::IntVec3((x, y, z)) => ("v3i", format!("{x}, {y}, {z}"), json!([x, y, z])),
        A::FloatVec3((x, y, z)) => ("v3f", format!("{x}, {y}, {z}"), json!([x, y, z])),
        A::IntegerBounds(b) => {
            let (x0, y0) = (b.position.0, b.position.1);
            let (x1, y1) = (x0 + b.size.0 as i32 - 1, y0 + b.size.1 as i32 - 1);
            (
                "box2i",
                format!("({x0}, {y0}) - ({x1}, {y1})"),
                json!([x0, y0, x1, y1]),
            )
        }
        A::FloatRect(r) => (
            "box2f",
            format!("({}, {}) - ({}, {})", r.min.0, r.min.1, r.max.0, r.max.1),
            json!([r.min.0, r.min.1, r.max.0, r.max.1]),
        ),
        A::Chromaticities(c) => {
            let v = [
                c.red.0, c.red.1, c.green.0, c.green.1, c.blue.0, c.blue.1, c.white.0, c.white.1,
            ];
            ("chromaticities", floats(&v), json!(v))
        }
        A::Matrix3x3(m) => ("m33f", floats(m), json!(m.to_vec())),
        A::Matrix4x4(m) => ("m44f", floats(m), json!(m.to_vec())),
        A::Compression(c) => {
            let name = crate::io::exr::compression_name(*c);
            ("compression", name.to_string(), json!(name))
        }
        A::LineOrder(o) => {
            // OpenEXR's INCREASING_Y, DECREASING_Y and RANDOM_Y (which the exr crate calls
            // `Unspecified`: a tiled part whose tiles come in any order).
            use exr::meta::attribute::LineOrder as L;
            let name = match o {
                L::Increasing => "increasing",
                L::Decreasing => "decreasing",
                L::Unspecified => "random",
            };
            ("lineOrder", name.to_string(), json!(name))
        }
        A::TimeCode(t) => {
            let sep = if t.drop_frame { ';' } else { ':' };
            let text = format!(
                "{:02}:{:02}:{:02}{sep}{:02}",
                t.hours, t.minutes, t.seconds, t.frame
            );
            ("timecode", text.clone(), json!(text))
        }
        A::KeyCode(k) => {
            let text = format!(
                "manufacturer {} type {} prefix {} count {} perf offset {} perfs/frame {} perfs/count {}",
                k.film_manufacturer_code,
                k.film_type,
                k.film_roll_prefix,
                k.count,
                k.perforation_offset,
                k.perforations_per_frame,
                k.perforations_per_count
            );
            ("keycode", text.clone(), json!(text))
        }
        A::Preview(p) => {
            let text = format!("{}x{} preview", p.size.0, p.size.1);
            (
                "preview",
                text,
                json!({"width": p.size.0, "height": p.size.1}),
            )
        }
        A::TileDescription(t) => {
            let text = format!(
                "{}x{} tiles, {:?}, round {:?}",
                t.tile_size.0, t.tile_size.1, t.level_mode, t.rounding_mode
            );
            ("tiledesc", text.clone(), json!(text))
        }
        A::EnvironmentMap(e) => {
            let text = format!("{e:?}").to_lowercase();
            ("envmap", text.clone(), json!(text))
        }
        A::BlockType(b) => {
            use exr::meta::attribute::BlockType as B;
            // As the file stores it (OpenEXR's names).
            let text = match b {
                B::ScanLine => "scanlineimage",
                B::Tile => "tiledimage",
                B::DeepScanLine => "deepscanline",
                B::DeepTile => "deeptile",
            };
            ("string", text.to_string(), json!(text))
        }
        A::ChannelList(list) => {
            let names: Vec<String> = (list.list.iter())
                .map(|c| crate::io::channels::name_of(&c.name))
                .collect();
            ("chlist", names.join(", "), json!(names))
        }
        A::Bytes { type_hint, bytes } => {
            let text = format!("{} bytes ({type_hint})", bytes.len());
            ("bytes", text.clone(), json!(text))
        }
        A::Custom { kind, bytes } => {
            let text = format!("{} bytes of type {kind}", bytes.len());
            ("custom", text.clone(), json!(text))
        }
    }
}

/// Every attribute of one EXR part but its channel list (which `info` lists with each
/// channel's class), sorted by name.
///
/// A part in a compression the exr crate does not know shows the compression it stores, not
/// the stand-in the crate was shown (`io::exr_unknown`).
pub fn of_header(header: &exr::meta::header::Header) -> Vec<Shown> {
    let stored = crate::io::exr_unknown::stored_compression(header);
    let mut shown: Vec<Shown> = header
        .all_named_attributes()
        .map(|(name, v)| (String::from_utf8_lossy(name).into_owned(), v))
        .filter(|(name, v)| {
            name != "channels" && !(stored.is_some() && matches!(v, AttributeValue::Compression(_)))
        })
        .map(|(name, v)| {
            let (kind, text, json) = match (stored, &v) {
                (Some(id), AttributeValue::Custom { .. }) if name == "compression" => {
                    let text = crate::io::exr_unknown::name_of_id(id)
                        .map_or_else(|| format!("{id} (unknown)"), String::from);
                    ("compression", text.clone(), json!(text))
                }
                _ => value(&v),
            };
            Shown {
                name,
                kind,
                text,
                json,
            }
        })
        .collect();
    shown.sort_by(|a, b| a.name.cmp(&b.name));
    shown
}

/// The metadata blocks of a photo, as [`Shown`] rows.
pub fn of_photo(photo: &crate::frame::Photo) -> Vec<Shown> {
    let mut shown = Vec::new();
    colour_rows(photo, &mut shown);
    let mut block = |name: &str, bytes: &Option<Vec<u8>>, extra: String| {
        if let Some(bytes) = bytes {
            let text = format!("{} bytes{extra}", bytes.len());
            shown.push(Shown {
                name: name.to_string(),
                kind: "block",
                text,
                json: json!({ "bytes": bytes.len() }),
            });
        }
    };
    block("icc_profile", &photo.icc, String::new());
    // The read turns the photo upright and records orientation 1 in what it keeps.
    block("exif", &photo.exif, String::new());
    block("xmp", &photo.xmp, String::new());
    block("iptc", &photo.iptc, String::new());
    shown
}

/// What a photo's reader found of its colour and density: which of its descriptions codes
/// the colour (`colour`: the cICP, the ICC profile, the sRGB chunk, gAMA and cHRM, or
/// nothing, sRGB's then), a PNG's gAMA, cHRM, sRGB and cICP as stored, and the resolution in
/// its unit, as the output writes them again.
fn colour_rows(photo: &crate::frame::Photo, shown: &mut Vec<Shown>) {
    use crate::io::image::ColourSource as S;
    let mut row = |name: &str, kind: &'static str, text: String, json: Value| {
        shown.push(Shown {
            name: name.to_string(),
            kind,
            text,
            json,
        })
    };
    let source = crate::io::image::colour_source(photo);
    let refused = crate::io::image::cicp_refused(photo);
    let text = match (source, &refused) {
        (S::Cicp, Some(why)) => format!("cICP, refused: {why}"),
        (S::Cicp, None) => "cICP (over any iCCP, sRGB, gAMA and cHRM)".into(),
        (S::Icc, _) => "ICC profile".into(),
        (S::Srgb, _) => "sRGB chunk".into(),
        (S::PngChunks, _) => "gAMA and cHRM (no iCCP or sRGB chunk)".into(),
        (S::None, _) => "none: sRGB's, as readers take it".into(),
    };
    row("colour", "source", text, json!(source.name()));
    let colour = photo.png_colour.unwrap_or_default();
    if let Some(g) = colour.gamma {
        let text = format!("{g} (light = code^{})", round(100_000.0 / f64::from(g)));
        row("gAMA", "chunk", text, json!(g));
    }
    if let Some(c) = colour.chromaticities {
        let xy = |i: usize| [c[i], c[i + 1]].map(|v| round(f64::from(v) / 100_000.0));
        let names = ["white", "red", "green", "blue"];
        let text = (0..4)
            .map(|k| format!("{} {}, {}", names[k], xy(2 * k)[0], xy(2 * k)[1]))
            .collect::<Vec<_>>()
            .join("; ");
        let json = json!({"white": xy(0), "red": xy(2), "green": xy(4), "blue": xy(6)});
        row("cHRM", "chunk", text, json);
    }
    if let Some(intent) = colour.srgb {
        let name = [
            "perceptual",
            "relative colorimetric",
            "saturation",
            "absolute colorimetric",
        ]
        .get(usize::from(intent))
        .unwrap_or(&"unknown");
        row(
            "sRGB",
            "chunk",
            format!("rendering intent {intent} ({name})"),
            json!(intent),
        );
    }
    if let Some([p, t, m, f]) = colour.cicp {
        let stored = colour.cicp_matrix_read_as_0;
        let matrix = stored.map_or(format!("{m}"), |s| format!("{s}, read as 0 (PNG is RGB)"));
        let text = format!(
            "primaries {p} ({}), transfer {t} ({}), matrix {matrix}, {} range",
            cicp_primaries(p),
            cicp_transfer(t),
            if f == 1 { "full" } else { "narrow" }
        );
        let json = json!({"primaries": p, "transfer": t, "matrix": stored.unwrap_or(m), "full_range": f == 1});
        row("cICP", "chunk", text, json);
    }
    if let Some(r) = &photo.resolution {
        use crate::frame::ResolutionUnit as U;
        let unit = match r.unit {
            U::None => "none",
            U::Inch => "inch",
            U::Centimetre => "centimetre",
            U::Metre => "metre",
        };
        let value = |(n, d): (u32, u32)| round(f64::from(n) / f64::from(d.max(1)));
        let (x, y) = (value(r.x), value(r.y));
        let text = match r.unit {
            U::None => format!("{x} x {y} (no unit: the pixels' aspect)"),
            _ => format!("{x} x {y} per {unit}"),
        };
        row(
            "resolution",
            "density",
            text,
            json!({"x": x, "y": y, "unit": unit}),
        );
    }
}

/// ITU-T H.273's names of its colour primaries (table 2).
fn cicp_primaries(code: u8) -> &'static str {
    match code {
        1 => "BT.709",
        4 => "BT.470 M",
        5 => "BT.470 BG",
        6 => "BT.601",
        7 => "SMPTE 240M",
        8 => "generic film",
        9 => "BT.2020",
        10 => "XYZ",
        11 => "DCI-P3",
        12 => "Display P3",
        22 => "EBU 3213",
        2 => "unspecified",
        _ => "reserved",
    }
}

/// ITU-T H.273's names of its transfer characteristics (table 3).
fn cicp_transfer(code: u8) -> &'static str {
    match code {
        1 | 6 | 14 | 15 => "BT.709",
        4 => "gamma 2.2",
        5 => "gamma 2.8",
        7 => "SMPTE 240M",
        8 => "linear",
        9 => "log 100:1",
        10 => "log 316:1",
        11 => "IEC 61966-2-4",
        12 => "BT.1361",
        13 => "sRGB",
        16 => "PQ",
        17 => "SMPTE 428",
        18 => "HLG",
        2 => "unspecified",
        _ => "reserved",
    }
}

/// A value to six significant places, as `info` prints it (0.3127, not 0.31270000000000003).
fn round(v: f64) -> f64 {
    format!("{v:.6e}").parse().unwrap_or(v)
}
