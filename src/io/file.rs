//! What is in a file, from its header alone: size, windows, channels, compression. Used by
//! preflight (before anything is decoded), by `shutter info`, and to plan which channels of
//! which file each pass reads.

use std::io::Read;
use std::path::{Path, PathBuf};

use crate::error::{Problem, ProblemKind};
use crate::frame::{Plane, Windows};
use crate::io::channels::name_of;
use crate::io::view::Views;
use crate::io::{exr as exr_io, image as image_io};

/// The EXR magic number.
const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

/// The default largest frame, in pixels (setting `max-pixels`): 16384 × 16384, which admits
/// a 16K frame (15360 × 8640) and any square up to 16384 a side. A file whose header
/// declares more is refused from its header, before anything is allocated for it: a few
/// hundred bytes can declare billions of pixels, and decoders then invent the ones the file
/// does not hold. At the limit a frame of four f32 planes takes 4 GiB.
pub const DEFAULT_MAX_PIXELS: usize = 16384 * 16384;

/// `width × height` when it is within `max_pixels`, else the problem that names both.
pub fn check_size(
    path: &Path,
    width: usize,
    height: usize,
    max_pixels: usize,
) -> Result<(), Problem> {
    match width.checked_mul(height) {
        Some(pixels) if pixels <= max_pixels => Ok(()),
        pixels => Err(Problem::new(
            ProblemKind::TooLarge,
            path,
            format!(
                "the header declares {width}x{height}{}, above the limit of {max_pixels} \
                 pixels; raise max-pixels if the file is real",
                pixels.map_or(String::new(), |p| format!(" ({p} pixels)"))
            ),
        )),
    }
}

/// The kind of file.
#[derive(Clone, Debug, PartialEq)]
pub enum FileKind {
    Exr {
        /// Compression of each part.
        compression: Vec<&'static str>,
        tiled: bool,
        multipart: bool,
        /// Every part's header, whole: what the output takes its attributes and form from
        /// when the file holds the colour.
        headers: Vec<exr::meta::header::Header>,
    },
    Image {
        format: &'static str,
        bits: u8,
        float: bool,
        /// Turned upright by its EXIF (or TIFF) orientation to another shape: its size is
        /// the upright picture's, stored the other way round.
        turned: bool,
    },
}

/// One channel: its name, and where it lives.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelInfo {
    /// The channel's name as stored.
    pub name: String,
    /// `part.name` when the file is multi-part and the part has a name not already in the
    /// channel name: lets `forward.u` find channel `u` of a part named `forward`.
    pub alias: Option<String>,
    /// EXR part (0 for images).
    pub part: usize,
    /// Index in the part's channel list.
    pub index: usize,
    /// `f16`, `f32`, `u32`, `u8`, `u16`.
    pub sample_type: &'static str,
    /// The view the channel belongs to, in a multi-view file (`None`: no view, or a file of
    /// no views).
    pub view: Option<String>,
}

/// A file's header, as shutter sees it.
#[derive(Clone, Debug, PartialEq)]
pub struct FileInfo {
    pub path: PathBuf,
    pub kind: FileKind,
    pub width: usize,
    pub height: usize,
    pub windows: Windows,
    pub channels: Vec<ChannelInfo>,
    /// The views of a multi-view EXR (`io::view`); `None` for a file of no views.
    pub views: Option<Views>,
    /// The view `channels` were narrowed to by [`FileInfo::in_view`], if any.
    pub view: Option<String>,
}

impl FileInfo {
    /// [`FileInfo::probe_within`] the default limit, [`DEFAULT_MAX_PIXELS`].
    pub fn probe(path: &Path) -> Result<FileInfo, Problem> {
        Self::probe_within(path, DEFAULT_MAX_PIXELS)
    }

