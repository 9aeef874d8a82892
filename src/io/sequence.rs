//! Frame sequences: path patterns (`shot.####.exr`, `shot.%04d.exr`) and frame specs
//! (`1001-1100`, `1-99x2`, `1,5,9-12`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The largest number of frames a spec may expand to: protects against `1-999999999`
/// typos eating memory before anything useful happens.
pub const MAX_FRAMES: usize = 1_000_000;

/// What [`PathPattern::discover`] found on disk.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Discovered {
    /// The frame numbers of the files that match the pattern, sorted.
    pub frames: Vec<i64>,
    /// The names of files spelled as frames of the pattern but numbered beyond
    /// ±[`MAX_FRAME_NUMBER`], sorted: not frames of the sequence (`--frames` refuses such
    /// numbers too, and the output lock has no byte for them).
    pub beyond: Vec<String>,
    /// A name spelled as a frame of the pattern but for its padding, by its width (`c.001.exr`
    /// beside `c.####.exr`; 1 for numbers with no zero first, `c.5.exr`, `c.12.exr`, all
    /// frames of `c.#.exr`), the first found of each width.
    pub other_widths: BTreeMap<usize, String>,
}

impl Discovered {
    /// One line on the files numbered beyond the limit, naming one of them; `None` when there
    /// are none. A warning beside the frames found, or the reason there are none.
    pub fn beyond_note(&self, pattern: &PathPattern) -> Option<String> {
        let first = self.beyond.first()?;
        let more = self.beyond.len() - 1;
        Some(format!(
            "'{first}'{} {} numbered beyond ±{MAX_FRAME_NUMBER}, the largest frame number \
             shutter reads or writes (--frames refuses it too): not {} of '{}'; \
             renumber the sequence to use {}",
            match more {
                0 => String::new(),
                1 => " and 1 more file".to_string(),
                n => format!(" and {n} more files"),
            },
            if more == 0 { "is" } else { "are" },
            if more == 0 { "a frame" } else { "frames" },
            pattern.raw,
            if more == 0 { "it" } else { "them" },
        ))
    }

    /// Why nothing matched, where files are the pattern's frames but for their padding (Nuke
    /// reads `#` as one digit, oiiotool and RV `#` as four): the first of each width found and
    /// the pattern to write for it. `None` when there are none.
    pub fn padding_note(&self, pattern: &PathPattern) -> Option<String> {
        let (before, after, _) = pattern.placeholder.as_ref()?;
        let found: Vec<String> = (self.other_widths.iter())
            .map(|(&width, name)| {
                let hashes = "#".repeat(width);
                let padded = match width {
                    1 => "is not padded".to_string(),
                    _ => format!("is padded to {width} digits"),
                };
                format!("'{name}' {padded}: '{before}{hashes}{after}'")
            })
            .collect();
        (!found.is_empty())
            .then(|| format!("{}; one # is one digit, as %04d is four", found.join("; ")))
    }
}

/// A path that may hold a frame-number placeholder.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PathPattern {
    /// The path as the user gave it.
    pub raw: String,
    /// Text before and after the placeholder (a `%%` of the file name as the `%` it stands
    /// for), and the zero-padded width; `None` when the path names one file.
    placeholder: Option<(String, String, usize)>,
}

