//! Error types: one for what the user typed wrong (exit code 2), one for problems with the
//! files on disk (exit code 1). Every file problem names the file, the frame and, where it
//! applies, the channel, and says what to do, on one line.

use std::fmt;
use std::path::PathBuf;

/// `text` as a terminal may be given it: every control character (ESC, a newline, a tab,
/// DEL, the C1 controls) and every bidirectional override or isolate written as Rust's escape
/// of it (`\u{1b}`, `\n`), everything else as it is (`lumière.R`, `"`, `\`). A name read from
/// a file is printed through this, so that a hostile channel `Z\x1b[31m\n` shows as
/// `Z\u{1b}[31m\n` on one line instead of colouring the terminal and breaking the line;
/// `shutter info` shows values the same way (`{:?}`).
pub fn printable(text: &str) -> String {
    let mut shown = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() || is_bidi_control(c) {
            shown.extend(c.escape_debug());
        } else {
            shown.push(c);
        }
    }
    shown
}

/// [`printable`] of each line of `text`, the line breaks kept: a command's output of many
/// lines, whose names were escaped where they were put in (this is the guard for any that
/// were not).
pub fn printable_lines(text: &str) -> String {
    text.split('\n')
        .map(printable)
        .collect::<Vec<_>>()
        .join("\n")
}

/// The Unicode format chars that reorder the text around them (U+200E/F marks, U+202A to
/// U+202E embeddings and overrides, U+2066 to U+2069 isolates): a name holding one could show
/// as another ("Trojan Source").
fn is_bidi_control(c: char) -> bool {
    matches!(c, '\u{200e}' | '\u{200f}' | '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}')
}

/// What kind of problem a file has. Tests and callers match on this, users read the message.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProblemKind {
    /// The file does not exist or cannot be opened.
    MissingFile,
    /// A channel the preset asks for is not in the file.
    MissingChannel,
    /// Passes (or a pass and the colour) have different sizes.
    SizeMismatch,
    /// The file is damaged: bad header, truncated, undecodable data.
    Corrupt,
    /// A valid file that uses a feature shutter cannot read (e.g. HTJ2K, deep data).
    Unsupported,
    /// An output cannot be written, or would overwrite an input.
    Output,
    /// The header declares more pixels than the limit (`max-pixels`) allows.
    TooLarge,
    /// A multi-view file does not hold the view asked for, or names no default view when
    /// none was asked for.
    View,
    /// Another job holds the output lock on a frame: worth retrying later (exit 75).
    Busy,
    /// Writing failed after the preflight passed with an error a retry may cure (a full
    /// disk or quota, an interrupted or timed-out write: [`is_transient_io`]), exit 75. A
    /// write that fails for good (permissions, a read-only file system, a folder in the
    /// file's place, a device error) is [`ProblemKind::Output`], exit 1.
    WriteFailed,
    /// An input changed after the preflight checked it (replaced mid-run): the run stops at
    /// the frame that reads it (exit 1: the input is not what was checked).
    Changed,
}

impl ProblemKind {
    /// The kind's stable name in `--json` error objects (README: "JSON").
    pub fn name(self) -> &'static str {
        match self {
            ProblemKind::MissingFile => "missing_file",
            ProblemKind::MissingChannel => "missing_channel",
            ProblemKind::SizeMismatch => "size_mismatch",
            ProblemKind::Corrupt => "corrupt",
            ProblemKind::Unsupported => "unsupported",
            ProblemKind::Output => "output",
            ProblemKind::TooLarge => "too_large",
            ProblemKind::View => "view",
            ProblemKind::Busy => "busy",
            ProblemKind::WriteFailed => "write_failed",
            ProblemKind::Changed => "changed",
        }
    }

    /// Whether a retry may succeed with the same inputs: the job was not wrong, the moment was.
    pub fn is_transient(self) -> bool {
        matches!(self, ProblemKind::Busy | ProblemKind::WriteFailed)
    }

    /// The kind of an I/O error met on the output side (making a folder, the lock file, the
    /// writability probe, writing or renaming a frame, standard output): a transient one
    /// ([`is_transient_io`]) is the moment's, [`ProblemKind::WriteFailed`] (exit 75)
    /// wherever it is found; any other is [`ProblemKind::Output`] (exit 1: permissions, a
    /// read-only file system, a file or folder in the way, a device error).
    pub fn of_output_error(error: &std::io::Error) -> ProblemKind {
        if is_transient_io(error) {
            ProblemKind::WriteFailed
        } else {
            ProblemKind::Output
        }
    }
}

