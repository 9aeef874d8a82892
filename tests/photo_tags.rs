//! What a photo's own tags say of the output, read back by exiftool (skipped with a note
//! where it is not installed, unless SHUTTER_REQUIRE_TOOLS=1): the EXIF and XMP of a photo
//! turned upright describe the upright pixels (its dimensions, its per-axis resolutions, no
//! thumbnail of the unturned view).

use std::path::Path;

use crate::photos::{blur, exiftool_set, portrait_on_its_side, tool, velocity_map};
use crate::support::*;

/// `exiftool -j -n -G1` of a file: each tag under its group (`IFD0:XResolution`,
/// `JFIF:XResolution`), where the same name in two places would otherwise be one of them.
fn exiftool(path: &Path) -> Option<serde_json::Value> {
    tool("exiftool", &["-j", "-n", "-G1", &s(path)]).map(|out| {
        let all: serde_json::Value = serde_json::from_str(&out).unwrap();
        all[0].clone()
    })
}

/// A JPEG of `sw` × `sh` stored pixels, encoded by the image crate.
fn write_jpeg(path: &Path, rgb: &[u8], sw: u32, sh: u32) {
    image::save_buffer(path, rgb, sw, sh, image::ColorType::Rgb8).unwrap();
}

/// A photo stored on its side (48 × 32, orientation 6: upright 32 × 48) whose EXIF says so
/// as a camera writes it: ExifImageWidth and ExifImageHeight of the stored pixels, X and Y
/// resolutions that differ, and a thumbnail of the stored view (IFD1). Out of it, in a JPEG,
/// a PNG and a TIFF, the EXIF says what the output holds: the upright size, the resolutions
/// swapped with the axes, and no thumbnail (dropped rather than turned: a thumbnail of the
/// unturned view shows sideways once the orientation says 1). An upright photo keeps its
/// thumbnail.
#[test]
fn the_exif_of_a_photo_turned_upright_says_the_upright_size_and_holds_no_sideways_thumbnail() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let (sw, sh) = (48u32, 32u32);
    write_jpeg(&p("thumb.jpg"), &[200u8; 12 * 8 * 3], 12, 8);
    let thumb = format!("-ThumbnailImage<={}", s(&p("thumb.jpg")));
    let tags = [
        "-Orientation#=6",
        "-ExifImageWidth=48",
        "-ExifImageHeight=32",
        "-IFD0:XResolution=300",
        "-IFD0:YResolution=150",
        "-IFD0:ResolutionUnit=inches",
        &thumb,
    ];
    let input = p("side.jpg");
    write_jpeg(&input, &portrait_on_its_side(sw, sh), sw, sh);
    if !exiftool_set(&input, &tags) {
        return;
    }
    let before = exiftool(&input).unwrap();
    let thumbnail = before["IFD1:ThumbnailLength"].clone();
    assert_eq!(thumbnail.as_u64().map(|n| n > 0), Some(true), "{before}");
    let velocity = p("v.png");
    velocity_map(&velocity, 32, 48, |_, _| 0.0);
    for out in ["out.jpg", "out.png", "out.tif"] {
        blur(&input, &velocity, &p(out), &[]);
        let tags = exiftool(&p(out)).unwrap();
        let get = |name: &str| tags[name].clone();
        let group = match out {
            "out.jpg" => "File",
            "out.png" => "PNG",
            _ => "IFD0",
        };
        let size = (
            get(&format!("{group}:ImageWidth")),
            get(&format!("{group}:ImageHeight")),
        );
        assert_eq!(size, (32.into(), 48.into()), "{out}: {tags}");
        let orientation = tags.get("IFD0:Orientation");
        assert!(orientation.is_none_or(|o| o == 1), "{out}: {tags}");
        let exif_size = (
            get("ExifIFD:ExifImageWidth"),
            get("ExifIFD:ExifImageHeight"),
        );
        assert_eq!(
            exif_size,
            (32.into(), 48.into()),
            "{out}: the upright size: {tags}"
        );
        // IFD0's resolutions belong to the axes: turned with them.
        let resolution = (get("IFD0:XResolution"), get("IFD0:YResolution"));
        assert_eq!(resolution, (150.into(), 300.into()), "{out}: {tags}");
        let thumbnail = tags.get("IFD1:ThumbnailLength");
        assert!(thumbnail.is_none(), "{out}: thumbnail left: {tags}");
    }
    // Upright already: nothing turned, the thumbnail is as true as it was.
    let upright = p("upright.jpg");
    write_jpeg(&upright, &[90u8; 32 * 48 * 3], 32, 48);
    let tags = ["-ExifImageWidth=32", "-ExifImageHeight=48", &thumb];
    exiftool_set(&upright, &tags);
    blur(&upright, &velocity, &p("upright_out.jpg"), &[]);
    let tags = exiftool(&p("upright_out.jpg")).unwrap();
    assert_eq!(tags["IFD1:ThumbnailLength"], thumbnail, "{tags}");
    let size = (
        &tags["ExifIFD:ExifImageWidth"],
        &tags["ExifIFD:ExifImageHeight"],
    );
    assert_eq!(size, (&32.into(), &48.into()), "{tags}");
}

