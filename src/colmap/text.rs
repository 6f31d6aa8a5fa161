//! The text format (`cameras.txt`, `images.txt`, `points3D.txt`): one record per line, `#`
//! comments; every error names the file and the 1-based line.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Point2, Point3, Vector3};

use super::model::{check_quaternion, Image, Images, Location, ModelError, Point3D};
use crate::camera::{Camera, CameraModel};

/// Lines of a text file with 1-based numbers; invalid UTF-8 is an error on its line.
fn text_lines<'a>(
    path: &Path,
    bytes: &'a [u8],
) -> Result<impl Iterator<Item = (usize, &'a str)>, ModelError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let upto = e.valid_up_to();
        let line = 1 + bytes[..upto].iter().filter(|&&b| b == b'\n').count();
        ModelError {
            file: path.to_path_buf(),
            location: Location::Line(line),
            reason: "invalid UTF-8".to_string(),
        }
    })?;
    Ok(text.lines().enumerate().map(|(i, l)| (i + 1, l)))
}

fn is_skipped(line: &str) -> bool {
    let t = line.trim();
    t.is_empty() || t.starts_with('#')
}

struct LineCtx<'a> {
    path: &'a Path,
    line: usize,
}

impl LineCtx<'_> {
    fn err(&self, reason: impl Into<String>) -> ModelError {
        ModelError {
            file: self.path.to_path_buf(),
            location: Location::Line(self.line),
            reason: reason.into(),
        }
    }

    fn field<'t>(
        &self,
        it: &mut impl Iterator<Item = &'t str>,
        what: &str,
    ) -> Result<&'t str, ModelError> {
        it.next()
            .ok_or_else(|| self.err(format!("line ends before {what} (truncated line?)")))
    }

    fn parse<T: std::str::FromStr>(&self, tok: &str, what: &str) -> Result<T, ModelError> {
        tok.parse()
            .map_err(|_| self.err(format!("bad {what}: {:?}", truncate(tok))))
    }

    fn float(&self, tok: &str, what: &str) -> Result<f64, ModelError> {
        let v: f64 = self.parse(tok, what)?;
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.err(format!("{what} is not finite: {:?}", truncate(tok))))
        }
    }
}

fn truncate(s: &str) -> String {
    if s.chars().count() > 40 {
        let mut t: String = s.chars().take(40).collect();
        t.push_str("...");
        t
    } else {
        s.to_string()
    }
}

pub(super) fn parse_cameras_text(
    path: &Path,
    bytes: &[u8],
) -> Result<BTreeMap<u32, Camera>, ModelError> {
    let mut cameras = BTreeMap::new();
    for (line, text) in text_lines(path, bytes)? {
        if is_skipped(text) {
            continue;
        }
        let cx = LineCtx { path, line };
        let mut it = text.split_whitespace();
        let id: u32 = cx.parse(cx.field(&mut it, "CAMERA_ID")?, "CAMERA_ID")?;
        let model_name = cx.field(&mut it, "MODEL")?;
        let width: u64 = cx.parse(cx.field(&mut it, "WIDTH")?, "WIDTH")?;
        let height: u64 = cx.parse(cx.field(&mut it, "HEIGHT")?, "HEIGHT")?;
        let model = CameraModel::from_name(model_name).map_err(|e| cx.err(e.to_string()))?;
        let mut params = Vec::with_capacity(model.num_params());
        for tok in it {
            if params.len() >= model.num_params() {
                return Err(cx.err(format!(
                    "too many parameters for {model} (expected {}: {})",
                    model.num_params(),
                    model.params_info()
                )));
            }
            params.push(cx.float(tok, "camera parameter")?);
        }
        let cam = Camera::new(model, width, height, params).map_err(|e| cx.err(e.to_string()))?;
        if cameras.insert(id, cam).is_some() {
            return Err(cx.err(format!("duplicate camera id {id}")));
        }
    }
    Ok(cameras)
}

