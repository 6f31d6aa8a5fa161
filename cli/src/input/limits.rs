//! The limits of `eopnp solve`'s input: its size (`--max-input-size`) and the length of a CSV
//! line or a JSON string or number, enforced while reading.

use std::fmt;
use std::io::{self, BufRead, Read};

use crate::source::bytes_text;
use crate::Failure;

/// The largest input `eopnp solve` reads by default, from a file or from standard input:
/// 1 GiB (`--max-input-size` changes it).
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// The longest CSV line (and quoted record spanning lines) and the longest JSON string or
/// number `eopnp solve` reads: 64 KiB. A correspondence is one short line; comment lines may
/// be longer (they are skipped unread).
pub const MAX_LINE_BYTES: usize = 1 << 16;

/// Limits of the input of `eopnp solve`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// The largest input, in bytes. Default [`MAX_INPUT_BYTES`].
    pub max_input_bytes: u64,
    /// The longest CSV line or record, JSON string or number, in bytes. Default
    /// [`MAX_LINE_BYTES`].
    pub max_line_bytes: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Limits {
            max_input_bytes: MAX_INPUT_BYTES,
            max_line_bytes: MAX_LINE_BYTES,
        }
    }
}

pub(super) fn too_large(name: &str, cap: u64) -> Failure {
    Failure::input(format!(
        "{name}: larger than {}, the input size limit of `eopnp solve` (--max-input-size)",
        bytes_text(cap)
    ))
}

/// The error a [`Capped`] source returns past its cap.
#[derive(Debug)]
struct OverCap;

impl fmt::Display for OverCap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("input size limit reached")
    }
}

impl std::error::Error for OverCap {}

/// A source limited to `left` more bytes: reading past them is an error ([`OverCap`]).
pub(super) struct Capped<R> {
    pub(super) inner: R,
    pub(super) left: u64,
}

impl<R: BufRead> Read for Capped<R> {
    fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
        let avail = self.fill_buf()?;
        let n = avail.len().min(out.len());
        out[..n].copy_from_slice(&avail[..n]);
        self.consume(n);
        Ok(n)
    }
}

impl<R: BufRead> BufRead for Capped<R> {
    fn fill_buf(&mut self) -> io::Result<&[u8]> {
        let left = self.left;
        let buf = self.inner.fill_buf()?;
        if left == 0 && !buf.is_empty() {
            return Err(io::Error::other(OverCap));
        }
        let n = usize::try_from(left).map_or(buf.len(), |l| l.min(buf.len()));
        Ok(&buf[..n])
    }

    fn consume(&mut self, n: usize) {
        self.left -= n as u64;
        self.inner.consume(n);
    }
}

/// The failure of a read error: the size limit, or the I/O error.
pub(super) fn read_failure(name: &str, e: &io::Error, limits: &Limits) -> Failure {
    if e.get_ref().is_some_and(|i| i.is::<OverCap>()) {
        too_large(name, limits.max_input_bytes)
    } else {
        Failure::input(format!("{name}: {e}"))
    }
}
