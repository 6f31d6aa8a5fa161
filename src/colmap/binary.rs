//! The binary format (`cameras.bin`, `images.bin`, `points3D.bin`, and `rigs.bin`,
//! `frames.bin` in `binary/rigs.rs`; little-endian, COLMAP's `reconstruction_io` layout): the
//! readers, streaming record by record and bounded by the bytes present (every count is
//! checked against the bytes left before anything is allocated for it), and the encoder the
//! writer (`write.rs`) uses.

use std::collections::BTreeMap;
use std::io::{self, BufRead};
use std::path::Path;

use nalgebra::{Point2, Point3, Vector3};

use super::model::{Image, Images, Location, Model, ModelError, ModelErrorKind, Point3D};
use super::options::{Limit, ReadOptions, MAX_FIELD_BYTES};
use super::pose::check_quaternion;
use crate::camera::{Camera, CameraError, CameraModel};

mod rigs;

pub(super) use rigs::{encode_rigs_binary, parse_frames_bin, parse_rigs_bin};

// Binary format (little-endian; COLMAP's reconstruction_io / read_write_model.py layout).

/// A binary file of `len` bytes read from `src`, with the offset of the next byte.
struct Reader<'a, R> {
    path: &'a Path,
    src: &'a mut R,
    pos: u64,
    len: u64,
}

impl<'a, R: BufRead> Reader<'a, R> {
    fn new(path: &'a Path, src: &'a mut R, len: u64) -> Self {
        Reader {
            path,
            src,
            pos: 0,
            len,
        }
    }

    fn err_at(&self, pos: u64, reason: impl Into<String>) -> ModelError {
        ModelError::invalid(self.path, Location::Offset(pos), reason)
    }

    fn remaining(&self) -> u64 {
        self.len.saturating_sub(self.pos)
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], ModelError> {
        if self.remaining() < N as u64 {
            return Err(self.err_at(
                self.pos,
                format!(
                    "unexpected end of file reading {what}: need {N} bytes, {} left \
                     (truncated file?)",
                    self.remaining()
                ),
            ));
        }
        let mut a = [0u8; N];
        self.src.read_exact(&mut a).map_err(|e| self.io_err(&e))?;
        self.pos += N as u64;
        Ok(a)
    }

    /// A read error (the file shrank while it was read, or an I/O error).
    fn io_err(&self, e: &io::Error) -> ModelError {
        ModelError {
            file: self.path.to_path_buf(),
            location: Location::Offset(self.pos),
            kind: ModelErrorKind::Io,
            reason: format!("cannot read: {e}"),
        }
    }

    fn u64(&mut self, what: &str) -> Result<u64, ModelError> {
        Ok(u64::from_le_bytes(self.array(what)?))
    }

    fn i64(&mut self, what: &str) -> Result<i64, ModelError> {
        Ok(i64::from_le_bytes(self.array(what)?))
    }

    fn u32(&mut self, what: &str) -> Result<u32, ModelError> {
        Ok(u32::from_le_bytes(self.array(what)?))
    }

    fn i32(&mut self, what: &str) -> Result<i32, ModelError> {
        Ok(i32::from_le_bytes(self.array(what)?))
    }

    fn u8(&mut self, what: &str) -> Result<u8, ModelError> {
        Ok(self.array::<1>(what)?[0])
    }

