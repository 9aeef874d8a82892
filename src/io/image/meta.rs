//! What a photo holds besides its pixels, read so that the output can hold it again
//! (`frame::Photo`): the ICC profile (JPEG APP2, PNG iCCP, TIFF tag 34675), EXIF (JPEG APP1,
//! PNG eXIf, a TIFF's IFD0 tags and Exif and GPS directories gathered into that form by
//! `tiff_meta`), XMP (JPEG APP1, PNG iTXt, TIFF tag 700), IPTC (JPEG APP13 and TIFF tag 34377
//! as Photoshop resource blocks, a TIFF's bare tag 33723 wrapped as one), the resolution
//! (`resolution`), the bits per sample and a JPEG's chroma subsampling.
//!
//! The pixels are turned upright on read (`read_planes`, by the orientation the image crate
//! reads from EXIF or the TIFF tag), so the frame holds the upright photo and the EXIF and XMP
//! carried with it say orientation 1: written again as they are, they describe the upright
//! pixels of the output, and no viewer turns them a second time. The EXIF and XMP are made
//! true of the upright pixels besides (`upright`): their size, each axis's resolution, no
//! thumbnail of the unturned view.
//!
//! Not read: a PNG's IPTC (a hex text chunk of no settled form: it comes through as the text
//! chunk it is). A PNG's text chunks (tEXt, zTXt, iTXt) are read with the png crate, whose
//! decoder the image crate does not expose for them; so are an eXIf and an XMP iTXt after the
//! image data, where the image crate does not look ([`png_info`]).

use std::path::Path;

use image::ImageDecoder;

use crate::frame::{Photo, PngColour, Resolution};

/// Reads the profile and metadata of an 8/16-bit image, without decoding its pixels, and sets
/// the orientation its EXIF and XMP record to 1 (upright, as `read_planes` delivers it), its
/// EXIF made true of the upright pixels (`upright::make_upright`).
pub fn read_photo(path: &Path) -> Result<Photo, String> {
    let mut reader = crate::io::image::input_reader(path)?
        .with_guessed_format()
        .map_err(|e| e.to_string())?;
    // The profile and metadata chunks inflated, and nothing else: capped as the probe caps
    // them.
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(crate::io::image::HEADER_ROOM);
    reader.limits(limits);
    let jpeg = reader.format() == Some(image::ImageFormat::Jpeg);
    let tiff = reader.format() == Some(image::ImageFormat::Tiff);
    let png = reader.format() == Some(image::ImageFormat::Png);
    // A PNG's chunks read once (those after its image data too), for its texts, colour
    // chunks, resolution, and an eXIf or XMP the image crate does not see.
    let png_header = png.then(|| png_info(path, false)).flatten();
    let (texts, png_colour, mut resolution) = match &png_header {
        Some(info) => png_chunks(path, info),
        None => (Vec::new(), None, None),
    };
    let mut decoder = match reader.into_decoder() {
        Ok(decoder) => decoder,
        Err(e) => {
            // A grey, palette or YCbCr TIFF the image crate refuses, which the tiff crate
            // reads (`tiff_float`).
            let header = tiff.then(|| super::tiff_float::header(path)).flatten();
            return header
                .map(|header| grey_float_photo(path, &header))
                .ok_or_else(|| e.to_string());
        }
    };
    // How `read_planes` turns the pixels, and the size it gives them.
    let turn = super::orientation(&mut decoder, path, png);
    let size = super::upright(decoder.dimensions(), turn);
    let orientation = turn.to_exif();
    let color = decoder.color_type();
    let bits = (color.bytes_per_pixel() / color.channel_count()) * 8;
    // A block that cannot be read is left out, not a reason to refuse the photo.
    let mut exif = decoder.exif_metadata().ok().flatten();
    let mut xmp = decoder.xmp_metadata().ok().flatten();
    let (mut icc, mut iptc) = (decoder.icc_profile().ok().flatten(), None);
    let (mut extra, mut more_images) = (None, false);
    if jpeg {
        iptc = decoder.iptc_metadata().ok().flatten();
    }
    if png_header.is_some() && (exif.is_none() || xmp.is_none()) {
        // An eXIf or an XMP iTXt after the image data, where the image crate does not look.
        if let Some(info) = png_header {
            if exif.is_none() {
                exif = info.exif_metadata.map(|e| e.into_owned());
            }
            if xmp.is_none() {
                xmp = info
                    .utf8_text
                    .iter()
                    .find(|t| t.keyword == super::write::PNG_XMP_KEYWORD)
                    .and_then(|t| t.get_text().ok())
                    .map(String::into_bytes);
            }
        }
    }
    if tiff {
        // The image crate's TIFF reader gives no profile stored as UNDEFINED (as exiftool
        // and Photoshop store it), refuses XMP under its limits and gives no EXIF: the tiff
        // crate reads them.
        ([icc, exif, xmp, iptc], extra, resolution, more_images) = tiff_blocks(path);
    }
    let (premultiplied, straight) = (extra == Some(1), extra == Some(2));
    if let Some(exif) = &mut exif {
        super::upright::make_upright(exif, orientation as u16, size);
    }
    if let Some(xmp) = &mut xmp {
        super::upright::make_xmp_upright(xmp, orientation as u16);
    }
    let bytes = jpeg
        .then(|| crate::io::input::read_input(path).ok())
        .flatten();
    let sampling = bytes.as_deref().and_then(super::jpeg::sampling);
    if let Some(bytes) = &bytes {
        resolution = super::resolution::jfif_density(bytes);
    }
    // Each axis's density goes with its axis.
    if let (Some(r), 5..=8) = (&mut resolution, orientation) {
        (r.x, r.y) = (r.y, r.x);
    }
    Ok(Photo {
        icc,
        exif,
        xmp,
        iptc,
        texts,
        bits,
        grey: color.channel_count() <= 2,
        sampling,
        png_colour,
        resolution,
        premultiplied,
        straight,
        more_images,
        hidden: None,
    })
}

