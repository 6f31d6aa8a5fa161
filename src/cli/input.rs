//! `eopnp solve`: correspondence files (CSV, JSON) in, pose JSON out.
//!
//! Input is streamed, never held whole: CSV line by line (a line, or a quoted record spanning
//! lines, of at most [`Limits::max_line_bytes`]), JSON through serde_json's reader (a string
//! or number of at most that length). The input is at most [`Limits::max_input_bytes`] long
//! (`--max-input-size`), and must be a regular file or standard input (`-`): a FIFO, a device
//! such as `/dev/zero` or a directory is refused before it is opened. Memory is what is
//! returned (40 bytes per correspondence, times up to 3 while the vectors grow) plus the
//! buffers (`tests/reader_memory.rs` measures it).

use std::fmt;
use std::io::{self, BufRead, BufReader, Read};
use std::path::Path;

use crate::camera::Camera;
use crate::source::{bytes_text, not_regular_message, open_regular, OpenError};
use crate::PnpError;
use crate::Solver;
use nalgebra::{Point2, Point3};
use serde::de::{DeserializeSeed, Error as _, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer};
use serde_json::json;

use super::Failure;

/// A parsed problem: camera, pixels and world points.
#[derive(Debug, PartialEq)]
pub struct Problem {
    camera: Camera,
    pixels: Vec<Point2<f64>>,
    world: Vec<Point3<f64>>,
}

impl Problem {
    /// The number of correspondences.
    #[must_use]
    pub fn correspondences(&self) -> usize {
        self.world.len()
    }
}

/// The most parameters a JSON camera may list (the largest model has 18).
const MAX_CAMERA_PARAMS: usize = 64;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonCamera {
    model: String,
    #[serde(deserialize_with = "camera_params")]
    params: Vec<f64>,
    #[serde(default)]
    width: u64,
    #[serde(default)]
    height: u64,
}

/// At most [`MAX_CAMERA_PARAMS`] numbers.
fn camera_params<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
    struct Params;
    impl<'de> Visitor<'de> for Params {
        type Value = Vec<f64>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            write!(f, "an array of at most {MAX_CAMERA_PARAMS} numbers")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Vec<f64>, A::Error> {
            let mut v = Vec::new();
            while let Some(x) = seq.next_element()? {
                if v.len() == MAX_CAMERA_PARAMS {
                    return Err(A::Error::custom(format!(
                        "more than {MAX_CAMERA_PARAMS} camera parameters"
                    )));
                }
                v.push(x);
            }
            Ok(v)
        }
    }
    d.deserialize_seq(Params)
}

/// The keys of a JSON problem.
#[derive(Deserialize)]
#[serde(field_identifier, rename_all = "lowercase")]
enum Field {
    Camera,
    Points2d,
    Points3d,
}

/// A JSON problem as read: the file's camera (validated unless `--camera` replaces it) and the
/// points.
struct JsonProblem {
    camera: Option<Camera>,
    points2d: Vec<Point2<f64>>,
    points3d: Vec<Point3<f64>>,
}

/// Deserializes a [`JsonProblem`]. Errors found in the values (a bad camera, point counts that
/// differ) are raised where the value ends, so that serde_json gives their line and column.
struct ProblemSeed {
    /// `--camera` is given: the file's camera is read but not used, nor checked.
    camera_given: bool,
}

impl<'de> DeserializeSeed<'de> for ProblemSeed {
    type Value = JsonProblem;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<JsonProblem, D::Error> {
        d.deserialize_map(self)
    }
}

