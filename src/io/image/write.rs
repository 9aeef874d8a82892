//! Writing a frame's colour as an 8/16-bit PNG, TIFF or JPEG that holds again what the photo
//! came with (`frame::Photo`): encoded with its profile's curves, the profile embedded, its
//! EXIF, XMP and IPTC carried over where the format has a place for them, its resolution in
//! the format's own place (pHYs, the TIFF tags, JFIF's density: `resolution`).
//!
//! Each format through its own encoder, for what image's encoders do not pass on:
//! - PNG (png crate): iCCP, eXIf, XMP as the iTXt chunk `XML:com.adobe.xmp`, and a PNG
//!   input's gAMA, cHRM, sRGB and cICP and text chunks (tEXt, zTXt, iTXt) again, each in its
//!   kind (a profile made from a cICP, or from gAMA and cHRM, `profile::profile_of`, goes
//!   out as those chunks, not as an iCCP; in a JPEG or TIFF, which have no such chunks, as
//!   the profile). IPTC is not written (PNG has no settled place for it).
//! - TIFF (`tiff_write`, the tiff crate's directory encoder): deflate with the horizontal
//!   predictor (lossless, and what every TIFF reader reads; LZW compresses photos less),
//!   `ExtraSamples` = 2 (unassociated alpha: the file holds straight alpha), the profile in
//!   tag 34675, XMP in tag 700, IPTC's datasets bare in tag 33723 (where exiftool writes them
//!   and libtiff's readers, OpenImageIO's among them, look) and any other Photoshop resources
//!   in tag 34377, every value and directory at a word boundary. EXIF is spread out as a TIFF holds it
//!   (`tiff_meta`): its descriptive IFD0 tags in the image's IFD0, its Exif and GPS
//!   directories as directories of their own that IFD0 points to.
//! - JPEG (jpeg-encoder): the quality asked for, the input's chroma subsampling (any of
//!   4:4:4, 4:4:0, 4:2:2, 4:2:0, 4:1:1, 4:4:1; 4:4:4 for a file that is not a JPEG), the
//!   profile in APP2 segments, EXIF and XMP in APP1, IPTC in APP13. No alpha (the colour is
//!   written premultiplied, as it is: composited over black, as oiiotool and a compositor
//!   write RGBA into a JPEG, so light where alpha is 0 stays; the run says the alpha was
//!   left out), 8 bits only.
//!
//! Straight colour is premultiplied colour over its alpha where alpha is above 0; where it
//! is 0 the colour is written as it is (premultiplied light of no coverage: a glow, an
//! additive effect), as oiiotool writes it, not made black.
//!
//! A grey input (with its Gray profile, if any) goes out grey while its three planes stay
//! equal ([`goes_out_grey`]). A float TIFF is written by `--bit-depth 32` (the default for a
//! float TIFF input to a TIFF): linear light, premultiplied, its alpha declared associated, as
//! float TIFFs are read.

use std::io::{Seek, Write};

use crate::frame::{Photo, PngColour};

use super::profile::{profile_is_made, profile_of, Transfer};
use super::record;
use super::resolution;
use super::tiff_write::{write_tiff, Samples};
use super::ImageFormat;

/// How a photo is written.
#[derive(Clone, Copy, Debug)]
pub struct PhotoOptions<'a> {
    /// Bits per sample: 8 or 16 (PNG, TIFF; JPEG is always 8), or 32, float (TIFF only).
    pub bits: u8,
    /// Write the values as they are (`--linear`), not through the profile's curves.
    pub linear: bool,
    /// JPEG quality, 1 to 100.
    pub jpeg_quality: u8,
    /// What the input photo held, to hold again.
    pub photo: Option<&'a Photo>,
    /// The profile of the codes of a frame that carries no photo (an EXR's `chromaticities`
    /// as a profile: `profile::primaries_profile`), embedded as a photo's is.
    pub icc: Option<&'a [u8]>,
    /// The settings that made the frame, as `shutter blur` flags (`record`: where each
    /// format keeps them); empty: none recorded.
    pub record: &'a str,
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

