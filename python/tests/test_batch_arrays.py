"""solve_batch_arrays: every row equals solve on that problem to the last bit (with 1 and 2
threads and rayon's default pool), failures in place with the exception solve raises, bad
shapes and dtypes raised before solving, any layout read as float64, the GIL released."""

import pickle

import numpy as np
import pytest

import eopnp
from conftest import assert_releases_gil, problem

CAM = eopnp.Camera("SIMPLE_RADIAL", [800.0, 320.0, 240.0, -0.05], 640, 480)


def stacked(rng, count=40, n=12, sigma_px=1.0):
    probs = [problem(rng, n, sigma_px=sigma_px)[:2] for _ in range(count)]
    return np.stack([w for w, _ in probs]), np.stack([i for _, i in probs])


def assert_row_equals_solve(res, i, *args, **kwargs):
    """Row i of res against solve(*args, **kwargs): the same numbers, or the same exception."""
    try:
        want = eopnp.solve(*args, **kwargs)
    except eopnp.PnpError as e:
        got = res.error(i)
        assert type(got) is type(e) and str(got) == str(e), i
        assert got.kind == e.kind and got.details == e.details, i
        assert not res.ok[i] and res.errors[i] is got, i
        assert np.isnan(res.R[i]).all() and np.isnan(res.t[i]).all(), i
        assert np.isnan(res.cost[i]) and np.isnan(res.reprojection_rmse[i]), i
        return False
    assert res.ok[i] and res.error(i) is None and i not in res.errors, i
    assert np.array_equal(res.R[i], want.R) and np.array_equal(res.t[i], want.t), i
    assert res.cost[i] == want.cost, i
    assert res.reprojection_rmse[i] == want.reprojection_rmse, i
    if want.covariance is None:
        assert res.covariance is None and res.sigma is None
    else:
        assert np.array_equal(res.covariance[i], want.covariance), i
        assert res.sigma[i] == want.sigma, i
    return True


@pytest.mark.parametrize("threads", [None, 1, 2])
def test_equals_solve(rng, threads):
    world, image = stacked(rng)
    image[7] = 0.1  # degenerate: coincident image points
    world[9, 4, 1] = np.nan  # NonFinite, the library's check
    got = eopnp.solve_batch_arrays(world, image, threads=threads)
    assert isinstance(got, eopnp.BatchResult) and len(got) == 40
    assert got.R.shape == (40, 3, 3) and got.t.shape == (40, 3)
    assert got.cost.shape == got.reprojection_rmse.shape == got.ok.shape == (40,)
    assert got.R.dtype == np.float64 and got.ok.dtype == np.bool_
    solved = [assert_row_equals_solve(got, i, world[i], image[i]) for i in range(40)]
    assert sum(solved) == 38 and sorted(got.errors) == [7, 9]
    assert isinstance(got.errors[7], eopnp.DegenerateError)
    assert got.errors[9].kind == "NonFinite" and got.errors[9].index == 4
    assert got.error(-31) is got.errors[9]
    with pytest.raises(IndexError):
        got.error(40)


@pytest.mark.parametrize("threads", [1, 2])
def test_weighted_options(rng, threads):
    world, image = stacked(rng, 20)
    weights = rng.uniform(0.5, 2.0, (20, 12))
    weights[3, 2] = -1.0  # InvalidWeight
    opts = dict(refinement="algebraic", planar="nonplanar", loss=("huber", 0.01))
    got = eopnp.solve_batch_arrays(world, image, weights, threads=threads, **opts)
    for i in range(20):
        assert_row_equals_solve(got, i, world[i], image[i], weights[i], **opts)
    assert got.errors[3].kind == "InvalidWeight" and got.errors[3].index == 2


@pytest.mark.parametrize("threads", [1, 2])
def test_pixels_cameras_covariance(rng, threads):
    world, image = stacked(rng, 20)
    pixels = np.stack([CAM.project(im) for im in image])
    pixels[2, 4] = np.nan  # rejected as solve rejects it
    other = eopnp.Camera.pinhole(700.0, 700.0, 320.0, 240.0)
    cams = [CAM if i % 2 else other for i in range(20)]
    for camera in (CAM, cams):
        got = eopnp.solve_batch_arrays(
            world, pixels, camera=camera, covariance="estimated", threads=threads
        )
        assert got.covariance.shape == (20, 6, 6) and got.sigma.shape == (20,)
        for i in range(20):
            cam = camera if isinstance(camera, eopnp.Camera) else cams[i]
            assert_row_equals_solve(
                got, i, world[i], pixels[i], camera=cam, covariance="estimated"
            )
        assert got.errors[2].kind == "NonFinite" and got.errors[2].input == "image"
        assert np.isnan(got.covariance[2]).all() and np.isnan(got.sigma[2])


