//! Depth of field from colour and depth (or a painted circle-of-confusion map).
//!
//! - [`coc`]: the thin lens's signed circle of confusion in pixels, and the `coc` stage
//!   ([`coc_plane`]), the first of both methods;
//! - [`blend`]: Wloka's blurriness blend (the sharp frame and progressively blurred images,
//!   mixed by the blurriness interpolator T: a binomial pyramid, or the talk's two copies);
//! - [`tiles`]: Sousa's tile min/max CoC, the stage between `coc` and the gather;
//! - [`bokeh`]: the gather's tap pattern and the n-blade diaphragm shape;
//! - [`gather`]: a flat-kernel bokeh gather in the spirit of Sousa's CryENGINE 3 filter, with
//!   near and far fields.
//!
//! Both methods read colour and depth only (never velocity or positions), and both work on
//! the signed CoC plane that [`coc_plane`] makes: negative in front of the focus plane, positive
//! behind it, and monotone in depth, so ordering by signed CoC is ordering by depth. A painted
//! CoC map is a plane of that kind with no near field.
//!
//! Each stage with a GPU twin (in `crate::gpu::dof`, under the same name) is a function of
//! its config and its buffers; the `#[repr(C)]` uniform or struct a twin reads is defined
//! here, beside the CPU stage it serves, and uploaded as it is. [`apply_with`] hands the
//! stages to a backend through [`Stages`], whose defaults are the CPU stages.

pub mod blend;
pub mod bokeh;
pub mod coc;
pub mod gather;
pub mod tiles;

use rayon::prelude::*;

use crate::frame::{Color, Frame, Passes};
pub use coc::{coc_plane, Lens};

/// Which depth-of-field method runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Wloka's blurriness blend.
    Blend,
    /// The bokeh gather with near and far fields.
    Gather,
}

impl Method {
    pub const ALL: &'static [(&'static str, Method)] =
        &[("blend", Method::Blend), ("gather", Method::Gather)];

    pub fn name(self) -> &'static str {
        match self {
            Method::Blend => "blend",
            Method::Gather => "gather",
        }
    }

    /// What the method holds in memory besides the frame's buffers that the preflight's
    /// planes factor counts, for a frame whose passes decode to `decoded` bytes: the
    /// gather's padded planes and the prefilter levels its tiles read, 1.5× (a 4K frame,
    /// three in flight, peaked 134 MiB over the rest of the estimate, 0.85× its planes);
    /// the blend's pyramid, nothing more (BENCHMARKS.md, the evening of 2026-12-07).
    pub fn memory_besides(self, decoded: u64) -> u64 {
        match self {
            Method::Blend => 0,
            Method::Gather => decoded.saturating_mul(3) / 2,
        }
    }
}

/// blend: how the blurred images are made and mixed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BlendForm {
    /// A binomial pyramid (each level half the size of the last), each pixel mixing the two
    /// levels whose blur brackets its CoC.
    Pyramid,
    /// The talk's form: the sharp frame and two blurred copies (n and 2n passes).
    Talk,
}

impl BlendForm {
    pub const ALL: &'static [(&'static str, BlendForm)] =
        &[("pyramid", BlendForm::Pyramid), ("talk", BlendForm::Talk)];
}

/// Where each pixel's circle of confusion comes from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CocSource {
    /// The thin lens and the depth pass.
    Lens(Lens),
    /// A painted map read in place of depth: CoC diameter (px) = stored value × `scale`.
    /// Every pixel counts as behind the focus plane (a map carries no near/far sign).
    Map { scale: f32 },
}

/// Depth-of-field parameters. Lengths in pixels of the output image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DofParams {
    pub method: Method,
    pub source: CocSource,
    /// ε: circles of confusion below this diameter are in focus (px). Default 1.
    pub epsilon: f32,
    /// The largest CoC diameter (px): larger ones are clamped. blend: E, the CoC its most
    /// blurred copy stands for, is the frame's largest CoC (so at most this). Default 48.
    pub max_coc: f32,
    /// gather: diaphragm blades; 0 is a round aperture. Default 0.
    pub blades: u32,
    /// gather: rotation of the diaphragm, degrees. Default 0.
    pub blade_rotation: f32,
    /// gather: rings of taps (ring k has 8k taps). Default 6 (169 taps): at 640×360 on
    /// `layers` 6 rings err 20 % less than 4 (BENCHMARKS.md). Bokehs up to `rings` px in
    /// radius gather every pixel; larger ones the rings, each tap reading a box the size of
    /// the ring step (radius / rings) so that a lone highlight fills its bokeh.
    pub rings: usize,
    /// blend, the talk's form: passes n of the 3×3 filter for the first copy (the second has
    /// 2n); `None` chooses n so the 2n copy has the blur of a CoC of E.
    pub passes: Option<usize>,
    /// blend: the pyramid (default) or the talk's two copies.
    pub blend_form: BlendForm,
}

