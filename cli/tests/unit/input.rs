use super::*;
use crate::solve::solve;
use eopnp::Solver;

fn csv_error(body: &str) -> String {
    let text = format!("x,y,X,Y,Z\n{body}\n");
    match parse_problem(
        "p.csv",
        text.as_bytes(),
        Some("csv"),
        Some("PINHOLE 800 800 320 240"),
    ) {
        Err(f) => {
            assert_eq!(f.code, 2);
            f.message
        }
        Ok(_) => panic!("{body}: accepted"),
    }
}

#[test]
fn csv_field_errors_say_which_field_and_why() {
    let m = csv_error("1,2,abc,4,5");
    assert_eq!(m, "p.csv:2: field 3 (X) is not a number: `abc`");
    let m = csv_error("1,2\u{1},3,4,5");
    assert_eq!(m, "p.csv:2: field 2 (y) is not a number: `2\\u{1}`");
    let m = csv_error("1,2,3,inf,5");
    assert!(m.starts_with("p.csv:2: field 4 (Y) is not finite"), "{m}");
    let m = csv_error("1,2,3,4,1e400");
    assert!(m.starts_with("p.csv:2: field 5 (Z) is not finite"), "{m}");
}

#[test]
fn unusable_pixels_name_the_correspondence() {
    let text = "x,y,X,Y,Z\n1e300,2,0,0,1\n3,4,1,0,1\n5,6,0,1,1\n7,8,1,1,2\n";
    let p = parse_problem(
        "p.csv",
        text.as_bytes(),
        None,
        Some("PINHOLE 1e-10 1e-10 5 5"),
    )
    .unwrap();
    let f = solve(&p, &Solver::default()).unwrap_err();
    assert_eq!(f.code, 2);
    assert!(
        f.message
            .starts_with("correspondence 1: pixel (1e300, 2.0)"),
        "{}",
        f.message
    );
}

/// Eight points of a PINHOLE 800 800 320 240 camera at distance ~6, as (pixel, world).
fn points() -> Vec<([f64; 2], [f64; 3])> {
    let world = [
        [0.1, -0.4, 0.3],
        [-0.7, 0.2, -0.5],
        [0.9, 0.8, 0.1],
        [-0.3, -0.9, 0.6],
        [0.5, 0.1, -0.8],
        [-0.6, 0.7, 0.9],
        [0.2, -0.2, -0.1],
        [0.8, -0.6, 0.4],
    ];
    world
        .iter()
        .map(|&[x, y, z]| {
            let zc = z + 6.0;
            ([800.0 * x / zc + 320.0, 800.0 * y / zc + 240.0], [x, y, z])
        })
        .collect()
}

const CAMERA: &str = "PINHOLE 800 800 320 240";

/// CSV text of `points()` with the columns in `order` (indices into x, y, X, Y, Z), the
/// delimiter `d` and every field wrapped in `q` (`""` or `"\""`).
fn csv_text(order: [usize; 5], d: &str, q: &str) -> String {
    let names = ["x", "y", "X", "Y", "Z"];
    let row = |v: [String; 5]| {
        order
            .iter()
            .map(|&k| format!("{q}{}{q}", v[k]))
            .collect::<Vec<_>>()
            .join(d)
            + "\n"
    };
    let mut s = row(names.map(String::from));
    for (p, w) in points() {
        s += &row([p[0], p[1], w[0], w[1], w[2]].map(|v| v.to_string()));
    }
    s
}

fn parse_csv(text: &str) -> Result<Problem, Failure> {
    parse_problem("p.csv", text.as_bytes(), Some("csv"), Some(CAMERA))
}

