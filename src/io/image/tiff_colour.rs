//! TIFFs whose colour is coded in a way the image crate refuses, read with the tiff crate and
//! turned into RGB as they are read: palette colour (PhotometricInterpretation 3, TIFF 6.0
//! section 5: each pixel an index into a ColorMap of 16-bit red, green and blue values) and
//! YCbCr (6, sections 21 and 22: luma and two colour differences, as a JPEG-compressed TIFF
//! from a camera, `oiiotool --compression jpeg` or `tiffcp -c jpeg` stores its colour).
//!
//! The output of either is RGB (the writers write RGB or grey): a photo's bits follow what
//! its colours hold, 8 for YCbCr of 8-bit samples and for a palette whose 16-bit values are
//! 8-bit ones widened (v·257, or v·256 as some writers store them: the high byte, as libtiff
//! and OpenImageIO read such a map), 16 for a palette of finer values.
//!
//! - **Palette.** The tiff crate reads a palette TIFF's strips, tiles, compression and
//!   predictor as it reads a grey one, but refuses its PhotometricInterpretation: the file is
//!   read through [`Patched`], which shows the decoder that one value as 1 (grey, black is
//!   zero), so that it hands over the indices (1, 2, 4, 8 or 16 bits), which are expanded
//!   through the ColorMap here.
//! - **YCbCr.** Turned into RGB as TIFF 6.0 section 22 says (the arithmetic of libtiff's
//!   `TIFFYCbCrToRGB`): each sample scaled by its ReferenceBlackWhite pair to full range,
//!   then `R = Y + Cr·(2 − 2·LumaRed)`, `B = Y + Cb·(2 − 2·LumaBlue)`,
//!   `G = (Y − LumaBlue·B − LumaRed·R) / LumaGreen` with the YCbCrCoefficients (defaults
//!   0.299, 0.587, 0.114, and ReferenceBlackWhite's for YCbCr, [0, 255, 128, 255, 128, 255],
//!   as libtiff supplies them to a file that lacks the tag). Chroma subsampled 2×2 or 2×1
//!   (YCbCrSubSampling; TIFF's default is 2×2) is read only JPEG-compressed, where the JPEG
//!   decoder upsamples it (its own, centred, siting: YCbCrPositioning is a JPEG-compressed
//!   file's JPEG stream's business); uncompressed, LZW or ZIP YCbCr must be unsubsampled (1×1),
//!   as the tiff crate lays out no other. A subsampled one of those, rare, is refused in words
//!   that say how to convert it ([`unread`]).

