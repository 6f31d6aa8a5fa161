//! The reconstruction as read: images (pose, camera, observations), 3D points and cameras (and
//! rigs and frames, in `rigs.rs`), and the errors of reading it.

use std::collections::BTreeMap;
use std::fmt;
use std::path::{Path, PathBuf};

use nalgebra::{Matrix3, Point2, Point3, Vector3};

use super::options::Limit;
use super::pose::quaternion_to_matrix;
use super::rigs::{Frame, SensorRig};
use crate::camera::Camera;
use crate::PnpError;

/// An image of the reconstruction: its pose, camera and 2D observations.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
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
///
/// Its rigs and frames are those of COLMAP 3.12 and later (`rigs.txt` and `frames.txt`, or
/// `.bin`): both empty for a model without those files, which reads and writes as before. A
/// model with rigs has every image in exactly one frame (the [module documentation](super)
/// explains them).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Model {
    /// Cameras by id.
    pub cameras: BTreeMap<u32, Camera>,
    /// Images by id.
    pub images: BTreeMap<u32, Image>,
    /// 3D points by id.
    pub points: BTreeMap<u64, Point3D>,
    /// Rigs by id (empty for a model without rig files).
    #[cfg_attr(feature = "serde", serde(default))]
    pub rigs: BTreeMap<u32, SensorRig>,
    /// Frames by id (empty for a model without rig files).
    #[cfg_attr(feature = "serde", serde(default))]
    pub frames: BTreeMap<u32, Frame>,
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
    /// (Every referenced 3D point exists: [`super::read_model`] checks this.) A
    /// [`super::Registrar`] registering several images of one model looks the points up in a
    /// table built once.
    #[must_use]
    pub fn correspondences(&self, image_id: u32) -> (Vec<Point3<f64>>, Vec<Point2<f64>>) {
        let Some(img) = self.images.get(&image_id) else {
            return (Vec::new(), Vec::new());
        };
        // The vectors sized once, to the triangulated observations (a model's images often have
        // several times as many keypoints as 3D points); the table of points pays for itself
        // within the call when their ids are not much larger than that count (COLMAP numbers
        // points from 1).
        let n = img.points2d.iter().filter(|(_, id)| id.is_some()).count();
        let (mut world, mut pixels) = (Vec::with_capacity(n), Vec::with_capacity(n));
        PointLookup::new(self, 4 * n, false).gather(img, &mut world, &mut pixels);
        (world, pixels)
    }
}

/// The 3D points of a model by id: a table indexed by id, filled by one in-order walk of the
/// map, when the largest id is at most `max_table` (a lookup in the map costs several times
/// an index); otherwise the map itself.
///
/// A table built for many images ([`super::Registrar`]) holds the coordinates: a lookup is
/// one load from a compact array instead of two dependent ones, the second into nodes spread
/// over the map (the bundled model's gathering took a third less time). A table built for
/// one image holds references: a quarter of the size, which for a one-off table matters more
/// (the allocator hands a larger one back to the system when it is freed, and the next call
/// pays the page faults again: `Model::correspondences` took twice the time with values).
#[derive(Debug)]
pub(super) struct PointLookup<'m> {
    points: &'m BTreeMap<u64, Point3D>,
    table: Table<'m>,
}

/// [`PointLookup`]'s table.
#[derive(Debug)]
enum Table<'m> {
    Coordinates(Vec<Option<Point3<f64>>>),
    References(Vec<Option<&'m Point3<f64>>>),
    None,
}

impl<'m> PointLookup<'m> {
    /// A table of coordinates when `many` (it serves many images), else of references.
    pub(super) fn new(model: &'m Model, max_table: usize, many: bool) -> Self {
        let max_id = model.points.keys().next_back().copied().unwrap_or(0);
        let size = usize::try_from(max_id)
            .ok()
            .filter(|&m| m <= max_table)
            .map(|m| m + 1);
        let table = match size {
            None => Table::None,
            Some(size) if many => Table::Coordinates(table_of(model, size, |p| p.xyz)),
            Some(size) => Table::References(table_of(model, size, |p| &p.xyz)),
        };
        PointLookup {
            points: &model.points,
            table,
        }
    }

    /// Appends `img`'s correspondences to `world` and `pixels`, in the order of its
    /// observations.
    pub(super) fn gather(
        &self,
        img: &Image,
        world: &mut Vec<Point3<f64>>,
        pixels: &mut Vec<Point2<f64>>,
    ) {
        // The lookup chosen once, not per observation.
        match &self.table {
            Table::Coordinates(t) => gather_with(img, world, pixels, |id| entry(t, id)),
            Table::References(t) => gather_with(img, world, pixels, |id| entry(t, id).copied()),
            Table::None => {
                gather_with(img, world, pixels, |id| self.points.get(&id).map(|p| p.xyz))
            }
        }
    }
}

/// A table of `size` entries by point id, `value(p)` at the id of each point `p` of `model`
/// (one in-order walk of the map; `size` above the largest id).
fn table_of<'m, T: Clone>(
    model: &'m Model,
    size: usize,
    value: impl Fn(&'m Point3D) -> T,
) -> Vec<Option<T>> {
    let mut table = vec![None; size];
    for (id, p) in &model.points {
        table[*id as usize] = Some(value(p));
    }
    table
}

/// The entry of point `id` in a table by id (`None` beyond it).
#[inline(always)]
fn entry<T: Copy>(table: &[Option<T>], id: u64) -> Option<T> {
    usize::try_from(id)
        .ok()
        .and_then(|i| table.get(i))
        .copied()
        .flatten()
}

