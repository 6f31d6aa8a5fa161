//! `eopnp solve`'s input: a correspondence file (CSV or JSON) or standard input, read into a
//! [`Problem`]. One file per job: this one opens the input and picks the format; `limits`
//! bounds what is read; `csv` and `json` parse.
//!
//! Input is streamed, never held whole: CSV line by line (a line, or a quoted record spanning
//! lines, of at most [`Limits::max_line_bytes`]), JSON through serde_json's reader (a string
//! or number of at most that length). The input is at most [`Limits::max_input_bytes`] long
//! (`--max-input-size`), and must be a regular file or standard input (`-`): a FIFO, a device
//! such as `/dev/zero` or a directory is refused before it is opened. Memory is what is
//! returned (40 bytes per correspondence, times up to 3 while the vectors grow) plus the
//! buffers (`cli/tests/reader_memory.rs` measures it).

mod csv;
mod json;
mod limits;

use std::io::{self, BufRead, BufReader, Read};
use std::path::Path;

use eopnp::camera::Camera;
use nalgebra::{Point2, Point3};

use crate::source::{not_regular_message, open_regular, OpenError};
use crate::Failure;
use csv::read_csv;
use json::read_json;
use limits::{read_failure, too_large, Capped};
pub use limits::{Limits, MAX_INPUT_BYTES, MAX_LINE_BYTES};

/// A parsed problem: camera, pixels and world points.
#[derive(Debug, PartialEq)]
pub struct Problem {
    pub(crate) camera: Camera,
    pub(crate) pixels: Vec<Point2<f64>>,
    pub(crate) world: Vec<Point3<f64>>,
}

impl Problem {
    /// The number of correspondences.
    #[must_use]
    pub fn correspondences(&self) -> usize {
        self.world.len()
    }
}

/// Parses `--camera "MODEL P1 P2 ..."`.
fn parse_camera_arg(s: &str) -> Result<Camera, Failure> {
    let mut it = s.split_whitespace();
    let model = it
        .next()
        .ok_or_else(|| Failure::input("--camera: empty; expected \"MODEL P1 P2 ...\""))?;
    let mut params = Vec::new();
    for tok in it {
        let v: f64 = tok
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| Failure::input(format!("--camera: bad parameter \"{}\"", shown(tok))))?;
        params.push(v);
    }
    Camera::from_colmap(model, 0, 0, params).map_err(|e| Failure::input(format!("--camera: {e}")))
}

/// The name standard input goes by in messages.
pub const STDIN_NAME: &str = "<stdin>";

/// An input format named by `--format`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Format {
    /// Comma-, semicolon- or tab-separated values with a header.
    Csv,
    /// `{"camera": ..., "points2d": [...], "points3d": [...]}`.
    Json,
}

impl Format {
    fn ext(self) -> &'static str {
        match self {
            Format::Csv => "csv",
            Format::Json => "json",
        }
    }
}

