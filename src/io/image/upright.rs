//! The EXIF of a photo turned upright, made true of the upright pixels: the read turns the
//! pixels by their orientation (`read_planes`), so the EXIF carried to the output must say
//! orientation 1, the upright size (the Exif directory's PixelXDimension and
//! PixelYDimension, which exiftool shows as ExifImageWidth and ExifImageHeight), and, where
//! the turn swapped the axes, each axis's resolution on its new axis (IFD0's XResolution and
//! YResolution, the Exif directory's FocalPlaneXResolution and FocalPlaneYResolution). Its
//! thumbnail (IFD1, a small JPEG of the view as stored) would show the unturned view beside
//! an orientation of 1: it is dropped, by ending IFD0's chain of directories before it,
//! rather than decoded, turned and encoded again (a thumbnail is a convenience readers make
//! again when it is missing; one turned wrong misleads). Its bytes stay in the block, which
//! nothing points to any more.
//!
//! Every edit is made in place, in the block's own byte order, and no value moves: a maker
//! note that locates its parts from the start of the block still finds them (rebuilding the
//! block, as `tiff_meta` does for a TIFF, could not promise that).
//!
//! The XMP packet says the same things in its own words ([`make_xmp_upright`]):
//! `tiff:Orientation` becomes 1, and after a quarter turn each axis's size and resolution
//! (`exif:PixelXDimension` and `exif:PixelYDimension`, `tiff:ImageWidth` and
//! `tiff:ImageLength`, `tiff:XResolution` and `tiff:YResolution`, the focal plane's) trade
//! places. The packet is text that each output writes whole, so its values may change length.

use std::ops::Range;

/// Tags edited here (TIFF 6.0; EXIF 2.32, 4.6.4 and 4.6.5).
const ORIENTATION: u16 = 0x0112;
const X_RESOLUTION: u16 = 0x011A;
const Y_RESOLUTION: u16 = 0x011B;
const EXIF_IFD: u16 = 0x8769;
const PIXEL_X_DIMENSION: u16 = 0xA002;
const PIXEL_Y_DIMENSION: u16 = 0xA003;
const FOCAL_PLANE_X_RESOLUTION: u16 = 0xA20E;
const FOCAL_PLANE_Y_RESOLUTION: u16 = 0xA20F;

/// TIFF field types: SHORT, LONG, and IFD (a LONG that points to a directory).
const SHORT: u16 = 3;
const LONG: u16 = 4;
const IFD: u16 = 13;

/// An EXIF block (a TIFF structure, with or without the `Exif\0\0` of a JPEG segment before
/// it) as read in place: where its TIFF header starts and its byte order. Offsets below are
/// from the TIFF header, as the block's own are.
struct Block {
    start: usize,
    little: bool,
}

impl Block {
    fn of(exif: &[u8]) -> Option<Block> {
        let start = if exif.starts_with(b"Exif\0\0") { 6 } else { 0 };
        let little = match exif.get(start..start + 2)? {
            b"II" => true,
            b"MM" => false,
            _ => return None,
        };
        Some(Block { start, little })
    }

    fn u16(&self, exif: &[u8], at: usize) -> Option<u16> {
        let b = exif.get(self.start + at..self.start + at + 2)?;
        let b = [b[0], b[1]];
        Some(if self.little {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        })
    }

