"""Every error path: each exception class of the PnpError hierarchy, with the library's message
and the variant's fields; never a crash or a silent wrong pose."""

import pickle

import numpy as np
import pytest

import eopnp
from conftest import DATA, problem


def test_hierarchy():
    assert issubclass(eopnp.InvalidInputError, eopnp.PnpError)
    assert issubclass(eopnp.InvalidInputError, ValueError)
    assert issubclass(eopnp.InputTypeError, eopnp.InvalidInputError)
    assert issubclass(eopnp.InputTypeError, TypeError)
    assert issubclass(eopnp.DegenerateError, ValueError)
    assert issubclass(eopnp.NoSolutionError, RuntimeError)
    assert issubclass(eopnp.InvalidOptionError, ValueError)
    assert issubclass(eopnp.NoConsensusError, RuntimeError)
    assert issubclass(eopnp.CameraError, ValueError)
    assert issubclass(eopnp.UnknownIdError, LookupError)
    for cls in [
        eopnp.InvalidInputError, eopnp.DegenerateError, eopnp.NoSolutionError,
        eopnp.InvalidOptionError, eopnp.NoConsensusError, eopnp.CameraError,
        eopnp.ModelError, eopnp.UnknownIdError,
    ]:
        assert issubclass(cls, eopnp.PnpError)


def test_too_few_points(rng):
    world, image, _, _ = problem(rng, 3)
    with pytest.raises(eopnp.InvalidInputError, match="too few correspondences: got 3") as e:
        eopnp.solve(world, image)
    assert (e.value.kind, e.value.got, e.value.need) == ("TooFewPoints", 3, 4)
    # With weights, only positive weights count.
    world, image, _, _ = problem(rng, 6)
    with pytest.raises(eopnp.InvalidInputError) as e:
        eopnp.solve(world, image, [1, 1, 1, 0, 0, 0])
    assert (e.value.kind, e.value.got) == ("TooFewPoints", 3)
    with pytest.raises(eopnp.InvalidInputError, match="got 0"):
        eopnp.solve(np.zeros((0, 3)), np.zeros((0, 2)))


def test_length_mismatch(rng):
    world, image, _, _ = problem(rng, 8)
    with pytest.raises(eopnp.InvalidInputError, match="point counts differ") as e:
        eopnp.solve(world, image[:7])
    assert (e.value.kind, e.value.world, e.value.image) == ("LengthMismatch", 8, 7)
    cam = eopnp.Camera.pinhole(800, 800, 320, 240)
    with pytest.raises(eopnp.InvalidInputError, match="point counts differ"):
        eopnp.solve(world, cam.project(image)[:7], camera=cam)


def test_weights_length(rng):
    world, image, _, _ = problem(rng, 8)
    with pytest.raises(eopnp.InvalidInputError, match="got 7 weights for 8") as e:
        eopnp.solve(world, image, np.ones(7))
    assert (e.value.kind, e.value.weights, e.value.points) == ("WeightsLength", 7, 8)
    cam = eopnp.Camera.pinhole(800, 800, 320, 240)
    with pytest.raises(eopnp.InvalidInputError, match="got 7 weights for 8"):
        eopnp.solve(world, cam.project(image), np.ones(7), camera=cam)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite(rng, bad):
    world, image, _, _ = problem(rng, 8)
    cam = eopnp.Camera("SIMPLE_RADIAL", [800, 320, 240, 0.01])
    pixels = cam.project(image)
    for camera, img in [(None, image), (cam, pixels)]:
        w = world.copy()
        w[5, 2] = bad
        with pytest.raises(eopnp.InvalidInputError, match="world point 5 is not finite") as e:
            eopnp.solve(w, img, camera=camera)
        assert (e.value.kind, e.value.index, e.value.input) == ("NonFinite", 5, "world")
        i = img.copy()
        i[2, 0] = bad
        with pytest.raises(eopnp.InvalidInputError, match="image point 2 is not finite") as e:
            eopnp.solve(world, i, camera=camera)
        assert (e.value.index, e.value.input) == (2, "image")
        wt = np.ones(8)
        wt[6] = bad
        with pytest.raises(eopnp.InvalidInputError, match="weight 6 is not finite") as e:
            eopnp.solve(world, img, wt, camera=camera)
        assert (e.value.index, e.value.input) == (6, "weights")
        # RANSAC too.
        kw = dict(camera=camera) if camera else dict(focal=(800.0, 800.0))
        with pytest.raises(eopnp.InvalidInputError, match="image point 2"):
            eopnp.solve_ransac(world, i, **kw)
    # The first index wins; at one index, world before image.
    w = world.copy()
    i = image.copy()
    w[4, 0] = i[4, 1] = i[3, 0] = bad
    with pytest.raises(eopnp.InvalidInputError) as e:
        eopnp.solve(w, i)
    assert (e.value.index, e.value.input) == (3, "image")
    i[3, 0] = 0.1
    with pytest.raises(eopnp.InvalidInputError) as e:
        eopnp.solve(w, i)
    assert (e.value.index, e.value.input) == (4, "world")


