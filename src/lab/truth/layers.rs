//! A truth scene split into two view layers, as Blender writes a multilayer render of them
//! (`shutter scene --layers`, `layers.####.exr`): `BG`, the farthest object (the background
//! plane) alone, and `FG`, every shape over a transparent film. Compositing them by hand,
//! each blurred alone and then `FG over BG`, is the baseline that the layered algorithms are
//! measured against (issue 33).
//!
//! Inputs: a scene, a frame time, the colour pass's samples and seed. Output: one
//! [`ViewLayer`] per layer, each with Blender's passes under Blender's names
//! (`{layer}.Combined.RGBA`, `{layer}.Depth.Z`, `{layer}.Vector.XYZW`), which the `blender`
//! preset reads with `--layer FG` or `--layer BG` (presets/blender.toml).
//!
//! - **Combined**: premultiplied, as Cycles' transparent film gives it: the sum of the
//!   layer's sample colours over the sample count, samples that miss the layer adding zero,
//!   and alpha the share of samples that hit it (antialiased coverage). The samples are the
//!   colour pass's own (`render::pixel_mean`, same sub-pixel positions), so where the
//!   background is uniform across a pixel `FG + (1 − FG.A)·BG` is the single-layer colour
//!   pass to rounding. Where the background changes inside a pixel that an FG edge also
//!   crosses, it is not: the separately antialiased layers lose which samples the FG hid, as
//!   they do in a real two-layer render.
//! - **Depth** and **Vector**: of the layer's surface seen at the pixel centre, as the
//!   single-layer passes are ([`super::render::render_passes`]). Vector is Blender's:
//!   pixels, y up, `X, Y = p(−1) − p(0)` and `Z, W = p(0) − p(+1)` (Cycles'
//!   `motion_pre − center`, `center − motion_post`; presets/blender.toml).
//! - **Empty pixels** of the FG (its pixel centre hits no shape): Depth [`EMPTY_DEPTH`] and
//!   Vector 0, what Cycles writes where a transparent-film layer's rays leave the scene: a
//!   ray that reaches the background writes depth 0, which the film reads out as 1e10
//!   (`film_get_pass_pixel_depth`), and no motion, so the Vector pass, divided by the weight
//!   of the samples that wrote one, is 0 (`film_get_pass_pixel_motion`). (Cycles takes a
//!   pixel's depth from its first sample and averages the vectors of the samples that hit a
//!   surface; here, as in the single-layer passes, both are the pixel centre's.)

use glam::DVec2;

use super::model::Scene;
use super::render::{pixel_mean, prev_next, render_planes};
use crate::frame::Plane;

/// Depth of a pixel whose centre sees nothing in its layer: Blender's 1e10 (the Z that
/// Cycles' film reads out where no surface was hit; the module's doc).
pub const EMPTY_DEPTH: f32 = 1e10;

/// The view layer of every shape (`FG`) and of the background plane (`BG`).
pub const FG: &str = "FG";
pub const BG: &str = "BG";

/// One view layer's passes, each a plane of `width × height` rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct ViewLayer {
    pub name: &'static str,
    /// Combined R, G, B (premultiplied) and A (coverage).
    pub combined: [Plane; 4],
    /// Depth Z, scene units; [`EMPTY_DEPTH`] where the pixel centre sees nothing.
    pub depth: Plane,
    /// Vector X, Y, Z, W: Blender's, pixels, y up (the module's doc); 0 where empty.
    pub vector: [Plane; 4],
}

impl ViewLayer {
    /// The layer's channels under Blender's multilayer names: `FG.Combined.R`, …,
    /// `FG.Depth.Z`, `FG.Vector.X`, ….
    pub fn channels(self) -> Vec<(String, Plane)> {
        let name = self.name;
        let combined = ["R", "G", "B", "A"].into_iter().zip(self.combined);
        let vector = ["X", "Y", "Z", "W"].into_iter().zip(self.vector);
        combined
            .map(|(c, p)| (format!("{name}.Combined.{c}"), p))
            .chain(std::iter::once((format!("{name}.Depth.Z"), self.depth)))
            .chain(vector.map(|(c, p)| (format!("{name}.Vector.{c}"), p)))
            .collect()
    }
}

