//! A TIFF's EXIF and IPTC in the forms a JPEG and a PNG hold them, and back again, so that
//! they pass from any photo input to any photo output (issue 29, point 4).
//!
//! EXIF in a JPEG (APP1) or a PNG (eXIf) is one block, a small TIFF structure of its own: an
//! IFD0 of descriptive tags (Make, Model, Orientation, DateTime, Artist, Copyright, …) whose
//! pointers name the Exif directory (tag 34665) and the GPS one (34853), the Exif directory
//! naming the Interoperability one (40965). A TIFF holds the same tags in its own IFD0, beside
//! those that lay out its pixels, and the same directories beside its image. Read from a TIFF,
//! IFD0's descriptive tags and the directories are gathered into such a block
//! ([`exif_of_tiff`], [`to_block`]); written to a TIFF, a block's ([`parse`]) are spread out
//! again ([`write_sub_directories`], [`write_ifd0`]): its IFD0 tags into the image's IFD0, the
//! directories as directories of their own outside the chain of images. Each value is copied
//! as stored (type, count, bytes), its byte order turned where the two files differ. The tiff
//! crate reads and writes the directories; the block's own structure is built here, as the
//! crate writes only whole files.
//!
//! Left out: the tags that lay out pixels ([`kept_in_ifd0`]), the blocks `Photo` carries
//! apart (profile, XMP, IPTC), a JPEG's thumbnail (its IFD1), values of BigTIFF's 8-byte
//! types and directories other than the three. A maker note is copied as its bytes: one that
//! locates its parts from the start of the block it came in (some makers' do, most do not)
//! points amiss once the block is built anew, as with any tool that rebuilds EXIF.
//!
//! IPTC: a JPEG holds it among Photoshop image resources (APP13), as a TIFF may (tag 34377,
//! which `Photo::iptc` holds and a TIFF output gets); exiftool and most other writers put a
//! TIFF's IPTC bare in tag 33723 (IPTC-NAA: its datasets typed LONG, padded to four bytes),
//! where libtiff's readers (OpenImageIO) look. [`iptc_resource`] wraps bare datasets as the
//! resource a JPEG holds; [`iptc_records`] finds them again for a TIFF output's tag 33723.

use std::io::{Read, Seek, Write};
use std::ops::Range;

use tiff::decoder::Decoder;
use tiff::encoder::{DirectoryEncoder, TiffEncoder, TiffKindStandard};
use tiff::tags::{IfdPointer, Tag, Type, ValueBuffer};
use tiff::{Directory, TiffResult};

/// One tag of a directory, its value as stored: TIFF type, count, and bytes in the byte order
/// of the [`Exif`] it belongs to.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Field {
    pub tag: u16,
    pub ty: u16,
    pub count: u32,
    pub bytes: Vec<u8>,
}

/// A directory: its fields, and the directories its pointers name (pointer tag, directory).
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct Dir {
    pub fields: Vec<Field>,
    pub subs: Vec<(u16, Dir)>,
}

/// EXIF: IFD0 and the directories below it, its values little- or big-endian.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Exif {
    pub little: bool,
    pub ifd0: Dir,
}

/// The pointer tags followed (EXIF 2.32, 4.6.3): IFD0's to the Exif and GPS directories, the
/// Exif directory's to the Interoperability one. None deeper, so a pointer that loops back
/// ends there.
const EXIF_IFD: u16 = 34665;
const GPS_IFD: u16 = 34853;
const INTEROP_IFD: u16 = 40965;

/// Whether `tag` is a pointer followed from a directory `depth` below IFD0; `None` for a tag
/// that is no pointer, `Some(false)` for one out of its place (left out: its offset means
/// nothing once copied).
fn follows(depth: usize, tag: u16) -> Option<bool> {
    let place = match tag {
        EXIF_IFD | GPS_IFD => 0,
        INTEROP_IFD => 1,
        _ => return None,
    };
    Some(place == depth)
}

