//! OpenCV's camera conventions: a [`Camera`] from `K` and a distortion vector (and back), as
//! `cv2.projectPoints`, `cv2.solvePnP` and `cv2.fisheye` take them.

use nalgebra::Matrix3;

use super::{Camera, CameraError, CameraModel};

impl Camera {
    /// A camera from OpenCV's camera matrix `K` and distortion vector, as passed to
    /// `cv2.projectPoints`, `cv2.solvePnP` or `cv2.undistortPoints`: [`Camera::project`] then
    /// equals `cv2.projectPoints` of the point `(x, y, 1)` with `rvec = tvec = 0`.
    ///
    /// `dist` is in OpenCV's order `(k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2, s3, s4[, tauX,
    /// tauY]]]])` (tilt angles in radians), and the model follows from its length alone:
    ///
    /// | coefficients | model                                                      |
    /// |--------------|------------------------------------------------------------|
    /// | 0            | `PINHOLE`                                                  |
    /// | 4            | `OPENCV`                                                   |
    /// | 5, 8         | `FULL_OPENCV` (missing coefficients 0)                     |
    /// | 12, 14       | `OPENCV_THIN_PRISM_TILTED` (missing tilt 0; not COLMAP's) |
    ///
    /// `K` must be `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]` with `fx, fy > 0`. OpenCV's image
    /// size is not part of these parameters: the camera's [`Camera::width`] and
    /// [`Camera::height`] are 0 (no computation of this crate uses them; build the camera with
    /// [`Camera::new`]`(cam.model(), width, height, cam.params().to_vec())` to record them).
    /// Pixels are in OpenCV's convention (see the module documentation).
    ///
    /// ```
    /// use eopnp::camera::{Camera, CameraModel};
    /// use nalgebra::{Matrix3, Point2};
    ///
    /// let k = Matrix3::new(800.0, 0.0, 320.0, 0.0, 810.0, 240.0, 0.0, 0.0, 1.0);
    /// let cam = Camera::from_opencv(&k, &[-0.2, 0.05, 1e-3, -5e-4, 0.01])?;
    /// assert_eq!(cam.model(), CameraModel::FullOpenCv);
    /// let n = Point2::new(0.3, -0.2);
    /// let px = cam.project(n); // cv2.projectPoints([(0.3, -0.2, 1)], 0, 0, K, dist)
    /// assert!((cam.undistort(px)? - n).norm() < 1e-12);
    /// # Ok::<(), eopnp::camera::CameraError>(())
    /// ```
    ///
    /// # Errors
    /// [`CameraError::InvalidParams`] for a distortion vector of another length, a non-finite
    /// entry, a `K` not of the form above, in particular a non-zero skew `K[0][1]` (which these
    /// models cannot represent, and which `cv2.projectPoints` ignores), non-positive focal
    /// lengths or a tilt angle of `pi/2` or more.
    pub fn from_opencv(k: &Matrix3<f64>, dist: &[f64]) -> Result<Self, CameraError> {
        const NAMES: [&str; 14] = [
            "k1", "k2", "p1", "p2", "k3", "k4", "k5", "k6", "s1", "s2", "s3", "s4", "tauX", "tauY",
        ];
        let mut params = opencv_intrinsics(k)?.to_vec();
        let n = dist.len();
        if !matches!(n, 0 | 4 | 5 | 8 | 12 | 14) {
            return Err(CameraError::InvalidParams(format!(
                "an OpenCV distortion vector has 0, 4, 5, 8, 12 or 14 coefficients, got {n}"
            )));
        }
        if let Some(i) = dist.iter().position(|c| !c.is_finite()) {
            return Err(CameraError::InvalidParams(format!(
                "distortion coefficient {} ({}) is not finite",
                i, NAMES[i]
            )));
        }
        let (model, len) = match n {
            0 => (CameraModel::Pinhole, 0),
            4 => (CameraModel::OpenCv, 4),
            5 | 8 => (CameraModel::FullOpenCv, 8),
            _ => (CameraModel::OpenCvThinPrismTilted, 14),
        };
        params.extend_from_slice(dist);
        params.resize(4 + len, 0.0);
        Camera::new(model, 0, 0, params)
    }