impl PathPattern {
    /// Parses `####` (one `#` per digit), `%0Nd` / `%d`, Houdini's `$F4` / `$F` or `@@@@` (two
    /// or more `@`, one per digit: a single `@` is left alone, as in `icon@2x.png`) in the file
    /// name part of a path: the same characters in a folder's name (`take#2/`) are part of
    /// that name.
    ///
    /// The file name is read as ffmpeg reads its image-sequence patterns, printf's rules where
    /// a pipeline expects them: `%%` is one `%` (`b.%%d.exr` names the file `b.%d.exr`, not a
    /// sequence `b.%1.exr`), and `%Nd` pads with zeros as `%0Nd` does, not with printf's
    /// spaces (a frame number padded with spaces is no renderer's or compositor's file name;
    /// Nuke and ffmpeg users write `%04d`, and `%4d` meant the same to them).
    pub fn parse(raw: &str) -> Result<Self> {
        let find = |raw: &str| {
            find_hashes(raw)
                .or_else(|| find_printf(raw))
                .or_else(|| find_houdini(raw))
                .or_else(|| find_ats(raw))
        };
        let name = name_start(raw);
        let placeholder =
            find(&raw[name..]).map(|(start, end, width)| (name + start, name + end, width));
        // Another placeholder before the one found (the kinds are looked for one after
        // another: `a.%04d.####.exr` found `####` and wrote `a.%04d.0001.exr`) or after it.
        if let Some((start, end, _)) = placeholder {
            if find(&raw[name..start]).is_some() || find(&raw[end..]).is_some() {
                return Err(Error::usage(format!(
                    "'{raw}' holds more than one frame placeholder; use one '####' or '%04d'"
                )));
            }
        }
        Ok(PathPattern {
            raw: raw.to_string(),
            placeholder: placeholder.map(|(start, end, width)| {
                (literal(&raw[..start]), raw[end..].replace("%%", "%"), width)
            }),
        })
    }

    pub fn is_sequence(&self) -> bool {
        self.placeholder.is_some()
    }

    /// The path of one frame (the path itself when it is not a pattern).
    pub fn path(&self, frame: Option<i64>) -> PathBuf {
        match (&self.placeholder, frame) {
            (Some((before, after, width)), Some(frame)) => {
                PathBuf::from(format!("{before}{frame:0width$}{after}"))
            }
            _ => PathBuf::from(literal(&self.raw)),
        }
    }

    /// The pattern with its placeholder written as `#`s, one per digit (`%04d` → `####`):
    /// two spellings of one sequence give the same text.
    pub fn with_hashes(&self) -> String {
        match &self.placeholder {
            Some((before, after, width)) => format!("{before}{}{after}", "#".repeat(*width)),
            None => literal(&self.raw),
        }
    }

    /// The frames of the files on disk that match this pattern, sorted, and the files
    /// spelled as frames but numbered beyond ±[`MAX_FRAME_NUMBER`] (left out).
    pub fn discover(&self) -> Result<Discovered> {
        let Some((before, after, width)) = &self.placeholder else {
            return Ok(Discovered::default());
        };
        // The text before the placeholder is the folder and the file name's start.
        let (dir, prefix) = before.split_at(name_start(before));
        let read_dir = Path::new(if dir.is_empty() { "." } else { dir });
        // A folder that is not there, or cannot be listed, is bad input (exit 1, as a pattern
        // that matches no file is), not a usage error: a farm reads exit 2 as "fix the
        // command", and the command may be right with the folder gone or its share stale.
        let entries = std::fs::read_dir(read_dir).map_err(|e| {
            Error::Files(vec![crate::error::Problem::new(
                crate::error::ProblemKind::MissingFile,
                read_dir,
                format!(
                    "cannot list the folder to find the frames of '{}': {e}; pass --frames",
                    self.raw
                ),
            )])
        })?;
        let mut frames = BTreeSet::new();
        let mut beyond = BTreeSet::new();
        let mut other_widths = BTreeMap::new();
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            match name
                .strip_prefix(prefix)
                .and_then(|rest| rest.strip_suffix(after.as_str()))
                .and_then(|number| frame_spelled(number, *width))
            {
                Some(Ok(frame)) => {
                    frames.insert(frame);
                }
                Some(Err(Beyond)) => {
                    beyond.insert(name);
                }
                None => {
                    // Digits alone where the placeholder stands: a frame of another padding.
                    let number = (name.strip_prefix(prefix))
                        .and_then(|rest| rest.strip_suffix(after.as_str()))
                        .filter(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
                    if let Some(number) = number {
                        // Unpadded numbers (no zero first) are all frames of one `#`.
                        let width = match number.starts_with('0') {
                            true => number.len(),
                            false => 1,
                        };
                        let first = other_widths.entry(width).or_insert(name.clone());
                        *first = name.clone().min(first.clone());
                    }
                }
            }
        }
        Ok(Discovered {
            frames: frames.into_iter().collect(),
            beyond: beyond.into_iter().collect(),
            other_widths,
        })
    }
}