/// Whether a tag of a TIFF's IFD0 is carried in EXIF: not one that lays out or encodes the
/// pixels (TIFF 6.0's baseline and extension tags for size, samples, strips, tiles,
/// compression, colour coding, pages and sub-images; shutter writes its own), nor a block
/// `Photo` carries apart (XMP 700, IPTC 33723, Photoshop resources 34377, ICC profile 34675),
/// nor Photoshop's layers (37724, pixels the blur leaves stale).
pub(super) fn kept_in_ifd0(tag: u16) -> bool {
    !matches!(
        tag,
        254..=266 // subfile types, size, bits, compression, photometric, thresholding, cells, fill order
            | 273 // StripOffsets
            | 277..=281 // SamplesPerPixel, RowsPerStrip, StripByteCounts, Min/MaxSampleValue
            | 284 // PlanarConfiguration
            | 288..=293 // free offsets, grey response, T4/T6 options
            | 297 // PageNumber
            | 301 // TransferFunction
            | 317 // Predictor
            | 320..=325 // ColorMap, HalftoneHints, tiles
            | 330 // SubIFDs
            | 332..=342 // InkSet … TransferRange: ink, extra samples, sample formats
            | 347 // JPEGTables
            | 512..=521 // old-style JPEG
            | 529..=532 // YCbCr coefficients, subsampling, positioning, ReferenceBlackWhite
            | 346 // Indexed
            | 433 // Decode
            | 32995..=32998 // SGI's Matteing (an associated alpha to libtiff), data and image depth
            | 33421 | 33422 // TIFF/EP's CFA pattern
            | 50706..=52999 // DNG's tags: with DNGVersion, readers take the output for raw
            | 700 | 33723 | 34377 | 34675 | 37724
    )
}

/// The bytes of one value of a TIFF type, and the size of the unit whose byte order turns
/// (a RATIONAL is two LONGs); `None` for a type not carried (IFD, BigTIFF's 8-byte types, an
/// unknown one).
fn unit(ty: u16) -> Option<(usize, usize)> {
    match ty {
        1 | 2 | 6 | 7 => Some((1, 1)),
        3 | 8 => Some((2, 2)),
        4 | 9 | 11 => Some((4, 4)),
        5 | 10 => Some((8, 4)),
        12 => Some((8, 8)),
        _ => None,
    }
}

/// Reads an EXIF block (a TIFF structure, with or without the `Exif\0\0` of a JPEG segment
/// before it): IFD0 and the directories it points to. A field whose value lies outside the
/// block, or of a type not carried, is left out; `None` when the block has no TIFF header.
pub(super) fn parse(block: &[u8]) -> Option<Exif> {
    let tiff = block.strip_prefix(b"Exif\0\0").unwrap_or(block);
    let little = match tiff.get(0..2)? {
        b"II" => true,
        b"MM" => false,
        _ => return None,
    };
    let read = Reader {
        tiff,
        little,
        room: std::cell::Cell::new(tiff.len()),
        visited: std::cell::RefCell::new(Vec::new()),
    };
    if read.u16(2)? != 42 {
        return None;
    }
    let ifd0 = read.dir(read.u32(4)? as usize, 0)?;
    Some(Exif { little, ifd0 })
}

struct Reader<'a> {
    tiff: &'a [u8],
    little: bool,
    /// The bytes the values stored apart from their entries may still take: the block's
    /// length, so a hostile block whose entries all point at one large value (or whose
    /// pointers name one directory many times) costs no more than the block.
    room: std::cell::Cell<usize>,
    /// The directories read: each once, so a pointer back to one (IFD0 among them) is not
    /// followed.
    visited: std::cell::RefCell<Vec<usize>>,
}