    /// A camera from the camera matrix `K` and the distortion `(k1, k2, k3, k4)` of OpenCV's
    /// fisheye model (`cv2.fisheye.projectPoints`, `cv2.fisheye.undistortPoints`): an
    /// `OPENCV_FISHEYE` camera, whose [`Camera::project`] equals `cv2.fisheye.projectPoints` of
    /// the point `(x, y, 1)` with `rvec = tvec = 0`.
    ///
    /// `K` and the image size are as in [`Camera::from_opencv`]; the skew `alpha` of
    /// `cv2.fisheye` must be 0 (`K[0][1] = 0`).
    ///
    /// ```
    /// use eopnp::camera::{Camera, CameraModel};
    /// use nalgebra::{Matrix3, Point2};
    ///
    /// let k = Matrix3::new(400.0, 0.0, 640.0, 0.0, 401.0, 480.0, 0.0, 0.0, 1.0);
    /// let cam = Camera::from_opencv_fisheye(&k, &[0.02, -0.01, 0.003, -0.001])?;
    /// assert_eq!(cam.model(), CameraModel::OpenCvFisheye);
    /// let n = Point2::new(1.5, -0.7); // about 59 degrees off axis
    /// assert!((cam.undistort(cam.project(n))? - n).norm() < 1e-12);
    /// # Ok::<(), eopnp::camera::CameraError>(())
    /// ```
    ///
    /// # Errors
    /// [`CameraError::InvalidParams`] as [`Camera::from_opencv`].
    pub fn from_opencv_fisheye(k: &Matrix3<f64>, dist: &[f64; 4]) -> Result<Self, CameraError> {
        let mut params = opencv_intrinsics(k)?.to_vec();
        if let Some(i) = dist.iter().position(|c| !c.is_finite()) {
            return Err(CameraError::InvalidParams(format!(
                "fisheye distortion coefficient k{} is not finite",
                i + 1
            )));
        }
        params.extend_from_slice(dist);
        Camera::new(CameraModel::OpenCvFisheye, 0, 0, params)
    }

    /// OpenCV's camera matrix and distortion vector of this camera, for `cv2.projectPoints`,
    /// `cv2.solvePnP` or `cv2.undistortPoints`, if its model has an exact OpenCV form: every
    /// perspective model (`PINHOLE` and `SIMPLE_PINHOLE` give an empty vector,
    /// `SIMPLE_RADIAL`, `RADIAL` and `OPENCV` 4 coefficients, `FULL_OPENCV` 8,
    /// `OPENCV_THIN_PRISM_TILTED` 14). `None` for the fisheye models (see
    /// [`Camera::to_opencv_fisheye`]).
    ///
    /// ```
    /// use eopnp::camera::{Camera, CameraModel};
    /// use nalgebra::Point2;
    ///
    /// let params = vec![1245.6, 600.0, 800.0, 0.06];
    /// let cam = Camera::from_colmap("SIMPLE_RADIAL", 1200, 1600, params)?;
    /// let (k, dist) = cam.to_opencv().unwrap();
    /// assert_eq!((k[(0, 0)], k[(1, 1)], k[(0, 2)], k[(1, 2)]), (1245.6, 1245.6, 600.0, 800.0));
    /// assert_eq!(dist, [0.06, 0.0, 0.0, 0.0]);
    /// // Back: the same mapping, as an OPENCV camera.
    /// let back = Camera::from_opencv(&k, &dist)?;
    /// assert_eq!(back.model(), CameraModel::OpenCv);
    /// let n = Point2::new(0.3, -0.2);
    /// assert!((back.project(n) - cam.project(n)).norm() < 1e-9);
    /// # Ok::<(), eopnp::camera::CameraError>(())
    /// ```
    #[must_use]
    pub fn to_opencv(&self) -> Option<(Matrix3<f64>, Vec<f64>)> {
        let p = self.params();
        let dist = match self.model {
            CameraModel::SimplePinhole | CameraModel::Pinhole => vec![],
            CameraModel::SimpleRadial => vec![p[3], 0.0, 0.0, 0.0],
            CameraModel::Radial => vec![p[3], p[4], 0.0, 0.0],
            CameraModel::OpenCv | CameraModel::FullOpenCv | CameraModel::OpenCvThinPrismTilted => {
                p[4..].to_vec()
            }
            CameraModel::OpenCvFisheye
            | CameraModel::SimpleRadialFisheye
            | CameraModel::RadialFisheye => return None,
        };
        Some((self.opencv_matrix(), dist))
    }

