#!/usr/bin/env python3
"""Checks, with pycolmap, eopnp's reading and writing of COLMAP models with rigs and frames
(the format of COLMAP 3.12 and later), and that `eopnp register` writes its frame poses as
pycolmap reads them.

Two input models:

- the bundled `data/colmap-rig` (text; pycolmap's noise-free synthetic rig model, made by
  `scripts/make_rig_model.py`), and
- a fresh model pycolmap synthesizes and writes here in binary (3 rigs of 3 cameras, 4 frames
  each, 200 3D points, 1 px of pixel noise: `pycolmap.synthesize_dataset`, `synthesize_noise`,
  seeded), whose frame 1 has no 2D-3D correspondences (so eopnp cannot register it).

For each input and each output format (text, binary) it runs

    eopnp register INPUT --json --write WORK/<input>-<format> --write-format <format>

(every frame registered as one rig pose; the JSON has each frame's `rig_from_world` and each of
its images' `cam_from_world`; the written model has those poses), loads the output with
`pycolmap.Reconstruction` and checks:

- the numbers of rigs, cameras, frames, images and 3D points equal the input's (read by
  pycolmap), and so do, exactly, the cameras' parameters, the 3D points, every rig (reference
  sensor, other sensors and their `sensor_from_rig`) and every frame's rig and data ids;
- every frame's `rig_from_world` (rotation matrix entries and translation) equals eopnp's JSON
  to 1e-12, relative (|a - b| <= 1e-12 max(1, |b|)); a frame eopnp could not register keeps the
  input's pose;
- every image's `cam_from_world` as pycolmap gives it (from its frame and the rig) equals the
  image pose in eopnp's JSON to the same tolerance, and the image is in the frame eopnp says.

It also prints how far eopnp's frame poses are from the input model's (the registration's
accuracy: rounding on the noise-free model, the pixel noise on the synthetic one).

Usage (needs `pip install pycolmap numpy`; from the repository root):

    python3 scripts/pycolmap_rig_roundtrip.py                     # cargo run --release
    python3 scripts/pycolmap_rig_roundtrip.py --eopnp target/release/eopnp --work /tmp/rt

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
SEED = 7


def close(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return bool(np.all(np.abs(a - b) <= TOL * np.maximum(1.0, np.abs(b))))


def rel_diff(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    return float(np.max(np.abs(a - b) / np.maximum(1.0, np.abs(b))))


def pose_key(p):
    """A Rigid3d as exact numbers (quaternion xyzw and translation), or None."""
    if p is None:
        return None
    return tuple(np.asarray(p.rotation.quat).tolist()) + tuple(np.asarray(p.translation).tolist())


def rig_key(rig):
    ref = rig.ref_sensor_id
    others = sorted(
        ((int(s.type.value), s.id, pose_key(p)) for s, p in rig.non_ref_sensors.items()),
        key=lambda x: x[:2],
    )
    return (int(ref.type.value), ref.id), others


def data_key(frame):
    return sorted((int(d.sensor_id.type.value), d.sensor_id.id, d.id) for d in frame.data_ids)


def synthesize(path):
    """A noisy synthetic rig model written by pycolmap (binary) to `path`."""
    pycolmap.set_random_seed(SEED)
    options = pycolmap.SyntheticDatasetOptions()
    options.num_rigs = 3
    options.num_cameras_per_rig = 3
    options.num_frames_per_rig = 4
    options.num_points3D = 200
    options.num_points2D_without_point3D = 5
    rec = pycolmap.synthesize_dataset(options)
    noise = pycolmap.SyntheticNoiseOptions()
    noise.point2D_stddev = 1.0
    pycolmap.synthesize_noise(noise, rec)
    # Frame 1 without correspondences (its images' observations leave their 3D points): eopnp
    # cannot register it, and --write must keep its input poses.
    for data in rec.frames[1].data_ids:
        image = rec.images[data.id]
        for idx, p in enumerate(image.points2D):
            if p.has_point3D():
                rec.delete_observation(data.id, idx)
    os.makedirs(path, exist_ok=True)
    rec.write_binary(path)
    return rec


def run_eopnp(cmd, model, out, fmt, json_path):
    args = cmd + ["register", model, "--json", "--write", out, "--write-format", fmt]
    print("$", " ".join(args))
    res = subprocess.run(args, capture_output=True, text=True)
    if res.returncode != 0:
        sys.exit(f"eopnp failed (exit {res.returncode}):\n{res.stderr}")
    with open(json_path, "w") as f:
        f.write(res.stdout)


def check(model, out, json_path, label):
    failures = []
    with open(json_path) as f:
        report = json.load(f)
    if report.get("registered") != "frames":
        return [f"eopnp did not register frames: {report.get('registered')!r}"]
    src = pycolmap.Reconstruction(model)
    rec = pycolmap.Reconstruction(out)

    def counts(r):
        return (r.num_rigs(), r.num_cameras(), r.num_frames(), r.num_images(), r.num_points3D())

    if counts(src) != counts(rec):
        failures.append(
            f"counts (rigs, cameras, frames, images, points) {counts(rec)} != {counts(src)}"
        )
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
    for rid, rig in src.rigs.items():
        if rid not in rec.rigs or rig_key(rig) != rig_key(rec.rigs[rid]):
            failures.append(f"rig {rid} differs from the input's")

    worst = {"frame R": 0.0, "frame t": 0.0, "image R": 0.0, "image t": 0.0}
    accuracy = []
    registered = kept = images = 0
    for entry in report["frames"]:
        fid = entry["frame_id"]
        if fid not in rec.frames:
            failures.append(f"frame {fid} missing from the written model")
            continue
        frame, frame_in = rec.frames[fid], src.frames[fid]
        if frame.rig_id != frame_in.rig_id or data_key(frame) != data_key(frame_in):
            failures.append(f"frame {fid}: rig or data ids differ from the input's")
        p = frame.rig_from_world
        r, t = p.rotation.matrix(), np.asarray(p.translation)
        if "error" in entry:
            kept += 1
            if pose_key(p) != pose_key(frame_in.rig_from_world):
                failures.append(f"frame {fid} (not registered) does not keep the input's pose")
            continue
        registered += 1
        want_r, want_t = np.array(entry["rotation"]), np.array(entry["translation"])
        worst["frame R"] = max(worst["frame R"], rel_diff(r, want_r))
        worst["frame t"] = max(worst["frame t"], rel_diff(t, want_t))
        if not (close(r, want_r) and close(t, want_t)):
            failures.append(f"frame {fid}: rig_from_world differs: R {r.tolist()} t {t.tolist()}")
        accuracy.append((entry["rotation_error_deg"], entry["translation_error_pct"]))
        for img in entry["images"]:
            iid = img["image_id"]
            if iid not in rec.images:
                failures.append(f"image {iid} missing from the written model")
                continue
            image = rec.images[iid]
            if image.frame_id != fid:
                failures.append(f"image {iid} is in frame {image.frame_id}, not {fid}")
            c = image.cam_from_world()
            r, t = c.rotation.matrix(), np.asarray(c.translation)
            want_r, want_t = np.array(img["rotation"]), np.array(img["translation"])
            worst["image R"] = max(worst["image R"], rel_diff(r, want_r))
            worst["image t"] = max(worst["image t"], rel_diff(t, want_t))
            if not (close(r, want_r) and close(t, want_t)):
                failures.append(
                    f"image {iid}: cam_from_world differs: R {r.tolist()} t {t.tolist()}"
                )
            images += 1
    n = counts(rec)
    print(
        f"{label}: pycolmap read {n[0]} rigs, {n[1]} cameras, {n[2]} frames, {n[3]} images, "
        f"{n[4]} points (input: {', '.join(map(str, counts(src)))}); rigs, cameras, points and "
        f"frames' data as the input's; {registered} frame poses and {images} image poses as "
        f"eopnp's JSON, {kept} frame(s) not registered keep the input's; worst relative "
        f"difference: frames R {worst['frame R']:.3g} t {worst['frame t']:.3g}, images "
        f"(pycolmap's cam_from_world) "
        f"R {worst['image R']:.3g} t {worst['image t']:.3g} (tolerance {TOL:g})"
    )
    if accuracy:
        rot, trans = zip(*accuracy)
        print(
            f"{' ' * len(label)}  eopnp's frame poses vs the input's: worst rotation "
            f"{max(rot):.3g} deg, translation {max(trans):.3g} %"
        )
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument(
        "--eopnp",
        default=None,
        help="eopnp binary (default: cargo run --release --quiet --)",
    )
    ap.add_argument("--work", default=None, help="directory for the outputs (default: temporary)")
    a = ap.parse_args()
    cmd = [a.eopnp] if a.eopnp else ["cargo", "run", "--release", "--quiet", "--"]
    work = a.work or tempfile.mkdtemp(prefix="eopnp-pycolmap-rig-")
    os.makedirs(work, exist_ok=True)
    print(f"pycolmap {pycolmap.__version__}, numpy {np.__version__}")
    synthetic = os.path.join(work, "synthetic-input")
    shutil.rmtree(synthetic, ignore_errors=True)
    rec = synthesize(synthetic)
    print(
        f"synthetic input (pycolmap, binary): {rec.num_rigs()} rigs, {rec.num_cameras()} cameras, "
        f"{rec.num_frames()} frames, {rec.num_images()} images, {rec.num_points3D()} points, "
        f"1 px pixel noise, frame 1 without correspondences"
    )
    failures = []
    for name, model in [("bundled", "data/colmap-rig"), ("synthetic", synthetic)]:
        for fmt in ["text", "binary"]:
            label = f"{name} -> {fmt}"
            out = os.path.join(work, f"{name}-{fmt}")
            js = out + ".json"
            shutil.rmtree(out, ignore_errors=True)
            run_eopnp(cmd, model, out, fmt, js)
            failures += [f"{label}: {f}" for f in check(model, out, js, label)]
    if not a.work:
        shutil.rmtree(work)
    for f in failures:
        print("FAIL", f)
    print(
        "OK: pycolmap reads every output with eopnp's rigs, frames and poses"
        if not failures
        else "FAILED"
    )
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