    /// Reads the header of an EXR, PNG, JPEG or TIFF file, and checks (without decoding
    /// pixels) that the file can be read: a declared size within `max_pixels`, supported
    /// features, a chunk table that covers the image once and lies inside the file (EXR),
    /// a complete stream (JPEG).
    pub fn probe_within(path: &Path, max_pixels: usize) -> Result<FileInfo, Problem> {
        let mut magic = [0u8; 4];
        let opened = crate::io::input::open_input(path).and_then(|mut f| f.read_exact(&mut magic));
        if let Err(e) = opened {
            let (kind, detail) = match e.kind() {
                std::io::ErrorKind::NotFound => (ProblemKind::MissingFile, "no such file".into()),
                std::io::ErrorKind::InvalidInput => (ProblemKind::Unsupported, e.to_string()),
                std::io::ErrorKind::UnexpectedEof => (
                    ProblemKind::Corrupt,
                    "the file is too short to be an image".into(),
                ),
                _ => (ProblemKind::MissingFile, e.to_string()),
            };
            return Err(Problem::new(kind, path, detail));
        }
        let is_exr_name = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        if magic == EXR_MAGIC {
            probe_exr(path, max_pixels)
        } else if is_exr_name {
            Err(Problem::new(
                ProblemKind::Corrupt,
                path,
                "not an OpenEXR file (bad magic number)",
            ))
        } else {
            probe_image(path, max_pixels)
        }
    }

    /// The parts whose names mark the main layer of a multi-part file: OpenEXR's and Nuke's
    /// `rgba`, and `beauty`.
    pub const MAIN_PARTS: [&str; 2] = ["rgba", "beauty"];

    /// Makes the channels `found` for `names` (by [`FileInfo::find`]) come from one part that
    /// can be told: where a name found by itself (not as `part.name`) is in several parts of
    /// a multi-part file (`rgba` and `diffuse` both holding R, G, B), the part named `rgba`
    /// or `beauty` ([`FileInfo::MAIN_PARTS`]) when exactly one of them holds it (in a file
    /// seen as one view, the view's own part), else an error naming the parts and how to
    /// choose, rather than the first part, silently.
    pub fn one_part(&self, names: &[String], found: &mut [Option<usize>]) -> Result<(), String> {
        let FileKind::Exr { headers, .. } = &self.kind else {
            return Ok(());
        };
        let part_name = |part: usize| {
            headers
                .get(part)
                .and_then(|h| h.own_attributes.layer_name.as_ref())
                .map_or(format!("part {part}"), name_of)
        };
        for (name, index) in names.iter().zip(found.iter_mut()) {
            let Some(at) = *index else { continue };
            if self.channels[at].name != *name {
                continue;
            }
            let mut parts: Vec<usize> = self
                .channels
                .iter()
                .filter(|c| c.name == *name && self.unreadable(c).is_none())
                .map(|c| c.part)
                .collect();
            parts.sort_unstable();
            parts.dedup();
            if parts.len() < 2 {
                continue;
            }
            // Seen as one view, the view's own part is the main one (a part of no view holds
            // channels of its own: a multi-view file's `R` is the view's).
            let of_view: Vec<usize> = parts
                .iter()
                .copied()
                .filter(|&p| {
                    self.channels
                        .iter()
                        .any(|c| c.part == p && c.view.is_some())
                })
                .collect();
            if let (Some(_), [part]) = (&self.view, &of_view[..]) {
                let part = *part;
                *index = self
                    .channels
                    .iter()
                    .position(|c| c.part == part && c.name == *name);
                continue;
            }
            let main: Vec<usize> = parts
                .iter()
                .copied()
                .filter(|&p| {
                    let n = part_name(p).to_ascii_lowercase();
                    Self::MAIN_PARTS.contains(&n.as_str())
                })
                .collect();
            if let [part] = main[..] {
                *index = self
                    .channels
                    .iter()
                    .position(|c| c.part == part && c.name == *name);
                continue;
            }
            let listed: Vec<String> = parts.iter().map(|&p| part_name(p)).collect();
            return Err(format!(
                "channel {name} is in more than one part ({}) and none is the main one (rgba \
                 or beauty); say which with a preset that names it as PART.{name} (for \
                 example {}.{name})",
                listed.join(", "),
                listed[0]
            ));
        }
        Ok(())
    }

