//! Everything between files on disk and frames in memory: EXR and integer images, pass files
//! and presets, frame sequences, and atomic output.

pub mod channels;
pub mod exr;
pub mod exr_channels;
pub mod exr_dwa;
pub mod exr_like;
pub mod exr_order;
pub mod exr_parts;
pub mod exr_unknown;
pub mod exr_zip;
pub mod file;
pub mod holes;
pub mod image;
pub mod input;
pub mod lock;
pub mod output;
pub mod output_notes;
pub mod passes;
pub mod preset;
pub mod sequence;
pub mod view;

/// What [`abandon`] cleaned up.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Abandoned {
    /// Temporary files of frames being written, removed.
    pub temporaries: usize,
    /// Output locks released.
    pub locks: usize,
}

/// Stops writing and cleans up, for a signal handler before the process exits: removes the
/// temporary files being written (later writes fail without creating anything), then
/// releases the output locks. Frames already renamed into place stay.
pub fn abandon() -> Abandoned {
    let temporaries = output::abandon_temporaries();
    let locks = lock::abandon_locks();
    Abandoned { temporaries, locks }
}