/// What a grey, palette or YCbCr TIFF the image crate refuses ([`super::tiff_float`]) holds
/// besides its pixels, as [`read_photo`]
/// reads a TIFF's: its profile, EXIF, XMP and IPTC (the EXIF made true of the upright
/// pixels), its resolution, and whether its alpha is associated.
fn grey_float_photo(path: &Path, header: &super::tiff_float::Header) -> Photo {
    let ([icc, mut exif, mut xmp, iptc], extra, mut resolution, more_images) = tiff_blocks(path);
    let orientation = header.orientation.to_exif();
    let size = super::tiff_float::upright_size(header);
    if let Some(exif) = &mut exif {
        super::upright::make_upright(exif, orientation as u16, size);
    }
    if let Some(xmp) = &mut xmp {
        super::upright::make_xmp_upright(xmp, orientation as u16);
    }
    if let (Some(r), 5..=8) = (&mut resolution, orientation) {
        (r.x, r.y) = (r.y, r.x);
    }
    Photo {
        icc,
        exif,
        xmp,
        iptc,
        texts: Vec::new(),
        bits: if header.float { 32 } else { header.bits },
        grey: header.samples <= 2,
        sampling: None,
        png_colour: None,
        resolution,
        premultiplied: extra == Some(1),
        straight: extra == Some(2),
        more_images,
        hidden: None,
    }
}

