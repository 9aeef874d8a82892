//! Readers and writers on real files: every EXR compression, sample type and layout the
//! exr crate reads, integer images and their transfer function.

use std::path::Path;

use exr::prelude::*;
use shutter::io::file::FileInfo;
use shutter::io::passes::{plan_frame, read_frame, Inputs, PlanOptions};
use shutter::io::preset::Preset;
use shutter::io::sequence::PathPattern;
use shutter::Passes;

use crate::support::*;

/// Reads a file's colour through the full path (probe, plan, decode, convert).
fn read_color(path: &Path) -> shutter::frame::Color {
    let preset = Preset::builtin("shutter").unwrap();
    let inputs = Inputs::color_only(PathPattern::parse(&s(path)).unwrap());
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: Passes::COLOR,
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let plan = plan_frame(&inputs, None, &options).unwrap();
    read_frame(&plan).unwrap().color.unwrap()
}

#[test]
fn every_compression_round_trips() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (67, 45); // not a multiple of any block height
    let n = w * h;
    let r = noise(n, 1, 0.0, 2.0);
    let g = noise(n, 2, 0.0, 1.0);
    let b = noise(n, 3, 0.0, 1.0);
    for name in shutter::io::exr::WRITABLE_COMPRESSIONS {
        for half in [false, true] {
            let path = dir.path().join(format!("{name}_{half}.exr"));
            let options = shutter::io::exr::ExrOptions {
                compression: shutter::io::exr::parse_compression(name).unwrap(),
                half,
            };
            write_exr_with(
                &path,
                w,
                h,
                vec![("R", r.clone()), ("G", g.clone()), ("B", b.clone())],
                options,
            );
            let reference = read_exr_reference(&path);
            let color = read_color(&path);
            // Whatever the codec did, our reader must agree with exr's own reader exactly.
            assert_exact(&color.r, channel(&reference, "R"), name);
            assert_exact(&color.b, channel(&reference, "B"), name);
            // And lossless codecs give back what was written.
            let lossless = !matches!(*name, "pxr24" | "b44" | "b44a" | "dwaa" | "dwab");
            if lossless && !half {
                assert_exact(&color.g, &g, name);
            } else {
                // Lossy codecs on white noise (their worst case): only roughly equal.
                assert_close(&color.g, &g, 0.25, name);
            }
        }
    }
}

fn layer_with(
    name: Option<&str>,
    size: (usize, usize),
    blocks: Blocks,
    compression: Compression,
    channels: Vec<AnyChannel<FlatSamples>>,
) -> Layer<AnyChannels<FlatSamples>> {
    let attributes = match name {
        Some(name) => LayerAttributes::named(name),
        None => LayerAttributes::default(),
    };
    Layer::new(
        size,
        attributes,
        Encoding {
            compression,
            blocks,
            line_order: LineOrder::Increasing,
        },
        AnyChannels::sort(channels.into()),
    )
}

#[test]
fn tiled_f16_u32_and_mip_mapped_files_read() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (70, 33);
    let n = w * h;
    let r = noise(n, 4, 0.0, 1.0);
    let r16: Vec<f16> = r.iter().map(|&v| f16::from_f32(v)).collect();
    let g: Vec<u32> = (0..n as u32).collect();
    let b = noise(n, 5, -1.0, 1.0);
    let channels = vec![
        AnyChannel::new("R", FlatSamples::F16(r16.clone())),
        AnyChannel::new("G", FlatSamples::U32(g.clone())),
        AnyChannel::new("B", FlatSamples::F32(b.clone())),
    ];
    for (label, blocks) in [
        ("tiles", Blocks::Tiles(Vec2(16, 16))),
        ("scanlines", Blocks::ScanLines),
    ] {
        for compression in [Compression::PIZ, Compression::ZIP1, Compression::RLE] {
            let path = dir.path().join(format!("{label}_{compression}.exr"));
            let layer = layer_with(None, (w, h), blocks, compression, channels.clone());
            Image::from_layer(layer).write().to_file(&path).unwrap();
            let color = read_color(&path);
            let r_expected: Vec<f32> = r16.iter().map(|v| v.to_f32()).collect();
            assert_exact(&color.r, &r_expected, "f16 channel");
            let g_expected: Vec<f32> = g.iter().map(|&v| v as f32).collect();
            assert_exact(&color.g, &g_expected, "u32 channel");
            assert_exact(&color.b, &b, "f32 channel");
        }
    }
}

