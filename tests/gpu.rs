//! The wgpu backend: every shader validated without a GPU (naga), each WGSL twin against its
//! CPU reference on generated and stress frames, the CLI's `--backend` (its one-line error
//! with no Vulkan driver, auto's fallback, and a `--backend wgpu` run equal to the CPU within
//! the tolerance).
//!
//! The parity tests need an adapter; Mesa's software Vulkan driver (lavapipe, Debian
//! `mesa-vulkan-drivers`) is enough. Without one they print `skipped: no GPU adapter` on
//! stderr (past the test harness's capture) and pass, unless `SHUTTER_REQUIRE_GPU=1` (CI
//! sets it), under which they fail.

use crate::support::*;

/// `--backend` and its preset key, in any build.
#[test]
fn the_backend_is_a_setting_with_a_preset_key_and_cpu_by_default() {
    let def = shutter::settings::def("backend").expect("backend is a setting");
    assert_eq!(def.default_text(), "cpu");
    assert_eq!(def.key(), "backend");
    assert_eq!(def.expect(), "cpu, wgpu or auto");
    let dir = tempfile::tempdir().unwrap();
    let preset = dir.path().join("gpu.toml");
    std::fs::write(&preset, "[blur]\nbackend = \"gpu\"\n").unwrap();
    let o = shutter(&[
        "blur",
        "--preset",
        &s(&preset),
        "--color",
        "missing.exr",
        "-o",
        &s(&dir.path().join("o.exr")),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("backend = \"gpu\": use cpu, wgpu or auto"),
        "{}",
        stderr(&o)
    );
    let help = stdout(&shutter(&["dof", "--help"]));
    assert!(help.contains("--backend <B>"), "{help}");
    assert!(help.contains("default: cpu"), "{help}");
}

/// The frame `dof` tests use, in a fresh folder: the `layers` truth scene.
fn layers() -> (tempfile::TempDir, String, String) {
    let dir = small_scene("layers", 96, 54, 1, 4);
    let color = role_pattern(dir.path(), "color");
    let depth = role_pattern(dir.path(), "depth");
    (dir, color, depth)
}

fn dof_args<'a>(color: &'a str, depth: &'a str, out: &'a str) -> Vec<&'a str> {
    vec![
        "dof",
        "--color",
        color,
        "--depth",
        depth,
        "-o",
        out,
        "--focal-length",
        "50",
        "--f-stop",
        "1.4",
        "--focus-distance",
        "3",
        "--json",
    ]
}

/// Runs `shutter` with the Vulkan loader pointed at no driver at all.
#[cfg(target_os = "linux")]
fn shutter_without_vulkan(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_shutter"))
        .args(args)
        // Both names: VK_DRIVER_FILES (loader 1.3.207+) and the older VK_ICD_FILENAMES.
        .env("VK_DRIVER_FILES", "/nonexistent/shutter-no-driver.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/shutter-no-driver.json")
        .output()
        .expect("run shutter")
}