def test_threads_identical(rng):
    world, image = stacked(rng, 200, n=30, sigma_px=2.0)
    image[50] = 0.0
    a = eopnp.solve_batch_arrays(world, image, covariance=1.0, threads=1)
    b = eopnp.solve_batch_arrays(world, image, covariance=1.0, threads=2)
    for name in ("R", "t", "cost", "reprojection_rmse", "ok", "covariance", "sigma"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    assert list(a.errors) == list(b.errors) == [50]
    assert str(a.errors[50]) == str(b.errors[50])


def test_padding_with_zero_weights(rng):
    """Problems with fewer points, padded with weight 0: as if the padding were dropped."""
    world, image = stacked(rng, 6, n=15)
    weights = np.ones((6, 15))
    sizes = [15, 10, 6, 12, 3, 8]
    for i, n in enumerate(sizes):
        weights[i, n:] = 0.0
    got = eopnp.solve_batch_arrays(world, image, weights, threads=2)
    for i, n in enumerate(sizes):
        assert_row_equals_solve(got, i, world[i, :n], image[i, :n], weights[i, :n])
    assert got.errors[4].kind == "TooFewPoints"


def test_too_few_points_and_empty(rng):
    world, image = stacked(rng, 3, n=3)
    got = eopnp.solve_batch_arrays(world, image)
    assert not got.ok.any() and all(e.kind == "TooFewPoints" for e in got.errors.values())
    for i in range(3):
        assert_row_equals_solve(got, i, world[i], image[i])
    empty = eopnp.solve_batch_arrays(np.zeros((0, 10, 3)), np.zeros((0, 10, 2)))
    assert len(empty) == 0 and empty.R.shape == (0, 3, 3) and empty.errors == {}


def test_layouts_and_dtypes(rng):
    world, image = stacked(rng, 8, n=15)
    want = eopnp.solve_batch_arrays(world, image)
    variants = [
        (world.astype(">f8"), image.astype(">f8")),
        (np.asfortranarray(world), np.asfortranarray(image)),
        (np.repeat(world, 2, axis=1)[:, ::2], np.repeat(image, 2, axis=1)[:, ::2]),
        (world.tolist(), image.tolist()),
        (np.round(world * 100).astype(np.int32), np.round(image * 100).astype(np.int64) / 100),
    ]
    for k, (w, im) in enumerate(variants):
        got = eopnp.solve_batch_arrays(w, im, threads=2)
        wf, imf = np.asarray(w, dtype=float), np.asarray(im, dtype=float)
        for i in range(8):
            assert_row_equals_solve(got, i, wf[i], imf[i])
        if k < 4:
            assert np.array_equal(got.R, want.R) and np.array_equal(got.t, want.t), k


def test_bad_input_raises(rng):
    world, image = stacked(rng, 3)
    with pytest.raises(eopnp.InvalidInputError, match=r"world: .*\(B, N, 3\).*\(3, 12, 2\)"):
        eopnp.solve_batch_arrays(image, image)
    with pytest.raises(eopnp.InvalidInputError, match=r"world: .*got shape \(12, 3\)"):
        eopnp.solve_batch_arrays(world[0], image[0])
    with pytest.raises(eopnp.InvalidInputError, match=r"image: .*\(3, 12, 2\).*\(2, 12, 2\)"):
        eopnp.solve_batch_arrays(world, image[:2])
    with pytest.raises(eopnp.InvalidInputError, match=r"image: .*got shape \(3, 11, 2\)"):
        eopnp.solve_batch_arrays(world, image[:, :11])
    with pytest.raises(eopnp.InvalidInputError, match=r"weights: .*\(3, 12\).*\(3, 12, 1\)"):
        eopnp.solve_batch_arrays(world, image, np.ones((3, 12, 1)))
    with pytest.raises(eopnp.InputTypeError, match=r"world: expected real numbers"):
        eopnp.solve_batch_arrays(np.full((3, 12, 3), "a"), image)
    with pytest.raises(eopnp.InputTypeError, match=r"weights"):
        eopnp.solve_batch_arrays(world, image, np.full((3, 12), 1 + 1j))
    with pytest.raises(eopnp.InvalidInputError, match=r"image: cannot be read"):
        eopnp.solve_batch_arrays(world, [[[0.0, 0.0]], [[0.0]]])
    with pytest.raises(eopnp.InvalidOptionError, match="2 cameras for 3 problems"):
        eopnp.solve_batch_arrays(world, image, camera=[CAM, CAM])
    with pytest.raises(eopnp.InvalidOptionError, match="camera must be"):
        eopnp.solve_batch_arrays(world, image, camera=[CAM, CAM, "x"])
    with pytest.raises(eopnp.InvalidOptionError, match="threads"):
        eopnp.solve_batch_arrays(world, image, threads=0)
    with pytest.raises(eopnp.InvalidOptionError, match="covariance"):
        eopnp.solve_batch_arrays(world, image, covariance=-1.0)
    with pytest.raises(eopnp.InvalidOptionError, match="refinement"):
        eopnp.solve_batch_arrays(world, image, refinement="fast")


def test_pickle(rng):
    world, image = stacked(rng, 5)
    image[1] = 0.0
    got = eopnp.solve_batch_arrays(world, image, covariance=1.0)
    back = pickle.loads(pickle.dumps(got))
    assert np.array_equal(back.R, got.R, equal_nan=True)
    assert np.array_equal(back.covariance, got.covariance, equal_nan=True)
    assert np.array_equal(back.ok, got.ok) and list(back.errors) == [1]
    assert type(back.errors[1]) is type(got.errors[1])
    assert str(back.errors[1]) == str(got.errors[1])
    assert repr(back) == "BatchResult(5 problems, 4 solved, 1 failed)"


def test_releases_gil(rng):
    world, image = stacked(rng, 500, n=50)

    def make(k):
        w, i = np.tile(world, (k, 1, 1)), np.tile(image, (k, 1, 1))
        return lambda: eopnp.solve_batch_arrays(w, i, threads=1)

    assert_releases_gil(make)
