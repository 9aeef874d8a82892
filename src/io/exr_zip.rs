//! Writes an EXR image as the exr crate's `to_buffered` does, but deflates its ZIP and ZIPS
//! blocks with libdeflate (the `libdeflater` crate), the library OpenEXR's own ZIP codec has
//! used since 3.2, instead of the exr crate's miniz_oxide.
//!
//! Why: an EXR output's deflate was a fifth to a quarter of a whole `blur` of a 1080p frame
//! (the bench's `moving` frame, `perf`: 21–26 % of the samples in miniz_oxide's deflate)
//! and most of the I/O floor. libdeflate at level 7 deflates the same blocks 1.4–2.6× faster
//! than miniz_oxide at the exr crate's level 4, the files no larger than they were (BENCHMARKS.md,
//! "EXR output: ZIP through libdeflate").
//!
//! In: an exr `Image` whose layers can be written, the writer, and whether the exr crate's
//! compatibility checks run. Out: the file, blocks in the order its line order asks for (the
//! same bytes for any thread count: each block is deflated alone). A ZIP block is the
//! OpenEXR format's: the block's little-endian bytes split into even and odd bytes, each byte
//! then stored as its difference from the one before plus 128, the whole deflated with a zlib
//! wrapper, and the raw bytes stored instead where that is not smaller. Every other
//! compression, and a big-endian machine, goes through the exr crate's own code.
//!
//! Reading, likewise: [`decompress_chunk`] inflates a deflated ZIP or ZIPS block with
//! libdeflate and undoes the predictor here, eight bytes at a time; every other block, and
//! any that libdeflate refuses, is decompressed by the exr crate as before.

use std::cell::RefCell;
use std::io::{Seek, Write};

use exr::block::chunk::{
    Chunk, CompressedBlock, CompressedScanLineBlock, CompressedTileBlock, TileCoordinates,
};
use exr::block::writer::ChunksWriter;
use exr::block::{BlockIndex, UncompressedBlock};
use exr::compression::Compression;
use exr::error::Error;
use exr::image::write::layers::{LayersWriter, WritableLayers};
use exr::image::Image;
use exr::math::Vec2;
use exr::meta::header::Header;
use exr::meta::{BlockDescription, MetaData};
use rayon::prelude::*;

/// The deflate level. Measured on the blocks of nine frames (`examples/deflate_levels.rs`:
/// rendered, blurred, noise, flat procedural colour, vectors, depth) against miniz_oxide at 4,
/// which wrote them before: libdeflate at 4 (OpenEXR's own default) is the fastest but writes
/// flat frames up to a third larger (the bench's checker 0.0158 of the raw bytes against
/// 0.0119) and a blurred truth scene 3.8 % larger; at 6, the blurred pan 7 % and its depth
/// 18 % larger; at 7 every frame but a velocity plane of 0.2 % comes out no larger (the
/// checker 35 % smaller), deflated 1.4–2.6× faster than before. Chosen by that worst case.
const LEVEL: i32 = 7;

/// Blocks deflated at once per thread of the pool, then written in order before the next
/// batch: enough that one slow block leaves the other threads work, few enough that a
/// frame's blocks are never all held (at most this many deflated blocks a thread).
const BLOCKS_PER_THREAD: usize = 4;

/// Writes `image` to `write` (buffered), as `image.write().to_buffered(write)` does with the
/// compatibility checks on where `checked`. Returns how many DWA blocks were written with
/// their highlights capped, and the lowest cap ([`crate::io::exr_dwa::Capped`]), if any were.
pub fn write<L>(
    image: &Image<L>,
    write: impl Write + Seek,
    checked: bool,
) -> exr::error::Result<Option<(usize, f32)>>
where
    L: for<'a> WritableLayers<'a>,
{
    let headers = image.layer_data.infer_headers(&image.attributes);
    let layers = image.layer_data.create_writer(&headers);
    let capped = crate::io::exr_dwa::Capped::new();
    exr::block::write(write, headers, checked, |meta, chunks| {
        let order: Vec<(usize, BlockIndex)> =
            meta.enumerate_ordered_header_block_indices().collect();
        let batch = (rayon::current_num_threads() * BLOCKS_PER_THREAD).max(1);
        for group in order.chunks(batch) {
            let compressed: Vec<exr::error::Result<(usize, Chunk)>> = group
                .par_iter()
                .map(|&(in_header, index)| {
                    let block = UncompressedBlock {
                        data: layers.extract_uncompressed_block(&meta.headers, index),
                        index,
                    };
                    let chunk = if deflated_here(&meta.headers[index.layer]) {
                        zip_chunk(&meta.headers[index.layer], block)?
                    } else if crate::io::exr_dwa::is_dwa(&meta.headers[index.layer]) {
                        crate::io::exr_dwa::finite_chunk(&meta, block, &capped)?
                    } else {
                        block.compress_to_chunk(&meta.headers)?
                    };
                    Ok((in_header, chunk))
                })
                .collect();
            for result in compressed {
                let (in_header, chunk) = result?;
                chunks.write_chunk(in_header, chunk)?;
            }
        }
        Ok(())
    })?;
    Ok(capped.report())
}

