"""loss= of every entry point: a robust loss resists gross outliers where the squared loss does
not, the reported cost is the loss's cost, every entry point passes the loss on (batch =
one by one), and bad values raise InvalidOptionError (an unusable scale with the library's
message) before anything is solved."""

import math

import numpy as np
import pytest

import eopnp
from conftest import DATA, problem, rotation_error_deg

CAM = eopnp.Camera("OPENCV", [800.0, 790.0, 320.0, 240.0, -0.3, 0.1, 1e-3, -5e-4])
LOSS_SCALE_MESSAGE = (
    "the loss scale is out of range: Huber and Cauchy take a finite scale s > 0 whose square "
    "and its reciprocal are normal numbers (about 1e-154 < s < 1e154)"
)


def with_outliers(rng, n=40, every=8, shift_px=60.0):
    """A noisy (0.5 px) pixel problem through CAM with a gross outlier every `every` points."""
    world, image, r, t = problem(rng, n, sigma_px=0.5)
    pixels = CAM.project(image)
    pixels[::every, 0] += shift_px
    return world, pixels, r, t


def test_robust_loss_resists_outliers_pixels(rng):
    # Measured (seed 12345): the robust rotation error is 0.018-0.085 (Huber) and 0.012-0.099
    # (Cauchy) times the squared loss's in each of the 10 problems.
    for _ in range(10):
        world, pixels, r, _ = with_outliers(rng)
        plain = eopnp.solve(world, pixels, camera=CAM)
        err = rotation_error_deg(plain.R, r)
        for kind in ["huber", "cauchy"]:
            robust = eopnp.solve(world, pixels, camera=CAM, loss=(kind, 1.5))
            assert rotation_error_deg(robust.R, r) < 0.2 * err, kind


def test_robust_loss_resists_outliers_normalised(rng):
    # Measured: the ratio is 0.035-0.104 in 9 problems, 0.37 in one.
    ratios = []
    for _ in range(10):
        world, image, r, t = problem(rng, 30, sigma_px=0.5)
        image[::6, 1] += 0.05  # 40 px at f = 800
        plain = eopnp.solve(world, image)
        robust = eopnp.solve(world, image, loss=("cauchy", 2.0 / 800))
        ratios.append(rotation_error_deg(robust.R, r) / rotation_error_deg(plain.R, r))
    assert max(ratios) < 0.5 and sorted(ratios)[8] < 0.2, ratios


@pytest.mark.parametrize("kind", ["huber", "cauchy"])
def test_cost_is_the_loss_cost_in_pixels(rng, kind):
    s = 1.5
    world, pixels, _, _ = with_outliers(rng)
    sol = eopnp.solve(world, pixels, camera=CAM, loss=(kind, s))
    cam_pts = world @ sol.R.T + sol.t
    proj = CAM.project(cam_pts[:, :2] / cam_pts[:, 2:])
    r2 = ((proj - pixels) ** 2).sum(axis=1)
    if kind == "huber":
        rho = np.where(r2 <= s * s, r2, 2 * s * np.sqrt(r2) - s * s)
    else:
        rho = s * s * np.log1p(r2 / (s * s))
    assert sol.cost == pytest.approx(rho.sum(), rel=1e-9)
    assert sol.converged


def test_squared_is_the_default(rng):
    world, pixels, _, _ = with_outliers(rng)
    default = eopnp.solve(world, pixels, camera=CAM)
    assert eopnp.solve(world, pixels, camera=CAM, loss="squared") == default
    assert eopnp.solve(world, pixels, camera=CAM, loss=None) == default
    assert eopnp.solve(world, pixels, camera=CAM, loss=("huber", 1.5)) != default
    # A list works as the tuple does.
    assert eopnp.solve(world, pixels, camera=CAM, loss=["huber", 1.5]) == eopnp.solve(
        world, pixels, camera=CAM, loss=("huber", 1.5)
    )