impl<'de> Visitor<'de> for ProblemSeed {
    type Value = JsonProblem;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("an object with \"camera\", \"points2d\" and \"points3d\"")
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<JsonProblem, A::Error> {
        let mut camera = None;
        let mut points2d: Option<Vec<Point2<f64>>> = None;
        let mut points3d: Option<Vec<Point3<f64>>> = None;
        while let Some(key) = map.next_key::<Field>()? {
            match key {
                Field::Camera if camera.is_some() => {
                    return Err(A::Error::duplicate_field("camera"))
                }
                Field::Points2d if points2d.is_some() => {
                    return Err(A::Error::duplicate_field("points2d"))
                }
                Field::Points3d if points3d.is_some() => {
                    return Err(A::Error::duplicate_field("points3d"))
                }
                Field::Camera => {
                    let c = map.next_value::<Option<JsonCamera>>()?;
                    camera = Some(match c {
                        Some(c) if !self.camera_given => Some(
                            Camera::from_colmap(&c.model, c.width, c.height, c.params)
                                .map_err(|e| A::Error::custom(format!("camera: {e}")))?,
                        ),
                        _ => None,
                    });
                }
                Field::Points2d => {
                    let to = |a: [f64; 2]| Point2::new(a[0], a[1]);
                    points2d = Some(map.next_value_seed(Points(to))?);
                }
                Field::Points3d => {
                    let to = |a: [f64; 3]| Point3::new(a[0], a[1], a[2]);
                    points3d = Some(map.next_value_seed(Points(to))?);
                }
            }
            if let (Some(p), Some(w)) = (&points2d, &points3d) {
                if p.len() != w.len() {
                    return Err(A::Error::custom(format!(
                        "{} points2d but {} points3d; they must correspond one to one",
                        p.len(),
                        w.len()
                    )));
                }
            }
        }
        Ok(JsonProblem {
            camera: camera.flatten(),
            points2d: points2d.ok_or_else(|| A::Error::missing_field("points2d"))?,
            points3d: points3d.ok_or_else(|| A::Error::missing_field("points3d"))?,
        })
    }
}

/// An array of points of `N` coordinates, each converted as it is read (no intermediate
/// vector).
struct Points<const N: usize, T>(fn([f64; N]) -> T);

impl<'de, const N: usize, T> DeserializeSeed<'de> for Points<N, T> {
    type Value = Vec<T>;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Vec<T>, D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de, const N: usize, T> Visitor<'de> for Points<N, T> {
    type Value = Vec<T>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "an array of points of {N} coordinates")
    }

    fn visit_seq<S: SeqAccess<'de>>(self, mut seq: S) -> Result<Vec<T>, S::Error> {
        let mut v = Vec::new();
        while let Some(Coords(a)) = seq.next_element::<Coords<N>>()? {
            v.push((self.0)(a));
        }
        v.shrink_to_fit();
        Ok(v)
    }
}

/// A point: an array of exactly `N` numbers.
struct Coords<const N: usize>([f64; N]);

impl<'de, const N: usize> Deserialize<'de> for Coords<N> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_tuple(N, CoordsVisitor::<N>)
    }
}

struct CoordsVisitor<const N: usize>;

impl<'de, const N: usize> Visitor<'de> for CoordsVisitor<N> {
    type Value = Coords<N>;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "an array of length {N}")
    }

    fn visit_seq<S: SeqAccess<'de>>(self, mut seq: S) -> Result<Coords<N>, S::Error> {
        let mut a = [0.0; N];
        for (i, x) in a.iter_mut().enumerate() {
            *x = seq
                .next_element()?
                .ok_or_else(|| S::Error::invalid_length(i, &self))?;
        }
        if seq.next_element::<IgnoredAny>()?.is_some() {
            return Err(S::Error::custom(format!(
                "a point with more than {N} coordinates (points2d entries are [x, y], points3d \
                 entries are [X, Y, Z])"
            )));
        }
        Ok(Coords(a))
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