/// Whether a part's blocks are deflated here: ZIP or ZIPS, flat (not deep) data, on a
/// little-endian machine (where a block's bytes in memory are already the file's).
fn deflated_here(header: &Header) -> bool {
    cfg!(target_endian = "little")
        && !header.deep
        && matches!(header.compression, Compression::ZIP1 | Compression::ZIP16)
}

/// One ZIP or ZIPS block as a chunk, laid out as the exr crate's `compress_to_chunk` lays it.
fn zip_chunk(header: &Header, block: UncompressedBlock) -> exr::error::Result<Chunk> {
    let UncompressedBlock { data, index } = block;
    let expected = header.channels.bytes_per_pixel * index.pixel_size.area();
    if data.len() != expected {
        return Err(Error::Invalid(std::borrow::Cow::Owned(format!(
            "block of {} bytes where {expected} were expected",
            data.len()
        ))));
    }
    let packed = deflate(&data);
    // Raw where deflating does not make the block smaller, as OpenEXR stores it.
    let compressed_pixels_le = if packed.len() < data.len() {
        packed
    } else {
        data
    };
    let compressed_block = match header.blocks {
        BlockDescription::ScanLines => {
            let y = i32::try_from(index.pixel_position.y())
                .map_err(|_| Error::Invalid("block position".into()))?;
            CompressedBlock::ScanLine(CompressedScanLineBlock {
                y_coordinate: y + header.own_attributes.layer_position.y(),
                compressed_pixels_le,
            })
        }
        BlockDescription::Tiles(_) => CompressedBlock::Tile(CompressedTileBlock {
            coordinates: TileCoordinates {
                tile_index: index.pixel_position / header.max_block_pixel_size(),
                level_index: index.level,
            },
            compressed_pixels_le,
        }),
    };
    Ok(Chunk {
        layer_index: index.layer,
        compressed_block,
    })
}

thread_local! {
    /// Each thread's compressor (its tables are reused from block to block).
    static COMPRESSOR: RefCell<Option<libdeflater::Compressor>> = const { RefCell::new(None) };
}

/// A block's bytes as OpenEXR's ZIP stores them: split into even and odd bytes, each byte
/// the difference from the one before (plus 128, wrapping), deflated with a zlib wrapper.
fn deflate(bytes: &[u8]) -> Vec<u8> {
    zlib(&predict(bytes))
}

/// `bytes` deflated with a zlib wrapper by this thread's compressor (libdeflate, level
/// [`LEVEL`]): OpenEXR's ZIP blocks, and a TIFF's deflate strips (`image::tiff_write`).
pub fn zlib(predicted: &[u8]) -> Vec<u8> {
    COMPRESSOR.with_borrow_mut(|slot| {
        let compressor = slot.get_or_insert_with(|| {
            libdeflater::Compressor::new(
                libdeflater::CompressionLvl::new(LEVEL).expect("a level libdeflate has"),
            )
        });
        let mut out = vec![0u8; compressor.zlib_compress_bound(predicted.len())];
        let size = compressor
            .zlib_compress(predicted, &mut out)
            .expect("the bound libdeflate gives holds its output");
        out.truncate(size);
        out
    })
}

/// OpenEXR's ZIP predictor: the even bytes then the odd ones, each byte then replaced by its
/// difference from the one before it plus 128 (wrapping; the first kept as it is).
pub fn predict(bytes: &[u8]) -> Vec<u8> {
    let n = bytes.len();
    SPLIT.with_borrow_mut(|split| {
        // Grown, never cleared: every byte of the block's share is written below.
        if split.len() < n {
            split.resize(n, 0);
        }
        let split = &mut split[..n];
        let (even, odd) = split.split_at_mut(n.div_ceil(2));
        split_pairs(bytes, even, odd);
        if n % 2 == 1 {
            even[n / 2] = bytes[n - 1];
        }
        differences(split)
    })
}