/// Whether a frame goes out grey: its input was grey, the format holds grey with the alpha
/// that goes out with it (the tiff crate writes no grey with alpha, integer or float), and
/// its three planes are still equal (the blur gives each the same weights).
pub fn goes_out_grey(
    photo: Option<&Photo>,
    format: ImageFormat,
    rgb: [&[f32]; 3],
    alpha: bool,
) -> bool {
    let alpha = alpha && format != ImageFormat::Jpeg;
    photo.is_some_and(|p| p.grey)
        && !(alpha && format == ImageFormat::Tiff)
        && rgb[0] == rgb[1]
        && rgb[1] == rgb[2]
}

/// How far beyond [0, 1] straight colour may go and still count as within it: more than
/// the rounding of the blur's weighted sums (about 10⁻⁶), less than any highlight worth
/// saying is clipped.
const CLIP_SLACK: f32 = 1e-3;

/// Whether straight colour (premultiplied colour over its alpha) goes above 1, and below 0,
/// by more than [`CLIP_SLACK`]: what an integer output clips.
pub fn out_of_range(rgb: [&[f32]; 3], alpha: Option<&[f32]>) -> (bool, bool) {
    let (mut above, mut below) = (false, false);
    for plane in rgb {
        for (i, &v) in plane.iter().enumerate() {
            // Where alpha is 0 the colour is written as it is ([`write_photo`]).
            let a = alpha.map_or(1.0, |a| written_alpha(a[i]));
            let a = if a > 0.0 { a } else { 1.0 };
            above |= v > (1.0 + CLIP_SLACK) * a;
            below |= v < -CLIP_SLACK * a;
        }
    }
    (above, below)
}

