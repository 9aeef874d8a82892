//! The output lock: one hidden file per output sequence, beside the outputs and named after
//! the pattern (`out/.o.####.exr.lock` for `-o out/o.####.exr`), in which each job holds an
//! advisory lock on the frames it writes. A second job on any of the same frames fails at
//! once, naming the process that holds them; jobs on other frames of the same sequence (a
//! farm's chunks) run side by side. The kernel releases a dead holder's locks, so a lock file
//! a killed run left behind is simply taken over.
//!
//! On Unix these are `fcntl` byte-range locks, byte `frame + 1e9` for a frame and byte 0 for a
//! single still: `F_GETLK` names the conflicting process and its frame. Whole-file locks
//! (`flock`, std's `File::lock`, fs4) were the simpler choice, rejected because they make
//! chunks of one sequence refuse each other. Elsewhere the whole file is locked (std).
//!
//! The lock file is removed when the run ends (normally, with an error, or by a caught
//! signal through [`abandon_locks`]) by the last job holding any frame of it: a job first
//! takes a lock on the whole file, which succeeds only when no other process holds a frame,
//! and unlinks while holding it. A job that opened the file just before that unlink finds,
//! once locked, that the path names another file (or none) and starts again.
//!
//! A lock file deleted under a running job (by hand, or with its folder) would let a second
//! job lock a new file at the same path and write the same frames: before each frame is
//! renamed into place the job checks that its lock is still the file its path names
//! ([`verify_held`]), takes it again on a new file when it is not, and stops (exit 75)
//! without writing the frame when another job holds any of its frames there. It never
//! removes a lock file that is not its own.

use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use crate::error::{Problem, ProblemKind, WriteFailure};
use crate::io::sequence::{PathPattern, MAX_FRAME_NUMBER};

/// The lock file of an output sequence: hidden, in the output folder, named after the
/// pattern with `####` for the frame number, so that `o.####.exr` and `o.%04d.exr` share it
/// (a placeholder is only ever in the file name: [`PathPattern::parse`]).
pub fn lock_path(output: &PathPattern) -> PathBuf {
    let pattern = output.with_hashes();
    let split = pattern.rfind(std::path::is_separator).map_or(0, |i| i + 1);
    let (folder, name) = pattern.split_at(split);
    let folder = if folder.is_empty() { "." } else { folder };
    Path::new(folder).join(format!(".{name}.lock"))
}

/// A held output lock; released (and the lock file removed when no other job holds a frame
/// of it) on drop.
#[derive(Debug)]
pub struct OutputLock {
    path: PathBuf,
}

/// The locks this process holds, so that a signal handler can release them and a write can
/// check them ([`verify_held`]).
struct Held {
    path: PathBuf,
    file: File,
    /// The byte ranges of its frames ([`byte_ranges`]).
    ranges: Vec<(u64, u64)>,
    /// Folders made for the lock file, deepest first: removed again if still empty.
    created: Vec<PathBuf>,
}

static HELD: Mutex<Vec<Held>> = Mutex::new(Vec::new());

fn held() -> MutexGuard<'static, Vec<Held>> {
    HELD.lock().unwrap_or_else(PoisonError::into_inner)
}

/// How many times a lock file unlinked under us is reopened before giving up.
const ATTEMPTS: usize = 20;

/// How many times, 2 ms apart, a job waits for a job releasing the lock file (a whole-file
/// lock, held for the moment of its unlink) before it calls the frames busy.
const PASSING_WAITS: usize = 1000;