thread_local! {
    /// Each thread's split bytes (a block's worth, reused from block to block).
    static SPLIT: RefCell<Vec<u8>> = const { RefCell::new(Vec::new()) };
}

/// The even bytes of `bytes` into `even` and the odd into `odd`, as many pairs as both hold.
/// (Compiled for the CPU at hand: with AVX2 the compiler splits the pairs in lanes, 2.2×
/// as fast on this machine's blocks; for SSE2 alone it does not.)
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn split_pairs(bytes: &[u8], even: &mut [u8], odd: &mut [u8]) {
    for ((pair, e), o) in bytes
        .chunks_exact(2)
        .zip(even.iter_mut())
        .zip(odd.iter_mut())
    {
        *e = pair[0];
        *o = pair[1];
    }
}

/// The first byte, then each byte's difference from the one before it plus 128 (wrapping).
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn differences(bytes: &[u8]) -> Vec<u8> {
    let Some(&first) = bytes.first() else {
        return Vec::new();
    };
    let mut out = Vec::with_capacity(bytes.len());
    out.push(first);
    out.extend(
        bytes[1..]
            .iter()
            .zip(bytes)
            .map(|(&value, &previous)| value.wrapping_sub(previous).wrapping_add(128)),
    );
    out
}

/// A chunk decompressed as the exr crate's `UncompressedBlock::decompress_chunk` does it
/// (not pedantic), but a deflated ZIP or ZIPS block inflated by libdeflate and un-predicted
/// here, where the exr crate inflates with zune-inflate and undoes the predictor a byte at a
/// time (`perf` of `blur --algorithm none` over ten 1080p frames: a fifth of the samples in
/// the two). The same bytes either way; a block this path does not take (another
/// compression, one stored raw, a subsampled channel, a big-endian machine), and one
/// libdeflate refuses or that inflates to another size, goes to the exr crate, so a damaged
/// file is refused in its words.
pub fn decompress_chunk(chunk: Chunk, meta: &MetaData) -> exr::error::Result<UncompressedBlock> {
    match inflated_here(&chunk, meta) {
        Some(block) => Ok(block),
        None => {
            dwa_counts_fit(&chunk, meta)?;
            UncompressedBlock::decompress_chunk(chunk, meta, false)
        }
    }
}

/// Refuses a DWAA/DWAB block whose header gives sizes no block of its part can have: the exr
/// crate allocates what the header's counts say before it reads the data (a damaged count
/// asked for 140 TB, and the process aborted where it should refuse the file). Each
/// uncompressed size and count is within a few times the part's largest block, each
/// compressed size at most the chunk's bytes.
/// The header is OpenEXR's (ImfDwaCompressor): eleven little-endian 64-bit counters.
fn dwa_counts_fit(chunk: &Chunk, meta: &MetaData) -> exr::error::Result<()> {
    use exr::compression::Compression;
    let Some(header) = meta.headers.get(chunk.layer_index) else {
        return Ok(());
    };
    if !matches!(
        header.compression,
        Compression::DWAA(_) | Compression::DWAB(_)
    ) {
        return Ok(());
    }
    let bytes = match &chunk.compressed_block {
        CompressedBlock::ScanLine(block) => &block.compressed_pixels_le,
        CompressedBlock::Tile(block) => &block.compressed_pixels_le,
        _ => return Ok(()),
    };
    let largest = header.max_block_byte_size() as u64;
    // A block stored raw (no smaller compressed) is the block's bytes, no header.
    if bytes.len() as u64 >= largest || bytes.len() < 88 {
        return Ok(());
    }
    let counter =
        |k: usize| u64::from_le_bytes(bytes[8 * k..8 * k + 8].try_into().expect("eight bytes"));
    let length = bytes.len() as u64;
    // 1 unknown uncompressed, 6 RLE uncompressed, 7 RLE raw, 8 AC count, 9 DC count;
    // 2 unknown compressed, 3 AC compressed, 4 DC compressed, 5 RLE compressed.
    // (Counts run over 8 × 8 blocks padded past the block's edge, and a lossy channel
    // read as half may be stored float: a bound four times the largest block's bytes leaves
    // room for both, and refuses the counts a damaged header gives, of many gigabytes.)
    let most = largest.saturating_mul(4).saturating_add(1 << 16);
    let fits = [1, 6, 7, 8, 9].iter().all(|&k| counter(k) <= most)
        && [2, 3, 4, 5].iter().all(|&k| counter(k) <= length);
    if fits {
        Ok(())
    } else {
        Err(exr::error::Error::Invalid(
            "a DWA block's header gives sizes larger than its part's blocks".into(),
        ))
    }
}