use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use tiff::decoder::{ifd::Value, Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

/// How a TIFF's pixels code their colour, with what turning them into RGB needs.
#[derive(Clone, Debug)]
pub(super) enum Coding {
    /// Indices of `bits` bits into `map` (red, green, blue in [0, 1], one entry per index).
    Palette { bits: u8, map: Vec<[f32; 3]> },
    /// Luma and colour differences of `bits` bits, with the file's YCbCrCoefficients
    /// (LumaRed, LumaGreen, LumaBlue) and ReferenceBlackWhite.
    YCbCr {
        bits: u8,
        luma: [f32; 3],
        reference: [f32; 6],
    },
}

/// The tag ids the tiff crate has no names for (TIFF 6.0, section 21).
const YCBCR_COEFFICIENTS: u16 = 529;
const REFERENCE_BLACK_WHITE: u16 = 532;
/// Compression 7: JPEG as TIFF Technical Note 2 has it (the one JPEG the tiff crate reads).
const JPEG: u16 = 7;

/// The coding of a palette or YCbCr TIFF the tiff crate can deliver the samples of, and the
/// bits a sample its RGB deserves (8 or 16); `None` for any other TIFF.
pub(super) fn coding(path: &Path) -> Option<(Coding, u8)> {
    let mut decoder = open(path, header_limits(), false)?;
    let photometric = decoder
        .find_tag_unsigned::<u16>(Tag::PhotometricInterpretation)
        .ok()??;
    let samples = decoder
        .find_tag_unsigned::<u16>(Tag::SamplesPerPixel)
        .ok()
        .flatten()
        .unwrap_or(1);
    let bits = decoder
        .find_tag_unsigned_vec::<u16>(Tag::BitsPerSample)
        .ok()
        .flatten()
        .unwrap_or_else(|| vec![1]);
    let format = decoder
        .find_tag_unsigned_vec::<u16>(Tag::SampleFormat)
        .ok()
        .flatten()
        .unwrap_or_else(|| vec![1]);
    if format.iter().any(|&f| f != 1) || bits.iter().any(|&b| Some(&b) != bits.first()) {
        return None;
    }
    let bits = u8::try_from(*bits.first()?).ok()?;
    match photometric {
        3 if samples == 1 && matches!(bits, 1 | 2 | 4 | 8 | 16) => {
            let values = decoder.find_tag_unsigned_vec::<u16>(Tag::ColorMap).ok()??;
            let entries = 1usize << bits;
            // TIFF 6.0: all the reds, then all the greens, then all the blues.
            if values.len() != 3 * entries {
                return None;
            }
            // A map of 8-bit values widened (v·257, or v·256): their high bytes, exactly.
            let eight = values.iter().all(|&v| v & 0xFF == 0 || v & 0xFF == v >> 8);
            let value = |v: u16| match eight {
                true => (v >> 8) as f32 / 255.0,
                false => v as f32 / 65535.0,
            };
            let map = (0..entries)
                .map(|i| [0, 1, 2].map(|c| value(values[c * entries + i])))
                .collect();
            Some((Coding::Palette { bits, map }, if eight { 8 } else { 16 }))
        }
        6 if samples == 3 && matches!(bits, 8 | 16) => {
            let compression = decoder
                .find_tag_unsigned::<u16>(Tag::Compression)
                .ok()
                .flatten()
                .unwrap_or(1);
            let subsampling = decoder
                .find_tag_unsigned_vec::<u16>(Tag::ChromaSubsampling)
                .ok()
                .flatten()
                .unwrap_or_else(|| vec![2, 2]);
            let chunky = matches!(
                decoder.find_tag_unsigned::<u16>(Tag::PlanarConfiguration),
                Ok(None | Some(1))
            );
            if !chunky || (compression != JPEG && subsampling != [1, 1]) {
                return None;
            }
            let luma = numbers(&mut decoder, YCBCR_COEFFICIENTS)
                .and_then(|v| <[f32; 3]>::try_from(v).ok())
                .unwrap_or([0.299, 0.587, 0.114]);
            let (full, half) = (((1u32 << bits) - 1) as f32, (1u32 << (bits - 1)) as f32);
            let reference = numbers(&mut decoder, REFERENCE_BLACK_WHITE)
                .and_then(|v| <[f32; 6]>::try_from(v).ok())
                .unwrap_or([0.0, full, half, full, half, full]);
            Some((
                Coding::YCbCr {
                    bits,
                    luma,
                    reference,
                },
                bits,
            ))
        }
        _ => None,
    }
}

/// What a palette or YCbCr TIFF that [`coding`] passes over is, and what to do, in words;
/// `None` for one of another coding (or one it reads).
pub(super) fn unread(path: &Path) -> Option<String> {
    let mut decoder = open(path, header_limits(), false)?;
    let photometric = decoder
        .find_tag_unsigned::<u16>(Tag::PhotometricInterpretation)
        .ok()??;
    let convert = "convert it to RGB first, e.g. `oiiotool in.tif --compression zip -o out.tif`";
    match photometric {
        6 => {
            let subsampling = decoder
                .find_tag_unsigned_vec::<u16>(Tag::ChromaSubsampling)
                .ok()
                .flatten()
                .unwrap_or_else(|| vec![2, 2]);
            let compression = decoder
                .find_tag_unsigned::<u16>(Tag::Compression)
                .ok()
                .flatten()
                .unwrap_or(1);
            let what = match (compression, subsampling.as_slice()) {
                (6, _) => "an old-style JPEG (compression 6) YCbCr TIFF".to_string(),
                (c, &[h, v]) if c != JPEG && [h, v] != [1, 1] => format!(
                    "a YCbCr TIFF with its chroma subsampled {h}×{v} and not JPEG-compressed \
                     (compression {c}): the TIFF decoder reads subsampled YCbCr only from JPEG"
                ),
                _ => "a YCbCr TIFF of a layout the TIFF decoder does not read (planar, or \
                      other than 3 samples of 8 or 16 bits)"
                    .to_string(),
            };
            Some(format!("{what}; {convert}"))
        }
        3 => Some(format!(
            "an indexed-colour (palette) TIFF of a layout the TIFF decoder does not read (not \
             one index of 1, 2, 4, 8 or 16 bits a pixel, or a ColorMap of another length than \
             those indices need); {convert}"
        )),
        _ => None,
    }
}

/// The RGB planes (in [0, 1], as stored, no transfer function applied) of the TIFF at `path`
/// coded as `coding` says, `stored` pixels as stored (before they are turned upright). The
/// decoder holds at most `max_bytes` of samples.
pub(super) fn read(
    path: &Path,
    coding: &Coding,
    (width, height): (u32, u32),
    max_bytes: u64,
) -> Result<Vec<Vec<f32>>, String> {
    let mut limits = header_limits();
    limits.decoding_buffer_size = usize::try_from(max_bytes).unwrap_or(usize::MAX);
    limits.intermediate_buffer_size = limits.decoding_buffer_size;
    let palette = matches!(coding, Coding::Palette { .. });
    let mut decoder = open(path, limits, palette)
        .ok_or_else(|| "the TIFF could not be opened again".to_string())?;
    let decoded = decoder.read_image().map_err(|e| e.to_string())?;
    let n = width as usize * height as usize;
    let short = |have: usize, need: usize| {
        format!("the TIFF holds {have} samples where its {width}×{height} pixels need {need}")
    };
    let mut planes: Vec<Vec<f32>> = (0..3).map(|_| Vec::with_capacity(n)).collect();
    match coding {
        Coding::Palette { bits, map } => {
            let indices = indices(decoded, *bits, width as usize, height as usize)
                .ok_or("the TIFF's indices are not of the size its header declares")?;
            // Every index is below 2^bits, the map's length.
            for &i in &indices {
                let rgb = map.get(i as usize).copied().unwrap_or_default();
                for (plane, v) in planes.iter_mut().zip(rgb) {
                    plane.push(v);
                }
            }
        }
        Coding::YCbCr {
            bits,
            luma,
            reference,
        } => {
            let samples: Vec<f32> = match decoded {
                DecodingResult::U8(v) if *bits == 8 => v.into_iter().map(f32::from).collect(),
                DecodingResult::U16(v) if *bits == 16 => v.into_iter().map(f32::from).collect(),
                _ => {
                    return Err("the TIFF's samples are not of the size its header declares".into())
                }
            };
            if samples.len() < 3 * n {
                return Err(short(samples.len(), 3 * n));
            }
            let convert = YCbCr::new(*bits, *luma, *reference)?;
            for ycc in samples[..3 * n].chunks_exact(3) {
                let rgb = convert.rgb([ycc[0], ycc[1], ycc[2]]);
                for (plane, v) in planes.iter_mut().zip(rgb) {
                    plane.push(v);
                }
            }
        }
    }
    Ok(planes)
}

/// YCbCr to RGB (TIFF 6.0 section 22), in [0, 1].
struct YCbCr {
    luma: [f32; 3],
    /// Per component, the code of its reference black and what one code is worth in full
    /// range (Y: of 2^bits − 1; Cb, Cr: of 2^(bits−1) − 1, libtiff's coding ranges).
    black: [f32; 3],
    scale: [f32; 3],
    /// 2^bits − 1: full range's white.
    full: f32,
}

impl YCbCr {
    fn new(bits: u8, luma: [f32; 3], reference: [f32; 6]) -> Result<Self, String> {
        let finite = luma.iter().chain(&reference).all(|v| v.is_finite());
        if !finite || luma[1] == 0.0 {
            return Err(format!(
                "its YCbCrCoefficients {luma:?} or ReferenceBlackWhite {reference:?} are not \
                 usable (LumaGreen 0, or not finite)"
            ));
        }
        let full = ((1u32 << bits) - 1) as f32;
        let range = [full, (full - 1.0) / 2.0, (full - 1.0) / 2.0];
        let black = [0, 1, 2].map(|c| reference[2 * c]);
        // libtiff's guard: a white at its black is taken as one code above it.
        let scale = [0, 1, 2].map(|c| {
            let span = reference[2 * c + 1] - reference[2 * c];
            range[c] / if span != 0.0 { span } else { 1.0 }
        });
        Ok(YCbCr {
            luma,
            black,
            scale,
            full,
        })
    }

    fn rgb(&self, ycc: [f32; 3]) -> [f32; 3] {
        let [y, cb, cr] = [0, 1, 2].map(|c| (ycc[c] - self.black[c]) * self.scale[c]);
        let [lr, lg, lb] = self.luma;
        let r = y + cr * (2.0 - 2.0 * lr);
        let b = y + cb * (2.0 - 2.0 * lb);
        let g = (y - lb * b - lr * r) / lg;
        [r, g, b].map(|v| (v / self.full).clamp(0.0, 1.0))
    }
}

/// The `width × height` indices of `bits` bits a palette TIFF's decoder gave: 8 or 16 bits a
/// sample as they are, fewer packed into bytes from the most significant bit, each row
/// beginning at a byte (TIFF 6.0, section 4, BitsPerSample; FillOrder 1). `None` where too
/// few were given.
fn indices(decoded: DecodingResult, bits: u8, width: usize, height: usize) -> Option<Vec<u16>> {
    let n = width * height;
    match decoded {
        DecodingResult::U16(v) if bits == 16 => v.get(..n).map(<[u16]>::to_vec),
        DecodingResult::U8(v) if bits == 8 => {
            v.get(..n).map(|v| v.iter().map(|&i| i.into()).collect())
        }
        DecodingResult::U8(v) if bits < 8 => {
            let bits = bits as usize;
            let row = (width * bits).div_ceil(8);
            if v.len() < row * height {
                return None;
            }
            let mask = (1u16 << bits) - 1;
            let mut out = Vec::with_capacity(n);
            for y in 0..height {
                for x in 0..width {
                    let at = x * bits;
                    let byte = v[y * row + at / 8] as u16;
                    out.push((byte >> (8 - bits - at % 8)) & mask);
                }
            }
            Some(out)
        }
        _ => None,
    }
}

/// A tag's values as numbers (RATIONALs as their quotients); `None` where it is absent or
/// not numbers.
fn numbers<R: Read + Seek>(decoder: &mut Decoder<R>, tag: u16) -> Option<Vec<f32>> {
    fn number(value: Value) -> Option<f32> {
        match value {
            Value::Rational(n, d) => Some(n as f32 / d as f32),
            Value::SRational(n, d) => Some(n as f32 / d as f32),
            Value::Float(v) => Some(v),
            Value::Double(v) => Some(v as f32),
            Value::Short(v) => Some(v.into()),
            Value::Unsigned(v) => Some(v as f32),
            _ => None,
        }
    }
    match decoder.find_tag(Tag::Unknown(tag)).ok()?? {
        Value::List(values) => values.into_iter().map(number).collect(),
        one => number(one).map(|v| vec![v]),
    }
}

/// The decoder's limits for a header: its values (a profile, XMP) capped as the probe caps
/// them.
fn header_limits() -> Limits {
    let mut limits = Limits::default();
    limits.ifd_value_size = super::HEADER_ROOM as usize;
    limits
}

/// A decoder on the TIFF's first image, read through [`Patched`] to show its
/// PhotometricInterpretation as grey when `as_grey` (a palette TIFF's indices); `None`
/// where the file cannot be opened or its header read.
fn open(path: &Path, limits: Limits, as_grey: bool) -> Option<Decoder<Patched>> {
    let file = crate::io::input::open_input(path).ok()?;
    let mut reader = Patched {
        inner: std::io::BufReader::new(file),
        at: 0,
        value: Vec::new(),
        position: 0,
    };
    if as_grey {
        let (at, value) = photometric_as_grey(&mut reader)?;
        reader.inner.seek(SeekFrom::Start(0)).ok()?;
        (reader.at, reader.value) = (at, value);
    }
    Decoder::new(reader).ok().map(|d| d.with_limits(limits))
}

/// A file read with a few of its bytes shown otherwise: `value` in place of those at `at`.
pub(super) struct Patched {
    inner: std::io::BufReader<std::fs::File>,
    at: u64,
    value: Vec<u8>,
    /// Where the next byte read comes from.
    position: u64,
}

impl Read for Patched {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let start = self.position;
        self.position += n as u64;
        for (k, &byte) in self.value.iter().enumerate() {
            let at = self.at + k as u64;
            if (start..self.position).contains(&at) {
                buf[(at - start) as usize] = byte;
            }
        }
        Ok(n)
    }
}

