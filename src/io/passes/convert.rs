//! Motion from whatever a preset's motion section stores (velocity, offsets or positions,
//! backward or forward, scaled, y up) to the canonical pass needed (see the table in the
//! module above).

use crate::frame::{pixel_centre, Plane, Positions, Velocity};
use crate::io::preset::{Encoding, Meaning, Units, VectorSpec};

use super::validity::nearest_valid;

/// How one section's stored values become offsets, resolved for the file they come from
/// (RSMB's codes depend on its bit depth).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Decode {
    /// `stored - zero` times `scale`; `|stored - zero| <= dead_zone` reads as 0.
    Plain {
        zero: f32,
        scale: f32,
        dead_zone: f32,
    },
    /// An integer file's code `c = round(stored · levels)` (the reader normalised it by the
    /// largest code, `levels`) read as `(c - still) / still · max_displace`.
    Codes {
        levels: f32,
        still: f32,
        max_displace: f32,
    },
}

impl Decode {
    /// The decode of `spec` (the preset's section `pass`) for a channel of this sample type (`u8`, `u16`, `f16`, `f32`,
    /// `u32`), or why the file cannot be read with it.
    pub(super) fn resolve(
        spec: &VectorSpec,
        pass: &str,
        sample_type: &str,
    ) -> Result<Decode, String> {
        match spec.encoding {
            Encoding::Plain => Ok(Decode::Plain {
                zero: spec.zero,
                scale: spec.scale,
                dead_zone: spec.dead_zone,
            }),
            Encoding::Rsmb => {
                let max_displace = spec.max_displace.ok_or_else(|| {
                    spec.incomplete(pass)
                        .unwrap_or_else(|| "max_displace is missing".into())
                })?;
                // RE:Vision's FAQ, "The Math": 8-bit maps (-1, +1) to (0, 254) "because with
                // this scheme we can represent a 0 displacement with a pixel value of 127";
                // 16-bit maps (-MaxDisplace, +MaxDisplace) to (0, 65534), so 32767 is still.
                // https://revisionfx.com/support/faqs/motion_vector_FAQs/motion_vector_math
                let (levels, still) = match sample_type {
                    "u8" => (255.0, 127.0),
                    "u16" => (65535.0, 32767.0),
                    other => {
                        return Err(format!(
                            "encoding \"rsmb\" is documented for 8- and 16-bit integer images \
                             only, and this file stores {other} samples (RE:Vision's text on \
                             float files was not found): write the vectors as 8/16-bit PNG or \
                             TIFF, or use a preset with encoding \"plain\", zero and scale"
                        ))
                    }
                };
                Ok(Decode::Codes {
                    levels,
                    still,
                    max_displace,
                })
            }
        }
    }

    /// The offset a stored value stands for, in the file's axes, times `units` (1 for
    /// pixels, the image's width or height for normalised vectors).
    fn apply(self, stored: f32, units: f32) -> f32 {
        match self {
            Decode::Plain {
                zero,
                scale,
                dead_zone,
            } => {
                let d = stored - zero;
                if d.abs() <= dead_zone {
                    0.0
                } else {
                    d * (scale * units)
                }
            }
            Decode::Codes {
                levels,
                still,
                max_displace,
            } => {
                // The reader divided the code by `levels` in f32; rounding recovers it
                // exactly, so the still code reads as exactly 0.
                let code = (stored * levels).round();
                (code - still) / still * max_displace * units
            }
        }
    }
}

/// What filling invalid vectors did to one motion source.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Filled {
    /// Invalid vectors that took the motion of their nearest valid one.
    pub(super) filled: usize,
    /// True when no vector was valid, so every one reads as still.
    pub(super) none_valid: bool,
}

/// A decoded motion source in canonical units (pixels, y down): either offsets from the pixel
/// centre or absolute positions, pointing backward (to p(-1)) or forward (to p(+1)).
pub(super) struct MotionSource {
    x: Plane,
    y: Plane,
    z: Option<Plane>,
    absolute: bool,
    backward: bool,
}

