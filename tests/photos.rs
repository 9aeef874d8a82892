//! Photos keep what they came with (issue 29, point 4): an 8/16-bit photo's ICC profile, EXIF,
//! XMP, IPTC and chroma subsampling come out again (EXIF, XMP and IPTC from and to JPEG, PNG
//! and TIFF alike), its colour is blurred in its profile's linear light, its bit depth is
//! kept, its orientation is honoured once, and TIFFs come out compressed with their alpha
//! declared. Fixtures are made here at run time (tagged by exiftool where a test needs what
//! only a real client writes); the outputs are read back by `exiftool`, `oiiotool` and
//! `tiffinfo` where installed (skipped with a note when absent, unless
//! SHUTTER_REQUIRE_TOOLS=1), and by the image and tiff crates' decoders.

use std::path::Path;

use image::{ImageDecoder, ImageEncoder};

use crate::support::*;

/// Adobe RGB (1998): its tone curve is a pure gamma of 563/256 (Adobe RGB (1998) Color Image
/// Encoding, 4.3.1.2), not sRGB's.
const ADOBE_GAMMA: f64 = 563.0 / 256.0;

fn adobe_icc() -> Vec<u8> {
    let mut icc = moxcms::ColorProfile::new_adobe_rgb().encode().unwrap();
    // The header's PCS illuminant exactly as ICC.1 (7.2.16) has it, D50 = (0.9642, 1.0,
    // 0.8249) in s15Fixed16: moxcms writes a D50 a few units off, which libpng refuses.
    icc[68..80].copy_from_slice(&[0, 0, 0xF6, 0xD6, 0, 1, 0, 0, 0, 0, 0xD3, 0x2D]);
    icc
}

/// A big-endian EXIF block (a TIFF structure) whose IFD0 holds Make "ShTs" and Orientation.
fn exif(orientation: u16) -> Vec<u8> {
    let mut b = b"MM\0\x2a\0\0\0\x08".to_vec();
    b.extend(2u16.to_be_bytes());
    // Make: ASCII, 5 bytes with its NUL, at offset 38 (after the IFD).
    b.extend([0x01, 0x0F, 0, 2, 0, 0, 0, 5, 0, 0, 0, 38]);
    b.extend([0x01, 0x12, 0, 3, 0, 0, 0, 1]);
    b.extend(orientation.to_be_bytes());
    b.extend([0, 0, 0, 0, 0, 0]);
    b.extend(b"ShTs\0");
    b
}

/// `exiftool -j -n` of a file, or `None` (with a note) when exiftool is not installed; fails
/// instead when SHUTTER_REQUIRE_TOOLS=1.
pub(crate) fn exiftool(path: &Path) -> Option<serde_json::Value> {
    tool("exiftool", &["-j", "-n", &s(path)]).map(|out| {
        let all: serde_json::Value = serde_json::from_str(&out).unwrap();
        all[0].clone()
    })
}

pub(crate) fn tool(name: &str, args: &[&str]) -> Option<String> {
    run_tool(name, args).map(|o| String::from_utf8_lossy(&o.stdout).into_owned())
}

/// A painted velocity map (the `painted` preset: (r, g) = v / 64 + 0.5) of `w` × `h`, moving
/// `dx(x, y)` pixels a frame to the right.
pub(crate) fn velocity_map(path: &Path, w: u32, h: u32, dx: impl Fn(u32, u32) -> f32) {
    let mut bytes = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let r = ((dx(x, y) / 64.0 + 0.5) * 65535.0).round() as u16;
            bytes.extend([r, 32768, 0].iter().flat_map(|v| v.to_ne_bytes()));
        }
    }
    image::save_buffer(path, &bytes, w, h, image::ColorType::Rgb16).unwrap();
}

/// Blurs through the `painted` preset (a flat depth made beside `velocity`); the run's
/// output, which succeeded.
pub(crate) fn blur(
    color: &Path,
    velocity: &Path,
    out: &Path,
    extra: &[&str],
) -> std::process::Output {
    let mut args = vec![
        "blur",
        "--algorithm",
        "reconstruct",
        "--preset",
        "painted",
        "--color",
    ];
    // Reconstruct needs depth: one flat plane (the `painted` preset's grey).
    let depth = velocity.with_file_name("depth.png");
    let size = image::image_dimensions(velocity).unwrap();
    let grey = vec![128u8; (size.0 * size.1) as usize];
    image::save_buffer(&depth, &grey, size.0, size.1, image::ColorType::L8).unwrap();
    let (color, velocity, depth, out) = (s(color), s(velocity), s(&depth), s(out));
    args.extend([color.as_str(), "--velocity", &velocity, "--depth", &depth]);
    args.extend(["-o", &out]);
    args.extend(extra);
    let o = shutter(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    o
}

/// An 8-bit RGB PNG of a gradient, written by the png crate with `exif` as its eXIf chunk
/// and whatever `chunks` adds (text chunks) before its image data.
fn write_png(
    path: &Path,
    w: u32,
    h: u32,
    exif: Option<Vec<u8>>,
    chunks: impl FnOnce(&mut png::Encoder<std::io::BufWriter<std::fs::File>>),
) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut info = png::Info::with_size(w, h);
    info.color_type = png::ColorType::Rgb;
    info.bit_depth = png::BitDepth::Eight;
    info.exif_metadata = exif.map(Into::into);
    let mut encoder = png::Encoder::with_info(file, info).unwrap();
    chunks(&mut encoder);
    let mut writer = encoder.write_header().unwrap();
    let pixels: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 256) as u8).collect();
    writer.write_image_data(&pixels).unwrap();
}

fn decoder(path: &Path) -> Box<dyn ImageDecoder> {
    let reader = image::ImageReader::open(path)
        .unwrap()
        .with_guessed_format()
        .unwrap();
    Box::new(reader.into_decoder().unwrap())
}

#[test]
fn a_jpeg_comes_out_with_its_profile_exif_and_subsampling() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (48u32, 32u32);
    let input = dir.path().join("in.jpg");
    let pixels: Vec<u8> = (0..w * h)
        .flat_map(|i| [(i % w * 5) as u8, (i / w * 7) as u8, 90])
        .collect();
    let icc = adobe_icc();
    // Written by jpeg-encoder at 4:2:0, the usual camera form.
    let mut encoder = jpeg_encoder::Encoder::new_file(&input, 92).unwrap();
    encoder.set_sampling_factor(jpeg_encoder::SamplingFactor::R_4_2_0);
    encoder.add_icc_profile(&icc).unwrap();
    encoder.add_exif_metadata(&exif(1)).unwrap();
    encoder
        .encode(&pixels, w as u16, h as u16, jpeg_encoder::ColorType::Rgb)
        .unwrap();
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, w, h, |_, _| 6.0);
    let out = dir.path().join("out.jpg");
    blur(&input, &velocity, &out, &[]);

    // The image crate's reader: the profile byte for byte, EXIF's Make.
    let mut read = decoder(&out);
    assert_eq!(read.icc_profile().unwrap().as_deref(), Some(&icc[..]));
    let exif_out = read.exif_metadata().unwrap().expect("EXIF kept");
    assert!(exif_out.windows(5).any(|w| w == b"ShTs\0"));
    let Some(tags) = exiftool(&out) else { return };
    assert_eq!(tags["Make"], "ShTs", "{tags}");
    assert_eq!(tags["ProfileDescription"], "Adobe RGB 1998", "{tags}");
    assert_eq!(tags["YCbCrSubSampling"], "2 2", "{tags}");
    assert_eq!(tags["Orientation"], 1, "{tags}");
}

/// Writes 8-bit RGB `pixels` as a PNG carrying the Adobe RGB profile.
fn write_adobe_png(path: &Path, (w, h): (u32, u32), pixels: &[u8]) {
    let mut png = Vec::new();
    let mut encoder = image::codecs::png::PngEncoder::new(&mut png);
    encoder.set_icc_profile(adobe_icc()).unwrap();
    encoder
        .write_image(pixels, w, h, image::ExtendedColorType::Rgb8)
        .unwrap();
    std::fs::write(path, png).unwrap();
}

/// A float TIFF of an 8-bit Adobe RGB photo holds linear light in Adobe RGB's primaries: it
/// carries a linear profile of them, which exiftool reads with the input's colorants and a
/// curve of gamma 1 (an outside probe: it carried no profile, so viewers showed it as linear
/// sRGB, Adobe's greens shifted).
#[test]
fn a_float_tiff_of_an_adobe_rgb_photo_carries_a_linear_profile_of_its_primaries() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16u32, 8u32);
    let input = dir.path().join("adobe.png");
    let pixels: Vec<u8> = (0..w * h).flat_map(|i| [(i * 2) as u8, 200, 60]).collect();
    write_adobe_png(&input, (w, h), &pixels);
    let out = dir.path().join("out.tif");
    let o = dof_still(&input, &out, &["--bit-depth", "32"]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(!err.contains("not embedded"), "{err}");
    let file = std::fs::File::open(&out).unwrap();
    let mut tiff = tiff::decoder::Decoder::new(file).unwrap();
    assert!(
        tiff.get_tag_u8_vec(tiff::tags::Tag::IccProfile).is_ok(),
        "no profile"
    );
    let (Some(before), Some(after)) = (exiftool(&input), exiftool(&out)) else {
        return;
    };
    assert_eq!(
        after["ProfileDescription"], "Linear light (shutter)",
        "{after}"
    );
    assert_eq!(after["ColorSpaceData"].as_str().map(str::trim), Some("RGB"));
    // A fixed date, so the same frame gives the same bytes (moxcms writes the time of day).
    assert_eq!(after["ProfileDateTime"], "2000:01:01 00:00:00", "{after}");
    for column in ["RedMatrixColumn", "GreenMatrixColumn", "BlueMatrixColumn"] {
        let numbers = |v: &serde_json::Value| -> Vec<f64> {
            let text = v[column].as_str().unwrap_or_default().to_string();
            text.split_whitespace()
                .map(|n| n.parse().unwrap())
                .collect()
        };
        let (a, b) = (numbers(&before), numbers(&after));
        assert_eq!(a.len(), 3, "{column}: {before}");
        for (a, b) in a.iter().zip(&b) {
            assert!((a - b).abs() < 2e-3, "{column}: {a} against {b}");
        }
    }
}

/// Blurred in the profile's own linear light: red and green hold the same pattern inverted
/// (full on one column, off the next), so whatever weights the blur gives a pixel, its red and
/// green in linear light add up to full: with Adobe RGB's pure gamma, G = (1 − (R/255)^γ)^(1/γ)
/// · 255 within a code. Blurred in sRGB's light instead, a mixed pixel misses it by 2 codes
/// and more; blurred in the encoded values, by 20.
#[test]
fn an_adobe_rgb_photo_blurs_in_its_own_linear_light() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64u32, 8u32);
    let input = dir.path().join("adobe.png");
    let pixels: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            if i % w % 2 == 0 {
                [255, 0, 60]
            } else {
                [0, 255, 60]
            }
        })
        .collect();
    write_adobe_png(&input, (w, h), &pixels);
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, w, h, |_, _| 9.0);
    let out = dir.path().join("out.png");
    blur(&input, &velocity, &out, &[]);

    let result = image::open(&out).unwrap().to_rgb8();
    let decode = |code: u8| (code as f64 / 255.0).powf(ADOBE_GAMMA);
    let encode = |linear: f64| linear.max(0.0).powf(1.0 / ADOBE_GAMMA) * 255.0;
    let mut mixed = 0;
    for p in result.pixels() {
        let [r, g, b] = p.0;
        let expected_g = encode(1.0 - decode(r));
        assert!(
            (g as f64 - expected_g).abs() <= 1.0,
            "R {r} G {g}: linear light wants G {expected_g:.2}"
        );
        assert_eq!(b, 60, "a flat channel stays as it was");
        mixed += (30..225).contains(&r) as usize;
    }
    assert!(mixed > (w * h / 2) as usize, "the blur mixes the columns");
}