    fn u32(&self, exif: &[u8], at: usize) -> Option<u32> {
        let b = exif.get(self.start + at..self.start + at + 4)?;
        let b = [b[0], b[1], b[2], b[3]];
        Some(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    fn put(&self, exif: &mut [u8], at: usize, bytes: &[u8]) -> Option<()> {
        exif.get_mut(self.start + at..self.start + at + bytes.len())?
            .copy_from_slice(bytes);
        Some(())
    }

    fn put_u16(&self, exif: &mut [u8], at: usize, value: u16) -> Option<()> {
        let bytes = if self.little {
            value.to_le_bytes()
        } else {
            value.to_be_bytes()
        };
        self.put(exif, at, &bytes)
    }

    fn put_u32(&self, exif: &mut [u8], at: usize, value: u32) -> Option<()> {
        let bytes = if self.little {
            value.to_le_bytes()
        } else {
            value.to_be_bytes()
        };
        self.put(exif, at, &bytes)
    }

    /// Where IFD0 starts.
    fn ifd0(&self, exif: &[u8]) -> Option<usize> {
        Some(self.u32(exif, 4)? as usize)
    }

    /// Where the entry of `tag` in the directory at `ifd` starts (its 12 bytes: tag, type,
    /// count, value or offset), if the directory holds it.
    fn entry(&self, exif: &[u8], ifd: usize, tag: u16) -> Option<usize> {
        let count = self.u16(exif, ifd)? as usize;
        (0..count)
            .map(|e| ifd + 2 + 12 * e)
            .take_while(|&at| self.start + at + 12 <= exif.len())
            .find(|&at| self.u16(exif, at) == Some(tag))
    }

    /// The entry of `tag` in the directory at `ifd` if it holds one SHORT.
    fn short_entry(&self, exif: &[u8], ifd: usize, tag: u16) -> Option<usize> {
        let at = self.entry(exif, ifd, tag)?;
        (self.u16(exif, at + 2)? == SHORT && self.u32(exif, at + 4)? == 1).then_some(at)
    }

    /// Where the Exif directory starts, if IFD0 points to one.
    fn exif_ifd(&self, exif: &[u8], ifd0: usize) -> Option<usize> {
        let at = self.entry(exif, ifd0, EXIF_IFD)?;
        matches!(self.u16(exif, at + 2)?, LONG | IFD).then_some(())?;
        Some(self.u32(exif, at + 8)? as usize)
    }

    /// Sets a one-value SHORT or LONG entry to `value`: a SHORT too small for it becomes a
    /// LONG in place (both are held in the entry itself).
    fn set_size(&self, exif: &mut [u8], ifd: usize, tag: u16, value: u32) -> Option<()> {
        let at = self.entry(exif, ifd, tag)?;
        if self.u32(exif, at + 4)? != 1 {
            return None;
        }
        match (self.u16(exif, at + 2)?, u16::try_from(value)) {
            (SHORT, Ok(short)) => {
                self.put_u16(exif, at + 8, short)?;
                self.put_u16(exif, at + 10, 0)
            }
            (SHORT | LONG, _) => {
                self.put_u16(exif, at + 2, LONG)?;
                self.put_u32(exif, at + 8, value)
            }
            _ => None,
        }
    }

    /// Swaps the values of two tags of one directory (type, count and value or offset, so
    /// each entry stays whole), where it holds both.
    fn swap(&self, exif: &mut [u8], ifd: usize, a: u16, b: u16) -> Option<()> {
        let (a, b) = (self.entry(exif, ifd, a)?, self.entry(exif, ifd, b)?);
        let (a, b) = (self.start + a + 2, self.start + b + 2);
        for k in 0..10 {
            exif.swap(a + k, b + k);
        }
        Some(())
    }
}

/// The orientation an EXIF block records (1 to 8), if it records one.
pub fn exif_orientation(exif: &[u8]) -> Option<u16> {
    let block = Block::of(exif)?;
    let at = block.short_entry(exif, block.ifd0(exif)?, ORIENTATION)?;
    block.u16(exif, at + 8)
}

/// Rewrites the orientation an EXIF block records, in place; a block without one is left.
fn set_exif_orientation(exif: &mut [u8], value: u16) {
    let Some(block) = Block::of(exif) else { return };
    let at = block
        .ifd0(exif)
        .and_then(|ifd0| block.short_entry(exif, ifd0, ORIENTATION));
    if let Some(at) = at {
        block.put_u16(exif, at + 8, value);
    }
}

/// Makes an EXIF block true of the photo turned upright by `orientation` (1 to 8, as the
/// pixels were turned), `size` its upright width and height: orientation 1, that size in the
/// Exif directory, the per-axis resolutions swapped where the turn swapped the axes (5 to
/// 8), and no thumbnail where the pixels were turned at all. What the block does not hold
/// is not added; a block that cannot be read is left as it is.
pub fn make_upright(exif: &mut [u8], orientation: u16, (width, height): (u32, u32)) {
    set_exif_orientation(exif, 1);
    let Some(block) = Block::of(exif) else { return };
    let Some(ifd0) = block.ifd0(exif) else { return };
    let transposed = (5..=8).contains(&orientation);
    if transposed {
        block.swap(exif, ifd0, X_RESOLUTION, Y_RESOLUTION);
    }
    if let Some(ifd) = block.exif_ifd(exif, ifd0) {
        block.set_size(exif, ifd, PIXEL_X_DIMENSION, width);
        block.set_size(exif, ifd, PIXEL_Y_DIMENSION, height);
        if transposed {
            block.swap(
                exif,
                ifd,
                FOCAL_PLANE_X_RESOLUTION,
                FOCAL_PLANE_Y_RESOLUTION,
            );
        }
    }
    if orientation != 1 {
        // IFD0's link to the next directory, IFD1, the thumbnail's: ended.
        if let Some(count) = block.u16(exif, ifd0) {
            block.put_u32(exif, ifd0 + 2 + 12 * count as usize, 0);
        }
    }
}

/// The XMP properties that hold one axis's value each, in pairs (x, y), which trade values
/// where the turn swapped the axes: the size (Exif's PixelXDimension and PixelYDimension,
/// TIFF's ImageWidth and ImageLength) and the resolution, as the EXIF's are.
const XMP_AXES: [(&str, &str); 4] = [
    ("exif:PixelXDimension", "exif:PixelYDimension"),
    ("tiff:ImageWidth", "tiff:ImageLength"),
    ("tiff:XResolution", "tiff:YResolution"),
    ("exif:FocalPlaneXResolution", "exif:FocalPlaneYResolution"),
];

/// Makes an XMP packet true of the photo turned upright by `orientation` (1 to 8), as
/// [`make_upright`] does its EXIF: `tiff:Orientation` 1, and where the turn swapped the axes
/// (5 to 8) each pair of [`XMP_AXES`] trades values, in the attribute form
/// (`exif:PixelXDimension="4000"`, either quote) and the element form
/// (`<tiff:ImageWidth>4000</tiff:ImageWidth>`) alike. A property whose pair is missing is
/// left as it is; the packet's length changes where the two values differ in length (it is
/// written whole again, framed by each output).
pub fn make_xmp_upright(xmp: &mut Vec<u8>, orientation: u16) {
    set_xmp_orientation(xmp);
    if !(5..=8).contains(&orientation) {
        return;
    }
    for (x, y) in XMP_AXES {
        let (xs, ys) = (xmp_values(xmp, x), xmp_values(xmp, y));
        let mut edits: Vec<(Range<usize>, Vec<u8>)> = xs
            .iter()
            .zip(&ys)
            .flat_map(|(a, b)| {
                [
                    (a.clone(), xmp[b.clone()].to_vec()),
                    (b.clone(), xmp[a.clone()].to_vec()),
                ]
            })
            .collect();
        // From the end back, so each edit leaves the ranges before it where they were.
        edits.sort_by_key(|(range, _)| std::cmp::Reverse(range.start));
        for (range, value) in edits {
            xmp.splice(range, value);
        }
    }
}

/// Where the values of the XMP property `name` (`tiff:ImageWidth`) are, in its attribute
/// and element forms, in the packet's order.
fn xmp_values(xmp: &[u8], name: &str) -> Vec<Range<usize>> {
    let mut spans = Vec::new();
    for (open, close) in [
        (format!("{name}=\""), b'"'),
        (format!("{name}='"), b'\''),
        (format!("<{name}>"), b'<'),
    ] {
        let open = open.as_bytes();
        let mut from = 0;
        while let Some(found) = find(&xmp[from..], open) {
            let start = from + found + open.len();
            let Some(length) = xmp[start..].iter().position(|&b| b == close) else {
                break;
            };
            spans.push(start..start + length);
            from = start + length;
        }
    }
    spans.sort_by_key(|span| span.start);
    spans
}

/// Sets XMP's `tiff:Orientation` (as an attribute or an element) to 1.
fn set_xmp_orientation(xmp: &mut [u8]) {
    for (open, close) in [
        (&b"tiff:Orientation=\""[..], b'"'),
        (&b"tiff:Orientation='"[..], b'\''),
        (&b"<tiff:Orientation>"[..], b'<'),
    ] {
        let mut from = 0;
        while let Some(found) = find(&xmp[from..], open) {
            let value = from + found + open.len();
            // A single digit 1-8: overwritten in place, so no length changes.
            if xmp.get(value + 1) == Some(&close) && xmp[value].is_ascii_digit() {
                xmp[value] = b'1';
            }
            from = value;
        }
    }
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xmp_orientation_becomes_1_in_both_forms() {
        let mut xmp = b"<x tiff:Orientation=\"6\"/><tiff:Orientation>8</tiff:Orientation>".to_vec();
        set_xmp_orientation(&mut xmp);
        assert_eq!(
            xmp,
            b"<x tiff:Orientation=\"1\"/><tiff:Orientation>1</tiff:Orientation>"
        );
    }

    /// Both forms, both quotes, values of different lengths; an unpaired property and a
    /// longer name that starts with a paired one left alone; nothing swapped by a half turn.
    #[test]
    fn a_quarter_turn_swaps_each_axis_pair_of_the_xmp() {
        let packet = "<d exif:PixelXDimension='4000' exif:PixelYDimension='300' \
             tiff:Orientation=\"6\"/><tiff:ImageWidth>640</tiff:ImageWidth>\
             <tiff:ImageLength>1000</tiff:ImageLength><tiff:ImageWidthX>7</tiff:ImageWidthX>\
             <tiff:XResolution>300/1</tiff:XResolution><tiff:YResolution>72/1</tiff:YResolution>\
             <exif:FocalPlaneXResolution>9/2</exif:FocalPlaneXResolution>";
        let mut xmp = packet.as_bytes().to_vec();
        make_xmp_upright(&mut xmp, 6);
        let expected = packet
            .replace("'4000'", "'T'")
            .replace("'300'", "'4000'")
            .replace("'T'", "'300'")
            .replace("\"6\"", "\"1\"")
            .replace(">640<", ">T<")
            .replace(">1000<", ">640<")
            .replace(">T<", ">1000<")
            .replace(">300/1<", ">T<")
            .replace(">72/1<", ">300/1<")
            .replace(">T<", ">72/1<");
        assert_eq!(String::from_utf8(xmp).unwrap(), expected);
        let mut xmp = packet.as_bytes().to_vec();
        make_xmp_upright(&mut xmp, 3);
        assert_eq!(
            String::from_utf8(xmp).unwrap(),
            packet.replace("\"6\"", "\"1\"")
        );
    }

    /// A big-endian EXIF block whose IFD0 holds Make (ASCII, 4 bytes inline) and Orientation.
    fn exif_with_orientation(orientation: u16) -> Vec<u8> {
        let mut b = b"MM\0\x2a\0\0\0\x08".to_vec();
        b.extend(2u16.to_be_bytes());
        b.extend([0x01, 0x0F, 0, 2, 0, 0, 0, 4]);
        b.extend(b"ABC\0");
        b.extend([0x01, 0x12, 0, 3, 0, 0, 0, 1]);
        b.extend(orientation.to_be_bytes());
        b.extend([0, 0, 0, 0, 0, 0]);
        b
    }

    #[test]
    fn exif_orientation_is_read_and_rewritten_in_place() {
        let mut exif = exif_with_orientation(6);
        assert_eq!(exif_orientation(&exif), Some(6));
        let before = exif.len();
        set_exif_orientation(&mut exif, 1);
        assert_eq!((exif_orientation(&exif), exif.len()), (Some(1), before));
        assert_eq!(exif_orientation(b"MM\0\x2a\0\0\0\x08\0\0"), None);
    }

    /// A little-endian block as a camera writes one: IFD0 of XResolution 300/1,
    /// YResolution 150/1 and the Exif pointer, linked to an IFD1; an Exif directory of a
    /// SHORT PixelXDimension and a LONG PixelYDimension.
    fn camera_block() -> Vec<u8> {
        let mut b = b"II\x2a\0\x08\0\0\0".to_vec();
        let entry = |b: &mut Vec<u8>, tag: u16, ty: u16, count: u32, value: u32| {
            b.extend(tag.to_le_bytes());
            b.extend(ty.to_le_bytes());
            b.extend(count.to_le_bytes());
            b.extend(value.to_le_bytes());
        };
        // IFD0 at 8: 3 entries, then the link (at 8 + 2 + 36 = 46) to IFD1 at 66.
        b.extend(3u16.to_le_bytes());
        entry(&mut b, X_RESOLUTION, 5, 1, 50);
        entry(&mut b, Y_RESOLUTION, 5, 1, 58);
        entry(&mut b, EXIF_IFD, LONG, 1, 68);
        b.extend(66u32.to_le_bytes());
        // The rationals at 50 and 58.
        b.extend([300u32, 1, 150, 1].iter().flat_map(|v| v.to_le_bytes()));
        // IFD1 at 66: no entries (a stand-in), no link.
        b.extend(0u16.to_le_bytes());
        // Exif directory at 68.
        b.extend(2u16.to_le_bytes());
        entry(&mut b, PIXEL_X_DIMENSION, SHORT, 1, 48);
        entry(&mut b, PIXEL_Y_DIMENSION, LONG, 1, 32);
        b.extend(0u32.to_le_bytes());
        b
    }

    #[test]
    fn a_block_turned_upright_says_the_upright_size_and_resolutions_and_links_no_thumbnail() {
        let mut exif = camera_block();
        let before = exif.len();
        make_upright(&mut exif, 6, (32, 70_000));
        let block = Block::of(&exif).unwrap();
        let ifd0 = block.ifd0(&exif).unwrap();
        let rational = |tag| {
            let at = block.entry(&exif, ifd0, tag).unwrap();
            let to = block.u32(&exif, at + 8).unwrap() as usize;
            block.u32(&exif, to).unwrap()
        };
        assert_eq!((rational(X_RESOLUTION), rational(Y_RESOLUTION)), (150, 300));
        let ifd = block.exif_ifd(&exif, ifd0).unwrap();
        let size = |tag| {
            let at = block.entry(&exif, ifd, tag).unwrap();
            (
                block.u16(&exif, at + 2).unwrap(),
                block.u32(&exif, at + 8).unwrap(),
            )
        };
        // A SHORT that holds the value stays a SHORT; one that cannot becomes a LONG.
        assert_eq!(size(PIXEL_X_DIMENSION), (SHORT, 32));
        assert_eq!(size(PIXEL_Y_DIMENSION), (LONG, 70_000));
        assert_eq!(block.u32(&exif, 46), Some(0), "IFD1 unlinked");
        assert_eq!(exif.len(), before);
        // Upright already: the size is set, the axes and the thumbnail left.
        let mut exif = camera_block();
        make_upright(&mut exif, 1, (48, 32));
        assert_eq!(block.u32(&exif, 46), Some(66));
        assert_eq!(block.u32(&exif, 50), Some(300));
        // A block of no Exif directory, or none at all, is left whole.
        let mut bare = b"II\x2a\0\x08\0\0\0\0\0".to_vec();
        make_upright(&mut bare, 8, (1, 1));
        assert_eq!(bare, b"II\x2a\0\x08\0\0\0\0\0");
        make_upright(&mut [], 8, (1, 1));
    }
}
