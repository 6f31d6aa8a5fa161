//! The checks of rigs and frames: each on its own (the readers, record by record) and their
//! references to the model's cameras and images (the reader, once the files are read, and the
//! writer, before anything is written).

use std::collections::BTreeMap;

use super::{Frame, SensorId, SensorRig, SensorType};
use crate::colmap::model::Model;

/// The record a rig or frame inconsistency is about, for the reader's location.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::colmap) enum Culprit {
    Rig(u32),
    Frame(u32),
    Image(u32),
}

/// A rig's own consistency: no sensor twice, no sensor without a reference sensor, every
/// known pose finite with a non-zero quaternion.
pub(in crate::colmap) fn check_rig(rig: &SensorRig) -> Result<(), String> {
    if rig.ref_sensor.is_none() && !rig.sensors.is_empty() {
        return Err(format!(
            "rig {} has sensors but no reference sensor",
            rig.id
        ));
    }
    let all: Vec<SensorId> = rig.all_sensors().collect();
    for (k, s) in all.iter().enumerate() {
        if all[..k].contains(s) {
            return Err(format!("rig {}: sensor {s} appears twice", rig.id));
        }
    }
    for (s, pose) in &rig.sensors {
        if let Some(p) = pose {
            p.check()
                .map_err(|e| format!("rig {}: sensor_from_rig of sensor {s}: {e}", rig.id))?;
        }
    }
    Ok(())
}

/// A frame's own consistency: a finite pose, no datum twice.
pub(in crate::colmap) fn check_frame(frame: &Frame) -> Result<(), String> {
    frame
        .rig_from_world
        .check()
        .map_err(|e| format!("frame {}: rig_from_world: {e}", frame.id))?;
    for (k, d) in frame.data_ids.iter().enumerate() {
        if frame.data_ids[..k].contains(d) {
            return Err(format!(
                "frame {}: data id {} {} appears twice",
                frame.id, d.sensor, d.id
            ));
        }
    }
    Ok(())
}

/// The cross-references of a model with rigs (`with_rigs`: it was read with rig files, or it
/// has rigs or frames to write): every map key is its record's id, every rig and frame is
/// consistent on its own, every camera sensor of a rig is a camera of the model, every
/// frame's rig exists, every datum's sensor is one of its rig's, every camera datum is an
/// image of that camera, and every image is in exactly one frame.
pub(in crate::colmap) fn check_rigs(
    model: &Model,
    with_rigs: bool,
) -> Result<(), (Culprit, String)> {
    if !with_rigs {
        return Ok(());
    }
    for (key, rig) in &model.rigs {
        let fail = |reason: String| Err((Culprit::Rig(rig.id), reason));
        if *key != rig.id {
            return fail(format!("rig {} is stored under key {key}", rig.id));
        }
        check_rig(rig).or_else(fail)?;
        for s in rig.all_sensors() {
            if s.kind == SensorType::Camera && !model.cameras.contains_key(&s.id) {
                return fail(format!(
                    "rig {} has camera {}, which is not in the cameras file",
                    rig.id, s.id
                ));
            }
        }
    }
    // The frame of each image, to find images in two frames or in none.
    let mut frame_of = BTreeMap::new();
    for (key, frame) in &model.frames {
        let fail = |reason: String| Err((Culprit::Frame(frame.id), reason));
        if *key != frame.id {
            return fail(format!("frame {} is stored under key {key}", frame.id));
        }
        check_frame(frame).or_else(fail)?;
        let Some(rig) = model.rigs.get(&frame.rig_id) else {
            return fail(format!(
                "frame {} refers to rig {}, which is not in the rigs file",
                frame.id, frame.rig_id
            ));
        };
        for d in &frame.data_ids {
            if !rig.has_sensor(d.sensor) {
                return fail(format!(
                    "frame {}: sensor {} of data id {} is not a sensor of rig {}",
                    frame.id, d.sensor, d.id, rig.id
                ));
            }
            if d.sensor.kind != SensorType::Camera {
                continue;
            }
            let image = u32::try_from(d.id).ok().and_then(|i| model.images.get(&i));
            let Some(image) = image else {
                return fail(format!(
                    "frame {} refers to image {}, which is not in the images file",
                    frame.id, d.id
                ));
            };
            if image.camera_id != d.sensor.id {
                return fail(format!(
                    "frame {}: image {} is of camera {}, not of camera {} as the frame says",
                    frame.id, image.id, image.camera_id, d.sensor.id
                ));
            }
            if let Some(other) = frame_of.insert(image.id, frame.id) {
                return fail(format!(
                    "image {} is in frames {other} and {}",
                    image.id, frame.id
                ));
            }
        }
    }
    for id in model.images.keys() {
        if !frame_of.contains_key(id) {
            return Err((
                Culprit::Image(*id),
                format!("image {id} is in no frame (a model with rigs has every image in one)"),
            ));
        }
    }
    Ok(())
}
