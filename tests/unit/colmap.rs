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
    let limits = ReadLimits::default();
    let len = b.len() as u64;
    let e = parse_points_bin(Path::new("points3D.bin"), &mut &b[..], len, &limits).unwrap_err();
    assert_eq!(e.location, Location::Offset(0));
    let e = parse_images_bin(Path::new("images.bin"), &mut &b[..], len, &limits).unwrap_err();
    assert_eq!(e.location, Location::Offset(0));
    let max = u64::MAX.to_le_bytes();
    let e = parse_cameras_bin(Path::new("cameras.bin"), &mut &max[..], 8, &limits).unwrap_err();
    assert_eq!(e.location, Location::Offset(0));
    assert_eq!(e.kind, ModelErrorKind::Invalid);
}

#[test]
fn text_numbers_are_shortest_round_trip() {
    use super::text::push_f64;
    for (v, want) in [
        (1245.65, "1245.65"),
        (0.0577095, "0.0577095"),
        (-0.0, "-0"),
        (1.0, "1"),
        (1e-5, "0.00001"),
        (9.99e-6, "9.99e-6"),
        (1e16, "1e16"),
        (123456789012345.6, "123456789012345.6"),
        (5e-324, "5e-324"),
        (f64::MAX, "1.7976931348623157e308"),
        (f64::NAN, "NaN"),
        (f64::NEG_INFINITY, "-inf"),
    ] {
        let mut s = String::new();
        push_f64(&mut s, v);
        assert_eq!(s, want);
        let back: f64 = s.parse().unwrap();
        assert!(back.to_bits() == v.to_bits() || (v.is_nan() && back.is_nan()));
    }
}

#[test]
fn text_names_that_read_back() {
    use super::text::text_name_ok;
    assert!(text_name_ok(
        "WhatsApp Image 2020-04-24 at 5.12.56 PM (1).jpeg"
    ));
    assert!(text_name_ok("a\tb"));
    for bad in ["", " a", "a ", "a\nb", "\u{a0}a"] {
        assert!(!text_name_ok(bad), "{bad:?}");
    }
}