#[test]
fn multi_part_files_find_channels_by_part_name() {
    // Nuke can write each layer as its own part: channel `u` of part `forward`.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (12, 9);
    let n = w * h;
    let r = noise(n, 6, 0.0, 1.0);
    let u = noise(n, 7, -5.0, 5.0);
    let v = noise(n, 8, -5.0, 5.0);
    let rgba = layer_with(
        Some("rgba"),
        (w, h),
        Blocks::ScanLines,
        Compression::ZIP16,
        vec![
            AnyChannel::new("R", FlatSamples::F32(r.clone())),
            AnyChannel::new("G", FlatSamples::F32(r.clone())),
            AnyChannel::new("B", FlatSamples::F32(r.clone())),
        ],
    );
    let forward = layer_with(
        Some("forward"),
        (w, h),
        Blocks::ScanLines,
        Compression::ZIP16,
        vec![
            AnyChannel::new("u", FlatSamples::F32(u.clone())),
            AnyChannel::new("v", FlatSamples::F32(v.clone())),
        ],
    );
    let path = dir.path().join("parts.exr");
    let image = Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions((w, h))))
        .with_layer(rgba)
        .with_layer(forward);
    image.write().to_file(&path).unwrap();

    let info = FileInfo::probe(&path).unwrap();
    assert!(info.find("forward.u").is_some(), "{}", info.channel_list());

    let preset = Preset::builtin("nuke").unwrap();
    let inputs = Inputs::color_only(PathPattern::parse(&s(&path)).unwrap());
    let options = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: Passes {
            color: true,
            next: true,
            ..Passes::default()
        },
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let plan = plan_frame(&inputs, None, &options).unwrap();
    let frame = read_frame(&plan).unwrap();
    assert_exact(&frame.color.unwrap().r, &r, "R");
    let next = frame.next.unwrap();
    let expected_x: Vec<f32> = (0..n).map(|i| (i % w) as f32 + 0.5 + u[i]).collect();
    let expected_y: Vec<f32> = (0..n).map(|i| (i / w) as f32 + 0.5 - v[i]).collect();
    assert_close(&next.x, &expected_x, 1e-5, "next x");
    assert_close(&next.y, &expected_y, 1e-5, "next y");
}

#[test]
fn data_and_display_windows_are_kept() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (10, 6);
    let n = w * h;
    let mut layer = layer_with(
        None,
        (w, h),
        Blocks::ScanLines,
        Compression::ZIP16,
        vec![
            AnyChannel::new("R", FlatSamples::F32(vec![1.0; n])),
            AnyChannel::new("G", FlatSamples::F32(vec![2.0; n])),
            AnyChannel::new("B", FlatSamples::F32(vec![3.0; n])),
        ],
    );
    layer.attributes.layer_position = Vec2(-3, 4);
    let image = Image {
        attributes: ImageAttributes::new(IntegerBounds::new((0, 0), (8, 8))),
        layer_data: layer,
    };
    let input = dir.path().join("overscan.exr");
    image.write().to_file(&input).unwrap();
    let out = dir.path().join("out.exr");
    let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = exr::meta::MetaData::read_from_file(&out, false).unwrap();
    let header = &meta.headers[0];
    assert_eq!(header.own_attributes.layer_position, Vec2(-3, 4));
    assert_eq!(header.layer_size, Vec2(10, 6));
    assert_eq!(
        header.shared_attributes.display_window,
        IntegerBounds::new((0, 0), (8, 8))
    );
    assert_eq!(header.compression, Compression::ZIP16);
    assert!(matches!(
        header.blocks,
        exr::meta::BlockDescription::ScanLines
    ));
}

