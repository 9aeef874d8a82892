//! OpenEXR through the `exr` crate.
//!
//! Reading uses exr's block API rather than its image API: chunks are filtered by part
//! (a part holding no wanted channel is never decompressed) and by level (only the full
//! resolution level of a mip/rip-mapped file), then decompressed in parallel on our rayon
//! pool — one task per band of rows — and copied straight into planar f32 buffers. Within a
//! part every chunk holds all of its channels, so a single-part file is always inflated
//! whole; only the wanted channels are converted and kept. f16, f32 and u32 channels all
//! become f32.
//!
//! Writing uses exr's image API with scan-line blocks and an explicit compression (exr's
//! default is RLE tiles, which is not what compositors expect).

use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::Path;

use exr::block::chunk::{Chunk, CompressedBlock};
use exr::block::lines::LineIndex;
use exr::compression::Compression;
use exr::math::Vec2;
use exr::meta::attribute::{IntegerBounds, SampleType};
use exr::meta::header::{Header, ImageAttributes, LayerAttributes};
use exr::meta::{BlockDescription, MetaData};
use exr::prelude::f16;
use rayon::prelude::*;

use crate::frame::{Plane, Windows};
use crate::io::exr_unknown::{self, stored_compression, View};

/// What starts the text of an error of [`read_channels_checked`]'s check.
pub const CHANGED: &str = "changed since the preflight: ";

/// A channel of an EXR file: which part (exr calls it a layer) and which index in the part's
/// sorted channel list.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ChannelRef {
    pub part: usize,
    pub index: usize,
    /// A u32 channel's samples as their bit patterns (`f32::from_bits`): exact, where a
    /// conversion to f32 rounds every value over 2²⁴ (IDs, hashes). Other types ignore it.
    pub bits: bool,
}

/// Reads the headers only, as the exr crate's reader does when it decodes: every attribute
/// must parse (a line order out of range, a chunk count that does not match the data
/// window, are errors there). [`validate`] then checks them as decoding does, so preflight
/// refuses exactly the headers decoding would. A part in a compression the crate does not
/// know is read as `exr_unknown` shows it, and marked.
pub fn read_meta(path: &Path) -> exr::error::Result<MetaData> {
    meta_of(&mut View::open(crate::io::input::open_input(path)?)?)
}

/// The headers read through `view` from where it stands, marked (`View::mark`).
fn meta_of(view: &mut View<std::fs::File>) -> exr::error::Result<MetaData> {
    // The exr crate's decoding reader reads attributes with its `pedantic` turned over.
    let mut meta = MetaData::read_from_buffered(BufReader::new(&mut *view), true)?;
    view.mark(&mut meta);
    Ok(meta)
}

/// Checks headers as the exr crate's decoding reader does (non-strictly): windows not
/// inverted, channels present, sorted and sampled at 1×1, and the rest. A deep part (which
/// the crate refuses whole, and shutter leaves out) is checked as the same part flat; a
/// part in a compression the crate does not know, as the crate parsed it.
pub fn validate(meta: &MetaData) -> exr::error::Result<()> {
    let parsed: Vec<Header>;
    let headers = if meta.headers.iter().any(|h| stored_compression(h).is_some()) {
        parsed = meta.headers.iter().map(exr_unknown::as_parsed).collect();
        &parsed[..]
    } else {
        &meta.headers[..]
    };
    if !headers.iter().any(|h| h.deep) {
        return MetaData::validate(headers, false).map(|_| ());
    }
    let mut long_names = false;
    for header in headers {
        let mut flat = header.clone();
        flat.deep = false;
        flat.validate(meta.headers.len() > 1, &mut long_names, false)?;
    }
    Ok(())
}