/// The resolution each output holds, by exiftool: a JPEG's JFIF density (x, y, unit: 0 none,
/// 1 inches, 2 cm), a PNG's pHYs (x, y per unit: 0 none, 1 metre), a TIFF's XResolution,
/// YResolution and ResolutionUnit (1 none, 2 inches, 3 cm).
fn resolution(tags: &serde_json::Value, out: &str) -> (f64, f64, u64) {
    let [x, y, unit] = match out {
        "jpg" => [
            "JFIF:XResolution",
            "JFIF:YResolution",
            "JFIF:ResolutionUnit",
        ],
        "png" => [
            "PNG-pHYs:PixelsPerUnitX",
            "PNG-pHYs:PixelsPerUnitY",
            "PNG-pHYs:PixelUnits",
        ],
        _ => [
            "IFD0:XResolution",
            "IFD0:YResolution",
            "IFD0:ResolutionUnit",
        ],
    };
    let number = |name: &str| {
        tags[name]
            .as_f64()
            .unwrap_or_else(|| panic!("{out}: no {name}: {tags}"))
    };
    (
        number(x),
        number(y),
        tags[unit]
            .as_u64()
            .unwrap_or_else(|| panic!("{out}: no {unit}: {tags}")),
    )
}

/// A photo's resolution comes out as it went in (QA: a JPEG's JFIF density, a PNG's pHYs and
/// a TIFF's resolution tags were all written as none, 1:1), in each output format's own
/// place: the same numbers into the same format; into another, in its unit (inches for a
/// JPEG or TIFF from a PNG's metres; pixels per metre for a PNG from inches or centimetres,
/// rounded as pHYs holds integers), x and y apart. Turned upright by a quarter turn, x and y
/// trade places.
#[test]
fn a_photos_resolution_comes_out_in_every_format_as_it_went_in() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let grey = [120u8; 48 * 32 * 3];
    let inputs: [(&str, &[&str]); 4] = [
        (
            "in.jpg",
            &[
                "-JFIF:XResolution=300",
                "-JFIF:YResolution=150",
                "-JFIF:ResolutionUnit=inches",
            ],
        ),
        (
            "in.png",
            &[
                "-PNG-pHYs:PixelsPerUnitX=11811",
                "-PNG-pHYs:PixelsPerUnitY=5906",
                "-PNG-pHYs:PixelUnits=meters",
            ],
        ),
        (
            "in.tif",
            &["-XResolution=72", "-YResolution=144", "-ResolutionUnit=cm"],
        ),
        (
            "side.jpg",
            &[
                "-JFIF:XResolution=300",
                "-JFIF:YResolution=150",
                "-JFIF:ResolutionUnit=inches",
                "-Orientation#=6",
            ],
        ),
    ];
    for (name, tags) in inputs {
        image::save_buffer(p(name), &grey, 48, 32, image::ColorType::Rgb8).unwrap();
        if !exiftool_set(&p(name), tags) {
            return;
        }
    }
    let velocity = p("v.png");
    velocity_map(&velocity, 48, 32, |_, _| 0.0);
    let turned = p("v_turned.png");
    velocity_map(&turned, 32, 48, |_, _| 0.0);
    // (input, output format, x, y, unit) as exiftool reads them.
    let inch: f64 = 0.0254;
    let expected = [
        ("in.jpg", "jpg", 300.0, 150.0, 1),
        (
            "in.jpg",
            "png",
            (300.0 / inch).round(),
            (150.0 / inch).round(),
            1,
        ),
        ("in.jpg", "tif", 300.0, 150.0, 2),
        ("in.png", "png", 11811.0, 5906.0, 1),
        ("in.png", "jpg", 300.0, 150.0, 1),
        ("in.png", "tif", 11811.0 * inch, 5906.0 * inch, 2),
        ("in.tif", "tif", 72.0, 144.0, 3),
        ("in.tif", "jpg", 72.0, 144.0, 2),
        ("in.tif", "png", 7200.0, 14400.0, 1),
        ("side.jpg", "jpg", 150.0, 300.0, 1),
        (
            "side.jpg",
            "png",
            (150.0 / inch).round(),
            (300.0 / inch).round(),
            1,
        ),
        ("side.jpg", "tif", 150.0, 300.0, 2),
    ];
    for (input, format, x, y, unit) in expected {
        let out = p(&format!("{input}.{format}"));
        let v = if input == "side.jpg" {
            &turned
        } else {
            &velocity
        };
        blur(&p(input), v, &out, &[]);
        let tags = exiftool(&out).unwrap();
        let (gx, gy, gunit) = resolution(&tags, format);
        assert!(
            (gx - x).abs() < 1e-3 && (gy - y).abs() < 1e-3 && gunit == unit,
            "{input} → {format}: ({gx}, {gy}, {gunit}), not ({x}, {y}, {unit})"
        );
    }
}

/// Black and white columns of 64 × 8, which a blur averages in the light the file codes: the
/// size, the RGB codes, written as `plain.png` in `dir` (no colour chunks), and a velocity map
/// `v.png` that moves them 12 px.
fn striped(dir: &Path) -> ((u32, u32), Vec<u8>, std::path::PathBuf) {
    let (w, h) = (64u32, 8u32);
    let stripes: Vec<u8> = (0..w * h)
        .flat_map(|i| [if i % 2 == 0 { 255u8 } else { 0 }; 3])
        .collect();
    let velocity = dir.join("v.png");
    velocity_map(&velocity, w, h, |_, _| 12.0);
    png_with_chunks(&dir.join("plain.png"), (w, h), &stripes, None, &[]);
    ((w, h), stripes, velocity)
}

