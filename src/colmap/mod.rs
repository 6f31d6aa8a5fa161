//! COLMAP sparse reconstructions: [`read_model`] reads the text (`cameras.txt`, `images.txt`,
//! `points3D.txt`) and binary (`cameras.bin`, `images.bin`, `points3D.bin`) formats,
//! [`write_model`] writes either atomically (reading back gives the identical [`Model`]), and
//! [`register_image`] re-estimates an image's pose from its 2D-3D correspondences
//! ([`Registrar`] for many images of one model).
//!
//! Conventions are COLMAP's: an image's pose `(q, t)` maps world to camera,
//! `x_cam = R(q) X + t`, with `q = (qw, qx, qy, qz)` a Hamilton quaternion; pixels follow
//! [`crate::camera`] (upper-left image corner at `(0, 0)`).
//!
//! Every reader is bounded and panic-free on any input: it streams (text token by token, binary
//! record by record), a count field can only claim as many records as the remaining bytes can
//! hold, only regular files are read (a FIFO or `/dev/zero` is refused before it is opened),
//! and the limits of [`ReadOptions`] bound one record; memory stays proportional to the model
//! returned. Every error carries the file name and the line number (text) or byte offset
//! (binary), its kind ([`ModelErrorKind`]: a limit hit names the limit) and the reason.
//!
//! ```
//! use eopnp::colmap::{
//!     read_model, register_image, write_model, ModelFormat, ReadOptions, Registrar, WriteOptions,
//! };
//! use eopnp::ransac::Ransac;
//! use eopnp::Solver;
//! use nalgebra::{Point3, UnitQuaternion, Vector3};
//!
//! // A small model in text form: one PINHOLE camera, ten 3D points, one image that sees them.
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
//! let dir = std::env::temp_dir().join(format!("eopnp-colmap-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! std::fs::write(dir.join("cameras.txt"), format!("1 PINHOLE 640 480 {f} {f} {cx} {cy}\n"))?;
//! std::fs::write(
//!     dir.join("images.txt"),
//!     format!("1 {w} {} {} {} {} {} {} 1 view.png\n{obs}\n", v.x, v.y, v.z, t.x, t.y, t.z),
//! )?;
//! let points3d: String = points
//!     .iter()
//!     .enumerate()
//!     .map(|(k, x)| format!("{} {} {} {} 200 200 200 0.5 1 {k}\n", k + 1, x.x, x.y, x.z))
//!     .collect();
//! std::fs::write(dir.join("points3D.txt"), points3d)?;
//! let model = read_model(&dir, &ReadOptions::default())?;
//!
//! // Re-estimate the image's pose from its correspondences alone, plain and with RANSAC.
//! let plain = register_image(&model, 1, &Solver::default(), None)?;
//! let robust = register_image(&model, 1, &Solver::default(), Some(&Ransac::default()))?;
//! assert!(plain.rotation_error_deg < 1e-9 && plain.rmse_px < 1e-6);
//! assert_eq!(robust.inliers, 10);
//!
//! // Many images of one model: a registrar builds its table of the 3D points once.
//! let mut registrar = Registrar::new(&model);
//! for id in model.images.keys() {
//!     let reg = registrar.register(*id, &Solver::default(), None)?;
//!     assert!(reg.rotation_error_deg < 1e-9);
//! }
//!
//! // Write it in binary (atomically) and read it back.
//! let bin = dir.join("binary");
//! write_model(&model, &bin, &WriteOptions::default().format(ModelFormat::Binary))?;
//! assert_eq!(read_model(&bin, &ReadOptions::default())?, model);
//! std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod binary;
mod model;
mod options;
mod register;
mod text;
mod write;

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use crate::source::{not_regular_message, open_regular, OpenError};

pub use model::{Image, Location, Model, ModelError, ModelErrorKind, Point3D, RegisterError};
pub use options::{Limit, ReadOptions};
#[cfg(test)]
pub(crate) use register::pixel_rmse;
pub use register::{register_image, Registrar, Registration};
#[cfg(feature = "internals")]
pub use write::encode_model;
pub use write::{write_model, Overwrite, WriteOptions};

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
/// default output, and exact), else text if all three `.txt` files exist. (Existing is
/// enough here: reading then refuses a model file that is not a regular file.)
///
/// # Errors
/// A [`ModelError`] of kind [`ModelErrorKind::Io`] naming the directory and the missing
/// files if neither set is complete.
pub fn detect_format(dir: &Path) -> Result<ModelFormat, ModelError> {
    let all = |names: &[&str; 3]| names.iter().all(|n| dir.join(n).exists());
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
            kind: ModelErrorKind::Io,
            reason,
        })
    }
}

/// Reads the model in `dir` and checks its cross-references (every image's camera and every
/// observed 3D point exist): in the format `options` names, or by default the one
/// [`detect_format`] finds (binary is preferred when both are present), within the readers'
/// limits ([`ReadOptions`]: see there for what reading costs).
///
/// # Errors
/// A [`ModelError`] with the file, line or byte offset, the kind (a missing or special file,
/// a limit, malformed content) and the reason; a limit that is hit is an error of kind
/// [`ModelErrorKind::Limit`].
pub fn read_model(dir: impl AsRef<Path>, options: &ReadOptions) -> Result<Model, ModelError> {
    let dir = dir.as_ref();
    let format = match options.format {
        Some(f) => f,
        None => detect_format(dir)?,
    };
    read_with(format, dir, options)
}

