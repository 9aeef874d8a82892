//! The vector check `blur` runs on the frames it reads (issue 32, point 2): the stored
//! vectors of one frame are fitted against the motion measured between its colour and its
//! neighbours' ([`super::fit`], as `shutter vectors` does), and the reading the preset
//! states is scored as it is. When another reading fits clearly closer (the preset's
//! residual over 1.5 times the best's plus a quarter pixel; residuals are truncated at a
//! pixel a point, so a wrong reading scores up to 1) the check gives a warning naming both.
//! It says the reading fits only where the fit chose one (the frame tells readings apart)
//! and both axes moved toward the neighbour the reading looks to; otherwise the frame says
//! nothing and the next is tried, three at most.
//!
//! It costs the run no read of its own: it takes the colour of frames the pipeline decodes
//! anyway (the luma of those it needs) and a copy of the stored vectors of each frame it
//! fits, before the preset's reading converts them. The frames fitted are those whose two
//! neighbours are read just before and after them. Only a job with no such frame (a farm
//! chunk of one or two frames) reads from disk, for one frame, the neighbour the preset's
//! reading looks toward (colour alone, with the run's layer and view: one read), unless it
//! is a chunk of two consecutive frames where the run reads that neighbour itself. Against
//! one side, a reading is judged for its axes, signs and scale, not for its direction in
//! time.

use std::collections::VecDeque;

use crate::frame::{Color, Frame};
use crate::io::preset::{Encoding, VectorSpec};
use crate::io::sequence::PathPattern;

use serde::Serialize;

use super::fit::{fit, Fit, FitInput, Reading};
use super::plan::{plan_frame, PlanOptions};
use super::read::{read_frame, StoredVectors};

/// Frames fitted at most before the check gives up (each a fit: ~10–40 ms at 1080p).
const TRIES: usize = 3;

/// Points the check samples at most: a quarter of `shutter vectors`'s, enough to tell a
/// clearly wrong reading (on the Cycles render at 1080p, ~1000 points followed; see
/// BENCHMARKS.md, "The vector check").
const CHECK_POINTS: usize = 1024;

/// Linear luma of a colour, non-finite values as 0.
pub fn luma(c: &Color) -> Vec<f32> {
    c.r.iter()
        .zip(&c.g)
        .zip(&c.b)
        .map(|((r, g), b)| 0.2126 * r + 0.7152 * g + 0.0722 * b)
        .map(|v| if v.is_finite() { v } else { 0.0 })
        .collect()
}

/// One frame's luma.
struct Luma {
    frame: i64,
    plane: Vec<f32>,
    size: (usize, usize),
}

/// The frame being fitted, waiting for its next neighbour.
struct Pending {
    current: Luma,
    prev: Option<Vec<f32>>,
    stored: StoredVectors,
}

/// What the check did, for `--json` (`vector_check`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct CheckReport {
    /// Seconds it took (within the read stage's).
    pub seconds: f64,
    /// The frames it fitted, in order.
    pub frames: Vec<i64>,
    /// `fits` (the preset's reading fits as well as any other), `warned` (another fits
    /// clearly better: the run's warning says which), or `nothing to judge` (no frame fitted
    /// had motion on both axes, detail to measure it, and a neighbour in the direction the
    /// reading looks).
    pub outcome: &'static str,
}

/// The check's state across the frames of one run, fed by the read stage in read order.
pub struct VectorCheck<'a> {
    color: &'a PathPattern,
    /// How the run plans its frames (its layer and view), for a neighbour read from disk.
    options: PlanOptions<'a>,
    /// The frames the run reads, in order.
    order: Vec<Option<i64>>,
    /// Indices into `order` of the frames to fit, in turn.
    candidates: VecDeque<usize>,
    /// Neighbours that are not read by the run come from disk (a job with no frame whose
    /// neighbours it reads).
    from_disk: bool,
    last: Option<Luma>,
    pending: Option<Pending>,
    report: CheckReport,
}

/// What one fit concluded.
enum Verdict {
    /// Another reading fits clearly better: the warning.
    Warn(String),
    /// The preset's reading fits as well as any.
    Fine,
    /// Nothing to judge by: no motion, no detail, an axis that never moves, no neighbour in
    /// the stated direction.
    Silent,
}

