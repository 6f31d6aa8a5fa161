#!/usr/bin/env python3
"""RANSAC with an unknown focal length: eopnp's ``solve_ransac(..., estimate_focal=True)``
side by side with pycolmap's ``estimate_and_refine_absolute_pose`` (``estimate_focal_length``
and ``refine_focal_length`` on), on the same problems, one thread; and PoseLib's P4Pf minimal
solver (``poselib.p4pf``) alone, its Python bindings having no robust estimator with an unknown
focal length (``estimate_absolute_pose`` takes a known camera).

    pip install numpy pycolmap poselib eopnp      # eopnp: the wheel of python/
    python3 scripts/compare_focal_peers.py [--problems 1000] [--n 100] [--levels 0 0.5 0.8]
        [--seed 7] [--threshold 4] [--passes 3] [--pycolmap-max-trials N]

Problems: a pinhole camera of focal length log-uniform in 300 to 3,000 px (640 x 480,
principal point at the centre), a Haar-random rotation and a translation up to a unit per axis,
``--n`` points 2 to 10 units away, uniform in the image, 1 px of noise; a fraction of the pixels
replaced by uniform ones (outliers). Both libraries get the camera with a focal length 1.3 times
the truth (the starting guess), the principal point exact, the same pixel threshold
(``RansacOptions.threshold_px``, pycolmap's ``RANSACOptions.max_error``), their default
options otherwise (``--pycolmap-max-trials`` sets pycolmap's ``RANSACOptions.max_num_trials``,
10,000 by default), one thread (``OMP_NUM_THREADS=1``; pycolmap's RANSAC has no threads of its
own here). Errors: the focal length's relative error and the rotation error (largest angle
between corresponding axes, degrees) against the truth; a problem without a pose counts as an
infinite error. The last column pairs the two libraries problem by problem: the share of the
problems where eopnp's focal length is the closer to the truth (ties, both infinite, halved). Time per problem: the median over ``--passes`` passes of (one pass over the
level's problems) / (number of problems), inputs converted outside the timed calls.

PoseLib's P4Pf: on each problem of the first level, four correspondences drawn from those kept
(not replaced by outliers), their pixels centred on the principal point, to
``poselib.p4pf(x, X, filter_solutions=True)``; the solutions' count, the focal error of the one
nearest the truth (an oracle's choice: what a RANSAC sample of four inliers can give at best)
and the time per call (median over ``--passes`` passes). No RANSAC row: it would be a loop of
this script's own, not PoseLib's.
"""
import os

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import argparse
import time

import numpy as np
import poselib
import pycolmap

import eopnp


def rot_err_deg(r, r_ref):
    worst = 0.0
    for k in range(3):
        a, b = r[:, k], r_ref[:, k]
        worst = max(worst, np.degrees(np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b))))
    return worst


