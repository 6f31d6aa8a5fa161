"""eopnp.SolverOptions: the library's defaults, readable attributes, repr, ==, hash, pickling,
validation at construction (InvalidOptionError naming the option), and options= accepted by
every function that solves, with the same results as the same options given as keywords;
options= together with keywords, unknown keywords and wrong types raise TypeError."""

import copy
import pickle

import numpy as np
import pytest

import eopnp
from conftest import DATA, problem

CAM = eopnp.Camera("SIMPLE_RADIAL", [800.0, 320.0, 240.0, -0.05], 640, 480)

DEFAULTS = dict(
    refinement="ml",
    planar="auto",
    newton_iterations=None,
    newton_step_tolerance=None,
    reprojection_iterations=None,
    exhaustive=False,
    loss="squared",
    covariance=None,
)
OTHERS = dict(
    refinement="algebraic",
    planar="nonplanar",
    newton_iterations=30,
    newton_step_tolerance=1e-10,
    reprojection_iterations=100,
    exhaustive=True,
    loss=("huber", 0.01),
    covariance="estimated",
)


def test_defaults_and_attributes():
    o = eopnp.SolverOptions()
    assert o.as_dict() == DEFAULTS
    assert all(getattr(o, k) == v for k, v in DEFAULTS.items())
    p = eopnp.SolverOptions(**OTHERS)
    assert p.as_dict() == OTHERS and all(getattr(p, k) == v for k, v in OTHERS.items())
    assert eopnp.SolverOptions(refinement="reprojection").refinement == "ml"
    assert eopnp.SolverOptions(loss=["cauchy", 2]).loss == ("cauchy", 2.0)
    assert eopnp.SolverOptions(covariance=2).covariance == 2.0
    with pytest.raises(TypeError):
        eopnp.SolverOptions("ml")  # keyword-only
    with pytest.raises(TypeError):
        eopnp.SolverOptions(refinment="ml")
    with pytest.raises(AttributeError):
        p.loss = None  # immutable


def test_repr_eq_hash_pickle_replace():
    o = eopnp.SolverOptions(**OTHERS)
    assert repr(o).startswith("SolverOptions(refinement='algebraic', planar='nonplanar'")
    assert eval(repr(o), {"SolverOptions": eopnp.SolverOptions}) == o
    same = eopnp.SolverOptions(**OTHERS)
    assert o == same and hash(o) == hash(same) and o != eopnp.SolverOptions() and o != OTHERS
    assert len({o, same, eopnp.SolverOptions()}) == 2
    for back in (pickle.loads(pickle.dumps(o)), copy.copy(o), copy.deepcopy(o)):
        assert type(back) is eopnp.SolverOptions and back == o
    r = o.replace(loss=None, exhaustive=False)
    assert r.loss == "squared" and not r.exhaustive and r.refinement == "algebraic"
    assert o.loss == ("huber", 0.01)  # unchanged
    assert eopnp.SolverOptions(newton_step_tolerance=-0.0) == eopnp.SolverOptions(
        newton_step_tolerance=0.0
    )
    with pytest.raises(TypeError):
        o.replace(refinment="ml")


@pytest.mark.parametrize(
    "kw, option",
    [
        (dict(refinement="fast"), "refinement"),
        (dict(planar="maybe"), "planar"),
        (dict(newton_iterations=-1), "newton_iterations"),
        (dict(reprojection_iterations=2**40), "reprojection_iterations"),
        (dict(newton_step_tolerance=float("nan")), "newton_step_tolerance"),
        (dict(newton_step_tolerance=-1.0), "newton_step_tolerance"),
        (dict(loss=("huber", 0.0)), "loss"),
        (dict(loss=("tukey", 1.0)), "loss"),
        (dict(loss="huber"), "loss"),
        (dict(covariance=-1.0), "covariance"),
        (dict(covariance=True), "covariance"),
        (dict(covariance="guess"), "covariance"),
    ],
)
def test_validated_at_construction(kw, option):
    with pytest.raises(eopnp.InvalidOptionError) as e:
        eopnp.SolverOptions(**kw)
    assert e.value.option == option
    with pytest.raises(eopnp.InvalidOptionError):
        eopnp.SolverOptions().replace(**kw)


@pytest.fixture(scope="module")
def model():
    return eopnp.read_colmap_model(DATA / "colmap-boxes")


