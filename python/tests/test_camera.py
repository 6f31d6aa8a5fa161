"""Cameras: every COLMAP model and OpenCV's K + distortion; projection against OpenCV's own
values (tests/data/opencv_projection.json, written by scripts/opencv_camera_data.py), the
undistortion round trip, and solves from pixels through each model."""

import json
import pickle

import numpy as np
import pytest

import eopnp
from conftest import REPO, log_so3, problem, rotation_error_deg

MODELS = {
    "SIMPLE_PINHOLE": [800.0, 320.0, 240.0],
    "PINHOLE": [800.0, 790.0, 320.0, 240.0],
    "SIMPLE_RADIAL": [800.0, 320.0, 240.0, -0.08],
    "RADIAL": [800.0, 320.0, 240.0, -0.08, 0.01],
    "OPENCV": [800.0, 790.0, 320.0, 240.0, -0.1, 0.01, 1e-3, -5e-4],
    "OPENCV_FISHEYE": [400.0, 401.0, 320.0, 240.0, 0.02, -0.01, 0.003, -0.001],
    "FULL_OPENCV": [800.0, 790.0, 320.0, 240.0, -0.1, 0.01, 1e-3, -5e-4, 0.001, 0.0, 0.0, 0.0],
    "SIMPLE_RADIAL_FISHEYE": [400.0, 320.0, 240.0, 0.02],
    "RADIAL_FISHEYE": [400.0, 320.0, 240.0, 0.02, -0.01],
    "OPENCV_THIN_PRISM_TILTED": [800.0, 790.0, 320.0, 240.0, -0.1, 0.01, 1e-3, -5e-4, 0.001,
                                 0.0, 0.0, 0.0, 1e-3, -1e-3, 2e-3, 1e-4, 0.01, -0.02],
}


@pytest.mark.parametrize("model", sorted(MODELS))
def test_models_round_trip_and_solve(rng, model):
    cam = eopnp.Camera(model, MODELS[model], 640, 480)
    assert cam.model == model and (cam.width, cam.height) == (640, 480)
    assert np.array_equal(cam.params, MODELS[model])
    assert cam.focal[0] > 0 and cam.principal_point == (320.0, 240.0)
    assert cam.has_distortion == (model not in ("SIMPLE_PINHOLE", "PINHOLE"))
    world, image, r, t = problem(rng, 30)
    pixels = cam.project(image)
    assert pixels.shape == (30, 2)
    assert np.abs(cam.undistort(pixels) - image).max() < 1e-12
    sol = eopnp.solve(world, pixels, camera=cam)
    assert rotation_error_deg(sol.R, r) < 1e-8 and np.abs(sol.t - t).max() < 1e-8
    assert (sol.used, sol.skipped) == (30, 0)
    # Pixel noise (1 px): the rotation error is within the noise's reach. Whitened by the
    # predicted covariance (checked against Monte Carlo in test_covariance.py), it is
    # chi-square with 3 degrees of freedom to first order, above 25 with probability 1.5e-5.
    # Measured: 13.8-14.1 (the same noise draw through each lens; rotation errors 0.25 deg
    # at f = 800, 0.51 deg at f = 400). Unit weights are the unweighted solve exactly.
    noisy = pixels + rng.normal(0, 1.0, pixels.shape)
    sol = eopnp.solve(world, noisy, camera=cam)
    cov = eopnp.solve(world, noisy, camera=cam, covariance=1.0).covariance[:3, :3]
    dq = log_so3(r @ sol.R.T) / 2  # the covariance's convention: R = Exp(2 dq) R_hat
    chi2 = dq @ np.linalg.solve(cov, dq)
    assert chi2 < 25.0, (chi2, rotation_error_deg(sol.R, r))
    assert eopnp.solve(world, noisy, np.ones(30), camera=cam) == sol
    assert pickle.loads(pickle.dumps(cam)) == cam


def test_pixels_match_normalised_for_pinhole(rng):
    """PINHOLE without distortion: solving pixels is solving the normalised points with the
    residual rows weighted by fx^2, fy^2 (equal focal lengths: the same problem)."""
    cam = eopnp.Camera.pinhole(800, 800, 320, 240)
    world, image, _, _ = problem(rng, 40, sigma_px=1.0)
    a = eopnp.solve(world, cam.project(image), camera=cam)
    b = eopnp.solve(world, image)
    assert rotation_error_deg(a.R, b.R) < 1e-9 and np.abs(a.t - b.t).max() < 1e-9