#[test]
fn a_16_bit_png_comes_out_16_bit_unless_told() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16u32, 8u32);
    let input = dir.path().join("in16.png");
    let pixels: Vec<u16> = (0..w * h * 3).map(|i| (i * 97 % 65536) as u16).collect();
    let bytes: Vec<u8> = pixels.iter().flat_map(|v| v.to_ne_bytes()).collect();
    image::save_buffer(&input, &bytes, w, h, image::ColorType::Rgb16).unwrap();
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, w, h, |_, _| 0.0);
    for (extra, bits) in [(&[][..], 16), (&["--bit-depth", "8"][..], 8)] {
        let out = dir.path().join(format!("out{bits}.png"));
        blur(&input, &velocity, &out, extra);
        let color = decoder(&out).color_type();
        assert_eq!(color.bytes_per_pixel() * 8 / color.channel_count(), bits);
        if let Some(tags) = exiftool(&out) {
            assert_eq!(tags["BitDepth"], bits, "{tags}");
        }
    }
}

/// A phone's portrait photo: stored 48 × 32 with EXIF orientation 6 (turn 90° clockwise to
/// view), so 32 × 48 upright. The velocity map is painted on the upright view: the top rows
/// move, the bottom rows are still.
#[test]
fn an_orientation_6_jpeg_lines_up_with_a_map_painted_upright() {
    let dir = tempfile::tempdir().unwrap();
    let (uw, uh) = (32u32, 48u32);
    // Upright: vertical stripes two pixels wide.
    let upright = |x: u32, _y: u32| if (x / 2).is_multiple_of(2) { 40u8 } else { 210 };
    // Stored S is the upright view turned back: D(x, y) = S(y, uw - 1 - x).
    let (sw, sh) = (uh, uw);
    let stored: Vec<u8> = (0..sw * sh)
        .flat_map(|i| {
            let (sx, sy) = (i % sw, i / sw);
            let v = upright(uw - 1 - sy, sx);
            [v, v, v]
        })
        .collect();
    let input = dir.path().join("portrait.jpg");
    let mut jpeg = Vec::new();
    let mut encoder = image::codecs::jpeg::JpegEncoder::new_with_quality(&mut jpeg, 98);
    encoder.set_exif_metadata(exif(6)).unwrap();
    encoder
        .write_image(&stored, sw, sh, image::ExtendedColorType::Rgb8)
        .unwrap();
    std::fs::write(&input, jpeg).unwrap();
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, uw, uh, |_, y| if y < 16 { 8.0 } else { 0.0 });
    let out = dir.path().join("out.png");
    blur(&input, &velocity, &out, &[]);

    let result = image::open(&out).unwrap().to_luma8();
    assert_eq!(result.dimensions(), (uw, uh), "written upright");
    let step = |y: u32| {
        (0..uw - 1)
            .map(|x| {
                (result.get_pixel(x + 1, y)[0] as i32 - result.get_pixel(x, y)[0] as i32).abs()
            })
            .sum::<i32>()
    };
    // The still rows far below the moving ones keep their stripes; the moving rows lose them.
    for y in 28..uh {
        for x in 0..uw {
            let (got, want) = (result.get_pixel(x, y)[0] as i32, upright(x, y) as i32);
            assert!(
                (got - want).abs() <= 12,
                "still ({x}, {y}): {got} vs {want}"
            );
        }
    }
    for y in 2..12 {
        assert!(
            3 * step(y) < step(40),
            "row {y}: {} vs {}",
            step(y),
            step(40)
        );
    }
    // Written upright, the EXIF it carries says so: no viewer turns it again.
    let exif = decoder(&out).exif_metadata().unwrap().expect("EXIF kept");
    assert_eq!(shutter::io::image::exif_orientation(&exif), Some(1));
    if let Some(tags) = exiftool(&out) {
        assert_eq!(tags["Orientation"], 1, "{tags}");
        assert_eq!(
            (tags["ImageWidth"].clone(), tags["ImageHeight"].clone()),
            (32.into(), 48.into())
        );
    }
    // A map painted on the photo as stored (48 × 32) is refused, the orientation said: the
    // error had read "32x48 but the color pass is 48x32"... the other way round, unexplained.
    let stored_map = dir.path().join("stored.png");
    velocity_map(&stored_map, sw, sh, |_, _| 4.0);
    let o = shutter(&[
        "blur",
        "--preset",
        "painted",
        "--algorithm",
        "reconstruct",
        "--color",
        &s(&input),
        "--velocity",
        &s(&stored_map),
        "-o",
        &s(&dir.path().join("no.png")),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(
        stderr(&o).contains(
            "48x32 but the color pass is 32x48 (upright by its EXIF orientation; stored 48x32): \
             a map is matched to the picture as it is shown, upright"
        ),
        "{}",
        stderr(&o)
    );
}

/// A 16-bit TIFF with straight alpha and a profile: out 16-bit, deflate or LZW, its alpha
/// declared unassociated, its profile kept.
#[test]
fn a_tiff_comes_out_compressed_with_its_alpha_declared() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (32u32, 16u32);
    let input = dir.path().join("in.tif");
    let pixels: Vec<u16> = (0..w * h)
        .flat_map(|i| {
            [
                (i % w * 2000) as u16,
                25000,
                9000,
                if i % 3 == 0 { 30000 } else { 65535 },
            ]
        })
        .collect();
    let bytes: Vec<u8> = pixels.iter().flat_map(|v| v.to_ne_bytes()).collect();
    let icc = adobe_icc();
    let mut encoder = image::codecs::tiff::TiffEncoder::new(std::fs::File::create(&input).unwrap());
    encoder.set_icc_profile(icc.clone()).unwrap();
    encoder
        .write_image(&bytes, w, h, image::ExtendedColorType::Rgba16)
        .unwrap();
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, w, h, |_, _| 3.0);
    let out = dir.path().join("out.tif");
    blur(&input, &velocity, &out, &[]);

    use tiff::tags::Tag;
    let mut tiff = tiff::decoder::Decoder::new(std::fs::File::open(&out).unwrap()).unwrap();
    let compression = tiff.get_tag_u32(Tag::Compression).unwrap();
    assert!(
        matches!(compression, 5 | 8 | 32946),
        "LZW or deflate, not {compression}"
    );
    assert_eq!(tiff.get_tag_u32_vec(Tag::ExtraSamples).unwrap(), [2]);
    assert_eq!(tiff.get_tag_u32_vec(Tag::BitsPerSample).unwrap(), [16; 4]);
    assert_eq!(tiff.get_tag_u8_vec(Tag::IccProfile).unwrap(), icc);
    if let Some(info) = tool("tiffinfo", &[&s(&out)]) {
        assert!(info.contains("Deflate") || info.contains("LZW"), "{info}");
        assert!(info.contains("unassoc-alpha"), "{info}");
    }
    if let Some(tags) = exiftool(&out) {
        assert_eq!(tags["ProfileDescription"], "Adobe RGB 1998", "{tags}");
        assert_eq!(tags["ExtraSamples"], 2, "{tags}");
        // The profile's tag of the type the ICC's TIFF embedding gives (UNDEFINED): stored
        // BYTE, exiftool's validation called it non-standard.
        let warnings = tool("exiftool", &["-validate", "-warning", "-a", &s(&out)]).unwrap();
        assert!(!warnings.contains("ICC_Profile"), "{warnings}");
    }
}

/// Every value a TIFF output keeps outside its directory entry, and every directory, begins
/// at an even offset (TIFF 6.0, section 2): the tiff crate's encoder wrote its own tags after
/// the last strip wherever it ended, so an odd-length strip left `BitsPerSample`,
/// `SampleFormat` and IFD0 at odd offsets (`exiftool -validate`: "Odd offset for IFD0 tag").
/// Sixteen outputs of noise of different sizes, kinds and bit depths: their strips end odd
/// and even.
#[test]
fn every_tiff_value_and_directory_begins_at_a_word_boundary() {
    let dir = tempfile::tempdir().unwrap();
    let mut checked = 0;
    for case in 0..16u32 {
        let (w, h) = (17 + case * 3, 9 + case % 5);
        let input = dir.path().join(format!("in{case}.tif"));
        let n = (w * h) as usize;
        let values = noise(n * 4, case + 1, 0.0, 1.0);
        // Grey, RGB and RGBA; 8 and 16 bits (the extra flags choose float for some).
        let (colour, channels) = match case % 3 {
            0 => (image::ExtendedColorType::L8, 1),
            1 => (image::ExtendedColorType::Rgb8, 3),
            _ => (image::ExtendedColorType::Rgba8, 4),
        };
        let bytes: Vec<u8> = values[..n * channels]
            .iter()
            .map(|v| (v * 255.0) as u8)
            .collect();
        let file = std::fs::File::create(&input).unwrap();
        image::codecs::tiff::TiffEncoder::new(file)
            .write_image(&bytes, w, h, colour)
            .unwrap();
        let velocity = dir.path().join(format!("v{case}.png"));
        velocity_map(&velocity, w, h, |x, _| (x % 4) as f32);
        let out = dir.path().join(format!("out{case}.tif"));
        let depth = ["8", "16", "32"][case as usize % 3];
        blur(&input, &velocity, &out, &["--bit-depth", depth]);
        let bytes = std::fs::read(&out).unwrap();
        let little = match &bytes[..2] {
            b"II" => true,
            b"MM" => false,
            other => panic!("not a TIFF: {other:?}"),
        };
        let u16_at = |at: usize| {
            let b = [bytes[at], bytes[at + 1]];
            if little {
                u16::from_le_bytes(b)
            } else {
                u16::from_be_bytes(b)
            }
        };
        let u32_at = |at: usize| {
            let b = [bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]];
            if little {
                u32::from_le_bytes(b)
            } else {
                u32::from_be_bytes(b)
            }
        };
        // IFD0 and the directories its Exif (34665) and GPS (34853) pointers lead to.
        let mut directories = vec![u32_at(4) as usize];
        let mut seen = 0;
        while let Some(&ifd) = directories.get(seen) {
            seen += 1;
            assert_eq!(ifd % 2, 0, "case {case}: a directory at odd offset {ifd}");
            for e in 0..u16_at(ifd) as usize {
                let at = ifd + 2 + 12 * e;
                let (tag, kind, count) = (u16_at(at), u16_at(at + 2), u32_at(at + 4));
                let unit = match kind {
                    1 | 2 | 6 | 7 => 1,
                    3 | 8 => 2,
                    4 | 9 | 11 | 13 => 4,
                    _ => 8,
                };
                if tag == 34665 || tag == 34853 {
                    directories.push(u32_at(at + 8) as usize);
                }
                if unit * count as usize > 4 {
                    let value = u32_at(at + 8);
                    assert_eq!(value % 2, 0, "case {case}: tag {tag} at odd offset {value}");
                    checked += 1;
                }
            }
        }
        if let Some(warnings) = tool("exiftool", &["-validate", "-warning", "-a", &s(&out)]) {
            assert!(!warnings.contains("Odd offset"), "case {case}: {warnings}");
        }
        // The pixels read back by the tiff crate as what was written (the strips deflated and
        // differenced as the tags say).
        let back = image::open(&out).unwrap();
        assert_eq!((back.width(), back.height()), (w, h), "case {case}");
    }
    assert!(
        checked >= 16 * 2,
        "values outside their entries checked: {checked}"
    );
}