impl Seek for Patched {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        self.position = self.inner.seek(to)?;
        Ok(self.position)
    }
}

/// Where the value of the first directory's PhotometricInterpretation lies (a SHORT or a
/// LONG, in the entry itself), and its bytes for 1 (grey, black is zero) in the file's byte
/// order; `None` where the header or directory cannot be walked, or the tag is not there.
/// Reads the header and the directory's entries, wherever the directory lies.
fn photometric_as_grey(file: &mut (impl Read + Seek)) -> Option<(u64, Vec<u8>)> {
    let mut header = [0u8; 16];
    file.read_exact(&mut header[..8]).ok()?;
    let little = match &header[..2] {
        b"II" => true,
        b"MM" => false,
        _ => return None,
    };
    let get = |b: &[u8], at: usize, len: usize| -> Option<u64> {
        let s = b.get(at..at.checked_add(len)?)?;
        let mut v = 0u64;
        for k in 0..len {
            let byte = if little { s[len - 1 - k] } else { s[k] };
            v = v << 8 | byte as u64;
        }
        Some(v)
    };
    let big = match get(&header, 2, 2)? {
        42 => false,
        43 => true,
        _ => return None,
    };
    let directory = if big {
        file.read_exact(&mut header[8..]).ok()?;
        get(&header, 8, 8)?
    } else {
        get(&header, 4, 4)?
    };
    // Entries: tag, type, count, value (12 bytes; BigTIFF's 20, its count 8 bytes).
    let (count_len, entry_len, value_at) = if big { (8, 20, 12) } else { (2, 12, 8) };
    file.seek(SeekFrom::Start(directory)).ok()?;
    let mut count = [0u8; 8];
    file.read_exact(&mut count[..count_len]).ok()?;
    // Tags come in ascending order: 262 is among the first dozen; a directory of more than
    // 4 096 entries is read no further.
    let count = get(&count, 0, count_len)?.min(1 << 12) as usize;
    let mut entries = Vec::new();
    file.by_ref()
        .take((count * entry_len) as u64)
        .read_to_end(&mut entries)
        .ok()?;
    for (k, entry) in entries.chunks_exact(entry_len).enumerate() {
        if get(entry, 0, 2)? != Tag::PhotometricInterpretation.to_u16() as u64 {
            continue;
        }
        let one: Vec<u8> = match (get(entry, 2, 2)?, little) {
            (3, true) => 1u16.to_le_bytes().to_vec(),
            (3, false) => 1u16.to_be_bytes().to_vec(),
            (4, true) => 1u32.to_le_bytes().to_vec(),
            (4, false) => 1u32.to_be_bytes().to_vec(),
            _ => return None,
        };
        let at = directory + (count_len + k * entry_len + value_at) as u64;
        return Some((at, one));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 4-bit indices packed two a byte, rows of 3 pixels padded to 2 bytes, written out by
    /// hand; and 1-bit ones, 8 a byte.
    #[test]
    fn packed_indices_unpack_from_the_high_bits_each_row_at_a_byte() {
        // Row 0: 1 2 3 (pad), row 1: 15 0 7 (pad).
        let packed = vec![0x12, 0x30, 0xF0, 0x70];
        let got = indices(DecodingResult::U8(packed), 4, 3, 2).unwrap();
        assert_eq!(got, [1, 2, 3, 15, 0, 7]);
        // 10 pixels of 1 bit: 1011001110, then padding.
        let got = indices(DecodingResult::U8(vec![0b1011_0011, 0b1000_0000]), 1, 10, 1);
        assert_eq!(got.unwrap(), [1, 0, 1, 1, 0, 0, 1, 1, 1, 0]);
        // Too few bytes: refused, not read past.
        assert!(indices(DecodingResult::U8(vec![0x12]), 4, 3, 2).is_none());
    }

    /// The spec's defaults (BT.601 coefficients, full range) against the JFIF conversion
    /// written out by hand (ITU T.871, 7): R = Y + 1.402 (Cr − 128), G = Y − 0.344136 (Cb −
    /// 128) − 0.714136 (Cr − 128), B = Y + 1.772 (Cb − 128).
    #[test]
    fn ycbcr_with_the_defaults_is_jfifs_conversion() {
        let c = YCbCr::new(8, [0.299, 0.587, 0.114], [0., 255., 128., 255., 128., 255.]).unwrap();
        for [y, cb, cr] in [
            [128.0f32, 128., 128.],
            [100., 90., 200.],
            [200., 160., 100.],
        ] {
            let want = [
                y + 1.402 * (cr - 128.),
                y - 0.344_136 * (cb - 128.) - 0.714_136 * (cr - 128.),
                y + 1.772 * (cb - 128.),
            ]
            .map(|v| (v / 255.).clamp(0., 1.));
            let got = c.rgb([y, cb, cr]);
            for k in 0..3 {
                assert!(
                    (got[k] - want[k]).abs() < 1e-4,
                    "{y} {cb} {cr}: {got:?} {want:?}"
                );
            }
        }
    }
}
