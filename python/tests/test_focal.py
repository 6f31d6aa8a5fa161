"""An unknown focal length: ``estimate_focal=`` and ``focal_range=`` on solve and solve_ransac,
``Solution.focal``, the typed errors, pickling; and against pycolmap's
estimate_and_refine_absolute_pose with estimate_focal_length and refine_focal_length on the same
noisy problems (a comparison-only package: skipped where it is not installed, an error under
EOPNP_REQUIRE_PEERS=1)."""

import pickle

import numpy as np
import pytest

import eopnp
from conftest import random_rotation, require, rotation_error_deg


def focal_case(rng, n, f, sigma=0.0, outliers=0.0):
    """A pinhole camera of focal length f (640 x 480, principal point (320, 240)), n points 2 to
    10 units away in view, sigma px of noise, a fraction of the pixels replaced by uniform ones."""
    R, t = random_rotation(rng), rng.uniform(-1, 1, 3)
    uv = np.column_stack([rng.uniform(0, 640, n), rng.uniform(0, 480, n)])
    z = rng.uniform(2, 10, n)
    cam = np.column_stack([(uv - [320, 240]) / f * z[:, None], z])
    world = (cam - t) @ R  # R @ X + t = cam
    pixels = uv + rng.normal(0, sigma, uv.shape)
    k = int(outliers * n)
    pixels[:k] = rng.uniform([0, 0], [640, 480], (k, 2))
    return world, pixels, R, t


def test_solve_estimates_the_focal_length():
    rng = np.random.default_rng(11)
    world, pixels, R, t = focal_case(rng, 30, 1500.0)
    guess = eopnp.Camera("PINHOLE", [900.0, 900.0, 320.0, 240.0], 640, 480)
    sol = eopnp.solve(world, pixels, camera=guess, estimate_focal=True)
    fx, fy = sol.focal
    assert abs(fx / 1500.0 - 1) < 1e-9 and fx == fy
    assert rotation_error_deg(sol.R, R) < 1e-8
    assert eopnp.solve(world, pixels, camera=guess).focal is None
    assert sol.as_dict()["focal"] == sol.focal
    back = pickle.loads(pickle.dumps(sol))
    assert back == sol and back.focal == sol.focal
    # A range that holds the truth; one that does not: the best within it.
    ok = eopnp.solve(world, pixels, camera=guess, focal_range=(1000.0, 2000.0))
    assert abs(ok.focal[0] / 1500.0 - 1) < 1e-9
    # Errors: no camera, an empty range, a known vertical too.
    with pytest.raises(eopnp.InvalidOptionError) as e:
        eopnp.solve(world, (pixels - 320.0) / 900.0, estimate_focal=True)
    assert e.value.option == "unknown_focal"
    with pytest.raises(eopnp.InvalidOptionError):
        eopnp.solve(world, pixels, camera=guess, focal_range=(2000.0, 1000.0))
    g = eopnp.Gravity([0, 1, 0], [0, 1, 0], 1.0)
    with pytest.raises(eopnp.InvalidOptionError):
        eopnp.solve(world, pixels, camera=guess, estimate_focal=True, gravity=g)


def test_ransac_estimates_the_focal_length():
    rng = np.random.default_rng(12)
    world, pixels, R, t = focal_case(rng, 100, 1200.0, sigma=1.0, outliers=0.5)
    guess = eopnp.Camera("SIMPLE_PINHOLE", [700.0, 320.0, 240.0], 640, 480)
    sol, info = eopnp.solve_ransac(world, pixels, camera=guess, estimate_focal=True)
    assert abs(sol.focal[0] / 1200.0 - 1) < 0.02
    assert rotation_error_deg(sol.R, R) < 0.5
    assert info["inliers"][50:].sum() >= 48 and info["rmse_px"] < 3.0


def test_against_pycolmap():
    pycolmap = require("pycolmap")
    rng = np.random.default_rng(13)
    ours_f, theirs_f = [], []
    for _ in range(20):
        f = float(10 ** rng.uniform(np.log10(300), np.log10(3000)))
        world, pixels, R, t = focal_case(rng, 100, f, sigma=1.0, outliers=0.5)
        guess = 1.3 * f
        cam = eopnp.Camera("SIMPLE_PINHOLE", [guess, 320.0, 240.0], 640, 480)
        sol, _ = eopnp.solve_ransac(world, pixels, camera=cam, estimate_focal=True)
        ours_f.append(abs(sol.focal[0] / f - 1))
        pc = pycolmap.Camera(model="SIMPLE_PINHOLE", width=640, height=480, params=[guess, 320, 240])
        est = pycolmap.AbsolutePoseEstimationOptions()
        est.estimate_focal_length = True
        est.ransac.max_error = 4.0
        ref = pycolmap.AbsolutePoseRefinementOptions()
        ref.refine_focal_length = True
        out = pycolmap.estimate_and_refine_absolute_pose(pixels, world, pc, est, ref)
        theirs_f.append(abs(pc.focal_length / f - 1) if out is not None else np.inf)
    assert np.median(ours_f) <= np.median(theirs_f) * 1.5 + 1e-4
