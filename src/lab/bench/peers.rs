//! Peers: other programs' outputs on the bench's own scene files, scored in the same run by
//! the same metrics over the same region as shutter's settings.
//!
//! A peer run (`scripts/peers/run.sh`: Blender's compositor, Vector Blur and Defocus) reads
//! the scenes under `OUT/scenes/NAME/`, writes one EXR per peer setting and a `peers.json`
//! beside them:
//!
//! ```json
//! {"peers": [{"label": "blender 5.2 vector blur S32", "peer": "blender 5.2.3",
//!             "scene": "pan", "target": "pan", "output": "blender-5.2/pan/vector_blur_S32.exr",
//!             "compute_ms": 41.0, "end_to_end_ms": 120.0, "settings": {"samples": 32}}]}
//! ```
//!
//! `target` is the bench target scored against (`pan`, `layers dof`, `layers dof+motion`);
//! `output` is relative to the folder of `peers.json`; `compute_ms` and `end_to_end_ms` are
//! what the peer measured (README: what each means for Blender). `shutter bench --peers DIR`
//! adds a row per entry whose scene is benched.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Problem, ProblemKind, Result};

/// One peer output.
#[derive(Clone, Debug, Deserialize)]
pub struct Peer {
    /// The row's setting label, e.g. "blender 5.2 vector blur S32".
    pub label: String,
    /// The program and version, e.g. "blender 5.2.3".
    pub peer: String,
    /// The bench scene whose files it read.
    pub scene: String,
    /// The bench target it is scored against.
    pub target: String,
    /// The output EXR (RGB), relative to the folder of peers.json.
    pub output: PathBuf,
    /// The peer's own median time for the effect, ms.
    pub compute_ms: f64,
    /// The peer's time including reading and writing its files, ms, if it measured one.
    #[serde(default)]
    pub end_to_end_ms: Option<f64>,
    /// The settings it ran with, as the peer reports them (kept in bench.json).
    #[serde(default)]
    pub settings: serde_json::Value,
}

#[derive(Debug, Deserialize)]
struct PeerFile {
    peers: Vec<Peer>,
}

/// Reads `DIR/peers.json`; outputs become paths under `DIR`.
pub fn read(dir: &Path) -> Result<Vec<Peer>> {
    let path = dir.join("peers.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Problem::new(
            ProblemKind::MissingFile,
            &path,
            format!("cannot read the peers' list: {e} (scripts/peers/run.sh writes it)"),
        )
    })?;
    let file: PeerFile = serde_json::from_str(&text).map_err(|e| {
        Problem::new(
            ProblemKind::Corrupt,
            &path,
            format!("not a peers' list: {e}"),
        )
    })?;
    Ok(file
        .peers
        .into_iter()
        .map(|mut p| {
            p.output = dir.join(&p.output);
            p
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_peers_list_reads_with_outputs_under_its_folder() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("peers.json"),
            r#"{"peers": [{"label": "blender 5.2 vector blur S32", "peer": "blender 5.2.3",
                "scene": "pan", "target": "pan", "output": "b/pan.exr", "compute_ms": 12.5}]}"#,
        )
        .unwrap();
        let peers = read(dir.path()).unwrap();
        assert_eq!(peers.len(), 1);
        assert_eq!(peers[0].output, dir.path().join("b/pan.exr"));
        assert_eq!(peers[0].end_to_end_ms, None);
        assert!(read(&dir.path().join("missing")).is_err());
    }
}
