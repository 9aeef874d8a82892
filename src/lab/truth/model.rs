//! The scene model: flat textured shapes at constant depths, each moved by a closed-form
//! transform of time, seen by a camera that pans and zooms, optionally through a thin lens.
//!
//! Coordinates: screen pixels, y down, at the scene's output size. A shape is defined in its
//! own local frame around its pivot; its motion maps local points to the parent's frame (the
//! world, or another shape for jointed limbs), and the camera maps the world to the screen.
//! All of it is f64 and evaluated in closed form, so the screen position of any surface point
//! at any time is exact — the passes are not finite differences of images.

use glam::{DAffine2, DVec2};

/// Linear RGB.
pub type Rgb = [f32; 3];

/// The outline of a shape in its local frame (pivot at the origin).
#[derive(Clone, Debug, PartialEq)]
pub enum Geometry {
    /// Axis-aligned rectangle centred on the pivot: half width, half height.
    Rect { half: DVec2 },
    /// Disc centred on the pivot.
    Disc { radius: f64 },
    /// Simple polygon (even-odd rule).
    Polygon { points: Vec<DVec2> },
    /// A tapered blade from the pivot along +x: length, width at the root and at the tip.
    Blade { length: f64, root: f64, tip: f64 },
    /// A gear: `teeth` trapezoid-free square teeth between the root and tip radii, with a hub
    /// hole of radius `hole`.
    Gear {
        teeth: u32,
        root: f64,
        tip: f64,
        hole: f64,
    },
    /// Nothing: a joint that only carries a transform for its children.
    None,
}

impl Geometry {
    pub fn contains(&self, p: DVec2) -> bool {
        match self {
            Geometry::Rect { half } => p.x.abs() <= half.x && p.y.abs() <= half.y,
            Geometry::Disc { radius } => p.length_squared() <= radius * radius,
            Geometry::Polygon { points } => {
                let mut inside = false;
                let mut j = points.len().wrapping_sub(1);
                for i in 0..points.len() {
                    let (a, b) = (points[i], points[j]);
                    if (a.y > p.y) != (b.y > p.y)
                        && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x
                    {
                        inside = !inside;
                    }
                    j = i;
                }
                inside
            }
            Geometry::Blade { length, root, tip } => {
                if p.x < 0.0 || p.x > *length {
                    return false;
                }
                let width = root + (tip - root) * p.x / length;
                p.y.abs() <= width * 0.5
            }
            Geometry::Gear {
                teeth,
                root,
                tip,
                hole,
            } => {
                let r = p.length();
                if r < *hole || r > *tip {
                    return false;
                }
                if r <= *root {
                    return true;
                }
                let turns = (p.y.atan2(p.x) / std::f64::consts::TAU).rem_euclid(1.0);
                (turns * *teeth as f64).fract() < 0.5
            }
            Geometry::None => false,
        }
    }

    /// Radius of a circle about the pivot that holds the whole shape.
    pub fn bound(&self) -> f64 {
        match self {
            Geometry::Rect { half } => half.length(),
            Geometry::Disc { radius } => *radius,
            Geometry::Polygon { points } => points.iter().map(|p| p.length()).fold(0.0, f64::max),
            Geometry::Blade { length, root, tip } => {
                DVec2::new(*length, root.max(*tip) * 0.5).length()
            }
            Geometry::Gear { tip, .. } => *tip,
            Geometry::None => 0.0,
        }
    }
}

/// Procedural colour in a shape's local frame (it moves with the shape).
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Solid(Rgb),
    Checker {
        a: Rgb,
        b: Rgb,
        size: f64,
    },
    /// Stripes across the direction `angle` (radians), `period` wide.
    Stripes {
        a: Rgb,
        b: Rgb,
        period: f64,
        angle: f64,
    },
    /// Linear ramp from `a` at `from` to `b` at `to`.
    Gradient {
        a: Rgb,
        b: Rgb,
        from: DVec2,
        to: DVec2,
    },
    /// A base texture moved by `by` (so a checker's cells can meet the frame's edges
    /// part-way).
    Shifted {
        base: Box<Texture>,
        by: DVec2,
    },
    /// A base texture with HDR spots (values above 1) centred on a grid of `period`.
    Spots {
        base: Box<Texture>,
        hot: Rgb,
        period: f64,
        radius: f64,
    },
}