/// The chunks of `parts` (full resolution only) of a file with a deep part, which the exr
/// crate's reader refuses whole, or a part in a compression it does not know (whose offset
/// table it would misread): read by the offset tables (which preflight checked:
/// `check_chunk_table`) as `meta` counts them, each chunk by the crate.
fn chunks_by_tables(
    file: View<std::fs::File>,
    meta: &MetaData,
    parts: &[usize],
) -> exr::error::Result<Vec<Chunk>> {
    let mut counting = CountingReader {
        inner: BufReader::new(file),
        count: 0,
    };
    MetaData::read_from_buffered(&mut counting, true)?;
    let mut offsets = Vec::new();
    for (part, header) in meta.headers.iter().enumerate() {
        for _ in 0..header.chunk_count {
            let mut bytes = [0u8; 8];
            counting.read_exact(&mut bytes)?;
            if parts.contains(&part) {
                offsets.push(u64::from_le_bytes(bytes));
            }
        }
    }
    let mut file = counting.inner;
    offsets.sort_unstable();
    let mut chunks = Vec::with_capacity(offsets.len());
    for offset in offsets {
        file.seek(SeekFrom::Start(offset))?;
        let chunk = Chunk::read(&mut file, meta)?;
        if !parts.contains(&chunk.layer_index) {
            return Err(invalid("chunk part number"));
        }
        let header = &meta.headers[chunk.layer_index];
        if header
            .get_block_data_indices(&chunk.compressed_block)?
            .level_index
            == Vec2(0, 0)
        {
            chunks.push(chunk);
        }
    }
    Ok(chunks)
}

/// The name of a compression method as users write it on the command line.
pub fn compression_name(compression: Compression) -> &'static str {
    match compression {
        Compression::Uncompressed => "none",
        Compression::RLE => "rle",
        Compression::ZIP1 => "zips",
        Compression::ZIP16 => "zip",
        Compression::PIZ => "piz",
        Compression::PXR24 => "pxr24",
        Compression::B44 => "b44",
        Compression::B44A => "b44a",
        Compression::DWAA(_) => "dwaa",
        Compression::DWAB(_) => "dwab",
        Compression::HTJ2K32 => "htj2k32",
        Compression::HTJ2K256 => "htj2k256",
    }
}

/// Whether compression `method` (by name) keeps a channel of this name and pixel type
/// exactly: DWAA and DWAB compress a channel whose name ends in R, G, B or Y (BY, RY; any
/// case) as colour, whatever its pixel type (OpenEXR's rule: a vector's `velocity.Y` is
/// one); B44 and B44A every half channel; PXR24 every float one (to 24 bits).
pub fn keeps_exactly(method: &str, name: &str, sample_type: &str) -> bool {
    let suffix = name.rsplit('.').next().unwrap_or("").to_ascii_lowercase();
    !match method {
        "dwaa" | "dwab" => ["r", "g", "b", "y", "by", "ry"].contains(&suffix.as_str()),
        "b44" | "b44a" => sample_type == "f16",
        "pxr24" => sample_type == "f32",
        _ => false,
    }
}

/// The compression methods shutter can write, by name.
pub const WRITABLE_COMPRESSIONS: &[&str] = &[
    "none", "rle", "zips", "zip", "piz", "pxr24", "b44", "b44a", "dwaa", "dwab",
];

/// Parses a compression name (see [`WRITABLE_COMPRESSIONS`]).
pub fn parse_compression(name: &str) -> Option<Compression> {
    Some(match name.to_ascii_lowercase().as_str() {
        "none" | "uncompressed" => Compression::Uncompressed,
        "rle" => Compression::RLE,
        "zips" | "zip1" => Compression::ZIP1,
        "zip" | "zip16" => Compression::ZIP16,
        "piz" => Compression::PIZ,
        "pxr24" => Compression::PXR24,
        "b44" => Compression::B44,
        "b44a" => Compression::B44A,
        "dwaa" => Compression::DWAA(None),
        "dwab" => Compression::DWAB(None),
        _ => return None,
    })
}

/// The name of a part's compression: [`compression_name`], or OpenEXR's where the exr crate
/// does not know it (`exr_unknown`; `unknown` where OpenEXR 3.5 does not either).
pub fn part_compression_name(header: &Header) -> &'static str {
    match stored_compression(header) {
        Some(id) => exr_unknown::name_of_id(id).unwrap_or("unknown"),
        None => compression_name(header.compression),
    }
}

