"""The batch functions copy their inputs with the GIL held before releasing it: another Python
thread that overwrites the arrays while the problems are solved does not change the results."""

import threading
import time

import numpy as np
import pytest

import eopnp
from conftest import problem


#: Attempts before a test gives up on the race (a loaded machine can run the writer thread only
#: after the call returns; each attempt takes fresh copies of the inputs).
ATTEMPTS = 8


def overwritten_during(make):
    """Runs a call while another thread overwrites its arrays with NaN as soon as it holds the
    GIL, which the call releases once it has read its inputs. ``make()`` returns ``(call,
    arrays)`` with fresh arrays; up to ``ATTEMPTS`` attempts, until the writes end before the
    call returns. Returns the result, whether they did, and the arrays of the last attempt."""
    for _ in range(ATTEMPTS):
        call, arrays = make()
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
        if written[0] < end:
            return result, True, arrays
    return result, False, arrays


def copies(probs):
    return [tuple(a.copy() for a in p) for p in probs]


@pytest.mark.parametrize("threads", [1, 2])
def test_solve_batch(rng, threads):
    probs = [problem(rng, 50, sigma_px=1.0)[:2] for _ in range(3000)]
    want = eopnp.solve_batch(probs, threads=threads)

    def make():
        fresh = copies(probs)
        return (lambda: eopnp.solve_batch(fresh, threads=threads)), [a for p in fresh for a in p]

    got, during, arrays = overwritten_during(make)
    if not during:
        pytest.skip(f"the writer thread never ran during the call in {ATTEMPTS} attempts")
    assert np.isnan(arrays[-2]).all()  # written
    assert got == want


@pytest.mark.parametrize("threads", [1, 2])
def test_solve_batch_arrays(rng, threads):
    probs = [problem(rng, 50, sigma_px=1.0)[:2] for _ in range(3000)]
    world = np.stack([w for w, _ in probs])
    image = np.stack([i for _, i in probs])
    weights = rng.uniform(0.5, 2.0, world.shape[:2])
    want = eopnp.solve_batch_arrays(world, image, weights, threads=threads)

    def make():
        w, i, wt = world.copy(), image.copy(), weights.copy()
        return (lambda: eopnp.solve_batch_arrays(w, i, wt, threads=threads)), [w, i, wt]

    got, during, arrays = overwritten_during(make)
    if not during:
        pytest.skip(f"the writer thread never ran during the call in {ATTEMPTS} attempts")
    assert np.isnan(arrays[0]).all()
    assert got.ok.all() and not got.errors
    assert np.array_equal(got.R, want.R) and np.array_equal(got.t, want.t)


def test_solve_ransac_batch(rng):
    cam = eopnp.Camera.pinhole(800.0, 800.0, 320.0, 240.0)
    probs = [(w, cam.project(i)) for w, i in (problem(rng, 40)[:2] for _ in range(300))]
    want = eopnp.solve_ransac_batch(probs, camera=cam, threads=1)

    def make():
        fresh = copies(probs)
        call = lambda: eopnp.solve_ransac_batch(fresh, camera=cam, threads=1)  # noqa: E731
        return call, [a for p in fresh for a in p]

    got, during, _ = overwritten_during(make)
    if not during:
        pytest.skip(f"the writer thread never ran during the call in {ATTEMPTS} attempts")
    assert [g[0] for g in got] == [w[0] for w in want]
