//! COLMAP sparse reconstructions: [`read_model`] reads the text (`cameras.txt`, `images.txt`,
//! `points3D.txt`) and binary (`cameras.bin`, `images.bin`, `points3D.bin`) formats,
//! [`write_model`] writes either atomically (reading back gives the identical [`Model`]), and
//! [`register_image`] re-estimates an image's pose from its 2D-3D correspondences
//! ([`Registrar`] for many images of one model; [`register_image_with`] with a
//! [`crate::Problem`]'s options, such as an unknown focal length).
//!
//! Conventions are COLMAP's: an image's pose `(q, t)` maps world to camera,
//! `x_cam = R(q) X + t`, with `q = (qw, qx, qy, qz)` a Hamilton quaternion; pixels follow
//! [`crate::camera`] (upper-left image corner at `(0, 0)`).
//!
//! # Rigs and frames
//!
//! A model may also hold rigs and frames, in the format of COLMAP 3.12 (the release that
//! introduced them; pycolmap 4.x writes the same files): `rigs.txt` and `frames.txt`, or
//! `rigs.bin` and `frames.bin`, next to the other three. They are read when present (both, or
//! an error names the missing one) into [`Model::rigs`] and [`Model::frames`], and written
//! when those are not empty; a model without them reads and writes exactly as before.
//!
//! - A rig ([`SensorRig`]) is a set of sensors fixed to one body: a reference sensor, whose
//!   pose in the rig is the identity (the rig's frame *is* the reference sensor's), and the
//!   others, each with its `sensor_from_rig` pose, `x_sensor = R x_rig + t` (COLMAP's
//!   `cam_from_rig` for a camera), or none if unknown.
//! - A frame ([`Frame`]) is one capture by a rig: its `rig_from_world` pose,
//!   `x_rig = R X + t`, and its data, each a sensor of the rig and the datum's id (for a
//!   camera, an image id). Every image is in exactly one frame, and its pose is the composed
//!   `cam_from_world = cam_from_rig * rig_from_world`; COLMAP still stores that pose in the
//!   images file, and this crate keeps it as read.
//!
//! [`register_frame`] re-estimates a frame's `rig_from_world` from the correspondences of all
//! its images at once (one [`crate::Rig`] pose, [`crate::Problem::rig`]) and compares it with
//! the model's. The readers check what ties the files together (every frame's rig, every
//! rig's camera, every frame's image, every image in one frame) and locate an error in the
//! file, line or offset of the record it is about.
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
mod pose;
mod register;
mod rigs;
mod text;
mod write;

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use crate::source::{not_regular_message, open_regular, OpenError};

pub use model::{Image, Location, Model, ModelError, ModelErrorKind, Point3D, RegisterError};
pub use options::{Limit, ReadOptions};
pub use pose::Pose;
#[cfg(test)]
pub(crate) use register::pixel_rmse;
pub use register::{
    register_frame, register_image, register_image_with, FrameRegistration, Registrar, Registration,
};
use rigs::Culprit;
pub use rigs::{DataId, Frame, SensorId, SensorRig, SensorType};
#[cfg(feature = "internals")]
pub use write::{encode_model, encode_model_files};
pub use write::{write_model, Overwrite, WriteOptions};

/// The on-disk format of a model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelFormat {
    /// `cameras.txt`, `images.txt`, `points3D.txt` (and `rigs.txt`, `frames.txt`).
    Text,
    /// `cameras.bin`, `images.bin`, `points3D.bin` (and `rigs.bin`, `frames.bin`).
    Binary,
}

const TEXT_FILES: [&str; 3] = ["cameras.txt", "images.txt", "points3D.txt"];
const BIN_FILES: [&str; 3] = ["cameras.bin", "images.bin", "points3D.bin"];
const TEXT_RIG_FILES: [&str; 2] = ["rigs.txt", "frames.txt"];
const BIN_RIG_FILES: [&str; 2] = ["rigs.bin", "frames.bin"];

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
/// observed 3D point exist; for a model with rigs, the rigs' cameras, the frames' rigs and
/// images, and every image in one frame): in the format `options` names, or by default the one
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
    parse_files(format, files, None, limits, None)
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
    parse_files(format, files, None, limits, Some(capacity))
}

/// [`parse_model`] of a model with rigs: `files` are cameras, images, points3D, rigs and
/// frames (the files [`ModelFormat::file_names`] and [`ModelFormat::rig_file_names`] name),
/// read whole, or through a buffer of `capacity` bytes as in [`parse_model_buffered`].
/// Feature `internals`: not a stable API.
///
/// # Errors
/// As [`read_model`].
#[cfg(feature = "internals")]
pub fn parse_model_with_rigs(
    format: ModelFormat,
    files: [&[u8]; 5],
    limits: &ReadOptions,
    capacity: Option<usize>,
) -> Result<Model, ModelError> {
    let [c, i, p, r, f] = files;
    parse_files(format, [c, i, p], Some([r, f]), limits, capacity)
}

