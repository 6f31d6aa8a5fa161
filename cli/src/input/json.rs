//! JSON input: `{"camera": {"model", "params"}, "points2d": [...], "points3d": [...]}`,
//! streamed through serde_json's reader under [`JsonGuard`], which bounds the length of a
//! string or number.

use std::fmt;
use std::io::{self, BufRead, BufReader, Read};

use eopnp::camera::Camera;
use nalgebra::{Point2, Point3};
use serde::de::{DeserializeSeed, Error as _, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde::{Deserialize, Deserializer};

use super::limits::{read_failure, Limits};
use super::{Problem, Start};
use crate::source::bytes_text;
use crate::Failure;

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

pub(super) fn read_json<R: BufRead>(
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
    // serde_json quotes what it read (an unknown key) as it is: escaped for the terminal.
    let message = crate::escaped(&e.to_string());
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