/// An 8-bit RGB PNG of `rgb`, written by the png crate with `icc` as its iCCP and then the
/// raw `chunks` (name, data) before its image data, in that order.
fn png_with_chunks(
    path: &Path,
    (w, h): (u32, u32),
    rgb: &[u8],
    icc: Option<&[u8]>,
    chunks: &[(&[u8; 4], Vec<u8>)],
) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut info = png::Info::with_size(w, h);
    info.color_type = png::ColorType::Rgb;
    info.bit_depth = png::BitDepth::Eight;
    info.icc_profile = icc.map(|icc| icc.to_vec().into());
    let encoder = png::Encoder::with_info(file, info).unwrap();
    let mut writer = encoder.write_header().unwrap();
    for (name, data) in chunks {
        writer
            .write_chunk(png::chunk::ChunkType(**name), data)
            .unwrap();
    }
    writer.write_image_data(rgb).unwrap();
}

/// gAMA's data: the encoding gamma × 100000.
fn gama(scaled: u32) -> Vec<u8> {
    scaled.to_be_bytes().to_vec()
}

/// Adobe RGB (1998)'s primaries and D65 white as cHRM holds them (× 100000): white x, y,
/// then red, green, blue.
const ADOBE_CHRM: [u32; 8] = [31270, 32900, 64000, 33000, 21000, 71000, 15000, 6000];

fn chrm(values: [u32; 8]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_be_bytes()).collect()
}

/// The pixels of a picture, as 8-bit RGB.
fn pixels(path: &Path) -> Vec<u8> {
    image::open(path).unwrap().to_rgb8().into_raw()
}

/// Two pictures' pixels are the same; else the first that differs is named.
fn assert_same_pixels(a: &Path, b: &Path, what: &str) {
    let (a, b) = (pixels(a), pixels(b));
    let first = a.iter().zip(&b).position(|(x, y)| x != y);
    assert!(
        a.len() == b.len() && first.is_none(),
        "{what}: sample {first:?} differs"
    );
}

/// A PNG's gAMA, cHRM and sRGB chunks and whether it holds an iCCP, by the png crate.
fn png_colour_chunks(path: &Path) -> (Option<u32>, Option<[u32; 8]>, bool, bool) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let reader = png::Decoder::new(file).read_info().unwrap();
    let info = reader.info();
    let chrm = info.chrm_chunk.map(|c| {
        let [w, r, g, b] = [c.white, c.red, c.green, c.blue];
        [w.0, w.1, r.0, r.1, g.0, g.1, b.0, b.1].map(|v| v.into_scaled())
    });
    let gamma = info.gama_chunk.map(|g| g.into_scaled());
    (gamma, chrm, info.srgb.is_some(), info.icc_profile.is_some())
}

/// The ICC profile a file embeds, as exiftool extracts it.
fn embedded_icc(path: &Path) -> Vec<u8> {
    let out = std::process::Command::new("exiftool")
        .args(["-b", "-ICC_Profile", &s(path)])
        .output()
        .unwrap();
    out.stdout
}

