//! What a bench run is asked for ([`BenchOptions`]): the scenes and their size, the
//! references' samples, the timed runs, the shutter offset, the binary timed end to end and
//! the peers' outputs scored beside ours.

use std::path::PathBuf;

/// What to run.
#[derive(Clone, Debug)]
pub struct BenchOptions {
    pub scenes: Vec<String>,
    pub width: usize,
    pub height: usize,
    pub out: PathBuf,
    /// Reference samples per pixel.
    pub samples: usize,
    /// Timed runs per measurement (the median is kept); at least 5.
    pub runs: usize,
    /// The shutter offset of the references and of every setting run against them
    /// (`motion::Shutter::offset`; 0 centred).
    pub shutter_offset: f32,
    /// The shutter binary for the end-to-end runs.
    pub binary: PathBuf,
    /// A folder with a peers.json ([`super::peers`]) whose outputs are scored too.
    pub peers: Option<PathBuf>,
    /// Each CPU setting run on the scenes' view layers too, as a stack and as a hand-made
    /// merge ([`super::layers`]).
    pub layers: bool,
}
