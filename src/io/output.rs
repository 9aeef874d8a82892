//! Writing frames: EXR (f32 or half, any compression exr writes), PNG/TIFF (8/16-bit) and
//! JPEG, sRGB-encoded unless told linear. Every file is written to a temporary file in the
//! destination folder and renamed into place, so an interrupted run never leaves a partial
//! frame under the final name. The temporary files in flight are registered, so that a
//! signal handler can remove them ([`abandon_temporaries`]), and a later run removes those a
//! killed process left ([`remove_stale_temporaries`]). [`existing_frame_problem`] says
//! whether an existing output is a finished frame (`--skip-existing`).

use std::collections::{BTreeMap, HashSet};
use std::fs::File;
use std::io::{BufWriter, Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use crate::error::{Problem, ProblemKind, WriteFailure};
use crate::frame::{Frame, Photo, Plane, Windows};
use crate::io::exr::{self as exr_io, ExrOptions};
use crate::io::exr_like::{self, ExrOutput};
use crate::io::file::{FileInfo, FileKind};
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
#[derive(Clone, Debug, PartialEq)]
pub struct OutputOptions {
    /// EXR output: what does not follow the input.
    pub exr: ExrOutput,
    /// What made the frames, as `shutter blur` flags: an EXR output's `shutter/settings`.
    pub record: String,
    /// An EXR output holds the beauty alone, not the colour file's other channels.
    pub beauty_only: bool,
    /// PNG/TIFF bits per channel: 8 or 16; `None`: as the input photo, 8 for any other input.
    pub bit_depth: Option<u8>,
    /// JPEG quality, 1 to 100.
    pub jpeg_quality: u8,
    /// Apply the sRGB transfer to integer outputs.
    pub srgb: bool,
}

impl Default for OutputOptions {
    fn default() -> Self {
        OutputOptions {
            exr: ExrOutput::default(),
            record: String::new(),
            beauty_only: false,
            bit_depth: None,
            jpeg_quality: 95,
            srgb: true,
        }
    }
}

/// The temporary name a frame is written under before it is renamed into place:
/// `.NAME.PID.tmp`. Starts with a dot so that sequence discovery and `####` patterns never
/// mistake it for a frame; carries the writer's process id so that a later run can tell a
/// dead process's leftovers ([`remove_stale_temporaries`]) from a live one's. NAME is
/// shortened where the whole would pass the 255 bytes a file name may have
/// ([`temporary_stem`]).
pub fn temporary_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(
        ".{}.{}.tmp",
        temporary_stem(&name),
        std::process::id()
    ))
}

/// The NAME of an output's temporary file: the output's name, or, where `.NAME.PID.tmp`
/// could pass 255 bytes (NAME_MAX of every common file system; an output name of 242 bytes
/// or more), its first 222 bytes and `~` and a 64-bit hash of the whole name (before, such
/// an output failed to open its temporary file: "File name too long").
fn temporary_stem(name: &str) -> String {
    // `.`, `.`, a process id of up to 10 digits, `.tmp`.
    const ROOM: usize = 255 - 16;
    if name.len() <= ROOM {
        return name.to_string();
    }
    let mut keep = 222;
    while !name.is_char_boundary(keep) {
        keep -= 1;
    }
    let hash = crate::io::lock::fnv1a(&[name.as_bytes()]);
    format!("{}~{hash:016x}", &name[..keep])
}

/// The temporary files this process is writing now, and whether it is stopping: what a
/// signal handler removes ([`abandon_temporaries`]) before the process exits.
struct InFlight {
    stopping: bool,
    temporaries: Vec<PathBuf>,
}

static IN_FLIGHT: Mutex<InFlight> = Mutex::new(InFlight {
    stopping: false,
    temporaries: Vec::new(),
});

fn in_flight() -> MutexGuard<'static, InFlight> {
    IN_FLIGHT.lock().unwrap_or_else(PoisonError::into_inner)
}

/// A temporary file being written: registered in [`IN_FLIGHT`] while it exists, removed on
/// drop (an error, or a panic while writing) unless it was renamed into place.
struct Temporary {
    path: PathBuf,
    renamed: bool,
}

impl Temporary {
    /// Creates the file. It is created while the registry is held, so a signal handler sees
    /// every temporary file that exists, and none is created once it has run.
    fn create(path: PathBuf) -> Result<(Temporary, File), WriteFailure> {
        let mut in_flight = in_flight();
        if in_flight.stopping {
            return Err(WriteFailure::transient(
                "the run is stopping (interrupted); nothing more is written",
            ));
        }
        // Readable too: an EXR's headers are read back to put its attributes in order.
        let file = File::options()
            .read(true)
            .write(true)
            .create(true)
            .truncate(true)
            .open(&path)
            .map_err(failed_write)?;
        in_flight.temporaries.push(path.clone());
        Ok((
            Temporary {
                path,
                renamed: false,
            },
            file,
        ))
    }

