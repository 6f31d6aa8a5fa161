"""Multi-camera rigs: eopnp.Rig, solve_generalized, solve_generalized_ransac,
refine_generalized and their batches, on synthetic rigs of 2 to 6 cameras looking outward
(baselines 0.1 to 2 units, points 2 to 30 units from their camera, pinhole and distorting
cameras), as the Rust tests (tests/rig.rs) build them; and against pycolmap's
estimate_and_refine_generalized_absolute_pose on the same noisy problems (a comparison-only
package: skipped where it is not installed, an error under EOPNP_REQUIRE_PEERS=1)."""

import pickle

import numpy as np
import pytest

import eopnp
from conftest import (
    assert_releases_gil,
    log_so3,
    random_rotation,
    require,
    rodrigues,
    rotation_error_deg,
)

PINHOLE = eopnp.Camera("PINHOLE", [500.0, 520.0, 320.0, 240.0], 640, 480)
RADIAL = eopnp.Camera("SIMPLE_RADIAL", [500.0, 320.0, 240.0, -0.1], 640, 480)


class Case:
    """A rig problem and its truth: pixels (N, 2), world points (N, 3), camera indices (N,),
    the rig's cameras and cams_from_rig as (R_k, t_k) pairs, the rig, rig_from_world (R, t)."""

    def __init__(self, pixels, world, idx, cameras, poses, R, t):
        self.pixels, self.world, self.idx = pixels, world, idx
        self.cameras, self.poses = cameras, poses
        self.rig = eopnp.Rig(cameras, poses)
        self.R, self.t = R, t


def rig_case(rng, n_cams, baseline, n, sigma=0.0, distort=False):
    """n_cams cameras on a circle of diameter `baseline`, each looking outward (yaw 2 pi k /
    n_cams, jittered), camera axes z outward, x to its right, y down; a random rig pose; n
    points, each seen by one camera (round robin), 2 to 30 units away within a 90-degree field
    of view; pixel noise sigma. Distorting cameras (SIMPLE_RADIAL, k = -0.1) when `distort`."""
    cameras, poses = [], []
    for k in range(n_cams):
        yaw = 2 * np.pi * k / n_cams + rng.uniform(-0.1, 0.1)
        z = np.array([np.sin(yaw), 0.0, np.cos(yaw)])
        x = np.array([np.cos(yaw), 0.0, -np.sin(yaw)])
        rk = np.stack([x, np.cross(z, x), z])
        centre = z * 0.5 * baseline
        poses.append((rk, -rk @ centre))  # x_cam = R_k x_rig + t_k
        cameras.append(RADIAL if distort else PINHOLE)
    R, t = random_rotation(rng), rng.uniform(-2, 2, 3)
    idx = np.arange(n) % n_cams
    m = np.column_stack([rng.uniform(-0.5, 0.5, n), rng.uniform(-0.4, 0.4, n)])
    depth = rng.uniform(2, 30, n)
    p_cam = np.column_stack([m * depth[:, None], depth])
    world = np.empty((n, 3))
    pixels = np.empty((n, 2))
    for i in range(n):
        rk, tk = poses[idx[i]]
        x_rig = rk.T @ (p_cam[i] - tk)
        world[i] = R.T @ (x_rig - t)  # x_rig = R X + t
        pixels[i] = cameras[idx[i]].project(m[i : i + 1])[0]
    pixels += rng.normal(0.0, sigma, pixels.shape)
    return Case(pixels, world, idx, cameras, poses, R, t)


def pixel_residuals(case, R, t, mask=None):
    """Each correspondence's pixel error through its camera at the rig pose (R, t)."""
    out = np.empty(len(case.world))
    for i in range(len(case.world)):
        rk, tk = case.poses[case.idx[i]]
        p = rk @ (R @ case.world[i] + t) + tk
        px = case.cameras[case.idx[i]].project((p[:2] / p[2])[None])[0]
        out[i] = np.linalg.norm(px - case.pixels[i])
    return out if mask is None else out[mask]