/// A PNG of no iCCP or sRGB chunk is coded as its gAMA and cHRM say (PNG 3rd ed., 4.3 and
/// 11.3.2: iCCP first, then sRGB, then gAMA and cHRM), not as sRGB (QA: both were ignored on
/// read and dropped on write): a linear one (gAMA 100000) blurs as the same codes do under
/// `--linear`; a PNG output holds the same chunks again, and no profile in their place; a
/// JPEG or TIFF, which have no such chunks, embed an ICC profile of the same curve
/// (light = code^(100000 / gAMA)) and primaries.
#[test]
fn a_pngs_gama_and_chrm_say_how_its_codes_are_coded_and_come_out_again() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let ((w, h), stripes, velocity) = striped(dir.path());
    let linear = [(b"gAMA", gama(100_000)), (b"cHRM", chrm(ADOBE_CHRM))];
    png_with_chunks(&p("linear.png"), (w, h), &stripes, None, &linear);
    blur(
        &p("plain.png"),
        &velocity,
        &p("plain_linear.png"),
        &["--linear"],
    );
    blur(&p("linear.png"), &velocity, &p("linear_out.png"), &[]);
    let (got, linear) = (p("linear_out.png"), p("plain_linear.png"));
    assert_same_pixels(&got, &linear, "a gAMA of 1.0 blurs as linear codes");
    assert_eq!(
        png_colour_chunks(&p("linear_out.png")),
        (Some(100_000), Some(ADOBE_CHRM), false, false),
        "the chunks again, and no iCCP"
    );

    // 1/2.2, as most gAMA chunks say: in a PNG again, and as a profile in a JPEG and a TIFF.
    let flat = vec![128u8; (w * h * 3) as usize];
    let chunks = [(b"gAMA", gama(45455)), (b"cHRM", chrm(ADOBE_CHRM))];
    png_with_chunks(&p("g22.png"), (w, h), &flat, None, &chunks);
    blur(&p("g22.png"), &velocity, &p("g22_out.png"), &[]);
    assert_eq!(
        png_colour_chunks(&p("g22_out.png")),
        (Some(45455), Some(ADOBE_CHRM), false, false)
    );
    // A flat grey round-trips through its own curve.
    assert_eq!(pixels(&p("g22_out.png")), flat);
    let Some(tags) = exiftool(&p("g22_out.png")) else {
        return;
    };
    assert!(
        (tags["PNG:Gamma"].as_f64().unwrap() - 2.2).abs() < 1e-3,
        "{tags}"
    );
    assert_eq!(tags["PNG:RedX"], 0.64, "{tags}");
    for out in ["g22_out.jpg", "g22_out.tif"] {
        blur(&p("g22.png"), &velocity, &p(out), &[]);
        let icc = embedded_icc(&p(out));
        let profile = moxcms::ColorProfile::new_from_slice(&icc)
            .unwrap_or_else(|e| panic!("{out}: no readable profile ({e:?}): {} bytes", icc.len()));
        for trc in [&profile.red_trc, &profile.green_trc, &profile.blue_trc] {
            let curve = trc.as_ref().unwrap().make_linear_evaluator().unwrap();
            for code in [0.25f32, 0.5, 0.75] {
                let expected = (code as f64).powf(100_000.0 / 45455.0);
                let got = curve.evaluate_value(code) as f64;
                assert!(
                    (got - expected).abs() < 1e-4,
                    "{out}: {code} → {got}, not {expected}"
                );
            }
        }
        let got = shutter::io::image::chromaticities(&icc).unwrap();
        let [wx, wy, rx, ry, gx, gy, bx, by] = ADOBE_CHRM.map(|v| v as f64 / 100_000.0);
        for ((x, y), (ex, ey)) in got.iter().zip([(rx, ry), (gx, gy), (bx, by), (wx, wy)]) {
            assert!(
                (x - ex).abs() < 1e-3 && (y - ey).abs() < 1e-3,
                "{out}: {got:?}"
            );
        }
        // The flat grey is the same code in the JPEG (within its quantisation).
        let back = pixels(&p(out));
        assert!(back.iter().all(|&c| c.abs_diff(128) <= 1), "{out}");
    }
    // An EXR holds no profile: cHRM's primaries and white as its chromaticities.
    blur(&p("g22.png"), &velocity, &p("g22_out.exr"), &[]);
    let meta = exr::meta::MetaData::read_from_file(p("g22_out.exr"), false).unwrap();
    let c = meta.headers[0]
        .shared_attributes
        .chromaticities
        .expect("chromaticities");
    let got = [c.white, c.red, c.green, c.blue]
        .map(|v| [v.0, v.1])
        .concat();
    let expected = ADOBE_CHRM.map(|v| v as f32 / 100_000.0);
    assert_eq!(got, expected);
    // A grey PNG: grey out, with a Gray profile of its curve in a JPEG.
    let grey = p("grey.png");
    let file = std::io::BufWriter::new(std::fs::File::create(&grey).unwrap());
    let mut encoder = png::Encoder::new(file, w, h);
    encoder.set_color(png::ColorType::Grayscale);
    encoder.set_source_gamma(png::ScaledFloat::from_scaled(45455));
    let mut writer = encoder.write_header().unwrap();
    writer
        .write_image_data(&vec![128u8; (w * h) as usize])
        .unwrap();
    writer.finish().unwrap();
    blur(&grey, &velocity, &p("grey_out.jpg"), &[]);
    let profile = moxcms::ColorProfile::new_from_slice(&embedded_icc(&p("grey_out.jpg"))).unwrap();
    assert_eq!(profile.color_space, moxcms::DataColorSpace::Gray);
    let curve = profile.gray_trc.unwrap().make_linear_evaluator().unwrap();
    let expected = 0.5f64.powf(100_000.0 / 45455.0);
    assert!((curve.evaluate_value(0.5) as f64 - expected).abs() < 1e-4);
}

/// An sRGB chunk, or an iCCP, takes precedence over gAMA (PNG 3rd ed., 4.3): a PNG of either
/// beside a gAMA of 1.0 blurs as the same PNG without the gAMA, and a PNG output holds its
/// chunks again (the iCCP as it came).
#[test]
fn a_pngs_srgb_or_iccp_chunk_wins_over_its_gama() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let ((w, h), stripes, velocity) = striped(dir.path());
    let icc = moxcms::ColorProfile::new_adobe_rgb().encode().unwrap();
    let srgb: &[(&[u8; 4], Vec<u8>)] = &[(b"sRGB", vec![0])];
    for (name, icc, chunks) in [("srgb", None, srgb), ("iccp", Some(&icc[..]), &[][..])] {
        let mut with_gama = chunks.to_vec();
        with_gama.push((b"gAMA", gama(100_000)));
        let path = |end: &str| p(&format!("{name}{end}"));
        png_with_chunks(&path(".png"), (w, h), &stripes, icc, &with_gama);
        png_with_chunks(&path("_alone.png"), (w, h), &stripes, icc, chunks);
        blur(&path(".png"), &velocity, &path("_out.png"), &[]);
        blur(&path("_alone.png"), &velocity, &path("_alone_out.png"), &[]);
        let what = format!("{name}: the gAMA is not what codes the colour");
        assert_same_pixels(&path("_out.png"), &path("_alone_out.png"), &what);
        let (_, _, srgb, iccp) = png_colour_chunks(&path("_out.png"));
        assert_eq!((srgb, iccp), (name == "srgb", name == "iccp"), "{name}");
    }
}