fn too_large(name: &str, cap: u64) -> Failure {
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
struct Capped<R> {
    inner: R,
    left: u64,
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
fn read_failure(name: &str, e: &io::Error, limits: &Limits) -> Failure {
    if e.get_ref().is_some_and(|i| i.is::<OverCap>()) {
        too_large(name, limits.max_input_bytes)
    } else {
        Failure::input(format!("{name}: {e}"))
    }
}

/// The buffered bytes of `src`, more read if needed (empty at the end of the input).
fn fill<R: BufRead>(src: &mut R) -> io::Result<&[u8]> {
    while let Err(e) = src.fill_buf() {
        if e.kind() != io::ErrorKind::Interrupted {
            return Err(e);
        }
    }
    src.fill_buf()
}

/// Where parsing starts, after a UTF-8 byte-order mark and, when the format is sniffed, the
/// leading whitespace.
struct Start {
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

/// What made [`JsonGuard`] stop the JSON reader.
enum Violation {
    /// A string or number longer than the limit, on this line.
    TooLong(usize),
    /// A read error (the size limit included).
    Read(io::Error),
}

/// States of [`JsonGuard`]'s scan.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Scan {
    Outside,
    InString,
    Escape,
}

/// The reader under serde_json's buffer: bounds the length of a string or number (serde_json
/// would buffer it whole), counting lines for the message. It hands over the bytes before a
/// violation, so that an earlier error in them is reported first, and fails the next read.
struct JsonGuard<R> {
    src: R,
    lines: usize,
    scan: Scan,
    run: usize,
    max: usize,
    violation: Option<Violation>,
}

impl<R: Read> Read for JsonGuard<R> {
    fn read(&mut self, out: &mut [u8]) -> io::Result<usize> {
        if self.violation.is_some() {
            return Err(io::Error::other("JSON input refused"));
        }
        let n = match self.src.read(out) {
            Ok(n) => n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => return Err(e),
            Err(e) => {
                let copy = io::Error::new(e.kind(), e.to_string());
                self.violation = Some(Violation::Read(e));
                return Err(copy);
            }
        };
        for (i, &b) in out[..n].iter().enumerate() {
            match self.scan {
                Scan::Outside if b == b'"' => {
                    self.scan = Scan::InString;
                    self.run = 0;
                }
                Scan::Outside if matches!(b, b'0'..=b'9' | b'-' | b'+' | b'.' | b'e' | b'E') => {
                    self.run += 1;
                }
                Scan::Outside => self.run = 0,
                Scan::InString => {
                    self.run += 1;
                    match b {
                        b'\\' => self.scan = Scan::Escape,
                        b'"' => self.scan = Scan::Outside,
                        _ => {}
                    }
                }
                Scan::Escape => {
                    self.run += 1;
                    self.scan = Scan::InString;
                }
            }
            if self.run > self.max {
                self.violation = Some(Violation::TooLong(self.lines + 1));
                // (No byte before it in this block: fail now, as `Ok(0)` would be the end.)
                return if i == 0 {
                    Err(io::Error::other("JSON input refused"))
                } else {
                    Ok(i)
                };
            }
            if b == b'\n' {
                self.lines += 1;
            }
        }
        Ok(n)
    }
}

fn read_json<R: BufRead>(
    name: &str,
    src: R,
    camera_arg: Option<Camera>,
    start: &Start,
    limits: &Limits,
) -> Result<Problem, Failure> {
    let mut guard = JsonGuard {
        src,
        lines: start.line - 1,
        scan: Scan::Outside,
        run: 0,
        max: limits.max_line_bytes,
        violation: None,
    };
    let parsed = {
        // serde_json reads a byte at a time: from a buffer, through `std`'s fast path.
        let mut de = serde_json::Deserializer::from_reader(BufReader::new(&mut guard));
        ProblemSeed {
            camera_given: camera_arg.is_some(),
        }
        .deserialize(&mut de)
        .and_then(|p| de.end().map(|()| p))
    };
    let p = match parsed {
        Ok(p) => p,
        Err(e) => {
            return Err(match guard.violation.take().filter(|_| e.is_io()) {
                Some(Violation::TooLong(line)) => Failure::input(format!(
                    "{name}:{line}: a string or number longer than {}, the limit of JSON input",
                    bytes_text(limits.max_line_bytes as u64)
                )),
                Some(Violation::Read(e)) => read_failure(name, &e, limits),
                None => json_failure(name, &e, start),
            })
        }
    };
    let camera = match (camera_arg, p.camera) {
        (Some(c), _) | (None, Some(c)) => c,
        (None, None) => {
            return Err(Failure::input(format!(
                "{name}: no \"camera\" object and no --camera argument"
            )))
        }
    };
    Ok(Problem {
        camera,
        pixels: p.points2d,
        world: p.points3d,
    })
}

/// The failure of a JSON syntax or data error, at its line and column in the input.
fn json_failure(name: &str, e: &serde_json::Error, start: &Start) -> Failure {
    let (line, column) = (e.line(), e.column());
    let message = e.to_string();
    let message = message
        .strip_suffix(&format!(" at line {line} column {column}"))
        .unwrap_or(&message);
    let column = if line == 1 {
        column + start.column
    } else {
        column
    };
    Failure::input(format!(
        "{name}:{}:{column}: {message}",
        line + start.line - 1
    ))
}

/// The CSV columns, in the order of `Problem`'s coordinates: pixel x, y, world X, Y, Z.
const COLUMNS: [&str; 5] = ["x", "y", "X", "Y", "Z"];

/// The accepted CSV delimiters, in the order they are tried, and their names for messages.
const DELIMITERS: [(u8, &str); 3] = [(b',', "comma"), (b';', "semicolon"), (b'\t', "tab")];

/// Whether a line is skipped: blank, or a comment (`#` after optional whitespace).
fn skipped(line: &str) -> bool {
    let l = line.trim();
    l.is_empty() || l.starts_with('#')
}

/// Maps the header's fields to the columns: `at[k]` is the index of the field named
/// `COLUMNS[k]`. `None` unless the fields are exactly the five names, in any order.
fn header_columns(fields: &[&str]) -> Option<[usize; 5]> {
    if fields.len() != 5 {
        return None;
    }
    let mut at = [usize::MAX; 5];
    for (i, f) in fields.iter().enumerate() {
        let k = COLUMNS.iter().position(|c| c == f)?;
        if at[k] != usize::MAX {
            return None;
        }
        at[k] = i;
    }
    Some(at)
}

/// The header error for the header line `line` (number `n`): what was expected and, for the
/// delimiter that splits it most, what is missing, unknown or repeated.
fn header_error(name: &str, n: usize, line: &str) -> Failure {
    let mut best: Vec<String> = vec![line.trim().to_string()];
    for (d, _) in DELIMITERS {
        let fields = first_record(line, d);
        if fields.len() > best.len() {
            best = fields;
        }
    }
    let mut problems = Vec::new();
    if best.len() > 1 {
        let missing: Vec<&str> = COLUMNS
            .iter()
            .copied()
            .filter(|c| !best.iter().any(|f| f == c))
            .collect();
        let mut unknown = Vec::new();
        let mut repeated = Vec::new();
        for (i, f) in best.iter().enumerate() {
            let shown = format!("`{}`", shown(f));
            if !COLUMNS.contains(&f.as_str()) {
                unknown.push(shown);
            } else if best[..i].contains(f) && !repeated.contains(&shown) {
                repeated.push(shown);
            }
        }
        if !missing.is_empty() {
            let s = if missing.len() == 1 { "" } else { "s" };
            problems.push(format!("missing column{s} {}", missing.join(", ")));
        }
        if !unknown.is_empty() {
            let s = if unknown.len() == 1 { "" } else { "s" };
            let more = unknown.len().saturating_sub(8);
            unknown.truncate(8);
            let more = if more > 0 {
                format!(" and {more} more")
            } else {
                String::new()
            };
            problems.push(format!("unknown column{s} {}{more}", unknown.join(", ")));
        }
        if !repeated.is_empty() {
            let s = if repeated.len() == 1 { "" } else { "s" };
            problems.push(format!("repeated column{s} {}", repeated.join(", ")));
        }
    }
    let problems = if problems.is_empty() {
        String::new()
    } else {
        format!(": {}", problems.join("; "))
    };
    Failure::input(format!(
        "{name}:{n}: expected the header `x,y,X,Y,Z` (pixel x, pixel y, world X, Y, Z; \
         separated by `,`, `;` or tab; in any order), found `{}`{problems}",
        shown(line.trim())
    ))
}

/// The fields (trimmed) of the first record of `line` split at `delim`.
fn first_record(line: &str, delim: u8) -> Vec<String> {
    let mut rec = Record::new(delim);
    if !rec.feed(line.as_bytes()) {
        rec.feed(b"");
    }
    rec.fields()
        .map(|f| String::from_utf8_lossy(f).trim().to_string())
        .collect()
}

/// The most fields of a CSV record that are kept: a record with more is refused (it needs
/// five), and its fields beyond these are not stored.
const MAX_FIELDS: usize = 64;

/// One CSV record parsed by `csv_core` (the `csv` crate's parser) from the lines fed to it:
/// quotes (a quoted field may span lines), `""` inside quotes, records ending at `\n` (a `\r`
/// before it is trimmed with the field). At most [`MAX_FIELDS`] fields.
struct Record {
    rdr: csv_core::Reader,
    out: Vec<u8>,
    ends: Vec<usize>,
    nout: usize,
    nend: usize,
    /// The record has more than [`MAX_FIELDS`] fields (it was cut there).
    overflow: bool,
}

impl Record {
    fn new(delim: u8) -> Self {
        Record {
            rdr: csv_core::ReaderBuilder::new()
                .delimiter(delim)
                .terminator(csv_core::Terminator::Any(b'\n'))
                .comment(Some(b'#'))
                .build(),
            out: vec![0; 256],
            ends: vec![0; 8],
            nout: 0,
            nend: 0,
            overflow: false,
        }
    }

    /// Starts a new record.
    fn clear(&mut self) {
        self.nout = 0;
        self.nend = 0;
        self.overflow = false;
    }

    /// Feeds a line (empty: the end of the input); whether the record is complete (or cut at
    /// [`MAX_FIELDS`] fields: the caller refuses it).
    fn feed(&mut self, mut input: &[u8]) -> bool {
        let eof = input.is_empty();
        loop {
            let (res, nin, nout, nend) = self.rdr.read_record(
                input,
                &mut self.out[self.nout..],
                &mut self.ends[self.nend..],
            );
            input = &input[nin..];
            self.nout += nout;
            self.nend += nend;
            match res {
                csv_core::ReadRecordResult::InputEmpty => return eof,
                csv_core::ReadRecordResult::OutputFull => {
                    let n = 2 * self.out.len();
                    self.out.resize(n, 0);
                }
                csv_core::ReadRecordResult::OutputEndsFull if self.ends.len() >= MAX_FIELDS => {
                    self.overflow = true;
                    return true;
                }
                csv_core::ReadRecordResult::OutputEndsFull => {
                    let n = 2 * self.ends.len();
                    self.ends.resize(n, 0);
                }
                csv_core::ReadRecordResult::Record | csv_core::ReadRecordResult::End => {
                    return true
                }
            }
        }
    }

    fn len(&self) -> usize {
        self.nend
    }

    fn fields(&self) -> impl Iterator<Item = &[u8]> + '_ {
        let mut start = 0;
        self.ends[..self.nend].iter().map(move |&end| {
            let f = &self.out[start..end];
            start = end;
            f
        })
    }
}

/// The lines of CSV input, numbered, each at most `max` bytes (a longer comment line is
/// skipped unread).
struct Lines<'a, R> {
    src: R,
    name: &'a str,
    limits: &'a Limits,
    /// The number of the line last read.
    line: usize,
    buf: Vec<u8>,
    /// The line last read was cut.
    cut: bool,
}