impl Reader<'_> {
    fn u16(&self, at: usize) -> Option<u16> {
        let b = self.tiff.get(at..at.checked_add(2)?)?;
        let b = [b[0], b[1]];
        Some(if self.little {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        })
    }

    fn u32(&self, at: usize) -> Option<u32> {
        let b = self.tiff.get(at..at.checked_add(4)?)?;
        let b = [b[0], b[1], b[2], b[3]];
        Some(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn dir(&self, at: usize, depth: usize) -> Option<Dir> {
        if self.visited.borrow().contains(&at) {
            return None;
        }
        self.visited.borrow_mut().push(at);
        let mut dir = Dir::default();
        // Each pointer tag followed once.
        let mut followed = Vec::new();
        for e in 0..self.u16(at)? as usize {
            let entry = at + 2 + 12 * e;
            let (tag, ty, count) = (self.u16(entry)?, self.u16(entry + 2)?, self.u32(entry + 4)?);
            let value = entry + 8;
            if let Some(follow) = follows(depth, tag) {
                let first = !followed.contains(&tag);
                followed.push(tag);
                let sub = self
                    .u32(value)
                    .filter(|_| follow && first)
                    .and_then(|to| self.dir(to as usize, depth + 1));
                if let Some(sub) = sub.filter(|s| !s.fields.is_empty()) {
                    dir.subs.push((tag, sub));
                }
                continue;
            }
            let Some(len) = unit(ty).and_then(|(size, _)| size.checked_mul(count as usize)) else {
                continue;
            };
            let from = if len <= 4 {
                value
            } else {
                let Some(to) = self.u32(value) else { continue };
                if len > self.room.get() {
                    continue;
                }
                self.room.set(self.room.get() - len);
                to as usize
            };
            if let Some(bytes) = self.tiff.get(from..from.saturating_add(len)) {
                if count > 0 {
                    let bytes = bytes.to_vec();
                    dir.fields.push(Field {
                        tag,
                        ty,
                        count,
                        bytes,
                    });
                }
            }
        }
        Some(dir)
    }
}

/// An EXIF block as a JPEG's APP1 (after its `Exif\0\0`) and a PNG's eXIf hold it: a TIFF
/// header, IFD0 and the directories below it, each directory's values after it, entries in
/// tag order, offsets from the header.
pub(super) fn to_block(exif: &Exif) -> Vec<u8> {
    let mut writer = Writer {
        out: if exif.little {
            b"II\x2a\0\x08\0\0\0".to_vec()
        } else {
            b"MM\0\x2a\0\0\0\x08".to_vec()
        },
        little: exif.little,
    };
    writer.dir(&exif.ifd0);
    writer.out
}

struct Writer {
    out: Vec<u8>,
    little: bool,
}

impl Writer {
    fn u16(&self, v: u16) -> [u8; 2] {
        if self.little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    }

    fn u32(&self, v: u32) -> [u8; 4] {
        if self.little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        }
    }

    /// Writes `dir` at the next word boundary; returns where it starts.
    fn dir(&mut self, dir: &Dir) -> u32 {
        if self.out.len() % 2 == 1 {
            self.out.push(0);
        }
        let at = self.out.len();
        // (tag, the field or the sub-directory's index), in tag order as TIFF asks.
        let mut entries: Vec<(u16, Result<&Field, usize>)> = dir
            .fields
            .iter()
            .map(|f| (f.tag, Ok(f)))
            .chain(
                dir.subs
                    .iter()
                    .enumerate()
                    .map(|(i, (tag, _))| (*tag, Err(i))),
            )
            .collect();
        entries.sort_by_key(|(tag, _)| *tag);
        // A directory counts its entries in 16 bits.
        entries.truncate(u16::MAX as usize);
        let count = self.u16(entries.len() as u16);
        self.out.extend(count);
        for (tag, entry) in &entries {
            let (ty, count, inline) = match entry {
                Ok(f) => (
                    f.ty,
                    f.count,
                    f.bytes.get(..f.bytes.len().min(4)).unwrap_or(&[]),
                ),
                Err(_) => (4, 1, &[][..]),
            };
            let head = [self.u16(*tag), self.u16(ty)].concat();
            self.out.extend(head);
            self.out.extend(self.u32(count));
            let mut value = [0u8; 4];
            value[..inline.len()].copy_from_slice(inline);
            self.out.extend(value);
        }
        self.out.extend([0; 4]);
        // Values too long for their entries, then the sub-directories, each at a word boundary
        // with its offset put in its entry.
        for (e, (_, entry)) in entries.iter().enumerate() {
            let offset_at = at + 2 + 12 * e + 8;
            let to = match entry {
                Ok(f) if f.bytes.len() > 4 => {
                    if self.out.len() % 2 == 1 {
                        self.out.push(0);
                    }
                    let to = self.out.len() as u32;
                    self.out.extend(&f.bytes);
                    to
                }
                Ok(_) => continue,
                Err(i) => self.dir(&dir.subs[*i].1),
            };
            let to = self.u32(to);
            self.out[offset_at..offset_at + 4].copy_from_slice(&to);
        }
        at as u32
    }
}

