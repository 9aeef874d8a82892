//! The bokeh gather's fields and what it makes of fine textures ([`super`]): the far field
//! beside a near one, at the frame's edge, and under the prefilter's levels.

use super::*;
use crate::dof::tiles::{tiles, TilesConfig};
use crate::dof::DofParams;
use crate::numeric::close;

/// A grey frame from `paint` with the signed CoC plane `coc`, gathered.
fn run(w: usize, h: usize, paint: &dyn Fn(usize, usize) -> f32, coc: &[f32]) -> Vec<f32> {
    let plane: Vec<f32> = (0..w * h).map(|i| paint(i % w, i / w)).collect();
    let color = Color {
        r: plane.clone(),
        g: plane.clone(),
        b: plane,
        a: None,
    };
    let config = DofConfig::new(w, h, &DofParams::default());
    let t = tiles(&TilesConfig::new(w, h, config.epsilon), coc);
    gather(&config, &color, coc, &t).r
}

/// Asserts that `with` and `without` (frames `w` wide and `h` tall) agree within 1e-5 at
/// every pixel `compared` keeps; how many it kept.
fn same_where(
    (w, h): (usize, usize),
    with: &[f32],
    without: &[f32],
    compared: impl Fn(usize, usize) -> bool,
) -> usize {
    let mut checked = 0;
    for y in 0..h {
        for x in 0..w {
            if !compared(x, y) {
                continue;
            }
            let i = y * w + x;
            assert!(
                close(with[i], without[i], 1e-5),
                "({x}, {y}): {} with the disc, {} without",
                with[i],
                without[i]
            );
            checked += 1;
        }
    }
    checked
}

#[test]
fn a_fine_far_texture_beside_a_large_near_bokeh_keeps_its_own_blur() {
    // A one-pixel checker far behind (CoC 8 px), and a disc far in front (CoC −60 px) in
    // the left part of the frame. The disc's bokeh sets the gather radius (30 px) of the
    // tiles around it, whose far pixels have a 4 px bokeh of their own: sampled with the
    // 30 px rings, they would keep the few ring taps inside 4 px and the checker would
    // come out as a grid of marks. Wherever the disc's bokeh cannot reach, the far field
    // must be what it is with no disc at all.
    let (w, h) = (192, 96);
    let checker = |x: usize, y: usize| ((x + y) % 2) as f32;
    let disc = |x: usize, y: usize| {
        let (dx, dy) = (x as f32 - 24.0, y as f32 - 48.0);
        dx * dx + dy * dy < 16.0 * 16.0
    };
    let paint = |x: usize, y: usize| if disc(x, y) { 0.3 } else { checker(x, y) };
    let coc: Vec<f32> = (0..w * h)
        .map(|i| if disc(i % w, i / w) { -60.0 } else { 8.0 })
        .collect();
    let with = run(w, h, &paint, &coc);
    let without = run(w, h, &checker, &vec![8.0; w * h]);
    let checked = same_where((w, h), &with, &without, |x, y| {
        let (dx, dy) = (x as f32 - 24.0, y as f32 - 48.0);
        // Beyond the disc's edge (16 px) plus its bokeh (30 px) and the far bokeh (4 px)
        // plus a pixel: nothing of the disc reaches.
        (dx * dx + dy * dy).sqrt() >= 16.0 + 30.0 + 4.0 + 1.0
    });
    // The comparison covers tiles whose radius the disc sets (within 30 px of it).
    assert!(checked > 1000);
    // And the blurred checker has no pattern left: a 4 px bokeh over a one-pixel checker
    // is within a few percent of its mean everywhere away from the frame's edge.
    for y in 8..h - 8 {
        for x in 100..w - 8 {
            let v = with[y * w + x];
            assert!(close(v, 0.5, 0.05), "({x}, {y}): {v}");
        }
    }
}