/// [`decompress_chunk`]'s own path, or `None` where the exr crate's takes the chunk.
fn inflated_here(chunk: &Chunk, meta: &MetaData) -> Option<UncompressedBlock> {
    let header = meta.headers.get(chunk.layer_index)?;
    if !deflated_here(header)
        || header
            .channels
            .list
            .iter()
            .any(|c| c.sampling != Vec2(1, 1))
    {
        return None;
    }
    let compressed = match &chunk.compressed_block {
        CompressedBlock::ScanLine(block) => &block.compressed_pixels_le,
        CompressedBlock::Tile(block) => &block.compressed_pixels_le,
        _ => return None,
    };
    // The block's place, checked as the exr crate checks it (against the layer, and the
    // block's size against the largest block, which it asserts).
    let tile = header
        .get_block_data_indices(&chunk.compressed_block)
        .ok()?;
    let bounds = header.get_absolute_block_pixel_coordinates(tile).ok()?;
    bounds.validate(Some(header.layer_size)).ok()?;
    bounds.validate(Some(header.max_block_pixel_size())).ok()?;
    let expected = bounds.size.area() * header.channels.bytes_per_pixel;
    if compressed.len() == expected {
        return None;
    }
    let data = INFLATER.with_borrow_mut(|(inflater, scratch)| {
        if scratch.len() < expected {
            scratch.resize(expected, 0);
        }
        let scratch = &mut scratch[..expected];
        let inflater = inflater.get_or_insert_with(libdeflater::Decompressor::new);
        match inflater.zlib_decompress(compressed, scratch) {
            Ok(size) if size == expected => {}
            _ => return None,
        }
        sums(scratch);
        Some(interleave(scratch))
    })?;
    Some(UncompressedBlock {
        data,
        index: BlockIndex {
            layer: chunk.layer_index,
            pixel_position: bounds.position.to_usize("data indices start").ok()?,
            level: tile.level_index,
            pixel_size: bounds.size,
        },
    })
}

thread_local! {
    /// Each thread's inflater and inflated bytes (reused from block to block).
    static INFLATER: RefCell<(Option<libdeflater::Decompressor>, Vec<u8>)> =
        const { RefCell::new((None, Vec::new())) };
}

/// The predictor undone in place: each byte after the first the one before it plus its
/// difference minus 128 (wrapping). Eight bytes at a time as one word: its even and its odd
/// bytes apart in 16-bit lanes, where one multiply each makes their running sums (no lane
/// reaches 2¹⁶, so none carries into the next); a byte is the sum of the even lanes up to
/// its own and of the odd ones before it (or up to it, for an odd byte), plus the last
/// byte of the word before. The chain from word to word is one add of the word's total,
/// where a byte at a time it was two adds a byte, most of the read's un-predicting.
fn sums(bytes: &mut [u8]) {
    let Some((&mut first, rest)) = bytes.split_first_mut() else {
        return;
    };
    let mut previous = first;
    let mut words = rest.chunks_exact_mut(8);
    for word in &mut words {
        let d = u64::from_le_bytes(word.try_into().expect("eight bytes")) ^ HIGH;
        // Running sums of the four even and the four odd differences (what a product
        // carries past the top lane is no sum of these: dropped, wrapping).
        let (even, odd) = (
            (d & LOW).wrapping_mul(LANES),
            ((d >> 8) & LOW).wrapping_mul(LANES),
        );
        let base = u64::from(previous) * LANES;
        let at_even = (even + (odd << 16) + base) & LOW;
        let at_odd = (even + odd + base) & LOW;
        word.copy_from_slice(&(at_even | (at_odd << 8)).to_le_bytes());
        previous = previous.wrapping_add(((even + odd) >> 48) as u8);
    }
    for byte in words.into_remainder() {
        previous = previous.wrapping_add(*byte ^ 0x80);
        *byte = previous;
    }
}

/// Every byte's 128; the low byte of each 16-bit lane; each 16-bit lane's 1.
const HIGH: u64 = 0x8080_8080_8080_8080;
const LOW: u64 = 0x00FF_00FF_00FF_00FF;
const LANES: u64 = 0x0001_0001_0001_0001;

