//! Parts in a compression the exr crate does not know (an outside tester's F13: a file with a
//! part in OpenEXR 3.5's ZSTD was refused whole, "unknown compression method", naming
//! neither the part nor the compression). The files are written by the exr crate (RLE: a
//! line a chunk, as OpenEXR 3.5 writes ZSTD), then a part's compression byte is set to
//! OpenEXR's id (`ZSTD_COMPRESSION = 13`, `LJ2K_COMPRESSION = 12`): shutter never decodes
//! that part's chunks, so what they hold is not looked at.

use std::path::Path;

use crate::support::*;

const W: usize = 8;
/// More chunks (RLE: a line each, 20) than the stand-in the crate is shown would give this
/// part (256 lines a chunk: one), so that a part after the unknown one is found only where
/// its offset table is read as stored.
const H: usize = 20;

/// Sets the compression of part `part` (in the order the headers list them) to `id`.
fn store_compression(path: &Path, part: usize, id: u8) {
    let mut bytes = std::fs::read(path).unwrap();
    let key = b"compression\0compression\0\x01\0\0\0";
    let at = (0..bytes.len() - key.len())
        .filter(|&p| bytes[p..].starts_with(key))
        .nth(part)
        .unwrap();
    bytes[at + key.len()] = id;
    std::fs::write(path, bytes).unwrap();
}

/// A part's name and channels.
type Named = (&'static str, Vec<(String, Vec<f32>)>);

/// The channels of a render of three parts: `rgba` (R, G, B, A), `spec` (spec.R, spec.G,
/// spec.B) and `depth` (Z), in that order.
fn render() -> Vec<Named> {
    let n = W * H;
    let plane = |seed| noise(n, seed, 0.0, 1.0);
    let named = |names: &[&str], seed: u32| -> Vec<(String, Vec<f32>)> {
        (names.iter().zip(seed..))
            .map(|(name, seed)| (name.to_string(), plane(seed)))
            .collect()
    };
    vec![
        ("rgba", named(&["A", "B", "G", "R"], 1)),
        ("spec", named(&["spec.B", "spec.G", "spec.R"], 10)),
        ("depth", vec![("Z".to_string(), noise(n, 20, 1.0, 9.0))]),
    ]
}

/// Writes `parts` as one multi-part EXR at `path`.
fn write_render(path: &Path, parts: &[Named]) {
    let parts = (parts.iter())
        .map(|(name, channels)| Part {
            name: Some(name),
            view: None,
            multi_view: None,
            channels: channels.clone(),
        })
        .collect();
    write_parts(path, (W, H), parts);
}

/// The channels of part `name` of `parts`.
fn part_of<'a>(parts: &'a [Named], name: &str) -> &'a [(String, Vec<f32>)] {
    &parts.iter().find(|(n, _)| *n == name).unwrap().1
}

/// A part in ZSTD, LJ2K or an id OpenEXR does not name, beside parts shutter reads (the
/// probe's `mp_zstd.exr`, whose colour pass failed "unknown compression method"): it is left
/// out with a warning naming it, its compression and what to re-save with; the others are
/// read (the part after it through its offset table as stored) and written as they came;
/// `info` lists its channels as not read and names its compression.
#[test]
fn a_part_of_unknown_compression_is_left_out_with_a_warning_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let parts = render();
    for (id, named) in [
        (13, "zstd compression"),
        (12, "lj2k compression"),
        (200, "compression method 200"),
    ] {
        let input = dir.path().join(format!("render{id}.exr"));
        write_render(&input, &parts);
        store_compression(&input, 1, id);
        let output = dir.path().join(format!("out{id}/out.exr"));
        let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&output)]);
        let err = stderr(&o);
        assert!(o.status.success(), "{id}: {err}");
        assert!(
            err.contains("part spec of the colour file not read")
                && err.contains(named)
                && err.contains("re-save with ZIP, PIZ or DWA"),
            "{id}: {err}"
        );
        let layers = read_exr_layers(&output);
        assert!(
            !layers
                .iter()
                .any(|l| l.attributes.layer_name == Some("spec".into())),
            "{id}: the part not read is written"
        );
        for part in ["rgba", "depth"] {
            let layer = part_named(&layers, part);
            for (name, plane) in part_of(&parts, part) {
                let written = (layer.channel_data.list.iter())
                    .find(|c| c.name.to_string() == *name)
                    .unwrap_or_else(|| panic!("{id}: no {part}.{name}"));
                let written: Vec<f32> = written.sample_data.values_as_f32().collect();
                assert_exact(&written, plane, &format!("{id}: {part}.{name}"));
            }
        }

        let o = shutter(&["info", &s(&input)]);
        let text = stdout(&o);
        assert!(o.status.success(), "{id}: {}", stderr(&o));
        let line = |name: &str| text.lines().find(|l| l.contains(name)).unwrap_or_default();
        assert!(line("spec.R").contains("not read"), "{id}: {text}");
        assert!(!line("depth.Z").contains("not read"), "{id}: {text}");
        if id == 13 {
            assert!(line("format:").contains("zstd"), "{text}");
            let rows: Vec<&str> = (text.lines())
                .filter(|l| l.trim_start().starts_with("compression "))
                .collect();
            assert_eq!(rows.len(), 3, "one compression row a part: {text}");
            assert!(rows[1].trim_end().ends_with("zstd"), "{text}");
        }
    }
}

