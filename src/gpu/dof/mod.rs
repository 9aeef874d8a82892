//! Depth of field's GPU twins, mirroring [`crate::dof`]: `coc`, tile min/max (`tiles`), the
//! bokeh `gather` and `blend`'s pyramid. Each file holds a stage's shader, its compiled
//! `Stage` and `Gpu::try_X`, the stage on the GPU or why it could not run; the configs and
//! structs the shaders read are defined beside the CPU stages, in [`crate::dof`], and
//! uploaded as they are. The impl below is where each stage falls back to its CPU twin,
//! through `Gpu::or_cpu`, and the only place.

use crate::dof::blend::{pyramid, talk};
use crate::dof::tiles::{Tiles, TilesConfig};
use crate::dof::{BlendForm, DofConfig, DofParams};
use crate::frame::{Color, Frame};
use crate::gpu::context::Gpu;
use crate::stages::Cpu;

pub mod blend;
pub mod coc;
pub mod gather;
pub mod tiles;

/// Every depth-of-field twin's shader by name, for the test that validates them all.
pub const SHADERS: &[(&str, &str)] = &[
    ("coc", coc::SHADER),
    ("tiles", tiles::SHADER),
    ("gather", gather::SHADER),
    ("blend", blend::SHADER),
];

/// Depth of field's stages run here, each on the CPU instead (counted in
/// [`Gpu::stages_on_cpu`], the first reason kept) where the GPU cannot run it for a frame.
impl crate::dof::Stages for Gpu {
    fn coc_plane(&self, frame: &Frame, params: &DofParams) -> Vec<f32> {
        self.or_cpu(
            "coc",
            || self.try_coc_plane(frame, params),
            || crate::dof::coc_plane(frame, params),
        )
    }

    fn tiles(&self, config: &TilesConfig, coc: &[f32]) -> Tiles {
        self.or_cpu(
            "tiles",
            || self.try_tiles(config, coc),
            || crate::dof::tiles::tiles(config, coc),
        )
    }

    fn gather(&self, config: &DofConfig, color: &Color, coc: &[f32], tiles: &Tiles) -> Color {
        self.or_cpu(
            "gather",
            || self.try_dof_gather(config, color, coc, tiles),
            || crate::dof::gather::gather(config, color, coc, tiles),
        )
    }

    /// The beauty and its layers through `gather_carrying`'s dispatches, each tap's weights
    /// computed once for every colour of a dispatch.
    fn gather_carrying(
        &self,
        config: &DofConfig,
        color: &Color,
        coc: &[f32],
        tiles: &Tiles,
        layers: &mut [Color],
    ) -> Color {
        let tried = {
            let colours: Vec<&Color> = std::iter::once(color).chain(layers.iter()).collect();
            self.try_dof_gather_carrying(config, &colours, coc, tiles)
        };
        match tried {
            Ok(mut gathered) => {
                for (layer, blurred) in layers.iter_mut().zip(gathered.drain(1..)) {
                    (layer.r, layer.g, layer.b) = (blurred.r, blurred.g, blurred.b);
                }
                gathered.pop().expect("the beauty")
            }
            Err(why) => {
                self.note_cpu_stage("gather", &why);
                crate::dof::Stages::gather_carrying(&Cpu, config, color, coc, tiles, layers)
            }
        }
    }

    fn blend(&self, config: &DofConfig, color: Color, coc: &[f32]) -> Color {
        match config.blend_form {
            BlendForm::Pyramid => {
                // Tried first, so a fallback can hand the frame to the CPU's pyramid, which
                // writes it in place.
                let tried = self.try_dof_blend(config, &color, coc);
                self.or_cpu("blend", || tried, || pyramid::blend(config, color, coc))
            }
            // The talk's form has no twin: it runs on the CPU, and is no fallback.
            BlendForm::Talk => talk::blend(config, &color, coc),
        }
    }

    /// Each layer through the twin in the beauty's place, then the beauty: the pyramid's
    /// dispatches do not carry layers yet (the CPU's `blend_carrying` does).
    fn blend_carrying(
        &self,
        config: &DofConfig,
        color: Color,
        coc: &[f32],
        layers: &mut [Color],
    ) -> Color {
        for layer in layers.iter_mut() {
            let alone = std::mem::replace(layer, Color::empty());
            *layer = self.blend(config, alone, coc);
        }
        self.blend(config, color, coc)
    }
}
