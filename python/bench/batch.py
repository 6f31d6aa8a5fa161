#!/usr/bin/env python3
"""Batch throughput of eopnp from Python: solve_batch, solve_batch_arrays (and
solve_ransac_batch) on 1 and 2 threads, against a Python loop of solve calls.

A benchmark, not a test: it prints a Markdown table and asserts nothing.

Problems: the paper's protocol (python/bench/compare.py's): N points uniform in [-2, 2] x
[-2, 2] x [4, 8] in the camera frame, a random rotation, f = 800 px, Gaussian noise of 2 px;
--problems problems (normalised points). For RANSAC, pixels through a pinhole camera with 10 %
of them replaced by outliers, 4 px threshold.

Time: the median over --passes passes (interleaved between the rows) of one batch call over
all the problems (and the best pass: on a shared machine, other processes only add time); throughput in problems per second; the ratio of the 2-thread throughput to
the 1-thread one. The reading of the arrays and the creation of the results are part of the
batch call's time (solve_batch_arrays: the problems stacked once, before the timing, into
(B, N, 3) and (B, N, 2) arrays).

CPU time per problem: of the whole process, and of the calling thread alone. A batch call
waits while the pool's threads solve, so the calling thread's CPU time is the serial part of
the call (the checks, conversions and result objects with the GIL held), which no thread count
shortens; measured as CPU time, it does not depend on the other processes of a shared machine
as the wall times do.

Reference, the machine's own limit: the Rust solve of one problem repeated in a loop inside
the extension (eopnp._eopnp._time_solve, the GIL released, no conversion, hot caches) on one
Python thread, and on two threads at once; the ratio of the throughputs is what two threads
give without any serial part.

Usage: python3 python/bench/batch.py [--n 100] [--problems 10000] [--passes 5] [--seed 1]
"""

import argparse
import os
import platform
import statistics
import threading
import time

import numpy as np

import eopnp
from compare import make_problem
from eopnp import _eopnp

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
    worlds = np.stack([w for w, _ in probs])
    images = np.stack([i for _, i in probs])
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
        "`solve_batch_arrays`, 1 thread": lambda: eopnp.solve_batch_arrays(
            worlds, images, threads=1
        ),
        "`solve_batch_arrays`, 2 threads": lambda: eopnp.solve_batch_arrays(
            worlds, images, threads=2
        ),
        "`solve_ransac_batch`, 1 thread": lambda: eopnp.solve_ransac_batch(
            rprobs, camera=cam, threads=1
        ),
        "`solve_ransac_batch`, 2 threads": lambda: eopnp.solve_ransac_batch(
            rprobs, camera=cam, threads=2
        ),
    }
    reps = 2000  # of the reference's solve, per thread
    rows["reference: Rust solve loop, 1 thread"] = lambda: reference(probs[0], reps, 1)
    rows["reference: Rust solve loop, 2 threads"] = lambda: reference(probs[0], reps, 2)
    count = {k: len(rprobs) if "ransac" in k else len(probs) for k in rows}
    count["reference: Rust solve loop, 1 thread"] = reps
    count["reference: Rust solve loop, 2 threads"] = 2 * reps
    times = {k: [] for k in rows}
    serial = {k: [] for k in rows}  # CPU time of the calling thread
    cpu = {k: [] for k in rows}  # CPU time of the process (every thread)
    for k, fn in rows.items():  # warm-up (the thread pools are built once)
        fn()
    for _ in range(args.passes):
        for k, fn in rows.items():
            c0, p0 = time.thread_time(), time.process_time()
            t0 = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t0)
            serial[k].append(time.thread_time() - c0)
            cpu[k].append(time.process_time() - p0)

    print(
        f"eopnp {eopnp.__version__}, numpy {np.__version__}, CPython "
        f"{platform.python_version()}, {os.cpu_count()} CPUs, load average "
        f"{os.getloadavg()[0]:.2f}; N = {args.n}, median of {args.passes} passes\n"
    )
    print(
        "| method | problems | time (s) | problems / s | us / problem | best pass, us / problem "
        "| CPU, us / problem | of which the calling thread |"
    )
    print("|---|---|---|---|---|---|---|---|")
    rate, best = {}, {}
    for k in rows:
        t = statistics.median(times[k])
        rate[k] = count[k] / t
        best[k] = count[k] / min(times[k])
        us = 1e6 / count[k]
        print(
            f"| {k} | {count[k]} | {t:.3f} | {rate[k]:,.0f} | {1e6 / rate[k]:.2f} | "
            f"{1e6 / best[k]:.2f} | {statistics.median(cpu[k]) * us:.2f} | "
            f"{statistics.median(serial[k]) * us:.2f} |"
        )
    ratio = {
        name: rate[f"{name}, 2 threads"] / rate[f"{name}, 1 thread"]
        for name in (
            "`solve_batch`",
            "`solve_batch_arrays`",
            "`solve_ransac_batch`",
            "reference: Rust solve loop",
        )
    }
    print("\n2 threads / 1 thread: " + ", ".join(f"{k} {v:.2f}x" for k, v in ratio.items()))
    best_ratio = {n: best[f"{n}, 2 threads"] / best[f"{n}, 1 thread"] for n in ratio}
    print(
        "best passes, 2 threads / 1 thread: "
        + ", ".join(f"{k} {v:.2f}x" for k, v in best_ratio.items())
    )
    print(f"load average after the run: {os.getloadavg()[0]:.2f}")


def reference(problem, reps, threads):
    """``reps`` Rust solves of ``problem`` on each of ``threads`` Python threads at once (the
    GIL released inside the extension)."""
    world, image = problem
    workers = [
        threading.Thread(target=_eopnp._time_solve, args=(world, image, reps))
        for _ in range(threads)
    ]
    for w in workers:
        w.start()
    for w in workers:
        w.join()


if __name__ == "__main__":
    main()