/// Whether an I/O error met writing may go away by itself, so that the same job run again
/// later may succeed (exit 75): a full disk or an exceeded quota (ENOSPC, EDQUOT: a farm's
/// scratch space is cleaned and quotas are raised without the job changing, and the frames
/// written before are kept for `--skip-existing`), an interrupted call (EINTR), a resource
/// busy for now (EAGAIN, EWOULDBLOCK) and a timeout (ETIMEDOUT: a network file system's
/// server that did not answer). Everything else is for good until someone acts, exit 1:
/// permissions (EACCES, EPERM), a read-only file system (EROFS), a folder or file in the
/// way (EISDIR, ENOTDIR, EEXIST), a name too long, a file too large for the file system
/// (EFBIG), a device error (EIO: the same disk answers the same way; a network file
/// system's lost server times out instead).
pub fn is_transient_io(error: &std::io::Error) -> bool {
    use std::io::ErrorKind;
    is_out_of_space(error)
        || matches!(
            error.kind(),
            ErrorKind::Interrupted | ErrorKind::WouldBlock | ErrorKind::TimedOut
        )
}

/// A full disk or an exceeded quota (ENOSPC, EDQUOT).
pub fn is_out_of_space(error: &std::io::Error) -> bool {
    #[cfg(unix)]
    {
        if let Some(code) = error.raw_os_error() {
            return code == nix::libc::ENOSPC || code == nix::libc::EDQUOT;
        }
    }
    matches!(
        error.kind(),
        std::io::ErrorKind::StorageFull | std::io::ErrorKind::QuotaExceeded
    )
}

/// Why writing a file failed: what to say, and whether a retry may cure it.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteFailure {
    pub detail: String,
    pub transient: bool,
}

impl WriteFailure {
    /// A failure that the I/O error `error` caused: transient as [`is_transient_io`] says.
    pub fn of_io(error: &std::io::Error, detail: impl Into<String>) -> Self {
        WriteFailure {
            detail: detail.into(),
            transient: is_transient_io(error),
        }
    }

    /// A failure a retry may cure (another job holds the frame).
    pub fn transient(detail: impl Into<String>) -> Self {
        WriteFailure {
            detail: detail.into(),
            transient: true,
        }
    }

    /// A failure a retry cannot cure (the data cannot be encoded, no I/O error in it).
    pub fn permanent(detail: impl Into<String>) -> Self {
        WriteFailure {
            detail: detail.into(),
            transient: false,
        }
    }

    /// Its kind as a file problem: [`ProblemKind::WriteFailed`] (exit 75) when transient,
    /// else [`ProblemKind::Output`] (exit 1).
    pub fn kind(&self) -> ProblemKind {
        if self.transient {
            ProblemKind::WriteFailed
        } else {
            ProblemKind::Output
        }
    }
}

/// One problem with one file of one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    pub kind: ProblemKind,
    pub path: PathBuf,
    /// The frame number, when the path comes from a sequence pattern.
    pub frame: Option<i64>,
    /// The pass the file was read for (`color`, `depth`, ...), if any.
    pub pass: Option<&'static str>,
    /// The channel concerned, if any.
    pub channel: Option<String>,
    /// What went wrong and what to do about it.
    pub detail: String,
}

impl Problem {
    pub fn new(kind: ProblemKind, path: impl Into<PathBuf>, detail: impl Into<String>) -> Self {
        Self {
            kind,
            path: path.into(),
            frame: None,
            pass: None,
            channel: None,
            detail: detail.into(),
        }
    }

    pub fn frame(mut self, frame: Option<i64>) -> Self {
        self.frame = frame;
        self
    }

    pub fn pass(mut self, pass: &'static str) -> Self {
        self.pass = Some(pass);
        self
    }

    pub fn channel(mut self, channel: impl Into<String>) -> Self {
        self.channel = Some(channel.into());
        self
    }
}

impl fmt::Display for Problem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let what = match self.kind {
            ProblemKind::MissingFile => "missing file",
            ProblemKind::MissingChannel => "missing channel",
            ProblemKind::SizeMismatch => "size mismatch",
            ProblemKind::Corrupt => "corrupt file",
            ProblemKind::Unsupported => "not supported",
            ProblemKind::Output => "cannot write",
            ProblemKind::TooLarge => "too large",
            ProblemKind::View => "which view",
            ProblemKind::Busy => "busy",
            ProblemKind::WriteFailed => "cannot write",
            ProblemKind::Changed => "changed",
        };
        write!(f, "{what}: {}", printable(&self.path.display().to_string()))?;
        if let Some(frame) = self.frame {
            write!(f, ", frame {frame}")?;
        }
        if let Some(pass) = self.pass {
            write!(f, ", {pass} pass")?;
        }
        if let Some(channel) = &self.channel {
            write!(f, ", channel {}", printable(channel))?;
        }
        // Keep the message on one line whatever the underlying error printed, and a name from
        // a file that holds control characters from reaching the terminal raw.
        let detail = printable(&self.detail.replace('\n', " "));
        write!(f, ": {detail}")
    }
}

