//! Metrics against independent computations: FLIP against NVIDIA's flip-evaluator (vectors in
//! fixtures/flip/expected.json, made by scripts/flip_vectors.py).

use shutter::lab::metrics::flip_map_rgb8;

use crate::support::close;

#[test]
fn flip_matches_nvidia_flip_evaluator() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/flip");
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root.join("expected.json")).unwrap())
            .unwrap();
    let pairs = expected["pairs"].as_object().unwrap();
    assert!(pairs.len() >= 4);
    for (name, value) in pairs {
        let load = |which: &str| {
            image::open(root.join(format!("{name}_{which}.png")))
                .unwrap()
                .to_rgb8()
        };
        let (reference, test) = (load("ref"), load("test"));
        let (w, h) = reference.dimensions();
        let map = flip_map_rgb8(w as usize, h as usize, reference.as_raw(), test.as_raw());
        let mean = map.iter().map(|&v| v as f64).sum::<f64>() / map.len() as f64;
        let want = value["mean_flip"].as_f64().unwrap();
        assert!(
            close(mean, want, 1e-4),
            "{name}: ours {mean:.6}, flip-evaluator {want:.6}"
        );
    }
}