/// Parses `text` and checks it gives `points()` in order.
fn assert_points(text: &str) {
    let p = parse_csv(text).unwrap_or_else(|f| panic!("{}\n{text}", f.message));
    let expected = points();
    assert_eq!(p.pixels.len(), expected.len(), "{text}");
    for ((px, w), (e_px, e_w)) in p.pixels.iter().zip(&p.world).zip(expected) {
        assert_eq!([px.x, px.y], e_px, "{text}");
        assert_eq!([w.x, w.y, w.z], e_w, "{text}");
    }
}

fn csv_failure(text: &str) -> String {
    match parse_csv(text) {
        Err(f) => {
            assert_eq!(f.code, 2, "{}", f.message);
            f.message
        }
        Ok(_) => panic!("accepted: {text}"),
    }
}

#[test]
fn csv_dialects_parse_to_the_same_points() {
    let plain = csv_text([0, 1, 2, 3, 4], ",", "");
    assert_points(&plain);
    // Byte-order mark.
    assert_points(&format!("\u{feff}{plain}"));
    // Quoted header and fields.
    assert_points(&csv_text([0, 1, 2, 3, 4], ",", "\""));
    assert_eq!(
        &csv_text([0, 1, 2, 3, 4], ",", "\"")[..20],
        "\"x\",\"y\",\"X\",\"Y\",\"Z\"\n"
    );
    // Semicolons and tabs, quoted or not, with a BOM.
    for d in [";", "\t"] {
        for q in ["", "\""] {
            let t = csv_text([0, 1, 2, 3, 4], d, q);
            assert_points(&t);
            assert_points(&format!("\u{feff}{t}"));
        }
    }
    // CRLF line ends and spaces around fields.
    assert_points(&plain.replace('\n', "\r\n").replace(',', " , "));
    let solved = solve(&parse_csv(&plain).unwrap(), &Solver::default()).unwrap();
    assert!(solved.contains("translation"));
}

#[test]
fn csv_columns_in_any_order_are_matched_by_name() {
    for order in [[4, 3, 2, 1, 0], [2, 0, 3, 1, 4], [1, 0, 4, 2, 3]] {
        for d in [",", ";", "\t"] {
            assert_points(&csv_text(order, d, ""));
        }
    }
    // Case matters: `x` is the pixel, `X` the world coordinate.
    let m = csv_failure("x,y,x,Y,Z\n1,2,3,4,5\n");
    assert!(m.contains("repeated column `x`"), "{m}");
    assert!(m.contains("missing column X"), "{m}");
}

#[test]
fn csv_blank_and_comment_lines_are_skipped_and_counted() {
    let plain = csv_text([0, 1, 2, 3, 4], ",", "");
    let mut lines: Vec<&str> = plain.lines().collect();
    lines.insert(0, "# a comment");
    lines.insert(1, "");
    lines.insert(3, "   ");
    lines.insert(4, "  # indented, \"quoted\" comment");
    lines.insert(6, "#x,y,X,Y,Z");
    lines.insert(8, "\t");
    let text = lines.join("\n");
    assert_points(&text);
    // The line numbers count the skipped lines: line 12 (index 11) is the 5th data row.
    let mut fields: Vec<&str> = lines[11].split(',').collect();
    fields[2] = "zz";
    let row = fields.join(",");
    lines[11] = &row;
    let bad = lines.join("\n");
    let m = csv_failure(&bad);
    assert!(
        m.starts_with("p.csv:12: field 3 (X) is not a number: `zz`"),
        "{m}"
    );
}

