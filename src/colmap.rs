//! COLMAP sparse reconstructions: readers for the text (`cameras.txt`, `images.txt`,
//! `points3D.txt`) and binary (`cameras.bin`, `images.bin`, `points3D.bin`) formats, a binary
//! writer, and [`register_image`], which re-estimates an image's pose from its 2D-3D
//! correspondences.
//!
//! Conventions are COLMAP's: an image's pose `(q, t)` maps world to camera,
//! `x_cam = R(q) X + t`, with `q = (qw, qx, qy, qz)` a Hamilton quaternion; pixels follow
//! [`crate::camera`] (upper-left image corner at `(0, 0)`).
//!
//! Every reader is bounded and panic-free on any input: a count field can only claim as many
//! records as the remaining bytes can hold, and every error carries the file name and the
//! line number (text) or byte offset (binary) with the reason.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use crate::camera::{Camera, CameraError, CameraModel};
use crate::{PnpError, Solution, Solver};

/// An image of the reconstruction: its pose, camera and 2D observations.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Image id.
    pub id: u32,
    /// World-to-camera rotation as a quaternion `(qw, qx, qy, qz)` as stored in the file (not
    /// renormalised; [`Image::pose`] normalises).
    pub q: [f64; 4],
    /// World-to-camera translation.
    pub t: Vector3<f64>,
    /// Id of the image's camera in [`Model::cameras`].
    pub camera_id: u32,
    /// Image name (may contain spaces).
    pub name: String,
    /// Observations: pixel and the id of the 3D point it observes (`None` if untriangulated).
    pub points2d: Vec<(Point2<f64>, Option<u64>)>,
}

impl Image {
    /// The model's pose `(R, t)` of this image, `x_cam = R X + t`, with `R` from the
    /// normalised quaternion in closed form.
    #[must_use]
    pub fn pose(&self) -> (Matrix3<f64>, Vector3<f64>) {
        (quaternion_to_matrix(self.q), self.t)
    }
}

/// A triangulated 3D point.
#[derive(Clone, Debug, PartialEq)]
pub struct Point3D {
    /// Point id.
    pub id: u64,
    /// World coordinates.
    pub xyz: Point3<f64>,
    /// Colour.
    pub rgb: [u8; 3],
    /// Mean reprojection error reported by COLMAP, pixels.
    pub error: f64,
    /// Track: `(image id, index into that image's points2d)`.
    pub track: Vec<(u32, u32)>,
}

/// A COLMAP sparse reconstruction.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Model {
    /// Cameras by id.
    pub cameras: BTreeMap<u32, Camera>,
    /// Images by id.
    pub images: BTreeMap<u32, Image>,
    /// 3D points by id.
    pub points: BTreeMap<u64, Point3D>,
}

impl Model {
    /// An image and its camera.
    ///
    /// # Errors
    /// [`RegisterError::UnknownImage`] or [`RegisterError::UnknownCamera`].
    pub fn image_and_camera(&self, image_id: u32) -> Result<(&Image, &Camera), RegisterError> {
        let img = self
            .images
            .get(&image_id)
            .ok_or(RegisterError::UnknownImage(image_id))?;
        let cam = self
            .cameras
            .get(&img.camera_id)
            .ok_or(RegisterError::UnknownCamera(img.camera_id))?;
        Ok((img, cam))
    }

    /// The 2D-3D correspondences of an image: world points and their observed (distorted)
    /// pixels, in the order of the image's observations. Empty for an unknown image id.
    /// (Every referenced 3D point exists: [`read_model`] checks this.)
    #[must_use]
    pub fn correspondences(&self, image_id: u32) -> (Vec<Point3<f64>>, Vec<Point2<f64>>) {
        let Some(img) = self.images.get(&image_id) else {
            return (Vec::new(), Vec::new());
        };
        img.points2d
            .iter()
            .filter_map(|(px, id)| {
                let p = self.points.get(&(*id)?)?;
                Some((p.xyz, *px))
            })
            .unzip()
    }
}

