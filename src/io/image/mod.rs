//! 8/16-bit (and float TIFF) images through the `image` crate: PNG, JPEG, TIFF.
//!
//! Channels are exposed by name like EXR channels: `R`, `G`, `B`, `A` for colour images and
//! `Y`, `A` for grey ones. Integer samples are normalised to [0, 1]; the transfer curve of
//! the photo's ICC profile (sRGB's when it has none, `profile`) is removed for colour passes
//! (not for data maps) by the caller through [`read_photo_colour`], which also reads what the
//! photo holds besides its pixels (`meta`) for the output to hold again (`write`). Every
//! image is turned upright by its orientation tag as it is read (the header's size is the
//! upright size), so a map painted on the upright view lines up. Integer files hold straight
//! (unassociated) alpha; shutter works premultiplied, so colour is premultiplied on read and
//! divided back on write where alpha is above 0 (where it is 0, written as it is, as
//! oiiotool does; a JPEG's is written premultiplied: over black).

mod jpeg;
mod meta;
mod png_mend;
mod profile;
mod record;
mod resolution;
mod tiff_colour;
mod tiff_cut;
mod tiff_float;
mod tiff_meta;
mod tiff_write;
mod upright;
mod write;

use std::io::{Seek, Write};
use std::path::Path;
use std::sync::OnceLock;

use image::{ColorType, DynamicImage, ImageDecoder, ImageReader, Limits};

use crate::frame::{Photo, Plane};

pub use jpeg::sampling as jpeg_sampling;
pub use meta::read_photo;
pub use profile::{
    chromaticities, cicp_profile_of, colour_source, linear_profile_of, primaries_profile,
    profile_of, ColourSource, Transfer,
};
pub use record::{as_held as record_as_held, recorded as recorded_settings};
pub use upright::exif_orientation;
pub use write::{goes_out_grey, jpeg_left_out, out_of_range, write_photo, PhotoOptions};

/// What the header of an integer image says.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageHeader {
    pub width: usize,
    pub height: usize,
    /// (name, index of the decoded plane it reads).
    pub channels: Vec<(&'static str, usize)>,
    /// 8, 16 or 32 (float).
    pub bits: u8,
    pub float: bool,
    pub format: &'static str,
    /// Turned upright by its orientation to another shape: stored `height`×`width`.
    pub turned: bool,
}

/// Channel names and the decoded plane each reads. A grey image also answers to R, G and B
/// (all reading its Y plane), so it works as a colour pass as well as a data map.
fn channel_names(count: u8) -> Vec<(&'static str, usize)> {
    match count {
        1 => vec![("Y", 0), ("R", 0), ("G", 0), ("B", 0)],
        2 => vec![("Y", 0), ("R", 0), ("G", 0), ("B", 0), ("A", 1)],
        3 => vec![("R", 0), ("G", 1), ("B", 2)],
        _ => vec![("R", 0), ("G", 1), ("B", 2), ("A", 3)],
    }
}

/// An image reader on an input file ([`crate::io::input::open_input`]: a regular file, opened
/// without waiting), its format guessed from the name until the content says otherwise.
pub fn input_reader(path: &Path) -> Result<ImageReader<png_mend::Source>, String> {
    let mut reader = ImageReader::new(png_mend::source(path)?);
    if let Ok(format) = image::ImageFormat::from_path(path) {
        reader.set_format(format);
    }
    Ok(reader)
}

/// What starts the text of an error for a valid file of a kind the decoders do not read
/// (`crate::io::file` reports it as "not supported", not "corrupt").
pub const NOT_SUPPORTED: &str = "not supported: ";

