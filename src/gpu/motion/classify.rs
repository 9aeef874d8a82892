//! reconstruct's tile classification on the GPU (`classify_tiles` then `classify_kinds` in
//! classify.wgsl, part of the reconstruct module): the twin of
//! [`crate::motion::reconstruct::classify::classify`]. In: the config, the packed texels, the
//! exposure variant's mattes and the dilated tiles, as [`reconstruct_with`] hands them to
//! [`Stages::classify`]. Out: each tile's [`TileKind`], read back, which the gather (on either
//! backend) then takes as the CPU's.
//!
//! The buffers are the gather's of the same frame shape (the shape of the gather of the
//! beauty alone), so the classification adds two small ones, the kinds and their summaries,
//! and no allocation of its own a frame. The texels travel twice a frame, once for this stage
//! and once for the gather: at 1080p 66 MB more to upload, against a classification on the
//! CPU that reads them all once (kept so: each stage a twin the parity tests can hold to the
//! CPU's answer, as the issue asks; a gather that took the kinds already on the device would
//! save the upload).

use crate::motion::reconstruct::classify::TileKind;
use crate::motion::reconstruct::matte::Matte;
#[cfg(doc)]
use crate::motion::reconstruct::{reconstruct_with, Stages};
use crate::motion::reconstruct::{ReconstructConfig, Texel2014};
use crate::motion::tile_max::TileGrid;

use super::reconstruct::{write_frame, ReconstructPass, Shape};
use crate::gpu::context::Gpu;
use crate::gpu::stage::{kept, read_back, Caught, StageError};

/// Tiles per workgroup (`@workgroup_size(64)` in classify.wgsl).
const WORKGROUP: u32 = 64;

impl Gpu {
    /// [`crate::motion::reconstruct::classify::classify`] on the GPU, or why it could not run.
    pub fn try_classify(
        &self,
        config: &ReconstructConfig,
        texels: &[Texel2014],
        mattes: &[Matte],
        tiles: &TileGrid,
    ) -> Result<Vec<TileKind>, StageError> {
        let pixels = config.width as usize * config.height as usize;
        let count = tiles.columns * tiles.rows;
        if pixels == 0 || count == 0 || texels.len() != pixels {
            return Ok(vec![TileKind::Full; count]);
        }
        let shape = Shape {
            pixels,
            tiles: count,
            texel: 8,
            velocity: false,
            mattes: !mattes.is_empty(),
            colours: 0,
        };
        let bytes = std::mem::size_of_val(texels) as u64;
        if bytes > self.max_binding() {
            return Err(StageError::TooLarge {
                bytes,
                limit: self.max_binding(),
            });
        }
        let pass = self.compiled("reconstruct", ReconstructPass::new);
        let caught = Caught::push(&self.device);
        let mut cache = pass.buffers.lock().unwrap_or_else(|e| e.into_inner());
        let buffers = kept(&mut cache, &shape, || {
            pass.make_buffers(&self.device, shape)
        });
        let mut clock = std::time::Instant::now();
        let frame = (
            bytemuck::cast_slice(texels),
            bytemuck::cast_slice(mattes),
            tiles,
        );
        write_frame(&self.queue, buffers, config, frame);
        self.uploaded(&mut clock)?;
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("classify"),
            });
        // Two passes: every summary is written before any kind reads it.
        for (label, pipeline) in [
            ("classify tiles", &pass.classify_tiles),
            ("classify kinds", &pass.classify_kinds),
        ] {
            let mut compute = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(label),
                timestamp_writes: None,
            });
            compute.set_pipeline(pipeline);
            compute.set_bind_group(0, &buffers.bind_group, &[]);
            compute.dispatch_workgroups((count as u32).div_ceil(WORKGROUP), 1, 1);
        }
        self.computed(&mut encoder, "classify", &mut clock)?;
        let bytes = (count * 4) as u64;
        encoder.copy_buffer_to_buffer(&buffers.kinds, 0, &buffers.readback, 0, bytes);
        self.queue.submit([encoder.finish()]);
        if let Err(error) = caught.check() {
            cache.remove(&shape);
            return Err(error);
        }
        let words = read_back(&self.device, &buffers.readback, bytes)?;
        self.mark(|t| &mut t.readback_ms, &mut clock)?;
        words
            .into_iter()
            .map(|word| match word {
                0 => Ok(TileKind::Full),
                1 => Ok(TileKind::Plain),
                2 => Ok(TileKind::Uniform),
                3 => Ok(TileKind::Hollow),
                _ => Err(StageError::Device(format!(
                    "the classification wrote {word}, no tile kind"
                ))),
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::super::reconstruct::SHADER;
    use crate::motion::reconstruct::classify::{TileKind, SUMMARY_WORDS, UNIFORM_SPREAD};

    #[test]
    fn the_shader_s_kinds_and_spread_are_the_cpu_s() {
        let has = |line: String| assert!(SHADER.contains(&line), "classify.wgsl lacks {line}");
        for (name, kind) in [
            ("FULL", TileKind::Full),
            ("PLAIN", TileKind::Plain),
            ("UNIFORM", TileKind::Uniform),
            ("HOLLOW", TileKind::Hollow),
        ] {
            has(format!("const {name}: u32 = {}u;", kind as u32));
        }
        has(format!("const UNIFORM_SPREAD: f32 = {UNIFORM_SPREAD:?};"));
        has(format!("const SUMMARY_WORDS: u32 = {SUMMARY_WORDS}u;"));
    }
}
