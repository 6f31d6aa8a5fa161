"""covariance=: the pose covariance against Monte Carlo (whitened chi-square), its options and
pickling, and against pycolmap's refine_absolute_pose(return_covariance=True) when pycolmap is
installed (a comparison-only package: skipped otherwise, except under EOPNP_REQUIRE_PEERS=1, as
scripts/test.sh runs the tests, where its absence is an error)."""

import pickle

import numpy as np
import pytest

import eopnp
from conftest import log_so3, problem, require

CAM = eopnp.Camera("SIMPLE_RADIAL", [800.0, 320.0, 240.0, -0.1], 640, 480)


def delta(sol, r_true, t_true):
    """[delta_q, delta_t] of the true pose from the estimate: R_true = Exp(2 dq) R_hat."""
    return np.concatenate([log_so3(r_true @ sol.R.T) / 2, t_true - sol.t])


@pytest.mark.parametrize("pixels", [False, True])
def test_monte_carlo_chi_square(pixels):
    """500 noise draws of one problem (N = 30, sigma = 1 px): d^T C^-1 d, with C each
    estimate's predicted covariance, is chi-square with 6 degrees of freedom to first order.
    Its mean over 500 draws has standard deviation sqrt(12 / 500) = 0.155: within 6 +- 0.6
    (about 4 standard deviations), and the empirical covariance whitened by the mean predicted
    one has eigenvalues within 0.7-1.35."""
    rng = np.random.default_rng(3)
    world, image, r, t = problem(rng, 30)
    sigma = 1.0
    draws = 500
    if pixels:
        clean = CAM.project(image)
        probs = [(world, clean + rng.normal(0, sigma, clean.shape)) for _ in range(draws)]
        sols = eopnp.solve_batch(probs, camera=CAM, covariance=sigma)
    else:
        s = sigma / 800.0
        probs = [(world, image + rng.normal(0, s, image.shape)) for _ in range(draws)]
        sols = eopnp.solve_batch(probs, covariance=s)
    chi2 = []
    deltas = []
    for sol in sols:
        assert isinstance(sol, eopnp.Solution) and sol.covariance is not None
        d = delta(sol, r, t)
        chi2.append(d @ np.linalg.solve(sol.covariance, d))
        deltas.append(d)
    assert abs(np.mean(chi2) - 6.0) < 0.6, np.mean(chi2)
    c_pred = np.mean([s.covariance for s in sols], axis=0)
    l = np.linalg.cholesky(c_pred)
    w = np.linalg.solve(l, np.array(deltas).T)
    ev = np.linalg.eigvalsh(w @ w.T / draws)
    assert 0.7 < ev.min() and ev.max() < 1.35, ev


def test_covariance_options(rng):
    world, image, _, _ = problem(rng, 20, sigma_px=1.0)
    plain = eopnp.solve(world, image)
    assert plain.covariance is None and plain.sigma is None
    a = eopnp.solve(world, image, covariance=2.0 / 800)
    b = eopnp.solve(world, image, covariance=1.0 / 800)
    assert a == eopnp.solve(world, image, covariance=2.0 / 800)
    assert a.sigma == 2.0 / 800 and a.covariance.shape == (6, 6)
    np.testing.assert_allclose(a.covariance, 4 * b.covariance, rtol=1e-12)
    np.testing.assert_allclose(a.covariance, a.covariance.T, rtol=1e-12)
    assert np.all(np.linalg.eigvalsh(a.covariance) > 0)
    est = eopnp.solve(world, image, covariance="estimated")
    assert est.sigma == pytest.approx(np.sqrt(est.cost / (2 * 20 - 6)), rel=1e-9)
    assert 0.5 / 800 < est.sigma < 2.0 / 800
    assert (est.R == plain.R).all() and est != plain  # same pose, plus the covariance
    back = pickle.loads(pickle.dumps(est))
    assert back == est and np.array_equal(back.covariance, est.covariance)
    assert est.as_dict()["sigma"] == est.sigma
    assert eopnp.solve_all(world, image, covariance=1.0)[0].covariance is not None
    for bad in (0.0, -1.0, float("nan"), float("inf"), "sigma", True, [1.0]):
        with pytest.raises(eopnp.InvalidOptionError, match="covariance"):
            eopnp.solve(world, image, covariance=bad)


