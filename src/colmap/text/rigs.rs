//! `rigs.txt` and `frames.txt` (COLMAP 3.12 and later): the readers, streaming token by token
//! like the other text readers, and the encoder. Layouts in [`crate::colmap::rigs`].

use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::Path;

use nalgebra::Vector3;

use super::{encode::push_f64, err_at, Tokens};
use crate::colmap::model::{Location, Model, ModelError};
use crate::colmap::options::ReadOptions;
use crate::colmap::pose::Pose;
use crate::colmap::rigs::{check_frame, check_rig, DataId, Frame, SensorId, SensorRig, SensorType};

/// Records by id and where each was read.
pub(in crate::colmap) type Records<T> = (BTreeMap<u32, T>, BTreeMap<u32, Location>);

impl<R: BufRead> Tokens<'_, R> {
    /// A sensor: its type name and id.
    fn sensor(&mut self, what: &str) -> Result<SensorId, ModelError> {
        let (path, line) = (self.path, self.line);
        let name = self.field(&format!("{what}_TYPE"))?;
        let kind = SensorType::from_name(name).ok_or_else(|| {
            err_at(
                path,
                line,
                format!(
                    "bad {what}_TYPE: {:?} (expected CAMERA or IMU)",
                    super::truncate(name)
                ),
            )
        })?;
        let id = self.parse(&format!("{what}_ID"))?;
        Ok(SensorId { kind, id })
    }

    /// Seven numbers `QW QX QY QZ TX TY TZ`, checked.
    fn pose(&mut self, what: &str) -> Result<Pose, ModelError> {
        let mut q = [0.0; 4];
        for (k, name) in ["QW", "QX", "QY", "QZ"].iter().enumerate() {
            q[k] = self.float(&format!("{what} {name}"))?;
        }
        let mut t = Vector3::zeros();
        for (k, name) in ["TX", "TY", "TZ"].iter().enumerate() {
            t[k] = self.float(&format!("{what} {name}"))?;
        }
        let pose = Pose { q, t };
        pose.check().map_err(|e| self.err(format!("{what}: {e}")))?;
        Ok(pose)
    }

    /// The end of a record's line: nothing may follow its last field.
    fn end_of_record(&mut self, what: &str) -> Result<(), ModelError> {
        match self.token()? {
            None => Ok(()),
            Some(t) => {
                let t = super::truncate(t);
                Err(self.err(format!("unexpected {t:?} after {what}")))
            }
        }
    }
}

pub(in crate::colmap) fn parse_rigs_text<R: BufRead>(
    path: &Path,
    src: &mut R,
    _len: u64,
    _limits: &ReadOptions,
) -> Result<Records<SensorRig>, ModelError> {
    let mut t = Tokens::new(path, src);
    let (mut rigs, mut locs) = (BTreeMap::new(), BTreeMap::new());
    while t.next_record()? {
        let line = t.line;
        let id: u32 = t.parse("RIG_ID")?;
        let n: u32 = t.parse("NUM_SENSORS")?;
        let ref_sensor = if n > 0 {
            Some(t.sensor("REF_SENSOR")?)
        } else {
            None
        };
        // Grown as the sensors are read: the count alone allocates nothing.
        let mut sensors = Vec::new();
        for _ in 1..n {
            let sensor = t.sensor("SENSOR")?;
            let pose = match t.field("HAS_POSE")? {
                "0" => None,
                "1" => Some(t.pose(&format!("sensor_from_rig of sensor {sensor}"))?),
                other => {
                    let other = super::truncate(other);
                    return Err(t.err(format!("bad HAS_POSE: {other:?} (expected 0 or 1)")));
                }
            };
            sensors.push((sensor, pose));
        }
        t.end_of_record(&format!("the {n} sensors of rig {id}"))?;
        let rig = SensorRig {
            id,
            ref_sensor,
            sensors,
        };
        check_rig(&rig).map_err(|e| t.err(e))?;
        if rigs.insert(id, rig).is_some() {
            return Err(err_at(path, line, format!("duplicate rig id {id}")));
        }
        locs.insert(id, Location::Line(line));
    }
    Ok((rigs, locs))
}

