//! The output lock: one hidden file per output folder (`out/.shutter.lock` for
//! `-o out/o.####.exr`), in which each job holds an advisory lock on the files it writes. A
//! second job on any of the same files fails at once, naming the process that holds them;
//! jobs on other files of the folder (a farm's chunks, other sequences) run side by side. The
//! kernel releases a dead holder's locks, so a lock file a killed run left behind is simply
//! taken over.
//!
//! A file's lock is keyed by its name, not by the pattern or frame number that made it:
//! `o.#.exr` and `o.####.exr` both write `o.1234.exr` for frame 1234, and a still written as
//! `-o o.1234.exr` is that file too, so each of them must exclude the others (keyed by the
//! pattern's spelling before, two such jobs wrote one file side by side, both exiting 0). On
//! Unix these are `fcntl` byte-range locks, one byte per file ([`name_byte`]): consecutive
//! frames of a sequence have consecutive bytes, so a chunk's frames lock as one range, and
//! `F_GETLK` says which of them another process holds. Whole-file locks (`flock`, std's
//! `File::lock`, fs4) were the simpler choice, rejected because they make chunks of one
//! sequence refuse each other. Elsewhere the whole file is locked (std).
//!
//! The lock file is removed when the run ends (normally, with an error, or by a caught
//! signal through [`abandon_locks`]) by the last job holding any file of it: a job first
//! takes a lock on the whole file, which succeeds only when no other process holds a file,
//! and unlinks while holding it. A job that opened the file just before that unlink finds,
//! once locked, that the path names another file (or none) and starts again.
//!
//! A lock file deleted under a running job (by hand) would let a second job lock a new file
//! at the same path and write the same frames: before each frame is renamed into place the
//! job checks that its lock is still the file its path names ([`verify_held`]), takes it
//! again on a new file when it is not, and stops (exit 75) without writing the frame when
//! another job holds any of its files there. Deleted with its folder, it stops (exit 75)
//! too: the frames it had written went with the folder, and a rerun writes them again. It never
//! removes a lock file that is not its own.

use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};
use std::sync::{Mutex, MutexGuard, PoisonError};

use crate::error::{Problem, ProblemKind, WriteFailure};
use crate::io::sequence::{name_start, PathPattern};

/// The name of the lock file in an output folder.
pub const LOCK_NAME: &str = ".shutter.lock";