impl OutputLock {
    /// Locks `frames` of `output` for this process, making the output folder if needed.
    /// Fails, naming the frame and the process, when another process holds one of them.
    pub fn acquire(output: &PathPattern, frames: &[Option<i64>]) -> Result<OutputLock, Problem> {
        let path = lock_path(output);
        let fail_with = |e: &std::io::Error, detail: String| {
            Problem::new(ProblemKind::of_output_error(e), &path, detail)
        };
        let fail = |detail: String| Problem::new(ProblemKind::Output, &path, detail);
        let folder = path.parent().unwrap_or(Path::new("."));
        let created = create_folders(folder).map_err(|e| {
            fail_with(
                &e,
                format!("cannot create the output folder {}: {e}", folder.display()),
            )
        })?;
        let ranges = byte_ranges(frames);
        let result = (|| {
            // Waits on a passing conflict (below), a few milliseconds each.
            let mut waits = 0;
            let mut attempt = 0;
            'attempts: while attempt < ATTEMPTS {
                let file = OpenOptions::new()
                    .read(true)
                    .write(true)
                    .create(true)
                    .truncate(false)
                    .open(&path)
                    .map_err(|e| fail_with(&e, format!("cannot open the lock file: {e}")))?;
                for &(start, len) in &ranges {
                    match platform::lock_range(&file, start, len) {
                        Ok(true) => {}
                        Ok(false) => {
                            let (frame, pid, passing) = platform::holder(&file, start, len);
                            if passing && waits < PASSING_WAITS {
                                waits += 1;
                                // A job releasing the file (the whole-file lock it takes
                                // to unlink it), or a lock already gone: not a job on this
                                // frame. Once it has unlinked the file, the next attempt
                                // opens a new one. (Reported as busy before: one run in a
                                // hundred of four chunks started one after another.)
                                std::thread::sleep(std::time::Duration::from_millis(2));
                                continue 'attempts;
                            }
                            let frame = frame_of(frame.unwrap_or(start));
                            let who = match pid {
                                Some(pid) => format!("another process (pid {pid})"),
                                None => "another process".to_string(),
                            };
                            return Err(Problem::new(
                                ProblemKind::Busy,
                                output.path(frame),
                                format!(
                                    "{who} is writing this frame of {} (lock {}); wait for it \
                                     to finish, or stop it, or write elsewhere with -o",
                                    output.raw,
                                    path.display()
                                ),
                            )
                            .frame(frame));
                        }
                        Err(e) => return Err(fail(format!("cannot lock the lock file: {e}"))),
                    }
                }
                if still_named(&file, &path) {
                    return Ok(file);
                }
                attempt += 1;
            }
            Err(fail(
                "the lock file keeps being replaced by other jobs; try again".to_string(),
            ))
        })();
        match result {
            Ok(file) => {
                held().push(Held {
                    path: path.clone(),
                    file,
                    ranges,
                    created,
                });
                Ok(OutputLock { path })
            }
            Err(problem) => {
                remove_empty(&created);
                Err(problem)
            }
        }
    }

    /// The lock file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for OutputLock {
    fn drop(&mut self) {
        let taken = {
            let mut held = held();
            held.iter()
                .position(|h| h.path == self.path)
                .map(|i| held.remove(i))
        };
        if let Some(held) = taken {
            release(held);
        }
    }
}

/// Checks that every lock this process holds is still on the file its path names, just
/// before a frame is renamed into place. Someone may have deleted the lock file (or its
/// folder) under a running job, and a second job on the same frames would then lock a new
/// file and run beside it: a lock whose file is gone is taken again on a new file at the
/// same path, and when another process holds any of its frames there, this fails, naming
/// it, so the frame is not written (the run stops with exit 75) and the two jobs do not
/// write one frame. Without held locks (a library caller) nothing is checked.
pub fn verify_held() -> Result<(), WriteFailure> {
    let mut held = held();
    for lock in held.iter_mut() {
        if still_named(&lock.file, &lock.path) {
            continue;
        }
        let lost = |why: String| -> String {
            format!(
                "the lock file {} was deleted while this run held it, and {why}; stopping so \
                 that two jobs do not write one frame",
                lock.path.display()
            )
        };
        if let Some(folder) = lock.path.parent() {
            std::fs::create_dir_all(folder).map_err(|e| {
                WriteFailure::of_io(&e, lost(format!("it cannot be made again: {e}")))
            })?;
        }
        let file = OpenOptions::new()
            .read(true)
            .write(true)
            .create(true)
            .truncate(false)
            .open(&lock.path)
            .map_err(|e| WriteFailure::of_io(&e, lost(format!("it cannot be made again: {e}"))))?;
        for &(start, len) in &lock.ranges {
            match platform::lock_range(&file, start, len) {
                Ok(true) => {}
                Ok(false) => {
                    let (frame, pid, _) = platform::holder(&file, start, len);
                    let who = pid.map_or("another process".to_string(), |pid| {
                        format!("another process (pid {pid})")
                    });
                    let frame = frame_of(frame.unwrap_or(start))
                        .map_or(String::new(), |f| format!(" frame {f}"));
                    return Err(WriteFailure::transient(lost(format!(
                        "{who} has since locked{frame}"
                    ))));
                }
                Err(e) => {
                    let why = lost(format!("it cannot be locked again: {e}"));
                    return Err(WriteFailure::of_io(&e, why));
                }
            }
        }
        if !still_named(&file, &lock.path) {
            return Err(WriteFailure::transient(lost(
                "it keeps being replaced".to_string(),
            )));
        }
        // The old file (unlinked) goes, and our locks on it with it.
        lock.file = file;
    }
    Ok(())
}

