#!/usr/bin/env python3
"""Makes the bundled COLMAP model with rigs, `data/colmap-rig` (text) and `data/colmap-rig-bin`
(binary, the same model), with pycolmap's synthetic dataset generator.

The model is COLMAP's own (pycolmap 4.x, the rigs-and-frames format of COLMAP 3.12 and later):
two rigs of three SIMPLE_RADIAL cameras each (the reference camera and two others at small
random offsets, `sensor_from_rig`), three frames per rig (each its `rig_from_world` pose and the
three images its cameras took at once), 40 3D points, and noise-free observations: every
observation is the exact projection of its 3D point through its camera's pose
(`cam_from_world = sensor_from_rig * rig_from_world`) and lens, plus three observations per
image without a 3D point. So registering a frame from its correspondences alone finds the
frame's pose to rounding (the text files hold 17 significant digits).

Usage (needs `pip install pycolmap`; from the repository root):

    python3 scripts/make_rig_model.py             # writes data/colmap-rig and data/colmap-rig-bin
    python3 scripts/make_rig_model.py --out /tmp/rig   # writes /tmp/rig and /tmp/rig-bin

The directories must not exist, or hold only a model's files (which are replaced).
"""
import argparse
import os
import sys

import pycolmap

SEED = 42
MODEL_FILES = {
    ext: [f"{n}.{ext}" for n in ("cameras", "images", "points3D", "rigs", "frames")]
    for ext in ("txt", "bin")
}


def prepare(path, ext):
    """Creates `path`, or empties it of a previous model's files (refusing anything else)."""
    os.makedirs(path, exist_ok=True)
    others = [f for f in os.listdir(path) if f not in MODEL_FILES[ext]]
    if others:
        sys.exit(f"{path} holds other files ({', '.join(sorted(others))}): refusing to write")
    for f in os.listdir(path):
        os.remove(os.path.join(path, f))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default="data/colmap-rig", help="the text model's directory")
    a = ap.parse_args()

    pycolmap.set_random_seed(SEED)
    options = pycolmap.SyntheticDatasetOptions()
    options.num_rigs = 2
    options.num_cameras_per_rig = 3
    options.num_frames_per_rig = 3
    options.num_points3D = 40
    options.num_points2D_without_point3D = 3
    rec = pycolmap.synthesize_dataset(options)

    text, binary = a.out, a.out.rstrip("/") + "-bin"
    prepare(text, "txt")
    rec.write_text(text)
    prepare(binary, "bin")
    rec.write_binary(binary)
    print(f"pycolmap {pycolmap.__version__}: wrote {text} and {binary}")
    print(
        f"{rec.num_rigs()} rigs, {rec.num_cameras()} cameras, {rec.num_frames()} frames, "
        f"{rec.num_images()} images, {rec.num_points3D()} 3D points, "
        f"{rec.compute_num_observations()} observations, mean reprojection error "
        f"{rec.compute_mean_reprojection_error():.3g} px"
    )


if __name__ == "__main__":
    main()
