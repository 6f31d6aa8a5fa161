//! Writing a model, text or binary, atomically: the model is checked and encoded in memory
//! first, then written to temporary files that are fsynced and renamed into place.
//!
//! Guarantees (see [`write_model`] and [`WriteOptions`]):
//! - `dir` does not exist: the model is written into a fresh temporary directory next to it
//!   (`.<name>.tmp-<pid>-<n>`), which is renamed to `dir`. All or nothing, even across a
//!   crash: `dir` either does not appear or appears with the complete model.
//! - `dir` is an existing empty directory (or, with [`Overwrite::Files`], any directory): each
//!   file is written to `.<file>.tmp-<pid>-<n>` in `dir`, fsynced, and renamed over its final
//!   name. Every file is replaced atomically (never truncated or half-written), and on any
//!   error the directory is returned to its previous state (temporaries removed, replaced
//!   files restored from hard-link backups). The three renames are not one atomic step: a
//!   crash during them can leave a mix of old and new files, and dot-named temporaries.

use std::fs::{self, File, OpenOptions};
use std::io::{self, ErrorKind, Write as _};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

use super::binary::{encode_binary, encode_rigs_binary, MAX_NAME};
use super::model::Model;
use super::pose::check_quaternion;
use super::rigs::check_rigs;
use super::text::{encode_rigs_text, encode_text, text_name_ok};
use super::{ModelFormat, BIN_FILES, BIN_RIG_FILES, TEXT_RIG_FILES};
use crate::camera::Camera;

/// What [`write_model`] may do to an existing, non-empty directory ([`WriteOptions::overwrite`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[non_exhaustive]
pub enum Overwrite {
    /// Refuse ([`ErrorKind::DirectoryNotEmpty`]) if `dir` exists and is not empty; nothing is
    /// written. The default.
    #[default]
    Never,
    /// Write into an existing directory whatever it holds, replacing the three files of the
    /// format (other files are left alone). Refused ([`ErrorKind::AlreadyExists`]) when writing
    /// text into a directory that holds a complete binary model, which readers (this crate's,
    /// COLMAP's) would keep preferring over the new text files.
    Files,
}

/// How [`write_model`] writes a model: its format and what it may overwrite.
///
/// ```
/// use eopnp::colmap::{ModelFormat, Overwrite, WriteOptions};
///
/// // The default: COLMAP's binary format, into a new or empty directory.
/// let new_dir = WriteOptions::default();
/// // Text, replacing the three text files of an existing model (other files are kept).
/// let replace = WriteOptions::default().format(ModelFormat::Text).overwrite(Overwrite::Files);
/// # let _ = (new_dir, replace);
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriteOptions {
    format: ModelFormat,
    overwrite: Overwrite,
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions {
            format: ModelFormat::Binary,
            overwrite: Overwrite::Never,
        }
    }
}

impl WriteOptions {
    /// The format to write. Default: [`ModelFormat::Binary`] (COLMAP's own default output;
    /// both formats read back exactly).
    #[must_use]
    pub fn format(mut self, format: ModelFormat) -> Self {
        self.format = format;
        self
    }

    /// What to do to an existing, non-empty directory. Default: [`Overwrite::Never`].
    #[must_use]
    pub fn overwrite(mut self, overwrite: Overwrite) -> Self {
        self.overwrite = overwrite;
        self
    }
}

impl ModelFormat {
    /// The three file names of the format: cameras, images, 3D points.
    #[must_use]
    pub fn file_names(self) -> [&'static str; 3] {
        match self {
            ModelFormat::Text => super::TEXT_FILES,
            ModelFormat::Binary => BIN_FILES,
        }
    }

    /// The two file names of a model with rigs (COLMAP 3.12 and later): rigs, frames.
    #[must_use]
    pub fn rig_file_names(self) -> [&'static str; 2] {
        match self {
            ModelFormat::Text => TEXT_RIG_FILES,
            ModelFormat::Binary => BIN_RIG_FILES,
        }
    }
}

fn invalid(format: ModelFormat, reason: String) -> io::Error {
    let f = match format {
        ModelFormat::Text => "text",
        ModelFormat::Binary => "binary",
    };
    io::Error::new(
        ErrorKind::InvalidInput,
        format!("cannot write the model in {f} format: {reason}"),
    )
}