#[test]
fn csv_errors_name_line_field_and_reason() {
    // Field named by the header, numbered by its place in the file.
    let m = csv_failure("\n# c\nZ;Y;X;y;x\n1;2;3;4;five\n");
    assert_eq!(m, "p.csv:4: field 5 (x) is not a number: `five`");
    let m = csv_failure("x\ty\tX\tY\tZ\n1\t2\t3\t4\t5\n1\t2\t3\t4\n");
    assert!(
        m.starts_with("p.csv:3: expected 5 tab-separated numbers (x, y, X, Y, Z), found 4 fields"),
        "{m}"
    );
    let m = csv_failure("x;y;X;Y;Z\n1;2;3;4;5;6\n");
    assert!(
        m.starts_with("p.csv:2: expected 5 semicolon-separated"),
        "{m}"
    );
    // Quoted fields spanning lines are reported at the line they start on.
    let m = csv_failure("x,y,X,Y,Z\n1,\"2\n3\",3,4,5\n");
    assert_eq!(m, "p.csv:2: field 2 (y) is not a number: `2\\n3`");
    // A comma file is not split at semicolons: one field.
    let m = csv_failure("x,y,X,Y,Z\n1;2;3;4;5\n");
    assert!(
        m.starts_with(
            "p.csv:2: expected 5 comma-separated numbers (x, y, X, Y, Z), found 1 field "
        ),
        "{m}"
    );
}

#[test]
fn csv_header_errors_say_what_is_wrong() {
    let m = csv_failure("x;y;X;Y\n1;2;3;4\n");
    assert!(
        m.starts_with("p.csv:1: expected the header `x,y,X,Y,Z`"),
        "{m}"
    );
    assert!(m.ends_with("found `x;y;X;Y`: missing column Z"), "{m}");
    let m = csv_failure("# c\n\nx,y,X,Y,Z,w\n");
    assert!(m.starts_with("p.csv:3:"), "{m}");
    assert!(m.ends_with(": unknown column `w`"), "{m}");
    // Control characters are escaped; the header may not mix delimiters.
    let m = csv_failure("x,y,X\u{1},Y,Z\n");
    assert!(m.contains("found `x,y,X\\u{1},Y,Z`"), "{m}");
    assert!(
        m.contains("missing column X; unknown column `X\\u{1}`"),
        "{m}"
    );
    let m = csv_failure("x,y;X,Y,Z\n");
    assert!(m.contains("unknown column `y;X`"), "{m}");
}

#[test]
fn csv_without_data_rows_is_an_input_error() {
    for text in [
        "x,y,X,Y,Z\n",
        "\u{feff}# c\n\"x\";\"y\";\"X\";\"Y\";\"Z\"\n\n# end\n",
    ] {
        let m = csv_failure(text);
        assert!(m.contains("no correspondences"), "{m}");
        assert!(m.starts_with("p.csv:") && m.contains("header"), "{m}");
    }
    assert!(csv_failure("x,y,X,Y,Z\n").starts_with("p.csv:1:"));
    let m = csv_failure("\n# only a comment\n");
    assert!(m.contains("empty file"), "{m}");
    let m = csv_failure("\u{feff}");
    assert!(m.contains("empty file"), "{m}");
}

#[test]
fn byte_order_mark_before_json_and_sniffing() {
    let text = format!(
        "\u{feff}{}",
        serde_json::json!({
            "camera": {"model": "PINHOLE", "params": [800, 800, 320, 240]},
            "points2d": points().iter().map(|p| p.0).collect::<Vec<_>>(),
            "points3d": points().iter().map(|p| p.1).collect::<Vec<_>>(),
        })
    );
    for ext in [Some("json"), None, Some("txt")] {
        let p = parse_problem("<stdin>", text.as_bytes(), ext, None)
            .unwrap_or_else(|f| panic!("{ext:?}: {}", f.message));
        assert_eq!(p.world.len(), 8);
    }
    // Without an extension, CSV is sniffed by not starting with `{`.
    let csv = csv_text([0, 1, 2, 3, 4], ";", "\"");
    let p = parse_problem("<stdin>", csv.as_bytes(), None, Some(CAMERA)).unwrap();
    assert_eq!(p.world.len(), 8);
}

