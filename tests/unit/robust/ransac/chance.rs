use super::*;

/// ln NFA(k) by direct evaluation (small n).
fn ln_nfa(n: usize, k: usize, p: f64) -> f64 {
    let ln_c = |a: usize, b: usize| -> f64 {
        (0..b)
            .map(|i| ((a - i) as f64).ln() - ((i + 1) as f64).ln())
            .sum()
    };
    (4.0 * (n - 3) as f64).ln() + ln_c(n, k) + ln_c(k, 3) + (k - 3) as f64 * p.ln()
}

#[test]
fn least_consensus_is_the_first_count_with_at_most_one_false_alarm() {
    for &(n, p) in &[
        (50usize, 0.01),
        (200, 0.002),
        (1000, 3e-4),
        (30, 0.05),
        (12, 0.001),
    ] {
        let k = least_consensus(n, p);
        assert!(k > 4 && k <= n, "n {n} p {p}: {k}");
        assert!(ln_nfa(n, k, p) <= 1e-9, "n {n} p {p}: {k}");
        assert!(
            ln_nfa(n, k - 1, p) > 0.0,
            "n {n} p {p}: {k} is not the least"
        );
    }
}

#[test]
fn nothing_is_accepted_when_every_point_is_within_chance() {
    assert_eq!(least_consensus(100, 1.0), 101);
    assert_eq!(least_consensus(100, 0.9), 101);
}

#[test]
fn four_points_spanning_an_image_are_accepted() {
    // The corners of a 400 x 300 px region at f = 800 px, 8 px final threshold.
    let image = [
        Point2::new(-0.25, -0.1875),
        Point2::new(0.25, -0.1875),
        Point2::new(0.25, 0.1875),
        Point2::new(-0.25, 0.1875),
    ];
    let p = chance_inlier_rate(&image, (800.0, 800.0), 8.0);
    // The extremes of four points: 400 x 300 px.
    assert!(
        (p - std::f64::consts::PI * 64.0 / 120_000.0).abs() < 1e-12,
        "{p}"
    );
    assert_eq!(least_consensus(4, p), 4);
}

#[test]
fn a_tiny_or_degenerate_spread_leaves_everything_to_chance() {
    let image = [Point2::new(0.1, 0.1); 10];
    assert_eq!(chance_inlier_rate(&image, (800.0, 800.0), 8.0), 1.0);
    let line: Vec<_> = (0..10)
        .map(|k| Point2::new(f64::from(k) * 0.01, 0.0))
        .collect();
    assert_eq!(chance_inlier_rate(&line, (800.0, 800.0), 8.0), 1.0);
}

#[test]
fn a_few_far_observations_do_not_widen_the_region() {
    let mut image: Vec<_> = (0..100)
        .map(|k| Point2::new(f64::from(k % 10) * 0.05, f64::from(k / 10) * 0.05))
        .collect();
    let p = chance_inlier_rate(&image, (800.0, 800.0), 8.0);
    image[0] = Point2::new(1e6, -1e6);
    image[1] = Point2::new(-1e6, 1e6);
    let q = chance_inlier_rate(&image, (800.0, 800.0), 8.0);
    assert!((q / p - 1.0).abs() < 0.25, "{p} {q}");
}