#[test]
fn a_fine_far_texture_in_a_near_rim_s_tiles_keeps_its_own_blur() {
    // A one-pixel checker far behind (CoC 8 px: a 4 px bokeh) and a disc in front (CoC
    // −14: a 7 px bokeh, beyond the 6 px the grids go to, so the four tiles it lies in
    // take the rings of 7 px) of radius 8 px. In those tiles the far checker's pixels
    // beyond the disc's bokeh must come out as they do with no disc at all: their far
    // field over every pixel of their 4 px bokeh. With the rings of the disc's radius, a
    // 4 px bokeh kept a few scattered taps and the pattern came out as marks.
    let (w, h) = (96, 64);
    let checker = |x: usize, y: usize| ((x + y) % 2) as f32;
    let (cx, cy) = (14.0, 14.0);
    let disc = |x: usize, y: usize| {
        let (dx, dy) = (x as f32 + 0.5 - cx, y as f32 + 0.5 - cy);
        dx * dx + dy * dy < 8.0 * 8.0
    };
    let paint = |x: usize, y: usize| if disc(x, y) { 0.3 } else { checker(x, y) };
    let coc: Vec<f32> = (0..w * h)
        .map(|i| if disc(i % w, i / w) { -14.0 } else { 8.0 })
        .collect();
    let with = run(w, h, &paint, &coc);
    let without = run(w, h, &checker, &vec![8.0; w * h]);
    let tile_of = |x: usize, y: usize| (x / TILE, y / TILE);
    let disc_tiles: std::collections::BTreeSet<_> = (0..w * h)
        .filter(|&i| disc(i % w, i / w))
        .map(|i| tile_of(i % w, i / w))
        .collect();
    let checked = same_where((w, h), &with, &without, |x, y| {
        let (dx, dy) = (x as f32 + 0.5 - cx, y as f32 + 0.5 - cy);
        // Beyond the disc's edge (8 px) plus its bokeh (7) and the far bokeh (4) plus a
        // pixel, inside a tile the disc lies in.
        (dx * dx + dy * dy).sqrt() >= 8.0 + 7.0 + 4.0 + 1.0 && disc_tiles.contains(&tile_of(x, y))
    });
    assert_eq!(disc_tiles.len(), 4);
    assert!(checked > 40, "{checked}");
}

/// A checker of `cell` px, 0.1 and 0.9 (mean 0.5), from the frame's top-left corner, so
/// that whole cells meet every edge.
fn checker(cell: usize) -> impl Fn(usize, usize) -> f32 {
    move |x, y| 0.1 + 0.8 * ((x / cell + y / cell) % 2) as f32
}

#[test]
fn a_fine_checker_meeting_the_frame_edge_keeps_its_mean_within_the_first_coc_radius() {
    // Issue 34: a fine far texture meeting the frame's edges, in both orientations (the
    // checker meets the top and bottom rows and the left and right columns alike).
    // Blurred, it is its mean, 0.5, up to the edge: what lies beyond is unknown, and the
    // gather must not make structure of it. Mirroring the frame about its edge doubled
    // the edge cell, and within the first CoC radius (corners included) the output swung
    // to 0.304 off the mean (4 px cells, CoC 9) and 0.260 (5 px, CoC 12); with the taps
    // outside weighing nothing it stays within 0.213 and 0.181. Inside, the discrete
    // bokeh's own ripple over such cells is up to 0.07.
    let (w, h) = (160, 96);
    for (cell, coc) in [(4, 9.0f32), (5, 12.0)] {
        let out = run(w, h, &checker(cell), &vec![coc; w * h]);
        let radius = (0.5 * coc).ceil() as usize;
        let mut checked = 0;
        for y in 0..h {
            for x in 0..w {
                if x.min(w - 1 - x).min(y).min(h - 1 - y) >= radius {
                    continue;
                }
                let v = out[y * w + x];
                assert!(
                    (v - 0.5).abs() <= 0.25,
                    "cell {cell}, CoC {coc}: ({x}, {y}): {v}"
                );
                checked += 1;
            }
        }
        assert_eq!(checked, w * h - (w - 2 * radius) * (h - 2 * radius));
    }
}

#[test]
fn a_fine_texture_keeps_its_mean_up_to_the_frame_edge() {
    // Stripes of one pixel (0, 1, 0, 1, …) blurred by a 12 px CoC (a 6 px bokeh, which
    // gathers every pixel of its neighbourhood): the world beyond the frame is unknown,
    // but the frame's own texture says its mean is ½. Mirroring keeps that mean at the
    // edges (within the one column the reflection repeats: 7 zeros to 6 ones across the
    // bokeh, 0.46); clamping to the edge would fill the bokeh's outer part with the edge
    // column's value (over 0.2 off).
    let (w, h) = (96, 48);
    let stripes = |x: usize, _y: usize| (x % 2) as f32;
    let out = run(w, h, &stripes, &vec![12.0; w * h]);
    for y in 0..h {
        for x in 0..w {
            let v = out[y * w + x];
            assert!(close(v, 0.5, 0.06), "({x}, {y}): {v}");
        }
    }
}