impl Texture {
    pub fn color(&self, p: DVec2) -> Rgb {
        match self {
            Texture::Solid(c) => *c,
            Texture::Checker { a, b, size } => {
                let i = (p.x / size).floor() as i64 + (p.y / size).floor() as i64;
                if i.rem_euclid(2) == 0 {
                    *a
                } else {
                    *b
                }
            }
            Texture::Stripes {
                a,
                b,
                period,
                angle,
            } => {
                let u = p.x * angle.cos() + p.y * angle.sin();
                if (u / period).rem_euclid(1.0) < 0.5 {
                    *a
                } else {
                    *b
                }
            }
            Texture::Gradient { a, b, from, to } => {
                let d = *to - *from;
                let s = ((p - *from).dot(d) / d.length_squared()).clamp(0.0, 1.0) as f32;
                [
                    a[0] + (b[0] - a[0]) * s,
                    a[1] + (b[1] - a[1]) * s,
                    a[2] + (b[2] - a[2]) * s,
                ]
            }
            Texture::Shifted { base, by } => base.color(p - *by),
            Texture::Spots {
                base,
                hot,
                period,
                radius,
            } => {
                // Offset from the nearest grid point: spots sit on multiples of the period.
                let cell = p - (p / *period).round() * *period;
                if cell.length_squared() <= radius * radius {
                    *hot
                } else {
                    base.color(p)
                }
            }
        }
    }
}

/// A closed-form motion of time t (in frames): local → parent.
///
/// `M(t) = T(origin + velocity·t + ½·accel·t² + orbit(t)) · R(angle + spin·t + swing(t)) ·
/// S(scale·e^(grow·t))` where `orbit(t) = radius·(cos(ω t + φ), sin(ω t + φ))` and
/// `swing(t) = amplitude·sin(ω t + φ)`.
#[derive(Clone, Debug, PartialEq)]
pub struct Motion {
    pub origin: DVec2,
    pub velocity: DVec2,
    pub accel: DVec2,
    /// (radius, angular speed in radians per frame, phase).
    pub orbit: Option<(f64, f64, f64)>,
    /// (amplitude in radians, angular speed in radians per frame, phase).
    pub swing: Option<(f64, f64, f64)>,
    pub angle: f64,
    /// Radians per frame.
    pub spin: f64,
    pub scale: f64,
    /// Logarithmic growth per frame.
    pub grow: f64,
}

impl Motion {
    /// A motionless placement at `origin`.
    pub fn at(origin: DVec2) -> Motion {
        Motion {
            origin,
            velocity: DVec2::ZERO,
            accel: DVec2::ZERO,
            orbit: None,
            swing: None,
            angle: 0.0,
            spin: 0.0,
            scale: 1.0,
            grow: 0.0,
        }
    }

    pub fn moving(mut self, velocity: DVec2) -> Motion {
        self.velocity = velocity;
        self
    }

    pub fn accelerating(mut self, accel: DVec2) -> Motion {
        self.accel = accel;
        self
    }

    pub fn spinning(mut self, angle: f64, spin: f64) -> Motion {
        self.angle = angle;
        self.spin = spin;
        self
    }

    pub fn orbiting(mut self, radius: f64, omega: f64, phase: f64) -> Motion {
        self.orbit = Some((radius, omega, phase));
        self
    }

    pub fn swinging(mut self, amplitude: f64, omega: f64, phase: f64) -> Motion {
        self.swing = Some((amplitude, omega, phase));
        self
    }

    pub fn scaled(mut self, scale: f64, grow: f64) -> Motion {
        self.scale = scale;
        self.grow = grow;
        self
    }

    pub fn transform(&self, t: f64) -> DAffine2 {
        let mut position = self.origin + self.velocity * t + self.accel * (0.5 * t * t);
        if let Some((radius, omega, phase)) = self.orbit {
            let a = omega * t + phase;
            position += DVec2::new(a.cos(), a.sin()) * radius;
        }
        let scale = self.scale * (self.grow * t).exp();
        let mut angle = self.angle + self.spin * t;
        if let Some((amplitude, omega, phase)) = self.swing {
            angle += amplitude * (omega * t + phase).sin();
        }
        DAffine2::from_scale_angle_translation(DVec2::splat(scale), angle, position)
    }
}