/// Writes premultiplied linear colour as an integer image with straight alpha (or a float
/// TIFF, premultiplied). JPEG has no alpha and no 16-bit: it is written 8-bit, its colour
/// premultiplied (over black).
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
    let kept_alpha = if jpeg { None } else { alpha };
    let float = options.bits == 32 && format == ImageFormat::Tiff;
    let sixteen_bit = options.bits == 16 && !jpeg;
    let photo = options.photo;
    let grey = goes_out_grey(photo, format, rgb, alpha.is_some());
    let profile = photo.and_then(|p| profile_of(p, grey));
    let transfer = Transfer::of(profile.as_deref());
    // A profile goes out where it describes what is written: an RGB one with RGB, a Gray one
    // with grey; in a float TIFF, only a float input's own (an 8/16-bit photo's describes
    // codes, not the linear light a float TIFF holds). One made from a PNG's gAMA and cHRM
    // goes into a PNG as those chunks again (`write_png`), not as an iCCP.
    let made = photo.is_some_and(profile_is_made);
    let icc = profile.as_deref().filter(|_| match (float, grey) {
        (true, true) => transfer.grey && photo.is_some_and(|p| p.bits == 32),
        (true, false) => transfer.embeds && photo.is_some_and(|p| p.bits == 32),
        (false, true) => transfer.grey,
        (false, false) => transfer.embeds,
    });
    // A float TIFF of an 8/16-bit photo holds linear light in the photo's primaries: a
    // linear profile of them (where its profile gives them).
    let linear = (float && !grey && transfer.embeds && photo.is_some_and(|p| p.bits != 32))
        .then(|| {
            profile
                .as_deref()
                .and_then(super::profile::linear_profile_of)
        })
        .flatten();
    let icc = linear.as_deref().or(icc);
    // Into a PNG, a made profile goes out as the chunks it was made from; beside a cICP,
    // the iCCP the PNG came with goes out again as it came, where it describes what is
    // written (one from gAMA and cHRM had none).
    let icc = if made && format == ImageFormat::Png {
        photo.and_then(|p| p.icc.as_deref()).filter(|own| {
            let own = Transfer::of(Some(own));
            if grey {
                own.grey
            } else {
                own.embeds
            }
        })
    } else {
        icc
    };
    let icc = icc.or(options.icc.filter(|_| photo.is_none()));
    let (w, h) = (width as u32, height as u32);
    let n = width * height;
    // What made the frame, in the TIFF's Software tag and the JPEG's comment (`record`).
    let software = Some(options.record)
        .filter(|r| !r.is_empty())
        .map(|r| record::software(r, format));
    let software = software.as_deref();
    if float {
        // Grey (one channel: a grey input goes out with no alpha in a TIFF), or RGB(A).
        let colours = if grey { 1 } else { 3 };
        let channels = colours + usize::from(kept_alpha.is_some());
        let mut samples = vec![0f32; n * channels];
        for (i, pixel) in samples.chunks_exact_mut(channels).enumerate() {
            for (sample, plane) in pixel[..colours].iter_mut().zip(rgb) {
                *sample = plane[i];
            }
            if let Some(a) = kept_alpha {
                pixel[colours] = a[i];
            }
        }
        let samples = Samples::Float(&samples);
        return write_tiff(writer, w, h, channels, samples, icc, photo, software);
    }
    let transfer = if options.linear {
        Transfer::linear()
    } else {
        transfer
    };
    let max = if sixteen_bit { 65535 } else { 255 };
    let encoder = transfer.encoder(max);
    let colours = if grey { 1 } else { 3 };
    let channels = colours + usize::from(kept_alpha.is_some());
    let mut codes = vec![0u16; n * channels];
    for i in 0..n {
        let a = alpha.map_or(1.0, |a| written_alpha(a[i]));
        // Unpremultiply where alpha is above 0, as oiiotool does; where it is 0 the colour
        // stays as it is (light of no coverage), or what alpha 0 hid there in the input
        // (below). A JPEG, which leaves the alpha out, holds the colour over black.
        let unpremultiply = if a > 0.0 { 1.0 / a } else { 1.0 };
        for c in 0..colours {
            let v = if kept_alpha.is_some() {
                rgb[c][i] * unpremultiply
            } else {
                rgb[c][i]
            };
            codes[i * channels + c] = encoder.encode(v, c) as u16;
        }
        if kept_alpha.is_some() {
            codes[i * channels + colours] = (a * max as f32 + 0.5) as u16;
        }
    }
    // Where alpha 0 hid a colour in the input and nothing covers the pixel now, that colour
    // again (the loop above wrote 0).
    if let (Some(hidden), Some(alpha)) = (photo.and_then(|p| p.hidden.as_ref()), kept_alpha) {
        if (hidden.width, hidden.height) == (width, height) {
            for &(i, colour) in &hidden.pixels {
                let i = i as usize;
                if written_alpha(alpha[i]) == 0.0 {
                    for c in 0..colours {
                        codes[i * channels + c] = encoder.encode(colour[c], c) as u16;
                    }
                }
            }
        }
    }
    match format {
        ImageFormat::Png => {
            let png = PngImage {
                width: w,
                height: h,
                channels,
                sixteen_bit,
                codes: &codes,
            };
            write_png(writer, png, icc, photo, options.record)
        }
        ImageFormat::Tiff => {
            let samples = Samples::Codes(&codes, sixteen_bit);
            write_tiff(writer, w, h, channels, samples, icc, photo, software)
        }
        ImageFormat::Jpeg => {
            let bytes: Vec<u8> = codes.iter().map(|&c| c as u8).collect();
            let jpeg = JpegImage {
                width: w,
                height: h,
                samples: &bytes,
                grey,
            };
            write_jpeg(writer, jpeg, options.jpeg_quality, icc, photo, software)
        }
    }
}

