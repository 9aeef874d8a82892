//! Depth of field's tile min/max stage on the GPU (`tiles.wgsl`): the twin of
//! [`crate::dof::gather::tiles`], the stage between `coc` and the bokeh gather (Sousa's
//! "tile min/max CoC").
//!
//! In: the signed CoC plane. Out: [`Tiles`]: each tile's gather radius (`reach`), its own
//! largest bokeh radius (`own`) and whether it has no near field (`far_only`). Bindings, in
//! order: the [`TilesConfig`] uniform, coc, the table of distances between tiles, then reach,
//! own, far_only, and the scratch the first entry point hands the second (each tile's lowest
//! and highest signed radius, the frame's largest radius). The distance table is the CPU's own
//! [`gap_distance`] for every offset in the grid, made on the host (WGSL's square root is not
//! correctly rounded); it depends on the frame size only.
//!
//! Every output is a max, min or comparison of input values, so the twin is exact; the one
//! exception (subnormal CoC) is stated and tested in tests/gpu.rs. Buffers are kept per frame
//! size and reused.

use bytemuck::{Pod, Zeroable};

use crate::dof::gather::{gap_distance, Tiles, LAYER, TILE};

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, Dispatch, Stage, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(include_str!("../prelude.wgsl"), include_str!("tiles.wgsl"));

/// Tiles per workgroup side (`@workgroup_size(8, 8)` in tiles.wgsl).
const WORKGROUP: u32 = 8;

// (overall + 1)/TILE is computed as a product with 1/TILE on the GPU (WGSL's division is not
// correctly rounded): exact only for a power of two.
const _: () = assert!(TILE.is_power_of_two());

/// The stage's uniform. Keep in sync with `TilesConfig` in tiles.wgsl (the size test guards
/// the layout: eight 4-byte fields, a multiple of 16 bytes as uniforms need).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct TilesConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// Tile edge, pixels ([`TILE`]).
    pub tile: u32,
    /// The grid: ⌈width/tile⌉ × ⌈height/tile⌉ tiles.
    pub columns: u32,
    pub rows: u32,
    /// ε: CoC diameters below it are in focus (px).
    pub epsilon: f32,
    /// [`LAYER`]: signed radii closer than this are one layer (px).
    pub layer: f32,
    /// 1/tile.
    pub inv_tile: f32,
}

impl TilesConfig {
    /// The uniform for `tiles(coc, width, height, epsilon)`.
    pub fn new(width: usize, height: usize, epsilon: f32) -> Self {
        TilesConfig {
            width: width as u32,
            height: height as u32,
            tile: TILE as u32,
            columns: width.div_ceil(TILE) as u32,
            rows: height.div_ceil(TILE) as u32,
            epsilon,
            layer: LAYER,
            inv_tile: 1.0 / TILE as f32,
        }
    }
}

/// The compiled stage: bindings config, coc, distance, reach, own, far_only, then the scratch
/// lowest, highest and overall.
pub(crate) fn stage(device: &wgpu::Device) -> Stage {
    Stage::new(
        device,
        "tiles",
        SHADER,
        &["tile_min_max", "tile_reach"],
        std::mem::size_of::<TilesConfig>(),
        2,
        6,
        3,
    )
}

/// The scratch output holding the frame's largest radius, cleared before each frame.
const OVERALL: usize = 5;

impl Gpu {
    /// [`crate::dof::gather::tiles`] on the GPU; the CPU stage where the GPU cannot run it,
    /// counted in [`Gpu::stages_on_cpu`].
    pub fn tiles(&self, coc: &[f32], width: usize, height: usize, epsilon: f32) -> Tiles {
        self.try_tiles(coc, width, height, epsilon)
            .unwrap_or_else(|e| {
                self.note_cpu_stage("tiles", &e);
                crate::dof::gather::tiles(coc, width, height, epsilon)
            })
    }

    /// [`crate::dof::gather::tiles`] on the GPU, or why it could not run.
    pub fn try_tiles(
        &self,
        coc: &[f32],
        width: usize,
        height: usize,
        epsilon: f32,
    ) -> Result<Tiles, StageError> {
        let config = TilesConfig::new(width, height, epsilon);
        let (columns, rows) = (config.columns as usize, config.rows as usize);
        let count = columns * rows;
        if count == 0 {
            return Ok(Tiles {
                reach: Vec::new(),
                own: Vec::new(),
                far_only: Vec::new(),
            });
        }
        let distance: Vec<f32> = (0..rows)
            .flat_map(|dy| (0..columns).map(move |dx| gap_distance(dx, dy)))
            .collect();
        let bytes = (count * 4) as u64;
        let groups = [
            config.columns.div_ceil(WORKGROUP),
            config.rows.div_ceil(WORKGROUP),
            1,
        ];
        let mut out = self.compiled("tiles", stage).run(
            self,
            bytemuck::bytes_of(&config),
            &[
                bytemuck::cast_slice(&coc[..width * height]),
                bytemuck::cast_slice(&distance),
            ],
            &[bytes, bytes, bytes, bytes, bytes, 4],
            &[OVERALL],
            &[Dispatch { entry: 0, groups }, Dispatch { entry: 1, groups }],
        )?;
        let far_only = out.pop().expect("three outputs");
        let own = floats(out.pop().expect("three outputs"));
        let reach = floats(out.pop().expect("three outputs"));
        Ok(Tiles {
            reach,
            own,
            far_only: far_only.into_iter().map(|f| f != 0).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_config_is_eight_plain_words() {
        // Keep in sync with tiles.wgsl: eight 4-byte fields, no padding, a multiple of 16.
        assert_eq!(std::mem::size_of::<TilesConfig>(), 32);
        assert_eq!(std::mem::align_of::<TilesConfig>(), 4);
        let c = TilesConfig::new(33, 16, 1.0);
        assert_eq!((c.columns, c.rows, c.tile), (3, 1, 16));
        // The reciprocal is exact: x·(1/tile) is x/tile.
        assert_eq!(c.inv_tile * TILE as f32, 1.0);
    }
}
