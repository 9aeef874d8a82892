//! `coc`: the circle of confusion of a thin lens, in pixels, and the stage that makes the
//! signed CoC plane both depth-of-field methods read ([`coc_plane`], the first stage of
//! [`super::apply`]; its GPU twin is `crate::gpu::dof::coc`, which reads a [`CocConfig`]).
//!
//! For focal length F, f-number N (aperture diameter A = F/N), focus distance P and a point
//! at depth D, the blur circle on the sensor has diameter
//! `|A·F·(P − D) / (D·(P − F))|` (Sousa's simplification of Potmesil & Chakravarty 1981).
//! Wloka's talk writes the same thing as `|(P/D − 1)·F² / (N·(P − F))|`; the tests show the
//! three forms agree. It is converted to pixels with the sensor width: an image `width`
//! pixels wide spans `sensor_mm` of sensor.
//!
//! The signed form is positive behind the focus plane (the far field) and negative in front
//! of it (the near field), as the near/far split of the gather needs.
//!
//! In: the depth plane (or a painted map read as depth). Out: the signed CoC diameter of
//! every pixel, clamped to ±`max_coc`.

use rayon::prelude::*;

use super::{CocSource, DofParams};
use crate::frame::Frame;
use crate::numeric::shown;

/// A thin lens. Distances (focus and depth) in metres, the focal length's unit once it is
/// out of millimetres: depth in other units is scaled on read (a preset's `[depth] scale`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lens {
    /// Focal length F, mm.
    pub focal_mm: f64,
    /// f-number N.
    pub f_number: f64,
    /// Focus distance P, metres.
    pub focus: f64,
    /// Sensor (film) width, mm (36 for full frame).
    pub sensor_mm: f64,
}

/// A [`Lens`] for one image width: [`PixelCoc::signed`] is [`Lens::signed_coc`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelCoc {
    /// Focus distance P, metres.
    focus: f64,
    /// The CoC in pixels per unit of (P/D − 1).
    scale: f64,
}

impl PixelCoc {
    /// Signed CoC diameter in pixels at `depth` (see [`Lens::signed_coc`]): (P − D)/D is
    /// written P/D − 1, so D = ∞ is exact.
    #[inline]
    pub fn signed(&self, depth: f64) -> f64 {
        let depth = if depth.is_nan() { f64::INFINITY } else { depth };
        if depth <= 0.0 {
            return -LARGEST;
        }
        (self.scale * (self.focus / depth - 1.0)).clamp(-LARGEST, LARGEST)
    }
}

/// Circles of confusion larger than this many pixels are clamped (a point at depth 0).
pub const LARGEST: f64 = 1e6;

impl Lens {
    /// A full-frame (35 mm) sensor's width: the default.
    pub const DEFAULT_SENSOR_MM: f64 = 36.0;

    /// Why these settings cannot describe a lens, if they cannot.
    pub fn check(&self) -> Result<(), String> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.focal_mm) {
            return Err(format!(
                "focal length {} mm: use a positive length",
                shown(self.focal_mm)
            ));
        }
        if !positive(self.f_number) {
            return Err(format!(
                "f-stop {}: use a positive f-number",
                shown(self.f_number)
            ));
        }
        if !positive(self.sensor_mm) {
            return Err(format!(
                "sensor width {} mm: use a positive width",
                shown(self.sensor_mm)
            ));
        }
        if !(self.focus.is_finite() && self.focus > self.focal_mm / 1000.0) {
            return Err(format!(
                "focus distance {}: use a distance beyond the focal length ({} m)",
                shown(self.focus),
                shown(self.focal_mm / 1000.0)
            ));
        }
        Ok(())
    }

    /// Signed circle-of-confusion diameter in pixels at `depth`, for an image `width` pixels
    /// wide: positive behind the focus plane, negative in front. Infinite depth gives the
    /// far limit `A·F / (P − F)`; NaN depth counts as infinite; depth 0 or less gives
    /// −[`LARGEST`].
    pub fn signed_coc(&self, depth: f64, width: f64) -> f64 {
        self.in_pixels(width).signed(depth)
    }

    /// The lens for an image `width` pixels wide, with what does not depend on depth worked
    /// out once (the CoC plane evaluates it at every pixel).
    pub fn in_pixels(&self, width: f64) -> PixelCoc {
        let f = self.focal_mm / 1000.0;
        let aperture = f / self.f_number;
        let p = self.focus;
        PixelCoc {
            focus: p,
            // On the sensor the diameter is −A·F·(P/D − 1)/(P − F); in pixels, times
            // width / sensor width.
            scale: -aperture * f / (p - f) * width / (self.sensor_mm / 1000.0),
        }
    }

    /// Circle-of-confusion diameter in pixels (the magnitude of [`Lens::signed_coc`]).
    pub fn coc(&self, depth: f64, width: f64) -> f64 {
        self.signed_coc(depth, width).abs()
    }
}

