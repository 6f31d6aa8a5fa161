#!/usr/bin/env python3
"""Optional: OpenCV's solvePnP on the exact problems of the eopnp comparison.

The comparison program (`cargo run --release -p eopnp-compare`) writes every problem it
solves to `target/compare/problems.json`; this script reads that file, runs `cv2.solvePnP`
with SOLVEPNP_SQPNP, SOLVEPNP_EPNP, SOLVEPNP_ITERATIVE and (planar rows) SOLVEPNP_IPPE on
the pixel coordinates with the same intrinsics, and prints a Markdown table with the same
columns and the same definitions as the comparison program's:

- failure: no solution (solvePnP returned False or raised) or rotation error > 5 degrees;
- rotation error: largest angle between corresponding columns of R and R_gt, degrees;
- translation error: 100 |t - t_gt| / |t_gt|, percent; median and mean over the non-failed
  trials;
- time: median over --passes timed passes of (time of one pass over all the row's problems) /
  (number of problems), microseconds (this includes Python's call overhead, a few us);
- last column: (cv2 SQPNP time) / (method time).

Requirements (not needed for anything else in the project):
    pip install opencv-python-headless numpy

Usage:
    python3 scripts/compare_opencv.py [target/compare/problems.json] [--passes 5] [--out FILE]
"""

import argparse
import json
import math
import statistics
import sys
import time

try:
    import cv2
    import numpy as np
except ImportError:  # pragma: no cover - optional tooling
    sys.exit("this script needs OpenCV and numpy: pip install opencv-python-headless numpy")

METHODS = [
    ("cv2 SQPNP", "SOLVEPNP_SQPNP", "any"),
    ("cv2 EPNP", "SOLVEPNP_EPNP", "any"),
    ("cv2 ITERATIVE", "SOLVEPNP_ITERATIVE", "any"),
    ("cv2 IPPE", "SOLVEPNP_IPPE", "planar"),
]


def rot_err_deg(r, r_gt):
    """Largest angle between corresponding columns, degrees (atan2 form, as the Rust code)."""
    worst = 0.0
    for k in range(3):
        a, b = r[:, k], r_gt[:, k]
        ang = math.degrees(math.atan2(np.linalg.norm(np.cross(a, b)), float(a @ b)))
        worst = max(worst, ang)
    return worst


def fmt(x):
    if x is None or not math.isfinite(x):
        return "–"
    if x == 0.0:
        return "0"
    if 0.01 <= abs(x) < 1e5:
        s = f"{x:.4f}".rstrip("0").rstrip(".")
        return s
    return f"{x:.2e}"


def fmt_time(us):
    if us is None:
        return "–"
    if us >= 100:
        return f"{us:.0f}"
    if us >= 10:
        return f"{us:.1f}"
    return f"{us:.2f}"


def solve(flag, obj, img, k, dist):
    try:
        ok, rvec, tvec = cv2.solvePnP(obj, img, k, dist, flags=flag)
    except cv2.error:
        return None
    if not ok:
        return None
    r, _ = cv2.Rodrigues(rvec)
    return r, tvec.reshape(3)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("problems", nargs="?", default="target/compare/problems.json")
    ap.add_argument("--passes", type=int, default=5)
    ap.add_argument("--out", default=None, help="also write the Markdown here")
    args = ap.parse_args()

    with open(args.problems) as f:
        data = json.load(f)
    fail_deg = data.get("fail_deg", 5.0)
    intr = data["intrinsics"]
    k = np.array([[intr["fx"], 0.0, intr["cx"]], [0.0, intr["fy"], intr["cy"]], [0.0, 0.0, 1.0]])
    dist = np.zeros(5)

    out = []
    out.append("# OpenCV on the eopnp comparison problems\n")
    out.append(f"OpenCV {cv2.__version__}, numpy {np.__version__}; problems: {args.problems} "
               f"(seed {data.get('seed')}); time = median of {args.passes} passes, per solve, "
               "including the Python call overhead.\n")
    groups = []
    for row in data["rows"]:
        if row["group"] not in groups:
            groups.append(row["group"])
    for g in groups:
        out.append(f"## {g}\n")
        out.append("| row | method | trials | failures | median rot err (deg) | mean rot err (deg) | "
                   "median t err (%) | mean t err (%) | median us / solve | cv2 SQPNP time / time |")
        out.append("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for row in (r for r in data["rows"] if r["group"] == g):
            probs = []
            for p in row["problems"]:
                probs.append((
                    np.ascontiguousarray(np.array(p["world"], dtype=np.float64)),
                    np.ascontiguousarray(np.array(p["pixels"], dtype=np.float64)),
                    np.array(p["r_gt"], dtype=np.float64),
                    np.array(p["t_gt"], dtype=np.float64),
                ))
            results = []
            for name, flag_name, kind in METHODS:
                if kind == "planar" and row["scene"] != "planar":
                    continue
                flag = getattr(cv2, flag_name, None)
                if flag is None:
                    continue
                rot, tr, fails = [], [], 0
                for obj, img, r_gt, t_gt in probs:
                    sol = solve(flag, obj, img, k, dist)
                    if sol is None:
                        fails += 1
                        continue
                    r, t = sol
                    er = rot_err_deg(r, r_gt)
                    et = 100.0 * np.linalg.norm(t - t_gt) / np.linalg.norm(t_gt)
                    if not (math.isfinite(er) and math.isfinite(et)) or er > fail_deg:
                        fails += 1
                        continue
                    rot.append(er)
                    tr.append(et)
                per = []
                for _ in range(args.passes):
                    t0 = time.perf_counter()
                    for obj, img, _, _ in probs:
                        try:
                            cv2.solvePnP(obj, img, k, dist, flags=flag)
                        except cv2.error:
                            pass
                    per.append((time.perf_counter() - t0) * 1e6 / max(len(probs), 1))
                us = statistics.median(per) if probs else None
                results.append((name, len(probs), fails,
                                statistics.median(rot) if rot else None,
                                statistics.fmean(rot) if rot else None,
                                statistics.median(tr) if tr else None,
                                statistics.fmean(tr) if tr else None, us))
            sq = next((r[7] for r in results if r[0] == "cv2 SQPNP"), None)
            for name, n, fails, mr, ar, mt, at, us in results:
                ratio = f"{sq / us:.2f}" if sq and us else "–"
                out.append(f"| {row['label']} | {name} | {n} | {fails} | {fmt(mr)} | {fmt(ar)} | "
                           f"{fmt(mt)} | {fmt(at)} | {fmt_time(us)} | {ratio} |")
        out.append("")
    text = "\n".join(out)
    print(text)
    if args.out:
        with open(args.out, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()