pub(in crate::colmap) fn parse_frames_text<R: BufRead>(
    path: &Path,
    src: &mut R,
    _len: u64,
    _limits: &ReadOptions,
) -> Result<Records<Frame>, ModelError> {
    let mut t = Tokens::new(path, src);
    let (mut frames, mut locs) = (BTreeMap::new(), BTreeMap::new());
    while t.next_record()? {
        let line = t.line;
        let id: u32 = t.parse("FRAME_ID")?;
        let rig_id: u32 = t.parse("RIG_ID")?;
        let rig_from_world = t.pose("RIG_FROM_WORLD")?;
        let n: u32 = t.parse("NUM_DATA_IDS")?;
        let mut data_ids = Vec::new();
        for _ in 0..n {
            let sensor = t.sensor("SENSOR")?;
            let data = t.parse("DATA_ID")?;
            data_ids.push(DataId { sensor, id: data });
        }
        t.end_of_record(&format!("the {n} data ids of frame {id}"))?;
        let frame = Frame {
            id,
            rig_id,
            rig_from_world,
            data_ids,
        };
        check_frame(&frame).map_err(|e| t.err(e))?;
        if frames.insert(id, frame).is_some() {
            return Err(err_at(path, line, format!("duplicate frame id {id}")));
        }
        locs.insert(id, Location::Line(line));
    }
    Ok((frames, locs))
}

fn push_pose(out: &mut String, pose: &Pose) {
    for &v in pose.q.iter().chain(pose.t.iter()) {
        out.push(' ');
        push_f64(out, v);
    }
}

/// `rigs.txt` and `frames.txt` of a model already checked by `write::validate`, with
/// COLMAP's header comments.
pub(in crate::colmap) fn encode_rigs_text(model: &Model) -> [Vec<u8>; 2] {
    use std::fmt::Write as _;
    let mut r = String::new();
    r.push_str("# Rig calib list with one line of data per calib:\n");
    r.push_str(
        "#   RIG_ID, NUM_SENSORS, REF_SENSOR_TYPE, REF_SENSOR_ID, SENSORS[] as (SENSOR_TYPE, \
         SENSOR_ID, HAS_POSE, [QW, QX, QY, QZ, TX, TY, TZ])\n",
    );
    let _ = writeln!(r, "# Number of rigs: {}", model.rigs.len());
    for rig in model.rigs.values() {
        let n = rig.sensors.len() + usize::from(rig.ref_sensor.is_some());
        let _ = write!(r, "{} {n}", rig.id);
        if let Some(s) = rig.ref_sensor {
            let _ = write!(r, " {s}");
        }
        for (s, pose) in &rig.sensors {
            let _ = write!(r, " {s}");
            match pose {
                Some(p) => {
                    r.push_str(" 1");
                    push_pose(&mut r, p);
                }
                None => r.push_str(" 0"),
            }
        }
        r.push('\n');
    }

    let mut f = String::new();
    f.push_str("# Frame list with one line of data per frame:\n");
    f.push_str(
        "#   FRAME_ID, RIG_ID, RIG_FROM_WORLD[QW, QX, QY, QZ, TX, TY, TZ], NUM_DATA_IDS, \
         DATA_IDS[] as (SENSOR_TYPE, SENSOR_ID, DATA_ID)\n",
    );
    let _ = writeln!(f, "# Number of frames: {}", model.frames.len());
    for frame in model.frames.values() {
        let _ = write!(f, "{} {}", frame.id, frame.rig_id);
        push_pose(&mut f, &frame.rig_from_world);
        let _ = write!(f, " {}", frame.data_ids.len());
        for d in &frame.data_ids {
            let _ = write!(f, " {} {}", d.sensor, d.id);
        }
        f.push('\n');
    }
    [r.into_bytes(), f.into_bytes()]
}