impl MotionSource {
    pub(super) fn decode(
        spec: &VectorSpec,
        decode: Decode,
        mut x: Plane,
        mut y: Plane,
        z: Option<Plane>,
        width: usize,
        height: usize,
    ) -> MotionSource {
        let absolute = spec.meaning.is_position();
        let (sx, sy) = match spec.units {
            Units::Pixels => (1.0, 1.0),
            Units::Normalized => (width as f32, height as f32),
        };
        // Canonical offsets point to the *other* time; velocity and from_next point back to
        // the current frame, so they change sign.
        let sign = match spec.meaning {
            Meaning::Velocity | Meaning::FromNext => -1.0,
            _ => 1.0,
        };
        let map = |v: f32, s: f32| decode.apply(v, s) * sign;
        x.iter_mut().for_each(|v| *v = map(*v, sx));
        y.iter_mut().for_each(|v| *v = map(*v, sy));
        if spec.y_up {
            if absolute {
                let h = height as f32;
                y.iter_mut().for_each(|v| *v = h - *v);
            } else {
                y.iter_mut().for_each(|v| *v = -*v);
            }
        }
        MotionSource {
            x,
            y,
            z,
            absolute,
            backward: spec.meaning.is_backward(),
        }
    }

    /// Gives every vector whose `alpha` is below full-on (1.0; NaN counts as below) the
    /// motion of the nearest vector that is valid, in Euclidean distance between pixel
    /// centres ([`nearest_valid`]): an offset is copied as it is, an absolute position as
    /// the same offset from its own pixel centre, with its depth. With no valid vector at
    /// all every vector reads as still (and depth at that time as unknown).
    pub(super) fn fill_invalid(&mut self, alpha: &[f32], width: usize, height: usize) -> Filled {
        let valid: Vec<bool> = alpha.iter().map(|&a| a >= 1.0).collect();
        let invalid = valid.iter().filter(|&&v| !v).count();
        if invalid == 0 {
            return Filled::default();
        }
        let Some(nearest) = nearest_valid(&valid, width, height) else {
            for (i, (x, y)) in self.x.iter_mut().zip(self.y.iter_mut()).enumerate() {
                (*x, *y) = if self.absolute {
                    pixel_centre(i, width)
                } else {
                    (0.0, 0.0)
                };
            }
            self.z = None;
            return Filled {
                filled: 0,
                none_valid: true,
            };
        };
        for (i, &j) in nearest.iter().enumerate() {
            if valid[i] {
                continue;
            }
            let (mut x, mut y) = (self.x[j], self.y[j]);
            if self.absolute {
                let (from, to) = (pixel_centre(j, width), pixel_centre(i, width));
                x += to.0 - from.0;
                y += to.1 - from.1;
            }
            self.x[i] = x;
            self.y[i] = y;
            if let Some(z) = &mut self.z {
                z[i] = z[j];
            }
        }
        Filled {
            filled: invalid,
            none_valid: false,
        }
    }

    /// Canonical velocity p(0) - p(-1).
    pub(super) fn velocity(self, width: usize) -> Velocity {
        let MotionSource {
            mut x,
            mut y,
            absolute,
            backward,
            ..
        } = self;
        for (i, (vx, vy)) in x.iter_mut().zip(y.iter_mut()).enumerate() {
            let (cx, cy) = pixel_centre(i, width);
            let (dx, dy) = if absolute {
                (*vx - cx, *vy - cy)
            } else {
                (*vx, *vy)
            };
            // Backward offset d = p(-1) - p0, velocity -d; forward offset approximates it.
            if backward {
                *vx = -dx;
                *vy = -dy;
            } else {
                *vx = dx;
                *vy = dy;
            }
        }
        Velocity { x, y }
    }