    fn rename_to(mut self, path: &Path) -> Result<(), WriteFailure> {
        std::fs::rename(&self.path, path).map_err(failed_write)?;
        self.renamed = true;
        Ok(())
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        if !self.renamed {
            let _ = std::fs::remove_file(&self.path);
        }
        in_flight().temporaries.retain(|p| *p != self.path);
    }
}

/// Stops all writing (for a signal handler, before the process exits): removes the
/// temporary files being written, and makes every later [`write_atomic`] fail without
/// creating anything. A write already under way goes on into a file that no longer has a
/// name, and its rename fails. Returns how many files were removed.
pub fn abandon_temporaries() -> usize {
    let mut in_flight = in_flight();
    in_flight.stopping = true;
    let removed = in_flight.temporaries.drain(..);
    removed
        .filter(|path| std::fs::remove_file(path).is_ok())
        .count()
}

/// The temporary file a file is written into: a `File` that keeps the I/O error of its
/// latest call, if it failed. Encoders (the exr crate, png, tiff, jpeg-encoder) hand their
/// errors on as text; the error kept says whether a failure was the system's, and whether a
/// retry may cure it ([`crate::error::is_transient_io`]).
pub struct OutputFile {
    file: File,
    error: Option<std::io::Error>,
}

impl OutputFile {
    fn kept<T>(&mut self, result: std::io::Result<T>) -> std::io::Result<T> {
        self.error = result.as_ref().err().map(|e| match e.raw_os_error() {
            Some(code) => std::io::Error::from_raw_os_error(code),
            None => std::io::Error::from(e.kind()),
        });
        result
    }
}

impl Write for OutputFile {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        let result = self.file.write(bytes);
        self.kept(result)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        let result = self.file.flush();
        self.kept(result)
    }
}

impl Read for OutputFile {
    fn read(&mut self, bytes: &mut [u8]) -> std::io::Result<usize> {
        let result = self.file.read(bytes);
        self.kept(result)
    }
}

impl Seek for OutputFile {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        let result = self.file.seek(to);
        self.kept(result)
    }
}

/// Writes a file atomically: `write` fills a buffered temporary file beside `path`, which is
/// flushed and renamed into place; on any failure (or a panic inside `write`) the temporary
/// file is removed and `path` is untouched. The folder must exist. A failure says whether
/// a retry may cure it: an I/O error by its kind, the output lock taken by another job
/// (transient), anything else `write` refuses (permanent).
pub fn write_atomic_classed(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<OutputFile>) -> Result<(), String>,
) -> Result<(), WriteFailure> {
    let (temporary, file) = Temporary::create(temporary_path(path))?;
    let mut writer = BufWriter::new(OutputFile { file, error: None });
    if let Err(detail) = write(&mut writer).and_then(|()| writer.flush().map_err(|e| e.to_string()))
    {
        // Read before the writer is dropped (its drop flushes again).
        return Err(match &writer.get_ref().error {
            Some(error) => WriteFailure::of_io(error, detail),
            None => WriteFailure::permanent(detail),
        });
    }
    drop(writer);
    // The output lock must still be ours (someone may have deleted its file): else another
    // job may be writing this frame.
    crate::io::lock::verify_held()?;
    temporary.rename_to(path)
}

/// A failure to make or rename a file: for want of its folder, the output folder may have
/// been removed (or removed and made again) under the run, taking the frames written there
/// with it, which the held lock tells ([`crate::io::lock::verify_held`]: transient, so that
/// a rerun writes them again; an outside probe: exit 1, "No such file or directory").
fn failed_write(e: std::io::Error) -> WriteFailure {
    let failure = WriteFailure::of_io(&e, e.to_string());
    match e.kind() {
        std::io::ErrorKind::NotFound => crate::io::lock::verify_held().err().unwrap_or(failure),
        _ => failure,
    }
}

/// [`write_atomic_classed`], the failure as text alone.
pub fn write_atomic(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<OutputFile>) -> Result<(), String>,
) -> Result<(), String> {
    write_atomic_classed(path, write).map_err(|failure| failure.detail)
}

