//! What made a picture: shutter's version and the settings a run records (`shutter blur`
//! flags, as an EXR output's `shutter/version` and `shutter/settings` hold them), written
//! where each format keeps such text, and read back so that `--skip-existing` can tell a
//! picture made with other settings from this run's:
//! - PNG: the text chunks `shutter/version` and `shutter/settings`, as the EXR's attributes
//!   (tEXt, or iTXt where the text is not Latin-1; OpenImageIO reads each under its keyword).
//!   A carried text chunk of either keyword (a PNG shutter made, blurred again) is replaced.
//! - TIFF: the Software tag (305), `shutter 0.1.0: --preset shutter …`, as oiiotool writes
//!   its own name and command there. It replaces the photo's (a camera's firmware, an
//!   editor's name): the tag names what made the file. ASCII only: a character outside it is
//!   written as `\u{…}`.
//! - JPEG: a comment segment (COM) of the same text, after the APP segments (exiftool reads
//!   it as `Comment`, OpenImageIO as `ImageDescription`); the EXIF's own Software stays.

use std::path::Path;

use super::ImageFormat;

/// The PNG keyword of shutter's version.
pub const PNG_VERSION: &str = "shutter/version";
/// The PNG keyword of the settings.
pub const PNG_SETTINGS: &str = "shutter/settings";

/// The most text a JPEG comment segment holds (its length field counts itself).
const JPEG_COMMENT_MOST: usize = 65533;

/// What a TIFF's Software tag or a JPEG's comment starts with, before the settings.
fn prefix() -> String {
    format!("shutter {}: ", env!("CARGO_PKG_VERSION"))
}

/// The text a TIFF's Software tag or a JPEG's comment holds for `record`.
pub fn software(record: &str, format: ImageFormat) -> String {
    prefix() + &as_held(record, format)
}

/// `text` with a backslash doubled and every character outside printable ASCII written as
/// `\u{…}` (as Rust's escapes write it), so that it fits a TIFF ASCII field and two texts
/// stay two (`è` and a typed `\u{e8}`).
fn ascii(text: &str) -> String {
    text.chars()
        .map(|c| match c {
            '\\' => "\\\\".to_string(),
            ' '..='~' => c.to_string(),
            _ => format!("\\u{{{:x}}}", c as u32),
        })
        .collect()
}

/// The settings as a picture of `format` holds them: what [`recorded`] reads back from a
/// picture written with `record` (in a TIFF in ASCII; in a JPEG cut to what one comment
/// segment holds, at a character).
pub fn as_held(record: &str, format: ImageFormat) -> String {
    match format {
        ImageFormat::Tiff => ascii(record),
        ImageFormat::Jpeg => {
            let most = JPEG_COMMENT_MOST - prefix().len();
            let mut end = record.len().min(most);
            while !record.is_char_boundary(end) {
                end -= 1;
            }
            record[..end].to_string()
        }
        ImageFormat::Png => record.to_string(),
    }
}

/// The settings of `text`, a Software tag or a comment shutter wrote ([`software`]); None
/// for another program's.
fn settings_of(text: &str) -> Option<String> {
    let (version, settings) = text.strip_prefix("shutter ")?.split_once(": ")?;
    let is_version = !version.is_empty()
        && version
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || ".-+".contains(c));
    is_version.then(|| settings.to_string())
}

/// The settings a picture shutter made records (None for one another program made, one that
/// records none, or one that cannot be read).
pub fn recorded(path: &Path, format: ImageFormat) -> Option<String> {
    match format {
        ImageFormat::Png => {
            let file = std::io::BufReader::new(std::fs::File::open(path).ok()?);
            let reader = png::Decoder::new(file).read_info().ok()?;
            let info = reader.info();
            // Our own chunks are tEXt or iTXt; a zTXt one is read as well.
            let mut texts: Vec<(String, String)> = (info.uncompressed_latin1_text.iter())
                .map(|t| (t.keyword.clone(), t.text.clone()))
                .collect();
            for t in &info.compressed_latin1_text {
                let mut t = t.clone();
                if t.decompress_text().is_ok() {
                    texts.extend(t.get_text().ok().map(|text| (t.keyword.clone(), text)));
                }
            }
            for t in &info.utf8_text {
                texts.extend(t.get_text().ok().map(|text| (t.keyword.clone(), text)));
            }
            texts
                .into_iter()
                .find(|(keyword, _)| keyword == PNG_SETTINGS)
                .map(|(_, text)| text)
        }
        ImageFormat::Tiff => {
            let file = std::io::BufReader::new(std::fs::File::open(path).ok()?);
            let mut decoder = tiff::decoder::Decoder::new(file).ok()?;
            let text = decoder
                .get_tag_ascii_string(tiff::tags::Tag::Software)
                .ok()?;
            settings_of(text.trim_end_matches('\0'))
        }
        ImageFormat::Jpeg => jpeg_settings(&std::fs::read(path).ok()?),
    }
}