/// A TIFF of associated alpha (ExtraSamples = 1, its colour premultiplied as stored) reads as
/// the colour it means: written straight, a still frame gives back the straight colour.
#[test]
fn a_tiff_of_associated_alpha_is_not_premultiplied_twice() {
    use tiff::encoder::{colortype, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (8u32, 8u32);
    let input = dir.path().join("assoc.tif");
    // Straight colour 200 at alpha 128, stored premultiplied: 200 · 128 / 255 ≈ 100.
    let pixels: Vec<u8> = (0..w * h).flat_map(|_| [100, 100, 100, 128]).collect();
    let mut tiff = TiffEncoder::new(std::fs::File::create(&input).unwrap()).unwrap();
    let mut image = tiff.new_image::<colortype::RGBA8>(w, h).unwrap();
    image
        .encoder()
        .write_tag(tiff::tags::Tag::ExtraSamples, &[1u16][..])
        .unwrap();
    image.write_data(&pixels).unwrap();
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, w, h, |_, _| 0.0);
    let out = dir.path().join("out.png");
    blur(&input, &velocity, &out, &[]);
    let result = image::open(&out).unwrap().to_rgba8();
    for p in result.pixels() {
        assert!((p[0] as i32 - 200).abs() <= 2 && p[3] == 128, "{p:?}");
    }
}

/// Grey and alpha in one TIFF, 8 or 16 bits a sample (a grey scan with its mask), as a
/// colour type of our own: the tiff crate writes none such.
struct GreyAlpha<T>(std::marker::PhantomData<T>);

impl tiff::encoder::colortype::ColorType for GreyAlpha<u8> {
    type Inner = u8;
    const TIFF_VALUE: tiff::tags::PhotometricInterpretation =
        tiff::tags::PhotometricInterpretation::BlackIsZero;
    const BITS_PER_SAMPLE: &'static [u16] = &[8, 8];
    const SAMPLE_FORMAT: &'static [tiff::tags::SampleFormat] = &[tiff::tags::SampleFormat::Uint; 2];
    fn horizontal_predict(_: &[u8], _: &mut Vec<u8>) {
        unreachable!("written without a predictor")
    }
}

impl tiff::encoder::colortype::ColorType for GreyAlpha<u16> {
    type Inner = u16;
    const TIFF_VALUE: tiff::tags::PhotometricInterpretation =
        tiff::tags::PhotometricInterpretation::BlackIsZero;
    const BITS_PER_SAMPLE: &'static [u16] = &[16, 16];
    const SAMPLE_FORMAT: &'static [tiff::tags::SampleFormat] = &[tiff::tags::SampleFormat::Uint; 2];
    fn horizontal_predict(_: &[u16], _: &mut Vec<u16>) {
        unreachable!("written without a predictor")
    }
}

/// Writes `samples` (grey and alpha, interleaved) as a TIFF of colour type `C`, its second
/// band declared unassociated alpha.
fn write_grey_alpha<C: tiff::encoder::colortype::ColorType>(
    path: &Path,
    (w, h): (u32, u32),
    samples: &[C::Inner],
) where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = tiff::encoder::TiffEncoder::new(file).unwrap();
    let mut image = encoder.new_image::<C>(w, h).unwrap();
    image
        .encoder()
        .write_tag(tiff::tags::Tag::ExtraSamples, &[2u16][..])
        .unwrap();
    image.write_data(samples).unwrap();
}

/// A TIFF of grey and alpha, 8 or 16 bits (an outside probe: refused, "the color type
/// Unknown(16)", as the image crate reads no such TIFF), reads as the PNG of the same grey
/// and alpha: still, it comes out as it went in.
#[test]
fn a_grey_and_alpha_tiff_reads_as_the_same_png() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (12u32, 8u32);
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, w, h, |_, _| 0.0);
    // 8 bits: a ramp under a half-covered mask.
    let grey8: Vec<u8> = (0..w * h)
        .flat_map(|i| [(i * 2) as u8, if i % 2 == 0 { 255 } else { 128 }])
        .collect();
    let input = dir.path().join("ga8.tif");
    write_grey_alpha::<GreyAlpha<u8>>(&input, (w, h), &grey8);
    let out = dir.path().join("ga8.png");
    blur(&input, &velocity, &out, &[]);
    let read = image::open(&out).unwrap();
    assert_eq!(read.color(), image::ColorType::La8);
    assert_eq!(read.as_bytes(), &grey8[..], "8 bits");
    // 16 bits.
    let grey16: Vec<u16> = (0..w * h)
        .flat_map(|i| [(i * 600) as u16, 65535 - (i * 7) as u16])
        .collect();
    let input = dir.path().join("ga16.tif");
    write_grey_alpha::<GreyAlpha<u16>>(&input, (w, h), &grey16);
    let out = dir.path().join("ga16.png");
    blur(&input, &velocity, &out, &[]);
    let read = image::open(&out).unwrap();
    assert_eq!(read.color(), image::ColorType::La16);
    assert_eq!(read.into_luma_alpha16().into_raw(), grey16, "16 bits");
}

/// A PNG's text chunks come out again, each in its kind: tEXt, zTXt (compressed) and iTXt
/// (UTF-8), as a renderer or an image generator leaves its settings there.
#[test]
fn a_pngs_text_chunks_come_out_again() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16u32, 8u32);
    let input = dir.path().join("texts.png");
    write_png(&input, w, h, None, |encoder| {
        encoder
            .add_text_chunk("Comment".into(), "made by hand".into())
            .unwrap();
        encoder
            .add_ztxt_chunk("Description".into(), "a long description ".repeat(20))
            .unwrap();
        encoder
            .add_itxt_chunk("Title".into(), "Été à Zürich".into())
            .unwrap();
    });
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, w, h, |_, _| 3.0);
    let out = dir.path().join("out.png");
    blur(&input, &velocity, &out, &[]);
    let reader = png_header(&out);
    let info = reader.info();
    let latin1: Vec<(&str, &str)> = info
        .uncompressed_latin1_text
        .iter()
        .map(|t| (t.keyword.as_str(), t.text.as_str()))
        .collect();
    // Its own chunks, then shutter's record of what made the output.
    assert_eq!(
        latin1,
        [
            ("shutter/version", env!("CARGO_PKG_VERSION")),
            (
                "shutter/settings",
                "--preset painted --algorithm reconstruct"
            ),
            ("Comment", "made by hand")
        ]
    );
    let compressed = &info.compressed_latin1_text;
    assert_eq!(compressed.len(), 1);
    assert_eq!(compressed[0].keyword, "Description");
    assert_eq!(
        compressed[0].get_text().unwrap(),
        "a long description ".repeat(20)
    );
    let utf8 = &info.utf8_text;
    assert_eq!(utf8.len(), 1);
    assert_eq!(utf8[0].keyword, "Title");
    assert_eq!(utf8[0].get_text().unwrap(), "Été à Zürich");
    if let Some(tags) = exiftool(&out) {
        assert_eq!(tags["Comment"], "made by hand", "{tags}");
        assert_eq!(tags["Title"], "Été à Zürich", "{tags}");
        assert!(
            tags["Description"].as_str().unwrap().starts_with("a long"),
            "{tags}"
        );
    }
}

/// A block one JPEG segment cannot hold (here a PNG's XMP of ~100 KB, as a long edit history
/// makes) is left out of a JPEG output with a warning naming it; the frame is written, with
/// its EXIF.
#[test]
fn a_jpeg_output_leaves_out_a_block_too_large_for_its_segment_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16u32, 8u32);
    let input = dir.path().join("big_xmp.png");
    let history = "<rdf:li>an edit</rdf:li>".repeat(4000);
    let xmp = format!(
        "<x:xmpmeta xmlns:x=\"adobe:ns:meta/\"><rdf:RDF \
         xmlns:rdf=\"http://www.w3.org/1999/02/22-rdf-syntax-ns#\"><rdf:Description \
         xmlns:dc=\"http://purl.org/dc/elements/1.1/\"><dc:subject><rdf:Bag>{history}\
         </rdf:Bag></dc:subject></rdf:Description></rdf:RDF></x:xmpmeta>"
    );
    assert!(xmp.len() > 90_000);
    write_png(&input, w, h, Some(exif(1)), |encoder| {
        encoder
            .add_itxt_chunk("XML:com.adobe.xmp".into(), xmp)
            .unwrap();
    });
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, w, h, |_, _| 2.0);
    let out = dir.path().join("out.jpg");
    let o = blur(&input, &velocity, &out, &[]);
    let err = stderr(&o);
    assert!(
        err.contains("the XMP the input holds") && err.contains("leaves it out"),
        "{err}"
    );
    assert!(!err.contains("EXIF the input"), "{err}");
    if let Some(tags) = exiftool(&out) {
        assert_eq!(tags["Make"], "ShTs", "{tags}");
        assert!(tags.get("Subject").is_none(), "{tags}");
    }
}

/// Sets tags of `path` with exiftool (`-overwrite_original`); false, with a note, where it is
/// not installed (a failure where SHUTTER_REQUIRE_TOOLS=1).
pub(crate) fn exiftool_set(path: &Path, args: &[&str]) -> bool {
    let path = s(path);
    let mut all = vec!["-q", "-q", "-overwrite_original"];
    all.extend(args);
    all.push(&path);
    tool("exiftool", &all).is_some()
}

/// What exiftool writes into a photo for the metadata tests: IFD0 tags, an Exif and a GPS
/// directory's, XMP and IPTC, and orientation 6 (turn 90° clockwise to view).
const TAGGED: [&str; 10] = [
    "-Make=ShTs",
    "-Model=Model X",
    "-Artist=A. Person",
    "-DateTimeOriginal=2024:05:06 07:08:09",
    "-GPSLatitude=12.5",
    "-GPSLatitudeRef=N",
    "-Orientation#=6",
    "-XMP-dc:Title=A title",
    "-IPTC:Keywords=one",
    "-IPTC:Keywords=two",
];

/// A portrait stored on its side, `sw` × `sh`, to be turned 90° clockwise: upright
/// (`sh` × `sw`) it is bright in its top-left corner, dark elsewhere.
pub(crate) fn portrait_on_its_side(sw: u32, sh: u32) -> Vec<u8> {
    let uw = sh;
    (0..sw * sh)
        .flat_map(|i| {
            let (ux, uy) = (uw - 1 - i / sw, i % sw);
            let v = if ux < 8 && uy < 8 { 230 } else { 20 };
            [v, v, v]
        })
        .collect()
}

/// What every output of the metadata tests holds, read by exiftool: the tags [`TAGGED`]
/// wrote (`iptc`: and its IPTC), the pixels upright and said to be so (orientation 1 or none).
fn assert_tagged(tags: &serde_json::Value, iptc: bool) {
    assert_eq!(tags["Make"], "ShTs", "{tags}");
    assert_eq!(tags["Model"], "Model X", "{tags}");
    assert_eq!(tags["Artist"], "A. Person", "{tags}");
    assert_eq!(tags["DateTimeOriginal"], "2024:05:06 07:08:09", "{tags}");
    assert_eq!(tags["GPSLatitude"], 12.5, "{tags}");
    assert_eq!(tags["Title"], "A title", "{tags}");
    if iptc {
        assert_eq!(
            tags["Keywords"],
            serde_json::json!(["one", "two"]),
            "{tags}"
        );
    }
    assert!(
        tags.get("Orientation").is_none_or(|o| o == 1),
        "turned upright once: {tags}"
    );
    assert_eq!(
        (&tags["ImageWidth"], &tags["ImageHeight"]),
        (&32.into(), &48.into())
    );
}

