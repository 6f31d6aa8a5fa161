//! The error metrics of docs/algorithm.md section 1 and the statistics of a sample.

use eopnp::Solution;
use nalgebra::{Matrix3, Vector3};

/// Rotation error: the largest angle between corresponding columns, degrees, via atan2.
pub fn rot_err_deg(r: &Matrix3<f64>, r_true: &Matrix3<f64>) -> f64 {
    (0..3)
        .map(|k| {
            let (a, b) = (r.column(k), r_true.column(k));
            a.cross(&b).norm().atan2(a.dot(&b)).to_degrees()
        })
        .fold(0.0, f64::max)
}

/// Relative translation error |t - t_true| / |t_true|.
pub fn trans_err_rel(t: &Vector3<f64>, t_true: &Vector3<f64>) -> f64 {
    (t - t_true).norm() / t_true.norm()
}

/// Translation error in percent: 100 |t - t_true| / |t_true|.
pub fn trans_err_pct(t: &Vector3<f64>, t_true: &Vector3<f64>) -> f64 {
    100.0 * trans_err_rel(t, t_true)
}

/// (R, t) of a solution, x_cam = R X + t.
pub fn pose_of(s: &Solution) -> (Matrix3<f64>, Vector3<f64>) {
    (
        s.pose().rotation.to_rotation_matrix().into_inner(),
        s.translation,
    )
}

/// Mean of a sample (NaN if empty).
pub fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Median of a sample (NaN if empty).
pub fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    if s.len() % 2 == 1 {
        s[m]
    } else {
        0.5 * (s[m - 1] + s[m])
    }
}

/// Largest element (NaN-propagating: a NaN makes the result NaN).
pub fn max_of(v: &[f64]) -> f64 {
    v.iter().fold(0.0_f64, |a, &b| {
        if a.is_nan() || b.is_nan() {
            f64::NAN
        } else {
            a.max(b)
        }
    })
}
