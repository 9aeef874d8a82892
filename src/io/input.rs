//! Opening inputs: every input file and preset is opened here, and must be a regular file
//! (issue 30: a named pipe hung a run, `/dev/zero` as a preset filled memory). A leaf of
//! `io`: it imports nothing of the crate.

use std::io::Read;
use std::path::Path;

/// Opens an input file for reading, refusing anything but a regular file (after links): a
/// named pipe would block the open (and the run, holding its lock) until a writer came, a
/// device such as /dev/zero never ends. On Unix the open itself does not wait (`O_NONBLOCK`,
/// which regular files ignore), and the check is made on the opened file, so a pipe put at
/// the path after an earlier check is refused too.
pub fn open_input(path: &Path) -> std::io::Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(nix::libc::O_NONBLOCK);
    }
    let file = options.open(path)?;
    let kind = file.metadata()?.file_type();
    if kind.is_file() {
        return Ok(file);
    }
    Err(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        format!(
            "not a regular file ({}); inputs must be files",
            describe(&kind)
        ),
    ))
}

/// What a file type that is not a regular file is, in words.
fn describe(kind: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a named pipe";
        }
        if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    if kind.is_dir() {
        "a folder"
    } else {
        "not a file"
    }
}

/// A whole input file's bytes, through [`open_input`].
pub fn read_input(path: &Path) -> std::io::Result<Vec<u8>> {
    let mut bytes = Vec::new();
    open_input(path)?.read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// A small text file (a preset) read whole, through [`open_input`], refused when larger than
/// `cap` bytes, so that a mistaken path cannot fill memory.
pub fn read_small_text(path: &Path, cap: u64) -> std::io::Result<String> {
    let file = open_input(path)?;
    let mut text = String::new();
    file.take(cap + 1).read_to_string(&mut text)?;
    if text.len() as u64 > cap {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "larger than {} KiB; a preset is a short text file",
                cap / 1024
            ),
        ));
    }
    Ok(text)
}