/// The frame `text` names in a placeholder `width` digits wide, when it is spelled exactly as
/// [`PathPattern::path`] writes that frame (`{frame:0width$}`: `0042`, `-002`, `12345`) and
/// nothing else: zeros after the sign make up the width and no more (`-02` and `-0002` are
/// not frames of `####`, as `01` and `00001` are not), no `+`, no sign on zero. A number so
/// spelled beyond ±[`MAX_FRAME_NUMBER`] (whatever its length) is [`Beyond`].
fn frame_spelled(text: &str, width: usize) -> Option<std::result::Result<i64, Beyond>> {
    let digits = text.strip_prefix('-').unwrap_or(text);
    let as_written = !digits.is_empty()
        && digits.bytes().all(|b| b.is_ascii_digit())
        && (text.len() == width || (text.len() > width && !digits.starts_with('0')))
        && !(text.starts_with('-') && digits.bytes().all(|b| b == b'0'));
    if !as_written {
        return None;
    }
    Some(
        text.parse::<i64>()
            .ok()
            .filter(|frame| frame.abs() <= MAX_FRAME_NUMBER)
            .ok_or(Beyond),
    )
}

/// A number spelled as a frame but beyond ±[`MAX_FRAME_NUMBER`].
#[derive(Debug, PartialEq, Eq)]
struct Beyond;

/// `path` with each `%%` of its file name written as the one `%` it stands for (printf's
/// escape; [`PathPattern::parse`]); a folder's name is left as it is, as for placeholders.
fn literal(path: &str) -> String {
    let (folder, name) = path.split_at(name_start(path));
    format!("{folder}{}", name.replace("%%", "%"))
}

/// Where the file name starts in `path`: after its last separator.
pub(crate) fn name_start(path: &str) -> usize {
    path.rfind(std::path::is_separator).map_or(0, |i| i + 1)
}

fn find_hashes(raw: &str) -> Option<(usize, usize, usize)> {
    let start = raw.find('#')?;
    let len = raw[start..].bytes().take_while(|&b| b == b'#').count();
    Some((start, start + len, len))
}

/// Houdini's `$F4` (four digits, zero-padded) or `$F` (unpadded), not `$FOO`.
fn find_houdini(raw: &str) -> Option<(usize, usize, usize)> {
    let mut from = 0;
    while let Some(at) = raw[from..].find("$F") {
        let start = from + at;
        let after = &raw[start + 2..];
        let digits = after.bytes().take_while(u8::is_ascii_digit).count();
        let next = after[digits..].chars().next();
        if !next.is_some_and(|c| c.is_ascii_alphabetic() || c == '_') {
            let width = after[..digits].parse().unwrap_or(1usize).max(1);
            return Some((start, start + 2 + digits, width));
        }
        from = start + 2;
    }
    None
}

/// A run of two or more `@`, one per digit.
fn find_ats(raw: &str) -> Option<(usize, usize, usize)> {
    let mut from = 0;
    while let Some(at) = raw[from..].find('@') {
        let start = from + at;
        let len = raw[start..].bytes().take_while(|&b| b == b'@').count();
        if len >= 2 {
            return Some((start, start + len, len));
        }
        from = start + len;
    }
    None
}