/// The EXIF a TIFF holds in its first image's directories: IFD0's descriptive tags
/// ([`kept_in_ifd0`]) and the Exif, GPS and Interoperability directories, as an [`Exif`] of
/// the file's byte order; `None` when it holds none. Values add up to `room` bytes at the
/// most (the rest are left out), each within the decoder's own limit.
pub(super) fn exif_of_tiff<R: Read + Seek>(decoder: &mut Decoder<R>, room: usize) -> Option<Exif> {
    let little = decoder.byte_order() == tiff::tags::ByteOrder::LittleEndian;
    let ifd0 = decoder.ifd_pointer()?;
    let mut room = room;
    let mut visited = Vec::new();
    let ifd0 = read_dir(decoder, ifd0, 0, &mut room, &mut visited)?;
    (!ifd0.fields.is_empty() || !ifd0.subs.is_empty()).then_some(Exif { little, ifd0 })
}

fn read_dir<R: Read + Seek>(
    decoder: &mut Decoder<R>,
    at: IfdPointer,
    depth: usize,
    room: &mut usize,
    visited: &mut Vec<u64>,
) -> Option<Dir> {
    // Each directory once: a pointer back to one (IFD0 among them) is not followed.
    if visited.contains(&at.0) {
        return None;
    }
    visited.push(at.0);
    let little = decoder.byte_order() == tiff::tags::ByteOrder::LittleEndian;
    let directory = decoder.read_directory(at).ok()?;
    let entries: Vec<(Tag, u16, u64)> = directory
        .iter()
        .map(|(tag, e)| (tag, e.field_type().to_u16(), e.count()))
        .collect();
    let mut dir = Dir::default();
    for (tag, ty, count) in entries {
        let code = tag.to_u16();
        if let Some(follow) = follows(depth, code) {
            if !follow {
                continue;
            }
            let to = decoder.read_directory_tags(&directory).find_tag(tag);
            let Some(to) = to.ok().flatten().and_then(|v| v.into_ifd_pointer().ok()) else {
                continue;
            };
            if let Some(sub) = read_dir(decoder, to, depth + 1, room, visited) {
                if !sub.fields.is_empty() {
                    dir.subs.push((code, sub));
                }
            }
            continue;
        }
        if depth == 0 && !kept_in_ifd0(code) {
            continue;
        }
        let (Some((size, _)), Ok(count)) = (unit(ty), u32::try_from(count)) else {
            continue;
        };
        let len = size.saturating_mul(count as usize);
        if count == 0 || len > *room {
            continue;
        }
        let mut value = ValueBuffer::empty(Type::BYTE);
        let read = decoder
            .read_directory_tags(&directory)
            .find_tag_buf(tag, &mut value);
        if read.is_ok_and(|found| found.is_some()) && value.as_bytes().len() == len {
            *room -= len;
            let field = Field {
                tag: code,
                ty,
                count,
                bytes: value.as_bytes().to_vec(),
            };
            dir.fields.push(if depth == 0 && code == ORIENTATION {
                as_short(field, little)
            } else {
                field
            });
        }
    }
    Some(dir)
}

/// The orientation tag, which the carried EXIF resets to 1 where the pixels were turned
/// upright (as a SHORT: [`super::meta`] looks for it so).
const ORIENTATION: u16 = 274;