/// The pixels of an output of the metadata tests are the upright view: bright top left.
fn assert_upright(out: &Path) {
    let result = image::open(out).unwrap().to_luma8();
    assert_eq!(result.dimensions(), (32, 48));
    assert!(result.get_pixel(3, 3)[0] > 150, "bright top left");
    assert!(result.get_pixel(28, 3)[0] < 80 && result.get_pixel(3, 44)[0] < 80);
}

/// A TIFF whose EXIF (IFD0's tags, its Exif and GPS directories), XMP and IPTC exiftool wrote,
/// stored on its side with orientation 6: a TIFF, a JPEG and a PNG out of it hold them all
/// again (but IPTC in a PNG, which has no place for it: the run says so), as exiftool and
/// OpenImageIO read them, the pixels turned upright once.
#[test]
fn a_tiffs_exif_xmp_and_iptc_come_out_in_a_tiff_a_jpeg_and_a_png_turned_upright_once() {
    let dir = tempfile::tempdir().unwrap();
    let (sw, sh) = (48u32, 32u32);
    let input = dir.path().join("tagged.tif");
    let encoder = image::codecs::tiff::TiffEncoder::new(std::fs::File::create(&input).unwrap());
    let stored = portrait_on_its_side(sw, sh);
    encoder
        .write_image(&stored, sw, sh, image::ExtendedColorType::Rgb8)
        .unwrap();
    if !exiftool_set(&input, &TAGGED) {
        return;
    }
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, sh, sw, |_, _| 0.0);
    for (name, iptc) in [("out.tif", true), ("out.jpg", true), ("out.png", false)] {
        let out = dir.path().join(name);
        let o = blur(&input, &velocity, &out, &[]);
        // What a PNG cannot hold is said, not dropped silently.
        let said = stderr(&o).contains("IPTC");
        assert_eq!(said, !iptc, "{name}: {}", stderr(&o));
        assert_upright(&out);
        assert_tagged(&exiftool(&out).unwrap(), iptc);
        if let Some(info) = oiiotool_info(&out) {
            let mut lines = vec![
                "Make: \"ShTs\"",
                "Artist: \"A. Person\"",
                "Exif:DateTimeOriginal: \"2024:05:06 07:08:09\"",
                "Orientation: 1 (normal)",
            ];
            if iptc {
                lines.push("Keywords: \"one; two\"");
            }
            for line in lines {
                assert!(info.contains(line), "{name}: {line} in\n{info}");
            }
        }
    }
}

/// A JPEG's EXIF (big-endian, as the helper and many cameras write it) comes out in a TIFF:
/// its IFD0 tags in the TIFF's IFD0, its Exif and GPS directories as directories of the TIFF,
/// its orientation 1 as the pixels are turned upright.
#[test]
fn a_jpegs_exif_comes_out_in_a_tiff() {
    let dir = tempfile::tempdir().unwrap();
    let (sw, sh) = (48u32, 32u32);
    let input = dir.path().join("tagged.jpg");
    let mut encoder = jpeg_encoder::Encoder::new_file(&input, 95).unwrap();
    encoder.add_exif_metadata(&exif(6)).unwrap();
    encoder
        .encode(
            &portrait_on_its_side(sw, sh),
            sw as u16,
            sh as u16,
            jpeg_encoder::ColorType::Rgb,
        )
        .unwrap();
    let tagged = exiftool_set(&input, &TAGGED[1..]);
    let velocity = dir.path().join("v.png");
    velocity_map(&velocity, sh, sw, |_, _| 0.0);
    let out = dir.path().join("out.tif");
    blur(&input, &velocity, &out, &[]);
    assert_upright(&out);

    use tiff::tags::Tag;
    let mut tiff = tiff::decoder::Decoder::new(std::fs::File::open(&out).unwrap()).unwrap();
    assert_eq!(tiff.get_tag_ascii_string(Tag::Make).unwrap(), "ShTs");
    assert_eq!(tiff.get_tag_u32(Tag::Orientation).unwrap(), 1);
    if tagged {
        let exif = tiff.get_tag(Tag::ExifDirectory).unwrap().into_ifd_pointer();
        let exif = tiff.read_directory(exif.unwrap()).unwrap();
        let date = tiff
            .read_directory_tags(&exif)
            .get_tag_ascii_string(Tag::Unknown(36867));
        assert_eq!(date.unwrap(), "2024:05:06 07:08:09");
        assert_tagged(&exiftool(&out).unwrap(), true);
    }
}

/// Runs `shutter dof` on `color` with a black blurriness map of its size (nothing blurs: the
/// frame comes back as it was read), writing `out`; the run's output, whatever its exit.
fn dof_still(color: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    dof_still_of(color, image::image_dimensions(color).unwrap(), out, extra)
}

/// [`dof_still`] for a `color` of size `(w, h)` (one the image crate does not read).
fn dof_still_of(
    color: &Path,
    (w, h): (u32, u32),
    out: &Path,
    extra: &[&str],
) -> std::process::Output {
    let coc = color.with_file_name("coc0.png");
    image::save_buffer(
        &coc,
        &vec![0u8; (w * h) as usize],
        w,
        h,
        image::ColorType::L8,
    )
    .unwrap();
    let (color, coc, out) = (s(color), s(&coc), s(out));
    let mut args = vec!["dof", "--color", &color, "--coc-map", &coc, "-o", &out];
    args.extend(extra);
    shutter(&args)
}

/// The `--json` report's warnings of a run, as one string.
fn json_warnings(o: &std::process::Output) -> String {
    let report: serde_json::Value = serde_json::from_str(&stdout(o)).unwrap();
    report["warnings"].to_string()
}

/// A float TIFF (scene-referred light, R running 0 to 8) comes out a float TIFF, its values
/// above 1 kept; an 8/16-bit output of it clips them and says so, naming the file; float
/// PNG, which PNG cannot hold, is refused.
#[test]
fn a_float_tiff_comes_out_float_and_an_integer_output_says_what_it_clips() {
    use tiff::encoder::{colortype, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (96u32, 64u32);
    let input = dir.path().join("hdr.tif");
    let red = |x: u32| x as f32 / w as f32 * 8.0;
    let pixels: Vec<f32> = (0..w * h).flat_map(|i| [red(i % w), 0.5, 0.25]).collect();
    let mut tiff = TiffEncoder::new(std::fs::File::create(&input).unwrap()).unwrap();
    tiff.write_image::<colortype::RGB32Float>(w, h, &pixels)
        .unwrap();
    for (name, extra) in [
        ("out.tif", &[][..]),
        ("out32.tif", &["--bit-depth", "32"][..]),
    ] {
        let out = dir.path().join(name);
        let o = dof_still(&input, &out, extra);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let image = image::open(&out).unwrap();
        assert_eq!(image.color(), image::ColorType::Rgb32F, "{name}");
        let image = image.to_rgb32f();
        for x in [0, 20, 95] {
            let got = image.get_pixel(x, 5)[0];
            assert!((got - red(x)).abs() < 1e-4, "{name} x {x}: {got}");
        }
        assert!(!stderr(&o).contains("clip"), "{name}: {}", stderr(&o));
    }
    for name in ["out.png", "out8.tif"] {
        let out = dir.path().join(name);
        let extra: &[&str] = if name == "out8.tif" {
            &["--json", "--bit-depth", "8"]
        } else {
            &["--json"]
        };
        let o = dof_still(&input, &out, extra);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let warnings = json_warnings(&o);
        assert!(
            warnings.contains(name) && warnings.contains("clipped") && warnings.contains("float"),
            "{name}: {warnings}"
        );
    }
    let o = dof_still(&input, &dir.path().join("f.png"), &["--bit-depth", "32"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("PNG"), "{}", stderr(&o));
}

/// A Gray ICC profile (ICC.1 kTRC, a gamma of 2.2, as Photoshop's "Gray Gamma 2.2"), made
/// by hand as mk.py in QA's repro made it: header, description, white point and curve.
fn grey_icc() -> Vec<u8> {
    let s15 = |v: f64| ((v * 65536.0).round() as i32).to_be_bytes();
    let mut desc = b"desc\0\0\0\0".to_vec();
    desc.extend(9u32.to_be_bytes());
    desc.extend(b"Gray 2.2\0");
    desc.extend([0u8; 79]);
    let mut wtpt = b"XYZ \0\0\0\0".to_vec();
    for v in [0.9642, 1.0, 0.8249] {
        wtpt.extend(s15(v));
    }
    let ktrc = [
        &b"curv\0\0\0\0"[..],
        &1u32.to_be_bytes(),
        &563u16.to_be_bytes(),
    ]
    .concat();
    let tags: [(&[u8], Vec<u8>); 3] = [(b"desc", desc), (b"wtpt", wtpt), (b"kTRC", ktrc)];
    let (mut table, mut data) = (Vec::new(), Vec::new());
    let start = 132 + 12 * tags.len();
    for (signature, mut body) in tags {
        body.resize(body.len().div_ceil(4) * 4, 0);
        table.extend(signature);
        table.extend(((start + data.len()) as u32).to_be_bytes());
        table.extend((body.len() as u32).to_be_bytes());
        data.extend(body);
    }
    let mut icc = ((128 + 4 + table.len() + data.len()) as u32)
        .to_be_bytes()
        .to_vec();
    icc.extend(b"none\x02\x10\0\0mntrGRAYXYZ ");
    icc.extend([0u8; 12]);
    icc.extend(b"acspAPPL");
    icc.extend([0u8; 24]);
    for v in [0.9642, 1.0, 0.8249] {
        icc.extend(s15(v));
    }
    icc.extend([0u8; 48]);
    icc.extend(((table.len() / 12) as u32).to_be_bytes());
    icc.extend(table);
    icc.extend(data);
    icc
}

/// A black-and-white photo with its Gray profile comes out grey with that profile, in a JPEG,
/// a PNG and a TIFF: what a photographer's grey file is, not RGB with the profile dropped.
#[test]
fn a_grey_photo_comes_out_grey_with_its_gray_profile() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40u32, 24u32);
    let input = dir.path().join("grey.jpg");
    let pixels: Vec<u8> = (0..w * h).map(|i| (i % w * 6) as u8).collect();
    let icc = grey_icc();
    let mut encoder = jpeg_encoder::Encoder::new_file(&input, 95).unwrap();
    encoder.add_icc_profile(&icc).unwrap();
    encoder
        .encode(&pixels, w as u16, h as u16, jpeg_encoder::ColorType::Luma)
        .unwrap();
    assert_eq!(
        decoder(&input).icc_profile().unwrap().as_deref(),
        Some(&icc[..])
    );
    for name in ["out.jpg", "out.png", "out.tif"] {
        let out = dir.path().join(name);
        let o = dof_still(&input, &out, &[]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let mut read = decoder(&out);
        assert_eq!(read.color_type(), image::ColorType::L8, "{name}");
        // (The image crate's TIFF reader gives no profile: the tiff crate reads its tag.)
        let profile = if name.ends_with(".tif") {
            let file = std::fs::File::open(&out).unwrap();
            let mut tiff = tiff::decoder::Decoder::new(file).unwrap();
            tiff.get_tag_u8_vec(tiff::tags::Tag::IccProfile).ok()
        } else {
            read.icc_profile().unwrap()
        };
        assert_eq!(profile.as_deref(), Some(&icc[..]), "{name}");
        let result = image::open(&out).unwrap().to_luma8();
        let original = image::open(&input).unwrap().to_luma8();
        for (a, b) in result.pixels().zip(original.pixels()) {
            assert!(
                (a[0] as i32 - b[0] as i32).abs() <= 3,
                "{name}: {a:?} {b:?}"
            );
        }
        if let Some(tags) = exiftool(&out) {
            assert_eq!(tags["ColorSpaceData"], "GRAY", "{name}: {tags}");
            assert_eq!(tags["ProfileDescription"], "Gray 2.2", "{name}: {tags}");
        }
    }
}

/// A grey JPEG carrying an RGB profile (a converter's slip): it goes out grey, without the
/// profile, which cannot describe grey, and the run says so (an outside probe: the profile
/// was dropped without a word).
#[test]
fn a_grey_jpeg_with_an_rgb_profile_says_the_profile_is_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (40u32, 24u32);
    let input = dir.path().join("grey.jpg");
    let pixels: Vec<u8> = (0..w * h).map(|i| (i % w * 6) as u8).collect();
    let mut encoder = jpeg_encoder::Encoder::new_file(&input, 95).unwrap();
    encoder.add_icc_profile(&adobe_icc()).unwrap();
    encoder
        .encode(&pixels, w as u16, h as u16, jpeg_encoder::ColorType::Luma)
        .unwrap();
    let out = dir.path().join("out.png");
    let o = dof_still(&input, &out, &[]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("RGB ICC profile is left out"), "{err}");
    let mut read = decoder(&out);
    assert_eq!(read.color_type(), image::ColorType::L8);
    assert_eq!(read.icc_profile().unwrap(), None);
}

