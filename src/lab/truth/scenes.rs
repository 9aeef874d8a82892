//! The procedural scenes. Each is laid out for any output size: lengths are in units of
//! `u = height / 360` (the default size is 640×360), speeds in pixels per frame scale with it.
//! `seed` varies the layout of the scenes that are random by design (orbit).

use std::f64::consts::{PI, TAU};

use glam::DVec2;

use super::model::{Camera, Geometry, Lens, Motion, Rgb, Scene, Shape, Texture};
use super::sample::hash01;

/// Every scene, by name, with what it exercises.
pub const SCENES: &[(&str, &str)] = &[
    ("rotor", "spinning blades: non-linear motion"),
    (
        "orbit",
        "many small objects on curved paths at different depths: chaotic",
    ),
    ("figure", "limbs rotating about joints"),
    (
        "crossing",
        "two objects crossing at different depths in opposite directions",
    ),
    ("pan", "the camera pans while tracking a sharp object"),
    ("zoom", "the camera zooms: radial motion"),
    ("gears", "interlocking gears turning opposite ways"),
    ("static", "nothing moves"),
    ("sparse", "one small object moves (under 5% of pixels)"),
    ("huge", "motion of several hundred pixels per frame"),
    (
        "layers",
        "objects at many depths, with a lens, for depth of field",
    ),
    (
        "border",
        "85 mm f/1.2: a fine far texture meeting every frame edge, a near disc, a card in focus",
    ),
    (
        "border-coarse",
        "the same lens over a coarse spotted wall, the near disc cut by the frame's corner",
    ),
    (
        "border-cut",
        "the fine far texture meeting the frame's edges part-way, the near disc cut by the right edge",
    ),
    (
        "follow",
        "the camera follows a still subject before stripes streaming 36 px a frame",
    ),
    (
        "follow-wall",
        "the camera follows a still disc diagonally before the spotted wall",
    ),
];

const WALL_A: Rgb = [0.18, 0.17, 0.15];
const WALL_B: Rgb = [0.05, 0.06, 0.07];

fn wall(u: f64) -> Texture {
    Texture::Spots {
        base: Box::new(Texture::Checker {
            a: WALL_A,
            b: WALL_B,
            size: 24.0 * u,
        }),
        hot: [2.5, 2.2, 1.6],
        period: 96.0 * u,
        radius: 2.5 * u,
    }
}

fn shape(geometry: Geometry, texture: Texture, depth: f64, motion: Motion) -> Shape {
    Shape {
        geometry,
        texture,
        depth,
        motion,
        parent: None,
    }
}

fn stripes(a: Rgb, b: Rgb, period: f64, angle: f64) -> Texture {
    Texture::Stripes {
        a,
        b,
        period,
        angle,
    }
}