pub(super) fn parse_images_text(path: &Path, bytes: &[u8]) -> Result<Images, ModelError> {
    let mut images = BTreeMap::new();
    let mut locs = BTreeMap::new();
    let mut lines = text_lines(path, bytes)?;
    while let Some((line, text)) = lines.next() {
        if is_skipped(text) {
            continue;
        }
        let cx = LineCtx { path, line };
        // IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (the name is the rest of the line).
        let mut rest = text.trim();
        let mut tok = [""; 9];
        const WHAT: [&str; 9] = [
            "IMAGE_ID",
            "QW",
            "QX",
            "QY",
            "QZ",
            "TX",
            "TY",
            "TZ",
            "CAMERA_ID",
        ];
        for (k, what) in WHAT.iter().enumerate() {
            let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
            if end == 0 {
                return Err(cx.err(format!("line ends before {what} (truncated line?)")));
            }
            tok[k] = &rest[..end];
            rest = rest[end..].trim_start();
        }
        let name = rest.to_string();
        if name.is_empty() {
            return Err(cx.err("line ends before NAME (truncated line?)"));
        }
        let id: u32 = cx.parse(tok[0], "IMAGE_ID")?;
        let mut q = [0.0; 4];
        for k in 0..4 {
            q[k] = cx.float(tok[1 + k], WHAT[1 + k])?;
        }
        check_quaternion(&q).map_err(|r| cx.err(r))?;
        let mut t = Vector3::zeros();
        for k in 0..3 {
            t[k] = cx.float(tok[5 + k], WHAT[5 + k])?;
        }
        let camera_id: u32 = cx.parse(tok[8], "CAMERA_ID")?;
        // The next line holds the observations (possibly empty), as COLMAP reads it.
        let mut points2d = Vec::new();
        let mut loc = Location::Line(line);
        if let Some((pline, ptext)) = lines.next() {
            let pc = LineCtx { path, line: pline };
            loc = Location::Line(pline);
            let toks: Vec<&str> = ptext.split_whitespace().collect();
            if !toks.chunks_exact(3).remainder().is_empty() {
                return Err(pc.err(format!(
                    "observations of image {id} must be triples X Y POINT3D_ID, got {} \
                     numbers (truncated line?)",
                    toks.len()
                )));
            }
            points2d.reserve(toks.len() / 3);
            for tr in toks.chunks_exact(3) {
                let x = pc.float(tr[0], "observation X")?;
                let y = pc.float(tr[1], "observation Y")?;
                let pid = if tr[2] == "-1" {
                    None
                } else {
                    Some(pc.parse::<u64>(tr[2], "POINT3D_ID")?)
                };
                points2d.push((Point2::new(x, y), pid));
            }
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
            return Err(cx.err(format!("duplicate image id {id}")));
        }
        locs.insert(id, loc);
    }
    Ok((images, locs))
}

pub(super) fn parse_points_text(
    path: &Path,
    bytes: &[u8],
) -> Result<BTreeMap<u64, Point3D>, ModelError> {
    let mut points = BTreeMap::new();
    for (line, text) in text_lines(path, bytes)? {
        if is_skipped(text) {
            continue;
        }
        let cx = LineCtx { path, line };
        let mut it = text.split_whitespace();
        let id: u64 = cx.parse(cx.field(&mut it, "POINT3D_ID")?, "POINT3D_ID")?;
        let mut xyz = [0.0; 3];
        for (k, what) in ["X", "Y", "Z"].iter().enumerate() {
            xyz[k] = cx.float(cx.field(&mut it, what)?, what)?;
        }
        let mut rgb = [0u8; 3];
        for (k, what) in ["R", "G", "B"].iter().enumerate() {
            rgb[k] = cx.parse(cx.field(&mut it, what)?, &format!("{what} (0-255)"))?;
        }
        let error: f64 = cx.parse(cx.field(&mut it, "ERROR")?, "ERROR")?;
        let toks: Vec<&str> = it.collect();
        if !toks.chunks_exact(2).remainder().is_empty() {
            return Err(cx.err(format!(
                "track of point {id} must be pairs IMAGE_ID POINT2D_IDX, got {} numbers \
                 (truncated line?)",
                toks.len()
            )));
        }
        let mut track = Vec::with_capacity(toks.len() / 2);
        for pair in toks.chunks_exact(2) {
            track.push((
                cx.parse::<u32>(pair[0], "track IMAGE_ID")?,
                cx.parse::<u32>(pair[1], "track POINT2D_IDX")?,
            ));
        }
        let p = Point3D {
            id,
            xyz: Point3::new(xyz[0], xyz[1], xyz[2]),
            rgb,
            error,
            track,
        };
        if points.insert(id, p).is_some() {
            return Err(cx.err(format!("duplicate 3D point id {id}")));
        }
    }
    Ok(points)
}

// ---------------------------------------------------------------------------------------------