/// Releases every lock this process holds (for a signal handler, before the process
/// exits): removes each lock file no other process holds a frame of, and the folders made
/// for it if they are empty. Returns how many locks were released.
pub fn abandon_locks() -> usize {
    let taken: Vec<Held> = std::mem::take(&mut *held());
    let count = taken.len();
    taken.into_iter().for_each(release);
    count
}

fn release(held: Held) {
    // Our own byte ranges never conflict with a lock we take over them, so the whole file
    // locks only when no other process holds a frame: then nobody needs the file.
    // A lock file deleted under us and made again by another job is that job's: left alone.
    if matches!(platform::lock_range(&held.file, 0, 0), Ok(true))
        && still_named(&held.file, &held.path)
    {
        let _ = std::fs::remove_file(&held.path);
    }
    drop(held.file);
    remove_empty(&held.created);
}

/// Byte ranges `(start, length)` to lock for `frames`: byte 0 for a still, `frame + 1e9` for a
/// frame, runs of consecutive frames merged.
fn byte_ranges(frames: &[Option<i64>]) -> Vec<(u64, u64)> {
    let mut bytes: Vec<u64> = frames.iter().map(|f| f.map_or(0, frame_byte)).collect();
    bytes.sort_unstable();
    bytes.dedup();
    let mut ranges: Vec<(u64, u64)> = Vec::new();
    for byte in bytes {
        match ranges.last_mut() {
            Some((start, len)) if *start + *len == byte => *len += 1,
            _ => ranges.push((byte, 1)),
        }
    }
    ranges
}

/// Frame numbers lie within ±[`MAX_FRAME_NUMBER`]: shifted by it (and one, byte 0 being a
/// still's), each has a byte of its own at a plain, positive offset.
fn frame_byte(frame: i64) -> u64 {
    (frame.clamp(-MAX_FRAME_NUMBER, MAX_FRAME_NUMBER) + MAX_FRAME_NUMBER) as u64 + 1
}

fn frame_of(byte: u64) -> Option<i64> {
    byte.checked_sub(1).map(|b| b as i64 - MAX_FRAME_NUMBER)
}

/// Makes `folder` and any missing folder above it; returns those it made, deepest first.
fn create_folders(folder: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut missing = Vec::new();
    let mut at = Some(folder);
    while let Some(dir) = at {
        if dir.as_os_str().is_empty() || dir.exists() {
            break;
        }
        missing.push(dir.to_path_buf());
        at = dir.parent();
    }
    std::fs::create_dir_all(folder)?;
    Ok(missing)
}

/// Removes the folders (deepest first) that are still empty.
fn remove_empty(folders: &[PathBuf]) {
    for folder in folders {
        if std::fs::remove_dir(folder).is_err() {
            break;
        }
    }
}

/// True when `path` still names the open `file` (no other job unlinked or replaced it).
fn still_named(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (file.metadata(), std::fs::metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        path.exists()
    }
}

#[cfg(unix)]
mod platform {
    use std::fs::File;

    use nix::errno::Errno;
    use nix::fcntl::{fcntl, FcntlArg};
    use nix::libc;

    fn flock(kind: libc::c_short, start: u64, len: u64) -> libc::flock {
        libc::flock {
            l_type: kind,
            l_whence: libc::SEEK_SET as libc::c_short,
            l_start: start as libc::off_t,
            l_len: len as libc::off_t,
            l_pid: 0,
        }
    }

    /// Takes a write lock on `len` bytes from `start` (0: to the end and beyond) without
    /// waiting: `Ok(false)` when another process holds some of them.
    pub fn lock_range(file: &File, start: u64, len: u64) -> std::io::Result<bool> {
        match fcntl(
            file,
            FcntlArg::F_SETLK(&flock(libc::F_WRLCK as _, start, len)),
        ) {
            Ok(_) => Ok(true),
            Err(Errno::EAGAIN | Errno::EACCES) => Ok(false),
            Err(e) => Err(e.into()),
        }
    }