#[cfg(target_os = "linux")]
#[test]
fn wgpu_without_a_vulkan_driver_fails_in_one_line_and_touches_nothing() {
    let (dir, color, depth) = layers();
    let out_dir = dir.path().join("out");
    std::fs::create_dir(&out_dir).unwrap();
    std::fs::write(out_dir.join("keep.txt"), "untouched").unwrap();
    let before = snapshot(dir.path());
    let out = s(&out_dir.join("o.####.exr"));
    let mut args = dof_args(&color, &depth, &out);
    args.extend(["--backend", "wgpu"]);
    let o = shutter_without_vulkan(&args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("shutter:")).collect();
    assert_eq!(lines.len(), 1, "one line: {err}");
    #[cfg(feature = "gpu")]
    assert!(
        lines[0].contains("no Vulkan adapter found")
            && lines[0].contains("mesa-vulkan-drivers")
            && lines[0].contains("--backend cpu"),
        "{err}"
    );
    #[cfg(not(feature = "gpu"))]
    assert!(lines[0].contains("without the GPU backend"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(snapshot(dir.path()), before, "the folder is untouched");
}

#[cfg(target_os = "linux")]
#[test]
fn auto_without_a_vulkan_driver_runs_on_the_cpu_and_says_so() {
    let (dir, color, depth) = layers();
    let out = s(&dir.path().join("o.####.exr"));
    let mut args = dof_args(&color, &depth, &out);
    args.extend(["--backend", "auto"]);
    let o = shutter_without_vulkan(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
    let backend = &json["backend"];
    assert_eq!(backend["requested"], "auto", "{json}");
    assert_eq!(backend["used"], "cpu", "{json}");
    assert!(backend["fallback"].is_string(), "{json}");
    assert!(dir.path().join("o.0001.exr").exists());
}

#[cfg(feature = "gpu")]
pub(crate) mod with_gpu {
    use super::*;
    use shutter::dof::{coc_plane, CocSource, DofParams, Lens};
    use shutter::frame::Frame;
    use shutter::gpu::{Gpu, Need};
    use shutter::motion::neighbor_max::neighbor_max;
    use shutter::motion::tile_max::{tile_max, TileGrid};
    use std::io::Write;
    use std::sync::OnceLock;

    /// The test binary's one GPU context (created once, as a run creates it once); `None`
    /// with a visible line when there is no adapter, a failure under SHUTTER_REQUIRE_GPU=1.
    pub(crate) fn gpu() -> Option<&'static Gpu> {
        static GPU: OnceLock<Result<Gpu, String>> = OnceLock::new();
        let gpu = GPU.get_or_init(|| {
            let start = std::time::Instant::now();
            let gpu = Gpu::new(Need::Any);
            if let Ok(gpu) = &gpu {
                let _ = writeln!(
                    std::io::stderr(),
                    "gpu: context on {} in {:.1} ms",
                    gpu.adapter(),
                    start.elapsed().as_secs_f64() * 1e3
                );
            }
            gpu
        });
        match gpu {
            Ok(gpu) => Some(gpu),
            Err(missing) if shutter::gpu::required() => {
                panic!("SHUTTER_REQUIRE_GPU is set but there is no GPU adapter: {missing}")
            }
            Err(missing) => {
                // Straight to stderr: the harness captures eprintln! of passing tests.
                let _ = writeln!(std::io::stderr(), "skipped: no GPU adapter ({missing})");
                None
            }
        }
    }

    #[test]
    fn every_wgsl_shader_parses_and_validates_with_naga() {
        use shutter::gpu::dof::coc;
        use wgpu::naga;
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/gpu");
        let mut found = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "wgsl") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let module = naga::front::wgsl::parse_str(&text).unwrap_or_else(|e| {
                panic!(
                    "{}",
                    e.emit_to_string_with_path(&text, &path.display().to_string())
                )
            });
            naga::valid::Validator::new(
                naga::valid::ValidationFlags::all(),
                naga::valid::Capabilities::empty(),
            )
            .validate(&module)
            .unwrap_or_else(|e| panic!("{}: {e:?}", path.display()));
            found += 1;
        }
        assert!(found >= 6, "{found} .wgsl under {}", dir.display());
        // What the context compiles is the file on disk.
        assert!(coc::SHADER.contains("fn lens_coc"));
        assert!(shutter::gpu::dof::tiles::SHADER.contains("fn tile_reach"));
        assert!(shutter::gpu::motion::tile_max::SHADER.contains("struct TileMaxConfig"));
        assert!(shutter::gpu::motion::neighbor_max::SHADER.contains("struct NeighborMaxConfig"));
        assert!(shutter::gpu::motion::dilate::SHADER.contains("struct SourceTile"));
        assert!(shutter::gpu::dof::gather::SHADER.contains("struct GatherConfig"));
        assert!(shutter::gpu::dof::blend::SHADER.contains("struct BlendConfig"));
    }

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
                let (lo, hi) = cpu
                    .iter()
                    .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
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
        use shutter::dof::gather::{gather, tiles};
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
                    let t = tiles(&coc, w, h, config.epsilon);
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
                        let (lo, hi) = cpu
                            .iter()
                            .filter(|v| v.abs() <= ORDINARY)
                            .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
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

    /// blend on `layers` at 320×180 with ε = 3 px through the CLI, cpu against wgpu: inside
    /// the blurred foreground the near field's spread equals each pixel's own blur but for
    /// rounding, where the two ladders once swapped on the last bit (dots up to 0.04 apart
    /// between the backends; `blend::SPREAD_MARGIN`). Bound as in the parity test below:
    /// 1e-5 of the range.
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
            let (lo, hi) = cpu
                .iter()
                .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
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
    /// eight, the half step, the near field's spread read at levels 0 to 7), with and
    /// without alpha, over a colour of fine noise (under one lens with stress values, made
    /// finite first as the pipeline does), and on frames one and two pixels wide or high.
    ///
    /// Tolerance: the twin runs the CPU's plan (E, levels, ladders, where T_near is read) and
    /// the same sums in the same order, so what differs is rounding: the divisions (a level's
    /// colour by its w, the half step by its weights; WGSL allows 2.5 ULP) and products a
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
                    // ε above the half step's CoC (2.5 px) under one lens.
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
                    let (lo, hi) = input
                        .iter()
                        .filter(|v| v.abs() <= ORDINARY)
                        .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
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

    /// Where two planes differ bit for bit (−0 and +0 differ; NaN equals a NaN of the same
    /// bits).
    fn differing(gpu: &[f32], cpu: &[f32]) -> Vec<usize> {
        assert_eq!(gpu.len(), cpu.len());
        (0..gpu.len())
            .filter(|&i| gpu[i].to_bits() != cpu[i].to_bits())
            .collect()
    }

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
        use shutter::dof::gather::tiles;
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
            let cpu = tiles(coc, *w, *h, *epsilon);
            let got = gpu
                .try_tiles(coc, *w, *h, *epsilon)
                .expect("the GPU stage runs");
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
        use shutter::dof::gather::tiles;
        let (w, h) = (1920, 1080);
        let coc = noise(w * h, 4, -48.0, 48.0);
        let mut got = None;
        let gpu_ms = milliseconds(&mut || got = Some(gpu.tiles(&coc, w, h, 1.0)));
        let cpu_ms = milliseconds(&mut || drop(tiles(&coc, w, h, 1.0)));
        let _ = writeln!(
            std::io::stderr(),
            "gpu: dof tiles 1920x1080 upload+dispatch+readback {gpu_ms:.2} ms (cpu {cpu_ms:.2} ms)"
        );
        assert_eq!(got.unwrap(), tiles(&coc, w, h, 1.0));
    }

    /// The time of a second call of `f` (the first makes the buffers), in milliseconds.
    fn milliseconds(f: &mut dyn FnMut()) -> f64 {
        f();
        let start = std::time::Instant::now();
        f();
        start.elapsed().as_secs_f64() * 1e3
    }

    /// |v|² as the CPU computes it (f32), and exactly (f64).
    fn magnitude(v: (f32, f32)) -> (f32, f64) {
        let exact = (v.0 as f64).powi(2) + (v.1 as f64).powi(2);
        (v.0 * v.0 + v.1 * v.1, exact)
    }

    /// Whether the GPU may have chosen `gpu` where the CPU chose `cpu` among `candidates` (the
    /// vectors the stage compared) without being wrong, as tile_max.wgsl says: the GPU's
    /// vector must be one of the candidates (bit for bit), and either
    /// - both |v|² are below the smallest normal f32 (2⁻¹²⁶ px², |v| < 1.1e-19 px): a GPU may
    ///   flush them to zero, after which neither wins over a still pixel; or
    /// - the two |v|² are within a rounding of each other (relative 2⁻²², four times the f32
    ///   rounding) and a square is inexact in f32: an fma leaves one square unrounded, which
    ///   moves the sum by at most a rounding. Exact ties of exact squares ((3, 4) and (4, 3))
    ///   must go to the first, as on the CPU.
    ///
    /// `None` when neither holds (a wrong answer), else whether it was the flush.
    fn near_tie(gpu: (f32, f32), cpu: (f32, f32), candidates: &[(f32, f32)]) -> Option<bool> {
        let bits = |v: (f32, f32)| (v.0.to_bits(), v.1.to_bits());
        if !candidates.iter().any(|&c| bits(c) == bits(gpu)) && bits(gpu) != (0, 0) {
            return None;
        }
        let ((g32, g), (c32, c)) = (magnitude(gpu), magnitude(cpu));
        let tiny = |m: f32| m < f32::MIN_POSITIVE;
        let inexact = |v: (f32, f32)| {
            [v.0, v.1]
                .iter()
                .any(|&a| (a * a) as f64 != (a as f64) * (a as f64))
        };
        if tiny(g32) && tiny(c32) {
            Some(true)
        } else if (inexact(gpu) || inexact(cpu)) && (g - c).abs() <= c.max(g) * 2f64.powi(-22) {
            Some(false)
        } else {
            None
        }
    }

    /// Velocity components that stress the tile stages: non-finite, huge, the numeric policy's
    /// limit, subnormal, squares that are subnormal, signed zeros, and vectors of equal
    /// length (ties, which the first in order wins).
    fn stress_velocities() -> Vec<(f32, f32)> {
        vec![
            (f32::NAN, 0.0),
            (3.0, -f32::NAN),
            (f32::INFINITY, 0.0),
            (0.0, f32::NEG_INFINITY),
            (f32::INFINITY, f32::INFINITY),
            (1e30, -1e30),
            (f32::MAX, 1.0),
            (f32::MIN, f32::MIN),
            (1e7, -1e7),
            (1e-40, 0.0),
            (0.0, -1e-20),
            (1e-20, 1e-20),
            (-0.0, 0.0),
            (0.0, -0.0),
            (3.0, 4.0),
            (4.0, 3.0),
            (-5.0, 0.0),
            (0.0, 5.0),
            (37.0, 0.0),
            (0.0, -37.0),
        ]
    }

    /// A `w`×`h` velocity field: noise in ±`range` px with the stress vectors through it.
    fn velocity_frame(w: usize, h: usize, seed: u32, range: f32) -> (Vec<f32>, Vec<f32>) {
        let n = w * h;
        let mut vx = noise(n, seed, -range, range);
        let mut vy = noise(n, seed ^ 0x5555, -range, range);
        for (k, v) in stress_velocities()
            .into_iter()
            .cycle()
            .take(n / 5)
            .enumerate()
        {
            let i = (k * 5 + seed as usize) % n;
            (vx[i], vy[i]) = v;
        }
        (vx, vy)
    }

    /// The tile grid's vector at tile `t`.
    fn at(grid: &TileGrid, t: usize) -> (f32, f32) {
        (grid.x[t], grid.y[t])
    }

    /// Tiles where a GPU's answer differs from the CPU's without being wrong ([`near_tie`]).
    #[derive(Default)]
    struct Ties {
        /// Both |v|² below 2⁻¹²⁶ px²: flushed.
        flushed: usize,
        /// Within a rounding, with an inexact square: an fma.
        rounding: usize,
    }

    /// Compares a GPU grid with the CPU's: every tile bit for bit, or a near tie among the
    /// tile's `candidates(t)`. Adds the near ties to `ties`; panics on anything else.
    fn compare_grids(
        what: &str,
        gpu: &TileGrid,
        cpu: &TileGrid,
        candidates: impl Fn(usize) -> Vec<(f32, f32)>,
        ties: &mut Ties,
    ) {
        assert_eq!(
            (gpu.columns, gpu.rows, gpu.size),
            (cpu.columns, cpu.rows, cpu.size)
        );
        let mut tiles: Vec<usize> = differing(&gpu.x, &cpu.x);
        tiles.extend(differing(&gpu.y, &cpu.y));
        tiles.sort_unstable();
        tiles.dedup();
        for t in tiles {
            let (g, c) = (at(gpu, t), at(cpu, t));
            match near_tie(g, c, &candidates(t)) {
                Some(true) => ties.flushed += 1,
                Some(false) => ties.rounding += 1,
                None => panic!(
                    "{what}: tile {t} ({}, {}): GPU {g:?}, CPU {c:?}",
                    t % cpu.columns,
                    t / cpu.columns
                ),
            }
        }
    }

    /// The `tile_max` twin against the CPU's, on noise with the stress vectors, raw and
    /// through the numeric policy (as reconstruct receives them), over sizes off every tile
    /// grid and tile sizes from 1 px to larger than the frame.
    ///
    /// Tolerance: exact. TileMax only selects: each tile's output is one of its input vectors,
    /// bit for bit, chosen by comparing |v|² = x·x + y·y, which WGSL rounds as Rust does. Two
    /// things a GPU may do differently, both allowed by WGSL and neither a wrong answer: fuse
    /// the multiply and add into an fma, and flush subnormals to zero. Each can only swap
    /// two candidates whose |v|² are within a rounding of each other (or both below 2⁻¹²⁶
    /// px²), which [`near_tie`] checks for each differing tile. Rounding near ties need two
    /// candidates within 2⁻²² of each other, which noise makes rare: at most 1 % of tiles.
    /// Flushed ones are not bounded (with 1-px tiles, 3 % of tiles hold only a stress vector
    /// whose |v|² is subnormal, which a flushing GPU leaves at (0, 0)). Every other tile must
    /// be the CPU's, bit for bit. Measured on lavapipe: none differ.
    #[test]
    fn tile_max_matches_the_cpu_exactly_on_generated_and_stress_velocities() {
        let Some(gpu) = gpu() else { return };
        let mut tiles = 0;
        let mut ties = Ties::default();
        for (k, &(w, h)) in [(37, 23), (64, 48), (101, 7), (1, 1), (130, 66)]
            .iter()
            .enumerate()
        {
            for size in [1, 3, 8, 20, 128] {
                for sanitised in [false, true] {
                    let (mut vx, mut vy) = velocity_frame(w, h, 7 + k as u32, 40.0);
                    if sanitised {
                        for v in vx.iter_mut().chain(vy.iter_mut()) {
                            *v = shutter::numeric::velocity(*v);
                        }
                    }
                    let cpu = tile_max(&vx, &vy, w, h, size);
                    let got = gpu
                        .try_tile_max(&vx, &vy, w, h, size)
                        .expect("the GPU stage runs");
                    let candidates = |t: usize| {
                        let (c, r) = (t % cpu.columns, t / cpu.columns);
                        let mut v = Vec::new();
                        for y in r * size..((r + 1) * size).min(h) {
                            for x in c * size..((c + 1) * size).min(w) {
                                v.push((vx[y * w + x], vy[y * w + x]));
                            }
                        }
                        v
                    };
                    let what = format!("tile_max {w}x{h} size {size} sanitised {sanitised}");
                    compare_grids(&what, &got, &cpu, candidates, &mut ties);
                    tiles += cpu.x.len();
                }
            }
        }
        let _ = writeln!(
            std::io::stderr(),
            "gpu: tile_max: of {tiles} tiles, {} rounding and {} flushed near ties, the rest \
             bit for bit",
            ties.rounding,
            ties.flushed
        );
        assert!(ties.rounding * 100 <= tiles, "{} of {tiles}", ties.rounding);
    }

    /// A grid of `columns`×`rows` tiles of noise in ±`range` px with the stress vectors.
    fn noise_grid(columns: usize, rows: usize, size: usize, seed: u32, range: f32) -> TileGrid {
        let (x, y) = velocity_frame(columns, rows, seed, range);
        TileGrid {
            columns,
            rows,
            size,
            x,
            y,
        }
    }

    /// The `neighbor_max` twin against the CPU's, on TileMax grids of the velocity frames and
    /// on noise grids with the stress vectors. Tolerance: exact, as `tile_max` (the same
    /// selection by |v|² over the 3×3 neighbourhood; the same near-tie rule and bound).
    #[test]
    fn neighbor_max_matches_the_cpu_exactly_on_generated_and_stress_grids() {
        let Some(gpu) = gpu() else { return };
        let mut grids = Vec::new();
        for (k, &(w, h, size)) in [(37, 23, 3), (130, 66, 8), (101, 7, 1)].iter().enumerate() {
            let (vx, vy) = velocity_frame(w, h, 20 + k as u32, 40.0);
            grids.push(tile_max(&vx, &vy, w, h, size));
        }
        for (k, &(columns, rows)) in [(1, 1), (2, 1), (1, 3), (17, 9), (40, 33)]
            .iter()
            .enumerate()
        {
            grids.push(noise_grid(columns, rows, 8, 30 + k as u32, 60.0));
        }
        let (mut tiles, mut ties) = (0, Ties::default());
        for grid in &grids {
            let cpu = neighbor_max(grid);
            let got = gpu.try_neighbor_max(grid).expect("the GPU stage runs");
            let candidates = |t: usize| {
                let (c, r) = (t % grid.columns, t / grid.columns);
                let mut v = Vec::new();
                for rr in r.saturating_sub(1)..(r + 2).min(grid.rows) {
                    for cc in c.saturating_sub(1)..(c + 2).min(grid.columns) {
                        v.push(at(grid, rr * grid.columns + cc));
                    }
                }
                v
            };
            let what = format!("neighbor_max {}x{}", grid.columns, grid.rows);
            compare_grids(&what, &got, &cpu, candidates, &mut ties);
            tiles += cpu.x.len();
        }
        let _ = writeln!(
            std::io::stderr(),
            "gpu: neighbor_max: of {tiles} tiles, {} rounding and {} flushed near ties, the \
             rest bit for bit",
            ties.rounding,
            ties.flushed
        );
        assert!(ties.rounding * 100 <= tiles, "{} of {tiles}", ties.rounding);
    }

    /// Half-spread vectors as reconstruct's 2014 variants hand them to `dilate` (k = 128 px
    /// over tiles of 8 px: spans up to 16 tiles), with what stresses the reach test: diagonal
    /// and axis-aligned vectors (the test meets its threshold exactly), whole multiples of the
    /// tile, zeros, NaN, huge (|M|² overflows), subnormal components. Never ±∞ nor |M| above
    /// ~10¹⁹ px: the CPU's loop bounds overflow there (reconstruct clamps to k first).
    fn dilate_grid(columns: usize, rows: usize, seed: u32) -> TileGrid {
        let n = columns * rows;
        let mut grid = TileGrid {
            columns,
            rows,
            size: 8,
            x: noise(n, seed, -90.0, 90.0),
            y: noise(n, seed ^ 0x5555, -90.0, 90.0),
        };
        let special = [
            (40.0, 40.0),
            (-24.0, 24.0),
            (16.0, 0.0),
            (0.0, -8.0),
            (8.0, 8.0),
            (0.0, 0.0),
            (-0.0, 0.0),
            (f32::NAN, 3.0),
            (1e19, 0.0),
            (1e-40, 20.0),
            (30.0, 1e-40),
            (127.9, -0.5),
            (0.3, 0.2),
        ];
        for i in 0..n {
            let h = (i as u32).wrapping_mul(0x9E37_79B9) ^ seed;
            match h % 4 {
                0 => (grid.x[i], grid.y[i]) = special[(h as usize / 4) % special.len()],
                1 => (grid.x[i], grid.y[i]) = (0.0, 0.0), // still: the spread is visible
                _ => {}
            }
        }
        grid
    }

    /// Still tiles but for a lattice of lone vectors (diagonal, axis-aligned, whole tiles
    /// long), so the reach test's threshold decides what the tiles around each receive: a
    /// tile beside a diagonal line is exactly √2 tiles from it.
    fn sparse_grid(columns: usize, rows: usize, seed: usize) -> TileGrid {
        let n = columns * rows;
        let lone = [
            (40.0, 40.0),
            (-24.0, 24.0),
            (8.0, -8.0),
            (16.0, 0.0),
            (0.0, 24.0),
            (-30.0, 10.0),
        ];
        let (mut x, mut y) = (vec![0.0; n], vec![0.0; n]);
        for i in (seed % 11..n).step_by(11) {
            (x[i], y[i]) = lone[(i / 11) % lone.len()];
        }
        TileGrid {
            columns,
            rows,
            size: 8,
            x,
            y,
        }
    }

    /// The `dilate` twin against the CPU's, on noise grids with stress vectors and on the
    /// chain reconstruct runs (tile_max of a velocity field, the 2014 half-spread).
    ///
    /// Tolerance: exact. dilate selects, per tile, one of the grid's vectors by the reach
    /// test and |M|²; |M|², the spans and the line's normal come from the CPU's own
    /// `Source::new` (the host computes them), and |M|² is compared by bits. What remains on
    /// the GPU is n·(dx, dy) against √2, two products and a sum: a driver may fuse one product
    /// into an fma, which changes the sum only where a product is inexact and only by a
    /// rounding. So a tile may differ only where some source holding the GPU's or the CPU's
    /// vector has |n·d| within 10⁻⁶ of √2 from that tile with an inexact product (checked
    /// here: never for diagonal or axis-aligned motion one tile over, whose products are
    /// exact and whose test meets √2 exactly), and at most 1 % of tiles; every other tile must
    /// be the CPU's, bit for bit. Measured on lavapipe: none differ.
    #[test]
    fn dilate_matches_the_cpu_exactly_on_generated_and_stress_grids() {
        let Some(gpu) = gpu() else { return };
        use shutter::motion::dilate::{dilate, Source, REACH};
        use shutter::motion::reconstruct::{spread_2014, ReconstructConfig, ReconstructParams};
        let mut grids = Vec::new();
        for (k, &(columns, rows)) in [(1, 1), (3, 1), (17, 9), (40, 33), (70, 12)]
            .iter()
            .enumerate()
        {
            grids.push(dilate_grid(columns, rows, 50 + k as u32));
            grids.push(sparse_grid(columns, rows, k));
        }
        // The chain of reconstruct's 2014 variants on a velocity field with the stress vectors
        // through the numeric policy.
        let params = ReconstructParams::default();
        for (k, &(w, h)) in [(130, 66), (203, 97)].iter().enumerate() {
            let (mut vx, mut vy) = velocity_frame(w, h, 60 + k as u32, 300.0);
            for v in vx.iter_mut().chain(vy.iter_mut()) {
                *v = shutter::numeric::velocity(*v);
            }
            let config = ReconstructConfig::new(w, h, &params, 0.5, 1);
            let mut grid = tile_max(&vx, &vy, w, h, config.tile as usize);
            for t in 0..grid.x.len() {
                (grid.x[t], grid.y[t]) = spread_2014(grid.x[t], grid.y[t], &config);
            }
            grids.push(grid);
        }
        let (mut tiles, mut ties) = (0, 0);
        for grid in &grids {
            let cpu = dilate(grid);
            let got = gpu.try_dilate(grid).expect("the GPU stage runs");
            let size = grid.size as f32;
            let mut tiles_differing = differing(&got.x, &cpu.x);
            tiles_differing.extend(differing(&got.y, &cpu.y));
            tiles_differing.sort_unstable();
            tiles_differing.dedup();
            for &t in &tiles_differing {
                let (c, r) = ((t % grid.columns) as isize, (t / grid.columns) as isize);
                let (g, want) = (at(&got, t), at(&cpu, t));
                let bits = |v: (f32, f32)| (v.0.to_bits(), v.1.to_bits());
                let on_threshold = (0..grid.x.len()).any(|s| {
                    let m = at(grid, s);
                    if bits(m) != bits(g) && bits(m) != bits(want) {
                        return false;
                    }
                    let source = Source::new(m, size);
                    let (sc, sr) = ((s % grid.columns) as isize, (s / grid.columns) as isize);
                    let (dx, dy) = ((c - sc) as f64, (r - sr) as f64);
                    let (px, py) = (source.nx as f64 * dx, source.ny as f64 * dy);
                    // An fma changes the sum only when a product is inexact in f32.
                    let inexact = |p: f64| p as f32 as f64 != p;
                    let dot = (px + py).abs();
                    (inexact(px) || inexact(py)) && (dot - REACH as f64).abs() < 1e-6
                });
                assert!(
                    on_threshold,
                    "dilate {}x{}: tile ({c}, {r}): GPU {g:?}, CPU {want:?}",
                    grid.columns, grid.rows
                );
                ties += 1;
            }
            tiles += cpu.x.len();
            // The dilation did something: some tile took a vector not its own.
            if grid.columns * grid.rows > 100 {
                assert!(differing(&cpu.x, &grid.x).len() > 10);
            }
        }
        let _ = writeln!(
            std::io::stderr(),
            "gpu: dilate: {ties} tiles on the reach threshold of {tiles}, the rest bit for bit"
        );
        assert!(ties * 100 <= tiles, "{ties} of {tiles} tiles");
    }

    /// Reconstruct's tile stages at 1920×1080 with its defaults (the 2014 variants' tiles of
    /// 8 px, k 128), printed (benchmarks measure, tests assert).
    #[test]
    fn motion_tile_stages_at_1080p_print_their_time() {
        let Some(gpu) = gpu() else { return };
        use shutter::motion::dilate::dilate;
        let (w, h) = (1920, 1080);
        let (vx, vy) = velocity_frame(w, h, 3, 250.0);
        let mut grid = None;
        let gpu_tile_max = milliseconds(&mut || grid = Some(gpu.tile_max(&vx, &vy, w, h, 8)));
        let cpu_tile_max = milliseconds(&mut || drop(tile_max(&vx, &vy, w, h, 8)));
        let mut grid = grid.unwrap();
        for v in grid.x.iter_mut().chain(grid.y.iter_mut()) {
            *v = shutter::numeric::velocity(*v).clamp(-128.0, 128.0);
        }
        let mut dilated = None;
        let gpu_dilate = milliseconds(&mut || dilated = Some(gpu.dilate(&grid)));
        let cpu_dilate = milliseconds(&mut || drop(dilate(&grid)));
        let mut neighbors = None;
        let gpu_neighbor_max = milliseconds(&mut || neighbors = Some(gpu.neighbor_max(&grid)));
        let cpu_neighbor_max = milliseconds(&mut || drop(neighbor_max(&grid)));
        let _ = writeln!(
            std::io::stderr(),
            "gpu: 1920x1080 upload+dispatch+readback (cpu): tile_max {gpu_tile_max:.2} ms \
             ({cpu_tile_max:.2}), dilate {gpu_dilate:.2} ms ({cpu_dilate:.2}), neighbor_max \
             {gpu_neighbor_max:.2} ms ({cpu_neighbor_max:.2})"
        );
        assert_eq!(dilated.unwrap(), dilate(&grid));
        assert_eq!(neighbors.unwrap(), neighbor_max(&grid));
    }

    /// Reconstruct with its tile stages on the GPU and its gather on the CPU gives the CPU's
    /// bits: the tile stages are exact (above), so routing them through the GPU cannot change
    /// the output. Every variant: paper and dual take neighbor_max, 2014 and exposure take
    /// dilate. (The gather's own twin differs by rounding: tests/gpu_reconstruct.rs.)
    #[test]
    fn reconstruct_with_its_tile_stages_on_the_gpu_gives_the_cpu_s_bits() {
        let Some(gpu) = gpu() else { return };
        use shutter::motion::reconstruct::{reconstruct, reconstruct_with};
        use shutter::motion::{ReconstructParams, Variant};
        let (w, h) = (83, 47);
        let mut frame = noise_frame(w, h, 40);
        let n = w * h;
        frame.velocity = Some(shutter::frame::Velocity {
            x: noise(n, 50, -30.0, 30.0),
            y: noise(n, 51, -12.0, 12.0),
        });
        for &(name, variant) in Variant::ALL {
            let params = ReconstructParams {
                variant,
                max_blur: 24,
                ..ReconstructParams::default()
            };
            let cpu = reconstruct(frame.clone(), &params, 0.5, 3).color.unwrap();
            let got = reconstruct_with(frame.clone(), &params, 0.5, 3, gpu, |c, inputs, color| {
                inputs.gather(c, color)
            })
            .color
            .unwrap();
            for (got, cpu) in [(&got.r, &cpu.r), (&got.g, &cpu.g), (&got.b, &cpu.b)] {
                assert!(differing(got, cpu).is_empty(), "{name}");
            }
        }
        assert_eq!(gpu.stages_on_cpu(), 0);
    }

    /// A frame too large for the device's storage bindings (here made so by lowering the
    /// limit to 4 KiB with SHUTTER_GPU_MAX_BINDING) runs those stages on the CPU: the CPU's
    /// bytes, counted in the summary and said in a warning with the reason.
    #[test]
    fn a_frame_over_the_device_s_limits_runs_on_the_cpu_and_says_so() {
        let Some(_gpu) = gpu() else { return };
        let (dir, color, depth) = layers();
        let mut bytes = Vec::new();
        for (backend, limit) in [("cpu", None), ("wgpu", Some("4096"))] {
            let out = s(&dir.path().join(format!("{backend}.####.exr")));
            let mut args = dof_args(&color, &depth, &out);
            args.extend(["--backend", backend]);
            let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_shutter"));
            command.args(&args);
            if let Some(limit) = limit {
                command.env("SHUTTER_GPU_MAX_BINDING", limit);
            }
            let o = command.output().unwrap();
            assert!(o.status.success(), "{}", stderr(&o));
            let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
            if backend == "wgpu" {
                assert!(
                    json["backend"]["stages_on_cpu"].as_u64().unwrap() >= 1,
                    "{json}"
                );
                let warnings = json["warnings"].to_string();
                assert!(
                    warnings.contains("fell back to the CPU") && warnings.contains("exceeds"),
                    "{json}"
                );
            }
            bytes.push(std::fs::read(dir.path().join(format!("{backend}.0001.exr"))).unwrap());
        }
        assert!(
            bytes[0] == bytes[1],
            "the fallback wrote other bytes than the CPU"
        );
    }

    /// `auto` never takes a software driver: with only lavapipe it runs on the CPU.
    #[test]
    fn auto_never_takes_a_software_driver() {
        let Some(gpu) = gpu() else { return };
        let (dir, color, depth) = layers();
        let out = s(&dir.path().join("o.####.exr"));
        let mut args = dof_args(&color, &depth, &out);
        args.extend(["--backend", "auto"]);
        let o = shutter(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let json: serde_json::Value = serde_json::from_str(&stdout(&o)).unwrap();
        // The best adapter is a software one only when there is no hardware one.
        if gpu.is_software() {
            assert_eq!(json["backend"]["used"], "cpu", "{json}");
            assert!(json["backend"]["fallback"].is_string(), "{json}");
        } else {
            assert_eq!(json["backend"]["used"], "wgpu", "{json}");
        }
    }
}