/// A one-value integer field (an orientation stored as LONG, which the decoder honours as it
/// does a SHORT) as the SHORT TIFF 6.0 asks for, so the reset to 1 finds it; any other as it
/// is.
fn as_short(field: Field, little: bool) -> Field {
    let value = match (field.ty, field.count, field.bytes.as_slice()) {
        (4 | 9, 1, &[a, b, c, d]) => {
            let v = if little {
                u32::from_le_bytes([a, b, c, d])
            } else {
                u32::from_be_bytes([a, b, c, d])
            };
            u16::try_from(v).ok()
        }
        _ => None,
    };
    match value {
        Some(v) => Field {
            ty: 3,
            bytes: if little {
                v.to_le_bytes()
            } else {
                v.to_be_bytes()
            }
            .to_vec(),
            ..field
        },
        None => field,
    }
}

/// Writes an EXIF's directories below IFD0 into a TIFF being encoded, each outside the chain
/// of images, before the image whose IFD0 points to them; returns IFD0's pointers (tag,
/// offset) for [`write_ifd0`].
pub(super) fn write_sub_directories<W: Write + Seek>(
    encoder: &mut TiffEncoder<W>,
    exif: &Exif,
) -> TiffResult<Vec<(u16, u32)>> {
    write_subs(encoder, &exif.ifd0.subs, exif.little)
}

fn write_subs<W: Write + Seek>(
    encoder: &mut TiffEncoder<W>,
    subs: &[(u16, Dir)],
    little: bool,
) -> TiffResult<Vec<(u16, u32)>> {
    let mut pointers = Vec::new();
    for (tag, sub) in subs {
        let below = write_subs(encoder, &sub.subs, little)?;
        let mut directory = encoder.extra_directory()?;
        write_fields(&mut directory, &sub.fields, little, |_| true)?;
        for &(tag, to) in &below {
            directory.write_tag(Tag::from_u16_exhaustive(tag), to)?;
        }
        pointers.push((*tag, directory.finish_with_offsets()?.offset));
    }
    Ok(pointers)
}

/// Writes an EXIF's IFD0 tags ([`kept_in_ifd0`]: not those that lay out pixels, which the
/// image writes its own) and its pointers to the directories [`write_sub_directories`] wrote,
/// into an image's IFD0; a tag the image already has (its resolution) takes EXIF's value.
pub(super) fn write_ifd0<W: Write + Seek>(
    directory: &mut DirectoryEncoder<'_, W, TiffKindStandard>,
    exif: &Exif,
    pointers: &[(u16, u32)],
) -> TiffResult<()> {
    write_fields(directory, &exif.ifd0.fields, exif.little, kept_in_ifd0)?;
    for &(tag, to) in pointers {
        directory.write_tag(Tag::from_u16_exhaustive(tag), to)?;
    }
    Ok(())
}

fn write_fields<W: Write + Seek>(
    directory: &mut DirectoryEncoder<'_, W, TiffKindStandard>,
    fields: &[Field],
    little: bool,
    keep: fn(u16) -> bool,
) -> TiffResult<()> {
    for field in fields.iter().filter(|f| keep(f.tag)) {
        let (Some(ty), Some((_, turn))) = (Type::from_u16(field.ty), unit(field.ty)) else {
            continue;
        };
        let mut bytes = field.bytes.clone();
        // The encoder writes the machine's byte order.
        if little != cfg!(target_endian = "little") {
            bytes.chunks_exact_mut(turn).for_each(<[u8]>::reverse);
        }
        write_raw(directory, field.tag, ty, &bytes)?;
    }
    Ok(())
}

