"""The batch functions copy their inputs with the GIL held before releasing it: another Python
thread that overwrites the arrays while the problems are solved does not change the results."""

import threading
import time

import numpy as np
import pytest

import eopnp
from conftest import problem


def overwritten_during(call, arrays):
    """Runs ``call()`` while another thread overwrites every array of ``arrays`` with NaN as
    soon as it holds the GIL, which the call releases once it has read its inputs; returns the
    result and whether the writes ended before the call returned."""
    go = threading.Event()
    written = []

    def write():
        go.wait()
        for a in arrays:
            a[...] = np.nan
        written.append(time.perf_counter())

    th = threading.Thread(target=write)
    th.start()
    go.set()
    result = call()
    end = time.perf_counter()
    th.join()
    return result, written[0] < end


@pytest.mark.parametrize("threads", [1, 2])
def test_solve_batch(rng, threads):
    probs = [problem(rng, 50, sigma_px=1.0)[:2] for _ in range(3000)]
    want = eopnp.solve_batch(probs, threads=threads)
    arrays = [a for p in probs for a in p]
    got, during = overwritten_during(lambda: eopnp.solve_batch(probs, threads=threads), arrays)
    if not during:
        pytest.skip("the writer thread did not run during the call (a loaded machine)")
    assert np.isnan(probs[-1][0]).all()  # written
    assert got == want


@pytest.mark.parametrize("threads", [1, 2])
def test_solve_batch_arrays(rng, threads):
    probs = [problem(rng, 50, sigma_px=1.0)[:2] for _ in range(3000)]
    world = np.stack([w for w, _ in probs])
    image = np.stack([i for _, i in probs])
    weights = rng.uniform(0.5, 2.0, world.shape[:2])
    want = eopnp.solve_batch_arrays(world, image, weights, threads=threads)
    got, during = overwritten_during(
        lambda: eopnp.solve_batch_arrays(world, image, weights, threads=threads),
        [world, image, weights],
    )
    if not during:
        pytest.skip("the writer thread did not run during the call (a loaded machine)")
    assert np.isnan(world).all()
    assert got.ok.all() and not got.errors
    assert np.array_equal(got.R, want.R) and np.array_equal(got.t, want.t)


def test_solve_ransac_batch(rng):
    cam = eopnp.Camera.pinhole(800.0, 800.0, 320.0, 240.0)
    probs = [(w, cam.project(i)) for w, i in (problem(rng, 40)[:2] for _ in range(300))]
    want = eopnp.solve_ransac_batch(probs, camera=cam, threads=1)
    arrays = [a for p in probs for a in p]
    got, during = overwritten_during(
        lambda: eopnp.solve_ransac_batch(probs, camera=cam, threads=1), arrays
    )
    if not during:
        pytest.skip("the writer thread did not run during the call (a loaded machine)")
    assert [g[0] for g in got] == [w[0] for w in want]
