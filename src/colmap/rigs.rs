//! COLMAP's rigs and frames, in the format of COLMAP 3.12 and later (pycolmap 4.x writes the
//! same): the types ([`SensorRig`], [`Frame`] and their parts) and, in `rigs/check.rs`, the
//! checks that tie them to the model's cameras and images, shared by the reader (errors
//! located in the files) and the writer (refusals).
//!
//! A rig (`rigs.txt`/`rigs.bin`) is a set of sensors fixed to one body: one reference sensor,
//! whose pose in the rig is the identity, and others, each with its `sensor_from_rig` pose
//! (or none, if unknown). A frame (`frames.txt`/`frames.bin`) is one capture by a rig: its
//! `rig_from_world` pose and its data ids, each a sensor of the rig and the id of its datum
//! (for a camera, the image's id). A model with rigs has every image in exactly one frame,
//! and the image's pose is then `cam_from_world = sensor_from_rig * rig_from_world` (COLMAP
//! still writes it in `images.txt`/`images.bin`; this crate keeps it as read).
//!
//! The file layouts (little-endian binary, one line per record in text):
//!
//! | file | record |
//! |---|---|
//! | `rigs.txt` | `RIG_ID NUM_SENSORS [REF_SENSOR_TYPE REF_SENSOR_ID] (SENSOR_TYPE SENSOR_ID HAS_POSE [QW QX QY QZ TX TY TZ])*` |
//! | `rigs.bin` | `u64` count; each rig `u32` id, `u32` sensors, if any the reference `i32` type and `u32` id, then per other sensor `i32` type, `u32` id, `u8` has-pose, if 1 seven `f64` |
//! | `frames.txt` | `FRAME_ID RIG_ID QW QX QY QZ TX TY TZ NUM_DATA_IDS (SENSOR_TYPE SENSOR_ID DATA_ID)*` |
//! | `frames.bin` | `u64` count; each frame `u32` id, `u32` rig id, seven `f64`, `u32` data ids, each `i32` type, `u32` sensor id, `u64` data id |
//!
//! Sensor types are `CAMERA` (0 in binary) and `IMU` (1).

mod check;

pub(super) use check::{check_frame, check_rig, check_rigs, Culprit};

use super::pose::Pose;

/// The type of a rig's sensor.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
#[non_exhaustive]
pub enum SensorType {
    /// A camera: its id is a camera id of [`super::Model::cameras`], its data ids image ids.
    Camera,
    /// An inertial measurement unit (kept as read; this crate uses only cameras).
    Imu,
}

impl SensorType {
    /// The name in the text format: `CAMERA`, `IMU`.
    pub(super) fn name(self) -> &'static str {
        match self {
            SensorType::Camera => "CAMERA",
            SensorType::Imu => "IMU",
        }
    }

    /// The type of a text name.
    pub(super) fn from_name(name: &str) -> Option<Self> {
        match name {
            "CAMERA" => Some(SensorType::Camera),
            "IMU" => Some(SensorType::Imu),
            _ => None,
        }
    }

    /// The number in the binary format: 0 for cameras, 1 for IMUs.
    pub(super) fn colmap_id(self) -> i32 {
        match self {
            SensorType::Camera => 0,
            SensorType::Imu => 1,
        }
    }

    /// The type of a binary number.
    pub(super) fn from_colmap_id(id: i32) -> Option<Self> {
        match id {
            0 => Some(SensorType::Camera),
            1 => Some(SensorType::Imu),
            _ => None,
        }
    }
}

/// A sensor of a rig: its type and its id (for a camera, the camera id).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct SensorId {
    /// The sensor's type.
    pub kind: SensorType,
    /// Its id among the sensors of its type.
    pub id: u32,
}

impl SensorId {
    /// The camera of id `id` as a sensor.
    #[must_use]
    pub fn camera(id: u32) -> Self {
        SensorId {
            kind: SensorType::Camera,
            id,
        }
    }
}

impl std::fmt::Display for SensorId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} {}", self.kind.name(), self.id)
    }
}

/// A rig of COLMAP's rigs file (pycolmap's `Rig`): sensors fixed to one body, one of them the
/// reference, whose pose in the rig is the identity. [`SensorRig::sensor_from_rig`] gives a
/// sensor's pose; a frame's registration ([`super::register_frame`]) builds the solver's
/// [`crate::Rig`] from the poses of the frame's cameras.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, PartialEq)]
pub struct SensorRig {
    /// Rig id.
    pub id: u32,
    /// The reference sensor (`None` only for a rig without sensors).
    pub ref_sensor: Option<SensorId>,
    /// The other sensors, in the file's order, each with its `sensor_from_rig` pose
    /// (`x_sensor = R x_rig + t`), or `None` if the model does not know it.
    pub sensors: Vec<(SensorId, Option<Pose>)>,
}

impl SensorRig {
    /// The pose of `sensor` in the rig, `x_sensor = R x_rig + t`: the identity for the
    /// reference sensor; `None` for a sensor of unknown pose or not in the rig.
    #[must_use]
    pub fn sensor_from_rig(&self, sensor: SensorId) -> Option<Pose> {
        if self.ref_sensor == Some(sensor) {
            return Some(Pose::identity());
        }
        self.sensors
            .iter()
            .find(|(s, _)| *s == sensor)
            .and_then(|(_, p)| *p)
    }

    /// Whether `sensor` is one of the rig's (the reference included).
    fn has_sensor(&self, sensor: SensorId) -> bool {
        self.ref_sensor == Some(sensor) || self.sensors.iter().any(|(s, _)| *s == sensor)
    }

    /// All sensors, the reference first.
    fn all_sensors(&self) -> impl Iterator<Item = SensorId> + '_ {
        self.ref_sensor
            .into_iter()
            .chain(self.sensors.iter().map(|(s, _)| *s))
    }
}

/// A datum of a frame: the sensor that took it and its id (for a camera, the image id).
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct DataId {
    /// The sensor.
    pub sensor: SensorId,
    /// The datum's id: an image id for a camera.
    pub id: u64,
}

/// A frame of COLMAP's frames file (pycolmap's `Frame`): the data one rig captured at once,
/// and the rig's pose then.
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Frame id.
    pub id: u32,
    /// The rig, in [`super::Model::rigs`].
    pub rig_id: u32,
    /// The rig's pose, world to rig: `x_rig = R X + t`.
    pub rig_from_world: Pose,
    /// The frame's data, in the file's order.
    pub data_ids: Vec<DataId>,
}

impl Frame {
    /// The ids of the frame's images (its cameras' data), in the order of [`Frame::data_ids`].
    pub fn image_ids(&self) -> impl Iterator<Item = u32> + '_ {
        self.data_ids
            .iter()
            .filter(|d| d.sensor.kind == SensorType::Camera)
            .map(|d| u32::try_from(d.id).unwrap_or(u32::MAX))
    }
}
