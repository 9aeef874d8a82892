//! A TIFF cut short, named as such. A file that ends inside its image directory, or before
//! the end of the strips or tiles that directory points to, is "truncated", as a cut PNG
//! ([`super::png_mend::png_cut_short`]), JPEG or EXR is; the decoders said only what their
//! read met at the cut ("failed to fill whole buffer", "incomplete deflate stream"), which
//! named no cause (an outside tester's deflate TIFF). Checked with the header
//! ([`super::probe`]), from the directory alone, no pixel decoded: a cut frame stops a
//! sequence before any frame of it is written, as a cut PNG does.

use std::io::ErrorKind;
use std::path::Path;

use tiff::decoder::Decoder;
use tiff::tags::Tag;
use tiff::TiffError;

/// Why the TIFF at `path` is truncated: it ends inside its first image directory (a writer
/// that puts the directory after the image data, as libtiff and the tiff crate do, loses it
/// first), or before the last byte of the strips or tiles that directory points to. `None`
/// for a whole TIFF, a file that is not one, and a directory that is bad in another way (the
/// decoder's error about it then stands). `strips_whole`: the strips must end within the
/// file (said after a decode failed); else only a strip that begins past its end counts (the
/// header's check: some writers overstate StripByteCounts, which libtiff and the tiff crate
/// read past, so a count alone refuses no file that decodes).
pub(super) fn tiff_cut_short(path: &Path, strips_whole: bool) -> Option<String> {
    let file = crate::io::input::open_input(path).ok()?;
    let size = file.metadata().ok()?.len();
    let mut decoder = match Decoder::new(std::io::BufReader::new(file)) {
        Ok(decoder) => decoder,
        Err(TiffError::IoError(e)) if e.kind() == ErrorKind::UnexpectedEof => {
            return Some(format!(
                "the file is truncated: it ends at byte {size}, before the end of its image \
                 directory"
            ));
        }
        Err(_) => return None,
    };
    let (offsets, counts) = match decoder.get_tag_u64_vec(Tag::StripOffsets) {
        Ok(offsets) => (offsets, decoder.get_tag_u64_vec(Tag::StripByteCounts).ok()?),
        Err(_) => (
            decoder.get_tag_u64_vec(Tag::TileOffsets).ok()?,
            decoder.get_tag_u64_vec(Tag::TileByteCounts).ok()?,
        ),
    };
    let end = (offsets.iter().zip(&counts))
        .filter(|(_, &count)| count > 0)
        .map(|(&offset, &count)| match strips_whole {
            true => offset.saturating_add(count),
            false => offset.saturating_add(1),
        })
        .max()?;
    (end > size).then(|| {
        format!(
            "the file is truncated: its image data runs to byte {end}, the file ends at byte \
             {size}"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A whole TIFF passes; cut through its directory (written after the data), or with a
    /// directory that places its strip past the end, it is named truncated.
    #[test]
    fn a_tiff_cut_anywhere_is_truncated_and_a_whole_one_is_not() {
        let dir = tempfile::tempdir().unwrap();
        let mut bytes = std::io::Cursor::new(Vec::new());
        let pixels: Vec<u8> = (0..16 * 16 * 3).map(|i| (i * 37 % 251) as u8).collect();
        (tiff::encoder::TiffEncoder::new(&mut bytes).unwrap())
            .write_image::<tiff::encoder::colortype::RGB8>(16, 16, &pixels)
            .unwrap();
        let bytes = bytes.into_inner();
        let path = dir.path().join("t.tif");
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(tiff_cut_short(&path, true), None);
        // The tiff crate writes its directory after the data: cut, it is lost.
        std::fs::write(&path, &bytes[..bytes.len() - 20]).unwrap();
        let why = tiff_cut_short(&path, false).expect("a cut directory");
        assert!(
            why.contains("truncated") && why.contains("directory"),
            "{why}"
        );
        // A directory that places its strip past the end: the data was cut.
        let ifd = u32::from_le_bytes(bytes[4..8].try_into().unwrap()) as usize;
        let entries = u16::from_le_bytes([bytes[ifd], bytes[ifd + 1]]) as usize;
        let at = (0..entries)
            .map(|e| ifd + 2 + 12 * e)
            .find(|&at| u16::from_le_bytes([bytes[at], bytes[at + 1]]) == 279)
            .expect("StripByteCounts");
        let mut longer = bytes.clone();
        longer[at + 8..at + 12].copy_from_slice(&(bytes.len() as u32 * 2).to_le_bytes());
        std::fs::write(&path, &longer).unwrap();
        let why = tiff_cut_short(&path, true).expect("cut data");
        assert!(
            why.contains("truncated") && why.contains("image data"),
            "{why}"
        );
        // A count overstated, the strip beginning inside the file: not refused by the
        // header's check (writers overstate counts; the decoder reads what it needs).
        assert_eq!(tiff_cut_short(&path, false), None);
        // A strip that begins past the end: the data was cut, said by the header's check.
        let at = (0..entries)
            .map(|e| ifd + 2 + 12 * e)
            .find(|&at| u16::from_le_bytes([bytes[at], bytes[at + 1]]) == 273)
            .expect("StripOffsets");
        let mut past = bytes.clone();
        past[at + 8..at + 12].copy_from_slice(&(bytes.len() as u32 + 8).to_le_bytes());
        std::fs::write(&path, &past).unwrap();
        let why = tiff_cut_short(&path, false).expect("data past the end");
        assert!(why.contains("truncated"), "{why}");
        // Not a TIFF: not this check's to say.
        std::fs::write(&path, b"not a tiff at all").unwrap();
        assert_eq!(tiff_cut_short(&path, true), None);
    }
}
