use super::*;

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
