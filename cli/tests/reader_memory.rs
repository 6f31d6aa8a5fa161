//! What reading costs: the peak memory of every reader (COLMAP text and binary, `eopnp solve`'s
//! CSV and JSON) measured by a counting global allocator, against the size of what it returns;
//! pathological inputs (a line of 50 million commas, an image with 10 million observations, a
//! count claiming 10^12 records, endless `/dev/zero`, a FIFO) refused quickly, with little
//! memory, by an error that names the limit hit.
//!
//! The measure: `peak` is the most bytes live at once during the call, above what was live
//! before it; `kept` is what is still live after it (the returned value). A reallocation that
//! moves counts the old and the new block as live together (the copy needs both), so a vector
//! that grows by doubling peaks at up to 3 times its final length (a block of 2^k elements
//! copied into one of 2^(k+1), then shrunk to fit).
//!
//! The bounds asserted (k = the multiple of `kept`, plus 1 MiB of buffers):
//! - COLMAP models, text or binary: `peak <= 1.5 * kept + 1 MiB`. Binary records are
//!   allocated at their exact size; text observations and tracks grow as they are read (their
//!   count is not known before the end of the line), so one image's observations may briefly
//!   take 3 times their size, a small part of a model of many images.
//! - `solve` problems, CSV or JSON: `peak <= 3 * kept + 1 MiB`: the two vectors of
//!   correspondences grow by doubling (the number of lines is not known in advance).
//! - Refusals: `peak <= 1 MiB` whatever the input's size, except an image over the
//!   observation limit (`ReadOptions::max_observations`, 1,000,000 by default), which costs up
//!   to 3 times the limit's 32 MB before it is refused.
//!
//! The tests run one at a time (a lock): the counter is global.

use std::alloc::{GlobalAlloc, Layout, System};
use std::io::{BufReader, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use eopnp::camera::{Camera, CameraModel};
use eopnp::colmap::{
    parse_model, read_model, write_model, Image, Limit, Model, ModelErrorKind, ModelFormat,
    Point3D, ReadOptions, WriteOptions,
};
use eopnp_cli::input::{read_problem, read_problem_from, Limits};
use nalgebra::{Point2, Point3, Vector3};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

fn grow(n: usize) {
    let live = LIVE.fetch_add(n, Ordering::SeqCst) + n;
    PEAK.fetch_max(live, Ordering::SeqCst);
}

fn shrink(n: usize) {
    LIVE.fetch_sub(n, Ordering::SeqCst);
}

// SAFETY: every call is forwarded to `System` unchanged; only sizes are counted.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc(layout);
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        let p = System.alloc_zeroed(layout);
        if !p.is_null() {
            grow(layout.size());
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        System.dealloc(ptr, layout);
        shrink(layout.size());
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let q = System.realloc(ptr, layout, new_size);
        if !q.is_null() {
            let old = layout.size();
            if q == ptr {
                if new_size >= old {
                    grow(new_size - old);
                } else {
                    shrink(old - new_size);
                }
            } else {
                // Moved: both blocks were live during the copy.
                grow(new_size);
                shrink(old);
            }
        }
        q
    }
}

#[global_allocator]
static COUNTING: Counting = Counting;

/// One test at a time: the counters are global.
static LOCK: Mutex<()> = Mutex::new(());

const MIB: usize = 1 << 20;

/// Runs `f`; returns its result, its peak (above what was live before) and what it kept.
fn measure<T>(f: impl FnOnce() -> T) -> (T, usize, usize) {
    let before = LIVE.load(Ordering::SeqCst);
    PEAK.store(before, Ordering::SeqCst);
    let r = f();
    let peak = PEAK.load(Ordering::SeqCst).saturating_sub(before);
    let kept = LIVE.load(Ordering::SeqCst).saturating_sub(before);
    (r, peak, kept)
}