/// The image crate's error in words, [`NOT_SUPPORTED`] first where it says the file uses a
/// feature its decoder lacks (a TIFF of 32-bit integers) rather than that the file is bad.
/// A read that met the end of the file is said as the truncation it is (the standard
/// library's "failed to fill whole buffer" named no cause).
fn image_error(e: image::ImageError) -> String {
    match e {
        image::ImageError::Unsupported(what) => format!("{NOT_SUPPORTED}{what}"),
        image::ImageError::IoError(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => {
            "the file is truncated: it ends before the data its header declares".into()
        }
        other => other.to_string(),
    }
}

/// [`image_error`] of a failed read of the image at `path`, where a TIFF cut short is said
/// as such ([`tiff_cut::tiff_cut_short`]) whatever its decoder met at the cut.
fn read_error(path: &Path, tiff: bool, e: image::ImageError) -> String {
    (tiff.then(|| tiff_cut::tiff_cut_short(path, true)).flatten()).unwrap_or_else(|| image_error(e))
}

/// Why a JPEG cannot be read though it may be valid, from its frame header: a precision
/// other than 8 bits (12-bit JPEG), or a coding other than Huffman baseline, extended or
/// progressive (arithmetic coding, lossless, hierarchical). `None` for a JPEG the decoder
/// reads, or whose markers end before a frame header (the decoder then says what is wrong).
pub fn jpeg_unsupported(bytes: &[u8]) -> Option<String> {
    let mut at = 2;
    loop {
        while bytes.get(at) == Some(&0xFF) && bytes.get(at + 1) == Some(&0xFF) {
            at += 1;
        }
        let (Some(&0xFF), Some(&marker)) = (bytes.get(at), bytes.get(at + 1)) else {
            return None;
        };
        at += 2;
        match marker {
            0xD9 | 0xDA => return None,
            0x01 | 0xD0..=0xD7 => continue,
            _ => {}
        }
        let length = u16::from_be_bytes([*bytes.get(at)?, *bytes.get(at + 1)?]) as usize;
        match marker {
            0xC0..=0xC2 => {
                let precision = *bytes.get(at + 2)?;
                return (precision != 8).then(|| {
                    format!("a {precision}-bit JPEG (only 8-bit JPEGs are read; convert it to a 16-bit PNG or TIFF)")
                });
            }
            0xC3 => return Some("a lossless JPEG (only lossy 8-bit JPEGs are read)".into()),
            0xC5..=0xC7 | 0xCD..=0xCF => {
                return Some(
                    "a hierarchical JPEG (only sequential and progressive JPEGs are read)".into(),
                )
            }
            0xC9..=0xCB => {
                return Some(
                    "an arithmetic-coded JPEG (only Huffman-coded JPEGs are read; re-encode it)"
                        .into(),
                )
            }
            _ => {}
        }
        at += length;
    }
}

/// Reads the header only. The decoder is told the pixel limit as a width and a height of
/// `max_pixels` each (the image crate's limits are per axis); the caller checks the product.
pub fn probe(path: &Path, max_pixels: usize) -> Result<ImageHeader, String> {
    let mut reader = crate::io::image::input_reader(path)?
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let mut limits = Limits::default();
    let side = u32::try_from(max_pixels).unwrap_or(u32::MAX);
    limits.max_image_width = Some(side);
    limits.max_image_height = Some(side);
    // Reading a header allocates only what its ancillary chunks inflate to (a profile, text):
    // capped, so a chunk that inflates to gigabytes is refused, not decompressed.
    limits.max_alloc = Some(HEADER_ROOM);
    reader.limits(limits);
    let format = match reader.format() {
        Some(image::ImageFormat::Png) => "png",
        Some(image::ImageFormat::Jpeg) => "jpeg",
        Some(image::ImageFormat::Tiff) => "tiff",
        _ => return Err("not a PNG, JPEG, TIFF or EXR file".into()),
    };
    // A JPEG is read once, for both checks of its stream: a kind the decoder does not read
    // (before the decoder says so as damage), and a stream cut short.
    let jpeg = if format == "jpeg" {
        let bytes = crate::io::input::read_input(path).map_err(|e| e.to_string())?;
        if let Some(why) = jpeg_unsupported(&bytes) {
            return Err(format!("{NOT_SUPPORTED}{why}"));
        }
        Some(bytes)
    } else {
        None
    };
    let cut = match format {
        "png" => png_mend::png_cut_short(path),
        "tiff" => tiff_cut::tiff_cut_short(path, false),
        _ => None,
    };
    if let Some(why) = cut {
        return Err(why);
    }
    let mut decoder = match reader.into_decoder() {
        Ok(decoder) => decoder,
        Err(e) => {
            return grey_float_header(path, format).ok_or_else(|| {
                let why = (format == "tiff").then(|| tiff_float::unread_kind(path));
                match why.flatten() {
                    Some(why) => format!("{NOT_SUPPORTED}{why}"),
                    None => image_error(e),
                }
            })
        }
    };
    let turn = orientation(&mut decoder, path, format == "png");
    let (width, height) = upright(decoder.dimensions(), turn);
    let turned = (width, height) != decoder.dimensions();
    // Past the pixel limit the caller's size check speaks first.
    let within = (width as u64).saturating_mul(height as u64) <= max_pixels as u64;
    if let (Some(bytes), true) = (&jpeg, within) {
        check_jpeg_bytes(bytes, width as usize, height as usize)?;
    }
    let color = decoder.color_type();
    let float = matches!(color, ColorType::Rgb32F | ColorType::Rgba32F);
    let bits = (color.bytes_per_pixel() / color.channel_count()) * 8;
    Ok(ImageHeader {
        width: width as usize,
        height: height as usize,
        channels: channel_names(color.channel_count()),
        bits,
        float,
        format,
        turned,
    })
}

/// The header of a TIFF the image crate refuses that the tiff crate reads (float grey, grey
/// and alpha, palette or YCbCr: [`tiff_float`]); `None` for any other file.
fn grey_float_header(path: &Path, format: &'static str) -> Option<ImageHeader> {
    let header = (format == "tiff")
        .then(|| tiff_float::header(path))
        .flatten()?;
    let (width, height) = tiff_float::upright_size(&header);
    Some(ImageHeader {
        width: width as usize,
        height: height as usize,
        channels: channel_names(header.samples as u8),
        bits: if header.float { 32 } else { header.bits },
        float: header.float,
        format,
        turned: (width, height) != header.stored,
    })
}

/// The orientation an image records (EXIF, or a TIFF's tag); upright when it records none or
/// one that cannot be read.
///
/// A PNG's eXIf may follow its image data (libpng writes it there, and readers take it there),
/// where the image crate does not look: a PNG with no eXIf before its image data is turned as
/// one after it says ([`meta::late_png_exif`]), so a photo turned by its viewer is turned here
/// too.
fn orientation(
    decoder: &mut impl ImageDecoder,
    path: &Path,
    png: bool,
) -> image::metadata::Orientation {
    use image::metadata::Orientation;
    let own = decoder.orientation().unwrap_or(Orientation::NoTransforms);
    if !png || own != Orientation::NoTransforms || decoder.exif_metadata().ok().flatten().is_some()
    {
        return own;
    }
    meta::late_png_exif(path)
        .and_then(|exif| Orientation::from_exif_chunk(&exif))
        .unwrap_or(own)
}

/// The size of an image of stored size `(width, height)` once turned upright.
fn upright((width, height): (u32, u32), orientation: image::metadata::Orientation) -> (u32, u32) {
    use image::metadata::Orientation::*;
    match orientation {
        Rotate90 | Rotate270 | Rotate90FlipH | Rotate270FlipH => (height, width),
        _ => (width, height),
    }
}

/// What reading a picture's header may allocate: its ICC profile, EXIF, XMP and text chunks
/// inflated (a profile is rarely over 1 MiB; the largest in use are a few MiB).
pub const HEADER_ROOM: u64 = 32 << 20;

/// Room the decoders get for their own buffers beyond the decoded image.
const DECODER_ROOM: u64 = 64 << 20;

/// The largest decoded pixel the image crate makes (RGBA, f32), in bytes.
const LARGEST_PIXEL: u64 = 16;

/// The decoded planes of an image (indexed as in [`ImageHeader::channels`]), turned upright,
/// integer samples normalised to [0, 1], no transfer function applied. `declared` is the
/// (upright) size the header gave when it was checked: the decoder may not decode another
/// size, nor allocate more than that size needs (in place of the image crate's fixed 512 MiB,
/// which refused large 16-bit images the pixel limit admits).
pub fn read_planes(
    path: &Path,
    declared: (usize, usize),
) -> Result<(usize, usize, Vec<Plane>), String> {
    let mut reader = crate::io::image::input_reader(path)?
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    let mut limits = Limits::default();
    // Either side may be the stored width: the orientation is read with the header.
    let side = u32::try_from(declared.0.max(declared.1)).unwrap_or(u32::MAX);
    limits.max_image_width = Some(side);
    limits.max_image_height = Some(side);
    limits.max_alloc = Some(
        (declared.0 as u64)
            .saturating_mul(declared.1 as u64)
            .saturating_mul(LARGEST_PIXEL)
            .saturating_add(DECODER_ROOM),
    );
    reader.limits(limits);
    let tiff = reader.format() == Some(image::ImageFormat::Tiff);
    let png = reader.format() == Some(image::ImageFormat::Png);
    let mut decoder = match reader.into_decoder() {
        Ok(decoder) => decoder,
        Err(e) => {
            // A grey, palette or YCbCr TIFF the image crate refuses, read by the tiff crate
            // within the same allowance.
            let header = tiff.then(|| tiff_float::header(path)).flatten();
            let Some(header) = header else {
                return Err(read_error(path, tiff, e));
            };
            let allowed = (declared.0 as u64)
                .saturating_mul(declared.1 as u64)
                .saturating_mul(LARGEST_PIXEL);
            return tiff_float::read(path, &header, allowed)
                .map_err(|why| tiff_cut::tiff_cut_short(path, true).unwrap_or(why));
        }
    };
    let orientation = orientation(&mut decoder, path, png);
    let mut image = DynamicImage::from_decoder(decoder).map_err(|e| read_error(path, tiff, e))?;
    image.apply_orientation(orientation);
    let (width, height) = (image.width() as usize, image.height() as usize);
    let count = image.color().channel_count() as usize;
    let n = width * height;
    let mut planes: Vec<Plane> = (0..count).map(|_| vec![0.0; n]).collect();
    let mut scatter = |values: &mut dyn Iterator<Item = f32>| {
        for (i, value) in values.enumerate() {
            planes[i % count][i / count] = value;
        }
    };
    match &image {
        DynamicImage::ImageLuma8(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageRgb8(_)
        | DynamicImage::ImageRgba8(_) => {
            scatter(&mut image.as_bytes().iter().map(|&b| b as f32 / 255.0));
        }
        DynamicImage::ImageLuma16(img) => {
            scatter(&mut img.as_raw().iter().map(|&v| v as f32 / 65535.0))
        }
        DynamicImage::ImageLumaA16(img) => {
            scatter(&mut img.as_raw().iter().map(|&v| v as f32 / 65535.0))
        }
        DynamicImage::ImageRgb16(img) => {
            scatter(&mut img.as_raw().iter().map(|&v| v as f32 / 65535.0))
        }
        DynamicImage::ImageRgba16(img) => {
            scatter(&mut img.as_raw().iter().map(|&v| v as f32 / 65535.0))
        }
        DynamicImage::ImageRgb32F(img) => scatter(&mut img.as_raw().iter().copied()),
        DynamicImage::ImageRgba32F(img) => scatter(&mut img.as_raw().iter().copied()),
        other => {
            let converted = other.to_rgba32f();
            planes = (0..4).map(|_| vec![0.0; n]).collect();
            for (i, value) in converted.as_raw().iter().enumerate() {
                planes[i % 4][i / 4] = *value;
            }
        }
    }
    Ok((width, height, planes))
}

/// Checks a JPEG's stream from its markers, without decoding: the image data must end with
/// the end-of-image marker, and must be long enough for the `width × height` its header
/// declares. A JPEG decoder fills whatever a stream lacks with invented pixels (a 634-byte
/// file declaring 12000×12000 decoded to 4 GB of them with no error), so a cut stream would
/// otherwise pass as a frame.
///
/// The length bound: a Huffman-coded frame (SOF0, SOF1, SOF2) codes every 8×8 block of its
/// full-resolution component, and every block's DC difference takes a code of at least one
/// bit (progressive AC scans can skip runs of blocks; DC scans cannot), so the entropy-coded
/// data holds at least ⌈w/8⌉·⌈h/8⌉ bits.
fn check_jpeg_bytes(bytes: &[u8], width: usize, height: usize) -> Result<(), String> {
    let cut = "the JPEG stream is cut short (no end-of-image marker after its image data); \
               the file is truncated or damaged";
    // Walk the marker segments up to the first scan.
    let mut at = 2;
    let mut huffman = false;
    loop {
        // Markers may be preceded by any number of 0xFF fill bytes.
        while bytes.get(at) == Some(&0xFF) && bytes.get(at + 1) == Some(&0xFF) {
            at += 1;
        }
        let (Some(&0xFF), Some(&marker)) = (bytes.get(at), bytes.get(at + 1)) else {
            return Err(cut.into());
        };
        at += 2;
        match marker {
            0xD9 => return Err("the JPEG stream ends before its image data".into()),
            0x01 | 0xD0..=0xD7 => continue,
            _ => {}
        }
        let (Some(&high), Some(&low)) = (bytes.get(at), bytes.get(at + 1)) else {
            return Err(cut.into());
        };
        let length = u16::from_be_bytes([high, low]) as usize;
        if matches!(marker, 0xC0..=0xC2) {
            huffman = true;
        }
        at += length;
        if marker == 0xDA {
            break;
        }
    }
    // Entropy-coded data escapes 0xFF as 0xFF 0x00, so 0xFF 0xD9 after the first scan's
    // header can only be the end-of-image marker.
    let data = bytes.get(at..).unwrap_or(&[]);
    let end = data
        .windows(2)
        .rposition(|w| w == [0xFF, 0xD9])
        .ok_or(cut)?;
    let blocks = (width.div_ceil(8) as u64) * (height.div_ceil(8) as u64);
    if huffman && (end as u64) * 8 < blocks {
        return Err(format!(
            "the JPEG declares {width}x{height} but holds {end} bytes of image data, fewer \
             than the {} its {blocks} blocks need at the least; the file is damaged",
            blocks.div_ceil(8)
        ));
    }
    Ok(())
}

/// sRGB electro-optical transfer: encoded [0, 1] to linear.
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// Inverse of [`srgb_to_linear`]: linear to encoded, for values in [0, 1].
pub fn linear_to_srgb(v: f32) -> f32 {
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// Linear [0, 1] to 16-bit sRGB codes through a 64k-entry table of code boundaries, so the
/// per-pixel cost is a binary search instead of a `powf`.
fn srgb_encode_table() -> &'static [f32] {
    static TABLE: OnceLock<Vec<f32>> = OnceLock::new();
    TABLE.get_or_init(|| {
        // Entry k: the linear value where code k+1 starts (midpoint between codes k and k+1).
        (0..65535)
            .map(|k| srgb_to_linear((k as f32 + 0.5) / 65535.0))
            .collect()
    })
}

/// Encodes a linear value as an integer code of `max` (255 or 65535) levels.
pub fn encode(v: f32, srgb: bool, max: u32) -> u32 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    if !srgb {
        return (v * max as f32 + 0.5) as u32;
    }
    if max == 65535 {
        srgb_encode_table().partition_point(|&edge| edge <= v) as u32
    } else {
        (linear_to_srgb(v) * max as f32 + 0.5) as u32
    }
}

/// Output format for integer images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Tiff,
    Jpeg,
}

