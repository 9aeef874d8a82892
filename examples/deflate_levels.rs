//! The deflate of EXR ZIP blocks: the exr crate's miniz_oxide at its level 4 against
//! libdeflate's levels, on the blocks of the EXR files given (every part, 16 lines a block,
//! OpenEXR's predictor applied, one thread): seconds, and compressed bytes over raw bytes.
//! BENCHMARKS.md, "EXR output: ZIP through libdeflate", records what it printed.
//!
//! ```text
//! cargo run --release --example deflate_levels -- FILE.exr...
//! ```

use std::time::Instant;

use exr::prelude::*;

/// A part's blocks of 16 lines, as an EXR ZIP block holds them before its predictor: line
/// by line, each channel's samples of the line in name order, little-endian.
fn blocks(layer: &Layer<AnyChannels<FlatSamples>>) -> Vec<Vec<u8>> {
    let (width, height) = (layer.size.width(), layer.size.height());
    let mut channels: Vec<&AnyChannel<FlatSamples>> = layer.channel_data.list.iter().collect();
    channels.sort_by(|a, b| a.name.cmp(&b.name));
    let mut out = Vec::new();
    for first in (0..height).step_by(16) {
        let mut block = Vec::new();
        for y in first..(first + 16).min(height) {
            for channel in &channels {
                let row = y * width..(y + 1) * width;
                match &channel.sample_data {
                    FlatSamples::F16(v) => {
                        v[row].iter().for_each(|s| block.extend(s.to_le_bytes()))
                    }
                    FlatSamples::F32(v) => {
                        v[row].iter().for_each(|s| block.extend(s.to_le_bytes()))
                    }
                    FlatSamples::U32(v) => {
                        v[row].iter().for_each(|s| block.extend(s.to_le_bytes()))
                    }
                }
            }
        }
        out.push(shutter::io::exr_zip::predict(&block));
    }
    out
}

fn main() {
    for path in std::env::args().skip(1) {
        let image = read_all_flat_layers_from_file(&path).expect("an EXR");
        let blocks: Vec<Vec<u8>> = image.layer_data.iter().flat_map(blocks).collect();
        let raw: usize = blocks.iter().map(Vec::len).sum();
        let mut row = format!("{path}: {raw} bytes |");
        // A block deflated no smaller than it is goes raw, as OpenEXR stores it.
        let mut measure = |label: String, deflate: &mut dyn FnMut(&[u8]) -> usize| {
            let start = Instant::now();
            let size: usize = blocks.iter().map(|b| deflate(b).min(b.len())).sum();
            let seconds = start.elapsed().as_secs_f64();
            row += &format!(" {label} {seconds:.3} s {:.4} |", size as f64 / raw as f64);
        };
        measure("miniz 4".into(), &mut |b| {
            miniz_oxide::deflate::compress_to_vec_zlib(b, 4).len()
        });
        for level in [1, 4, 6, 7] {
            let mut compressor =
                libdeflater::Compressor::new(libdeflater::CompressionLvl::new(level).unwrap());
            measure(format!("libdeflate {level}"), &mut |b| {
                let mut out = vec![0u8; compressor.zlib_compress_bound(b.len())];
                compressor.zlib_compress(b, &mut out).unwrap()
            });
        }
        println!("{row}");
    }
}