/// The alpha an integer image holds for `a`: clamped to [0, 1], not finite as 0.
fn written_alpha(a: f32) -> f32 {
    if a.is_finite() {
        a.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// A JPEG's pixels: 8-bit RGB, or grey.
struct JpegImage<'a> {
    width: u32,
    height: u32,
    samples: &'a [u8],
    grey: bool,
}

/// A PNG's samples: `channels` a pixel, 8- or 16-bit codes.
struct PngImage<'a> {
    width: u32,
    height: u32,
    channels: usize,
    sixteen_bit: bool,
    codes: &'a [u16],
}

fn write_png(
    writer: impl Write,
    image: PngImage,
    icc: Option<&[u8]>,
    photo: Option<&Photo>,
    settings: &str,
) -> Result<(), String> {
    let PngImage {
        width,
        height,
        channels,
        sixteen_bit,
        codes,
    } = image;
    let mut info = png::Info::with_size(width, height);
    info.color_type = match channels {
        1 => png::ColorType::Grayscale,
        2 => png::ColorType::GrayscaleAlpha,
        3 => png::ColorType::Rgb,
        _ => png::ColorType::Rgba,
    };
    info.bit_depth = if sixteen_bit {
        png::BitDepth::Sixteen
    } else {
        png::BitDepth::Eight
    };
    info.icc_profile = icc.map(Into::into);
    if let Some(colour) = photo.and_then(|p| p.png_colour) {
        png_colour(&mut info, &colour);
    }
    info.pixel_dims = photo
        .and_then(|p| p.resolution.as_ref())
        .map(resolution::to_png);
    info.exif_metadata = photo.and_then(|p| p.exif.as_deref()).map(Into::into);
    let mut encoder = png::Encoder::with_info(writer, info).map_err(|e| e.to_string())?;
    if let Some(xmp) = photo.and_then(|p| p.xmp.as_deref()) {
        let text = String::from_utf8_lossy(xmp).into_owned();
        encoder
            .add_itxt_chunk(PNG_XMP_KEYWORD.into(), text)
            .map_err(|e| e.to_string())?;
    }
    // What made the frame (`record`), in place of what a PNG shutter made said of it.
    let ours = [
        (record::PNG_VERSION, env!("CARGO_PKG_VERSION")),
        (record::PNG_SETTINGS, settings),
    ];
    let mut international = Vec::new();
    if !settings.is_empty() {
        for (keyword, text) in ours {
            let latin1 = text
                .chars()
                .all(|c| matches!(c, ' '..='~' | '\u{a1}'..='\u{ff}'));
            if latin1 {
                encoder
                    .add_text_chunk(keyword.into(), text.into())
                    .map_err(|e| e.to_string())?;
            } else {
                international.push(png::text_metadata::ITXtChunk::new(keyword, text));
            }
        }
    }
    // The input PNG's text chunks, each in its own kind (one the encoder refuses, a keyword
    // over 79 bytes say, is left out rather than losing the frame).
    let carried = photo.map_or(&[][..], |p| &p.texts[..]).iter();
    for t in carried.filter(|t| settings.is_empty() || !ours.iter().any(|o| o.0 == t.keyword)) {
        use crate::frame::TextKind;
        let (keyword, text) = (t.keyword.clone(), t.text.clone());
        let _ = match t.kind {
            TextKind::Latin1 => encoder.add_text_chunk(keyword, text),
            TextKind::Compressed => encoder.add_ztxt_chunk(keyword, text),
            TextKind::International => {
                // With its language tag and translated keyword, as it came.
                let mut chunk = png::text_metadata::ITXtChunk::new(keyword, text);
                chunk.language_tag = t.language.clone();
                chunk.translated_keyword = t.translated.clone();
                international.push(chunk);
                Ok(())
            }
        };
    }
    let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
    for chunk in &international {
        let _ = writer.write_text_chunk(chunk);
    }
    // The input's cICP as it came, before the image data (PNG 3rd ed., 5.6): the png crate
    // reads it but does not write it.
    if let Some(cicp) = photo.and_then(|p| p.png_colour?.cicp) {
        writer
            .write_chunk(png::chunk::cICP, &cicp)
            .map_err(|e| e.to_string())?;
    }
    // PNG stores 16-bit samples big-endian.
    let bytes: Vec<u8> = if sixteen_bit {
        codes.iter().flat_map(|c| c.to_be_bytes()).collect()
    } else {
        codes.iter().map(|&c| c as u8).collect()
    };
    writer.write_image_data(&bytes).map_err(|e| e.to_string())?;
    writer.finish().map_err(|e| e.to_string())
}