/// Wloka's form, on the sensor in metres: `|(P/D − 1)·F² / (N·(P − F))|`.
pub fn coc_wloka(depth: f64, focus: f64, focal: f64, f_number: f64) -> f64 {
    ((focus / depth - 1.0) * focal * focal / (f_number * (focus - focal))).abs()
}

/// Potmesil's unsimplified form as Sousa's slides give it, on the sensor in metres:
/// `|F·D/(D − F) − F·P/(P − F)| · (D − F)/(N·D)`.
pub fn coc_potmesil(depth: f64, focus: f64, focal: f64, f_number: f64) -> f64 {
    (focal * depth / (depth - focal) - focal * focus / (focus - focal)).abs() * (depth - focal)
        / (f_number * depth)
}

/// The signed CoC diameter of every pixel, in pixels, clamped to ±`max_coc`; NaN never comes
/// out (NaN depth is far; zero and negative depth are nearest).
///
/// The thin lens is evaluated in f64 (its twin folds it into [`CocConfig`] and works in f32,
/// a difference bounded and tested in tests/gpu_dof.rs), so this stage reads the parameters,
/// not the config.
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

/// The `coc` stage's uniform, as its GPU twin reads it (`CocConfig` in
/// src/gpu/dof/coc.wgsl; a test there holds the two layouts together): eight 4-byte fields,
/// a multiple of 16 bytes as uniforms need.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "gpu", derive(bytemuck::Pod, bytemuck::Zeroable))]
#[repr(C)]
pub struct CocConfig {
    /// Frame size, pixels.
    pub width: u32,
    pub height: u32,
    /// 0: the thin lens and the depth pass; 1: a painted map.
    pub source: u32,
    /// The largest |CoC| (px): `max_coc`.
    pub limit: f32,
    /// lens: K, the far-limit CoC (px), `Lens::signed_coc(∞)`. map: the CoC of a stored 1.
    pub scale: f32,
    /// lens: the focus distance P (scene units).
    pub focus: f32,
    /// map: limit/scale, the largest stored value below the limit (0 when scale is 0).
    pub cap: f32,
    pub _pad: u32,
}