/// Why a file cannot be read, found from its header alone.
pub fn unsupported_reason(header: &Header) -> Option<String> {
    if header.deep {
        return Some("deep data is not supported; flatten the image first".into());
    }
    if let Some(id) = stored_compression(header) {
        return Some(exr_unknown::reason(id));
    }
    if matches!(
        header.compression,
        Compression::HTJ2K32 | Compression::HTJ2K256
    ) {
        return Some(format!(
            "{} compression cannot be decoded by the exr crate; re-save with ZIP, PIZ or DWA",
            compression_name(header.compression)
        ));
    }
    if let Some(channel) = header
        .channels
        .list
        .iter()
        .find(|c| c.sampling != Vec2(1, 1))
    {
        return Some(format!(
            "channel {} is subsampled ({}x{}), which shutter does not read",
            channel.name, channel.sampling.0, channel.sampling.1
        ));
    }
    None
}

/// Checks, without decompressing anything, that the offset tables describe the image: every
/// chunk lies inside the file, no two chunks share bytes, and each part's chunks name each
/// of its blocks (scan-line blocks or tiles of its levels) exactly once. Catches truncated
/// and half-copied files, and tables that point several entries at one chunk, which a
/// decoder would otherwise turn into a frame with black lines, before any output is written.
pub fn check_chunk_table(path: &Path, meta: &MetaData) -> Result<(), String> {
    let file = crate::io::input::open_input(path).map_err(|e| e.to_string())?;
    let file_len = file.metadata().map_err(|e| e.to_string())?.len();
    let mut file = View::open(file).map_err(|e| e.to_string())?;
    let mut counting = CountingReader {
        inner: BufReader::new(&mut file),
        count: 0,
    };
    MetaData::read_from_buffered(&mut counting, false).map_err(|e| e.to_string())?;
    let header_len = counting.count;
    let multipart = meta.requirements.has_multiple_layers;
    // The table is read first: its length is bounded by the file's, so what follows is too.
    let mut offsets = Vec::new();
    for (part, header) in meta.headers.iter().enumerate() {
        for _ in 0..header.chunk_count {
            let mut bytes = [0u8; 8];
            counting
                .read_exact(&mut bytes)
                .map_err(|_| "the chunk offset table is cut short".to_string())?;
            offsets.push((u64::from_le_bytes(bytes), part));
        }
    }
    drop(counting);
    let mut header = vec![0u8; header_len as usize];
    file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
    file.read_exact(&mut header).map_err(|e| e.to_string())?;
    check_windows(&header)?;
    // Each part's blocks, as (tile x, tile y, level x, level y); a scan-line block is tile
    // (0, k) of level (0, 0). A part in a compression the exr crate does not know has blocks
    // of lines shutter does not know: its chunks are only checked to lie in the file, apart.
    let unknown = |part: usize| stored_compression(&meta.headers[part]).is_some();
    let mut blocks: Vec<std::collections::HashMap<[usize; 4], bool>> = meta
        .headers
        .iter()
        .map(|header| {
            let known = stored_compression(header).is_none();
            header
                .blocks_increasing_y_order()
                .filter(|_| known)
                .map(|b| {
                    let (t, l) = (b.location.tile_index, b.location.level_index);
                    ([t.0, t.1, l.0, l.1], false)
                })
                .collect()
        })
        .collect();
    let mut spans = Vec::with_capacity(offsets.len());
    for (offset, part) in offsets {
        let header = &meta.headers[part];
        let tiled = matches!(header.blocks, BlockDescription::Tiles(_));
        // Chunk layout: [part number: i32 when multi-part] then the block coordinates (y for
        // scan lines, four i32 for tiles), then the data size as i32, then the data. A deep
        // part's chunk has three u64 instead of the size (its sample-count table's packed
        // size, its samples' packed and unpacked sizes), then the table and the samples.
        let coordinates = if tiled { 16 } else { 4 };
        let skip = if multipart { 4 } else { 0 } + coordinates;
        let sizes = if header.deep { 24 } else { 4 };
        let size_at = offset.checked_add(skip).ok_or("chunk offset overflows")?;
        if size_at + sizes > file_len {
            return Err(format!(
                "the file is truncated: a chunk starts at byte {offset} of {file_len}"
            ));
        }
        file.seek(SeekFrom::Start(offset))
            .map_err(|e| e.to_string())?;
        let mut bytes = vec![0u8; (skip + sizes) as usize];
        file.read_exact(&mut bytes).map_err(|e| e.to_string())?;
        let (bytes, size_bytes) = bytes.split_at(skip as usize);
        let words: Vec<i32> = bytes
            .chunks_exact(4)
            .map(|w| i32::from_le_bytes([w[0], w[1], w[2], w[3]]))
            .collect();
        let size = if header.deep {
            let word = |i: usize| {
                let mut w = [0u8; 8];
                w.copy_from_slice(&size_bytes[i * 8..i * 8 + 8]);
                u64::from_le_bytes(w)
            };
            word(0).checked_add(word(1)).filter(|&s| s <= file_len)
        } else {
            let size =
                i32::from_le_bytes([size_bytes[0], size_bytes[1], size_bytes[2], size_bytes[3]]);
            u64::try_from(size).ok()
        };
        let Some(size) = size else {
            return Err(format!(
                "a chunk at byte {offset} has an invalid size; the file is damaged"
            ));
        };
        let end = size_at + sizes + size;
        if end > file_len {
            return Err(format!(
                "the file is truncated: a chunk at byte {offset} needs {size} bytes, the file has {file_len}"
            ));
        }
        let words = if multipart {
            if words[0] as i64 != part as i64 {
                return Err(format!(
                    "the chunk at byte {offset} belongs to part {}, but part {part}'s table points at it; the file is damaged",
                    words[0]
                ));
            }
            &words[1..]
        } else {
            &words[..]
        };
        if unknown(part) {
            spans.push((offset, end));
            continue;
        }
        let key = if tiled {
            let mut key = [0usize; 4];
            for (k, &w) in key.iter_mut().zip(words) {
                *k = usize::try_from(w).unwrap_or(usize::MAX);
            }
            key
        } else {
            let lines = header.compression.scan_lines_per_block() as i64;
            let from_top = words[0] as i64 - header.own_attributes.layer_position.1 as i64;
            let index = if from_top < 0 || from_top % lines != 0 {
                usize::MAX
            } else {
                usize::try_from(from_top / lines).unwrap_or(usize::MAX)
            };
            [0, index, 0, 0]
        };
        match blocks[part].get_mut(&key) {
            None => {
                return Err(if tiled {
                    format!(
                        "the chunk at byte {offset} names tile {:?}, which the image does not have; the file is damaged",
                        words
                    )
                } else {
                    format!(
                        "the chunk at byte {offset} names line {}, outside the data window or off a block start; the file is damaged",
                        words[0]
                    )
                })
            }
            Some(seen) if *seen => {
                return Err(format!(
                    "the chunk at byte {offset} names a block another chunk already holds; the file is damaged"
                ))
            }
            Some(seen) => *seen = true,
        }
        spans.push((offset, end));
    }
    for (part, blocks) in blocks.iter().enumerate() {
        if let Some((key, _)) = blocks.iter().find(|(_, seen)| !**seen) {
            let what = if matches!(meta.headers[part].blocks, BlockDescription::Tiles(_)) {
                format!("tile {:?}", key)
            } else {
                format!("scan-line block {}", key[1])
            };
            return Err(format!(
                "no chunk holds {what}{}; the file is damaged",
                if multipart {
                    format!(" of part {part}")
                } else {
                    String::new()
                }
            ));
        }
    }
    spans.sort_unstable();
    if let Some(w) = spans.windows(2).find(|w| w[1].0 < w[0].1) {
        return Err(format!(
            "the chunks at bytes {} and {} overlap; the file is damaged",
            w[0].0, w[1].0
        ));
    }
    Ok(())
}