impl ImageFormat {
    /// The format's name, as a reader knows it.
    pub fn name(self) -> &'static str {
        match self {
            ImageFormat::Png => "PNG",
            ImageFormat::Tiff => "TIFF",
            ImageFormat::Jpeg => "JPEG",
        }
    }

    /// The most pixels a side the format holds: a JPEG frame header stores each side in 16
    /// bits (ITU T.81, B.2.2), a PNG's IHDR in 31 (PNG, 11.2.2), a TIFF's ImageWidth and
    /// ImageLength in a LONG (TIFF 6.0). Only JPEG's is within the pixel limit's reach.
    pub fn most_a_side(self) -> u64 {
        match self {
            ImageFormat::Png => (1 << 31) - 1,
            ImageFormat::Tiff => u32::MAX as u64,
            ImageFormat::Jpeg => u16::MAX as u64,
        }
    }

    pub fn from_path(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "png" => Some(ImageFormat::Png),
            "tif" | "tiff" => Some(ImageFormat::Tiff),
            "jpg" | "jpeg" => Some(ImageFormat::Jpeg),
            _ => None,
        }
    }
}

/// Writes premultiplied linear colour as an sRGB-encoded (or linear) integer image with
/// straight alpha and nothing else: [`write_photo`] for a frame that carries no photo.
#[allow(clippy::too_many_arguments)]
pub fn write_color(
    writer: impl Write + Seek,
    format: ImageFormat,
    width: usize,
    height: usize,
    rgb: [&[f32]; 3],
    alpha: Option<&[f32]>,
    sixteen_bit: bool,
    srgb: bool,
) -> Result<(), String> {
    let options = PhotoOptions {
        bits: if sixteen_bit { 16 } else { 8 },
        linear: !srgb,
        jpeg_quality: 95,
        photo: None,
        icc: None,
        record: "",
    };
    write_photo(writer, format, width, height, rgb, alpha, &options)
}

