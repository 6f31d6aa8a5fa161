"""COLMAP rigs and frames (COLMAP 3.12+): Model.frames / Model.rigs on the bundled rig models
(data/colmap-rig, text, and data/colmap-rig-bin, binary: two three-camera rigs, six frames,
noise-free), register_frame and register_frames: every frame's rig pose comes back to round-off,
equal to the CLI's (`eopnp register --json`) and to pycolmap's frame poses; the frame errors as
typed exceptions; pickling."""

import json
import pickle
import shutil
import subprocess

import numpy as np
import pytest

import eopnp
from conftest import DATA, require

RIG_MODELS = ["colmap-rig", "colmap-rig-bin"]


@pytest.fixture(scope="module", params=RIG_MODELS)
def model(request):
    return eopnp.read_colmap_model(DATA / request.param)


def rt(r, t):
    return np.hstack([np.asarray(r), np.asarray(t).reshape(3, 1)])


def test_frames_and_rigs(model):
    assert model.frame_ids == [1, 2, 3, 4, 5, 6]
    frames, rigs = model.frames, model.rigs
    assert sorted(frames) == model.frame_ids and sorted(rigs) == [1, 2]
    assert [frames[i].rig_id for i in model.frame_ids] == [1, 1, 1, 2, 2, 2]
    assert frames[2].image_ids == [4, 5, 6] and model.frame(5).image_ids == [13, 14, 15]
    assert rigs[1].id == 1 and rigs[1].ref_camera_id == 1 and rigs[2].ref_camera_id == 4
    assert list(rigs[2].cams_from_rig) == [4, 5, 6]
    assert np.array_equal(rigs[2].cams_from_rig[4], np.eye(3, 4))
    # Every image is in exactly one frame, and its pose is its camera's cam_from_rig composed
    # with the frame's rig_from_world (COLMAP's rule; the model is consistent to round-off).
    seen = []
    for f in frames.values():
        assert f.id in model.frame_ids
        assert np.allclose(f.R @ f.R.T, np.eye(3), atol=1e-12)
        assert np.linalg.norm(f.q) == pytest.approx(1.0, abs=1e-12)
        for i in f.image_ids:
            seen.append(i)
            img = model.image(i)
            cam_from_rig = rigs[f.rig_id].cams_from_rig[img.camera_id]
            r, t = cam_from_rig[:, :3], cam_from_rig[:, 3]
            assert np.abs(r @ f.R - img.R).max() < 1e-12
            assert np.abs(r @ f.t + t - img.t).max() < 1e-12
    assert sorted(seen) == model.image_ids
    assert repr(frames[1]) == "Frame(id=1, rig_id=1, image_ids=[1, 2, 3])"
    assert repr(rigs[1]) == "SensorRig(id=1, camera_ids=[1, 2, 3])"
    with pytest.raises(eopnp.UnknownIdError, match="no frame with id 99") as e:
        model.frame(99)
    assert (e.value.kind, e.value.id) == ("UnknownFrame", 99)


def test_text_and_binary_frames_equal():
    text, binary = (eopnp.read_colmap_model(DATA / m) for m in RIG_MODELS)
    assert text.frame_ids == binary.frame_ids
    for i in text.frame_ids:
        a, b = text.frame(i), binary.frame(i)
        assert (a.rig_id, a.image_ids) == (b.rig_id, b.image_ids)
        assert np.array_equal(a.q, b.q) and np.array_equal(a.t, b.t)


def test_model_without_rigs():
    boxes = eopnp.read_colmap_model(DATA / "colmap-boxes")
    assert boxes.frame_ids == [] and boxes.frames == {} and boxes.rigs == {}
    assert eopnp.register_frames(boxes) == []
    with pytest.raises(eopnp.UnknownIdError) as e:
        eopnp.register_frame(boxes, 1)
    assert e.value.kind == "UnknownFrame"