#[test]
fn half_and_compression_flags_reach_the_file() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 5, 5);
    let out = dir.path().join("h.exr");
    let o = shutter(&[
        "blur",
        "--color",
        &s(&dir.path().join("C.exr")),
        "--half",
        "--compression",
        "piz",
        "-o",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let meta = exr::meta::MetaData::read_from_file(&out, false).unwrap();
    assert_eq!(meta.headers[0].compression, Compression::PIZ);
    assert!(meta.headers[0]
        .channels
        .list
        .iter()
        .all(|c| c.sample_type == exr::meta::attribute::SampleType::F16));
}

#[test]
fn png_round_trip_is_srgb_and_exact_at_8_and_16_bits() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16, 16);
    // Every 8-bit code appears once, as sRGB.
    let codes: Vec<u8> = (0..=255u8).collect();
    let mut rgb = Vec::new();
    for &c in &codes {
        rgb.extend([c, 255 - c, c / 2]);
    }
    let input = dir.path().join("in.png");
    image::save_buffer(&input, &rgb, w as u32, h as u32, image::ColorType::Rgb8).unwrap();
    let color = read_color(&input);
    // Decoded to linear: code 128 is 21.6% linear.
    assert!(close(color.r[128], 0.215_861, 1e-5), "{}", color.r[128]);
    assert!(color.a.is_none());
    for bits in ["8", "16"] {
        let out = dir.path().join(format!("out{bits}.png"));
        let o = shutter(&[
            "blur",
            "--color",
            &s(&input),
            "--bit-depth",
            bits,
            "-o",
            &s(&out),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let back = image::open(&out).unwrap();
        if bits == "8" {
            assert_eq!(back.to_rgb8().into_raw(), rgb, "8-bit sRGB round trip");
        } else {
            let back16 = back.to_rgb16().into_raw();
            let expected: Vec<u16> = rgb.iter().map(|&c| c as u16 * 257).collect();
            assert_eq!(back16, expected, "16-bit holds the same sRGB codes");
        }
    }
}

#[test]
fn straight_alpha_of_integer_images_is_premultiplied_in_memory() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("a.png");
    // One pixel: sRGB white at 50% alpha (straight).
    image::save_buffer(&input, &[255, 255, 255, 128], 1, 1, image::ColorType::Rgba8).unwrap();
    let color = read_color(&input);
    let alpha = 128.0 / 255.0;
    assert!(
        close(color.r[0], alpha, 1e-6),
        "premultiplied: {}",
        color.r[0]
    );
    assert!(close(color.a.unwrap()[0], alpha, 1e-6));
    let out = dir.path().join("a_out.png");
    let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&out)]);
    assert!(o.status.success());
    assert_eq!(
        image::open(&out).unwrap().to_rgba8().into_raw(),
        [255, 255, 255, 128]
    );
}

#[test]
fn linear_flag_skips_the_transfer_function() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("lin.png");
    image::save_buffer(&input, &[128, 64, 0], 1, 1, image::ColorType::Rgb8).unwrap();
    let out = dir.path().join("lin.exr");
    let o = shutter(&["blur", "--linear", "--color", &s(&input), "-o", &s(&out)]);
    assert!(o.status.success());
    let written = read_exr_reference(&out);
    assert_exact(channel(&written, "R"), &[128.0 / 255.0], "R");
    assert_exact(channel(&written, "G"), &[64.0 / 255.0], "G");
}

#[test]
fn tiff_and_jpeg_outputs_are_readable() {
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 9, 7);
    for (name, bits) in [("o.tif", "16"), ("o.tiff", "8"), ("o.jpg", "8")] {
        let out = dir.path().join(name);
        let o = shutter(&[
            "blur",
            "--color",
            &s(&dir.path().join("C.exr")),
            "--bit-depth",
            bits,
            "-o",
            &s(&out),
        ]);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        let img = image::open(&out).unwrap();
        assert_eq!((img.width(), img.height()), (9, 7), "{name}");
    }
}

#[test]
fn garbage_files_never_panic() {
    // Whatever the bytes, probing and reading give an error or a frame, never a panic.
    let dir = tempfile::tempdir().unwrap();
    write_canonical_frame(dir.path(), None, 33, 17);
    let good = std::fs::read(dir.path().join("C.exr")).unwrap();
    let path = dir.path().join("fuzz.exr");
    for seed in 0..200u32 {
        let mut bytes = good.clone();
        let flips = noise(4, seed, 0.0, bytes.len() as f32);
        for (k, at) in flips.iter().enumerate() {
            let at = (*at as usize).min(bytes.len() - 1);
            bytes[at] ^= 1 << ((seed as usize + k) % 8);
        }
        if seed % 3 == 0 {
            let cut = (seed as usize * 37) % bytes.len();
            bytes.truncate(cut.max(1));
        }
        std::fs::write(&path, &bytes).unwrap();
        let result = std::panic::catch_unwind(|| {
            if let Ok(info) = FileInfo::probe(&path) {
                let all: Vec<usize> = (0..info.channels.len()).collect();
                let _ = info.read(&all);
            }
        });
        assert!(result.is_ok(), "panic on seed {seed}");
    }
}