/// The camera: pans (screen pixels per frame) and zooms (log scale per frame) about the
/// screen centre. Applied to everything.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub centre: DVec2,
    pub pan: DVec2,
    pub zoom: f64,
}

impl Camera {
    pub fn transform(&self, t: f64) -> DAffine2 {
        let s = (self.zoom * t).exp();
        DAffine2::from_translation(self.centre + self.pan * t)
            * DAffine2::from_scale(DVec2::splat(s))
            * DAffine2::from_translation(-self.centre)
    }
}

/// The scene's thin lens is the compositor's own ([`crate::dof::coc::Lens`]: its circle of
/// confusion is the one the DoF algorithms use); the renderer adds where a point lands
/// through a given aperture point.
pub use crate::dof::coc::Lens;

impl Lens {
    /// Screen offset in pixels, for an image `width` pixels wide, of the point at depth
    /// `depth` seen through the aperture point `l` (unit disk): `l · (A/2) · f' · (1/D − 1/P)`,
    /// with f' the lens-to-sensor distance `F·P / (P − F)`. Its length for |l| = 1 is the
    /// radius of the circle of confusion: `½·|A·F·(P − D) / (D·(P − F))|` on the sensor.
    pub fn offset(&self, l: DVec2, depth: f64, width: f64) -> DVec2 {
        let f = self.focal_mm / 1000.0;
        let aperture = f / self.f_number;
        let image_distance = f * self.focus / (self.focus - f);
        let pixels_per_metre = width / (self.sensor_mm / 1000.0);
        let inverse = if depth.is_finite() { 1.0 / depth } else { 0.0 };
        l * (0.5 * aperture * image_distance * (inverse - 1.0 / self.focus) * pixels_per_metre)
    }
}

/// One shape of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct Shape {
    pub geometry: Geometry,
    pub texture: Texture,
    /// Distance along the view axis (scene units). Constant over time.
    pub depth: f64,
    pub motion: Motion,
    /// Index of the shape whose frame this one's motion is relative to (a joint); must be
    /// lower than this shape's index.
    pub parent: Option<usize>,
}

/// A scene: shapes in front of a background, a camera, an optional lens.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    pub name: String,
    pub width: usize,
    pub height: usize,
    pub background: Texture,
    /// The background is a plane this far away, moving with the camera only.
    pub background_depth: f64,
    pub shapes: Vec<Shape>,
    pub camera: Camera,
    pub lens: Option<Lens>,
}

/// What a ray hits: its colour, depth, and which shape (None = background) at which local
/// point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub color: Rgb,
    pub depth: f64,
    pub shape: Option<usize>,
    pub local: DVec2,
}

/// Every shape's local→screen transform (and its inverse and screen bound) at one time.
#[derive(Clone, Debug)]
pub struct Posed {
    pub to_screen: Vec<DAffine2>,
    pub to_local: Vec<DAffine2>,
    /// Screen-space bounding box (min, max) of each shape, empty for joints.
    pub bounds: Vec<(DVec2, DVec2)>,
    pub background_to_local: DAffine2,
}

