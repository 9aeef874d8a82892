//! Writing frames: EXR (f32 or half, any compression exr writes), PNG/TIFF (8/16-bit) and
//! JPEG, sRGB-encoded unless told linear. Every file is written to a temporary file in the
//! destination folder and renamed into place, so an interrupted run never leaves a partial
//! frame under the final name.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use crate::error::{Problem, ProblemKind};
use crate::frame::{Frame, Plane, Windows};
use crate::io::exr::{self as exr_io, ExrOptions};
use crate::io::image::{self as image_io, ImageFormat};

/// Output format, from the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutputFormat {
    Exr,
    Image(ImageFormat),
}

impl OutputFormat {
    pub fn from_path(path: &Path) -> Option<Self> {
        if path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"))
        {
            return Some(OutputFormat::Exr);
        }
        ImageFormat::from_path(path).map(OutputFormat::Image)
    }
}

/// How outputs are encoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OutputOptions {
    pub exr: ExrOptions,
    /// PNG/TIFF bits per channel: 8 or 16.
    pub sixteen_bit: bool,
    /// Apply the sRGB transfer to integer outputs.
    pub srgb: bool,
}

impl Default for OutputOptions {
    fn default() -> Self {
        OutputOptions {
            exr: ExrOptions::default(),
            sixteen_bit: false,
            srgb: true,
        }
    }
}

/// The temporary name a frame is written under before it is renamed into place. Starts with
/// a dot so that sequence discovery and `####` patterns never mistake it for a frame.
pub fn temporary_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// Writes a file atomically: `write` fills a buffered temporary file beside `path`, which is
/// flushed and renamed into place; on any failure the temporary file is removed and `path`
/// is untouched. The folder must exist.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<(), String>,
) -> Result<(), String> {
    let temporary = temporary_path(path);
    let file = File::create(&temporary).map_err(|e| e.to_string())?;
    let mut writer = BufWriter::new(file);
    let result = write(&mut writer).and_then(|()| writer.flush().map_err(|e| e.to_string()));
    drop(writer);
    if let Err(detail) = result {
        let _ = std::fs::remove_file(&temporary);
        return Err(detail);
    }
    std::fs::rename(&temporary, path).map_err(|e| {
        let _ = std::fs::remove_file(&temporary);
        e.to_string()
    })
}

/// Writes every pass `frame` holds as a canonical pass file (the `shutter` preset's channel
/// names, f32, the default compression), atomically: colour as R, G, B, A (A = 1 where the
/// frame has no alpha), depth as Z, velocity as X, Y and positions as X, Y (, Z), each to
/// `path(role)` with role `color`, `depth`, `velocity`, `prev` or `next`.
pub fn write_passes(frame: Frame, path: impl Fn(&str) -> PathBuf) -> Result<(), Problem> {
    let (width, height, windows) = (frame.width, frame.height, frame.windows);
    let write = |role: &str, channels: Vec<(&str, Plane)>| {
        let path = path(role);
        let channels = channels
            .into_iter()
            .map(|(n, p)| (n.to_string(), p))
            .collect();
        write_exr_atomic(
            &path,
            width,
            height,
            windows,
            channels,
            ExrOptions::default(),
        )
        .map_err(|detail| Problem::new(ProblemKind::Output, &path, detail))
    };
    if let Some(c) = frame.color {
        let a = c.a.unwrap_or_else(|| vec![1.0; width * height]);
        write("color", vec![("R", c.r), ("G", c.g), ("B", c.b), ("A", a)])?;
    }
    if let Some(z) = frame.depth {
        write("depth", vec![("Z", z)])?;
    }
    if let Some(v) = frame.velocity {
        write("velocity", vec![("X", v.x), ("Y", v.y)])?;
    }
    for (role, positions) in [("prev", frame.prev), ("next", frame.next)] {
        if let Some(p) = positions {
            let mut channels = vec![("X", p.x), ("Y", p.y)];
            if let Some(z) = p.z {
                channels.push(("Z", z));
            }
            write(role, channels)?;
        }
    }
    Ok(())
}

/// Writes named planes as an EXR, atomically.
pub fn write_exr_atomic(
    path: &Path,
    width: usize,
    height: usize,
    windows: Windows,
    channels: Vec<(String, Plane)>,
    options: ExrOptions,
) -> Result<(), String> {
    write_atomic(path, |writer| {
        exr_io::write_channels(writer, width, height, windows, channels, options)
            .map_err(|e| e.to_string())
    })
}

/// Writes the colour of `frame` to `path` atomically. The folder must exist.
pub fn write_frame(
    path: &Path,
    frame: Frame,
    options: &OutputOptions,
    frame_number: Option<i64>,
) -> Result<(), Problem> {
    let fail = |detail: String| Problem::new(ProblemKind::Output, path, detail).frame(frame_number);
    let format = OutputFormat::from_path(path).ok_or_else(|| {
        fail("unknown output format; use .exr, .png, .tif, .tiff, .jpg or .jpeg".into())
    })?;
    let Some(color) = frame.color else {
        return Err(fail("the frame has no colour to write".into()));
    };
    match format {
        OutputFormat::Exr => {
            let mut channels = vec![
                ("R".to_string(), color.r),
                ("G".to_string(), color.g),
                ("B".to_string(), color.b),
            ];
            if let Some(a) = color.a {
                channels.push(("A".to_string(), a));
            }
            write_exr_atomic(
                path,
                frame.width,
                frame.height,
                frame.windows,
                channels,
                options.exr,
            )
        }
        OutputFormat::Image(format) => write_atomic(path, |writer| {
            image_io::write_color(
                writer,
                format,
                frame.width,
                frame.height,
                [&color.r, &color.g, &color.b],
                color.a.as_deref(),
                options.sixteen_bit,
                options.srgb,
            )
        }),
    }
    .map_err(fail)
}