    /// Index of the channel with this name (stored name first, then part-qualified alias),
    /// of the parts shutter can read: a deep part's `A` is not the beauty's alpha.
    pub fn find(&self, name: &str) -> Option<usize> {
        let readable = |c: &ChannelInfo| self.unreadable(c).is_none();
        self.channels
            .iter()
            .position(|c| c.name == name && readable(c))
            .or_else(|| {
                self.channels
                    .iter()
                    .position(|c| c.alias.as_deref() == Some(name) && readable(c))
            })
    }

    /// A pass's `alternatives` (each a list of names, its first `required` the ones it needs)
    /// but those that need one of the channels `taken` (the colour's: `R,G` are no vectors
    /// to offer where R and G are the beauty); all of them where that leaves none.
    pub fn not_taken(
        &self,
        alternatives: &[Vec<String>],
        required: usize,
        taken: &[usize],
    ) -> Vec<Vec<String>> {
        let needs_taken = |names: &Vec<String>| {
            (names.iter().take(required)).any(|n| self.find(n).is_some_and(|c| taken.contains(&c)))
        };
        let free: Vec<Vec<String>> = (alternatives.iter())
            .filter(|names| !needs_taken(names))
            .cloned()
            .collect();
        if free.is_empty() {
            alternatives.to_vec()
        } else {
            free
        }
    }

    /// Why the part holding `channel` cannot be read (deep data, HTJ2K, subsampled
    /// channels), where it cannot: its channels are left out.
    pub fn unreadable(&self, channel: &ChannelInfo) -> Option<String> {
        let FileKind::Exr { headers, .. } = &self.kind else {
            return None;
        };
        exr_io::unsupported_reason(headers.get(channel.part)?)
    }

    /// Where one of `names` (as stored, or part-qualified) is a channel of a part shutter
    /// cannot read: which, in which part, and why ([`FileInfo::unreadable`]), for an error
    /// that says what to do rather than that the channel is missing.
    pub fn unread_among(&self, names: &[&str]) -> Option<String> {
        let FileKind::Exr { headers, .. } = &self.kind else {
            return None;
        };
        let named = |n: &str, c: &ChannelInfo| c.name == n || c.alias.as_deref() == Some(n);
        let (channel, why) = names.iter().find_map(|&n| {
            let c = self.channels.iter().find(|c| named(n, c))?;
            Some((c, self.unreadable(c)?))
        })?;
        let part = (headers.get(channel.part))
            .and_then(|h| h.own_attributes.layer_name.as_ref())
            .map_or(format!("part {}", channel.part), |n| {
                format!("part {}", name_of(n))
            });
        Some(format!(
            "channel {} is in {part}, which shutter does not read: {why}",
            channel.alias.as_ref().unwrap_or(&channel.name)
        ))
    }

