"""A known vertical: eopnp.Gravity and ``gravity=`` on solve, refine, solve_ransac,
solve_generalized, solve_generalized_ransac and refine_generalized: the exact pose from
noise-free input, the prior's pull towards the measured vertical, the mismatch error on a
wrong vertical, RANSAC's samples of two, the class's checks, equality and pickling."""

import pickle

import numpy as np
import pytest

import eopnp
from conftest import problem, rodrigues, rotation_error_deg
from test_rig import rig_case

DOWN = np.array([0.2, -0.3, -1.0]) / np.linalg.norm([0.2, -0.3, -1.0])
CAMERA = eopnp.Camera("PINHOLE", [800.0, 800.0, 320.0, 240.0], 640, 480)


def tilted(g, deg, rng):
    """g turned by `deg` degrees about a random axis across it."""
    axis = np.cross(g, rng.normal(size=3))
    axis /= np.linalg.norm(axis)
    return rodrigues(axis * np.radians(deg)) @ g


def test_gravity_class():
    g = eopnp.Gravity([0.0, 2.0, 0.0], [0, 0, -3], 0.5)
    np.testing.assert_array_equal(g.in_camera, [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(g.in_world, [0.0, 0.0, -1.0])
    assert g.sigma_deg == 0.5
    assert repr(g) == "Gravity([0, 1, 0], [0, 0, -1], sigma_deg=0.5)"
    assert g == eopnp.Gravity([0, 1, 0], [0, 0, -1], 0.5) and g != "gravity"
    assert g != eopnp.Gravity([0, 1, 0], [0, 0, -1], 0.4)
    back = pickle.loads(pickle.dumps(g))
    assert back == g
    # Unit vectors along no axis survive the round trip bit for bit too.
    h = eopnp.Gravity(DOWN @ rodrigues([0.3, 0.1, -0.2]).T, DOWN, 0.1)
    assert pickle.loads(pickle.dumps(h)) == h
    for args in [
        ([0, 0, 0], DOWN, 0.1),
        (DOWN, [0, 0, 0], 0.1),
        ([np.nan, 1, 0], DOWN, 0.1),
        (DOWN, [0, np.inf, 0], 0.1),
        (DOWN, DOWN, 0.0),
        (DOWN, DOWN, -1.0),
        (DOWN, DOWN, np.nan),
        (DOWN, DOWN, np.inf),
        ([0, 1], DOWN, 0.1),
    ]:
        with pytest.raises(eopnp.InvalidOptionError) as e:
            eopnp.Gravity(*args)
        assert e.value.option == "gravity"
    with pytest.raises(AttributeError):
        g.sigma_deg = 1.0


def test_exact_pose_and_the_prior():
    rng = np.random.default_rng(3)
    world, image, R, t = problem(rng, 30)
    g = eopnp.Gravity(R @ DOWN, DOWN, 0.1)
    sol = eopnp.solve(world, image, gravity=g)
    assert rotation_error_deg(sol.R, R) < 1e-8
    # Noisy pixels: the prior pulls the pose's vertical towards the measured one.
    world, pixels_true = world, image * 800.0 + [320.0, 240.0]
    pixels = pixels_true + rng.normal(0, 1.0, pixels_true.shape)
    measured = tilted(R @ DOWN, 0.05, rng)
    g = eopnp.Gravity(measured, DOWN, 0.1)
    ml = eopnp.solve(world, pixels, camera=CAMERA)
    mp = eopnp.solve(world, pixels, camera=CAMERA, gravity=g)
    off = lambda s: np.linalg.norm(s.R @ DOWN - measured)
    assert off(mp) < off(ml)
    assert mp.cost >= ml.cost * (1 - 1e-9)
    # refine from the ML pose with the vertical gives the same maximum a posteriori pose.
    rf = eopnp.refine(world, pixels, ml, camera=CAMERA, gravity=g)
    assert rotation_error_deg(rf.R, mp.R) < 1e-6


def test_a_wrong_vertical_raises():
    rng = np.random.default_rng(4)
    world, image, R, t = problem(rng, 100, sigma_px=1.0)
    wrong = tilted(R @ DOWN, 1.0, rng)
    with pytest.raises(eopnp.GravityMismatchError) as e:
        eopnp.solve(world, image, gravity=eopnp.Gravity(wrong, DOWN, 0.1))
    assert isinstance(e.value, ValueError) and isinstance(e.value, eopnp.PnpError)
    assert e.value.kind == "GravityMismatch"
    assert abs(e.value.angle_deg - 1.0) < 0.2 and e.value.sigmas > 3.44
    assert e.value.details == {"angle_deg": e.value.angle_deg, "sigmas": e.value.sigmas}
    back = pickle.loads(pickle.dumps(e.value))
    assert type(back) is eopnp.GravityMismatchError and back.angle_deg == e.value.angle_deg
    # Stated to 2 degrees, the same vertical is within its uncertainty.
    sol = eopnp.solve(world, image, gravity=eopnp.Gravity(wrong, DOWN, 2.0))
    assert rotation_error_deg(sol.R, R) < 0.5


def test_ransac_samples_two_points():
    rng = np.random.default_rng(5)
    world, image, R, t = problem(rng, 100, sigma_px=1.0)
    pixels = image * 800.0 + [320.0, 240.0]
    bad = rng.choice(100, 80, replace=False)
    pixels[bad] = rng.uniform([0, 0], [640, 480], (80, 2))
    g = eopnp.Gravity(tilted(R @ DOWN, 0.1, rng), DOWN, 0.1)
    plain, info = eopnp.solve_ransac(world, pixels, camera=CAMERA, ransac={"seed": 1})
    up, info_up = eopnp.solve_ransac(world, pixels, camera=CAMERA, gravity=g, ransac={"seed": 1})
    assert rotation_error_deg(up.R, R) < 0.5 and rotation_error_deg(plain.R, R) < 0.5
    # Samples of two need about 5x fewer iterations at 20 % inliers (0.999 confidence).
    assert info["iterations"] >= 4 * info_up["iterations"]
    assert not info_up["inliers"][bad].any()


def test_rigs_take_a_vertical():
    rng = np.random.default_rng(6)
    case = rig_case(rng, 3, 1.0, 60, sigma=1.0)
    g = eopnp.Gravity(tilted(case.R @ DOWN, 0.05, rng), DOWN, 0.1)
    args = (case.pixels, case.world, case.idx)
    ml = eopnp.solve_generalized(*args, rig=case.rig)
    mp = eopnp.solve_generalized(*args, rig=case.rig, gravity=g)
    off = lambda s: np.linalg.norm(s.R @ DOWN - g.in_camera)
    assert off(mp) < off(ml)
    rs, info = eopnp.solve_generalized_ransac(*args, rig=case.rig, gravity=g)
    assert rotation_error_deg(rs.R, case.R) < 0.5
    rf = eopnp.refine_generalized(ml, *args, rig=case.rig, gravity=g)
    assert rotation_error_deg(rf.R, mp.R) < 1e-6
    wrong = eopnp.Gravity(tilted(case.R @ DOWN, 2.0, rng), DOWN, 0.1)
    with pytest.raises(eopnp.GravityMismatchError):
        eopnp.solve_generalized(*args, rig=case.rig, gravity=wrong)
