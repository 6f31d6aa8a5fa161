//! Replays `solve` inputs and prints how many reached the exact-pose assertion:
//! `cargo run --release --example exact_share -- corpus/solve [seeds/solve ...]` (in `fuzz/`;
//! stable Rust is enough). Every input is also checked against all the other properties of
//! the `solve` target (a failing input panics with its file name).
//!
//! The same count over the committed seeds and corpus is asserted by the test
//! `exact_pose_check_runs_on_most_solve_inputs` in `tests/fuzz_corpus.rs`.

fn main() {
    let dirs: Vec<String> = std::env::args().skip(1).collect();
    assert!(!dirs.is_empty(), "usage: exact_share DIR [DIR ...]");
    let (mut n, mut decoded, mut derived, mut either) = (0usize, 0usize, 0usize, 0usize);
    for dir in &dirs {
        let mut files: Vec<_> = std::fs::read_dir(dir)
            .unwrap_or_else(|e| panic!("{dir}: {e}"))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .collect();
        files.sort();
        for f in files {
            let Ok(data) = std::fs::read(&f) else {
                continue;
            };
            let r = std::panic::catch_unwind(|| eopnp_fuzz::solve_report(&data))
                .unwrap_or_else(|_| panic!("{} fails", f.display()));
            n += 1;
            decoded += usize::from(r.exact_decoded);
            derived += usize::from(r.exact_derived);
            either += usize::from(r.exact_decoded || r.exact_derived);
        }
    }
    let pct = |k: usize| 100.0 * k as f64 / n.max(1) as f64;
    println!("{n} inputs");
    println!(
        "exact-pose assertion ran on {either} ({:.1} %): decoded problem {decoded} ({:.1} %), \
         derived problem {derived} ({:.1} %)",
        pct(either),
        pct(decoded),
        pct(derived)
    );
}