/// Rotation matrix of a quaternion `(w, x, y, z)` (normalised first), closed form.
/// A zero or non-finite quaternion gives a NaN matrix ([`read_model`] rejects those).
#[must_use]
pub fn quaternion_to_matrix(q: [f64; 4]) -> Matrix3<f64> {
    let n = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
    let (w, x, y, z) = (q[0] / n, q[1] / n, q[2] / n, q[3] / n);
    Matrix3::new(
        1.0 - 2.0 * (y * y + z * z),
        2.0 * (x * y - w * z),
        2.0 * (x * z + w * y),
        2.0 * (x * y + w * z),
        1.0 - 2.0 * (x * x + z * z),
        2.0 * (y * z - w * x),
        2.0 * (x * z - w * y),
        2.0 * (y * z + w * x),
        1.0 - 2.0 * (x * x + y * y),
    )
}

/// Where in a file an error is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    /// No particular place (e.g. the file cannot be opened).
    File,
    /// 1-based line number of a text file.
    Line(usize),
    /// Byte offset into a binary file.
    Offset(u64),
}

/// An error reading a model: the file, where in it, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModelError {
    /// The file (or directory) concerned.
    pub file: PathBuf,
    /// Where in the file.
    pub location: Location,
    /// What is wrong.
    pub reason: String,
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let file = self.file.display();
        match self.location {
            Location::File => write!(f, "{file}: {}", self.reason),
            Location::Line(l) => write!(f, "{file}:{l}: {}", self.reason),
            Location::Offset(o) => write!(f, "{file}: at byte offset {o}: {}", self.reason),
        }
    }
}

impl std::error::Error for ModelError {}

/// The on-disk format of a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFormat {
    /// `cameras.txt`, `images.txt`, `points3D.txt`.
    Text,
    /// `cameras.bin`, `images.bin`, `points3D.bin`.
    Binary,
}

const TEXT_FILES: [&str; 3] = ["cameras.txt", "images.txt", "points3D.txt"];
const BIN_FILES: [&str; 3] = ["cameras.bin", "images.bin", "points3D.bin"];

/// The format of the model in `dir`: binary if all three `.bin` files exist (COLMAP's own
/// default output, and exact), else text if all three `.txt` files exist.
///
/// # Errors
/// A [`ModelError`] naming the directory and the missing files if neither set is complete.
pub fn detect_format(dir: &Path) -> Result<ModelFormat, ModelError> {
    let all = |names: &[&str; 3]| names.iter().all(|n| dir.join(n).is_file());
    if all(&BIN_FILES) {
        Ok(ModelFormat::Binary)
    } else if all(&TEXT_FILES) {
        Ok(ModelFormat::Text)
    } else {
        let reason = if dir.is_dir() {
            "not a COLMAP model: expected cameras.txt, images.txt and points3D.txt (text \
             format) or cameras.bin, images.bin and points3D.bin (binary format)"
                .to_string()
        } else {
            "no such directory".to_string()
        };
        Err(ModelError {
            file: dir.to_path_buf(),
            location: Location::File,
            reason,
        })
    }
}

/// Reads the model in `dir`, text or binary (see [`detect_format`]: binary is preferred when
/// both are present), and checks its cross-references (every image's camera and every
/// observed 3D point exist).
///
/// # Errors
/// A [`ModelError`] with the file, line or byte offset, and the reason.
pub fn read_model(dir: impl AsRef<Path>) -> Result<Model, ModelError> {
    let dir = dir.as_ref();
    match detect_format(dir)? {
        ModelFormat::Text => read_model_text(dir),
        ModelFormat::Binary => read_model_binary(dir),
    }
}

fn read_file(path: &Path) -> Result<Vec<u8>, ModelError> {
    std::fs::read(path).map_err(|e| ModelError {
        file: path.to_path_buf(),
        location: Location::File,
        reason: format!("cannot read: {e}"),
    })
}

/// Reads a text-format model (`cameras.txt`, `images.txt`, `points3D.txt`) from `dir`.
///
/// # Errors
/// As [`read_model`].
pub fn read_model_text(dir: impl AsRef<Path>) -> Result<Model, ModelError> {
    read_with(&TEXT, dir.as_ref())
}

/// Reads a binary-format model (`cameras.bin`, `images.bin`, `points3D.bin`) from `dir`.
///
/// # Errors
/// As [`read_model`].
pub fn read_model_binary(dir: impl AsRef<Path>) -> Result<Model, ModelError> {
    read_with(&BINARY, dir.as_ref())
}