impl<R: BufRead> Lines<'_, R> {
    fn too_long(&self) -> Failure {
        Failure::input(format!(
            "{}:{}: line longer than {}, the line length limit of CSV input",
            self.name,
            self.line,
            bytes_text(self.limits.max_line_bytes as u64)
        ))
    }

    /// The next line, with its `\n` (a comment line: `#`); `None` at the end of the input.
    /// `in_record`: the line continues a record (a quoted field), so it is not a comment. `header`: a line that is
    /// too long is returned cut, for the header error (and `cut` set; nothing more is read).
    fn next(&mut self, in_record: bool, header: bool) -> Result<Option<&str>, Failure> {
        let max = self.limits.max_line_bytes;
        loop {
            self.line += 1;
            let read = read_line(&mut self.src, &mut self.buf, max)
                .map_err(|e| read_failure(self.name, &e, self.limits))?;
            match read {
                None => return Ok(None),
                Some(true) => break,
                Some(false) if !in_record && self.buf.trim_ascii_start().starts_with(b"#") => {
                    skip_line(&mut self.src)
                        .map_err(|e| read_failure(self.name, &e, self.limits))?;
                }
                Some(false) if header => {
                    // Cut at a character boundary.
                    let valid = match std::str::from_utf8(&self.buf) {
                        Ok(_) => self.buf.len(),
                        Err(e) => e.valid_up_to(),
                    };
                    self.buf.truncate(valid);
                    self.cut = true;
                    break;
                }
                Some(false) => return Err(self.too_long()),
            }
        }
        if !in_record && self.buf.trim_ascii_start().starts_with(b"#") {
            // A comment: skipped, whatever its bytes (as a longer one is skipped unread).
            return Ok(Some("#"));
        }
        let (name, line) = (self.name, self.line);
        std::str::from_utf8(&self.buf)
            .map(Some)
            .map_err(|_| Failure::input(format!("{name}:{line}: invalid UTF-8")))
    }
}