/// Opens a model file: a regular file within the size limit.
fn open_file(path: &Path, limits: &ReadOptions) -> Result<(std::fs::File, u64), ModelError> {
    let error = |kind, reason| ModelError {
        file: path.to_path_buf(),
        location: Location::File,
        kind,
        reason,
    };
    let (file, len) = open_regular(path).map_err(|e| match e {
        OpenError::NotRegular(what) => error(
            ModelErrorKind::NotRegularFile,
            format!(
                "{}; a model file must be a regular file",
                not_regular_message(what)
            ),
        ),
        OpenError::Io(e) => error(ModelErrorKind::Io, format!("cannot read: {e}")),
    })?;
    check_size(path, len, limits)?;
    Ok((file, len))
}

fn check_size(path: &Path, len: u64, limits: &ReadOptions) -> Result<(), ModelError> {
    if len > limits.max_file_bytes {
        return Err(ModelError::limit(
            path,
            Location::File,
            Limit::FileBytes(limits.max_file_bytes),
            &format!("the file is {len} bytes long"),
        ));
    }
    Ok(())
}

/// Parses a model of format `format` from the contents of its three files (cameras, images,
/// points3D), within the limits of `limits` (its format is not used). Errors name the files
/// by their usual names (`cameras.txt`, ...). Feature `internals`: for the fuzz harness and
/// tests, not a stable API.
///
/// # Errors
/// As [`read_model`].
#[cfg(feature = "internals")]
pub fn parse_model(
    format: ModelFormat,
    files: [&[u8]; 3],
    limits: &ReadOptions,
) -> Result<Model, ModelError> {
    let paths = format.file_names().map(PathBuf::from);
    for (path, bytes) in paths.iter().zip(files) {
        check_size(path, bytes.len() as u64, limits)?;
    }
    let [cl, il, pl] = files.map(|f| f.len() as u64);
    let [mut c, mut i, mut p] = files;
    parse_with(
        format,
        &paths,
        [(&mut c, cl), (&mut i, il), (&mut p, pl)],
        limits,
    )
}

/// [`parse_model`] reading each file through a buffer of `capacity` bytes, as [`read_model`]
/// reads a file: for tests and fuzzing of the streaming (tokens, names and records cut at
/// buffer boundaries). Feature `internals`: not a stable API.
#[cfg(feature = "internals")]
pub fn parse_model_buffered(
    format: ModelFormat,
    files: [&[u8]; 3],
    limits: &ReadOptions,
    capacity: usize,
) -> Result<Model, ModelError> {
    let paths = format.file_names().map(PathBuf::from);
    for (path, bytes) in paths.iter().zip(files) {
        check_size(path, bytes.len() as u64, limits)?;
    }
    let [cl, il, pl] = files.map(|f| f.len() as u64);
    let [mut c, mut i, mut p] = files.map(|f| BufReader::with_capacity(capacity.max(1), f));
    parse_with(
        format,
        &paths,
        [(&mut c, cl), (&mut i, il), (&mut p, pl)],
        limits,
    )
}

/// Opens the three files (so that a missing or special file is reported before any content),
/// then streams each through a buffer, never past the size it had when opened.
fn read_with(format: ModelFormat, dir: &Path, limits: &ReadOptions) -> Result<Model, ModelError> {
    let paths = format.file_names().map(|n| dir.join(n));
    let [c, i, p] = [0, 1, 2].map(|k| open_file(&paths[k], limits));
    let [c, i, p] = [c?, i?, p?].map(|(file, len)| (BufReader::new(file.take(len)), len));
    let ((mut c, cl), (mut i, il), (mut p, pl)) = (c, i, p);
    parse_with(
        format,
        &paths,
        [(&mut c, cl), (&mut i, il), (&mut p, pl)],
        limits,
    )
}

/// Parses the three files of a model: each source with its length in bytes. (Generic, not
/// `dyn`: the readers call the source for every token.)
fn parse_with<R: BufRead>(
    format: ModelFormat,
    paths: &[PathBuf; 3],
    [(c, cl), (i, il), (p, pl)]: [(&mut R, u64); 3],
    limits: &ReadOptions,
) -> Result<Model, ModelError> {
    let (cameras, (images, locs), points) = match format {
        ModelFormat::Text => (
            text::parse_cameras_text(&paths[0], c, cl, limits)?,
            text::parse_images_text(&paths[1], i, il, limits)?,
            text::parse_points_text(&paths[2], p, pl, limits)?,
        ),
        ModelFormat::Binary => (
            binary::parse_cameras_bin(&paths[0], c, cl, limits)?,
            binary::parse_images_bin(&paths[1], i, il, limits)?,
            binary::parse_points_bin(&paths[2], p, pl, limits)?,
        ),
    };
    let model = Model {
        cameras,
        images,
        points,
    };
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
        let err = |reason: String| ModelError::invalid(images_file, location, reason);
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