/// A single-part file in ZSTD (the probe's `zstd.exr`): refused, not supported, with a
/// message naming ZSTD and what to re-save with, not "unknown compression method"; with a
/// chunk count and without one (as OpenEXR writes a single part).
#[test]
fn a_single_part_zstd_file_is_refused_naming_zstd() {
    let dir = tempfile::tempdir().unwrap();
    let n = W * H;
    for counted in [true, false] {
        let input = dir.path().join(format!("zstd-{counted}.exr"));
        let channels = ["A", "B", "G", "R"].map(|c| (c, noise(n, 3, 0.0, 1.0)));
        write_exr(&input, W, H, channels.to_vec());
        store_compression(&input, 0, 13);
        if !counted {
            let mut bytes = std::fs::read(&input).unwrap();
            let at = (bytes.windows(11))
                .position(|w| w == b"chunkCount\0")
                .unwrap();
            bytes[at + 9] = b'X';
            std::fs::write(&input, bytes).unwrap();
        }
        let output = dir.path().join("out").join("o.exr");
        for args in [
            vec!["info", &s(&input)],
            vec!["blur", "--color", &s(&input), "-o", &s(&output)],
        ] {
            let o = shutter(&args);
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(1), "{counted} {args:?}: {err}");
            assert!(
                err.contains("not supported")
                    && err.contains(&s(&input))
                    && err.contains("zstd compression cannot be decoded by the exr crate")
                    && err.contains("re-save with ZIP, PIZ or DWA")
                    && !err.contains("unknown compression method"),
                "{counted} {args:?}: {err}"
            );
            assert!(!output.exists());
        }
    }
}

/// The colour in a ZSTD part: not a missing channel but an unsupported file, the message
/// naming the file, the part and the compression.
#[test]
fn the_colour_in_a_zstd_part_is_refused_naming_the_part_and_the_compression() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("render.exr");
    write_render(&input, &render());
    store_compression(&input, 0, 13);
    let output = dir.path().join("out").join("o.exr");
    let o = shutter(&["blur", "--color", &s(&input), "-o", &s(&output)]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("not supported")
            && err.contains(&s(&input))
            && err.contains("color pass")
            && err.contains("part rgba")
            && err.contains("zstd compression")
            && !err.contains("missing channel"),
        "{err}"
    );
    assert!(!output.exists());
}

/// A damaged file is refused as damaged where its damage lies in the part of unknown
/// compression too: cut short, two of the part's table entries at one chunk, or a chunk
/// count its lines cannot have (a review: it was taken as stored, or as 0). Never a panic,
/// nothing written.
#[test]
fn a_damaged_zstd_part_is_refused_as_damaged() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("render.exr");
    write_render(&input, &render());
    let bytes = std::fs::read(&input).unwrap();
    // The headers' length, read before the part is made unknown: the tables follow.
    let mut rest = &bytes[..];
    exr::meta::MetaData::read_from_buffered(&mut rest, false).unwrap();
    let tables = bytes.len() - rest.len();
    store_compression(&input, 1, 13);
    let bytes = std::fs::read(&input).unwrap();
    let mut twice = bytes.clone();
    let spec = tables + 8 * H;
    twice.copy_within(spec..spec + 8, spec + 8);
    // The unknown part's own chunk count, which only shutter reads, impossible for its lines.
    let counts = |value: i32| {
        let key = b"chunkCount\0int\0\x04\0\0\0";
        let mut bytes = bytes.clone();
        let at = (0..bytes.len() - key.len())
            .filter(|&p| bytes[p..].starts_with(key))
            .nth(1)
            .unwrap()
            + key.len();
        bytes[at..at + 4].copy_from_slice(&value.to_le_bytes());
        bytes
    };
    for (name, damaged, says) in [
        (
            "cut.exr",
            bytes[..bytes.len() * 3 / 4].to_vec(),
            "truncated",
        ),
        ("twice.exr", twice, "overlap"),
        ("none.exr", counts(-1), "chunkCount -1"),
        ("more.exr", counts(i32::MAX), "chunkCount 2147483647"),
    ] {
        let path = dir.path().join(name);
        std::fs::write(&path, damaged).unwrap();
        let output = dir.path().join("out").join("o.exr");
        let o = shutter(&["blur", "--color", &s(&path), "-o", &s(&output)]);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(says) && !err.contains("panicked"),
            "{name}: {err}"
        );
        assert!(!output.exists(), "{name}");
    }
}
