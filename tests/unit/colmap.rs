use super::binary::{parse_cameras_bin, parse_images_bin, parse_points_bin};
use super::*;
use nalgebra::Matrix3;

#[test]
fn quaternion_matrix_is_a_rotation_and_matches_nalgebra() {
    let q = [0.803317, -0.0451533, 0.58139, 0.12095];
    let r = quaternion_to_matrix(q);
    assert!((r.transpose() * r - Matrix3::identity()).norm() < 1e-14);
    assert!((r.determinant() - 1.0).abs() < 1e-14);
    let uq = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        q[0], q[1], q[2], q[3],
    ));
    assert!((uq.to_rotation_matrix().matrix() - r).norm() < 1e-14);
}

#[test]
fn binary_count_cannot_allocate_beyond_the_file() {
    let mut b = Vec::new();
    b.extend_from_slice(&1_000_000_000_000u64.to_le_bytes());
    b.extend_from_slice(&[0u8; 30]);
    let e = parse_points_bin(Path::new("points3D.bin"), &b).unwrap_err();
    assert_eq!(e.location, Location::Offset(0));
    let e = parse_images_bin(Path::new("images.bin"), &b).unwrap_err();
    assert_eq!(e.location, Location::Offset(0));
    let e = parse_cameras_bin(Path::new("cameras.bin"), &u64::MAX.to_le_bytes()).unwrap_err();
    assert_eq!(e.location, Location::Offset(0));
}
