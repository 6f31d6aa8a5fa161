"""Refined intrinsics: ``refine_principal_point=`` and ``refine_distortion=`` on solve, refine,
solve_ransac and the batch forms, ``Solution.camera``, ``Solution.focal_sigma`` with a
covariance, pickling, the typed errors."""

import pickle

import numpy as np
import pytest

import eopnp
from conftest import random_rotation, rotation_error_deg

TRUTH = eopnp.Camera("OPENCV", [600.0, 604.0, 322.0, 236.0, -0.18, 0.04, 0.001, -0.002], 640, 480)
# The guess: the principal point 6 px off, no distortion, the focal lengths 20 % long.
GUESS = eopnp.Camera("OPENCV", [720.0, 724.8, 328.0, 232.0, 0.0, 0.0, 0.0, 0.0], 640, 480)


def case(rng, n, sigma=0.0, outliers=0):
    """n points 2 to 10 units away over the whole image of TRUTH, the first `outliers` pixels
    uniform over the image."""
    R, t = random_rotation(rng), rng.uniform(-1, 1, 3)
    uv = np.column_stack([rng.uniform(20, 620, n), rng.uniform(20, 460, n)])
    m = TRUTH.undistort(uv)
    z = rng.uniform(2, 10, n)
    cam = np.column_stack([m * z[:, None], z])
    world = (cam - t) @ R
    pixels = uv + rng.normal(0, sigma, uv.shape)
    pixels[:outliers] = rng.uniform([0, 0], [640, 480], (outliers, 2))
    return world, pixels, R, t


def close(a, b, rel):
    return np.all(np.abs(np.asarray(a) - np.asarray(b)) <= rel * np.maximum(np.abs(b), 1.0))


def test_solve_gives_the_camera_back():
    rng = np.random.default_rng(21)
    world, pixels, R, t = case(rng, 60)
    sol = eopnp.solve(
        world,
        pixels,
        camera=GUESS,
        estimate_focal=True,
        refine_principal_point=True,
        refine_distortion=True,
    )
    assert sol.camera.model == "OPENCV"
    assert close(sol.camera.params, TRUTH.params, 1e-7), sol.camera.params
    assert sol.focal == sol.camera.focal
    assert rotation_error_deg(sol.R, R) < 1e-7
    assert sol.as_dict()["camera"] == sol.camera
    back = pickle.loads(pickle.dumps(sol))
    assert back == sol and back.camera == sol.camera
    # Only the distortion free: the focal length and the principal point stay the guess's.
    only = eopnp.solve(world, pixels, camera=GUESS, refine_distortion=True)
    assert np.array_equal(only.camera.params[:4], GUESS.params[:4])
    assert not np.array_equal(only.camera.params[4:], GUESS.params[4:])
    assert eopnp.solve(world, pixels, camera=GUESS).camera is None


def test_refine_and_ransac_refine_the_distortion():
    rng = np.random.default_rng(22)
    world, pixels, R, t = case(rng, 200, outliers=60)
    guess = eopnp.Camera("OPENCV", [600.0, 604.0, 322.0, 236.0, 0.0, 0.0, 0.0, 0.0], 640, 480)
    sol, info = eopnp.solve_ransac(world, pixels, camera=guess, refine_distortion=True)
    # Every true inlier found again through the refined camera (a guess without distortion
    # misses those at the image's edges), the camera the truth.
    assert info["num_inliers"] == 140 and info["inliers"][60:].all()
    assert close(sol.camera.params, TRUTH.params, 1e-7), sol.camera.params
    ref = eopnp.refine(
        world[60:], pixels[60:], (R, t), camera=guess, refine_distortion=True
    )
    assert close(ref.camera.params, TRUTH.params, 1e-7)
    assert ref.source == "initial"


def test_batches_equal_the_single_calls():
    rng = np.random.default_rng(23)
    problems = [case(rng, 40, sigma=0.5)[:2] for _ in range(4)]
    batch = eopnp.solve_batch(problems, camera=GUESS, estimate_focal=True, refine_distortion=True)
    for (w, p), b in zip(problems, batch):
        one = eopnp.solve(w, p, camera=GUESS, estimate_focal=True, refine_distortion=True)
        assert b == one and b.camera == one.camera
        assert b.camera.params[4] != 0.0


def test_focal_sigma_with_a_covariance():
    rng = np.random.default_rng(24)
    world, pixels, _, _ = case(rng, 40, sigma=1.0)
    pin = eopnp.Camera("PINHOLE", [600.0, 604.0, 322.0, 236.0], 640, 480)
    sol = eopnp.solve(world, pixels, camera=pin, estimate_focal=True, covariance=1.0)
    assert 0.1 < sol.focal_sigma < 50.0
    assert sol.as_dict()["focal_sigma"] == sol.focal_sigma
    assert pickle.loads(pickle.dumps(sol)).focal_sigma == sol.focal_sigma
    assert eopnp.solve(world, pixels, camera=pin, covariance=1.0).focal_sigma is None
    assert eopnp.solve(world, pixels, camera=pin, estimate_focal=True).focal_sigma is None


def test_bad_requests_raise():
    rng = np.random.default_rng(25)
    world, pixels, _, _ = case(rng, 12)
    with pytest.raises(eopnp.InvalidOptionError) as e:
        eopnp.solve(world, TRUTH.undistort(pixels), refine_distortion=True)
    assert e.value.option == "refine_distortion"
    g = eopnp.Gravity([0, 1, 0], [0, 1, 0], 1.0)
    with pytest.raises(eopnp.InvalidOptionError) as e:
        eopnp.solve(world, pixels, camera=GUESS, refine_principal_point=True, gravity=g)
    assert e.value.option == "refine_principal_point"
    # 6 + 1 + 2 + 4 parameters: 7 points at least.
    with pytest.raises(eopnp.InvalidInputError) as e:
        eopnp.solve(
            world[:6],
            pixels[:6],
            camera=GUESS,
            estimate_focal=True,
            refine_principal_point=True,
            refine_distortion=True,
        )
    assert e.value.kind == "TooFewPoints"