def test_undistortable_pixels_are_skipped(rng):
    cam = eopnp.Camera("OPENCV_FISHEYE", MODELS["OPENCV_FISHEYE"])
    world, image, r, _ = problem(rng, 20)
    pixels = cam.project(image)
    pixels[4] = [1e200, 1e200]  # too far outside the image
    nrm = cam.undistort(pixels)
    assert np.isnan(nrm[4]).all() and np.isfinite(np.delete(nrm, 4, axis=0)).all()
    sol = eopnp.solve(world, pixels, camera=cam)
    assert (sol.used, sol.skipped) == (19, 1)
    assert rotation_error_deg(sol.R, r) < 1e-8


def _opencv_cases():
    data = json.loads((REPO / "tests" / "data" / "opencv_projection.json").read_text())
    return data["cases"]


@pytest.mark.parametrize("case", _opencv_cases(), ids=lambda c: f"{c['kind']}-{len(c['dist'])}")
def test_from_opencv_matches_cv2_projectpoints(case):
    k = np.array(case["K"])
    if case["kind"] == "fisheye":
        cam = eopnp.Camera.from_opencv_fisheye(k, case["dist"])
        assert cam.model == "OPENCV_FISHEYE"
        back_k, back_d = cam.to_opencv_fisheye()
        assert cam.to_opencv() is None
    else:
        cam = eopnp.Camera.from_opencv(k, np.array(case["dist"])[None, :])  # (1, n) as cv2
        back_k, back_d = cam.to_opencv()
    assert np.array_equal(back_k, k)
    normalised = np.array(case["normalised"])
    pixels = np.array(case["pixels"])
    assert np.abs(cam.project(normalised) - pixels).max() < 1e-11
    assert np.abs(cam.undistort(pixels) - normalised).max() < 1e-11
    assert (cam.width, cam.height) == (0, 0)


def test_from_opencv_models():
    k = [[800.0, 0, 320], [0, 810.0, 240], [0, 0, 1]]
    assert eopnp.Camera.from_opencv(k).model == "PINHOLE"
    assert eopnp.Camera.from_opencv(k, None).model == "PINHOLE"
    assert eopnp.Camera.from_opencv(k, [0.1, 0.01, 0, 0]).model == "OPENCV"
    assert eopnp.Camera.from_opencv(k, np.zeros((5, 1))).model == "FULL_OPENCV"
    assert eopnp.Camera.from_opencv(k, np.zeros(8)).model == "FULL_OPENCV"
    assert eopnp.Camera.from_opencv(k, np.zeros(12)).model == "OPENCV_THIN_PRISM_TILTED"
    assert eopnp.Camera.from_opencv(k, np.zeros(14)).model == "OPENCV_THIN_PRISM_TILTED"


def test_to_opencv_of_colmap_camera():
    cam = eopnp.Camera("SIMPLE_RADIAL", [1245.6, 600.0, 800.0, 0.06], 1200, 1600)
    k, d = cam.to_opencv()
    assert np.array_equal(k, [[1245.6, 0, 600.0], [0, 1245.6, 800.0], [0, 0, 1]])
    assert np.array_equal(d, [0.06, 0, 0, 0])
    back = eopnp.Camera.from_opencv(k, d)
    n = np.array([[0.3, -0.2], [0.0, 0.1]])
    assert np.abs(back.project(n) - cam.project(n)).max() < 1e-9
    assert "SIMPLE_RADIAL" in repr(cam)


def test_opencv_camera_solve(rng):
    """A pose from OpenCV's K + distortion and pixels from cv2's projection model."""
    k = np.array([[800.0, 0, 320], [0, 810.0, 240], [0, 0, 1]])
    cam = eopnp.Camera.from_opencv(k, [-0.2, 0.05, 1e-3, -5e-4, 0.01])
    world, image, r, t = problem(rng, 50)
    sol = eopnp.solve(world, cam.project(image), camera=cam)
    assert rotation_error_deg(sol.R, r) < 1e-8 and np.abs(sol.t - t).max() < 1e-8
