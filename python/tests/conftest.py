"""Shared helpers of the eopnp Python tests: synthetic problems, rotation metrics, paths."""

import importlib
import math
import os
import pathlib
import threading
import time

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
DATA = REPO / "data"


def rodrigues(rvec):
    """Rotation matrix of an axis-angle vector."""
    rvec = np.asarray(rvec, dtype=float)
    th = np.linalg.norm(rvec)
    if th == 0.0:
        return np.eye(3)
    k = rvec / th
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(th) * kx + (1 - math.cos(th)) * kx @ kx


def rotation_error_deg(r, r_ref):
    """Largest angle between corresponding columns, degrees (the crate's metric)."""
    worst = 0.0
    for k in range(3):
        a, b = r[:, k], r_ref[:, k]
        worst = max(worst, math.degrees(math.atan2(np.linalg.norm(np.cross(a, b)), a @ b)))
    return worst


def log_so3(r):
    """Rotation vector of a rotation matrix (small and moderate angles)."""
    c = np.clip((np.trace(r) - 1) / 2, -1.0, 1.0)
    th = np.arccos(c)
    w = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]])
    return w / 2 if th < 1e-12 else w * th / (2 * np.sin(th))


def random_rotation(rng):
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    w, x, y, z = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def problem(rng, n, sigma_px=0.0, f=800.0, planar=False):
    """The paper's protocol: points in [-2, 2]^2 x [4, 8] in the camera frame (planar: z = 0
    in the world frame), a random pose, noise of sigma_px pixels at focal length f.

    Returns (world (n, 3), image (n, 2) normalised, R, t)."""
    r = random_rotation(rng)
    if planar:
        world = np.column_stack([rng.uniform(-2, 2, (n, 2)), np.zeros(n)])
        t = np.array([rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(4, 8)])
    else:
        cam = np.column_stack([rng.uniform(-2, 2, (n, 2)), rng.uniform(4, 8, n)])
        t = cam.mean(axis=0)
        world = (cam - t) @ r  # R^T (cam - t): R @ world + t = cam
    c = world @ r.T + t
    image = c[:, :2] / c[:, 2:]
    if sigma_px > 0:
        image = image + rng.normal(0.0, sigma_px / f, image.shape)
    return world, image, r, t


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def peers_required():
    """Whether the comparisons with other packages and with the CLI must run: scripts/test.sh
    (CI) sets EOPNP_REQUIRE_PEERS=1, under which a missing peer is an error, not a skip."""
    return os.environ.get("EOPNP_REQUIRE_PEERS") == "1"


def require(module):
    """`import module` for a comparison test: skipped where it is not installed, an
    ImportError (a test error) when peers_required()."""
    if peers_required():
        return importlib.import_module(module)
    return pytest.importorskip(module)


@pytest.fixture(scope="session")
def cli():
    """The eopnp CLI built by `cargo test --workspace --release` (path in $EOPNP_CLI, as
    scripts/test.sh sets it): skipped when unset (an error under EOPNP_REQUIRE_PEERS=1), an
    error when set but missing."""
    path = os.environ.get("EOPNP_CLI")
    if not path:
        if peers_required():
            raise RuntimeError("EOPNP_CLI not set and EOPNP_REQUIRE_PEERS=1")
        pytest.skip("EOPNP_CLI not set (scripts/test.sh sets it to the release CLI)")
    if not os.path.isfile(path):
        raise FileNotFoundError(f"EOPNP_CLI={path} does not exist")
    return path


def assert_releases_gil(make_call, seconds=0.2):
    """Asserts that a call releases the GIL while it works, on a machine of any speed.

    `make_call(k)` returns a call whose work grows with k (e.g. a batch of k copies of some
    problems). k is doubled until one call takes at least `seconds` (timed alone); that call
    then runs while a Python thread ticks (appends a timestamp, sleeps 1 ms) and the ticks
    stamped during the call are counted. With the GIL released the ticker runs throughout:
    about one tick per millisecond, 200 in 0.2 s (at least 10 are asserted: the ticker may get
    a core only now and then on a loaded machine). With the GIL held it cannot run at all
    during the call: at most the tick in progress when the call started, whatever its length.
    """
    k = 1
    while True:
        call = make_call(k)
        start = time.perf_counter()
        call()
        if time.perf_counter() - start >= seconds:
            break
        assert k < 1 << 16, "the call does not grow with k"
        k *= 2
    ticks = []
    stop = threading.Event()

    def tick():
        while not stop.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    th = threading.Thread(target=tick)
    th.start()
    try:
        time.sleep(0.01)  # the ticker is running
        start = time.perf_counter()
        call()
        end = time.perf_counter()
    finally:
        stop.set()
        th.join()
    during = sum(start < t < end for t in ticks)
    assert end - start >= seconds / 4, f"the call took {end - start:.3f} s: too short to tell"
    assert during >= 10, (
        f"{during} ticks of the Python thread during the {end - start:.3f} s call (k = {k}): "
        "the GIL was held"
    )
