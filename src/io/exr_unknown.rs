//! Parts in a compression the exr crate does not know (an outside tester's F13): OpenEXR
//! 3.5's ZSTD and LJ2K, and whatever id a later OpenEXR adds.
//!
//! The exr crate's header parser fails on a compression id it does not know ("unknown
//! compression method"), so a file with one such part was refused whole, before any part was
//! looked at, where an HTJ2K part (which the crate parses but does not decode) is left out
//! with a warning. Here the headers are first read raw ([`View::open`]: the magic number, the
//! version, then each part's attributes: name, type, size, value; a part ends with an empty
//! name, and a multi-part file's list of parts with one more): where a part's `compression`
//! holds an id the crate does not know, the crate is handed a [`View`] of the file in which
//! that byte reads as [`STAND_IN`] (a compression the crate parses and shutter leaves out
//! too) and the part's `chunkCount` as the count the crate computes for a part of that
//! compression. Every other byte reads as stored, and a file with no such part reads
//! unchanged. After the crate's parse, [`View::mark`] gives the part's header back the chunk
//! count the file stores (so the offset tables are read as they are) and records the id as
//! the file stores it, as a custom attribute `compression` ([`stored_compression`]), which
//! `exr::unsupported_reason` names and an output never carries (`exr_like`'s layout names).
//! The part's chunks are never decoded. How many lines each holds is the compression's
//! (OpenEXR 3.5 writes ZSTD a line a chunk, LJ2K a whole small image in one), so the
//! chunk-table check only checks that they lie in the file, apart.
//!
//! A part of unknown compression without `chunkCount` (OpenEXR writes one in every part of a
//! multi-part file, not in a single-part file) leaves the length of its offset table unknown:
//! the file is refused, naming the compression (a single-part file has no other part to
//! read anyway).

use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};

use exr::compression::Compression;
use exr::meta::attribute::{AttributeValue, Text};
use exr::meta::header::Header;
use exr::meta::MetaData;

/// What the exr crate is shown in place of a compression it does not know: HTJ2K over 256
/// lines, which it parses and shutter does not decode either (`exr::unsupported_reason`),
/// so a part whose mark were lost would still be left out, never decoded as something else.
pub const STAND_IN: Compression = Compression::HTJ2K256;

/// The name of the custom attribute [`View::mark`] records a part's stored compression id
/// in: the standard attribute's own name, which the crate never puts among the custom ones
/// with the type `compression` (it parses those, or fails).
const STORED: &str = "compression";

/// The names OpenEXR gives the compression ids the exr crate does not know, as OpenEXR 3.5
/// numbers them (`ImfCompression.h`: `LJ2K_COMPRESSION = 12`, `ZSTD_COMPRESSION = 13`; its
/// Python module 3.5.3 writes ZSTD as 13). A branch of OpenEXR's before LJ2K (`zstd-beta`)
/// numbered ZSTD 12: a file from a build of it reads as LJ2K here, left out the same way.
pub fn name_of_id(id: u8) -> Option<&'static str> {
    match id {
        12 => Some("lj2k"),
        13 => Some("zstd"),
        _ => None,
    }
}

/// Why a part in compression `id` (one the exr crate does not know) is not read, and what to
/// do: as `exr::unsupported_reason` says it of HTJ2K.
pub fn reason(id: u8) -> String {
    let what = match name_of_id(id) {
        Some(name) => format!("{name} compression"),
        None => format!("compression method {id} (not one OpenEXR 3.5 names either)"),
    };
    format!("{what} cannot be decoded by the exr crate; re-save with ZIP, PIZ or DWA")
}

/// The compression id `header`'s part stores where the exr crate does not know it (the mark
/// [`View::mark`] leaves); `None` for every other part.
pub fn stored_compression(header: &Header) -> Option<u8> {
    match header.own_attributes.other.get(&Text::from(STORED))? {
        AttributeValue::Custom { kind, bytes } if kind.eq(STORED) && bytes.len() == 1 => {
            Some(bytes[0])
        }
        _ => None,
    }
}

