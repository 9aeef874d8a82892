//! A photo's pixel density (`frame::Resolution`), read from where each format keeps it beside
//! the pixels and written to where the output's format keeps it: a JPEG's JFIF APP0 segment
//! (JFIF 1.02: units 0 for an aspect ratio alone, 1 dots per inch, 2 per centimetre; x and y
//! densities in 16 bits), a PNG's pHYs chunk (PNG 11.3.5.3: pixels per unit in 32 bits, the
//! unit the metre or none), a TIFF's XResolution and YResolution (RATIONALs) and
//! ResolutionUnit (1 none, 2 inch, 3 centimetre; inch where it is absent, TIFF 6.0).
//!
//! Into the format it came from, the numbers go out as they came. Into another, they go in
//! that format's unit: a PNG's metres become inches in a JPEG or TIFF (the unit their readers
//! show, and the one a PNG's density was most likely set in: 300 dpi is 11811 px/m), inches
//! and centimetres become metres in a PNG; a value the format holds only whole (JFIF, pHYs)
//! is rounded to the nearest. x and y stay apart.
//!
//! A density of no unit whose x and y are equal says only that pixels are square, which every
//! reader assumes: it is read as no resolution, so an output that had none gains none (most
//! JPEG encoders write JFIF's 1:1 of no unit for want of a density).

use crate::frame::{Resolution, ResolutionUnit};

/// Metres in an inch.
const INCH: f64 = 0.0254;

/// A resolution read from a file, `None` where it says no more than square pixels or a
/// density is 0 (which no reader can use).
pub(super) fn resolution(x: (u32, u32), y: (u32, u32), unit: ResolutionUnit) -> Option<Resolution> {
    let zero = |(n, d): (u32, u32)| n == 0 || d == 0;
    let square =
        unit == ResolutionUnit::None && (x.0 as u64 * y.1 as u64 == y.0 as u64 * x.1 as u64);
    (!zero(x) && !zero(y) && !square).then_some(Resolution { x, y, unit })
}

/// The density a JPEG's JFIF segment gives, from the file's bytes.
pub(super) fn jfif_density(bytes: &[u8]) -> Option<Resolution> {
    super::jpeg::segment(bytes, |marker, segment| {
        if marker != 0xE0 || !segment.starts_with(b"JFIF\0") || segment.len() < 12 {
            return None;
        }
        let unit = match segment[7] {
            0 => ResolutionUnit::None,
            1 => ResolutionUnit::Inch,
            2 => ResolutionUnit::Centimetre,
            _ => return Some(None),
        };
        let x = u16::from_be_bytes([segment[8], segment[9]]) as u32;
        let y = u16::from_be_bytes([segment[10], segment[11]]) as u32;
        Some(resolution((x, 1), (y, 1), unit))
    })
    .flatten()
}

/// The density a PNG's pHYs chunk gives.
pub(super) fn png_density(dims: png::PixelDimensions) -> Option<Resolution> {
    let unit = match dims.unit {
        png::Unit::Meter => ResolutionUnit::Metre,
        png::Unit::Unspecified => ResolutionUnit::None,
    };
    resolution((dims.xppu, 1), (dims.yppu, 1), unit)
}

/// The density a TIFF's tags give: XResolution, YResolution (RATIONAL, or a whole number as
/// some writers type them) and ResolutionUnit.
pub(super) fn tiff_density<R: std::io::Read + std::io::Seek>(
    decoder: &mut tiff::decoder::Decoder<R>,
) -> Option<Resolution> {
    use tiff::decoder::ifd::Value;
    use tiff::tags::Tag;
    let mut ratio = |tag| match decoder.find_tag(tag).ok()?? {
        Value::Rational(n, d) => Some((n, d)),
        Value::Short(n) => Some((n as u32, 1)),
        Value::Unsigned(n) => Some((n, 1)),
        _ => None,
    };
    let (x, y) = (ratio(Tag::XResolution)?, ratio(Tag::YResolution)?);
    let unit = match decoder
        .find_tag_unsigned::<u16>(Tag::ResolutionUnit)
        .ok()
        .flatten()
    {
        Some(1) => ResolutionUnit::None,
        None | Some(2) => ResolutionUnit::Inch,
        Some(3) => ResolutionUnit::Centimetre,
        Some(_) => return None,
    };
    resolution(x, y, unit)
}

/// A ratio's value.
fn value((n, d): (u32, u32)) -> f64 {
    n as f64 / d as f64
}

/// A value rounded to a whole number within `1..=most` (0 is no density).
fn whole(v: f64, most: u32) -> u32 {
    v.round().clamp(1.0, most as f64) as u32
}

/// The pHYs of a resolution: pixels per metre (or the aspect ratio, of no unit), whole.
pub(super) fn to_png(r: &Resolution) -> png::PixelDimensions {
    let per_metre = |v: (u32, u32)| match r.unit {
        ResolutionUnit::Inch => value(v) / INCH,
        ResolutionUnit::Centimetre => value(v) * 100.0,
        ResolutionUnit::Metre | ResolutionUnit::None => value(v),
    };
    png::PixelDimensions {
        xppu: whole(per_metre(r.x), u32::MAX),
        yppu: whole(per_metre(r.y), u32::MAX),
        unit: if r.unit == ResolutionUnit::None {
            png::Unit::Unspecified
        } else {
            png::Unit::Meter
        },
    }
}

