//! The vector check `blur` runs on the frames it reads (issue 32, point 2): the stored
//! vectors of one frame are fitted against the motion measured between its colour and its
//! neighbours' ([`super::fit`], as `shutter vectors` does), and the reading the preset
//! states is scored as it is. When another reading fits clearly better (more than twice as
//! close, and by over a quarter pixel) the check gives a warning naming both.
//!
//! It costs the run no read of its own: it takes the colour of frames the pipeline decodes
//! anyway (their luma, while the check is undecided) and a copy of the stored vectors of the
//! frame it fits, before the preset's reading converts them. The frame fitted is the first
//! whose two neighbours are read just before and after it; a frame without motion (or
//! without detail to measure it) says nothing, and the next such frame is tried, three at
//! most. Only a job with no such frame (a farm chunk of one or two frames) reads from disk,
//! for its first frame, the neighbour the preset's reading looks toward (the previous frame
//! for backward vectors), colour alone: one read. Against one side, a reading is judged for
//! its axes, signs and scale, not for its direction in time.

use std::collections::VecDeque;

use crate::frame::{Color, Frame};
use crate::io::preset::{Encoding, Preset, VectorSpec};
use crate::io::sequence::PathPattern;

use super::fit::{fit, Fit, FitInput, Reading};
use super::read::{read_color, StoredVectors};

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

/// The check's state across the frames of one run, fed by the read stage in read order.
pub struct VectorCheck<'a> {
    color: &'a PathPattern,
    preset: &'a Preset,
    /// The frames the run reads, in order.
    order: Vec<Option<i64>>,
    /// Indices into `order` of the frames to fit, in turn.
    candidates: VecDeque<usize>,
    /// Neighbours that are not read by the run come from disk (a job with no frame whose
    /// neighbours it reads).
    from_disk: bool,
    last: Option<Luma>,
    pending: Option<Pending>,
}

/// What one fit concluded.
enum Verdict {
    /// Another reading fits clearly better: the warning.
    Warn(String),
    /// The preset's reading fits as well as any.
    Fine,
    /// Nothing to judge by: no motion, no detail, no neighbour in the stated direction.
    Silent,
}

impl<'a> VectorCheck<'a> {
    /// The check of a run reading `order` (the frames in read order) from `color`, or `None`
    /// when there is nothing to check: a still, or motion `needs` does not read.
    pub fn new(
        color: &'a PathPattern,
        preset: &'a Preset,
        order: &[Option<i64>],
        needs: crate::frame::Passes,
    ) -> Option<Self> {
        if !Self::applies(color, needs) {
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
            at(0)?;
            candidates.push_back(0);
        }
        Some(VectorCheck {
            color,
            preset,
            order: order.to_vec(),
            candidates,
            from_disk,
            last: None,
            pending: None,
        })
    }

    /// Whether a run reading `needs` from `color` has anything to check: motion, in a
    /// sequence.
    pub fn applies(color: &PathPattern, needs: crate::frame::Passes) -> bool {
        (needs.velocity || needs.prev || needs.next) && color.is_sequence()
    }

    /// Whether the check is over (it keeps nothing then).
    pub fn done(&self) -> bool {
        self.candidates.is_empty() && self.pending.is_none()
    }

    /// Whether the read of the frame at `index` of the order should keep its stored vectors.
    pub fn keeps(&self, index: usize) -> bool {
        self.candidates.front() == Some(&index)
    }