/// `header` as the exr crate parsed it through a [`View`]: unmarked, with the chunk count it
/// computes for the stand-in (which its checks hold the header to).
pub fn as_parsed(header: &Header) -> Header {
    let mut parsed = header.clone();
    if parsed
        .own_attributes
        .other
        .remove(&Text::from(STORED))
        .is_some()
    {
        parsed.chunk_count =
            exr::meta::compute_chunk_count(parsed.compression, parsed.layer_size, parsed.blocks);
    }
    parsed
}

/// A part whose compression the exr crate does not know, as [`View::open`] found it.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Unknown {
    part: usize,
    /// The compression id stored.
    id: u8,
    /// The part's chunk count as stored (`chunkCount`).
    chunks: usize,
}

/// A file as the exr crate is shown it: every byte as stored, but those of [`Unknown`]
/// parts' `compression` and `chunkCount` (see the module doc). Reads and seeks as the file
/// does. A clone shares the file's position, as `File::try_clone` does, but counts it on its
/// own: seek a view before reading it after another has moved the file.
pub struct View<R> {
    inner: R,
    /// The position in the file (the next byte read).
    at: u64,
    /// The bytes shown otherwise: (position, byte), in increasing position.
    patches: Vec<(u64, u8)>,
    unknown: Vec<Unknown>,
}

impl<R: Read + Seek> View<R> {
    /// `file` (at its start) as the exr crate is to read it, its headers read raw first. A
    /// header the raw read cannot follow is left to the crate to refuse (nothing is changed
    /// in it). Fails, not supported, where a part of unknown compression says no chunk count.
    pub fn open(mut file: R) -> exr::error::Result<Self> {
        let (multipart, parts) = scan(BufReader::new(&mut file)).unwrap_or_default();
        file.seek(SeekFrom::Start(0))?;
        let mut view = View {
            inner: file,
            at: 0,
            patches: Vec::new(),
            unknown: Vec::new(),
        };
        for (part, scanned) in parts.iter().enumerate() {
            let Some((at, id)) = scanned.compression else {
                continue;
            };
            if Compression::read(&mut &[id][..]).is_ok() {
                continue;
            }
            let Some((count_at, chunks)) = scanned.chunk_count else {
                let which = match (&scanned.name, multipart) {
                    (Some(name), true) => format!("part {name}: "),
                    (None, true) => format!("part {part}: "),
                    _ => String::new(),
                };
                return Err(exr::error::Error::NotSupported(
                    format!("{which}{}", reason(id)).into(),
                ));
            };
            // The count read as stored must be one a part of its lines can have (each chunk a
            // line or more): the crate checks the stand-in's, never this one, and the tables
            // of every later part are found by it.
            if let (false, Some(height)) = (scanned.tiled, scanned.height) {
                if chunks < 1 || i64::from(chunks) > height {
                    return Err(exr::error::Error::Invalid(
                        format!("chunkCount {chunks} of a part of {height} lines").into(),
                    ));
                }
            }
            let mut stand_in = Vec::new();
            STAND_IN.write(&mut stand_in)?;
            view.patches.push((at, stand_in[0]));
            // A part of tiles has as many chunks in any compression; scan lines, as many
            // blocks of the stand-in's lines as its data window holds.
            if let (false, Some(height)) = (scanned.tiled, scanned.height) {
                let lines = STAND_IN.scan_lines_per_block() as i64;
                let count = i32::try_from((height + lines - 1) / lines).unwrap_or(i32::MAX);
                let bytes = count.to_le_bytes();
                view.patches
                    .extend((0..4).map(|k| (count_at + k as u64, bytes[k])));
            }
            view.unknown.push(Unknown {
                part,
                id,
                chunks: usize::try_from(chunks).unwrap_or(0),
            });
        }
        view.patches.sort_unstable();
        Ok(view)
    }
}

impl View<std::fs::File> {
    /// Another view of the same open file, sharing its position.
    pub fn try_clone(&self) -> std::io::Result<Self> {
        Ok(View {
            inner: self.inner.try_clone()?,
            at: self.at,
            patches: self.patches.clone(),
            unknown: self.unknown.clone(),
        })
    }
}

