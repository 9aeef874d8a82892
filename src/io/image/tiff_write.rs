//! Writing a TIFF: the image's directory laid out here, its strips deflated by EXR's ZIP
//! compressor (libdeflate, `exr_zip::zlib`), its metadata's directories by [`tiff_meta`]
//! through the tiff crate's directory encoder.
//!
//! The tiff crate's image encoder writes each value where the last one ended, so after a
//! strip of odd length its sample format, strip offsets and the directory itself begin at odd
//! offsets, which TIFF 6.0 (section 2) forbids and `exiftool -validate` reports ("Odd offset
//! for IFD0 tag 0x0102"); and it only compresses strips written all at once, which then ends
//! the directory before a pad can go in. So the image's tags are written here, every value and
//! directory padded to a word boundary ([`word_align`]): deflate (Adobe, code 8) with the
//! horizontal predictor on integers (floats deflated as they are: predictor 3 is not written),
//! alpha declared in `ExtraSamples`, strips of about a megabyte as the crate made them.

use std::io::{Seek, Write};

use rayon::prelude::*;
use tiff::encoder::{DirectoryEncoder, Rational, TiffEncoder, TiffKindStandard};
use tiff::tags::{Tag, Type};
use tiff::TiffResult;

use super::{resolution, tiff_meta};
use crate::frame::Photo;

/// The TIFF tags of what a photo carries: its ICC profile (ICC.1, annex B.4), XMP (Adobe XMP
/// part 3, 1.1.6), Photoshop image resources (TIFF/EP) and bare IPTC (IPTC-NAA, TIFF/EP).
const TIFF_ICC: u16 = 34675;
const TIFF_XMP: u16 = 700;
const TIFF_PHOTOSHOP: u16 = 34377;
const TIFF_IPTC: u16 = 33723;

/// `ExtraSamples` values for associated (premultiplied) and unassociated (straight) alpha
/// (TIFF 6.0, section 18).
const ASSOCIATED_ALPHA: u16 = 1;
const UNASSOCIATED_ALPHA: u16 = 2;

/// Compression 8 (Adobe deflate, TIFF Technical Note 2) and the predictors (section 14).
const DEFLATE: u16 = 8;
const NO_PREDICTOR: u16 = 1;
const HORIZONTAL: u16 = 2;

/// Uncompressed bytes a strip holds at most (whole rows; one row where a row is larger).
const STRIP_BYTES: usize = 1_000_000;

