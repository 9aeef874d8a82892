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

use std::cell::RefCell;
use std::io::{Seek, Write};

use exr::block::chunk::{
    Chunk, CompressedBlock, CompressedScanLineBlock, CompressedTileBlock, TileCoordinates,
};
use exr::block::writer::ChunksWriter;
use exr::block::{BlockIndex, UncompressedBlock};
use exr::compression::Compression;
use exr::error::{Error, UnitResult};
use exr::image::write::layers::{LayersWriter, WritableLayers};
use exr::image::Image;
use exr::meta::header::Header;
use exr::meta::BlockDescription;
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
/// compatibility checks on where `checked`.
pub fn write<L>(image: &Image<L>, write: impl Write + Seek, checked: bool) -> UnitResult
where
    L: for<'a> WritableLayers<'a>,
{
    let headers = image.layer_data.infer_headers(&image.attributes);
    let layers = image.layer_data.create_writer(&headers);
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
    })
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
    let predicted = predict(bytes);
    COMPRESSOR.with_borrow_mut(|slot| {
        let compressor = slot.get_or_insert_with(|| {
            libdeflater::Compressor::new(
                libdeflater::CompressionLvl::new(LEVEL).expect("a level libdeflate has"),
            )
        });
        let mut out = vec![0u8; compressor.zlib_compress_bound(predicted.len())];
        let size = compressor
            .zlib_compress(&predicted, &mut out)
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
        split.clear();
        split.resize(n, 0);
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

    /// A block through [`zip_chunk`], read back by the exr crate's own ZIP decompressor:
    /// deflated where that makes it smaller, raw where it does not (noise), each read as the
    /// bytes it was.
    #[test]
    fn a_zip_chunk_reads_back_through_exr_deflated_or_raw() {
        let width = 64;
        let smooth: Vec<u8> = (0..width * 16)
            .flat_map(|i| (i as f32 * 0.01).to_le_bytes())
            .collect();
        let mut state = 1u32;
        let noise: Vec<u8> = (0..width * 16 * 4)
            .map(|_| {
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (state >> 24) as u8
            })
            .collect();
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
}