/// A PNG's text chunks (before its image data, where writers put them, and after it), in file order, each
/// as its kind: tEXt, zTXt (inflated), iTXt (but XMP's, which is `Photo::xmp`); its gAMA,
/// cHRM, sRGB and cICP; and its pHYs. A chunk that cannot be read is left out; the decoder's
/// allocations are capped as the header's are.
fn png_chunks(
    path: &Path,
    info: &png::Info<'static>,
) -> (
    Vec<crate::frame::PngText>,
    Option<PngColour>,
    Option<Resolution>,
) {
    use crate::frame::{PngText, TextKind};
    // The three lists are kept apart by the decoder: file order within each kind.
    let mut texts: Vec<PngText> = info
        .uncompressed_latin1_text
        .iter()
        .map(|t| PngText {
            keyword: t.keyword.clone(),
            text: t.text.clone(),
            kind: TextKind::Latin1,
            language: String::new(),
            translated: String::new(),
        })
        .collect();
    texts.extend(info.compressed_latin1_text.iter().filter_map(|t| {
        Some(PngText {
            keyword: t.keyword.clone(),
            text: t.get_text().ok()?,
            kind: TextKind::Compressed,
            language: String::new(),
            translated: String::new(),
        })
    }));
    texts.extend(
        info.utf8_text
            .iter()
            .filter(|t| t.keyword != super::write::PNG_XMP_KEYWORD)
            .filter_map(|t| {
                Some(PngText {
                    keyword: t.keyword.clone(),
                    text: t.get_text().ok()?,
                    kind: TextKind::International,
                    language: t.language_tag.clone(),
                    translated: t.translated_keyword.clone(),
                })
            }),
    );
    let resolution = info.pixel_dims.and_then(super::resolution::png_density);
    let colour = PngColour {
        gamma: info.gama_chunk.map(|g| g.into_scaled()),
        chromaticities: info.chrm_chunk.map(|c| {
            let [w, r, g, b] = [c.white, c.red, c.green, c.blue];
            [w.0, w.1, r.0, r.1, g.0, g.1, b.0, b.1].map(|v| v.into_scaled())
        }),
        srgb: info.srgb.map(|intent| intent as u8),
        cicp: info.coding_independent_code_points.map(|c| {
            let full = u8::from(c.is_video_full_range_image);
            [
                c.color_primaries,
                c.transfer_function,
                c.matrix_coefficients,
                full,
            ]
        }),
        cicp_matrix_read_as_0: crate::io::input::open_input(path)
            .ok()
            .map(std::io::BufReader::new)
            .and_then(|mut file| super::png_mend::cicp_matrix(&mut file)),
    };
    let colour = (colour != PngColour::default()).then_some(colour);
    (texts, colour, resolution)
}

/// A TIFF's profile (tag 34675), EXIF (its IFD0's descriptive tags and the directories they
/// point to, as one block: `tiff_meta`), XMP (tag 700) and Photoshop resource blocks (tag
/// 34377, where IPTC sits beside its JPEG form; bare IPTC, tag 33723, wrapped as one where
/// they hold none), each as its bytes; its first extra sample's kind (ExtraSamples: 1
/// associated alpha, the colour premultiplied; 2 unassociated, straight); its resolution;
/// and whether it holds more images after its first.
#[allow(clippy::type_complexity)]
fn tiff_blocks(path: &Path) -> ([Option<Vec<u8>>; 4], Option<u16>, Option<Resolution>, bool) {
    use super::tiff_meta;
    use tiff::tags::{Tag, Type, ValueBuffer};
    let Ok(mut decoder) = crate::io::input::open_input(path)
        .map(std::io::BufReader::new)
        .map_err(tiff::TiffError::from)
        .and_then(tiff::decoder::Decoder::new)
    else {
        return ([None, None, None, None], None, None, false);
    };
    // Each value's bytes as stored, whatever its type (exiftool types tag 33723 LONG).
    let [icc, xmp, photoshop, bare] = [34675, 700, 34377, 33723].map(|tag| {
        let mut value = ValueBuffer::empty(Type::BYTE);
        let tag = Tag::from_u16_exhaustive(tag);
        let found = decoder.image_ifd().find_tag_buf(tag, &mut value).ok()??;
        (found.count() > 0).then(|| value.as_bytes().to_vec())
    });
    let iptc = match (photoshop, bare) {
        (Some(resources), _) if tiff_meta::iptc_records(&resources).is_some() => Some(resources),
        (resources, Some(records)) => {
            let mut resources = resources.unwrap_or_default();
            resources.extend(tiff_meta::iptc_resource(&records));
            Some(resources)
        }
        (resources, None) => resources,
    };
    let resolution = super::resolution::tiff_density(&mut decoder);
    let extra = decoder.find_tag_unsigned_vec::<u16>(Tag::ExtraSamples);
    let extra = extra.ok().flatten().and_then(|e| e.first().copied());
    let room = crate::io::image::HEADER_ROOM as usize;
    let exif = tiff_meta::exif_of_tiff(&mut decoder, room).map(|e| tiff_meta::to_block(&e));
    let more = decoder.more_images();
    ([icc, exif, xmp, iptc], extra, resolution, more)
}

