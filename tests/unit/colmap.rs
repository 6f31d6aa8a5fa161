use super::binary::{parse_cameras_bin, parse_images_bin, parse_points_bin};
use super::pose::quaternion_to_matrix;
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
    let limits = ReadOptions::default();
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

/// `pixel_rmse`'s vectorised pass against the per-point formula: every length from 0 to 11
/// (full blocks and every partial one), with and without a selection, a point at depth 0
/// outside the selection (it must not poison the sum), both builds of the pass.
#[test]
fn pixel_rmse_matches_the_per_point_formula() {
    use crate::camera::Camera;
    use nalgebra::{Point2, Point3, Rotation3, Vector3};
    let cam = Camera::from_colmap(
        "OPENCV",
        640,
        480,
        vec![500.0, 510.0, 320.0, 240.0, -0.2, 0.05, 0.001, -0.002],
    )
    .unwrap();
    let r = *Rotation3::from_euler_angles(0.1, -0.2, 0.3).matrix();
    let t = Vector3::new(0.1, -0.2, 5.0);
    for n in 0..12usize {
        let world: Vec<Point3<f64>> = (0..n)
            .map(|i| {
                Point3::new(
                    (i % 3) as f64 - 1.0,
                    (i % 4) as f64 * 0.4 - 0.6,
                    (i % 5) as f64 * 0.3,
                )
            })
            .collect();
        let pixels: Vec<Point2<f64>> = world
            .iter()
            .enumerate()
            .map(|(i, x)| {
                let p = r * x.coords + t;
                cam.project(Point2::new(p.x / p.z, p.y / p.z))
                    + nalgebra::Vector2::new(0.3 * (i as f64).sin(), -0.2)
            })
            .collect();
        let mut world_bad = world.clone();
        let keep: Vec<bool> = (0..n).map(|i| i % 3 != 1).collect();
        if n > 1 {
            // Point 1 (not kept) at depth 0.
            let p = r.transpose() * (Vector3::new(0.5, 0.5, 0.0) - t);
            world_bad[1] = Point3::from(p);
        }
        let expected = |w: &[Point3<f64>], sel: Option<&[bool]>| {
            let (mut s, mut k) = (0.0, 0usize);
            for (i, (x, m)) in w.iter().zip(&pixels).enumerate() {
                if sel.is_some_and(|s| !s[i]) {
                    continue;
                }
                let p = r * x.coords + t;
                s += (cam.project(Point2::new(p.x / p.z, p.y / p.z)) - m).norm_squared();
                k += 1;
            }
            if k == 0 {
                f64::NAN
            } else {
                (s / k as f64).sqrt()
            }
        };
        for baseline in [false, true] {
            let run = |w: &[Point3<f64>], sel: Option<&[bool]>| {
                if baseline {
                    crate::numeric::lanes::with_baseline(|| {
                        pixel_rmse(&cam, w, &pixels, sel, &r, &t)
                    })
                } else {
                    pixel_rmse(&cam, w, &pixels, sel, &r, &t)
                }
            };
            for (w, sel) in [
                (&world, None),
                (&world, Some(&keep[..])),
                (&world_bad, Some(&keep[..])),
            ] {
                let (got, want) = (run(w, sel), expected(w, sel));
                if want.is_nan() {
                    assert!(got.is_nan(), "n = {n}: {got}");
                } else {
                    assert!(got.is_finite(), "n = {n}: {got}");
                    assert!(
                        (got - want).abs() <= 1e-13 * want.max(1e-3),
                        "n = {n}: {got} vs {want}"
                    );
                }
            }
        }
    }
}

