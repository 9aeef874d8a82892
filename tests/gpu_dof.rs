//! Depth of field's GPU twins (`coc`, tile min/max, the bokeh gather, blend's pyramid), each
//! against its CPU reference on generated and stress frames, and `shutter dof --backend wgpu`
//! against `--backend cpu` within the stated tolerances. Without an adapter these tests skip
//! or fail as tests/gpu.rs says.

#![cfg(feature = "gpu")]

use crate::gpu::{dof_args, layers};
use crate::support::*;

mod with_gpu {
    use super::*;
    use crate::gpu::with_gpu::{differing, gpu, milliseconds};
    use shutter::dof::tiles::{tiles, TilesConfig};
    use shutter::dof::{coc_plane, CocSource, DofParams, Lens, Stages};
    use shutter::frame::Frame;
    use std::io::Write;

    /// Depth values that stress the stage: non-finite, huge, tiny, subnormal, zero, negative,
    /// the focus plane itself and its neighbours.
    fn stress_values(focus: f32) -> Vec<f32> {
        vec![
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            1e30,
            -1e30,
            f32::MAX,
            f32::MIN,
            0.0,
            -0.0,
            -3.0,
            1e-30,
            1e-40, // subnormal: a GPU may flush it to 0, which gives the same answer
            f32::MIN_POSITIVE,
            focus,
            focus * (1.0 + f32::EPSILON),
            focus * (1.0 - f32::EPSILON),
            0.5 * focus,
            2.0 * focus,
            1e-3,
            1e6,
        ]
    }

    /// A `w`×`h` depth plane: noise over [0.05, 200) m (log-spaced), with the stress values
    /// spread through it.
    fn depth_frame(w: usize, h: usize, seed: u32, focus: f32) -> Frame {
        let n = w * h;
        let mut depth: Vec<f32> = noise(n, seed, -3.0, 5.3)
            .into_iter()
            .map(f32::exp)
            .collect();
        let stress = stress_values(focus);
        for (k, v) in stress.iter().cycle().take(n / 7).enumerate() {
            depth[(k * 7 + seed as usize) % n] = *v;
        }
        let mut frame = Frame::new(w, h);
        frame.depth = Some(depth);
        frame
    }

    struct Diff {
        max: f32,
        mean: f64,
        worst: usize,
    }

