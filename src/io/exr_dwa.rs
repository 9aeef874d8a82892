//! DWAA and DWAB output kept finite. DWA compresses a colour channel (a name ending in R, G,
//! B or Y) lossily: in 8×8 blocks of a log-like curve of the half values, through a DCT,
//! so a block near half's largest value (a sun, a light) can decode past it, to ±Inf, from
//! finite colour (`shutter blur --compression dwaa` on a highlight of 2·10⁵ gave 73
//! infinite pixels; oiiotool reads them so too). Every DWA chunk that holds a bright sample
//! ([`CALM`]) is therefore decoded again as it is written; where a lossy channel comes back
//! from a finite sample non-finite or within a margin of half's largest value ([`LARGEST`]),
//! the chunk is compressed again with its lossy samples capped at 0.8 of the largest
//! magnitude it holds (at most half's largest), and so on until it decodes within it: the
//! highlight loses what the codec could not hold, never the frame its finiteness.
//!
//! In: the part's headers and meta data, one uncompressed block. Out: its chunk. Blocks of
//! other compressions never come here.

use exr::block::chunk::Chunk;
use exr::block::UncompressedBlock;
use exr::compression::Compression;
use exr::meta::attribute::SampleType;
use exr::meta::header::Header;
use exr::meta::MetaData;
use exr::prelude::f16;
use std::sync::atomic::{AtomicU32, AtomicUsize, Ordering};

/// A block whose lossy samples are all within this magnitude is not decoded again: on DWA's
/// curve (`1 + ln(v)/2.2` above 1) 512 lies 2.0 below [`LARGEST`], ten times the largest
/// overshoot measured (a highlight capped at 32752 decoded to 50848: 0.2 up the curve), and
/// the DCT's quantisation at DWA's default level moves a sample by well under one. Decoding
/// every block cost 0.075 s a 1080p frame (0.11 → 0.18 s of writing).
const CALM: f32 = 512.0;

/// Each retry caps the block's lossy samples at this share of the cap before.
const STEP: f32 = 0.8;

/// Retries before a block is refused (65504 · 0.8⁶⁴ is below 0.01: a block whose colour is
/// that small has never come back infinite).
const MOST_RETRIES: u32 = 64;

/// The largest magnitude a lossy sample may decode to here: half's largest, 65504, less a
/// margin for another decoder's rounding (OpenEXR's own, oiiotool's): near the top of half's
/// range one step of the curve's half value is 0.9 % of the linear value, so a block that
/// decodes to 65248 here could decode one step higher, to infinity, there.
const LARGEST: f32 = 60000.0;

/// Whether a part's blocks are DWA's.
pub fn is_dwa(header: &Header) -> bool {
    matches!(
        header.compression,
        Compression::DWAA(_) | Compression::DWAB(_)
    )
}

/// Whether the exr crate's DWA encoder, which writes shutter's output, compresses a channel
/// of this name lossily: its suffix exactly R, G, B, Y, BY or RY (its rules, as OpenEXR's
/// current ones, are case-sensitive: a `spec.r` is stored exactly).
fn encoded_lossily(name: &str) -> bool {
    let suffix = name.rsplit('.').next().unwrap_or("");
    ["R", "G", "B", "Y", "BY", "RY"].contains(&suffix)
}

/// Visits the samples of `block` in the channels DWA compresses lossily (each one's byte
/// offset and type); false, visiting none, where a channel is subsampled (its lines are not
/// all there).
fn each_lossy(
    header: &Header,
    block: &UncompressedBlock,
    mut visit: impl FnMut((usize, SampleType)),
) -> bool {
    let channels = &header.channels.list;
    if channels
        .iter()
        .any(|c| c.sampling.x() != 1 || c.sampling.y() != 1)
    {
        return false;
    }
    let lossy: Vec<bool> = channels
        .iter()
        .map(|channel| {
            channel.sample_type != SampleType::U32 && encoded_lossily(&channel.name.to_string())
        })
        .collect();
    let width = block.index.pixel_size.width();
    let mut at = 0;
    for _ in 0..block.index.pixel_size.height() {
        for (channel, &lossy) in channels.iter().zip(&lossy) {
            let size = channel.sample_type.bytes_per_sample();
            if lossy {
                for k in 0..width {
                    visit((at + k * size, channel.sample_type));
                }
            }
            at += width * size;
        }
    }
    true
}

