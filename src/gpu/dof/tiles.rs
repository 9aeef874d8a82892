//! Depth of field's tile min/max stage on the GPU (`tiles.wgsl`): the twin of
//! [`crate::dof::tiles::tiles`], the stage between `coc` and the bokeh gather (Sousa's
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
//! exception (subnormal CoC) is stated and tested in tests/gpu_dof.rs. Buffers are kept per
//! frame size and reused.

use crate::dof::tiles::{gap_distance, Tiles, TilesConfig};

use crate::gpu::context::Gpu;
use crate::gpu::stage::{floats, Dispatch, Stage, StageError};

/// The shader's source.
pub const SHADER: &str = concat!(include_str!("../prelude.wgsl"), include_str!("tiles.wgsl"));

/// Tiles per workgroup side (`@workgroup_size(8, 8)` in tiles.wgsl).
const WORKGROUP: u32 = 8;

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
    /// [`crate::dof::tiles::tiles`] on the GPU, or why it could not run;
    /// [`crate::dof::Stages::tiles`] falls back to the CPU stage.
    pub fn try_tiles(&self, config: &TilesConfig, coc: &[f32]) -> Result<Tiles, StageError> {
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
        let pixels = config.width as usize * config.height as usize;
        let mut out = self.compiled("tiles", stage).run(
            self,
            bytemuck::bytes_of(config),
            &[
                bytemuck::cast_slice(&coc[..pixels]),
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
    fn the_config_is_the_shader_s() {
        // Eight 4-byte fields, no padding, a multiple of 16 as uniforms need.
        assert_eq!(std::mem::align_of::<TilesConfig>(), 4);
        crate::gpu::layout::assert_same_layout!(
            TilesConfig,
            SHADER,
            "TilesConfig",
            [width, height, tile, columns, rows, epsilon, layer, inv_tile]
        );
    }
}
