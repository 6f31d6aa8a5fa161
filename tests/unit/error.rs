use super::*;

#[test]
fn display_is_actionable() {
    let cases = [
        PnpError::TooFewPoints { got: 3, need: 4 },
        PnpError::LengthMismatch { world: 5, image: 4 },
        PnpError::WeightsLength {
            weights: 3,
            points: 5,
        },
        PnpError::NonFinite {
            index: 7,
            input: InputKind::Image,
        },
        PnpError::InvalidWeight { index: 2 },
        PnpError::Degenerate(DegenerateKind::CollinearWorldPoints),
        PnpError::Degenerate(DegenerateKind::CoincidentWorldPoints),
        PnpError::Degenerate(DegenerateKind::CoincidentImagePoints),
        PnpError::Degenerate(DegenerateKind::ScaleOutOfRange),
        PnpError::NoSolution,
        PnpError::InvalidOption {
            option: "confidence",
        },
        PnpError::NoConsensus {
            iterations: 30,
            inliers: 7,
            needed: 12,
        },
    ];
    for e in &cases {
        let s = e.to_string();
        assert!(s.len() > 20, "{s}");
        let _: &dyn std::error::Error = e;
    }
    assert!(cases[3].to_string().contains("image point 7"));
    assert!(cases[0].to_string().contains("got 3"));
    assert_eq!(cases[0].clone(), cases[0]);
}