impl<'a> VectorCheck<'a> {
    /// The check of a run reading `order` (the frames in read order) from `color` as
    /// `options` plans them, or `None` when there is nothing to check: a still, or motion
    /// the run does not read.
    pub fn new(
        color: &'a PathPattern,
        options: &PlanOptions<'a>,
        order: &[Option<i64>],
    ) -> Option<Self> {
        if !Self::applies(color, options.needs) {
            return None;
        }
        let at = |i: usize| order.get(i).copied().flatten();
        let mut candidates: VecDeque<usize> = (1..order.len())
            .filter(|&i| {
                let f = at(i);
                f.is_some() && at(i - 1) == f.map(|f| f - 1) && at(i + 1) == f.map(|f| f + 1)
            })
            .take(TRIES)
            .collect();
        let from_disk = candidates.is_empty();
        if from_disk {
            let first = at(0)?;
            candidates.push_back(0);
            // Two consecutive frames: the second is fitted against the first where the
            // reading looks back (decided when the first is read).
            if at(1) == Some(first + 1) {
                candidates.push_back(1);
            }
        }
        Some(VectorCheck {
            color,
            options: PlanOptions {
                needs: crate::frame::Passes::COLOR,
                ..options.clone()
            },
            order: order.to_vec(),
            candidates,
            from_disk,
            last: None,
            pending: None,
            report: CheckReport {
                outcome: "nothing to judge",
                ..CheckReport::default()
            },
        })
    }

    /// Whether a run reading `needs` from `color` has anything to check: motion, in a
    /// sequence.
    pub fn applies(color: &PathPattern, needs: crate::frame::Passes) -> bool {
        (needs.velocity || needs.prev || needs.next) && color.is_sequence()
    }

    /// Whether the check is over (it holds nothing then).
    pub fn done(&self) -> bool {
        self.candidates.is_empty() && self.pending.is_none()
    }

    /// What it did.
    pub fn report(&self) -> CheckReport {
        self.report.clone()
    }

    /// Whether the read of the frame at `index` of the order should keep its stored vectors.
    pub fn keeps(&self, index: usize) -> bool {
        self.candidates.front() == Some(&index)
    }

    /// The memory the check holds at most, in bytes: eight planes of a frame (the pending
    /// frame's luma, its previous neighbour's and its stored vectors; the frame being read's
    /// luma and the next candidate's stored vectors; the fit's pyramids), or, reading a
    /// neighbour from disk, its colour instead of a frame's worth of them.
    pub fn memory(width: usize, height: usize) -> u64 {
        8 * (width as u64).saturating_mul(height as u64) * 4
    }

    /// Takes the frame at `index` of the order, as read (after the numeric policy), with its
    /// stored vectors when [`keeps`](Self::keeps) asked for them; returns the warning when a
    /// fit finds one.
    pub fn offer(
        &mut self,
        index: usize,
        frame: &Frame,
        stored: Option<StoredVectors>,
    ) -> Option<String> {
        let warning = self.take(index, frame, stored);
        if self.done() {
            self.last = None;
        }
        warning
    }