/// Parses a text-format model from the contents of its three files (e.g. read from an
/// archive). Errors name the files `cameras.txt`, `images.txt` and `points3D.txt`.
///
/// # Errors
/// As [`read_model`].
pub fn parse_model_text(
    cameras: &[u8],
    images: &[u8],
    points3d: &[u8],
) -> Result<Model, ModelError> {
    parse_with(
        &TEXT,
        &TEXT.files.map(PathBuf::from),
        [cameras, images, points3d],
    )
}

/// Parses a binary-format model from the contents of its three files. Errors name the files
/// `cameras.bin`, `images.bin` and `points3D.bin`.
///
/// # Errors
/// As [`read_model`].
pub fn parse_model_binary(
    cameras: &[u8],
    images: &[u8],
    points3d: &[u8],
) -> Result<Model, ModelError> {
    parse_with(
        &BINARY,
        &BINARY.files.map(PathBuf::from),
        [cameras, images, points3d],
    )
}

/// A file parser: the file's path (for messages) and its bytes.
type Parser<T> = fn(&Path, &[u8]) -> Result<T, ModelError>;

/// A model format: its file names and the parser of each file.
struct Format {
    files: [&'static str; 3],
    cameras: Parser<BTreeMap<u32, Camera>>,
    images: Parser<Images>,
    points: Parser<BTreeMap<u64, Point3D>>,
}

const TEXT: Format = Format {
    files: TEXT_FILES,
    cameras: parse_cameras_text,
    images: parse_images_text,
    points: parse_points_text,
};

const BINARY: Format = Format {
    files: BIN_FILES,
    cameras: parse_cameras_bin,
    images: parse_images_bin,
    points: parse_points_bin,
};

fn read_with(format: &Format, dir: &Path) -> Result<Model, ModelError> {
    let paths = format.files.map(|n| dir.join(n));
    let [c, i, p] = [0, 1, 2].map(|k| read_file(&paths[k]));
    parse_with(format, &paths, [&c?, &i?, &p?])
}

fn parse_with(
    format: &Format,
    paths: &[PathBuf; 3],
    [c, i, p]: [&[u8]; 3],
) -> Result<Model, ModelError> {
    let mut model = Model {
        cameras: (format.cameras)(&paths[0], c)?,
        ..Model::default()
    };
    let (images, locs) = (format.images)(&paths[1], i)?;
    model.images = images;
    model.points = (format.points)(&paths[2], p)?;
    check_references(&model, &paths[1], &locs)?;
    Ok(model)
}

fn check_references(
    model: &Model,
    images_file: &Path,
    locs: &BTreeMap<u32, Location>,
) -> Result<(), ModelError> {
    for img in model.images.values() {
        let location = locs.get(&img.id).copied().unwrap_or(Location::File);
        let err = |reason: String| ModelError {
            file: images_file.to_path_buf(),
            location,
            reason,
        };
        if !model.cameras.contains_key(&img.camera_id) {
            return Err(err(format!(
                "image {} refers to camera {}, which is not in the cameras file",
                img.id, img.camera_id
            )));
        }
        for (k, (_, pid)) in img.points2d.iter().enumerate() {
            if let Some(pid) = pid {
                if !model.points.contains_key(pid) {
                    return Err(err(format!(
                        "observation {k} of image {} refers to 3D point {pid}, which is not in \
                         the points3D file",
                        img.id
                    )));
                }
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Text format.

/// Lines of a text file with 1-based numbers; invalid UTF-8 is an error on its line.
fn text_lines<'a>(
    path: &Path,
    bytes: &'a [u8],
) -> Result<impl Iterator<Item = (usize, &'a str)>, ModelError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let upto = e.valid_up_to();
        let line = 1 + bytes[..upto].iter().filter(|&&b| b == b'\n').count();
        ModelError {
            file: path.to_path_buf(),
            location: Location::Line(line),
            reason: "invalid UTF-8".to_string(),
        }
    })?;
    Ok(text.lines().enumerate().map(|(i, l)| (i + 1, l)))
}

fn is_skipped(line: &str) -> bool {
    let t = line.trim();
    t.is_empty() || t.starts_with('#')
}

struct LineCtx<'a> {
    path: &'a Path,
    line: usize,
}

impl LineCtx<'_> {
    fn err(&self, reason: impl Into<String>) -> ModelError {
        ModelError {
            file: self.path.to_path_buf(),
            location: Location::Line(self.line),
            reason: reason.into(),
        }
    }