def test_every_entry_point_passes_the_loss_on(rng):
    world, pixels, _, _ = with_outliers(rng)
    image = CAM.undistort(pixels)
    loss = ("cauchy", 1.5)
    one = eopnp.solve(world, pixels, camera=CAM, loss=loss)
    assert eopnp.solve_batch([(world, pixels)] * 2, camera=CAM, loss=loss, threads=2) == [one] * 2
    normalised = eopnp.solve(world, image, loss=("cauchy", 1.5 / 800))
    assert normalised != eopnp.solve(world, image)
    # solve_all's best minimum is solve's pose (as without a loss: to rounding, not bitwise).
    best = eopnp.solve_all(world, image, loss=("cauchy", 1.5 / 800))[0]
    assert np.abs(best.R - normalised.R).max() < 1e-12
    assert np.abs(best.t - normalised.t).max() < 1e-12
    assert best.cost == pytest.approx(normalised.cost, rel=1e-12)
    # RANSAC: the loss of the fits' final refinement; batch = one by one.
    opts = eopnp.RansacOptions(threshold_px=8.0)
    r_plain, _ = eopnp.solve_ransac(world, pixels, camera=CAM, ransac=opts)
    r_loss, info = eopnp.solve_ransac(world, pixels, camera=CAM, ransac=opts, loss=loss)
    assert r_loss != r_plain and info["cost"] == r_loss.cost
    batch = eopnp.solve_ransac_batch([(world, pixels)], camera=CAM, ransac=opts, loss=loss)
    assert batch[0][0] == r_loss
    # register_image: solve() through the image's camera.
    model = eopnp.read_colmap_model(DATA / "colmap-boxes")
    w, p = model.correspondences(2)
    reg = eopnp.register_image(model, 2, loss=("huber", 1.0))
    assert reg.solution == eopnp.solve(w, p, camera=model.camera_of(2), loss=("huber", 1.0))
    assert reg.solution != eopnp.register_image(model, 2).solution


BAD_FORMS = [
    "huber",
    "cauchy",
    "l2",
    3.0,
    ("huber",),
    ("huber", 1.0, 2.0),
    ("tukey", 1.0),
    ("huber", "1"),
    ("huber", True),
    ("huber", None),
    {"huber": 1.0},
    (1.0, "huber"),
]


@pytest.mark.parametrize("loss", BAD_FORMS, ids=repr)
def test_bad_loss_forms(rng, loss):
    world, image, _, _ = problem(rng, 10)
    with pytest.raises(eopnp.InvalidOptionError, match="loss must be None") as e:
        eopnp.solve(world, image, loss=loss)
    assert (e.value.option, e.value.kind) == ("loss", "InvalidOption")


BAD_SCALES = [0.0, -1.0, -0.0, math.nan, math.inf, -math.inf, 1e-160, 1e160]


@pytest.mark.parametrize("scale", BAD_SCALES)
@pytest.mark.parametrize("kind", ["huber", "cauchy"])
def test_unusable_scale_has_the_library_message(rng, kind, scale):
    world, image, _, _ = problem(rng, 10)
    with pytest.raises(eopnp.InvalidOptionError) as e:
        eopnp.solve(world, image, loss=(kind, scale))
    assert str(e.value) == LOSS_SCALE_MESSAGE
    assert (e.value.option, e.value.kind) == ("loss", "InvalidOption")


def test_usable_extreme_scales(rng):
    world, image, r, _ = problem(rng, 10)
    for s in [1e-150, 1e150]:
        assert rotation_error_deg(eopnp.solve(world, image, loss=("huber", s)).R, r) < 1e-6


def test_every_entry_point_rejects_a_bad_loss_before_solving(rng):
    world, image, _, _ = problem(rng, 10)
    pixels = CAM.project(image)
    model = eopnp.read_colmap_model(DATA / "colmap-boxes")
    calls = [
        lambda loss: eopnp.solve(world, image, loss=loss),
        lambda loss: eopnp.solve_all(world, image, loss=loss),
        lambda loss: eopnp.refine(world, image, (np.eye(3), np.zeros(3)), loss=loss),
        lambda loss: eopnp.solve_ransac(world, pixels, camera=CAM, loss=loss),
        # Raised, not returned per problem.
        lambda loss: eopnp.solve_batch([(world, image)], loss=loss),
        lambda loss: eopnp.solve_ransac_batch([(world, pixels)], camera=CAM, loss=loss),
        lambda loss: eopnp.register_image(model, 1, loss=loss),
    ]
    for call in calls:
        with pytest.raises(eopnp.InvalidOptionError) as e:
            call(("cauchy", -1.0))
        assert str(e.value) == LOSS_SCALE_MESSAGE
        with pytest.raises(eopnp.InvalidOptionError, match="loss must be None"):
            call("welsch")
