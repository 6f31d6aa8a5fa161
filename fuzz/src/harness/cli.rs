//! The `cli_input` target: the command line's problem-file parser and its pose output.

use eopnp::Solver;

/// The CLI's problem-file parser (CSV or JSON) and its pose output. The first byte picks the
/// extension and whether a `--camera` argument (the first line) is given.
///
/// Properties: a parse failure is an input error (exit code 2) with a message that shows no raw
/// control character, whatever the input mode (CSV, JSON, `--camera`: what it echoes of the
/// input is escaped); a parsed
/// problem solves or fails with code 1 or 2, and a pose is JSON with a translation. The seeds cover the CSV dialects the csv crate reads
/// (byte-order mark, quotes, `;` and tab, reordered columns, comments).
pub fn cli_input(data: &[u8]) {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let ext = match mode & 3 {
        0 => Some("json"),
        1 => Some("csv"),
        2 => Some("txt"),
        _ => None,
    };
    let (camera, body) = if mode & 4 != 0 {
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        let cam = std::str::from_utf8(&rest[..end]).ok();
        (cam, rest.get(end + 1..).unwrap_or(&[]))
    } else {
        (None, rest)
    };
    let whole = eopnp_cli::input::parse_problem("fuzz", body, ext, camera);
    check_problem_reading(body, ext, camera, &whole);
    match whole {
        Ok(problem) => match eopnp_cli::solve::solve(&problem, &Solver::default()) {
            Ok(json) => {
                let v: serde_json::Value = serde_json::from_str(&json).expect("output is JSON");
                assert!(v["translation"].is_array(), "pose JSON without translation");
            }
            Err(f) => {
                assert!(!f.message.is_empty());
                assert!(f.code == 1 || f.code == 2, "exit code {}", f.code);
            }
        },
        Err(f) => {
            assert!(!f.message.is_empty());
            assert_eq!(f.code, 2, "a parse failure is bad input (exit code 2)");
            // Every input mode (CSV, JSON, no or another extension, the `--camera` argument):
            // what the message echoes of the input is escaped.
            assert!(
                !f.message.chars().any(char::is_control),
                "raw control character in the error of a {} input{}: {:?}",
                ext.unwrap_or("extensionless"),
                if camera.is_some() {
                    " with --camera"
                } else {
                    ""
                },
                f.message
            );
        }
    }
}

/// Limits small enough for fuzzed inputs to reach: 1 KiB of input, lines (and JSON strings
/// and numbers) of 48 bytes.
pub fn small_input_limits() -> eopnp_cli::input::Limits {
    eopnp_cli::input::Limits {
        max_input_bytes: 1024,
        max_line_bytes: 48,
    }
}

/// The streaming properties of `solve`'s reader on one input (`whole`: its result read from
/// the slice with the default limits):
/// - read through a buffer of 1 to 7 bytes (a stream that delivers little at a time: a
///   byte-order mark, lines, tokens cut anywhere), the result is the same;
/// - with [`small_input_limits`], a problem that is read is the same, and one that is
///   refused although it reads with the default limits is refused for a limit, which the
///   message names.
fn check_problem_reading(
    body: &[u8],
    ext: Option<&str>,
    camera: Option<&str>,
    whole: &Result<eopnp_cli::input::Problem, eopnp_cli::Failure>,
) {
    use eopnp_cli::input::{read_problem_from, Limits};
    let capacity = 1 + body.len() % 7;
    let src = || std::io::BufReader::with_capacity(capacity, body);
    let buffered = read_problem_from("fuzz", src(), ext, camera, &Limits::default());
    match (whole, &buffered) {
        (Ok(a), Ok(b)) => assert_eq!(a, b, "buffered through {capacity} bytes"),
        (Err(a), Err(b)) => assert_eq!(
            (a.code, &a.message),
            (b.code, &b.message),
            "buffered through {capacity} bytes"
        ),
        (a, b) => panic!(
            "buffered through {capacity} bytes: {:?}, whole: {:?}",
            b.as_ref().map_err(|f| &f.message),
            a.as_ref().map_err(|f| &f.message)
        ),
    }
    match (
        whole,
        read_problem_from("fuzz", src(), ext, camera, &small_input_limits()),
    ) {
        (Ok(a), Ok(b)) => assert_eq!(*a, b, "limited"),
        (Ok(_), Err(f)) => {
            assert_eq!(f.code, 2, "{}", f.message);
            assert!(f.message.contains("limit"), "limited: {}", f.message);
        }
        (Err(a), Ok(_)) => panic!("bad input read under smaller limits: {}", a.message),
        (Err(_), Err(f)) => assert_eq!(f.code, 2, "{}", f.message),
    }
}