#[test]
fn parts_without_wanted_channels_are_never_decompressed() {
    // Two parts; the last chunk of the file (the vector part's) is damaged. Reading colour
    // must not touch it; reading vectors must report it.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64, 48);
    let n = w * h;
    let smooth: Vec<f32> = (0..n).map(|k| (k % w) as f32 * 0.01).collect();
    let part = |name: &str, channels: &[&str]| {
        layer_with(
            Some(name),
            (w, h),
            Blocks::ScanLines,
            Compression::ZIP16,
            channels
                .iter()
                .map(|c| AnyChannel::new(*c, FlatSamples::F32(smooth.clone())))
                .collect(),
        )
    };
    let image = Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions((w, h))))
        .with_layer(part("rgba", &["R", "G", "B"]))
        .with_layer(part("forward", &["u", "v"]));
    let path = dir.path().join("parts.exr");
    image.write().to_file(&path).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    let len = bytes.len();
    for b in &mut bytes[len - 40..len - 20] {
        *b ^= 0x5A;
    }
    std::fs::write(&path, &bytes).unwrap();

    let preset = Preset::builtin("nuke").unwrap();
    let inputs = Inputs::color_only(PathPattern::parse(&s(&path)).unwrap());
    let needs_color = PlanOptions {
        preset: &preset,
        layer: None,
        view: None,
        needs: Passes::COLOR,
        max_pixels: shutter::io::file::DEFAULT_MAX_PIXELS,
    };
    let frame = read_frame(&plan_frame(&inputs, None, &needs_color).unwrap()).unwrap();
    assert_exact(&frame.color.unwrap().r, &smooth, "R");
    let needs_next = PlanOptions {
        needs: Passes {
            next: true,
            ..Passes::default()
        },
        ..needs_color
    };
    let problem = read_frame(&plan_frame(&inputs, None, &needs_next).unwrap()).unwrap_err();
    assert_eq!(problem.kind, shutter::ProblemKind::Corrupt, "{problem}");
}

#[test]
fn multi_part_files_of_every_mix_of_compressions_and_blocks_are_not_called_damaged() {
    // The usual way to keep data lossless beside a lossy beauty: a DWAA part for the beauty,
    // a ZIP one for depth and vectors. Parts of different chunk heights (32, 16, 1, 256 lines)
    // and forms (scan lines, tiles) interleave their chunks in the file.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (64, 300);
    let n = w * h;
    let r = noise(n, 9, 0.0, 1.0);
    let half: Vec<f16> = r.iter().map(|&v| f16::from_f32(v)).collect();
    let beauty = |compression, blocks| {
        layer_with(
            Some("beauty"),
            (w, h),
            blocks,
            compression,
            ["R", "G", "B"]
                .map(|c| AnyChannel::new(c, FlatSamples::F16(half.clone())))
                .into(),
        )
    };
    let data = |compression, blocks| {
        layer_with(
            Some("data"),
            (w, h),
            blocks,
            compression,
            vec![AnyChannel::new("Z", FlatSamples::F32(r.clone()))],
        )
    };
    let tiles = Blocks::Tiles(Vec2(32, 32));
    for (i, (a, a_blocks, b, b_blocks)) in [
        (
            Compression::DWAA(None),
            Blocks::ScanLines,
            Compression::ZIP16,
            Blocks::ScanLines,
        ),
        (
            Compression::DWAB(None),
            Blocks::ScanLines,
            Compression::ZIP1,
            Blocks::ScanLines,
        ),
        (Compression::PIZ, Blocks::ScanLines, Compression::RLE, tiles),
        (
            Compression::DWAA(None),
            tiles,
            Compression::Uncompressed,
            Blocks::ScanLines,
        ),
        (
            Compression::B44,
            Blocks::ScanLines,
            Compression::PXR24,
            Blocks::ScanLines,
        ),
    ]
    .into_iter()
    .enumerate()
    {
        let path = dir.path().join(format!("mix{i}.exr"));
        let image = Image::empty(ImageAttributes::new(IntegerBounds::from_dimensions((w, h))))
            .with_layer(beauty(a, a_blocks))
            .with_layer(data(b, b_blocks));
        image.write().to_file(&path).unwrap();
        let info = FileInfo::probe(&path);
        assert!(info.is_ok(), "{a} + {b}: {:?}", info.err());
        // Every channel of both parts in one read: parts whose chunks cut the rows
        // differently were once refused as "overlapping chunks".
        let info = info.unwrap();
        let z = info.find("Z").expect("Z");
        let planes = info
            .read(&[0, z])
            .unwrap_or_else(|e| panic!("{a} + {b}: {e:?}"));
        if b == Compression::PXR24 {
            // PXR24 keeps 24 bits of a float.
            assert_close(&planes[1], &r, 1e-4, "Z");
        } else {
            assert_exact(&planes[1], &r, "Z");
        }
        let color = read_color(&path);
        let expected: Vec<f32> = half.iter().map(|v| v.to_f32()).collect();
        if !matches!(
            a,
            Compression::DWAA(_) | Compression::DWAB(_) | Compression::B44
        ) {
            assert_exact(&color.r, &expected, "R");
        }
    }
}