/// The XMP of a photo turned upright by a quarter turn says the upright size too, as its
/// EXIF does (QA: after orientation 6 the XMP's `exif:PixelXDimension`/`PixelYDimension` and
/// `tiff:ImageWidth`/`ImageLength` still gave the stored size): each axis's value goes with
/// its axis, and so do the XMP's X and Y resolutions. Turned half a turn (orientation 3), the
/// axes stay where they were. Read back by exiftool from a JPEG, a PNG and a TIFF.
#[test]
fn the_xmp_of_a_photo_turned_upright_says_the_upright_size() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let (sw, sh) = (48u32, 32u32);
    let xmp = |orientation: &str| {
        [
            format!("-XMP-tiff:Orientation#={orientation}"),
            // exiftool's names of exif:PixelXDimension, PixelYDimension and tiff:ImageLength.
            "-XMP-exif:ExifImageWidth=48".into(),
            "-XMP-exif:ExifImageHeight=32".into(),
            "-XMP-tiff:ImageWidth=48".into(),
            "-XMP-tiff:ImageHeight=32".into(),
            "-XMP-tiff:XResolution=300".into(),
            "-XMP-tiff:YResolution=150".into(),
            format!("-Orientation#={orientation}"),
        ]
    };
    // (orientation, the upright size's velocity map, what the XMP then says: width, height,
    // x and y resolution).
    let cases = [
        (6, (32, 48), [32, 48, 150, 300]),
        (3, (48, 32), [48, 32, 300, 150]),
    ];
    for (orientation, (uw, uh), expected) in cases {
        let input = p(&format!("o{orientation}.jpg"));
        write_jpeg(&input, &portrait_on_its_side(sw, sh), sw, sh);
        let tags = xmp(&orientation.to_string());
        let tags: Vec<&str> = tags.iter().map(String::as_str).collect();
        if !exiftool_set(&input, &tags) {
            return;
        }
        let before = exiftool(&input).unwrap();
        assert_eq!(before["XMP-exif:ExifImageWidth"], 48, "{before}");
        let velocity = p(&format!("v{orientation}.png"));
        velocity_map(&velocity, uw, uh, |_, _| 0.0);
        for format in ["jpg", "png", "tif"] {
            let out = p(&format!("o{orientation}_out.{format}"));
            blur(&input, &velocity, &out, &[]);
            let tags = exiftool(&out).unwrap();
            let got = [
                "XMP-exif:ExifImageWidth",
                "XMP-exif:ExifImageHeight",
                "XMP-tiff:ImageWidth",
                "XMP-tiff:ImageHeight",
                "XMP-tiff:XResolution",
                "XMP-tiff:YResolution",
            ]
            .map(|name| {
                tags[name]
                    .as_u64()
                    .unwrap_or_else(|| panic!("no {name}: {tags}"))
            });
            let [w, h, x, y] = expected;
            assert_eq!(
                got,
                [w, h, w, h, x, y],
                "orientation {orientation} → {format}: {tags}"
            );
            assert_eq!(tags["XMP-tiff:Orientation"], 1, "{format}: {tags}");
        }
    }
}