/// Checks the windows as stored: the exr crate reads a box whose minimum lies beyond its
/// maximum as the box between the two, so an inverted data window would read as a frame of
/// another size whose chunks then fail to decode. `header` is the file up to its offset
/// tables: magic, version, then each part's attributes (name, type, size, value), each part
/// ended by an empty name.
fn check_windows(header: &[u8]) -> Result<(), String> {
    let mut at = 8;
    let text = |at: &mut usize| -> Option<&[u8]> {
        let rest = header.get(*at..)?;
        let end = rest.iter().position(|&b| b == 0)?;
        *at += end + 1;
        Some(&rest[..end])
    };
    while at < header.len() {
        let Some(name) = text(&mut at) else { break };
        if name.is_empty() {
            // The end of a part's header (or of the list of parts).
            continue;
        }
        let Some(kind) = text(&mut at) else { break };
        let Some(size) = header.get(at..at + 4) else {
            break;
        };
        let size = i32::from_le_bytes([size[0], size[1], size[2], size[3]]).max(0) as usize;
        at += 4;
        let value = header.get(at..at + size).unwrap_or(&[]);
        at += size;
        if kind == b"box2i" && (name == b"dataWindow" || name == b"displayWindow") {
            let v: Vec<i32> = value
                .chunks_exact(4)
                .map(|w| i32::from_le_bytes([w[0], w[1], w[2], w[3]]))
                .collect();
            if let [x_min, y_min, x_max, y_max] = v[..] {
                if x_min > x_max || y_min > y_max {
                    return Err(format!(
                        "the {} is inverted: ({x_min}, {y_min}) - ({x_max}, {y_max}); the file is damaged",
                        if name == b"dataWindow" {
                            "data window"
                        } else {
                            "display window"
                        }
                    ));
                }
            }
        }
    }
    Ok(())
}

