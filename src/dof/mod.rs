//! Depth of field from colour and depth (or a painted circle-of-confusion map).
//!
//! - [`coc`]: the thin lens's signed circle of confusion in pixels;
//! - [`blend`]: Wloka's blurriness blend (the sharp frame and progressively blurred images,
//!   mixed by the blurriness interpolator T: a binomial pyramid, or the talk's two copies);
//! - [`bokeh`]: the gather's tap pattern and the n-blade diaphragm shape;
//! - [`gather`]: a flat-kernel bokeh gather in the spirit of Sousa's CryENGINE 3 filter, with
//!   near and far fields and tile min/max CoC.
//!
//! Both methods read colour and depth only (never velocity or positions), and both work on
//! the signed CoC plane that [`coc_plane`] makes: negative in front of the focus plane, positive
//! behind it, and monotone in depth, so ordering by signed CoC is ordering by depth. A painted
//! CoC map is a plane of that kind with no near field.

pub mod blend;
pub mod bokeh;
pub mod coc;
pub mod gather;

use rayon::prelude::*;

use crate::frame::{Color, Frame, Passes};
pub use coc::Lens;

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
    /// `layers` 6 rings err 20 % less than 4 (BENCHMARKS.md).
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

/// Everything the stages after `coc` read besides their buffers, as plain numbers: the shape
/// of the uniform their GPU twins will take (keep the two in sync). Lengths in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C)]
pub struct DofConfig {
    /// Frame size.
    pub width: u32,
    pub height: u32,
    /// ε: CoC diameters below this are in focus.
    pub epsilon: f32,
    /// The largest CoC diameter (the `coc` stage clamps to it).
    pub max_coc: f32,
    /// gather: diaphragm blades, 0 for round.
    pub blades: u32,
    /// gather: diaphragm rotation, degrees.
    pub blade_rotation: f32,
    /// gather: rings of taps.
    pub rings: u32,
    /// blend, the talk's form: passes n of the first copy; 0 chooses n from the frame's
    /// largest CoC.
    pub passes: u32,
    /// blend: 0 the pyramid, 1 the talk's two copies.
    pub blend_form: u32,
}

impl DofConfig {
    pub fn new(width: usize, height: usize, params: &DofParams) -> Self {
        DofConfig {
            width: width as u32,
            height: height as u32,
            epsilon: params.epsilon,
            max_coc: params.max_coc,
            blades: params.blades,
            blade_rotation: params.blade_rotation,
            rings: params.rings as u32,
            passes: params.passes.map_or(0, |n| n as u32),
            blend_form: match params.blend_form {
                BlendForm::Pyramid => 0,
                BlendForm::Talk => 1,
            },
        }
    }
}

/// The signed CoC diameter of every pixel, in pixels, clamped to ±`max_coc`; NaN never comes
/// out (NaN depth is far; zero and negative depth are nearest).
pub fn coc_plane(frame: &Frame, params: &DofParams) -> Vec<f32> {
    let limit = params.max_coc;
    let n = frame.pixel_count();
    let Some(depth) = frame.depth.as_ref() else {
        return vec![0.0; n];
    };
    match params.source {
        CocSource::Lens(lens) => {
            // The sensor spans the display window (the picture), not an overscan data window.
            let display = frame.windows.display.width;
            let width = if display > 0 { display } else { frame.width } as f64;
            let lens = lens.in_pixels(width);
            depth
                .par_iter()
                .map(|&d| (lens.signed(d as f64) as f32).clamp(-limit, limit))
                .collect()
        }
        CocSource::Map { scale } => depth
            .par_iter()
            .map(|&v| {
                let c = v * scale;
                if c.is_nan() {
                    0.0
                } else {
                    c.clamp(0.0, limit)
                }
            })
            .collect(),
    }
}

/// The stages of depth of field a backend may run elsewhere (the GPU): the dispatch hook of
/// [`apply_with`]. Each must return what the CPU stage it stands for returns (the defaults are
/// the CPU stages; a GPU twin's parity with them is tested in tests/gpu.rs).
pub trait Stages {
    /// [`coc_plane`].
    fn coc_plane(&self, frame: &Frame, params: &DofParams) -> Vec<f32> {
        coc_plane(frame, params)
    }

    /// [`gather::tiles`].
    fn tiles(&self, coc: &[f32], width: usize, height: usize, epsilon: f32) -> gather::Tiles {
        gather::tiles(coc, width, height, epsilon)
    }

    /// [`gather::gather`].
    fn gather(
        &self,
        config: &DofConfig,
        color: &Color,
        coc: &[f32],
        tiles: &gather::Tiles,
    ) -> Color {
        gather::gather(config, color, coc, tiles)
    }

    /// [`blend::blend`].
    fn blend(&self, config: &DofConfig, color: Color, coc: &[f32]) -> Color {
        blend::blend(config, color, coc)
    }
}

pub use crate::stages::Cpu;

impl Stages for Cpu {}

/// Applies depth of field, stage by stage: `coc` ([`coc_plane`]) → tile min/max
/// ([`gather::tiles`]) → [`gather::gather`], or `coc` → [`blend::blend`]. The output holds
/// the new colour and keeps every other pass, so motion blur can run after it ("DoF before
/// MB", Sousa).
pub fn apply(frame: Frame, params: &DofParams) -> Frame {
    apply_with(frame, params, &Cpu)
}

/// [`apply`] with the stages that have a twin elsewhere (`coc`, tile min/max, the gather,
/// blend) run by `stages`; the others run here on the CPU.
pub fn apply_with(frame: Frame, params: &DofParams, stages: &impl Stages) -> Frame {
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
        Method::Blend => stages.blend(&config, color, &coc),
        Method::Gather => {
            let tiles = stages.tiles(&coc, frame.width, frame.height, config.epsilon);
            stages.gather(&config, &color, &coc, &tiles)
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
    fn the_config_is_nine_plain_words() {
        // Uploaded as one uniform by the GPU twins: nine 4-byte fields, no padding.
        assert_eq!(std::mem::size_of::<DofConfig>(), 36);
        let auto = DofConfig::new(4, 3, &DofParams::default());
        assert_eq!((auto.passes, auto.rings), (0, 6));
    }

    #[test]
    fn the_sensor_spans_the_display_window_not_the_overscan() {
        let lens = Lens {
            focal_mm: 50.0,
            f_number: 2.0,
            focus: 2.0,
            sensor_mm: 36.0,
        };
        let params = DofParams::new(CocSource::Lens(lens));
        // A 1920-wide picture rendered with 40 px of overscan each side.
        let mut frame = Frame::new(2000, 4);
        frame.windows.display = crate::frame::Window {
            x: 0,
            y: 0,
            width: 1920,
            height: 4,
        };
        frame.depth = Some(vec![4.0; 8000]);
        // 17.094 px at 1920 wide (coc.rs's hand-computed value), not 17.806 at 2000.
        let coc = coc_plane(&frame, &params);
        assert!((coc[0] - 17.094).abs() < 1e-3, "{}", coc[0]);
    }
}