    /// The file as one view reads it (`io::view`): `view`, or the file's default view when
    /// `None`; the channels of that view named without it, and those of no view. A file of
    /// no views is returned as it is, whatever `view` says. Fails, with a message listing
    /// the views, for a view the file does not hold, or with no `view` when the file names no
    /// default.
    pub fn in_view(&self, view: Option<&str>) -> Result<FileInfo, String> {
        let Some(views) = &self.views else {
            return Ok(self.clone());
        };
        let chosen = views.choose(view)?;
        let mut channels: Vec<ChannelInfo> = self
            .channels
            .iter()
            .filter(|c| c.view.as_deref() == Some(chosen.as_str()))
            .map(|c| ChannelInfo {
                name: views.strip(&c.name, &chosen),
                alias: c.alias.as_ref().map(|a| views.strip(a, &chosen)),
                ..c.clone()
            })
            .collect();
        let names = views.scheme == crate::io::view::Scheme::Names;
        let taken = |name: &str, channels: &[ChannelInfo]| {
            channels
                .iter()
                .any(|c| c.name == name || c.alias.as_deref() == Some(name))
        };
        // In the one-part scheme, a layer another view writes as its own (`diffuse.right.R`)
        // is a layer of each view: its plain channels (`diffuse.R`, `diffuse.A`) are the
        // default view's, even where the other view lacks one of them (OpenEXR writes the
        // default view's channels without its name; `view::layer_of`).
        let layer = |name: &str| crate::io::view::layer_of(name).map(str::to_string);
        let per_view: std::collections::BTreeSet<String> = self
            .channels
            .iter()
            .filter(|c| {
                names
                    && c.view
                        .as_ref()
                        .is_some_and(|v| Some(v) != views.default.as_ref())
            })
            .filter_map(|c| layer(&views.strip(&c.name, c.view.as_deref().unwrap_or(""))))
            .collect();
        let default = views.default.as_deref() == Some(chosen.as_str());
        let shared: Vec<ChannelInfo> = self
            .channels
            .iter()
            .filter(|c| c.view.is_none())
            // Parts of no view hold channels of their own, whatever their names: only the
            // one-part scheme's names can stand for a channel of the view.
            .filter(|c| !names || !taken(&c.name, &channels))
            .filter(|c| default || !layer(&c.name).is_some_and(|l| per_view.contains(&l)))
            .cloned()
            .collect();
        channels.extend(shared);
        // In the file's order, as the channels of a file of one view are (a name in the
        // view's part and a part of no view is settled by `one_part`).
        channels.sort_by_key(|c| (c.part, c.index));
        // The view's size and windows are its first part's (the file's are its first
        // part's, which may be another view's, or a part of no view of another window).
        let first = (channels.iter())
            .find(|c| c.view.as_deref() == Some(chosen.as_str()))
            .map(|c| c.part);
        let (mut width, mut height, mut windows) = (self.width, self.height, self.windows);
        if let (Some(part), FileKind::Exr { headers, .. }) = (first, &self.kind) {
            if let Some(header) = headers.get(part) {
                (width, height) = (header.layer_size.0, header.layer_size.1);
                windows = exr_io::windows_of(header);
            }
        }
        Ok(FileInfo {
            channels,
            width,
            height,
            windows,
            view: Some(chosen),
            ..self.clone()
        })
    }

    /// Whether the file stores one channel: a one-channel EXR, or a grey image (whose `Y`,
    /// and the `R`, `G`, `B` that read it too, are one stored plane).
    pub fn has_one_channel(&self) -> bool {
        let stored = |c: &ChannelInfo| (c.part, c.index);
        self.channels
            .first()
            .is_some_and(|first| self.channels.iter().all(|c| stored(c) == stored(first)))
    }