def calls(rng, model):
    """(name, call(**solver options)) of every function that solves; each result compared
    with ==."""
    world, image = problem(rng, 12, sigma_px=1.0)[:2]
    pixels = CAM.project(image)
    prior = eopnp.solve(world, image)
    probs = [problem(rng, 12, sigma_px=1.0)[:2] for _ in range(4)]
    stacked = np.stack([w for w, _ in probs]), np.stack([i for _, i in probs])

    def arrays(res):
        return (res.R.tolist(), res.t.tolist(), res.cost.tolist(), res.errors.keys())

    def registration(r):
        return (r.solution, r.inliers)

    return [
        ("solve", lambda **o: eopnp.solve(world, pixels, camera=CAM, **o)),
        ("solve_all", lambda **o: eopnp.solve_all(world, image, **o)),
        ("refine", lambda **o: eopnp.refine(world, image, prior, **o)),
        (
            "solve_ransac",
            lambda **o: eopnp.solve_ransac(world, pixels, camera=CAM, **o)[0],
        ),
        ("solve_batch", lambda **o: eopnp.solve_batch(probs, threads=2, **o)),
        (
            "solve_ransac_batch",
            lambda **o: [r[0] for r in eopnp.solve_ransac_batch(probs, focal=800.0, **o)],
        ),
        ("solve_batch_arrays", lambda **o: arrays(eopnp.solve_batch_arrays(*stacked, **o))),
        ("register_image", lambda **o: registration(eopnp.register_image(model, 2, **o))),
        (
            "register_images",
            lambda **o: [registration(r) for r in eopnp.register_images(model, [1, 3], **o)],
        ),
    ]


def test_every_function_takes_options(rng, model):
    kw = dict(loss=("huber", 2.0), covariance="estimated", reprojection_iterations=150)
    full = dict(kw, refinement="algebraic", planar="nonplanar")
    for name, call in calls(rng, model):
        given = kw if name == "refine" else full  # refine: the options of its refinement
        want = call(**given)
        assert call(options=eopnp.SolverOptions(**given)) == want, name
        assert call(options=given) == want, name  # a dict of its fields
        assert call(options=None) == call(), name
        with pytest.raises(TypeError, match="not both"):
            call(options=eopnp.SolverOptions(), loss=None)
        with pytest.raises(TypeError, match="unexpected keyword argument 'refinment'"):
            call(refinment="ml")
        with pytest.raises(eopnp.InvalidOptionError, match="options must be") as e:
            call(options=5)
        assert e.value.option == "options"
        with pytest.raises(eopnp.InvalidOptionError, match="unknown solver option") as e:
            call(options={"los": None})
        with pytest.raises(eopnp.InvalidOptionError) as e:
            call(options={"loss": ("huber", -1.0)})
        assert e.value.option == "loss"
        with pytest.raises(TypeError, match="exhaustive"):
            call(exhaustive="yes")


def test_options_change_the_result(rng):
    world, image = problem(rng, 12, sigma_px=1.0)[:2]
    ml = eopnp.solve(world, image)
    alg = eopnp.solve(world, image, options=eopnp.SolverOptions(refinement="algebraic"))
    assert alg != ml and alg.reprojection_iterations == 0
    cov = eopnp.solve(world, image, options=eopnp.SolverOptions(covariance=1e-3))
    assert ml.covariance is None and cov.covariance.shape == (6, 6) and cov.sigma == 1e-3


def test_refine_keywords_and_global_search_options(rng):
    world, image = problem(rng, 12, sigma_px=1.0)[:2]
    prior = eopnp.solve(world, image)
    for kw in ("refinement", "planar", "exhaustive"):
        with pytest.raises(TypeError, match=f"unexpected keyword argument '{kw}'"):
            eopnp.refine(world, image, prior, **{kw: OTHERS[kw]})
    # In options=, planar and exhaustive have no effect on refine; refinement="algebraic" only
    # iterates its Newton start further (the same pose).
    want = eopnp.refine(world, image, prior)
    search = eopnp.SolverOptions(planar="nonplanar", exhaustive=True)
    assert eopnp.refine(world, image, prior, options=search) == want
    alg = eopnp.refine(world, image, prior, options=search.replace(refinement="algebraic"))
    assert alg.converged and alg.source == "initial" and alg.reprojection_iterations > 0
    assert np.allclose(alg.R, want.R, atol=1e-9) and np.allclose(alg.t, want.t, atol=1e-9)