#[test]
fn input_size_is_capped() {
    let limits = |max_input_bytes| Limits {
        max_input_bytes,
        ..Limits::default()
    };
    let text = "x,y,X,Y,Z\n1,2,3,4,5\n";
    let n = text.len() as u64;
    let read =
        |cap| read_problem_from("<stdin>", text.as_bytes(), None, Some(CAMERA), &limits(cap));
    assert_eq!(read(n).unwrap().correspondences(), 1);
    let f = read(n - 1).err().unwrap();
    assert_eq!(f.code, 2);
    assert_eq!(
        f.message,
        format!(
            "<stdin>: larger than {} bytes, the input size limit of `eopnp solve` \
             (--max-input-size)",
            n - 1
        )
    );
    let f = too_large("big.csv", MAX_INPUT_BYTES);
    assert_eq!(
        f.message,
        "big.csv: larger than 1 GiB, the input size limit of `eopnp solve` (--max-input-size)"
    );
}

#[test]
fn streaming_through_tiny_buffers_gives_the_same_problem() {
    let json = format!(
        "\u{feff}\n\n  {}",
        serde_json::json!({
            "camera": {"model": "PINHOLE", "params": [800, 800, 320, 240]},
            "points2d": points().iter().map(|p| p.0).collect::<Vec<_>>(),
            "points3d": points().iter().map(|p| p.1).collect::<Vec<_>>(),
        })
    );
    let csv = format!(
        "\u{feff}# c\n\n{}",
        csv_text([2, 0, 3, 1, 4], ";", "\"").replace('\n', "\r\n")
    );
    for (text, ext) in [
        (&json, None),
        (&json, Some("json")),
        (&csv, None),
        (&csv, Some("csv")),
    ] {
        let whole = read_problem_from("p", text.as_bytes(), ext, Some(CAMERA), &Limits::default())
            .unwrap_or_else(|f| panic!("{}", f.message));
        assert_eq!(whole.correspondences(), 8);
        for capacity in 1..=9 {
            let src = std::io::BufReader::with_capacity(capacity, text.as_bytes());
            let p = read_problem_from("p", src, ext, Some(CAMERA), &Limits::default()).unwrap();
            assert_eq!(p, whole, "{ext:?} through {capacity} bytes");
        }
    }
}

#[test]
fn lines_after_sniffed_whitespace_are_counted() {
    // JSON after two blank lines: the syntax error is on line 4, column 9.
    let text = "\n\n  {\"points2d\": [],\n \"points3d\": [1]}";
    let f = parse_problem("p", text.as_bytes(), None, None)
        .err()
        .unwrap();
    assert!(f.message.starts_with("p:4:"), "{}", f.message);
    let f = parse_problem("p", text.as_bytes(), Some("json"), None)
        .err()
        .unwrap();
    assert!(f.message.starts_with("p:4:"), "{}", f.message);
    // On the line of `{`, the columns count the spaces before it.
    let text = "\n   {\"points2d\": x}";
    let f = parse_problem("p", text.as_bytes(), None, None)
        .err()
        .unwrap();
    assert!(
        f.message.starts_with("p:2:17: expected value"),
        "{}",
        f.message
    );
    // The camera and count errors are where their values end.
    let text = "\n{\"camera\": {\"model\": \"X\",\n \"params\": []},\n\"points2d\": [[1, 2]],\n\
                \"points3d\": []}";
    let f = parse_problem("p", text.as_bytes(), None, None)
        .err()
        .unwrap();
    assert!(f.message.starts_with("p:3:"), "{}", f.message);
    assert!(
        f.message
            .contains(": camera: unsupported camera model \"X\""),
        "{}",
        f.message
    );
    let f = parse_problem("p", text.as_bytes(), None, Some(CAMERA))
        .err()
        .unwrap();
    assert!(f.message.starts_with("p:5:"), "{}", f.message);
    assert!(
        f.message
            .ends_with(": 1 points2d but 0 points3d; they must correspond one to one"),
        "{}",
        f.message
    );
    // A point with a coordinate too many, or too few.
    let text = "{\"points2d\": [[1, 2, 3]], \"points3d\": []}";
    let f = parse_problem("p", text.as_bytes(), None, Some(CAMERA))
        .err()
        .unwrap();
    assert!(
        f.message.starts_with(
            "p:1:23: a point with more than 2 coordinates (points2d entries are [x, y]"
        ),
        "{}",
        f.message
    );
    let text = "{\"points2d\": [], \"points3d\": [[1, 2]]}";
    let f = parse_problem("p", text.as_bytes(), None, Some(CAMERA))
        .err()
        .unwrap();
    assert!(
        f.message
            .contains("invalid length 2, expected an array of length 3"),
        "{}",
        f.message
    );
    // CSV after blank lines and indentation.
    let text = "\n\n   x,y,X,Y,Z\n1,2,3,4,five\n";
    let f = csv_failure(text);
    assert_eq!(f, "p.csv:4: field 5 (Z) is not a number: `five`");
    let f = parse_problem("p", text.as_bytes(), None, Some(CAMERA))
        .err()
        .unwrap();
    assert_eq!(f.message, "p:4: field 5 (Z) is not a number: `five`");
}