/// Checks that `model` reads back identically from `format`: everything the reader rejects
/// (non-finite or zero quaternion, non-finite coordinates, a missing camera or observed 3D
/// point, a map key different from the record's id, a camera model COLMAP does not know) and
/// what the format cannot represent.
fn validate(model: &Model, format: ModelFormat) -> io::Result<()> {
    let bad = |reason: String| Err(invalid(format, reason));
    for (id, cam) in &model.cameras {
        if cam.model().colmap_id().is_none() {
            return bad(format!(
                "camera {id}: model {} is not a COLMAP model",
                cam.model()
            ));
        }
        if let Err(e) = Camera::new(
            cam.model(),
            cam.width(),
            cam.height(),
            cam.params().to_vec(),
        ) {
            return bad(format!("camera {id}: {e}"));
        }
    }
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    for (key, img) in &model.images {
        let id = img.id;
        if *key != id {
            return bad(format!("image {id} is stored under key {key}"));
        }
        if let Err(e) = check_quaternion(&img.q) {
            return bad(format!("image {id}: {e}"));
        }
        if !finite(img.t.as_slice()) {
            return bad(format!("image {id}: translation is not finite"));
        }
        if !model.cameras.contains_key(&img.camera_id) {
            return bad(format!(
                "image {id} refers to camera {}, which is not in the model",
                img.camera_id
            ));
        }
        let name_ok = match format {
            ModelFormat::Text => text_name_ok(&img.name),
            ModelFormat::Binary => !img.name.contains('\0') && img.name.len() <= MAX_NAME,
        };
        if !name_ok {
            let rule = match format {
                ModelFormat::Text => {
                    "must be one non-empty line without leading or trailing whitespace"
                }
                ModelFormat::Binary => "must not contain a NUL byte or be longer than 64 KiB",
            };
            return bad(format!("image {id}: name {:?} {rule}", img.name));
        }
        for (k, (px, pid)) in img.points2d.iter().enumerate() {
            if !finite(px.coords.as_slice()) {
                return bad(format!("image {id}: observation {k} is not finite"));
            }
            if let Some(p) = pid {
                if !model.points.contains_key(p) {
                    return bad(format!(
                        "observation {k} of image {id} refers to 3D point {p}, which is not in \
                         the model"
                    ));
                }
                if format == ModelFormat::Binary && i64::try_from(*p).is_err() {
                    return bad(format!(
                        "observation {k} of image {id}: 3D point id {p} does not fit the \
                         format's signed 64-bit field"
                    ));
                }
            }
        }
    }
    for (key, pt) in &model.points {
        if *key != pt.id {
            return bad(format!("3D point {} is stored under key {key}", pt.id));
        }
        if !finite(pt.xyz.coords.as_slice()) {
            return bad(format!("3D point {key}: coordinates are not finite"));
        }
    }
    check_rigs(model, has_rigs(model)).or_else(|(_, reason)| bad(reason))?;
    for rig in model.rigs.values() {
        if rig.sensors.len() >= u32::MAX as usize {
            return bad(format!("rig {}: too many sensors for the format", rig.id));
        }
    }
    for frame in model.frames.values() {
        if u32::try_from(frame.data_ids.len()).is_err() {
            return bad(format!(
                "frame {}: too many data ids for the format",
                frame.id
            ));
        }
    }
    Ok(())
}

/// Whether the model has rig files to write: it has rigs or frames.
fn has_rigs(model: &Model) -> bool {
    !model.rigs.is_empty() || !model.frames.is_empty()
}