fn scratch(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("reader-memory-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A model of `images` images with `obs` observations each (three quarters of them of one of
/// `points` 3D points) and tracks of the matching lengths.
fn model(images: u32, obs: usize, points: u64) -> Model {
    let mut m = Model::default();
    m.cameras.insert(
        1,
        Camera::new(
            CameraModel::SimpleRadial,
            1600,
            1200,
            vec![1245.65, 800.0, 600.0, 0.05],
        )
        .unwrap(),
    );
    let mut tracks: Vec<Vec<(u32, u32)>> = vec![Vec::new(); points as usize];
    let mut state = 12345u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        state >> 11
    };
    for id in 1..=images {
        let mut points2d = Vec::with_capacity(obs);
        for k in 0..obs {
            let px = Point2::new(
                (next() % 160_000) as f64 / 100.0,
                (next() % 120_000) as f64 / 100.0,
            );
            let pid = (k % 4 != 0).then(|| next() % points);
            if let Some(p) = pid {
                tracks[p as usize].push((id, k as u32));
            }
            points2d.push((px, pid));
        }
        m.images.insert(
            id,
            Image {
                id,
                q: [0.9, 0.1, -0.2, 0.3],
                t: Vector3::new(0.1, -0.2, 5.0),
                camera_id: 1,
                name: format!("image {id:05}.jpg"),
                points2d,
            },
        );
    }
    for (id, track) in tracks.into_iter().enumerate() {
        let f = id as f64;
        m.points.insert(
            id as u64,
            Point3D {
                id: id as u64,
                xyz: Point3::new(f.sin(), f.cos(), 3.0 + (f * 0.1).sin()),
                rgb: [200, 100, 50],
                error: 0.5,
                track,
            },
        );
    }
    m
}

fn dir_size(dir: &Path) -> u64 {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().metadata().unwrap().len())
        .sum()
}