/// Whether a process with this id is running. Unix: `kill(pid, 0)` (a process of another
/// user counts as running); elsewhere every process counts as running, so nothing is
/// removed.
fn process_is_running(pid: u32) -> bool {
    #[cfg(unix)]
    {
        let Ok(pid) = i32::try_from(pid) else {
            return true;
        };
        if pid <= 0 {
            return true;
        }
        !matches!(
            nix::sys::signal::kill(nix::unistd::Pid::from_raw(pid), None),
            Err(nix::errno::Errno::ESRCH)
        )
    }
    #[cfg(not(unix))]
    {
        let _ = pid;
        true
    }
}

/// Removes the temporary files that processes no longer running left beside `outputs`
/// (`.NAME.PID.tmp` for an output named NAME ([`temporary_path`]), a SIGKILL or a power cut
/// being what leaves them); a running process's are kept, whatever it is. Each folder is
/// listed once. Returns the files removed.
pub fn remove_stale_temporaries(outputs: &[PathBuf]) -> Vec<PathBuf> {
    let mut by_folder: BTreeMap<PathBuf, HashSet<String>> = BTreeMap::new();
    for path in outputs {
        let (Some(folder), Some(name)) = (path.parent(), path.file_name()) else {
            continue;
        };
        by_folder
            .entry(folder.to_path_buf())
            .or_default()
            .insert(temporary_stem(&name.to_string_lossy()));
    }
    let mut removed = Vec::new();
    for (folder, names) in by_folder {
        let listed = if folder.as_os_str().is_empty() {
            Path::new(".")
        } else {
            folder.as_path()
        };
        let Ok(entries) = std::fs::read_dir(listed) else {
            continue;
        };
        for entry in entries.flatten() {
            let file_name = entry.file_name().to_string_lossy().into_owned();
            let Some((name, pid)) = file_name
                .strip_prefix('.')
                .and_then(|n| n.strip_suffix(".tmp"))
                .and_then(|n| n.rsplit_once('.'))
            else {
                continue;
            };
            let Ok(pid) = pid.parse::<u32>() else {
                continue;
            };
            if names.contains(name)
                && !process_is_running(pid)
                && std::fs::remove_file(entry.path()).is_ok()
            {
                removed.push(folder.join(&file_name));
            }
        }
    }
    removed
}

/// Why an existing output cannot stand for a finished frame of `width` × `height` in the
/// format its name says (`--skip-existing`); `None` when it can. EXR: the header and the
/// chunk table (every chunk inside the file, as preflight checks inputs); PNG, TIFF, JPEG:
/// the header and a full decode (they have no chunk table to check).
pub fn existing_frame_problem(
    path: &Path,
    width: usize,
    height: usize,
    largest: usize,
    views: &[&str],
) -> Option<String> {
    let meta = match std::fs::metadata(path) {
        Ok(meta) => meta,
        Err(e) => return Some(format!("it cannot be read: {e}")),
    };
    if !meta.is_file() {
        return Some("it is not a file".into());
    }
    if meta.len() == 0 {
        return Some("it is empty".into());
    }
    let expected = OutputFormat::from_path(path)?;
    // The header checks preflight makes of inputs (for EXR the chunk table too, for JPEG the
    // stream), with the frame's own size as the pixel limit (or `largest`, the largest part
    // of the colour file, which a part passed through at its own window may be).
    let limit = width.saturating_mul(height).max(largest).max(1);
    let info = match FileInfo::probe_within(path, limit) {
        Ok(info) => info,
        Err(problem) => return Some(problem.detail),
    };
    let format = match (&info.kind, expected) {
        (FileKind::Exr { .. }, OutputFormat::Exr) => None,
        (FileKind::Image { format, .. }, OutputFormat::Image(expected)) => {
            let name = match expected {
                ImageFormat::Png => "png",
                ImageFormat::Tiff => "tiff",
                ImageFormat::Jpeg => "jpeg",
            };
            (*format != name).then(|| format!("it is a {format} file, not {name}"))
        }
        (FileKind::Exr { .. }, _) => Some("it is an EXR file".to_string()),
        (FileKind::Image { format, .. }, _) => Some(format!("it is a {format} file, not EXR")),
    };
    if format.is_some() {
        return format;
    }
    // An EXR's beauty may be in any of its parts.
    let sizes: Vec<(usize, usize)> = match &info.kind {
        FileKind::Exr { headers, .. } => (headers.iter())
            .map(|h| (h.layer_size.0, h.layer_size.1))
            .collect(),
        FileKind::Image { .. } => vec![(info.width, info.height)],
    };
    // An output of every view holds each of them (one of a view, or of an older run, does
    // not).
    let held = info.views.as_ref().map_or(Vec::new(), |v| v.names.clone());
    if let Some(view) = views.iter().find(|v| !held.iter().any(|h| h == *v)) {
        return Some(format!("it does not hold the view {view}"));
    }
    if !sizes.contains(&(width, height)) {
        return Some(format!(
            "it is {}x{}, the frame is {width}x{height}",
            info.width, info.height
        ));
    }
    // PNG and TIFF have no chunk table to check: decode them whole.
    match info.kind {
        FileKind::Image { .. } => image_io::read_planes(path, (width, height))
            .err()
            .map(|e| format!("it cannot be decoded (cut short?): {e}")),
        FileKind::Exr { .. } => None,
    }
}