/// A TIFF's samples: integer codes (16-bit or not) or float values.
pub(super) enum Samples<'a> {
    Codes(&'a [u16], bool),
    Float(&'a [f32]),
}

/// Pads what is being encoded to a word boundary (one zero byte after an odd length), where
/// TIFF 6.0 (section 2) asks a value outside its entry, and a directory, to begin.
pub(super) fn word_align<W: Write + Seek>(
    directory: &mut DirectoryEncoder<'_, W, TiffKindStandard>,
) -> TiffResult<()> {
    let at = directory.write_data(&[][..] as &[u8])?;
    if at % 2 == 1 {
        directory.write_data(0u8)?;
    }
    Ok(())
}

/// Writes a tag whose value (`value` written by the crate) may lie outside its entry: at a
/// word boundary.
fn aligned_tag<W: Write + Seek, T: tiff::encoder::TiffValue>(
    directory: &mut DirectoryEncoder<'_, W, TiffKindStandard>,
    tag: Tag,
    value: T,
) -> TiffResult<()> {
    word_align(directory)?;
    directory.write_tag(tag, value)
}

/// A strip's samples as the file's bytes (the encoder's byte order, the machine's), each row
/// differenced (the horizontal predictor) where the samples are integers.
fn strip_bytes(
    samples: &Samples,
    range: std::ops::Range<usize>,
    row: usize,
    spp: usize,
) -> Vec<u8> {
    match samples {
        Samples::Float(values) => values[range].iter().flat_map(|v| v.to_ne_bytes()).collect(),
        Samples::Codes(codes, sixteen) => {
            let codes = &codes[range];
            let mut out = Vec::with_capacity(codes.len() * if *sixteen { 2 } else { 1 });
            for line in codes.chunks(row) {
                for (i, &c) in line.iter().enumerate() {
                    let before = if i >= spp { line[i - spp] } else { 0 };
                    if *sixteen {
                        out.extend(c.wrapping_sub(before).to_ne_bytes());
                    } else {
                        out.push((c as u8).wrapping_sub(before as u8));
                    }
                }
            }
            out
        }
    }
}

/// Writes a photo's frame as a TIFF: `channels` interleaved samples a pixel (grey or RGB,
/// and alpha after them when there are 2 or 4), its profile and metadata beside, and
/// `software` (what made it: ASCII) in the Software tag.
#[allow(clippy::too_many_arguments)]
pub(super) fn write_tiff(
    writer: impl Write + Seek,
    width: u32,
    height: u32,
    channels: usize,
    samples: Samples,
    icc: Option<&[u8]>,
    photo: Option<&Photo>,
    software: Option<&str>,
) -> Result<(), String> {
    let error = |e: tiff::TiffError| e.to_string();
    let (bits, format, alpha_kind) = match samples {
        Samples::Float(_) => (32u16, 3u16, ASSOCIATED_ALPHA),
        Samples::Codes(_, true) => (16, 1, UNASSOCIATED_ALPHA),
        Samples::Codes(_, false) => (8, 1, UNASSOCIATED_ALPHA),
    };
    let float = matches!(samples, Samples::Float(_));
    let total = match samples {
        Samples::Float(v) => v.len(),
        Samples::Codes(c, _) => c.len(),
    };
    let row = width as usize * channels;
    if width == 0 || height == 0 || total != row * height as usize {
        return Err(format!(
            "{width}x{height} with {channels} channels is not the {total} samples given"
        ));
    }
    let row_bytes = row * usize::from(bits / 8);
    let rows_per_strip = STRIP_BYTES.div_ceil(row_bytes).min(height as usize);
    // Each strip deflated on its own (in parallel: each strip's bytes depend on it alone).
    let strips: Vec<Vec<u8>> = (0..height as usize)
        .into_par_iter()
        .step_by(rows_per_strip)
        .map(|y| {
            let rows = rows_per_strip.min(height as usize - y);
            let raw = strip_bytes(&samples, y * row..(y + rows) * row, row, channels);
            crate::io::exr_zip::zlib(&raw)
        })
        .collect();

    let mut encoder = TiffEncoder::new(writer).map_err(error)?;
    let xmp = photo.and_then(|p| p.xmp.as_deref());
    let iptc = photo.and_then(|p| p.iptc.as_deref());
    // IPTC's datasets in tag 33723, the other Photoshop resources (if any) in 34377.
    let records = iptc.and_then(tiff_meta::iptc_records);
    let resources = iptc.map(tiff_meta::without_iptc).filter(|r| !r.is_empty());
    // EXIF's directories below IFD0 go before the image, whose IFD0 points to them.
    let exif = photo
        .and_then(|p| p.exif.as_deref())
        .and_then(tiff_meta::parse);
    let pointers = match &exif {
        Some(exif) => tiff_meta::write_sub_directories(&mut encoder, exif).map_err(error)?,
        None => Vec::new(),
    };
    let mut tags = encoder.image_directory().map_err(error)?;
    let mut offsets = Vec::with_capacity(strips.len());
    let mut counts = Vec::with_capacity(strips.len());
    for strip in &strips {
        offsets.push(tags.write_data(&strip[..]).map_err(error)?);
        counts.push(strip.len() as u32);
    }
    let offsets: Vec<u32> = offsets
        .into_iter()
        .map(u32::try_from)
        .collect::<Result<_, _>>()
        .map_err(|_| "the TIFF is larger than 4 GiB (classic TIFF's offsets)".to_string())?;
    let colours = if channels >= 3 { 3 } else { 1 };
    let spp = channels as u16;
    (|| -> TiffResult<()> {
        tags.write_tag(Tag::ImageWidth, width)?;
        tags.write_tag(Tag::ImageLength, height)?;
        aligned_tag(&mut tags, Tag::BitsPerSample, &vec![bits; channels][..])?;
        tags.write_tag(Tag::Compression, DEFLATE)?;
        tags.write_tag(
            Tag::PhotometricInterpretation,
            if colours == 3 { 2u16 } else { 1 },
        )?;
        aligned_tag(&mut tags, Tag::StripOffsets, &offsets[..])?;
        tags.write_tag(Tag::SamplesPerPixel, spp)?;
        tags.write_tag(Tag::RowsPerStrip, rows_per_strip as u32)?;
        aligned_tag(&mut tags, Tag::StripByteCounts, &counts[..])?;
        tags.write_tag(Tag::PlanarConfiguration, 1u16)?;
        let predictor = if float { NO_PREDICTOR } else { HORIZONTAL };
        tags.write_tag(Tag::Predictor, predictor)?;
        if channels > colours {
            tags.write_tag(Tag::ExtraSamples, &[alpha_kind][..])?;
        }
        aligned_tag(&mut tags, Tag::SampleFormat, &vec![format; channels][..])?;
        // The profile UNDEFINED, as the ICC's TIFF embedding gives it (written BYTE,
        // `exiftool -validate` called it non-standard); XMP and the Photoshop blocks BYTE.
        for (tag, kind, block) in [
            (TIFF_ICC, Type::UNDEFINED, icc),
            (TIFF_XMP, Type::BYTE, xmp),
            (TIFF_PHOTOSHOP, Type::BYTE, resources.as_deref()),
        ] {
            if let Some(block) = block {
                tiff_meta::write_raw(&mut tags, tag, kind, block)?;
            }
        }
        if let Some(records) = records {
            let longs = tiff_meta::iptc_as_longs(records);
            tiff_meta::write_raw(&mut tags, TIFF_IPTC, Type::LONG, &longs)?;
        }
        // No resolution but the photo's (the tiff crate wrote 1 a unit, unitless); EXIF's
        // IFD0 may say one, and the photo's own goes over it (a JPEG's EXIF may say 72 dpi
        // beside the JFIF density it is shown at).
        let one = Rational { n: 1, d: 1 };
        aligned_tag(&mut tags, Tag::XResolution, one.clone())?;
        aligned_tag(&mut tags, Tag::YResolution, one)?;
        tags.write_tag(Tag::ResolutionUnit, 1u16)?;
        if let Some(exif) = &exif {
            tiff_meta::write_ifd0(&mut tags, exif, &pointers)?;
        }
        // What made the file, over the photo's own (`record`).
        if let Some(software) = software {
            aligned_tag(&mut tags, Tag::Software, software)?;
        }
        if let Some(resolution) = photo.and_then(|p| p.resolution.as_ref()) {
            let (x, y, unit) = resolution::to_tiff(resolution);
            aligned_tag(&mut tags, Tag::XResolution, x)?;
            aligned_tag(&mut tags, Tag::YResolution, y)?;
            tags.write_tag(Tag::ResolutionUnit, unit.to_u16())?;
        }
        word_align(&mut tags)?;
        tags.finish()
    })()
    .map_err(error)
}
