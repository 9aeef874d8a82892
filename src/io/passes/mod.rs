//! From pass files to a canonical [`Frame`]: which channels of which file each pass reads
//! (planned from headers, so preflight can check every frame before anything is decoded),
//! then the decode and the conversion from the preset's convention to the canonical one.
//!
//! Motion can come from any of the three motion sections of a preset (velocity, prev, next),
//! whatever each stores; a needed pass is taken from its own section first, then from the
//! others, converting between them:
//!
//! | needed   | from a backward source (`p(-1)`) | from a forward source (`p(+1)`)      |
//! |----------|----------------------------------|--------------------------------------|
//! | velocity | `p0 - p(-1)`                     | `p(+1) - p0` (linear, warned)        |
//! | prev     | `p(-1)`                          | `2·p0 - p(+1)` (linear, warned)      |
//! | next     | `2·p0 - p(-1)` (linear, warned)  | `p(+1)`                              |
//!
//! - [`plan`]: which channels of which files, from headers alone (preflight plans every
//!   frame before anything is decoded);
//! - [`preflight`]: every frame planned, and outputs checked against inputs, before anything
//!   is read or written;
//! - [`read`]: the decode, colour and depth conversions;
//! - [`convert`]: motion from any of the preset's motion sections to the pass needed;
//! - [`suggest`]: the preset a file most likely needs, and why (`shutter info`), from the
//!   passes a preset finds in a file ([`found`]);
//! - [`memory`]: what a frame costs in memory, from its plan;
//! - [`validity`]: vectors marked invalid (by the vector file's alpha) take the motion of
//!   the nearest valid one.

mod carried;
mod check;
mod convert;
mod fit;
mod found;
mod grey_map;
mod memory;
mod missing;
mod parts;
mod plan;
mod preflight;
mod read;
mod suggest;
mod validity;
mod window;

pub use carried::stack_problem;
pub use check::{luma, CheckReport, VectorCheck};
pub use fit::{
    describe as describe_reading, fit, Fit, FitInput, Reading, FIT_POINTS, TRUNCATE as FIT_TRUNCATE,
};
pub use found::pass_layers;
pub use memory::BASE as BASE_MEMORY;
pub use plan::{plan_frame, FramePlan, PlanOptions};
pub use preflight::{in_the_way, output_folder_problems, outputs_over_inputs, preflight};
pub use read::{
    plan_color, plan_color_in, read_color, read_frame, read_frame_keeping, read_frame_noted,
    StoredVectors,
};
pub use suggest::{
    other_ways_to_depth, other_ways_to_motion, passes_found, suggest, Candidate, Found, Suggestion,
};

use crate::io::sequence::PathPattern;

/// The pass files given by the user (patterns or plain paths).
#[derive(Clone, Debug)]
pub struct Inputs {
    pub color: PathPattern,
    pub depth: Option<PathPattern>,
    pub velocity: Option<PathPattern>,
    pub prev: Option<PathPattern>,
    pub next: Option<PathPattern>,
}

impl Inputs {
    /// Colour only (other passes, if any, are looked up in the colour file).
    pub fn color_only(color: PathPattern) -> Inputs {
        Inputs {
            color,
            depth: None,
            velocity: None,
            prev: None,
            next: None,
        }
    }

    /// Every pattern given, with the pass it was given for.
    pub fn all(&self) -> Vec<(&'static str, &PathPattern)> {
        let mut all = vec![("color", &self.color)];
        for (name, pattern) in [
            ("depth", &self.depth),
            ("velocity", &self.velocity),
            ("prev", &self.prev),
            ("next", &self.next),
        ] {
            if let Some(pattern) = pattern {
                all.push((name, pattern));
            }
        }
        all
    }

    pub fn is_sequence(&self) -> bool {
        self.all().iter().any(|(_, p)| p.is_sequence())
    }
}

/// The first pair of channels of `info` that a motion section's alternatives name
/// (`{layer}` substituted with each view layer found), skipping the colour's channels when the
/// vectors share the colour's file: what `shutter vectors` fits.
pub fn vector_channels(
    info: &crate::io::file::FileInfo,
    preset: &crate::io::preset::Preset,
    section: &crate::io::preset::VectorSpec,
    shared: bool,
) -> Option<[usize; 2]> {
    let skip: Vec<usize> = if shared {
        plan::find_channels(info, &preset.color.channels, 3, &[], None)
            .ok()
            .flatten()
            .map(|found| found.into_iter().flatten().collect())
            .unwrap_or_default()
    } else {
        Vec::new()
    };
    let found = plan::find_channels(info, &section.channels, 2, &skip, None)
        .ok()
        .flatten()?;
    Some([
        found.first().copied().flatten()?,
        found.get(1).copied().flatten()?,
    ])
}
