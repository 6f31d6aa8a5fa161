//! The guard of every exported function: a panic inside it becomes `EOPNP_PANIC` with its
//! message as the thread's last error, and does not cross the boundary.

use super::*;
use std::ffi::CStr;

fn message() -> String {
    // SAFETY: `last_message` is a NUL-terminated string owned by this thread's slot.
    unsafe { CStr::from_ptr(last_message()) }
        .to_str()
        .unwrap()
        .to_owned()
}

#[test]
fn a_panic_is_caught_and_reported() {
    let status = guard(|| panic!("boom {}", 42));
    assert_eq!(status, EopnpStatus::EOPNP_PANIC);
    assert_eq!(last_info().status, EopnpStatus::EOPNP_PANIC);
    assert!(message().contains("boom 42"), "{}", message());
    // A `&'static str` payload too.
    assert_eq!(guard(|| panic!("static")), EopnpStatus::EOPNP_PANIC);
    assert!(message().ends_with("static"), "{}", message());
}

#[test]
fn a_message_with_a_nul_is_cut_there() {
    let status = guard(|| Err(Failure::invalid("before\0after")));
    assert_eq!(status, EopnpStatus::EOPNP_INVALID_ARGUMENT);
    assert_eq!(message(), "before");
}

#[test]
fn success_keeps_the_last_failure() {
    assert_eq!(
        guard(|| Err(Failure::null("x"))),
        EopnpStatus::EOPNP_NULL_POINTER
    );
    assert_eq!(guard(|| Ok(())), EopnpStatus::EOPNP_OK);
    assert_eq!(message(), "`x` is NULL");
}

#[test]
fn every_known_pnp_error_has_its_own_status() {
    use eopnp::PnpError as E;
    use EopnpStatus as S;
    let cases = [
        (E::TooFewPoints { got: 3, need: 4 }, S::EOPNP_TOO_FEW_POINTS),
        (
            E::LengthMismatch { world: 4, image: 5 },
            S::EOPNP_LENGTH_MISMATCH,
        ),
        (
            E::WeightsLength {
                weights: 3,
                points: 4,
            },
            S::EOPNP_WEIGHTS_LENGTH,
        ),
        (
            E::NonFinite {
                index: 2,
                input: eopnp::InputKind::Image,
            },
            S::EOPNP_NON_FINITE,
        ),
        (
            E::CameraIndicesLength {
                indices: 3,
                points: 4,
            },
            S::EOPNP_CAMERA_INDICES_LENGTH,
        ),
        (
            E::UnknownCamera {
                index: 1,
                camera: 7,
            },
            S::EOPNP_UNKNOWN_CAMERA,
        ),
        (E::InvalidWeight { index: 0 }, S::EOPNP_INVALID_WEIGHT),
        (
            E::Degenerate(eopnp::DegenerateKind::CollinearWorldPoints),
            S::EOPNP_DEGENERATE,
        ),
        (E::NoSolution, S::EOPNP_NO_SOLUTION),
        (
            E::InvalidOption { option: "gravity" },
            S::EOPNP_INVALID_OPTION,
        ),
        (
            E::InvalidOption {
                option: "unknown_focal",
            },
            S::EOPNP_INVALID_OPTION,
        ),
        (
            E::NoConsensus {
                iterations: 10,
                inliers: 3,
                needed: 9,
            },
            S::EOPNP_NO_CONSENSUS,
        ),
        (
            E::GravityMismatch {
                angle_deg: 4.25,
                sigmas: 8.5,
            },
            S::EOPNP_GRAVITY_MISMATCH,
        ),
    ];
    for (e, want) in cases {
        let f = Failure::from(e.clone());
        assert_eq!(f.info.status, want, "{e:?}");
        assert_eq!(f.message, e.to_string());
    }
    // The mismatch's message carries the angle and the sigmas.
    let f = Failure::from(E::GravityMismatch {
        angle_deg: 4.25,
        sigmas: 8.5,
    });
    assert!(
        f.message.contains("4.250 degrees") && f.message.contains("8.5 standard"),
        "{}",
        f.message
    );
    assert_eq!(guard(|| Err(f)), S::EOPNP_GRAVITY_MISMATCH);
    assert_eq!(last_info().status, S::EOPNP_GRAVITY_MISMATCH);
    assert!(message().contains("contradict"), "{}", message());
}
