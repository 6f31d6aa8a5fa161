//! The text format (`cameras.txt`, `images.txt`, `points3D.txt`): one record per line, `#`
//! comments; every error names the file and the 1-based line. Also the encoder the writer
//! (`write.rs`) uses.

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Point2, Point3, Vector3};

use super::model::{check_quaternion, Image, Images, Location, Model, ModelError, Point3D};
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

// Writing.

/// Appends `v` in Rust's shortest round-trip form (parsing it back gives the same `f64`, sign
/// of zero included): plain decimal for moderate magnitudes, exponent form (`1e300`,
/// `5e-324`) otherwise so that no number needs hundreds of digits. Both forms are read by
/// COLMAP (`std::istream >> double`). Non-finite values (only possible in a point's ERROR)
/// print as `NaN`, `inf`, `-inf`, which this crate's reader accepts.
pub(super) fn push_f64(out: &mut String, v: f64) {
    use std::fmt::Write as _;
    let a = v.abs();
    if a == 0.0 || !v.is_finite() || (1e-5..1e16).contains(&a) {
        let _ = write!(out, "{v}");
    } else {
        let _ = write!(out, "{v:e}");
    }
}

/// A statistic of a header comment as C++ streams print a double by default (six significant
/// digits, `%g`), as COLMAP writes it.
fn six_digits(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let exp = x.abs().log10().floor() as i32;
    if !(-5..6).contains(&exp) {
        return format!("{x:.5e}");
    }
    let decimals = usize::try_from(5 - exp).unwrap_or(0);
    let s = format!("{x:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// Whether `name` reads back unchanged from an `images.txt` line: non-empty, one line, no
/// leading or trailing whitespace (the reader trims; inner spaces are kept).
pub(super) fn text_name_ok(name: &str) -> bool {
    !name.is_empty() && !name.contains('\n') && name.trim() == name
}

/// `cameras.txt`, `images.txt` and `points3D.txt` of a model already checked by
/// `write::validate` for the text format, with COLMAP's header comments.
pub(super) fn encode_text(model: &Model) -> [Vec<u8>; 3] {
    use std::fmt::Write as _;
    let mut c = String::new();
    c.push_str("# Camera list with one line of data per camera:\n");
    c.push_str("#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n");
    let _ = writeln!(c, "# Number of cameras: {}", model.cameras.len());
    for (id, cam) in &model.cameras {
        let _ = write!(
            c,
            "{id} {} {} {}",
            cam.model().name(),
            cam.width(),
            cam.height()
        );
        for &p in cam.params() {
            c.push(' ');
            push_f64(&mut c, p);
        }
        c.push('\n');
    }

    let mut i = String::new();
    let observed: usize = model
        .images
        .values()
        .map(|img| img.points2d.iter().filter(|(_, p)| p.is_some()).count())
        .sum();
    let mean_obs = if model.images.is_empty() {
        0.0
    } else {
        observed as f64 / model.images.len() as f64
    };
    i.push_str("# Image list with two lines of data per image:\n");
    i.push_str("#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n");
    i.push_str("#   POINTS2D[] as (X, Y, POINT3D_ID)\n");
    let _ = writeln!(
        i,
        "# Number of images: {}, mean observations per image: {}",
        model.images.len(),
        six_digits(mean_obs)
    );
    for img in model.images.values() {
        let _ = write!(i, "{}", img.id);
        for &v in img.q.iter().chain(img.t.iter()) {
            i.push(' ');
            push_f64(&mut i, v);
        }
        let _ = writeln!(i, " {} {}", img.camera_id, img.name);
        for (k, (px, pid)) in img.points2d.iter().enumerate() {
            if k > 0 {
                i.push(' ');
            }
            push_f64(&mut i, px.x);
            i.push(' ');
            push_f64(&mut i, px.y);
            match pid {
                Some(p) => {
                    let _ = write!(i, " {p}");
                }
                None => i.push_str(" -1"),
            }
        }
        i.push('\n');
    }

    let mut p = String::new();
    let track_sum: usize = model.points.values().map(|pt| pt.track.len()).sum();
    let mean_track = if model.points.is_empty() {
        0.0
    } else {
        track_sum as f64 / model.points.len() as f64
    };
    p.push_str("# 3D point list with one line of data per point:\n");
    p.push_str("#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n");
    let _ = writeln!(
        p,
        "# Number of points: {}, mean track length: {}",
        model.points.len(),
        six_digits(mean_track)
    );
    for pt in model.points.values() {
        let _ = write!(p, "{}", pt.id);
        for &v in pt.xyz.iter() {
            p.push(' ');
            push_f64(&mut p, v);
        }
        let _ = write!(p, " {} {} {} ", pt.rgb[0], pt.rgb[1], pt.rgb[2]);
        push_f64(&mut p, pt.error);
        for (img, idx) in &pt.track {
            let _ = write!(p, " {img} {idx}");
        }
        p.push('\n');
    }
    [c.into_bytes(), i.into_bytes(), p.into_bytes()]
}
