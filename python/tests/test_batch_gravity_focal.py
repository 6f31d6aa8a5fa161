"""``gravity=``, ``estimate_focal=`` and ``focal_range=`` on the batch forms (solve_batch,
solve_batch_arrays, solve_ransac_batch, solve_generalized_batch,
solve_generalized_ransac_batch): each entry equals the one-problem call with the same
arguments, bit for bit, whatever the thread count; a problem's own failure (a vertical its
images contradict) returned in place, an option error raised. And ``refine(estimate_focal=)``:
the focal length recovered from a wrong guess."""

import pickle

import numpy as np
import pytest

import eopnp
from conftest import problem, rodrigues, rotation_error_deg
from test_focal import focal_case
from test_gravity import CAMERA, DOWN, tilted
from test_rig import rig_case


def same(got, want, k):
    """`got` (a batch entry) is what the one-problem call gave: `want`, or raised `want`."""
    if isinstance(want, eopnp.PnpError):
        assert type(got) is type(want) and str(got) == str(want), k
        assert got.kind == want.kind and got.details == want.details, k
    else:
        assert isinstance(got, eopnp.Solution) and got == want, k


def call(f, *args, **kw):
    """f(*args, **kw), or the PnpError it raised."""
    try:
        return f(*args, **kw)
    except eopnp.PnpError as e:
        return e


def gravity_batch(rng, count=12, n=30):
    """Noisy pixel problems, each with a vertical measured to 0.05 degrees; problem 4's vertical
    is 3 degrees off (its images contradict it), problem 7 has none."""
    probs, gs = [], []
    for k in range(count):
        world, image, R, _ = problem(rng, n, sigma_px=1.0)
        probs.append((world, image * 800.0 + [320.0, 240.0]))
        off = 3.0 if k == 4 else 0.05
        gs.append(eopnp.Gravity(tilted(R @ DOWN, off, rng), DOWN, 0.1))
    gs[7] = None
    return probs, gs


@pytest.mark.parametrize("threads", [None, 1, 2])
def test_solve_batch_gravity_equals_solve(rng, threads):
    probs, gs = gravity_batch(rng)
    got = eopnp.solve_batch(probs, camera=CAMERA, gravity=gs, threads=threads)
    assert len(got) == len(probs)
    for k, (p, g) in enumerate(zip(probs, gs)):
        same(got[k], call(eopnp.solve, *p, camera=CAMERA, gravity=g), k)
    assert isinstance(got[4], eopnp.GravityMismatchError)
    # The vertical was used: with it, the pose differs from the one without.
    plain = eopnp.solve_batch(probs, camera=CAMERA, threads=threads)
    assert got[0] != plain[0] and got[7] == plain[7]
    # One Gravity for every problem.
    one = eopnp.solve_batch(probs[:3], camera=CAMERA, gravity=gs[0], threads=threads)
    for k, p in enumerate(probs[:3]):
        same(one[k], call(eopnp.solve, *p, camera=CAMERA, gravity=gs[0]), k)
    assert isinstance(one[1], eopnp.GravityMismatchError)


@pytest.mark.parametrize("threads", [1, 2])
def test_solve_batch_arrays_gravity_equals_solve(rng, threads):
    probs, gs = gravity_batch(rng)
    world = np.stack([p[0] for p in probs])
    pixels = np.stack([p[1] for p in probs])
    res = eopnp.solve_batch_arrays(world, pixels, camera=CAMERA, gravity=gs, threads=threads)
    assert res.focal is None
    for k, (p, g) in enumerate(zip(probs, gs)):
        want = call(eopnp.solve, *p, camera=CAMERA, gravity=g)
        if isinstance(want, eopnp.PnpError):
            assert not res.ok[k] and np.isnan(res.R[k]).all()
            same(res.error(k), want, k)
            continue
        assert res.ok[k]
        assert np.array_equal(res.R[k], want.R) and np.array_equal(res.t[k], want.t)
        assert res.cost[k] == want.cost and res.reprojection_rmse[k] == want.reprojection_rmse
    assert set(res.errors) == {4}