/// The observations of `img` with a 3D point that `lookup` finds, appended to `world` and
/// `pixels`.
///
/// Written into the vectors' spare capacity, which the callers size to every observation with
/// a point id (all of the image's keypoints for a [`super::Registrar`], the triangulated ones
/// for [`Model::correspondences`]), their lengths set once at the end: a `push` per point
/// checked the capacity and stored the length of both vectors each time (the bundled model's
/// gathering took about a quarter more time). Should the room run out, the rest is pushed.
#[inline(always)]
fn gather_with(
    img: &Image,
    world: &mut Vec<Point3<f64>>,
    pixels: &mut Vec<Point2<f64>>,
    lookup: impl Fn(u64) -> Option<Point3<f64>>,
) {
    let (world_len, pixels_len) = (world.len(), pixels.len());
    let (spare_world, spare_pixels) = (world.spare_capacity_mut(), pixels.spare_capacity_mut());
    let mut written = 0;
    let mut rest = &img.points2d[..0];
    for (i, (px, id)) in img.points2d.iter().enumerate() {
        if let Some(x) = id.and_then(&lookup) {
            let (Some(w), Some(p)) = (spare_world.get_mut(written), spare_pixels.get_mut(written))
            else {
                rest = &img.points2d[i..];
                break;
            };
            w.write(x);
            p.write(*px);
            written += 1;
        }
    }
    // SAFETY: the first `written` slots of each vector's spare capacity have just been
    // initialised, and both capacities hold them (`get_mut` found them).
    unsafe {
        world.set_len(world_len + written);
        pixels.set_len(pixels_len + written);
    }
    for (px, id) in rest {
        if let Some(x) = id.and_then(&lookup) {
            world.push(x);
            pixels.push(*px);
        }
    }
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

/// An error reading a model: the file, where in it, what kind of problem and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ModelError {
    /// The file (or directory) concerned.
    pub file: PathBuf,
    /// Where in the file.
    pub location: Location,
    /// What kind of problem: for callers that react differently to a missing file, a special
    /// file, a limit of [`ReadOptions`](super::ReadOptions) and malformed content.
    pub kind: ModelErrorKind,
    /// What is wrong.
    pub reason: String,
}

impl ModelError {
    /// An error of kind [`ModelErrorKind::Invalid`] (malformed content).
    pub(crate) fn invalid(file: &Path, location: Location, reason: impl Into<String>) -> Self {
        ModelError {
            file: file.to_path_buf(),
            location,
            kind: ModelErrorKind::Invalid,
            reason: reason.into(),
        }
    }

    /// An error of kind [`ModelErrorKind::Limit`]; the reason says what exceeds the limit, and
    /// the message adds the limit.
    pub(crate) fn limit(file: &Path, location: Location, limit: Limit, what: &str) -> Self {
        ModelError {
            file: file.to_path_buf(),
            location,
            kind: ModelErrorKind::Limit(limit),
            reason: format!("{what}: {limit}"),
        }
    }
}

/// The kind of a [`ModelError`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum ModelErrorKind {
    /// The directory or a file cannot be found, inspected, opened or read (a missing file, a
    /// permission, an I/O error), or the directory does not hold a model.
    Io,
    /// A path where a regular file is expected is something else: a directory, a named pipe
    /// (FIFO), a device such as `/dev/zero`, a socket. Refused before it is opened.
    NotRegularFile,
    /// A limit of [`ReadOptions`](super::ReadOptions) (or the fixed field length limit) was hit: which one, with its
    /// value.
    Limit(Limit),
    /// Malformed content: syntax, values, counts, duplicate ids, dangling references.
    Invalid,
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

/// The images of a model and where each was read (for the cross-reference errors).
pub(crate) type Images = (BTreeMap<u32, Image>, BTreeMap<u32, Location>);

/// Errors of [`super::register_image`] and [`super::register_frame`].
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum RegisterError {
    /// No image with this id in the model.
    UnknownImage(u32),
    /// The image's camera is missing from the model.
    UnknownCamera(u32),
    /// No frame with this id in the model.
    UnknownFrame(u32),
    /// The frame's rig is missing from the model.
    UnknownRig(u32),
    /// A camera of the frame has no known pose in its rig (it is not one of the rig's sensors,
    /// or its `sensor_from_rig` is unknown).
    NoSensorPose {
        /// The rig.
        rig_id: u32,
        /// The camera.
        camera_id: u32,
    },
    /// The frame has no images (only data of other sensors).
    EmptyFrame(u32),
    /// The solver failed.
    Solver(PnpError),
}

impl fmt::Display for RegisterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RegisterError::UnknownImage(i) => write!(f, "no image with id {i} in the model"),
            RegisterError::UnknownCamera(c) => write!(f, "no camera with id {c} in the model"),
            RegisterError::UnknownFrame(i) => write!(f, "no frame with id {i} in the model"),
            RegisterError::UnknownRig(r) => write!(f, "no rig with id {r} in the model"),
            RegisterError::NoSensorPose { rig_id, camera_id } => write!(
                f,
                "camera {camera_id} has no known pose in rig {rig_id} (not one of its sensors, \
                 or its sensor_from_rig is unknown)"
            ),
            RegisterError::EmptyFrame(i) => write!(f, "frame {i} has no images"),
            RegisterError::Solver(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for RegisterError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            RegisterError::Solver(e) => Some(e),
            _ => None,
        }
    }
}

impl From<PnpError> for RegisterError {
    fn from(e: PnpError) -> Self {
        RegisterError::Solver(e)
    }
}
