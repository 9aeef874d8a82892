//! Preflight: every input of every frame checked from its headers before anything is decoded
//! or written (files, channels, sizes, compression, layout, and outputs that would overwrite
//! an input); every problem found is returned, each naming its file and frame.

use std::path::Path;

use rayon::prelude::*;

use crate::error::{Error, Problem, ProblemKind, Result};
use crate::io::sequence::PathPattern;

use super::plan::{plan_frame, FramePlan, PlanOptions};
use super::Inputs;

/// True when two paths name the same file (or would, once the output exists).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => {
            let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
            absolute(a) == absolute(b)
        }
    }
}

/// Plans every frame of `frames` and checks that no output would overwrite an input; returns
/// the plans, or all the problems found.
pub fn preflight(
    inputs: &Inputs,
    output: &PathPattern,
    frames: &[Option<i64>],
    options: &PlanOptions,
) -> Result<Vec<FramePlan>> {
    let results: Vec<std::result::Result<FramePlan, Vec<Problem>>> = frames
        .par_iter()
        .map(|&frame| {
            let mut plan = plan_frame(inputs, frame, options);
            let output = output.path(frame);
            let clash = inputs
                .all()
                .into_iter()
                .map(|(_, p)| p.path(frame))
                .find(|input| same_file(input, &output));
            if let Some(input) = clash {
                let problem = Problem::new(
                    ProblemKind::Output,
                    &output,
                    format!(
                        "the output would overwrite the input {}; choose another -o",
                        input.display()
                    ),
                )
                .frame(frame);
                plan = match plan {
                    Ok(_) => Err(vec![problem]),
                    Err(mut problems) => {
                        problems.push(problem);
                        Err(problems)
                    }
                };
            }
            plan
        })
        .collect();
    let mut plans = Vec::with_capacity(results.len());
    let mut problems = Vec::new();
    for result in results {
        match result {
            Ok(plan) => plans.push(plan),
            Err(found) => problems.extend(found),
        }
    }
    if problems.is_empty() {
        Ok(plans)
    } else {
        Err(Error::Files(problems))
    }
}