/// The JFIF density of a resolution: dots per inch (from a PNG's metres too) or per
/// centimetre, or the aspect ratio, whole and within 16 bits.
pub(super) fn to_jfif(r: &Resolution) -> jpeg_encoder::PixelDensity {
    use jpeg_encoder::PixelDensityUnit as Unit;
    let (scale, unit) = match r.unit {
        ResolutionUnit::None => (1.0, Unit::PixelAspectRatio),
        ResolutionUnit::Inch => (1.0, Unit::Inches),
        ResolutionUnit::Centimetre => (1.0, Unit::Centimeters),
        ResolutionUnit::Metre => (INCH, Unit::Inches),
    };
    let density = |v| whole(value(v) * scale, u16::MAX as u32) as u16;
    jpeg_encoder::PixelDensity {
        density: (density(r.x), density(r.y)),
        unit,
    }
}

/// A TIFF's XResolution, YResolution and ResolutionUnit of a resolution: the ratios as they
/// are, a PNG's metres as inches (n · 254 / (d · 10000), exact where it fits in 32 bits).
pub(super) fn to_tiff(
    r: &Resolution,
) -> (
    tiff::encoder::Rational,
    tiff::encoder::Rational,
    tiff::tags::ResolutionUnit,
) {
    use tiff::tags::ResolutionUnit as Unit;
    let (scale, unit) = match r.unit {
        ResolutionUnit::None => ((1, 1), Unit::None),
        ResolutionUnit::Inch => ((1, 1), Unit::Inch),
        ResolutionUnit::Centimetre => ((1, 1), Unit::Centimeter),
        ResolutionUnit::Metre => ((254, 10_000), Unit::Inch),
    };
    let ratio = |(n, d): (u32, u32)| {
        let (mut n, mut d) = (n as u64 * scale.0, d as u64 * scale.1);
        let common = gcd(n, d);
        (n, d) = (n / common, d / common);
        // Beyond 32 bits (a density of millions per metre): the largest denominator that
        // keeps the numerator within them, the numerator rounded to it.
        if n > u32::MAX as u64 || d > u32::MAX as u64 {
            let v = n as f64 / d as f64;
            let most = u32::MAX as f64;
            let below = (most / v.max(1.0)).floor().clamp(1.0, most);
            (n, d) = ((v * below).round().clamp(1.0, most) as u64, below as u64);
        }
        tiff::encoder::Rational {
            n: n as u32,
            d: d as u32,
        }
    };
    (ratio(r.x), ratio(r.y), unit)
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a.max(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(x: (u32, u32), y: (u32, u32), unit: ResolutionUnit) -> Resolution {
        Resolution { x, y, unit }
    }

    #[test]
    fn square_pixels_of_no_unit_and_zero_densities_are_no_resolution() {
        assert_eq!(resolution((1, 1), (1, 1), ResolutionUnit::None), None);
        assert_eq!(resolution((72, 1), (144, 2), ResolutionUnit::None), None);
        assert_eq!(resolution((0, 1), (72, 1), ResolutionUnit::Inch), None);
        assert!(resolution((1, 1), (2, 1), ResolutionUnit::None).is_some());
        assert!(resolution((72, 1), (72, 1), ResolutionUnit::Inch).is_some());
    }

    #[test]
    fn a_jfif_segment_is_read() {
        // SOI, APP0 JFIF 1.02, dots per inch, 300 × 150, no thumbnail.
        let mut jpeg = vec![0xFF, 0xD8, 0xFF, 0xE0, 0, 16];
        jpeg.extend(b"JFIF\0\x01\x02\x01\x01\x2C\x00\x96\0\0");
        jpeg.extend([0xFF, 0xD9]);
        let got = jfif_density(&jpeg).unwrap();
        assert_eq!(got, r((300, 1), (150, 1), ResolutionUnit::Inch));
    }

    /// 300 dpi is 11811.02 px/m: pHYs holds 11811, which is 299.9994 dpi, which JFIF holds
    /// as 300 and a TIFF exactly.
    #[test]
    fn each_format_gets_its_own_unit() {
        let dpi = r((300, 1), (150, 1), ResolutionUnit::Inch);
        let png = to_png(&dpi);
        assert_eq!(
            (png.xppu, png.yppu, png.unit),
            (11811, 5906, png::Unit::Meter)
        );
        let ppm = png_density(png).unwrap();
        let jfif = to_jfif(&ppm);
        assert_eq!(jfif.density, (300, 150));
        assert_eq!(jfif.unit, jpeg_encoder::PixelDensityUnit::Inches);
        let (x, _, unit) = to_tiff(&ppm);
        assert_eq!(
            (x.n as f64 / x.d as f64, unit),
            (11811.0 * 0.0254, tiff::tags::ResolutionUnit::Inch)
        );
        let dpcm = r((72, 1), (144, 1), ResolutionUnit::Centimetre);
        assert_eq!((to_png(&dpcm).xppu, to_png(&dpcm).yppu), (7200, 14400));
        assert_eq!(to_jfif(&dpcm).density, (72, 144));
        let (x, y, _) = to_tiff(&r((1, 3), (u32::MAX, 7), ResolutionUnit::Metre));
        assert!((x.n as f64 / x.d as f64 - 0.0254 / 3.0).abs() < 1e-12);
        let expected = u32::MAX as f64 / 7.0 * 0.0254;
        assert!((y.n as f64 / y.d as f64 / expected - 1.0).abs() < 1e-9);
    }
}