def test_ransac_covariance_is_that_of_its_inliers(rng):
    """solve_ransac(covariance=...): the returned pose's covariance from its inliers, as
    solve() reports it on the same points with the outliers' weights set to 0 (normalised
    input: the same computation, to the last bits; pixels through a distorting camera: the
    fits start differently and agree to the refinement's convergence). solve_ransac_batch
    gives each problem's one-call result; without the keyword, no covariance."""
    n = 60
    world, image, _, _ = problem(rng, n, sigma_px=1.0)
    wrong = np.arange(n) % 5 == 0
    image = image.copy()
    image[wrong] += [0.05, -0.04]  # about 50 px at f = 800
    weights = 1.0 + 0.5 * (np.arange(n) % 3)
    opts = {"threshold_px": 4.0, "seed": 3}
    sol, info = eopnp.solve_ransac(
        world, image, weights, focal=800.0, ransac=opts, covariance=1.0 / 800
    )
    inl = info["inliers"]
    assert not (inl & wrong).any() and inl.sum() >= 40
    direct = eopnp.solve(world, image, np.where(inl, weights, 0.0), covariance=1.0 / 800)
    np.testing.assert_allclose(sol.R, direct.R, rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.covariance, direct.covariance, rtol=1e-10, atol=0)
    assert sol.sigma == 1.0 / 800
    plain, _ = eopnp.solve_ransac(world, image, weights, focal=800.0, ransac=opts)
    assert plain.covariance is None and plain.sigma is None

    pixels = CAM.project(image)
    sol, info = eopnp.solve_ransac(
        world, pixels, weights, camera=CAM, ransac=opts, covariance="estimated"
    )
    inl = info["inliers"]
    assert not (inl & wrong).any() and inl.sum() >= 40
    direct = eopnp.solve(
        world, pixels, np.where(inl, weights, 0.0), camera=CAM, covariance="estimated"
    )
    np.testing.assert_allclose(sol.R, direct.R, rtol=0, atol=1e-9)
    scale = np.abs(direct.covariance).max()
    assert np.abs(sol.covariance - direct.covariance).max() < 1e-6 * scale
    assert sol.sigma == pytest.approx(direct.sigma, rel=1e-6)

    batch = eopnp.solve_ransac_batch(
        [(world, pixels, weights)] * 2, camera=CAM, ransac=opts, covariance="estimated"
    )
    for i, (s, _) in enumerate(batch):
        one, _ = eopnp.solve_ransac(
            world,
            pixels,
            weights,
            camera=CAM,
            ransac={**opts, "seed": eopnp.problem_seed(3, i)},
            covariance="estimated",
        )
        assert s == one and np.array_equal(s.covariance, one.covariance)
    with pytest.raises(eopnp.InvalidOptionError, match="covariance"):
        eopnp.solve_ransac(world, image, focal=800.0, covariance=-1.0)


def test_against_pycolmap(rng):
    pycolmap = require("pycolmap")
    world, image, _, _ = problem(rng, 40)
    pixels = CAM.project(image) + rng.normal(0, 1.0, (40, 2))
    sol = eopnp.solve(world, pixels, camera=CAM, covariance=1.0)  # pycolmap assumes 1 px
    cam = pycolmap.Camera(
        model=CAM.model, width=CAM.width, height=CAM.height, params=CAM.params
    )
    opts = pycolmap.AbsolutePoseRefinementOptions()
    opts.loss_function_scale = 1e9  # squared loss over these residuals
    opts.refine_focal_length = False
    opts.refine_extra_params = False
    opts.gradient_tolerance = 1e-14
    res = pycolmap.refine_absolute_pose(
        pycolmap.Rigid3d(pycolmap.Rotation3d(sol.R), sol.t),
        pixels,
        world,
        np.ones(len(world), bool),
        cam,
        opts,
        return_covariance=True,
    )
    pose = res["cam_from_world"]
    assert np.abs(pose.rotation.matrix() - sol.R).max() < 1e-9  # already at the optimum
    rel = np.abs(res["covariance"] - sol.covariance).max() / np.abs(sol.covariance).max()
    assert rel < 1e-6, rel
