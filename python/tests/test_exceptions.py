"""The exception classes are created by the extension module (PyO3's create_exception!), in
module eopnp, with the hierarchy and builtin bases of the package; instances carry kind,
details and the fields, and pickle with them."""

import importlib
import pickle

import numpy as np
import pytest

import eopnp
from conftest import DATA, problem

MRO = {
    "PnpError": ["Exception"],
    "InvalidInputError": ["PnpError", "ValueError", "Exception"],
    "InputTypeError": ["InvalidInputError", "PnpError", "ValueError", "TypeError", "Exception"],
    "DegenerateError": ["PnpError", "ValueError", "Exception"],
    "NoSolutionError": ["PnpError", "RuntimeError", "Exception"],
    "InvalidOptionError": ["PnpError", "ValueError", "Exception"],
    "NoConsensusError": ["PnpError", "RuntimeError", "Exception"],
    "CameraError": ["PnpError", "ValueError", "Exception"],
    "ModelError": ["PnpError", "Exception"],
    "UnknownIdError": ["PnpError", "LookupError", "Exception"],
}


def test_classes_from_the_extension():
    for name, bases in MRO.items():
        cls = getattr(eopnp, name)
        assert cls is getattr(eopnp._eopnp, name) and name in eopnp.__all__
        assert cls.__module__ == "eopnp" and cls.__qualname__ == name and cls.__doc__
        assert [c.__name__ for c in cls.__mro__] == [name, *bases, "BaseException", "object"]
    with pytest.raises(ImportError):
        importlib.import_module("eopnp._errors")


def raised(call):
    try:
        call()
    except eopnp.PnpError as e:
        return e
    raise AssertionError("no exception")


def test_fields_and_pickling(rng, tmp_path):
    world, image, _, _ = problem(rng, 8)
    bad = world.copy()
    bad[5, 2] = np.nan
    cases = [
        (lambda: eopnp.solve(bad, image), eopnp.InvalidInputError, "NonFinite",
         {"index": 5, "input": "world"}),
        (lambda: eopnp.solve(world, np.full((8, 2), "a")), eopnp.InputTypeError, "DType",
         {"argument": "image"}),
        (lambda: eopnp.solve(world, np.tile([0.1, 0.2], (8, 1))), eopnp.DegenerateError,
         "Degenerate", {"degeneracy": "coincident_image_points"}),
        (lambda: eopnp.solve_ransac(
            np.random.default_rng(3).uniform(-1, 1, (30, 3)),
            np.random.default_rng(4).uniform(-0.5, 0.5, (30, 2)), focal=800.0,
            ransac=dict(threshold_px=1e-6, max_iterations=50, final_threshold_factor=1.0)),
         eopnp.NoConsensusError, "NoConsensus", None),
        (lambda: eopnp.solve(world, image, planar="maybe"), eopnp.InvalidOptionError,
         "InvalidOption", {"option": "planar"}),
        (lambda: eopnp.Camera("FOV", [1, 2, 3, 4, 5]), eopnp.CameraError, "UnsupportedModel",
         {}),
        (lambda: eopnp.read_colmap_model(tmp_path / "missing"), eopnp.ModelError, "Model",
         None),
        (lambda: eopnp.register_image(eopnp.read_colmap_model(DATA / "colmap-boxes"), 99),
         eopnp.UnknownIdError, "UnknownImage", {"id": 99}),
    ]
    for call, cls, kind, details in cases:
        e = raised(call)
        assert type(e) is cls and e.kind == kind, kind
        if details is not None:
            assert e.details == details, kind
        assert all(getattr(e, k) == v for k, v in e.details.items()), kind
        back = pickle.loads(pickle.dumps(e))
        assert type(back) is cls and str(back) == str(e) and back.args == e.args
        assert back.kind == e.kind and back.details == e.details
        assert all(getattr(back, k) == v for k, v in e.details.items())
    e = raised(cases[3][0])
    assert set(e.details) == {"iterations", "inliers", "needed"} and e.inliers < e.needed


def test_user_constructed():
    e = eopnp.InvalidOptionError("my message")
    assert isinstance(e, ValueError) and str(e) == "my message"
    with pytest.raises(eopnp.PnpError):
        raise e