/// CoC diameter in pixels of a painted map's value 1 (white): the default.
pub const DEFAULT_COC_SCALE: f32 = 32.0;

impl Default for DofParams {
    /// The defaults, for a painted map of [`DEFAULT_COC_SCALE`].
    fn default() -> Self {
        DofParams::new(CocSource::Map {
            scale: DEFAULT_COC_SCALE,
        })
    }
}

impl DofParams {
    /// The defaults for a source.
    pub fn new(source: CocSource) -> Self {
        DofParams {
            method: Method::Gather,
            source,
            epsilon: 1.0,
            max_coc: 48.0,
            blades: 0,
            blade_rotation: 0.0,
            rings: 6,
            passes: None,
            blend_form: BlendForm::Pyramid,
        }
    }

    /// Why these parameters cannot run together, if they cannot (each value's own range is
    /// checked where it is read: `crate::settings`).
    pub fn check(&self) -> Result<(), String> {
        if let CocSource::Lens(lens) = &self.source {
            lens.check()?;
        }
        if self.max_coc.partial_cmp(&self.epsilon) != Some(std::cmp::Ordering::Greater) {
            return Err(format!(
                "max-coc {} must be above epsilon {} (px)",
                self.max_coc, self.epsilon
            ));
        }
        Ok(())
    }

    /// The passes depth of field reads: colour and depth (a CoC map is read as depth).
    pub fn needs(&self) -> Passes {
        Passes {
            color: true,
            depth: true,
            velocity: false,
            prev: false,
            next: false,
        }
    }
}

/// What the gather and blend read besides their buffers: the depth-of-field stages'
/// host-side parameters, typed. Lengths in pixels.
///
/// It is never uploaded. The numbers a twin reads go in its stage's own uniform, defined
/// beside the CPU stage and built from this or from the params ([`coc::CocConfig`],
/// [`tiles::TilesConfig`], [`gather::GatherConfig`], [`blend::pyramid::BlendConfig`]): most
/// of what is here is spent on the host (the rings and the diaphragm make the gather's tap
/// lists; the form and the passes choose blend's code), and what the shaders read besides (a
/// frame's alpha, the tile columns, the pyramid's levels and ladders) is known per frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DofConfig {
    /// Frame size.
    pub width: usize,
    pub height: usize,
    /// ε: CoC diameters below this are in focus.
    pub epsilon: f32,
    /// gather: diaphragm blades, 0 for round.
    pub blades: u32,
    /// gather: diaphragm rotation, degrees.
    pub blade_rotation: f32,
    /// gather: rings of taps.
    pub rings: usize,
    /// blend, the talk's form: passes n of the first copy; `None` (or 0, which would blur
    /// nothing) chooses n from the frame's largest CoC.
    pub passes: Option<usize>,
    /// blend: the pyramid or the talk's two copies.
    pub blend_form: BlendForm,
}

impl DofConfig {
    pub fn new(width: usize, height: usize, params: &DofParams) -> Self {
        DofConfig {
            width,
            height,
            epsilon: params.epsilon,
            blades: params.blades,
            blade_rotation: params.blade_rotation,
            rings: params.rings,
            passes: params.passes,
            blend_form: params.blend_form,
        }
    }
}

/// The stages of depth of field a backend may run elsewhere (the GPU): the dispatch hook of
/// [`apply_with`]. Each must return what the CPU stage it stands for returns: the defaults
/// are the CPU stages, and a GPU twin's parity with them is tested in tests/gpu_dof.rs. A
/// backend that cannot run a stage for a frame runs the default instead.
pub trait Stages {
    /// [`coc_plane`].
    fn coc_plane(&self, frame: &Frame, params: &DofParams) -> Vec<f32> {
        coc_plane(frame, params)
    }

    /// [`tiles::tiles`].
    fn tiles(&self, config: &tiles::TilesConfig, coc: &[f32]) -> tiles::Tiles {
        tiles::tiles(config, coc)
    }

    /// [`gather::gather`].
    fn gather(
        &self,
        config: &DofConfig,
        color: &Color,
        coc: &[f32],
        tiles: &tiles::Tiles,
    ) -> Color {
        gather::gather(config, color, coc, tiles)
    }