    fn field<'t>(
        &self,
        it: &mut impl Iterator<Item = &'t str>,
        what: &str,
    ) -> Result<&'t str, ModelError> {
        it.next()
            .ok_or_else(|| self.err(format!("line ends before {what} (truncated line?)")))
    }

    fn parse<T: std::str::FromStr>(&self, tok: &str, what: &str) -> Result<T, ModelError> {
        tok.parse()
            .map_err(|_| self.err(format!("bad {what}: {:?}", truncate(tok))))
    }

    fn float(&self, tok: &str, what: &str) -> Result<f64, ModelError> {
        let v: f64 = self.parse(tok, what)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(format!("{what} is not finite: {:?}", truncate(tok))))
        }
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

fn parse_cameras_text(path: &Path, bytes: &[u8]) -> Result<BTreeMap<u32, Camera>, ModelError> {
    let mut cameras = BTreeMap::new();
    for (line, text) in text_lines(path, bytes)? {
        if is_skipped(text) {
            continue;
        }
        let cx = LineCtx { path, line };
        let mut it = text.split_whitespace();
        let id: u32 = cx.parse(cx.field(&mut it, "CAMERA_ID")?, "CAMERA_ID")?;
        let model_name = cx.field(&mut it, "MODEL")?;
        let width: u64 = cx.parse(cx.field(&mut it, "WIDTH")?, "WIDTH")?;
        let height: u64 = cx.parse(cx.field(&mut it, "HEIGHT")?, "HEIGHT")?;
        let model = CameraModel::from_name(model_name).map_err(|e| cx.err(e.to_string()))?;
        let mut params = Vec::with_capacity(model.num_params());
        for tok in it {
            if params.len() >= model.num_params() {
                return Err(cx.err(format!(
                    "too many parameters for {model} (expected {}: {})",
                    model.num_params(),
                    model.params_info()
                )));
            }
            params.push(cx.float(tok, "camera parameter")?);
        }
        let cam = Camera::new(model, width, height, params).map_err(|e| cx.err(e.to_string()))?;
        if cameras.insert(id, cam).is_some() {
            return Err(cx.err(format!("duplicate camera id {id}")));
        }
    }
    Ok(cameras)
}

type Images = (BTreeMap<u32, Image>, BTreeMap<u32, Location>);

