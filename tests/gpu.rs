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
pub(crate) fn layers() -> (tempfile::TempDir, String, String) {
    let dir = small_scene("layers", 96, 54, 1, 4);
    let color = role_pattern(dir.path(), "color");
    let depth = role_pattern(dir.path(), "depth");
    (dir, color, depth)
}

pub(crate) fn dof_args<'a>(color: &'a str, depth: &'a str, out: &'a str) -> Vec<&'a str> {
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
    use shutter::gpu::{Gpu, Need};
    use shutter::motion::neighbor_max::neighbor_max;
    use shutter::motion::reconstruct::Stages as _;
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

    /// Where two planes differ bit for bit (−0 and +0 differ; NaN equals a NaN of the same
    /// bits).
    pub(crate) fn differing(gpu: &[f32], cpu: &[f32]) -> Vec<usize> {
        assert_eq!(gpu.len(), cpu.len());
        (0..gpu.len())
            .filter(|&i| gpu[i].to_bits() != cpu[i].to_bits())
            .collect()
    }

    /// The time of a second call of `f` (the first makes the buffers), in milliseconds.
    pub(crate) fn milliseconds(f: &mut dyn FnMut()) -> f64 {
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
    /// the GPU is n·(dx, dy) against √2, two products and a sum, and the normal's 11
    /// significant bits make both products exact, so a driver that fuses one into the sum
    /// (an fma) rounds it as the CPU does. Before the normal was cut, NVIDIA's driver (H200)
    /// fused them and 62 of these 5125 tiles, on the threshold, differed; lavapipe none.
    #[test]
    fn dilate_matches_the_cpu_exactly_on_generated_and_stress_grids() {
        let Some(gpu) = gpu() else { return };
        use shutter::motion::dilate::dilate;
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
        let mut tiles = 0;
        for grid in &grids {
            let cpu = dilate(grid);
            let got = gpu.try_dilate(grid).expect("the GPU stage runs");
            let mut tiles_differing = differing(&got.x, &cpu.x);
            tiles_differing.extend(differing(&got.y, &cpu.y));
            tiles_differing.sort_unstable();
            tiles_differing.dedup();
            if let Some(&t) = tiles_differing.first() {
                panic!(
                    "dilate {}x{}: {} tiles differ; tile ({}, {}): GPU {:?}, CPU {:?}",
                    grid.columns,
                    grid.rows,
                    tiles_differing.len(),
                    t % grid.columns,
                    t / grid.columns,
                    at(&got, t),
                    at(&cpu, t)
                );
            }
            tiles += cpu.x.len();
            // The dilation did something: some tile took a vector not its own.
            if grid.columns * grid.rows > 100 {
                assert!(differing(&cpu.x, &grid.x).len() > 10);
            }
        }
        let _ = writeln!(std::io::stderr(), "gpu: dilate: {tiles} tiles, bit for bit");
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
        use shutter::motion::reconstruct::Stages;
        /// The tile stages on the GPU, the gather on the CPU.
        struct TilesOnGpu<'a>(&'a Gpu);
        impl Stages for TilesOnGpu<'_> {
            fn tile_max(&self, vx: &[f32], vy: &[f32], w: usize, h: usize, s: usize) -> TileGrid {
                self.0.tile_max(vx, vy, w, h, s)
            }
            fn neighbor_max(&self, tiles: &TileGrid) -> TileGrid {
                self.0.neighbor_max(tiles)
            }
            fn dilate(&self, tiles: &TileGrid) -> TileGrid {
                self.0.dilate(tiles)
            }
        }
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
            let got = reconstruct_with(frame.clone(), &params, 0.5, 3, &TilesOnGpu(gpu))
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
