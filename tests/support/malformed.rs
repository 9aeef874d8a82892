//! The malformed-file corpus (`fixtures/malformed/`): small files, each named after the one
//! defect it carries, made from valid files written by shutter's own writers and damaged in
//! one place. `SHUTTER_BLESS=1 cargo test --test integration malformed` writes them again.

use std::io::Cursor;

use shutter::frame::Windows;
use shutter::io::exr::{write_channels, ExrOptions};
use shutter::io::image::{write_color, ImageFormat};

use super::noise;

const W: usize = 16;
const H: usize = 12;

/// A valid RGBA EXR of smooth ramps, W × H, with `compression`. Smooth, so that ZIP
/// really compresses it: EXR stores a chunk raw when compression would not shrink it, and
/// damage to raw samples is undetectable by any reader.
pub fn exr(compression: exr::compression::Compression) -> Vec<u8> {
    exr_stored(compression, false)
}

/// [`exr`], its channels stored half where `half`.
pub fn exr_stored(compression: exr::compression::Compression, half: bool) -> Vec<u8> {
    let n = W * H;
    let channels = ["R", "G", "B", "A"]
        .iter()
        .enumerate()
        .map(|(k, name)| {
            let ramp = (0..n).map(|i| ((i % W) + k) as f32 / W as f32).collect();
            (name.to_string(), ramp)
        })
        .collect();
    let mut bytes = Cursor::new(Vec::new());
    write_channels(
        &mut bytes,
        W,
        H,
        Windows::full(W, H),
        channels,
        ExrOptions { compression, half },
    )
    .unwrap();
    bytes.into_inner()
}

/// A valid PNG, JPEG or TIFF of noise, W × H.
pub fn image(format: ImageFormat) -> Vec<u8> {
    let n = W * H;
    let (r, g, b) = (
        noise(n, 1, 0.0, 1.0),
        noise(n, 2, 0.0, 1.0),
        noise(n, 3, 0.0, 1.0),
    );
    let mut bytes = Cursor::new(Vec::new());
    write_color(&mut bytes, format, W, H, [&r, &g, &b], None, false, true).unwrap();
    bytes.into_inner()
}

/// The position of attribute `name`'s value in an EXR header (after its name, type name and
/// size).
pub fn attribute_value(bytes: &[u8], name: &str, kind: &str) -> usize {
    let key = [name.as_bytes(), b"\0", kind.as_bytes(), b"\0"].concat();
    let at = bytes
        .windows(key.len())
        .position(|w| w == key.as_slice())
        .unwrap_or_else(|| panic!("no {name} attribute"));
    at + key.len() + 4
}

/// The byte position of a single-part EXR's offset table of `chunks` entries: the first
/// entry points just past the table.
pub fn offset_table(bytes: &[u8], chunks: usize) -> usize {
    (8..bytes.len() - 8)
        .find(|&p| {
            u64::from_le_bytes(bytes[p..p + 8].try_into().unwrap()) == (p + 8 * chunks) as u64
        })
        .expect("an offset table")
}

fn entry(bytes: &[u8], table: usize, k: usize) -> usize {
    u64::from_le_bytes(bytes[table + 8 * k..table + 8 * k + 8].try_into().unwrap()) as usize
}

/// CRC-32 (ISO-HDLC, as PNG uses), bit by bit: small and independent of any crate.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
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

/// A PNG whose IHDR (CRC fixed) declares `size` × `size`.
pub fn png_declaring(size: u32) -> Vec<u8> {
    let mut bytes = image(ImageFormat::Png);
    // Signature (8), length (4), "IHDR" (4), width (4), height (4), ... CRC after 13 bytes.
    assert_eq!(&bytes[12..16], b"IHDR");
    bytes[16..20].copy_from_slice(&size.to_be_bytes());
    bytes[20..24].copy_from_slice(&size.to_be_bytes());
    let crc = crc32(&bytes[12..29]);
    bytes[29..33].copy_from_slice(&crc.to_be_bytes());
    bytes
}

/// A JPEG whose frame header declares `size` × `size`.
pub fn jpeg_declaring(size: u16) -> Vec<u8> {
    let mut bytes = image(ImageFormat::Jpeg);
    let sof = bytes
        .windows(2)
        .position(|w| w[0] == 0xFF && (0xC0..=0xC2).contains(&w[1]))
        .unwrap();
    // FF Cn, length (2), precision (1), height (2), width (2).
    bytes[sof + 5..sof + 7].copy_from_slice(&size.to_be_bytes());
    bytes[sof + 7..sof + 9].copy_from_slice(&size.to_be_bytes());
    bytes
}

/// An uncompressed EXR (one scan line per chunk) with every table entry pointing at the
/// first chunk.
pub fn exr_offsets_at_one_chunk() -> Vec<u8> {
    let mut bytes = exr(exr::compression::Compression::Uncompressed);
    let table = offset_table(&bytes, H);
    let first: [u8; 8] = bytes[table..table + 8].try_into().unwrap();
    for k in 1..H {
        bytes[table + 8 * k..table + 8 * k + 8].copy_from_slice(&first);
    }
    bytes
}