    /// [`gather::gather`], and the R, G and B of `layers` (light layers beside the beauty)
    /// blurred in place with its weights: on the CPU carried through the beauty's taps
    /// ([`gather::gather_carrying`]); their alpha is left as it came.
    fn gather_carrying(
        &self,
        config: &DofConfig,
        color: &Color,
        coc: &[f32],
        tiles: &tiles::Tiles,
        layers: &mut [Color],
    ) -> Color {
        let planes: Vec<Vec<f32>> = layers
            .iter_mut()
            .flat_map(|l| [&mut l.r, &mut l.g, &mut l.b])
            .map(std::mem::take)
            .collect();
        let (out, carried) = gather::gather_carrying(config, color, coc, tiles, planes);
        let mut carried = carried.into_iter();
        for layer in layers.iter_mut() {
            for plane in [&mut layer.r, &mut layer.g, &mut layer.b] {
                *plane = carried.next().expect("three planes a layer");
            }
        }
        out
    }

    /// [`blend::blend`].
    fn blend(&self, config: &DofConfig, color: Color, coc: &[f32]) -> Color {
        blend::blend(config, color, coc)
    }

    /// [`blend::blend`], and the R, G and B of `layers` (light layers beside the beauty)
    /// blurred in place with its weights: on the CPU the pyramid carries them through the
    /// beauty's plan, weights and mixes ([`blend::blend_carrying`]); their alpha is left as
    /// it came.
    fn blend_carrying(
        &self,
        config: &DofConfig,
        color: Color,
        coc: &[f32],
        layers: &mut [Color],
    ) -> Color {
        blend::blend_carrying(config, color, coc, layers)
    }
}

pub use crate::stages::Cpu;

impl Stages for Cpu {}

/// Applies depth of field, stage by stage: `coc` ([`coc_plane`]) → tile min/max
/// ([`tiles::tiles`]) → [`gather::gather`], or `coc` → [`blend::blend`]. The output holds
/// the new colour and keeps every other pass, so motion blur can run after it ("DoF before
/// MB", Sousa).
pub fn apply(frame: Frame, params: &DofParams) -> Frame {
    apply_with(frame, params, &Cpu)
}

/// [`apply`] with the stages that have a twin elsewhere (`coc`, tile min/max, the gather,
/// blend) run by `stages`; the others run here on the CPU.
pub fn apply_with(frame: Frame, params: &DofParams, stages: &impl Stages) -> Frame {
    apply_layers_with(frame, &mut [], params, stages)
}

/// [`apply_with`], and `layers` (light layers beside the beauty, each with the beauty's
/// alpha) blurred in place with exactly the beauty's weights: the CoC plane and the tiles
/// are made once, the gather carries the layers through the beauty's taps
/// ([`Stages::gather_carrying`]), and blend's pyramid through the beauty's weights and mixes
/// ([`Stages::blend_carrying`]).
pub fn apply_layers_with(
    frame: Frame,
    layers: &mut [Color],
    params: &DofParams,
    stages: &impl Stages,
) -> Frame {
    let coc = stages.coc_plane(&frame, params);
    let largest = coc.par_iter().map(|c| c.abs()).reduce(|| 0.0, f32::max);
    if largest < params.epsilon || frame.color.is_none() {
        // The whole frame is in focus: nothing to do.
        return frame;
    }
    let config = DofConfig::new(frame.width, frame.height, params);
    let mut frame = frame;
    let color = frame.color.take().expect("checked");
    let out = match params.method {
        // blend writes the colour in place.
        Method::Blend => {
            if layers.is_empty() {
                stages.blend(&config, color, &coc)
            } else {
                stages.blend_carrying(&config, color, &coc, layers)
            }
        }
        Method::Gather => {
            let grid = tiles::TilesConfig::new(frame.width, frame.height, config.epsilon);
            let tiles = stages.tiles(&grid, &coc);
            if layers.is_empty() {
                stages.gather(&config, &color, &coc, &tiles)
            } else {
                stages.gather_carrying(&config, &color, &coc, &tiles, layers)
            }
        }
    };
    Frame {
        color: Some(out),
        ..frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_config_carries_the_params_typed() {
        let auto = DofConfig::new(4, 3, &DofParams::default());
        assert_eq!((auto.passes, auto.rings), (None, 6));
        assert_eq!(auto.blend_form, BlendForm::Pyramid);
    }
}