@pytest.mark.parametrize("threads", [None, 1, 2])
def test_solve_ransac_batch_gravity_equals_solve_ransac(rng, threads):
    probs, gs = [], []
    for _ in range(8):
        world, image, R, _ = problem(rng, 60, sigma_px=0.5)
        pixels = image * 800.0 + [320.0, 240.0]
        pixels[:30] = rng.uniform([0, 0], [640, 480], (30, 2))
        probs.append((world, pixels))
        gs.append(eopnp.Gravity(tilted(R @ DOWN, 0.05, rng), DOWN, 0.1))
    gs[2] = None
    opts = eopnp.RansacOptions(threshold_px=2.0, seed=5)
    for camera, focal, inputs in [
        (CAMERA, None, probs),
        (None, (800.0, 800.0), [(w, (p - [320.0, 240.0]) / 800.0) for w, p in probs]),
    ]:
        got = eopnp.solve_ransac_batch(
            inputs, camera=camera, focal=focal, gravity=gs, ransac=opts, threads=threads
        )
        for k, (p, g) in enumerate(zip(inputs, gs)):
            o = eopnp.RansacOptions(threshold_px=2.0, seed=eopnp.problem_seed(5, k))
            sol, info = eopnp.solve_ransac(*p, camera=camera, focal=focal, gravity=g, ransac=o)
            gs_, gi = got[k]
            assert gs_ == sol, k
            assert np.array_equal(gi["inliers"], info["inliers"])
            for key in ("num_inliers", "iterations", "hypotheses", "cost", "rmse", "rmse_px"):
                assert gi[key] == info[key], (k, key)
        # Samples of two: far fewer iterations than P3P's at 50 % outliers.
        plain = eopnp.solve_ransac_batch(
            inputs, camera=camera, focal=focal, ransac=opts, threads=threads
        )
        assert got[0][1]["iterations"] < plain[0][1]["iterations"]
        assert got[2][1]["iterations"] == plain[2][1]["iterations"]


def focal_batch(rng, count=10, n=30, sigma=0.0):
    """Pixel problems of focal lengths 400 to 2500 px, each with a guess 30 % too long."""
    probs, cams, fs = [], [], []
    for _ in range(count):
        f = float(rng.uniform(400, 2500))
        world, pixels, _, _ = focal_case(rng, n, f, sigma=sigma)
        probs.append((world, pixels))
        cams.append(eopnp.Camera("PINHOLE", [1.3 * f, 1.3 * f, 320.0, 240.0], 640, 480))
        fs.append(f)
    return probs, cams, fs


@pytest.mark.parametrize("threads", [None, 1, 2])
def test_solve_batch_focal_equals_solve(rng, threads):
    probs, cams, fs = focal_batch(rng, sigma=0.5)
    probs[3] = (probs[3][0][:3], probs[3][1][:3])  # too few points: returned in place
    got = eopnp.solve_batch(probs, camera=cams, estimate_focal=True, threads=threads)
    for k, (p, c) in enumerate(zip(probs, cams)):
        same(got[k], call(eopnp.solve, *p, camera=c, estimate_focal=True), k)
        if k != 3:
            assert abs(got[k].focal[0] / fs[k] - 1) < 0.05, k
    assert isinstance(got[3], eopnp.InvalidInputError)
    ranged = eopnp.solve_batch(probs, camera=cams, focal_range=(300.0, 3000.0), threads=threads)
    for k, (p, c) in enumerate(zip(probs, cams)):
        same(ranged[k], call(eopnp.solve, *p, camera=c, focal_range=(300.0, 3000.0)), k)
    assert eopnp.solve_batch(probs[:2], camera=cams[:2], threads=threads)[0].focal is None


@pytest.mark.parametrize("threads", [1, 2])
def test_solve_batch_arrays_focal_equals_solve(rng, threads):
    probs, cams, fs = focal_batch(rng, sigma=0.5)
    world = np.stack([p[0] for p in probs])
    pixels = np.stack([p[1] for p in probs])
    pixels[6, 2] = np.nan  # rejected, as solve rejects it
    res = eopnp.solve_batch_arrays(
        world, pixels, camera=cams, estimate_focal=True, threads=threads
    )
    assert res.focal.shape == (10, 2)
    for k, c in enumerate(cams):
        want = call(eopnp.solve, world[k], pixels[k], camera=c, estimate_focal=True)
        if k == 6:
            assert isinstance(want, eopnp.InvalidInputError) and not res.ok[k]
            same(res.error(k), want, k)
            assert np.isnan(res.focal[k]).all()
            continue
        assert np.array_equal(res.R[k], want.R) and np.array_equal(res.t[k], want.t), k
        assert tuple(res.focal[k]) == want.focal, k
        assert abs(res.focal[k, 0] / fs[k] - 1) < 0.05, k
    back = pickle.loads(pickle.dumps(res))
    assert np.array_equal(back.focal, res.focal, equal_nan=True)
    assert back.errors.keys() == res.errors.keys()