#[test]
fn line_limits_name_themselves() {
    let limits = Limits {
        max_input_bytes: u64::MAX,
        max_line_bytes: 20,
    };
    let read =
        |text: &str| read_problem_from("p", text.as_bytes(), Some("csv"), Some(CAMERA), &limits);
    // A long comment is skipped unread, whatever its bytes; a long data line is refused.
    let mut ok = format!("# {}", "c".repeat(100)).into_bytes();
    ok.extend_from_slice(b"\xff\nx,y,X,Y,Z\n1,2,3,4,5\n");
    let p = read_problem_from("p", &ok[..], Some("csv"), Some(CAMERA), &limits).unwrap();
    assert_eq!(p.correspondences(), 1);
    let f = read("x,y,X,Y,Z\n1,2,3,4,5,6,7,8,9,10,11\n").err().unwrap();
    assert_eq!(
        f.message,
        "p:2: line longer than 20 bytes, the line length limit of CSV input"
    );
    // A quoted record spanning lines, past the limit.
    let f = read("x,y,X,Y,Z\n\"1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n11\n")
        .err()
        .unwrap();
    assert!(
        f.message.starts_with("p:2: record longer than 20 bytes"),
        "{}",
        f.message
    );
    // A header followed by spaces past the limit, and a long line that is not a header.
    let f = read(&format!("x,y,X,Y,Z{}\n1,2,3,4,5\n", " ".repeat(30)))
        .err()
        .unwrap();
    assert!(
        f.message.starts_with("p:1: line longer than 20 bytes"),
        "{}",
        f.message
    );
    let f = read("x,y,X,Y,Z,width,height,depth\n").err().unwrap();
    assert!(
        f.message.starts_with("p:1: expected the header"),
        "{}",
        f.message
    );
    assert!(
        f.message.ends_with("(the line is longer than 20 bytes, the line length limit of CSV input: only its start was read)"),
        "{}",
        f.message
    );
    // More than 64 fields.
    let f = csv_failure(&format!("x,y,X,Y,Z\n{}\n", ",".repeat(100)));
    assert!(f.ends_with("found more than 64 fields"), "{f}");
    // JSON strings and numbers.
    let json = |text: &str| read_problem_from("p", text.as_bytes(), Some("json"), None, &limits);
    let f = json(&format!("{{\"points2d\": [[1.{}, 2]]}}", "0".repeat(30)))
        .err()
        .unwrap();
    assert_eq!(
        f.message,
        "p:1: a string or number longer than 20 bytes, the limit of JSON input"
    );
    let f = json(&format!(
        "{{\"camera\": {{\"model\": \"{}\"}}}}",
        "A".repeat(30)
    ))
    .err()
    .unwrap();
    assert!(
        f.message.contains("string or number longer than 20 bytes"),
        "{}",
        f.message
    );
}
