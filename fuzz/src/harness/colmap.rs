//! The COLMAP targets: the text and binary readers (`colmap_text`, `colmap_binary`) and the
//! writer (`colmap_write`).

use eopnp::ransac::Ransac;
use eopnp::Solver;

use super::solve::check_solution;

/// Splits the input into three files at the first two occurrences of the separator byte
/// sequence `\0\0\xff`.
fn three_files(data: &[u8]) -> [&[u8]; 3] {
    const SEP: &[u8] = b"\0\0\xff";
    let mut parts = [&data[..0]; 3];
    let mut rest = data;
    for (k, part) in parts.iter_mut().enumerate() {
        if k == 2 {
            *part = rest;
            break;
        }
        match rest.windows(SEP.len()).position(|w| w == SEP) {
            Some(at) => {
                *part = &rest[..at];
                rest = &rest[at + SEP.len()..];
            }
            None => {
                *part = rest;
                rest = &rest[rest.len()..];
            }
        }
    }
    parts
}

/// Registers (at most three of) the images of a parsed model, plain and with RANSAC.
fn exercise_model(model: &eopnp::colmap::Model) {
    let solver = Solver::default();
    let ransac = Ransac::default().seed(1).max_iterations(50);
    for &id in model.images.keys().take(3) {
        if let Ok(reg) = eopnp::colmap::register_image(model, id, &solver, None) {
            check_solution(&reg.solution);
        }
        if let Ok(reg) = eopnp::colmap::register_image(model, id, &solver, Some(&ransac)) {
            check_solution(&reg.solution);
            assert!(reg.ransac.is_some() && reg.inliers <= reg.n);
        }
    }
}