def test_rig_class():
    rng = np.random.default_rng(1)
    case = rig_case(rng, 3, 1.0, 12)
    (r0, t0), (r1, t1), (r2, t2) = case.poses
    rig = case.rig
    assert len(rig) == 3 and rig.cameras == case.cameras
    want = np.stack([np.column_stack([r, t]) for r, t in case.poses])
    assert rig.cams_from_rig.shape == (3, 3, 4)
    np.testing.assert_allclose(rig.cams_from_rig, want, rtol=0, atol=1e-15)
    np.testing.assert_allclose(rig.centres, [-r.T @ t for r, t in case.poses], atol=1e-15)
    # Every pose form of `refine`'s `initial`, and a stacked (K, 3, 4) array.
    q1 = eopnp.Rig([PINHOLE], [(r1, t1)])
    forms = [
        (r1, t1),
        [r1, t1],
        (rotation_vector(r1), t1),
        (quaternion_wxyz(r1), t1),
        np.column_stack([r1, t1]),
        np.vstack([np.column_stack([r1, t1]), [0, 0, 0, 1]]),
    ]
    for form in forms:
        other = eopnp.Rig([PINHOLE], [form])
        np.testing.assert_allclose(other.cams_from_rig, q1.cams_from_rig, rtol=0, atol=1e-14)
    again = eopnp.Rig(rig.cameras, rig.cams_from_rig)  # a (K, 3, 4) array of poses
    np.testing.assert_allclose(again.cams_from_rig, rig.cams_from_rig, rtol=0, atol=1e-15)
    # A Solution is a pose too (its R, t).
    sol = eopnp.solve_generalized(case.pixels, case.world, case.idx, rig=rig)
    np.testing.assert_allclose(
        eopnp.Rig([PINHOLE], [sol]).cams_from_rig[0], sol.Rt, rtol=0, atol=1e-15
    )
    # ==, repr, pickling (exact: the same solves).
    assert rig == eopnp.Rig(case.cameras, case.poses) and rig != q1 and rig != "rig"
    assert repr(rig).startswith("Rig(3 cameras: PINHOLE at (")
    assert repr(eopnp.Rig([RADIAL], [np.eye(4)])) == "Rig(1 camera: SIMPLE_RADIAL at (0, 0, 0))"
    back = pickle.loads(pickle.dumps(rig))
    assert back == rig and np.array_equal(back.cams_from_rig, rig.cams_from_rig)
    assert eopnp.solve_generalized(case.pixels, case.world, case.idx, rig=back) == sol
    with pytest.raises(AttributeError):
        rig.cameras = []  # immutable


def rotation_vector(r):
    return log_so3(r)


def quaternion_wxyz(r):
    w = np.sqrt(max(0.0, 1 + np.trace(r))) / 2
    if w > 1e-3:
        return np.array(
            [w, (r[2, 1] - r[1, 2]) / (4 * w), (r[0, 2] - r[2, 0]) / (4 * w),
             (r[1, 0] - r[0, 1]) / (4 * w)]
        )
    return np.array([w, *np.sqrt(np.maximum(0.0, 1 + 2 * np.diag(r) - np.trace(r))) / 2])


def test_rig_errors():
    r, t = np.eye(3), np.zeros(3)
    with pytest.raises(eopnp.InvalidOptionError, match="at least one camera") as e:
        eopnp.Rig([], [])
    assert e.value.option == "cameras"
    with pytest.raises(eopnp.InvalidOptionError, match="1 poses for 2 cameras") as e:
        eopnp.Rig([PINHOLE, RADIAL], [(r, t)])
    assert e.value.option == "cams_from_rig"
    # A single (3, 4) matrix is not a sequence of poses: its rows are counted as poses.
    with pytest.raises(eopnp.InvalidOptionError, match="3 poses for 1 cameras"):
        eopnp.Rig([PINHOLE], np.column_stack([r, t]))
    with pytest.raises(eopnp.InvalidOptionError, match=r"cameras\[1\]: expected a Camera"):
        eopnp.Rig([PINHOLE, "PINHOLE"], [(r, t), (r, t)])
    with pytest.raises(eopnp.InvalidOptionError, match=r"cams_from_rig\[1\]: the 3x3 matrix"):
        eopnp.Rig([PINHOLE, PINHOLE], [(r, t), (2 * r, t)])
    with pytest.raises(eopnp.InvalidOptionError, match=r"cams_from_rig\[0\]: the pose is not"):
        eopnp.Rig([PINHOLE], [(r, [0, np.nan, 0])])
    with pytest.raises(eopnp.InvalidOptionError, match="expected a sequence of Camera"):
        eopnp.Rig(PINHOLE, [(r, t)])
    with pytest.raises(eopnp.InvalidOptionError, match=r"cams_from_rig\[0\]: expected a"):
        eopnp.Rig([PINHOLE], ["pose"])