impl<R> View<R> {
    /// Whether a part's compression is one the exr crate does not know.
    pub fn has_unknown(&self) -> bool {
        !self.unknown.is_empty()
    }

    /// The headers the crate read through this view as the file stores them: each part of
    /// unknown compression given back its chunk count, and marked with its compression id
    /// ([`stored_compression`]).
    pub fn mark(&self, meta: &mut MetaData) {
        for unknown in &self.unknown {
            let Some(header) = meta.headers.get_mut(unknown.part) else {
                continue;
            };
            header.chunk_count = unknown.chunks;
            header.own_attributes.other.insert(
                Text::from(STORED),
                AttributeValue::Custom {
                    kind: Text::from(STORED),
                    bytes: vec![unknown.id].into(),
                },
            );
        }
    }
}

impl<R: Read> Read for View<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        let end = self.at + n as u64;
        let from = self.patches.partition_point(|&(at, _)| at < self.at);
        for &(at, byte) in self.patches[from..].iter().take_while(|(at, _)| *at < end) {
            buf[(at - self.at) as usize] = byte;
        }
        self.at = end;
        Ok(n)
    }
}

impl<R: Seek> Seek for View<R> {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        self.at = self.inner.seek(to)?;
        Ok(self.at)
    }
}

/// What the raw read found of one part's header: where its compression id and chunk count
/// are stored, and what they are; its data window's height, whether it is tiled, its name.
#[derive(Debug, Default)]
struct Scanned {
    compression: Option<(u64, u8)>,
    chunk_count: Option<(u64, i32)>,
    height: Option<i64>,
    tiled: bool,
    name: Option<String>,
}

/// Each part's header read raw, as far as [`Scanned`] needs, and whether the file is
/// multi-part; `None` where the bytes are not an EXR's headers (the crate then says what is
/// wrong).
fn scan(read: impl BufRead) -> Option<(bool, Vec<Scanned>)> {
    let mut raw = Raw { read, at: 0 };
    if raw.bytes(4)? != [0x76, 0x2f, 0x31, 0x01] {
        return None;
    }
    let flags = u32::from_le_bytes(raw.bytes(4)?.try_into().ok()?);
    let multipart = flags & 0x1000 != 0;
    // A single-part file says it is tiled in the version's flags.
    let tiled = !multipart && flags & 0x200 != 0;
    let mut parts = Vec::new();
    let mut part = Scanned {
        tiled,
        ..Scanned::default()
    };
    let mut attributes = 0;
    loop {
        let name = raw.text()?;
        if name.is_empty() {
            // The end of a part, or (where no attribute came) of the list of parts.
            if attributes == 0 {
                break;
            }
            parts.push(std::mem::take(&mut part));
            attributes = 0;
            if !multipart {
                break;
            }
            continue;
        }
        attributes += 1;
        let kind = raw.text()?;
        let size = i32::from_le_bytes(raw.bytes(4)?.try_into().ok()?);
        let size = usize::try_from(size).ok()?;
        let value_at = raw.at;
        let wanted = matches!(
            (&name[..], &kind[..], size),
            (b"compression", b"compression", 1)
                | (b"chunkCount", b"int", 4)
                | (b"dataWindow", b"box2i", 16)
                | (b"type" | b"name", b"string", 0..=255)
        );
        if !wanted {
            raw.skip(size)?;
            continue;
        }
        let value = raw.bytes(size)?;
        let int =
            |k: usize| i32::from_le_bytes([value[k], value[k + 1], value[k + 2], value[k + 3]]);
        match &name[..] {
            b"compression" => part.compression = Some((value_at, value[0])),
            b"chunkCount" => part.chunk_count = Some((value_at, int(0))),
            b"dataWindow" => {
                part.height = Some(int(12) as i64 - int(4) as i64 + 1).filter(|&h| h > 0);
            }
            b"type" => part.tiled = value.starts_with(b"tiled") || value == b"deeptile",
            _ => part.name = Some(String::from_utf8_lossy(&value).into_owned()),
        }
    }
    Some((multipart, parts))
}

