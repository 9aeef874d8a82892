//! `shutter bench` end to end on tiny scenes.

use crate::support::*;

#[test]
fn bench_runs_end_to_end_and_writes_its_reports() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let o = shutter(&[
        "bench",
        "--scenes",
        "static,sparse",
        "--size",
        "64x36",
        "--samples",
        "16",
        "--out",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("| sparse | none |"), "{}", stdout(&o));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    let all = report["rows"].as_array().unwrap();
    let rows: Vec<&serde_json::Value> = all.iter().filter(|r| r["backend"] == "cpu").collect();
    let settings = shutter::lab::bench::sweep().len();
    assert_eq!(rows.len(), 2 * settings);
    // Static: nothing to blur, so every setting is exact; sparse: `none` misses the blur.
    assert!(rows[..settings]
        .iter()
        .all(|r| r["region"]["pixels"] == 0 && r["region"]["rmse"] == 0.0));
    assert_eq!(rows[settings]["setting"], "none");
    assert!(rows[settings]["region"]["rmse"].as_f64().unwrap() > 0.01);
    // With an adapter (CI has Mesa's software driver), every reconstruct, scatter and stretch
    // setting also runs on wgpu, in a row beside the CPU's, with its GPU stages timed apart
    // and its error within 1 % of the CPU's (the backends agree to rounding, so the errors do
    // too).
    let gpu: Vec<&serde_json::Value> = all.iter().filter(|r| r["backend"] == "wgpu").collect();
    use shutter::motion::Algorithm;
    let twins = shutter::lab::bench::sweep()
        .iter()
        .filter(|s| {
            matches!(
                s.algorithm,
                Algorithm::Reconstruct | Algorithm::Scatter | Algorithm::Stretch
            )
        })
        .count();
    if shutter::gpu::open(shutter::gpu::Backend::Wgpu).is_ok() {
        assert_eq!(gpu.len(), 2 * twins, "{all:?}");
        for row in &gpu {
            let label = row["setting"].as_str().unwrap();
            let cpu_label = label.strip_suffix(" [wgpu]").expect("labelled");
            let cpu = rows
                .iter()
                .find(|r| r["scene"] == row["scene"] && r["setting"] == cpu_label)
                .expect("a CPU row");
            let (e_gpu, e_cpu) = (
                row["region"]["rmse"].as_f64().unwrap(),
                cpu["region"]["rmse"].as_f64().unwrap(),
            );
            assert!(
                close_relative(e_gpu, e_cpu, 0.01),
                "{label}: {e_gpu} against {e_cpu}"
            );
            // stretch returns before any stage where nothing moves (the static scene), on
            // either backend.
            let idle = row["scene"] == "static" && label.starts_with("stretch");
            assert!(
                idle || row["gpu_stages"]["compute_ms"].as_f64().unwrap() > 0.0,
                "{row}"
            );
            assert_eq!(row["stages_on_cpu"], 0, "{row}");
        }
        assert!(stdout(&o).contains("GPU stages of the [wgpu] rows"));
    } else {
        assert!(gpu.is_empty());
    }
    for file in ["bench.md", "pareto.svg", "pareto.png"] {
        assert!(out.join(file).metadata().unwrap().len() > 100, "{file}");
    }
    let sheet = image::open(out.join("contact/sparse.png")).unwrap();
    // sharp, each setting, reference: a grid of panels 4 px apart, each under a label strip.
    let columns = shutter::lab::bench::plot::SHEET_COLUMNS as u32;
    let per_scene = all.iter().filter(|r| r["scene"] == "sparse").count();
    let rows = (per_scene as u32 + 2).div_ceil(columns);
    assert_eq!(sheet.width(), columns * (64 + 4));
    assert!(sheet.height() > rows * 36 && sheet.height().is_multiple_of(rows));
    let svg = std::fs::read_to_string(out.join("pareto.svg")).unwrap();
    assert!(svg.contains("sparse") && svg.contains("RMSE"));
    // The defaults, marked in bench.json and bench.md: one a motion-blur algorithm.
    let defaults: Vec<&str> = (all.iter())
        .filter(|r| r["scene"] == "sparse" && r["backend"] == "cpu" && r["default"] == true)
        .map(|r| r["setting"].as_str().unwrap())
        .collect();
    assert_eq!(
        defaults,
        [
            "reconstruct exposure S31 k128",
            "scatter exposure bezier box Δ10",
            "stretch centre extent2"
        ]
    );
    let md = std::fs::read_to_string(out.join("bench.md")).unwrap();
    assert!(md.contains("| sparse | stretch centre extent2 **(default)** |"));
    assert!(!md.contains("stretch rear extent2 **(default)**"));
}

