//! What a photo's own tags say of the output, read back by exiftool (skipped with a note
//! where it is not installed, unless SHUTTER_REQUIRE_TOOLS=1): the EXIF of a photo turned
//! upright describes the upright pixels (its dimensions, its per-axis resolutions, no
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
