//! Motion blur's GPU twins, mirroring [`crate::motion`]: reconstruct's tile stages
//! (`tile_max`, `neighbor_max`, `dilate`), its tile classification (`classify`) and its gather
//! (`reconstruct`), `scatter` and `stretch`.

use crate::frame::{Color, Positions};
use crate::gpu::context::Gpu;
use crate::motion::reconstruct::classify::TileKind;
use crate::motion::reconstruct::matte::Matte;
use crate::motion::reconstruct::{self as reconstruct_cpu, GatherInputs, ReconstructConfig};
use crate::motion::reconstruct::{Texel2014, TileMask};
use crate::motion::scatter::{self as scatter_cpu, ScatterConfig};
use crate::motion::stretch::{self as stretch_cpu, StretchConfig};
use crate::motion::tile_max::TileGrid;

pub mod classify;
pub mod dilate;
pub mod neighbor_max;
pub mod reconstruct;
pub mod scatter;
pub mod stretch;
pub mod tile_max;

/// Every motion twin's shader by name, for the test that validates them all.
pub const SHADERS: &[(&str, &str)] = &[
    ("tile_max", tile_max::SHADER),
    ("neighbor_max", neighbor_max::SHADER),
    ("dilate", dilate::SHADER),
    ("reconstruct", reconstruct::SHADER),
    ("scatter", scatter::SHADER),
    ("stretch", stretch::SHADER),
];

/// Reconstruct's stages with a twin run here: the tile stages, the classification and the
/// gather (the pack and the matte run on the CPU in the same run).
impl reconstruct_cpu::Stages for Gpu {
    fn tile_max(
        &self,
        vx: &[f32],
        vy: &[f32],
        width: usize,
        height: usize,
        size: usize,
    ) -> TileGrid {
        self.or_cpu(
            "tile_max",
            || self.try_tile_max(vx, vy, width, height, size),
            || crate::motion::tile_max::tile_max(vx, vy, width, height, size),
        )
    }

    fn neighbor_max(&self, tiles: &TileGrid) -> TileGrid {
        self.or_cpu(
            "neighbor_max",
            || self.try_neighbor_max(tiles),
            || crate::motion::neighbor_max::neighbor_max(tiles),
        )
    }

    fn dilate(&self, tiles: &TileGrid) -> TileGrid {
        self.or_cpu(
            "dilate",
            || self.try_dilate(tiles),
            || crate::motion::dilate::dilate(tiles),
        )
    }

    fn classify(
        &self,
        config: &ReconstructConfig,
        texels: &[Texel2014],
        mattes: &[Matte],
        tiles: &TileGrid,
    ) -> Vec<TileKind> {
        self.or_cpu(
            "classify",
            || self.try_classify(config, texels, mattes, tiles),
            || reconstruct_cpu::classify::classify(config, texels, mattes, tiles),
        )
    }

    fn gather(&self, config: &ReconstructConfig, inputs: GatherInputs<'_>, color: &mut Color) {
        // In place: a gather that could not run has left the colour untouched.
        let tried = self.try_reconstruct_gather(config, &inputs, color);
        self.or_cpu(
            "reconstruct gather",
            || tried,
            || inputs.gather(config, color),
        )
    }