def test_negative_weight(rng):
    world, image, _, _ = problem(rng, 8)
    with pytest.raises(eopnp.InvalidInputError, match="weight 3 is negative") as e:
        eopnp.solve(world, image, [1, 1, 1, -0.5, 1, 1, 1, 1])
    assert (e.value.kind, e.value.index) == ("InvalidWeight", 3)
    cam = eopnp.Camera.pinhole(800, 800, 320, 240)
    with pytest.raises(eopnp.InvalidInputError, match="weight 3 is negative"):
        eopnp.solve(world, cam.project(image), [1, 1, 1, -0.5, 1, 1, 1, 1], camera=cam)


def test_degenerate(rng):
    world, image, _, _ = problem(rng, 8)
    cases = {
        "coincident_world_points": (np.tile([1.0, 2.0, 3.0], (8, 1)), image),
        "collinear_world_points": (np.outer(np.arange(8.0), [1.0, 2.0, 0.5]), image),
        "coincident_image_points": (world, np.tile([0.1, 0.2], (8, 1))),
        "scale_out_of_range": (world * 1e-310, image),
    }
    for kind, (w, i) in cases.items():
        with pytest.raises(eopnp.DegenerateError, match="degenerate input") as e:
            eopnp.solve(w, i)
        assert (e.value.kind, e.value.degeneracy) == ("Degenerate", kind)


def test_no_solution():
    # An input found by search: image coordinates up to 7e16 make every candidate fail.
    world = [[0.0, 1.0, 2.0], [-2.0, -2.0, 2.0], [2.0, -1.0, -1.0], [2.0, 0.0, -1.0],
             [2.0, -1.0, 0.0]]
    image = [[1e8, 0.0], [-0.002, -2.0], [0.002, 1e8], [7e16, 0.0], [2.0, -1e8]]
    with pytest.raises(eopnp.NoSolutionError, match="no solution found") as e:
        eopnp.solve(world, image)
    assert e.value.kind == "NoSolution"


def test_invalid_options(rng):
    world, image, _, _ = problem(rng, 8)
    for kw, option in [
        (dict(refinement="fast"), "refinement"),
        (dict(planar="maybe"), "planar"),
        (dict(newton_iterations=-1), "newton_iterations"),
        (dict(reprojection_iterations=2**40), "reprojection_iterations"),
        (dict(newton_step_tolerance=float("nan")), "newton_step_tolerance"),
        (dict(newton_step_tolerance=-1.0), "newton_step_tolerance"),
    ]:
        with pytest.raises(eopnp.InvalidOptionError) as e:
            eopnp.solve(world, image, **kw)
        assert e.value.option == option, kw
    with pytest.raises(TypeError):
        eopnp.solve(world, image, refinment="ml")  # misspelt keyword: Python's TypeError


@pytest.mark.parametrize(
    "opts, option",
    [
        (dict(threshold_px=0.0), "threshold_px"),
        (dict(threshold_px=float("nan")), "threshold_px"),
        (dict(threshold_px=1e-200), "threshold_px"),
        (dict(confidence=1.0), "confidence"),
        (dict(confidence=0.0), "confidence"),
        (dict(max_iterations=0), "max_iterations"),
        (dict(max_iterations=-5), "max_iterations"),
        (dict(min_iterations=2**33), "min_iterations"),
        (dict(final_threshold_factor=0.5), "final_threshold_factor"),
    ],
)
def test_invalid_ransac_options(rng, opts, option):
    world, image, _, _ = problem(rng, 20)
    for ransac in [eopnp.RansacOptions(**opts), opts]:
        with pytest.raises(eopnp.InvalidOptionError, match=option) as e:
            eopnp.solve_ransac(world, image, focal=(800.0, 800.0), ransac=ransac)
        assert e.value.option == option