struct CountingReader<R> {
    inner: R,
    count: u64,
}

impl<R: Read> Read for CountingReader<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count += n as u64;
        Ok(n)
    }
}

/// The planes read from one file, with the file's size and windows.
pub struct ReadChannels {
    pub width: usize,
    pub height: usize,
    pub windows: Windows,
    pub planes: Vec<Plane>,
}

/// The windows of a part: data window origin and the file's display window.
pub fn windows_of(header: &Header) -> Windows {
    let display = header.shared_attributes.display_window;
    Windows {
        data_origin: (
            header.own_attributes.layer_position.0,
            header.own_attributes.layer_position.1,
        ),
        display: crate::frame::Window {
            x: display.position.0,
            y: display.position.1,
            width: display.size.0,
            height: display.size.1,
        },
    }
}

/// Reads the wanted channels (distinct) into planes, in the order asked for. All wanted
/// channels must lie in parts of the same data-window size.
pub fn read_channels(path: &Path, wanted: &[ChannelRef]) -> exr::error::Result<ReadChannels> {
    read_channels_checked(path, wanted, |_| Ok(()))
}

/// An EXR's wanted channels decoded, as [`read_channels`], after `check` has seen the
/// headers read from the same open file (so a file replaced between a check of its path and
/// the open cannot slip through); an error of `check` stops the read before any pixel is
/// decoded, as [`Error::Invalid`](exr::error::Error::Invalid) with its text after
/// [`CHANGED`].
pub fn read_channels_checked(
    path: &Path,
    wanted: &[ChannelRef],
    check: impl FnOnce(&MetaData) -> Result<(), String>,
) -> exr::error::Result<ReadChannels> {
    let mut file = View::open(crate::io::input::open_input(path)?)?;
    // The exr crate's reader refuses a file with a deep part whole ("not supported"), and
    // would misread the offset table of a part in a compression it does not know
    // (`exr_unknown`): only for those are the headers read again, checked as `validate`
    // checks them, and the other parts' chunks read by the offset tables
    // (`chunks_by_tables`). Every other file is read once, by the crate's reader, as before.
    let read = match file.has_unknown() {
        true => Err(None),
        false => exr::block::read(BufReader::new(file.try_clone()?), false).map_err(Some),
    };
    let (reader, meta) = match read {
        Ok(reader) => {
            let meta = reader.meta_data().clone();
            (Some(reader), meta)
        }
        Err(refused @ (None | Some(exr::error::Error::NotSupported(_)))) => {
            file.seek(SeekFrom::Start(0))?;
            let meta = meta_of(&mut file)?;
            let beside = |h: &Header| h.deep || stored_compression(h).is_some();
            if !meta.headers.iter().any(beside) {
                return Err(refused
                    .unwrap_or_else(|| unsupported("a compression the exr crate does not know")));
            }
            validate(&meta)?;
            file.seek(SeekFrom::Start(0))?;
            (None, meta)
        }
        Err(Some(other)) => return Err(other),
    };
    check(&meta).map_err(|e| exr::error::Error::Invalid(format!("{CHANGED}{e}").into()))?;

    let first = wanted.first().map_or(0, |c| c.part);
    let header = meta
        .headers
        .get(first)
        .ok_or_else(|| invalid("part index"))?;
    let (width, height) = (header.layer_size.0, header.layer_size.1);
    let windows = windows_of(header);
    for channel in wanted {
        let part = meta
            .headers
            .get(channel.part)
            .ok_or_else(|| invalid("part index"))?;
        if part.layer_size != header.layer_size {
            return Err(invalid(
                "the parts holding the wanted channels differ in size",
            ));
        }
        if channel.index >= part.channels.list.len() {
            return Err(invalid("channel index"));
        }
        if let Some(reason) = unsupported_reason(part) {
            return Err(unsupported(reason));
        }
    }

    // Allocated fallibly: memory refused by the system is an error that ends the run cleanly
    // (temporary files removed, the lock released), not an abort.
    let mut planes: Vec<Plane> = wanted
        .iter()
        .map(|_| crate::frame::try_plane(width * height))
        .collect::<Result<_, String>>()
        .map_err(|e| {
            exr::error::Error::Io(std::io::Error::new(std::io::ErrorKind::OutOfMemory, e))
        })?;
    if wanted.is_empty() || width == 0 || height == 0 {
        return Ok(ReadChannels {
            width,
            height,
            windows,
            planes,
        });
    }

    let parts: Vec<usize> = {
        let mut parts: Vec<usize> = wanted.iter().map(|c| c.part).collect();
        parts.sort_unstable();
        parts.dedup();
        parts
    };
    let chunks: Vec<Chunk> = match reader {
        Some(reader) => reader
            .filter_chunks(false, |_, tile, block| {
                tile.level_index == Vec2(0, 0) && parts.contains(&block.layer)
            })?
            .collect::<exr::error::Result<_>>()?,
        None => chunks_by_tables(file, &meta, &parts)?,
    };

    // Group the chunks into bands of rows that do not overlap, so each band can be written by
    // its own task without locks. A chunk that starts inside a band joins it and the band
    // grows to hold it: the parts of one file may cut their rows differently (a PIZ part's
    // 32-line chunks beside a ZIP part's 16).
    let mut located = Vec::with_capacity(chunks.len());
    for chunk in chunks {
        let header = &meta.headers[chunk.layer_index];
        let tile = header.get_block_data_indices(&chunk.compressed_block)?;
        let bounds = header.get_absolute_block_pixel_coordinates(tile)?;
        bounds.validate(Some(header.layer_size))?;
        let y = bounds.position.1 as usize;
        located.push((y, bounds.size.1, bounds.position.0 as usize, chunk));
    }
    located.sort_by_key(|(y, _, x, chunk)| (*y, *x, chunk.layer_index));
    let mut bands: Vec<(usize, usize, Vec<Chunk>)> = Vec::new();
    for (y, h, _, chunk) in located {
        match bands.last_mut() {
            Some((band_y, band_h, chunks)) if y < *band_y + *band_h || y == *band_y => {
                *band_h = (*band_h).max(y + h - *band_y);
                chunks.push(chunk);
            }
            _ => bands.push((y, h, vec![chunk])),
        }
    }
    if let Some((y, h, _)) = bands.last() {
        if y + h > height {
            return Err(invalid("chunk outside the data window"));
        }
    }

    // Carve each plane into one mutable slice per band.
    let mut band_slices: Vec<Vec<&mut [f32]>> = bands.iter().map(|_| Vec::new()).collect();
    for plane in planes.iter_mut() {
        let mut rest: &mut [f32] = plane.as_mut_slice();
        let mut consumed = 0;
        for (slices, (y, h, _)) in band_slices.iter_mut().zip(&bands) {
            let taken = std::mem::take(&mut rest);
            let (_, tail) = taken.split_at_mut(y * width - consumed);
            let (mine, tail) = tail.split_at_mut(h * width);
            slices.push(mine);
            rest = tail;
            consumed = (y + h) * width;
        }
    }

    let meta_ref = &meta;
    bands
        .into_par_iter()
        .zip(band_slices.into_par_iter())
        .try_for_each(|((band_y, _, chunks), mut slices)| {
            for chunk in chunks {
                if !matches!(
                    chunk.compressed_block,
                    CompressedBlock::ScanLine(_) | CompressedBlock::Tile(_)
                ) {
                    return Err(unsupported("deep data"));
                }
                let block = crate::io::exr_zip::decompress_chunk(chunk, meta_ref)?;
                let header = &meta_ref.headers[block.index.layer];
                for (range, line) in LineIndex::lines_in_block(block.index, &header.channels) {
                    let target = wanted
                        .iter()
                        .position(|c| c.part == block.index.layer && c.index == line.channel);
                    let Some(target) = target else { continue };
                    let bytes = block.data.get(range).ok_or_else(|| invalid("block size"))?;
                    let start = (line.position.1 - band_y) * width + line.position.0;
                    let dest = slices[target]
                        .get_mut(start..start + line.sample_count)
                        .ok_or_else(|| invalid("line outside its band"))?;
                    let kind = header.channels.list[line.channel].sample_type;
                    convert_line(kind, bytes, dest, wanted[target].bits)?;
                }
            }
            Ok(())
        })?;

    Ok(ReadChannels {
        width,
        height,
        windows,
        planes,
    })
}

