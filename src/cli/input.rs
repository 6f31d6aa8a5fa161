//! `eopnp solve`: correspondence files (CSV, JSON) in, pose JSON out.

use std::io::Read;
use std::path::Path;

use crate::camera::Camera;
use crate::PnpError;
use crate::Solver;
use nalgebra::{Point2, Point3};
use serde::Deserialize;
use serde_json::json;

use super::Failure;

/// A parsed problem: camera, pixels and world points.
pub struct Problem {
    camera: Camera,
    pixels: Vec<Point2<f64>>,
    world: Vec<Point3<f64>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonCamera {
    model: String,
    params: Vec<f64>,
    #[serde(default)]
    width: u64,
    #[serde(default)]
    height: u64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JsonProblem {
    camera: Option<JsonCamera>,
    points2d: Vec<[f64; 2]>,
    points3d: Vec<[f64; 3]>,
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

/// 1-based line of the first occurrence of `needle` in `text` (for semantic JSON errors).
fn line_of(text: &str, needle: &str) -> Option<usize> {
    text.find(needle)
        .map(|at| 1 + text[..at].bytes().filter(|&b| b == b'\n').count())
}

/// The largest input `eopnp solve` reads, from a file or from standard input: 1 GiB.
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

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
/// standard input and other extensions, the content (JSON if it starts with `{`). Inputs
/// larger than [`MAX_INPUT_BYTES`] are refused.
pub(crate) fn read_problem(
    path: &Path,
    format: Option<Format>,
    camera_arg: Option<&str>,
) -> Result<Problem, Failure> {
    let (name, bytes, ext) = if path.as_os_str() == "-" {
        let bytes = read_capped(STDIN_NAME, std::io::stdin().lock(), MAX_INPUT_BYTES)?;
        (STDIN_NAME.to_string(), bytes, None)
    } else {
        let name = path.display().to_string();
        let file = std::fs::File::open(path).map_err(|e| Failure::input(format!("{name}: {e}")))?;
        if let Ok(meta) = file.metadata() {
            if meta.is_file() && meta.len() > MAX_INPUT_BYTES {
                return Err(too_large(&name, MAX_INPUT_BYTES));
            }
        }
        let bytes = read_capped(&name, file, MAX_INPUT_BYTES)?;
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        (name, bytes, ext)
    };
    let ext = format.map(Format::ext).or(ext.as_deref());
    parse_problem(&name, &bytes, ext, camera_arg)
}

/// Reads all of `r`, refusing more than `cap` bytes.
fn read_capped(name: &str, r: impl Read, cap: u64) -> Result<Vec<u8>, Failure> {
    let mut bytes = Vec::new();
    r.take(cap.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| Failure::input(format!("{name}: {e}")))?;
    if bytes.len() as u64 > cap {
        return Err(too_large(name, cap));
    }
    Ok(bytes)
}

fn too_large(name: &str, cap: u64) -> Failure {
    const GIB: u64 = 1 << 30;
    let limit = if cap.is_multiple_of(GIB) {
        format!("{} GiB", cap / GIB)
    } else {
        format!("{cap} bytes")
    };
    Failure::input(format!(
        "{name}: larger than {limit}, the input size limit of `eopnp solve`"
    ))
}

/// Parses the contents of a problem file named `name` (for messages) with extension `ext`
/// (`"json"`, `"csv"`, or anything else: JSON when the text starts with `{`). A UTF-8
/// byte-order mark at the start is ignored.
pub fn parse_problem(
    name: &str,
    bytes: &[u8],
    ext: Option<&str>,
    camera_arg: Option<&str>,
) -> Result<Problem, Failure> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let line = 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        Failure::input(format!("{name}:{line}: invalid UTF-8"))
    })?;
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let camera_arg = camera_arg.map(parse_camera_arg).transpose()?;
    let is_json = match ext {
        Some("json") => true,
        Some("csv") => false,
        _ => text.trim_start().starts_with('{'),
    };
    if is_json {
        read_json(name, text, camera_arg)
    } else {
        let camera = camera_arg.ok_or_else(|| {
            Failure::input(format!(
                "{name}: a CSV file needs the camera: --camera \"MODEL P1 P2 ...\", e.g. \
                 --camera \"SIMPLE_RADIAL 1245.65 600 800 0.0577\""
            ))
        })?;
        read_csv(name, text, camera)
    }
}

fn read_json(name: &str, text: &str, camera_arg: Option<Camera>) -> Result<Problem, Failure> {
    // serde_json reports line and column for syntax errors, wrong types and wrong array
    // lengths.
    let p: JsonProblem = serde_json::from_str(text).map_err(|e| {
        // serde_json reports a fixed-size array with too many elements as trailing characters.
        let after_comma = text
            .lines()
            .nth(e.line().saturating_sub(1))
            .map(|l| {
                l.chars()
                    .take(e.column().saturating_sub(1))
                    .collect::<String>()
            })
            .is_some_and(|before| before.trim_end().ends_with(','));
        let hint = if e.to_string().starts_with("trailing characters") && after_comma {
            " (a point with too many coordinates? points2d entries are [x, y], points3d entries \
             are [X, Y, Z])"
        } else {
            ""
        };
        Failure::input(format!("{name}:{}:{}: {e}{hint}", e.line(), e.column()))
    })?;
    let camera = match (camera_arg, p.camera) {
        (Some(c), _) => c,
        (None, Some(c)) => {
            Camera::from_colmap(&c.model, c.width, c.height, c.params).map_err(|e| {
                let line = line_of(text, "\"camera\"").unwrap_or(1);
                Failure::input(format!("{name}:{line}: camera: {e}"))
            })?
        }
        (None, None) => {
            return Err(Failure::input(format!(
                "{name}: no \"camera\" object and no --camera argument"
            )))
        }
    };
    if p.points2d.len() != p.points3d.len() {
        let line = line_of(text, "\"points3d\"").unwrap_or(1);
        return Err(Failure::input(format!(
            "{name}:{line}: {} points2d but {} points3d; they must correspond one to one",
            p.points2d.len(),
            p.points3d.len()
        )));
    }
    Ok(Problem {
        camera,
        pixels: p.points2d.iter().map(|a| Point2::new(a[0], a[1])).collect(),
        world: p
            .points3d
            .iter()
            .map(|a| Point3::new(a[0], a[1], a[2]))
            .collect(),
    })
}