#[test]
fn colmap_models_peak_within_1_5_times_the_model() {
    let _lock = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let m = model(200, 3000, 150_000);
    for format in [ModelFormat::Text, ModelFormat::Binary] {
        let dir = scratch(&format!("{format:?}"));
        let out = dir.join("model");
        write_model(&m, &out, &WriteOptions::default().format(format)).unwrap();
        let size = dir_size(&out);
        let (read, peak, kept) = measure(|| read_model(&out, &ReadOptions::default()).unwrap());
        assert_eq!(read, m);
        eprintln!(
            "{format:?} model: files {:.1} MB, kept {:.1} MB, peak {:.1} MB = {:.3} x kept",
            size as f64 / 1e6,
            kept as f64 / 1e6,
            peak as f64 / 1e6,
            peak as f64 / kept as f64
        );
        assert!(
            peak as f64 <= 1.5 * kept as f64 + MIB as f64,
            "{format:?}: peak {peak} for {kept} kept"
        );
        drop(read);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

/// A camera for the CSV problems.
const CAMERA: &str = "SIMPLE_RADIAL 1245.65 600 800 0.0577";

/// `n` correspondences as CSV, or as JSON.
fn problem_text(n: usize, json: bool) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    if json {
        s.push_str("{\"camera\": {\"model\": \"PINHOLE\", \"params\": [800, 800, 320, 240]},\n");
    } else {
        s.push_str("x,y,X,Y,Z\n");
    }
    let point = |k: usize| {
        let f = k as f64;
        (
            [
                320.0 + (f * 0.37).sin() * 300.0,
                240.0 + (f * 0.11).cos() * 200.0,
            ],
            [(f * 0.7).sin(), (f * 0.3).cos(), 5.0 + (f * 0.01).sin()],
        )
    };
    if json {
        s.push_str("\"points2d\": [");
        for k in 0..n {
            let (p, _) = point(k);
            let sep = if k + 1 < n { "," } else { "" };
            let _ = writeln!(s, "[{}, {}]{sep}", p[0], p[1]);
        }
        s.push_str("],\n\"points3d\": [");
        for k in 0..n {
            let (_, w) = point(k);
            let sep = if k + 1 < n { "," } else { "" };
            let _ = writeln!(s, "[{}, {}, {}]{sep}", w[0], w[1], w[2]);
        }
        s.push_str("]}\n");
    } else {
        for k in 0..n {
            let (p, w) = point(k);
            let _ = writeln!(s, "{},{},{},{},{}", p[0], p[1], w[0], w[1], w[2]);
        }
    }
    s
}

#[test]
fn solve_inputs_peak_within_3_times_the_problem() {
    let _lock = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("problems");
    let n = 1_000_000;
    for (json, name) in [(false, "big.csv"), (true, "big.json")] {
        let path = dir.join(name);
        std::fs::write(&path, problem_text(n, json)).unwrap();
        let size = std::fs::metadata(&path).unwrap().len();
        let camera = (!json).then_some(CAMERA);
        let (p, peak, kept) = measure(|| {
            read_problem(&path, None, camera, &Limits::default())
                .unwrap_or_else(|f| panic!("{}", f.message))
        });
        assert_eq!(p.correspondences(), n);
        eprintln!(
            "{name}: file {:.1} MB, kept {:.1} MB (40 B per correspondence), peak {:.1} MB = \
             {:.3} x kept",
            size as f64 / 1e6,
            kept as f64 / 1e6,
            peak as f64 / 1e6,
            peak as f64 / kept as f64
        );
        assert!(kept <= 40 * n + MIB, "{name}: kept {kept}");
        assert!(
            peak as f64 <= 3.0 * kept as f64 + MIB as f64,
            "{name}: peak {peak} for {kept} kept"
        );
        drop(p);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A reader of `n` bytes `b` after `head`, made on the fly (the test holds none of it).
fn generated(head: &str, b: u8, n: u64) -> impl std::io::BufRead {
    BufReader::new(std::io::Cursor::new(head.as_bytes().to_vec()).chain(std::io::repeat(b).take(n)))
}

/// `solve`'s parser on a generated input: the failure message, the peak and the time.
fn solve_refusal(
    input: impl std::io::BufRead,
    ext: Option<&str>,
    limits: &Limits,
) -> (String, usize, Duration) {
    let t = Instant::now();
    let (r, peak, _) = measure(|| read_problem_from("<stdin>", input, ext, Some(CAMERA), limits));
    let f = r.expect_err("refused");
    assert_eq!(f.code, 2, "{}", f.message);
    (f.message, peak, t.elapsed())
}

#[test]
fn pathological_solve_inputs_are_refused_with_little_memory() {
    let _lock = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let limits = Limits {
        max_input_bytes: u64::MAX,
        ..Limits::default()
    };
    // One line of 50 million commas (cost 833 MB when the line was parsed whole).
    let (m, peak, _) = solve_refusal(generated("x,y,X,Y,Z\n", b',', 50_000_000), None, &limits);
    assert_eq!(
        m,
        "<stdin>:2: line longer than 64 KiB, the line length limit of CSV input"
    );
    eprintln!("50 million commas: {m}; peak {} KiB", peak >> 10);
    assert!(peak <= MIB, "peak {peak}");
    // The same as the header.
    let (m, peak, _) = solve_refusal(generated("", b',', 50_000_000), Some("csv"), &limits);
    assert!(m.starts_with("<stdin>:1: expected the header"), "{m}");
    assert!(peak <= MIB, "peak {peak}");
    // Endless zeros on standard input (`solve - < /dev/zero`), as CSV and as JSON, and a
    // JSON string and number of 50 million characters.
    for (head, byte, ext, expected) in [
        ("", 0, None, "<stdin>:1: expected the header"),
        ("", 0, Some("json"), "<stdin>:1:1: expected value"),
        (
            "{\"camera\": \"",
            b'a',
            Some("json"),
            "<stdin>:1: a string or number longer than 64 KiB, the limit of JSON input",
        ),
    ] {
        let (m, peak, time) = solve_refusal(generated(head, byte, u64::MAX), ext, &limits);
        assert!(m.starts_with(expected), "{m}");
        assert!(peak <= MIB, "{m}: peak {peak}");
        assert!(time < Duration::from_secs(2), "{m}: {time:?}");
    }
    let (m, peak, _) = solve_refusal(
        generated("{\"points2d\": [[1", b'1', 50_000_000),
        Some("json"),
        &limits,
    );
    assert!(m.contains("a string or number longer than 64 KiB"), "{m}");
    assert!(peak <= MIB, "peak {peak}");
    // Valid lines past the size limit: refused at the limit, which the message names.
    let small = Limits {
        max_input_bytes: 1 << 20,
        ..Limits::default()
    };
    let (m, peak, _) = solve_refusal(
        generated("x,y,X,Y,Z\n", b'\n', 1 << 30),
        Some("csv"),
        &small,
    );
    assert_eq!(
        m,
        "<stdin>: larger than 1 MiB, the input size limit of `eopnp solve` (--max-input-size)"
    );
    assert!(peak <= MIB, "peak {peak}");
}

#[test]
fn pathological_models_are_refused_with_little_memory() {
    let _lock = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let cameras = b"1 SIMPLE_PINHOLE 640 480 500 320 240\n".as_slice();
    let header = "1 1 0 0 0 0 0 5 1 a.png\n";
    let limits = ReadOptions::default();
    let text = |images: &[u8], limits: &ReadOptions| {
        measure(|| parse_model(ModelFormat::Text, [cameras, images, b""], limits))
    };
    // One image with 10 million observations (cost 856 MB when read whole): refused at the
    // observation limit, having held at most 3 times its 32 MB.
    let images = format!("{header}{}\n", "0 0 -1 ".repeat(10_000_000));
    let (r, peak, _) = text(images.as_bytes(), &limits);
    let e = r.unwrap_err();
    assert_eq!(
        e.kind,
        ModelErrorKind::Limit(Limit::Observations(1_000_000))
    );
    eprintln!(
        "10 million observations ({} MB): {e}; peak {:.1} MB",
        images.len() / 1_000_000,
        peak as f64 / 1e6
    );
    assert!(peak <= 3 * 32 * 1_000_000 + MIB, "peak {peak}");
    // With a lower limit, less.
    let (r, peak, _) = text(images.as_bytes(), &limits.max_observations(10_000));
    assert_eq!(
        r.unwrap_err().kind,
        ModelErrorKind::Limit(Limit::Observations(10_000))
    );
    assert!(peak <= MIB, "peak {peak}");
    drop(images);
    // With a higher one, 4 million are read: 32 bytes per observation kept.
    let images = format!("{header}{}\n", "0 0 -1 ".repeat(4_000_000));
    let (r, peak, kept) = text(images.as_bytes(), &limits.max_observations(4_000_000));
    let m = r.unwrap();
    assert_eq!(m.images[&1].points2d.len(), 4_000_000);
    eprintln!(
        "4 million observations read: kept {:.1} MB, peak {:.1} MB = {:.3} x kept",
        kept as f64 / 1e6,
        peak as f64 / 1e6,
        peak as f64 / kept as f64
    );
    assert!(peak as f64 <= 3.0 * kept as f64 + MIB as f64);
    drop(m);
    drop(images);
    // One line of 50 million commas (then a space), in each file.
    let commas = format!("{} 1\n", ",".repeat(50_000_000));
    for k in 0..3 {
        let mut files = [cameras, header.as_bytes(), b"".as_slice()];
        files[k] = commas.as_bytes();
        let (r, peak, _) = measure(|| parse_model(ModelFormat::Text, files, &limits));
        let e = r.unwrap_err();
        assert_eq!(
            e.kind,
            ModelErrorKind::Limit(Limit::FieldBytes(1 << 16)),
            "{e}"
        );
        assert!(peak <= MIB, "{e}: peak {peak}");
    }
    // A track of 10 million elements.
    let points = format!("1 0 0 0 1 2 3 0.5{}\n", " 1 0".repeat(10_000_000));
    let (r, peak, _) = measure(|| {
        parse_model(
            ModelFormat::Text,
            [cameras, header.as_bytes(), points.as_bytes()],
            &limits,
        )
    });
    let e = r.unwrap_err();
    assert_eq!(e.kind, ModelErrorKind::Limit(Limit::TrackLength(1_000_000)));
    assert!(peak <= 3 * 8 * 1_000_000 + MIB, "peak {peak}");
    drop(points);
    // Binary counts claiming 10^12 records, or 2^64 - 1.
    for count in [1_000_000_000_000u64, u64::MAX] {
        let mut b = count.to_le_bytes().to_vec();
        b.extend_from_slice(&[0; 100]);
        for k in 0..3 {
            let mut files = [&[0u8; 8][..], &[0u8; 8][..], &[0u8; 8][..]];
            files[k] = &b;
            let (r, peak, _) = measure(|| parse_model(ModelFormat::Binary, files, &limits));
            let e = r.unwrap_err();
            assert_eq!(e.kind, ModelErrorKind::Invalid, "{e}");
            assert!(e.reason.contains("remain"), "{e}");
            assert!(peak <= 1 << 16, "{e}: peak {peak}");
        }
    }
    // A binary image claiming 2 million observations, present: over the observation limit.
    let mut images = 1u64.to_le_bytes().to_vec();
    images.extend_from_slice(&1u32.to_le_bytes());
    for v in [1.0f64, 0.0, 0.0, 0.0, 0.0, 0.0, 5.0] {
        images.extend_from_slice(&v.to_le_bytes());
    }
    images.extend_from_slice(&1u32.to_le_bytes());
    images.extend_from_slice(b"a.png\0");
    images.extend_from_slice(&2_000_000u64.to_le_bytes());
    images.resize(images.len() + 24 * 2_000_000, 0);
    let cams = eopnp::colmap::encode_model(
        &parse_model(ModelFormat::Text, [cameras, b"", b""], &limits).unwrap(),
        ModelFormat::Binary,
    )
    .unwrap();
    let (r, peak, _) =
        measure(|| parse_model(ModelFormat::Binary, [&cams[0], &images, &cams[2]], &limits));
    let e = r.unwrap_err();
    assert_eq!(
        e.kind,
        ModelErrorKind::Limit(Limit::Observations(1_000_000))
    );
    assert!(e.to_string().contains("image 1"), "{e}");
    assert!(peak <= 1 << 16, "peak {peak}");
}

/// `path` made a symbolic link to `target`.
#[cfg(unix)]
fn link(target: &str, path: &Path) {
    let _ = std::fs::remove_file(path);
    std::os::unix::fs::symlink(target, path).unwrap();
}

/// Runs `f` in a thread, failing the test if it takes longer than 5 seconds (a reader that
/// opened a FIFO would block forever).
#[cfg(unix)]
fn within_5s<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(f());
    });
    rx.recv_timeout(Duration::from_secs(5))
        .expect("refused within 5 seconds")
}