fn convert_line(
    kind: SampleType,
    bytes: &[u8],
    dest: &mut [f32],
    bits: bool,
) -> exr::error::Result<()> {
    let size = kind.bytes_per_sample();
    if bytes.len() != dest.len() * size {
        return Err(invalid("line byte count"));
    }
    match kind {
        SampleType::F16 => {
            for (d, b) in dest.iter_mut().zip(bytes.chunks_exact(2)) {
                *d = f16::from_ne_bytes([b[0], b[1]]).to_f32();
            }
        }
        SampleType::F32 => {
            for (d, b) in dest.iter_mut().zip(bytes.chunks_exact(4)) {
                *d = f32::from_ne_bytes([b[0], b[1], b[2], b[3]]);
            }
        }
        SampleType::U32 if bits => {
            for (d, b) in dest.iter_mut().zip(bytes.chunks_exact(4)) {
                *d = f32::from_bits(u32::from_ne_bytes([b[0], b[1], b[2], b[3]]));
            }
        }
        SampleType::U32 => {
            for (d, b) in dest.iter_mut().zip(bytes.chunks_exact(4)) {
                *d = u32::from_ne_bytes([b[0], b[1], b[2], b[3]]) as f32;
            }
        }
    }
    Ok(())
}

/// How to write an EXR.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExrOptions {
    pub compression: Compression,
    /// Write 16-bit half floats instead of 32-bit floats.
    pub half: bool,
}

