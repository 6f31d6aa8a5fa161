//! The text format (`cameras.txt`, `images.txt`, `points3D.txt`, and `rigs.txt`, `frames.txt`
//! in `text/rigs.rs`): one record per line, `#` comments; every error names the file and the
//! 1-based line. Read as a stream of tokens: the memory is what is returned plus one field
//! (never a whole file or a whole line), so lines need no length limit of their own. The
//! encoder the writer (`write.rs`) uses is in `text/encode.rs`.

use std::collections::BTreeMap;
use std::io::{self, BufRead};
use std::path::Path;

use nalgebra::{Point2, Point3, Vector3};

use super::model::{Image, Images, Location, ModelError, ModelErrorKind, Point3D};
use super::options::{Limit, ReadOptions, MAX_FIELD_BYTES};
use super::pose::check_quaternion;
use crate::camera::{Camera, CameraModel};

mod encode;
mod rigs;

#[cfg(test)]
pub(super) use encode::push_f64;
pub(super) use encode::{encode_text, text_name_ok};
pub(super) use rigs::{encode_rigs_text, parse_frames_text, parse_rigs_text, Records};

/// ASCII whitespace as C's `isspace` (COLMAP's reader) and `char::is_whitespace` both see it.
fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\n' | 0x0b | 0x0c | b'\r')
}

/// An error of kind [`ModelErrorKind::Invalid`] at `line`.
fn err_at(path: &Path, line: usize, reason: impl Into<String>) -> ModelError {
    ModelError::invalid(path, Location::Line(line), reason)
}

fn io_err(path: &Path, line: usize, e: &io::Error) -> ModelError {
    ModelError {
        file: path.to_path_buf(),
        location: Location::Line(line),
        kind: ModelErrorKind::Io,
        reason: format!("cannot read: {e}"),
    }
}

/// The buffered bytes of `src` (more read if it is empty; empty at the end of the file). (A
/// regular file's read is not interrupted by signals; any error is the file's.)
fn fill<'b, R: BufRead>(src: &'b mut R, path: &Path, line: usize) -> Result<&'b [u8], ModelError> {
    src.fill_buf().map_err(|e| io_err(path, line, &e))
}

/// A text model file as lines of whitespace-separated tokens, whitespace as
/// `str::split_whitespace` sees it (Unicode included), read through the caller's buffer: a token
/// is at most [`MAX_FIELD_BYTES`], everything else (whitespace, comments) streams.
struct Tokens<'a, R> {
    src: &'a mut R,
    path: &'a Path,
    /// The current line, 1-based (0 before the first).
    line: usize,
    /// The current line's end was read (its `\n` consumed, or the end of the file).
    at_eol: bool,
    /// The current token.
    cur: String,
    /// What follows the current token in a token read up to ASCII whitespace that held other
    /// (Unicode) whitespace.
    pending: String,
    /// The next `token` returns `cur` again (after `next_record` peeked at it).
    replay: bool,
    /// Raw bytes of the token being read.
    raw: Vec<u8>,
}

impl<'a, R: BufRead> Tokens<'a, R> {
    fn new(path: &'a Path, src: &'a mut R) -> Self {
        Tokens {
            src,
            path,
            line: 0,
            at_eol: true,
            cur: String::new(),
            pending: String::new(),
            replay: false,
            raw: Vec::new(),
        }
    }

    fn err(&self, reason: impl Into<String>) -> ModelError {
        err_at(self.path, self.line, reason)
    }

    fn too_long(&self, what: &str) -> ModelError {
        ModelError::limit(
            self.path,
            Location::Line(self.line),
            Limit::FieldBytes(MAX_FIELD_BYTES),
            what,
        )
    }

    /// Skips the rest of the current line.
    fn skip_line(&mut self) -> Result<(), ModelError> {
        self.pending.clear();
        self.replay = false;
        while !self.at_eol {
            let buf = fill(self.src, self.path, self.line)?;
            if buf.is_empty() {
                self.at_eol = true;
            } else if let Some(i) = buf.iter().position(|&b| b == b'\n') {
                self.src.consume(i + 1);
                self.at_eol = true;
            } else {
                let n = buf.len();
                self.src.consume(n);
            }
        }
        Ok(())
    }