/// Builds the named scene at the given size, or `None` for an unknown name.
pub fn build(name: &str, width: usize, height: usize, seed: u64) -> Option<Scene> {
    let u = height as f64 / 360.0;
    let (w, h) = (width as f64, height as f64);
    let centre = DVec2::new(w * 0.5, h * 0.5);
    let mut scene = Scene {
        name: name.to_string(),
        width,
        height,
        background: wall(u),
        background_depth: 50.0,
        shapes: Vec::new(),
        camera: Camera {
            centre,
            pan: DVec2::ZERO,
            zoom: 0.0,
        },
        lens: None,
    };
    let shapes = &mut scene.shapes;
    match name {
        "rotor" => {
            let spin = 0.35; // radians per frame: 20° — tips move ~45 px at the default size
            for k in 0..4 {
                shapes.push(shape(
                    Geometry::Blade {
                        length: 130.0 * u,
                        root: 34.0 * u,
                        tip: 18.0 * u,
                    },
                    Texture::Spots {
                        base: Box::new(stripes(
                            [0.85, 0.25, 0.08],
                            [0.95, 0.8, 0.3],
                            14.0 * u,
                            0.0,
                        )),
                        hot: [6.0, 5.0, 3.0],
                        period: 40.0 * u,
                        radius: 3.0 * u,
                    },
                    5.0,
                    Motion::at(centre).spinning(k as f64 * TAU / 4.0, spin),
                ));
            }
            shapes.push(shape(
                Geometry::Disc { radius: 22.0 * u },
                Texture::Checker {
                    a: [0.7, 0.7, 0.75],
                    b: [0.2, 0.2, 0.25],
                    size: 8.0 * u,
                },
                4.9,
                Motion::at(centre).spinning(0.0, spin),
            ));
        }
        "orbit" => {
            for k in 0..36u64 {
                let r = |i: u64| hash01(seed, 7, k, i);
                let depth = 2.0 + 20.0 * r(0);
                let size = (6.0 + 16.0 * r(1)) * u;
                let geometry = match k % 3 {
                    0 => Geometry::Disc { radius: size },
                    1 => Geometry::Rect {
                        half: DVec2::new(size, size * 0.6),
                    },
                    _ => Geometry::Polygon {
                        points: (0..5)
                            .map(|i| {
                                let a = i as f64 * TAU / 5.0;
                                let radius = if i % 2 == 0 { size } else { size * 0.6 };
                                DVec2::new(a.cos(), a.sin()) * radius
                            })
                            .collect(),
                    },
                };
                let hue = [r(2) as f32, r(3) as f32, r(4) as f32];
                let texture = stripes(
                    [hue[0] * 1.5, hue[1], hue[2] * 0.5],
                    [hue[2] * 0.3, hue[0] * 0.6, hue[1] * 1.2],
                    5.0 * u,
                    r(5) * PI,
                );
                let orbit_centre = DVec2::new(w * (0.15 + 0.7 * r(6)), h * (0.15 + 0.7 * r(7)));
                let omega = (0.08 + 0.25 * r(8)) * if r(9) < 0.5 { -1.0 } else { 1.0 };
                shapes.push(shape(
                    geometry,
                    texture,
                    depth,
                    Motion::at(orbit_centre)
                        .orbiting((30.0 + 90.0 * r(10)) * u, omega, r(11) * TAU)
                        .spinning(r(12) * TAU, (r(13) - 0.5) * 0.6),
                ));
            }
        }
        "figure" => {
            let torso_colour = stripes([0.2, 0.35, 0.8], [0.1, 0.15, 0.4], 10.0 * u, 0.3);
            let limb = |colour: Rgb| stripes(colour, [0.9, 0.85, 0.7], 8.0 * u, PI / 2.0);
            // Torso walks right, 3 px per frame.
            shapes.push(shape(
                Geometry::Rect {
                    half: DVec2::new(28.0 * u, 60.0 * u),
                },
                torso_colour,
                6.0,
                Motion::at(DVec2::new(w * 0.42, h * 0.45)).moving(DVec2::new(3.0 * u, 0.0)),
            ));
            shapes.push(shape(
                Geometry::Disc { radius: 22.0 * u },
                Texture::Solid([0.9, 0.7, 0.55]),
                6.0,
                Motion::at(DVec2::new(0.0, -88.0 * u)),
            ));
            shapes.last_mut().expect("head").parent = Some(0);
            // Limbs: (joint in torso frame, swing phase, colour, depth offset).
            let limbs = [
                (DVec2::new(-30.0 * u, -52.0 * u), 0.0, [0.8, 0.2, 0.2], -0.2),
                (DVec2::new(30.0 * u, -52.0 * u), PI, [0.2, 0.7, 0.3], 0.2),
                (DVec2::new(-16.0 * u, 58.0 * u), PI, [0.7, 0.5, 0.1], -0.1),
                (DVec2::new(16.0 * u, 58.0 * u), 0.0, [0.3, 0.5, 0.8], 0.1),
            ];
            for (joint, phase, colour, dz) in limbs {
                let upper = shapes.len();
                shapes.push(Shape {
                    geometry: Geometry::Blade {
                        length: 62.0 * u,
                        root: 18.0 * u,
                        tip: 14.0 * u,
                    },
                    texture: limb(colour),
                    depth: 6.0 + dz,
                    motion: Motion::at(joint)
                        .spinning(PI / 2.0, 0.0)
                        .swinging(0.9, 0.5, phase),
                    parent: Some(0),
                });
                shapes.push(Shape {
                    geometry: Geometry::Blade {
                        length: 55.0 * u,
                        root: 14.0 * u,
                        tip: 10.0 * u,
                    },
                    texture: limb([colour[1], colour[2], colour[0]]),
                    depth: 6.0 + dz * 1.5,
                    motion: Motion::at(DVec2::new(60.0 * u, 0.0)).swinging(0.7, 0.5, phase + 1.0),
                    parent: Some(upper),
                });
            }
        }
        "crossing" => {
            shapes.push(shape(
                Geometry::Rect {
                    half: DVec2::new(60.0 * u, 45.0 * u),
                },
                Texture::Checker {
                    a: [0.9, 0.3, 0.1],
                    b: [0.95, 0.9, 0.8],
                    size: 10.0 * u,
                },
                4.0,
                Motion::at(DVec2::new(w * 0.5, h * 0.42)).moving(DVec2::new(24.0 * u, 0.0)),
            ));
            shapes.push(shape(
                Geometry::Rect {
                    half: DVec2::new(70.0 * u, 55.0 * u),
                },
                stripes([0.1, 0.4, 0.9], [0.6, 0.9, 1.0], 12.0 * u, 0.8),
                12.0,
                Motion::at(DVec2::new(w * 0.5, h * 0.58)).moving(DVec2::new(-24.0 * u, 0.0)),
            ));
        }
        "pan" => {
            let pan = DVec2::new(-10.0 * u, 0.0);
            scene.camera.pan = pan;
            // Props fixed in the world: they blur with the pan.
            for k in 0..6 {
                shapes.push(shape(
                    Geometry::Rect {
                        half: DVec2::new(10.0 * u, 70.0 * u),
                    },
                    stripes([0.6, 0.6, 0.1], [0.2, 0.2, 0.05], 9.0 * u, PI / 2.0),
                    20.0,
                    Motion::at(DVec2::new(w * (0.1 + 0.17 * k as f64), h * 0.5)),
                ));
            }
            // The tracked object moves with the camera: sharp on screen.
            shapes.push(shape(
                Geometry::Disc { radius: 60.0 * u },
                Texture::Spots {
                    base: Box::new(Texture::Checker {
                        a: [0.95, 0.95, 0.95],
                        b: [0.1, 0.5, 0.2],
                        size: 12.0 * u,
                    }),
                    hot: [4.0, 4.0, 4.0],
                    period: 30.0 * u,
                    radius: 2.0 * u,
                },
                5.0,
                Motion::at(centre).moving(-pan),
            ));
        }
        "zoom" => {
            scene.camera.zoom = 0.05;
            for k in 0..8 {
                let a = k as f64 * TAU / 8.0;
                shapes.push(shape(
                    Geometry::Rect {
                        half: DVec2::new(14.0 * u, 14.0 * u),
                    },
                    Texture::Checker {
                        a: [0.9, 0.9, 0.2],
                        b: [0.3, 0.1, 0.6],
                        size: 7.0 * u,
                    },
                    8.0,
                    Motion::at(centre + DVec2::new(a.cos(), a.sin()) * 120.0 * u).spinning(a, 0.0),
                ));
            }
        }
        "gears" => {
            let teeth = 16;
            let (root, tip) = (58.0 * u, 70.0 * u);
            let pitch = (root + tip) * 0.5;
            let spin = 0.12;
            let half_tooth = TAU / teeth as f64 / 2.0;
            let gear = |c: Rgb| Texture::Gradient {
                a: c,
                b: [c[0] * 0.3, c[1] * 0.3, c[2] * 0.3],
                from: DVec2::new(-tip, -tip),
                to: DVec2::new(tip, tip),
            };
            let left = DVec2::new(w * 0.5 - pitch, h * 0.5);
            let right = DVec2::new(w * 0.5 + pitch, h * 0.5);
            let below = right + DVec2::new(0.0, 2.0 * pitch);
            shapes.push(shape(
                Geometry::Gear {
                    teeth,
                    root,
                    tip,
                    hole: 12.0 * u,
                },
                gear([0.9, 0.6, 0.2]),
                6.0,
                Motion::at(left).spinning(0.0, spin),
            ));
            shapes.push(shape(
                Geometry::Gear {
                    teeth,
                    root,
                    tip,
                    hole: 12.0 * u,
                },
                gear([0.3, 0.7, 0.9]),
                6.0,
                Motion::at(right).spinning(PI + half_tooth, -spin),
            ));
            shapes.push(shape(
                Geometry::Gear {
                    teeth,
                    root,
                    tip,
                    hole: 12.0 * u,
                },
                gear([0.8, 0.3, 0.6]),
                6.0,
                Motion::at(below).spinning(-PI / 2.0, spin),
            ));
        }
        "static" => {
            shapes.push(shape(
                Geometry::Disc { radius: 70.0 * u },
                stripes([0.9, 0.4, 0.1], [0.2, 0.2, 0.6], 11.0 * u, 0.5),
                5.0,
                Motion::at(centre),
            ));
            shapes.push(shape(
                Geometry::Rect {
                    half: DVec2::new(50.0 * u, 30.0 * u),
                },
                Texture::Checker {
                    a: [3.0, 3.0, 3.0],
                    b: [0.1, 0.1, 0.1],
                    size: 10.0 * u,
                },
                3.0,
                Motion::at(DVec2::new(w * 0.25, h * 0.3)).spinning(0.3, 0.0),
            ));
        }
        "sparse" => {
            shapes.push(shape(
                Geometry::Rect {
                    half: DVec2::new(80.0 * u, 50.0 * u),
                },
                stripes([0.5, 0.5, 0.5], [0.2, 0.25, 0.3], 9.0 * u, 0.2),
                8.0,
                Motion::at(DVec2::new(w * 0.3, h * 0.6)),
            ));
            shapes.push(shape(
                Geometry::Disc { radius: 16.0 * u },
                Texture::Checker {
                    a: [1.0, 0.9, 0.1],
                    b: [0.8, 0.1, 0.1],
                    size: 6.0 * u,
                },
                4.0,
                Motion::at(DVec2::new(w * 0.7, h * 0.35)).moving(DVec2::new(14.0 * u, 5.0 * u)),
            ));
        }
        "huge" => {
            shapes.push(shape(
                Geometry::Rect {
                    half: DVec2::new(40.0 * u, 90.0 * u),
                },
                Texture::Spots {
                    base: Box::new(stripes([0.9, 0.9, 0.9], [0.1, 0.3, 0.9], 10.0 * u, 0.0)),
                    hot: [8.0, 6.0, 4.0],
                    period: 45.0 * u,
                    radius: 4.0 * u,
                },
                5.0,
                Motion::at(centre).moving(DVec2::new(480.0 * u, 40.0 * u)),
            ));
            shapes.push(shape(
                Geometry::Disc { radius: 40.0 * u },
                Texture::Solid([0.2, 0.8, 0.3]),
                7.0,
                Motion::at(DVec2::new(w * 0.3, h * 0.25)).moving(DVec2::new(-300.0 * u, 0.0)),
            ));
        }
        "layers" => {
            scene.lens = Some(Lens {
                focal_mm: 50.0,
                f_number: 1.4,
                focus: 3.0,
                sensor_mm: 36.0,
            });
            let depths = [1.2, 1.7, 2.3, 3.0, 4.5, 7.0, 11.0, 18.0];
            for (k, depth) in depths.iter().enumerate() {
                let x = w * (0.1 + 0.8 * (k as f64 + 0.5) / depths.len() as f64);
                let y = h * (0.3 + 0.4 * ((k * 5) % 8) as f64 / 7.0);
                let colour: Rgb = [
                    0.2 + 0.1 * k as f32,
                    0.9 - 0.1 * k as f32,
                    0.3 + 0.05 * k as f32,
                ];
                let texture = Texture::Spots {
                    base: Box::new(Texture::Checker {
                        a: colour,
                        b: [colour[2], colour[0], colour[1]],
                        size: 8.0 * u,
                    }),
                    hot: [5.0, 5.0, 5.0],
                    period: 24.0 * u,
                    radius: 1.5 * u,
                };
                // A little motion, so the combined reference differs from the lens-only one.
                let velocity = DVec2::new(if k % 2 == 0 { 12.0 } else { -12.0 } * u, 0.0);
                shapes.push(shape(
                    Geometry::Rect {
                        half: DVec2::new(45.0 * u, 60.0 * u),
                    },
                    texture,
                    *depth,
                    Motion::at(DVec2::new(x, y)).moving(velocity),
                ));
            }
            scene.background_depth = 40.0;
        }
        "border" | "border-coarse" | "border-cut" => {
            // 85 mm f/1.2 focused at 9 m: the background at 50 m takes a circle of
            // confusion about 10 px across at 640 wide, the near disc at 2.5 m about 31 px.
            scene.lens = Some(Lens {
                focal_mm: 85.0,
                f_number: 1.2,
                focus: 9.0,
                sensor_mm: 36.0,
            });
            let coarse = name == "border-coarse";
            let cut = name == "border-cut";
            if !coarse {
                // Cells of a few pixels: blurred, they average to mid-grey everywhere,
                // the frame's edges included. `border-cut` moves them by 1.5/4 of a cell,
                // so they meet every edge part-way rather than whole: 1.5/4 of a cell along
                // the top and left edges, 2.5/4 along the others (at 640x360 and 320x180).
                let checker = Texture::Checker {
                    a: [0.9, 0.9, 0.9],
                    b: [0.1, 0.1, 0.1],
                    size: 4.0 * u,
                };
                scene.background = if cut {
                    Texture::Shifted {
                        base: Box::new(checker),
                        by: DVec2::new(1.5 * u, 1.5 * u),
                    }
                } else {
                    checker
                };
            }
            shapes.push(shape(
                Geometry::Rect {
                    half: DVec2::new(60.0 * u, 45.0 * u),
                },
                Texture::Checker {
                    a: [0.8, 0.5, 0.2],
                    b: [0.2, 0.3, 0.6],
                    size: 10.0 * u,
                },
                9.0,
                Motion::at(DVec2::new(w * 0.68, h * 0.45)),
            ));
            // Inside the frame over the fine texture; cut by the bottom-left corner over
            // the coarse wall.
            let at = if coarse {
                DVec2::new(25.0 * u, h - 30.0 * u)
            } else if cut {
                // Cut by the right edge: the near rim over the fine texture at the frame's
                // edge.
                DVec2::new(w - 20.0 * u, h * 0.4)
            } else {
                DVec2::new(w * 0.3, h * 0.55)
            };
            shapes.push(shape(
                Geometry::Disc { radius: 55.0 * u },
                Texture::Checker {
                    a: [0.95, 0.3, 0.3],
                    b: [0.6, 0.1, 0.1],
                    size: 14.0 * u,
                },
                2.5,
                Motion::at(at),
            ));
        }
        "follow" | "follow-wall" => {
            // The camera moves with the subject: it is still on screen while what is
            // behind it streams past, wholly hidden behind it at the frame's instant.
            let wall = name == "follow-wall";
            let pan = if wall {
                DVec2::new(-24.0 * u, 16.0 * u)
            } else {
                DVec2::new(-36.0 * u, 0.0)
            };
            scene.camera.pan = pan;
            if !wall {
                scene.background = stripes([0.6, 0.6, 0.6], [0.3, 0.3, 0.3], 18.0 * u, 0.0);
            }
            let geometry = if wall {
                Geometry::Disc { radius: 70.0 * u }
            } else {
                Geometry::Rect {
                    half: DVec2::new(45.0 * u, 100.0 * u),
                }
            };
            shapes.push(shape(
                geometry,
                Texture::Checker {
                    a: [0.9, 0.6, 0.2],
                    b: [0.15, 0.1, 0.05],
                    size: 15.0 * u,
                },
                5.0,
                Motion::at(centre).moving(-pan),
            ));
        }
        _ => return None,
    }
    Some(scene)
}