/// The CSV columns, in the order of `Problem`'s coordinates: pixel x, y, world X, Y, Z.
const COLUMNS: [&str; 5] = ["x", "y", "X", "Y", "Z"];

/// The accepted CSV delimiters, in the order they are tried, and their names for messages.
const DELIMITERS: [(u8, &str); 3] = [(b',', "comma"), (b';', "semicolon"), (b'\t', "tab")];

/// A CSV reader over `text` with delimiter `delim`: no header handling (done here), any
/// number of fields per record (checked here), records end at `\n` (a `\r` before it is
/// trimmed with the field), lines starting with `#` skipped.
fn csv_reader(text: &str, delim: u8) -> csv::Reader<&[u8]> {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .delimiter(delim)
        .terminator(csv::Terminator::Any(b'\n'))
        .comment(Some(b'#'))
        .from_reader(text.as_bytes())
}

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
            problems.push(format!("unknown column{s} {}", unknown.join(", ")));
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
    let mut rec = csv::StringRecord::new();
    match csv_reader(line, delim).read_record(&mut rec) {
        Ok(true) => rec.iter().map(|f| f.trim().to_string()).collect(),
        _ => Vec::new(),
    }
}

/// Reads CSV: a header naming the columns x, y, X, Y, Z (any order, separated by `,`, `;` or
/// tab, which is then the delimiter of the whole file), then one correspondence per line.
/// Fields may be quoted and are trimmed; blank lines and lines starting with `#` are skipped.
fn read_csv(name: &str, text: &str, camera: Camera) -> Result<Problem, Failure> {
    // The header line: the first line not skipped.
    let Some((header_n, header_line)) = text
        .split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .find(|(_, l)| !skipped(l))
    else {
        return Err(Failure::input(format!(
            "{name}: empty file; expected the header `x,y,X,Y,Z` and one correspondence per line"
        )));
    };
    let Some(&(delim, delim_name)) = DELIMITERS.iter().find(|(d, _)| {
        let fields = first_record(header_line, *d);
        header_columns(&fields.iter().map(String::as_str).collect::<Vec<_>>()).is_some()
    }) else {
        return Err(header_error(name, header_n, header_line));
    };

    let mut pixels = Vec::new();
    let mut world = Vec::new();
    // The header's fields, in file order, once read.
    let mut header: Option<(Vec<String>, [usize; 5])> = None;
    let mut rdr = csv_reader(text, delim);
    let mut rec = csv::StringRecord::new();
    // Line counting: the number of the line starting at byte `counted`.
    let (mut counted, mut line) = (0, 1);
    let bytes = text.as_bytes();
    loop {
        let start = rdr.position().byte() as usize;
        match rdr.read_record(&mut rec) {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => return Err(Failure::input(format!("{name}: {e}"))),
        }
        let end = (rdr.position().byte() as usize).min(bytes.len());
        // The reader skips empty lines and `#` lines before a record, as `record_start` does.
        let start = record_start(bytes, start.min(end));
        line += bytes[counted..start]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        counted = start;
        // Whitespace-only lines and indented comments reach here as records.
        if skipped(&text[start..end]) {
            continue;
        }
        let fields: Vec<&str> = rec.iter().map(str::trim).collect();
        let Some((names, at)) = &header else {
            let at = header_columns(&fields).ok_or_else(|| {
                header_error(name, line, text[start..end].lines().next().unwrap_or(""))
            })?;
            header = Some((fields.iter().map(|f| f.to_string()).collect(), at));
            continue;
        };
        if fields.len() != 5 {
            return Err(Failure::input(format!(
                "{name}:{line}: expected 5 {delim_name}-separated numbers ({}), found {} field{} \
                 (truncated line?)",
                names.join(", "),
                fields.len(),
                if fields.len() == 1 { "" } else { "s" }
            )));
        }
        let mut v = [0.0; 5];
        for (i, f) in fields.iter().enumerate() {
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
    Ok(Problem {
        camera,
        pixels,
        world,
    })
}

/// Where the record the CSV reader reads from byte `at` starts: past empty lines and lines
/// starting with `#` (which the reader skips).
fn record_start(bytes: &[u8], mut at: usize) -> usize {
    loop {
        while bytes.get(at) == Some(&b'\n') {
            at += 1;
        }
        if bytes.get(at) != Some(&b'#') {
            return at;
        }
        at = bytes[at..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(bytes.len(), |p| at + p + 1);
    }
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