/// Two parts that both hold R, G, B and A, neither named as the main one (issue 30): which is
/// the colour cannot be told from the names, so the run stops naming both parts and how to
/// choose, instead of reading the first silently; a preset naming `PART.R` reads that part,
/// and a part named `rgba` is the main one wherever it is in the file.
#[test]
fn a_colour_in_two_parts_is_refused_until_a_preset_names_the_part() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.exr");
    let part = |name: &'static str, value: f32| Part {
        name: Some(name),
        view: None,
        multi_view: None,
        channels: ["R", "G", "B", "A"]
            .iter()
            .map(|c| (c.to_string(), vec![value; 16]))
            .collect(),
    };
    write_parts(
        &path,
        (4, 4),
        vec![part("first", 0.25), part("other", 0.75)],
    );
    let out = dir.path().join("o.exr");
    let o = shutter(&["blur", "--color", &s(&path), "-o", &s(&out)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("channel R is in more than one part (first, other)")
            && err.contains("first.R"),
        "{err}"
    );
    assert!(!out.exists());
    let preset = dir.path().join("other.toml");
    std::fs::write(
        &preset,
        "[color]\nchannels = [[\"other.R\", \"other.G\", \"other.B\", \"other.A\"]]\n",
    )
    .unwrap();
    // The beauty alone, read from the part holding 0.75.
    let (input, output) = (s(&path), s(&out));
    let reads_the_second_part = |extra: &[&str]| {
        let mut args = vec!["blur", "--color", &input, "-o", &output, "--beauty-only"];
        args.extend(extra);
        let o = shutter(&args);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        let written = read_exr_reference(&out);
        assert!(
            channel(&written, "R").iter().all(|&v| v == 0.75),
            "{extra:?}"
        );
    };
    reads_the_second_part(&["--preset", &s(&preset)]);
    // `rgba` second: still the one read.
    write_parts(&path, (4, 4), vec![part("first", 0.25), part("rgba", 0.75)]);
    reads_the_second_part(&[]);
}

