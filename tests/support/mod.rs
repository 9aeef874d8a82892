//! Helpers shared by the integration tests: writing EXRs with any channels, running the
//! binary, and the one approximate comparison used everywhere.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use shutter::frame::Windows;
use shutter::io::exr::{write_channels, ExrOptions};

/// Writes a single-part scan-line EXR with the given f32 channels (ZIP).
pub fn write_exr(path: &Path, width: usize, height: usize, channels: Vec<(&str, Vec<f32>)>) {
    write_exr_with(path, width, height, channels, ExrOptions::default());
}

pub fn write_exr_with(
    path: &Path,
    width: usize,
    height: usize,
    channels: Vec<(&str, Vec<f32>)>,
    options: ExrOptions,
) {
    if let Some(parent) = path.parent() {
        std::fs::create_dir_all(parent).unwrap();
    }
    let file = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let channels = channels
        .into_iter()
        .map(|(n, p)| (n.to_string(), p))
        .collect();
    write_channels(
        file,
        width,
        height,
        Windows::full(width, height),
        channels,
        options,
    )
    .unwrap();
}

/// A deterministic pseudo-random plane, values in [lo, hi).
pub fn noise(n: usize, seed: u32, lo: f32, hi: f32) -> Vec<f32> {
    (0..n as u32)
        .map(|i| {
            let mut h = i.wrapping_mul(0x9E37_79B9) ^ seed.wrapping_mul(0x85EB_CA6B);
            h ^= h >> 15;
            h = h.wrapping_mul(0x2C1B_3C6D);
            h ^= h >> 12;
            lo + (hi - lo) * (h as f32 / u32::MAX as f32)
        })
        .collect()
}

/// Reads every channel of an EXR through exr's own image API (independent of our reader).
pub fn read_exr_reference(path: &Path) -> Vec<(String, Vec<f32>)> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .unwrap();
    let mut out = Vec::new();
    for layer in image.layer_data {
        for channel in layer.channel_data.list {
            let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
            out.push((channel.name.to_string(), values));
        }
    }
    out
}

pub fn channel<'a>(channels: &'a [(String, Vec<f32>)], name: &str) -> &'a [f32] {
    &channels
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no channel {name}"))
        .1
}

/// The one approximate comparison: |a - b| <= tolerance, NaN equal only to NaN, infinities
/// equal only to themselves. Panics naming the first differing index.
pub fn assert_close(actual: &[f32], expected: &[f32], tolerance: f32, what: &str) {
    assert_eq!(actual.len(), expected.len(), "{what}: lengths differ");
    for (i, (a, e)) in actual.iter().zip(expected).enumerate() {
        let ok = if a.is_nan() || e.is_nan() {
            a.is_nan() && e.is_nan()
        } else if a.is_infinite() || e.is_infinite() {
            a == e
        } else {
            (a - e).abs() <= tolerance
        };
        assert!(
            ok,
            "{what}: index {i}: got {a}, expected {e} (tolerance {tolerance})"
        );
    }
}

/// Bit-exact comparison (tolerance 0, NaN rules as above).
pub fn assert_exact(actual: &[f32], expected: &[f32], what: &str) {
    assert_close(actual, expected, 0.0, what);
}

/// Runs the shutter binary.
pub fn shutter(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_shutter"))
        .args(args)
        .output()
        .expect("run shutter")
}

pub fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

pub fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// Every file under a folder with its size and modification time, to check that a failed run
/// left it exactly as it was.
pub fn snapshot(dir: &Path) -> Vec<(PathBuf, u64, std::time::SystemTime)> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for entry in entries.flatten() {
            let meta = entry.metadata().unwrap();
            if meta.is_dir() {
                out.push((entry.path(), 0, meta.modified().unwrap()));
                out.extend(snapshot(&entry.path()));
            } else {
                out.push((entry.path(), meta.len(), meta.modified().unwrap()));
            }
        }
    }
    out.sort();
    out
}

pub fn s(path: &Path) -> String {
    path.display().to_string()
}

/// A small canonical frame written as separate pass files `C`, `Z`, `V` (with `.####` when
/// `frame` is given); returns the colour it wrote.
pub fn write_canonical_frame(
    dir: &Path,
    frame: Option<i64>,
    width: usize,
    height: usize,
) -> [Vec<f32>; 4] {
    let n = width * height;
    let seed = frame.unwrap_or(0) as u32;
    let rgba = [
        noise(n, seed * 10 + 1, 0.0, 4.0),
        noise(n, seed * 10 + 2, 0.0, 1.0),
        noise(n, seed * 10 + 3, -0.1, 1.0),
        noise(n, seed * 10 + 4, 0.0, 1.0),
    ];
    let suffix = frame.map_or(String::new(), |f| format!(".{f:04}"));
    write_exr(
        &dir.join(format!("C{suffix}.exr")),
        width,
        height,
        vec![
            ("R", rgba[0].clone()),
            ("G", rgba[1].clone()),
            ("B", rgba[2].clone()),
            ("A", rgba[3].clone()),
        ],
    );
    write_exr(
        &dir.join(format!("Z{suffix}.exr")),
        width,
        height,
        vec![("Z", noise(n, seed * 10 + 5, 1.0, 100.0))],
    );
    write_exr(
        &dir.join(format!("V{suffix}.exr")),
        width,
        height,
        vec![
            ("X", noise(n, seed * 10 + 6, -20.0, 20.0)),
            ("Y", noise(n, seed * 10 + 7, -20.0, 20.0)),
        ],
    );
    rgba
}

/// Writes a small truth scene into a fresh folder.
pub fn small_scene(
    name: &str,
    width: usize,
    height: usize,
    frames: usize,
    samples: usize,
) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let options = shutter::truth::write::SceneOptions {
        width,
        height,
        frames,
        samples,
        ..Default::default()
    };
    shutter::truth::write::write_scene(name, dir.path(), &options, &mut |_, _| {}).unwrap();
    dir
}

/// The sequence pattern of one role (`color`, `depth`, ...) in a scene folder.
pub fn role_pattern(dir: &Path, role: &str) -> String {
    format!("{}/{role}.####.exr", dir.display())
}