/// `shutter info`'s rows for one photo: (name, text) from its text output, and the JSON
/// values by name.
fn photo_info(path: &Path) -> (Vec<(String, String)>, serde_json::Value) {
    let o = shutter(&["info", &s(path)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    let rows = text
        .lines()
        .skip_while(|l| l.trim() != "attributes:")
        .skip(1)
        .take_while(|l| l.starts_with("    "))
        .map(|l| {
            let mut words = l.split_whitespace();
            let name = words.next().unwrap().to_string();
            let _kind = words.next();
            (name, words.collect::<Vec<_>>().join(" "))
        })
        .collect();
    let o = shutter(&["info", &s(path), "--json"]);
    let doc: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let mut values = serde_json::Map::new();
    for a in doc["files"][0]["attributes"][0]["attributes"]
        .as_array()
        .unwrap()
    {
        values.insert(a["name"].as_str().unwrap().into(), a["value"].clone());
    }
    (rows, values.into())
}

/// `shutter info` on a photo shows what the reader found of its colour and density (QA: it
/// showed neither a PNG's gAMA and cHRM nor any resolution, nor a cICP): which of the file's
/// colour descriptions codes its colour, the gAMA, cHRM, sRGB and cICP chunks as stored, and
/// the resolution with its unit.
#[test]
fn info_shows_a_photos_colour_chunks_and_resolution() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let flat = vec![128u8; 8 * 4 * 3];
    let mut phys = 11811u32.to_be_bytes().to_vec();
    phys.extend(5906u32.to_be_bytes());
    phys.push(1);
    let chunks = [
        (b"gAMA", gama(45455)),
        (b"cHRM", chrm(ADOBE_CHRM)),
        (b"pHYs", phys),
    ];
    png_with_chunks(&p("g.png"), (8, 4), &flat, None, &chunks);
    let (rows, json) = photo_info(&p("g.png"));
    let row = |name: &str| {
        rows.iter()
            .find(|(n, _)| n == name)
            .map(|(_, t)| t.clone())
            .unwrap_or_else(|| panic!("no {name} in {rows:?}"))
    };
    assert!(row("colour").contains("gAMA and cHRM"), "{rows:?}");
    assert!(row("gAMA").starts_with("45455"), "{rows:?}");
    assert_eq!(
        row("cHRM"),
        "white 0.3127, 0.329; red 0.64, 0.33; green 0.21, 0.71; blue 0.15, 0.06"
    );
    assert_eq!(row("resolution"), "11811 x 5906 per metre");
    assert_eq!(json["colour"], "gama_chrm", "{json}");
    assert_eq!(json["gAMA"], 45455, "{json}");
    assert_eq!(
        json["cHRM"]["red"],
        serde_json::json!([0.64, 0.33]),
        "{json}"
    );
    assert_eq!(
        json["resolution"],
        serde_json::json!({"x": 11811.0, "y": 5906.0, "unit": "metre"}),
        "{json}"
    );
    // An sRGB chunk beside an ICC profile: the profile codes the colour; both are shown.
    let icc = moxcms::ColorProfile::new_adobe_rgb().encode().unwrap();
    png_with_chunks(&p("i.png"), (8, 4), &flat, Some(&icc), &[]);
    let (rows, json) = photo_info(&p("i.png"));
    assert_eq!(json["colour"], "icc", "{rows:?}");
    // No chunk at all: sRGB, as readers assume.
    png_with_chunks(&p("plain.png"), (8, 4), &flat, None, &[(b"sRGB", vec![0])]);
    let (rows, json) = photo_info(&p("plain.png"));
    assert_eq!(json["colour"], "srgb", "{rows:?}");
    assert_eq!(json["sRGB"], 0, "{json}");
    // A cICP beside the profile: the cICP codes the colour.
    let chunks = [(b"cICP", cicp(1, 8, true))];
    png_with_chunks(&p("c.png"), (8, 4), &flat, Some(&icc), &chunks);
    let (rows, json) = photo_info(&p("c.png"));
    assert_eq!(json["colour"], "cicp", "{rows:?}");
    assert_eq!(
        json["cICP"],
        serde_json::json!({"primaries": 1, "transfer": 8, "matrix": 0, "full_range": true}),
        "{rows:?}"
    );
    let text = rows
        .iter()
        .find(|(n, _)| n == "cICP")
        .map(|(_, t)| t.as_str());
    assert_eq!(
        text,
        Some("primaries 1 (BT.709), transfer 8 (linear), matrix 0, full range")
    );
    // A TIFF's resolution in its own unit.
    image::save_buffer(p("t.tif"), &flat, 8, 4, image::ColorType::Rgb8).unwrap();
    let tags = ["-XResolution=72", "-YResolution=144", "-ResolutionUnit=cm"];
    if !exiftool_set(&p("t.tif"), &tags) {
        return;
    }
    let (rows, json) = photo_info(&p("t.tif"));
    assert_eq!(json["colour"], "none", "{rows:?}");
    assert_eq!(
        json["resolution"],
        serde_json::json!({"x": 72.0, "y": 144.0, "unit": "centimetre"}),
        "{rows:?}"
    );
}

/// cICP's data: colour primaries, transfer function, matrix coefficients (0: RGB), full
/// range (1) or narrow (0), as ITU-T H.273 numbers them.
fn cicp(primaries: u8, transfer: u8, full: bool) -> Vec<u8> {
    vec![primaries, transfer, 0, u8::from(full)]
}

/// A PNG's cICP chunk (PNG 3rd ed., 4.3: it takes precedence over iCCP, sRGB, gAMA and cHRM)
/// says how its codes are coded (QA: it was ignored): a linear one (BT.709 primaries,
/// transfer 8) beside an Adobe RGB iCCP and a gAMA of 1/2.2 blurs as the same codes do under
/// `--linear`; a PNG output holds it again and a JPEG embeds a profile of its linear curve.
/// PQ and HLG (high dynamic range), and narrow-range codes, are refused
/// before anything is written, naming the file and why; a cICP of numbers shutter cannot
/// read (unspecified primaries) is passed over for the chunks after it, with a warning.
#[test]
fn a_pngs_cicp_says_how_its_codes_are_coded() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let ((w, h), stripes, velocity) = striped(dir.path());
    let icc = moxcms::ColorProfile::new_adobe_rgb().encode().unwrap();
    let linear = [(b"cICP", cicp(1, 8, true)), (b"gAMA", gama(45455))];
    png_with_chunks(&p("linear.png"), (w, h), &stripes, Some(&icc), &linear);
    blur(
        &p("plain.png"),
        &velocity,
        &p("plain_linear.png"),
        &["--linear"],
    );
    blur(&p("linear.png"), &velocity, &p("linear_out.png"), &[]);
    assert_same_pixels(
        &p("linear_out.png"),
        &p("plain_linear.png"),
        "a linear cICP blurs as linear codes, over its iCCP and gAMA",
    );
    let cicp_of = |path: &Path| {
        let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
        let reader = png::Decoder::new(file).read_info().unwrap();
        let c = reader.info().coding_independent_code_points?;
        let full = c.is_video_full_range_image;
        Some([
            c.color_primaries,
            c.transfer_function,
            c.matrix_coefficients,
            u8::from(full),
        ])
    };
    assert_eq!(cicp_of(&p("linear_out.png")), Some([1, 8, 0, 1]));
    // A JPEG has no cICP: it embeds the profile the cICP describes.
    blur(&p("linear.png"), &velocity, &p("linear_out.jpg"), &[]);
    if tool("exiftool", &["-ver"]).is_none() {
        return;
    }
    let profile = moxcms::ColorProfile::new_from_slice(&embedded_icc(&p("linear_out.jpg")))
        .expect("an embedded profile");
    let curve = profile.red_trc.unwrap().make_linear_evaluator().unwrap();
    assert!((curve.evaluate_value(0.5) - 0.5).abs() < 1e-3);
    // High dynamic range and narrow range: refused, naming the file, before any output.
    let out_dir = p("out");
    std::fs::create_dir_all(&out_dir).unwrap();
    for (name, data, why) in [
        ("pq.png", cicp(9, 16, true), "PQ"),
        ("hlg.png", cicp(9, 18, true), "HLG"),
        ("narrow.png", cicp(1, 13, false), "narrow"),
    ] {
        png_with_chunks(&p(name), (w, h), &stripes, None, &[(b"cICP", data)]);
        let depth = p("depth.png");
        image::save_buffer(
            &depth,
            &vec![128u8; (w * h) as usize],
            w,
            h,
            image::ColorType::L8,
        )
        .unwrap();
        let o = shutter(&[
            "blur",
            "--algorithm",
            "reconstruct",
            "--preset",
            "painted",
            "--color",
            &s(&p(name)),
            "--velocity",
            &s(&velocity),
            "--depth",
            &s(&depth),
            "-o",
            &s(&out_dir.join("o.png")),
        ]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(name) && err.contains("cICP") && err.contains(why),
            "{err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert_eq!(std::fs::read_dir(&out_dir).unwrap().count(), 0, "{name}");
    }
    // Unspecified primaries: the chunks after it code the colour (none here: sRGB).
    png_with_chunks(
        &p("odd.png"),
        (w, h),
        &stripes,
        None,
        &[(b"cICP", cicp(2, 13, true))],
    );
    blur(&p("plain.png"), &velocity, &p("plain_out.png"), &[]);
    let o = blur(&p("odd.png"), &velocity, &p("odd_out.png"), &[]);
    assert_same_pixels(&p("odd_out.png"), &p("plain_out.png"), "an unreadable cICP");
    assert!(stderr(&o).contains("cICP"), "{}", stderr(&o));
}

/// A cICP whose matrix coefficients are 1, as PNG's drafts called the default and tools
/// written to them wrote it (PNG's samples are RGB: the 3rd edition says 0): the png crate
/// refuses such a file as invalid data, where libpng reads it. shutter reads it as the drafts
/// told readers to, the matrix taken as 0 and the rest of the chunk honoured (a linear cICP
/// blurs as the same codes do under `--linear`), says so, writes a valid cICP (matrix 0) and
/// leaves the file as it was; `shutter info` shows the 1. A PQ one is refused as PQ, not as
/// damage.
#[test]
fn a_pngs_cicp_with_matrix_coefficients_1_is_read_as_0_and_said_so() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name);
    let ((w, h), stripes, velocity) = striped(dir.path());
    png_with_chunks(
        &p("matrix.png"),
        (w, h),
        &stripes,
        None,
        &[(b"cICP", vec![1, 8, 1, 1])],
    );
    let before = std::fs::read(p("matrix.png")).unwrap();
    blur(
        &p("plain.png"),
        &velocity,
        &p("plain_linear.png"),
        &["--linear"],
    );
    let o = blur(&p("matrix.png"), &velocity, &p("matrix_out.png"), &[]);
    let err = stderr(&o);
    assert!(
        err.contains("matrix coefficients 1") && err.contains("read as 0"),
        "{err}"
    );
    assert_same_pixels(
        &p("matrix_out.png"),
        &p("plain_linear.png"),
        "a linear cICP of matrix 1 blurs as linear codes",
    );
    let file = std::io::BufReader::new(std::fs::File::open(p("matrix_out.png")).unwrap());
    let reader = png::Decoder::new(file).read_info().unwrap();
    let c = reader.info().coding_independent_code_points.unwrap();
    assert_eq!(
        (
            c.color_primaries,
            c.transfer_function,
            c.matrix_coefficients
        ),
        (1, 8, 0)
    );
    assert_eq!(std::fs::read(p("matrix.png")).unwrap(), before, "the input");
    let info = shutter(&["info", &s(&p("matrix.png"))]);
    assert!(info.status.success(), "{}", stderr(&info));
    assert!(
        stdout(&info).contains("matrix 1, read as 0"),
        "{}",
        stdout(&info)
    );
    // High dynamic range: refused as such, naming the file.
    png_with_chunks(
        &p("pq.png"),
        (w, h),
        &stripes,
        None,
        &[(b"cICP", vec![9, 16, 1, 1])],
    );
    let out = p("pq_out.png");
    let o = shutter(&[
        "blur",
        "--algorithm",
        "reconstruct",
        "--preset",
        "painted",
        "--color",
        &s(&p("pq.png")),
        "--velocity",
        &s(&velocity),
        "--depth",
        &s(&p("depth.png")),
        "-o",
        &s(&out),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("pq.png") && err.contains("PQ"), "{err}");
    assert!(!err.contains("corrupt"), "{err}");
    assert!(!out.exists());
}