impl CocConfig {
    /// The uniform for a `width`×`height` frame whose picture (display window) is
    /// `display_width` pixels wide (0: the frame's width), as [`coc_plane`] reads them.
    pub fn new(width: usize, height: usize, display_width: usize, params: &DofParams) -> Self {
        let limit = params.max_coc.min(LARGEST as f32);
        let mut config = CocConfig {
            width: width as u32,
            height: height as u32,
            source: 0,
            limit,
            scale: 0.0,
            focus: 0.0,
            cap: 0.0,
            _pad: 0,
        };
        match params.source {
            CocSource::Lens(lens) => {
                // The sensor spans the display window, as on the CPU.
                let span = if display_width > 0 {
                    display_width
                } else {
                    width
                } as f64;
                // The CPU's own function at D = ∞ gives K rounded exactly as it rounds the
                // far field; it is at most LARGEST (1e6), far below the 1e15 the shader's
                // floor on P/D assumes.
                config.scale = lens.signed_coc(f64::INFINITY, span) as f32;
                config.focus = lens.focus as f32;
            }
            CocSource::Map { scale } => {
                config.source = 1;
                config.scale = scale;
                config.cap = if scale > 0.0 {
                    ((limit as f64 / scale as f64).min(f32::MAX as f64)) as f32
                } else {
                    0.0
                };
            }
        }
        config
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    const LENS: Lens = Lens {
        focal_mm: 50.0,
        f_number: 2.0,
        focus: 2.0,
        sensor_mm: 36.0,
    };

    #[test]
    fn hand_computed_values() {
        // F = 0.05 m, A = 0.025 m, P = 2 m, 1920 px over 36 mm (53.33 px per mm).
        // D = 4 m: 0.025·0.05·(2 − 4)/(4·1.95) = −3.2051e-4 m = 0.32051 mm → 17.094 px.
        let far = LENS.signed_coc(4.0, 1920.0);
        assert!(close(far, 17.094, 1e-3), "{far}");
        // D = 1 m: 0.025·0.05·1/(1·1.95) = 6.4103e-4 m → 34.188 px, in front.
        let near = LENS.signed_coc(1.0, 1920.0);
        assert!(close(near, -34.188, 1e-3), "{near}");
        // D = ∞: A·F/(P − F) = 0.00125/1.95 m → 34.188 px, behind.
        assert!(close(LENS.signed_coc(f64::INFINITY, 1920.0), 34.188, 1e-3));
        assert!(close(LENS.signed_coc(f64::NAN, 1920.0), 34.188, 1e-3));
        // In focus at P; degenerate depths are clamped, never NaN.
        assert!(LENS.coc(2.0, 1920.0) < 1e-12);
        assert_eq!(LENS.signed_coc(0.0, 1920.0), -LARGEST);
        assert_eq!(LENS.signed_coc(-3.0, 1920.0), -LARGEST);
        assert!(LENS.signed_coc(1e-300, 1920.0).is_finite());
    }

    #[test]
    fn the_seeds_formulas_agree() {
        for (d, p, f, n) in [
            (4.0, 2.0, 0.05, 2.0),
            (1.0, 2.0, 0.05, 2.0),
            (0.7, 3.0, 0.085, 1.4),
            (30.0, 5.0, 0.024, 8.0),
        ] {
            let sousa = (f / n) * f * (p - d) / (d * (p - f));
            let lens = Lens {
                focal_mm: f * 1000.0,
                f_number: n,
                focus: p,
                sensor_mm: 36.0,
            };
            let ours = lens.coc(d, 36.0) / 1000.0; // 36 px over 36 mm: px = mm
            for other in [coc_wloka(d, p, f, n), coc_potmesil(d, p, f, n), ours] {
                assert!(
                    close(other, sousa.abs(), 1e-12 + 1e-9 * sousa.abs()),
                    "D={d}: {other} vs {sousa}"
                );
            }
        }
    }

    #[test]
    fn settings_are_checked() {
        assert!(LENS.check().is_ok());
        assert!(Lens {
            f_number: 0.0,
            ..LENS
        }
        .check()
        .is_err());
        assert!(Lens {
            focus: 0.04,
            ..LENS
        }
        .check()
        .is_err());
        assert!(Lens {
            focal_mm: f64::NAN,
            ..LENS
        }
        .check()
        .is_err());
        assert!(Lens {
            sensor_mm: -1.0,
            ..LENS
        }
        .check()
        .is_err());
    }

    #[test]
    fn the_sensor_spans_the_display_window_not_the_overscan() {
        let params = DofParams::new(CocSource::Lens(LENS));
        // A 1920-wide picture rendered with 40 px of overscan each side.
        let mut frame = Frame::new(2000, 4);
        frame.windows.display = crate::frame::Window {
            x: 0,
            y: 0,
            width: 1920,
            height: 4,
        };
        frame.depth = Some(vec![4.0; 8000]);
        // 17.094 px at 1920 wide (the hand-computed value above), not 17.806 at 2000.
        let coc = coc_plane(&frame, &params);
        assert!(close(coc[0], 17.094, 1e-3), "{}", coc[0]);
    }

    #[test]
    fn the_config_s_far_limit_is_the_cpu_s_own() {
        let config = CocConfig::new(1920, 4, 0, &DofParams::new(CocSource::Lens(LENS)));
        // A·F/(P − F) at 1920 px over 36 mm: 34.188 px (above).
        assert!(close(config.scale, 34.188, 1e-3), "{}", config.scale);
        assert_eq!(config.source, 0);
        let map = CocConfig::new(4, 4, 0, &DofParams::default());
        assert_eq!((map.source, map.scale, map.cap), (1, 32.0, 1.5));
    }
}
