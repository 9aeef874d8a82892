//! An EXR's header attributes put in name order, in place, after the exr crate wrote them in
//! the order of a `HashMap` (`exr_like::write_like`): the same frame then gives the same
//! bytes, as OpenEXR's own library writes them in name order.

use std::io::{Read, Seek, SeekFrom, Write};

/// Puts the attributes of every header of the EXR in `file` in name order, in place, and
/// declares RANDOM_Y the line order of each part `random_y` marks (its blocks are in
/// increasing order, which a random order allows). Every attribute is a self-contained
/// record (name, type, size, value), so reordering them, or changing the one byte of a
/// `lineOrder`, leaves each header, and so the offset tables after them, the same length.
pub fn sort_attributes(
    file: &mut (impl Read + Write + Seek),
    random_y: &[bool],
) -> std::io::Result<()> {
    /// OpenEXR's `RANDOM_Y` in a `lineOrder` attribute.
    const RANDOM_Y: u8 = 2;
    const MULTIPART: u32 = 0x1000;
    let invalid = |what: &str| std::io::Error::new(std::io::ErrorKind::InvalidData, what);
    file.seek(SeekFrom::Start(0))?;
    let mut bytes = Vec::new();
    // Headers are small; read them in growing steps until the last one ends.
    let mut step = 1 << 16;
    loop {
        let have = bytes.len();
        Read::by_ref(file).take(step).read_to_end(&mut bytes)?;
        let complete = bytes.len() < have + step as usize;
        if let Some(end) = headers_end(&bytes)? {
            bytes.truncate(end);
            break;
        }
        if complete {
            return Err(invalid("the headers do not end"));
        }
        step *= 2;
    }
    let version = u32::from_le_bytes(bytes[4..8].try_into().expect("eight bytes"));
    let mut at = 8;
    let mut sorted = bytes[..8].to_vec();
    for part in 0.. {
        let records = header_records(&bytes, at)?;
        if random_y.get(part).copied().unwrap_or(false) {
            let line_order = records
                .iter()
                .find(|r| &bytes[r.start..r.name_end] == b"lineOrder")
                .ok_or_else(|| invalid("a part has no lineOrder"))?;
            // The value is the record's last byte (size 1).
            bytes[line_order.end - 1] = RANDOM_Y;
        }
        let end = records.last().map_or(at, |r| r.end);
        let mut order: Vec<_> = records.iter().collect();
        order.sort_by_key(|r| &bytes[r.start..r.name_end]);
        for r in order {
            sorted.extend_from_slice(&bytes[r.start..r.end]);
        }
        sorted.push(0);
        at = end + 1;
        if version & MULTIPART == 0 || bytes.get(at) == Some(&0) {
            break;
        }
    }
    sorted.extend_from_slice(&bytes[at..]);
    debug_assert_eq!(sorted.len(), bytes.len());
    file.seek(SeekFrom::Start(0))?;
    file.write_all(&sorted)?;
    file.seek(SeekFrom::End(0))?;
    Ok(())
}

/// One attribute's bytes: `start..end`, its name `start..name_end`.
struct Record {
    start: usize,
    name_end: usize,
    end: usize,
}

/// The attributes of the header that starts at `at` (up to its terminating zero byte).
fn header_records(bytes: &[u8], mut at: usize) -> std::io::Result<Vec<Record>> {
    let short = || std::io::Error::new(std::io::ErrorKind::UnexpectedEof, "a header is cut off");
    let mut records = Vec::new();
    while *bytes.get(at).ok_or_else(short)? != 0 {
        let start = at;
        let zero = |from: usize| {
            bytes[from.min(bytes.len())..]
                .iter()
                .position(|&b| b == 0)
                .map(|p| from + p)
                .ok_or_else(short)
        };
        let name_end = zero(start)?;
        let type_end = zero(name_end + 1)?;
        let size_at = type_end + 1;
        let size = bytes.get(size_at..size_at + 4).ok_or_else(short)?;
        let size = i32::from_le_bytes(size.try_into().expect("four bytes"));
        let size = usize::try_from(size).map_err(|_| short())?;
        let end = size_at + 4 + size;
        if end > bytes.len() {
            return Err(short());
        }
        records.push(Record {
            start,
            name_end,
            end,
        });
        at = end;
    }
    Ok(records)
}