/// An EXR of `chromaticities` (x, y of red, green, blue, white) holding a grey ramp.
fn write_exr_of_primaries(path: &Path, [r, g, b, w]: [(f32, f32); 4]) {
    use exr::prelude::*;
    let (width, height) = (16usize, 8usize);
    let ramp: Vec<f32> = (0..width * height)
        .map(|i| (i % width) as f32 / 16.0)
        .collect();
    let channel = |name: &str| AnyChannel::new(name, FlatSamples::F32(ramp.clone()));
    let mut attributes = ImageAttributes::new(IntegerBounds::from_dimensions((width, height)));
    let xy = |(x, y): (f32, f32)| Vec2(x, y);
    attributes.chromaticities = Some(exr::meta::attribute::Chromaticities {
        red: xy(r),
        green: xy(g),
        blue: xy(b),
        white: xy(w),
    });
    let channels = AnyChannels::sort(vec![channel("R"), channel("G"), channel("B")].into());
    let layer = Layer::new(
        (width, height),
        LayerAttributes::default(),
        Encoding::default(),
        channels,
    );
    let image = Image {
        attributes,
        layer_data: layer,
    };
    image.write().to_file(path).unwrap();
}

/// `shutter blur` of a colour file alone (no motion: its colour as it is) to `out`.
fn blur_exr(input: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    shutter(&[&["blur", "--color", &s(input), "-o", &s(out)][..], extra].concat())
}