fn parse_images_text(path: &Path, bytes: &[u8]) -> Result<Images, ModelError> {
    let mut images = BTreeMap::new();
    let mut locs = BTreeMap::new();
    let mut lines = text_lines(path, bytes)?;
    while let Some((line, text)) = lines.next() {
        if is_skipped(text) {
            continue;
        }
        let cx = LineCtx { path, line };
        // IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (the name is the rest of the line).
        let mut rest = text.trim();
        let mut tok = [""; 9];
        const WHAT: [&str; 9] = [
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
        for (k, what) in WHAT.iter().enumerate() {
            let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
            if end == 0 {
                return Err(cx.err(format!("line ends before {what} (truncated line?)")));
            }
            tok[k] = &rest[..end];
            rest = rest[end..].trim_start();
        }
        let name = rest.to_string();
        if name.is_empty() {
            return Err(cx.err("line ends before NAME (truncated line?)"));
        }
        let id: u32 = cx.parse(tok[0], "IMAGE_ID")?;
        let mut q = [0.0; 4];
        for k in 0..4 {
            q[k] = cx.float(tok[1 + k], WHAT[1 + k])?;
        }
        check_quaternion(&q).map_err(|r| cx.err(r))?;
        let mut t = Vector3::zeros();
        for k in 0..3 {
            t[k] = cx.float(tok[5 + k], WHAT[5 + k])?;
        }
        let camera_id: u32 = cx.parse(tok[8], "CAMERA_ID")?;
        // The next line holds the observations (possibly empty), as COLMAP reads it.
        let mut points2d = Vec::new();
        let mut loc = Location::Line(line);
        if let Some((pline, ptext)) = lines.next() {
            let pc = LineCtx { path, line: pline };
            loc = Location::Line(pline);
            let toks: Vec<&str> = ptext.split_whitespace().collect();
            if !toks.chunks_exact(3).remainder().is_empty() {
                return Err(pc.err(format!(
                    "observations of image {id} must be triples X Y POINT3D_ID, got {} \
                     numbers (truncated line?)",
                    toks.len()
                )));
            }
            points2d.reserve(toks.len() / 3);
            for tr in toks.chunks_exact(3) {
                let x = pc.float(tr[0], "observation X")?;
                let y = pc.float(tr[1], "observation Y")?;
                let pid = if tr[2] == "-1" {
                    None
                } else {
                    Some(pc.parse::<u64>(tr[2], "POINT3D_ID")?)
                };
                points2d.push((Point2::new(x, y), pid));
            }
        }
        let img = Image {
            id,
            q,
            t,
            camera_id,
            name,
            points2d,
        };
        if images.insert(id, img).is_some() {
            return Err(cx.err(format!("duplicate image id {id}")));
        }
        locs.insert(id, loc);
    }
    Ok((images, locs))
}

fn check_quaternion(q: &[f64; 4]) -> Result<(), String> {
    let n2: f64 = q.iter().map(|x| x * x).sum();
    if n2.is_finite() && n2 > 1e-12 {
        Ok(())
    } else {
        Err(format!(
            "quaternion ({}, {}, {}, {}) is zero or not finite",
            q[0], q[1], q[2], q[3]
        ))
    }
}

fn parse_points_text(path: &Path, bytes: &[u8]) -> Result<BTreeMap<u64, Point3D>, ModelError> {
    let mut points = BTreeMap::new();
    for (line, text) in text_lines(path, bytes)? {
        if is_skipped(text) {
            continue;
        }
        let cx = LineCtx { path, line };
        let mut it = text.split_whitespace();
        let id: u64 = cx.parse(cx.field(&mut it, "POINT3D_ID")?, "POINT3D_ID")?;
        let mut xyz = [0.0; 3];
        for (k, what) in ["X", "Y", "Z"].iter().enumerate() {
            xyz[k] = cx.float(cx.field(&mut it, what)?, what)?;
        }
        let mut rgb = [0u8; 3];
        for (k, what) in ["R", "G", "B"].iter().enumerate() {
            rgb[k] = cx.parse(cx.field(&mut it, what)?, &format!("{what} (0-255)"))?;
        }
        let error: f64 = cx.parse(cx.field(&mut it, "ERROR")?, "ERROR")?;
        let toks: Vec<&str> = it.collect();
        if !toks.chunks_exact(2).remainder().is_empty() {
            return Err(cx.err(format!(
                "track of point {id} must be pairs IMAGE_ID POINT2D_IDX, got {} numbers \
                 (truncated line?)",
                toks.len()
            )));
        }
        let mut track = Vec::with_capacity(toks.len() / 2);
        for pair in toks.chunks_exact(2) {
            track.push((
                cx.parse::<u32>(pair[0], "track IMAGE_ID")?,
                cx.parse::<u32>(pair[1], "track POINT2D_IDX")?,
            ));
        }
        let p = Point3D {
            id,
            xyz: Point3::new(xyz[0], xyz[1], xyz[2]),
            rgb,
            error,
            track,
        };
        if points.insert(id, p).is_some() {
            return Err(cx.err(format!("duplicate 3D point id {id}")));
        }
    }
    Ok(points)
}

// ---------------------------------------------------------------------------------------------
// Binary format (little-endian; COLMAP's reconstruction_io / read_write_model.py layout).

struct Reader<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    fn err_at(&self, pos: usize, reason: impl Into<String>) -> ModelError {
        ModelError {
            file: self.path.to_path_buf(),
            location: Location::Offset(pos as u64),
            reason: reason.into(),
        }
    }

    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], ModelError> {
        if self.remaining() < n {
            return Err(self.err_at(
                self.pos,
                format!(
                    "unexpected end of file reading {what}: need {n} bytes, {} left \
                     (truncated file?)",
                    self.remaining()
                ),
            ));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], ModelError> {
        let s = self.take(N, what)?;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        Ok(a)
    }

    fn u64(&mut self, what: &str) -> Result<u64, ModelError> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }

    fn i64(&mut self, what: &str) -> Result<i64, ModelError> {
        Ok(i64::from_le_bytes(self.array(what)?))
    }

    fn u32(&mut self, what: &str) -> Result<u32, ModelError> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }

    fn i32(&mut self, what: &str) -> Result<i32, ModelError> {
        Ok(i32::from_le_bytes(self.array(what)?))
    }

    fn u8(&mut self, what: &str) -> Result<u8, ModelError> {
        Ok(self.array::<1>(what)?[0])
    }

    fn f64(&mut self, what: &str) -> Result<f64, ModelError> {
        let at = self.pos;
        let v = f64::from_le_bytes(self.array(what)?);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err_at(at, format!("{what} is not finite ({v})")))
        }
    }

    /// A count of records of at least `min_size` bytes each, checked against the bytes left
    /// (so a corrupt count can never cause a huge allocation or a long loop).
    fn count(&mut self, what: &str, min_size: usize) -> Result<usize, ModelError> {
        let at = self.pos;
        let n = self.u64(what)?;
        let fits = usize::try_from(n)
            .ok()
            .and_then(|n| n.checked_mul(min_size))
            .is_some_and(|b| b <= self.remaining());
        if !fits {
            return Err(self.err_at(
                at,
                format!(
                    "{what} = {n} needs at least {} bytes but only {} remain (corrupt or \
                     truncated file?)",
                    u128::from(n) * min_size as u128,
                    self.remaining()
                ),
            ));
        }
        Ok(n as usize)
    }

    fn finish(&self) -> Result<(), ModelError> {
        if self.remaining() == 0 {
            Ok(())
        } else {
            Err(self.err_at(
                self.pos,
                format!("{} unexpected trailing bytes", self.remaining()),
            ))
        }
    }
}

