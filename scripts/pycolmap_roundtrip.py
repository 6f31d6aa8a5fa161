#!/usr/bin/env python3
"""Checks that COLMAP itself (through pycolmap) reads the models `eopnp register --write` writes,
with exactly the poses eopnp reports.

For each output format (text and binary) it runs

    eopnp register MODEL --json --write WORK/<format> --write-format <format>

(which prints every image's re-estimated pose as JSON and writes the model with those poses),
loads WORK/<format> with `pycolmap.Reconstruction`, and checks:

- every image's `cam_from_world` (rotation matrix entries and translation) equals the pose in
  eopnp's JSON output to 1e-12, relative (|a - b| <= 1e-12 max(1, |b|));
- the numbers of cameras, images and 3D points equal the input model's (read by pycolmap), and
  so do the cameras' parameters and the 3D points' coordinates (exactly);
- images eopnp could not register (none on the bundled model) keep the input's pose.

Usage (needs `pip install pycolmap numpy`; from the repository root):

    python3 scripts/pycolmap_roundtrip.py                        # data/colmap-boxes, cargo run --release
    python3 scripts/pycolmap_roundtrip.py --model data/colmap-boxes-bin
    python3 scripts/pycolmap_roundtrip.py --eopnp target/release/eopnp --work /tmp/rt
    python3 scripts/pycolmap_roundtrip.py --work /tmp/rt --reuse  # check outputs already written:
        # /tmp/rt/text and /tmp/rt/binary with eopnp's JSON in /tmp/rt/text.json, binary.json

Exit status 0 if every check passes, 1 otherwise.
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

import numpy as np
import pycolmap

TOL = 1e-12


def cam_from_world(image):
    """The image's world-to-camera pose (a method since pycolmap 3.12, an attribute before)."""
    p = image.cam_from_world
    return p() if callable(p) else p


def close(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return bool(np.all(np.abs(a - b) <= TOL * np.maximum(1.0, np.abs(b))))


def run_eopnp(cmd, model, out, fmt, json_path):
    args = cmd + ["register", model, "--json", "--write", out, "--write-format", fmt]
    print("$", " ".join(args))
    res = subprocess.run(args, capture_output=True, text=True)
    if res.returncode != 0:
        sys.exit(f"eopnp failed (exit {res.returncode}):\n{res.stderr}")
    with open(json_path, "w") as f:
        f.write(res.stdout)


def check(model, out, json_path, fmt):
    failures = []
    with open(json_path) as f:
        report = json.load(f)
    src = pycolmap.Reconstruction(model)
    rec = pycolmap.Reconstruction(out)
    counts = [(len(r.cameras), len(r.images), len(r.points3D)) for r in (src, rec)]
    if counts[0] != counts[1]:
        failures.append(f"counts (cameras, images, points) {counts[1]} != input's {counts[0]}")
    for cid, cam in src.cameras.items():
        if cid not in rec.cameras or not np.array_equal(cam.params, rec.cameras[cid].params):
            failures.append(f"camera {cid} differs from the input's")
    diff_points = sum(
        1
        for pid, p in src.points3D.items()
        if pid not in rec.points3D or not np.array_equal(p.xyz, rec.points3D[pid].xyz)
    )
    if diff_points:
        failures.append(f"{diff_points} 3D points differ from the input's")
    worst_r = worst_t = 0.0
    registered = kept = 0
    for entry in report["images"]:
        iid = entry["image_id"]
        if iid not in rec.images:
            failures.append(f"image {iid} missing from the written model")
            continue
        pose = cam_from_world(rec.images[iid])
        r, t = pose.rotation.matrix(), np.asarray(pose.translation)
        if "error" in entry:
            ref = cam_from_world(src.images[iid])
            want_r, want_t = ref.rotation.matrix(), np.asarray(ref.translation)
            kept += 1
        else:
            want_r, want_t = np.array(entry["rotation"]), np.array(entry["translation"])
            registered += 1
        scale = lambda b: np.maximum(1.0, np.abs(b))
        worst_r = max(worst_r, float(np.max(np.abs(r - want_r) / scale(want_r))))
        worst_t = max(worst_t, float(np.max(np.abs(t - want_t) / scale(want_t))))
        if not (close(r, want_r) and close(t, want_t)):
            failures.append(f"image {iid}: pose differs: R {r.tolist()} t {t.tolist()}")
    print(
        f"{fmt:>6}: pycolmap read {out}: {counts[1][0]} cameras, {counts[1][1]} images, "
        f"{counts[1][2]} points (input: {counts[0][0]}, {counts[0][1]}, {counts[0][2]}); "
        f"{registered} poses as eopnp's JSON, {kept} kept; worst relative difference: "
        f"rotation {worst_r:.3g}, translation {worst_t:.3g} (tolerance {TOL:g})"
    )
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--model", default="data/colmap-boxes", help="input COLMAP model directory")
    ap.add_argument(
        "--eopnp",
        default=None,
        help="eopnp binary (default: cargo run --release --quiet --)",
    )
    ap.add_argument("--work", default=None, help="directory for the outputs (default: temporary)")
    ap.add_argument(
        "--reuse",
        action="store_true",
        help="do not run eopnp; check WORK/{text,binary} and WORK/{text,binary}.json",
    )
    a = ap.parse_args()
    cmd = [a.eopnp] if a.eopnp else ["cargo", "run", "--release", "--quiet", "--"]
    if a.reuse and not a.work:
        sys.exit("--reuse needs --work")
    work = a.work or tempfile.mkdtemp(prefix="eopnp-pycolmap-")
    os.makedirs(work, exist_ok=True)
    print(f"pycolmap {pycolmap.__version__}, numpy {np.__version__}")
    failures = []
    for fmt in ["text", "binary"]:
        out, js = os.path.join(work, fmt), os.path.join(work, fmt + ".json")
        if not a.reuse:
            run_eopnp(cmd, a.model, out, fmt, js)
        failures += [f"{fmt}: {f}" for f in check(a.model, out, js, fmt)]
    if not a.work:
        shutil.rmtree(work)
    for f in failures:
        print("FAIL", f)
    print("OK: pycolmap reads both outputs with eopnp's poses" if not failures else "FAILED")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