/// ZIP and ZIPS blocks are deflated by libdeflate (src/io/exr_zip.rs), not by the exr crate:
/// OpenEXR (through `idiff`) and the exr crate must read them as the pixels of the same blur
/// written uncompressed, in a tiled part at an offset data window with float and half
/// channels beside a scan-line part, at a size no block height divides.
#[test]
fn zip_outputs_read_as_their_uncompressed_twin_in_openexr_and_the_exr_crate() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (67, 45);
    let n = w * h;
    let half = |v: Vec<f32>| FlatSamples::F16(v.into_iter().map(f16::from_f32).collect());
    // Smooth planes, which deflate shrinks (noise it would store raw, deflating nothing).
    let smooth = |fx: f32, fy: f32, lo: f32, hi: f32| -> Vec<f32> {
        (0..n)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                lo + (hi - lo) * (0.5 + 0.5 * (fx * x + fy * y).sin())
            })
            .collect()
    };
    let mut beauty = layer_with(
        Some("rgba"),
        (w, h),
        Blocks::Tiles(Vec2(16, 16)),
        Compression::ZIP16,
        vec![
            AnyChannel::new("R", FlatSamples::F32(smooth(0.11, 0.03, 0.0, 2.0))),
            AnyChannel::new("G", FlatSamples::F32(smooth(0.05, 0.07, 0.0, 1.0))),
            AnyChannel::new("B", FlatSamples::F32(smooth(0.02, 0.13, 0.0, 1.0))),
            AnyChannel::new("diffuse.R", half(smooth(0.09, 0.01, 0.0, 1.0))),
            AnyChannel::new("Z", FlatSamples::F32(smooth(0.01, 0.02, 1.0, 9.0))),
            AnyChannel::new(
                "velocity.X",
                FlatSamples::F32(smooth(0.03, 0.01, -6.0, 6.0)),
            ),
            AnyChannel::new(
                "velocity.Y",
                FlatSamples::F32(smooth(0.01, 0.04, -3.0, 3.0)),
            ),
        ],
    );
    beauty.attributes.layer_position = Vec2(-5, 7);
    let mut extra = layer_with(
        Some("extra"),
        (w, h),
        Blocks::ScanLines,
        Compression::ZIP1,
        vec![AnyChannel::new(
            "N.X",
            FlatSamples::F32(smooth(0.07, 0.05, -1.0, 1.0)),
        )],
    );
    extra.attributes.layer_position = Vec2(-5, 7);
    let input = dir.path().join("in.exr");
    Image::from_layers(
        ImageAttributes::new(IntegerBounds::new((0, 0), (60, 60))),
        vec![beauty, extra],
    )
    .write()
    .to_file(&input)
    .unwrap();
    let blur = |compression: &str| {
        let out = dir.path().join(format!("{compression}.exr"));
        let o = shutter(&[
            "blur",
            "--algorithm",
            "reconstruct",
            "--color",
            &s(&input),
            "--compression",
            compression,
            "-o",
            &s(&out),
        ]);
        assert!(o.status.success(), "{compression}: {}", stderr(&o));
        out
    };
    let raw = blur("none");
    for compression in ["zip", "zips"] {
        let out = blur(compression);
        let meta = exr::meta::MetaData::read_from_file(&out, false).unwrap();
        assert_eq!(
            meta.headers.len(),
            2,
            "{compression}: multi-part in, multi-part out"
        );
        assert!(matches!(
            meta.headers[0].blocks,
            exr::meta::BlockDescription::Tiles(_)
        ));
        assert_eq!(meta.headers[0].own_attributes.layer_position, Vec2(-5, 7));
        let name = if compression == "zip" {
            Compression::ZIP16
        } else {
            Compression::ZIP1
        };
        assert!(
            meta.headers.iter().all(|h| h.compression == name),
            "{compression}"
        );
        // Deflated, not stored raw: the path under test ran.
        let size = |p: &Path| std::fs::metadata(p).unwrap().len();
        let (packed, whole) = (size(&out), size(&raw));
        assert!(
            packed * 10 < whole * 9,
            "{compression}: {packed} of {whole} bytes"
        );
        // The exr crate's reading, part by part and channel by channel, bit for bit.
        let (got, expected) = (read_exr_layers(&out), read_exr_layers(&raw));
        assert_eq!(got.len(), expected.len());
        for (part, raw_part) in got.iter().zip(&expected) {
            let (list, raw_list) = (&part.channel_data.list, &raw_part.channel_data.list);
            assert_eq!(list.len(), raw_list.len());
            for (channel, raw_channel) in list.iter().zip(raw_list) {
                assert_eq!(channel.name, raw_channel.name);
                let bits = |samples: &FlatSamples| -> Vec<u32> {
                    match samples {
                        FlatSamples::F16(v) => v.iter().map(|s| u32::from(s.to_bits())).collect(),
                        FlatSamples::F32(v) => v.iter().map(|s| s.to_bits()).collect(),
                        FlatSamples::U32(v) => v.clone(),
                    }
                };
                assert!(
                    bits(&channel.sample_data) == bits(&raw_channel.sample_data),
                    "{compression}: {:?} {} differs",
                    part.attributes.layer_name,
                    channel.name
                );
            }
        }
        // OpenEXR's.
        if let Some(o) = run_tool("idiff", &["-a", &s(&out), &s(&raw)]) {
            let report = stdout(&o);
            assert!(
                o.status.success(),
                "{compression}: OpenEXR reads other pixels: {report}"
            );
        }
    }
}

