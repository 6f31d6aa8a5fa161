#!/usr/bin/env python3
"""A known vertical: eopnp's RANSAC with it (``solve_ransac(..., gravity=)``: samples of two,
the upright two-point pose) and without it (P3P), and PoseLib's upright two-point minimal solver
(``poselib.up2p``) alone, on the same problems, one thread. PoseLib's Python bindings (2.0.5)
have no robust estimator with a known vertical (``estimate_absolute_pose`` takes none), and
eopnp's up2p is reached from Python only through its RANSAC: the rows are not like for like,
and the table says which is which.

    pip install numpy poselib eopnp      # eopnp: the wheel of python/
    python3 scripts/compare_gravity_peers.py [--problems 200] [--n 100] [--outliers 0.8]
        [--sigma 0.1] [--seed 7] [--passes 3]

Problems: a pinhole camera of focal length 800 px (640 x 480, principal point at the centre),
a Haar-random rotation and a translation up to a unit per axis, ``--n`` points 2 to 10 units
away, uniform in the image, 1 px of noise; a fraction ``--outliers`` of the pixels replaced by
uniform ones. The vertical: the world's down direction ``(0.2, -0.3, -1)`` (normalised),
measured in the camera with a Gaussian tilt of ``--sigma`` degrees about each of the two axes
across it, given with that sigma. eopnp: ``RansacOptions(threshold_px=4, seed=i)``, its
defaults otherwise. PoseLib's up2p: two correspondences drawn from those kept (not outliers),
as bearing vectors, in frames turned so that the measured vertical is their ``y`` axis (up2p's
convention); the rotation error of the solution nearest the truth (an oracle's choice: what a
sample of two inliers can give at best). Rotation error: the largest angle between
corresponding axes, degrees; a problem without a pose counts as an infinite error. Times: the
median over ``--passes`` passes of (one pass over the problems) / (number of problems).
"""
import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse
import time

import numpy as np
import poselib

import eopnp
from compare_focal_peers import haar, rot_err_deg  # the same metric and draw

DOWN = np.array([0.2, -0.3, -1.0]) / np.linalg.norm([0.2, -0.3, -1.0])
CAM = eopnp.Camera("PINHOLE", [800.0, 800.0, 320.0, 240.0], 640, 480)


def rodrigues(w):
    th = np.linalg.norm(w)
    if th == 0:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def to_y(g):
    """A rotation taking the unit vector g to (0, 1, 0)."""
    y = np.array([0.0, 1.0, 0.0])
    axis = np.cross(g, y)
    s, c = np.linalg.norm(axis), np.dot(g, y)
    if s < 1e-12:
        return np.eye(3) if c > 0 else np.diag([1.0, -1.0, -1.0])
    return rodrigues(axis / s * np.arctan2(s, c))


def problem(rng, n, outliers, sigma_deg):
    R, t = haar(rng), rng.uniform(-1, 1, 3)
    uv = np.column_stack([rng.uniform(0, 640, n), rng.uniform(0, 480, n)])
    z = rng.uniform(2, 10, n)
    cam = np.column_stack([(uv - [320, 240]) / 800.0 * z[:, None], z])
    world = (cam - t) @ R
    pixels = uv + rng.normal(0, 1.0, uv.shape)
    k = int(round(outliers * n))
    idx = rng.permutation(n)[:k]
    pixels[idx] = rng.uniform([0, 0], [640, 480], (k, 2))
    g = R @ DOWN
    a = np.cross(g, rng.normal(size=3))
    a /= np.linalg.norm(a)
    b = np.cross(g, a)
    s = np.radians(sigma_deg)
    measured = rodrigues(a * s * rng.normal() + b * s * rng.normal()) @ g
    return dict(
        world=world, pixels=pixels, R=R, t=t, kept=np.setdiff1d(np.arange(n), idx),
        gravity=eopnp.Gravity(measured, DOWN, sigma_deg), measured=measured,
    )


def timed(run, probs, passes):
    times = []
    for _ in range(passes):
        t0 = time.perf_counter()
        for i, p in enumerate(probs):
            run(p, i)
        times.append((time.perf_counter() - t0) / len(probs))
    return np.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--problems", type=int, default=200)
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--outliers", type=float, default=0.8)
    ap.add_argument("--sigma", type=float, default=0.1)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--passes", type=int, default=3)
    a = ap.parse_args()
    rng = np.random.default_rng(a.seed)
    probs = [problem(rng, a.n, a.outliers, a.sigma) for _ in range(a.problems)]

    def eopnp_ransac(with_gravity):
        def run(p, i):
            try:
                return eopnp.solve_ransac(
                    p["world"], p["pixels"], camera=CAM,
                    gravity=p["gravity"] if with_gravity else None,
                    ransac={"threshold_px": 4.0, "seed": i},
                )
            except eopnp.PnpError:
                return None
        return run

    print(
        f"N = {a.n}, {a.outliers:.0%} outliers, sigma 1 px, the vertical measured to "
        f"{a.sigma:g} deg, {a.problems} problems, one thread; medians over the problems:"
    )
    print()
    print("| estimator | what | rotation error | failures | samples drawn | time |")
    print("|---|---|---|---|---|---|")
    for name, what, g in (
        ("eopnp `solve_ransac(gravity=)`", "RANSAC, up2p samples", True),
        ("eopnp `solve_ransac`", "RANSAC, P3P samples", False),
    ):
        run = eopnp_ransac(g)
        errs, its, fails = [], [], 0
        for i, p in enumerate(probs):
            out = run(p, i)
            if out is None:
                errs.append(np.inf)
                fails += 1
                continue
            errs.append(rot_err_deg(out[0].R, p["R"]))
            its.append(out[1]["iterations"])
        tm = timed(run, probs, a.passes)
        print(
            f"| {name} | {what} | {np.median(errs):.4f} deg | {fails} | "
            f"{np.median(its):.0f} | {1e6 * tm:.0f} µs per problem |"
        )

    # PoseLib's up2p on two kept correspondences, in upright frames.
    srng = np.random.default_rng([a.seed, 2])
    samples = []
    for p in probs:
        two = srng.choice(p["kept"], 2, replace=False)
        qc, qw = to_y(p["measured"]), to_y(DOWN)
        rays = np.column_stack([(p["pixels"][two] - [320.0, 240.0]) / 800.0, np.ones(2)])
        rays /= np.linalg.norm(rays, axis=1)[:, None]
        x = np.ascontiguousarray(rays @ qc.T)
        X = np.ascontiguousarray(p["world"][two] @ qw.T)
        samples.append((x, X, qc, qw, p["R"]))
    errs, counts, none = [], [], 0
    for x, X, qc, qw, R in samples:
        poses = poselib.up2p(x, X)
        counts.append(len(poses))
        if not poses:
            errs.append(np.inf)
            none += 1
            continue
        # x_cam' = R' X' + t' in the upright frames: R = qc^T R' qw.
        errs.append(min(rot_err_deg(qc.T @ q.R @ qw, R) for q in poses))
    times = []
    for _ in range(a.passes):
        t0 = time.perf_counter()
        for x, X, *_ in samples:
            poselib.up2p(x, X)
        times.append((time.perf_counter() - t0) / len(samples))
    print(
        f"| PoseLib {poselib.__version__} `up2p` | minimal solver alone, 2 inliers | "
        f"{np.median(errs):.4f} deg | {none} | {np.median(counts):g} solutions | "
        f"{1e6 * np.median(times):.1f} µs per call |"
    )


if __name__ == "__main__":
    main()