/// Blender's Vector pass of the surface seen at `centre` that is at `prev` one frame earlier
/// and at `next` one frame later (screen pixels, y down): `p(−1) − p(0)` and `p(0) − p(+1)`
/// with y up, so the y components change sign.
fn blender_vector(centre: DVec2, prev: DVec2, next: DVec2) -> [f32; 4] {
    [
        (prev.x - centre.x) as f32,
        (centre.y - prev.y) as f32,
        (centre.x - next.x) as f32,
        (next.y - centre.y) as f32,
    ]
}

/// Values per pixel: FG's R, G, B, A, Z, X, Y, Z, W, then BG's R, G, B, Z, X, Y, Z, W.
const VALUES: usize = 17;

/// The two view layers of frame time `t`, `FG` then `BG`, antialiased with the colour pass's
/// `samples` sub-pixel samples and `seed` (the module's doc).
pub fn render_layers(scene: &Scene, t: f64, samples: usize, seed: u64) -> [ViewLayer; 2] {
    let (width, height) = (scene.width, scene.height);
    let samples = samples.max(1);
    let posed = scene.pose(t);
    let order = scene.front_to_back();
    // The background alone: no shape is traced.
    let nothing: [usize; 0] = [];
    let planes = render_planes::<VALUES>(width, height, |i, j| {
        let [fr, fg, fb, fa, br, bg, bb] = pixel_mean(i, j, width, samples, seed, |_, p| {
            let hit = scene.trace(&posed, &order, p, DVec2::ZERO);
            let back = scene.trace(&posed, &nothing, p, DVec2::ZERO).color;
            let [r, g, b] = match hit.shape {
                Some(_) => hit.color,
                None => [0.0; 3],
            };
            let covered = if hit.shape.is_some() { 1.0 } else { 0.0 };
            [r, g, b, covered, back[0], back[1], back[2]]
        });
        let centre = DVec2::new(i as f64 + 0.5, j as f64 + 0.5);
        let front = scene.trace(&posed, &order, centre, DVec2::ZERO);
        let (front_depth, front_vector) = match front.shape {
            Some(_) => {
                let (prev, next) = prev_next(scene, &front, centre, t);
                (front.depth as f32, blender_vector(centre, prev, next))
            }
            None => (EMPTY_DEPTH, [0.0; 4]),
        };
        let back = scene.trace(&posed, &nothing, centre, DVec2::ZERO);
        let (prev, next) = prev_next(scene, &back, centre, t);
        let [fx, fy, fz, fw] = front_vector;
        let [bx, by, bz, bw] = blender_vector(centre, prev, next);
        [
            fr,
            fg,
            fb,
            fa,
            front_depth,
            fx,
            fy,
            fz,
            fw,
            br,
            bg,
            bb,
            back.depth as f32,
            bx,
            by,
            bz,
            bw,
        ]
    });
    let mut it = planes.into_iter();
    let mut take = || it.next().expect("seventeen planes");
    let fg = ViewLayer {
        name: FG,
        combined: [take(), take(), take(), take()],
        depth: take(),
        vector: [take(), take(), take(), take()],
    };
    let bg = ViewLayer {
        name: BG,
        combined: [take(), take(), take(), vec![1.0; width * height]],
        depth: take(),
        vector: [take(), take(), take(), take()],
    };
    [fg, bg]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lab::truth::model::{Camera, Geometry, Motion, Shape, Texture};
    use crate::lab::truth::render::render_passes;
    use crate::numeric::close;

    const DISC: [f32; 3] = [0.9, 0.5, 0.2];
    const WALL: [f32; 3] = [0.1, 0.2, 0.3];

    /// A disc of radius 10 at (32.5, 20.5) at depth 5 moving (3, −2) px per frame (y down)
    /// over a plain wall at depth 100, seen by a camera that pans (0, 1) px per frame: on
    /// screen the disc moves (3, −1) and the wall (0, 1).
    fn disc_scene() -> Scene {
        Scene {
            name: "disc".into(),
            width: 64,
            height: 40,
            background: Texture::Solid(WALL),
            background_depth: 100.0,
            shapes: vec![Shape {
                geometry: Geometry::Disc { radius: 10.0 },
                texture: Texture::Solid(DISC),
                depth: 5.0,
                motion: Motion::at(DVec2::new(32.5, 20.5)).moving(DVec2::new(3.0, -2.0)),
                parent: None,
            }],
            camera: Camera {
                centre: DVec2::new(32.0, 20.0),
                pan: DVec2::new(0.0, 1.0),
                zoom: 0.0,
            },
            lens: None,
        }
    }

    /// Every pass of `layer` at pixel `(i, j)`: R, G, B, A, Depth, Vector X, Y, Z, W.
    fn at(layer: &ViewLayer, width: usize, (i, j): (usize, usize)) -> [f32; 9] {
        let k = j * width + i;
        let [r, g, b, a] = &layer.combined;
        let [x, y, z, w] = &layer.vector;
        [
            r[k],
            g[k],
            b[k],
            a[k],
            layer.depth[k],
            x[k],
            y[k],
            z[k],
            w[k],
        ]
    }

    /// Blender's vectors worked out by hand: the disc moves (3, −1) on screen, y down, so it
    /// was 3 px left and 1 px lower, which is y-up −1: X, Y = (−3, −1), and for linear
    /// motion Z, W = p(0) − p(+1) = the same. The wall moves (0, 1) down: (0, +1, 0, +1).
    #[test]
    fn layers_hold_blender_passes_worked_out_by_hand() {
        let scene = disc_scene();
        let [fg, bg] = render_layers(&scene, 0.0, 16, 1);
        assert_eq!((fg.name, bg.name), ("FG", "BG"));
        let w = scene.width;
        let [r, g, b] = DISC;
        let [wr, wg, wb] = WALL;
        // The disc's centre pixel, and a corner that only the wall reaches.
        assert_eq!(
            at(&fg, w, (32, 20)),
            [r, g, b, 1.0, 5.0, -3.0, -1.0, -3.0, -1.0]
        );
        assert_eq!(
            at(&bg, w, (32, 20)),
            [wr, wg, wb, 1.0, 100.0, 0.0, 1.0, 0.0, 1.0]
        );
        assert_eq!(
            at(&fg, w, (2, 2)),
            [0.0, 0.0, 0.0, 0.0, 1e10, 0.0, 0.0, 0.0, 0.0]
        );
        assert_eq!(
            at(&bg, w, (2, 2)),
            [wr, wg, wb, 1.0, 100.0, 0.0, 1.0, 0.0, 1.0]
        );
        // On the disc's edge, 10 px right of its centre, coverage is partial and the colour
        // premultiplied by it.
        let edge = at(&fg, w, (42, 20));
        assert!(edge[3] > 0.2 && edge[3] < 0.8, "{edge:?}");
        assert!(close(edge[0], r * edge[3], 1e-6), "{edge:?}");
    }

    #[test]
    fn layers_are_named_as_blender_names_a_multilayer_render() {
        let scene = disc_scene();
        let [fg, _] = render_layers(&scene, 0.0, 1, 1);
        let names: Vec<String> = fg.channels().into_iter().map(|(n, _)| n).collect();
        let expected = [
            "FG.Combined.R",
            "FG.Combined.G",
            "FG.Combined.B",
            "FG.Combined.A",
            "FG.Depth.Z",
            "FG.Vector.X",
            "FG.Vector.Y",
            "FG.Vector.Z",
            "FG.Vector.W",
        ];
        assert_eq!(names, expected);
    }

    /// `FG over BG` is the single-layer colour pass, to rounding, at every pixel, the ones the
    /// FG covers in part included: the layers split the colour pass's own samples. The wall
    /// is plain, so that the over is exact (the module's doc: a wall that changes inside a
    /// pixel an FG edge crosses is not recovered by any split into two antialiased layers).
    /// The rotor's blades (a spin, edges at every angle) and its striped, spotted texture
    /// stand in for FG.
    #[test]
    fn fg_over_bg_is_the_colour_pass_where_coverage_is_fractional() {
        let mut scene = super::super::scenes::build("rotor", 96, 54, 1).unwrap();
        scene.background = Texture::Solid(WALL);
        let single = render_passes(&scene, 0.0, 32, 7).color.unwrap();
        let [fg, bg] = render_layers(&scene, 0.0, 32, 7);
        let alpha = &fg.combined[3];
        let mut fractional = 0;
        for (c, single) in [&single.r, &single.g, &single.b].into_iter().enumerate() {
            for k in 0..alpha.len() {
                let over = fg.combined[c][k] + (1.0 - alpha[k]) * bg.combined[c][k];
                assert!(
                    close(over, single[k], 1e-6 * single[k].max(1.0)),
                    "channel {c}, pixel {k}: over {over}, colour pass {}",
                    single[k]
                );
            }
        }
        for &a in alpha {
            fractional += usize::from(a > 0.0 && a < 1.0);
        }
        // The blades' outlines cross some hundreds of pixels at this size.
        assert!(fractional > 100, "{fractional} pixels covered in part");
    }
}
