//! The parts of an EXR colour file besides the beauty's (issue 29): which channels ride with
//! the beauty's own read (the parts of its data window), which parts are read apart (another
//! data window), and which cannot be read (deep data, and what the exr crate does not
//! decode). A multi-view file is seen as the view read.

use crate::io::file::FileInfo;

/// A part of the colour file read apart, at its own data window: its channels (indices into
/// the file's `channels`) and each one's class.
#[derive(Clone, Debug)]
pub(super) struct PartApart {
    pub(super) part: usize,
    pub(super) channels: Vec<usize>,
    pub(super) classes: Vec<crate::frame::LayerClass>,
}

impl PartApart {
    /// Whether the part is passed through as it came, at its own window: every channel is
    /// data (none blurred, none carried with the motion). Otherwise the part is placed on
    /// the beauty's window, which the passes work on.
    pub(super) fn passed_through(&self) -> bool {
        (self.classes.iter()).all(|&c| c == crate::frame::LayerClass::Data)
    }
}

/// The channels of an EXR colour file other than the beauty's (`beauty`, indices into
/// `info.channels`): those of the beauty's part, and of every other part whose data window is
/// the beauty's; then the parts left out of those (by name: `part N` or `part NAME`), each
/// with its index when it can be read apart (its data window is another), or why it cannot
/// be read at all (deep data, or data the exr crate does not decode: `exr::unsupported_reason`). None for an integer image, whose channels are all
/// the beauty's. A multi-view file is seen as the view read ([`FileInfo::in_view`]): its
/// channels and those of no view, named without the view, so it comes out as a file of that
/// view.
pub(super) fn other_channels(
    info: &FileInfo,
    beauty: &[usize],
) -> (Vec<usize>, Vec<Result<usize, String>>, Vec<String>) {
    let crate::io::file::FileKind::Exr { headers, .. } = &info.kind else {
        return Default::default();
    };
    let Some(&first) = beauty.first() else {
        return Default::default();
    };
    let colour = &headers[info.channels[first].part];
    let unreadable = |part: usize| crate::io::exr::unsupported_reason(&headers[part]);
    let readable = |part: usize| unreadable(part).is_none();
    let alike = |part: usize| {
        let h = &headers[part];
        h.layer_size == colour.layer_size
            && h.own_attributes.layer_position == colour.own_attributes.layer_position
            && readable(part)
    };
    let others = (0..info.channels.len())
        .filter(|&i| alike(info.channels[i].part) && !beauty.contains(&i))
        .collect();
    // Parts of the channels seen (a multi-view file's other views are not).
    let seen: std::collections::BTreeSet<usize> = info.channels.iter().map(|c| c.part).collect();
    let (apart, left) = (0..headers.len())
        .filter(|&p| seen.contains(&p) && !alike(p))
        .map(|p| {
            let name = headers[p]
                .own_attributes
                .layer_name
                .as_ref()
                .map_or(format!("part {p}"), |n| {
                    format!("part {}", crate::io::channels::name_of(n))
                });
            (unreadable(p).map_or(Ok(p), Err), name)
        })
        .unzip();
    (others, apart, left)
}
