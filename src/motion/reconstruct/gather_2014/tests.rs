//! Unit tests of the 2014 gather ([`super`]).
use super::*;
use crate::frame::{Frame, Velocity};
use crate::motion::reconstruct::classify::classify;
use crate::motion::reconstruct::{
    matte, pack_2014, packed_2014, reconstruct_layers_with, spread_2014, ReconstructParams, Variant,
};
use crate::motion::{dilate::dilate, tile_max::tile_max};
use crate::stages::Cpu;

/// A textured disc moving over a still textured background, with a fringe of mixed
/// colour at its rim (so the exposure variant's mattes pair pixels), and `n` light
/// layers of other textures.
fn scene(w: usize, h: usize, n: usize) -> (Frame, Vec<Color>) {
    let wave = |k: f32| -> Vec<f32> {
        (0..w * h)
            .map(|i| (i as f32 * k).sin() * 0.5 + 0.5)
            .collect()
    };
    let inside = |i: usize| {
        let (dx, dy) = ((i % w) as f32 - 30.0, (i / w) as f32 - 24.0);
        (dx * dx + dy * dy).sqrt()
    };
    let mut frame = Frame::new(w, h);
    let alpha: Vec<f32> = (0..w * h)
        .map(|i| (inside(i) < 13.0) as u8 as f32 * 0.5 + 0.5)
        .collect();
    let mut color = Color {
        r: wave(0.37),
        g: wave(0.21),
        b: wave(0.05),
        a: Some(alpha.clone()),
    };
    for i in 0..w * h {
        // The rim: a mix of the disc's colour and the background's.
        if (12.0..13.0).contains(&inside(i)) {
            color.r[i] = 0.5 * color.r[i] + 0.4;
        }
    }
    frame.color = Some(color);
    frame.depth = Some(
        (0..w * h)
            .map(|i| if inside(i) < 12.5 { 1.0 } else { 9.0 })
            .collect(),
    );
    frame.velocity = Some(Velocity {
        x: (0..w * h)
            .map(|i| if inside(i) < 12.5 { 9.0 } else { 0.0 })
            .collect(),
        y: (0..w * h)
            .map(|i| if inside(i) < 12.5 { 3.0 } else { 0.0 })
            .collect(),
    });
    let layers = (0..n)
        .map(|k| Color {
            r: wave(0.011 * (k + 1) as f32),
            g: wave(0.7 + k as f32),
            b: wave(0.003 * (k + 2) as f32),
            a: Some(alpha.clone()),
        })
        .collect();
    (frame, layers)
}

/// Each of `layers` gathered alone in the beauty's place as it was before colours were
/// carried: packed with its own colour, gathered with the beauty's tiles and mattes.
fn alone(frame: &Frame, layers: &[Color], params: &ReconstructParams) -> Vec<Color> {
    let (w, h) = (frame.width, frame.height);
    let config = ReconstructConfig::new(w, h, params, 0.5, 7);
    let velocity = frame.velocity.as_ref().unwrap();
    let depth = frame.depth.as_ref().unwrap();
    let mut tiles = tile_max(&velocity.x, &velocity.y, w, h, config.tile as usize);
    for (x, y) in tiles.x.iter_mut().zip(tiles.y.iter_mut()) {
        (*x, *y) = spread_2014(*x, *y, &config);
    }
    let dilated = dilate(&tiles);
    let packed = packed_2014(&config, &dilated);
    let beauty = frame.color.as_ref().unwrap();
    let texels = pack_2014(&config, beauty, depth, velocity, &dilated, &packed);
    let mattes = if params.variant == Variant::Exposure {
        matte::mattes(&config, &texels, |c, row| packed.get(c, row))
    } else {
        Vec::new()
    };
    assert!(
        params.variant != Variant::Exposure
            || mattes
                .iter()
                .enumerate()
                .any(|(i, m)| !matte::unpaired(m, i))
    );
    layers
        .iter()
        .map(|layer| {
            let texels = pack_2014(&config, layer, depth, velocity, &dilated, &packed);
            let mut out = layer.clone();
            let kinds = classify(&config, &texels, &mattes, &dilated);
            gather_2014(&config, &texels, &mattes, (&dilated, &kinds), &mut out);
            out
        })
        .collect()
}