fn parse_cameras_bin(path: &Path, bytes: &[u8]) -> Result<BTreeMap<u32, Camera>, ModelError> {
    let mut r = Reader {
        path,
        bytes,
        pos: 0,
    };
    let n = r.count("number of cameras", 24)?;
    let mut cameras = BTreeMap::new();
    for _ in 0..n {
        let at = r.pos;
        let id = r.u32("CAMERA_ID")?;
        let model_id = r.i32("MODEL_ID")?;
        let width = r.u64("WIDTH")?;
        let height = r.u64("HEIGHT")?;
        let model =
            CameraModel::from_colmap_id(model_id).map_err(|e| r.err_at(at, e.to_string()))?;
        let mut params = Vec::with_capacity(model.num_params());
        for _ in 0..model.num_params() {
            params.push(r.f64("camera parameter")?);
        }
        let cam = Camera::new(model, width, height, params)
            .map_err(|e: CameraError| r.err_at(at, e.to_string()))?;
        if cameras.insert(id, cam).is_some() {
            return Err(r.err_at(at, format!("duplicate camera id {id}")));
        }
    }
    r.finish()?;
    Ok(cameras)
}

/// Longest image name accepted (bytes), a bound on the NUL search.
const MAX_NAME: usize = 1 << 16;

fn parse_images_bin(path: &Path, bytes: &[u8]) -> Result<Images, ModelError> {
    let mut r = Reader {
        path,
        bytes,
        pos: 0,
    };
    // Smallest record: 4 + 7 * 8 + 4 + 1 (empty name's NUL) + 8 = 73 bytes.
    let n = r.count("number of images", 73)?;
    let mut images = BTreeMap::new();
    let mut locs = BTreeMap::new();
    for _ in 0..n {
        let at = r.pos;
        let id = r.u32("IMAGE_ID")?;
        let mut q = [0.0; 4];
        for v in &mut q {
            *v = r.f64("quaternion")?;
        }
        check_quaternion(&q).map_err(|e| r.err_at(at, e))?;
        let mut t = Vector3::zeros();
        for k in 0..3 {
            t[k] = r.f64("translation")?;
        }
        let camera_id = r.u32("CAMERA_ID")?;
        let name_at = r.pos;
        let window = &r.bytes[r.pos..r.bytes.len().min(r.pos + MAX_NAME + 1)];
        let Some(len) = window.iter().position(|&b| b == 0) else {
            return Err(r.err_at(
                name_at,
                "image name is not NUL-terminated (truncated file, or name longer than 64 KiB)",
            ));
        };
        let name = std::str::from_utf8(&window[..len])
            .map_err(|_| r.err_at(name_at, "image name is not valid UTF-8"))?
            .to_string();
        r.pos += len + 1;
        let np = r.count("number of 2D points", 24)?;
        let mut points2d = Vec::with_capacity(np);
        for _ in 0..np {
            let x = r.f64("observation x")?;
            let y = r.f64("observation y")?;
            let pat = r.pos;
            let pid = r.i64("POINT3D_ID")?;
            let pid = match pid {
                -1 => None,
                p if p >= 0 => Some(p as u64),
                p => return Err(r.err_at(pat, format!("invalid POINT3D_ID {p}"))),
            };
            points2d.push((Point2::new(x, y), pid));
        }
        let img = Image {
            id,
            q,
            t,
            camera_id,
            name,
            points2d,
        };
        if images.insert(id, img).is_some() {
            return Err(r.err_at(at, format!("duplicate image id {id}")));
        }
        locs.insert(id, Location::Offset(at as u64));
    }
    r.finish()?;
    Ok((images, locs))
}

