"""Array input: any real dtype, layout, byte order and array-like is read as float64; other
dtypes and wrong shapes raise clear errors."""

import numpy as np
import pytest

import eopnp
from conftest import problem


@pytest.fixture
def prob(rng):
    world, image, _, _ = problem(rng, 12, sigma_px=0.5)
    return world, image, eopnp.solve(world, image)


def test_float32_and_ints(prob):
    world, image, ref = prob
    s32 = eopnp.solve(world.astype(np.float32), image.astype(np.float32))
    assert np.abs(s32.R - ref.R).max() < 1e-4
    # exact conversion of float32 data: identical to solving the converted float64 arrays
    assert s32 == eopnp.solve(world.astype(np.float32).astype(float),
                              image.astype(np.float32).astype(float))
    wi = np.round(world * 100).astype(np.int32)
    assert eopnp.solve(wi, image) == eopnp.solve(wi.astype(float), image)
    assert eopnp.solve(world.astype(np.longdouble), image) == ref
    assert eopnp.solve(world.astype(np.float16), image).used == 12


def test_layouts(prob):
    world, image, ref = prob
    assert eopnp.solve(np.asfortranarray(world), np.asfortranarray(image)) == ref
    big_w = np.zeros((24, 5))
    big_w[::2, 1:4] = world
    big_i = np.zeros((12, 4))
    big_i[:, ::2] = image
    assert eopnp.solve(big_w[::2, 1:4], big_i[:, ::2]) == ref  # strided views
    assert eopnp.solve(world[::-1][::-1], image) == ref  # negative strides
    assert eopnp.solve(world.astype(">f8"), image.astype(">f8")) == ref  # big-endian
    ro = world.copy()
    ro.flags.writeable = False
    assert eopnp.solve(ro, image) == ref
    assert eopnp.solve(world.tolist(), image.tolist()) == ref  # nested lists
    assert eopnp.solve(tuple(map(tuple, world)), image) == ref
    assert eopnp.solve(world, image, weights=[1] * 12) == eopnp.solve(world, image, np.ones(12))


def test_inputs_not_modified(prob):
    world, image, _ = prob
    w0, i0 = world.copy(), image.copy()
    eopnp.solve(world, image)
    eopnp.solve_ransac(world, image, focal=(800.0, 800.0))
    assert np.array_equal(world, w0) and np.array_equal(image, i0)


@pytest.mark.parametrize(
    "world_fn, match",
    [
        (lambda w: w[:, :2], r"world: expected an array of shape \(N, 3\), got shape \(12, 2\)"),
        (lambda w: w.T, r"got shape \(3, 12\)"),
        (lambda w: w.ravel(), r"got shape \(36,\)"),
        (lambda w: w[None], r"got shape \(1, 12, 3\)"),
        (lambda w: 1.0, r"got shape \(\)"),
        (lambda w: [[1, 2, 3], [1, 2]], "world"),  # ragged
    ],
)
def test_bad_shapes(prob, world_fn, match):
    world, image, _ = prob
    with pytest.raises(eopnp.InvalidInputError, match=match) as e:
        eopnp.solve(world_fn(world), image)
    assert e.value.kind == "Shape" and e.value.argument == "world"
    assert not isinstance(e.value, TypeError)


def test_bad_image_and_weight_shapes(prob):
    world, image, _ = prob
    with pytest.raises(eopnp.InvalidInputError, match=r"image: expected an array of shape \(N, 2\)"):
        eopnp.solve(world, np.column_stack([image, np.ones(12)]))
    with pytest.raises(eopnp.InvalidInputError, match=r"weights: expected an array of shape \(n,\)"):
        eopnp.solve(world, image, np.ones((12, 1)))


@pytest.mark.parametrize(
    "convert",
    [
        lambda a: a.astype(np.complex128),
        lambda a: a > 0,
        lambda a: a.astype(object),
        lambda a: a.astype(str),
        lambda a: np.array([["a", "b", "c"]] * 12),
        lambda a: a.astype("timedelta64[s]"),
        lambda a: None,
    ],
)
def test_bad_dtypes(prob, convert):
    world, image, _ = prob
    with pytest.raises(eopnp.InputTypeError, match="world: expected real numbers") as e:
        eopnp.solve(convert(world), image)
    assert isinstance(e.value, TypeError) and isinstance(e.value, eopnp.InvalidInputError)
    assert e.value.kind == "DType" and e.value.argument == "world"


def test_bad_weight_dtype(prob):
    world, image, _ = prob
    with pytest.raises(eopnp.InputTypeError, match="weights"):
        eopnp.solve(world, image, np.ones(12, dtype=bool))


def test_outputs_are_new_float64_arrays(prob):
    world, image, ref = prob
    for a in [ref.R, ref.t, ref.rvec, ref.q, ref.Rt]:
        assert a.dtype == np.float64 and a.flags.c_contiguous and a.flags.owndata
    cam = eopnp.Camera.pinhole(800, 800, 320, 240)
    px = cam.project(image.astype(np.float32))
    assert px.dtype == np.float64 and px.shape == (12, 2)