    /// The beauty and its layers carried through the 2014 gather's dispatches
    /// ([`Gpu::try_reconstruct_gather_carrying`]): each tap's weights computed once for as
    /// many colours as a dispatch holds, in groups as even as the CPU's passes. A group the
    /// GPU could not run is gathered on the CPU (the same weights; the others are kept).
    fn gather_2014_carrying(
        &self,
        config: &ReconstructConfig,
        inputs: (&[Texel2014], &[Matte], &TileGrid, &[TileKind]),
        packed: &TileMask,
        colours: &mut [&mut Color],
    ) {
        let pixels = config.width as usize * config.height as usize;
        let (texels, mattes, tiles, kinds) = inputs;
        let cpu = |group: &mut [&mut Color]| {
            reconstruct_cpu::gather_2014::gather_2014_carrying(
                config,
                texels,
                mattes,
                (tiles, kinds),
                packed,
                group,
            )
        };
        let most = self.reconstruct_colours_per_dispatch(pixels);
        if most == 0 {
            // Not even the texels fit a binding: all on the CPU, eight colours a pass.
            let why = crate::gpu::stage::StageError::TooLarge {
                bytes: 32 * pixels as u64,
                limit: self.max_binding(),
            };
            return self.or_cpu("reconstruct gather", || Err(why), || cpu(colours));
        }
        let size = colours.len().div_ceil(colours.len().div_ceil(most).max(1));
        for group in colours.chunks_mut(size.max(1)) {
            let tried = self.try_reconstruct_gather_carrying(config, inputs, packed, group);
            self.or_cpu("reconstruct gather", || tried, || cpu(group))
        }
    }
}

/// Scatter's three stages run here, as one.
impl scatter_cpu::Stages for Gpu {
    fn stages(
        &self,
        config: &ScatterConfig,
        color: Color,
        depth: &[f32],
        positions: [&Positions; 2],
        fringe: &scatter_cpu::Fringe,
    ) -> Color {
        let order = scatter::Order::default();
        let tried = self.try_scatter(config, &color, depth, positions, fringe, order);
        self.or_cpu(
            "scatter",
            || tried,
            || scatter_cpu::stages(config, color, depth, positions, fringe),
        )
    }

    /// The layers carried through the same dispatches (`Gpu::try_scatter_carrying`: the
    /// curves drawn once, each deposit into the layers' sums with the beauty's weight, each
    /// pixel resolved once for all); the whole frame on the CPU where that cannot run.
    fn stages_carrying(
        &self,
        config: &ScatterConfig,
        color: Color,
        depth: &[f32],
        positions: [&Positions; 2],
        fringe: &scatter_cpu::Fringe,
        layers: &mut [Color],
    ) -> Color {
        let order = scatter::Order::default();
        match self.try_scatter_carrying(config, &color, depth, positions, fringe, layers, order) {
            Ok(beauty) => beauty,
            Err(why) => {
                // The layers are as they came.
                self.note_cpu_stage("scatter", &why);
                scatter_cpu::stages_carrying(config, color, depth, positions, fringe, layers)
            }
        }
    }
}

/// Stretch's three stages run here, as one (a device that cannot blend float targets runs
/// them on the CPU).
impl stretch_cpu::Stages for Gpu {
    fn stages(
        &self,
        config: &StretchConfig,
        planes: &[Vec<f32>; 4],
        z: &[f32],
        v: &[[f32; 2]],
    ) -> [Vec<f32>; 4] {
        self.or_cpu(
            "stretch",
            || self.try_stretch(config, planes, z, v),
            || stretch_cpu::stages(config, planes, z, v),
        )
    }

    /// Each layer drawn in the beauty's place, one run of the three stages a layer (with the
    /// beauty's alpha, as the CPU's carrying path reads it), then the beauty: the render
    /// pipeline's two targets already take the 32 bytes a pixel WebGPU promises for colour
    /// attachments, so a layer cannot ride in the beauty's draw (src/gpu/motion/stretch.rs).
    fn stages_carrying(
        &self,
        config: &StretchConfig,
        planes: &[Vec<f32>; 4],
        z: &[f32],
        v: &[[f32; 2]],
        layers: &mut [Color],
    ) -> [Vec<f32>; 4] {
        for layer in layers.iter_mut() {
            let alone = [
                std::mem::take(&mut layer.r),
                std::mem::take(&mut layer.g),
                std::mem::take(&mut layer.b),
                planes[3].clone(),
            ];
            let [r, g, b, _] = self.stages(config, &alone, z, v);
            (layer.r, layer.g, layer.b) = (r, g, b);
        }
        self.stages(config, planes, z, v)
    }
}