/// The in-memory readers: the three files and, if given, the two rig files, whole or through
/// a buffer of `capacity` bytes.
#[cfg(feature = "internals")]
fn parse_files(
    format: ModelFormat,
    files: [&[u8]; 3],
    rig_files: Option<[&[u8]; 2]>,
    limits: &ReadOptions,
    capacity: Option<usize>,
) -> Result<Model, ModelError> {
    let paths = format.file_names().map(PathBuf::from);
    let rig_paths = format.rig_file_names().map(PathBuf::from);
    for (path, bytes) in paths.iter().zip(files) {
        check_size(path, bytes.len() as u64, limits)?;
    }
    for (path, bytes) in rig_paths.iter().zip(rig_files.iter().flatten()) {
        check_size(path, bytes.len() as u64, limits)?;
    }
    let [cl, il, pl] = files.map(|f| f.len() as u64);
    let rig_lens = rig_files.map(|r| r.map(|f| f.len() as u64));
    match capacity {
        None => {
            let [mut c, mut i, mut p] = files;
            let mut rigs = rig_files;
            let rig_sources = rigs
                .as_mut()
                .zip(rig_lens)
                .map(|([r, f], [rl, fl])| [(r, rl), (f, fl)]);
            parse_with(
                format,
                &paths,
                [(&mut c, cl), (&mut i, il), (&mut p, pl)],
                (&rig_paths, rig_sources),
                limits,
            )
        }
        Some(capacity) => {
            let capacity = capacity.max(1);
            let [mut c, mut i, mut p] = files.map(|f| BufReader::with_capacity(capacity, f));
            let mut rigs = rig_files.map(|r| r.map(|f| BufReader::with_capacity(capacity, f)));
            let rig_sources = rigs
                .as_mut()
                .zip(rig_lens)
                .map(|([r, f], [rl, fl])| [(r, rl), (f, fl)]);
            parse_with(
                format,
                &paths,
                [(&mut c, cl), (&mut i, il), (&mut p, pl)],
                (&rig_paths, rig_sources),
                limits,
            )
        }
    }
}

/// Whether the model in `dir` has rig files (both, or an error naming the missing one): a
/// path that exists in any form counts (a dangling link, a directory are refused when
/// opened).
fn has_rig_files(dir: &Path, format: ModelFormat) -> Result<bool, ModelError> {
    let [rigs, frames] = format.rig_file_names();
    let exists = |n: &str| std::fs::symlink_metadata(dir.join(n)).is_ok();
    match (exists(rigs), exists(frames)) {
        (false, false) => Ok(false),
        (true, true) => Ok(true),
        (has_rigs, _) => {
            let (present, missing) = if has_rigs {
                (rigs, frames)
            } else {
                (frames, rigs)
            };
            Err(ModelError {
                file: dir.join(missing),
                location: Location::File,
                kind: ModelErrorKind::Io,
                reason: format!(
                    "missing, but {present} is there: a model with rigs (COLMAP 3.12 and \
                     later) has both {rigs} and {frames}"
                ),
            })
        }
    }
}

/// Opens the model's files (so that a missing or special file is reported before any
/// content), then streams each through a buffer, never past the size it had when opened.
fn read_with(format: ModelFormat, dir: &Path, limits: &ReadOptions) -> Result<Model, ModelError> {
    let paths = format.file_names().map(|n| dir.join(n));
    let rig_paths = format.rig_file_names().map(|n| dir.join(n));
    let [c, i, p] = [0, 1, 2].map(|k| open_file(&paths[k], limits));
    let [c, i, p] = [c?, i?, p?].map(|(file, len)| (BufReader::new(file.take(len)), len));
    let mut rigs = if has_rig_files(dir, format)? {
        let [r, f] = [0, 1].map(|k| open_file(&rig_paths[k], limits));
        Some([r?, f?].map(|(file, len)| (BufReader::new(file.take(len)), len)))
    } else {
        None
    };
    let ((mut c, cl), (mut i, il), (mut p, pl)) = (c, i, p);
    let rig_sources = rigs.as_mut().map(|[(r, rl), (f, fl)]| [(r, *rl), (f, *fl)]);
    parse_with(
        format,
        &paths,
        [(&mut c, cl), (&mut i, il), (&mut p, pl)],
        (&rig_paths, rig_sources),
        limits,
    )
}

/// The rig files' paths and, for a model with rigs, their sources with their lengths.
type RigSources<'a, R> = (&'a [PathBuf; 2], Option<[(&'a mut R, u64); 2]>);

/// Parses the files of a model: each source with its length in bytes. (Generic, not `dyn`:
/// the readers call the source for every token.)
fn parse_with<R: BufRead>(
    format: ModelFormat,
    paths: &[PathBuf; 3],
    [(c, cl), (i, il), (p, pl)]: [(&mut R, u64); 3],
    (rig_paths, rig_sources): RigSources<'_, R>,
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
    let with_rigs = rig_sources.is_some();
    let ((rigs, rig_locs), (frames, frame_locs)) = match rig_sources {
        None => Default::default(),
        Some([(r, rl), (f, fl)]) => match format {
            ModelFormat::Text => (
                text::parse_rigs_text(&rig_paths[0], r, rl, limits)?,
                text::parse_frames_text(&rig_paths[1], f, fl, limits)?,
            ),
            ModelFormat::Binary => (
                binary::parse_rigs_bin(&rig_paths[0], r, rl, limits)?,
                binary::parse_frames_bin(&rig_paths[1], f, fl, limits)?,
            ),
        },
    };
    let model = Model {
        cameras,
        images,
        points,
        rigs,
        frames,
    };
    check_references(&model, &paths[1], &locs)?;
    rigs::check_rigs(&model, with_rigs).map_err(|(culprit, reason)| {
        let (file, locs, id) = match culprit {
            Culprit::Rig(id) => (&rig_paths[0], &rig_locs, id),
            Culprit::Frame(id) => (&rig_paths[1], &frame_locs, id),
            Culprit::Image(id) => (&paths[1], &locs, id),
        };
        let location = locs.get(&id).copied().unwrap_or(Location::File);
        ModelError::invalid(file, location, reason)
    })?;
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