/// Writes a tag whose value is `bytes` as they are, typed `ty` (in the encoder's byte order
/// where the type has one), at a word boundary as TIFF 6.0 (section 2) asks of a value
/// outside its entry (the encoder writes each where the last ended).
pub(super) fn write_raw<W: Write + Seek>(
    directory: &mut DirectoryEncoder<'_, W, TiffKindStandard>,
    tag: u16,
    ty: Type,
    bytes: &[u8],
) -> TiffResult<()> {
    let at = directory.write_data(&[][..] as &[u8])?;
    if bytes.len() > 4 && at % 2 == 1 {
        directory.write_data(0u8)?;
    }
    let entry = directory.write_entry_bytes(ty, bytes)?;
    directory.extend_from(&Directory::from_iter([(
        Tag::from_u16_exhaustive(tag),
        entry,
    )]));
    Ok(())
}

/// The Photoshop image resource that holds IPTC (Photoshop File Formats, Image Resource IDs:
/// 0x0404, "IPTC-NAA record").
const IPTC_NAA: u16 = 0x0404;

/// Where the IPTC resource lies among Photoshop image resources (each `8BIM`, its ID, a
/// Pascal name padded to even, a big-endian size and its data padded to even): the whole
/// resource's bytes, and its data's.
fn iptc_at(resources: &[u8]) -> Option<(Range<usize>, Range<usize>)> {
    let mut at = 0;
    while resources.get(at..at + 4)? == b"8BIM" {
        let id = u16::from_be_bytes([*resources.get(at + 4)?, *resources.get(at + 5)?]);
        let name = *resources.get(at + 6)? as usize;
        let size_at = at + 6 + (1 + name).next_multiple_of(2);
        let size = resources.get(size_at..size_at + 4)?;
        let size = u32::from_be_bytes([size[0], size[1], size[2], size[3]]) as usize;
        let data = size_at + 4..(size_at + 4).checked_add(size)?;
        resources.get(data.clone())?;
        let end = (size_at + 4 + size.next_multiple_of(2)).min(resources.len());
        if id == IPTC_NAA {
            return Some((at..end, data));
        }
        at = end;
    }
    None
}

/// The IPTC datasets among Photoshop image resources, if they hold them.
pub(super) fn iptc_records(resources: &[u8]) -> Option<&[u8]> {
    iptc_at(resources).map(|(_, data)| &resources[data])
}

/// Photoshop image resources but the IPTC one: a TIFF holds IPTC in tag 33723 (exiftool
/// takes a second copy among the resources for a second, non-standard IPTC).
pub(super) fn without_iptc(resources: &[u8]) -> Vec<u8> {
    match iptc_at(resources) {
        Some((whole, _)) => [&resources[..whole.start], &resources[whole.end..]].concat(),
        None => resources.to_vec(),
    }
}

/// Bare IPTC datasets (a TIFF's tag 33723) as the Photoshop resource a JPEG's APP13 holds,
/// ending at the last whole dataset (the tag pads them to LONGs).
pub(super) fn iptc_resource(records: &[u8]) -> Vec<u8> {
    let records = &records[..records_end(records)];
    let mut out = b"8BIM".to_vec();
    out.extend(IPTC_NAA.to_be_bytes());
    out.extend([0, 0]);
    out.extend((records.len() as u32).to_be_bytes());
    out.extend(records);
    if records.len() % 2 == 1 {
        out.push(0);
    }
    out
}

/// Where IPTC datasets end: each a tag marker 0x1C, record and dataset numbers, then a
/// big-endian length, or with its top bit set the number of bytes of a longer length (IPTC
/// IIM 4.2, 1.5).
fn records_end(records: &[u8]) -> usize {
    let mut at = 0;
    while records.get(at) == Some(&0x1C) {
        let Some(&[high, low]) = records.get(at + 3..at + 5) else {
            break;
        };
        let length = u16::from_be_bytes([high, low]) as usize;
        let (head, size) = if length & 0x8000 == 0 {
            (5, Some(length))
        } else {
            let n = length & 0x7FFF;
            let size = records
                .get(at + 5..at + 5 + n)
                .filter(|_| n <= 8)
                .map(|b| b.iter().fold(0u64, |s, &v| s << 8 | v as u64) as usize);
            (5 + n, size)
        };
        match size.and_then(|s| (at + head).checked_add(s)) {
            Some(end) if end <= records.len() => at = end,
            _ => break,
        }
    }
    at
}

