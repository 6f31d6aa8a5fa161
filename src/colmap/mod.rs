//! COLMAP sparse reconstructions: readers for the text (`cameras.txt`, `images.txt`,
//! `points3D.txt`) and binary (`cameras.bin`, `images.bin`, `points3D.bin`) formats, an atomic
//! writer of both ([`write_model`]: reading back gives the identical [`Model`]), and
//! [`register_image`], which re-estimates an image's pose from its 2D-3D correspondences.
//!
//! Conventions are COLMAP's: an image's pose `(q, t)` maps world to camera,
//! `x_cam = R(q) X + t`, with `q = (qw, qx, qy, qz)` a Hamilton quaternion; pixels follow
//! [`crate::camera`] (upper-left image corner at `(0, 0)`).
//!
//! Every reader is bounded and panic-free on any input: a count field can only claim as many
//! records as the remaining bytes can hold, and every error carries the file name and the
//! line number (text) or byte offset (binary) with the reason.
//!
//! ```
//! use eopnp::colmap::{parse_model_text, read_model, register_image, write_model, ModelFormat};
//! use eopnp::ransac::Ransac;
//! use eopnp::Solver;
//! use nalgebra::{Point3, UnitQuaternion, Vector3};
//!
//! // A small model: one PINHOLE camera, ten 3D points, one image that observes them all.
//! let (f, cx, cy) = (800.0, 320.0, 240.0);
//! let points: Vec<Point3<f64>> = (0..10)
//!     .map(|i| Point3::new((i % 3) as f64 - 1.0, (i % 4) as f64 * 0.5 - 0.7, (i % 5) as f64 * 0.3))
//!     .collect();
//! let q = UnitQuaternion::from_euler_angles(0.1, -0.2, 0.3);
//! let t = Vector3::new(0.1, -0.2, 6.0);
//! let mut obs = String::new();
//! for (k, x) in points.iter().enumerate() {
//!     let p = q * x + t;
//!     obs += &format!("{} {} {} ", f * p.x / p.z + cx, f * p.y / p.z + cy, k + 1);
//! }
//! let (w, v) = (q.quaternion().w, q.quaternion().imag());
//! let cameras = format!("1 PINHOLE 640 480 {f} {f} {cx} {cy}\n");
//! let images = format!("1 {w} {} {} {} {} {} {} 1 view.png\n{obs}\n", v.x, v.y, v.z, t.x, t.y, t.z);
//! let points3d: String = points
//!     .iter()
//!     .enumerate()
//!     .map(|(k, x)| format!("{} {} {} {} 200 200 200 0.5 1 {k}\n", k + 1, x.x, x.y, x.z))
//!     .collect();
//! let model = parse_model_text(cameras.as_bytes(), images.as_bytes(), points3d.as_bytes())?;
//!
//! // Re-estimate the image's pose from its correspondences alone, plain and with RANSAC.
//! let plain = register_image(&model, 1, &Solver::default(), None)?;
//! let robust = register_image(&model, 1, &Solver::default(), Some(&Ransac::default()))?;
//! assert!(plain.rotation_error_deg < 1e-9 && plain.rmse_px < 1e-6);
//! assert_eq!(robust.inliers, 10);
//!
//! // Write it (atomically) and read it back.
//! let dir = std::env::temp_dir().join(format!("eopnp-colmap-doc-{}", std::process::id()));
//! write_model(&model, &dir, ModelFormat::Binary)?;
//! assert_eq!(read_model(&dir)?, model);
//! std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod binary;
mod model;
mod register;
mod text;
mod write;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use crate::camera::Camera;

pub use model::{quaternion_to_matrix, Image, Location, Model, ModelError, Point3D, RegisterError};
#[cfg(feature = "cli")]
pub(crate) use register::pixel_rmse;
pub use register::{register_image, Registration};
pub use write::{encode_model, write_model, write_model_binary, write_model_with, Overwrite};

use model::Images;

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
        } else if dir.exists() {
            "not a directory: a COLMAP model is a directory holding cameras, images and \
             points3D files"
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
    cameras: text::parse_cameras_text,
    images: text::parse_images_text,
    points: text::parse_points_text,
};

const BINARY: Format = Format {
    files: BIN_FILES,
    cameras: binary::parse_cameras_bin,
    images: binary::parse_images_bin,
    points: binary::parse_points_bin,
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

#[cfg(test)]
#[path = "../../tests/unit/colmap.rs"]
mod tests;
