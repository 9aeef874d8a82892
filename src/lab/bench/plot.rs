//! The bench's pictures: time-versus-error plots with the Pareto front marked (plotters, SVG
//! and PNG, text in the DejaVu Sans Mono shipped in assets/) and labelled contact sheets.

use std::path::Path;
use std::sync::Once;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use plotters::style::{register_font, FontStyle};

use super::report::BenchReport;
use crate::error::{Problem, ProblemKind, Result};
use crate::frame::Frame;
use crate::lab::metrics::{display_rgb8, Rgb};

const FONT: &[u8] = include_bytes!("../../../assets/DejaVuSansMono.ttf");
const PANEL: (u32, u32) = (420, 300);
const LABEL_HEIGHT: usize = 22;

fn ensure_font() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The font is compiled in and known good; a failure would only lose labels.
        let _ = register_font("sans-serif", FontStyle::Normal, FONT);
    });
}

/// Indices of the points not dominated by another (less time and less error), by time.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// A label's size in pixels at 11 px DejaVu Sans Mono: 0.6 em a character, one em high.
fn label_size(text: &str) -> (i32, i32) {
    ((text.chars().count() as f64 * 6.6).ceil() as i32, 11)
}

/// Where each point's label goes, in `order`: the first place around its point (right, then
/// left; above, beside, below; then the same moved up and down by one, two and three label
/// heights, drawn with a leader) whose box lies in `bounds` (x0, y0, x1, y1) and overlaps no
/// label placed before it and no point's dot; a label with no such place is left out (bench.md's
/// table has every row). Returns (the point's index, the label's top-left corner, whether it
/// needs a leader), in `order`.
fn place_labels(
    points: &[(i32, i32)],
    texts: &[&str],
    order: &[usize],
    bounds: (i32, i32, i32, i32),
) -> Vec<(usize, (i32, i32), bool)> {
    type Rect = (i32, i32, i32, i32);
    let overlap = |a: &Rect, b: &Rect| a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3;
    let dots: Vec<Rect> = points
        .iter()
        .map(|&(x, y)| (x - 4, y - 4, x + 5, y + 5))
        .collect();
    let mut placed: Vec<Rect> = Vec::new();
    let mut labels = Vec::new();
    for &i in order {
        let (x, y) = points[i];
        let (w, h) = label_size(texts[i]);
        let near = [
            (x + 6, y - 6 - h / 2),
            (x + 7, y - h / 2),
            (x + 6, y + 4),
            (x - 6 - w, y - 6 - h / 2),
            (x - 7 - w, y - h / 2),
            (x - 6 - w, y + 4),
            (x - w / 2, y - 8 - h),
            (x - w / 2, y + 8),
        ];
        let places = (0..4).flat_map(|step| {
            let d = step * (h + 2);
            near.into_iter()
                .flat_map(move |(left, top)| [(left, top - d), (left, top + d)])
                .map(move |p| (p, step > 0))
        });
        let free = places.into_iter().find(|&((left, top), _)| {
            let rect = (left, top, left + w, top + h);
            let inside =
                left >= bounds.0 && top >= bounds.1 && rect.2 <= bounds.2 && rect.3 <= bounds.3;
            inside
                && !placed.iter().any(|p| overlap(p, &rect))
                && !(dots.iter().enumerate()).any(|(j, d)| j != i && overlap(d, &rect))
        });
        if let Some(((left, top), leader)) = free {
            placed.push((left, top, left + w, top + h));
            labels.push((i, (left, top), leader));
        }
    }
    labels
}