    /// Starts the next line, skipping what is left of the current one; `false` at the end of
    /// the file (as `str::lines`, a final `\n` does not start an empty line).
    fn next_line(&mut self) -> Result<bool, ModelError> {
        self.skip_line()?;
        if fill(self.src, self.path, self.line)?.is_empty() {
            return Ok(false);
        }
        self.line += 1;
        self.at_eol = false;
        Ok(true)
    }

    /// Moves to the next line that holds a record (not blank, not a comment: its first token
    /// does not start with `#`); `false` at the end of the file.
    fn next_record(&mut self) -> Result<bool, ModelError> {
        while self.next_line()? {
            if self.token()?.is_some_and(|t| !t.starts_with('#')) {
                self.replay = true;
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// The next token of the current line; `None` at its end.
    fn token(&mut self) -> Result<Option<&str>, ModelError> {
        if std::mem::take(&mut self.replay) {
            return Ok(Some(&self.cur));
        }
        loop {
            if !self.pending.is_empty() {
                let rest = self.pending.trim_start();
                if !rest.is_empty() {
                    let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
                    self.cur.clear();
                    self.cur.push_str(&rest[..end]);
                    self.pending = rest[end..].to_string();
                    return Ok(Some(&self.cur));
                }
                self.pending.clear();
            }
            if self.at_eol {
                return Ok(None);
            }
            // Usually the blanks before the token and the token are in the buffer, and ASCII.
            let buf = fill(self.src, self.path, self.line)?;
            if let Some(start) = buf.iter().position(|&b| !is_space(b)) {
                let rest = &buf[start..];
                if !buf[..start].contains(&b'\n') {
                    let end = rest.iter().position(|&b| is_space(b));
                    if let Some(len) = end.filter(|&len| len <= MAX_FIELD_BYTES) {
                        if let Ok(tok) = std::str::from_utf8(&rest[..len]) {
                            if tok.is_ascii() {
                                self.cur.clear();
                                self.cur.push_str(tok);
                                self.src.consume(start + len);
                                return Ok(Some(&self.cur));
                            }
                        }
                    }
                }
            }
            // Whitespace up to the token or the end of the line.
            loop {
                let buf = fill(self.src, self.path, self.line)?;
                if buf.is_empty() {
                    self.at_eol = true;
                    return Ok(None);
                }
                match buf.iter().position(|&b| !is_space(b) || b == b'\n') {
                    Some(i) if buf[i] == b'\n' => {
                        self.src.consume(i + 1);
                        self.at_eol = true;
                        return Ok(None);
                    }
                    Some(i) => {
                        self.src.consume(i);
                        break;
                    }
                    None => {
                        let n = buf.len();
                        self.src.consume(n);
                    }
                }
            }
            // The token, up to ASCII whitespace or the end of the file.
            self.raw.clear();
            loop {
                let buf = fill(self.src, self.path, self.line)?;
                let end = buf.iter().position(|&b| is_space(b));
                let n = end.unwrap_or(buf.len());
                if self.raw.len() + n > MAX_FIELD_BYTES {
                    return Err(self.too_long("a field longer than 64 KiB"));
                }
                self.raw.extend_from_slice(&buf[..n]);
                self.src.consume(n);
                if end.is_some() || n == 0 {
                    break;
                }
            }
            let text = std::str::from_utf8(&self.raw).map_err(|_| self.err("invalid UTF-8"))?;
            if text.is_ascii() || !text.contains(char::is_whitespace) {
                self.cur.clear();
                self.cur.push_str(text);
                return Ok(Some(&self.cur));
            }
            // Other whitespace inside: split it as `split_whitespace` would.
            self.pending = text.to_string();
        }
    }

    /// The rest of the current line, trimmed (an image name, which may contain spaces).
    fn rest_of_line(&mut self) -> Result<&str, ModelError> {
        self.replay = false;
        self.raw.clear();
        self.raw
            .extend_from_slice(std::mem::take(&mut self.pending).as_bytes());
        while !self.at_eol {
            let buf = fill(self.src, self.path, self.line)?;
            if buf.is_empty() {
                self.at_eol = true;
                break;
            }
            let end = buf.iter().position(|&b| b == b'\n');
            let n = end.unwrap_or(buf.len());
            if self.raw.len() + n > MAX_FIELD_BYTES {
                return Err(self.too_long("the image name is longer than 64 KiB"));
            }
            self.raw.extend_from_slice(&buf[..n]);
            self.src.consume(n + usize::from(end.is_some()));
            self.at_eol = end.is_some();
        }
        let text = std::str::from_utf8(&self.raw).map_err(|_| self.err("invalid UTF-8"))?;
        self.cur.clear();
        self.cur.push_str(text.trim());
        Ok(&self.cur)
    }

    /// The next token, which must be there: `what` names it in the error.
    fn field(&mut self, what: &str) -> Result<&str, ModelError> {
        let (path, line) = (self.path, self.line);
        self.token()?.ok_or_else(|| {
            err_at(
                path,
                line,
                format!("line ends before {what} (truncated line?)"),
            )
        })
    }

    /// The next token parsed as a `T`.
    fn parse<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, ModelError> {
        let (path, line) = (self.path, self.line);
        let tok = self.field(what)?;
        parse_tok(path, line, tok, what)
    }

    /// The next token as a finite number.
    fn float(&mut self, what: &str) -> Result<f64, ModelError> {
        let (path, line) = (self.path, self.line);
        let tok = self.field(what)?;
        float_tok(path, line, tok, what)
    }
}

fn parse_tok<T: std::str::FromStr>(
    path: &Path,
    line: usize,
    tok: &str,
    what: &str,
) -> Result<T, ModelError> {
    tok.parse()
        .map_err(|_| err_at(path, line, format!("bad {what}: {:?}", truncate(tok))))
}

fn float_tok(path: &Path, line: usize, tok: &str, what: &str) -> Result<f64, ModelError> {
    let v: f64 = parse_tok(path, line, tok, what)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(err_at(
            path,
            line,
            format!("{what} is not finite: {:?}", truncate(tok)),
        ))
    }
}

fn truncate(s: &str) -> String {
    if s.chars().count() > 40 {
        let mut t: String = s.chars().take(40).collect();
        t.push_str("...");
        t
    } else {
        s.to_string()
    }
}

pub(super) fn parse_cameras_text<R: BufRead>(
    path: &Path,
    src: &mut R,
    _len: u64,
    _limits: &ReadOptions,
) -> Result<BTreeMap<u32, Camera>, ModelError> {
    let mut t = Tokens::new(path, src);
    let mut cameras = BTreeMap::new();
    while t.next_record()? {
        let id: u32 = t.parse("CAMERA_ID")?;
        let model_name = t.field("MODEL")?.to_string();
        let width: u64 = t.parse("WIDTH")?;
        let height: u64 = t.parse("HEIGHT")?;
        let model = CameraModel::from_name(&model_name).map_err(|e| t.err(e.to_string()))?;
        let mut params = Vec::with_capacity(model.num_params());
        let (path, line) = (t.path, t.line);
        while let Some(tok) = t.token()? {
            if params.len() >= model.num_params() {
                return Err(err_at(
                    path,
                    line,
                    format!(
                        "too many parameters for {model} (expected {}: {})",
                        model.num_params(),
                        model.params_info()
                    ),
                ));
            }
            params.push(float_tok(path, line, tok, "camera parameter")?);
        }
        let cam = Camera::new(model, width, height, params).map_err(|e| t.err(e.to_string()))?;
        if cameras.insert(id, cam).is_some() {
            return Err(t.err(format!("duplicate camera id {id}")));
        }
    }
    Ok(cameras)
}

/// The fields of an `images.txt` header line before the name.
const IMAGE_FIELDS: [&str; 9] = [
    "IMAGE_ID",
    "QW",
    "QX",
    "QY",
    "QZ",
    "TX",
    "TY",
    "TZ",
    "CAMERA_ID",
];

pub(super) fn parse_images_text<R: BufRead>(
    path: &Path,
    src: &mut R,
    _len: u64,
    limits: &ReadOptions,
) -> Result<Images, ModelError> {
    let mut t = Tokens::new(path, src);
    let mut images = BTreeMap::new();
    let mut locs = BTreeMap::new();
    let mut tok: [String; 9] = Default::default();
    while t.next_record()? {
        let line = t.line;
        // IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (the name is the rest of the line).
        for (k, what) in IMAGE_FIELDS.iter().enumerate() {
            tok[k].clear();
            tok[k].push_str(t.field(what)?);
        }
        let name = t.rest_of_line()?.to_string();
        if name.is_empty() {
            return Err(t.err("line ends before NAME (truncated line?)"));
        }
        let id: u32 = parse_tok(path, line, &tok[0], "IMAGE_ID")?;
        let mut q = [0.0; 4];
        for k in 0..4 {
            q[k] = float_tok(path, line, &tok[1 + k], IMAGE_FIELDS[1 + k])?;
        }
        check_quaternion(&q).map_err(|r| t.err(r))?;
        let mut tr = Vector3::zeros();
        for k in 0..3 {
            tr[k] = float_tok(path, line, &tok[5 + k], IMAGE_FIELDS[5 + k])?;
        }
        let camera_id: u32 = parse_tok(path, line, &tok[8], "CAMERA_ID")?;
        // The next line holds the observations (possibly empty), as COLMAP reads it.
        let mut points2d = Vec::new();
        let mut loc = Location::Line(line);
        if t.next_line()? {
            let pline = t.line;
            loc = Location::Line(pline);
            let mut numbers = 0usize;
            while let Some(x) = t.token()? {
                if points2d.len() == limits.max_observations {
                    return Err(ModelError::limit(
                        path,
                        loc,
                        Limit::Observations(limits.max_observations),
                        &format!(
                            "image {id} has more than {} observations",
                            limits.max_observations
                        ),
                    ));
                }
                let x = float_tok(path, pline, x, "observation X")?;
                let triple = |numbers: usize| {
                    err_at(
                        path,
                        pline,
                        format!(
                            "observations of image {id} must be triples X Y POINT3D_ID, got \
                             {numbers} numbers (truncated line?)"
                        ),
                    )
                };
                let Some(y) = t.token()? else {
                    return Err(triple(numbers + 1));
                };
                let y = float_tok(path, pline, y, "observation Y")?;
                let Some(p) = t.token()? else {
                    return Err(triple(numbers + 2));
                };
                let pid = if p == "-1" {
                    None
                } else {
                    Some(parse_tok::<u64>(path, pline, p, "POINT3D_ID")?)
                };
                numbers += 3;
                points2d.push((Point2::new(x, y), pid));
            }
            points2d.shrink_to_fit();
        }
        let img = Image {
            id,
            q,
            t: tr,
            camera_id,
            name,
            points2d,
        };
        if images.insert(id, img).is_some() {
            return Err(err_at(path, line, format!("duplicate image id {id}")));
        }
        locs.insert(id, loc);
    }
    Ok((images, locs))
}

pub(super) fn parse_points_text<R: BufRead>(
    path: &Path,
    src: &mut R,
    _len: u64,
    limits: &ReadOptions,
) -> Result<BTreeMap<u64, Point3D>, ModelError> {
    let mut t = Tokens::new(path, src);
    let mut points = BTreeMap::new();
    while t.next_record()? {
        let (path, line) = (t.path, t.line);
        let id: u64 = t.parse("POINT3D_ID")?;
        let mut xyz = [0.0; 3];
        for (k, what) in ["X", "Y", "Z"].iter().enumerate() {
            xyz[k] = t.float(what)?;
        }
        let mut rgb = [0u8; 3];
        for (k, what) in ["R", "G", "B"].iter().enumerate() {
            let tok = t.field(what)?;
            rgb[k] = parse_tok(path, line, tok, &format!("{what} (0-255)"))?;
        }
        let error: f64 = t.parse("ERROR")?;
        let mut track = Vec::new();
        while let Some(img) = t.token()? {
            if track.len() == limits.max_track_length {
                return Err(ModelError::limit(
                    path,
                    Location::Line(line),
                    Limit::TrackLength(limits.max_track_length),
                    &format!(
                        "the track of point {id} has more than {} elements",
                        limits.max_track_length
                    ),
                ));
            }
            let img = parse_tok::<u32>(path, line, img, "track IMAGE_ID")?;
            let Some(idx) = t.token()? else {
                return Err(err_at(
                    path,
                    line,
                    format!(
                        "track of point {id} must be pairs IMAGE_ID POINT2D_IDX, got {} \
                         numbers (truncated line?)",
                        2 * track.len() + 1
                    ),
                ));
            };
            track.push((img, parse_tok::<u32>(path, line, idx, "track POINT2D_IDX")?));
        }
        track.shrink_to_fit();
        let p = Point3D {
            id,
            xyz: Point3::new(xyz[0], xyz[1], xyz[2]),
            rgb,
            error,
            track,
        };
        if points.insert(id, p).is_some() {
            return Err(err_at(path, line, format!("duplicate 3D point id {id}")));
        }
    }
    Ok(points)
}
