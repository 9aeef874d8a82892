//! Grey TIFFs the image crate refuses as an unknown colour type: one IEEE float sample a
//! pixel (16, 32 or 64 bits), or grey and alpha, float or 8/16-bit integer. Its TIFF decoder
//! reads floats only as 32-bit RGB or RGBA, and grey with alpha not at all, yet a depth map
//! written by a depth estimator, a 32-bit grey image saved from an editor, or a grey scan with
//! a mask is such a file. The tiff crate (the image crate's own TIFF codec) reads them here;
//! their planes are turned upright by their Orientation tag, as [`super::read_planes`] turns
//! what the image crate reads. A palette or YCbCr TIFF (as a JPEG-compressed TIFF stores its
//! colour), which the image crate refuses too, is read here as RGB ([`super::tiff_colour`]);
//! one of those of a layout the tiff crate does not deliver is named as such, with what to do
//! ([`unread_kind`]); the rest keep the image crate's error.

use std::path::Path;

use image::imageops;
use image::metadata::Orientation;
use image::{ImageBuffer, Luma};
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;
use tiff::ColorType;

/// The header of a grey TIFF, or of a palette or YCbCr one read as RGB.
#[derive(Clone, Debug)]
pub(super) struct Header {
    /// The size as stored (before it is turned upright).
    pub(super) stored: (u32, u32),
    /// 1 (grey), 2 (grey and alpha) or 3 (RGB, from a palette or YCbCr: `colour`).
    pub(super) samples: usize,
    /// Bits a sample: 16, 32 or 64 for floats, 8 or 16 for integers (for `colour`, those its
    /// RGB deserves).
    pub(super) bits: u8,
    /// IEEE floats; else unsigned integers, read normalised to [0, 1].
    pub(super) float: bool,
    pub(super) orientation: Orientation,
    /// How a palette or YCbCr TIFF codes its colour; `None` for grey.
    pub(super) colour: Option<super::tiff_colour::Coding>,
}

/// The TIFF's first image, its decoder limited as the caller says.
fn open(path: &Path, limits: Limits) -> Option<Decoder<std::io::BufReader<std::fs::File>>> {
    let file = crate::io::input::open_input(path).ok()?;
    let decoder = Decoder::new(std::io::BufReader::new(file)).ok()?;
    Some(decoder.with_limits(limits))
}

/// The header of a TIFF the image crate refuses that is read here: float grey, grey and
/// alpha, palette or YCbCr; `None` for any other TIFF, and for one whose header the tiff
/// crate cannot read (the image crate's error about it then stands).
pub(super) fn header(path: &Path) -> Option<Header> {
    let mut limits = Limits::default();
    limits.ifd_value_size = super::HEADER_ROOM as usize;
    let mut decoder = open(path, limits)?;
    let orientation = decoder
        .find_tag_unsigned::<u8>(Tag::Orientation)
        .ok()
        .flatten()
        .and_then(Orientation::from_exif)
        .unwrap_or(Orientation::NoTransforms);
    if let Some((coding, bits)) = super::tiff_colour::coding(path) {
        return Some(Header {
            stored: decoder.dimensions().ok()?,
            samples: 3,
            bits,
            float: false,
            orientation,
            colour: Some(coding),
        });
    }
    // The tiff crate gives grey and alpha as two bands (`Multiband`), not `GrayA`.
    let (samples, bits) = match decoder.colortype().ok()? {
        ColorType::Gray(bits @ (16 | 32 | 64)) => (1, bits),
        ColorType::GrayA(bits @ (8 | 16 | 32 | 64))
        | ColorType::Multiband {
            bit_depth: bits @ (8 | 16 | 32 | 64),
            num_samples: 2,
        } => (2, bits),
        _ => return None,
    };
    // The second band is alpha: PhotometricInterpretation 1, grey with black as 0.
    let photometric = decoder.find_tag_unsigned::<u16>(Tag::PhotometricInterpretation);
    if samples == 2 && !matches!(photometric, Ok(Some(1))) {
        return None;
    }
    // SampleFormat 3: IEEE floating point, for every sample; 1 (the default): unsigned
    // integers, which the image crate reads but for grey and alpha.
    let formats = decoder
        .find_tag_unsigned_vec::<u16>(Tag::SampleFormat)
        .ok()
        .flatten()
        .unwrap_or_else(|| vec![1]);
    let float = match (formats.first(), samples, bits) {
        (Some(3), _, 16 | 32 | 64) => true,
        (Some(1), 2, 8 | 16) => false,
        _ => return None,
    };
    if formats.iter().any(|&f| Some(&f) != formats.first()) {
        return None;
    }
    Some(Header {
        stored: decoder.dimensions().ok()?,
        samples,
        bits,
        float,
        orientation,
        colour: None,
    })
}

/// What a TIFF the decoders do not read is, and what to do, in words, for the kinds photos
/// come in: a YCbCr or palette one of a layout the tiff crate does not deliver
/// ([`super::tiff_colour::unread`]). `None` for any other TIFF (the image crate's words then
/// stand).
pub(super) fn unread_kind(path: &Path) -> Option<String> {
    super::tiff_colour::unread(path)
}

/// The size of `header`'s image once turned upright.
pub(super) fn upright_size(header: &Header) -> (u32, u32) {
    super::upright(header.stored, header.orientation)
}