/// `%0Nd`, `%Nd` (zero-padded to N digits either way) or `%d`; a `%%` is a `%` and starts
/// none (`%%d` is the text `%d`).
fn find_printf(raw: &str) -> Option<(usize, usize, usize)> {
    let bytes = raw.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && bytes.get(i + 1) == Some(&b'%') {
            i += 2;
            continue;
        }
        if bytes[i] == b'%' {
            let mut j = i + 1;
            while j < bytes.len() && bytes[j].is_ascii_digit() {
                j += 1;
            }
            if j < bytes.len() && bytes[j] == b'd' {
                let digits = &raw[i + 1..j];
                let width = if digits.is_empty() {
                    1
                } else {
                    digits.trim_start_matches('0').parse().unwrap_or(1)
                };
                return Some((i, j + 1, width.max(1)));
            }
        }
        i += 1;
    }
    None
}

/// Frame numbers beyond ±this are refused: far beyond any shot's numbering, and small
/// enough that a frame's number fits the 30 bits the output lock keeps of a file's number
/// ([`crate::io::lock`]), so that a sequence's frames have consecutive bytes there.
pub const MAX_FRAME_NUMBER: i64 = 999_999_999;

/// Parses a frame spec: comma-separated items, each `N`, `A-B`, or a range with a step,
/// `A-B:S` (Open Job Description's range expressions, as farms write them: `1-100:5`,
/// `1,3,7-20:2`, negative frames `-10--1`, a descending range with a negative step
/// `10-1:-1`) or `A-BxS` (every S-th frame from A, S positive). Spaces around numbers and
/// dashes are allowed. Frames come out in the order given (a range in its own direction),
/// each once.
pub fn parse_frames(spec: &str) -> Result<Vec<i64>> {
    let bad = |why: String| {
        Error::usage(format!(
            "bad --frames '{spec}': {why} (examples: 1001-1100, 1-99:2, 1,5,9-12, -10--1)"
        ))
    };
    let mut frames = Vec::new();
    let mut seen = BTreeSet::new();
    for item in spec.split(',') {
        let (first, last, step) = parse_item(item).map_err(|why| bad(why.to_string()))?;
        let count = (last as i128 - first as i128) / step as i128 + 1;
        if count > MAX_FRAMES as i128 {
            return Err(bad(format!("more than {MAX_FRAMES} frames")));
        }
        for k in 0..count as i64 {
            let frame = first + k * step;
            if seen.insert(frame) {
                frames.push(frame);
                if frames.len() > MAX_FRAMES {
                    return Err(bad(format!("more than {MAX_FRAMES} frames")));
                }
            }
        }
    }
    Ok(frames)
}

/// One item of a frame spec as (first, last, step), `last` reached from `first` by whole
/// steps (the last frame of `1-10:4` is 9).
fn parse_item(item: &str) -> std::result::Result<(i64, i64, i64), &'static str> {
    let item = item.trim();
    if item.is_empty() {
        return Err("empty item");
    }
    let (range, step) = match item.split_once(':') {
        Some((range, step)) => {
            let (step, rest) = take_int(step.trim())?;
            if !rest.trim().is_empty() {
                return Err("the step is not a number");
            }
            (range, Some(step))
        }
        None => match item.split_once('x') {
            Some((range, step)) => {
                let (step, rest) = take_int(step.trim())?;
                if !rest.trim().is_empty() || step < 1 {
                    return Err("the step after x is a whole number of at least 1");
                }
                (range, Some(step))
            }
            None => (item, None),
        },
    };
    let (first, rest) = take_int(range.trim())?;
    let rest = rest.trim_start();
    let last = if rest.is_empty() {
        if step.is_some() {
            return Err("a step needs a range (A-B:S)");
        }
        first
    } else {
        let rest = rest
            .strip_prefix('-')
            .ok_or("expected '-' between two frames")?;
        let (last, rest) = take_int(rest.trim_start())?;
        if !rest.trim().is_empty() {
            return Err("unexpected text after a range");
        }
        last
    };
    let step = match step {
        Some(0) => return Err("the step must not be 0"),
        Some(step) if (step > 0) != (last >= first) && first != last => {
            return Err("a range runs the way its step does: 1-10:2, or 10-1:-1")
        }
        Some(step) => step,
        None if last < first => {
            return Err("a range must not run backwards without a negative step (10-1:-1)")
        }
        None => 1,
    };
    // The last frame whole steps reach.
    let last = first + (last - first) / step * step;
    Ok((first, last, step))
}