/// The lock file of an output: hidden, in the output folder, one for every file written there
/// (a placeholder is only ever in the file name: [`PathPattern::parse`]).
pub fn lock_path(output: &PathPattern) -> PathBuf {
    let folder = &output.raw[..name_start(&output.raw)];
    let folder = if folder.is_empty() { "." } else { folder };
    Path::new(folder).join(LOCK_NAME)
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
    /// The bytes of its files.
    keys: Keys,
    /// Folders made for the lock file, deepest first: removed again if still empty.
    created: Vec<PathBuf>,
    /// The output folder as it was when the lock was taken ([`folder_id`]).
    folder: Option<(u64, u64)>,
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
        let keys = Keys::of(output, frames);
        let result = (|| {
            // Waits on a passing conflict (below), a few milliseconds each.
            let mut waits = 0;
            let mut attempt = 0;
            'attempts: while attempt < ATTEMPTS {
                let file = open_shared(&path).map_err(|e| {
                    fail_with(
                        &e,
                        format!(
                            "cannot open the lock file: {e} (one for every job writing in the \
                             folder, whoever runs it: made writable to all by shutter; one \
                             another user made otherwise may be removed while no job runs)"
                        ),
                    )
                })?;
                for &(start, len) in &keys.ranges {
                    match platform::lock_range(&file, start, len) {
                        Ok(true) => {}
                        Ok(false) => {
                            let (byte, pid, passing) = platform::holder(&file, start, len);
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
                            let frame = keys.frame_at(byte.unwrap_or(start));
                            let who = match pid {
                                Some(pid) => format!("another process (pid {pid})"),
                                None => "another process".to_string(),
                            };
                            return Err(Problem::new(
                                ProblemKind::Busy,
                                output.path(frame),
                                format!(
                                    "{who} is writing this file (lock {}); wait for it to \
                                     finish, or stop it, or write elsewhere with -o",
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
                    folder: folder_id(folder),
                    path: path.clone(),
                    file,
                    keys,
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
/// before a frame is renamed into place. Someone may have deleted the lock file under a
/// running job, and a second job on the same frames would then lock a new file and run
/// beside it: a lock whose file is gone is taken again on a new file at the same path, and
/// when another process holds any of its frames there, this fails, naming it, so the frame is
/// not written (the run stops with exit 75) and the two jobs do not write one frame. A lock
/// whose folder is gone fails too (transient): the outputs written there went with it.
/// Without held locks (a library caller) nothing is checked.
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
        // Gone with its folder (made again or not: another folder), the outputs written
        // into it went too: the run stops so that a rerun writes them again, rather than
        // make the folder again and end well without them.
        let folder = lock.path.parent().unwrap_or(Path::new("."));
        if lock.folder.is_some() && folder_id(folder) != lock.folder {
            return Err(WriteFailure::transient(format!(
                "the output folder {} was removed while this run wrote into it, and the \
                 frames written into it before with it; run again (with --skip-existing) to \
                 write them",
                folder.display()
            )));
        }
        let file = open_shared(&lock.path)
            .map_err(|e| WriteFailure::of_io(&e, lost(format!("it cannot be made again: {e}"))))?;
        for &(start, len) in &lock.keys.ranges {
            match platform::lock_range(&file, start, len) {
                Ok(true) => {}
                Ok(false) => {
                    let (byte, pid, _) = platform::holder(&file, start, len);
                    let who = pid.map_or("another process".to_string(), |pid| {
                        format!("another process (pid {pid})")
                    });
                    let frame = lock
                        .keys
                        .frame_at(byte.unwrap_or(start))
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

/// The lock bytes of a job's files.
#[derive(Debug)]
struct Keys {
    /// Byte ranges `(start, length)` to lock: runs of consecutive bytes merged.
    ranges: Vec<(u64, u64)>,
    /// Each file's byte and frame, sorted by byte.
    frames: Vec<(u64, Option<i64>)>,
}

impl Keys {
    fn of(output: &PathPattern, frames: &[Option<i64>]) -> Keys {
        let mut keyed: Vec<(u64, Option<i64>)> = frames
            .iter()
            .map(|&frame| {
                let path = output.path(frame);
                let name = path.file_name().unwrap_or(path.as_os_str());
                // Case folded: on a file system that folds case (macOS, SMB shares)
                // `Shot.0001.exr` and `shot.0001.exr` are one file. (Where it does not, two
                // such names only wait for each other.)
                (name_byte(&name_bytes(name).to_ascii_lowercase()), frame)
            })
            .collect();
        keyed.sort_unstable();
        keyed.dedup_by_key(|k| k.0);
        let mut ranges: Vec<(u64, u64)> = Vec::new();
        // Without byte-range locks the whole file is locked, once: a second lock through the
        // same handle would refuse the job itself (Windows).
        #[cfg(not(unix))]
        keyed.truncate(1);
        for &(byte, _) in &keyed {
            match ranges.last_mut() {
                Some((start, len)) if *start + *len == byte => *len += 1,
                _ => ranges.push((byte, 1)),
            }
        }
        Keys {
            ranges,
            frames: keyed,
        }
    }

    /// The frame whose file has `byte` (none for a still, or a byte not ours).
    fn frame_at(&self, byte: u64) -> Option<i64> {
        let at = self.frames.binary_search_by_key(&byte, |k| k.0).ok()?;
        self.frames[at].1
    }
}

#[cfg(unix)]
fn name_bytes(name: &std::ffi::OsStr) -> Vec<u8> {
    use std::os::unix::ffi::OsStrExt;
    name.as_bytes().to_vec()
}

#[cfg(not(unix))]
fn name_bytes(name: &std::ffi::OsStr) -> Vec<u8> {
    name.to_string_lossy().into_owned().into_bytes()
}

/// The lock byte of the file named `name` (one byte per name; byte 0 is left for the whole
/// file's lock of a job releasing it). The name's last run of digits (the frame number of
/// every pattern whose placeholder comes last) is kept as its number and length, the rest of
/// the name hashed (64-bit FNV-1a, 28 bits kept), so that one sequence's consecutive frames
/// have consecutive bytes; a name without such a number (none, or one longer than 15 digits
/// or over 2^30) is hashed whole. `[hash: 28 bits][digits: 4][number: 30]`, plus one: below
/// 2^62, inside a 64-bit `off_t`. Two names share a byte only when they are the same name, or by
/// a hash collision (one chance in 2^28 for two sequences in one folder, and then only on
/// frames of the same number), which makes a job wait, never two jobs write one file.
fn name_byte(name: &[u8]) -> u64 {
    const NUMBER: u64 = (1 << 30) - 1;
    let number = name.iter().rposition(u8::is_ascii_digit).and_then(|last| {
        let end = last + 1;
        let start = name[..end]
            .iter()
            .rposition(|b| !b.is_ascii_digit())
            .map_or(0, |i| i + 1);
        let digits = &name[start..end];
        let value = std::str::from_utf8(digits).ok()?.parse::<u64>().ok()?;
        (digits.len() <= 15 && value <= NUMBER).then(|| {
            let rest = fnv1a(&[&name[..start], &[0xFF], &name[end..]]);
            (rest, (digits.len() as u64) << 30 | value)
        })
    });
    let (hash, low) = number.unwrap_or_else(|| {
        let hash = fnv1a(&[name]);
        (hash, hash & NUMBER)
    });
    let byte = (hash >> 36) << 34 | low;
    // Where a lock offset has 32 bits (a 32-bit target's `off_t`), folded into them: a
    // sequence's frames stay consecutive, other names share bytes more often (and wait).
    match std::mem::size_of::<OffT>() {
        4 => 1 + byte % (i32::MAX as u64 - 1),
        _ => 1 + byte,
    }
}

#[cfg(unix)]
type OffT = nix::libc::off_t;
#[cfg(not(unix))]
type OffT = i64;

/// 64-bit FNV-1a over the parts, one after another (stable across runs and machines, as
/// names on disk must be).
pub(crate) fn fnv1a(parts: &[&[u8]]) -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for &byte in parts.iter().flat_map(|p| p.iter()) {
        hash ^= u64::from(byte);
        hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
    }
    hash
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

/// Opens the lock file for locking, making it where it is missing writable to every user
/// (mode 0666, whatever the umask): one lock file serves every job writing in the folder,
/// and a job of another user must be able to lock it too (an `fcntl` write lock needs the
/// file open for writing).
fn open_shared(path: &Path) -> std::io::Result<File> {
    let open = || {
        OpenOptions::new()
            .read(true)
            .write(true)
            .truncate(false)
            .open(path)
    };
    // A few times: a file found there may be unlinked by a job releasing it before it opens.
    let mut tries = 0;
    loop {
        tries += 1;
        let made = OpenOptions::new()
            .read(true)
            .write(true)
            .create_new(true)
            .open(path);
        match made {
            Ok(file) => {
                #[cfg(unix)]
                {
                    use std::os::unix::fs::PermissionsExt;
                    let _ = file.set_permissions(std::fs::Permissions::from_mode(0o666));
                }
                return Ok(file);
            }
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => match open() {
                Err(e) if e.kind() == std::io::ErrorKind::NotFound && tries < 5 => continue,
                opened => return opened,
            },
            Err(e) => return Err(e),
        }
    }
}

/// What `folder` is (device and inode, Unix), while it is a folder that is still linked
/// (a removed working folder still answers to `.`, with no link left); `None` otherwise, and
/// elsewhere than Unix (where a removed folder is told by its path alone).
fn folder_id(folder: &Path) -> Option<(u64, u64)> {
    let folder = if folder.as_os_str().is_empty() {
        Path::new(".")
    } else {
        folder
    };
    let meta = std::fs::metadata(folder).ok().filter(|m| m.is_dir())?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        (meta.nlink() > 0).then_some((meta.dev(), meta.ino()))
    }
    #[cfg(not(unix))]
    {
        let _ = meta;
        Some((0, 0))
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
    fn one_hidden_lock_file_per_output_folder() {
        let lock = |raw: &str| lock_path(&PathPattern::parse(raw).unwrap());
        assert_eq!(lock("out/o.####.exr"), PathBuf::from("out/.shutter.lock"));
        assert_eq!(lock("out/b.%04d.exr"), PathBuf::from("out/.shutter.lock"));
        assert_eq!(lock("o.exr"), PathBuf::from("./.shutter.lock"));
        // A `#` in a folder's name is part of the name, not a placeholder.
        assert_eq!(
            lock("/a/s_##/o.exr"),
            PathBuf::from("/a/s_##/.shutter.lock")
        );
        assert_eq!(
            lock("take#2/o.%04d.exr"),
            PathBuf::from("take#2/.shutter.lock")
        );
    }

    /// A file has one byte whatever pattern names it; other files have other bytes.
    #[test]
    fn a_file_has_the_same_byte_whatever_pattern_names_it() {
        let keys = |raw: &str, frames: &[Option<i64>]| {
            let k = Keys::of(&PathPattern::parse(raw).unwrap(), frames);
            k.frames.iter().map(|f| f.0).collect::<Vec<_>>()
        };
        let four = keys("out/o.####.exr", &[Some(1234)]);
        assert_eq!(keys("out/o.#.exr", &[Some(1234)]), four);
        assert_eq!(keys("out/o.%04d.exr", &[Some(1234)]), four);
        assert_eq!(keys("out/o.$F2.exr", &[Some(1234)]), four);
        assert_eq!(keys("out/o.1234.exr", &[None]), four);
        // o.1.exr and o.0001.exr are two files; so are frames 1234 of other sequences.
        assert_ne!(
            keys("out/o.#.exr", &[Some(1)]),
            keys("out/o.####.exr", &[Some(1)])
        );
        assert_ne!(keys("out/p.####.exr", &[Some(1234)]), four);
        assert_ne!(keys("out/o.####.tif", &[Some(1234)]), four);
        assert_ne!(
            keys("out/o.-###.exr", &[Some(234)]),
            keys("out/o.####.exr", &[Some(234)])
        );
        // Case folded, as file systems that fold it see one file.
        assert_eq!(keys("out/O.####.EXR", &[Some(1234)]), four);
        // Names without a number, or with one too long to keep, are hashed whole.
        assert_ne!(keys("o.exr", &[None]), keys("p.exr", &[None]));
        let long = keys("o.12345678901234567890.exr", &[None]);
        assert_ne!(long, keys("o.12345678901234567891.exr", &[None]));
        assert!(long[0] > 0 && long[0] < 1 << 62);
    }

    #[test]
    fn consecutive_frames_become_one_byte_range() {
        let output = PathPattern::parse("o.####.exr").unwrap();
        let keys = Keys::of(&output, &[Some(3), Some(1), Some(2), Some(7), Some(2)]);
        let first = keys.frames[0].0;
        assert_eq!(keys.ranges, [(first, 3), (first + 6, 1)]);
        assert_eq!(keys.frame_at(first + 1), Some(2));
        assert_eq!(keys.frame_at(first + 6), Some(7));
        assert_eq!(keys.frame_at(first + 3), None);
        // Negative frames (`-002`) and frames past the width (`12345`) have bytes of their
        // own, and are named back.
        let keys = Keys::of(&output, &[Some(-2), Some(-1), Some(12345), Some(2)]);
        assert_eq!(keys.ranges.len(), 3);
        for frame in [-2, -1, 12345, 2] {
            let byte = keys.frames.iter().find(|f| f.1 == Some(frame)).unwrap().0;
            assert_eq!(keys.frame_at(byte), Some(frame));
        }
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
        // Writable to every user whatever the umask: one file serves every job in the folder.
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            let mode = std::fs::metadata(lock.path()).unwrap().permissions().mode();
            assert_eq!(mode & 0o777, 0o666);
        }
        drop(lock);
        assert!(!dir.path().join("new/.shutter.lock").exists());
        // The folder made for the lock was empty, so it went too.
        assert!(!dir.path().join("new").exists());
    }
}
