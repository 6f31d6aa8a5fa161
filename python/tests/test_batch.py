"""solve_batch, solve_ransac_batch and problem_seed: each entry equals the one-problem call
(with 1 and 2 threads and rayon's default pool), errors returned in place, a malformed batch
raised before solving, and the GIL released during a batch."""

import numpy as np
import pytest

import eopnp
from conftest import assert_releases_gil, problem

CAM = eopnp.Camera("SIMPLE_RADIAL", [800.0, 320.0, 240.0, -0.05], 640, 480)


def batch(rng, count=40, n=12, sigma_px=1.0):
    return [problem(rng, n, sigma_px=sigma_px)[:2] for _ in range(count)]


def with_outliers(rng, count=20, n=40):
    out = []
    for _ in range(count):
        world, image = problem(rng, n, sigma_px=0.5)[:2]
        pixels = CAM.project(image)
        pixels[: n // 4] += rng.uniform(50, 200, (n // 4, 2))
        out.append((world, pixels))
    return out


@pytest.mark.parametrize("threads", [None, 1, 2])
def test_solve_batch_equals_serial(rng, threads):
    probs = batch(rng)
    probs[3] = (probs[3][0], probs[3][1], rng.uniform(0.5, 2.0, 12))  # weighted
    probs[5] = (probs[5][0][:3], probs[5][1][:3])  # too few points
    probs[7] = (probs[7][0], np.full((12, 2), 0.1))  # degenerate
    got = eopnp.solve_batch(probs, threads=threads)
    assert len(got) == len(probs)
    for k, (p, g) in enumerate(zip(probs, got)):
        try:
            want = eopnp.solve(*p)
        except eopnp.PnpError as e:
            assert type(g) is type(e) and str(g) == str(e) and g.kind == e.kind, k
            continue
        assert isinstance(g, eopnp.Solution) and g == want, k
    assert isinstance(got[5], eopnp.InvalidInputError) and got[5].kind == "TooFewPoints"
    assert isinstance(got[7], eopnp.DegenerateError)


@pytest.mark.parametrize("threads", [1, 2])
def test_solve_batch_pixels_covariance(rng, threads):
    probs = [(w, CAM.project(im)) for w, im in batch(rng, 20)]
    probs[2][1][4] = np.nan  # rejected as solve rejects it
    cams = [CAM] * len(probs)
    for camera in (CAM, cams):
        got = eopnp.solve_batch(probs, camera=camera, covariance="estimated", threads=threads)
        for k, (p, g) in enumerate(zip(probs, got)):
            if k == 2:
                assert isinstance(g, eopnp.InvalidInputError) and g.kind == "NonFinite"
                continue
            want = eopnp.solve(*p, camera=CAM, covariance="estimated")
            assert g == want and g.covariance is not None
            assert np.array_equal(g.covariance, want.covariance) and g.sigma == want.sigma


@pytest.mark.parametrize("threads", [None, 1, 2])
def test_ransac_batch_equals_serial(rng, threads):
    probs = with_outliers(rng)
    probs.append((probs[0][0][:5], rng.uniform(0, 640, (5, 2))))  # no consensus
    opts = eopnp.RansacOptions(threshold_px=2.0, seed=7)
    got = eopnp.solve_ransac_batch(probs, camera=CAM, ransac=opts, threads=threads)
    for k, (p, g) in enumerate(zip(probs, got)):
        o = eopnp.RansacOptions(threshold_px=2.0, seed=eopnp.problem_seed(7, k))
        try:
            sol, info = eopnp.solve_ransac(*p, camera=CAM, ransac=o)
        except eopnp.PnpError as e:
            assert type(g) is type(e) and str(g) == str(e), k
            continue
        gs, gi = g
        assert gs == sol, k
        assert np.array_equal(gi["inliers"], info["inliers"])
        for key in ("num_inliers", "iterations", "hypotheses", "cost", "rmse", "rmse_px"):
            assert gi[key] == info[key], (k, key)
    assert isinstance(got[-1], eopnp.NoConsensusError)


def test_ransac_batch_normalised_focal(rng):
    probs = [(w, CAM.undistort(p)) for w, p in with_outliers(rng, 8)]
    got = eopnp.solve_ransac_batch(probs, focal=800.0, threads=2)
    for k, (p, g) in enumerate(zip(probs, got)):
        o = eopnp.RansacOptions(seed=eopnp.problem_seed(0, k))
        assert g[0] == eopnp.solve_ransac(*p, focal=(800.0, 800.0), ransac=o)[0]


def test_problem_seed():
    assert eopnp.problem_seed(0, 0) != eopnp.problem_seed(0, 1)
    assert eopnp.problem_seed(1, 0) != eopnp.problem_seed(0, 0)
    assert eopnp.problem_seed(2**64 - 1, 10**6) >= 0


def test_malformed_batch_raises(rng):
    good = batch(rng, 3)
    with pytest.raises(eopnp.InvalidInputError, match=r"problems\[1\] world.*\(N, 3\)"):
        eopnp.solve_batch([good[0], (np.zeros((12, 2)), good[1][1]), good[2]])
    with pytest.raises(eopnp.InvalidInputError, match=r"problems\[2\] image"):
        eopnp.solve_batch([good[0], good[1], (good[2][0], np.zeros(12))])
    with pytest.raises(eopnp.InvalidInputError, match=r"problems\[0\] weights"):
        eopnp.solve_batch([(good[0][0], good[0][1], np.ones((12, 2)))])
    with pytest.raises(eopnp.InputTypeError, match=r"problems\[1\] world"):
        eopnp.solve_batch([good[0], (np.full((12, 3), "a"), good[1][1])])
    with pytest.raises(eopnp.InvalidInputError, match=r"problems\[1\]: expected"):
        eopnp.solve_batch([good[0], good[1][0]])
    with pytest.raises(eopnp.InvalidInputError, match="sequence"):
        eopnp.solve_batch(5)
    with pytest.raises(eopnp.InvalidOptionError, match="2 cameras for 3 problems"):
        eopnp.solve_batch(good, camera=[CAM, CAM])
    with pytest.raises(eopnp.InvalidOptionError, match="threads"):
        eopnp.solve_batch(good, threads=0)
    with pytest.raises(eopnp.InvalidOptionError, match="exactly one"):
        eopnp.solve_ransac_batch(good)
    with pytest.raises(eopnp.InvalidOptionError, match="covariance"):
        eopnp.solve_batch(good, covariance=-1.0)
    # A RANSAC option out of range fails every problem alike: raised, as by solve_ransac.
    with pytest.raises(eopnp.InvalidOptionError, match="confidence"):
        eopnp.solve_ransac_batch(good, focal=800.0, ransac={"confidence": 2.0})
    assert eopnp.solve_batch([]) == []


def test_batch_releases_gil(rng):
    probs = batch(rng, 500, n=50)

    def make(k):
        many = probs * k
        return lambda: eopnp.solve_batch(many, threads=1)

    assert_releases_gil(make)


def test_batch_array_layouts(rng):
    """Any dtype, byte order and layout gives the same result as solve (the batch's fast
    path takes C-contiguous float64 only)."""
    world, image = problem(rng, 15, sigma_px=1.0)[:2]
    want = eopnp.solve(world, image)
    variants = [
        (world, image),
        (world.astype(">f8"), image.astype(">f8")),
        (np.asfortranarray(world), np.asfortranarray(image)),
        (np.repeat(world, 2, axis=0)[::2], np.repeat(image, 2, axis=0)[::2]),
        (world.astype(np.float32).astype(float), image),
        (world.tolist(), image.tolist()),
    ]
    got = eopnp.solve_batch(variants, threads=2)
    for k, (v, g) in enumerate(zip(variants, got)):
        assert g == eopnp.solve(*v), k
    assert got[1] == got[2] == got[3] == got[5] == want


@pytest.mark.parametrize("threads", [1, 2])
def test_batch_views_of_one_array(rng, threads):
    """Problems that are rows of stacked arrays (views of one base array, read in place)."""
    probs = batch(rng, 30)
    world = np.stack([w for w, _ in probs])
    image = np.stack([i for _, i in probs])
    weights = rng.uniform(0.5, 2.0, (30, 12))
    views = [(world[k], image[k], weights[k] if k % 3 == 0 else None) for k in range(30)]
    got = eopnp.solve_batch(views, threads=threads)
    for k, (v, g) in enumerate(zip(views, got)):
        assert g == eopnp.solve(*v), k


def test_solve_batch_results_untracked_by_gc(rng):
    """A batch's Solution objects hold no Python reference, so they are kept off the garbage
    collector's lists (no collection traverses them); they stay intact through collections."""
    import gc

    probs = batch(rng, count=30)
    got = eopnp.solve_batch(probs, threads=2)
    assert not any(gc.is_tracked(s) for s in got)
    gc.collect()
    assert got == [eopnp.solve(*p) for p in probs]