@pytest.mark.parametrize("threads", [None, 1, 2])
def test_solve_ransac_batch_focal_equals_solve_ransac(rng, threads):
    probs, cams, fs = [], [], []
    for _ in range(6):
        f = float(rng.uniform(500, 2000))
        world, pixels, _, _ = focal_case(rng, 80, f, sigma=1.0, outliers=0.4)
        probs.append((world, pixels))
        cams.append(eopnp.Camera("SIMPLE_PINHOLE", [0.7 * f, 320.0, 240.0], 640, 480))
        fs.append(f)
    got = eopnp.solve_ransac_batch(
        probs, camera=cams, estimate_focal=True, ransac={"seed": 3}, threads=threads
    )
    for k, (p, c) in enumerate(zip(probs, cams)):
        o = eopnp.RansacOptions(seed=eopnp.problem_seed(3, k))
        sol, info = eopnp.solve_ransac(*p, camera=c, estimate_focal=True, ransac=o)
        assert got[k][0] == sol and sol.focal is not None, k
        assert np.array_equal(got[k][1]["inliers"], info["inliers"])
        assert got[k][1]["rmse_px"] == info["rmse_px"]
        assert abs(sol.focal[0] / fs[k] - 1) < 0.05, k


@pytest.mark.parametrize("threads", [None, 2])
def test_generalized_batches_gravity_equal_single(threads):
    rng = np.random.default_rng(21)
    cases = [rig_case(rng, 3, 1.0, 60, sigma=1.0) for _ in range(5)]
    gs = [eopnp.Gravity(tilted(c.R @ DOWN, 0.05, rng), DOWN, 0.1) for c in cases]
    gs[1] = eopnp.Gravity(tilted(cases[1].R @ DOWN, 3.0, rng), DOWN, 0.1)  # contradicted
    gs[3] = None
    rigs = [c.rig for c in cases]  # one per problem (rig_case's camera yaws are jittered)
    probs = [(c.pixels, c.world, c.idx) for c in cases]
    got = eopnp.solve_generalized_batch(probs, rig=rigs, gravity=gs, threads=threads)
    for k, (p, r, g) in enumerate(zip(probs, rigs, gs)):
        same(got[k], call(eopnp.solve_generalized, *p, rig=r, gravity=g), k)
    assert isinstance(got[1], eopnp.GravityMismatchError)
    plain = eopnp.solve_generalized_batch(probs, rig=rigs, threads=threads)
    assert got[0] != plain[0] and got[3] == plain[3]
    got = eopnp.solve_generalized_ransac_batch(
        probs, rig=rigs, gravity=gs, ransac={"seed": 9}, threads=threads
    )
    for k, (p, r, g) in enumerate(zip(probs, rigs, gs)):
        o = eopnp.RansacOptions(seed=eopnp.problem_seed(9, k))
        want = call(eopnp.solve_generalized_ransac, *p, rig=r, gravity=g, ransac=o)
        if isinstance(want, eopnp.PnpError):
            same(got[k], want, k)
            continue
        assert got[k][0] == want[0], k
        assert np.array_equal(got[k][1]["inliers"], want[1]["inliers"])
        assert got[k][1]["rmse_px"] == want[1]["rmse_px"]


def test_batch_option_errors_raise(rng):
    probs, cams, _ = focal_batch(rng, count=3)
    normalised = [(w, (p - [320.0, 240.0]) / 800.0) for w, p in probs]
    g = eopnp.Gravity(DOWN, DOWN, 0.1)
    world = np.stack([p[0] for p in probs])
    pixels = np.stack([p[1] for p in probs])
    # An unknown focal length needs a camera, no vertical and a non-empty range: raised, with
    # the option's name, as by solve and solve_ransac.
    for run in [
        lambda: eopnp.solve_batch(normalised, estimate_focal=True),
        lambda: eopnp.solve_batch(probs, camera=cams, estimate_focal=True, gravity=g),
        lambda: eopnp.solve_batch(probs, camera=cams, focal_range=(2000.0, 1000.0)),
        lambda: eopnp.solve_batch_arrays(world, pixels / 800.0, estimate_focal=True),
        lambda: eopnp.solve_batch_arrays(world, pixels, camera=cams, focal_range=(5.0, np.nan)),
        lambda: eopnp.solve_ransac_batch(normalised, focal=800.0, estimate_focal=True),
        lambda: eopnp.solve_ransac_batch(probs, camera=cams, estimate_focal=True, gravity=g),
    ]:
        with pytest.raises(eopnp.InvalidOptionError) as e:
            run()
        assert e.value.option == "unknown_focal"
    # A bad gravity= argument: raised before anything is solved.
    for bad, match in [
        ("down", "gravity must be"),
        ([g, "down", None], "gravity must be"),
        ([g, g], "2 entries for 3 problems"),
        (5, "gravity must be"),
    ]:
        for run in [
            lambda: eopnp.solve_batch(probs, camera=CAMERA, gravity=bad),
            lambda: eopnp.solve_batch_arrays(world, pixels, camera=CAMERA, gravity=bad),
            lambda: eopnp.solve_ransac_batch(probs, camera=CAMERA, gravity=bad),
        ]:
            with pytest.raises(eopnp.InvalidOptionError, match=match) as e:
                run()
            assert e.value.option == "gravity"
    case = rig_case(np.random.default_rng(2), 2, 1.0, 20)
    with pytest.raises(eopnp.InvalidOptionError, match="gravity must be"):
        eopnp.solve_generalized_batch([(case.pixels, case.world, case.idx)], rig=case.rig, gravity=1)
    with pytest.raises(eopnp.InvalidOptionError, match="2 entries for 1 problems"):
        eopnp.solve_generalized_ransac_batch(
            [(case.pixels, case.world, case.idx)], rig=case.rig, gravity=[g, g]
        )
    # Every gravity entry None: as without gravity=.
    assert eopnp.solve_batch(probs, camera=CAMERA, gravity=[None] * 3) == eopnp.solve_batch(
        probs, camera=CAMERA
    )


