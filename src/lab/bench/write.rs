//! The files a bench run writes from its report: bench.json, bench.md
//! ([`markdown`](super::report::markdown)), pareto.svg/.png and one contact sheet per target
//! (drawn by [`plot`](super::plot)).

use std::path::Path;

use super::options::BenchOptions;
use super::plot;
use super::report::{markdown, BenchReport};
use crate::error::{Error, Problem, ProblemKind, Result};
use crate::frame::Frame;

pub(super) type Sheet = (String, Frame, Vec<(String, Frame)>, Frame);

fn output_problem(path: &Path, detail: String) -> Error {
    Problem::new(ProblemKind::Output, path, detail).into()
}

pub(super) fn write_text(path: &Path, text: &str) -> Result<()> {
    crate::io::output::write_atomic(path, |w| {
        use std::io::Write;
        w.write_all(text.as_bytes()).map_err(|e| e.to_string())
    })
    .map_err(|d| output_problem(path, d))
}

pub(super) fn write_outputs(
    options: &BenchOptions,
    report: &BenchReport,
    sheets: &[Sheet],
) -> Result<()> {
    let out = &options.out;
    std::fs::create_dir_all(out.join("contact")).map_err(|e| output_problem(out, e.to_string()))?;
    write_text(
        &out.join("bench.json"),
        &serde_json::to_string_pretty(report).unwrap_or_default(),
    )?;
    write_text(&out.join("bench.md"), &markdown(report))?;
    let svg = plot::pareto_svg(report);
    write_text(&out.join("pareto.svg"), &svg)?;
    let (w, h, pixels) = plot::pareto_png(report);
    plot::write_png(&out.join("pareto.png"), w, h, &pixels)?;
    for (name, sharp, outputs, reference) in sheets {
        let mut panels: Vec<(&str, &Frame)> = vec![("sharp input", sharp)];
        for (label, frame) in outputs {
            panels.push((label, frame));
        }
        panels.push(("reference", reference));
        let (w, h, pixels) = plot::contact_sheet(&panels);
        plot::write_png(
            &out.join("contact")
                .join(format!("{}.png", name.replace([' ', '+'], "-"))),
            w,
            h,
            &pixels,
        )?;
    }
    Ok(())
}
