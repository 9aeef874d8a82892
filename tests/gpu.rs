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
        use shutter::gpu::coc;
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
        assert!(found >= 1, "no .wgsl under {}", dir.display());
        // What the context compiles is the file on disk.
        assert!(coc::SHADER.contains("fn lens_coc"));
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

    /// `--backend wgpu` through the CLI gives the CPU's output within the tolerance: only
    /// the `coc` stage runs on the GPU, the rest on the CPU in the same run. Its CoC differs
    /// by at most ~1e-4 px (above), which moves a gather weight by as little; a pixel can
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
