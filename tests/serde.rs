//! Feature `serde`: the public data types survive a JSON round trip unchanged, and a
//! deserialized `Camera` is validated like `Camera::new`.

use eopnp::camera::{Camera, CameraModel};
use eopnp::ransac::{Ransac, RansacSolution};
use eopnp::Problem;
use eopnp::{Refinement, Solution, Solver};
use nalgebra::{Point2, Point3, Rotation3, Vector3};

fn round_trip<T: serde::Serialize + serde::de::DeserializeOwned>(x: &T) -> T {
    let text = serde_json::to_string(x).expect("serialize");
    serde_json::from_str(&text).expect("deserialize")
}

fn problem() -> (Vec<Point3<f64>>, Vec<Point2<f64>>) {
    let r = Rotation3::from_euler_angles(0.1, -0.2, 0.3);
    let t = Vector3::new(0.1, -0.2, 6.0);
    let world: Vec<Point3<f64>> = (0..12)
        .map(|i| {
            Point3::new(
                (i % 3) as f64 - 1.0,
                (i % 4) as f64 * 0.5 - 0.7,
                (i % 5) as f64 * 0.3,
            )
        })
        .collect();
    let image = world
        .iter()
        .map(|x| {
            let p = r * x + t;
            Point2::new(p.x / p.z, p.y / p.z)
        })
        .collect();
    (world, image)
}

#[test]
fn solution_and_options_round_trip() {
    let (world, image) = problem();
    for solver in [
        Solver::default(),
        Solver::default().refinement(Refinement::Algebraic),
    ] {
        let sol = solver.solve(&Problem::normalised(&world, &image)).unwrap();
        let back: Solution = round_trip(&sol);
        assert_eq!(back, sol);
    }
    assert_eq!(round_trip(&Refinement::Algebraic), Refinement::Algebraic);
    let r = Ransac::default().threshold_px(3.0).seed(9);
    assert_eq!(round_trip(&r), r);
    let sol = r
        .estimate(
            &Solver::default(),
            &Problem::normalised(&world, &image).focal(800.0, 800.0),
        )
        .unwrap();
    let back: RansacSolution = round_trip(&sol);
    assert_eq!(back.solution, sol.solution);
    assert_eq!(back.inliers, sol.inliers);
    assert_eq!(back.stats, sol.stats);
}

#[test]
fn camera_round_trips_and_is_validated() {
    let cam = Camera::from_colmap(
        "SIMPLE_RADIAL",
        1200,
        1600,
        vec![1245.65, 600.0, 800.0, 0.0577],
    )
    .unwrap();
    let text = serde_json::to_string(&cam).unwrap();
    assert!(text.contains("\"SIMPLE_RADIAL\""), "{text}");
    assert_eq!(serde_json::from_str::<Camera>(&text).unwrap(), cam);
    assert_eq!(
        round_trip(&CameraModel::OpenCvFisheye),
        CameraModel::OpenCvFisheye
    );
    // A negative focal length, a wrong parameter count and an unknown model are refused.
    for bad in [
        r#"{"model":"PINHOLE","width":0,"height":0,"params":[-1.0,1.0,0.0,0.0]}"#,
        r#"{"model":"PINHOLE","width":0,"height":0,"params":[1.0,1.0,0.0]}"#,
        r#"{"model":"NO_SUCH_MODEL","width":0,"height":0,"params":[1.0,1.0,0.0,0.0]}"#,
    ] {
        let e = serde_json::from_str::<Camera>(bad).unwrap_err().to_string();
        assert!(!e.is_empty(), "{bad}");
    }
}

#[test]
fn colmap_model_and_registration_round_trip() {
    use eopnp::colmap::{read_model, register_image, Model, ReadOptions, Registration};
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/data/colmap-boxes");
    let model = read_model(dir, &ReadOptions::default()).unwrap();
    let back: Model = round_trip(&model);
    assert_eq!(back, model);
    let id = *model.images.keys().next().unwrap();
    let reg = register_image(&model, id, &Solver::default(), Some(&Ransac::default())).unwrap();
    let back: Registration = round_trip(&reg);
    assert_eq!(back.solution, reg.solution);
    assert_eq!(back.ransac, reg.ransac);
    assert_eq!(back.rotation_error_deg, reg.rotation_error_deg);
}

#[test]
fn colmap_rig_model_and_frame_registration_round_trip() {
    use eopnp::colmap::{read_model, register_frame, FrameRegistration, Model, ReadOptions};
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/data/colmap-rig");
    let model = read_model(dir, &ReadOptions::default()).unwrap();
    assert_eq!((model.rigs.len(), model.frames.len()), (2, 6));
    let back: Model = round_trip(&model);
    assert_eq!(back, model);
    // A model serialized before rigs existed (no `rigs`, `frames` keys) reads as one without.
    let mut value = serde_json::to_value(&model).unwrap();
    let object = value.as_object_mut().unwrap();
    object.remove("rigs");
    object.remove("frames");
    let old: Model = serde_json::from_value(value).unwrap();
    assert!(old.rigs.is_empty() && old.frames.is_empty());
    assert_eq!(old.images, model.images);
    let reg = register_frame(&model, 1, &Solver::default(), Some(&Ransac::default())).unwrap();
    let back: FrameRegistration = round_trip(&reg);
    assert_eq!(back.solution, reg.solution);
    assert_eq!(back.image_ids, reg.image_ids);
    assert_eq!(back.ransac, reg.ransac);
}