/// Reads the next line, its `\n` included, into `buf`: `None` at the end of the input,
/// `Some(false)` if it is longer than `max` bytes (`buf` then holds its start, and the rest is
/// unread).
fn read_line<R: BufRead>(src: &mut R, buf: &mut Vec<u8>, max: usize) -> io::Result<Option<bool>> {
    buf.clear();
    loop {
        let avail = fill(src)?;
        if avail.is_empty() {
            return Ok((!buf.is_empty()).then_some(true));
        }
        let nl = avail.iter().position(|&b| b == b'\n');
        let n = nl.map_or(avail.len(), |i| i + 1);
        // The line's `\n` does not count.
        let room = max + 1 - buf.len();
        if n > room || (nl.is_none() && n == room) {
            let take = n.min(room);
            buf.extend_from_slice(&avail[..take]);
            src.consume(take);
            return Ok(Some(false));
        }
        buf.extend_from_slice(&avail[..n]);
        src.consume(n);
        if nl.is_some() {
            return Ok(Some(true));
        }
    }
}

/// Skips the rest of the current line, its `\n` included.
fn skip_line<R: BufRead>(src: &mut R) -> io::Result<()> {
    loop {
        let avail = fill(src)?;
        if avail.is_empty() {
            return Ok(());
        }
        if let Some(i) = avail.iter().position(|&b| b == b'\n') {
            src.consume(i + 1);
            return Ok(());
        }
        let n = avail.len();
        src.consume(n);
    }
}