@pytest.mark.parametrize("distort", [False, True])
def test_noise_free_rigs_give_the_exact_pose(distort):
    """60 noise-free rigs, 2 to 6 cameras, baselines 0.1 to 2, N = 4 to 100: the rotation
    within 1e-8 degrees; both ways of giving the rig give the same Solution."""
    rng = np.random.default_rng(10 + distort)
    worst = 0.0
    for k in range(60):
        n_cams = 2 + k % 5
        n = max(n_cams, [4, 5, 6, 10, 30, 100][k % 6])
        case = rig_case(rng, n_cams, [0.1, 0.5, 1.0, 2.0][k % 4], n, 0.0, distort)
        sol = eopnp.solve_generalized(
            case.pixels, case.world, case.idx, case.poses, case.cameras
        )
        err = rotation_error_deg(sol.R, case.R)
        worst = max(worst, err)
        assert err < 1e-8, (k, n_cams, n, err)
        assert np.linalg.norm(sol.t - case.t) < 1e-8 * (1 + np.linalg.norm(case.t))
        assert sol.converged and sol.used == n and sol.source in (
            "generalized", "gp3p", "case1", "case2", "case3", "case4", "p3p"
        )
        assert sol == eopnp.solve_generalized(
            case.pixels, case.world, list(case.idx), rig=case.rig
        )
    print(f"rig, noise-free, distort={distort}: worst rotation error {worst:.1e} deg")


def test_one_camera_is_the_central_problem():
    """Every point in one camera of the rig: solve(..., camera=) with that camera, composed
    with its pose in the rig (x_cam = R_k (R X + t) + t_k), to 1e-10 degrees; a rig of that
    camera alone at the identity gives solve's pose bit for bit."""
    rng = np.random.default_rng(5)
    for k in range(20):
        case = rig_case(rng, 3, 0.5, 30, 1.0, k % 2 == 0)
        keep = case.idx == 1
        world, pixels = case.world[keep], case.pixels[keep]
        sol = eopnp.solve_generalized(pixels, world, case.idx[keep], rig=case.rig)
        cam = case.cameras[1]
        central = eopnp.solve(world, pixels, camera=cam)
        rk, tk = case.poses[1]
        assert rotation_error_deg(rk @ sol.R, central.R) < 1e-10
        np.testing.assert_allclose(rk @ sol.t + tk, central.t, rtol=0, atol=1e-9)
        alone = eopnp.Rig([cam], [np.eye(4)])
        s1 = eopnp.solve_generalized(pixels, world, np.zeros(len(world), int), rig=alone)
        assert np.array_equal(s1.R, central.R) and np.array_equal(s1.t, central.t)
        assert s1.cost == central.cost and s1.source == central.source


def test_noisy_rig_is_the_ml_pose():
    """sigma = 1 px: the default pose's pixel cost is no higher than that of
    refine_generalized from the truth (the maximum-likelihood pose), covariance included."""
    rng = np.random.default_rng(7)
    for k in range(30):
        case = rig_case(rng, 2 + k % 5, 0.1 + 0.3 * (k % 7), 30, 1.0, k % 2 == 1)
        sol = eopnp.solve_generalized(
            case.pixels, case.world, case.idx, rig=case.rig, covariance=1.0
        )
        ml = eopnp.refine_generalized(
            (case.R, case.t), case.pixels, case.world, case.idx, rig=case.rig
        )
        a = np.sum(pixel_residuals(case, sol.R, sol.t) ** 2)
        b = np.sum(pixel_residuals(case, ml.R, ml.t) ** 2)
        assert a <= b * (1 + 1e-9), (k, a, b)
        assert sol.cost == pytest.approx(a, rel=1e-9)
        assert rotation_error_deg(sol.R, ml.R) < 1e-6
        assert sol.covariance.shape == (6, 6) and sol.sigma == 1.0
        assert ml.source == "initial" and ml.converged