/// A reader of raw header bytes that counts its position.
struct Raw<R> {
    read: R,
    at: u64,
}

impl<R: BufRead> Raw<R> {
    /// The next `n` bytes.
    fn bytes(&mut self, n: usize) -> Option<Vec<u8>> {
        let mut bytes = vec![0; n];
        self.read.read_exact(&mut bytes).ok()?;
        self.at += n as u64;
        Some(bytes)
    }

    /// Passes `n` bytes (a value the raw read does not need) without holding them.
    fn skip(&mut self, n: usize) -> Option<()> {
        let skipped = std::io::copy(&mut (&mut self.read).take(n as u64), &mut std::io::sink());
        (skipped.ok()? == n as u64).then_some(())?;
        self.at += n as u64;
        Some(())
    }

    /// A null-terminated attribute name or type name, of at most 255 bytes (OpenEXR's long
    /// names).
    fn text(&mut self) -> Option<Vec<u8>> {
        let mut text = Vec::new();
        loop {
            let byte = self.bytes(1)?[0];
            if byte == 0 {
                return Some(text);
            }
            if text.len() == 255 {
                return None;
            }
            text.push(byte);
        }
    }
}

#[cfg(test)]
mod tests {
    use std::io::{BufReader, Cursor, Read, Seek, SeekFrom};

    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::meta::attribute::{IntegerBounds, Text};
    use exr::meta::header::{ImageAttributes, LayerAttributes};
    use exr::meta::MetaData;
    use exr::prelude::{Blocks, LineOrder, WritableImage};

    use super::*;

    const HEIGHT: usize = 40;

    /// A scan-line EXR of 4 × [`HEIGHT`] with one part per name (several: multi-part), each
    /// holding a channel R, RLE: a line a chunk, as OpenEXR 3.5 writes ZSTD.
    fn exr_of(parts: &[&str]) -> Vec<u8> {
        let layers: Vec<_> = (parts.iter())
            .map(|&name| {
                let attributes = LayerAttributes {
                    layer_name: (parts.len() > 1).then(|| Text::from(name)),
                    ..LayerAttributes::default()
                };
                let samples = FlatSamples::F32((0..4 * HEIGHT).map(|i| i as f32).collect());
                let encoding = Encoding {
                    compression: Compression::RLE,
                    blocks: Blocks::ScanLines,
                    line_order: LineOrder::Increasing,
                };
                let channels = AnyChannels::sort(vec![AnyChannel::new("R", samples)].into());
                Layer::new((4, HEIGHT), attributes, encoding, channels)
            })
            .collect();
        let attributes = ImageAttributes::new(IntegerBounds::new((0, 0), (4, HEIGHT)));
        let mut bytes = Cursor::new(Vec::new());
        Image::from_layers(attributes, layers)
            .write()
            .to_buffered(&mut bytes)
            .unwrap();
        bytes.into_inner()
    }

    /// Where the `k`th value of attribute `name` of type `kind` lies in `bytes`.
    fn value_at(bytes: &[u8], name: &str, kind: &str, k: usize) -> usize {
        let key = [name.as_bytes(), b"\0", kind.as_bytes(), b"\0"].concat();
        let at = (0..bytes.len() - key.len())
            .filter(|&p| bytes[p..].starts_with(&key))
            .nth(k)
            .unwrap();
        at + key.len() + 4
    }

    /// Every byte read through `view` in pieces of `piece` bytes, from its start.
    fn read_all(view: &mut View<Cursor<Vec<u8>>>, piece: usize) -> Vec<u8> {
        view.seek(SeekFrom::Start(0)).unwrap();
        let (mut out, mut buf) = (Vec::new(), vec![0; piece]);
        loop {
            let n = view.read(&mut buf).unwrap();
            if n == 0 {
                return out;
            }
            out.extend(&buf[..n]);
        }
    }