/// The contents of the model's three files (cameras, images, 3D points, in the order of
/// [`ModelFormat::file_names`]) in `format`, as [`write_model`] writes them, for a model
/// without rigs ([`encode_model_files`] encodes any model). Text numbers are in Rust's
/// shortest round-trip form, so parsing the result gives `model` back exactly (every `f64`
/// bit for bit, except that a NaN ERROR of a 3D point reads back as the canonical NaN in
/// text). Feature `internals` (for the fuzz harness): not a stable API.
///
/// # Errors
/// [`ErrorKind::InvalidInput`] for a model with rigs or frames, and if the model would not
/// read back identically: a non-finite or zero quaternion, a non-finite translation, pixel or
/// 3D point, a missing camera or observed 3D point, a map key that differs from the record's
/// id, a camera model without a COLMAP id
/// ([`crate::camera::CameraModel::OpenCvThinPrismTilted`]); text: an image name that is empty,
/// spans lines or has leading or trailing whitespace; binary: a name with a NUL byte or longer
/// than 64 KiB, an observed 3D point id above `i64::MAX`.
#[cfg(feature = "internals")]
pub fn encode_model(model: &Model, format: ModelFormat) -> io::Result<[Vec<u8>; 3]> {
    if has_rigs(model) {
        return Err(invalid(
            format,
            "the model has rigs or frames: encode it with encode_model_files".to_string(),
        ));
    }
    let mut files = encode_all(model, format)?
        .into_iter()
        .map(|(_, bytes)| bytes);
    let mut next = || files.next().unwrap_or_default();
    Ok([next(), next(), next()])
}

/// The files of the model as [`write_model`] writes them, each with its name: the three of
/// [`ModelFormat::file_names`], then for a model with rigs or frames the two of
/// [`ModelFormat::rig_file_names`]. Feature `internals` (for the fuzz harness): not a stable
/// API.
///
/// # Errors
/// As [`write_model`]'s [`ErrorKind::InvalidInput`].
#[cfg(feature = "internals")]
pub fn encode_model_files(
    model: &Model,
    format: ModelFormat,
) -> io::Result<Vec<(&'static str, Vec<u8>)>> {
    encode_all(model, format)
}

fn encode_all(model: &Model, format: ModelFormat) -> io::Result<Vec<(&'static str, Vec<u8>)>> {
    validate(model, format)?;
    let files = match format {
        ModelFormat::Text => encode_text(model),
        ModelFormat::Binary => encode_binary(model),
    };
    let mut named: Vec<_> = format.file_names().into_iter().zip(files).collect();
    if has_rigs(model) {
        let rig_files = match format {
            ModelFormat::Text => encode_rigs_text(model),
            ModelFormat::Binary => encode_rigs_binary(model),
        };
        named.extend(format.rig_file_names().into_iter().zip(rig_files));
    }
    Ok(named)
}

