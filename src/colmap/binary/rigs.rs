//! `rigs.bin` and `frames.bin` (COLMAP 3.12 and later): the readers, streaming record by record
//! with every count checked against the bytes left, and the encoder. Layouts in
//! [`crate::colmap::rigs`].

use std::collections::BTreeMap;
use std::io::BufRead;
use std::path::Path;

use nalgebra::Vector3;

use super::Reader;
use crate::colmap::model::{Location, Model, ModelError};
use crate::colmap::options::ReadOptions;
use crate::colmap::pose::Pose;
use crate::colmap::rigs::{check_frame, check_rig, DataId, Frame, SensorId, SensorRig, SensorType};
use crate::colmap::text::Records;

impl<R: BufRead> Reader<'_, R> {
    /// A `u32` count of records of at least `min_size` bytes each, checked against the bytes
    /// left.
    fn count32(&mut self, what: &str, min_size: u64) -> Result<usize, ModelError> {
        let at = self.pos;
        let n = self.u32(what)?;
        let need = u64::from(n) * min_size;
        if need > self.remaining() {
            return Err(self.err_at(
                at,
                format!(
                    "{what} = {n} needs at least {need} bytes but only {} remain (corrupt or \
                     truncated file?)",
                    self.remaining()
                ),
            ));
        }
        Ok(n as usize)
    }

    /// A sensor: `i32` type, `u32` id.
    fn sensor(&mut self, what: &str) -> Result<SensorId, ModelError> {
        let at = self.pos;
        let code = self.i32(what)?;
        let kind = SensorType::from_colmap_id(code).ok_or_else(|| {
            self.err_at(
                at,
                format!("bad {what}: sensor type {code} (expected 0, a camera, or 1, an IMU)"),
            )
        })?;
        let id = self.u32("sensor id")?;
        Ok(SensorId { kind, id })
    }

    /// Seven `f64` `qw qx qy qz tx ty tz`, checked.
    fn pose(&mut self, what: &str) -> Result<Pose, ModelError> {
        let at = self.pos;
        let mut q = [0.0; 4];
        for v in &mut q {
            *v = self.f64("quaternion")?;
        }
        let mut t = Vector3::zeros();
        for k in 0..3 {
            t[k] = self.f64("translation")?;
        }
        let pose = Pose { q, t };
        pose.check()
            .map_err(|e| self.err_at(at, format!("{what}: {e}")))?;
        Ok(pose)
    }
}

pub(in crate::colmap) fn parse_rigs_bin<R: BufRead>(
    path: &Path,
    src: &mut R,
    len: u64,
    _limits: &ReadOptions,
) -> Result<Records<SensorRig>, ModelError> {
    let mut r = Reader::new(path, src, len);
    // Smallest record: 4 + 4 (no sensors).
    let n = r.count("number of rigs", 8, None)?;
    let (mut rigs, mut locs) = (BTreeMap::new(), BTreeMap::new());
    for _ in 0..n {
        let at = r.pos;
        let id = r.u32("RIG_ID")?;
        // Each sensor takes at least 8 bytes (the reference: type and id; the others 9 and
        // more).
        let ns = r.count32("number of sensors", 8)?;
        let ref_sensor = if ns > 0 {
            Some(r.sensor("reference sensor type")?)
        } else {
            None
        };
        let mut sensors = Vec::with_capacity(ns.saturating_sub(1));
        for _ in 1..ns {
            let sensor = r.sensor("sensor type")?;
            let flag_at = r.pos;
            let pose = match r.u8("HAS_POSE")? {
                0 => None,
                1 => Some(r.pose(&format!("sensor_from_rig of sensor {sensor}"))?),
                b => return Err(r.err_at(flag_at, format!("bad HAS_POSE: {b} (expected 0 or 1)"))),
            };
            sensors.push((sensor, pose));
        }
        let rig = SensorRig {
            id,
            ref_sensor,
            sensors,
        };
        check_rig(&rig).map_err(|e| r.err_at(at, e))?;
        if rigs.insert(id, rig).is_some() {
            return Err(r.err_at(at, format!("duplicate rig id {id}")));
        }
        locs.insert(id, Location::Offset(at));
    }
    r.finish()?;
    Ok((rigs, locs))
}

pub(in crate::colmap) fn parse_frames_bin<R: BufRead>(
    path: &Path,
    src: &mut R,
    len: u64,
    _limits: &ReadOptions,
) -> Result<Records<Frame>, ModelError> {
    let mut r = Reader::new(path, src, len);
    // Smallest record: 4 + 4 + 7 * 8 + 4 = 68 bytes.
    let n = r.count("number of frames", 68, None)?;
    let (mut frames, mut locs) = (BTreeMap::new(), BTreeMap::new());
    for _ in 0..n {
        let at = r.pos;
        let id = r.u32("FRAME_ID")?;
        let rig_id = r.u32("RIG_ID")?;
        let rig_from_world = r.pose("RIG_FROM_WORLD")?;
        let nd = r.count32("number of data ids", 16)?;
        let mut data_ids = Vec::with_capacity(nd);
        for _ in 0..nd {
            let sensor = r.sensor("sensor type")?;
            let data = r.u64("DATA_ID")?;
            data_ids.push(DataId { sensor, id: data });
        }
        let frame = Frame {
            id,
            rig_id,
            rig_from_world,
            data_ids,
        };
        check_frame(&frame).map_err(|e| r.err_at(at, e))?;
        if frames.insert(id, frame).is_some() {
            return Err(r.err_at(at, format!("duplicate frame id {id}")));
        }
        locs.insert(id, Location::Offset(at));
    }
    r.finish()?;
    Ok((frames, locs))
}

fn push_sensor(out: &mut Vec<u8>, s: SensorId) {
    out.extend_from_slice(&s.kind.colmap_id().to_le_bytes());
    out.extend_from_slice(&s.id.to_le_bytes());
}

fn push_pose(out: &mut Vec<u8>, pose: &Pose) {
    for v in pose.q.iter().chain(pose.t.iter()) {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

/// `rigs.bin` and `frames.bin` of a model already checked by `write::validate` (every count
/// fits its `u32` field).
pub(in crate::colmap) fn encode_rigs_binary(model: &Model) -> [Vec<u8>; 2] {
    let mut r = Vec::new();
    r.extend_from_slice(&(model.rigs.len() as u64).to_le_bytes());
    for rig in model.rigs.values() {
        let n = rig.sensors.len() + usize::from(rig.ref_sensor.is_some());
        r.extend_from_slice(&rig.id.to_le_bytes());
        r.extend_from_slice(&(n as u32).to_le_bytes());
        if let Some(s) = rig.ref_sensor {
            push_sensor(&mut r, s);
        }
        for (s, pose) in &rig.sensors {
            push_sensor(&mut r, *s);
            r.push(u8::from(pose.is_some()));
            if let Some(p) = pose {
                push_pose(&mut r, p);
            }
        }
    }

    let mut f = Vec::new();
    f.extend_from_slice(&(model.frames.len() as u64).to_le_bytes());
    for frame in model.frames.values() {
        f.extend_from_slice(&frame.id.to_le_bytes());
        f.extend_from_slice(&frame.rig_id.to_le_bytes());
        push_pose(&mut f, &frame.rig_from_world);
        f.extend_from_slice(&(frame.data_ids.len() as u32).to_le_bytes());
        for d in &frame.data_ids {
            push_sensor(&mut f, d.sensor);
            f.extend_from_slice(&d.id.to_le_bytes());
        }
    }
    [r, f]
}
