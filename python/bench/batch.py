#!/usr/bin/env python3
"""Batch throughput of eopnp from Python: solve_batch (and solve_ransac_batch) on 1 and 2
threads, against a Python loop of solve calls.

A benchmark, not a test: it prints a Markdown table and asserts nothing.

Problems: the paper's protocol (python/bench/compare.py's): N points uniform in [-2, 2] x
[-2, 2] x [4, 8] in the camera frame, a random rotation, f = 800 px, Gaussian noise of 2 px;
--problems problems (normalised points). For RANSAC, pixels through a pinhole camera with 10 %
of them replaced by outliers, 4 px threshold.

Time: the median over --passes passes (interleaved between the rows) of one batch call over
all the problems; throughput in problems per second; the ratio of the 2-thread throughput to
the 1-thread one. The conversion of the arrays is part of the batch call's time.

Usage: python3 python/bench/batch.py [--n 100] [--problems 10000] [--passes 5] [--seed 1]
"""

import argparse
import os
import platform
import statistics
import time

import numpy as np

import eopnp
from compare import make_problem

F, CX, CY = 800.0, 320.0, 240.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--problems", type=int, default=10000)
    ap.add_argument("--passes", type=int, default=5)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--ransac-problems", type=int, default=2000)
    args = ap.parse_args()

    rng = np.random.default_rng(args.seed)
    made = [make_problem(rng, args.n, 2.0) for _ in range(args.problems)]
    probs = [(p["world"], p["normalised"]) for p in made]
    cam = eopnp.Camera.pinhole(F, F, CX, CY)
    rprobs = []
    for p in made[: args.ransac_problems]:
        px = p["pixels"].copy()
        bad = rng.random(len(px)) < 0.1
        px[bad] = rng.uniform([0, 0], [640, 480], (bad.sum(), 2))
        rprobs.append((p["world"], px))

    rows = {
        "python loop of `solve`": lambda: [eopnp.solve(w, i) for w, i in probs],
        "`solve_batch`, 1 thread": lambda: eopnp.solve_batch(probs, threads=1),
        "`solve_batch`, 2 threads": lambda: eopnp.solve_batch(probs, threads=2),
        "`solve_ransac_batch`, 1 thread": lambda: eopnp.solve_ransac_batch(
            rprobs, camera=cam, threads=1
        ),
        "`solve_ransac_batch`, 2 threads": lambda: eopnp.solve_ransac_batch(
            rprobs, camera=cam, threads=2
        ),
    }
    count = {k: len(rprobs) if "ransac" in k else len(probs) for k in rows}
    times = {k: [] for k in rows}
    for k, fn in rows.items():  # warm-up (the thread pools are built once)
        fn()
    for _ in range(args.passes):
        for k, fn in rows.items():
            t0 = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t0)

    print(
        f"eopnp {eopnp.__version__}, numpy {np.__version__}, CPython "
        f"{platform.python_version()}, {os.cpu_count()} CPUs, load average "
        f"{os.getloadavg()[0]:.2f}; N = {args.n}, median of {args.passes} passes\n"
    )
    print("| method | problems | time (s) | problems / s | us / problem |")
    print("|---|---|---|---|---|")
    rate = {}
    for k in rows:
        t = statistics.median(times[k])
        rate[k] = count[k] / t
        print(f"| {k} | {count[k]} | {t:.3f} | {rate[k]:,.0f} | {1e6 / rate[k]:.2f} |")
    print(
        "\n2 threads / 1 thread: solve_batch "
        f"{rate['`solve_batch`, 2 threads'] / rate['`solve_batch`, 1 thread']:.2f}x, "
        "solve_ransac_batch "
        f"{rate['`solve_ransac_batch`, 2 threads'] / rate['`solve_ransac_batch`, 1 thread']:.2f}x"
    )


if __name__ == "__main__":
    main()