fn draw<DB: DrawingBackend>(
    root: DrawingArea<DB, plotters::coord::Shift>,
    report: &BenchReport,
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let mut scenes: Vec<&str> = report.rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    let cols = 3.min(scenes.len().max(1));
    let rows = scenes.len().div_ceil(cols).max(1);
    let areas = root.split_evenly((rows, cols));
    for (scene, area) in scenes.iter().zip(areas) {
        let rows: Vec<_> = report.rows.iter().filter(|r| r.scene == *scene).collect();
        let points: Vec<(f64, f64)> = rows.iter().map(|r| (r.compute_ms, r.region.rmse)).collect();
        let x_max = points.iter().map(|p| p.0).fold(0.0, f64::max).max(1e-3) * 1.25;
        let y_max = points.iter().map(|p| p.1).fold(0.0, f64::max).max(1e-4) * 1.25;
        let mut chart = ChartBuilder::on(&area)
            .caption(*scene, ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(34)
            .y_label_area_size(56)
            .build_cartesian_2d(0.0..x_max, 0.0..y_max)
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .max_light_lines(1)
            .x_desc("compute ms")
            .y_desc("RMSE, changed region")
            .label_style(("sans-serif", 11))
            .draw()
            .map_err(|e| e.to_string())?;
        chart
            .draw_series((points.iter()).map(|&(x, y)| Circle::new((x, y), 4, BLUE.filled())))
            .map_err(|e| e.to_string())?;
        // Labels where they overlap no other label, point or the panel's edge, the defaults'
        // and the front's first; one with no free place is left to bench.md's table.
        let pixels: Vec<(i32, i32)> = points.iter().map(|p| chart.backend_coord(p)).collect();
        let front = pareto_front(&points);
        let mut order: Vec<usize> = (0..rows.len()).collect();
        order.sort_by_key(|&i| (!rows[i].default, !front.contains(&i)));
        let texts: Vec<&str> = rows.iter().map(|r| r.setting.as_str()).collect();
        let bounds = chart.plotting_area().get_pixel_range();
        let bounds = (bounds.0.start, bounds.1.start, bounds.0.end, bounds.1.end);
        for (i, at, leader) in place_labels(&pixels, &texts, &order, bounds) {
            // In the backend's pixels, as `backend_coord` gives them: drawn on the root. A
            // label left of its point is anchored at its right end, so that it ends where it
            // was placed in whatever font a viewer draws an SVG's text with.
            let (w, h) = label_size(texts[i]);
            let right = at.0 + w <= pixels[i].0;
            let (anchor, x) = match right {
                true => (HPos::Right, at.0 + w),
                false => (HPos::Left, at.0),
            };
            let style =
                TextStyle::from(("sans-serif", 11).into_font()).pos(Pos::new(anchor, VPos::Top));
            root.draw(&Text::new(texts[i], (x, at.1), style))
                .map_err(|e| e.to_string())?;
            if leader {
                // From the point to the middle of the label's nearer side.
                let side = if right { x + 1 } else { x - 1 };
                let line = PathElement::new(vec![pixels[i], (side, at.1 + h / 2)], BLACK.mix(0.4));
                root.draw(&line).map_err(|e| e.to_string())?;
            }
        }
        // The defaults, what a user gets: a green square around the point.
        chart
            .draw_series(points.iter().zip(&rows).filter(|(_, row)| row.default).map(
                |(&(x, y), _)| {
                    EmptyElement::at((x, y))
                        + Rectangle::new([(-7, -7), (7, 7)], GREEN.stroke_width(2))
                },
            ))
            .map_err(|e| e.to_string())?;
        let front: Vec<(f64, f64)> = pareto_front(&points).iter().map(|&i| points[i]).collect();
        chart
            .draw_series(LineSeries::new(front.clone(), RED.stroke_width(2)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(
                front
                    .iter()
                    .map(|&p| Circle::new(p, 6, RED.stroke_width(2))),
            )
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())
}

fn plot_size(report: &BenchReport) -> (u32, u32) {
    let mut scenes: Vec<&str> = report.rows.iter().map(|r| r.scene.as_str()).collect();
    scenes.dedup();
    let cols = 3.min(scenes.len().max(1)) as u32;
    let rows = scenes.len().div_ceil(cols as usize).max(1) as u32;
    (PANEL.0 * cols, PANEL.1 * rows)
}

/// The time-versus-error plot as SVG: a panel per scene, the Pareto front in red, the
/// defaults in green squares.
pub fn pareto_svg(report: &BenchReport) -> String {
    ensure_font();
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, plot_size(report)).into_drawing_area();
        let _ = draw(root, report);
    }
    svg
}

/// The same plot as RGB pixels.
pub fn pareto_png(report: &BenchReport) -> (usize, usize, Vec<u8>) {
    ensure_font();
    let (w, h) = plot_size(report);
    let mut pixels = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (w, h)).into_drawing_area();
        let _ = draw(root, report);
    }
    (w as usize, h as usize, pixels)
}

/// Panels per row of a contact sheet.
pub const SHEET_COLUMNS: usize = 5;