/// The datasets for a TIFF's tag 33723: typed LONG as libtiff's readers ask, so padded with
/// zeros to a multiple of four bytes, and written as they are (the type's byte order is not
/// theirs).
pub(super) fn iptc_as_longs(records: &[u8]) -> Vec<u8> {
    let mut padded = records.to_vec();
    padded.resize(records.len().next_multiple_of(4), 0);
    padded
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field(tag: u16, ty: u16, count: u32, bytes: &[u8]) -> Field {
        Field {
            tag,
            ty,
            count,
            bytes: bytes.to_vec(),
        }
    }

    /// Make (ASCII, out of line), Orientation (SHORT, inline), an Exif directory with a
    /// RATIONAL and an Interoperability directory below it, and a GPS directory.
    fn sample(little: bool) -> Exif {
        let short = |v: u16| [v.to_be_bytes(), v.to_le_bytes()][little as usize];
        let long = |v: u32| [v.to_be_bytes(), v.to_le_bytes()][little as usize];
        let interop = Dir {
            fields: vec![field(1, 2, 4, b"R98\0")],
            subs: vec![],
        };
        let exif = Dir {
            fields: vec![
                field(33434, 5, 1, &[long(1), long(250)].concat()),
                field(36867, 2, 20, b"2024:05:06 07:08:09\0"),
            ],
            subs: vec![(INTEROP_IFD, interop)],
        };
        let gps = Dir {
            fields: vec![field(1, 2, 2, b"N\0")],
            subs: vec![],
        };
        Exif {
            little,
            ifd0: Dir {
                fields: vec![field(271, 2, 5, b"ShTs\0"), field(274, 3, 1, &short(6))],
                subs: vec![(EXIF_IFD, exif), (GPS_IFD, gps)],
            },
        }
    }

    #[test]
    fn a_block_built_reads_back_the_same_in_both_byte_orders() {
        for little in [true, false] {
            let exif = sample(little);
            let block = to_block(&exif);
            assert_eq!(parse(&block).as_ref(), Some(&exif));
            let mut prefixed = b"Exif\0\0".to_vec();
            prefixed.extend(&block);
            assert_eq!(parse(&prefixed).as_ref(), Some(&exif));
            // The orientation where the JPEG path looks for it.
            assert_eq!(super::super::upright::exif_orientation(&block), Some(6));
        }
    }

    #[test]
    fn a_hostile_block_costs_no_more_than_itself_and_no_directory_is_read_twice() {
        // IFD0: 100 Exif pointers to one directory and 100 descriptions each the whole block
        // (offset 0); the directory's Interoperability pointer names IFD0 again.
        let (n, len) = (200u16, 4096u32);
        let sub = 8 + 2 + 12 * u32::from(n) + 4;
        let mut b = b"II*\0\x08\0\0\0".to_vec();
        let entry = |b: &mut Vec<u8>, tag: u16, ty: u16, count: u32, value: u32| {
            b.extend([tag.to_le_bytes(), ty.to_le_bytes()].concat());
            b.extend([count.to_le_bytes(), value.to_le_bytes()].concat());
        };
        b.extend(n.to_le_bytes());
        for e in 0..n {
            match e % 2 {
                0 => entry(&mut b, EXIF_IFD, 4, 1, sub),
                _ => entry(&mut b, 270, 2, len, 0),
            }
        }
        b.extend([0u8; 4]);
        b.extend(2u16.to_le_bytes());
        entry(&mut b, 36867, 2, 2, u32::from_le_bytes(*b"A\0\0\0"));
        entry(&mut b, INTEROP_IFD, 4, 1, 8);
        b.resize(len as usize, 0);
        let read = parse(&b).unwrap();
        let stored: usize = read.ifd0.fields.iter().map(|f| f.bytes.len()).sum();
        assert!(
            stored <= b.len(),
            "{stored} bytes from a block of {}",
            b.len()
        );
        assert_eq!(read.ifd0.subs.len(), 1);
        assert!(read.ifd0.subs[0].1.subs.is_empty());
    }

    #[test]
    fn an_orientation_stored_as_a_long_is_carried_as_a_short() {
        for little in [true, false] {
            let six = if little {
                6u32.to_le_bytes()
            } else {
                6u32.to_be_bytes()
            };
            let short = as_short(field(ORIENTATION, 4, 1, &six), little);
            let want = if little {
                6u16.to_le_bytes()
            } else {
                6u16.to_be_bytes()
            };
            assert_eq!(short, field(ORIENTATION, 3, 1, &want));
        }
    }

    #[test]
    fn a_value_outside_the_block_or_of_an_uncarried_type_is_left_out() {
        let mut block = to_block(&sample(false));
        // IFD0's first entry (Make): its value's offset pointed past the end.
        block[8 + 2 + 8..8 + 2 + 12].copy_from_slice(&9999u32.to_be_bytes());
        // Its second (Orientation): typed IFD8.
        block[8 + 2 + 12 + 2..8 + 2 + 12 + 4].copy_from_slice(&18u16.to_be_bytes());
        let read = parse(&block).unwrap();
        assert!(read.ifd0.fields.is_empty(), "{:?}", read.ifd0.fields);
        assert_eq!(read.ifd0.subs.len(), 2);
        assert_eq!(parse(b"not a tiff"), None);
    }

    #[test]
    fn a_pointer_back_to_ifd0_is_not_followed() {
        // IFD0 whose Exif pointer names IFD0 itself: its Make kept, no Exif directory (it
        // would hold IFD0's layout tags).
        let mut block = b"MM\0\x2a\0\0\0\x08\0\x02".to_vec();
        block.extend([0x01, 0x0F, 0, 2, 0, 0, 0, 2, b'A', 0, 0, 0]);
        block.extend([0x87, 0x69, 0, 4, 0, 0, 0, 1, 0, 0, 0, 8]);
        block.extend([0; 4]);
        let read = parse(&block).unwrap();
        assert_eq!(read.ifd0.fields.len(), 1);
        assert!(read.ifd0.subs.is_empty());
    }

    #[test]
    fn layout_tags_and_blocks_carried_apart_stay_out_of_ifd0() {
        for tag in [
            256, 257, 258, 259, 262, 273, 277, 278, 279, 284, 317, 338, 339, 34675,
        ] {
            assert!(!kept_in_ifd0(tag), "{tag}");
        }
        for tag in [270, 271, 272, 274, 282, 283, 296, 305, 306, 315, 33432] {
            assert!(kept_in_ifd0(tag), "{tag}");
        }
    }

    #[test]
    fn bare_iptc_is_wrapped_as_a_photoshop_resource_and_found_again() {
        // Keywords "one" (2:25), padded to LONGs as tag 33723 holds it.
        let records = [0x1C, 2, 25, 0, 3, b'o', b'n', b'e'];
        let padded = iptc_as_longs(&records[..]);
        assert_eq!(padded.len(), 8);
        let mut odd = records.to_vec();
        odd.extend([0x1C, 2, 25, 0, 2, b'a', b'b', 0, 0, 0]);
        let resource = iptc_resource(&odd);
        assert_eq!(iptc_records(&resource), Some(&odd[..15]));
        assert_eq!(resource.len() % 2, 0);
        // Between a resource with a name and one without.
        let (before, after) = (
            b"8BIM\x04\x0c\x03abc\0\0\0\x01X\0",
            b"8BIM\x04\x0d\0\0\0\0\0\x02YZ",
        );
        let three = [&before[..], &iptc_resource(&padded), &after[..]].concat();
        assert_eq!(iptc_records(&three), Some(&records[..]));
        assert_eq!(without_iptc(&three), [&before[..], &after[..]].concat());
        assert_eq!(without_iptc(&resource), b"");
        assert_eq!(iptc_records(b"8BIM\x04\x0c\0\0\0\0\0\0"), None);
    }
}