/// Reads CSV: a header naming the columns x, y, X, Y, Z (any order, separated by `,`, `;` or
/// tab, which is then the delimiter of the whole file), then one correspondence per line.
/// Fields may be quoted and are trimmed; blank lines and lines starting with `#` are skipped.
/// `first_line`: the number of the first line `src` holds.
fn read_csv<R: BufRead>(
    name: &str,
    src: R,
    camera: Camera,
    first_line: usize,
    limits: &Limits,
) -> Result<Problem, Failure> {
    let mut lines = Lines {
        src,
        name,
        limits,
        line: first_line - 1,
        buf: Vec::new(),
        cut: false,
    };
    // The header line: the first line not skipped.
    let (header_n, header_line) = loop {
        match lines.next(false, true)? {
            None => {
                return Err(Failure::input(format!(
                    "{name}: empty file; expected the header `x,y,X,Y,Z` and one correspondence \
                     per line"
                )))
            }
            Some(l) if skipped(l) => {}
            Some(l) => {
                let l = l.to_string();
                break (lines.line, l);
            }
        }
    };
    let first = header_line
        .strip_suffix('\n')
        .unwrap_or(&header_line)
        .to_string();
    let Some(&(delim, delim_name)) = DELIMITERS.iter().find(|(d, _)| {
        let fields = first_record(&first, *d);
        header_columns(&fields.iter().map(String::as_str).collect::<Vec<_>>()).is_some()
    }) else {
        let mut f = header_error(name, header_n, &first);
        if lines.cut {
            f.message.push_str(&format!(
                " (the line is longer than {}, the line length limit of CSV input: only its \
                 start was read)",
                bytes_text(limits.max_line_bytes as u64)
            ));
        }
        return Err(f);
    };
    if lines.cut {
        // A header, then more than the line length limit of whitespace.
        return Err(lines.too_long());
    }

    let mut pixels = Vec::new();
    let mut world = Vec::new();
    // The header's fields, in file order, once read.
    let mut header: Option<(Vec<String>, [usize; 5])> = None;
    let mut rec = Record::new(delim);
    // The header line is the first record.
    let mut header_record = Some(header_line);
    loop {
        rec.clear();
        let (line, mut done) = match header_record.take() {
            Some(h) => (header_n, rec.feed(h.as_bytes())),
            None => match lines.next(false, false)? {
                None => break,
                Some(l) if skipped(l) => continue,
                Some(l) => {
                    let done = rec.feed(l.as_bytes());
                    (lines.line, done)
                }
            },
        };
        // A quoted field continues on the next lines.
        let mut bytes = 0;
        while !done {
            match lines.next(true, false)? {
                None => done = rec.feed(b""),
                Some(l) => {
                    bytes += l.len();
                    if bytes > limits.max_line_bytes {
                        return Err(Failure::input(format!(
                            "{name}:{line}: record longer than {}, the line length limit of CSV \
                             input (a quote that is not closed?)",
                            bytes_text(limits.max_line_bytes as u64)
                        )));
                    }
                    done = rec.feed(l.as_bytes());
                }
            }
        }
        let Some((names, at)) = &header else {
            let fields: Vec<String> = rec
                .fields()
                .map(|f| String::from_utf8_lossy(f).trim().to_string())
                .collect();
            let at = header_columns(&fields.iter().map(String::as_str).collect::<Vec<_>>())
                .ok_or_else(|| header_error(name, line, &first))?;
            header = Some((fields, at));
            continue;
        };
        if rec.overflow {
            return Err(Failure::input(format!(
                "{name}:{line}: expected 5 {delim_name}-separated numbers ({}), found more than \
                 {MAX_FIELDS} fields",
                names.join(", "),
            )));
        }
        if rec.len() != 5 {
            return Err(Failure::input(format!(
                "{name}:{line}: expected 5 {delim_name}-separated numbers ({}), found {} field{} \
                 (truncated line?)",
                names.join(", "),
                rec.len(),
                if rec.len() == 1 { "" } else { "s" }
            )));
        }
        let mut v = [0.0; 5];
        for (i, f) in rec.fields().enumerate() {
            let f = String::from_utf8_lossy(f);
            let f = f.trim();
            let what = format!("{name}:{line}: field {} ({})", i + 1, names[i]);
            let shown = shown(f);
            let x = match f.parse::<f64>() {
                Ok(x) if x.is_finite() => x,
                Ok(_) => {
                    return Err(Failure::input(format!(
                        "{what} is not finite (NaN, inf or beyond +-1.8e308): `{shown}`"
                    )))
                }
                Err(_) => return Err(Failure::input(format!("{what} is not a number: `{shown}`"))),
            };
            let k = at.iter().position(|&a| a == i).unwrap_or(i);
            v[k] = x;
        }
        pixels.push(Point2::new(v[0], v[1]));
        world.push(Point3::new(v[2], v[3], v[4]));
    }
    if pixels.is_empty() {
        return Err(Failure::input(format!(
            "{name}:{header_n}: no correspondences: the header is not followed by any data line \
             (one correspondence per line expected)"
        )));
    }
    pixels.shrink_to_fit();
    world.shrink_to_fit();
    Ok(Problem {
        camera,
        pixels,
        world,
    })
}