/// Writes `model` to the directory `dir`, atomically, in the format of `options`
/// ([`WriteOptions`]; default binary).
///
/// - `dir` does not exist (its parent must): the model is written into a fresh temporary
///   directory next to it (`.<name>.tmp-<pid>-<n>` in the parent), every file fsynced, and the
///   directory renamed to `dir`: all or nothing, even across a crash.
/// - `dir` is an empty directory: each file is written to `.<file>.tmp-<pid>-<n>` in `dir`,
///   fsynced and renamed into place; on any error the files already renamed and the
///   temporaries are removed (`dir` is empty again). A crash during the renames can leave
///   part of the model.
/// - `dir` exists and is not empty: refused, unless [`WriteOptions::overwrite`] is
///   [`Overwrite::Files`]: then the files of the format are replaced one by one, each
///   atomically (a hard-link backup of each existing file is taken first), and for a model
///   without rigs the format's rig files, if any, are removed (a stale `rigs.txt` would
///   otherwise be read with the new model); on any error the directory is restored (old
///   files back in place, temporaries and backups removed); a crash during the renames can
///   leave a mix of old and new files (and dot-named `.tmp-`/`.bak-` files, which no reader
///   takes for a model).
///
/// The files are the three of [`ModelFormat::file_names`] and, for a model with rigs or
/// frames ([`Model::rigs`], [`Model::frames`]), the two of [`ModelFormat::rig_file_names`] in
/// COLMAP 3.12's layout. The model is checked and encoded in memory first, so an
/// unrepresentable model fails before anything is created. Reading `dir` back
/// ([`super::read_model`]) gives `model` exactly (every `f64` bit for bit: text numbers are
/// written in Rust's shortest round-trip form).
///
/// # Errors
/// [`ErrorKind::InvalidInput`] if the model would not read back identically (a non-finite or
/// zero quaternion, a non-finite translation, pixel or 3D point, a missing camera or observed
/// 3D point, a map key that differs from the record's id, a camera model without a COLMAP id
/// ([`crate::camera::CameraModel::OpenCvThinPrismTilted`]); text: an image name that is empty,
/// spans lines or has leading or trailing whitespace; binary: a name with a NUL byte or longer
/// than 64 KiB, an observed 3D point id above `i64::MAX`; rigs and frames that do not read
/// back: a frame's rig, a sensor's camera or a datum's image missing, an image in no frame or
/// in two, a pose that is not finite), or for a `dir` without a final name (`/`, `..`);
/// [`ErrorKind::DirectoryNotEmpty`] if `dir` exists and is not empty (with
/// [`Overwrite::Never`]); [`ErrorKind::AlreadyExists`] for text over a complete binary model
/// (with [`Overwrite::Files`]); [`ErrorKind::NotADirectory`] if `dir` or its parent is not a
/// directory; [`ErrorKind::NotFound`] if the parent does not exist; any I/O error of the
/// writing (in every case with nothing of the model left behind, or the previous files
/// restored).
pub fn write_model(model: &Model, dir: impl AsRef<Path>, options: &WriteOptions) -> io::Result<()> {
    let (format, overwrite) = (options.format, options.overwrite);
    let dir = dir.as_ref();
    let files = encode_all(model, format)?;
    match fs::metadata(dir) {
        Ok(m) if m.is_dir() => {
            // Rig files of the format that the model does not have: removed if present.
            let stale: &[&str] = if has_rigs(model) {
                &[]
            } else {
                &format.rig_file_names()
            };
            write_into_existing(dir, &files, stale, format, overwrite)
        }
        Ok(_) => Err(io::Error::new(
            ErrorKind::NotADirectory,
            format!("{}: exists and is not a directory", dir.display()),
        )),
        Err(e) if e.kind() == ErrorKind::NotFound => write_new_dir(dir, &files),
        Err(e) => Err(context(dir, e)),
    }
}

/// The error with the path in its message.
fn context(path: &Path, e: io::Error) -> io::Error {
    io::Error::new(e.kind(), format!("{}: {e}", path.display()))
}

/// A suffix unique to this process and call: `<pid>-<n>`.
fn unique() -> String {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    format!(
        "{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    )
}

/// Creates `path` (which must not exist), writes `bytes` and fsyncs it.
fn write_synced(path: &Path, bytes: &[u8]) -> io::Result<()> {
    let mut f = OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
        .map_err(|e| context(path, e))?;
    f.write_all(bytes)
        .and_then(|()| f.sync_all())
        .map_err(|e| context(path, e))
}

/// Fsyncs a directory (its entries: created and renamed files), where the platform allows it;
/// best effort (some file systems refuse to fsync a directory).
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = (dir, File::open);
}

/// `dir` does not exist: write into a fresh sibling directory and rename it to `dir`.
fn write_new_dir(dir: &Path, files: &[(&str, Vec<u8>)]) -> io::Result<()> {
    let Some(name) = dir.file_name() else {
        return Err(io::Error::new(
            ErrorKind::InvalidInput,
            format!("{}: not a directory name", dir.display()),
        ));
    };
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    match fs::metadata(&parent) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(io::Error::new(
                ErrorKind::NotADirectory,
                format!("{}: parent is not a directory", dir.display()),
            ))
        }
        Err(e) if e.kind() == ErrorKind::NotFound => {
            return Err(io::Error::new(
                ErrorKind::NotFound,
                format!(
                    "{}: parent directory {} does not exist",
                    dir.display(),
                    parent.display()
                ),
            ))
        }
        Err(e) => return Err(context(&parent, e)),
    }
    let target = parent.join(name);
    let tmp = parent.join(format!(".{}.tmp-{}", name.to_string_lossy(), unique()));
    fs::create_dir(&tmp).map_err(|e| context(&tmp, e))?;
    let result = (|| {
        for (n, bytes) in files {
            write_synced(&tmp.join(n), bytes)?;
        }
        sync_dir(&tmp);
        fs::rename(&tmp, &target).map_err(|e| {
            // An empty directory created meanwhile is replaced; a non-empty one is not.
            let kind = match e.kind() {
                ErrorKind::AlreadyExists | ErrorKind::DirectoryNotEmpty => {
                    ErrorKind::DirectoryNotEmpty
                }
                k => k,
            };
            io::Error::new(
                kind,
                format!(
                    "{}: cannot rename the written model into place: {e}",
                    dir.display()
                ),
            )
        })
    })();
    match result {
        Ok(()) => {
            sync_dir(&parent);
            Ok(())
        }
        Err(e) => {
            let _ = fs::remove_dir_all(&tmp);
            Err(e)
        }
    }
}

