#!/usr/bin/env python3
"""Per-call time and accuracy of eopnp from Python against cv2.solvePnP and PoseLib, on
identical problems in one process, and the Python call overhead of eopnp.

A benchmark, not a test: it prints Markdown tables and asserts nothing.

Problems: the paper's protocol (as the Rust comparison program): N points uniform in
[-2, 2] x [-2, 2] x [4, 8] in the camera frame, a random rotation, the camera of f = 800 px,
principal point (320, 240), Gaussian pixel noise of sigma = 2 px; --problems problems per N,
the same arrays for every method (pixels with K for OpenCV and PoseLib, normalised points for
eopnp.solve; the "pixels" row solves the pixels through an eopnp.Camera).

Time: per call, the median over --passes passes of (one pass over all of a row's problems) /
(number of problems), microseconds, one thread; the passes of the methods are interleaved. Rotation error: the largest angle between
corresponding columns of R and the true R, degrees; median and maximum over the problems.

Python call overhead: for each of --overhead-problems problems, (time of one eopnp.solve call
from Python) - (time of the same solve in Rust, run `repeats` times in a loop inside the
extension by eopnp._eopnp._time_solve, the same binary, no conversion); each the minimum over
5 runs of `repeats` calls; the median over the problems is reported, without and with reading
the result's R and t.

Requirements (not needed by the package): pip install numpy opencv-python-headless poselib

Usage: python3 python/bench/compare.py [--problems 200] [--passes 5] [--seed 1]
"""

import argparse
import math
import platform
import statistics
import sys
import time

import numpy as np

import eopnp
from eopnp import _eopnp

try:
    import cv2
except ImportError:  # pragma: no cover - optional
    cv2 = None
try:
    import poselib
except ImportError:  # pragma: no cover - optional
    poselib = None

F, CX, CY = 800.0, 320.0, 240.0
K = np.array([[F, 0.0, CX], [0.0, F, CY], [0.0, 0.0, 1.0]])


def random_rotation(rng):
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def make_problem(rng, n, sigma_px):
    r = random_rotation(rng)
    cam = np.column_stack([rng.uniform(-2, 2, (n, 2)), rng.uniform(4, 8, n)])
    t = cam.mean(axis=0)
    world = np.ascontiguousarray((cam - t) @ r)
    pixels = cam[:, :2] / cam[:, 2:] * F + [CX, CY] + rng.normal(0, sigma_px, (n, 2))
    normalised = (pixels - [CX, CY]) / F
    return {
        "world": world,
        "pixels": np.ascontiguousarray(pixels),
        "normalised": np.ascontiguousarray(normalised),
        "R": r,
        "t": t,
    }


def rot_err_deg(r, r_gt):
    worst = 0.0
    for k in range(3):
        a, b = r[:, k], r_gt[:, k]
        worst = max(worst, math.degrees(math.atan2(np.linalg.norm(np.cross(a, b)), a @ b)))
    return worst


def rodrigues(rvec):
    return cv2.Rodrigues(np.asarray(rvec, dtype=float))[0]


def methods():
    cam = eopnp.Camera.pinhole(F, F, CX, CY)
    ms = [
        ("eopnp default (ML)", lambda p: eopnp.solve(p["world"], p["normalised"]),
         lambda s: s.R),
        ("eopnp default, pixels + Camera",
         lambda p: eopnp.solve(p["world"], p["pixels"], camera=cam), lambda s: s.R),
        ("eopnp algebraic",
         lambda p: eopnp.solve(p["world"], p["normalised"], refinement="algebraic"),
         lambda s: s.R),
    ]
    if cv2 is not None:
        for name, flag in [("cv2 SQPNP", cv2.SOLVEPNP_SQPNP),
                           ("cv2 ITERATIVE", cv2.SOLVEPNP_ITERATIVE)]:
            ms.append((name, lambda p, flag=flag: cv2.solvePnP(
                p["world"], p["pixels"], K, None, flags=flag), lambda s: rodrigues(s[1])))

        def sqpnp_lm(p):
            ok, rvec, tvec = cv2.solvePnP(p["world"], p["pixels"], K, None,
                                          flags=cv2.SOLVEPNP_SQPNP)
            return cv2.solvePnPRefineLM(p["world"], p["pixels"], K, None, rvec, tvec)

        ms.append(("cv2 SQPNP + solvePnPRefineLM", sqpnp_lm, lambda s: rodrigues(s[0])))
    ms.append(("eopnp solve_ransac (4 px)", lambda p: eopnp.solve_ransac(
        p["world"], p["pixels"], camera=cam), lambda s: s[0].R))
    if poselib is not None:
        pl_cam = {"model": "PINHOLE", "width": 640, "height": 480, "params": [F, F, CX, CY]}
        ms.append(("poselib RANSAC (4 px)", lambda p: poselib.estimate_absolute_pose(
            p["pixels"], p["world"], pl_cam, {"max_reproj_error": 4.0}, {}),
            lambda s: s[0].R))
    return ms