/// Reads a CSV or JSON problem from the file `path`, or from standard input if `path` is `-`.
///
/// The format is `format` if given; otherwise the file's extension (`.csv`, `.json`) or, for
/// standard input and other extensions, the content (JSON if it starts with `{`). The file
/// must be a regular file; inputs larger than `limits.max_input_bytes` are refused (a file
/// before it is read).
pub fn read_problem(
    path: &Path,
    format: Option<Format>,
    camera_arg: Option<&str>,
    limits: &Limits,
) -> Result<Problem, Failure> {
    let format_ext = format.map(Format::ext);
    if path.as_os_str() == "-" {
        let stdin = io::stdin().lock();
        return read_problem_from(STDIN_NAME, stdin, format_ext, camera_arg, limits);
    }
    let name = path.display().to_string();
    let (file, len) = open_regular(path).map_err(|e| match e {
        OpenError::NotRegular(what) => Failure::input(format!(
            "{name}: {}; the input must be a regular file, or `-` for standard input",
            not_regular_message(what)
        )),
        OpenError::Io(e) => Failure::input(format!("{name}: {e}")),
    })?;
    if len > limits.max_input_bytes {
        return Err(too_large(&name, limits.max_input_bytes));
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    // Never more than the size checked (the file may grow while it is read).
    let src = BufReader::with_capacity(1 << 16, file.take(len));
    let ext = format_ext.or(ext.as_deref());
    read_problem_from(&name, src, ext, camera_arg, limits)
}

/// The buffered bytes of `src`, more read if needed (empty at the end of the input).
pub(crate) fn fill<R: BufRead>(src: &mut R) -> io::Result<&[u8]> {
    while let Err(e) = src.fill_buf() {
        if e.kind() != io::ErrorKind::Interrupted {
            return Err(e);
        }
    }
    src.fill_buf()
}

/// Where parsing starts, after a UTF-8 byte-order mark and, when the format is sniffed, the
/// leading whitespace.
pub(crate) struct Start {
    /// The 1-based line parsing starts on.
    line: usize,
    /// The characters of that line already consumed (whitespace).
    column: usize,
    /// The start of a byte-order mark that is not one, to be read again; or the whitespace
    /// consumed on the current line (kept up to `keep` bytes), given back to the CSV reader.
    replay: Vec<u8>,
    /// Whether the input is JSON.
    json: bool,
}

/// Consumes a byte-order mark and, unless `ext` names the format, the leading ASCII
/// whitespace, to decide the format: JSON when the first character is `{`. Of the whitespace
/// on the line of that character, at most `keep` bytes are kept for [`Start::replay`].
fn start<R: BufRead>(src: &mut R, ext: Option<&str>, keep: usize) -> io::Result<Start> {
    const BOM: &[u8] = b"\xef\xbb\xbf";
    let mut matched = 0;
    while matched < BOM.len() && fill(src)?.first() == Some(&BOM[matched]) {
        src.consume(1);
        matched += 1;
    }
    let replay = if matched == BOM.len() {
        Vec::new()
    } else {
        BOM[..matched].to_vec()
    };
    let mut s = Start {
        line: 1,
        column: 0,
        replay,
        json: ext == Some("json"),
    };
    if matches!(ext, Some("json" | "csv")) || !s.replay.is_empty() {
        return Ok(s);
    }
    loop {
        let buf = fill(src)?;
        let end = buf.iter().position(|b| !b.is_ascii_whitespace());
        let ws = &buf[..end.unwrap_or(buf.len())];
        for &b in ws {
            if b == b'\n' {
                s.line += 1;
                s.column = 0;
                s.replay.clear();
            } else {
                s.column += 1;
                if s.replay.len() < keep {
                    s.replay.push(b);
                }
            }
        }
        let n = ws.len();
        match end {
            Some(i) => {
                s.json = buf[i] == b'{';
                src.consume(n);
                if s.json {
                    s.replay.clear();
                }
                return Ok(s);
            }
            None if n == 0 => return Ok(s),
            None => src.consume(n),
        }
    }
}

/// Reads a CSV or JSON problem from `src`, named `name` in messages, streaming within `limits`.
/// `ext` is `"json"`, `"csv"`, or anything else or nothing: then JSON when the text starts
/// with `{`. A UTF-8 byte-order mark at the start is ignored.
pub fn read_problem_from(
    name: &str,
    src: impl BufRead,
    ext: Option<&str>,
    camera_arg: Option<&str>,
    limits: &Limits,
) -> Result<Problem, Failure> {
    let camera_arg = camera_arg.map(parse_camera_arg).transpose()?;
    let mut src = Capped {
        inner: src,
        left: limits.max_input_bytes,
    };
    let mut start = start(&mut src, ext, limits.max_line_bytes.saturating_add(1))
        .map_err(|e| read_failure(name, &e, limits))?;
    let src = io::Cursor::new(std::mem::take(&mut start.replay)).chain(src);
    if start.json {
        read_json(name, src, camera_arg, &start, limits)
    } else {
        let camera = camera_arg.ok_or_else(|| {
            Failure::input(format!(
                "{name}: a CSV file needs the camera: --camera \"MODEL P1 P2 ...\", e.g. \
                 --camera \"SIMPLE_RADIAL 1245.65 600 800 0.0577\""
            ))
        })?;
        read_csv(name, src, camera, start.line, limits)
    }
}

/// Parses the contents of a problem file named `name` (for messages) with extension `ext`
/// (`"json"`, `"csv"`, or anything else: JSON when the text starts with `{`), with the default
/// [`Limits`]. A UTF-8 byte-order mark at the start is ignored.
pub fn parse_problem(
    name: &str,
    bytes: &[u8],
    ext: Option<&str>,
    camera_arg: Option<&str>,
) -> Result<Problem, Failure> {
    read_problem_from(name, bytes, ext, camera_arg, &Limits::default())
}

/// `s` for a message: control and other invisible characters escaped (`\u{1}`, `\t`), quotes
/// as they are; at most 60 characters.
pub(crate) fn shown(s: &str) -> String {
    let mut escaped = String::with_capacity(s.len());
    for c in s.chars() {
        if c == '"' || c == '\'' {
            escaped.push(c);
        } else {
            escaped.extend(c.escape_debug());
        }
    }
    truncate(&escaped)
}

fn truncate(s: &str) -> String {
    if s.chars().count() > 60 {
        let mut t: String = s.chars().take(60).collect();
        t.push_str("...");
        t
    } else {
        s.to_string()
    }
}

#[cfg(test)]
#[path = "../../tests/unit/input.rs"]
mod tests;