    /// The least and greatest of `values` (MAX, MIN where there are none).
    fn bounds<'a>(values: impl IntoIterator<Item = &'a f32>) -> (f32, f32) {
        (values.into_iter()).fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)))
    }

    fn diff(gpu: &[f32], cpu: &[f32]) -> Diff {
        assert_eq!(gpu.len(), cpu.len());
        let mut d = Diff {
            max: 0.0,
            mean: 0.0,
            worst: 0,
        };
        for (i, (&g, &c)) in gpu.iter().zip(cpu).enumerate() {
            assert!(g.is_finite(), "pixel {i}: GPU gave {g}");
            let e = (g - c).abs();
            if e > d.max {
                d.max = e;
                d.worst = i;
            }
            d.mean += e as f64;
        }
        d.mean /= gpu.len().max(1) as f64;
        d
    }

    /// The `coc` twin against `coc_plane`, thin lens.
    ///
    /// Tolerance, per pixel: 2⁻²⁰·(K + limit) px, with K the far-limit CoC. Why: the CPU
    /// evaluates K·(1 − P/D) in f64 and rounds once (≤ 2⁻²⁴·limit). The shader rounds K and
    /// P to f32 (2⁻²⁴ each), divides (WGSL allows 2.5 ulp: 5·2⁻²⁴), subtracts and multiplies
    /// (2⁻²⁴ each). The quotient's error is amplified by K through the cancellation in
    /// 1 − P/D: an absolute error of at most K·(P/D)·6·2⁻²⁴, where an unclamped pixel has
    /// P/D ≤ 1 + limit/K; with the roundings of the result, the total is below
    /// 2⁻²⁴·(6K + 10·limit) ≤ 2⁻²⁰·(K + limit). Clamping to ±limit only shrinks errors. For
    /// K = 34 px and limit 48 px that is 7.8e-5 px, 8e-7 of the CoC range (2·limit). Every
    /// pixel must be within it (no fraction of outliers is allowed); the mean is bounded by a
    /// quarter of it, since rounding errors of independent operations do not all reach their
    /// bounds together (lavapipe measured below a tenth).
    #[test]
    fn coc_matches_the_cpu_on_lenses_and_stress_depths() {
        let Some(gpu) = gpu() else { return };
        let lenses = [
            (50.0, 2.0, 2.0, 48.0),
            (85.0, 1.4, 3.0, 48.0),
            (24.0, 8.0, 5.0, 48.0),
            (200.0, 2.8, 10.0, 512.0),
            (35.0, 1.2, 0.5, 512.0),
        ];
        // Sizes off the 16-px workgroup grid, one with overscan (the display window differs).
        for (k, &(w, h, display)) in [(37, 23, 0), (64, 48, 0), (101, 7, 80)].iter().enumerate() {
            for &(focal_mm, f_number, focus, max_coc) in &lenses {
                let lens = Lens {
                    focal_mm,
                    f_number,
                    focus,
                    sensor_mm: 36.0,
                };
                let params = DofParams {
                    max_coc,
                    ..DofParams::new(CocSource::Lens(lens))
                };
                let mut frame = depth_frame(w, h, 11 + k as u32, focus as f32);
                if display > 0 {
                    frame.windows.display.width = display;
                }
                let cpu = coc_plane(&frame, &params);
                let got = gpu
                    .try_coc_plane(&frame, &params)
                    .expect("the GPU stage runs");
                let span = if display > 0 { display } else { w } as f64;
                let far = lens.signed_coc(f64::INFINITY, span) as f32;
                let tolerance = (far + max_coc) * 2f32.powi(-20);
                let d = diff(&got, &cpu);
                let depth = frame.depth.as_ref().unwrap();
                assert!(
                    d.max <= tolerance,
                    "{w}x{h}, lens {lens:?}: pixel {} (depth {}) GPU {} CPU {}: {} > {tolerance}",
                    d.worst,
                    depth[d.worst],
                    got[d.worst],
                    cpu[d.worst],
                    d.max
                );
                assert!(
                    d.mean <= tolerance as f64 / 4.0,
                    "{w}x{h}, lens {lens:?}: mean {} > {}",
                    d.mean,
                    tolerance / 4.0
                );
                // The stress values come out exactly where the CPU clamps them.
                for (i, &v) in depth.iter().enumerate() {
                    if v.is_nan() || v == f32::INFINITY {
                        assert_eq!(got[i], cpu[i], "depth {v}");
                    }
                    if v <= 0.0 {
                        assert_eq!(got[i], -max_coc, "depth {v}");
                    }
                }
            }
        }
    }

    /// The `coc` twin against `coc_plane`, painted map: the same f32 product on both sides
    /// (WGSL's multiplication is correctly rounded), except that stored values above
    /// limit/scale are clamped before the product on the GPU and after it on the CPU, which
    /// can move a clamped pixel by the rounding of limit/scale: tolerance 2⁻²²·limit.
    #[test]
    fn coc_matches_the_cpu_on_painted_maps() {
        let Some(gpu) = gpu() else { return };
        for (k, scale) in [32.0f32, 0.0, 512.0, 1e-3, 7.3].into_iter().enumerate() {
            let params = DofParams {
                max_coc: 48.0,
                ..DofParams::new(CocSource::Map { scale })
            };
            let (w, h) = (45, 31);
            let mut frame = Frame::new(w, h);
            let mut map = noise(w * h, 40 + k as u32, -0.5, 2.0);
            for (i, v) in stress_values(1.0).into_iter().enumerate() {
                map[i * 13] = v;
            }
            frame.depth = Some(map);
            let cpu = coc_plane(&frame, &params);
            let got = gpu
                .try_coc_plane(&frame, &params)
                .expect("the GPU stage runs");
            let tolerance = 48.0 * 2f32.powi(-22);
            let d = diff(&got, &cpu);
            assert!(
                d.max <= tolerance,
                "scale {scale}: pixel {}: GPU {} CPU {}",
                d.worst,
                got[d.worst],
                cpu[d.worst]
            );
        }
    }

    /// A frame without depth, and an empty one: what the CPU gives, without a dispatch.
    #[test]
    fn coc_of_a_frame_without_depth_is_zero() {
        let Some(gpu) = gpu() else { return };
        let params = DofParams::default();
        let frame = Frame::new(5, 3);
        assert_eq!(gpu.coc_plane(&frame, &params), vec![0.0; 15]);
        assert!(gpu.coc_plane(&Frame::new(0, 0), &params).is_empty());
    }

    /// A 50 mm f/2 lens focused at 2 m on a full-frame sensor.
    const LENS: Lens = Lens {
        focal_mm: 50.0,
        f_number: 2.0,
        focus: 2.0,
        sensor_mm: 36.0,
    };

    /// Buffers are kept per size and reused: a second frame of one size, then a third of
    /// another, then the first size again, all match the CPU.
    #[test]
    fn coc_reuses_its_buffers_across_frames_and_sizes() {
        let Some(gpu) = gpu() else { return };
        let params = DofParams::new(CocSource::Lens(LENS));
        for (seed, (w, h)) in [(1, (33, 17)), (2, (33, 17)), (3, (20, 20)), (4, (33, 17))] {
            let frame = depth_frame(w, h, seed, 2.0);
            let cpu = coc_plane(&frame, &params);
            let got = gpu.coc_plane(&frame, &params);
            assert!(diff(&got, &cpu).max <= 1e-4, "seed {seed}");
        }
    }

    /// The cost of the stage at 1920×1080, printed (benchmarks measure, tests assert).
    #[test]
    fn coc_at_1080p_prints_its_time() {
        let Some(gpu) = gpu() else { return };
        let params = DofParams::new(CocSource::Lens(LENS));
        let frame = depth_frame(1920, 1080, 5, 2.0);
        let _ = gpu.coc_plane(&frame, &params); // buffers made here
        let runs = 5;
        let start = std::time::Instant::now();
        let mut got = Vec::new();
        for _ in 0..runs {
            got = gpu.coc_plane(&frame, &params);
        }
        let seconds = start.elapsed().as_secs_f64() / runs as f64;
        let start = std::time::Instant::now();
        let cpu = coc_plane(&frame, &params);
        let cpu_seconds = start.elapsed().as_secs_f64();
        let d = diff(&got, &cpu);
        let _ = writeln!(
            std::io::stderr(),
            "gpu: coc 1920x1080 upload+dispatch+readback {:.2} ms (cpu {:.2} ms); max diff {:e} px, mean {:e} px",
            seconds * 1e3,
            cpu_seconds * 1e3,
            d.max,
            d.mean
        );
        assert!(d.max <= (34.2 + 48.0) * 2f32.powi(-20));
    }

    /// `--backend wgpu` through the CLI gives the CPU's output within the tolerance: the `coc`
    /// and tile min/max stages run on the GPU, the rest on the CPU in the same run. The tiles
    /// are exact for a given CoC plane (above); the CoC differs by at most ~1e-4 px (above),
    /// which moves a gather weight by as little; a pixel can
    /// differ more only where a CoC sits on a threshold (in focus at ε, a tile's reach, the
    /// near/far layer test), which the smooth depths of `layers` make rare. Bound: colour
    /// differences ≤ 1e-3 of the frame's range at every pixel, both methods.
    #[test]
    fn dof_on_wgpu_equals_the_cpu_within_the_tolerance() {
        let Some(_gpu) = gpu() else { return };
        let (dir, color, depth) = layers();
        for method in ["gather", "blend"] {
            let mut outputs = Vec::new();
            for backend in ["cpu", "wgpu"] {
                let out = s(&dir.path().join(format!("{method}-{backend}.####.exr")));
                let mut args = dof_args(&color, &depth, &out);
                args.extend(["--backend", backend, "--method", method]);
                let o = shutter(&args);
                assert!(o.status.success(), "{backend}: {}", stderr(&o));
                let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
                assert_eq!(json["backend"]["used"], backend, "{json}");
                if backend == "wgpu" {
                    assert!(json["backend"]["adapter"].is_string(), "{json}");
                    assert_eq!(json["backend"]["stages_on_cpu"], 0, "{json}");
                }
                outputs.push(read_exr_reference(
                    &dir.path().join(format!("{method}-{backend}.0001.exr")),
                ));
            }
            for name in ["R", "G", "B"] {
                let cpu = channel(&outputs[0], name);
                let got = channel(&outputs[1], name);
                let (lo, hi) = bounds(cpu);
                let d = diff(got, cpu);
                let _ = writeln!(
                    std::io::stderr(),
                    "gpu: dof {method} {name}: max diff {:e}, mean {:e} (range {})",
                    d.max,
                    d.mean,
                    hi - lo
                );
                assert!(
                    d.max <= 1e-3 * (hi - lo),
                    "{method} {name}: {} > 1e-3 of {}",
                    d.max,
                    hi - lo
                );
            }
        }
    }

    /// Depth of field's bokeh gather twin against `gather`, on the stress depth frames under
    /// three lenses (CoC up to 48, 200 and 512 px: grid taps, ring taps and near fields
    /// reaching over far ones, so every tile mode), round and five-bladed (the near field sees
    /// the pentagon turned over), 2 and 6 rings, with
    /// and without alpha, over a colour of fine noise (under one lens with stress values, NaN,
    /// ±Inf, ±1e30, which the numeric policy makes finite first, as the pipeline does).
    ///
    /// Tolerance: the twin runs the CPU's plan (the same taps in the same order) on the
    /// CPU's bokeh areas, so what differs is rounding: the composite's two divisions (WGSL
    /// allows 2.5 ULP) and products a driver may fuse into the sums (a rounding fewer per
    /// tap, up to 2 × 169 sums). Relative to the frame's range r that is a few times
    /// 2⁻²⁴·r per pixel (≈ 1e-6 r), where the weights and offsets are O(1) and O(r). Bound:
    /// max difference ≤ 1e-5·r (ten times that), mean ≤ 1e-7·r; every pixel finite.
    #[test]
    fn dof_gather_matches_the_cpu_within_rounding() {
        let Some(gpu) = gpu() else { return };
        use shutter::dof::gather::gather;
        use shutter::dof::DofConfig;
        use shutter::numeric::{sanitize, DepthKind};
        let lenses = [
            (50.0, 2.0, 2.0, 48.0),
            (85.0, 1.4, 3.0, 200.0),
            (35.0, 1.2, 0.5, 512.0),
        ];
        let (mut cases, mut worst) = (0, 0.0f32);
        for (k, &(w, h)) in [(37, 23), (160, 90), (64, 211)].iter().enumerate() {
            for (j, &(focal_mm, f_number, focus, max_coc)) in lenses.iter().enumerate() {
                let lens = Lens {
                    focal_mm,
                    f_number,
                    focus,
                    sensor_mm: 36.0,
                };
                let mut frame = depth_frame(w, h, 90 + k as u32, focus as f32);
                let n = w * h;
                let mut color = shutter::frame::Color {
                    r: noise(n, 3 + k as u32, 0.0, 4.0),
                    g: noise(n, 5 + k as u32, -1.0, 1.0),
                    b: noise(n, 7 + k as u32, 0.0, 0.01),
                    a: (j != 1).then(|| noise(n, 11 + k as u32, 0.0, 1.0)),
                };
                // Stress colour under the third lens only: its ±1e30 set the range there, which
                // would make the bound loose for the others.
                if j == 2 {
                    let stress = stress_values(focus as f32);
                    for (i, v) in stress.iter().enumerate() {
                        color.r[(i * 13 + 5) % n] = *v;
                        color.g[(i * 17 + 3) % n] = *v;
                    }
                }
                frame.color = Some(color);
                let _ = sanitize(&mut frame, DepthKind::Depth);
                for (blades, rings) in [(0, 6), (5, 2)] {
                    let params = DofParams {
                        max_coc,
                        blades,
                        rings,
                        ..DofParams::new(CocSource::Lens(lens))
                    };
                    let coc = coc_plane(&frame, &params);
                    let config = DofConfig::new(w, h, &params);
                    let t = tiles(&TilesConfig::new(w, h, config.epsilon), &coc);
                    let color = frame.color.as_ref().unwrap();
                    let cpu = gather(&config, color, &coc, &t);
                    let got = gpu
                        .try_dof_gather(&config, color, &coc, &t)
                        .unwrap_or_else(|e| panic!("{e}"));
                    assert_eq!(got.a.is_some(), cpu.a.is_some());
                    let planes = [
                        ("r", &got.r, &cpu.r),
                        ("g", &got.g, &cpu.g),
                        ("b", &got.b, &cpu.b),
                    ];
                    let alpha = got.a.as_ref().zip(cpu.a.as_ref()).map(|(g, c)| ("a", g, c));
                    for (name, got, cpu) in planes.into_iter().chain(alpha) {
                        // The range of the ordinary pixels: the stress values (±1e30) would
                        // make a bound relative to the whole range vacuous. A pixel whose
                        // output is itself huge (a stress value's light) is held to 1e-5 of
                        // its own magnitude instead.
                        const ORDINARY: f32 = 1e6;
                        let (lo, hi) = bounds(cpu.iter().filter(|v| v.abs() <= ORDINARY));
                        let range = (hi - lo).max(f32::MIN_POSITIVE);
                        let d = diff(got, cpu);
                        let what = format!("lens {j} {w}x{h} blades {blades} rings {rings} {name}");
                        let (mut sum, mut ordinary) = (0.0f64, 0usize);
                        for (i, (&g, &c)) in got.iter().zip(cpu.iter()).enumerate() {
                            let e = (g - c).abs();
                            let bound = 1e-5 * range.max(c.abs());
                            assert!(
                                e <= bound,
                                "{what}: {e} > {bound} at {i} (GPU {g} CPU {c}, range {range})"
                            );
                            if c.abs() <= ORDINARY {
                                sum += e as f64;
                                ordinary += 1;
                                worst = worst.max(e / range);
                            }
                        }
                        let mean = sum / ordinary.max(1) as f64;
                        assert!(mean <= 1e-7 * range as f64, "{what}: mean {mean}");
                        assert!(d.max.is_finite());
                        cases += 1;
                    }
                }
            }
        }
        let _ = writeln!(
            std::io::stderr(),
            "gpu: dof gather: {cases} planes, largest difference {worst:e} of the range"
        );
    }

    /// Issue 34 on the twins: the fine checkers of the CPU's edge test (src: tests/dof.rs,
    /// `EDGE_CHECKERS`: 4 px cells under a 9 px CoC, 5 px under 12, meeting the edges whole,
    /// cut in half and as a 1 px sliver) keep their mean, 0.5, within 0.25 in the first CoC
    /// radius of every edge, corners included, through the gather's twin and the blend's, as
    /// the CPU's do (mirroring the frame about its edge reached 0.304 and 0.260 in the
    /// gather), and each twin matches its CPU pass within its parity tests' tolerance (1e-5
    /// of the range, 0.8 here).
    #[test]
    fn dof_twins_keep_a_fine_checker_s_mean_at_the_frame_edge() {
        let Some(gpu) = gpu() else { return };
        use crate::dof::{edge_case, EDGE_CHECKERS, EDGE_FRAME};
        use shutter::dof::blend::blend;
        use shutter::dof::gather::gather;
        let (w, h) = EDGE_FRAME;
        for (cell, coc, shifts) in EDGE_CHECKERS {
            for shift in shifts {
                let (config, color, coc_plane, t) = edge_case(cell, coc, shift);
                let pairs = [
                    (
                        "gather",
                        gpu.try_dof_gather(&config, &color, &coc_plane, &t)
                            .unwrap_or_else(|e| panic!("{e}")),
                        gather(&config, &color, &coc_plane, &t),
                    ),
                    (
                        "blend",
                        gpu.try_dof_blend(&config, &color, &coc_plane)
                            .unwrap_or_else(|e| panic!("{e}")),
                        blend(&config, color.clone(), &coc_plane),
                    ),
                ];
                let radius = (0.5 * coc).ceil() as usize;
                for (method, got, cpu) in pairs {
                    let what = format!("{method}, cell {cell} shift {shift}, CoC {coc}");
                    twin_within_checker_range(&got.r, &cpu.r, w, |_| what.clone());
                    for y in 0..h {
                        for x in 0..w {
                            let g = got.r[y * w + x];
                            if x.min(w - 1 - x).min(y).min(h - 1 - y) < radius {
                                assert!((g - 0.5).abs() <= 0.25, "{what}: ({x}, {y}): {g}");
                            }
                        }
                    }
                }
            }
        }
    }

    /// blend's discs below level 3 (issue 34): a noise frame under a CoC that runs across
    /// the frame from 1 to 24 px, behind the focus plane on the left half and in front on
    /// the right, so every pixel's kernel is met (the frame's disc, its mix into level 1's,
    /// level 1's, its mix into the pyramid, the pyramid alone) as are the near field's
    /// spread and the frame's edges: the twin within 1e-5 of the range of the CPU.
    #[test]
    fn blend_twin_gathers_the_discs_as_the_cpu_does() {
        let Some(gpu) = gpu() else { return };
        use crate::dof::{edge_case, EDGE_FRAME};
        use shutter::dof::blend::blend;
        let (w, _) = EDGE_FRAME;
        let (config, mut color, mut coc_plane, _) = edge_case(2, 5.0, 1);
        let noise = |i: usize, k: usize| ((i * 7919 + k * 104_729) % 1000) as f32 / 1000.0;
        for (k, plane) in [&mut color.r, &mut color.g, &mut color.b]
            .into_iter()
            .enumerate()
        {
            for (i, v) in plane.iter_mut().enumerate() {
                *v = noise(i, k);
            }
        }
        for (i, c) in coc_plane.iter_mut().enumerate() {
            let x = i % w;
            let size = 1.0 + 23.0 * x as f32 / (w - 1) as f32;
            *c = if x < w / 2 { size } else { -size };
        }
        // Without alpha, and with an alpha of its own noise.
        let with_alpha = shutter::frame::Color {
            a: Some((0..color.r.len()).map(|i| noise(i, 3)).collect()),
            ..color.clone()
        };
        for color in [color, with_alpha] {
            let got = gpu
                .try_dof_blend(&config, &color, &coc_plane)
                .unwrap_or_else(|e| panic!("{e}"));
            let cpu = blend(&config, color.clone(), &coc_plane);
            for (k, (got, cpu)) in got.planes().iter().zip(cpu.planes()).enumerate() {
                twin_within_checker_range(got, cpu, w, |i| {
                    format!("plane {k}, CoC {}", coc_plane[i])
                });
            }
            assert_eq!(got.a.is_some(), cpu.a.is_some());
        }
    }

    /// Every sample of a twin's plane within 1e-5 of the range (0.8, the edge checker's)
    /// of the CPU's; `what(i)` names sample i's case.
    fn twin_within_checker_range(
        got: &[f32],
        cpu: &[f32],
        w: usize,
        what: impl Fn(usize) -> String,
    ) {
        for (i, (g, c)) in got.iter().zip(cpu).enumerate() {
            assert!(
                (g - c).abs() <= 1e-5 * 0.8,
                "{}: ({}, {}): GPU {g}, CPU {c}",
                what(i),
                i % w,
                i / w
            );
        }
    }

    /// A near disc's rim over a fine far checker, 96×64: the colour (the disc 0.3, the
    /// checker 0 and 1, G its complement) and the CoC plane (the disc −14, the checker 8).
    fn near_rim_over_checker() -> (usize, usize, shutter::frame::Color, Vec<f32>) {
        let (w, h) = (96, 64);
        let disc = |x: usize, y: usize| {
            let (dx, dy) = (x as f32 + 0.5 - 14.0, y as f32 + 0.5 - 14.0);
            dx * dx + dy * dy < 8.0 * 8.0
        };
        let plane: Vec<f32> = (0..w * h)
            .map(|i| {
                if disc(i % w, i / w) {
                    0.3
                } else {
                    ((i % w + i / w) % 2) as f32
                }
            })
            .collect();
        let color = shutter::frame::Color {
            r: plane.clone(),
            g: plane.iter().map(|v| 1.0 - v).collect(),
            b: plane,
            a: Some(vec![1.0; w * h]),
        };
        let coc = (0..w * h)
            .map(|i| if disc(i % w, i / w) { -14.0 } else { 8.0 })
            .collect();
        (w, h, color, coc)
    }

    /// A near disc's rim over a fine far checker (disc CoC −14: its tiles take the rings of
    /// 7 px; the checker's 4 px bokeh reads the dense grid there): the twin picks the dense
    /// grid per pixel as the CPU picks it per lane, within the gather's tolerance (1e-5 of
    /// the range), beauty and carried alike.
    #[test]
    fn dof_gather_reads_the_dense_grid_in_a_near_rim_s_tiles_as_the_cpu_does() {
        let Some(gpu) = gpu() else { return };
        use shutter::dof::gather::plan;
        use shutter::dof::DofConfig;
        let (w, h, color, coc) = near_rim_over_checker();
        let config = DofConfig::new(w, h, &DofParams::default());
        let t = tiles(&TilesConfig::new(w, h, config.epsilon), &coc);
        assert!(plan(&config, &t).tiles.iter().any(|t| t.dense_count > 0));
        let (cpu, got, carried, _) = gathered(gpu, &config, &color, &coc, &t);
        for out in [&got, &carried[0], &carried[1]] {
            for (name, g, c) in [("r", &out.r, &cpu.r), ("g", &out.g, &cpu.g)] {
                for (i, (g, c)) in g.iter().zip(c.iter()).enumerate() {
                    assert!((g - c).abs() <= 1e-5, "{name} at {i}: GPU {g}, CPU {c}");
                }
            }
        }
    }

    /// `color` gathered on the CPU, and on the twin alone and carried twice over (two copies
    /// as carried colours); the CPU's carrying gather, carrying `color`'s red, checked to
    /// give the beauty it gives alone. The CPU's, the twin's, the twin's carried, and the
    /// CPU's carried plane.
    fn gathered(
        gpu: &shutter::gpu::Gpu,
        config: &shutter::dof::DofConfig,
        color: &shutter::frame::Color,
        coc: &[f32],
        t: &shutter::dof::tiles::Tiles,
    ) -> (
        shutter::frame::Color,
        shutter::frame::Color,
        Vec<shutter::frame::Color>,
        Vec<Vec<f32>>,
    ) {
        use shutter::dof::gather::{gather, gather_carrying};
        let cpu = gather(config, color, coc, t);
        let got = gpu
            .try_dof_gather(config, color, coc, t)
            .unwrap_or_else(|e| panic!("{e}"));
        let carried = gpu
            .try_dof_gather_carrying(config, &[color, color], coc, t)
            .unwrap_or_else(|e| panic!("{e}"));
        let (cpu_beauty, cpu_carried) =
            gather_carrying(config, color, coc, t, vec![color.r.clone()]);
        assert_eq!(cpu_beauty, cpu);
        (cpu, got, carried, cpu_carried)
    }

    /// The prefilter levels on the twin: a lone highlight (50) and a one-pixel checker under
    /// a 42 px CoC (ring taps reading a box of 4 px), beside a near disc (CoC −40) over a far
    /// field of CoC 9 (both fields, and fields apart with the far taps on the planes
    /// themselves): the twin's `prefilter` makes the CPU's levels and its taps read them as
    /// the CPU's do, beauty and carried, within the gather's tolerance (1e-5 of the range per
    /// pixel, `dof_gather_matches_the_cpu_within_rounding`). With the twin reading single
    /// pixels where the CPU reads levels, the highlight's pixels differ by 8× the disc's level.
    #[test]
    fn dof_gather_reads_the_prefilter_levels_as_the_cpu_does() {
        let Some(gpu) = gpu() else { return };
        use shutter::dof::gather::plan;
        use shutter::dof::DofConfig;
        let (w, h) = (160, 96);
        let n = w * h;
        let disc = |x: usize, y: usize| {
            let (dx, dy) = (x as f32 - 40.0, y as f32 - 48.0);
            dx * dx + dy * dy < 18.0 * 18.0
        };
        let coc: Vec<f32> = (0..n)
            .map(|i| match (i % w, i / w) {
                (x, y) if disc(x, y) => -40.0,
                (x, _) if x > 100 => 42.0,
                _ => 9.0,
            })
            .collect();
        let paint = |i: usize, k: usize| match (i % w, i / w) {
            (135, 48) => 50.0,
            (x, y) if disc(x, y) => 0.3 + 0.1 * k as f32,
            (x, y) => ((x + y + k) % 2) as f32,
        };
        let color = shutter::frame::Color {
            r: (0..n).map(|i| paint(i, 0)).collect(),
            g: (0..n).map(|i| paint(i, 1)).collect(),
            b: (0..n).map(|i| paint(i, 2)).collect(),
            a: Some(
                (0..n)
                    .map(|i| if disc(i % w, i / w) { 1.0 } else { 0.5 })
                    .collect(),
            ),
        };
        let config = DofConfig::new(w, h, &DofParams::default());
        let t = tiles(&TilesConfig::new(w, h, config.epsilon), &coc);
        let p = plan(&config, &t);
        assert!(!p.sides.is_empty());
        assert!(p.tiles.iter().any(|t| t.fields == 1 && t.level > 0));
        assert!(p.tiles.iter().any(|t| t.fields != 1 && t.level > 0));
        let (cpu, got, carried, cpu_carried) = gathered(gpu, &config, &color, &coc, &t);
        let range = cpu.r.iter().fold(0.0f32, |m, &v| m.max(v.abs()));
        let tolerance = 1e-5 * range;
        for (what, out) in [
            ("gather", &got),
            ("carrying 0", &carried[0]),
            ("carrying 1", &carried[1]),
        ] {
            let planes = [
                ("r", &out.r, &cpu.r),
                ("g", &out.g, &cpu.g),
                ("b", &out.b, &cpu.b),
                ("a", out.a.as_ref().unwrap(), cpu.a.as_ref().unwrap()),
            ];
            for (name, g, c) in planes {
                for (i, (g, c)) in g.iter().zip(c.iter()).enumerate() {
                    assert!(
                        (g - c).abs() <= tolerance,
                        "{what} {name} at ({}, {}): GPU {g}, CPU {c}",
                        i % w,
                        i / w
                    );
                }
            }
        }
        // The CPU's carried plane is the beauty's red within its own rounding (32 ulps of
        // the plane's largest value, 50, as src/dof/gather/carry.rs holds it).
        for (i, (c, r)) in cpu_carried[0].iter().zip(&cpu.r).enumerate() {
            let bound = 32.0 * f32::EPSILON * 50.0;
            assert!((c - r).abs() <= bound, "carried at {i}: {c}, beauty {r}");
        }
    }

    /// Odd blade counts on the twin. Three and five blades (turned 0° and 20°) have no
    /// centre of symmetry: a source's bokeh is the aperture behind the focus plane and the
    /// aperture turned over in front of it, and a tile's taps cover both (src/dof/bokeh.rs).
    /// On a near disc's rim over a fine far checker (the dense grid, which the twin reads
    /// whole where the CPU reads the smallest that holds a lane's bokeh) and on the stress
    /// depth frame under a lens of CoC up to 48 px (grid, ring and split tiles, near and far
    /// fields), 2 and 6 rings, the twin matches the CPU within the gather's tolerance
    /// (`dof_gather_matches_the_cpu_within_rounding`: 1e-5 of the range per pixel, mean
    /// 1e-7), beauty and carried. When the grid held only the shape's own offsets, a larger
    /// grid held offsets of the reflected shape that a smaller one lacked, and the twin's
    /// checker under a triangle erred by a quarter of its range (0.075 of 0.30).
    #[test]
    fn dof_gather_with_odd_blades_matches_the_cpu_within_rounding() {
        let Some(gpu) = gpu() else { return };
        use shutter::dof::gather::gather;
        use shutter::dof::DofConfig;
        use shutter::numeric::{sanitize, DepthKind};
        // Every pixel within 1e-5 of the CPU plane's range, the mean within 1e-7.
        let within = |got: &[f32], cpu: &[f32], what: &str| {
            let (lo, hi) = bounds(cpu);
            let range = (hi - lo).max(f32::MIN_POSITIVE);
            let d = diff(got, cpu);
            assert!(
                d.max <= 1e-5 * range,
                "{what}: {} > 1e-5 of {range} at {} (GPU {} CPU {})",
                d.max,
                d.worst,
                got[d.worst],
                cpu[d.worst]
            );
            assert!(d.mean <= 1e-7 * range as f64, "{what}: mean {}", d.mean);
        };
        // The near rim over the checker, as the CoC plane.
        let (w, h, rim, rim_coc) = near_rim_over_checker();
        // The stress depth frame under a lens of CoC up to 48 px, over noise.
        let (sw, sh) = (160, 90);
        let lens = Lens {
            focal_mm: 50.0,
            f_number: 2.0,
            focus: 2.0,
            sensor_mm: 36.0,
        };
        let mut frame = depth_frame(sw, sh, 93, 2.0);
        let n = sw * sh;
        frame.color = Some(shutter::frame::Color {
            r: noise(n, 13, 0.0, 4.0),
            g: noise(n, 15, -1.0, 1.0),
            b: noise(n, 17, 0.0, 0.01),
            a: None,
        });
        let _ = sanitize(&mut frame, DepthKind::Depth);
        for blades in [3, 5] {
            for rotation in [0.0, 20.0] {
                for rings in [6, 2] {
                    let params = DofParams {
                        max_coc: 48.0,
                        blades,
                        blade_rotation: rotation,
                        rings,
                        ..DofParams::new(CocSource::Lens(lens))
                    };
                    let what = format!("blades {blades} rotation {rotation} rings {rings}");
                    // The rim.
                    let config = DofConfig::new(w, h, &params);
                    let t = tiles(&TilesConfig::new(w, h, config.epsilon), &rim_coc);
                    let cpu = gather(&config, &rim, &rim_coc, &t);
                    let got = gpu
                        .try_dof_gather(&config, &rim, &rim_coc, &t)
                        .unwrap_or_else(|e| panic!("{e}"));
                    let carried = gpu
                        .try_dof_gather_carrying(&config, &[&rim, &rim], &rim_coc, &t)
                        .unwrap_or_else(|e| panic!("{e}"));
                    for (k, out) in [&got, &carried[0], &carried[1]].into_iter().enumerate() {
                        within(&out.r, &cpu.r, &format!("{what}: rim {k} r"));
                        within(&out.g, &cpu.g, &format!("{what}: rim {k} g"));
                    }
                    // The stress frame.
                    let coc = coc_plane(&frame, &params);
                    let config = DofConfig::new(sw, sh, &params);
                    let t = tiles(&TilesConfig::new(sw, sh, config.epsilon), &coc);
                    let color = frame.color.as_ref().unwrap();
                    let cpu = gather(&config, color, &coc, &t);
                    let got = gpu
                        .try_dof_gather(&config, color, &coc, &t)
                        .unwrap_or_else(|e| panic!("{e}"));
                    for (name, g, c) in [("r", &got.r, &cpu.r), ("g", &got.g, &cpu.g)] {
                        within(g, c, &format!("{what}: stress {name}"));
                    }
                }
            }
        }
    }

    /// The gather carrying light layers (`gather_carrying`): ten colours (two dispatches of at
    /// most eight) against the CPU's carried gather, each colour within the tolerance the
    /// gather's own parity test states (1e-5 of its range per pixel, mean 1e-7; the light
    /// layers, carried in the CPU's other form, mean 3e-7), on two lenses with and without
    /// alpha; the beauty carried equals the beauty gathered alone on
    /// the GPU within the same bound.
    #[test]
    fn dof_gather_carrying_layers_matches_the_cpu_within_rounding() {
        let Some(gpu) = gpu() else { return };
        use shutter::dof::gather::gather_carrying;
        use shutter::dof::DofConfig;
        use shutter::frame::Color;
        use shutter::numeric::{sanitize, DepthKind};
        let (w, h) = (70, 45);
        let n = w * h;
        for (k, (focus, alpha)) in [(2.0f32, true), (0.7, false)].into_iter().enumerate() {
            let lens = Lens {
                focal_mm: 85.0,
                f_number: 1.4,
                focus: focus as f64,
                sensor_mm: 36.0,
            };
            let mut frame = depth_frame(w, h, 40 + k as u32, focus);
            let colour = |seed: u32| Color {
                r: noise(n, seed, 0.0, 4.0),
                g: noise(n, seed + 1, -1.0, 1.0),
                b: noise(n, seed + 2, 0.0, 0.01),
                a: alpha.then(|| noise(n, 99, 0.0, 1.0)),
            };
            frame.color = Some(colour(1));
            let _ = sanitize(&mut frame, DepthKind::Depth);
            let params = DofParams {
                max_coc: 64.0,
                ..DofParams::new(CocSource::Lens(lens))
            };
            let coc = coc_plane(&frame, &params);
            let config = DofConfig::new(w, h, &params);
            let t = tiles(&TilesConfig::new(w, h, config.epsilon), &coc);
            let beauty = frame.color.clone().unwrap();
            let layers: Vec<Color> = (0..9).map(|j| colour(10 + 3 * j)).collect();
            let colours: Vec<&Color> = std::iter::once(&beauty).chain(&layers).collect();
            let got = gpu
                .try_dof_gather_carrying(&config, &colours, &coc, &t)
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(got.len(), 10);
            let planes: Vec<Vec<f32>> = layers
                .iter()
                .flat_map(|l| [l.r.clone(), l.g.clone(), l.b.clone()])
                .collect();
            let (cpu_beauty, cpu_layers) = gather_carrying(&config, &beauty, &coc, &t, planes);
            let alone = gpu.try_dof_gather(&config, &beauty, &coc, &t).unwrap();
            let mut want: Vec<(&str, &[f32], &[f32])> = vec![
                ("beauty r", &got[0].r, &cpu_beauty.r),
                ("beauty b", &got[0].b, &cpu_beauty.b),
                ("beauty alone r", &got[0].r, &alone.r),
            ];
            if alpha {
                want.push((
                    "beauty a",
                    got[0].a.as_ref().unwrap(),
                    cpu_beauty.a.as_ref().unwrap(),
                ));
            }
            for (j, layer) in got[1..].iter().enumerate() {
                want.push(("layer r", &layer.r, &cpu_layers[3 * j]));
                want.push(("layer g", &layer.g, &cpu_layers[3 * j + 1]));
                want.push(("layer b", &layer.b, &cpu_layers[3 * j + 2]));
            }
            for (what, got, cpu) in want {
                let (lo, hi) = bounds(cpu);
                let range = (hi - lo).max(f32::MIN_POSITIVE);
                let d = diff(got, cpu);
                assert!(
                    d.max <= 1e-5 * range,
                    "lens {k} {what}: {} > 1e-5 of {range}",
                    d.max
                );
                // The light layers come through the CPU's carried form (one weight a tap,
                // fused multiply-adds) against the twin's sums of the beauty's form, and where
                // ring taps read the prefilter levels each sample is itself a box's sums,
                // which a driver may fuse: measured 1.9e-7 of the range on lavapipe.
                let mean_bound = if what.starts_with("layer") {
                    3e-7
                } else {
                    1e-7
                };
                assert!(
                    d.mean <= mean_bound * range as f64,
                    "lens {k} {what}: mean {}",
                    d.mean
                );
            }
            // The layers moved: this is no comparison of copies.
            assert_ne!(cpu_layers[0], layers[0].r);
        }
    }

    /// blend on `layers` at 320×180 with ε = 3 px through the CLI, cpu against wgpu: inside
    /// the blurred foreground the near field's spread equals each pixel's own blur but for
    /// rounding, where the two ladders once swapped on the last bit (dots up to 0.04 apart
    /// between the backends; `SPREAD_MARGIN` in src/dof/blend/pyramid/compose.rs). Bound as
    /// in the parity test below: 1e-5 of the range.
    #[test]
    fn dof_blend_on_wgpu_keeps_the_cpu_s_ladders_inside_a_foreground() {
        let Some(_gpu) = gpu() else { return };
        let dir = small_scene("layers", 320, 180, 1, 4);
        let (color, depth) = (
            role_pattern(dir.path(), "color"),
            role_pattern(dir.path(), "depth"),
        );
        let mut outputs = Vec::new();
        for backend in ["cpu", "wgpu"] {
            let out = s(&dir.path().join(format!("eps3-{backend}.####.exr")));
            let mut args = dof_args(&color, &depth, &out);
            args.extend(["--backend", backend, "--method", "blend", "--epsilon", "3"]);
            let o = shutter(&args);
            assert!(o.status.success(), "{backend}: {}", stderr(&o));
            outputs.push(read_exr_reference(
                &dir.path().join(format!("eps3-{backend}.0001.exr")),
            ));
        }
        for name in ["R", "G", "B"] {
            let cpu = channel(&outputs[0], name);
            let got = channel(&outputs[1], name);
            let (lo, hi) = bounds(cpu);
            let d = diff(got, cpu);
            assert!(
                d.max <= 1e-5 * (hi - lo),
                "{name}: {} at {} > 1e-5 of {}",
                d.max,
                d.worst,
                hi - lo
            );
        }
    }

    /// Depth of field's blend twin (the pyramid) against `blend`, on the stress depth frames
    /// under the gather test's three lenses (E from 48 to 512 px: from four levels to
    /// eight, the discs below level 3's CoC, the near field's spread read at levels 0 to 7), with and
    /// without alpha, over a colour of fine noise (under one lens with stress values, made
    /// finite first as the pipeline does), and on frames one and two pixels wide or high.
    ///
    /// Tolerance: the twin runs the CPU's plan (E, levels, ladders, where T_near is read) and
    /// the same sums in the same order, so what differs is rounding: the divisions (a level's
    /// colour by its w, the discs by theirs; WGSL allows 2.5 ULP) and products a
    /// driver may fuse into the sums (the lerps, the [1 3 3 1]/8 taps). Each is a few
    /// 2⁻²⁴ of the values it combines, which are within the frame's range r of the
    /// reference; the pyramid's levels add a rounding per halving, at most a dozen. Bound: max
    /// difference ≤ 1e-5·r per pixel (held to 1e-5 of a pixel's own magnitude where a stress
    /// value's light makes it huge), mean ≤ 1e-7·r; every pixel finite.
    #[test]
    fn dof_blend_matches_the_cpu_within_rounding() {
        let Some(gpu) = gpu() else { return };
        use shutter::dof::blend::blend;
        use shutter::dof::DofConfig;
        use shutter::numeric::{sanitize, DepthKind};
        let lenses = [
            (50.0, 2.0, 2.0, 48.0),
            (85.0, 1.4, 3.0, 200.0),
            (35.0, 1.2, 0.5, 512.0),
        ];
        let sizes = [(37, 23), (160, 90), (64, 211), (1, 9), (2, 2), (13, 1)];
        let (mut cases, mut worst) = (0, 0.0f32);
        for (k, &(w, h)) in sizes.iter().enumerate() {
            for (j, &(focal_mm, f_number, focus, max_coc)) in lenses.iter().enumerate() {
                let lens = Lens {
                    focal_mm,
                    f_number,
                    focus,
                    sensor_mm: 36.0,
                };
                let mut frame = depth_frame(w, h, 90 + k as u32, focus as f32);
                let n = w * h;
                if k == 1 {
                    // Uniform depths in blocks (a foreground at 0.6 of the focus distance,
                    // the focus plane, a background): inside the foreground the near
                    // field's spread equals the pixels' own blur but for rounding.
                    let depth = frame.depth.as_mut().unwrap();
                    for (i, d) in depth.iter_mut().enumerate() {
                        let (x, y) = (i % w, i / w);
                        *d = focus as f32 * [0.6, 1.0, 4.0][(x / 40 + y / 30) % 3];
                    }
                }
                let mut color = shutter::frame::Color {
                    r: noise(n, 3 + k as u32, 0.0, 4.0),
                    g: noise(n, 5 + k as u32, -1.0, 1.0),
                    b: noise(n, 7 + k as u32, 0.0, 0.01),
                    a: (j != 1).then(|| noise(n, 11 + k as u32, 0.0, 1.0)),
                };
                if j == 2 {
                    let stress = stress_values(focus as f32);
                    for (i, v) in stress.iter().enumerate() {
                        color.r[(i * 13 + 5) % n] = *v;
                        color.g[(i * 17 + 3) % n] = *v;
                    }
                }
                frame.color = Some(color);
                let _ = sanitize(&mut frame, DepthKind::Depth);
                let params = DofParams {
                    max_coc,
                    method: shutter::dof::Method::Blend,
                    // ε of 3 px under one lens: the discs' smallest CoCs and the spread's
                    // margin over a wider in-focus band.
                    epsilon: if j == 1 { 3.0 } else { 1.0 },
                    ..DofParams::new(CocSource::Lens(lens))
                };
                let coc = coc_plane(&frame, &params);
                let config = DofConfig::new(w, h, &params);
                let color = frame.color.as_ref().unwrap();
                let cpu = blend(&config, color.clone(), &coc);
                let got = gpu
                    .try_dof_blend(&config, color, &coc)
                    .unwrap_or_else(|e| panic!("{e}"));
                assert_eq!(got.a.is_some(), cpu.a.is_some());
                let planes = [
                    ("r", &got.r, &cpu.r, &color.r),
                    ("g", &got.g, &cpu.g, &color.g),
                    ("b", &got.b, &cpu.b, &color.b),
                ];
                let alpha = (got.a.as_ref().zip(cpu.a.as_ref()))
                    .zip(color.a.as_ref())
                    .map(|((g, c), i)| ("a", g, c, i));
                for (name, got, cpu, input) in planes.into_iter().chain(alpha) {
                    // The range of the values the blur combines: the input plane's ordinary
                    // pixels (a heavy blur narrows the output's own range).
                    const ORDINARY: f32 = 1e6;
                    let (lo, hi) = bounds(input.iter().filter(|v| v.abs() <= ORDINARY));
                    let range = (hi - lo).max(f32::MIN_POSITIVE);
                    // A pixel a stress value's light reaches is a sum of terms as large as
                    // the largest input (±1e30, which cancel in part): its rounding is
                    // relative to that.
                    let largest = input.iter().fold(0.0f32, |m, v| m.max(v.abs()));
                    let what = format!("lens {j} {w}x{h} {name}");
                    let (mut sum, mut ordinary) = (0.0f64, 0usize);
                    for (i, (&g, &c)) in got.iter().zip(cpu.iter()).enumerate() {
                        assert!(g.is_finite(), "{what}: GPU gave {g} at {i}");
                        let e = (g - c).abs();
                        let scale = if c.abs() <= ORDINARY { range } else { largest };
                        let bound = 1e-5 * scale;
                        assert!(
                            e <= bound,
                            "{what}: {e} > {bound} at {i} (GPU {g} CPU {c}, range {range})"
                        );
                        if c.abs() <= ORDINARY {
                            sum += e as f64;
                            ordinary += 1;
                            worst = worst.max(e / range);
                        }
                    }
                    let mean = sum / ordinary.max(1) as f64;
                    assert!(mean <= 1e-7 * range as f64, "{what}: mean {mean}");
                    cases += 1;
                }
            }
        }
        let _ = writeln!(
            std::io::stderr(),
            "gpu: dof blend: {cases} planes, largest difference {worst:e} of the range"
        );
    }

    // ---- The tile stages: max/min reductions, exact or nearly ----

    /// Depth of field's tile min/max twin against `tiles`: on the CoC planes of the stress
    /// depth frames under several lenses, on signed noise (near and far fields meeting), on
    /// planes with NaN and subnormal values, on uniform and in-focus planes, with ε from 0 to
    /// 4 px.
    ///
    /// Tolerance: none — every tile's reach, own radius and far-only flag equal the CPU's bit
    /// for bit. Each is a max, a min or a comparison of input values halved (exact) or plus
    /// one (correctly rounded in WGSL), and the distances between tiles come from the CPU's
    /// own `gap_distance`. The one case a GPU may differ (a CoC below 2⁻¹²⁵ px, whose half a
    /// GPU may flush to zero) matters only with ε = 0, so the planes with subnormal values run
    /// with ε > 0.
    #[test]
    fn dof_tiles_match_the_cpu_exactly_on_lenses_stress_and_noise() {
        let Some(gpu) = gpu() else { return };
        let mut planes: Vec<(String, usize, usize, Vec<f32>, f32)> = Vec::new();
        let lenses = [
            (50.0, 2.0, 2.0, 48.0),
            (85.0, 1.4, 3.0, 200.0),
            (35.0, 1.2, 0.5, 512.0),
        ];
        for (k, &(w, h)) in [(37, 23), (64, 48), (101, 7), (250, 130)]
            .iter()
            .enumerate()
        {
            for (j, &(focal_mm, f_number, focus, max_coc)) in lenses.iter().enumerate() {
                let lens = Lens {
                    focal_mm,
                    f_number,
                    focus,
                    sensor_mm: 36.0,
                };
                let params = DofParams {
                    max_coc,
                    ..DofParams::new(CocSource::Lens(lens))
                };
                let frame = depth_frame(w, h, 70 + k as u32, focus as f32);
                let coc = coc_plane(&frame, &params);
                let epsilon = [1.0, 0.0, 4.0][j];
                planes.push((format!("lens {j} {w}x{h}"), w, h, coc, epsilon));
            }
            // Signed noise: near and far fields side by side, with NaN, subnormals, signed
            // zeros, exact layer boundaries, and radii whose reach (r + 1 px) is exactly a
            // whole gap between tiles (15 + 1 = 16, 31 + 1 = 32).
            let mut coc = noise(w * h, 80 + k as u32, -60.0, 60.0);
            let specials = [
                f32::NAN,
                -f32::NAN,
                1e-40,
                -1e-40,
                0.0,
                -0.0,
                1.0,
                -1.0,
                2.0,
                30.0,
                -30.0,
                62.0,
                60.0,
                -60.0,
            ];
            for (i, v) in specials.iter().cycle().take(w * h / 9).enumerate() {
                coc[(i * 9 + k) % (w * h)] = *v;
            }
            planes.push((format!("noise {w}x{h}"), w, h, coc, 1.0));
            // Mostly in focus, with a few out-of-focus islands.
            let coc: Vec<f32> = noise(w * h, 90 + k as u32, -1.0, 1.0)
                .into_iter()
                .enumerate()
                .map(|(i, v)| if i % 97 == 0 { v * 90.0 } else { v * 0.4 })
                .collect();
            planes.push((format!("islands {w}x{h}"), w, h, coc, 1.0));
            // In focus but for single pixels whose reach is exactly a whole gap between tiles
            // (radius 15 reaches 16 px, two tiles away; 31 reaches 32 px, three away), sparse
            // enough that these thresholds decide the reach of the tiles around them.
            let columns = w.div_ceil(16);
            let mut coc = vec![0.2; w * h];
            for (i, v) in coc.iter_mut().enumerate() {
                let (x, y) = (i % w, i / w);
                let (tx, ty) = (x / 16, y / 16);
                if x % 16 == 0 && y % 16 == 0 && (tx + 3 * ty) % 7 == 0 {
                    *v = [30.0, -30.0, 62.0, -62.0][(ty * columns + tx) % 4];
                }
            }
            planes.push((format!("thresholds {w}x{h}"), w, h, coc, 1.0));
            planes.push((format!("uniform {w}x{h}"), w, h, vec![12.0; w * h], 1.0));
            planes.push((format!("in focus {w}x{h}"), w, h, vec![0.2; w * h], 1.0));
            // A tile of nothing but NaN (the CPU's +∞/−∞ starts).
            let mut coc = noise(w * h, 95, -8.0, 8.0);
            for y in 0..h.min(16) {
                for x in 0..w.min(16) {
                    coc[y * w + x] = f32::NAN;
                }
            }
            planes.push((format!("NaN tile {w}x{h}"), w, h, coc, 1.0));
        }
        let (mut count, mut far, mut near, mut reached) = (0, 0, 0, 0);
        for (what, w, h, coc, epsilon) in &planes {
            let config = TilesConfig::new(*w, *h, *epsilon);
            let cpu = tiles(&config, coc);
            let got = gpu.try_tiles(&config, coc).expect("the GPU stage runs");
            for (name, g, c) in [
                ("reach", &got.reach, &cpu.reach),
                ("own", &got.own, &cpu.own),
            ] {
                let d = differing(g, c);
                assert!(
                    d.is_empty(),
                    "{what} ε {epsilon}: {name} differs at {} tiles, first {}: GPU {} CPU {}",
                    d.len(),
                    d[0],
                    g[d[0]],
                    c[d[0]]
                );
            }
            let d: Vec<usize> = (0..cpu.far_only.len())
                .filter(|&t| got.far_only[t] != cpu.far_only[t])
                .collect();
            assert!(
                d.is_empty(),
                "{what} ε {epsilon}: far_only differs at {d:?}"
            );
            count += cpu.reach.len();
            far += cpu.far_only.iter().filter(|&&f| f).count();
            near += cpu.far_only.iter().filter(|&&f| !f).count();
            reached += (0..cpu.reach.len())
                .filter(|&t| cpu.reach[t] > cpu.own[t])
                .count();
        }
        // The planes exercise both answers of the flag and reaches beyond a tile's own.
        assert!(
            far > 100 && near > 100 && reached > 100,
            "{far} {near} {reached}"
        );
        let _ = writeln!(
            std::io::stderr(),
            "gpu: dof tiles: {count} tiles over {} planes, bit for bit",
            planes.len()
        );
    }

    /// Depth of field's tile min/max at 1920×1080 with CoC up to 48 px, printed (benchmarks
    /// measure, tests assert).
    #[test]
    fn dof_tiles_at_1080p_print_their_time() {
        let Some(gpu) = gpu() else { return };
        let (w, h) = (1920, 1080);
        let coc = noise(w * h, 4, -48.0, 48.0);
        let config = TilesConfig::new(w, h, 1.0);
        let mut got = None;
        let gpu_ms = milliseconds(&mut || got = Some(gpu.tiles(&config, &coc)));
        let cpu_ms = milliseconds(&mut || drop(tiles(&config, &coc)));
        let _ = writeln!(
            std::io::stderr(),
            "gpu: dof tiles 1920x1080 upload+dispatch+readback {gpu_ms:.2} ms (cpu {cpu_ms:.2} ms)"
        );
        assert_eq!(got.unwrap(), tiles(&config, &coc));
    }
}