/// A frame in focus but for a strip and a near disc, whose tiles read prefilter levels of
/// three sides (the disc's, its rim's far field apart, and the strip's): its colour, signed
/// CoC and three carried planes.
fn strip_and_disc(w: usize, h: usize) -> (Color, Vec<f32>, Vec<Vec<f32>>) {
    let wave = |k: f32| -> Vec<f32> { (0..w * h).map(|i| (i as f32 * k).sin()).collect() };
    let coc: Vec<f32> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32, (i / w) as f32);
            if (x - 130.0).powi(2) + (y - 60.0).powi(2) < 15.0 * 15.0 {
                -62.0
            } else if (40.0..60.0).contains(&x) {
                27.0
            } else if x > 100.0 {
                40.0
            } else {
                0.3
            }
        })
        .collect();
    let color = Color {
        r: wave(0.37),
        g: wave(0.21),
        b: wave(0.05),
        a: Some(wave(0.013)),
    };
    (color, coc, [0.11, 0.7, 0.003].map(wave).into())
}

/// The gather's config and tiles for the frame `coc` with `blades` blades.
fn setup(w: usize, h: usize, coc: &[f32], blades: u32) -> (DofConfig, Tiles) {
    let params = DofParams {
        blades,
        blade_rotation: 10.0,
        ..DofParams::default()
    };
    let config = DofConfig::new(w, h, &params);
    let t = tiles(&TilesConfig::new(w, h, config.epsilon), coc);
    assert!(level_sides(&config, &t).len() >= 3);
    (config, t)
}

#[test]
fn every_level_pixel_a_tap_reads_is_made() {
    // The levels are made only around the tiles that read them, as far as their taps
    // reach: every pixel that a tile's taps (and, where its far taps read a level, its
    // pixels' own box) read in a level must be among those made, for each of a tile's 16
    // lanes, round and with six blades.
    let (w, h) = (176, 112);
    let (color, coc, _) = strip_and_disc(w, h);
    for blades in [0, 6] {
        let (config, t) = setup(w, h, &coc, blades);
        let aperture = Aperture::new(config.blades, config.blade_rotation);
        let rings = taps(config.rings, &aperture);
        let norms = norms_for(aperture, largest_reach(&t));
        let pad = largest_reach(&t).ceil() as usize + 2;
        let padded = Padded::new(&color, &coc, (w, h), pad, aperture.unit_area());
        let sides = level_sides(&config, &t);
        let reads = level_reads(&config, &t, &padded, &sides, &rings, &norms, false);
        let plan = plan(&config, &t);
        let columns = w.div_ceil(TILE);
        let mut checked = 0;
        for (i, tile) in plan.tiles.iter().enumerate() {
            let (x0, y0) = (i % columns * TILE, i / columns * TILE);
            let list =
                |start: u32, count: u32| &plan.taps[start as usize..(start + count) as usize];
            let centre = [OffsetTap {
                dx: 0,
                dy: 0,
                norm_far: 0.0,
                norm_near: 0.0,
                area: 0.0,
            }];
            for (level, offsets) in [
                (tile.level, list(tile.taps_start, tile.taps_count)),
                (tile.far_level, list(tile.far_start, tile.far_count)),
                (tile.far_level, &centre[..]),
            ] {
                if level == 0 {
                    continue;
                }
                for tap in offsets {
                    for y in y0..(y0 + TILE).min(h) {
                        for x in x0..x0 + TILE {
                            let px = (x + pad) as isize + tap.dx as isize;
                            let py = (y + pad) as isize + tap.dy as isize;
                            assert!(
                                reads[level as usize - 1].is_read(px as usize, py as usize),
                                "{blades} blades, tile {i}, level {level}: ({px}, {py})"
                            );
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert!(checked > 0);
    }
}

#[test]
fn levels_made_only_where_their_taps_read_give_the_bits_of_levels_over_the_whole_frame() {
    // Against levels made over the whole padded frame (as they were), the beauty and every
    // carried plane must keep their bits, round and with six blades.
    let (w, h) = (176, 112);
    let (color, coc, extra) = strip_and_disc(w, h);
    for blades in [0, 6] {
        let (config, t) = setup(w, h, &coc, blades);
        let bits = |(c, carried): (Color, Vec<Vec<f32>>)| {
            let mut all = vec![c.r, c.g, c.b, c.a.unwrap_or_default()];
            all.extend(carried);
            all.iter()
                .map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
                .collect::<Vec<_>>()
        };
        let read = gather_levels_where(&config, &color, &coc, &t, extra.clone(), false);
        let whole = gather_levels_where(&config, &color, &coc, &t, extra.clone(), true);
        assert!(bits(read) == bits(whole), "{blades} blades");
    }
}