def test_refine_generalized():
    rng = np.random.default_rng(8)
    case = rig_case(rng, 4, 1.0, 40, 1.0, True)
    best = eopnp.solve_generalized(case.pixels, case.world, case.idx, rig=case.rig)
    start_r = rodrigues(np.radians([1.0, -0.5, 0.7])) @ case.R
    for start in [(start_r, case.t + 0.05), np.column_stack([start_r, case.t]), best]:
        ref = eopnp.refine_generalized(
            start, case.pixels, case.world, case.idx, case.poses, case.cameras
        )
        assert ref.source == "initial" and ref.converged
        assert rotation_error_deg(ref.R, best.R) < 1e-8
        np.testing.assert_allclose(ref.t, best.t, rtol=0, atol=1e-8)
    # pycolmap's inlier_mask: weights of 0 and 1 (a point of weight 0 is dropped exactly).
    mask = np.arange(40) % 3 != 0
    a = eopnp.refine_generalized(
        best, case.pixels, case.world, case.idx, rig=case.rig, weights=mask.astype(float)
    )
    b = eopnp.refine_generalized(
        best, case.pixels[mask], case.world[mask], case.idx[mask], rig=case.rig
    )
    assert rotation_error_deg(a.R, b.R) < 1e-10 and a.used == b.used == mask.sum()
    with pytest.raises(eopnp.InvalidOptionError, match="rig_from_world") as e:
        eopnp.refine_generalized(
            (np.eye(3), [np.nan, 0, 0]), case.pixels, case.world, case.idx, rig=case.rig
        )
    assert e.value.option == "rig_from_world"
    with pytest.raises(eopnp.InvalidOptionError, match="rig_from_world"):
        eopnp.refine_generalized("pose", case.pixels, case.world, case.idx, rig=case.rig)
    with pytest.raises(TypeError, match="refinement"):
        eopnp.refine_generalized(
            best, case.pixels, case.world, case.idx, rig=case.rig, refinement="algebraic"
        )


def outliers(rng, case, fraction):
    """Moves the world points of the first `fraction` of the correspondences by up to 10 units
    in each coordinate; returns how many."""
    k = int(fraction * len(case.world))
    case.world = case.world.copy()
    case.world[:k] += rng.uniform(-10, 10, (k, 3))
    return k


def test_ransac_with_half_outliers():
    rng = np.random.default_rng(9)
    for k in range(12):
        case = rig_case(rng, 2 + k % 5, 1.0, 200, 1.0, k % 2 == 0)
        bad = outliers(rng, case, 0.5)
        sol, info = eopnp.solve_generalized_ransac(
            case.pixels, case.world, case.idx, case.poses, case.cameras, ransac={"seed": k}
        )
        assert rotation_error_deg(sol.R, case.R) < 0.5, k
        inl = info["inliers"]
        assert inl[:bad].sum() <= bad // 50 and inl[bad:].mean() > 0.95
        assert set(info) == {
            "inliers", "num_inliers", "inlier_ratio", "iterations", "hypotheses",
            "local_fits", "final_fits", "cost", "rmse", "rmse_px", "micros",
        }
        assert info["num_inliers"] == inl.sum() and inl.shape == (200,)
        rmse = np.sqrt(np.mean(pixel_residuals(case, sol.R, sol.t, inl) ** 2))
        assert info["rmse_px"] == pytest.approx(rmse, rel=1e-9) and 0.5 < rmse < 2.0
        # The same with a prebuilt Rig.
        again, info2 = eopnp.solve_generalized_ransac(
            case.pixels, case.world, case.idx, rig=case.rig, ransac={"seed": k}
        )
        assert again == sol and np.array_equal(info2["inliers"], inl)


