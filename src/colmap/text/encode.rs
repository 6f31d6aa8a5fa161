//! Writing the text format: `cameras.txt`, `images.txt` and `points3D.txt` of a model, with
//! COLMAP's header comments, for the writer (`write.rs`).

use crate::colmap::model::Model;

/// Appends `v` in Rust's shortest round-trip form (parsing it back gives the same `f64`, sign
/// of zero included): plain decimal for moderate magnitudes, exponent form (`1e300`,
/// `5e-324`) otherwise so that no number needs hundreds of digits. Both forms are read by
/// COLMAP (`std::istream >> double`). Non-finite values (only possible in a point's ERROR)
/// print as `NaN`, `inf`, `-inf`, which this crate's reader accepts.
pub(in crate::colmap) fn push_f64(out: &mut String, v: f64) {
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
pub(in crate::colmap) fn text_name_ok(name: &str) -> bool {
    !name.is_empty() && !name.contains('\n') && name.trim() == name
}

/// `cameras.txt`, `images.txt` and `points3D.txt` of a model already checked by
/// `write::validate` for the text format, with COLMAP's header comments.
pub(in crate::colmap) fn encode_text(model: &Model) -> [Vec<u8>; 3] {
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