def test_ransac_argument_errors(rng):
    world, image, _, _ = problem(rng, 20)
    cam = eopnp.Camera.pinhole(800, 800, 320, 240)
    with pytest.raises(eopnp.InvalidOptionError, match="focal"):
        eopnp.solve_ransac(world, image)
    with pytest.raises(eopnp.InvalidOptionError, match="not both"):
        eopnp.solve_ransac(world, image, camera=cam, focal=(800.0, 800.0))
    with pytest.raises(eopnp.InvalidOptionError, match="focal") as e:
        eopnp.solve_ransac(world, image, focal=(0.0, 800.0))
    assert e.value.option == "focal"
    with pytest.raises(eopnp.InvalidOptionError, match="unknown RANSAC option"):
        eopnp.solve_ransac(world, image, focal=(800.0, 800.0), ransac={"treshold_px": 2.0})
    with pytest.raises(eopnp.InvalidOptionError, match="ransac must be"):
        eopnp.solve_ransac(world, image, focal=(800.0, 800.0), ransac=[1, 2])


def test_no_consensus():
    rng = np.random.default_rng(3)
    world = rng.uniform(-1, 1, (30, 3))
    image = rng.uniform(-0.5, 0.5, (30, 2))
    with pytest.raises(eopnp.NoConsensusError, match="found no consensus after 50 samples") as e:
        eopnp.solve_ransac(
            world, image, focal=(800.0, 800.0),
            ransac=dict(threshold_px=1e-6, max_iterations=50, final_threshold_factor=1.0),
        )
    assert e.value.kind == "NoConsensus" and e.value.iterations == 50
    assert e.value.inliers < e.value.needed


def test_camera_errors():
    cases = [
        (lambda: eopnp.Camera("FOV", [1, 2, 3, 4, 5]), "UnsupportedModel", "unsupported"),
        (lambda: eopnp.Camera("PINHOLE", [800, 800, 320]), "ParamCount", "takes 4 parameters"),
        (lambda: eopnp.Camera("PINHOLE", [800, np.nan, 1, 1]), "InvalidParams", "not finite"),
        (lambda: eopnp.Camera("PINHOLE", [-800, 800, 1, 1]), "InvalidParams", "positive"),
        (lambda: eopnp.Camera("PINHOLE", [800, 800, 1, 1], width=-1), "InvalidParams", "width"),
        (lambda: eopnp.Camera.pinhole(0, 800, 1, 1), "InvalidParams", "positive"),
        (lambda: eopnp.Camera.from_opencv(np.eye(3), [0.1, 0.2, 0.3]), "InvalidParams", "0, 4, 5"),
        (
            lambda: eopnp.Camera.from_opencv([[800, 1, 320], [0, 800, 240], [0, 0, 1]]),
            "InvalidParams",
            "skew",
        ),
        (lambda: eopnp.Camera.from_opencv_fisheye(np.eye(3), [0.1]), "InvalidParams", "4"),
    ]
    for make, kind, match in cases:
        with pytest.raises(eopnp.CameraError, match=match) as e:
            make()
        assert e.value.kind == kind
    with pytest.raises(eopnp.InvalidInputError, match="3x3"):
        eopnp.Camera.from_opencv(np.eye(4)[:, :3])


def test_model_errors(tmp_path):
    with pytest.raises(eopnp.ModelError, match="no such directory") as e:
        eopnp.read_colmap_model(tmp_path / "missing")
    assert e.value.kind == "Model" and e.value.line is None
    model = tmp_path / "m"
    model.mkdir()
    for name in ["cameras.txt", "images.txt", "points3D.txt"]:
        (model / name).write_text((DATA / "colmap-boxes" / name).read_text())
    with open(model / "cameras.txt", "a") as f:
        f.write("7 PINHOLE 640 480 800 800\n")  # one parameter short
    with pytest.raises(eopnp.ModelError, match="cameras.txt") as e:
        eopnp.read_colmap_model(str(model))
    assert e.value.line is not None and e.value.file.endswith("cameras.txt") and e.value.reason


def test_unknown_image():
    m = eopnp.read_colmap_model(DATA / "colmap-boxes")
    with pytest.raises(eopnp.UnknownIdError, match="no image with id 99") as e:
        eopnp.register_image(m, 99)
    assert (e.value.kind, e.value.id) == ("UnknownImage", 99)
    with pytest.raises(LookupError):
        m.correspondences(99)
    with pytest.raises(eopnp.UnknownIdError):
        m.image(99)


def test_exceptions_pickle(rng):
    world, image, _, _ = problem(rng, 3)
    with pytest.raises(eopnp.InvalidInputError) as info:
        eopnp.solve(world, image)
    e = info.value
    back = pickle.loads(pickle.dumps(e))
    assert type(back) is type(e) and str(back) == str(e)
    assert (back.kind, back.got, back.need) == ("TooFewPoints", 3, 4)