/// A registration's RMS pixel error, which in the default mode comes from the solution (`refine`'s
/// or `refine_pixels`' last pass), against `pixel_rmse`'s own pass at the same pose: a synthetic
/// model (three images of 300 points, 1 px noise, a quarter of the keypoints untriangulated)
/// through a `SIMPLE_RADIAL` camera (`refine_pixels`) and through a pinhole camera with the same
/// intrinsics (`refine`), with the squared loss and a robust one (`refine_pixels` either way). With
/// RANSAC and in the algebraic mode the registrar runs the pass itself, so these agree by
/// construction.
#[test]
fn registration_rmse_is_the_pixel_rmse_of_its_pose() {
    use crate::camera::Camera;
    use crate::{Loss, Solver};
    use nalgebra::{Point2, Point3, Rotation3, UnitQuaternion, Vector3};
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg64::seed_from_u64(0x2545_F491);
    let mut rnd = move || rng.random_range(-0.5..0.5);
    let radial =
        Camera::from_colmap("SIMPLE_RADIAL", 1280, 960, vec![900.0, 640.0, 480.0, -0.12]).unwrap();
    let pinhole =
        Camera::from_colmap("SIMPLE_PINHOLE", 1280, 960, vec![900.0, 640.0, 480.0]).unwrap();
    let mut points = std::collections::BTreeMap::new();
    for id in 1..=300u64 {
        let xyz = Point3::new(8.0 * rnd(), 6.0 * rnd(), 4.0 * rnd());
        let p = Point3D {
            id,
            xyz,
            rgb: [0; 3],
            error: 0.5,
            track: Vec::new(),
        };
        points.insert(id, p);
    }
    let mut checked = 0;
    for cam in [radial, pinhole] {
        let mut model = Model {
            points: points.clone(),
            ..Model::default()
        };
        model.cameras.insert(1, cam);
        for id in 1..=3u32 {
            let r = Rotation3::from_euler_angles(0.2 * rnd(), 0.2 * rnd(), 0.2 * rnd());
            let t = Vector3::new(rnd(), rnd(), 10.0 + rnd());
            let mut points2d = Vec::new();
            for (pid, p) in &points {
                let x = r * p.xyz.coords + t;
                let px = cam.project(Point2::new(x.x / x.z, x.y / x.z));
                points2d.push((px + nalgebra::Vector2::new(rnd(), rnd()), Some(*pid)));
                if pid % 3 == 0 {
                    points2d.push((
                        Point2::new(640.0 + 900.0 * rnd(), 480.0 + 900.0 * rnd()),
                        None,
                    ));
                }
            }
            let q = UnitQuaternion::from_rotation_matrix(&r);
            let image = Image {
                id,
                q: [q.w, q.i, q.j, q.k],
                t,
                camera_id: 1,
                name: format!("{id}.jpg"),
                points2d,
            };
            model.images.insert(id, image);
        }
        let mut reg = Registrar::new(&model);
        for solver in [Solver::default(), Solver::default().loss(Loss::Huber(2.0))] {
            for id in 1..=3u32 {
                let got = reg.register(id, &solver, None).unwrap();
                assert_eq!((got.n, got.skipped), (300, 0));
                let (world, pixels) = model.correspondences(id);
                let r = got.solution.rotation;
                let t = got.solution.translation;
                let want = pixel_rmse(&cam, &world, &pixels, None, &r, &t);
                assert!(want > 0.1 && want < 2.0, "image {id}: {want} px");
                assert!(
                    (got.rmse_px - want).abs() <= 1e-12 * want,
                    "image {id}: {} vs {want}",
                    got.rmse_px
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 12);
}

/// `PointLookup::gather` appends the observations with a known 3D point, in order, with every
/// kind of table (coordinates, references, the map), whether the vectors have room for all of
/// them (written in place), for none (pushed) or for some (written, then pushed), after what
/// they already hold.
#[test]
fn gathering_appends_in_order_whatever_the_room() {
    use super::model::PointLookup;
    use nalgebra::{Point2, Point3};
    let mut model = Model::default();
    for id in [2u64, 3, 5, 8, 13] {
        let xyz = Point3::new(id as f64, -(id as f64), 0.5 * id as f64);
        let p = Point3D {
            id,
            xyz,
            rgb: [0; 3],
            error: 0.0,
            track: Vec::new(),
        };
        model.points.insert(id, p);
    }
    // Known ids, untriangulated keypoints and ids the model does not have, mixed.
    let ids = [
        Some(3),
        None,
        Some(4),
        Some(13),
        Some(2),
        None,
        Some(99),
        Some(8),
        Some(3),
    ];
    let points2d: Vec<_> = ids
        .iter()
        .enumerate()
        .map(|(k, id)| (Point2::new(k as f64, 10.0 * k as f64), *id))
        .collect();
    let image = Image {
        id: 1,
        q: [1.0, 0.0, 0.0, 0.0],
        t: nalgebra::Vector3::zeros(),
        camera_id: 1,
        name: "1.jpg".into(),
        points2d,
    };
    let held = (Point3::new(7.0, 7.0, 7.0), Point2::new(-1.0, -1.0));
    let mut want = (vec![held.0], vec![held.1]);
    for (px, id) in &image.points2d {
        if let Some(p) = id.and_then(|id| model.points.get(&id)) {
            want.0.push(p.xyz);
            want.1.push(*px);
        }
    }
    assert_eq!(want.0.len(), 6);
    // (largest id for a table, a table of coordinates)
    for (max_table, many) in [(100, true), (100, false), (0, true)] {
        let lookup = PointLookup::new(&model, max_table, many);
        for room in [0, 3, 4, 5, 20] {
            let mut world = Vec::with_capacity(1 + room);
            let mut pixels = Vec::with_capacity(1 + room);
            world.push(held.0);
            pixels.push(held.1);
            lookup.gather(&image, &mut world, &mut pixels);
            assert_eq!(
                (&world, &pixels),
                (&want.0, &want.1),
                "{max_table} {many} {room}"
            );
        }
    }
}