def test_register_every_frame(model):
    """Noise-free: the rig pose, and each image's pose from it, to round-off; and the pose
    solve_generalized gives on the same correspondences through the same rig."""
    rigs = model.rigs
    for fid in model.frame_ids:
        frame = model.frame(fid)
        reg = eopnp.register_frame(model, fid)
        assert (reg.frame_id, reg.rig_id, reg.image_ids) == (fid, frame.rig_id, frame.image_ids)
        corr = [model.correspondences(i) for i in frame.image_ids]
        assert reg.n == sum(len(w) for w, _ in corr) == 120
        assert (reg.inliers, reg.skipped, reg.ransac) == (reg.n, 0, None)
        assert reg.rotation_error_deg < 1e-9 and reg.translation_error_pct < 1e-9
        assert reg.rmse_px < 1e-9 and reg.model_rmse_px < 1e-9
        assert np.abs(reg.solution.R - frame.R).max() < 1e-12
        assert np.abs(reg.solution.t - frame.t).max() < 1e-12
        assert np.array_equal(reg.model_rig_from_world, rt(frame.R, frame.t))
        assert reg.cams_from_world.shape == (3, 3, 4)
        for k, i in enumerate(frame.image_ids):
            img = model.image(i)
            assert np.abs(reg.cams_from_world[k] - rt(img.R, img.t)).max() < 1e-12
        # The same problem through the public rig API.
        cams = [model.camera_of(i) for i in frame.image_ids]
        poses = [rigs[frame.rig_id].cams_from_rig[c.camera_id]
                 for c in (model.image(i) for i in frame.image_ids)]
        rig = eopnp.Rig(cams, poses)
        world = np.vstack([w for w, _ in corr])
        pixels = np.vstack([p for _, p in corr])
        idx = np.concatenate([np.full(len(w), k) for k, (w, _) in enumerate(corr)])
        sol = eopnp.solve_generalized(pixels, world, idx, rig=rig)
        assert np.abs(sol.R - reg.solution.R).max() < 1e-12
        assert np.abs(sol.t - reg.solution.t).max() < 1e-12
        assert "FrameRegistration(frame_id=" in repr(reg)


def test_register_frame_moves_with_the_model(tmp_path):
    """A frame whose stored pose is off: the registration recovers the pose the images'
    observations give, and reports the difference (the errors are measured, not assumed)."""
    src = DATA / "colmap-rig"
    shutil.copytree(src, tmp_path / "m")
    path = tmp_path / "m" / "frames.txt"
    lines = path.read_text().splitlines()
    k = next(n for n, ln in enumerate(lines) if ln.startswith("2 1 "))
    parts = lines[k].split()
    parts[8] = repr(float(parts[8]) + 0.5)  # TZ of frame 2's rig_from_world
    lines[k] = " ".join(parts)
    path.write_text("\n".join(lines) + "\n")
    moved = eopnp.read_colmap_model(tmp_path / "m")
    reg = eopnp.register_frame(moved, 2)
    assert reg.translation_error_pct == pytest.approx(100 * 0.5 / 5.5, rel=1e-9)
    assert reg.rotation_error_deg < 1e-9 and reg.rmse_px < 1e-9 and reg.model_rmse_px > 1.0
    original = eopnp.read_colmap_model(src).frame(2)
    assert np.abs(reg.solution.t - original.t).max() < 1e-12
    assert reg.model_rig_from_world[2, 3] == pytest.approx(original.t[2] + 0.5, abs=1e-15)


