#!/usr/bin/env python3
"""eopnp's RANSAC side by side with PoseLib's on the same problems, in one run.

    pip install poselib numpy
    cargo build --release
    python3 scripts/compare_poselib.py [--binary target/release/eopnp] [--model data/colmap-boxes]
        [--levels 0 0.5 0.8] [--seed 42] [--threshold 4] [--repeats 3]

For each outlier level the script
1. runs `eopnp register MODEL --ransac --outliers L --seed S --threshold T --json
   --export-problems FILE`: eopnp's poses, errors, floor (EOPnP on the true correspondences)
   and time per image (best of 3, undistortion included), and the exact problems it solved
   (pixels, 3D points with the injected wrong points, camera);
2. solves the same problems with `poselib.estimate_absolute_pose` with the same camera
   (COLMAP model and parameters; PoseLib undistorts internally), the same pixel threshold
   (`max_reproj_error`) and PoseLib's default RANSAC and bundle options otherwise, timing each
   image (best of --repeats);
3. prints success, rotation and translation errors against the model's pose (the metrics of
   `eopnp register`: largest axis angle in degrees, |t - t_ref| / |t_ref| in percent) and
   milliseconds per image, side by side.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import poselib


def rot_err_deg(r, r_ref):
    worst = 0.0
    for k in range(3):
        a, b = r[:, k], r_ref[:, k]
        ang = np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b))
        worst = max(worst, np.degrees(ang))
    return worst


def trans_err_pct(t, t_ref):
    return 100.0 * np.linalg.norm(t - t_ref) / np.linalg.norm(t_ref)


def poselib_solve(img, threshold, repeats):
    cam = img["camera"]
    camera = {"model": cam["model"], "width": cam["width"], "height": cam["height"],
              "params": cam["params"]}
    p2 = np.asarray(img["points2d"], dtype=np.float64)
    p3 = np.asarray(img["points3d"], dtype=np.float64)
    best_t, result = float("inf"), None
    for _ in range(repeats):
        t0 = time.perf_counter()
        pose, info = poselib.estimate_absolute_pose(
            p2, p3, camera, {"max_reproj_error": threshold}, {})
        best_t = min(best_t, time.perf_counter() - t0)
        result = (pose, info)
    pose, info = result
    r = np.asarray(pose.R)
    t = np.asarray(pose.t)
    return r, t, info, best_t * 1e3


def summary(values):
    v = np.asarray(values, dtype=np.float64)
    return v.max(), np.median(v)


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--binary", default=os.path.join(root, "target", "release", "eopnp"))
    ap.add_argument("--model", default=os.path.join(root, "data", "colmap-boxes"))
    ap.add_argument("--levels", type=float, nargs="+", default=[0.0, 0.5, 0.8])
    ap.add_argument("--seed", type=int, default=42)
    ap.add_argument("--threshold", type=float, default=4.0)
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args()
    print(f"PoseLib {getattr(poselib, '__version__', '?')}; threshold {a.threshold} px; "
          f"seed {a.seed}; times: best of 3 (eopnp) / {a.repeats} (PoseLib) per image\n")
    hdr = (f"{'outl':>5} {'image':>5} {'ok e/p':>6} | {'rot deg eopnp':>13} {'poselib':>9} "
           f"{'floor':>9} | {'trans % eopnp':>13} {'poselib':>9} {'floor':>9} | "
           f"{'ms eopnp':>8} {'poselib':>8} {'ratio':>6}")
    print(hdr)
    print("-" * len(hdr))
    totals = []
    for level in a.levels:
        with tempfile.TemporaryDirectory() as d:
            prob_path = os.path.join(d, "problems.json")
            out = subprocess.run(
                [a.binary, "register", a.model, "--ransac", "--outliers", str(level),
                 "--seed", str(a.seed), "--threshold", str(a.threshold), "--json",
                 "--export-problems", prob_path],
                check=True, capture_output=True, text=True).stdout
            ours = {im["image_id"]: im for im in json.loads(out)["images"]}
            with open(prob_path) as f:
                problems = json.load(f)
        rows = []
        for img in problems["images"]:
            iid = img["image_id"]
            r_ref = np.asarray(img["reference_rotation"])
            t_ref = np.asarray(img["reference_translation"])
            e = ours.get(iid, {})
            e_ok = "error" not in e
            r, t, info, ms = poselib_solve(img, a.threshold, a.repeats)
            p_ok = bool(np.all(np.isfinite(r))) and info.get("num_inliers", 0) >= 4
            floor = (e.get("robust") or {}).get("floor") or {}
            row = dict(
                e_ok=e_ok, p_ok=p_ok,
                e_r=e.get("rotation_error_deg", float("nan")),
                p_r=rot_err_deg(r, r_ref),
                f_r=floor.get("rotation_error_deg", float("nan")),
                e_t=e.get("translation_error_pct", float("nan")),
                p_t=trans_err_pct(t, t_ref),
                f_t=floor.get("translation_error_pct", float("nan")),
                e_ms=e.get("micros", float("nan")) / 1e3, p_ms=ms)
            rows.append(row)
            print(f"{level:>5.2f} {iid:>5} {int(e_ok)}/{int(p_ok):<4} | {row['e_r']:>13.5f} "
                  f"{row['p_r']:>9.5f} {row['f_r']:>9.5f} | {row['e_t']:>13.5f} "
                  f"{row['p_t']:>9.5f} {row['f_t']:>9.5f} | {row['e_ms']:>8.2f} "
                  f"{row['p_ms']:>8.2f} {row['p_ms'] / row['e_ms']:>6.1f}")
        totals.append((level, rows))
    print("\nPer level: worst / median over images")
    print(f"{'outl':>5} {'success e/p':>11} | {'rot deg eopnp':>17} {'poselib':>17} {'floor':>17} | "
          f"{'trans % eopnp':>17} {'poselib':>17} {'floor':>17} | {'ms eopnp':>13} {'poselib':>13}")
    for level, rows in totals:
        def s(key):
            w, m = summary([r[key] for r in rows])
            return f"{w:>8.5f}/{m:<8.5f}"

        def ms(key):
            v = [r[key] for r in rows]
            return f"{min(v):>5.1f}-{max(v):<7.1f}"

        ne = sum(r["e_ok"] for r in rows)
        np_ = sum(r["p_ok"] for r in rows)
        print(f"{level:>5.2f} {ne:>5}/{np_:<5} | {s('e_r')} {s('p_r')} {s('f_r')} | "
              f"{s('e_t')} {s('p_t')} {s('f_t')} | {ms('e_ms')} {ms('p_ms')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
