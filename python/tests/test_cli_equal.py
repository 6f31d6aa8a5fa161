"""The package gives the Rust library's results: the same poses as the eopnp CLI (built by
`cargo test --workspace --release`; scripts/test.sh passes its path in EOPNP_CLI), to the
last bit, on the bundled model (plain and RANSAC) and on a synthetic `solve` problem; and
`refine` started from the CLI's pose stays on it."""

import json
import subprocess

import numpy as np
import pytest

import eopnp
from conftest import DATA, problem


def cli_json(cli, *args, stdin=None):
    out = subprocess.run([cli, *args], input=stdin, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def assert_same_pose(sol, entry):
    assert np.array_equal(sol.R, np.array(entry["rotation"]))
    assert np.array_equal(sol.t, np.array(entry["translation"]))
    assert np.array_equal(sol.q, np.array(entry["quaternion_wxyz"]))


def test_register_equals_cli(cli):
    model = eopnp.read_colmap_model(DATA / "colmap-boxes")
    for args, kw in [([], {}), (["--ransac"], {"ransac": True}), (["--algebraic"],
                                                                   {"refinement": "algebraic"})]:
        out = cli_json(cli, "register", str(DATA / "colmap-boxes"), "--json", *args)
        assert [e["image_id"] for e in out["images"]] == model.image_ids
        for entry in out["images"]:
            reg = eopnp.register_image(model, entry["image_id"], **kw)
            assert_same_pose(reg.solution, entry)
            assert (reg.n, reg.inliers, reg.skipped) == (entry["n"], entry["inliers"],
                                                         entry["skipped"])
            assert reg.rotation_error_deg == entry["rotation_error_deg"]
            assert reg.rmse_px == entry["rmse_px"]


def test_solve_equals_cli(cli, rng):
    cam = eopnp.Camera("OPENCV", [800.0, 790.0, 320.0, 240.0, -0.1, 0.01, 1e-3, -5e-4])
    world, image, _, _ = problem(rng, 40, sigma_px=1.0)
    pixels = cam.project(image)
    doc = {
        "camera": {"model": cam.model, "params": cam.params.tolist()},
        "points2d": pixels.tolist(),
        "points3d": world.tolist(),
    }
    out = cli_json(cli, "solve", "-", "--format", "json", stdin=json.dumps(doc))
    sol = eopnp.solve(world, pixels, camera=cam)
    assert_same_pose(sol, out)
    assert sol.cost == out["cost"]
    assert (sol.cheirality_ok, sol.degenerate) == (out["cheirality_ok"], out["degenerate"])
    # Tracking from the Rust pose: refine keeps it (it is the pixel ML pose).
    start = (np.array(out["rotation"]), np.array(out["translation"]))
    for initial in [start, (np.array(out["quaternion_wxyz"]), start[1])]:
        ref = eopnp.refine(world, pixels, initial, camera=cam)
        assert ref.converged and ref.source == "initial"
        assert np.abs(ref.R - start[0]).max() < 1e-12
        assert np.abs(ref.t - start[1]).max() < 1e-12
        assert ref.cost == pytest.approx(out["cost"], rel=1e-12)