def cli_json(cli, *args):
    out = subprocess.run([cli, *args], capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


@pytest.mark.parametrize("name", RIG_MODELS)
@pytest.mark.parametrize("args,kw", [([], {}), (["--ransac"], {"ransac": True})])
def test_register_frame_equals_cli(cli, name, args, kw):
    model = eopnp.read_colmap_model(DATA / name)
    out = cli_json(cli, "register", str(DATA / name), "--json", *args)
    assert out["registered"] == "frames"
    assert [e["frame_id"] for e in out["frames"]] == model.frame_ids
    for entry in out["frames"]:
        reg = eopnp.register_frame(model, entry["frame_id"], **kw)
        assert (reg.rig_id, reg.image_ids) == (entry["rig_id"], entry["image_ids"])
        assert (reg.n, reg.inliers, reg.skipped) == (entry["n"], entry["inliers"],
                                                     entry["skipped"])
        assert np.array_equal(reg.solution.R, np.array(entry["rotation"]))
        assert np.array_equal(reg.solution.t, np.array(entry["translation"]))
        assert np.array_equal(reg.solution.q, np.array(entry["quaternion_wxyz"]))
        assert reg.rotation_error_deg == entry["rotation_error_deg"]
        assert reg.translation_error_pct == entry["translation_error_pct"]
        assert (reg.rmse_px, reg.model_rmse_px) == (entry["rmse_px"], entry["model_rmse_px"])
        assert (reg.ransac is None) == (entry["robust"] is None)
        # The CLI composes each image's pose through quaternions, the package through
        # matrices: the same pose to round-off.
        assert [e["image_id"] for e in entry["images"]] == reg.image_ids
        for k, image in enumerate(entry["images"]):
            want = rt(image["rotation"], image["translation"])
            assert np.abs(reg.cams_from_world[k] - want).max() < 1e-14


def _same_frame_registration(a, b):
    """Equal but the times."""
    assert (a.frame_id, a.rig_id, a.image_ids, a.n, a.inliers, a.skipped) == (
        b.frame_id, b.rig_id, b.image_ids, b.n, b.inliers, b.skipped)
    assert a.solution == b.solution
    assert (a.rotation_error_deg, a.translation_error_pct, a.rmse_px, a.model_rmse_px) == (
        b.rotation_error_deg, b.translation_error_pct, b.rmse_px, b.model_rmse_px)
    assert np.array_equal(a.model_rig_from_world, b.model_rig_from_world)
    assert np.array_equal(a.cams_from_world, b.cams_from_world)
    if a.ransac is None or b.ransac is None:
        assert a.ransac is None and b.ransac is None
    else:
        assert {k: v for k, v in a.ransac.items() if k != "micros"} == {
            k: v for k, v in b.ransac.items() if k != "micros"}


@pytest.mark.parametrize("threads", [None, 1, 2])
def test_register_frames_equals_register_frame(model, threads):
    regs = eopnp.register_frames(model, threads=threads)
    assert [r.frame_id for r in regs] == model.frame_ids
    for r in regs:
        _same_frame_registration(r, eopnp.register_frame(model, r.frame_id))
    # Any iterable of ids, in its order, repeats allowed; options as register_frame's.
    ids = [5, 1, 5]
    kw = {"ransac": {"threshold_px": 2.0}, "covariance": 1.0}
    robust = eopnp.register_frames(model, iter(ids), threads=threads, **kw)
    assert len(robust) == 3
    for i, r in zip(ids, robust):
        assert r.ransac is not None and r.solution.covariance.shape == (6, 6)
        _same_frame_registration(r, eopnp.register_frame(model, i, **kw))
    alg = eopnp.register_frames(model, [3], options=eopnp.SolverOptions(refinement="algebraic"),
                                threads=threads)
    _same_frame_registration(alg[0], eopnp.register_frame(model, 3, refinement="algebraic"))


def test_register_frames_reports_each_failure(model):
    out = eopnp.register_frames(model, [1, 999, 2])
    assert isinstance(out[0], eopnp.FrameRegistration)
    assert isinstance(out[2], eopnp.FrameRegistration)
    assert isinstance(out[1], eopnp.UnknownIdError)
    with pytest.raises(eopnp.UnknownIdError) as e:
        eopnp.register_frame(model, 999)
    assert str(out[1]) == str(e.value) == "no frame with id 999 in the model"
    assert (out[1].kind, out[1].id) == (e.value.kind, e.value.id) == ("UnknownFrame", 999)
    # The same kind of exception as an unknown image id.
    with pytest.raises(eopnp.UnknownIdError):
        eopnp.register_image(model, 999)
    assert eopnp.register_frames(model, []) == []


def test_bad_options(model):
    for call in (lambda **kw: eopnp.register_frame(model, 1, **kw),
                 lambda **kw: eopnp.register_frames(model, **kw)):
        with pytest.raises(eopnp.InvalidOptionError):
            call(refinement="nonsense")
        with pytest.raises(eopnp.InvalidOptionError, match="covariance"):
            call(covariance=0.0)
        with pytest.raises(TypeError):
            call(no_such_option=1)
    # A RANSAC option out of range is found by the library when it runs; it fails every frame
    # alike, so the batch raises it as one call does.
    with pytest.raises(eopnp.InvalidOptionError, match="threshold_px"):
        eopnp.register_frame(model, 1, ransac={"threshold_px": -1.0})
    with pytest.raises(eopnp.InvalidOptionError, match="threshold_px"):
        eopnp.register_frames(model, [1, 2], ransac={"threshold_px": -1.0})
    with pytest.raises(eopnp.InvalidOptionError):
        eopnp.register_frames(model, threads=0)
    with pytest.raises(TypeError):
        eopnp.register_frame(model, "1")
    with pytest.raises(OverflowError):
        eopnp.register_frame(model, -1)


def _edited(tmp_path, name, edit):
    """data/colmap-rig copied, its `name` file edited by `edit(lines) -> lines`."""
    out = tmp_path / "model"
    shutil.copytree(DATA / "colmap-rig", out)
    path = out / name
    path.write_text("\n".join(edit(path.read_text().splitlines())) + "\n")
    return eopnp.read_colmap_model(out)


def test_camera_without_pose_in_rig(tmp_path):
    """Rig 1's camera 3 with an unknown cam_from_rig: frames of rig 1 cannot be registered
    (UnknownIdError, kind NoSensorPose), rig 2's can."""

    def edit(lines):
        out = []
        for ln in lines:
            if ln.startswith("1 3 "):
                ln = ln[: ln.index("CAMERA 3 1 ")] + "CAMERA 3 0"
            out.append(ln)
        return out

    model = _edited(tmp_path, "rigs.txt", edit)
    assert model.rigs[1].cams_from_rig[3] is None
    with pytest.raises(eopnp.UnknownIdError, match="camera 3 has no known pose in rig 1") as e:
        eopnp.register_frame(model, 1)
    assert (e.value.kind, e.value.rig_id, e.value.camera_id, e.value.id) == (
        "NoSensorPose", 1, 3, 3)
    back = pickle.loads(pickle.dumps(e.value))
    assert (type(back), back.kind, back.details) == (type(e.value), e.value.kind, e.value.details)
    out = eopnp.register_frames(model, threads=2)
    assert [type(r).__name__ for r in out] == ["UnknownIdError"] * 3 + ["FrameRegistration"] * 3
    assert out[3].rotation_error_deg < 1e-9


def test_frame_without_images(tmp_path):
    """A frame with no data: InvalidInputError, kind EmptyFrame."""
    model = _edited(tmp_path, "frames.txt",
                    lambda lines: lines + ["7 1 1 0 0 0 0 0 5 0"])
    assert model.frame(7).image_ids == []
    with pytest.raises(eopnp.InvalidInputError, match="frame 7 has no images") as e:
        eopnp.register_frame(model, 7)
    assert (e.value.kind, e.value.id) == ("EmptyFrame", 7)
    out = eopnp.register_frames(model, [7, 1])
    assert isinstance(out[0], eopnp.InvalidInputError) and out[1].frame_id == 1


@pytest.mark.parametrize("ransac", [None, True])
def test_pickle(model, ransac):
    reg = eopnp.register_frame(model, 4, ransac=ransac, covariance="estimated")
    back = pickle.loads(pickle.dumps(reg))
    assert type(back) is eopnp.FrameRegistration
    _same_frame_registration(back, reg)
    assert back.micros == reg.micros and back.ransac == reg.ransac
    assert back.solution.covariance is not None
    assert repr(back) == repr(reg)


def test_against_pycolmap():
    """pycolmap reads the same models: its frame poses and image poses are what register_frame
    recovers, its rigs' sensor poses what SensorRig.cams_from_rig reads."""
    pycolmap = require("pycolmap")
    for name in RIG_MODELS:
        rec = pycolmap.Reconstruction(str(DATA / name))
        model = eopnp.read_colmap_model(DATA / name)
        assert sorted(rec.frames) == model.frame_ids
        for reg in eopnp.register_frames(model, threads=2):
            frame = rec.frames[reg.frame_id]
            assert frame.rig_id == reg.rig_id
            assert [d.id for d in frame.image_ids] == reg.image_ids
            assert np.abs(frame.rig_from_world.matrix() - reg.solution.Rt).max() < 1e-12
            for k, i in enumerate(reg.image_ids):
                assert np.abs(rec.images[i].cam_from_world().matrix()
                              - reg.cams_from_world[k]).max() < 1e-12
        for rid, rig in model.rigs.items():
            prig = rec.rigs[rid]
            assert prig.ref_sensor_id.id == rig.ref_camera_id
            for cam, pose in rig.cams_from_rig.items():
                sensor = pycolmap.sensor_t(pycolmap.SensorType.CAMERA, cam)
                if cam == rig.ref_camera_id:
                    assert np.array_equal(pose, np.eye(3, 4))
                else:
                    assert np.abs(prig.sensor_from_rig(sensor).matrix() - pose).max() < 1e-15
