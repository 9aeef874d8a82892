//! Where a pass's pixels lie: its data window in the file's coordinates. A pass is placed by
//! it against the colour's (issue 29): one that covers the colour's window is read and cut to
//! it (depth rendered with overscan beside an auto-bbox beauty), one that does not is refused
//! by the plan, naming both windows.

use crate::frame::Plane;
use crate::io::file::FileInfo;

/// Where a file's pixels lie in the file's coordinates: its data window.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DataWindow {
    pub origin: (i32, i32),
    pub width: usize,
    pub height: usize,
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