impl Scene {
    /// Shape indices, nearest first (stable for equal depths).
    pub fn front_to_back(&self) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.shapes.len())
            .filter(|&i| self.shapes[i].geometry != Geometry::None)
            .collect();
        order.sort_by(|&a, &b| self.shapes[a].depth.total_cmp(&self.shapes[b].depth));
        order
    }

    /// The local→screen transform of every shape at time t.
    pub fn pose(&self, t: f64) -> Posed {
        let camera = self.camera.transform(t);
        let mut world: Vec<DAffine2> = Vec::with_capacity(self.shapes.len());
        for shape in &self.shapes {
            let own = shape.motion.transform(t);
            let parent = shape.parent.map_or(DAffine2::IDENTITY, |p| world[p]);
            world.push(parent * own);
        }
        let to_screen: Vec<DAffine2> = world.iter().map(|w| camera * *w).collect();
        let to_local = to_screen.iter().map(|m| m.inverse()).collect();
        let bounds = self
            .shapes
            .iter()
            .zip(&to_screen)
            .map(|(shape, m)| {
                let r = shape.geometry.bound();
                let centre = m.translation;
                // The affine is a similarity: its scale is the length of a column.
                let extent = m.matrix2.x_axis.length() * r;
                (centre - DVec2::splat(extent), centre + DVec2::splat(extent))
            })
            .collect();
        Posed {
            to_screen,
            to_local,
            bounds,
            background_to_local: camera.inverse(),
        }
    }

    /// What the ray through screen point `p` hits in pose `posed`; with a lens, through the
    /// aperture point `lens_point` (unit disk).
    pub fn trace(&self, posed: &Posed, order: &[usize], p: DVec2, lens_point: DVec2) -> Hit {
        for &i in order {
            let shape = &self.shapes[i];
            let q = match &self.lens {
                Some(lens) => p + lens.offset(lens_point, shape.depth, self.width as f64),
                None => p,
            };
            let (lo, hi) = posed.bounds[i];
            if q.x < lo.x || q.y < lo.y || q.x > hi.x || q.y > hi.y {
                continue;
            }
            let local = posed.to_local[i].transform_point2(q);
            if shape.geometry.contains(local) {
                return Hit {
                    color: shape.texture.color(local),
                    depth: shape.depth,
                    shape: Some(i),
                    local,
                };
            }
        }
        let q = match &self.lens {
            Some(lens) => p + lens.offset(lens_point, self.background_depth, self.width as f64),
            None => p,
        };
        let local = posed.background_to_local.transform_point2(q);
        Hit {
            color: self.background.color(local),
            depth: self.background_depth,
            shape: None,
            local,
        }
    }

    /// Screen position at time t of the surface point hit at `hit` (local coordinates).
    pub fn screen_position(&self, hit: &Hit, t: f64) -> DVec2 {
        match hit.shape {
            Some(i) => {
                let mut m = self.shapes[i].motion.transform(t);
                let mut parent = self.shapes[i].parent;
                while let Some(p) = parent {
                    m = self.shapes[p].motion.transform(t) * m;
                    parent = self.shapes[p].parent;
                }
                (self.camera.transform(t) * m).transform_point2(hit.local)
            }
            None => self.camera.transform(t).transform_point2(hit.local),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::numeric::close;

    fn scene_with(shape: Shape) -> Scene {
        Scene {
            name: "test".into(),
            width: 100,
            height: 80,
            background: Texture::Solid([0.1; 3]),
            background_depth: 100.0,
            shapes: vec![shape],
            camera: Camera {
                centre: DVec2::new(50.0, 40.0),
                pan: DVec2::ZERO,
                zoom: 0.0,
            },
            lens: None,
        }
    }

    fn disc(motion: Motion) -> Shape {
        Shape {
            geometry: Geometry::Disc { radius: 30.0 },
            texture: Texture::Solid([1.0; 3]),
            depth: 5.0,
            motion,
            parent: None,
        }
    }

    #[test]
    fn pure_translation_positions_by_hand() {
        // A disc at (50, 40) moving (+3, -2) px per frame: the surface seen at (52.5, 41.5)
        // at t = 0 was at (49.5, 43.5) one frame before and will be at (55.5, 39.5).
        let scene = scene_with(disc(
            Motion::at(DVec2::new(50.0, 40.0)).moving(DVec2::new(3.0, -2.0)),
        ));
        let posed = scene.pose(0.0);
        let order = scene.front_to_back();
        let p = DVec2::new(52.5, 41.5);
        let hit = scene.trace(&posed, &order, p, DVec2::ZERO);
        assert_eq!(hit.shape, Some(0));
        assert!((scene.screen_position(&hit, -1.0) - DVec2::new(49.5, 43.5)).length() < 1e-12);
        assert!((scene.screen_position(&hit, 1.0) - DVec2::new(55.5, 39.5)).length() < 1e-12);
        assert!((scene.screen_position(&hit, 0.0) - p).length() < 1e-12);
    }

    #[test]
    fn pure_rotation_positions_by_hand() {
        // Spinning a quarter turn per frame about (50, 40) (y down, so +angle turns
        // clockwise on screen): the point 10 px right of the pivot was 10 px below it... in
        // screen terms, rotating (10, 0) by -90° gives (0, -10), by +90° gives (0, 10).
        let quarter = std::f64::consts::FRAC_PI_2;
        let scene = scene_with(disc(
            Motion::at(DVec2::new(50.0, 40.0)).spinning(0.0, quarter),
        ));
        let posed = scene.pose(0.0);
        let hit = scene.trace(
            &posed,
            &scene.front_to_back(),
            DVec2::new(60.0, 40.0),
            DVec2::ZERO,
        );
        let prev = scene.screen_position(&hit, -1.0);
        let next = scene.screen_position(&hit, 1.0);
        assert!((prev - DVec2::new(50.0, 30.0)).length() < 1e-9, "{prev}");
        assert!((next - DVec2::new(50.0, 50.0)).length() < 1e-9, "{next}");
        // Half a frame later it has turned 45°.
        let half = scene.screen_position(&hit, 0.5);
        let r = 10.0 / 2f64.sqrt();
        assert!(
            (half - DVec2::new(50.0 + r, 40.0 + r)).length() < 1e-9,
            "{half}"
        );
    }

    #[test]
    fn camera_pan_moves_the_background() {
        let mut scene = scene_with(disc(Motion::at(DVec2::new(-500.0, 0.0))));
        scene.camera.pan = DVec2::new(4.0, 0.0);
        let posed = scene.pose(0.0);
        let hit = scene.trace(
            &posed,
            &scene.front_to_back(),
            DVec2::new(10.5, 10.5),
            DVec2::ZERO,
        );
        assert_eq!(hit.shape, None);
        assert!((scene.screen_position(&hit, -1.0) - DVec2::new(6.5, 10.5)).length() < 1e-12);
    }

    #[test]
    fn thin_lens_circle_of_confusion_matches_the_formula() {
        // CoC = |A·F·(P − D) / (D·(P − F))| on the sensor, A = F/N.
        let lens = Lens {
            focal_mm: 50.0,
            f_number: 2.0,
            focus: 3.0,
            sensor_mm: 36.0,
        };
        let (f, n, p, d) = (0.05_f64, 2.0, 3.0, 10.0);
        let coc_sensor = ((f / n) * f * (p - d) / (d * (p - f))).abs();
        let width = 1920.0;
        let expected = coc_sensor * width / 0.036;
        assert!(close(lens.coc(d, width), expected, 1e-9 * expected));
        assert!(lens.coc(p, width) < 1e-9, "in focus at P");
        // The renderer's aperture offsets trace the compositor's circle of confusion.
        for depth in [0.5, 2.0, 10.0, f64::INFINITY] {
            let rendered = 2.0 * lens.offset(DVec2::X, depth, width).length();
            let coc = lens.coc(depth, width);
            assert!(
                close(rendered, coc, 1e-9 * coc.max(1.0)),
                "{depth}: {rendered} vs {coc}"
            );
        }
    }

    #[test]
    fn geometry_tests() {
        let blade = Geometry::Blade {
            length: 10.0,
            root: 4.0,
            tip: 2.0,
        };
        assert!(blade.contains(DVec2::new(5.0, 1.4)));
        assert!(!blade.contains(DVec2::new(5.0, 1.6)));
        assert!(!blade.contains(DVec2::new(-0.1, 0.0)));
        let square = Geometry::Polygon {
            points: vec![
                DVec2::new(-1.0, -1.0),
                DVec2::new(1.0, -1.0),
                DVec2::new(1.0, 1.0),
                DVec2::new(-1.0, 1.0),
            ],
        };
        assert!(square.contains(DVec2::ZERO));
        assert!(!square.contains(DVec2::new(1.5, 0.0)));
        let gear = Geometry::Gear {
            teeth: 4,
            root: 5.0,
            tip: 7.0,
            hole: 1.0,
        };
        assert!(gear.contains(DVec2::new(3.0, 0.0)));
        assert!(!gear.contains(DVec2::new(0.5, 0.0)));
        // First tooth spans angles [0, 45°).
        let a = 20f64.to_radians();
        assert!(gear.contains(DVec2::new(a.cos(), a.sin()) * 6.0));
        let a = 60f64.to_radians();
        assert!(!gear.contains(DVec2::new(a.cos(), a.sin()) * 6.0));
    }
}