/// The planes of the grey TIFF `header` describes (grey, then alpha), as stored (a half or a
/// double as the nearest f32, an integer normalised to [0, 1], no transfer function
/// applied), turned upright. The decoder holds at most `max_bytes` of samples.
pub(super) fn read(
    path: &Path,
    header: &Header,
    max_bytes: u64,
) -> Result<(usize, usize, Vec<Vec<f32>>), String> {
    let mut limits = Limits::default();
    limits.ifd_value_size = super::HEADER_ROOM as usize;
    limits.decoding_buffer_size = usize::try_from(max_bytes).unwrap_or(usize::MAX);
    limits.intermediate_buffer_size = limits.decoding_buffer_size;
    if let Some(coding) = &header.colour {
        let planes = super::tiff_colour::read(path, coding, header.stored, max_bytes)?;
        return Ok(upright_planes(planes, header));
    }
    let mut decoder =
        open(path, limits).ok_or_else(|| "the TIFF could not be opened again".to_string())?;
    let values: Vec<f32> = match decoder.read_image().map_err(|e| e.to_string())? {
        DecodingResult::F16(v) => v.iter().map(|x| x.to_f32()).collect(),
        DecodingResult::F32(v) => v,
        DecodingResult::F64(v) => v.iter().map(|&x| x as f32).collect(),
        DecodingResult::U8(v) if !header.float => v.iter().map(|&x| x as f32 / 255.0).collect(),
        DecodingResult::U16(v) if !header.float => v.iter().map(|&x| x as f32 / 65535.0).collect(),
        _ => return Err("the TIFF's samples are not of the kind its header declares".into()),
    };
    let (width, height) = (header.stored.0 as usize, header.stored.1 as usize);
    let count = header.samples;
    let n = width * height;
    if values.len() < n * count {
        return Err(format!(
            "the TIFF holds {} samples where its {width}×{height} pixels need {}",
            values.len(),
            n * count
        ));
    }
    let mut planes: Vec<Vec<f32>> = (0..count).map(|_| Vec::with_capacity(n)).collect();
    for (i, &v) in values[..n * count].iter().enumerate() {
        planes[i % count].push(v);
    }
    Ok(upright_planes(planes, header))
}

/// The planes of `header`'s image as stored, turned upright, with their upright size.
fn upright_planes(mut planes: Vec<Vec<f32>>, header: &Header) -> (usize, usize, Vec<Vec<f32>>) {
    let (mut width, mut height) = (header.stored.0 as usize, header.stored.1 as usize);
    for plane in &mut planes {
        let (turned, w, h) =
            upright_plane(std::mem::take(plane), header.stored, header.orientation);
        *plane = turned;
        (width, height) = (w, h);
    }
    (width, height, planes)
}

/// One plane of size `(width, height)` turned as `orientation` says (the image crate's
/// `DynamicImage::apply_orientation`, for a grey float plane, which it has no variant for).
fn upright_plane(
    plane: Vec<f32>,
    (width, height): (u32, u32),
    orientation: Orientation,
) -> (Vec<f32>, usize, usize) {
    let Some(mut image) = ImageBuffer::<Luma<f32>, Vec<f32>>::from_raw(width, height, plane) else {
        return (Vec::new(), 0, 0);
    };
    image = match orientation {
        Orientation::NoTransforms => image,
        Orientation::Rotate90 => imageops::rotate90(&image),
        Orientation::Rotate180 => imageops::rotate180(&image),
        Orientation::Rotate270 => imageops::rotate270(&image),
        Orientation::FlipHorizontal => imageops::flip_horizontal(&image),
        Orientation::FlipVertical => imageops::flip_vertical(&image),
        Orientation::Rotate90FlipH => imageops::flip_horizontal(&imageops::rotate90(&image)),
        Orientation::Rotate270FlipH => imageops::flip_horizontal(&imageops::rotate270(&image)),
    };
    let (w, h) = (image.width() as usize, image.height() as usize);
    (image.into_raw(), w, h)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3×2 plane numbered in reading order, turned each way, against the pixels that
    /// orientation's EXIF meaning puts where (written out by hand).
    #[test]
    fn a_plane_turns_as_its_orientation_says() {
        // 0 1 2
        // 3 4 5
        let plane: Vec<f32> = (0..6).map(|v| v as f32).collect();
        let cases: [(Orientation, usize, usize, [f32; 6]); 8] = [
            (Orientation::NoTransforms, 3, 2, [0., 1., 2., 3., 4., 5.]),
            (Orientation::FlipHorizontal, 3, 2, [2., 1., 0., 5., 4., 3.]),
            (Orientation::Rotate180, 3, 2, [5., 4., 3., 2., 1., 0.]),
            (Orientation::FlipVertical, 3, 2, [3., 4., 5., 0., 1., 2.]),
            (Orientation::Rotate90, 2, 3, [3., 0., 4., 1., 5., 2.]),
            (Orientation::Rotate270, 2, 3, [2., 5., 1., 4., 0., 3.]),
            (Orientation::Rotate90FlipH, 2, 3, [0., 3., 1., 4., 2., 5.]),
            (Orientation::Rotate270FlipH, 2, 3, [5., 2., 4., 1., 3., 0.]),
        ];
        for (orientation, w, h, want) in cases {
            let (got, gw, gh) = upright_plane(plane.clone(), (3, 2), orientation);
            assert_eq!((gw, gh), (w, h), "{orientation:?}");
            assert_eq!(got, want, "{orientation:?}");
        }
    }
}