/// Frames in a grid, [`SHEET_COLUMNS`] to a row, each under its label, tone mapped as the
/// perceptual metrics see them.
pub fn contact_sheet(panels: &[(&str, &Frame)]) -> (usize, usize, Vec<u8>) {
    ensure_font();
    let gap = 4;
    let cell_w = panels.iter().map(|(_, f)| f.width).max().unwrap_or(0) + gap;
    let cell_h = panels.iter().map(|(_, f)| f.height).max().unwrap_or(0) + LABEL_HEIGHT + gap;
    let columns = panels.len().clamp(1, SHEET_COLUMNS);
    let rows = panels.len().div_ceil(columns).max(1);
    let (width, height) = ((columns * cell_w).max(1), rows * cell_h);
    let mut pixels = vec![32u8; width * height * 3];
    let mut labels = Vec::new();
    for (k, (label, frame)) in panels.iter().enumerate() {
        let (x0, y0) = ((k % columns) * cell_w, (k / columns) * cell_h);
        if let Some(color) = &frame.color {
            let rgb = display_rgb8(&Rgb {
                width: frame.width,
                height: frame.height,
                planes: [&color.r, &color.g, &color.b],
            });
            for j in 0..frame.height {
                let src = &rgb[j * frame.width * 3..(j + 1) * frame.width * 3];
                let start = ((y0 + j + LABEL_HEIGHT) * width + x0) * 3;
                pixels[start..start + src.len()].copy_from_slice(src);
            }
        }
        labels.push((label.to_string(), x0, y0));
    }
    {
        let root = BitMapBackend::with_buffer(&mut pixels, (width as u32, height as u32))
            .into_drawing_area();
        for (label, x, y) in labels {
            let _ = root.draw(&Text::new(
                label,
                (x as i32 + 4, y as i32 + 4),
                ("sans-serif", 14).into_font().color(&WHITE),
            ));
        }
        let _ = root.present();
    }
    (width, height, pixels)
}

/// Writes RGB pixels as a PNG, atomically.
pub fn write_png(path: &Path, width: usize, height: usize, pixels: &[u8]) -> Result<()> {
    crate::io::output::write_atomic(path, |w| {
        use image::ImageEncoder;
        image::codecs::png::PngEncoder::new(w)
            .write_image(
                pixels,
                width as u32,
                height as u32,
                image::ExtendedColorType::Rgb8,
            )
            .map_err(|e| e.to_string())
    })
    .map_err(|d| Problem::new(ProblemKind::Output, path, d).into())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pareto_front_keeps_only_undominated_points() {
        let points = [(1.0, 5.0), (2.0, 3.0), (3.0, 4.0), (4.0, 1.0), (0.5, 9.0)];
        assert_eq!(pareto_front(&points), [4, 0, 1, 3]);
    }

    #[test]
    fn labels_overlap_neither_each_other_nor_points_nor_the_edge() {
        // A cluster of six points 3 px apart, and two points alone.
        let mut points: Vec<(i32, i32)> = (0..6).map(|k| (100 + 3 * k, 100 + 2 * k)).collect();
        points.extend([(300, 40), (20, 250)]);
        let texts = [
            "reconstruct",
            "scatter",
            "stretch",
            "2012 k 4",
            "gather R6",
            "blend",
            "alone",
            "corner",
        ];
        let order: Vec<usize> = (0..points.len()).collect();
        let bounds = (10, 10, 400, 280);
        let placed = place_labels(&points, &texts, &order, bounds);
        let rect = |&(i, (x, y), _): &(usize, (i32, i32), bool)| {
            let (w, h) = label_size(texts[i]);
            (x, y, x + w, y + h)
        };
        let overlap = |a: (i32, i32, i32, i32), b: (i32, i32, i32, i32)| {
            a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3
        };
        for (n, a) in placed.iter().enumerate() {
            let r = rect(a);
            assert!(r.0 >= 10 && r.1 >= 10 && r.2 <= 400 && r.3 <= 280, "{r:?}");
            for b in &placed[n + 1..] {
                assert!(!overlap(r, rect(b)), "{a:?} {b:?}");
            }
            for (j, &(x, y)) in points.iter().enumerate() {
                assert!(
                    j == a.0 || !overlap(r, (x - 4, y - 4, x + 5, y + 5)),
                    "{a:?} on {j}"
                );
            }
        }
        // The points alone and most of the cluster get their labels.
        let labelled: Vec<usize> = placed.iter().map(|p| p.0).collect();
        assert!(
            labelled.contains(&6) && labelled.contains(&7),
            "{labelled:?}"
        );
        assert_eq!(labelled.len(), 8, "{labelled:?}");
    }
}