/// A 3 × 3 matrix's inverse (the test's own, by cofactors).
fn inverse(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let c = |r: usize, k: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
        m[r1][k1] * m[r2][k2] - m[r1][k2] * m[r2][k1]
    };
    let det: f64 = (0..3).map(|k| m[0][k] * c(0, k)).sum();
    let mut out = [[0.0; 3]; 3];
    for r in 0..3 {
        for k in 0..3 {
            out[r][k] = c(k, r) / det;
        }
    }
    out
}

/// An EXR's `chromaticities` (ACEScg's AP1 primaries, the ACES white) go into a PNG, TIFF
/// or JPEG made from it as an ICC profile of those primaries: exiftool reads its colorants
/// (stored adapted to D50) and its `chad`; undone here, the colorants' chromaticities are
/// the EXR's. They were dropped without a word, and a viewer showed AP1 light as sRGB's.
/// An EXR of Rec. 709's primaries gets no profile (sRGB's, as before); primaries on one line
/// make none, and the run says so.
#[test]
fn an_exrs_chromaticities_go_into_a_picture_as_an_icc_profile() {
    let dir = tempfile::tempdir().unwrap();
    let ap1 = [
        (0.713, 0.293),
        (0.165, 0.830),
        (0.128, 0.044),
        (0.32168, 0.33767),
    ];
    let input = dir.path().join("acescg.exr");
    write_exr_of_primaries(&input, ap1);
    for name in ["o.png", "o.tif", "o.jpg"] {
        let out = dir.path().join(name);
        let o = blur_exr(&input, &out, &["--json"]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let Some(tags) = exiftool(&out) else { return };
        let numbers = |tag: &str| -> Vec<f64> {
            let value = &tags[format!("ICC_Profile:{tag}")];
            let text = value
                .as_str()
                .unwrap_or_else(|| panic!("{name}: no {tag}: {tags}"));
            text.split_whitespace()
                .map(|v| v.parse().unwrap())
                .collect()
        };
        let chad = numbers("ChromaticAdaptation");
        let chad = [0, 1, 2].map(|r| [0, 1, 2].map(|k| chad[r * 3 + k]));
        let undo = inverse(chad);
        for (tag, (x, y)) in ["RedMatrixColumn", "GreenMatrixColumn", "BlueMatrixColumn"]
            .iter()
            .zip(ap1)
        {
            let d50 = numbers(tag);
            let xyz = [0, 1, 2].map(|r| (0..3).map(|k| undo[r][k] * d50[k]).sum::<f64>());
            let sum: f64 = xyz.iter().sum();
            let (gx, gy) = (xyz[0] / sum, xyz[1] / sum);
            assert!(
                (gx - f64::from(x)).abs() < 2e-3 && (gy - f64::from(y)).abs() < 2e-3,
                "{name}: {tag} is at ({gx}, {gy}), the EXR says ({x}, {y})"
            );
        }
    }
    // Rec. 709's own: no profile, as before.
    let rec709 = [(0.64, 0.33), (0.30, 0.60), (0.15, 0.06), (0.3127, 0.3290)];
    let input = dir.path().join("rec709.exr");
    write_exr_of_primaries(&input, rec709);
    let out = dir.path().join("rec709.png");
    let o = blur_exr(&input, &out, &[]);
    assert!(o.status.success(), "{}", stderr(&o));
    if let Some(tags) = exiftool(&out) {
        assert!(tags.get("ICC_Profile:RedMatrixColumn").is_none(), "{tags}");
    }
    // Primaries on one line make no profile: said.
    let flat = [(0.2, 0.2), (0.4, 0.4), (0.6, 0.6), (0.3127, 0.3290)];
    let input = dir.path().join("flat.exr");
    write_exr_of_primaries(&input, flat);
    let out = dir.path().join("flat.png");
    let o = blur_exr(&input, &out, &["--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let warnings = report["warnings"].to_string();
    assert!(warnings.contains("chromaticities"), "{warnings}");
}