fn parse_points_bin(path: &Path, bytes: &[u8]) -> Result<BTreeMap<u64, Point3D>, ModelError> {
    let mut r = Reader {
        path,
        bytes,
        pos: 0,
    };
    // Smallest record: 8 + 3 * 8 + 3 + 8 + 8 = 51 bytes.
    let n = r.count("number of 3D points", 51)?;
    let mut points = BTreeMap::new();
    for _ in 0..n {
        let at = r.pos;
        let id = r.u64("POINT3D_ID")?;
        let mut xyz = [0.0; 3];
        for v in &mut xyz {
            *v = r.f64("point coordinate")?;
        }
        let rgb = [r.u8("colour")?, r.u8("colour")?, r.u8("colour")?];
        let error = f64::from_le_bytes(r.array("ERROR")?);
        let nt = r.count("track length", 8)?;
        let mut track = Vec::with_capacity(nt);
        for _ in 0..nt {
            track.push((r.u32("track IMAGE_ID")?, r.u32("track POINT2D_IDX")?));
        }
        let p = Point3D {
            id,
            xyz: Point3::new(xyz[0], xyz[1], xyz[2]),
            rgb,
            error,
            track,
        };
        if points.insert(id, p).is_some() {
            return Err(r.err_at(at, format!("duplicate 3D point id {id}")));
        }
    }
    r.finish()?;
    Ok(points)
}

/// Writes `model` in COLMAP's binary format (`cameras.bin`, `images.bin`, `points3D.bin`) to
/// `dir`, which must exist. Reading it back with [`read_model_binary`] gives an identical
/// model.
///
/// # Errors
/// Any I/O error.
pub fn write_model_binary(model: &Model, dir: impl AsRef<Path>) -> std::io::Result<()> {
    let dir = dir.as_ref();
    let mut b = Vec::new();
    b.extend_from_slice(&(model.cameras.len() as u64).to_le_bytes());
    for (id, cam) in &model.cameras {
        b.extend_from_slice(&id.to_le_bytes());
        b.extend_from_slice(&cam.model().colmap_id().to_le_bytes());
        b.extend_from_slice(&cam.width().to_le_bytes());
        b.extend_from_slice(&cam.height().to_le_bytes());
        for p in cam.params() {
            b.extend_from_slice(&p.to_le_bytes());
        }
    }
    std::fs::write(dir.join("cameras.bin"), &b)?;

    b.clear();
    b.extend_from_slice(&(model.images.len() as u64).to_le_bytes());
    for img in model.images.values() {
        if img.name.as_bytes().contains(&0) {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("image {} name contains a NUL byte", img.id),
            ));
        }
        b.extend_from_slice(&img.id.to_le_bytes());
        for v in img.q.iter().chain(img.t.iter()) {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&img.camera_id.to_le_bytes());
        b.extend_from_slice(img.name.as_bytes());
        b.push(0);
        b.extend_from_slice(&(img.points2d.len() as u64).to_le_bytes());
        for (px, pid) in &img.points2d {
            b.extend_from_slice(&px.x.to_le_bytes());
            b.extend_from_slice(&px.y.to_le_bytes());
            let id = pid.map_or(-1i64, |p| i64::try_from(p).unwrap_or(-1));
            b.extend_from_slice(&id.to_le_bytes());
        }
    }
    std::fs::write(dir.join("images.bin"), &b)?;

    b.clear();
    b.extend_from_slice(&(model.points.len() as u64).to_le_bytes());
    for p in model.points.values() {
        b.extend_from_slice(&p.id.to_le_bytes());
        for v in p.xyz.iter() {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&p.rgb);
        b.extend_from_slice(&p.error.to_le_bytes());
        b.extend_from_slice(&(p.track.len() as u64).to_le_bytes());
        for (i, k) in &p.track {
            b.extend_from_slice(&i.to_le_bytes());
            b.extend_from_slice(&k.to_le_bytes());
        }
    }
    std::fs::write(dir.join("points3D.bin"), &b)
}