/// A whole number (optionally negative) at the start of `text`, within
/// ±[`MAX_FRAME_NUMBER`], and the text after it.
fn take_int(text: &str) -> std::result::Result<(i64, &str), &'static str> {
    let (negative, digits) = match text.strip_prefix('-') {
        Some(rest) => (true, rest.trim_start()),
        None => (false, text),
    };
    let end = digits
        .bytes()
        .position(|b| !b.is_ascii_digit())
        .unwrap_or(digits.len());
    if end == 0 {
        return Err("not a number");
    }
    let value: i64 = digits[..end]
        .parse()
        .ok()
        .filter(|v: &i64| *v <= MAX_FRAME_NUMBER)
        .ok_or("a frame number beyond ±999999999")?;
    Ok((if negative { -value } else { value }, &digits[end..]))
}

/// `frames` cut, in order, into chunks of `size` frames (the last may be shorter): every
/// frame lands in exactly one chunk, whatever the spec, its steps and the size (the chunks
/// of a farm task each, OpenCue's lost last frames being the cautionary tale).
pub fn chunks(frames: &[i64], size: usize) -> Vec<&[i64]> {
    frames.chunks(size.max(1)).collect()
}

/// `frames` written back as a frame spec in Open Job Description's syntax, runs of a constant
/// step as `A-B` or `A-B:S`: parsing it gives `frames` again, in the same order.
pub fn format_frames(frames: &[i64]) -> String {
    let mut items = Vec::new();
    let mut i = 0;
    while i < frames.len() {
        let first = frames[i];
        // The longest run of one step from here (at least three frames to be worth a range).
        let step = frames.get(i + 1).map(|next| next - first);
        let mut j = i + 1;
        if let Some(step) = step.filter(|s| *s != 0) {
            while j < frames.len() && frames[j] - frames[j - 1] == step {
                j += 1;
            }
        }
        if j - i >= 3 {
            let last = frames[j - 1];
            let step = frames[i + 1] - first;
            items.push(if step == 1 {
                format!("{first}-{last}")
            } else {
                format!("{first}-{last}:{step}")
            });
            i = j;
        } else {
            items.push(first.to_string());
            i += 1;
        }
    }
    items.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hashes_give_one_digit_each() {
        let p = PathPattern::parse("shots/a.####.exr").unwrap();
        assert!(p.is_sequence());
        assert_eq!(p.path(Some(7)), PathBuf::from("shots/a.0007.exr"));
        assert_eq!(p.path(Some(12345)), PathBuf::from("shots/a.12345.exr"));
    }

    #[test]
    fn printf_patterns_pad_to_their_width() {
        let p = PathPattern::parse("a_%04d.png").unwrap();
        assert_eq!(p.path(Some(42)), PathBuf::from("a_0042.png"));
        let p = PathPattern::parse("a_%d.png").unwrap();
        assert_eq!(p.path(Some(42)), PathBuf::from("a_42.png"));
    }

    /// `%%` is one `%`, as printf and ffmpeg write it: `b.%%d.exr` was read as `b.%` and a
    /// `%d` placeholder, and wrote `b.%1.exr`. A `%` of neither stays itself; a folder's name
    /// is left as it is, as for every placeholder.
    #[test]
    fn a_doubled_percent_is_one_percent_sign() {
        for (raw, single) in [
            ("out/b.%%d.exr", "out/b.%d.exr"),
            ("50%.exr", "50%.exr"),
            ("a%%/c.%%04d.exr", "a%%/c.%04d.exr"),
        ] {
            let p = PathPattern::parse(raw).unwrap();
            assert!(!p.is_sequence(), "{raw}");
            assert_eq!(p.path(None), PathBuf::from(single), "{raw}");
            assert_eq!(p.with_hashes(), single, "{raw}");
        }
        for (raw, frame_7, hashes) in [
            ("b.%%.%04d.exr", "b.%.0007.exr", "b.%.####.exr"),
            ("b.%%%04d.exr", "b.%0007.exr", "b.%####.exr"),
            ("50%%_####.exr", "50%_0007.exr", "50%_####.exr"),
        ] {
            let p = PathPattern::parse(raw).unwrap();
            assert_eq!(p.path(Some(7)), PathBuf::from(frame_7), "{raw}");
            assert_eq!(p.with_hashes(), hashes, "{raw}");
        }
        assert!(PathPattern::parse("a.%04d.%%d.%d.exr").is_err());
        // Discovery matches the names written.
        let dir = tempfile::tempdir().unwrap();
        for name in ["b.%.0001.exr", "b.%.0002.exr", "b.%%.0003.exr"] {
            std::fs::write(dir.path().join(name), b"").unwrap();
        }
        let p = PathPattern::parse(&format!("{}/b.%%.%04d.exr", dir.path().display())).unwrap();
        assert_eq!(p.discover().unwrap().frames, [1, 2]);
    }

    /// `%4d` pads with zeros as `%04d` does: ffmpeg's reading of its image-sequence patterns,
    /// not printf's spaces (a frame number padded with spaces is nobody's file name).
    #[test]
    fn a_printf_width_without_a_zero_pads_with_zeros() {
        let p = PathPattern::parse("a_%4d.png").unwrap();
        assert_eq!(p.path(Some(42)), PathBuf::from("a_0042.png"));
        assert_eq!(p.with_hashes(), "a_####.png");
    }

    #[test]
    fn plain_paths_are_single_files() {
        let p = PathPattern::parse("C.exr").unwrap();
        assert!(!p.is_sequence());
        assert_eq!(p.path(Some(3)), PathBuf::from("C.exr"));
    }

    #[test]
    fn two_placeholders_are_refused() {
        assert!(PathPattern::parse("a.####.%04d.exr").is_err());
        assert!(PathPattern::parse("a.%04d.####.exr").is_err());
        assert!(PathPattern::parse("a.$F4.####.exr").is_err());
        assert!(PathPattern::parse("a.@@.%d.exr").is_err());
        assert!(PathPattern::parse("a.$F4.@@@@.exr").is_err());
    }

    #[test]
    fn houdini_and_at_tokens_are_frame_placeholders() {
        let p = PathPattern::parse("render/beauty.$F4.exr").unwrap();
        assert_eq!(p.path(Some(42)), PathBuf::from("render/beauty.0042.exr"));
        assert_eq!(p.with_hashes(), "render/beauty.####.exr");
        let p = PathPattern::parse("beauty.$F.exr").unwrap();
        assert_eq!(p.path(Some(42)), PathBuf::from("beauty.42.exr"));
        let p = PathPattern::parse("beauty.@@@@.exr").unwrap();
        assert_eq!(p.path(Some(7)), PathBuf::from("beauty.0007.exr"));
        // Not placeholders: a variable that only starts with F, a single @.
        for plain in ["$FOO/beauty.exr", "icon@2x.png", "$F_x.exr"] {
            assert!(!PathPattern::parse(plain).unwrap().is_sequence(), "{plain}");
        }
    }

    /// Files numbered beyond ±[`MAX_FRAME_NUMBER`] (what `--frames` refuses) are not frames,
    /// but are named (QA: they were frames up to i64::MAX).
    #[test]
    fn discovery_leaves_out_and_names_numbers_beyond_the_limit() {
        let dir = tempfile::tempdir().unwrap();
        let p = PathPattern::parse(&format!("{}/c.####.exr", dir.path().display())).unwrap();
        for name in [
            "c.-999999999.exr",
            "c.999999999.exr",
            "c.1000000000.exr",
            "c.-1000000000.exr",
            "c.9223372036854775807.exr",
            "c.123456789012345678901234567890.exr",
            // Not spelled as a frame at all: not named either.
            "c.01000000000.exr",
        ] {
            std::fs::write(dir.path().join(name), b"").unwrap();
        }
        let found = p.discover().unwrap();
        assert_eq!(found.frames, [-999999999, 999999999]);
        assert_eq!(
            found.beyond,
            [
                "c.-1000000000.exr",
                "c.1000000000.exr",
                "c.123456789012345678901234567890.exr",
                "c.9223372036854775807.exr",
            ]
        );
        let note = found.beyond_note(&p).unwrap();
        assert!(
            note.contains("'c.-1000000000.exr' and 3 more files are numbered beyond ±999999999"),
            "{note}"
        );
        let nothing_beyond = Discovered {
            frames: vec![1],
            ..Discovered::default()
        };
        assert_eq!(nothing_beyond.beyond_note(&p), None);
    }

    /// Only the file name holds a placeholder: `#`, `%d`, `$F` and `@@` in a folder's name
    /// are part of it (QA: `take#2/color.0001.exr` was taken for a pattern, and
    /// `take#2/color.####.exr` for one with two placeholders).
    #[test]
    fn a_placeholder_is_only_looked_for_in_the_file_name() {
        for plain in ["take#2/color.0001.exr", "a%d/$F/@@/c.exr", "x##/y.exr"] {
            let p = PathPattern::parse(plain).unwrap();
            assert!(!p.is_sequence(), "{plain}");
            assert_eq!(p.path(Some(3)), PathBuf::from(plain));
        }
        for (raw, frame_7, hashes) in [
            (
                "take#2/c.####.exr",
                "take#2/c.0007.exr",
                "take#2/c.####.exr",
            ),
            ("a%d/c.%04d.exr", "a%d/c.0007.exr", "a%d/c.####.exr"),
            ("$F/c.$F2.exr", "$F/c.07.exr", "$F/c.##.exr"),
            ("@@/c.@@@.exr", "@@/c.007.exr", "@@/c.###.exr"),
        ] {
            let p = PathPattern::parse(raw).unwrap();
            assert_eq!(p.path(Some(7)), PathBuf::from(frame_7), "{raw}");
            assert_eq!(p.with_hashes(), hashes, "{raw}");
        }
        // And discovery lists the folder named so.
        let dir = tempfile::tempdir().unwrap();
        let take = dir.path().join("take#2");
        std::fs::create_dir(&take).unwrap();
        for name in ["c.0001.exr", "c.0002.exr"] {
            std::fs::write(take.join(name), b"").unwrap();
        }
        let p = PathPattern::parse(&format!("{}/c.####.exr", take.display())).unwrap();
        assert_eq!(p.discover().unwrap().frames, [1, 2]);
    }

    #[test]
    fn frame_specs() {
        assert_eq!(parse_frames("1001-1004").unwrap(), [1001, 1002, 1003, 1004]);
        assert_eq!(parse_frames("1-9x2").unwrap(), [1, 3, 5, 7, 9]);
        assert_eq!(parse_frames("1-10x4").unwrap(), [1, 5, 9]);
        assert_eq!(parse_frames("1,5,9-12").unwrap(), [1, 5, 9, 10, 11, 12]);
        assert_eq!(parse_frames("3,3,2-4").unwrap(), [3, 2, 4]);
        for bad in [
            "",
            "a",
            "5-1",
            "1-5x0",
            "1,,2",
            "0-99999999999",
            "1-9:0",
            "9-1:2",
            "1-9:-1",
            "4:2",
            "1-2-3",
        ] {
            assert!(parse_frames(bad).is_err(), "{bad} should be refused");
        }
    }

    #[test]
    fn open_job_description_range_expressions() {
        // The forms of the Open Job Description specification's range expressions.
        assert_eq!(parse_frames("1-10:4").unwrap(), [1, 5, 9]);
        assert_eq!(parse_frames("1,3,7-12:2").unwrap(), [1, 3, 7, 9, 11]);
        assert_eq!(parse_frames("-3").unwrap(), [-3]);
        assert_eq!(parse_frames("-3-1").unwrap(), [-3, -2, -1, 0, 1]);
        assert_eq!(parse_frames("-10--8").unwrap(), [-10, -9, -8]);
        assert_eq!(parse_frames("5-1:-2").unwrap(), [5, 3, 1]);
        assert_eq!(parse_frames(" 1 - 3 , 7 ").unwrap(), [1, 2, 3, 7]);
        assert_eq!(parse_frames("4-4:3").unwrap(), [4]);
    }

    #[test]
    fn frames_format_back_to_a_spec_that_parses_to_them() {
        for (frames, spec) in [
            (vec![1, 2, 3, 4], "1-4"),
            (vec![1, 5, 9], "1-9:4"),
            (vec![1, 2, 7], "1,2,7"),
            (vec![-3, -2, -1, 5], "-3--1,5"),
            (vec![9, 7, 5, 4], "9-5:-2,4"),
            (vec![], ""),
        ] {
            assert_eq!(format_frames(&frames), spec);
            if !frames.is_empty() {
                assert_eq!(parse_frames(spec).unwrap(), frames);
            }
        }
    }

    #[test]
    fn discovery_finds_frames_on_disk() {
        let dir = tempfile::tempdir().unwrap();
        for name in [
            "a.0001.exr",
            "a.0003.exr",
            "a.0002.png",
            "b.0004.exr",
            "a.01.exr",
            // What a run leaves while it writes: never frames.
            ".a.0005.exr.1234.tmp",
            ".shutter.lock",
        ] {
            std::fs::write(dir.path().join(name), b"").unwrap();
        }
        let pattern = format!("{}/a.####.exr", dir.path().display());
        let p = PathPattern::parse(&pattern).unwrap();
        assert_eq!(p.discover().unwrap().frames, [1, 3]);
    }

    /// Negative frames are found as shutter's own `####` writes them (`-002`: the sign takes
    /// one of the four places), with the same strict padding as positive ones (QA: discovery
    /// took digits only, so `c.-002.exr` was never a frame, even one shutter had written).
    #[test]
    fn discovery_finds_negative_frames_as_shutter_writes_them() {
        let dir = tempfile::tempdir().unwrap();
        let p = PathPattern::parse(&format!("{}/c.####.exr", dir.path().display())).unwrap();
        let frames = [-12345, -2, -1, 0, 1, 12345];
        for frame in frames {
            std::fs::write(p.path(Some(frame)), b"").unwrap();
        }
        // Not how shutter writes any frame: padded too little or too much, a sign on zero,
        // a plus sign, two signs.
        for name in [
            "c.-02.exr",
            "c.-0002.exr",
            "c.-000.exr",
            "c.+001.exr",
            "c.--01.exr",
        ] {
            std::fs::write(dir.path().join(name), b"").unwrap();
        }
        assert_eq!(p.discover().unwrap().frames, frames);
        // Unpadded: `%d` writes -2 as `-2`, never `-02` or `-0`.
        let p = PathPattern::parse(&format!("{}/u.%d.exr", dir.path().display())).unwrap();
        for name in ["u.-2.exr", "u.-02.exr", "u.-0.exr", "u.0.exr", "u.7.exr"] {
            std::fs::write(dir.path().join(name), b"").unwrap();
        }
        assert_eq!(p.discover().unwrap().frames, [-2, 0, 7]);
    }
}
