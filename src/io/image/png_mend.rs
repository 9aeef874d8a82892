//! PNGs whose cICP chunk gives matrix coefficients other than 0. PNG's samples are RGB, so the
//! 3rd edition says the value shall be 0; its drafts called 1 the default and told readers to
//! take 0 whatever the chunk said, and tools written to them (among them the spec editors' own
//! cICP inserter, until March 2025) wrote 1. libpng and OpenImageIO read such files; the png
//! crate refuses the whole image as invalid data. shutter reads them as the drafts said: the
//! matrix coefficients taken as 0 (the bytes mended in memory, the file untouched), the rest
//! of the chunk honoured, and a note says so.

use std::io::{BufRead, BufReader, Cursor, Read, Seek, SeekFrom};
use std::path::Path;

/// An input's bytes: the file, or a PNG mended in memory ([`mended`]).
pub enum Source {
    File(BufReader<std::fs::File>),
    Mended(Cursor<Vec<u8>>),
}

impl Read for Source {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        match self {
            Source::File(f) => f.read(buf),
            Source::Mended(c) => c.read(buf),
        }
    }
}

impl BufRead for Source {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        match self {
            Source::File(f) => f.fill_buf(),
            Source::Mended(c) => c.fill_buf(),
        }
    }
    fn consume(&mut self, amount: usize) {
        match self {
            Source::File(f) => f.consume(amount),
            Source::Mended(c) => c.consume(amount),
        }
    }
}

impl Seek for Source {
    fn seek(&mut self, to: SeekFrom) -> std::io::Result<u64> {
        match self {
            Source::File(f) => f.seek(to),
            Source::Mended(c) => c.seek(to),
        }
    }
}

/// The input at `path` to decode: the file itself, or, for a PNG whose cICP gives matrix
/// coefficients other than 0, its bytes with them 0.
pub fn source(path: &Path) -> Result<Source, String> {
    let file = crate::io::input::open_input(path).map_err(|e| e.to_string())?;
    let mut file = BufReader::new(file);
    if cicp_matrix(&mut file).is_some() {
        let mut bytes = Vec::new();
        file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
        file.read_to_end(&mut bytes).map_err(|e| e.to_string())?;
        if mend(&mut bytes).is_some() {
            return Ok(Source::Mended(Cursor::new(bytes)));
        }
    }
    file.seek(SeekFrom::Start(0)).map_err(|e| e.to_string())?;
    Ok(Source::File(file))
}

/// The matrix coefficients a PNG's cICP gives, where they are not 0 (the first cICP before the
/// image data, as the png crate reads it); `None` for any other file. Reads the chunks' heads
/// only, seeking past their data.
pub fn cicp_matrix(file: &mut (impl Read + Seek)) -> Option<u8> {
    let mut head = [0u8; 8];
    file.read_exact(&mut head).ok()?;
    if head != *b"\x89PNG\r\n\x1a\n" {
        return None;
    }
    loop {
        file.read_exact(&mut head).ok()?;
        let length = u32::from_be_bytes(head[..4].try_into().ok()?);
        match &head[4..] {
            b"IDAT" | b"IEND" => return None,
            b"cICP" if length == 4 => {
                let mut data = [0u8; 4];
                file.read_exact(&mut data).ok()?;
                return (data[2] != 0).then_some(data[2]);
            }
            _ => {
                file.seek(SeekFrom::Current(length as i64 + 4)).ok()?;
            }
        }
    }
}

/// Where a PNG is cut short, in words: a chunk that runs past the end of the file, or no IEND
/// chunk before it ends (the header alone reads fine, so a sequence stopped at such a frame
/// after writing the ones before: an outside probe). Reads the chunks' heads only, seeking
/// past their data; `None` for a whole PNG or a file that is not one.
pub fn png_cut_short(path: &Path) -> Option<String> {
    let file = crate::io::input::open_input(path).ok()?;
    let size = file.metadata().ok()?.len();
    let mut file = BufReader::new(file);
    let mut head = [0u8; 8];
    file.read_exact(&mut head).ok()?;
    if head != *b"\x89PNG\r\n\x1a\n" {
        return None;
    }
    let mut at = 8u64;
    loop {
        if at + 8 > size {
            return Some(format!(
                "the file is truncated: it ends at byte {size} with no IEND chunk"
            ));
        }
        file.read_exact(&mut head).ok()?;
        let length = u64::from(u32::from_be_bytes(head[..4].try_into().ok()?));
        let end = at + 12 + length;
        if end > size {
            let kind = String::from_utf8_lossy(&head[4..]);
            return Some(format!(
                "the file is truncated: its {kind} chunk at byte {at} needs {} bytes, the \
                 file has {size}",
                end
            ));
        }
        if &head[4..] == b"IEND" {
            return None;
        }
        file.seek_relative(length as i64 + 4).ok()?;
        at = end;
    }
}

/// Sets the matrix coefficients of a PNG's first cICP (before its image data) to 0 and its
/// CRC to match, in `bytes`; the value it held, where that was not 0.
fn mend(bytes: &mut [u8]) -> Option<u8> {
    let mut at = 8;
    loop {
        let length = u32::from_be_bytes(bytes.get(at..at + 4)?.try_into().ok()?) as usize;
        let kind = bytes.get(at + 4..at + 8)?;
        match kind {
            b"IDAT" | b"IEND" => return None,
            b"cICP" if length == 4 => {
                let chunk = bytes.get_mut(at + 4..at + 16)?;
                let matrix = chunk[6];
                if matrix == 0 {
                    return None;
                }
                chunk[6] = 0;
                let crc = crc32(&chunk[..8]);
                chunk[8..].copy_from_slice(&crc.to_be_bytes());
                return Some(matrix);
            }
            _ => at = at.checked_add(length)?.checked_add(12)?,
        }
    }
}

/// CRC-32 as PNG computes it over a chunk's type and data (ISO 3309; PNG 3rd ed., 5.5).
fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= b as u32;
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xEDB8_8320
            } else {
                crc >> 1
            };
        }
    }
    !crc
}

#[cfg(test)]
mod tests {
    use super::*;

    /// PNG's own example (PNG 3rd ed., D: the IEND chunk's CRC is AE 42 60 82).
    #[test]
    fn the_crc_is_pngs() {
        assert_eq!(crc32(b"IEND"), 0xAE42_6082);
    }
}
