"""solve_ransac: outliers, the info dict, options as an object or a dict, seeds, weights."""

import pickle

import numpy as np
import pytest

import eopnp
from conftest import problem, rotation_error_deg


def with_outliers(rng, n, fraction, cam=None, sigma_px=0.5):
    world, image, r, t = problem(rng, n)
    f = cam.focal[0] if cam else 800.0
    image = image + rng.normal(0, sigma_px / f, image.shape)
    k = int(round(fraction * n))
    bad = rng.choice(n, k, replace=False)
    world[bad] = rng.uniform(-3, 3, (k, 3)) + world.mean(axis=0)
    truth = np.ones(n, dtype=bool)
    truth[bad] = False
    obs = cam.project(image) if cam else image
    return world, obs, r, t, truth


@pytest.mark.parametrize("fraction", [0.0, 0.3, 0.6])
def test_outliers_normalised(rng, fraction):
    world, image, r, t, truth = with_outliers(rng, 200, fraction)
    sol, info = eopnp.solve_ransac(world, image, focal=(800.0, 800.0))
    assert rotation_error_deg(sol.R, r) < 0.2
    mask = info["inliers"]
    assert mask.dtype == np.bool_ and mask.shape == (200,)
    assert info["num_inliers"] == mask.sum() == sol.used
    # every true inlier found, few false ones
    assert (mask & truth).sum() >= 0.97 * truth.sum()
    assert (mask & ~truth).sum() <= 3
    assert info["inlier_ratio"] == pytest.approx(mask.mean())
    assert info["iterations"] >= 20 and info["hypotheses"] >= info["iterations"] // 2
    # rmse_px is rmse in pixels (f = 800 on both axes, the same inliers): equal but for
    # rounding (measured: 4e-15 relative).
    assert info["rmse_px"] < 2.0
    assert info["rmse"] * 800 == pytest.approx(info["rmse_px"], rel=1e-12)
    assert info["cost"] == sol.cost and info["micros"] > 0
    assert set(info) == {
        "inliers", "num_inliers", "inlier_ratio", "iterations", "hypotheses", "local_fits",
        "final_fits", "cost", "rmse", "rmse_px", "micros",
    }


def test_outliers_camera(rng):
    cam = eopnp.Camera("OPENCV", [800.0, 790.0, 320.0, 240.0, -0.1, 0.01, 1e-3, -5e-4])
    world, pixels, r, t, truth = with_outliers(rng, 300, 0.5, cam)
    sol, info = eopnp.solve_ransac(world, pixels, camera=cam, ransac={"threshold_px": 2.0})
    assert rotation_error_deg(sol.R, r) < 0.2
    assert (info["inliers"] == truth).mean() > 0.97
    assert info["rmse_px"] < 1.5
    # Unit weights: exactly the unweighted run (the binding's weighted path = the library's).
    sol1, info1 = eopnp.solve_ransac(world, pixels, np.ones(300), camera=cam,
                                     ransac={"threshold_px": 2.0})
    assert sol1 == sol and np.array_equal(info1["inliers"], info["inliers"])
    # Weight 0 on the outliers: they are never fitted (nor inliers with weight... scored as 0).
    w = truth.astype(float)
    sol2, _ = eopnp.solve_ransac(world, pixels, w, camera=cam, ransac={"threshold_px": 2.0})
    assert rotation_error_deg(sol2.R, r) < 0.2


def test_seed_and_options(rng):
    world, image, _, _, _ = with_outliers(rng, 150, 0.5)
    kw = dict(focal=(800.0, 800.0))
    a = eopnp.solve_ransac(world, image, **kw, ransac=eopnp.RansacOptions(seed=5))
    b = eopnp.solve_ransac(world, image, **kw, ransac={"seed": 5})
    assert a[0] == b[0] and a[1]["iterations"] == b[1]["iterations"]
    assert np.array_equal(a[1]["inliers"], b[1]["inliers"])
    # Other seeds draw other samples (and land on about the same pose).
    runs = [eopnp.solve_ransac(world, image, **kw, ransac={"seed": s}) for s in range(6)]
    assert len({(i["iterations"], i["hypotheses"], i["local_fits"]) for _, i in runs}) > 1
    assert all(rotation_error_deg(s.R, a[0].R) < 0.05 for s, _ in runs)
    d = eopnp.solve_ransac(world, image, **kw)
    assert d[0] == eopnp.solve_ransac(world, image, **kw, ransac=eopnp.RansacOptions())[0]
    few = eopnp.solve_ransac(world, image, **kw, ransac={"max_iterations": 30,
                                                          "min_iterations": 30})
    assert few[1]["iterations"] == 30
    nolo = eopnp.solve_ransac(world, image, **kw, ransac={"local_optimisation": False})
    assert nolo[1]["local_fits"] == 0
    alg = eopnp.solve_ransac(world, image, **kw, refinement="algebraic")
    assert alg[0].reprojection_iterations == 0


def test_options_object():
    o = eopnp.RansacOptions(threshold_px=2.5, seed=3)
    assert (o.threshold_px, o.seed, o.confidence, o.max_iterations) == (2.5, 3, 0.999, 10000)
    assert (o.min_iterations, o.local_optimisation, o.final_threshold_factor) == (20, True, 2.0)
    o.confidence = 0.99
    assert o.as_dict()["confidence"] == 0.99
    assert eopnp.RansacOptions(**o.as_dict()) == o
    back = pickle.loads(pickle.dumps(o))
    assert back == o and back is not o
    assert "threshold_px=2.5" in repr(o)
    with pytest.raises(TypeError):
        eopnp.RansacOptions(2.0)  # keyword-only
    with pytest.raises(TypeError):
        o.threshold_px = "big"


def test_minimum_points(rng):
    world, image, r, _ = problem(rng, 4)
    sol, info = eopnp.solve_ransac(world, image, focal=(800.0, 800.0))
    assert info["num_inliers"] == 4
    with pytest.raises(eopnp.InvalidInputError, match="too few"):
        eopnp.solve_ransac(world[:3], image[:3], focal=(800.0, 800.0))


def test_focal_forms(rng):
    world, image, _, _, _ = with_outliers(rng, 60, 0.3)
    ref = eopnp.solve_ransac(world, image, focal=(800.0, 800.0))[0]
    for f in [800.0, 800, [800, 800], np.array([800.0, 800.0])]:
        assert eopnp.solve_ransac(world, image, focal=f)[0] == ref
    with pytest.raises(eopnp.InvalidOptionError, match="one focal length or two"):
        eopnp.solve_ransac(world, image, focal=(800.0, 800.0, 1.0))