/// An uncompressed EXR whose last chunk names line `y`.
pub fn exr_chunk_at_line(y: i32) -> Vec<u8> {
    let mut bytes = exr(exr::compression::Compression::Uncompressed);
    let table = offset_table(&bytes, H);
    let last = entry(&bytes, table, H - 1);
    bytes[last..last + 4].copy_from_slice(&y.to_le_bytes());
    bytes
}

/// An EXR with `attribute`'s first value byte set to `value`.
fn exr_with_byte(name: &str, kind: &str, offset: usize, value: u8) -> Vec<u8> {
    let mut bytes = exr(exr::compression::Compression::ZIP16);
    let at = attribute_value(&bytes, name, kind) + offset;
    bytes[at] = value;
    bytes
}

/// Every file of the corpus, by name.
pub fn corpus() -> Vec<(&'static str, Vec<u8>)> {
    use exr::compression::Compression;
    let zip = exr(Compression::ZIP16);
    let zip_table = offset_table(&zip, H.div_ceil(16));
    let mut files: Vec<(&'static str, Vec<u8>)> = vec![
        ("empty.exr", Vec::new()),
        ("exr-bad-magic.exr", b"not an OpenEXR file".to_vec()),
        ("exr-cut-in-the-header.exr", zip[..zip_table / 2].to_vec()),
        (
            "exr-cut-in-the-offset-table.exr",
            zip[..zip_table + 4].to_vec(),
        ),
        ("exr-cut-in-a-chunk.exr", zip[..zip.len() - 40].to_vec()),
        (
            "exr-offsets-all-at-one-chunk.exr",
            exr_offsets_at_one_chunk(),
        ),
        (
            "exr-chunk-outside-the-data-window.exr",
            exr_chunk_at_line(1000),
        ),
        ("exr-chunk-off-a-block-start.exr", exr_chunk_at_line(-3)),
        (
            "exr-line-order-out-of-range.exr",
            exr_with_byte("lineOrder", "lineOrder", 0, 7),
        ),
        (
            "exr-compression-out-of-range.exr",
            exr_with_byte("compression", "compression", 0, 200),
        ),
    ];
    // Channels A, B, G, R listed as R, B, G, A.
    let mut unsorted = zip.clone();
    let list = attribute_value(&unsorted, "channels", "chlist");
    unsorted.swap(list, list + 18 * 3);
    files.push(("exr-channels-not-sorted.exr", unsorted));
    // xMin beyond xMax.
    let mut inverted = zip.clone();
    let at = attribute_value(&inverted, "dataWindow", "box2i");
    inverted[at..at + 4].copy_from_slice(&100i32.to_le_bytes());
    files.push(("exr-data-window-inverted.exr", inverted));
    // A data window of 20000 × 20000 over the chunks of 16 × 12.
    let mut huge = zip.clone();
    let at = attribute_value(&huge, "dataWindow", "box2i");
    huge[at + 8..at + 12].copy_from_slice(&19999i32.to_le_bytes());
    huge[at + 12..at + 16].copy_from_slice(&19999i32.to_le_bytes());
    files.push(("exr-declares-20000x20000.exr", huge));
    // A chunk's size beyond the file.
    let mut oversized = zip.clone();
    let first = entry(&oversized, zip_table, 0);
    oversized[first + 4..first + 8].copy_from_slice(&i32::MAX.to_le_bytes());
    files.push(("exr-chunk-size-beyond-the-file.exr", oversized));
    // Compressed data damaged in the middle (found only by decoding).
    let mut damaged = zip.clone();
    let middle = first + 8 + (zip.len() - first - 8) / 2;
    for b in &mut damaged[middle..middle + 16] {
        *b ^= 0x5A;
    }
    files.push(("exr-zip-data-damaged.exr", damaged));
    // A DWAB block (half RGB: DWA's lossy sections) whose header counts 2⁴⁶ DC coefficients,
    // more than any block holds: the exr crate allocated what it said, and the process
    // aborted (exit 134) where it should refuse the file.
    let mut dwa = exr_stored(Compression::DWAB(None), true);
    let first = entry(&dwa, offset_table(&dwa, 1), 0);
    // The chunk's line and size, then the DWA header's eleven counters; the DC count is the
    // tenth.
    dwa[first + 8 + 72..first + 8 + 80].copy_from_slice(&(1u64 << 46).to_le_bytes());
    files.push(("exr-dwa-count-beyond-the-block.exr", dwa));
    files.push(("png-declares-20000x20000.png", png_declaring(20000)));
    let png = image(ImageFormat::Png);
    files.push(("png-cut-short.png", png[..png.len() * 2 / 3].to_vec()));
    files.push(("jpeg-declares-12000x12000.jpg", jpeg_declaring(12000)));
    let jpeg = image(ImageFormat::Jpeg);
    files.push(("jpeg-cut-short.jpg", jpeg[..jpeg.len() * 2 / 3].to_vec()));
    let tiff = image(ImageFormat::Tiff);
    files.push(("tiff-cut-short.tif", tiff[..tiff.len() / 2].to_vec()));
    files
}