/// The two halves of `split` (the first one byte longer where the count is odd) as the even
/// and the odd bytes of the block they came from.
#[multiversion::multiversion(targets("x86_64+avx2"))]
fn interleave(split: &[u8]) -> Vec<u8> {
    let n = split.len();
    let (even, odd) = split.split_at(n.div_ceil(2));
    let mut out = Vec::with_capacity(n);
    out.extend(even.iter().zip(odd).flat_map(|(&e, &o)| [e, o]));
    if n % 2 == 1 {
        out.push(even[n / 2]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// OpenEXR's ZIP layout, written out by hand from the format's description, on bytes of
    /// odd and even counts.
    #[test]
    fn the_predictor_splits_even_and_odd_bytes_then_stores_differences() {
        assert_eq!(
            predict(&[10, 200, 13, 190, 7]),
            // even 10 13 7, odd 200 190 → 10 (13−10+128) (7−13+128) (200−7+128) (190−200+128)
            vec![10, 131, 122, 65, 118]
        );
        assert_eq!(predict(&[5, 6]), vec![5, 129]);
        assert_eq!(predict(&[9]), vec![9]);
        assert_eq!(predict(&[]), Vec::<u8>::new());
        // Every length to 64, against the description written out byte by byte.
        for n in 0..64usize {
            let bytes: Vec<u8> = (0..n).map(|i| (i * 37 + 11) as u8 ^ 0xA5).collect();
            let split: Vec<u8> = bytes
                .iter()
                .step_by(2)
                .chain(bytes.iter().skip(1).step_by(2))
                .copied()
                .collect();
            let want: Vec<u8> = (0..n)
                .map(|i| {
                    if i == 0 {
                        split[0]
                    } else {
                        split[i].wrapping_sub(split[i - 1]).wrapping_add(128)
                    }
                })
                .collect();
            assert_eq!(predict(&bytes), want, "{n} bytes");
        }
    }

    /// A part of `width` × 16 pixels, one f32 channel, ZIP, as exr lays it out.
    fn part(width: usize) -> Header {
        use exr::meta::attribute::{ChannelDescription, LineOrder, SampleType, Text};
        let channel = ChannelDescription::new("Y", SampleType::F32, false);
        Header::new(
            Text::from("p"),
            (width, 16),
            exr::prelude::SmallVec::from_vec(vec![channel]),
        )
        .with_encoding(
            Compression::ZIP16,
            BlockDescription::ScanLines,
            LineOrder::Increasing,
        )
    }

    /// Two blocks of `width` × 16 f32 pixels: a smooth ramp, which deflates, and noise
    /// (`seed`), which does not.
    fn blocks(width: usize, seed: u32) -> (Vec<u8>, Vec<u8>) {
        let smooth = (0..width * 16)
            .flat_map(|i| (i as f32 * 0.01).to_le_bytes())
            .collect();
        let mut state = seed;
        let noise = (0..width * 16 * 4)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 24) as u8
            })
            .collect();
        (smooth, noise)
    }

    /// A block through [`zip_chunk`], read back by the exr crate's own ZIP decompressor:
    /// deflated where that makes it smaller, raw where it does not (noise), each read as the
    /// bytes it was.
    #[test]
    fn a_zip_chunk_reads_back_through_exr_deflated_or_raw() {
        let width = 64;
        let (smooth, noise) = blocks(width, 1u32);
        let header = part(width);
        for (label, data, deflated) in [("smooth", smooth, true), ("noise", noise, false)] {
            let index = BlockIndex {
                layer: 0,
                pixel_position: exr::math::Vec2(0, 0),
                pixel_size: exr::math::Vec2(width, 16),
                level: exr::math::Vec2(0, 0),
            };
            let chunk = zip_chunk(
                &header,
                UncompressedBlock {
                    data: data.clone(),
                    index,
                },
            )
            .unwrap();
            let CompressedBlock::ScanLine(block) = chunk.compressed_block else {
                panic!("{label}: a scan-line block")
            };
            assert_eq!(block.y_coordinate, 0);
            let stored = block.compressed_pixels_le;
            assert_eq!(
                stored.len() < data.len(),
                deflated,
                "{label}: {} bytes",
                stored.len()
            );
            if !deflated {
                assert_eq!(stored, data, "{label}: stored raw");
            }
            let section = exr::meta::attribute::IntegerBounds::new((0, 0), (width, 16));
            let read = Compression::ZIP16
                .decompress_image_section_from_le(&header, stored, section, true)
                .unwrap();
            assert_eq!(read, data, "{label}");
        }
    }

    #[test]
    fn a_deflated_block_inflates_to_the_predicted_bytes() {
        let bytes: Vec<u8> = (0..10_000u32).map(|i| (i * 7 % 251) as u8).collect();
        let deflated = deflate(&bytes);
        let mut inflated = vec![0u8; bytes.len()];
        let size = libdeflater::Decompressor::new()
            .zlib_decompress(&deflated, &mut inflated)
            .unwrap();
        assert_eq!(size, bytes.len());
        assert_eq!(inflated, predict(&bytes));
    }

    /// The predictor undone, by its definition a byte at a time, on every length to 40
    /// (words of eight and the bytes after them) and on bytes of every value.
    #[test]
    fn sums_undo_the_predictor_at_every_length() {
        for n in 0..40usize {
            let bytes: Vec<u8> = (0..n).map(|i| (i * 101 + 7) as u8 ^ 0x5C).collect();
            let mut want = bytes.clone();
            for i in 1..n {
                want[i] = want[i - 1].wrapping_add(want[i]).wrapping_sub(128);
            }
            let mut got = bytes.clone();
            sums(&mut got);
            assert_eq!(got, want, "{n} bytes");
        }
        let bytes: Vec<u8> = (0..=255u8).chain((0..=255u8).rev()).collect();
        let mut predicted = predict(&bytes);
        sums(&mut predicted);
        assert_eq!(interleave(&predicted), bytes);
    }

    /// Chunks read by [`decompress_chunk`] against the exr crate's own reading: a deflated
    /// block (ours) and one stored raw (the exr crate's path) give the same bytes and the
    /// same place; a damaged stream is refused, as the exr crate refuses it.
    #[test]
    fn chunks_read_here_are_the_exr_crates_reading() {
        let width = 64;
        let header = part(width);
        let meta = MetaData {
            requirements: exr::meta::Requirements {
                file_format_version: 2,
                is_single_layer_and_tiled: false,
                has_long_names: false,
                has_deep_data: false,
                has_multiple_layers: false,
            },
            headers: exr::prelude::SmallVec::from_vec(vec![header.clone()]),
        };
        let (smooth, noise) = blocks(width, 9u32);
        let index = BlockIndex {
            layer: 0,
            pixel_position: exr::math::Vec2(0, 0),
            pixel_size: exr::math::Vec2(width, 16),
            level: exr::math::Vec2(0, 0),
        };
        for (label, data, here) in [("smooth", smooth, true), ("noise", noise, false)] {
            let block = UncompressedBlock { data, index };
            let chunk = zip_chunk(&header, block.clone()).unwrap();
            assert_eq!(inflated_here(&chunk, &meta).is_some(), here, "{label}");
            let ours = decompress_chunk(chunk.clone(), &meta).unwrap();
            let theirs = UncompressedBlock::decompress_chunk(chunk, &meta, false).unwrap();
            assert_eq!(ours.data, block.data, "{label}");
            assert_eq!(ours.data, theirs.data, "{label}");
            assert_eq!(ours.index, theirs.index, "{label}");
        }
        // A deflated block cut short, and one with a byte of its stream changed.
        let block = UncompressedBlock {
            data: (0..width * 16 * 4).map(|i| (i / 64) as u8).collect(),
            index,
        };
        let chunk = zip_chunk(&header, block).unwrap();
        let CompressedBlock::ScanLine(stored) = &chunk.compressed_block else {
            panic!("a scan-line block")
        };
        let n = stored.compressed_pixels_le.len();
        for damage in [Damage::Cut(n / 2), Damage::Flip(n / 2)] {
            let mut damaged = stored.clone();
            match damage {
                Damage::Cut(at) => damaged.compressed_pixels_le.truncate(at),
                Damage::Flip(at) => damaged.compressed_pixels_le[at] ^= 0x55,
            }
            let chunk = Chunk {
                layer_index: 0,
                compressed_block: CompressedBlock::ScanLine(damaged),
            };
            let theirs = UncompressedBlock::decompress_chunk(chunk.clone(), &meta, false);
            let ours = decompress_chunk(chunk, &meta);
            assert!(
                ours.is_err(),
                "{damage:?} read as {} bytes",
                ours.unwrap().data.len()
            );
            assert!(theirs.is_err() || theirs.unwrap().data.len() != 64 * 16 * 4);
        }
    }

    #[derive(Debug, Clone, Copy)]
    enum Damage {
        Cut(usize),
        Flip(usize),
    }
}