def test_errors():
    rng = np.random.default_rng(11)
    case = rig_case(rng, 3, 1.0, 20)
    args = (case.pixels, case.world)
    for bad_camera in (3, 7, -1):
        idx = case.idx.copy()
        idx[7] = bad_camera
        with pytest.raises(eopnp.InvalidInputError, match=f"correspondence 7 is in camera "
                           f"{bad_camera}, which the rig does not have") as e:
            eopnp.solve_generalized(*args, idx, rig=case.rig)
        assert (e.value.kind, e.value.index, e.value.camera) == ("UnknownCamera", 7, bad_camera)
        assert e.value.details == {"index": 7, "camera": bad_camera}
        back = pickle.loads(pickle.dumps(e.value))
        assert (type(back), back.kind, back.index, back.camera) == (
            eopnp.InvalidInputError, "UnknownCamera", 7, bad_camera
        )
    with pytest.raises(eopnp.InvalidInputError, match="19 camera indices for 20") as e:
        eopnp.solve_generalized(*args, case.idx[:19], rig=case.rig)
    assert (e.value.kind, e.value.indices, e.value.points) == ("CameraIndicesLength", 19, 20)
    with pytest.raises(eopnp.InvalidInputError) as e:
        eopnp.solve_generalized(case.pixels[:3], case.world[:3], case.idx[:3], rig=case.rig)
    assert (e.value.kind, e.value.got, e.value.need) == ("TooFewPoints", 3, 4)
    with pytest.raises(eopnp.InvalidInputError) as e:
        eopnp.solve_generalized(case.pixels[:19], case.world, case.idx, rig=case.rig)
    assert e.value.kind == "LengthMismatch"
    with pytest.raises(eopnp.InputTypeError, match="camera_idxs: expected integers"):
        eopnp.solve_generalized(*args, case.idx.astype(float), rig=case.rig)
    with pytest.raises(eopnp.InvalidInputError, match=r"camera_idxs: expected an array of shape"):
        eopnp.solve_generalized(*args, case.idx[:, None], rig=case.rig)
    # A NaN pixel is rejected, also when every point is in one camera (solve(camera=) too).
    one = case.idx == 0
    pixels = case.pixels[one].copy()
    pixels[2] = np.nan
    for idx in (case.idx[one], np.zeros(one.sum(), int)):
        with pytest.raises(eopnp.InvalidInputError) as e:
            eopnp.solve_generalized(pixels, case.world[one], idx, rig=case.rig)
        assert (e.value.kind, e.value.index, e.value.input) == ("NonFinite", 2, "image")
    with pytest.raises(eopnp.InvalidInputError) as e:
        eopnp.solve_generalized(*args, case.idx, rig=case.rig, weights=-np.ones(20))
    assert (e.value.kind, e.value.index) == ("InvalidWeight", 0)
    # The rig: one of the two forms.
    for kwargs, what in [
        ({}, "got neither"),
        ({"rig": case.rig, "cameras": case.cameras}, "not both"),
        ({"cameras": case.cameras}, "cameras without cams_from_rig"),
        ({"cams_from_rig": case.poses}, "cams_from_rig without cameras"),
    ]:
        with pytest.raises(eopnp.InvalidOptionError, match=what) as e:
            eopnp.solve_generalized(*args, case.idx, **kwargs)
        assert e.value.option == "rig"
    with pytest.raises(eopnp.InvalidOptionError, match="rig must be a Rig"):
        eopnp.solve_generalized(*args, case.idx, rig=case.cameras)
    with pytest.raises(TypeError, match="unexpected keyword"):
        eopnp.solve_generalized(*args, case.idx, rig=case.rig, camera=PINHOLE)


@pytest.mark.parametrize("threads", [None, 1, 2])
def test_batch_equals_one_problem_calls(threads):
    rng = np.random.default_rng(12)
    cases = [rig_case(rng, 2 + k % 5, 0.5, 30, 1.0, k % 2 == 0) for k in range(16)]
    probs = [(c.pixels, c.world, c.idx) for c in cases]
    rigs = [c.rig for c in cases]
    probs[3] = (*probs[3], rng.uniform(0.5, 2.0, 30))  # weighted
    probs[5] = (probs[5][0][:3], probs[5][1][:3], probs[5][2][:3])  # too few points
    bad = probs[7][2].copy()
    bad[4] = -3
    probs[7] = (probs[7][0], probs[7][1], bad)  # unknown camera
    probs[9] = (*probs[9], None)  # weights None
    got = eopnp.solve_generalized_batch(probs, rig=rigs, threads=threads)
    assert len(got) == len(probs)
    for k, (p, g, rig) in enumerate(zip(probs, got, rigs)):
        w = p[3] if len(p) == 4 else None
        try:
            want = eopnp.solve_generalized(*p[:3], rig=rig, weights=w)
        except eopnp.PnpError as e:
            assert type(g) is type(e) and str(g) == str(e) and g.details == e.details, k
            continue
        assert isinstance(g, eopnp.Solution) and g == want, k
    assert got[5].kind == "TooFewPoints"
    assert (got[7].kind, got[7].index, got[7].camera) == ("UnknownCamera", 4, -3)

    # RANSAC: problem i with seed problem_seed(seed, i); one Rig for every problem.
    case = cases[0]
    outliers(rng, case, 0.4)
    rprobs = [(case.pixels, case.world, case.idx)] * 3 + [probs[5]]
    opts = {"seed": 4, "threshold_px": 3.0}
    got = eopnp.solve_generalized_ransac_batch(
        rprobs, rig=case.rig, ransac=opts, threads=threads, loss=("huber", 2.0)
    )
    for k, (p, g) in enumerate(zip(rprobs, got)):
        o = dict(opts, seed=eopnp.problem_seed(4, k))
        try:
            want, info = eopnp.solve_generalized_ransac(
                *p, rig=case.rig, ransac=o, loss=("huber", 2.0)
            )
        except eopnp.PnpError as e:
            assert type(g) is type(e) and str(g) == str(e), k
            continue
        sol, ginfo = g
        assert sol == want, k
        for key in info:
            if key != "micros":
                assert np.array_equal(ginfo[key], info[key]), (k, key)
    assert isinstance(got[3], eopnp.InvalidInputError)


