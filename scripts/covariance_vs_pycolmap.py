"""Compares eopnp's pose covariance with pycolmap's on the problem written by
`cargo run --release --example covariance -- problem.json`:

    python3 scripts/covariance_vs_pycolmap.py problem.json

pycolmap refines eopnp's pose (squared loss, intrinsics fixed) and returns its covariance for
1 px noise; the script prints the pose change and the largest difference between the two
matrices relative to the largest entry. pycolmap is a comparison tool only.
"""
import json
import sys

import numpy as np
import pycolmap

d = json.load(open(sys.argv[1]))
world = np.array(d["world"])
pixels = np.array(d["pixels"])
cov = np.array(d["covariance"])
R = np.array(d["R"])
t = np.array(d["t"])
c = d["camera"]
cam = pycolmap.Camera(model=c["model"], width=c["width"], height=c["height"], params=c["params"])
opts = pycolmap.AbsolutePoseRefinementOptions()
opts.loss_function_scale = 1e9  # squared loss over the residuals that occur here
opts.refine_focal_length = False
opts.refine_extra_params = False
opts.gradient_tolerance = 1e-14
res = pycolmap.refine_absolute_pose(
    pycolmap.Rigid3d(pycolmap.Rotation3d(R), t), pixels, world,
    np.ones(len(world), bool), cam, opts, return_covariance=True)
pose = res["cam_from_world"]
print(f"pycolmap {pycolmap.__version__}")
print("pose change: rotation %.1e, translation %.1e" % (
    np.abs(pose.rotation.matrix() - R).max(), np.abs(pose.translation - t).max()))
rel = np.abs(res["covariance"] - cov).max() / np.abs(cov).max()
print("max |C_pycolmap - C_eopnp| / max |C_eopnp| = %.1e" % rel)