/// Reads what a photo holds besides its pixels ([`read_photo`]) and makes its colour planes
/// (as [`read_planes`] gave them) straight: a file of associated alpha has its colour divided
/// by `alpha` as stored, in its encoded values (where the file multiplied it). Then, when
/// `linearise`, turns them into the linear light of its profile (or of what a PNG's cICP, or
/// its gAMA and cHRM, say: [`profile_of`]), refusing a cICP it cannot honour
/// ([`cicp_refused`], the error [`NOT_SUPPORTED`] first). Returns the photo and a note when
/// the profile could not give its curves, or a cICP was passed over.
pub fn read_photo_colour(
    path: &Path,
    mut planes: [&mut [f32]; 3],
    alpha: Option<&[f32]>,
    linearise: bool,
) -> Result<(Photo, Option<String>), String> {
    let photo = read_photo(path)?;
    if let (true, Some(alpha)) = (photo.premultiplied, alpha) {
        for plane in planes.iter_mut() {
            for (v, &a) in plane.iter_mut().zip(alpha) {
                *v = if a > 0.0 { (*v / a).min(1.0) } else { 0.0 };
            }
        }
    }
    if !linearise {
        let note = more_images_note(&photo);
        return Ok((photo, note));
    }
    if let Some(why) = cicp_refused(&photo) {
        return Err(format!("{NOT_SUPPORTED}{why}"));
    }
    let transfer = Transfer::of(profile_of(&photo, photo.grey).as_deref());
    let max = if photo.bits == 16 { 65535 } else { 255 };
    transfer.linearise(planes, max);
    let notes: Vec<String> = profile::cicp_note(&photo)
        .into_iter()
        .chain(transfer.note)
        .chain(more_images_note(&photo))
        .collect();
    Ok((photo, (!notes.is_empty()).then(|| notes.join("; "))))
}