/// The settings the first comment segment (COM) of a JPEG that shutter wrote holds, before
/// its scan (the walk `meta` and `resolution` share: `jpeg::segment`).
fn jpeg_settings(bytes: &[u8]) -> Option<String> {
    super::jpeg::segment(bytes, |marker, body| {
        (marker == 0xFE)
            .then(|| settings_of(&String::from_utf8_lossy(body)))
            .flatten()
    })
}

/// `jpeg` (a whole JPEG file) with a comment segment of `text` after the APP segments that
/// follow its start (where readers look for the JFIF, EXIF, profile and IPTC first); as it
/// is if the text does not fit a segment (64 KiB).
pub fn with_jpeg_comment(jpeg: Vec<u8>, text: &str) -> Vec<u8> {
    let Ok(length) = u16::try_from(text.len() + 2) else {
        return jpeg;
    };
    if !jpeg.starts_with(&[0xFF, 0xD8]) {
        return jpeg;
    }
    let mut at = 2;
    while at + 4 <= jpeg.len() && jpeg[at] == 0xFF && (0xE0..=0xEF).contains(&jpeg[at + 1]) {
        at += 2 + usize::from(u16::from_be_bytes([jpeg[at + 2], jpeg[at + 3]]));
    }
    if at > jpeg.len() {
        return jpeg;
    }
    let mut out = Vec::with_capacity(jpeg.len() + text.len() + 4);
    out.extend_from_slice(&jpeg[..at]);
    out.extend_from_slice(&[0xFF, 0xFE]);
    out.extend_from_slice(&length.to_be_bytes());
    out.extend_from_slice(text.as_bytes());
    out.extend_from_slice(&jpeg[at..]);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_comment_goes_after_the_app_segments_and_is_read_back() {
        // SOI, APP0 (4 bytes of body), APP1 (2), DQT (2 bytes of body), SOS, EOI.
        let jpeg = vec![
            0xFF, 0xD8, 0xFF, 0xE0, 0, 6, b'J', b'F', b'I', b'F', 0xFF, 0xE1, 0, 4, 1, 2, 0xFF,
            0xDB, 0, 4, 9, 9, 0xFF, 0xDA, 0, 2, 0xFF, 0xD9,
        ];
        let text = software("--preset shutter --algorithm scatter", ImageFormat::Jpeg);
        let with = with_jpeg_comment(jpeg.clone(), &text);
        // The comment right before the DQT, everything else as it was.
        assert_eq!(&with[..16], &jpeg[..16]);
        assert_eq!(&with[16..18], &[0xFF, 0xFE]);
        assert_eq!(&with[20 + text.len()..], &jpeg[16..]);
        assert_eq!(
            jpeg_settings(&with).as_deref(),
            Some("--preset shutter --algorithm scatter")
        );
        assert_eq!(jpeg_settings(&jpeg), None);
    }

    #[test]
    fn settings_too_long_for_a_comment_are_held_cut_as_written() {
        let record = format!("--layer {}", "é".repeat(40_000));
        let text = software(&record, ImageFormat::Jpeg);
        assert!(text.len() <= JPEG_COMMENT_MOST, "{}", text.len());
        let jpeg = vec![0xFF, 0xD8, 0xFF, 0xDA, 0, 2, 0xFF, 0xD9];
        let with = with_jpeg_comment(jpeg, &text);
        let read = jpeg_settings(&with);
        assert_eq!(read, Some(as_held(&record, ImageFormat::Jpeg)));
        assert_ne!(read.as_deref(), Some(&record[..]));
    }

    #[test]
    fn another_program_s_software_records_no_settings() {
        assert_eq!(settings_of("Adobe Photoshop 25.0 (Windows)"), None);
        assert_eq!(
            settings_of("OpenImageIO 2.4.7 : oiiotool in.exr -o out.tif"),
            None
        );
        assert_eq!(settings_of("shutter : x"), None);
        assert_eq!(
            settings_of("shutter 0.1.0: --preset x").as_deref(),
            Some("--preset x")
        );
    }

    #[test]
    fn a_tiff_holds_the_settings_in_ascii() {
        let record = "--preset shutter --layer 'Vue lumière'";
        let held = as_held(record, ImageFormat::Tiff);
        assert_eq!(held, "--preset shutter --layer 'Vue lumi\\u{e8}re'");
        // A layer typed with the escape is another layer, and held as another.
        let typed = "--preset shutter --layer 'Vue lumi\\u{e8}re'";
        assert_ne!(as_held(typed, ImageFormat::Tiff), held);
        assert!(software(record, ImageFormat::Tiff).is_ascii());
        assert_eq!(
            settings_of(&software(record, ImageFormat::Tiff)),
            Some(held)
        );
        assert_eq!(as_held(record, ImageFormat::Png), record);
    }
}