/// Each depth-of-field method's default, and each with a motion blur after it, are the
/// defaults of a lens scene's targets; nothing else is.
#[test]
fn the_defaults_of_a_lens_scene_are_marked() {
    let lens = shutter::lab::truth::scenes::build("layers", 64, 36, 1)
        .unwrap()
        .lens;
    let defaults: Vec<String> = (shutter::lab::bench::targets("layers", lens).iter())
        .flat_map(|t| t.settings.iter().map(move |s| (t, s)))
        .filter(|(_, s)| s.is_default())
        .map(|(t, s)| format!("{}: {}", t.label, s.label))
        .collect();
    assert_eq!(
        defaults,
        [
            "layers: reconstruct exposure S31 k128",
            "layers: scatter exposure bezier box Δ10",
            "layers: stretch centre extent2",
            "layers dof: gather R6",
            "layers dof: blend",
            "layers dof+motion: scatter",
            "layers dof+motion: gather",
            "layers dof+motion: gather + scatter",
            "layers dof+motion: gather + reconstruct",
            "layers dof+motion: blend + scatter",
        ]
    );
}

/// `bench --layers`: every CPU setting gets a `[layers]` row (the stack, end to end too) and
/// a `[hand merge]` row on the scene's view layers, scored against the same reference; with
/// nothing blurred (`none`) both are FG over BG, which is the colour pass but where an FG
/// edge and a background edge share a pixel.
#[test]
fn bench_with_layers_adds_a_stack_and_a_hand_merge_row_for_every_cpu_setting() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("bench");
    let o = shutter(&[
        "bench",
        "--scenes",
        "sparse",
        "--size",
        "64x36",
        "--samples",
        "16",
        "--layers",
        "--out",
        &s(&out),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.join("scenes/sparse/layers.0001.exr").exists());
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("bench.json")).unwrap()).unwrap();
    let rows: Vec<&serde_json::Value> = (report["rows"].as_array().unwrap().iter())
        .filter(|r| r["backend"] == "cpu")
        .collect();
    let settings = shutter::lab::bench::sweep().len();
    assert_eq!(rows.len(), 3 * settings);
    let rmse = |label: &str| {
        let row = rows
            .iter()
            .find(|r| r["setting"] == label)
            .unwrap_or_else(|| panic!("{label}"));
        row["region"]["rmse"].as_f64().unwrap()
    };
    for setting in shutter::lab::bench::sweep() {
        let stack = rows
            .iter()
            .find(|r| r["setting"] == format!("{} [layers]", setting.label))
            .unwrap_or_else(|| panic!("{} [layers]", setting.label));
        assert!(stack["end_to_end_ms"].as_f64().is_some(), "{stack}");
        rmse(&format!("{} [hand merge]", setting.label));
    }
    assert_eq!(rmse("none [layers]"), rmse("none [hand merge]"));
    // And what `none [layers]` wrote is FG over BG, worked out here from the layers.
    let layers = read_exr_reference(&out.join("scenes/sparse/layers.0001.exr"));
    let written = read_exr_reference(&out.join("runs/sparse/none_[layers].0001.exr"));
    let fg_alpha = channel(&layers, "FG.Combined.A");
    for c in ["R", "G", "B"] {
        let (fg, bg) = (
            channel(&layers, &format!("FG.Combined.{c}")),
            channel(&layers, &format!("BG.Combined.{c}")),
        );
        let over: Vec<f32> = (0..fg.len())
            .map(|i| fg[i] + (1.0 - fg_alpha[i]) * bg[i])
            .collect();
        assert_close(channel(&written, c), &over, 1e-6, c);
    }
}
