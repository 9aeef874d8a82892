//! Frame sequences: path patterns (`shot.####.exr`, `shot.%04d.exr`) and frame specs
//! (`1001-1100`, `1-99x2`, `1,5,9-12`).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// The largest number of frames a spec may expand to: protects against `1-999999999`
/// typos eating memory before anything useful happens.
pub const MAX_FRAMES: usize = 1_000_000;

/// A path that may hold a frame-number placeholder.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PathPattern {
    /// The path as the user gave it.
    pub raw: String,
    /// Text before and after the placeholder, and the zero-padded width; `None` when the path
    /// names one file.
    placeholder: Option<(String, String, usize)>,
}

impl PathPattern {
    /// Parses `####` (one `#` per digit) or `%0Nd` / `%d` in the file name part of a path.
    pub fn parse(raw: &str) -> Result<Self> {
        let placeholder = find_hashes(raw).or_else(|| find_printf(raw));
        if let Some((start, end, _)) = &placeholder {
            let rest = &raw[*end..];
            if find_hashes(rest).is_some() || find_printf(rest).is_some() {
                return Err(Error::usage(format!(
                    "'{raw}' holds more than one frame placeholder; use one '####' or '%04d'"
                )));
            }
            let _ = start;
        }
        Ok(PathPattern {
            raw: raw.to_string(),
            placeholder: placeholder.map(|(start, end, width)| {
                (raw[..start].to_string(), raw[end..].to_string(), width)
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
            _ => PathBuf::from(&self.raw),
        }
    }

    /// The pattern with its placeholder written as `#`s, one per digit (`%04d` → `####`):
    /// two spellings of one sequence give the same text.
    pub fn with_hashes(&self) -> String {
        match &self.placeholder {
            Some((before, after, width)) => format!("{before}{}{after}", "#".repeat(*width)),
            None => self.raw.clone(),
        }
    }

    /// The frame numbers of the files on disk that match this pattern, sorted.
    pub fn discover(&self) -> Result<Vec<i64>> {
        let Some((before, after, width)) = &self.placeholder else {
            return Ok(Vec::new());
        };
        let before_path = Path::new(before.as_str());
        // Split the text before the placeholder into the directory and a file-name prefix.
        let (dir, prefix) = if before.ends_with('/') || before.is_empty() {
            (before_path.to_path_buf(), String::new())
        } else {
            let dir = before_path
                .parent()
                .map(Path::to_path_buf)
                .unwrap_or_default();
            let prefix = before_path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            (dir, prefix)
        };
        let read_dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir.as_path()
        };
        let entries = std::fs::read_dir(read_dir).map_err(|e| {
            Error::usage(format!(
                "cannot list '{}' to find the frames of '{}': {e}; pass --frames",
                read_dir.display(),
                self.raw
            ))
        })?;
        let mut frames = BTreeSet::new();
        for entry in entries.flatten() {
            let name = entry.file_name().to_string_lossy().into_owned();
            if let Some(digits) = name
                .strip_prefix(prefix.as_str())
                .and_then(|rest| rest.strip_suffix(after.as_str()))
            {
                if digits.len() >= *width
                    && !digits.is_empty()
                    && digits.bytes().all(|b| b.is_ascii_digit())
                    && (digits.len() == *width || !digits.starts_with('0'))
                {
                    if let Ok(frame) = digits.parse::<i64>() {
                        frames.insert(frame);
                    }
                }
            }
        }
        Ok(frames.into_iter().collect())
    }
}

fn find_hashes(raw: &str) -> Option<(usize, usize, usize)> {
    let start = raw.find('#')?;
    let len = raw[start..].bytes().take_while(|&b| b == b'#').count();
    Some((start, start + len, len))
}

fn find_printf(raw: &str) -> Option<(usize, usize, usize)> {
    let bytes = raw.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
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

/// Parses a frame spec: comma-separated items, each `N`, `A-B` or `A-BxS` (every S-th frame
/// from A to B inclusive). Frames come out in the order given, duplicates removed.
pub fn parse_frames(spec: &str) -> Result<Vec<i64>> {
    let bad = |why: &str| {
        Error::usage(format!(
            "bad --frames '{spec}': {why} (examples: 1001-1100, 1-99x2, 1,5,9-12)"
        ))
    };
    let mut frames = Vec::new();
    let mut seen = BTreeSet::new();
    for item in spec.split(',') {
        let item = item.trim();
        if item.is_empty() {
            return Err(bad("empty item"));
        }
        let (range, step) = match item.split_once('x') {
            Some((range, step)) => {
                let step: i64 = step
                    .trim()
                    .parse()
                    .map_err(|_| bad("step is not a number"))?;
                if step < 1 {
                    return Err(bad("step must be at least 1"));
                }
                (range, step)
            }
            None => (item, 1),
        };
        let (first, last) = match range.split_once('-') {
            Some((a, b)) => (
                a.trim().parse::<i64>().map_err(|_| bad("not a number"))?,
                b.trim().parse::<i64>().map_err(|_| bad("not a number"))?,
            ),
            None => {
                let n = range
                    .trim()
                    .parse::<i64>()
                    .map_err(|_| bad("not a number"))?;
                (n, n)
            }
        };
        if first < 0 || last < 0 {
            return Err(bad("frames are not negative"));
        }
        if last < first {
            return Err(bad("a range must not run backwards"));
        }
        if ((last - first) / step) as usize >= MAX_FRAMES {
            return Err(bad("too many frames"));
        }
        let mut frame = first;
        while frame <= last {
            if seen.insert(frame) {
                frames.push(frame);
                if frames.len() > MAX_FRAMES {
                    return Err(bad("too many frames"));
                }
            }
            frame += step;
        }
    }
    Ok(frames)
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

    #[test]
    fn plain_paths_are_single_files() {
        let p = PathPattern::parse("C.exr").unwrap();
        assert!(!p.is_sequence());
        assert_eq!(p.path(Some(3)), PathBuf::from("C.exr"));
    }

    #[test]
    fn two_placeholders_are_refused() {
        assert!(PathPattern::parse("a.####.%04d.exr").is_err());
    }

    #[test]
    fn frame_specs() {
        assert_eq!(parse_frames("1001-1004").unwrap(), [1001, 1002, 1003, 1004]);
        assert_eq!(parse_frames("1-9x2").unwrap(), [1, 3, 5, 7, 9]);
        assert_eq!(parse_frames("1-10x4").unwrap(), [1, 5, 9]);
        assert_eq!(parse_frames("1,5,9-12").unwrap(), [1, 5, 9, 10, 11, 12]);
        assert_eq!(parse_frames("3,3,2-4").unwrap(), [3, 2, 4]);
        for bad in ["", "a", "5-1", "1-5x0", "1,,2", "-3", "0-99999999999"] {
            assert!(parse_frames(bad).is_err(), "{bad} should be refused");
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
            ".a.####.exr.lock",
        ] {
            std::fs::write(dir.path().join(name), b"").unwrap();
        }
        let pattern = format!("{}/a.####.exr", dir.path().display());
        let p = PathPattern::parse(&pattern).unwrap();
        assert_eq!(p.discover().unwrap(), [1, 3]);
    }
}