    /// Absolute p(-1) (`want_prev`) or p(+1).
    pub(super) fn position(self, width: usize, want_prev: bool) -> Positions {
        let MotionSource {
            mut x,
            mut y,
            z,
            absolute,
            backward,
        } = self;
        let same_direction = backward == want_prev;
        for (i, (px, py)) in x.iter_mut().zip(y.iter_mut()).enumerate() {
            let (cx, cy) = pixel_centre(i, width);
            match (absolute, same_direction) {
                (true, true) => {}
                (true, false) => {
                    *px = 2.0 * cx - *px;
                    *py = 2.0 * cy - *py;
                }
                (false, true) => {
                    *px += cx;
                    *py += cy;
                }
                (false, false) => {
                    *px = cx - *px;
                    *py = cy - *py;
                }
            }
        }
        Positions {
            x,
            y,
            z: if same_direction { z } else { None },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::preset::Preset;
    use crate::numeric::close;

    fn rsmb(max_displace: f32) -> VectorSpec {
        let mut spec = Preset::builtin("rsmb").unwrap().velocity;
        spec.max_displace = Some(max_displace);
        spec
    }

    #[test]
    fn rsmb_codes_decode_by_bit_depth() {
        let spec = rsmb(10.0);
        let u8 = Decode::resolve(&spec, "velocity", "u8").unwrap();
        let u16 = Decode::resolve(&spec, "velocity", "u16").unwrap();
        // As the reader hands them over: codes divided by the largest code.
        let at8 = |code: u16| u8.apply(code as f32 / 255.0, 1.0);
        let at16 = |code: u16| u16.apply(code as f32 / 65535.0, 1.0);
        assert_eq!(at8(127), 0.0);
        assert_eq!(at8(254), 10.0);
        assert_eq!(at8(0), -10.0);
        assert_eq!(at16(32767), 0.0);
        assert_eq!(at16(65534), 10.0);
        assert_eq!(at16(0), -10.0);
        // The same stored value means different motion at the two depths.
        assert!(close(at8(191), 64.0 / 127.0 * 10.0, 1e-6));
        assert!(close(at16(49151), 16384.0 / 32767.0 * 10.0, 1e-6));
        for code in 0..=255u16 {
            let expected = (code as f32 - 127.0) / 127.0 * 10.0;
            assert_eq!(at8(code), expected, "code {code}");
        }
    }

    #[test]
    fn rsmb_refuses_float_and_needs_max_displace() {
        for sample_type in ["f16", "f32", "u32"] {
            let err = Decode::resolve(&rsmb(4.0), "next", sample_type).unwrap_err();
            assert!(err.contains("8- and 16-bit"), "{err}");
        }
        let mut spec = rsmb(4.0);
        spec.max_displace = None;
        let err = Decode::resolve(&spec, "next", "u8").unwrap_err();
        assert!(
            err.contains("[next] encoding \"rsmb\" needs max_displace"),
            "{err}"
        );
    }

    #[test]
    fn an_invalid_position_takes_its_neighbours_offset_and_depth() {
        // 3×1 absolute p(-1) positions, every valid one 2 px right and 1 px up of its
        // pixel; pixel 1 invalid (alpha one step short of full-on), holding garbage.
        let mut spec = Preset::builtin("shutter").unwrap().prev;
        spec.meaning = Meaning::PrevPosition;
        let decode = Decode::resolve(&spec, "prev", "f32").unwrap();
        let x = vec![0.5 + 2.0, 999.0, 2.5 + 2.0];
        let y = vec![0.5 - 1.0, -999.0, 0.5 - 1.0];
        let z = Some(vec![4.0, -1.0, 4.0]);
        let mut source = MotionSource::decode(&spec, decode, x, y, z, 3, 1);
        let filled = source.fill_invalid(&[1.0, 0.999, 1.0], 3, 1);
        assert_eq!(
            filled,
            Filled {
                filled: 1,
                none_valid: false
            }
        );
        let prev = source.position(3, true);
        assert_eq!(prev.x, [2.5, 3.5, 4.5]);
        assert_eq!(prev.y, [-0.5, -0.5, -0.5]);
        assert_eq!(prev.z.unwrap(), [4.0, 4.0, 4.0]);
    }

    #[test]
    fn plain_is_zero_and_scale_whatever_the_sample_type() {
        let mut spec = rsmb(4.0);
        spec.encoding = Encoding::Plain;
        spec.zero = 0.5;
        spec.scale = 64.0;
        for sample_type in ["u8", "u16", "f32"] {
            let decode = Decode::resolve(&spec, "velocity", sample_type).unwrap();
            assert_eq!(decode.apply(0.75, 1.0), 16.0);
            assert_eq!(decode.apply(0.75, 2.0), 32.0);
        }
    }
}
