//! What writing a frame leaves out or changes, in words for the run's warnings: said before
//! it is written ([`output_notes`]: what a JPEG, PNG or TIFF cannot hold, values an integer
//! output clips) and, for what only writing finds (a DWA highlight capped),
//! [`crate::io::exr_dwa::capped_warning`].

use std::path::Path;

use crate::frame::Frame;
use crate::io::image::{self as image_io, ImageFormat};
use crate::io::output::{exr_picture_profile, picture_bits, OutputFormat, OutputOptions};

/// What writing `frame` to `path` leaves out or changes, in words for the run's warnings (the
/// caller names the output): blocks too large for a JPEG's segments, IPTC a PNG cannot
/// hold, values an integer
/// output clips (a float input's above all), an alpha a JPEG cannot hold, a profile that
/// cannot go with what is written, primaries an EXR cannot be told.
pub fn output_notes(path: &Path, frame: &Frame, options: &OutputOptions) -> Vec<String> {
    let (Some(format), Some(color)) = (OutputFormat::from_path(path), frame.color.as_ref()) else {
        return Vec::new();
    };
    let photo = frame.carried.photo.as_ref();
    let icc = photo.and_then(|p| p.icc.as_deref());
    let mut notes = Vec::new();
    let format = match format {
        OutputFormat::Image(format) => format,
        OutputFormat::Exr => {
            if icc.is_some_and(|icc| image_io::chromaticities(icc).is_none()) {
                notes.push(
                    "the input's ICC profile gives no RGB primaries (not an RGB matrix \
                     profile): the EXR holds no chromaticities, and readers take Rec. 709's"
                        .into(),
                );
            }
            return notes;
        }
    };
    if let (ImageFormat::Jpeg, Some(photo)) = (format, photo) {
        for (block, bytes) in image_io::jpeg_left_out(photo) {
            notes.push(format!(
                "the {block} the input holds ({} KB) is larger than a JPEG segment holds \
                 (64 KB): the JPEG output leaves it out (a PNG or TIFF output keeps it)",
                bytes.div_ceil(1024)
            ));
        }
    }
    // PNG has no settled place for IPTC (exiftool and libpng agree on none).
    if let (ImageFormat::Png, Some(iptc)) = (format, photo.and_then(|p| p.iptc.as_ref())) {
        notes.push(format!(
            "the input's IPTC ({} bytes: captions, keywords, credits) has no place in a PNG: \
             the output leaves it out (a TIFF or JPEG output keeps it)",
            iptc.len()
        ));
    }
    let bits = picture_bits(photo, format, options);
    if let Err(why) = exr_picture_profile(frame, format, bits, options) {
        notes.push(format!(
            "the EXR's chromaticities make no ICC profile ({why}): the picture carries none, \
             and readers take its codes for sRGB's"
        ));
    }
    let float_in = photo.is_some_and(|p| p.bits == 32);
    let float_out = bits == 32 && format == ImageFormat::Tiff;
    let rgb = [&color.r[..], &color.g[..], &color.b[..]];
    let alpha = color.a.as_deref();
    // A JPEG holds the colour premultiplied (over black), not over its alpha.
    let straight = alpha.filter(|_| format != ImageFormat::Jpeg);
    let (above, below) = image_io::out_of_range(rgb, straight);
    if !float_out && (above || below || float_in) {
        let clipped = match (above, below) {
            (true, true) => "values above 1 and below 0 are clipped",
            (true, false) => "values above 1 are clipped to 1",
            (false, true) => "values below 0 are clipped to 0",
            (false, false) => "its values (all within 0 to 1) are rounded to codes",
        };
        notes.push(if float_in {
            format!(
                "the colour file holds float values, which this {bits}-bit {} cannot: \
                 {clipped} (a .tif output, or --bit-depth 32, keeps them float; so does \
                 .exr)",
                format.name()
            )
        } else {
            format!(
                "{clipped} in this {bits}-bit {} (an .exr output keeps them)",
                format.name()
            )
        });
    }
    if format == ImageFormat::Jpeg && alpha.is_some_and(|a| a.iter().any(|&a| a < OPAQUE)) {
        notes.push(
            "JPEG holds no alpha: the alpha is left out, and the colour written as it is, \
             premultiplied: composited over black, as oiiotool and a compositor write it \
             (light where alpha is 0 stays); a .png or .tif output keeps the alpha"
                .into(),
        );
    }
    let transfer = icc.map(|icc| image_io::Transfer::of(Some(icc)));
    let grey = image_io::goes_out_grey(photo, format, rgb, alpha.is_some());
    if transfer.as_ref().is_some_and(|t| t.grey) && !grey {
        let why = if photo.is_some_and(|p| !p.grey) {
            "the colour file is RGB"
        } else if format == ImageFormat::Tiff && alpha.is_some() {
            "a TIFF of grey and alpha is not written"
        } else {
            "the frame's R, G and B differ"
        };
        notes.push(format!(
            "the input's Gray ICC profile is left out: this output is RGB ({why})"
        ));
    }
    // A grey photo carrying an RGB profile (a converter's slip): grey out, with no profile
    // (an RGB one does not describe grey), said (an outside probe: dropped without a word).
    if transfer.as_ref().is_some_and(|t| t.embeds && !t.grey) && grey {
        notes.push(
            "the input's RGB ICC profile is left out: this output is grey, as the colour file \
             is, and an RGB profile does not describe grey (the grey was read through its \
             curves)"
                .into(),
        );
    }
    // (An RGB matrix profile's primaries go out in a linear profile instead: `write_photo`.)
    let linear = icc.and_then(image_io::linear_profile_of).is_some() && !grey;
    if float_out && icc.is_some() && !float_in && !linear {
        notes.push(
            "a float TIFF holds linear light: the input's ICC profile, which describes its \
             8/16-bit codes, is not embedded"
                .into(),
        );
    }
    notes
}

/// Alpha below this is not opaque: half an 8-bit code under 1.
const OPAQUE: f32 = 1.0 - 0.5 / 255.0;
