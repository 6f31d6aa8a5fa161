#!/usr/bin/env python3
"""Generates tests/data/opencv_projection.json: OpenCV's projections of random points through
random cameras, the reference data of tests/opencv_camera.rs (`Camera::from_opencv` and
`Camera::from_opencv_fisheye` must reproduce these pixels, and undistort them back).

What it does (seeded, so rerunning it with the same OpenCV gives the same file):

- for each OpenCV distortion-vector length 0, 4, 5, 8, 12 and 14 (`cv2.projectPoints`, order
  k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4, tauX, tauY) and for the fisheye model
  (`cv2.fisheye.projectPoints`, k1..k4), CAMERAS_PER_CASE random cameras with realistic
  values: fx in [400, 2000] px, fy within 2 % of fx, no skew, the principal point near the
  centre of a random image size; k1 in [-0.4, 0.2], k2 in [-0.1, 0.1], p1, p2 in
  [-2e-3, 2e-3], k3 in [-0.02, 0.02], k4 in [-0.3, 0.3], k5 in [-0.05, 0.05], k6 in
  [-0.01, 0.01], s1..s4 in [-2e-3, 2e-3], tauX, tauY up to 3 degrees (radians in the vector);
  fisheye k1 in [-0.05, 0.05], k2 in [-0.02, 0.02], k3 in [-0.01, 0.01], k4 in [-5e-3, 5e-3];
- POINTS_PER_CAMERA points in front of the camera: the first on the optical axis, the others
  with normalised coordinates (x, y) uniform in the disc of radius 0.6 (perspective; about 31
  degrees off axis) or with an angle off axis uniform up to 70 degrees (fisheye), at a depth z
  that is a power of two in [0.5, 16]; X = x z, Y = y z are then exact, so OpenCV's normalised
  coordinates (X * (1 / z) in projectPoints, X / z in fisheye.projectPoints) are exactly the
  stored (x, y) whatever the division order;
- a point is kept only where the lens map is comfortably invertible (the determinant of its
  Jacobian, by central differences of OpenCV's projection, above 0.2 fx fy), so that the
  undistortion round trip is well posed;
- pixels from cv2.projectPoints / cv2.fisheye.projectPoints with rvec = tvec = 0, so a pixel
  is the image of the normalised point; floats are written with repr (shortest round-trip
  form, exact in f64).

Command (from the repository root):
    pip install opencv-python-headless numpy
    python3 scripts/opencv_camera_data.py            # writes tests/data/opencv_projection.json

Generated with OpenCV 5.0.0 (opencv-python-headless 5.0.0.93), numpy 2.4.6, Python 3.11.7.
"""

import json
import math
import os
import sys

try:
    import cv2
    import numpy as np
except ImportError:  # pragma: no cover - optional tooling
    sys.exit("this script needs OpenCV and numpy: pip install opencv-python-headless numpy")

SEED = 20240611
CAMERAS_PER_CASE = 3
POINTS_PER_CAMERA = 12
COUNTS = [0, 4, 5, 8, 12, 14]
OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data",
                   "opencv_projection.json")


def random_k(rng, fisheye):
    w = int(rng.integers(640, 4001))
    h = int(rng.integers(480, 3001))
    fx = rng.uniform(300.0, 800.0) if fisheye else rng.uniform(400.0, 2000.0)
    fy = fx * (1.0 + rng.uniform(-0.02, 0.02))
    cx = w / 2 + rng.uniform(-20.0, 20.0)
    cy = h / 2 + rng.uniform(-20.0, 20.0)
    return np.array([[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]]), (w, h)