/// A PNG input's gAMA, cHRM and sRGB, as they came, on a PNG output's `info`. The sRGB chunk
/// goes out only where no iCCP does (the png crate writes no iCCP beside one, and a PNG
/// should not hold both); beside it, gAMA and cHRM go out where they are sRGB's own values.
fn png_colour(info: &mut png::Info, colour: &PngColour) {
    use png::{ScaledFloat, SourceChromaticities};
    info.source_gamma = colour.gamma.map(ScaledFloat::from_scaled);
    info.source_chromaticities = colour.chromaticities.map(|c| {
        let xy = |i: usize| {
            (
                ScaledFloat::from_scaled(c[i]),
                ScaledFloat::from_scaled(c[i + 1]),
            )
        };
        SourceChromaticities {
            white: xy(0),
            red: xy(2),
            green: xy(4),
            blue: xy(6),
        }
    });
    if info.icc_profile.is_none() {
        info.srgb = colour.srgb.and_then(|intent| match intent {
            0 => Some(png::SrgbRenderingIntent::Perceptual),
            1 => Some(png::SrgbRenderingIntent::RelativeColorimetric),
            2 => Some(png::SrgbRenderingIntent::Saturation),
            3 => Some(png::SrgbRenderingIntent::AbsoluteColorimetric),
            _ => None,
        });
    }
}

fn write_jpeg(
    mut writer: impl Write,
    image: JpegImage,
    quality: u8,
    icc: Option<&[u8]>,
    photo: Option<&Photo>,
    comment: Option<&str>,
) -> Result<(), String> {
    use jpeg_encoder::{ChromaSubsamplingMethod, ColorType, Encoder, SamplingFactor};
    let error = |e: jpeg_encoder::EncodingError| e.to_string();
    let (width, height) = (image.width, image.height);
    // The preflight refuses a frame larger than this (`ImageFormat::most_a_side`).
    let (Ok(w), Ok(h)) = (u16::try_from(width), u16::try_from(height)) else {
        return Err(format!(
            "{width}x{height} is larger than JPEG allows (65535 a side)"
        ));
    };
    // Made whole first: the encoder writes no comment, which goes in after its APP segments.
    let mut bytes = Vec::new();
    let mut encoder = Encoder::new(&mut bytes, quality);
    let sampling = photo
        .and_then(|p| p.sampling)
        .and_then(|(h, v)| SamplingFactor::from_factors(h, v))
        .unwrap_or(SamplingFactor::R_4_4_4);
    encoder.set_sampling_factor(sampling);
    // Each chroma sample the mean of the pixels it stands for, as libjpeg makes it: the
    // encoder's default keeps the block's top-left pixel, which moves the chroma half a pixel
    // (on a gradient, Cb +2.4 codes a pass, +20 after five).
    encoder.set_chroma_subsampling_method(ChromaSubsamplingMethod::Average);
    if let Some(resolution) = photo.and_then(|p| p.resolution.as_ref()) {
        encoder.set_density(resolution::to_jfif(resolution));
    }
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
    let color = if image.grey {
        ColorType::Luma
    } else {
        ColorType::Rgb
    };
    encoder.encode(image.samples, w, h, color).map_err(error)?;
    if let Some(comment) = comment {
        bytes = record::with_jpeg_comment(bytes, comment);
    }
    writer.write_all(&bytes).map_err(|e| e.to_string())
}