/// `s` for a message: control and other invisible characters escaped (`\u{1}`, `\t`), quotes
/// as they are; at most 60 characters.
fn shown(s: &str) -> String {
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

/// Solves the problem and renders the pose JSON.
pub fn solve(p: &Problem, solver: &Solver) -> Result<String, Failure> {
    // Undistortion failures are input errors here (`Solver::solve_pixels` would skip the point).
    for (k, px) in p.pixels.iter().enumerate() {
        p.camera
            .undistort_weighted(*px)
            .map_err(|e| Failure::input(format!("correspondence {}: {e}", k + 1)))?;
    }
    let sol = solver
        .solve_pixels(&p.world, &p.pixels, &p.camera)
        .map_err(|e| {
            // Degenerate or malformed input is the input's problem (exit 2); only a numerical
            // failure on valid input is the solver's (exit 1).
            let message = format!("no pose: {e}");
            match e {
                PnpError::NoSolution => Failure::solver(message),
                _ => Failure::input(message),
            }
        })?;

    let r = sol.rotation;
    let t = sol.pose.translation.vector;
    let q = sol.pose.rotation;
    let mut s2 = 0.0;
    for (x, px) in p.world.iter().zip(&p.pixels) {
        let c = r * x.coords + t;
        s2 += (p.camera.project(Point2::new(c.x / c.z, c.y / c.z)) - px).norm_squared();
    }
    let rmse_px = (s2 / p.world.len().max(1) as f64).sqrt();
    let v = json!({
        "rotation": [
            [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
            [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
            [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
        ],
        "quaternion_wxyz": [q.w, q.i, q.j, q.k],
        "translation": [t.x, t.y, t.z],
        "n": p.world.len(),
        "inliers": p.world.len(),
        "cost": sol.cost,
        "reprojection_rmse_px": rmse_px,
        "cheirality_ok": sol.cheirality_ok,
        "degenerate": sol.degenerate,
        "camera": { "model": p.camera.model().name(), "params": p.camera.params() },
    });
    let mut out = serde_json::to_string_pretty(&v).unwrap_or_default();
    out.push('\n');
    Ok(out)
}

#[cfg(test)]
#[path = "../../tests/unit/cli/input.rs"]
mod tests;