def test_batch_errors():
    rng = np.random.default_rng(13)
    case = rig_case(rng, 2, 0.5, 10)
    p = (case.pixels, case.world, case.idx)
    with pytest.raises(eopnp.InvalidInputError, match=r"problems\[1\]: expected a \(points2D"):
        eopnp.solve_generalized_batch([p, p[:2]], rig=case.rig)
    with pytest.raises(eopnp.InvalidInputError, match=r"problems\[0\] points3D: expected an"):
        eopnp.solve_generalized_batch([(p[0], p[0], p[2])], rig=case.rig)
    with pytest.raises(eopnp.InputTypeError, match=r"problems\[0\] camera_idxs: expected int"):
        eopnp.solve_generalized_batch([(p[0], p[1], p[2] * 1.0)], rig=case.rig)
    with pytest.raises(eopnp.InvalidOptionError, match="1 rigs for 2 problems"):
        eopnp.solve_generalized_batch([p, p], rig=[case.rig])
    with pytest.raises(eopnp.InvalidOptionError, match="rig must be a Rig or a sequence"):
        eopnp.solve_generalized_batch([p], rig=[PINHOLE])
    with pytest.raises(TypeError, match="rig"):
        eopnp.solve_generalized_batch([p])  # rig= is required
    # A RANSAC option out of range fails every problem alike: raised, as by the single call.
    with pytest.raises(eopnp.InvalidOptionError, match="max_iterations"):
        eopnp.solve_generalized_ransac_batch([p, p], rig=case.rig, ransac={"max_iterations": 0})
    assert eopnp.solve_generalized_batch([], rig=case.rig) == []


def test_batch_releases_the_gil():
    rng = np.random.default_rng(14)
    case = rig_case(rng, 4, 1.0, 100, 1.0, True)
    p = (case.pixels, case.world, case.idx)
    assert_releases_gil(lambda k: lambda: eopnp.solve_generalized_batch([p] * k, rig=case.rig))


@pytest.mark.parametrize("threads", [1, 2])
def test_batch_copies_its_inputs(threads):
    """As test_batch_copies.py: another thread overwriting the pixels and world points with NaN
    while the problems are solved does not change the results."""
    from test_batch_copies import ATTEMPTS, copies, overwritten_during

    rng = np.random.default_rng(16)
    case = rig_case(rng, 3, 1.0, 30, 1.0)
    probs = [(case.pixels.copy(), case.world.copy(), case.idx.copy()) for _ in range(2000)]
    want = eopnp.solve_generalized_batch(probs, rig=case.rig, threads=threads)

    def make():
        fresh = copies(probs)
        call = lambda: eopnp.solve_generalized_batch(fresh, rig=case.rig, threads=threads)  # noqa: E731
        return call, [a for p in fresh for a in p[:2]]

    got, during, floats = overwritten_during(make)
    if not during:
        pytest.skip(f"the writer thread never ran during the call in {ATTEMPTS} attempts")
    assert np.isnan(floats[-2]).all()  # written
    assert got == want