// ---------------------------------------------------------------------------------------------
// Registration.

/// The result of [`register_image`].
#[derive(Clone, Debug)]
#[non_exhaustive]
pub struct Registration {
    /// Image id.
    pub image_id: u32,
    /// Image name.
    pub name: String,
    /// Number of 2D-3D correspondences used.
    pub n: usize,
    /// Correspondences counted as inliers (all of them in this non-robust mode).
    pub inliers: usize,
    /// Observations skipped because their pixel could not be undistorted.
    pub skipped: usize,
    /// The estimated pose.
    pub solution: Solution,
    /// Rotation difference to the model's pose, degrees (largest angle between corresponding
    /// columns, [`crate::metrics::rotation_error_deg`]).
    pub rotation_error_deg: f64,
    /// Translation difference to the model's pose, percent of the model's `|t|`
    /// ([`crate::metrics::translation_error_pct`]).
    pub translation_error_pct: f64,
    /// RMS reprojection error of the estimated pose in pixels, through the full camera model.
    pub rmse_px: f64,
    /// RMS reprojection error of the model's own pose in pixels, for comparison.
    pub model_rmse_px: f64,
    /// Wall time of undistortion plus solve, microseconds.
    pub micros: f64,
}

/// Errors of [`register_image`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum RegisterError {
    /// No image with this id in the model.
    UnknownImage(u32),
    /// The image's camera is missing from the model.
    UnknownCamera(u32),
    /// The solver failed.
    Solver(PnpError),
}

impl fmt::Display for RegisterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RegisterError::UnknownImage(i) => write!(f, "no image with id {i} in the model"),
            RegisterError::UnknownCamera(c) => write!(f, "no camera with id {c} in the model"),
            RegisterError::Solver(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for RegisterError {}

impl From<PnpError> for RegisterError {
    fn from(e: PnpError) -> Self {
        RegisterError::Solver(e)
    }
}

/// RMS pixel reprojection error of pose `(r, t)` through the full camera model.
fn pixel_rmse(
    cam: &Camera,
    world: &[Point3<f64>],
    pixels: &[Point2<f64>],
    r: &Matrix3<f64>,
    t: &Vector3<f64>,
) -> f64 {
    if world.is_empty() {
        return f64::NAN;
    }
    let mut s = 0.0;
    for (x, px) in world.iter().zip(pixels) {
        let p = r * x.coords + t;
        let q = cam.project(Point2::new(p.x / p.z, p.y / p.z));
        s += (q - px).norm_squared();
    }
    (s / world.len() as f64).sqrt()
}

/// Re-estimates the pose of image `image_id` from all its 2D-3D correspondences with `solver`
/// and compares it with the model's pose.
///
/// Solved with [`crate::camera::solve_pixels`]: the observed pixels are undistorted with the
/// image's camera and solved in normalised coordinates with per-point pixel-scale weights, so
/// the minimised error is, to first order, the pixel reprojection error that COLMAP's bundle
/// adjustment minimises. The time reported includes the undistortion.
///
/// # Errors
/// [`RegisterError`] for an unknown image or camera and for solver failures (e.g. fewer than
/// four correspondences).
pub fn register_image(
    model: &Model,
    image_id: u32,
    solver: &Solver,
) -> Result<Registration, RegisterError> {
    let (img, cam) = model.image_and_camera(image_id)?;
    let (world, pixels) = model.correspondences(image_id);

    let start = Instant::now();
    let sol = solver.solve_camera(cam, &world, &pixels)?;
    let micros = start.elapsed().as_secs_f64() * 1e6;
    let solution = sol.solution;

    let (r_ref, t_ref) = img.pose();
    let r = solution.rotation;
    let t = solution.pose.translation.vector;
    Ok(Registration {
        image_id,
        name: img.name.clone(),
        n: sol.used,
        inliers: sol.used,
        skipped: sol.skipped,
        rotation_error_deg: crate::metrics::rotation_error_deg(&r, &r_ref),
        translation_error_pct: crate::metrics::translation_error_pct(&t, &t_ref),
        rmse_px: pixel_rmse(cam, &world, &pixels, &r, &t),
        model_rmse_px: pixel_rmse(cam, &world, &pixels, &r_ref, &t_ref),
        solution,
        micros,
    })
}

#[cfg(test)]
mod tests;