def time_pass(fn, problems):
    """Microseconds per call over one pass through the problems."""
    start = time.perf_counter()
    for p in problems:
        fn(p)
    return (time.perf_counter() - start) / len(problems) * 1e6


def overhead(problems, repeats, read_result):
    diffs = []
    rust = []
    for p in problems:
        w, x = p["world"], p["normalised"]
        if read_result:
            def call():
                s = eopnp.solve(w, x)
                return s.R, s.t
        else:
            def call():
                return eopnp.solve(w, x)
        best_py = math.inf
        best_rs = math.inf
        for _ in range(5):
            start = time.perf_counter()
            for _ in range(repeats):
                call()
            best_py = min(best_py, (time.perf_counter() - start) / repeats)
            best_rs = min(best_rs, _eopnp._time_solve(w, x, repeats))
        diffs.append((best_py - best_rs) * 1e6)
        rust.append(best_rs * 1e6)
    return statistics.median(diffs), statistics.median(rust)


def fmt_us(us):
    if us >= 100:
        return f"{us:,.0f}"
    if us >= 10:
        return f"{us:.1f}"
    return f"{us:.2f}"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--problems", type=int, default=200)
    ap.add_argument("--passes", type=int, default=7)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--sigma", type=float, default=2.0)
    ap.add_argument("--sizes", default="10,100,1000")
    ap.add_argument("--overhead-problems", type=int, default=20)
    args = ap.parse_args()
    if cv2 is not None:
        cv2.setNumThreads(1)
    sizes = [int(s) for s in args.sizes.split(",")]
    ms = methods()
    print(f"eopnp {eopnp.__version__}, numpy {np.__version__}, "
          f"cv2 {cv2.__version__ if cv2 else '-'}, "
          f"poselib {getattr(poselib, '__version__', '-') if poselib else '-'}, "
          f"Python {platform.python_version()}, {platform.machine()}")
    print(f"{args.problems} problems per N, sigma = {args.sigma} px, f = {F:g} px, "
          f"{args.passes} passes, seed {args.seed}\n")
    times = {}
    errors = {}
    for n in sizes:
        rng = np.random.default_rng(args.seed * 1000 + n)
        problems = [make_problem(rng, n, args.sigma) for _ in range(args.problems)]
        for name, fn, rot in ms:
            errs = [rot_err_deg(rot(fn(p)), p["R"]) for p in problems]
            errors[name, n] = (statistics.median(errs), max(errs))
        # Passes interleaved across the methods: a load change on a shared machine affects
        # every method alike.
        per_pass = {name: [] for name, _, _ in ms}
        for _ in range(args.passes):
            for name, fn, _ in ms:
                per_pass[name].append(time_pass(fn, problems))
        for name, _, _ in ms:
            times[name, n] = statistics.median(per_pass[name])
    print("Microseconds per call (median of passes):\n")
    print("| method | " + " | ".join(f"N = {n}" for n in sizes) + " |")
    print("|---|" + "---|" * len(sizes))
    for name, _, _ in ms:
        print(f"| {name} | " + " | ".join(fmt_us(times[name, n]) for n in sizes) + " |")
    base = "eopnp default (ML)"
    print(f"\nSpeed-up of `{base}` (time of the method / time of eopnp):\n")
    print("| method | " + " | ".join(f"N = {n}" for n in sizes) + " |")
    print("|---|" + "---|" * len(sizes))
    for name, _, _ in ms:
        if name.startswith("cv2"):
            print(f"| {name} | " + " | ".join(
                f"{times[name, n] / times[base, n]:.1f}x" for n in sizes) + " |")
    print("\nRotation error, degrees (median / max over the problems):\n")
    print("| method | " + " | ".join(f"N = {n}" for n in sizes) + " |")
    print("|---|" + "---|" * len(sizes))
    for name, _, _ in ms:
        print(f"| {name} | " + " | ".join(
            f"{errors[name, n][0]:.4f} / {errors[name, n][1]:.4f}" for n in sizes) + " |")
    print("\nPython call overhead of eopnp.solve (Python call - the same solve in Rust), us, "
          f"median over {args.overhead_problems} problems:\n")
    print("| N | Rust solve | overhead | overhead, reading R and t |")
    print("|---|---|---|---|")
    for n in sizes:
        rng = np.random.default_rng(args.seed * 1000 + n)
        problems = [make_problem(rng, n, args.sigma) for _ in range(args.overhead_problems)]
        repeats = max(20, 20000 // n)
        plain, rust = overhead(problems, repeats, False)
        read, _ = overhead(problems, repeats, True)
        print(f"| {n} | {fmt_us(rust)} | {plain:.2f} | {read:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