def test_refine_estimates_the_focal_length():
    rng = np.random.default_rng(31)
    for f in (450.0, 1500.0, 2800.0):
        world, pixels, R, t = focal_case(rng, 40, f)
        guess = eopnp.Camera("PINHOLE", [0.75 * f, 0.75 * f, 320.0, 240.0], 640, 480)
        # The initial pose a little off the truth, the focal length 25 % short.
        initial = (rodrigues(rng.normal(0, 0.02, 3)) @ R, t + rng.normal(0, 0.02, 3))
        sol = eopnp.refine(world, pixels, initial, camera=guess, estimate_focal=True)
        fx, fy = sol.focal
        assert abs(fx / f - 1) < 1e-6 and fx == fy, f
        assert rotation_error_deg(sol.R, R) < 1e-6 and np.linalg.norm(sol.t - t) < 1e-6 * (
            1 + np.linalg.norm(t)
        )
        assert sol.source == "initial"
        # Without estimate_focal, the wrong focal length stays: the pose is off.
        fixed = eopnp.refine(world, pixels, initial, camera=guess)
        assert fixed.focal is None and rotation_error_deg(fixed.R, R) > 1e-3
        # A range holding the truth: the same; refine from solve's estimate: the same focal.
        ranged = eopnp.refine(
            world, pixels, initial, camera=guess, focal_range=(0.5 * f, 2.0 * f)
        )
        assert abs(ranged.focal[0] / f - 1) < 1e-6
        solved = eopnp.solve(world, pixels, camera=guess, estimate_focal=True)
        again = eopnp.refine(world, pixels, solved, camera=guess, estimate_focal=True)
        assert abs(again.focal[0] / solved.focal[0] - 1) < 1e-9
    back = pickle.loads(pickle.dumps(sol))
    assert back == sol and back.focal == sol.focal


def test_refine_focal_errors():
    rng = np.random.default_rng(32)
    world, pixels, R, t = focal_case(rng, 20, 1000.0)
    guess = eopnp.Camera("PINHOLE", [900.0, 900.0, 320.0, 240.0], 640, 480)
    g = eopnp.Gravity(R @ DOWN, DOWN, 0.1)
    for kw in [
        dict(estimate_focal=True),  # normalised input
        dict(camera=guess, estimate_focal=True, gravity=g),
        dict(camera=guess, focal_range=(1200.0, 1100.0)),
        dict(camera=guess, focal_range=(-1.0, 1100.0)),
    ]:
        img = pixels if "camera" in kw else (pixels - 320.0) / 900.0
        with pytest.raises(eopnp.InvalidOptionError) as e:
            eopnp.refine(world, img, (R, t), **kw)
        assert e.value.option == "unknown_focal", kw
    # A range that is not two numbers: the same typed error, from every function taking one.
    for bad in [(1.0, 2.0, 3.0), "wide", 5.0, (1.0, "x")]:
        for run in [
            lambda: eopnp.refine(world, pixels, (R, t), camera=guess, focal_range=bad),
            lambda: eopnp.solve(world, pixels, camera=guess, focal_range=bad),
            lambda: eopnp.solve_ransac(world, pixels, camera=guess, focal_range=bad),
            lambda: eopnp.solve_batch([(world, pixels)], camera=guess, focal_range=bad),
            lambda: eopnp.solve_ransac_batch([(world, pixels)], camera=guess, focal_range=bad),
            lambda: eopnp.solve_batch_arrays(
                world[None], pixels[None], camera=guess, focal_range=bad
            ),
        ]:
            with pytest.raises(eopnp.InvalidOptionError, match="two numbers") as e:
                run()
            assert e.value.option == "unknown_focal"
    # Any sequence of two numbers is a range.
    sol = eopnp.refine(world, pixels, (R, t), camera=guess, focal_range=np.array([500.0, 2e3]))
    assert abs(sol.focal[0] / 1000.0 - 1) < 1e-6