/// A two-part EXR of `w`×`h` laid out as OpenEXR writes it: part `beauty` flat (A, B, G, R
/// float, uncompressed, a line a chunk) holding `rgba`, and part `deep` of deep scan lines
/// (Z float, one sample a pixel, the depth 2). Written byte by byte: neither the exr crate
/// nor OpenEXR's Python module writes deep data.
fn exr_with_a_deep_part(path: &Path, (w, h): (usize, usize), rgba: &[[f32; 4]]) {
    fn attr(out: &mut Vec<u8>, name: &str, kind: &str, value: &[u8]) {
        for text in [name, kind] {
            out.extend(text.as_bytes());
            out.push(0);
        }
        out.extend((value.len() as i32).to_le_bytes());
        out.extend(value);
    }
    let ints = |v: &[i32]| v.iter().flat_map(|i| i.to_le_bytes()).collect::<Vec<u8>>();
    let header = |out: &mut Vec<u8>, name: &str, channels: &[&str], deep: bool| {
        let mut list = Vec::new();
        for channel in channels {
            list.extend(channel.as_bytes());
            list.push(0);
            // Type float, pLinear 0 and three reserved bytes, sampling 1×1.
            list.extend(ints(&[2, 0, 1, 1]));
        }
        list.push(0);
        let window = ints(&[0, 0, w as i32 - 1, h as i32 - 1]);
        attr(out, "channels", "chlist", &list);
        attr(out, "compression", "compression", &[0]);
        attr(out, "dataWindow", "box2i", &window);
        attr(out, "displayWindow", "box2i", &window);
        attr(out, "lineOrder", "lineOrder", &[0]);
        attr(out, "pixelAspectRatio", "float", &1f32.to_le_bytes());
        attr(out, "screenWindowCenter", "v2f", &[0; 8]);
        attr(out, "screenWindowWidth", "float", &1f32.to_le_bytes());
        attr(out, "name", "string", name.as_bytes());
        let kind = if deep {
            "deepscanline"
        } else {
            "scanlineimage"
        };
        attr(out, "type", "string", kind.as_bytes());
        attr(out, "chunkCount", "int", &(h as i32).to_le_bytes());
        if deep {
            attr(out, "version", "int", &1i32.to_le_bytes());
            attr(out, "maxSamplesPerPixel", "int", &1i32.to_le_bytes());
        }
        out.push(0);
    };
    let mut bytes = vec![0x76, 0x2f, 0x31, 0x01];
    bytes.extend((2u32 | 0x800 | 0x1000).to_le_bytes());
    header(&mut bytes, "beauty", &["A", "B", "G", "R"], false);
    header(&mut bytes, "deep", &["Z"], true);
    bytes.push(0);
    let floats = |v: &[f32]| v.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let mut chunks = Vec::new();
    for y in 0..h {
        let row = &rgba[y * w..(y + 1) * w];
        let mut data = Vec::new();
        for c in [3, 2, 1, 0] {
            data.extend(floats(&row.iter().map(|p| p[c]).collect::<Vec<_>>()));
        }
        let mut chunk = ints(&[0, y as i32, data.len() as i32]);
        chunk.extend(data);
        chunks.push(chunk);
    }
    for y in 0..h {
        let counts = ints(&(1..=w as i32).collect::<Vec<_>>());
        let samples = floats(&vec![2.0; w]);
        let mut chunk = ints(&[1, y as i32]);
        for size in [counts.len(), samples.len(), samples.len()] {
            chunk.extend((size as u64).to_le_bytes());
        }
        chunk.extend(counts);
        chunk.extend(samples);
        chunks.push(chunk);
    }
    let mut at = bytes.len() + 8 * chunks.len();
    for chunk in &chunks {
        bytes.extend((at as u64).to_le_bytes());
        at += chunk.len();
    }
    bytes.extend(chunks.concat());
    std::fs::write(path, bytes).unwrap();
}