def random_dist(rng, n):
    full = [
        rng.uniform(-0.4, 0.2),  # k1
        rng.uniform(-0.1, 0.1),  # k2
        rng.uniform(-2e-3, 2e-3),  # p1
        rng.uniform(-2e-3, 2e-3),  # p2
        rng.uniform(-0.02, 0.02),  # k3
        rng.uniform(-0.3, 0.3),  # k4
        rng.uniform(-0.05, 0.05),  # k5
        rng.uniform(-0.01, 0.01),  # k6
        rng.uniform(-2e-3, 2e-3),  # s1
        rng.uniform(-2e-3, 2e-3),  # s2
        rng.uniform(-2e-3, 2e-3),  # s3
        rng.uniform(-2e-3, 2e-3),  # s4
        math.radians(rng.uniform(-3.0, 3.0)),  # tauX
        math.radians(rng.uniform(-3.0, 3.0)),  # tauY
    ]
    return np.array(full[:n], dtype=np.float64)


def random_fisheye_dist(rng):
    return np.array([
        rng.uniform(-0.05, 0.05),
        rng.uniform(-0.02, 0.02),
        rng.uniform(-0.01, 0.01),
        rng.uniform(-5e-3, 5e-3),
    ])


def project(xyz, k, dist, fisheye):
    pts = np.asarray(xyz, dtype=np.float64).reshape(-1, 1, 3)
    zero = np.zeros((3, 1))
    if fisheye:
        px, _ = cv2.fisheye.projectPoints(pts, zero, zero, k, dist)
    else:
        px, _ = cv2.projectPoints(pts, zero, zero, k, dist)
    return px.reshape(-1, 2)


def invertible(x, y, k, dist, fisheye):
    h = 1e-6
    p = project([[x + h, y, 1.0], [x - h, y, 1.0], [x, y + h, 1.0], [x, y - h, 1.0]], k, dist,
                fisheye)
    dx = (p[0] - p[1]) / (2 * h)
    dy = (p[2] - p[3]) / (2 * h)
    det = dx[0] * dy[1] - dx[1] * dy[0]
    return det > 0.2 * k[0, 0] * k[1, 1]


def random_points(rng, k, dist, fisheye):
    norm = [(0.0, 0.0)]
    while len(norm) < POINTS_PER_CAMERA:
        phi = rng.uniform(0.0, 2.0 * math.pi)
        if fisheye:
            r = math.tan(math.radians(rng.uniform(0.0, 70.0)))
        else:
            r = 0.6 * math.sqrt(rng.uniform(0.0, 1.0))
        x, y = r * math.cos(phi), r * math.sin(phi)
        if invertible(x, y, k, dist, fisheye):
            norm.append((x, y))
    xyz = []
    for x, y in norm:
        z = 2.0 ** int(rng.integers(-1, 5))
        xyz.append([x * z, y * z, z])
    return norm, xyz


def main():
    rng = np.random.default_rng(SEED)
    cases = []
    for kind, counts in (("standard", COUNTS), ("fisheye", [4])):
        for n in counts:
            for _ in range(CAMERAS_PER_CASE):
                fisheye = kind == "fisheye"
                k, size = random_k(rng, fisheye)
                dist = random_fisheye_dist(rng) if fisheye else random_dist(rng, n)
                norm, xyz = random_points(rng, k, dist, fisheye)
                px = project(xyz, k, dist, fisheye)
                cases.append({
                    "kind": kind,
                    "image_size": list(size),
                    "K": [[float(v) for v in row] for row in k],
                    "dist": [float(v) for v in dist],
                    "points3d": [[float(v) for v in p] for p in xyz],
                    "normalised": [[float(x), float(y)] for x, y in norm],
                    "pixels": [[float(u), float(v)] for u, v in px],
                })
    data = {
        "description": "OpenCV's projections of random points through random cameras "
                       "(scripts/opencv_camera_data.py): for each case, K, the distortion "
                       "vector (cv2.projectPoints order, or cv2.fisheye's k1..k4), the 3D points, "
                       "their exact normalised coordinates and OpenCV's pixels (rvec = tvec = 0).",
        "opencv_version": cv2.__version__,
        "seed": SEED,
        "cases": cases,
    }
    with open(OUT, "w", encoding="utf-8") as f:
        json.dump(data, f, indent=1)
        f.write("\n")
    npts = sum(len(c["pixels"]) for c in cases)
    print(f"wrote {len(cases)} cameras, {npts} points to {os.path.normpath(OUT)}")


if __name__ == "__main__":
    main()
