//! CSV input: a header naming the columns x, y, X, Y, Z (any order; `,`, `;` or tab), then one
//! correspondence per line, parsed by `csv_core` (the `csv` crate's record parser) fed line by
//! line.

use std::io::{self, BufRead};

use eopnp::camera::Camera;
use nalgebra::{Point2, Point3};

use super::limits::{read_failure, Limits};
use super::{fill, shown, Problem};
use crate::source::bytes_text;
use crate::Failure;

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
pub(super) fn read_csv<R: BufRead>(
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