    /// OpenCV's fisheye camera matrix and distortion `(k1, k2, k3, k4)` of this camera, for
    /// `cv2.fisheye.projectPoints` or `cv2.fisheye.undistortPoints`, if it is a fisheye
    /// camera (`OPENCV_FISHEYE`, `SIMPLE_RADIAL_FISHEYE`, `RADIAL_FISHEYE`, missing
    /// coefficients 0); `None` for the perspective models (see [`Camera::to_opencv`]).
    ///
    /// ```
    /// use eopnp::camera::Camera;
    ///
    /// let params = vec![700.0, 600.0, 800.0, 0.03, -0.004];
    /// let cam = Camera::from_colmap("RADIAL_FISHEYE", 1200, 1600, params)?;
    /// let (k, dist) = cam.to_opencv_fisheye().unwrap();
    /// assert_eq!(dist, [0.03, -0.004, 0.0, 0.0]);
    /// assert!(cam.to_opencv().is_none());
    /// # Ok::<(), eopnp::camera::CameraError>(())
    /// ```
    #[must_use]
    pub fn to_opencv_fisheye(&self) -> Option<(Matrix3<f64>, [f64; 4])> {
        let p = self.params();
        let dist = match self.model {
            CameraModel::OpenCvFisheye => [p[4], p[5], p[6], p[7]],
            CameraModel::SimpleRadialFisheye => [p[3], 0.0, 0.0, 0.0],
            CameraModel::RadialFisheye => [p[3], p[4], 0.0, 0.0],
            CameraModel::SimplePinhole
            | CameraModel::Pinhole
            | CameraModel::SimpleRadial
            | CameraModel::Radial
            | CameraModel::OpenCv
            | CameraModel::FullOpenCv
            | CameraModel::OpenCvThinPrismTilted => return None,
        };
        Some((self.opencv_matrix(), dist))
    }

    /// `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]`.
    pub(super) fn opencv_matrix(&self) -> Matrix3<f64> {
        let (fx, fy) = self.focal_lengths();
        let (cx, cy) = self.principal_point();
        Matrix3::new(fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0)
    }
}

/// `[fx, fy, cx, cy]` of OpenCV's camera matrix, which must be
/// `[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]` with finite entries (`fx, fy > 0` is checked by
/// [`Camera::new`]).
fn opencv_intrinsics(k: &Matrix3<f64>) -> Result<[f64; 4], CameraError> {
    let bad = |why: String| Err(CameraError::InvalidParams(why));
    if k.iter().any(|v| !v.is_finite()) {
        return bad("camera matrix K has a non-finite entry".to_string());
    }
    let row2 = [k[(2, 0)], k[(2, 1)], k[(2, 2)]];
    if row2 != [0.0, 0.0, 1.0] {
        return bad(format!(
            "camera matrix K must have last row [0, 0, 1], got {row2:?}"
        ));
    }
    if k[(1, 0)] != 0.0 {
        return bad(format!(
            "camera matrix K must have K[1][0] = 0, got {}",
            k[(1, 0)]
        ));
    }
    if k[(0, 1)] != 0.0 {
        return bad(format!(
            "camera matrix K has skew K[0][1] = {}: not representable by these camera models \
             (cv2.projectPoints ignores it too)",
            k[(0, 1)]
        ));
    }
    Ok([k[(0, 0)], k[(1, 1)], k[(0, 2)], k[(1, 2)]])
}
