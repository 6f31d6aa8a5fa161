"""eopnp: camera pose from 2D-3D point correspondences (the Perspective-n-Point problem).

EOPnP (Zhou and Kaess, IROS 2019) followed by default by a Levenberg-Marquardt refinement of
the reprojection error (the maximum-likelihood pose), from the Rust crate ``eopnp``.

>>> import numpy as np, eopnp
>>> sol = eopnp.solve(world, image)            # world (N, 3), image (N, 2) normalised
>>> sol.R, sol.t, sol.rvec, sol.cost           # x_cam = R @ X + t
>>> cam = eopnp.Camera("SIMPLE_RADIAL", [1245.6, 600, 800, 0.06], 1200, 1600)
>>> sol = eopnp.solve(world, pixels, camera=cam)
>>> sol, info = eopnp.solve_ransac(world, pixels, camera=cam)   # info["inliers"]: bool mask
>>> sol = eopnp.solve(world, pixels, camera=cam, covariance=1.0)  # sol.covariance: 6x6
>>> opts = eopnp.SolverOptions(loss=("huber", 2.0), covariance="estimated")
>>> sol = eopnp.solve(world, pixels, camera=cam, options=opts)  # or the options as keywords
>>> results = eopnp.solve_batch([(world, pixels), ...], camera=cam, threads=2)
>>> res = eopnp.solve_batch_arrays(worlds, images, threads=2)  # (B, N, 3), (B, N, 2)
>>> res.R, res.t, res.ok, res.errors            # (B, 3, 3), (B, 3), (B,) bool, {i: exc}
>>> sol = eopnp.solve(world, pixels, camera=cam, loss=("cauchy", 2.0))  # robust, 2 px scale
>>> sol = eopnp.refine(world, pixels, prev_sol, camera=cam)     # tracking: from a prior pose
>>> rig = eopnp.Rig([cam0, cam1], [cam0_from_rig, cam1_from_rig])  # x_cam = R_k @ x_rig + t_k
>>> sol = eopnp.solve_generalized(pixels, world, camera_idxs, rig=rig)  # x_rig = R @ X + t
>>> sol, info = eopnp.solve_generalized_ransac(pixels, world, camera_idxs, cams_from_rig, cams)
>>> model = eopnp.read_colmap_model("sparse/0")             # COLMAP; with rigs (3.12+):
>>> freg = eopnp.register_frame(model, model.frame_ids[0])  # freg.solution: rig_from_world

Arrays: any array-like of real numbers (float or integer dtype, any layout) is accepted and
read as float64 (copied, with the GIL held); results are new float64 arrays. Errors raise the
exceptions of ``eopnp.PnpError``'s hierarchy. Every solve releases the GIL; the batch
functions run on several threads.
"""

from ._batch import BatchResult
from ._eopnp import (
    Camera,
    CameraError,
    DegenerateError,
    Frame,
    FrameRegistration,
    Gravity,
    GravityMismatchError,
    Image,
    InputTypeError,
    InvalidInputError,
    InvalidOptionError,
    Model,
    ModelError,
    NoConsensusError,
    NoSolutionError,
    PnpError,
    RansacOptions,
    Registration,
    Rig,
    SensorRig,
    Solution,
    SolverOptions,
    UnknownIdError,
    __version__,
    problem_seed,
    read_colmap_model,
    refine,
    refine_generalized,
    register_frame,
    register_frames,
    register_image,
    register_images,
    solve,
    solve_all,
    solve_batch,
    solve_batch_arrays,
    solve_generalized,
    solve_generalized_batch,
    solve_generalized_ransac,
    solve_generalized_ransac_batch,
    solve_ransac,
    solve_ransac_batch,
)

__all__ = [
    "BatchResult",
    "Camera",
    "CameraError",
    "DegenerateError",
    "Frame",
    "FrameRegistration",
    "Gravity",
    "GravityMismatchError",
    "Image",
    "InputTypeError",
    "InvalidInputError",
    "InvalidOptionError",
    "Model",
    "ModelError",
    "NoConsensusError",
    "NoSolutionError",
    "PnpError",
    "RansacOptions",
    "Registration",
    "Rig",
    "SensorRig",
    "Solution",
    "SolverOptions",
    "UnknownIdError",
    "__version__",
    "problem_seed",
    "read_colmap_model",
    "refine",
    "refine_generalized",
    "register_frame",
    "register_frames",
    "register_image",
    "register_images",
    "solve",
    "solve_all",
    "solve_batch",
    "solve_batch_arrays",
    "solve_generalized",
    "solve_generalized_batch",
    "solve_generalized_ransac",
    "solve_generalized_ransac_batch",
    "solve_ransac",
    "solve_ransac_batch",
]