/// A CMYK JPEG with a CMYK profile: the decoder turns its colour into RGB without the
/// profile, and an RGB output cannot embed a CMYK profile: the note says both, not that the
/// profile is kept.
#[test]
fn a_cmyk_jpegs_note_says_its_profile_is_left_out() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16u32, 8u32);
    let input = dir.path().join("cmyk.jpg");
    // A CMYK output profile: sRGB's, its data colour space said to be CMYK (the note is
    // about the colour space; moxcms reads no curves for it).
    let mut icc = moxcms::ColorProfile::new_srgb().encode().unwrap();
    icc[16..20].copy_from_slice(b"CMYK");
    icc[12..16].copy_from_slice(b"prtr");
    let pixels: Vec<u8> = (0..w * h)
        .flat_map(|i| [(i * 3) as u8, 40, 90, 10])
        .collect();
    let mut encoder = jpeg_encoder::Encoder::new_file(&input, 95).unwrap();
    encoder.add_icc_profile(&icc).unwrap();
    encoder
        .encode(&pixels, w as u16, h as u16, jpeg_encoder::ColorType::Cmyk)
        .unwrap();
    let out = dir.path().join("out.jpg");
    let o = dof_still(&input, &out, &["--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let warnings = json_warnings(&o);
    assert!(!warnings.contains("the profile is kept"), "{warnings}");
    assert!(
        warnings.contains("CMYK") && warnings.contains("not embedded"),
        "{warnings}"
    );
    assert!(warnings.contains("without the profile"), "{warnings}");
    assert_eq!(decoder(&out).icc_profile().unwrap(), None);
}

/// sRGB's encoding of linear `v` (IEC 61966-2-1), from 0 to 1: the test's own.
fn srgb(v: f64) -> f64 {
    let e = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    e.clamp(0.0, 1.0)
}

/// [`srgb`] as an 8-bit code.
fn srgb8(v: f64) -> f64 {
    (srgb(v) * 255.0).round()
}

/// sRGB's decoding of an 8-bit code to linear light: the test's own.
fn linear8(code: u8) -> f64 {
    let e = f64::from(code) / 255.0;
    if e <= 0.040_45 {
        e / 12.92
    } else {
        ((e + 0.055) / 1.055).powf(2.4)
    }
}

/// An RGBA photo written to JPEG, which has no alpha: the JPEG holds the photo composited
/// over black, in linear light (its straight (127, 119, 36) times its alpha), as oiiotool
/// and a compositor flatten RGBA into a JPEG, and the run says that the alpha was left out
/// and the colour is over black. (It held the straight colour, as if opaque: an FX element's
/// light where alpha is 0 vanished, the rest was brightened.) The name is the one README's
/// "What survives" table gives it; it is to become
/// `a_jpeg_of_an_rgba_photo_holds_it_over_black_and_says_alpha_is_dropped` with the row.
#[test]
fn a_jpeg_of_an_rgba_photo_holds_it_over_black_and_says_alpha_is_dropped() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64u32, 16u32);
    let input = dir.path().join("rgba.png");
    let alpha_at = |x: u32| (x % w * 4 + 3) as u8;
    let pixels: Vec<u8> = (0..w * h)
        .flat_map(|i| [127, 119, 36, alpha_at(i)])
        .collect();
    image::save_buffer(&input, &pixels, w, h, image::ColorType::Rgba8).unwrap();
    let out = dir.path().join("a.jpg");
    let o = dof_still(&input, &out, &["--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let result = image::open(&out).unwrap().to_rgb8();
    // x = 8: alpha 35; x = 31: alpha 127; x = 60: alpha 243.
    for x in [8, 31, 60] {
        let a = f64::from(alpha_at(x)) / 255.0;
        let p = result.get_pixel(x, 8).0;
        for (got, straight) in p.iter().zip([127u8, 119, 36]) {
            let want = srgb8(linear8(straight) * a);
            assert!(
                (f64::from(*got) - want).abs() <= 3.0,
                "x {x}: {p:?}, want {want}"
            );
        }
    }
    let warnings = json_warnings(&o);
    assert!(
        warnings.contains("alpha") && warnings.contains("a.jpg") && warnings.contains("over black"),
        "{warnings}"
    );
}

/// Premultiplied light where alpha is 0 (a glow, an additive effect rendered over nothing):
/// an 8/16-bit PNG or TIFF holds it as it is, with alpha 0, as oiiotool writes it (it
/// unpremultiplies only where alpha is above 0); a JPEG holds the colour over black. It came
/// out 0 everywhere alpha was 0. Where alpha is 0.5 the straight colour is the colour over
/// it. The expected codes are sRGB's encoding, worked out here.
#[test]
fn light_where_alpha_is_zero_survives_into_png_tiff_and_jpeg() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (30usize, 20usize);
    let grey = vec![0.5f32; w * h];
    let alpha: Vec<f32> = (0..w * h)
        .map(|i| if i % w < 15 { 0.0 } else { 0.5 })
        .collect();
    let input = dir.path().join("glow.exr");
    write_exr(
        &input,
        w,
        h,
        vec![
            ("R", grey.clone()),
            ("G", grey.clone()),
            ("B", grey),
            ("A", alpha),
        ],
    );
    for (name, bits) in [("o.png", 8), ("o.tif", 8), ("o16.png", 16), ("o16.tif", 16)] {
        let out = dir.path().join(name);
        let depth = bits.to_string();
        let o = shutter(&[
            "blur",
            "--color",
            &s(&input),
            "--bit-depth",
            &depth,
            "-o",
            &s(&out),
            "--json",
        ]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        // Read as 16-bit codes (an 8-bit file's widened × 257 by the image crate).
        let picture = image::open(&out).unwrap().to_rgba16();
        let (left, right) = (picture.get_pixel(10, 5).0, picture.get_pixel(25, 5).0);
        let max = if bits == 8 { 255.0 } else { 65535.0 };
        let widen = 65535.0 / max;
        let code = |v: f64| (v * max).round() * widen;
        for c in 0..3 {
            let want = code(srgb(0.5));
            let d = (f64::from(left[c]) - want).abs();
            assert!(d <= widen, "{name}: alpha 0 holds {left:?}, want {want}");
            assert_eq!(
                right[c], 65535,
                "{name}: 0.5 over alpha 0.5 is 1: {right:?}"
            );
        }
        assert_eq!(left[3], 0, "{name}: {left:?}");
        let d = (f64::from(right[3]) - code(0.5)).abs();
        assert!(d <= widen, "{name}: {right:?}");
        let warnings = json_warnings(&o);
        assert!(!warnings.contains("alpha"), "{name}: {warnings}");
    }
    let out = dir.path().join("o.jpg");
    let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&out), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let picture = image::open(&out).unwrap().to_rgb8();
    let glow = srgb8(0.5);
    for x in [10, 25] {
        let p = picture.get_pixel(x, 5).0;
        assert!(
            p.iter().all(|&c| (f64::from(c) - glow).abs() <= 2.0),
            "x {x}: {p:?}, want {glow} (0.5 over black)"
        );
    }
    assert!(
        json_warnings(&o).contains("over black"),
        "{}",
        json_warnings(&o)
    );
}

/// A JPEG holds at most 65535 pixels a side: a wider frame is refused by the preflight (bad
/// settings, exit 1, nothing written), naming its size and the limit, not found at write
/// time as a transient failure (exit 75).
#[test]
fn a_frame_wider_than_a_jpeg_holds_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (70000u32, 2u32);
    let input = dir.path().join("wide.png");
    image::save_buffer(
        &input,
        &vec![90u8; (w * h * 3) as usize],
        w,
        h,
        image::ColorType::Rgb8,
    )
    .unwrap();
    let out = dir.path().join("out").join("wide.jpg");
    let o = dof_still(&input, &out, &[]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("70000") && err.contains("65535"), "{err}");
    assert!(!dir.path().join("out").exists(), "nothing written");
    let o = dof_still(&input, &out, &["--dry-run"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
}

/// An Adobe RGB photo written to EXR: its primaries and white, from the profile's D50-adapted
/// colorants, go in the EXR's `chromaticities`, as Adobe RGB (1998) gives them.
#[test]
fn an_adobe_rgb_photos_exr_carries_its_primaries_as_chromaticities() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16u32, 8u32);
    let input = dir.path().join("adobe.jpg");
    let pixels: Vec<u8> = (0..w * h).flat_map(|i| [(i * 2) as u8, 100, 60]).collect();
    let mut encoder = jpeg_encoder::Encoder::new_file(&input, 95).unwrap();
    encoder.add_icc_profile(&adobe_icc()).unwrap();
    encoder
        .encode(&pixels, w as u16, h as u16, jpeg_encoder::ColorType::Rgb)
        .unwrap();
    let out = dir.path().join("out.exr");
    let o = dof_still(&input, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = exr::meta::MetaData::read_from_file(&out, false).unwrap();
    let c = meta.headers[0]
        .shared_attributes
        .chromaticities
        .expect("chromaticities written");
    let got = [c.red, c.green, c.blue, c.white].map(|v| (v.0, v.1));
    let adobe = [(0.64, 0.33), (0.21, 0.71), (0.15, 0.06), (0.3127, 0.3290)];
    for (g, a) in got.iter().zip(adobe) {
        assert!(
            (g.0 - a.0).abs() < 1e-3 && (g.1 - a.1).abs() < 1e-3,
            "{got:?} vs {adobe:?}"
        );
    }
    if let Some(info) = oiiotool_info(&out) {
        assert!(info.contains("chromaticities"), "{info}");
    }
}