impl Default for ExrOptions {
    fn default() -> Self {
        ExrOptions {
            compression: Compression::ZIP16,
            half: false,
        }
    }
}

/// Writes named planes as one single-part scan-line EXR with the given windows. The writer
/// should be buffered.
pub fn write_channels(
    writer: impl std::io::Write + Seek,
    width: usize,
    height: usize,
    windows: Windows,
    channels: Vec<(String, Plane)>,
    options: ExrOptions,
) -> exr::error::Result<()> {
    use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
    use exr::prelude::{Blocks, LineOrder};

    let list = channels
        .into_iter()
        .map(|(name, plane)| {
            let samples = if options.half {
                FlatSamples::F16(plane.into_iter().map(f16::from_f32).collect())
            } else {
                FlatSamples::F32(plane)
            };
            // OpenEXR's default pLinear (off), not the exr crate's guess from the name (see
            // `exr_like::channels_like`).
            AnyChannel {
                quantize_linearly: false,
                ..AnyChannel::new(crate::io::channels::name_text(&name), samples)
            }
        })
        .collect();
    let encoding = Encoding {
        compression: options.compression,
        blocks: Blocks::ScanLines,
        line_order: LineOrder::Increasing,
    };
    let attributes = LayerAttributes {
        layer_position: Vec2(windows.data_origin.0, windows.data_origin.1),
        ..LayerAttributes::default()
    };
    let layer = Layer::new(
        (width, height),
        attributes,
        encoding,
        AnyChannels::sort(list),
    );
    let image = Image {
        attributes: ImageAttributes::new(IntegerBounds::new(
            (windows.display.x, windows.display.y),
            (windows.display.width, windows.display.height),
        )),
        layer_data: layer,
    };
    // (Scenes and maps: a capped DWA highlight is not reported here.)
    crate::io::exr_zip::write(&image, writer, true).map(|_| ())
}

fn invalid(message: impl Into<std::borrow::Cow<'static, str>>) -> exr::error::Error {
    exr::error::Error::Invalid(message.into())
}

fn unsupported(message: impl Into<std::borrow::Cow<'static, str>>) -> exr::error::Error {
    exr::error::Error::NotSupported(message.into())
}