/// A textured frame moving (24, 8) or (22, 8) px a frame everywhere over one depth, but for
/// the still pixels `still`: the exposure gather's plain tiles and its output.
fn uniform_pan(still: &[(usize, usize)]) -> (Vec<bool>, usize, Color) {
    let (w, h) = (80usize, 64usize);
    let wave = |k: f32| -> Vec<f32> {
        (0..w * h)
            .map(|i| (i as f32 * k).sin() * 0.5 + 0.5)
            .collect()
    };
    let mut frame = Frame::new(w, h);
    let color = Color {
        r: wave(0.37),
        g: wave(0.21),
        b: wave(0.05),
        a: None,
    };
    // Two motions in a checker, 2 px a frame apart: every pixel moves, but the flow is not
    // smooth, so no tile takes the uniform tiles' box (super::uniform).
    let mut vx: Vec<f32> = (0..w * h)
        .map(|i| if (i % w + i / w) % 2 == 0 { 24.0 } else { 22.0 })
        .collect();
    let mut vy = vec![8.0; w * h];
    for &(x, y) in still {
        (vx[y * w + x], vy[y * w + x]) = (0.0, 0.0);
    }
    let params = ReconstructParams::default();
    let config = ReconstructConfig::new(w, h, &params, 0.5, 7);
    let mut tiles = tile_max(&vx, &vy, w, h, config.tile as usize);
    for (x, y) in tiles.x.iter_mut().zip(tiles.y.iter_mut()) {
        (*x, *y) = spread_2014(*x, *y, &config);
    }
    let dilated = dilate(&tiles);
    let packed = packed_2014(&config, &dilated);
    let depth = vec![5.0; w * h];
    frame.velocity = Some(Velocity { x: vx, y: vy });
    let velocity = frame.velocity.as_ref().unwrap();
    let texels = pack_2014(&config, &color, &depth, velocity, &dilated, &packed);
    let mattes = matte::mattes(&config, &texels, |c, row| packed.get(c, row));
    let kinds = classify(&config, &texels, &mattes, &dilated);
    assert!(!kinds.contains(&TileKind::Uniform));
    let plain = kinds.iter().map(|&k| k == TileKind::Plain).collect();
    let mut out = color.clone();
    gather_2014(&config, &texels, &mattes, (&dilated, &kinds), &mut out);
    (plain, dilated.columns, out)
}

#[test]
fn a_plain_tile_s_pixels_come_out_as_they_do_through_the_split_taps() {
    // Tile (4, 4) (pixels 32–39 both ways; tiles of 8) with every pixel moving, then with
    // a still pixel 15 px to its right: within the tile's tested reach (|M| = 6.3 px:
    // 6.3 + 2·6.3 + 2 px), so the tile is no longer plain, but beyond what its pixels'
    // taps read (6.3 px and a pixel, no tap slid: one depth). Its pixels must not change.
    let (plain, columns, all_moving) = uniform_pan(&[]);
    let (plain_with, _, with_still) = uniform_pan(&[(54, 36)]);
    let tile = 4 * columns + 4;
    assert!(
        plain[tile] && !plain_with[tile],
        "the tile is plain only without the still pixel"
    );
    let mut compared = 0;
    for y in 32..40 {
        for x in 32..40 {
            let i = y * 80 + x;
            for (a, b) in [
                (&all_moving.r, &with_still.r),
                (&all_moving.g, &with_still.g),
                (&all_moving.b, &with_still.b),
            ] {
                assert_eq!(a[i].to_bits(), b[i].to_bits(), "pixel ({x}, {y})");
            }
            compared += 1;
        }
    }
    assert_eq!(compared, 64);
}

#[test]
fn carried_layers_get_the_bits_they_get_in_the_beautys_place() {
    // Nine layers and the beauty: two passes of five colours. Both 2014 forms.
    let bits =
        |c: &Color| [&c.r, &c.g, &c.b].map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
    for variant in [Variant::Exposure, Variant::Stable] {
        let params = ReconstructParams {
            variant,
            ..ReconstructParams::default()
        };
        let (frame, layers) = scene(64, 48, 9);
        let want = alone(&frame, &layers, &params);
        let beauty = alone(&frame, &[frame.color.clone().unwrap()], &params);
        let mut carried = layers.clone();
        let out = reconstruct_layers_with(frame, &mut carried, &params, 0.5, 7, &Cpu);
        assert_eq!(
            bits(out.color.as_ref().unwrap()),
            bits(&beauty[0]),
            "{variant:?}"
        );
        for (k, (got, want)) in carried.iter().zip(&want).enumerate() {
            assert_ne!(
                bits(want),
                bits(&layers[k]),
                "{variant:?} {k}: the layer moved"
            );
            assert_eq!(bits(got), bits(want), "{variant:?} layer {k}");
            // Each layer's alpha comes back as the beauty's.
            assert_eq!(
                got.a,
                out.color.as_ref().unwrap().a,
                "{variant:?} layer {k}"
            );
        }
    }
}

#[test]
fn a_layer_with_an_alpha_of_its_own_gets_the_bits_it_gets_in_the_beautys_place() {
    // The layers' channels go four to a colour only where every layer's alpha is the
    // beauty's; here the second layer's is not, and every layer goes one to a colour.
    let bits = |c: &Color| {
        [&c.r, &c.g, &c.b, c.a.as_ref().unwrap()]
            .map(|p| p.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
    };
    let params = ReconstructParams::default();
    let (frame, mut layers) = scene(64, 48, 3);
    let own: Vec<f32> = (0..64 * 48).map(|i| (i % 7) as f32 / 6.0).collect();
    layers[1].a = Some(own);
    let want = alone(&frame, &layers, &params);
    let mut carried = layers.clone();
    let out = reconstruct_layers_with(frame, &mut carried, &params, 0.5, 7, &Cpu);
    assert_ne!(carried[1].a, out.color.as_ref().unwrap().a);
    for (k, (got, want)) in carried.iter().zip(&want).enumerate() {
        assert_eq!(bits(got), bits(want), "layer {k}");
    }
}