    /// The memory the check holds at most: five planes of a frame (three lumas, two stored
    /// components) and the fit's pyramids.
    pub fn memory(width: usize, height: usize) -> u64 {
        6 * (width as u64).saturating_mul(height as u64) * 4
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
        if self.done() {
            self.last = None;
            return None;
        }
        let (Some(number), Some(color)) = (self.order.get(index).copied().flatten(), &frame.color)
        else {
            return None;
        };
        let here = Luma {
            frame: number,
            plane: luma(color),
            size: (frame.width, frame.height),
        };
        let mut warning = None;
        if let Some(pending) = self.pending.take() {
            if pending.current.frame + 1 == number {
                warning = self.conclude(pending, Some(&here));
            }
        }
        if self.candidates.front() == Some(&index) {
            self.candidates.pop_front();
            if let (Some(stored), None) = (stored, &warning) {
                let size = here.size;
                let prev = match self.last.take() {
                    Some(l) if l.frame + 1 == number && l.size == size => Some(l.plane),
                    _ => None,
                };
                let next_read = self.order.get(index + 1).copied().flatten() == Some(number + 1);
                // Without the run's neighbours, the one the preset's reading looks toward
                // is read from disk (one read: the reading is judged against that side).
                let backward = stored.spec.meaning.is_backward();
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
                } else {
                    let next = (self.from_disk && !backward)
                        .then(|| self.disk(number + 1, size))
                        .flatten()
                        .map(|plane| Luma {
                            frame: number + 1,
                            plane,
                            size,
                        });
                    warning = self.conclude(pending, next.as_ref());
                }
                return warning;
            }
        }
        self.last = Some(here);
        if warning.is_some() {
            // Said once: the check is over.
            self.candidates.clear();
            self.last = None;
        }
        warning
    }

    /// A neighbour's luma read from disk (colour alone), where it exists at this size.
    fn disk(&self, frame: i64, size: (usize, usize)) -> Option<Vec<f32>> {
        if !self.color.path(Some(frame)).is_file() {
            return None;
        }
        let read = read_color(self.color, Some(frame), self.preset).ok()?;
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
        self.last = Some(current);
        match verdict {
            Verdict::Warn(text) => {
                self.candidates.clear();
                self.last = None;
                Some(format!(
                    "the vectors fit another reading better than the preset's, measured on \
                     frame {frame} against {against}: {text}; check with shutter vectors, or \
                     --check-vectors off"
                ))
            }
            Verdict::Fine => {
                self.candidates.clear();
                self.last = None;
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
        fitted_scale: [0.0; 2],
        consistent: true,
    }
}

/// The fit of one frame and what it says of the preset's reading.
fn judge(
    current: &Luma,
    prev: Option<&[f32]>,
    next: Option<&[f32]>,
    stored: &StoredVectors,
) -> Verdict {
    if stored.spec.encoding != Encoding::Plain || (prev.is_none() && next.is_none()) {
        return Verdict::Silent;
    }
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
    let Some(best) = result.readings.first() else {
        return Verdict::Silent;
    };
    // Still, or stored vectors that never change where motion was measured (a still
    // frame's zeros beside a moving neighbour): no reading can be told from another.
    if result.no_motion < 0.5 || result.varying == [false, false] {
        return Verdict::Silent;
    }
    let stated = stated(&stored.spec);
    let Some(own) = result.residual_of(&stated) else {
        return Verdict::Silent;
    };
    if own > 2.0 * best.residual + 0.25 {
        Verdict::Warn(format!(
            "{} ({:.2} px) against the preset's {} ({:.2} px; no motion {:.2} px)",
            super::fit::describe(best),
            best.residual,
            super::fit::describe(&stated),
            own,
            result.no_motion
        ))
    } else {
        Verdict::Fine
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::Passes;

    fn order(frames: &[i64]) -> Vec<Option<i64>> {
        frames.iter().copied().map(Some).collect()
    }

    fn check(frames: &[i64]) -> Option<(Vec<usize>, bool)> {
        let pattern = PathPattern::parse("/nowhere/c.####.exr").unwrap();
        let preset = Preset::load(&[]).unwrap();
        let needs = Passes {
            velocity: true,
            ..Passes::COLOR
        };
        VectorCheck::new(&pattern, &preset, &order(frames), needs)
            .map(|c| (c.candidates.iter().copied().collect(), c.from_disk))
    }

    /// The frames fitted are the first three whose neighbours the run reads just before and
    /// after them; a job with none fits its first frame against neighbours from disk.
    #[test]
    fn fits_frames_whose_neighbours_are_read_around_them() {
        assert_eq!(check(&[1, 2, 3, 4, 5, 6]), Some((vec![1, 2, 3], false)));
        assert_eq!(check(&[1, 2, 4, 5, 6]), Some((vec![3], false)));
        assert_eq!(check(&[7]), Some((vec![0], true)));
        assert_eq!(check(&[7, 8]), Some((vec![0], true)));
        assert_eq!(check(&[1, 3, 5]), Some((vec![0], true)));
        let pattern = PathPattern::parse("/nowhere/c.####.exr").unwrap();
        let preset = Preset::load(&[]).unwrap();
        assert!(VectorCheck::new(&pattern, &preset, &order(&[1, 2, 3]), Passes::COLOR).is_none());
    }
}