/// A PNG's header chunks as the png crate reads them (`Info`): those before its image data,
/// and, where an eXIf, tEXt, zTXt or iTXt chunk follows the image data (libpng and exiftool
/// write them there; PNG allows text after IDAT, and readers take eXIf there too), those after
/// it as well, the image data read through and dropped. With `exif_only`, only an eXIf after
/// the image data is worth reading the file through for. `None` for a file that is not a
/// readable PNG. The decoder's allocations are capped as the header's are.
pub(super) fn png_info(path: &Path, exif_only: bool) -> Option<png::Info<'static>> {
    let late = late_chunks(path)?;
    let worth = if exif_only {
        late.contains(b"eXIf")
    } else {
        !late.is_empty()
    };
    let source = super::png_mend::source(path).ok()?;
    let limits = png::Limits {
        bytes: crate::io::image::HEADER_ROOM as usize,
    };
    let mut reader = png::Decoder::new_with_limits(source, limits)
        .read_info()
        .ok()?;
    let before = reader.info().clone();
    if !worth {
        return Some(before);
    }
    // A chunk after the image data that cannot be read (a second eXIf, a broken zTXt) leaves
    // those before it as they were read.
    match reader.finish() {
        Ok(()) => Some(reader.info().clone()),
        Err(_) => Some(before),
    }
}

/// The kinds of the metadata chunks (eXIf, tEXt, zTXt, iTXt) that follow a PNG's image data,
/// read from the chunks' heads alone (seeking past their data); `None` for a file that is not
/// a PNG or whose chunks cannot be walked.
fn late_chunks(path: &Path) -> Option<Vec<[u8; 4]>> {
    use std::io::{Read, Seek, SeekFrom};
    let mut file = std::io::BufReader::new(crate::io::input::open_input(path).ok()?);
    let mut head = [0u8; 8];
    file.read_exact(&mut head).ok()?;
    if head != *b"\x89PNG\r\n\x1a\n" {
        return None;
    }
    let (mut seen_data, mut late) = (false, Vec::new());
    loop {
        if file.read_exact(&mut head).is_err() {
            return Some(late);
        }
        let length = u32::from_be_bytes(head[..4].try_into().ok()?);
        let kind: [u8; 4] = head[4..].try_into().ok()?;
        match &kind {
            b"IEND" => return Some(late),
            b"IDAT" => seen_data = true,
            b"eXIf" | b"tEXt" | b"zTXt" | b"iTXt" if seen_data => late.push(kind),
            _ => {}
        }
        file.seek(SeekFrom::Current(i64::from(length) + 4)).ok()?;
    }
}

/// The EXIF block of a PNG whose only eXIf chunk follows its image data (the image crate
/// reads the chunks before it alone); `None` for any other file.
pub(super) fn late_png_exif(path: &Path) -> Option<Vec<u8>> {
    let info = png_info(path, true)?;
    info.exif_metadata.map(|e| e.into_owned())
}
