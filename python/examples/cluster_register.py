"""Registers a batch of images on a Dask distributed cluster with eopnp, and checks the poses
equal the serial ones.

The batch: every image of the bundled COLMAP model (data/colmap-boxes), copied ``--copies``
times with fresh pixel noise (0.5 px) and 10 % of the observations replaced by outliers, so
that each copy is a separate robust registration (``solve_ransac_batch``). The batch is split
into partitions; each partition is one Dask task that calls ``eopnp.solve_ransac_batch`` on
its problems (the GIL released, ``--threads`` threads per task). Partition ``p`` uses the base
seed ``problem_seed(SEED, p)``, so problem ``k`` of it uses ``problem_seed(that, k)``: the
result of every problem is fixed by (partition, index) alone, whichever worker runs it.

Locally (the default) it starts a ``LocalCluster`` of ``--workers`` worker processes:

    python python/examples/cluster_register.py --workers 2 --copies 20

On a real cluster, install the same eopnp wheel on every worker (``pip install
eopnp-*.whl``), start ``dask scheduler`` and ``dask worker tcp://scheduler:8786`` processes
(or use dask-jobqueue, dask-kubernetes, ...), and point the client at the scheduler:

    python python/examples/cluster_register.py --scheduler tcp://scheduler:8786

Only the arrays (world points, pixels) and the Cameras travel to the workers (eopnp's
``Camera``, ``Solution``, ``RansacOptions`` and exceptions pickle); the workers need no copy
of the model. Exit status 0 when every cluster result equals the serial one.
"""

import argparse
import pathlib
import sys
import time

import numpy as np

import eopnp

SEED = 2026
MODEL = pathlib.Path(__file__).resolve().parents[2] / "data" / "colmap-boxes"


def make_problems(model, copies, rng):
    """(world, pixels) problems and their cameras: every image, ``copies`` noisy copies."""
    problems, cameras = [], []
    for image_id in model.image_ids:
        world, pixels = model.correspondences(image_id)
        camera = model.camera_of(image_id)
        for _ in range(copies):
            p = pixels + rng.normal(0.0, 0.5, pixels.shape)
            bad = rng.random(len(p)) < 0.1
            p[bad] = rng.uniform([0, 0], [camera.width, camera.height], (bad.sum(), 2))
            problems.append((world, p))
            cameras.append(camera)
    return problems, cameras


def partitions(n, parts):
    """``parts`` contiguous index ranges covering 0..n."""
    bounds = np.linspace(0, n, parts + 1).astype(int)
    return [range(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]


def register_partition(problems, cameras, part, threads):
    """One Dask task: a partition's robust registrations (runs on a worker)."""
    opts = eopnp.RansacOptions(threshold_px=4.0, seed=eopnp.problem_seed(SEED, part))
    return eopnp.solve_ransac_batch(problems, camera=cameras, ransac=opts, threads=threads)


def serial(problems, cameras, ranges):
    """The reference: every problem alone through ``solve_ransac``, in this process."""
    out = []
    for part, rg in enumerate(ranges):
        base = eopnp.problem_seed(SEED, part)
        for k, i in enumerate(rg):
            opts = eopnp.RansacOptions(threshold_px=4.0, seed=eopnp.problem_seed(base, k))
            try:
                out.append(eopnp.solve_ransac(*problems[i], camera=cameras[i], ransac=opts))
            except eopnp.PnpError as e:
                out.append(e)
    return out


def same(a, b):
    """Two entries are equal: the same pose and inliers, or the same error."""
    if isinstance(a, Exception) or isinstance(b, Exception):
        return type(a) is type(b) and str(a) == str(b)
    return a[0] == b[0] and np.array_equal(a[1]["inliers"], b[1]["inliers"])


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scheduler", help="a running scheduler's address (default: LocalCluster)")
    ap.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    ap.add_argument("--copies", type=int, default=20, help="noisy copies of each image")
    ap.add_argument("--partitions", type=int, default=8)
    ap.add_argument("--threads", type=int, default=1, help="eopnp threads per task")
    args = ap.parse_args(argv)

    from dask.distributed import Client, LocalCluster

    model = eopnp.read_colmap_model(MODEL)
    problems, cameras = make_problems(model, args.copies, np.random.default_rng(SEED))
    ranges = partitions(len(problems), args.partitions)

    start = time.perf_counter()
    if args.scheduler:
        client, cluster = Client(args.scheduler), None
    else:
        cluster = LocalCluster(
            n_workers=args.workers, threads_per_worker=1, processes=True,
            dashboard_address=None,
        )
        client = Client(cluster)
    try:
        started = time.perf_counter()
        futures = [
            client.submit(
                register_partition,
                [problems[i] for i in rg],
                [cameras[i] for i in rg],
                part,
                args.threads,
                pure=False,
            )
            for part, rg in enumerate(ranges)
        ]
        distributed = [r for chunk in client.gather(futures) for r in chunk]
        done = time.perf_counter()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    reference = serial(problems, cameras, ranges)
    serial_s = time.perf_counter() - done
    mismatches = [i for i, (a, b) in enumerate(zip(distributed, reference)) if not same(a, b)]
    failed = sum(isinstance(r, Exception) for r in distributed)
    errors = [
        r[1]["rmse_px"] for r in distributed if not isinstance(r, Exception)
    ]
    print(
        f"{len(problems)} registrations ({len(model)} images x {args.copies} copies, "
        f"{len(ranges)} partitions) on {args.scheduler or f'{args.workers} local workers'}: "
        f"cluster start {started - start:.1f} s, solve {done - started:.2f} s, "
        f"serial {serial_s:.2f} s; {failed} failed; median inlier RMSE "
        f"{np.median(errors):.3f} px; {len(mismatches)} differ from the serial results"
    )
    return 1 if mismatches or len(distributed) != len(reference) else 0


if __name__ == "__main__":
    sys.exit(main())
