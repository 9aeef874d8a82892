//! Each channel of an EXR output in its pixel type (`exr_like`): as its input part stored
//! it (half with `--half`, but data half cannot hold), and whether the output's compression
//! would store it lossily, so that data goes to a lossless part instead.

use exr::compression::Compression;
use exr::image::{AnyChannel, FlatSamples};
use exr::meta::attribute::SampleType;
use exr::meta::header::Header;
use exr::prelude::f16;

use crate::frame::{LayerClass, Plane};
use crate::io::channels::{self, name_of, name_text};

/// One channel to write.
#[derive(Clone, Debug)]
pub struct OutChannel {
    pub name: String,
    pub plane: Plane,
    /// Whether it is data (a DWA part keeps its data apart, lossless).
    pub class: LayerClass,
    /// A u32 channel's values as read, exactly (`CarriedChannel::exact`): written when the
    /// channel goes out as u32.
    pub exact: Option<Vec<u32>>,
    /// Its name as the input part stores it, where that is not `name` (a view's channel
    /// written as a file of one view: `id.right.v` written `id.v`): its pixel type and
    /// pLinear flag are that channel's, not those of a channel of another view (or none)
    /// that the output name happens to match.
    pub source: Option<String>,
    /// In an output of every view of a file whose channel names say their views (OpenEXR's
    /// single-part scheme): the channel's view and its name in that view (`right` and `R`
    /// for `right.R`), for a multi-part output, whose parts say their views instead (see
    /// `exr_like::write_like`); `None`: a channel of no view, or a file not of that scheme.
    pub view: Option<(String, String)>,
}

/// Whether `channel` is data that `compression` would store lossily in the output: every data
/// channel under DWAA and DWAB (lossy for names ending in R, G, B or Y, so a layer's data
/// goes apart whole), a half one under B44 and B44A, a float one under PXR24 (to 24 bits).
/// Such data goes to a part of its own, with ZIP (an outside probe: `--compression b44` wrote
/// half depth and vectors through B44, 15 px off, with no word).
pub fn lossy_for(
    compression: Compression,
    channel: &OutChannel,
    input: Option<&Header>,
    half: bool,
) -> bool {
    channel.class.is_data()
        && match compression {
            Compression::DWAA(_) | Compression::DWAB(_) => true,
            Compression::B44 | Compression::B44A => {
                stored_as(channel, input, half) == SampleType::F16
            }
            Compression::PXR24 => stored_as(channel, input, half) == SampleType::F32,
            _ => false,
        }
}

/// The pixel type `channel` is written in: as its input part stored it; half for every float
/// channel with `half`, but data half cannot hold; a u32 channel (IDs) stays u32, which half
/// would destroy (every ID over 2048), and so does one read exactly as u32.
fn stored_as(channel: &OutChannel, input: Option<&Header>, half: bool) -> SampleType {
    let read_as = channel.source.as_deref().unwrap_or(&channel.name);
    match stored(input, read_as) {
        _ if channel.exact.is_some() => SampleType::U32,
        Some(SampleType::U32) => SampleType::U32,
        // A data channel that half cannot hold (a depth of 1e10 for empty pixels, a world
        // position of −7e4, an object index of 3001) stays float: half would make it ±∞, where
        // colour saturates, or another index. So does Cryptomatte's, whose IDs are hashes
        // stored in a float's bits (its specification: 32-bit float), which half would make
        // other IDs or 0.
        _ if half
            && channel.class != LayerClass::Colour
            && (!fits_half(&channel.plane) || is_crypto(channel, input)) =>
        {
            SampleType::F32
        }
        _ if half => SampleType::F16,
        stored => stored.unwrap_or(SampleType::F32),
    }
}

/// How the input part describes the channel it stores as `name`.
fn described<'h>(
    input: Option<&'h Header>,
    name: &str,
) -> Option<&'h exr::meta::attribute::ChannelDescription> {
    input.and_then(|h| h.channels.list.iter().find(|c| name_of(&c.name) == name))
}

fn stored(input: Option<&Header>, name: &str) -> Option<SampleType> {
    described(input, name).map(|c| c.sample_type)
}

/// Whether half holds what `plane` means: every finite value within half's range (its
/// infinities are half's too), and, where every finite value is a whole number (an index, a
/// count), each of them exactly (half's are whole up to 2048).
fn fits_half(plane: &[f32]) -> bool {
    let finite = || plane.iter().filter(|v| v.is_finite());
    let in_range = finite().all(|v| v.abs() <= f32::from(f16::MAX));
    let whole = finite().all(|v| v.fract() == 0.0);
    in_range && (!whole || finite().all(|&v| f16::from_f32(v).to_f32() == v))
}

/// Whether `channel` is a Cryptomatte layer's: by its name, or by the input header's
/// `cryptomatte/<key>/name` attributes.
fn is_crypto(channel: &OutChannel, input: Option<&Header>) -> bool {
    let named = input.map(channels::crypto_layers).unwrap_or_default();
    channels::is_crypto(&channel.name, &named)
}

/// Each channel's samples in the pixel type its input part stored it in (half with `half`:
/// `--half`).
pub fn channels_like(
    channels: Vec<OutChannel>,
    input: Option<&Header>,
    half: bool,
) -> Vec<AnyChannel<FlatSamples>> {
    channels
        .into_iter()
        .map(|channel| {
            let kind = stored_as(&channel, input, half);
            let OutChannel {
                name,
                plane,
                exact,
                class,
                source,
                view: _,
            } = channel;
            let read_as = source.as_deref().unwrap_or(&name);
            let samples = match kind {
                // Colour (blurred: finite by the numeric policy) saturates at half's largest
                // value instead of overflowing to ±Inf: a half plate with an infinite or huge
                // pixel, clamped to ±1e30 and blurred, must not come back with infinities
                // around it. Data goes back as it came (an infinite depth stays infinite).
                SampleType::F16 if class == LayerClass::Colour => FlatSamples::F16(
                    plane
                        .into_iter()
                        .map(crate::numeric::half_saturated)
                        .collect(),
                ),
                SampleType::F16 => FlatSamples::F16(plane.into_iter().map(f16::from_f32).collect()),
                // Integer channels are ids and counts: they come back as they were read, to
                // the bit where they were read exactly (IDs over 2²⁴).
                SampleType::U32 => FlatSamples::U32(match exact {
                    Some(values) => values,
                    // A u32 classed colour by a preset (blurred): to the nearest integer.
                    None => plane.into_iter().map(|v| v.round() as u32).collect(),
                }),
                SampleType::F32 => FlatSamples::F32(plane),
            };
            // The channel's pLinear flag as the input stored it (OpenEXR's default, off, for
            // a channel it did not have). The exr crate guesses it from the name, on for all
            // but R, G, B, L, Y, X and Z: B44 then encodes `A`, `velocity.X` or `diffuse.R`
            // through its perceptual curve, which writes every negative value as 0.
            let linear = described(input, read_as).is_some_and(|c| c.quantize_linearly);
            AnyChannel {
                quantize_linearly: linear,
                ..AnyChannel::new(name_text(&name), samples)
            }
        })
        .collect()
}