    /// All channel names, for messages.
    pub fn channel_list(&self) -> String {
        if self.channels.is_empty() {
            return "(none)".into();
        }
        self.channels
            .iter()
            .map(|c| {
                // Escaped: a name is a file's, and this list goes into messages.
                let name = crate::error::printable(c.alias.as_ref().unwrap_or(&c.name));
                match self.unreadable(c) {
                    Some(_) => format!("{name} (in a part not read)"),
                    None => name,
                }
            })
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// True for 8/16-bit integer images, where colour carries a transfer function.
    pub fn is_integer_image(&self) -> bool {
        matches!(self.kind, FileKind::Image { float: false, .. })
    }

    /// A PNG, JPEG or TIFF, integer or float (not an EXR).
    pub fn is_image(&self) -> bool {
        matches!(self.kind, FileKind::Image { .. })
    }

    /// A picture turned upright by its orientation to another shape (see [`FileKind::Image`]).
    pub fn is_turned(&self) -> bool {
        matches!(self.kind, FileKind::Image { turned: true, .. })
    }

    /// The problem of a file that is no longer what the preflight checked: `what` changed.
    /// An EXR's `channels` (indices into `channels`, all in parts of one data window),
    /// `bits` as in [`FileInfo::read_bits`], at their parts' window: the colour's, or that of
    /// a part read apart (a part whose data window is not the beauty's, carried to the
    /// output).
    pub fn read_exr(
        &self,
        channels: &[usize],
        bits: &[usize],
    ) -> Result<exr_io::ReadChannels, Problem> {
        let corrupt = |detail: String| Problem::new(ProblemKind::Corrupt, &self.path, detail);
        let refs: Vec<exr_io::ChannelRef> = channels
            .iter()
            .map(|&i| exr_io::ChannelRef {
                part: self.channels[i].part,
                index: self.channels[i].index,
                bits: bits.contains(&i),
            })
            .collect();
        exr_io::read_channels_checked(&self.path, &refs, |meta| self.same_headers(meta, channels))
            .map_err(|e| match e {
                exr::error::Error::Invalid(what) if what.starts_with(exr_io::CHANGED) => {
                    self.changed(&what[exr_io::CHANGED.len()..])
                }
                exr::error::Error::NotSupported(what) => {
                    Problem::new(ProblemKind::Unsupported, &self.path, what.to_string())
                }
                exr::error::Error::Io(io) if io.kind() == std::io::ErrorKind::NotFound => {
                    Problem::new(ProblemKind::MissingFile, &self.path, io.to_string())
                }
                // Memory the system refused for the planes (`frame::try_plane`): the file is
                // fine, the frame too large for the memory this run has.
                exr::error::Error::Io(io) if io.kind() == std::io::ErrorKind::OutOfMemory => {
                    Problem::new(
                        ProblemKind::TooLarge,
                        &self.path,
                        format!("{io}; give the run more memory, or read smaller frames"),
                    )
                }
                other => corrupt(other.to_string()),
            })
    }

    fn changed(&self, what: &str) -> Problem {
        Problem::new(
            ProblemKind::Changed,
            &self.path,
            format!(
                "the file changed after the preflight checked it: {what}; nothing was read \
                 from it (check it again with shutter info, then rerun with --skip-existing)"
            ),
        )
    }

    /// Whether the headers `meta` (read again when the frame is decoded) still hold what the
    /// preflight saw: the same parts, and for each of `channels` (indices into
    /// [`FileInfo::channels`]) the same name and sample type at the same place, in a part of
    /// the same windows. Else what changed, naming the channel.
    fn same_headers(&self, meta: &exr::meta::MetaData, channels: &[usize]) -> Result<(), String> {
        let FileKind::Exr { headers, .. } = &self.kind else {
            return Ok(());
        };
        if meta.headers.len() != headers.len() {
            return Err(format!(
                "it has {} part{}, it had {}",
                meta.headers.len(),
                if meta.headers.len() == 1 { "" } else { "s" },
                headers.len()
            ));
        }
        for &i in channels {
            let info = &self.channels[i];
            let (was, now) = (&headers[info.part], &meta.headers[info.part]);
            // As stored (a view's channel is known by its name without the view).
            let Some(stored) = was.channels.list.get(info.index) else {
                continue;
            };
            let name = name_of(&stored.name);
            let found = now.channels.list.get(info.index);
            if found.is_none_or(|c| c.name != stored.name) {
                let moved = now.channels.list.iter().any(|c| c.name == stored.name);
                return Err(if moved {
                    format!("channel {name} moved")
                } else {
                    format!("channel {name} is no longer in it")
                });
            }
            let sample = sample_type_name(found.expect("found").sample_type);
            if sample != info.sample_type {
                return Err(format!(
                    "channel {name} is {sample}, it was {}",
                    info.sample_type
                ));
            }
            if exr_io::windows_of(now) != exr_io::windows_of(was)
                || now.layer_size != was.layer_size
            {
                return Err(format!(
                    "the data or display window of channel {name}'s part changed"
                ));
            }
        }
        Ok(())
    }

    /// Decodes the given channels (indices into `channels`, distinct) into planes.
    pub fn read(&self, channels: &[usize]) -> Result<Vec<Plane>, Problem> {
        self.read_bits(channels, &[])
    }

    /// [`FileInfo::read`], the channels `bits` lists (indices into `channels`) that are
    /// u32 read as their bit patterns (`f32::from_bits`): exact, for channels written back
    /// as they came (IDs over 2²⁴).
    pub fn read_bits(&self, channels: &[usize], bits: &[usize]) -> Result<Vec<Plane>, Problem> {
        let corrupt = |detail: String| Problem::new(ProblemKind::Corrupt, &self.path, detail);
        match self.kind {
            FileKind::Exr { .. } => {
                let read = self.read_exr(channels, bits)?;
                if (read.width, read.height) != (self.width, self.height) {
                    return Err(self.changed(&format!(
                        "it is {}x{}, it was {}x{}",
                        read.width, read.height, self.width, self.height
                    )));
                }
                Ok(read.planes)
            }
            FileKind::Image { .. } => {
                let (width, height, mut planes) =
                    image_io::read_planes(&self.path, (self.width, self.height)).map_err(
                        |detail| match detail.strip_prefix(image_io::NOT_SUPPORTED) {
                            Some(what) => Problem::new(ProblemKind::Unsupported, &self.path, what),
                            None => corrupt(detail),
                        },
                    )?;
                if (width, height) != (self.width, self.height) {
                    return Err(self.changed(&format!(
                        "it is {width}x{height}, it was {}x{}",
                        self.width, self.height
                    )));
                }
                let stored = self.channels.iter().map(|c| c.index + 1).max().unwrap_or(0);
                if planes.len() != stored {
                    return Err(self.changed(&format!(
                        "it holds {} channel{}, it held {stored}",
                        planes.len(),
                        if planes.len() == 1 { "" } else { "s" }
                    )));
                }
                // A grey image's R, G and B share one plane: take it on its last use.
                let mut result = Vec::with_capacity(channels.len());
                for (k, &i) in channels.iter().enumerate() {
                    let plane = self.channels[i].index;
                    let used_later = channels[k + 1..]
                        .iter()
                        .any(|&j| self.channels[j].index == plane);
                    let plane = planes
                        .get_mut(plane)
                        .ok_or_else(|| corrupt("fewer channels than the header said".into()))?;
                    result.push(if used_later {
                        plane.clone()
                    } else {
                        std::mem::take(plane)
                    });
                }
                Ok(result)
            }
        }
    }
}

fn probe_exr(path: &Path, max_pixels: usize) -> Result<FileInfo, Problem> {
    let meta = exr_io::read_meta(path).map_err(|e| match e {
        exr::error::Error::NotSupported(what) => {
            Problem::new(ProblemKind::Unsupported, path, what.to_string())
        }
        other => Problem::new(
            ProblemKind::Corrupt,
            path,
            format!("cannot read the EXR header: {other}"),
        ),
    })?;
    if meta.headers.is_empty() {
        return Err(Problem::new(ProblemKind::Corrupt, path, "no parts"));
    }
    for header in &meta.headers {
        check_size(path, header.layer_size.0, header.layer_size.1, max_pixels)?;
    }
    // A part shutter cannot read (deep data, HTJ2K, subsampled channels) beside parts it can
    // is left out of what is read, with a warning (`passes::parts`), and refused only where a
    // pass's channel lies in it (`plan`): a file of no other part is refused whole. (Before,
    // a render's deep part refused the whole file.)
    let Some(first) = (meta.headers.iter()).find(|h| exr_io::unsupported_reason(h).is_none())
    else {
        let reason = exr_io::unsupported_reason(&meta.headers[0]).unwrap_or_default();
        return Err(Problem::new(ProblemKind::Unsupported, path, reason));
    };
    exr_io::validate(&meta).map_err(|e| {
        Problem::new(
            ProblemKind::Corrupt,
            path,
            format!("the EXR header is invalid: {e}"),
        )
    })?;
    exr_io::check_chunk_table(path, &meta)
        .map_err(|detail| Problem::new(ProblemKind::Corrupt, path, detail))?;
    let multipart = meta.headers.len() > 1;
    let views = Views::of(&meta.headers);
    let mut channels = Vec::new();
    for (part, header) in meta.headers.iter().enumerate() {
        // A multi-view part's name without its view (Blender's `ViewLayer.Combined-left`).
        let view = header.own_attributes.view_name.as_ref().map(name_of);
        let part_name = (header.own_attributes.layer_name.as_ref())
            .map(|n| crate::io::view::part_name_without_view(&name_of(n), view.as_deref()));
        for (index, channel) in header.channels.list.iter().enumerate() {
            let name = name_of(&channel.name);
            let alias = match &part_name {
                Some(part_name) if multipart && !name.starts_with(&format!("{part_name}.")) => {
                    Some(format!("{part_name}.{name}"))
                }
                _ => None,
            };
            let view = views.as_ref().and_then(|v| v.view_of(part, &name));
            channels.push(ChannelInfo {
                name,
                alias,
                part,
                index,
                sample_type: sample_type_name(channel.sample_type),
                view,
            });
        }
    }
    Ok(FileInfo {
        path: path.to_path_buf(),
        kind: FileKind::Exr {
            compression: meta
                .headers
                .iter()
                .map(exr_io::part_compression_name)
                .collect(),
            tiled: meta
                .headers
                .iter()
                .any(|h| matches!(h.blocks, exr::meta::BlockDescription::Tiles(_))),
            multipart,
            headers: meta.headers.to_vec(),
        },
        width: first.layer_size.0,
        height: first.layer_size.1,
        windows: exr_io::windows_of(first),
        channels,
        views,
        view: None,
    })
}

fn probe_image(path: &Path, max_pixels: usize) -> Result<FileInfo, Problem> {
    let header = image_io::probe(path, max_pixels).map_err(|detail| {
        match detail.strip_prefix(image_io::NOT_SUPPORTED) {
            Some(what) => Problem::new(ProblemKind::Unsupported, path, what),
            None if detail.starts_with("not a ") => {
                Problem::new(ProblemKind::Unsupported, path, detail)
            }
            None => Problem::new(ProblemKind::Corrupt, path, detail),
        }
    })?;
    // (A JPEG's stream was checked by the probe: cut short is corrupt.)
    check_size(path, header.width, header.height, max_pixels)?;
    let sample_type = match (header.float, header.bits) {
        (true, _) => "f32",
        (false, 16) => "u16",
        _ => "u8",
    };
    Ok(FileInfo {
        path: path.to_path_buf(),
        kind: FileKind::Image {
            format: header.format,
            bits: header.bits,
            float: header.float,
            turned: header.turned,
        },
        width: header.width,
        height: header.height,
        windows: Windows::full(header.width, header.height),
        channels: header
            .channels
            .iter()
            .map(|&(name, index)| ChannelInfo {
                name: name.to_string(),
                alias: None,
                part: 0,
                index,
                sample_type,
                view: None,
            })
            .collect(),
        views: None,
        view: None,
    })
}

/// The name [`ChannelInfo::sample_type`] gives an EXR sample type.
fn sample_type_name(kind: exr::meta::attribute::SampleType) -> &'static str {
    match kind {
        exr::meta::attribute::SampleType::F16 => "f16",
        exr::meta::attribute::SampleType::F32 => "f32",
        exr::meta::attribute::SampleType::U32 => "u32",
    }
}
