//! Opening `eopnp solve`'s input file: regular files only (the rule of the library's COLMAP
//! readers, with the same messages). A named pipe, a device (`/dev/zero`),
//! a socket or a directory where a file is expected is refused before it is opened, so that
//! opening cannot block (a FIFO without a writer) and reading cannot be endless (`/dev/zero`);
//! the size of the file is known before the first byte is read.

use std::fs::{File, FileType};
use std::io;
use std::path::Path;

/// Why a path cannot be read as an input file.
#[derive(Debug)]
pub(crate) enum OpenError {
    /// Not a regular file: what it is instead (`"a named pipe (FIFO)"`, ...).
    NotRegular(&'static str),
    /// The path cannot be inspected or opened.
    Io(io::Error),
}

/// The message of a [`OpenError::NotRegular`]: "not a regular file (it is a named pipe
/// (FIFO))".
pub(crate) fn not_regular_message(what: &str) -> String {
    format!("not a regular file (it is {what})")
}

/// Opens `path` (symbolic links followed) for reading if it is a regular file; returns the
/// file and its size at the time it was opened.
pub(crate) fn open_regular(path: &Path) -> Result<(File, u64), OpenError> {
    let meta = std::fs::metadata(path).map_err(OpenError::Io)?;
    if !meta.is_file() {
        return Err(OpenError::NotRegular(describe(&meta.file_type())));
    }
    let file = File::open(path).map_err(OpenError::Io)?;
    // The path may have been replaced between the check and the open: check what was opened.
    let meta = file.metadata().map_err(OpenError::Io)?;
    if !meta.is_file() {
        return Err(OpenError::NotRegular(describe(&meta.file_type())));
    }
    Ok((file, meta.len()))
}

/// What a file that is not a regular file is, for messages.
fn describe(t: &FileType) -> &'static str {
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a named pipe (FIFO)";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "a special file"
}

/// `n` bytes for messages: `1 GiB`, `64 KiB`, `3 MiB`, else `12345 bytes`.
pub(crate) fn bytes_text(n: u64) -> String {
    for (unit, name) in [
        (1u64 << 40, "TiB"),
        (1 << 30, "GiB"),
        (1 << 20, "MiB"),
        (1 << 10, "KiB"),
    ] {
        if n >= unit && n.is_multiple_of(unit) {
            return format!("{} {name}", n / unit);
        }
    }
    if n == 1 {
        "1 byte".to_string()
    } else {
        format!("{n} bytes")
    }
}