/// The COLMAP text reader (three files separated by `\0\0\xff`), then registration; and the
/// reading properties of [`check_model_reading`].
pub fn colmap_text(data: &[u8]) {
    let [c, i, p] = three_files(data);
    let whole = eopnp::colmap::parse_model(
        eopnp::colmap::ModelFormat::Text,
        [c, i, p],
        &eopnp::colmap::ReadOptions::default(),
    );
    check_model_reading(eopnp::colmap::ModelFormat::Text, [c, i, p], &whole);
    match whole {
        Ok(model) => exercise_model(&model),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

/// The COLMAP binary reader (three files separated by `\0\0\xff`), then registration; and
/// the reading properties of [`check_model_reading`].
pub fn colmap_binary(data: &[u8]) {
    let [c, i, p] = three_files(data);
    let whole = eopnp::colmap::parse_model(
        eopnp::colmap::ModelFormat::Binary,
        [c, i, p],
        &eopnp::colmap::ReadOptions::default(),
    );
    check_model_reading(eopnp::colmap::ModelFormat::Binary, [c, i, p], &whole);
    match whole {
        Ok(model) => exercise_model(&model),
        Err(e) => assert!(!e.to_string().is_empty()),
    }
}

/// Limits small enough for fuzzed inputs to reach: 2 KiB files, 8 observations per image, 8
/// track elements per point.
const SMALL_FILE_BYTES: u64 = 2048;
const SMALL_OBSERVATIONS: usize = 8;
const SMALL_TRACK_LENGTH: usize = 8;

/// The reader options of [`SMALL_FILE_BYTES`], [`SMALL_OBSERVATIONS`] and
/// [`SMALL_TRACK_LENGTH`].
pub fn small_model_limits() -> eopnp::colmap::ReadOptions {
    eopnp::colmap::ReadOptions::default()
        .max_file_bytes(SMALL_FILE_BYTES)
        .max_observations(SMALL_OBSERVATIONS)
        .max_track_length(SMALL_TRACK_LENGTH)
}

/// The streaming readers' properties on one input (`whole`: its result with the default
/// limits):
/// - read through a buffer of 1 to 13 bytes (tokens, names and records cut anywhere), the
///   result is the same;
/// - with [`small_model_limits`], a model within them reads the same, one beyond them fails
///   with an error of kind `Limit`, and input that fails still fails.
fn check_model_reading(
    format: eopnp::colmap::ModelFormat,
    files: [&[u8]; 3],
    whole: &Result<eopnp::colmap::Model, eopnp::colmap::ModelError>,
) {
    use eopnp::colmap::{parse_model, parse_model_buffered, ModelErrorKind};
    let len: usize = files.iter().map(|f| f.len()).sum();
    let capacity = 1 + len % 13;
    let buffered = parse_model_buffered(format, files, &Default::default(), capacity);
    match (whole, &buffered) {
        (Ok(a), Ok(b)) => assert_same_model(a, b, "buffered"),
        (Err(a), Err(b)) => assert_eq!(a, b, "buffered through {capacity} bytes"),
        (a, b) => panic!("buffered through {capacity} bytes: {b:?}, whole: {a:?}"),
    }
    let small = small_model_limits();
    let limited = parse_model(format, files, &small);
    match (whole, limited) {
        (Ok(a), Ok(b)) => assert_same_model(a, &b, "limited"),
        (Ok(m), Err(e)) => {
            assert!(matches!(e.kind, ModelErrorKind::Limit(_)), "{e}");
            let within = files.iter().all(|f| f.len() as u64 <= SMALL_FILE_BYTES)
                && m.images
                    .values()
                    .all(|i| i.points2d.len() <= SMALL_OBSERVATIONS)
                && m.points
                    .values()
                    .all(|p| p.track.len() <= SMALL_TRACK_LENGTH);
            assert!(!within, "a model within the limits is refused: {e}");
        }
        (Err(e), Ok(_)) => panic!("bad input read under smaller limits: {e}"),
        (Err(_), Err(_)) => {}
    }
}

/// Whether two `f64` are the same value bit for bit (`-0.0` differs from `0.0`), any NaN
/// matching any NaN (text prints every NaN as `NaN`).
fn same_f64(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn same_f64s<'a>(
    a: impl IntoIterator<Item = &'a f64>,
    b: impl IntoIterator<Item = &'a f64>,
) -> bool {
    let (a, b): (Vec<f64>, Vec<f64>) = (
        a.into_iter().copied().collect(),
        b.into_iter().copied().collect(),
    );
    a.len() == b.len() && a.iter().zip(&b).all(|(x, y)| same_f64(*x, *y))
}

/// Asserts that two models are identical, every number bit for bit (NaN for NaN).
pub fn assert_same_model(a: &eopnp::colmap::Model, b: &eopnp::colmap::Model, what: &str) {
    assert_eq!(a.cameras.len(), b.cameras.len(), "{what}: cameras");
    for ((ia, ca), (ib, cb)) in a.cameras.iter().zip(&b.cameras) {
        assert_eq!(ia, ib, "{what}: camera ids");
        assert_eq!(
            (ca.model(), ca.width(), ca.height()),
            (cb.model(), cb.width(), cb.height()),
            "{what}: camera {ia}"
        );
        assert!(
            same_f64s(ca.params(), cb.params()),
            "{what}: camera {ia} params"
        );
    }
    assert_eq!(a.images.len(), b.images.len(), "{what}: images");
    for ((ka, ia), (kb, ib)) in a.images.iter().zip(&b.images) {
        assert_eq!(
            (ka, ia.id, ia.camera_id, &ia.name),
            (kb, ib.id, ib.camera_id, &ib.name),
            "{what}"
        );
        assert!(same_f64s(&ia.q, &ib.q), "{what}: image {ka} q");
        assert!(same_f64s(ia.t.iter(), ib.t.iter()), "{what}: image {ka} t");
        assert_eq!(
            ia.points2d.len(),
            ib.points2d.len(),
            "{what}: image {ka} observations"
        );
        for ((pa, ida), (pb, idb)) in ia.points2d.iter().zip(&ib.points2d) {
            assert_eq!(ida, idb, "{what}: image {ka} observation point id");
            assert!(same_f64s(pa.iter(), pb.iter()), "{what}: image {ka} pixel");
        }
    }
    assert_eq!(a.points.len(), b.points.len(), "{what}: points");
    for ((ka, pa), (kb, pb)) in a.points.iter().zip(&b.points) {
        assert_eq!(
            (ka, pa.id, pa.rgb, &pa.track),
            (kb, pb.id, pb.rgb, &pb.track),
            "{what}"
        );
        assert!(
            same_f64s(pa.xyz.iter(), pb.xyz.iter()),
            "{what}: point {ka} xyz"
        );
        assert!(same_f64(pa.error, pb.error), "{what}: point {ka} error");
    }
}

fn parse_as(
    format: eopnp::colmap::ModelFormat,
    [c, i, p]: [&[u8]; 3],
) -> Result<eopnp::colmap::Model, eopnp::colmap::ModelError> {
    eopnp::colmap::parse_model(format, [c, i, p], &eopnp::colmap::ReadOptions::default())
}

/// A fresh scratch directory of this process (removed by the caller).
fn scratch_dir() -> std::path::PathBuf {
    use std::sync::atomic::{AtomicU64, Ordering};
    static N: AtomicU64 = AtomicU64::new(0);
    let d = std::env::temp_dir().join(format!(
        "eopnp-fuzz-colmap-write-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch directory");
    d
}

fn sorted_entries(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("list directory")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The COLMAP writer: the input (three files separated by `\0\0\xff`) is parsed as a text
/// and as a binary model; each model that parses is encoded in both formats and parsed back,
/// and written to a fresh directory with `colmap::write_model` and read back. Properties:
/// - a model always writes in the format it was read from; in the other format the only
///   failure is `InvalidInput` (a name text cannot hold, a 3D point id binary cannot hold);
/// - what is written reads back identical, every number bit for bit (NaN for NaN), and
///   encoding the model read back gives the same bytes;
/// - the directory written holds exactly the three files (no temporaries left).
pub fn colmap_write(data: &[u8]) {
    use eopnp::colmap::{
        encode_model, read_model, write_model, ModelFormat, ReadOptions, WriteOptions,
    };
    let files = three_files(data);
    for source in [ModelFormat::Text, ModelFormat::Binary] {
        let Ok(model) = parse_as(source, files) else {
            continue;
        };
        for format in [ModelFormat::Text, ModelFormat::Binary] {
            let what = format!("{source:?} -> {format:?}");
            let encoded = match encode_model(&model, format) {
                Ok(e) => e,
                Err(e) => {
                    assert_ne!(
                        source, format,
                        "{what}: a parsed model writes in its own format: {e}"
                    );
                    assert_eq!(e.kind(), std::io::ErrorKind::InvalidInput, "{what}: {e}");
                    assert!(!e.to_string().is_empty());
                    continue;
                }
            };
            let [c, i, p] = &encoded;
            let back = parse_as(format, [c, i, p])
                .unwrap_or_else(|e| panic!("{what}: written model does not parse: {e}"));
            assert_same_model(&model, &back, &what);
            let again = encode_model(&back, format).expect("re-encode");
            assert!(again == encoded, "{what}: re-encoding differs");

            let base = scratch_dir();
            let dir = base.join("model");
            write_model(&model, &dir, &WriteOptions::default().format(format))
                .unwrap_or_else(|e| panic!("{what}: write: {e}"));
            assert_eq!(sorted_entries(&base), ["model"], "{what}: leftovers");
            let mut names = format.file_names().map(String::from).to_vec();
            names.sort();
            assert_eq!(sorted_entries(&dir), names, "{what}: files written");
            let read = read_model(&dir, &ReadOptions::default().format(format));
            let _ = std::fs::remove_dir_all(&base);
            assert_same_model(
                &model,
                &read.unwrap_or_else(|e| panic!("{what}: read back: {e}")),
                &what,
            );
        }
    }
}