#[cfg(unix)]
#[test]
fn special_files_are_refused_before_they_are_opened() {
    let _lock = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("special");
    let fifo = dir.join("fifo.csv");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success());
    let mut inputs = vec![PathBuf::from("/dev/zero"), dir.clone()];
    if made {
        inputs.push(fifo.clone());
    }
    for input in inputs {
        let shown = input.display().to_string();
        let (f, peak) = within_5s(move || {
            let (r, peak, _) =
                measure(|| read_problem(&input, None, Some(CAMERA), &Limits::default()));
            (r.expect_err("refused"), peak)
        });
        assert_eq!(f.code, 2);
        assert!(peak <= 1 << 16, "{}: peak {peak}", f.message);
        assert!(
            f.message
                .starts_with(&format!("{shown}: not a regular file (it is ")),
            "{}",
            f.message
        );
        assert!(
            f.message.contains("`-` for standard input"),
            "{}",
            f.message
        );
    }
    // A model whose cameras file is /dev/zero, a FIFO, a directory.
    let model = dir.join("model");
    std::fs::create_dir_all(&model).unwrap();
    for f in ["images.txt", "points3D.txt"] {
        std::fs::write(model.join(f), "").unwrap();
    }
    let cameras = model.join("cameras.txt");
    let mut specials = vec![("/dev/zero", "a character device")];
    if made {
        specials.push((fifo.to_str().unwrap(), "a named pipe (FIFO)"));
    }
    specials.push((dir.to_str().unwrap(), "a directory"));
    for (target, what) in specials {
        link(target, &cameras);
        let m = model.clone();
        let (e, peak) = within_5s(move || {
            let (r, peak, _) = measure(|| read_model(&m, &ReadOptions::default()));
            (r.unwrap_err(), peak)
        });
        assert_eq!(e.kind, ModelErrorKind::NotRegularFile, "{e}");
        assert!(peak <= 1 << 16, "{e}: peak {peak}");
        assert_eq!(e.file, cameras);
        assert_eq!(
            e.reason,
            format!("not a regular file (it is {what}); a model file must be a regular file")
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn oversized_files_are_refused_before_they_are_read() {
    let _lock = LOCK.lock().unwrap_or_else(|e| e.into_inner());
    let dir = scratch("oversized");
    // A 2 GB sparse file (cost 2 GB before its header was rejected): over `solve`'s default
    // limit, refused before reading; without the limit, refused at its first line.
    let sparse = dir.join("sparse.csv");
    std::fs::File::create(&sparse)
        .unwrap()
        .set_len(2 << 30)
        .unwrap();
    let (r, peak, _) = measure(|| read_problem(&sparse, None, Some(CAMERA), &Limits::default()));
    let m = r.err().unwrap().message;
    assert_eq!(
        m,
        format!(
            "{}: larger than 1 GiB, the input size limit of `eopnp solve` (--max-input-size)",
            sparse.display()
        )
    );
    assert!(peak <= MIB, "peak {peak}");
    let no_limit = Limits {
        max_input_bytes: u64::MAX,
        ..Limits::default()
    };
    let t = Instant::now();
    let (r, peak, _) = measure(|| read_problem(&sparse, None, Some(CAMERA), &no_limit));
    let m = r.err().unwrap().message;
    assert!(m.contains(":1: expected the header"), "{m}");
    assert!(peak <= MIB, "peak {peak}");
    assert!(t.elapsed() < Duration::from_secs(2));
    // The same as a model's cameras file, text and binary.
    for (names, expected) in [
        (
            ["cameras.txt", "images.txt", "points3D.txt"],
            "longer than 64 KiB",
        ),
        (
            ["cameras.bin", "images.bin", "points3D.bin"],
            "unexpected trailing bytes",
        ),
    ] {
        let model = dir.join(names[0]);
        std::fs::create_dir_all(&model).unwrap();
        std::fs::File::create(model.join(names[0]))
            .unwrap()
            .set_len(2 << 30)
            .unwrap();
        let empty: &[u8] = if names[1].ends_with("bin") {
            &[0; 8]
        } else {
            b""
        };
        for f in &names[1..] {
            std::fs::File::create(model.join(f))
                .unwrap()
                .write_all(empty)
                .unwrap();
        }
        let t = Instant::now();
        let (r, peak, _) = measure(|| read_model(&model, &ReadOptions::default()));
        let e = r.unwrap_err();
        assert!(e.to_string().contains(expected), "{e}");
        assert!(peak <= MIB, "{e}: peak {peak}");
        assert!(t.elapsed() < Duration::from_secs(2));
        // And over a size limit, before reading.
        let limits = ReadOptions::default().max_file_bytes(1 << 30);
        let e = read_model(&model, &limits).unwrap_err();
        assert_eq!(e.kind, ModelErrorKind::Limit(Limit::FileBytes(1 << 30)));
        assert_eq!(
            e.to_string(),
            format!(
                "{}: the file is {} bytes long: over the file size limit of 1 GiB \
                 (ReadOptions::max_file_bytes)",
                model.join(names[0]).display(),
                2u64 << 30
            )
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