    #[test]
    fn a_file_of_known_compressions_reads_as_stored() {
        let bytes = exr_of(&["rgba", "spec"]);
        let mut view = View::open(Cursor::new(bytes.clone())).unwrap();
        assert!(!view.has_unknown());
        assert_eq!(read_all(&mut view, 7), bytes);
    }

    #[test]
    fn a_zstd_part_reads_as_the_stand_in_then_is_marked_with_its_id_and_chunk_count() {
        let mut bytes = exr_of(&["rgba", "spec", "depth"]);
        let at = value_at(&bytes, "compression", "compression", 1);
        bytes[at] = 13;
        let mut view = View::open(Cursor::new(bytes.clone())).unwrap();
        assert!(view.has_unknown());
        // The crate fails on the file as stored, and parses the view.
        assert!(MetaData::read_from_buffered(&bytes[..], true).is_err());
        let mut meta = MetaData::read_from_buffered(BufReader::new(&mut view), true).unwrap();
        assert_eq!(meta.headers[1].compression, STAND_IN);
        assert_eq!(
            meta.headers[1].chunk_count, 1,
            "the stand-in's 256 lines a chunk"
        );
        view.mark(&mut meta);
        assert_eq!(stored_compression(&meta.headers[1]), Some(13));
        assert_eq!(
            meta.headers[1].chunk_count, HEIGHT,
            "as stored: a line a chunk"
        );
        for other in [0, 2] {
            assert_eq!(stored_compression(&meta.headers[other]), None);
            assert_eq!(meta.headers[other].compression, Compression::RLE);
        }
        assert_eq!(as_parsed(&meta.headers[1]).chunk_count, 1);
        assert_eq!(stored_compression(&as_parsed(&meta.headers[1])), None);
        // Only the part's compression and chunk count read otherwise, wherever reads fall.
        let count = value_at(&bytes, "chunkCount", "int", 1);
        let mut shown = bytes.clone();
        shown[at] = 10;
        shown[count..count + 4].copy_from_slice(&1i32.to_le_bytes());
        for piece in [1, 3, 7, 4096] {
            assert_eq!(read_all(&mut view, piece), shown, "pieces of {piece}");
        }
    }

    #[test]
    fn an_unknown_part_without_a_chunk_count_is_refused_naming_its_compression() {
        let mut bytes = exr_of(&["rgba"]);
        let at = value_at(&bytes, "compression", "compression", 0);
        bytes[at] = 13;
        // A chunk count under another name (as OpenEXR writes a single part: without one).
        let count = value_at(&bytes, "chunkCount", "int", 0);
        bytes[count - 10] = b'X';
        let refused = View::open(Cursor::new(bytes.clone())).err().unwrap();
        let text = refused.to_string();
        assert!(
            text.contains("zstd compression") && text.contains("re-save"),
            "{text}"
        );
        bytes[at] = 200;
        let text = View::open(Cursor::new(bytes)).err().unwrap().to_string();
        assert!(text.contains("compression method 200"), "{text}");
    }

    #[test]
    fn a_header_cut_short_is_left_to_the_crate() {
        let mut bytes = exr_of(&["rgba", "spec"]);
        let at = value_at(&bytes, "compression", "compression", 1);
        bytes[at] = 13;
        for cut in [0, 3, 8, at - 20, at + 1] {
            let view = View::open(Cursor::new(bytes[..cut].to_vec())).unwrap();
            assert!(!view.has_unknown(), "cut at {cut}");
        }
    }

    #[test]
    fn compressions_are_named_as_openexr_names_them() {
        assert_eq!(name_of_id(13), Some("zstd"));
        assert_eq!(name_of_id(12), Some("lj2k"));
        assert_eq!(name_of_id(14), None);
        assert!(reason(13).starts_with("zstd compression cannot be decoded"));
        // The crate knows every id below, and none of those above.
        for id in 0..=11u8 {
            assert!(Compression::read(&mut &[id][..]).is_ok(), "{id}");
        }
        for id in 12..=13u8 {
            assert!(Compression::read(&mut &[id][..]).is_err(), "{id}");
        }
    }
}