/// The note of a TIFF that holds more images after its first (pages, or a reduced-size
/// preview): shutter reads the first, and the output holds it alone.
pub fn more_images_note(photo: &Photo) -> Option<String> {
    photo.more_images.then(|| {
        "the TIFF holds more images after its first (pages, or a preview): only the first is \
         read, and the output holds it alone"
            .to_string()
    })
}

/// Why a photo's colour cannot be read as its PNG's cICP says it is coded (high dynamic
/// range, narrow range: [`profile::cicp_refusal`]), where it cannot.
pub fn cicp_refused(photo: &Photo) -> Option<String> {
    profile::cicp_refusal(photo.png_colour?.cicp?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    #[test]
    fn srgb_round_trips_every_8_bit_code() {
        for code in 0..=255u32 {
            let linear = srgb_to_linear(code as f32 / 255.0);
            assert_eq!(encode(linear, true, 255), code);
        }
    }

    #[test]
    fn srgb_round_trips_every_16_bit_code() {
        for code in (0..=65535u32).step_by(7).chain([65535]) {
            let linear = srgb_to_linear(code as f32 / 65535.0);
            assert_eq!(encode(linear, true, 65535), code, "code {code}");
        }
    }

    #[test]
    fn srgb_known_values() {
        // 50% sRGB grey is 21.4% linear (IEC 61966-2-1).
        assert!(close(srgb_to_linear(0.5), 0.214_041, 1e-5));
        assert!(close(linear_to_srgb(0.214_041), 0.5, 1e-5));
    }

    #[test]
    fn encode_clamps_and_maps_nan_to_zero() {
        assert_eq!(encode(f32::NAN, true, 255), 0);
        assert_eq!(encode(f32::INFINITY, true, 255), 255);
        assert_eq!(encode(-3.0, false, 65535), 0);
        assert_eq!(encode(7.0, false, 65535), 65535);
    }
}