    fn f64(&mut self, what: &str) -> Result<f64, ModelError> {
        let at = self.pos;
        let v = f64::from_le_bytes(self.array(what)?);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err_at(at, format!("{what} is not finite ({v})")))
        }
    }

    /// A count of records of at least `min_size` bytes each, checked against the bytes left
    /// (so a corrupt count can never cause a huge allocation or a long loop) and against
    /// `limit` (the limit then hit, for the error).
    fn count(
        &mut self,
        what: &str,
        min_size: u64,
        limit: Option<(usize, Limit, &str)>,
    ) -> Result<usize, ModelError> {
        let at = self.pos;
        let n = self.u64(what)?;
        if u128::from(n) * u128::from(min_size) > u128::from(self.remaining()) {
            return Err(self.err_at(
                at,
                format!(
                    "{what} = {n} needs at least {} bytes but only {} remain (corrupt or \
                     truncated file?)",
                    u128::from(n) * u128::from(min_size),
                    self.remaining()
                ),
            ));
        }
        if let Some((max, limit, which)) = limit {
            if n > max as u64 {
                return Err(ModelError::limit(
                    self.path,
                    Location::Offset(at),
                    limit,
                    &format!("{which} has {n}"),
                ));
            }
        }
        // Fits in the file, which is in memory or at most `usize::MAX` bytes long to read.
        usize::try_from(n).map_err(|_| self.err_at(at, format!("{what} = {n} is too large")))
    }

    /// A NUL-terminated name of at most [`MAX_FIELD_BYTES`] bytes.
    fn name(&mut self) -> Result<String, ModelError> {
        let at = self.pos;
        let mut bytes = Vec::new();
        loop {
            // Never past the file's length (it may have grown since it was opened).
            let left = usize::try_from(self.remaining()).unwrap_or(usize::MAX);
            let buf = match self.src.fill_buf() {
                Ok(b) => b,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(self.io_err(&e)),
            };
            let buf = &buf[..buf.len().min(left)];
            if buf.is_empty() {
                return Err(self.err_at(at, "image name is not NUL-terminated (truncated file?)"));
            }
            let nul = buf.iter().position(|&b| b == 0);
            let n = nul.unwrap_or(buf.len());
            if bytes.len() + n > MAX_FIELD_BYTES {
                return Err(ModelError::limit(
                    self.path,
                    Location::Offset(at),
                    Limit::FieldBytes(MAX_FIELD_BYTES),
                    "image name longer than 64 KiB (no NUL byte within it)",
                ));
            }
            bytes.extend_from_slice(&buf[..n]);
            let used = n + usize::from(nul.is_some());
            self.src.consume(used);
            self.pos += used as u64;
            if nul.is_some() {
                break;
            }
        }
        String::from_utf8(bytes).map_err(|_| self.err_at(at, "image name is not valid UTF-8"))
    }

    fn finish(&self) -> Result<(), ModelError> {
        if self.remaining() == 0 {
            Ok(())
        } else {
            Err(self.err_at(
                self.pos,
                format!("{} unexpected trailing bytes", self.remaining()),
            ))
        }
    }
}

pub(super) fn parse_cameras_bin<R: BufRead>(
    path: &Path,
    src: &mut R,
    len: u64,
    _limits: &ReadOptions,
) -> Result<BTreeMap<u32, Camera>, ModelError> {
    let mut r = Reader::new(path, src, len);
    let n = r.count("number of cameras", 24, None)?;
    let mut cameras = BTreeMap::new();
    for _ in 0..n {
        let at = r.pos;
        let id = r.u32("CAMERA_ID")?;
        let model_id = r.i32("MODEL_ID")?;
        let width = r.u64("WIDTH")?;
        let height = r.u64("HEIGHT")?;
        let model =
            CameraModel::from_colmap_id(model_id).map_err(|e| r.err_at(at, e.to_string()))?;
        let mut params = Vec::with_capacity(model.num_params());
        for _ in 0..model.num_params() {
            params.push(r.f64("camera parameter")?);
        }
        let cam = Camera::new(model, width, height, params)
            .map_err(|e: CameraError| r.err_at(at, e.to_string()))?;
        if cameras.insert(id, cam).is_some() {
            return Err(r.err_at(at, format!("duplicate camera id {id}")));
        }
    }
    r.finish()?;
    Ok(cameras)
}

/// Longest image name accepted (bytes), a bound on the NUL search; the writer refuses longer
/// names.
pub(super) const MAX_NAME: usize = MAX_FIELD_BYTES;

pub(super) fn parse_images_bin<R: BufRead>(
    path: &Path,
    src: &mut R,
    len: u64,
    limits: &ReadOptions,
) -> Result<Images, ModelError> {
    let mut r = Reader::new(path, src, len);
    // Smallest record: 4 + 7 * 8 + 4 + 1 (empty name's NUL) + 8 = 73 bytes.
    let n = r.count("number of images", 73, None)?;
    let mut images = BTreeMap::new();
    let mut locs = BTreeMap::new();
    for _ in 0..n {
        let at = r.pos;
        let id = r.u32("IMAGE_ID")?;
        let mut q = [0.0; 4];
        for v in &mut q {
            *v = r.f64("quaternion")?;
        }
        check_quaternion(&q).map_err(|e| r.err_at(at, e))?;
        let mut t = Vector3::zeros();
        for k in 0..3 {
            t[k] = r.f64("translation")?;
        }
        let camera_id = r.u32("CAMERA_ID")?;
        let name = r.name()?;
        let which = format!("image {id}: the number of 2D points");
        let np = r.count(
            "number of 2D points",
            24,
            Some((
                limits.max_observations,
                Limit::Observations(limits.max_observations),
                &which,
            )),
        )?;
        let mut points2d = Vec::with_capacity(np);
        for _ in 0..np {
            let x = r.f64("observation x")?;
            let y = r.f64("observation y")?;
            let pat = r.pos;
            let pid = r.i64("POINT3D_ID")?;
            let pid = match pid {
                -1 => None,
                p if p >= 0 => Some(p as u64),
                p => return Err(r.err_at(pat, format!("invalid POINT3D_ID {p}"))),
            };
            points2d.push((Point2::new(x, y), pid));
        }
        let img = Image {
            id,
            q,
            t,
            camera_id,
            name,
            points2d,
        };
        if images.insert(id, img).is_some() {
            return Err(r.err_at(at, format!("duplicate image id {id}")));
        }
        locs.insert(id, Location::Offset(at));
    }
    r.finish()?;
    Ok((images, locs))
}