    /// The first byte another process holds in the range, its pid (unknown on some network
    /// file systems), and whether the conflict is passing: the lock is gone by now, or it is
    /// on the whole file, which only a job releasing the file takes ([`super::release`]).
    pub fn holder(file: &File, start: u64, len: u64) -> (Option<u64>, Option<i32>, bool) {
        let mut query = flock(libc::F_WRLCK as _, start, len);
        match fcntl(file, FcntlArg::F_GETLK(&mut query)) {
            Ok(_) if query.l_type != libc::F_UNLCK as libc::c_short => (
                Some((query.l_start as u64).max(start)),
                (query.l_pid > 0).then_some(query.l_pid),
                query.l_start == 0 && query.l_len == 0,
            ),
            Ok(_) => (None, None, true),
            Err(_) => (None, None, false),
        }
    }
}

#[cfg(not(unix))]
mod platform {
    use std::fs::File;

    /// Without byte-range locks the whole file is locked: any two jobs on one sequence
    /// exclude each other.
    pub fn lock_range(file: &File, _start: u64, _len: u64) -> std::io::Result<bool> {
        match file.try_lock() {
            Ok(()) => Ok(true),
            Err(std::fs::TryLockError::WouldBlock) => Ok(false),
            Err(std::fs::TryLockError::Error(e)) => Err(e),
        }
    }

    pub fn holder(_file: &File, _start: u64, _len: u64) -> (Option<u64>, Option<i32>, bool) {
        (None, None, false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lock_files_are_hidden_and_named_after_the_pattern() {
        let lock = |raw: &str| lock_path(&PathPattern::parse(raw).unwrap());
        assert_eq!(
            lock("out/o.####.exr"),
            PathBuf::from("out/.o.####.exr.lock")
        );
        assert_eq!(
            lock("out/o.%04d.exr"),
            PathBuf::from("out/.o.####.exr.lock")
        );
        assert_eq!(lock("o.exr"), PathBuf::from("./.o.exr.lock"));
        // A `#` in a folder's name is part of the name, not a placeholder.
        assert_eq!(lock("/a/s_##/o.exr"), PathBuf::from("/a/s_##/.o.exr.lock"));
        assert_eq!(
            lock("take#2/o.%04d.exr"),
            PathBuf::from("take#2/.o.####.exr.lock")
        );
    }

    #[test]
    fn frames_become_merged_byte_ranges() {
        let frames = [Some(3), Some(1), Some(2), Some(7), Some(2)];
        let base = MAX_FRAME_NUMBER as u64 + 1;
        assert_eq!(byte_ranges(&frames), [(base + 1, 3), (base + 7, 1)]);
        assert_eq!(byte_ranges(&[None]), [(0, 1)]);
        // Negative frames have bytes of their own, and come back as themselves.
        let ranges = byte_ranges(&[Some(-2), Some(-1), Some(0)]);
        assert_eq!(ranges, [(base - 2, 3)]);
        assert_eq!(frame_of(base - 2), Some(-2));
        assert_eq!(frame_of(0), None);
    }

    #[test]
    fn a_lock_file_made_again_by_another_job_is_left_to_it() {
        let dir = tempfile::tempdir().unwrap();
        let output = PathPattern::parse(&format!("{}/o.####.exr", dir.path().display())).unwrap();
        let lock = OutputLock::acquire(&output, &[Some(1)]).unwrap();
        // Deleted under the job, and made again by another one.
        std::fs::remove_file(lock.path()).unwrap();
        std::fs::write(lock.path(), b"").unwrap();
        let path = lock.path().to_path_buf();
        drop(lock);
        assert!(path.exists(), "the other job's lock file was removed");
    }

    #[test]
    fn a_lock_is_released_and_its_file_removed_on_drop() {
        let dir = tempfile::tempdir().unwrap();
        let output =
            PathPattern::parse(&format!("{}/new/o.####.exr", dir.path().display())).unwrap();
        let lock = OutputLock::acquire(&output, &[Some(1), Some(2)]).unwrap();
        assert!(lock.path().exists());
        drop(lock);
        assert!(!dir.path().join("new/.o.####.exr.lock").exists());
        // The folder made for the lock was empty, so it went too.
        assert!(!dir.path().join("new").exists());
    }
}
