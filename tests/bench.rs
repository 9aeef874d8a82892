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
    let rows = report["rows"].as_array().unwrap();
    let settings = shutter::bench::sweep().len();
    assert_eq!(rows.len(), 2 * settings);
    // Static: nothing to blur, so every setting is exact; sparse: `none` misses the blur.
    assert!(rows[..settings]
        .iter()
        .all(|r| r["region"]["pixels"] == 0 && r["region"]["rmse"] == 0.0));
    assert_eq!(rows[settings]["setting"], "none");
    assert!(rows[settings]["region"]["rmse"].as_f64().unwrap() > 0.01);
    for file in ["bench.md", "pareto.svg", "pareto.png"] {
        assert!(out.join(file).metadata().unwrap().len() > 100, "{file}");
    }
    let sheet = image::open(out.join("contact/sparse.png")).unwrap();
    // sharp, each setting, reference: a grid of panels 4 px apart, each under a label strip.
    let columns = shutter::bench::plot::SHEET_COLUMNS as u32;
    let rows = (settings as u32 + 2).div_ceil(columns);
    assert_eq!(sheet.width(), columns * (64 + 4));
    assert!(sheet.height() > rows * 36 && sheet.height().is_multiple_of(rows));
    let svg = std::fs::read_to_string(out.join("pareto.svg")).unwrap();
    assert!(svg.contains("sparse") && svg.contains("RMSE"));
}