/// A multi-part render with a deep part beside its flat beauty: the deep part is left out
/// with a warning and the rest is read and written (an outside probe: the whole file was
/// refused, "deep data is not supported"); `info` shows its channels as not read.
#[test]
fn a_deep_part_beside_a_flat_one_is_left_out_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (8, 4);
    let rgba: Vec<[f32; 4]> = (0..w * h)
        .map(|i| [i as f32 / 32.0, 0.5, 1.0 - i as f32 / 32.0, 1.0])
        .collect();
    let input = dir.path().join("deep.exr");
    exr_with_a_deep_part(&input, (w, h), &rgba);
    if let Some(text) = oiiotool_info(&input) {
        assert!(text.contains("2 subimages"), "not a valid file: {text}");
    }
    let output = dir.path().join("out.exr");
    let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&output)]);
    let err = stderr(&o);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("part deep of the colour file") && err.contains("deep data"),
        "{err}"
    );
    let read = read_exr_reference(&output);
    for (c, name) in ["R", "G", "B", "A"].iter().enumerate() {
        let expected: Vec<f32> = rgba.iter().map(|p| p[c]).collect();
        assert_exact(channel(&read, name), &expected, name);
    }
    assert!(
        !read.iter().any(|(name, _)| name.contains('Z')),
        "{:?}",
        read.len()
    );
    if let Some(text) = oiiotool_info(&output) {
        assert!(text.contains("4 channel"), "{text}");
    }

    let o = shutter(&["info", &s(&input)]);
    let text = stdout(&o);
    assert!(o.status.success(), "{}", stderr(&o));
    let z = text
        .lines()
        .find(|l| l.contains("deep.Z"))
        .unwrap_or_default();
    assert!(z.contains("not read"), "{text}");
}

/// Writes a single-part EXR whose channels are named by the UTF-8 of `channels` (through
/// the exr crate's bytes, not its Latin-1 `Text::from`), as OpenEXR 3 and Blender write them.
fn write_utf8_named(path: &Path, (w, h): (usize, usize), channels: Vec<(String, Vec<f32>)>) {
    let channels = channels
        .into_iter()
        .map(|(name, plane)| {
            let name = exr::meta::attribute::Text::from_slice_unchecked(name.as_bytes());
            AnyChannel::new(name, FlatSamples::F32(plane))
        })
        .collect();
    let layer = layer_with(
        None,
        (w, h),
        Blocks::ScanLines,
        Compression::ZIP16,
        channels,
    );
    Image::from_layer(layer).write().to_file(path).unwrap();
}

/// Channel and layer names are UTF-8 (an outside probe: Blender's view layer `Vordergrund_ü`
/// was read as `Vordergrund_Ã¼`, so `--layers Vordergrund_ü,Hintergrund` found no such
/// layer, and `info` suggested the garbled name): the layer is found, and the output names
/// its channels with the same bytes.
#[test]
fn utf8_layer_names_are_found_and_written_back_byte_for_byte() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16, 8);
    let n = w * h;
    let inside = |i: usize| (4..10).contains(&(i % w)) && (2..6).contains(&(i / w));
    let mut channels = Vec::new();
    for (layer, depth) in [("Vordergrund_ü", 5.0), ("Hintergrund", 20.0)] {
        let front = layer != "Hintergrund";
        let alpha: Vec<f32> = (0..n)
            .map(|i| if !front || inside(i) { 1.0 } else { 0.0 })
            .collect();
        for c in ["R", "G", "B", "A"] {
            channels.push((format!("{layer}.Combined.{c}"), alpha.clone()));
        }
        channels.push((format!("{layer}.Depth.Z"), vec![depth; n]));
        for c in ["X", "Y", "Z", "W"] {
            channels.push((format!("{layer}.Vector.{c}"), vec![0.0; n]));
        }
    }
    let input = dir.path().join("layers.exr");
    write_utf8_named(&input, (w, h), channels);

    let o = shutter(&["info", &s(&input)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("view layers Hintergrund, Vordergrund_ü:"),
        "{}",
        stdout(&o)
    );

    let output = dir.path().join("out.exr");
    let o = shutter(&[
        "blur",
        "--preset",
        "blender",
        "--layers",
        "Vordergrund_ü,Hintergrund",
        "--algorithm",
        "none",
        "--color",
        &s(&input),
        "-o",
        &s(&output),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The names as the file stores them: bytes, read by the exr crate without decoding.
    let names: Vec<Vec<u8>> = read_exr_layers(&output)
        .iter()
        .flat_map(|l| l.channel_data.list.iter())
        .map(|c| c.name.bytes().to_vec())
        .collect();
    for name in [
        "Vordergrund_ü.Combined.R",
        "Vordergrund_ü.Depth.Z",
        "Hintergrund.Vector.X",
    ] {
        assert!(
            names.iter().any(|n| n == name.as_bytes()),
            "{name} not in {:?}",
            names
                .iter()
                .map(|n| String::from_utf8_lossy(n))
                .collect::<Vec<_>>()
        );
    }
}
