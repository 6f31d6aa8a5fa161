//! Test fixtures shared by unit tests, read from `tests/data/`: the problems of
//! `test_vectors.json` (the reference prototype's test vectors) with the intermediates it
//! stored, and the prototype's `newton` minima (`reference_newton.json`).

use nalgebra::{Matrix3, Point2, Point3, SMatrix, Vector3};
use serde_json::Value;

/// One problem of `test_vectors.json` and its stored working-frame intermediates.
pub(crate) struct Vector {
    pub world: Vec<Point3<f64>>,
    pub image: Vec<Point2<f64>>,
    pub c: Vector3<f64>,
    pub d: f64,
    pub rw: Matrix3<f64>,
    pub ratio: f64,
    pub m: SMatrix<f64, 9, 9>,
    pub g: SMatrix<f64, 3, 9>,
}

/// The numbers of a (nested) JSON array, row-major.
pub(crate) fn numbers(v: &Value) -> Vec<f64> {
    match v {
        Value::Array(a) => a.iter().flat_map(numbers).collect(),
        x => vec![x.as_f64().expect("a number")],
    }
}

fn parse(text: &str) -> Value {
    serde_json::from_str(text).expect("valid JSON")
}

/// The problem `name` of `tests/data/test_vectors.json`.
pub(crate) fn vector(name: &str) -> Vector {
    let all = parse(include_str!("../data/test_vectors.json"));
    let v = all
        .as_array()
        .unwrap()
        .iter()
        .find(|v| v["name"] == name)
        .expect("a problem of that name");
    let i = &v["intermediate"];
    let pw = numbers(&v["P_world"]);
    let uv = numbers(&v["uv"]);
    Vector {
        world: pw
            .chunks(3)
            .map(|p| Point3::new(p[0], p[1], p[2]))
            .collect(),
        image: uv.chunks(2).map(|p| Point2::new(p[0], p[1])).collect(),
        c: Vector3::from_row_slice(&numbers(&i["c"])),
        d: i["d"].as_f64().unwrap(),
        rw: Matrix3::from_row_slice(&numbers(&i["Rw"])),
        ratio: i["ratio"].as_f64().unwrap(),
        m: SMatrix::from_row_slice(&numbers(&i["M"])),
        g: SMatrix::from_row_slice(&numbers(&i["G"])),
    }
}

/// The names of every problem of `tests/data/test_vectors.json`.
pub(crate) fn vector_names() -> Vec<String> {
    let all = parse(include_str!("../data/test_vectors.json"));
    all.as_array()
        .unwrap()
        .iter()
        .map(|v| v["name"].as_str().unwrap().to_string())
        .collect()
}

/// `tests/data/reference_newton.json`.
pub(crate) fn newton_reference() -> Value {
    parse(include_str!("../data/reference_newton.json"))
}
