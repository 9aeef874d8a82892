//! What a frame costs in memory, from its plan (the headers alone), so that a run that would
//! not fit is refused in the preflight instead of failing, or aborting, part-way (issue 30:
//! a 446 KB PNG declaring 12000×12000 needed 3.8 GB).
//!
//! The estimate is an upper bound measured against peak RSS (BENCHMARKS.md, "Memory"): a
//! frame's decoded planes (every channel read, four bytes a sample) five times over (the
//! frame being read, the one being processed with its buffers, the one being written: a
//! 1080p reconstruct peaks at 3.1× its planes and scatter at 1.7×; with light layers carried
//! through the passes, a three-frame bokeh gather of twenty RGB layers at 4.7× and scatter at
//! 4.4×, the processed frame holding its layers' padded copies or their sums beside them),
//! plus what a picture's decoder holds besides (its own buffer, and a copy when it turns the
//! picture upright), plus a fixed base for the program itself.

use super::plan::FramePlan;
use crate::io::file::FileKind;

/// The program's own memory besides the frames' (code, threads, the GPU context's host
/// side).
pub const BASE: u64 = 96 << 20;

/// How many times its decoded planes a frame may hold at once, across the pipeline's stages.
pub const PLANES_FACTOR: u64 = 5;

/// What a GPU backend adds: the driver's host side (with a software driver such as
/// lavapipe, its device memory and shader compiler too), and the frame's buffers mirrored on
/// the host up to [`GPU_PLANES_FACTOR`] times its planes. On lavapipe at 1080p the GPU runs
/// peak at 640 MiB (reconstruct), 540 (scatter) and 394 (the bokeh gather), against 178, 124
/// and 141 on the CPU.
pub const GPU_BASE: u64 = 320 << 20;
pub const GPU_PLANES_FACTOR: u64 = 3;

impl FramePlan {
    /// The decoded planes' bytes: every channel read, as f32 (a part of the colour file read
    /// apart at its own window counted at the larger of its window and the beauty's, which
    /// it may be placed on).
    pub fn decoded_bytes(&self) -> u64 {
        let apart: u64 = self.color.as_ref().map_or(0, |color| {
            let info = &self.files[color.rgb[0].file].info;
            let FileKind::Exr { headers, .. } = &info.kind else {
                return 0;
            };
            let beauty = pixels(info.width, info.height);
            (color.apart_read.iter())
                .map(|part| {
                    let size = headers
                        .get(part.part)
                        .map_or(0, |h| pixels(h.layer_size.0, h.layer_size.1));
                    part.channels.len() as u64 * size.max(beauty) * 4
                })
                .sum()
        });
        self.files
            .iter()
            .map(|f| f.channels.len() as u64 * pixels(f.info.width, f.info.height) * 4)
            .sum::<u64>()
            .saturating_add(apart)
    }

    /// The light layers' bytes (the colour channels carried beside the beauty, as f32 on the
    /// beauty's window): what a pass that holds another copy of them adds
    /// ([`crate::motion::Algorithm::layer_copies`]).
    pub fn light_layer_bytes(&self) -> u64 {
        let Some(color) = &self.color else {
            return 0;
        };
        let colour = |c: &&crate::frame::LayerClass| **c == crate::frame::LayerClass::Colour;
        let channels = color.other_classes.iter().filter(colour).count()
            + (color.apart_read.iter())
                .map(|p| p.classes.iter().filter(colour).count())
                .sum::<usize>();
        channels as u64 * pixels(self.width, self.height) * 4
    }

    /// The most a picture decoder holds besides the planes: its decoded buffer and the copy
    /// an orientation makes (0 for EXR, decoded straight into the planes).
    pub fn decoder_bytes(&self) -> u64 {
        self.files
            .iter()
            .map(|f| match f.info.kind {
                FileKind::Image { bits, float, .. } => {
                    let sample = if float {
                        4
                    } else {
                        u64::from(bits.div_ceil(8))
                    };
                    let stored = f
                        .info
                        .channels
                        .iter()
                        .map(|c| c.index + 1)
                        .max()
                        .unwrap_or(1);
                    2 * pixels(f.info.width, f.info.height) * stored as u64 * sample
                }
                FileKind::Exr { .. } => 0,
            })
            .max()
            .unwrap_or(0)
    }

    /// The memory a run over frames like this one needs at most: [`PLANES_FACTOR`] times the
    /// decoded planes, the decoder's own, and [`BASE`]; with `gpu` (a backend that may run
    /// on one), [`GPU_PLANES_FACTOR`] times the planes and [`GPU_BASE`] more.
    pub fn memory_needed(&self, gpu: bool) -> u64 {
        let planes = self.decoded_bytes();
        let cpu = PLANES_FACTOR
            .saturating_mul(planes)
            .saturating_add(self.decoder_bytes())
            .saturating_add(BASE);
        if gpu {
            cpu.saturating_add(GPU_PLANES_FACTOR.saturating_mul(planes))
                .saturating_add(GPU_BASE)
        } else {
            cpu
        }
    }
}

fn pixels(width: usize, height: usize) -> u64 {
    (width as u64).saturating_mul(height as u64)
}