/// A grey float TIFF (32-bit IEEE floats, one sample a pixel: what a depth estimator or an
/// editor's 32-bit grey writes), which the image crate's decoder refuses, is read as a map: a
/// painted depth map stored so gives the bytes the same map gives as a 16-bit PNG of the same
/// values, and one stored sideways (Orientation 6, the upright map turned back a quarter)
/// gives them too, turned upright once.
#[test]
fn a_grey_float_tiff_depth_map_reads_as_the_same_map_in_a_png() {
    use tiff::encoder::{colortype::Gray32Float, TiffEncoder};
    use tiff::tags::Tag;
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (24u32, 16u32);
    let code = |x: u32, y: u32| ((x * 2731 + y * 4099) % 65536) as u16;
    // The upright map as a 16-bit grey PNG, and its values as the PNG's reader makes them.
    let codes: Vec<u16> = (0..w * h).map(|i| code(i % w, i / w)).collect();
    let bytes: Vec<u8> = codes.iter().flat_map(|c| c.to_ne_bytes()).collect();
    let png = dir.path().join("depth.png");
    image::save_buffer(&png, &bytes, w, h, image::ColorType::L16).unwrap();
    let value = |x: u32, y: u32| code(x, y) as f32 / 65535.0;
    let write =
        |name: &str, (sw, sh): (u32, u32), orientation: u16, at: &dyn Fn(u32, u32) -> f32| {
            let path = dir.path().join(name);
            let mut encoder = TiffEncoder::new(std::fs::File::create(&path).unwrap()).unwrap();
            let mut image = encoder.new_image::<Gray32Float>(sw, sh).unwrap();
            image
                .encoder()
                .write_tag(Tag::Orientation, orientation)
                .unwrap();
            let samples: Vec<f32> = (0..sw * sh).map(|i| at(i % sw, i / sw)).collect();
            image.write_data(&samples).unwrap();
            path
        };
    let upright = write("upright.tif", (w, h), 1, &|x, y| value(x, y));
    // Orientation 6: the stored row 0 is the upright image's right column, read top down, so
    // stored (x, y) is upright (w − 1 − y, x).
    let sideways = write("sideways.tif", (h, w), 6, &|x, y| value(w - 1 - y, x));
    let colour = dir.path().join("photo.png");
    write_png(&colour, w, h, None, |_| {});
    let run = |depth: &Path, out: &str| {
        let out = dir.path().join(out);
        let o = shutter(&[
            "dof",
            "--preset",
            "painted",
            "--color",
            &s(&colour),
            "--depth",
            &s(depth),
            "--focal-length",
            "85",
            "--f-stop",
            "1.4",
            "--focus-distance",
            "20",
            "-o",
            &s(&out),
        ]);
        assert!(o.status.success(), "{}: {}", depth.display(), stderr(&o));
        std::fs::read(out).unwrap()
    };
    let from_png = run(&png, "png.png");
    assert_eq!(
        run(&upright, "upright.png"),
        from_png,
        "the upright float TIFF"
    );
    assert_eq!(
        run(&sideways, "sideways.png"),
        from_png,
        "the sideways float TIFF"
    );
    // As colour, it goes out as it came: a grey float TIFF, upright.
    let out = dir.path().join("grey.tif");
    let o = shutter(&[
        "dof",
        "--color",
        &s(&sideways),
        "--coc-map",
        &s(&png),
        "--coc-scale",
        "0",
        "-o",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut decoder = tiff::decoder::Decoder::new(std::fs::File::open(&out).unwrap()).unwrap();
    assert_eq!(decoder.colortype().unwrap(), tiff::ColorType::Gray(32));
    assert_eq!(decoder.dimensions().unwrap(), (w, h));
    let tiff::decoder::DecodingResult::F32(values) = decoder.read_image().unwrap() else {
        panic!("not floats")
    };
    let want: Vec<f32> = (0..w * h).map(|i| value(i % w, i / w)).collect();
    assert_eq!(
        values, want,
        "an in-focus grey float TIFF comes out as it went in"
    );
    if let Some(info) = tool("iinfo", &[&s(&out)]) {
        assert!(info.contains("1 channel, float tiff"), "{info}");
    }
}

/// A TIFF of two images (pages, or a page and its reduced-size preview): the first is read
/// and written, alone, and the run says the rest was left out; a TIFF of one image says
/// nothing of the kind.
#[test]
fn a_tiffs_images_after_the_first_are_left_out_and_said_so() {
    use tiff::encoder::{colortype::RGB8, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16u32, 12u32);
    let first: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 256) as u8).collect();
    let write = |name: &str, pages: usize| {
        let path = dir.path().join(name);
        let mut encoder = TiffEncoder::new(std::fs::File::create(&path).unwrap()).unwrap();
        encoder.write_image::<RGB8>(w, h, &first).unwrap();
        if pages > 1 {
            let preview = vec![255u8; (w * h * 3 / 4) as usize];
            encoder.write_image::<RGB8>(w / 2, h / 2, &preview).unwrap();
        }
        path
    };
    let coc = dir.path().join("coc.png");
    image::save_buffer(
        &coc,
        &vec![0u8; (w * h) as usize],
        w,
        h,
        image::ColorType::L8,
    )
    .unwrap();
    let run = |input: &Path, out: &str| {
        let out = dir.path().join(out);
        let o = shutter(&[
            "dof",
            "--color",
            &s(input),
            "--coc-map",
            &s(&coc),
            "--coc-scale",
            "0",
            "-o",
            &s(&out),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        (stderr(&o), out)
    };
    let (said, out) = run(&write("pages.tif", 2), "pages_out.tif");
    assert!(said.contains("more images after its first"), "{said}");
    let file = std::fs::File::open(&out).unwrap();
    let mut decoder = tiff::decoder::Decoder::new(file).unwrap();
    assert_eq!(decoder.dimensions().unwrap(), (w, h));
    assert!(!decoder.more_images(), "the output holds one image");
    let tiff::decoder::DecodingResult::U8(pixels) = decoder.read_image().unwrap() else {
        panic!("not 8-bit")
    };
    assert_eq!(pixels, first, "the first image, in focus, as it came");
    let (said, _) = run(&write("one.tif", 1), "one_out.tif");
    assert!(!said.contains("more images"), "{said}");
}

/// A painted map is the picture it was painted on: one of another size than the photo is
/// refused, larger as well as smaller, naming the map, before any output is written (an 8/16-bit
/// file has no data window to be placed by, so a map made at twice the photo's size was cut
/// to its top-left corner and blurred the wrong places without a word).
#[test]
fn a_map_of_another_size_than_the_photo_is_refused_larger_as_well_as_smaller() {
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("photo.png");
    write_png(&photo, 16, 12, None, |_| {});
    for (w, h) in [(32u32, 24u32), (17, 12), (16, 13), (15, 12)] {
        let map = dir.path().join(format!("coc_{w}x{h}.png"));
        image::save_buffer(
            &map,
            &vec![255u8; (w * h) as usize],
            w,
            h,
            image::ColorType::L8,
        )
        .unwrap();
        let out = dir.path().join("out.png");
        let o = shutter(&[
            "dof",
            "--color",
            &s(&photo),
            "--coc-map",
            &s(&map),
            "-o",
            &s(&out),
        ]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{w}x{h}: {err}");
        assert!(
            err.contains("size mismatch")
                && err.contains(&format!("coc_{w}x{h}.png"))
                && err.contains(&format!("{w}x{h} but the color pass is 16x12")),
            "{w}x{h}: {err}"
        );
        assert!(!out.exists(), "{w}x{h}: nothing is written");
    }
}

/// A PNG chunk: its length, kind, data and CRC (PNG 3rd ed., 5.3).
fn png_chunk(kind: &[u8; 4], data: &[u8]) -> Vec<u8> {
    let crc = crate::support::malformed::crc32(&[&kind[..], data].concat());
    let mut chunk = (data.len() as u32).to_be_bytes().to_vec();
    chunk.extend(kind);
    chunk.extend(data);
    chunk.extend(crc.to_be_bytes());
    chunk
}

/// A PNG's header chunks as the png crate reads them.
fn png_header(path: &Path) -> png::Reader<std::io::BufReader<std::fs::File>> {
    png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()))
        .read_info()
        .unwrap()
}

/// `png`'s bytes with `early` spliced in after its IHDR and `late` before its IEND.
fn splice_png(png: &Path, early: &[u8], late: &[u8]) {
    let bytes = std::fs::read(png).unwrap();
    // The signature (8) and IHDR (25) first; IEND, the last 12 bytes.
    let (head, rest) = bytes.split_at(33);
    let (body, end) = rest.split_at(rest.len() - 12);
    assert_eq!(&end[4..8], b"IEND");
    std::fs::write(png, [head, early, body, late, end].concat()).unwrap();
}

/// An eXIf and text after a PNG's image data (where libpng writes them, and where exiftool and
/// Pillow read them) are read as those before it: the photo is turned as its orientation says
/// (so a map painted on the upright photo lines up), and its EXIF and text come out again.
#[test]
fn a_pngs_exif_and_text_after_its_image_data_are_read() {
    let dir = tempfile::tempdir().unwrap();
    // Stored 12 wide and 16 high, orientation 6 (turn 90° clockwise to view): upright 16 × 12.
    let photo = dir.path().join("late.png");
    write_png(&photo, 12, 16, None, |_| {});
    let late = [
        png_chunk(b"eXIf", &exif(6)),
        png_chunk(b"tEXt", b"Comment\0written late"),
    ]
    .concat();
    splice_png(&photo, &[], &late);
    let map = dir.path().join("coc.png");
    image::save_buffer(&map, &[0u8; 16 * 12], 16, 12, image::ColorType::L8).unwrap();
    let out = dir.path().join("out.png");
    let o = shutter(&[
        "dof",
        "--color",
        &s(&photo),
        "--coc-map",
        &s(&map),
        "-o",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let reader = png_header(&out);
    let info = reader.info();
    assert_eq!((info.width, info.height), (16, 12), "turned upright");
    let exif = info.exif_metadata.as_ref().expect("the EXIF comes out");
    assert!(exif.windows(4).any(|w| w == b"ShTs"), "its Make is kept");
    let texts: Vec<(&str, &str)> = info
        .uncompressed_latin1_text
        .iter()
        .map(|t| (t.keyword.as_str(), t.text.as_str()))
        .filter(|(keyword, _)| !keyword.starts_with("shutter/"))
        .collect();
    assert_eq!(texts, [("Comment", "written late")]);
    if let Some(tags) = exiftool(&out) {
        assert_eq!(tags["Make"], "ShTs", "{tags}");
        assert!(
            tags.get("Orientation").is_none() || tags["Orientation"] == 1,
            "not turned twice: {tags}"
        );
    }
}

/// An iTXt's language tag and translated keyword come out with it.
#[test]
fn a_pngs_international_text_keeps_its_language() {
    let dir = tempfile::tempdir().unwrap();
    let photo = dir.path().join("lang.png");
    write_png(&photo, 16, 12, None, |_| {});
    let itxt = png_chunk(
        b"iTXt",
        "Description\0\0\0de-CH\0Beschreibung\0Été ✓".as_bytes(),
    );
    splice_png(&photo, &itxt, &[]);
    let out = dir.path().join("out.png");
    let o = dof_still(&photo, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let reader = png_header(&out);
    let utf8 = &reader.info().utf8_text;
    assert_eq!(utf8.len(), 1);
    assert_eq!(
        (
            utf8[0].keyword.as_str(),
            utf8[0].language_tag.as_str(),
            utf8[0].translated_keyword.as_str(),
            utf8[0].get_text().unwrap().as_str()
        ),
        ("Description", "de-CH", "Beschreibung", "Été ✓")
    );
}

/// A straight-alpha photo's colour under alpha 0 (a cut-out's background, a texture's
/// bleed) comes out as it came where nothing covers the pixel, as Pillow keeps it (`oiiotool`
/// premultiplies as it reads, and drops it): 8- and 16-bit PNG, on a frame that does not
/// blur. Premultiplied on read, it had come out black. A JPEG holds the photo over black
/// (`a_jpeg_of_an_rgba_photo_holds_its_straight_colour_and_says_alpha_is_dropped`): black
/// there.
#[test]
fn a_photos_colour_under_alpha_0_comes_out_as_it_came() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (32u32, 8u32);
    let hidden = |i: u32| i % w < 12;
    let rgba8: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            if hidden(i) {
                [200, 50, (i % 7 * 30) as u8, 0]
            } else {
                [90, 160, 220, (128 + i % 3 * 60) as u8]
            }
        })
        .collect();
    let input8 = dir.path().join("in8.png");
    image::save_buffer(&input8, &rgba8, w, h, image::ColorType::Rgba8).unwrap();
    let rgba16: Vec<u16> = rgba8.iter().map(|&v| v as u16 * 257 + 3).collect();
    let rgba16: Vec<u16> = (rgba16.chunks(4))
        .flat_map(|p| [p[0], p[1], p[2], if p[3] == 3 { 0 } else { p[3] }])
        .collect();
    let bytes: Vec<u8> = rgba16.iter().flat_map(|v| v.to_ne_bytes()).collect();
    let input16 = dir.path().join("in16.png");
    image::save_buffer(&input16, &bytes, w, h, image::ColorType::Rgba16).unwrap();
    let out = dir.path().join("out8.png");
    let o = dof_still(&input8, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let got = image::open(&out).unwrap().to_rgba8();
    for (i, (g, want)) in got.pixels().zip(rgba8.chunks(4)).enumerate() {
        assert_eq!(&g.0[..], want, "8-bit, pixel {i}");
    }
    let out = dir.path().join("out16.png");
    let o = dof_still(&input16, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let got = image::open(&out).unwrap().to_rgba16();
    for (i, (g, want)) in got.pixels().zip(rgba16.chunks(4)).enumerate() {
        let close = g.0.iter().zip(want).all(|(&g, &w)| g.abs_diff(w) <= 1);
        assert!(close, "16-bit, pixel {i}: {:?} for {want:?}", g.0);
    }
    let out = dir.path().join("out.jpg");
    let o = dof_still(&input8, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let got = image::open(&out).unwrap().to_rgb8();
    // Each channel's mean away from the edge (JPEG smooths colour: up to 9 codes a pixel
    // here): black, what alpha 0 over black is.
    let region: Vec<[u8; 3]> = (1..8)
        .flat_map(|x| (0..h).map(move |y| (x, y)))
        .map(|(x, y)| got.get_pixel(x, y).0)
        .collect();
    for c in 0..3 {
        let mean = region.iter().map(|p| p[c] as f64).sum::<f64>() / region.len() as f64;
        assert!(mean <= 4.0, "JPEG, channel {c}: mean {mean}");
    }
}

/// A 4:2:0 JPEG goes out 4:2:0 with each chroma sample the mean of its block, as libjpeg
/// makes it: the encoder's default (the block's top-left pixel) moved the chroma half a
/// pixel, so a still frame of a colour gradient came back with Cb 2.4 codes off on average
/// (1.8 codes a channel) and drifted further each pass. Found by an outside probe; Pillow's
/// re-save of the same file is off by 0.17 codes a channel.
#[test]
fn a_subsampled_jpeg_keeps_its_chroma_in_place() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64u16, 48u16);
    let mut rgb = Vec::new();
    for y in 0..h as u32 {
        for x in 0..w as u32 {
            let (u, v) = (x * 255 / (w as u32 - 1), y * 255 / (h as u32 - 1));
            rgb.extend([u as u8, v as u8, (255 - u) as u8]);
        }
    }
    let input = dir.path().join("grad.jpg");
    let mut encoder = jpeg_encoder::Encoder::new_file(&input, 95).unwrap();
    encoder.set_sampling_factor(jpeg_encoder::SamplingFactor::R_4_2_0);
    encoder.set_chroma_subsampling_method(jpeg_encoder::ChromaSubsamplingMethod::Average);
    encoder
        .encode(&rgb, w, h, jpeg_encoder::ColorType::Rgb)
        .unwrap();
    let out = dir.path().join("out.jpg");
    let o = dof_still(&input, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    let decoded = |p: &Path| image::open(p).unwrap().to_rgb8().into_raw();
    let (a, b) = (decoded(&input), decoded(&out));
    let cb = |p: &[u8]| -0.1687 * p[0] as f64 - 0.3313 * p[1] as f64 + 0.5 * p[2] as f64;
    let n = (w as usize * h as usize) as f64;
    let shift: f64 = a
        .chunks(3)
        .zip(b.chunks(3))
        .map(|(p, q)| cb(q) - cb(p))
        .sum::<f64>()
        / n;
    let off: f64 = a
        .iter()
        .zip(&b)
        .map(|(&p, &q)| (p as f64 - q as f64).abs())
        .sum::<f64>()
        / (3.0 * n);
    assert!(
        shift.abs() < 0.6 && off < 0.8,
        "Cb moved {shift}, {off} codes a channel"
    );
}

/// A float TIFF of straight alpha (ExtraSamples = 2) is premultiplied as it is read, as an
/// 8/16-bit one is: a still frame comes back as the colour the file means. It had been read
/// as premultiplied already, so its float TIFF came back declared associated with colour
/// above its alpha (four times too bright under alpha 0.25), and a PNG of it four times too
/// bright. Found by an outside probe (oiiotool premultiplies the same file on read). The same
/// file declared associated comes back as stored.
#[test]
fn a_float_tiff_of_straight_alpha_is_premultiplied_as_it_is_read() {
    use tiff::encoder::{colortype, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (8u32, 4u32);
    let pixels: Vec<f32> = (0..w * h).flat_map(|_| [0.8, 0.4, 0.2, 0.25]).collect();
    for (extra, name) in [(2u16, "straight"), (1, "associated")] {
        let input = dir.path().join(format!("{name}.tif"));
        let mut tiff = TiffEncoder::new(std::fs::File::create(&input).unwrap()).unwrap();
        let mut image = tiff.new_image::<colortype::RGBA32Float>(w, h).unwrap();
        image
            .encoder()
            .write_tag(tiff::tags::Tag::ExtraSamples, &[extra][..])
            .unwrap();
        image.write_data(&pixels).unwrap();
        let out = dir.path().join(format!("{name}.out.tif"));
        let o = dof_still(&input, &out, &[]);
        assert!(o.status.success(), "{}", stderr(&o));
        let mut decoder = tiff::decoder::Decoder::new(std::fs::File::open(&out).unwrap()).unwrap();
        let tiff::decoder::DecodingResult::F32(got) = decoder.read_image().unwrap() else {
            panic!("{name}: not float");
        };
        let scale = if extra == 2 { 0.25 } else { 1.0 };
        let want = [0.8 * scale, 0.4 * scale, 0.2 * scale, 0.25];
        for p in got.chunks(4) {
            let close = p.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-6);
            assert!(close, "{name}: {p:?} for {want:?}");
        }
    }
}

/// Indexed colour: one 8-bit index a pixel into the file's ColorMap, as the tiff crate writes
/// no such file.
struct Palette8;

impl tiff::encoder::colortype::ColorType for Palette8 {
    type Inner = u8;
    const TIFF_VALUE: tiff::tags::PhotometricInterpretation =
        tiff::tags::PhotometricInterpretation::RGBPalette;
    const BITS_PER_SAMPLE: &'static [u16] = &[8];
    const SAMPLE_FORMAT: &'static [tiff::tags::SampleFormat] = &[tiff::tags::SampleFormat::Uint];
    fn horizontal_predict(_: &[u8], _: &mut Vec<u8>) {
        unreachable!("written without a predictor")
    }
}

/// The bits a sample and the colour type of a TIFF, and whether it holds a ColorMap.
fn tiff_coding(path: &Path) -> (tiff::ColorType, bool) {
    let mut decoder = tiff::decoder::Decoder::new(std::fs::File::open(path).unwrap()).unwrap();
    let map = decoder.find_tag(tiff::tags::Tag::ColorMap).unwrap();
    (decoder.colortype().unwrap(), map.is_some())
}

/// An indexed-colour TIFF (Pillow's mode 'P', a GIF converted) is read through its ColorMap
/// and comes out RGB, with its profile: refused before ("an indexed-colour (palette) TIFF,
/// which the TIFF decoder does not read"). Three maps: 8-bit values widened as v·257 (LZW,
/// with an Adobe RGB profile) and as v·256 (as Pillow writes them), both 8-bit codes (their
/// high bytes, as libtiff and Pillow read them) in an 8-bit output; and a map of finer
/// values, in a 16-bit output holding them exactly. Expected: the map's entries, as written.
#[test]
fn a_palette_tiff_reads_through_its_colour_map_and_comes_out_rgb() {
    use tiff::encoder::{Compression, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (32u32, 16u32);
    let indices: Vec<u8> = (0..w * h).map(|i| (i * 37 % 256) as u8).collect();
    let entry = |i: usize| [(i * 7 % 256) as u16, 255 - i as u16, (i * 13 % 256) as u16];
    let fine = |i: usize| {
        [
            i as u16 * 251 + 3,
            65535 - i as u16 * 199,
            (i as u16) << 8 | 0x5A,
        ]
    };
    let icc = adobe_icc();
    for (name, widen, lzw) in [("v257", Some(257u16), true), ("v256", Some(256), false)]
        .into_iter()
        .chain([("fine", None, false)])
    {
        // All the reds, then the greens, then the blues (TIFF 6.0, ColorMap).
        let map: Vec<u16> = (0..3)
            .flat_map(|c| {
                (0..256).map(move |i| match widen {
                    Some(k) => entry(i)[c] * k,
                    None => fine(i)[c],
                })
            })
            .collect();
        let input = dir.path().join(format!("{name}.tif"));
        let file = std::fs::File::create(&input).unwrap();
        let mut tiff = TiffEncoder::new(file).unwrap();
        if lzw {
            tiff = tiff.with_compression(Compression::Lzw);
        }
        let mut image = tiff.new_image::<Palette8>(w, h).unwrap();
        let directory = image.encoder();
        directory
            .write_tag(tiff::tags::Tag::ColorMap, &map[..])
            .unwrap();
        if widen == Some(257) {
            directory
                .write_tag(tiff::tags::Tag::Unknown(34675), &icc[..])
                .unwrap();
        }
        image.write_data(&indices).unwrap();
        let out = dir.path().join(format!("{name}.out.tif"));
        let o = dof_still_of(&input, (w, h), &out, &[]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let (coding, has_map) = tiff_coding(&out);
        assert!(!has_map, "{name}: the output carries a ColorMap");
        let read = image::open(&out).unwrap();
        match widen {
            Some(_) => {
                assert_eq!(coding, tiff::ColorType::RGB(8), "{name}");
                let got = read.to_rgb8();
                for (k, p) in got.pixels().enumerate() {
                    let want = entry(indices[k] as usize).map(|v| v as i32);
                    // The Adobe profile's curve there and back: within a code.
                    let off = (0..3).map(|c| (p[c] as i32 - want[c]).abs()).max().unwrap();
                    assert!(
                        off <= (widen == Some(257)) as i32,
                        "{name} {k}: {p:?} {want:?}"
                    );
                }
            }
            None => {
                assert_eq!(coding, tiff::ColorType::RGB(16), "{name}");
                let got = read.to_rgb16();
                for (k, p) in got.pixels().enumerate() {
                    assert_eq!(p.0, fine(indices[k] as usize), "{name} {k}");
                }
            }
        }
        if widen == Some(257) {
            let file = std::fs::File::open(&out).unwrap();
            let mut decoder = tiff::decoder::Decoder::new(file).unwrap();
            let profile = decoder.get_tag_u8_vec(tiff::tags::Tag::Unknown(34675));
            assert_eq!(profile.unwrap(), icc, "{name}: its profile");
        }
    }
}

/// YCbCr, sampled 1×1 and stored uncompressed, with BT.709's coefficients and video range
/// (ReferenceBlackWhite 16–235, chroma 16–240) in its tags, comes out RGB as TIFF 6.0
/// (section 22) converts it: against that conversion written out here, and against
/// OpenImageIO's read of the file (libtiff's `TIFFYCbCrToRGB`, whose tables truncate the
/// full-range luma to an integer) within 2 codes, 1 on average (0.54 measured). Refused before ("a YCbCr TIFF
/// …, which the TIFF decoder does not read").
#[test]
fn a_ycbcr_tiff_comes_out_rgb_by_its_coefficients_and_reference_black_and_white() {
    use tiff::encoder::{colortype, Rational, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (24u32, 16u32);
    let ycc: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            let (x, y) = (i % w, i / w);
            [
                16 + (x * 9) as u8,
                16 + (y * 14) as u8,
                128 + (x as u8 * 4) - 40,
            ]
        })
        .collect();
    let input = dir.path().join("ycc.tif");
    let mut tiff = TiffEncoder::new(std::fs::File::create(&input).unwrap()).unwrap();
    let mut image = tiff.new_image::<colortype::YCbCr8>(w, h).unwrap();
    let rational = |n: u32, d: u32| Rational { n, d };
    let coefficients = [
        rational(2126, 10000),
        rational(7152, 10000),
        rational(722, 10000),
    ];
    let reference = [16, 235, 128, 240, 128, 240].map(|v| rational(v, 1));
    let directory = image.encoder();
    directory
        .write_tag(tiff::tags::Tag::Unknown(529), &coefficients[..])
        .unwrap();
    directory
        .write_tag(tiff::tags::Tag::Unknown(532), &reference[..])
        .unwrap();
    image.write_data(&ycc).unwrap();
    let out = dir.path().join("ycc.out.tif");
    let o = dof_still_of(&input, (w, h), &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(tiff_coding(&out).0, tiff::ColorType::RGB(8));
    let got = image::open(&out).unwrap().to_rgb8();
    // Full range: Y' = (Y − 16)·255/219, Cb' = (Cb − 128)·127/112; then the section's
    // R = Y' + Cr'(2 − 2·0.2126), B = Y' + Cb'(2 − 2·0.0722), G = (Y' − 0.0722 B − 0.2126 R)
    // / 0.7152.
    for (k, p) in got.pixels().enumerate() {
        let [y, cb, cr] = [0, 1, 2].map(|c| ycc[3 * k + c] as f64);
        let y = (y - 16.0) * 255.0 / 219.0;
        let (cb, cr) = ((cb - 128.0) * 127.0 / 112.0, (cr - 128.0) * 127.0 / 112.0);
        let r = y + cr * (2.0 - 2.0 * 0.2126);
        let b = y + cb * (2.0 - 2.0 * 0.0722);
        let g = (y - 0.0722 * b - 0.2126 * r) / 0.7152;
        let want = [r, g, b].map(|v| v.clamp(0.0, 255.0));
        for c in 0..3 {
            assert!((p[c] as f64 - want[c]).abs() <= 0.51, "{k}: {p:?} {want:?}");
        }
    }
    if let Some((most, mean)) = against_oiiotool(&input, &got, &dir.path().join("ref.png")) {
        assert!(
            most <= 2 && mean <= 1.0,
            "off by {most} at most, {mean} on average"
        );
    }
}

/// How far `got` lies from OpenImageIO's 8-bit RGB read of `input` (written to `reference`):
/// the largest difference in codes and the mean; `None` where oiiotool is not installed.
fn against_oiiotool(input: &Path, got: &image::RgbImage, reference: &Path) -> Option<(u8, f64)> {
    let args = [
        &s(input),
        "--ch",
        "R,G,B",
        "-d",
        "uint8",
        "-o",
        &s(reference),
    ];
    let converted = run_tool("oiiotool", &args)?;
    assert!(converted.status.success(), "{}", stderr(&converted));
    let want = image::open(reference).unwrap().to_rgb8();
    let (mut most, mut sum) = (0u8, 0u64);
    for (p, q) in got.pixels().zip(want.pixels()) {
        for c in 0..3 {
            most = most.max(p[c].abs_diff(q[c]));
            sum += p[c].abs_diff(q[c]) as u64;
        }
    }
    Some((most, sum as f64 / (3 * got.width() * got.height()) as f64))
}

/// A JPEG-compressed YCbCr TIFF, its chroma subsampled 2×2 (what `tiffcp -c jpeg`, cameras
/// and `oiiotool --compression jpeg` write) comes out RGB: against OpenImageIO's read of the
/// same file (libjpeg's upsampling and conversion) within 8 codes, 1 on average (zune-jpeg
/// upsamples chroma otherwise: 4 and 0.4 measured on this picture). Refused before.
#[test]
fn a_jpeg_compressed_ycbcr_tiff_reads_as_libjpeg_reads_it() {
    use tiff::encoder::{colortype, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64u32, 48u32);
    let rgb: Vec<u8> = (0..w * h)
        .flat_map(|i| {
            let (x, y) = (i % w, i / w);
            match (x / 16 + y / 16) % 4 {
                0 => [220, 40, 30],
                1 => [(x * 4) as u8, (y * 5) as u8, 128],
                2 => [30, 200, 60],
                _ => [250, 250, (x * 3) as u8],
            }
        })
        .collect();
    let plain = dir.path().join("rgb.tif");
    let mut tiff = TiffEncoder::new(std::fs::File::create(&plain).unwrap()).unwrap();
    tiff.write_image::<colortype::RGB8>(w, h, &rgb).unwrap();
    let input = dir.path().join("jpeg.tif");
    let made = run_tool(
        "tiffcp",
        &["-c", "jpeg:90", "-r", "16", &s(&plain), &s(&input)],
    );
    let Some(made) = made else { return };
    assert!(made.status.success(), "{}", stderr(&made));
    let mut decoder = tiff::decoder::Decoder::new(std::fs::File::open(&input).unwrap()).unwrap();
    let photometric = decoder.get_tag_u32(tiff::tags::Tag::PhotometricInterpretation);
    assert_eq!(photometric.unwrap(), 6, "tiffcp wrote no YCbCr");
    let out = dir.path().join("jpeg.out.tif");
    let o = dof_still_of(&input, (w, h), &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(tiff_coding(&out).0, tiff::ColorType::RGB(8));
    let got = image::open(&out).unwrap().to_rgb8();
    let reference = dir.path().join("ref.png");
    let Some((most, mean)) = against_oiiotool(&input, &got, &reference) else {
        return;
    };
    assert!(
        most <= 8 && mean <= 1.0,
        "off by {most} at most, {mean} on average"
    );
}

/// A YCbCr TIFF subsampled 2×2 and not JPEG-compressed, whose layout the TIFF decoder does
/// not deliver, is refused naming the file, what it is and the command that converts it.
#[test]
fn a_subsampled_uncompressed_ycbcr_tiff_is_refused_saying_how_to_convert_it() {
    use tiff::encoder::{colortype, TiffEncoder};
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("ycc22.tif");
    let mut tiff = TiffEncoder::new(std::fs::File::create(&input).unwrap()).unwrap();
    let mut image = tiff.new_image::<colortype::YCbCr8>(8, 4).unwrap();
    image
        .encoder()
        .write_tag(tiff::tags::Tag::ChromaSubsampling, &[2u16, 2][..])
        .unwrap();
    image.write_data(&[128u8; 8 * 4 * 3]).unwrap();
    let o = dof_still_of(&input, (8, 4), &dir.path().join("out.tif"), &[]);
    assert!(!o.status.success());
    let err = stderr(&o);
    for part in [
        "ycc22.tif",
        "subsampled 2×2",
        "not JPEG-compressed",
        "oiiotool in.tif",
    ] {
        assert!(err.contains(part), "{part}: {err}");
    }
}

/// A painted map of one value a pixel (a CoC map, a depth map) saved as RGB: grey (R = G = B)
/// is read without a word; in colour, its R is read (as before) and a warning names the file
/// and the channel read. Both kinds of map, both cases; the CoC map's R is what blurs.
#[test]
fn a_painted_map_in_colour_says_which_channel_is_read_and_a_grey_one_says_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (32u32, 16u32);
    let color = dir.path().join("photo.png");
    let pixels: Vec<u8> = (0..w * h * 3).map(|i| (i * 7 % 256) as u8).collect();
    image::save_buffer(&color, &pixels, w, h, image::ColorType::Rgb8).unwrap();
    let map = |name: &str, rgb: fn(u32) -> [u8; 3]| {
        let path = dir.path().join(name);
        let bytes: Vec<u8> = (0..w * h).flat_map(|i| rgb(i % w)).collect();
        image::save_buffer(&path, &bytes, w, h, image::ColorType::Rgb8).unwrap();
        path
    };
    // No blur in R: a map in colour whose R is 0 leaves the photo as it is.
    let grey = map("grey.png", |x| [(x * 8) as u8; 3]);
    let colour = map("colour.png", |x| [0, (x * 8) as u8, 255]);
    for (kind, flag, extra) in [
        ("coc", "--coc-map", &[][..]),
        (
            "depth",
            "--depth",
            &[
                "--preset",
                "painted",
                "--focal-length",
                "50",
                "--f-stop",
                "2",
                "--focus-distance",
                "10",
            ][..],
        ),
    ] {
        for (map, differs) in [(&grey, false), (&colour, true)] {
            let out = dir.path().join(format!("{kind}.out.png"));
            let (c, m, o) = (s(&color), s(map), s(&out));
            let mut args = vec!["dof", "--color", &c, flag, &m, "-o", &o, "--json"];
            args.extend(extra);
            let run = shutter(&args);
            assert!(run.status.success(), "{kind}: {}", stderr(&run));
            let warnings = json_warnings(&run);
            let named = warnings.contains(&s(map)) && warnings.contains("its R channel is read");
            assert_eq!(named, differs, "{kind} {}: {warnings}", s(map));
            if kind == "coc" && differs {
                let got = image::open(&out).unwrap().to_rgb8().into_raw();
                assert_eq!(
                    got, pixels,
                    "the CoC map's R (0 everywhere) is not what was read"
                );
            }
        }
    }
}

/// A sequence of painted maps in colour is noted once, at the first frame found so, not once
/// a file (each note named its own file, so a 100-frame run said it 100 times).
#[test]
fn a_sequence_of_maps_in_colour_is_noted_once() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16u32, 8u32);
    for frame in 1..=3 {
        let pixels: Vec<u8> = (0..w * h * 3).map(|i| (i * 5 % 256) as u8).collect();
        let color = dir.path().join(format!("photo.{frame:04}.png"));
        image::save_buffer(&color, &pixels, w, h, image::ColorType::Rgb8).unwrap();
        let map: Vec<u8> = (0..w * h)
            .flat_map(|i| [0, (i % w * 8) as u8, 200])
            .collect();
        let path = dir.path().join(format!("coc.{frame:04}.png"));
        image::save_buffer(&path, &map, w, h, image::ColorType::Rgb8).unwrap();
    }
    let (c, m) = (
        s(&dir.path().join("photo.####.png")),
        s(&dir.path().join("coc.####.png")),
    );
    let o = s(&dir.path().join("out.####.png"));
    let run = shutter(&["dof", "--color", &c, "--coc-map", &m, "-o", &o, "--json"]);
    assert!(run.status.success(), "{}", stderr(&run));
    let report: serde_json::Value = serde_json::from_str(&stdout(&run)).unwrap();
    let notes: Vec<&str> = (report["warnings"].as_array().unwrap().iter())
        .filter_map(|w| w.as_str())
        .filter(|w| w.contains("saved in colour"))
        .collect();
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(notes[0].contains("coc.0001.png") && notes[0].contains("frame 1"));
}