/// `dir` exists: temporaries in `dir`, fsynced, renamed over the final names, and the `stale`
/// files removed, with rollback.
fn write_into_existing(
    dir: &Path,
    files: &[(&str, Vec<u8>)],
    stale: &[&str],
    format: ModelFormat,
    overwrite: Overwrite,
) -> io::Result<()> {
    let non_empty = fs::read_dir(dir)
        .map_err(|e| context(dir, e))?
        .next()
        .is_some();
    if non_empty {
        match overwrite {
            Overwrite::Never => {
                return Err(io::Error::new(
                    ErrorKind::DirectoryNotEmpty,
                    format!(
                        "{}: exists and is not empty (refusing to write a model into it)",
                        dir.display()
                    ),
                ))
            }
            Overwrite::Files => {
                if format == ModelFormat::Text && BIN_FILES.iter().all(|n| dir.join(n).is_file()) {
                    return Err(io::Error::new(
                        ErrorKind::AlreadyExists,
                        format!(
                            "{}: holds a binary model, which readers prefer over the text model \
                             being written; remove cameras.bin, images.bin and points3D.bin first",
                            dir.display()
                        ),
                    ));
                }
            }
        }
    }
    let suffix = unique();
    // The files written, then the stale ones (which have no temporary).
    let names: Vec<&str> = files
        .iter()
        .map(|f| f.0)
        .chain(stale.iter().copied())
        .collect();
    let written = files.len();
    let targets: Vec<PathBuf> = names.iter().map(|n| dir.join(n)).collect();
    let temps: Vec<PathBuf> = names[..written]
        .iter()
        .map(|n| dir.join(format!(".{n}.tmp-{suffix}")))
        .collect();
    let backups: Vec<PathBuf> = names
        .iter()
        .map(|n| dir.join(format!(".{n}.bak-{suffix}")))
        .collect();
    let remove_all = |paths: &[PathBuf]| {
        for p in paths {
            let _ = fs::remove_file(p);
        }
    };

    // 1. The new files, fsynced, under temporary names.
    for (k, (_, bytes)) in files.iter().enumerate() {
        if let Err(e) = write_synced(&temps[k], bytes) {
            remove_all(&temps[..=k]);
            return Err(e);
        }
    }
    // 2. Hard-link backups of the files about to be replaced or removed.
    let mut backed_up = vec![false; names.len()];
    for k in 0..names.len() {
        match fs::symlink_metadata(&targets[k]) {
            Err(e) if e.kind() == ErrorKind::NotFound => continue,
            _ => {}
        }
        if let Err(e) = fs::hard_link(&targets[k], &backups[k]) {
            remove_all(&temps);
            remove_all(&backups);
            return Err(context(&targets[k], e));
        }
        backed_up[k] = true;
    }
    // 3. The renames and removals; on failure put back what was there.
    for k in 0..names.len() {
        let result = if k < written {
            fs::rename(&temps[k], &targets[k])
        } else if backed_up[k] {
            fs::remove_file(&targets[k])
        } else {
            Ok(())
        };
        if let Err(e) = result {
            for j in 0..k {
                if backed_up[j] {
                    let _ = fs::rename(&backups[j], &targets[j]);
                } else if j < written {
                    let _ = fs::remove_file(&targets[j]);
                }
            }
            remove_all(&temps);
            remove_all(&backups);
            sync_dir(dir);
            return Err(context(&targets[k], e));
        }
    }
    remove_all(&backups);
    sync_dir(dir);
    Ok(())
}
