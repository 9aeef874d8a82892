//! Motion from whatever a preset's motion section stores (velocity, offsets or positions,
//! backward or forward, scaled, y up) to the canonical pass needed (see the table in the
//! module above).

use crate::frame::{pixel_centre, Plane, Positions, Velocity};
use crate::io::preset::{Meaning, Units, VectorSpec};

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
        mut x: Plane,
        mut y: Plane,
        z: Option<Plane>,
        width: usize,
        height: usize,
    ) -> MotionSource {
        let absolute = spec.meaning.is_position();
        let (sx, sy) = match spec.units {
            Units::Pixels => (spec.scale, spec.scale),
            Units::Normalized => (spec.scale * width as f32, spec.scale * height as f32),
        };
        // Canonical offsets point to the *other* time; velocity and from_next point back to
        // the current frame, so they change sign.
        let sign = match spec.meaning {
            Meaning::Velocity | Meaning::FromNext => -1.0,
            _ => 1.0,
        };
        let map = |v: f32, s: f32| {
            let d = v - spec.zero;
            if d.abs() <= spec.dead_zone {
                0.0
            } else {
                d * s * sign
            }
        };
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