    fn take(
        &mut self,
        index: usize,
        frame: &Frame,
        stored: Option<StoredVectors>,
    ) -> Option<String> {
        if self.done() {
            return None;
        }
        let number = self.order.get(index).copied().flatten();
        let candidate = self.candidates.front() == Some(&index);
        // A frame's luma serves only the frame pending, a candidate, or the one before it.
        let wanted =
            self.pending.is_some() || candidate || self.candidates.front() == Some(&(index + 1));
        let (Some(number), Some(color), true) = (number, &frame.color, wanted) else {
            self.last = None;
            return None;
        };
        let here = Luma {
            frame: number,
            plane: luma(color),
            size: (frame.width, frame.height),
        };
        if let Some(pending) = self.pending.take() {
            if pending.current.frame + 1 == number {
                if let Some(warning) = self.conclude(pending, Some(&here)) {
                    return Some(warning);
                }
            }
        }
        if self.candidates.front() != Some(&index) {
            self.last = Some(here);
            return None;
        }
        self.candidates.pop_front();
        let Some(stored) = stored else {
            self.last = Some(here);
            return None;
        };
        // Codes (RE:Vision's) are not a reading the fit states: nothing to check, at all.
        if stored.spec.encoding != Encoding::Plain {
            self.candidates.clear();
            return None;
        }
        let size = here.size;
        let backward = stored.spec.meaning.is_backward();
        let prev = match self.last.take() {
            Some(l) if l.frame + 1 == number && l.size == size => Some(l.plane),
            _ => None,
        };
        let next_read = self.order.get(index + 1).copied().flatten() == Some(number + 1);
        // A chunk of two frames and a reading that looks back: its second frame is fitted
        // against this one, with no read of its own.
        if self.from_disk && backward && prev.is_none() && next_read && !self.candidates.is_empty()
        {
            self.last = Some(here);
            return None;
        }
        // Without the run's neighbour, the one the preset's reading looks toward is read
        // from disk (one read: the reading is judged against that side).
        let prev = match prev {
            None if self.from_disk && backward => self.disk(number - 1, size),
            prev => prev,
        };
        let pending = Pending {
            current: here,
            prev,
            stored,
        };
        if next_read {
            self.pending = Some(pending);
            return None;
        }
        let next = (self.from_disk && !backward)
            .then(|| self.disk(number + 1, size))
            .flatten()
            .map(|plane| Luma {
                frame: number + 1,
                plane,
                size,
            });
        self.conclude(pending, next.as_ref())
    }

    /// A neighbour's luma read from disk (colour alone, of the run's layer and view), where
    /// it exists at this size.
    fn disk(&self, frame: i64, size: (usize, usize)) -> Option<Vec<f32>> {
        if !self.color.path(Some(frame)).is_file() {
            return None;
        }
        let inputs = super::Inputs::color_only(self.color.clone());
        let plan = plan_frame(&inputs, Some(frame), &self.options).ok()?;
        let read = read_frame(&plan).ok()?;
        if (read.width, read.height) != size {
            return None;
        }
        read.color.as_ref().map(luma)
    }

    /// Fits the pending frame with its next neighbour; keeps its luma as the last frame's.
    fn conclude(&mut self, pending: Pending, next: Option<&Luma>) -> Option<String> {
        let Pending {
            current,
            prev,
            stored,
        } = pending;
        let next = next.filter(|n| n.size == current.size);
        let frame = current.frame;
        let against = match (prev.is_some(), next.is_some()) {
            (true, true) => format!("frames {} and {}", frame - 1, frame + 1),
            (true, false) => format!("frame {}", frame - 1),
            _ => format!("frame {}", frame + 1),
        };
        let verdict = judge(
            &current,
            prev.as_deref(),
            next.map(|n| &n.plane[..]),
            &stored,
        );
        if verdict.is_some() {
            self.report.frames.push(frame);
        }
        let verdict = verdict.unwrap_or(Verdict::Silent);
        self.last = Some(current);
        match verdict {
            Verdict::Warn(text) => {
                self.report.outcome = "warned";
                self.candidates.clear();
                Some(format!(
                    "the vectors fit another reading better than the preset's, measured on \
                     frame {frame} against {against}: {text}; check with shutter vectors, or \
                     --check-vectors off"
                ))
            }
            Verdict::Fine => {
                self.report.outcome = "fits";
                self.candidates.clear();
                None
            }
            Verdict::Silent => None,
        }
    }
}

/// The preset's reading as it is stated (its own scale and zero).
fn stated(spec: &VectorSpec) -> Reading {
    Reading {
        meaning: spec.meaning,
        swap: false,
        y_up: spec.y_up,
        zero: spec.zero,
        scale: spec.scale,
        units: spec.units,
        residual: 0.0,
        motion: 0.0,
        fitted_scale: [0.0; 2],
        consistent: true,
    }
}

/// The fit of one frame and what it says of the preset's reading; `None` where no fit ran
/// (no neighbour, or codes no reading states).
fn judge(
    current: &Luma,
    prev: Option<&[f32]>,
    next: Option<&[f32]>,
    stored: &StoredVectors,
) -> Option<Verdict> {
    if stored.spec.encoding != Encoding::Plain || (prev.is_none() && next.is_none()) {
        return None;
    }
    Some(judge_fit(current, prev, next, stored))
}