/// The exit code of a failure a retry may cure (another job holds the frames, a write
/// failed with a transient error, [`is_transient_io`]): sysexits' EX_TEMPFAIL, which
/// schedulers and wrappers read as "try again later".
pub const TRANSIENT_EXIT: i32 = 75;

/// Everything the library can fail with.
#[derive(Debug)]
pub enum Error {
    /// The request itself is wrong (bad flag value, unknown preset, bad frame spec): exit 2.
    Usage(String),
    /// One or more problems with input or output files, all found before anything was
    /// written (preflight) or while a frame was processed: exit 1.
    Files(Vec<Problem>),
    /// The requested backend cannot run here (no suitable GPU adapter, or a build without
    /// the GPU backend), found before anything was read or written: exit 1. One line that
    /// says what is missing and what to install or use instead.
    Device(String),
}

impl Error {
    pub fn usage(message: impl Into<String>) -> Self {
        Error::Usage(message.into())
    }

    /// The process exit code for this error: 2 for usage errors, 1 for everything else.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Usage(_) => 2,
            Error::Files(problems)
                if !problems.is_empty() && problems.iter().all(|p| p.kind.is_transient()) =>
            {
                TRANSIENT_EXIT
            }
            Error::Files(_) | Error::Device(_) => 1,
        }
    }

    /// The problems, if this is a file error.
    pub fn problems(&self) -> &[Problem] {
        match self {
            Error::Usage(_) | Error::Device(_) => &[],
            Error::Files(problems) => problems,
        }
    }
}

impl From<Problem> for Error {
    fn from(problem: Problem) -> Self {
        Error::Files(vec![problem])
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Usage(message) | Error::Device(message) => write!(f, "{message}"),
            Error::Files(problems) => {
                for (i, problem) in problems.iter().enumerate() {
                    if i > 0 {
                        writeln!(f)?;
                    }
                    write!(f, "{problem}")?;
                }
                Ok(())
            }
        }
    }
}

impl std::error::Error for Error {}

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    /// A hostile name's ESC, newline and bidirectional override are escaped; what a name may
    /// hold besides (UTF-8, quotes, backslashes, spaces) is left as it is.
    #[test]
    fn printable_escapes_control_characters_only() {
        assert_eq!(printable("Z\"\u{1b}[31m\n"), "Z\"\\u{1b}[31m\\n");
        assert_eq!(printable("a\tb\u{7f}\u{9b}"), "a\\tb\\u{7f}\\u{9b}");
        assert_eq!(printable("x\u{202e}y"), "x\\u{202e}y");
        assert_eq!(
            printable("lumière.R \"q\" a\\b 前景"),
            "lumière.R \"q\" a\\b 前景"
        );
        assert_eq!(printable_lines("a\u{1b}\nb\n"), "a\\u{1b}\nb\n");
        let problem = Problem::new(ProblemKind::MissingChannel, "f.exr", "has Z\u{1b}[0m")
            .channel("V\u{1b}".to_string());
        assert_eq!(
            problem.to_string(),
            "missing channel: f.exr, channel V\\u{1b}: has Z\\u{1b}[0m"
        );
    }

    /// The rule README's exit codes give: errno by errno, which write failures a retry may
    /// cure (75) and which it cannot (1).
    #[cfg(unix)]
    #[test]
    fn write_errors_are_transient_by_their_kind() {
        use nix::libc;
        let kind = |code| ProblemKind::of_output_error(&std::io::Error::from_raw_os_error(code));
        for code in [
            libc::ENOSPC,
            libc::EDQUOT,
            libc::EINTR,
            libc::EAGAIN,
            libc::ETIMEDOUT,
        ] {
            assert_eq!(kind(code), ProblemKind::WriteFailed, "errno {code}");
        }
        for code in [
            libc::EACCES,
            libc::EPERM,
            libc::EROFS,
            libc::EISDIR,
            libc::ENOTDIR,
            libc::EEXIST,
            libc::ENAMETOOLONG,
            libc::EFBIG,
            libc::EIO,
        ] {
            assert_eq!(kind(code), ProblemKind::Output, "errno {code}");
        }
        let files = |kind| Error::from(Problem::new(kind, "o.exr", "x")).exit_code();
        assert_eq!(files(ProblemKind::WriteFailed), TRANSIENT_EXIT);
        assert_eq!(files(ProblemKind::Output), 1);
    }
}
