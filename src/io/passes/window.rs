//! Where a pass's pixels lie: its data window in the file's coordinates. A pass is placed by
//! it against the colour's (issue 29): one that covers the colour's window is read and cut to
//! it (depth rendered with overscan beside an auto-bbox beauty), one that does not is refused
//! by the plan, naming both windows.

use crate::frame::{Plane, Windows};
use crate::io::file::FileInfo;

/// Where a file's pixels lie in the file's coordinates: its data window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DataWindow {
    pub origin: (i32, i32),
    pub width: usize,
    pub height: usize,
}

impl From<crate::frame::Window> for DataWindow {
    fn from(w: crate::frame::Window) -> Self {
        DataWindow {
            origin: (w.x, w.y),
            width: w.width,
            height: w.height,
        }
    }
}

impl DataWindow {
    pub fn of(info: &FileInfo) -> Self {
        DataWindow {
            origin: info.windows.data_origin,
            width: info.width,
            height: info.height,
        }
    }

    /// The window as the frame keeps windows.
    pub fn as_window(&self) -> crate::frame::Window {
        crate::frame::Window {
            x: self.origin.0,
            y: self.origin.1,
            width: self.width,
            height: self.height,
        }
    }

    fn end(&self) -> (i64, i64) {
        (
            i64::from(self.origin.0) + self.width as i64,
            i64::from(self.origin.1) + self.height as i64,
        )
    }

    /// Whether every pixel of `other` lies in this window.
    pub fn covers(&self, other: &DataWindow) -> bool {
        let (end, other_end) = (self.end(), other.end());
        self.origin.0 <= other.origin.0
            && self.origin.1 <= other.origin.1
            && end.0 >= other_end.0
            && end.1 >= other_end.1
    }

    /// `(x0, y0) - (x1, y1)`, inclusive, as EXR headers and `shutter info` give windows.
    pub fn describe(&self) -> String {
        let end = self.end();
        format!(
            "({}, {}) - ({}, {})",
            self.origin.0,
            self.origin.1,
            end.0 - 1,
            end.1 - 1
        )
    }

    /// The pixels of `colour` this window leaves out, as windows ([`DataWindow::describe`],
    /// joined with "and"): the bands left and right of it over `colour`'s height, then those
    /// above and below it between them; `colour` whole where they do not meet.
    pub fn uncovered_in(&self, colour: &DataWindow) -> String {
        let (end, c_end) = (self.end(), colour.end());
        let (x0, y0) = (i64::from(colour.origin.0), i64::from(colour.origin.1));
        let (sx, sy) = (i64::from(self.origin.0), i64::from(self.origin.1));
        let band = |x: (i64, i64), y: (i64, i64)| {
            (x.0 < x.1 && y.0 < y.1).then(|| DataWindow {
                origin: (x.0 as i32, y.0 as i32),
                width: (x.1 - x.0) as usize,
                height: (y.1 - y.0) as usize,
            })
        };
        let meet = sx < c_end.0 && end.0 > x0 && sy < c_end.1 && end.1 > y0;
        if !meet {
            return colour.describe();
        }
        let inner = (sx.max(x0), end.0.min(c_end.0));
        let bands = [
            band((x0, sx.min(c_end.0)), (y0, c_end.1)),
            band((end.0.max(x0), c_end.0), (y0, c_end.1)),
            band(inner, (y0, sy.min(c_end.1))),
            band(inner, (end.1.max(y0), c_end.1)),
        ];
        (bands.iter().flatten())
            .map(DataWindow::describe)
            .collect::<Vec<_>>()
            .join(" and ")
    }

    /// `plane` (this window's samples) cut to `to`, which it covers.
    pub fn crop(&self, plane: &[f32], to: &DataWindow) -> Plane {
        let dx = (to.origin.0 - self.origin.0) as usize;
        let dy = (to.origin.1 - self.origin.1) as usize;
        let mut out = Vec::with_capacity(to.width * to.height);
        for y in 0..to.height {
            let start = (dy + y) * self.width + dx;
            out.extend_from_slice(&plane[start..start + to.width]);
        }
        out
    }
}

/// The warning that `pass`, read from `info`, was framed for another picture than the colour
/// pass: its display window differs from the colour's (`colour`). Its pixels are still placed
/// by their data window in the file's coordinates, as EXR places them, which is right for an
/// overscan render (the display window kept, the data window widened) but not for a pass
/// rendered at another resolution or framing, whose pixels then land on the wrong ones
/// without a word. `None` for a file with no display window of its own (an image) or the
/// same one.
pub fn display_warning(pass: &str, info: &FileInfo, colour: &Windows) -> Option<String> {
    let display = info.windows.display;
    let exr = matches!(info.kind, crate::io::file::FileKind::Exr { .. });
    (exr && display != colour.display).then(|| {
        let text = |w: &crate::frame::Window| DataWindow::from(*w).describe();
        format!(
            "{pass}: the file's display window {} is not the color pass's {}: its pixels are \
             placed by their data window in the file's coordinates, right for an overscan \
             render of the same picture, wrong for one rendered at another resolution or \
             framing",
            text(&display),
            text(&colour.display)
        )
    })
}

/// `info` as the part holding its channel `channel` sees it: the size and windows of that
/// part, where a multi-part file's parts differ (a beauty cut to its bounding box beside a
/// data part rendered with overscan). A pass read from such a part is then placed by that
/// part's data window, as a pass in a file of its own is; read with the file's first part's
/// window, its channels were refused as a "corrupt" file whose parts differ in size.
pub fn part_view(info: &FileInfo, channel: usize) -> FileInfo {
    let part = info.channels.get(channel).map_or(0, |c| c.part);
    if let crate::io::file::FileKind::Exr { headers, .. } = &info.kind {
        if let Some(header) = headers.get(part) {
            let windows = crate::io::exr::windows_of(header);
            let (width, height) = (header.layer_size.0, header.layer_size.1);
            if (width, height, windows) != (info.width, info.height, info.windows) {
                return FileInfo {
                    width,
                    height,
                    windows,
                    ..info.clone()
                };
            }
        }
    }
    info.clone()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn window(x0: i32, y0: i32, x1: i32, y1: i32) -> DataWindow {
        DataWindow {
            origin: (x0, y0),
            width: (x1 - x0 + 1) as usize,
            height: (y1 - y0 + 1) as usize,
        }
    }

    #[test]
    fn a_window_names_the_pixels_of_the_colour_s_it_leaves_out() {
        let colour = window(0, 0, 159, 89);
        // A box inside: the bands left and right over the whole height, then above and below.
        assert_eq!(
            window(30, 20, 100, 70).uncovered_in(&colour),
            "(0, 0) - (29, 89) and (101, 0) - (159, 89) and (30, 0) - (100, 19) and \
             (30, 71) - (100, 89)"
        );
        // Short of the right edge alone.
        assert_eq!(
            window(-5, -5, 149, 99).uncovered_in(&colour),
            "(150, 0) - (159, 89)"
        );
        // Apart: all of it.
        assert_eq!(
            window(200, 0, 250, 89).uncovered_in(&colour),
            "(0, 0) - (159, 89)"
        );
        assert_eq!(colour.uncovered_in(&colour), "");
    }
}