fn judge_fit(
    current: &Luma,
    prev: Option<&[f32]>,
    next: Option<&[f32]>,
    stored: &StoredVectors,
) -> Verdict {
    let (width, height) = current.size;
    let [x, y] = &stored.planes;
    let result: Fit = fit(&FitInput {
        width,
        height,
        current: &current.plane,
        prev,
        next,
        stored: [x, y],
        max_points: CHECK_POINTS,
    });
    // The best reading that moves the points: one that moves them less is no motion, which
    // `shutter vectors` would not choose either.
    let Some(best) = result.readings.iter().find(|r| !r.is_still()) else {
        return Verdict::Silent;
    };
    let stated = stated(&stored.spec);
    let (Some(own), Some(motion)) = (
        result.residual_of(&stated),
        result.motion_toward(!stated.meaning.is_backward()),
    ) else {
        return Verdict::Silent;
    };
    // No motion toward the neighbour the reading looks to (a still frame beside one that
    // moves): nothing to judge it by.
    if motion[0].hypot(motion[1]) < 0.5 {
        return Verdict::Silent;
    }
    if own > 1.5 * best.residual + 0.25 {
        return Verdict::Warn(format!(
            "{} ({:.2} px) against the preset's {} ({:.2} px; no motion {:.2} px)",
            super::fit::describe(best),
            best.residual,
            super::fit::describe(&stated),
            own,
            result.no_motion
        ));
    }
    // "Fits" only where the frame tells readings apart (the fit chose one: `shutter
    // vectors` would not answer undecided), with motion on both axes: an axis that does not
    // move hides that axis's errors (a pan says nothing of y), and where every reading fits
    // alike (a still background and moving parts not followed, as on `orbit`) a wrong one
    // fits too. Otherwise another frame may tell.
    if result.chosen.is_some() && motion[0] >= 0.25 && motion[1] >= 0.25 {
        Verdict::Fine
    } else {
        Verdict::Silent
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Passes;
    use crate::io::preset::Preset;

    fn order(frames: &[i64]) -> Vec<Option<i64>> {
        frames.iter().copied().map(Some).collect()
    }

    fn options(preset: &Preset, needs: Passes) -> PlanOptions<'_> {
        PlanOptions {
            preset,
            layer: None,
            view: None,
            needs,
            max_pixels: crate::io::file::DEFAULT_MAX_PIXELS,
        }
    }

    fn check(frames: &[i64]) -> Option<(Vec<usize>, bool)> {
        let pattern = PathPattern::parse("/nowhere/c.####.exr").unwrap();
        let preset = Preset::load(&[]).unwrap();
        let needs = Passes {
            velocity: true,
            ..Passes::COLOR
        };
        VectorCheck::new(&pattern, &options(&preset, needs), &order(frames))
            .map(|c| (c.candidates.iter().copied().collect(), c.from_disk))
    }

    /// The frames fitted are the first three whose neighbours the run reads just before and
    /// after them; a job with none fits its first frame (and, of two consecutive frames, the
    /// second: which, the reading's direction decides) against a neighbour from disk.
    #[test]
    fn fits_frames_whose_neighbours_are_read_around_them() {
        assert_eq!(check(&[1, 2, 3, 4, 5, 6]), Some((vec![1, 2, 3], false)));
        assert_eq!(check(&[1, 2, 4, 5, 6]), Some((vec![3], false)));
        assert_eq!(check(&[7]), Some((vec![0], true)));
        assert_eq!(check(&[7, 8]), Some((vec![0, 1], true)));
        assert_eq!(check(&[1, 3, 5]), Some((vec![0], true)));
        let pattern = PathPattern::parse("/nowhere/c.####.exr").unwrap();
        let preset = Preset::load(&[]).unwrap();
        let still = options(&preset, Passes::COLOR);
        assert!(VectorCheck::new(&pattern, &still, &order(&[1, 2, 3])).is_none());
    }
}