def haar(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q @ np.diag(np.sign(np.diag(r)))
    return q * np.linalg.det(q)


def problem(rng, n, outliers):
    f = float(10 ** rng.uniform(np.log10(300), np.log10(3000)))
    R, t = haar(rng), rng.uniform(-1, 1, 3)
    uv = np.column_stack([rng.uniform(0, 640, n), rng.uniform(0, 480, n)])
    z = rng.uniform(2, 10, n)
    cam = np.column_stack([(uv - [320, 240]) / f * z[:, None], z])
    world = (cam - t) @ R
    pixels = uv + rng.normal(0, 1.0, uv.shape)
    k = int(round(outliers * n))
    idx = rng.permutation(n)[:k]
    pixels[idx] = rng.uniform([0, 0], [640, 480], (k, 2))
    kept = np.setdiff1d(np.arange(n), idx)
    return dict(world=world, pixels=pixels, R=R, t=t, f=f, kept=kept)


def poselib_p4pf(probs, rng, passes):
    """PoseLib's P4Pf on four kept correspondences of each problem: median solutions per call,
    median (and 90th percentile) focal error of the solution nearest the truth, problems without
    a solution, median time per call."""
    samples = []
    for p in probs:
        four = rng.choice(p["kept"], 4, replace=False)
        x = np.ascontiguousarray(p["pixels"][four] - [320.0, 240.0])
        samples.append((x, np.ascontiguousarray(p["world"][four]), p["f"]))
    counts, errs, none = [], [], 0
    for x, X, f in samples:
        _, fs = poselib.p4pf(x, X, True)
        counts.append(len(fs))
        if not fs:
            none += 1
            errs.append(np.inf)
            continue
        errs.append(min(abs(g / f - 1) for g in fs))
    times = []
    for _ in range(passes):
        t0 = time.perf_counter()
        for x, X, _ in samples:
            poselib.p4pf(x, X, True)
        times.append((time.perf_counter() - t0) / len(samples))
    return np.median(counts), np.median(errs), np.quantile(errs, 0.9, method="higher"), none, np.median(times)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--problems", type=int, default=1000)
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--levels", type=float, nargs="+", default=[0.0, 0.5, 0.8])
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--threshold", type=float, default=4.0)
    ap.add_argument("--passes", type=int, default=3)
    ap.add_argument("--pycolmap-max-trials", type=int, default=None)
    a = ap.parse_args()
    print(
        f"N = {a.n}, sigma 1 px, {a.problems} problems per level, the focal length guessed "
        f"1.3x the truth, threshold {a.threshold:g} px, one thread; medians over the problems:"
    )
    print()
    print(
        "| outliers | library | focal error | rotation error | failures | time per problem "
        "| pycolmap / eopnp | eopnp's focal closer |"
    )
    print("|---|---|---|---|---|---|---|---|")
    first = None
    for level in a.levels:
        rng = np.random.default_rng([a.seed, int(level * 100)])
        probs = [problem(rng, a.n, level) for _ in range(a.problems)]
        first = first or probs
        for p in probs:
            p["eopnp_cam"] = eopnp.Camera("SIMPLE_PINHOLE", [1.3 * p["f"], 320.0, 240.0], 640, 480)

        def run_eopnp(p, i):
            try:
                s, _ = eopnp.solve_ransac(
                    p["world"], p["pixels"], camera=p["eopnp_cam"], estimate_focal=True,
                    ransac={"threshold_px": a.threshold, "seed": i},
                )
                return s.R, s.focal[0]
            except eopnp.PnpError:
                return None

        est = pycolmap.AbsolutePoseEstimationOptions()
        est.estimate_focal_length = True
        est.ransac.max_error = a.threshold
        if a.pycolmap_max_trials is not None:
            est.ransac.max_num_trials = a.pycolmap_max_trials
        ref = pycolmap.AbsolutePoseRefinementOptions()
        ref.refine_focal_length = True

        def run_pycolmap(p, i):
            cam = pycolmap.Camera(
                model="SIMPLE_PINHOLE", width=640, height=480, params=[1.3 * p["f"], 320.0, 240.0]
            )
            est.ransac.random_seed = i
            out = pycolmap.estimate_and_refine_absolute_pose(p["pixels"], p["world"], cam, est, ref)
            if out is None:
                return None
            return out["cam_from_world"].rotation.matrix(), cam.focal_length

        rows = {}
        for name, run in (("eopnp", run_eopnp), ("pycolmap", run_pycolmap)):
            fe, re_, fails = [], [], 0
            for i, p in enumerate(probs):
                out = run(p, i)
                if out is None:
                    fe.append(np.inf)
                    re_.append(np.inf)
                    fails += 1
                    continue
                R, f = out
                fe.append(abs(f / p["f"] - 1))
                re_.append(rot_err_deg(R, p["R"]))
            times = []
            for _ in range(a.passes):
                t0 = time.perf_counter()
                for i, p in enumerate(probs):
                    run(p, i)
                times.append((time.perf_counter() - t0) / len(probs))
            rows[name] = (np.median(fe), np.median(re_), fails, np.median(times), np.array(fe))
        ours, theirs = rows["eopnp"][4], rows["pycolmap"][4]
        closer = np.mean(np.where(ours == theirs, 0.5, ours < theirs))
        for name in ("eopnp", "pycolmap"):
            fe, re_, fails, tm, _ = rows[name]
            ratio = rows["pycolmap"][3] / rows["eopnp"][3]
            paired = f"{ratio:.1f}x | {100 * closer:.1f} %" if name == "pycolmap" else " | "
            print(
                f"| {level:.0%} | {name} | {100 * fe:.3f} % | {re_:.4f} deg | {fails} | "
                f"{1e3 * tm:.3f} ms | {paired} |"
            )
    count, med, p90, none, tm = poselib_p4pf(first, np.random.default_rng([a.seed, 1]), a.passes)
    print()
    print(
        f"PoseLib {poselib.__version__} P4Pf (poselib.p4pf) alone, 4 correspondences of each of the "
        f"{len(first)} problems of the first level (no outliers among them), 1 px noise:"
    )
    print()
    print("| solutions per call | focal error, nearest solution | 90th percentile | no solution | time per call |")
    print("|---|---|---|---|---|")
    print(f"| {count:g} | {100 * med:.2f} % | {100 * p90:.2f} % | {none} | {1e6 * tm:.1f} µs |")


if __name__ == "__main__":
    main()