/// Where the headers of the file whose first bytes are `bytes` end (after the last header's
/// terminator, and the empty header that ends a multi-part file's list), or `None` when
/// `bytes` stops before that.
fn headers_end(bytes: &[u8]) -> std::io::Result<Option<usize>> {
    if bytes.len() < 8 {
        return Ok(None);
    }
    let multipart = u32::from_le_bytes(bytes[4..8].try_into().expect("eight bytes")) & 0x1000 != 0;
    let mut at = 8;
    loop {
        let records = match header_records(bytes, at) {
            Ok(records) => records,
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(None),
            Err(e) => return Err(e),
        };
        at = records.last().map_or(at, |r| r.end) + 1;
        if !multipart {
            return Ok(Some(at));
        }
        match bytes.get(at) {
            None => return Ok(None),
            Some(0) => return Ok(Some(at + 1)),
            Some(_) => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::image::Encoding;
    use exr::meta::attribute::{AttributeValue, IntegerBounds, Text};
    use exr::meta::header::{ImageAttributes, LayerAttributes};
    use exr::meta::MetaData;
    use exr::prelude::WritableImage;
    use std::fs::File;

    /// A two-part file whose parts carry custom attributes, written by the exr crate.
    fn two_parts(path: &std::path::Path) {
        use exr::image::{AnyChannel, AnyChannels, FlatSamples, Image, Layer};
        let layer = |name: &str, attributes: &[(&str, i32)]| {
            let mut own = LayerAttributes::named(name);
            for &(key, value) in attributes {
                own.other
                    .insert(Text::from(key), AttributeValue::I32(value));
            }
            Layer::new(
                (3, 2),
                own,
                Encoding::FAST_LOSSLESS,
                AnyChannels::sort(
                    vec![AnyChannel::new(
                        Text::from("Y"),
                        FlatSamples::F32(vec![0.5; 6]),
                    )]
                    .into(),
                ),
            )
        };
        let image = Image::from_layers(
            ImageAttributes::new(IntegerBounds::from_dimensions((3, 2))),
            vec![
                layer("beauty", &[("zeta", 1), ("alpha", 2), ("mid", 3)]),
                layer("data", &[("b", 4), ("a", 5)]),
            ],
        );
        image.write().to_file(path).unwrap();
    }

    /// The attribute names of each header, in the order the file holds them.
    fn names_in_order(bytes: &[u8]) -> Vec<Vec<String>> {
        let mut at = 8;
        let mut headers = Vec::new();
        loop {
            let records = header_records(bytes, at).unwrap();
            headers.push(
                records
                    .iter()
                    .map(|r| String::from_utf8_lossy(&bytes[r.start..r.name_end]).into_owned())
                    .collect(),
            );
            at = records.last().unwrap().end + 1;
            if bytes[at] == 0 {
                return headers;
            }
        }
    }

    #[test]
    fn a_multi_part_files_attributes_are_put_in_name_order_and_read_the_same() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.exr");
        two_parts(&path);
        let before = MetaData::read_from_file(&path, false).unwrap();
        let length = std::fs::metadata(&path).unwrap().len();
        let mut file = File::options().read(true).write(true).open(&path).unwrap();
        sort_attributes(&mut file, &[]).unwrap();
        drop(file);
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(bytes.len() as u64, length);
        let headers = names_in_order(&bytes);
        assert_eq!(headers.len(), 2);
        for names in &headers {
            let mut sorted = names.clone();
            sorted.sort();
            assert_eq!(names, &sorted);
        }
        assert!(headers[0].contains(&"zeta".to_string()) && headers[1].contains(&"a".to_string()));
        // The same headers, and the pixels still where the offset tables say.
        let after = MetaData::read_from_file(&path, false).unwrap();
        assert_eq!(before.headers, after.headers);
        let image = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
        assert_eq!(image.layer_data.len(), 2);
    }
}