fn sample(data: &[u8], (at, kind): (usize, SampleType)) -> f32 {
    match kind {
        SampleType::F16 => f16::from_ne_bytes([data[at], data[at + 1]]).to_f32(),
        _ => f32::from_ne_bytes([data[at], data[at + 1], data[at + 2], data[at + 3]]),
    }
}

fn set(data: &mut [u8], (at, kind): (usize, SampleType), value: f32) {
    match kind {
        SampleType::F16 => data[at..at + 2].copy_from_slice(&f16::from_f32(value).to_ne_bytes()),
        _ => data[at..at + 4].copy_from_slice(&value.to_ne_bytes()),
    }
}

/// What [`finite_chunk`] capped over one file's blocks, for the run's warnings: a highlight
/// written dimmer than it came must be said.
pub struct Capped {
    blocks: AtomicUsize,
    /// The lowest cap a block was written with, as its bits (positive: ordered as the values).
    lowest: AtomicU32,
}

impl Capped {
    pub fn new() -> Capped {
        Capped {
            blocks: AtomicUsize::new(0),
            lowest: AtomicU32::new(f32::INFINITY.to_bits()),
        }
    }

    /// How many blocks were capped, and the lowest cap; `None` where none was.
    pub fn report(&self) -> Option<(usize, f32)> {
        let blocks = self.blocks.load(Ordering::Relaxed);
        (blocks > 0).then(|| (blocks, f32::from_bits(self.lowest.load(Ordering::Relaxed))))
    }
}

impl Default for Capped {
    fn default() -> Self {
        Capped::new()
    }
}

/// The warning for DWA blocks written with their highlights capped (`Capped::report`).
pub fn capped_warning((blocks, cap): (usize, f32)) -> String {
    format!(
        "{blocks} DWA chunk{} held a highlight that DWA decodes past half's range (to \
         infinity): written with its colour capped at {cap:.0}, so the file reads finite but \
         the highlight dimmer; a lossless --compression (zip, piz) keeps it",
        if blocks == 1 { "" } else { "s" }
    )
}

/// `block` compressed as its part's DWA, decoding finite wherever the block is finite (see
/// the module's doc); an error where no cap makes it so. A block written capped is counted in
/// `capped`.
pub fn finite_chunk(
    meta: &MetaData,
    block: UncompressedBlock,
    capped: &Capped,
) -> exr::error::Result<Chunk> {
    let header = &meta.headers[block.index.layer];
    let mut largest = 0.0f32;
    let whole = each_lossy(header, &block, |s| {
        let v = sample(&block.data, s).abs();
        if v.is_finite() {
            largest = largest.max(v);
        }
    });
    if !whole || largest <= CALM {
        return block.compress_to_chunk(&meta.headers);
    }
    let mut samples = Vec::new();
    each_lossy(header, &block, |s| samples.push(s));
    let finite_in: Vec<bool> = samples
        .iter()
        .map(|&s| sample(&block.data, s).is_finite())
        .collect();
    let index = block.index;
    let mut data = block.data;
    // (The encoder clamps a lossy sample to half's range: a cap above it changes nothing.)
    let mut cap = largest.min(f32::from(f16::MAX));
    for retry in 0..=MOST_RETRIES {
        let chunk = UncompressedBlock {
            data: data.clone(),
            index,
        }
        .compress_to_chunk(&meta.headers)?;
        let decoded = UncompressedBlock::decompress_chunk(chunk.clone(), meta, false)?;
        let fine = samples.iter().zip(&finite_in).all(|(&s, &finite)| {
            // A sample the codec kept as it was (a block it stored raw) is fine as it is.
            let (before, after) = (sample(&data, s), sample(&decoded.data, s));
            !finite || after.abs() <= LARGEST || after.to_bits() == before.to_bits()
        });
        if fine {
            if retry > 0 {
                capped.blocks.fetch_add(1, Ordering::Relaxed);
                capped.lowest.fetch_min(cap.to_bits(), Ordering::Relaxed);
            }
            return Ok(chunk);
        }
        cap *= STEP;
        for &s in &samples {
            let v = sample(&data, s);
            if v.is_finite() && v.abs() > cap {
                set(&mut data, s, cap.copysign(v));
            }
        }
    }
    Err(exr::error::Error::Invalid(
        "a DWA block whose colour decodes to infinity however far it is capped".into(),
    ))
}