pub(super) fn parse_points_bin<R: BufRead>(
    path: &Path,
    src: &mut R,
    len: u64,
    limits: &ReadOptions,
) -> Result<BTreeMap<u64, Point3D>, ModelError> {
    let mut r = Reader::new(path, src, len);
    // Smallest record: 8 + 3 * 8 + 3 + 8 + 8 = 51 bytes.
    let n = r.count("number of 3D points", 51, None)?;
    let mut points = BTreeMap::new();
    for _ in 0..n {
        let at = r.pos;
        let id = r.u64("POINT3D_ID")?;
        let mut xyz = [0.0; 3];
        for v in &mut xyz {
            *v = r.f64("point coordinate")?;
        }
        let rgb = [r.u8("colour")?, r.u8("colour")?, r.u8("colour")?];
        let error = f64::from_le_bytes(r.array("ERROR")?);
        let which = format!("point {id}: the track length");
        let nt = r.count(
            "track length",
            8,
            Some((
                limits.max_track_length,
                Limit::TrackLength(limits.max_track_length),
                &which,
            )),
        )?;
        let mut track = Vec::with_capacity(nt);
        for _ in 0..nt {
            track.push((r.u32("track IMAGE_ID")?, r.u32("track POINT2D_IDX")?));
        }
        let p = Point3D {
            id,
            xyz: Point3::new(xyz[0], xyz[1], xyz[2]),
            rgb,
            error,
            track,
        };
        if points.insert(id, p).is_some() {
            return Err(r.err_at(at, format!("duplicate 3D point id {id}")));
        }
    }
    r.finish()?;
    Ok(points)
}

/// `cameras.bin`, `images.bin` and `points3D.bin` of a model already checked by
/// `write::validate` for the binary format (every camera has a COLMAP model id, no name holds
/// a NUL byte or is longer than the reader accepts, every observed 3D point id fits an `i64`).
pub(super) fn encode_binary(model: &Model) -> [Vec<u8>; 3] {
    let mut c = Vec::new();
    c.extend_from_slice(&(model.cameras.len() as u64).to_le_bytes());
    for (id, cam) in &model.cameras {
        let model_id = cam.model().colmap_id().unwrap_or(-1);
        c.extend_from_slice(&id.to_le_bytes());
        c.extend_from_slice(&model_id.to_le_bytes());
        c.extend_from_slice(&cam.width().to_le_bytes());
        c.extend_from_slice(&cam.height().to_le_bytes());
        for p in cam.params() {
            c.extend_from_slice(&p.to_le_bytes());
        }
    }

    let mut i = Vec::new();
    i.extend_from_slice(&(model.images.len() as u64).to_le_bytes());
    for img in model.images.values() {
        i.extend_from_slice(&img.id.to_le_bytes());
        for v in img.q.iter().chain(img.t.iter()) {
            i.extend_from_slice(&v.to_le_bytes());
        }
        i.extend_from_slice(&img.camera_id.to_le_bytes());
        i.extend_from_slice(img.name.as_bytes());
        i.push(0);
        i.extend_from_slice(&(img.points2d.len() as u64).to_le_bytes());
        for (px, pid) in &img.points2d {
            i.extend_from_slice(&px.x.to_le_bytes());
            i.extend_from_slice(&px.y.to_le_bytes());
            let id = pid.map_or(-1i64, |p| i64::try_from(p).unwrap_or(-1));
            i.extend_from_slice(&id.to_le_bytes());
        }
    }

    let mut p = Vec::new();
    p.extend_from_slice(&(model.points.len() as u64).to_le_bytes());
    for pt in model.points.values() {
        p.extend_from_slice(&pt.id.to_le_bytes());
        for v in pt.xyz.iter() {
            p.extend_from_slice(&v.to_le_bytes());
        }
        p.extend_from_slice(&pt.rgb);
        p.extend_from_slice(&pt.error.to_le_bytes());
        p.extend_from_slice(&(pt.track.len() as u64).to_le_bytes());
        for (img, k) in &pt.track {
            p.extend_from_slice(&img.to_le_bytes());
            p.extend_from_slice(&k.to_le_bytes());
        }
    }
    [c, i, p]
}
