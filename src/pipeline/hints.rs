//! What a preflight's problem of a missing pass adds, so it says every way to give the pass:
//! a painted CoC map's problems named as the user gave it (`coc-map`, read through the
//! depth pass); depth looked up in the colour file and not found, every other way to give
//! it (`suggest::other_ways_to_depth`); motion looked up there and not found, the convention
//! presets that would find vectors in the file (`suggest::other_ways_to_motion`: V-Ray's
//! `VRayVelocity.R/G` under the default preset named `--preset vray`, as `shutter info`
//! suggests).

use crate::error::ProblemKind;
use crate::io::preset::Preset;

/// `error` with its missing passes' problems named and completed (see the module doc):
/// `preset` is the run's, `coc_map` whether depth is a painted CoC map, `dof` whether the
/// run makes depth of field, `view` the view of a multi-view file being read (`None`: its
/// default), whose channels alone the other ways are looked for in.
pub fn name_pass(
    error: crate::Error,
    preset: &Preset,
    (coc_map, dof): (bool, bool),
    view: Option<&str>,
) -> crate::Error {
    let crate::Error::Files(mut problems) = error else {
        return error;
    };
    // The file as the view reads it: another view's channels are no way to give this one's.
    let probe = |path: &std::path::Path| {
        let info = crate::io::file::FileInfo::probe(path).ok()?;
        Some(info.in_view(view).unwrap_or(info))
    };
    for problem in problems.iter_mut() {
        let missing = problem.kind == ProblemKind::MissingChannel;
        match problem.pass {
            Some("depth") if coc_map => problem.pass = Some("coc-map"),
            Some("depth") if missing && problem.detail.ends_with("or give --depth FILE") => {
                if let Some(info) = probe(&problem.path) {
                    let ways = crate::io::passes::other_ways_to_depth(&info, preset, dof);
                    problem.detail.push_str(&ways);
                }
            }
            // No motion in the colour file (a --velocity file without it is another problem).
            Some("velocity" | "prev" | "next")
                if missing && problem.detail.contains("; or give --velocity FILE") =>
            {
                if let Some(info) = probe(&problem.path) {
                    let ways = crate::io::passes::other_ways_to_motion(&info, preset);
                    problem.detail.push_str(&ways);
                }
            }
            _ => {}
        }
    }
    crate::Error::Files(problems)
}