/// The settings an output records it was made with, which `--skip-existing` holds against
/// the run's own: an EXR's `shutter/settings` (its first part's that holds them), a
/// picture's where its format keeps them (`image::record`, as that format holds them:
/// [`image_io::record_as_held`]); `None` for a file another program made, or one that
/// cannot be read.
pub fn recorded_settings(path: &Path) -> Option<String> {
    if let OutputFormat::Image(format) = OutputFormat::from_path(path)? {
        return image_io::recorded_settings(path, format);
    }
    let meta = exr_io::read_meta(path).ok()?;
    let name = exr::meta::attribute::Text::from("shutter/settings");
    meta.headers
        .iter()
        .find_map(|header| match header.own_attributes.other.get(&name)? {
            exr::meta::attribute::AttributeValue::Text(text) => {
                Some(crate::io::channels::name_of(text))
            }
            _ => None,
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

/// Bits per sample of a picture output: `--bit-depth`, else the input photo's (a float
/// TIFF's 32 where the output is a TIFF, 16 in a PNG, the most it holds), else 8; a JPEG's
/// are 8 whatever is asked.
pub fn picture_bits(photo: Option<&Photo>, format: ImageFormat, options: &OutputOptions) -> u8 {
    let bits = options
        .bit_depth
        .unwrap_or_else(|| match photo.map_or(8, |p| p.bits) {
            32 if format != ImageFormat::Tiff => 16,
            bits => bits,
        });
    if format == ImageFormat::Jpeg {
        8
    } else {
        bits
    }
}

/// An ICC profile's primaries and white as an EXR's `chromaticities`.
fn exr_chromaticities(icc: &[u8]) -> Option<exr::meta::attribute::Chromaticities> {
    let [r, g, b, w] = image_io::chromaticities(icc)?;
    let xy = |(x, y): (f64, f64)| exr::math::Vec2(x as f32, y as f32);
    Some(exr::meta::attribute::Chromaticities {
        red: xy(r),
        green: xy(g),
        blue: xy(b),
        white: xy(w),
    })
}

/// A photo's primaries and white as an EXR's `chromaticities`: its PNG's cICP's or its ICC
/// profile's, else a PNG's cHRM as it stores them (where no sRGB chunk says sRGB's, which
/// are Rec. 709's, the EXR's own default). A PNG's gAMA alone says no primaries: none.
fn photo_chromaticities(photo: &Photo) -> Option<exr::meta::attribute::Chromaticities> {
    if let Some(icc) = image_io::cicp_profile_of(photo, false).or_else(|| photo.icc.clone()) {
        return exr_chromaticities(&icc);
    }
    let colour = photo.png_colour.filter(|c| c.srgb.is_none())?;
    let c = colour.chromaticities?.map(|v| v as f32 / 100_000.0);
    let xy = |i: usize| exr::math::Vec2(c[i], c[i + 1]);
    Some(exr::meta::attribute::Chromaticities {
        white: xy(0),
        red: xy(2),
        green: xy(4),
        blue: xy(6),
    })
}

/// The ICC profile a picture made from an EXR carries: its `chromaticities` (the first
/// part's), with the curve the picture's codes are encoded with (sRGB's; linear light's
/// with `--linear` or in a float TIFF). `Ok(None)` where the frame came from a photo, or
/// the EXR says no primaries or Rec. 709's; `Err` where its primaries make no profile.
pub(crate) fn exr_picture_profile(
    frame: &Frame,
    format: ImageFormat,
    bits: u8,
    options: &OutputOptions,
) -> Result<Option<Vec<u8>>, String> {
    if frame.carried.photo.is_some() {
        return Ok(None);
    }
    let header = frame.carried.headers.first();
    let Some(c) = header.and_then(|h| h.shared_attributes.chromaticities) else {
        return Ok(None);
    };
    let xy = [c.white, c.red, c.green, c.blue].map(|v| [v.0, v.1]);
    let linear = !options.srgb || (bits == 32 && format == ImageFormat::Tiff);
    let [[wx, wy], [rx, ry], [gx, gy], [bx, by]] = xy;
    image_io::primaries_profile([wx, wy, rx, ry, gx, gy, bx, by], linear)
}

/// Writes the colour of `frame` to `path` atomically. The folder must exist.
pub fn write_frame(
    path: &Path,
    frame: Frame,
    options: &OutputOptions,
    frame_number: Option<i64>,
) -> Result<(), Problem> {
    write_views(path, vec![frame], options, frame_number).map(|_| ())
}

/// Writes `views`, the frames of every view of one multi-view colour file (each read as
/// that view alone, in the file's order of views), to `path` atomically, as one EXR of every
/// view: each view's channels under the names and in the parts they are stored in, the
/// channels of no view once (the first view's), and the input's view attributes. One frame is
/// written as [`write_frame`] writes it; a picture holds the first view. The folder must
/// exist. Returns what the writing changed that the run must say (a DWA highlight capped), in
/// words for its warnings (the caller names the output), as
/// `output_notes` says beforehand
/// what it will leave out.
pub fn write_views(
    path: &Path,
    views: Vec<Frame>,
    options: &OutputOptions,
    frame_number: Option<i64>,
) -> Result<Vec<String>, Problem> {
    let fail = |detail: String| Problem::new(ProblemKind::Output, path, detail).frame(frame_number);
    let format = OutputFormat::from_path(path).ok_or_else(|| {
        fail("unknown output format; use .exr, .png, .tif, .tiff, .jpg or .jpeg".into())
    })?;
    if views.iter().any(|f| f.color.is_none()) || views.is_empty() {
        return Err(fail("the frame has no colour to write".into()));
    }
    match format {
        OutputFormat::Exr => {
            let every = if views.len() > 1 {
                exr_like::Views::Every
            } else {
                exr_like::Views::One
            };
            let display = views[0].windows.display;
            let headers = views[0].carried.headers.clone();
            // A photo's primaries, from its profile, where no EXR header says them.
            let photo = views[0].carried.photo.as_ref();
            let exr = ExrOutput {
                chromaticities: photo.and_then(photo_chromaticities),
                ..options.exr
            };
            let parts = crate::io::exr_parts::exr_parts(views, &headers);
            let mut capped = None;
            write_atomic_classed(path, |writer| {
                capped =
                    exr_like::write_like(writer, display, parts, &exr, &options.record, every)?;
                Ok(())
            })
            .map(|()| {
                capped
                    .map(crate::io::exr_dwa::capped_warning)
                    .into_iter()
                    .collect()
            })
        }
        OutputFormat::Image(format) => write_atomic_classed(path, |writer| {
            let frame = &views[0];
            let color = frame.color.as_ref().expect("checked");
            // A picture is the display window: an EXR's overscan is cut off, and what its
            // data window does not cover is transparent black.
            let display = frame.windows.display;
            let (width, height) = (display.width, display.height);
            if width
                .checked_mul(height)
                .is_none_or(|n| n > crate::io::file::DEFAULT_MAX_PIXELS)
            {
                return Err(format!(
                    "the display window is {width}x{height}, too large for a picture"
                ));
            }
            let on_display =
                |plane: &[f32]| frame.windows.on_display(plane, frame.width, frame.height);
            let rgb = [
                on_display(&color.r),
                on_display(&color.g),
                on_display(&color.b),
            ];
            let alpha = color.a.as_deref().map(on_display);
            // What the input photo held, held again; its bit depth unless told otherwise.
            let photo = frame.carried.photo.as_ref();
            let bits = picture_bits(photo, format, options);
            // An EXR's primaries, as a profile of the curve its codes are encoded with.
            let exr_icc = exr_picture_profile(frame, format, bits, options)
                .ok()
                .flatten();
            let photo_options = image_io::PhotoOptions {
                bits,
                linear: !options.srgb,
                jpeg_quality: options.jpeg_quality,
                photo,
                icc: exr_icc.as_deref(),
                record: &options.record,
            };
            image_io::write_photo(
                writer,
                format,
                width,
                height,
                [&rgb[0], &rgb[1], &rgb[2]],
                alpha.as_deref(),
                &photo_options,
            )
        })
        .map(|()| Vec::new()),
    }
    // The preflight found the place writable: a failure now is the moment's where its error
    // says so (a full disk, a timeout: exit 75), else for good (a folder made in the file's
    // place, permissions changed: exit 1).
    .map_err(|failure| Problem::new(failure.kind(), path, failure.detail).frame(frame_number))
}
