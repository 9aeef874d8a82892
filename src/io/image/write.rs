//! Writing a frame's colour as an 8/16-bit PNG, TIFF or JPEG that holds again what the photo
//! came with (`frame::Photo`): encoded with its profile's curves, the profile embedded, its
//! EXIF, XMP and IPTC carried over where the format has a place for them.
//!
//! Each format through its own encoder, for what image's encoders do not pass on:
//! - PNG (png crate): iCCP, eXIf, XMP as the iTXt chunk `XML:com.adobe.xmp`, and a PNG
//!   input's text chunks (tEXt, zTXt, iTXt) again, each in its kind. IPTC is not written (PNG
//!   has no settled place for it).
//! - TIFF (tiff crate): deflate with the horizontal predictor (lossless, and what every TIFF
//!   reader reads; LZW compresses photos less), `ExtraSamples` = 2 (unassociated alpha: the
//!   file holds straight alpha), the profile in tag 34675, XMP in tag 700, IPTC's datasets
//!   bare in tag 33723 (where exiftool writes them and libtiff's readers, OpenImageIO's among
//!   them, look) and any other Photoshop resources in tag 34377, each value at a word
//!   boundary (the encoder's own tags are not always). EXIF is spread out as a TIFF holds it
//!   (`tiff_meta`): its descriptive IFD0 tags in the image's IFD0, its Exif and GPS
//!   directories as directories of their own that IFD0 points to.
//! - JPEG (jpeg-encoder): the quality asked for, the input's chroma subsampling (any of
//!   4:4:4, 4:4:0, 4:2:2, 4:2:0, 4:1:1, 4:4:1; 4:4:4 for a file that is not a JPEG), the
//!   profile in APP2 segments, EXIF and XMP in APP1, IPTC in APP13. No alpha, 8 bits only.

use std::io::{Seek, Write};

use crate::frame::Photo;

use super::profile::Transfer;
use super::tiff_meta;
use super::ImageFormat;

/// How a photo is written.
#[derive(Clone, Copy, Debug)]
pub struct PhotoOptions<'a> {
    /// 16 bits per sample (PNG, TIFF), else 8.
    pub sixteen_bit: bool,
    /// Write the values as they are (`--linear`), not through the profile's curves.
    pub linear: bool,
    /// JPEG quality, 1 to 100.
    pub jpeg_quality: u8,
    /// What the input photo held, to hold again.
    pub photo: Option<&'a Photo>,
}

/// The XMP packet's keyword in a PNG iTXt chunk (XMP specification part 3, 1.1.5).
pub(super) const PNG_XMP_KEYWORD: &str = "XML:com.adobe.xmp";

/// The header of XMP in a JPEG APP1 segment, and of Photoshop resource blocks in APP13.
const JPEG_XMP_HEADER: &[u8] = b"http://ns.adobe.com/xap/1.0/\0";
const JPEG_IPTC_HEADER: &[u8] = b"Photoshop 3.0\0";

/// The most an APPn segment of a JPEG holds after its marker and length: 65535 − 2.
const JPEG_SEGMENT_ROOM: usize = 65533;

/// The blocks of a photo too large for the one JPEG segment each goes in (EXIF, XMP, IPTC
/// over 64 KB: a PNG's eXIf or a long edit history's XMP), with their sizes in bytes: a JPEG
/// output leaves them out (Extended XMP, split over segments, is not written), and the run
/// warns. The profile is split over as many segments as it needs.
pub fn jpeg_left_out(photo: &Photo) -> Vec<(&'static str, usize)> {
    let exif = photo
        .exif
        .as_deref()
        .map(|e| e.strip_prefix(b"Exif\0\0").unwrap_or(e));
    [
        ("EXIF", exif.map(|e| e.len() + 6)),
        (
            "XMP",
            photo.xmp.as_ref().map(|x| x.len() + JPEG_XMP_HEADER.len()),
        ),
        (
            "IPTC",
            photo
                .iptc
                .as_ref()
                .map(|i| i.len() + JPEG_IPTC_HEADER.len()),
        ),
    ]
    .into_iter()
    .filter_map(|(name, size)| size.filter(|&n| n > JPEG_SEGMENT_ROOM).map(|n| (name, n)))
    .collect()
}

/// The TIFF tags of what a photo carries: its ICC profile (ICC.1, annex B.4), XMP (Adobe XMP
/// part 3, 1.1.6), Photoshop image resources (TIFF/EP) and bare IPTC (IPTC-NAA, TIFF/EP).
const TIFF_ICC: u16 = 34675;
const TIFF_XMP: u16 = 700;
const TIFF_PHOTOSHOP: u16 = 34377;
const TIFF_IPTC: u16 = 33723;