def test_against_pycolmap():
    """pycolmap's estimate_and_refine_generalized_absolute_pose and eopnp on the same noisy
    problems (sigma 1 px, 50 % outliers, 2-6 cameras, 100 points): the same inliers, and the
    same pose. pycolmap refines with a Cauchy loss of scale 1 px, and Ceres stops it at a
    relative cost decrease of 1e-6, 1e-5 to 2e-3 degrees short of its minimum here. So: eopnp
    with that loss on pycolmap's inliers (solve_generalized, and solve_generalized_ransac with
    pycolmap's threshold) is within 5e-3 degrees of pycolmap's pose, at a cost no higher, and
    is the minimum of pycolmap's own objective: refine_generalized_absolute_pose started
    there does not move it (1e-9 degrees), while from 0.05-0.15 degrees away it moves at least
    ten times closer to it."""
    pycolmap = require("pycolmap")
    rng = np.random.default_rng(15)
    worst = {"pose": 0.0, "ransac": 0.0, "fixed": 0.0, "moved": 0.0, "default": 0.0}
    for k in range(10):
        case = rig_case(rng, 2 + k % 5, [0.1, 0.5, 1.0, 2.0][k % 4], 100, 1.0, k % 2 == 0)
        outliers(rng, case, 0.5)
        # pycolmap's objects, and back (the conversions of the README).
        pc_cams = [
            pycolmap.Camera(model=c.model, width=c.width, height=c.height, params=c.params)
            for c in case.cameras
        ]
        pc_poses = [pycolmap.Rigid3d(np.column_stack([r, t])) for r, t in case.poses]
        rig = eopnp.Rig(
            [eopnp.Camera(c.model.name, c.params, c.width, c.height) for c in pc_cams],
            [p.matrix() for p in pc_poses],
        )
        assert rig.cameras == case.cameras
        res = pycolmap.estimate_and_refine_generalized_absolute_pose(
            case.pixels, case.world, list(case.idx), pc_poses, pc_cams,
            estimation_options=pycolmap.RANSACOptions(max_error=4.0, random_seed=k),
        )
        theirs = res["rig_from_world"].matrix()
        mask = np.asarray(res["inlier_mask"], dtype=bool)
        args = (case.pixels, case.world, case.idx)

        ours = eopnp.solve_generalized(
            *args, rig=rig, weights=mask.astype(float), loss=("cauchy", 1.0)
        )
        worst["pose"] = max(worst["pose"], rotation_error_deg(ours.R, theirs[:, :3]))
        assert np.linalg.norm(ours.t - theirs[:, 3]) < 1e-3
        cauchy = lambda R, t: np.sum(np.log1p(pixel_residuals(case, R, t, mask) ** 2))
        assert cauchy(ours.R, ours.t) <= cauchy(theirs[:, :3], theirs[:, 3]) * (1 + 1e-12)

        robust, info = eopnp.solve_generalized_ransac(
            *args, rig=rig, loss=("cauchy", 1.0),
            ransac={"seed": k, "threshold_px": 4.0, "final_threshold_factor": 1.0},
        )
        assert np.array_equal(info["inliers"], mask), k
        worst["ransac"] = max(worst["ransac"], rotation_error_deg(robust.R, theirs[:, :3]))

        def pycolmap_refine(R, t):
            out = pycolmap.refine_generalized_absolute_pose(
                pycolmap.Rigid3d(np.column_stack([R, t])), case.pixels, case.world, mask,
                list(case.idx), pc_poses, pc_cams,
            )
            return out["rig_from_world"].matrix()

        fixed = pycolmap_refine(ours.R, ours.t)
        worst["fixed"] = max(worst["fixed"], rotation_error_deg(fixed[:, :3], ours.R))
        start = rodrigues(rng.normal(size=3) * np.radians(0.1) / np.sqrt(3)) @ ours.R
        moved = pycolmap_refine(start, ours.t + 0.01)
        ratio = rotation_error_deg(moved[:, :3], ours.R) / rotation_error_deg(start, ours.R)
        worst["moved"] = max(worst["moved"], ratio)

        # The defaults (squared loss, final threshold 8 px): the same inliers here (1 px
        # noise, gross outliers) and the least-squares pose, 0.005-0.05 degrees from the
        # Cauchy one.
        default, info = eopnp.solve_generalized_ransac(*args, rig=rig, ransac={"seed": k})
        assert np.array_equal(info["inliers"], mask), k
        worst["default"] = max(worst["default"], rotation_error_deg(default.R, theirs[:, :3]))
    print("eopnp vs pycolmap, worst rotation differences (deg; moved: a ratio):", worst)
    assert worst["pose"] < 5e-3 and worst["ransac"] < 5e-3
    assert worst["fixed"] < 1e-9 and worst["moved"] < 0.1
    assert worst["default"] < 0.1
