//! How a model is read ([`ReadOptions`]: its format and the readers' limits) and the error
//! detail naming the limit hit ([`Limit`]).

use std::fmt;

use super::ModelFormat;
use crate::source::bytes_text;

/// The longest name (image name, camera model name) or number the readers accept, in bytes:
/// 64 KiB. Longer fields are refused with [`Limit::FieldBytes`]. (The binary writer refuses to
/// write longer image names, so everything written reads back.)
pub(crate) const MAX_FIELD_BYTES: usize = 1 << 16;

/// How [`read_model`](super::read_model) reads a model: its format (detected by default) and
/// the limits of the readers.
///
/// The readers stream: text files token by token, binary files record by record, with every
/// count checked against the bytes left in the file before anything is allocated for it, and a
/// regular file is required (a FIFO, `/dev/zero` or a directory is refused before it is opened:
/// [`ModelErrorKind::NotRegularFile`](super::ModelErrorKind::NotRegularFile)). So memory stays
/// proportional to the model returned, whatever the input. The limits bound the files and
/// the records:
///
/// | limit | default | bounds |
/// |---|---|---|
/// | [`max_file_bytes`](Self::max_file_bytes) | none (`u64::MAX`) | the size of each of the three files |
/// | [`max_observations`](Self::max_observations) | 1,000,000 (32 MB in memory) | the observations (2D points) of one image |
/// | [`max_track_length`](Self::max_track_length) | 1,000,000 (8 MB in memory) | the track of one 3D point |
/// | fixed | 64 KiB | one name or number |
///
/// (COLMAP extracts at most 8,192 features per image by default, and a 3D point's track
/// usually has one element per image that sees it.) A limit that is hit is an error of kind
/// [`ModelErrorKind::Limit`](super::ModelErrorKind::Limit) naming it.
///
/// ```
/// use eopnp::colmap::{read_model, Limit, ModelErrorKind, ModelFormat, ReadOptions};
///
/// let dir = std::env::temp_dir().join(format!("eopnp-read-options-{}", std::process::id()));
/// std::fs::create_dir_all(&dir)?;
/// std::fs::write(dir.join("cameras.txt"), "1 SIMPLE_PINHOLE 640 480 500 320 240\n")?;
/// std::fs::write(dir.join("images.txt"), "1 1 0 0 0 0 0 5 1 a.png\n10 20 -1 30 40 -1 50 60 -1\n")?;
/// std::fs::write(dir.join("points3D.txt"), "")?;
/// let options = ReadOptions::default().format(ModelFormat::Text).max_observations(2);
/// let e = read_model(&dir, &options).unwrap_err();
/// assert_eq!(e.kind, ModelErrorKind::Limit(Limit::Observations(2)));
/// assert!(e.to_string().ends_with(
///     "images.txt:2: image 1 has more than 2 observations: over the limit of 2 observations \
///      per image (ReadOptions::max_observations)"
/// ));
/// assert_eq!(read_model(&dir, &ReadOptions::default())?.images[&1].points2d.len(), 3);
/// std::fs::remove_dir_all(&dir)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReadOptions {
    pub(crate) format: Option<ModelFormat>,
    pub(crate) max_file_bytes: u64,
    pub(crate) max_observations: usize,
    pub(crate) max_track_length: usize,
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            format: None,
            max_file_bytes: u64::MAX,
            max_observations: 1_000_000,
            max_track_length: 1_000_000,
        }
    }
}

impl ReadOptions {
    /// Read this format. Default: detected ([`detect_format`](super::detect_format): binary
    /// when the three `.bin` files exist, else text).
    #[must_use]
    pub fn format(mut self, format: ModelFormat) -> Self {
        self.format = Some(format);
        self
    }

    /// The largest size of each model file, in bytes, checked before reading. Default:
    /// `u64::MAX` (no limit: memory stays proportional to the model read, and a file of
    /// garbage fails at its first bad record).
    #[must_use]
    pub fn max_file_bytes(mut self, bytes: u64) -> Self {
        self.max_file_bytes = bytes;
        self
    }

    /// The most observations (2D points, with or without a 3D point) of one image. Default:
    /// `1_000_000`.
    #[must_use]
    pub fn max_observations(mut self, n: usize) -> Self {
        self.max_observations = n;
        self
    }

    /// The most elements of one 3D point's track. Default: `1_000_000`.
    #[must_use]
    pub fn max_track_length(mut self, n: usize) -> Self {
        self.max_track_length = n;
        self
    }
}

/// Which limit a model file exceeded, with its value (the detail of
/// [`ModelErrorKind::Limit`](super::ModelErrorKind::Limit)).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Limit {
    /// [`ReadOptions::max_file_bytes`].
    FileBytes(u64),
    /// A name or a number is longer than 64 KiB.
    FieldBytes(usize),
    /// [`ReadOptions::max_observations`].
    Observations(usize),
    /// [`ReadOptions::max_track_length`].
    TrackLength(usize),
}

impl fmt::Display for Limit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Limit::FileBytes(n) => write!(
                f,
                "over the file size limit of {} (ReadOptions::max_file_bytes)",
                bytes_text(n)
            ),
            Limit::FieldBytes(n) => write!(
                f,
                "over the limit of {} for one name or number",
                bytes_text(n as u64)
            ),
            Limit::Observations(n) => write!(
                f,
                "over the limit of {n} observations per image (ReadOptions::max_observations)"
            ),
            Limit::TrackLength(n) => write!(
                f,
                "over the limit of {n} track elements per 3D point (ReadOptions::max_track_length)"
            ),
        }
    }
}