/// `ExtraSamples` value for unassociated (straight) alpha (TIFF 6.0, section 18).
const UNASSOCIATED_ALPHA: u16 = 2;

/// Writes premultiplied linear colour as an integer image with straight alpha. JPEG has no
/// alpha and no 16-bit: it is written 8-bit RGB.
#[allow(clippy::too_many_arguments)]
pub fn write_photo(
    writer: impl Write + Seek,
    format: ImageFormat,
    width: usize,
    height: usize,
    rgb: [&[f32]; 3],
    alpha: Option<&[f32]>,
    options: &PhotoOptions,
) -> Result<(), String> {
    let jpeg = format == ImageFormat::Jpeg;
    let alpha = if jpeg { None } else { alpha };
    let sixteen_bit = options.sixteen_bit && !jpeg;
    let icc = options.photo.and_then(|p| p.icc.as_deref());
    let transfer = Transfer::of(icc);
    let icc = icc.filter(|_| transfer.embeds);
    let transfer = if options.linear {
        Transfer::linear()
    } else {
        transfer
    };
    let max = if sixteen_bit { 65535 } else { 255 };
    let encoder = transfer.encoder(max);
    let channels = if alpha.is_some() { 4 } else { 3 };
    let n = width * height;
    let mut codes = vec![0u16; n * channels];
    for i in 0..n {
        let a = alpha.map_or(1.0, |a| {
            let a = a[i];
            if a.is_finite() {
                a.clamp(0.0, 1.0)
            } else {
                0.0
            }
        });
        // Unpremultiply; where alpha is 0 the colour is 0.
        let unpremultiply = if a > 0.0 { 1.0 / a } else { 0.0 };
        for c in 0..3 {
            let v = if alpha.is_some() {
                rgb[c][i] * unpremultiply
            } else {
                rgb[c][i]
            };
            codes[i * channels + c] = encoder.encode(v, c) as u16;
        }
        if alpha.is_some() {
            codes[i * channels + 3] = (a * max as f32 + 0.5) as u16;
        }
    }
    let (w, h) = (width as u32, height as u32);
    let photo = options.photo;
    match format {
        ImageFormat::Png => write_png(writer, w, h, channels, sixteen_bit, &codes, icc, photo),
        ImageFormat::Tiff => write_tiff(writer, w, h, channels, sixteen_bit, &codes, icc, photo),
        ImageFormat::Jpeg => {
            let bytes: Vec<u8> = codes.iter().map(|&c| c as u8).collect();
            write_jpeg(writer, w, h, &bytes, options.jpeg_quality, icc, photo)
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn write_png(
    writer: impl Write,
    width: u32,
    height: u32,
    channels: usize,
    sixteen_bit: bool,
    codes: &[u16],
    icc: Option<&[u8]>,
    photo: Option<&Photo>,
) -> Result<(), String> {
    let mut info = png::Info::with_size(width, height);
    info.color_type = if channels == 4 {
        png::ColorType::Rgba
    } else {
        png::ColorType::Rgb
    };
    info.bit_depth = if sixteen_bit {
        png::BitDepth::Sixteen
    } else {
        png::BitDepth::Eight
    };
    info.icc_profile = icc.map(Into::into);
    info.exif_metadata = photo.and_then(|p| p.exif.as_deref()).map(Into::into);
    let mut encoder = png::Encoder::with_info(writer, info).map_err(|e| e.to_string())?;
    if let Some(xmp) = photo.and_then(|p| p.xmp.as_deref()) {
        let text = String::from_utf8_lossy(xmp).into_owned();
        encoder
            .add_itxt_chunk(PNG_XMP_KEYWORD.into(), text)
            .map_err(|e| e.to_string())?;
    }
    // The input PNG's text chunks, each in its own kind (one the encoder refuses, a keyword
    // over 79 bytes say, is left out rather than losing the frame).
    for t in photo.map_or(&[][..], |p| &p.texts[..]) {
        use crate::frame::TextKind;
        let (keyword, text) = (t.keyword.clone(), t.text.clone());
        let _ = match t.kind {
            TextKind::Latin1 => encoder.add_text_chunk(keyword, text),
            TextKind::Compressed => encoder.add_ztxt_chunk(keyword, text),
            TextKind::International => encoder.add_itxt_chunk(keyword, text),
        };
    }
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    // PNG stores 16-bit samples big-endian.
    let bytes: Vec<u8> = if sixteen_bit {
        codes.iter().flat_map(|c| c.to_be_bytes()).collect()
    } else {
        codes.iter().map(|&c| c as u8).collect()
    };
    writer.write_image_data(&bytes).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

#[allow(clippy::too_many_arguments)]
fn write_tiff(
    writer: impl Write + Seek,
    width: u32,
    height: u32,
    channels: usize,
    sixteen_bit: bool,
    codes: &[u16],
    icc: Option<&[u8]>,
    photo: Option<&Photo>,
) -> Result<(), String> {
    use tiff::encoder::{colortype, Compression, DeflateLevel, Predictor, TiffEncoder};
    use tiff::tags::{Tag, Type};
    let error = |e: tiff::TiffError| e.to_string();
    let mut encoder = TiffEncoder::new(writer)
        .map_err(error)?
        .with_compression(Compression::Deflate(DeflateLevel::Balanced))
        .with_predictor(Predictor::Horizontal);
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
    // The tags beside the pixels: alpha declared, then what the photo came with.
    macro_rules! write_image {
        ($color:ty, $data:expr) => {{
            let mut image = encoder.new_image::<$color>(width, height).map_err(error)?;
            let tags = image.encoder();
            if channels == 4 {
                tags.write_tag(Tag::ExtraSamples, &[UNASSOCIATED_ALPHA][..])
                    .map_err(error)?;
            }
            for (tag, block) in [
                (TIFF_ICC, icc),
                (TIFF_XMP, xmp),
                (TIFF_PHOTOSHOP, resources.as_deref()),
            ] {
                if let Some(block) = block {
                    tiff_meta::write_raw(tags, tag, Type::BYTE, block).map_err(error)?;
                }
            }
            if let Some(records) = records {
                let longs = tiff_meta::iptc_as_longs(records);
                tiff_meta::write_raw(tags, TIFF_IPTC, Type::LONG, &longs).map_err(error)?;
            }
            if let Some(exif) = &exif {
                tiff_meta::write_ifd0(tags, exif, &pointers).map_err(error)?;
            }
            image.write_data($data).map_err(error)
        }};
    }
    let bytes = || codes.iter().map(|&c| c as u8).collect::<Vec<u8>>();
    match (channels, sixteen_bit) {
        (3, false) => write_image!(colortype::RGB8, &bytes()),
        (4, false) => write_image!(colortype::RGBA8, &bytes()),
        (3, true) => write_image!(colortype::RGB16, codes),
        _ => write_image!(colortype::RGBA16, codes),
    }
}

fn write_jpeg(
    writer: impl Write,
    width: u32,
    height: u32,
    rgb: &[u8],
    quality: u8,
    icc: Option<&[u8]>,
    photo: Option<&Photo>,
) -> Result<(), String> {
    use jpeg_encoder::{ColorType, Encoder, SamplingFactor};
    let error = |e: jpeg_encoder::EncodingError| e.to_string();
    let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
        return Err(format!(
            "{width}x{height} is larger than JPEG allows (65535 a side)"
        ));
    };
    let mut encoder = Encoder::new(writer, quality);
    let sampling = photo
        .and_then(|p| p.sampling)
        .and_then(|(h, v)| SamplingFactor::from_factors(h, v))
        .unwrap_or(SamplingFactor::R_4_4_4);
    encoder.set_sampling_factor(sampling);
    // EXIF first (readers look for it right after the JFIF header), then XMP, the profile
    // and IPTC; a block one segment cannot hold is left out (`jpeg_left_out`: the run warns),
    // not the frame.
    let left_out = photo.map(jpeg_left_out).unwrap_or_default();
    let kept = |name: &str| !left_out.iter().any(|(block, _)| *block == name);
    if let Some(exif) = photo
        .and_then(|p| p.exif.as_deref())
        .filter(|_| kept("EXIF"))
    {
        let exif = exif.strip_prefix(b"Exif\0\0").unwrap_or(exif);
        encoder.add_exif_metadata(exif).map_err(error)?;
    }
    if let Some(xmp) = photo.and_then(|p| p.xmp.as_deref()).filter(|_| kept("XMP")) {
        encoder
            .add_app_segment(1, [JPEG_XMP_HEADER, xmp].concat())
            .map_err(error)?;
    }
    if let Some(icc) = icc {
        encoder.add_icc_profile(icc).map_err(error)?;
    }
    if let Some(iptc) = photo
        .and_then(|p| p.iptc.as_deref())
        .filter(|_| kept("IPTC"))
    {
        encoder
            .add_app_segment(13, [JPEG_IPTC_HEADER, iptc].concat())
            .map_err(error)?;
    }
    encoder.encode(rgb, w, h, ColorType::Rgb).map_err(error)
}
