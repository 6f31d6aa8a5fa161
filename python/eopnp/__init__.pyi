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

# The type stubs of the eopnp package (the extension module eopnp._eopnp and eopnp._batch).
# Every docstring here is generated from the runtime object's __doc__ (the Rust doc comments of
# python/src, the docstring of eopnp/__init__.py) by `python python/gen_stub_docs.py`;
# python/tests/test_stub_docs.py fails when they differ. Edit the Rust side, then regenerate.

import os
from typing import Any, Iterable, Literal, Mapping, Sequence, TypedDict, Union, final

import numpy as np
import numpy.typing as npt

from ._batch import BatchResult as BatchResult

__version__: str

_ArrayLike = npt.ArrayLike
_F64Array = npt.NDArray[np.float64]
_Refinement = Literal["ml", "reprojection", "algebraic"]
_Planar = Literal["auto", "planar", "nonplanar"]
_Source = Literal[
    "case1",
    "case2",
    "case3",
    "case4",
    "planar1",
    "planar2",
    "extra_start",
    "initial",
    "p3p",
    "generalized",
    "gp3p",
    "other",
]
# loss=: None or "squared" (default), ("huber", s) or ("cauchy", s), the scale s in pixels
# with a camera, in normalised units otherwise (finite, > 0).
_Loss = Union[
    Literal["squared"], tuple[Literal["huber", "cauchy"], float], None
]
_Covariance = Union[Literal["estimated"], float, None]

class PnpError(Exception):
    """Base class of every exception raised by eopnp.

    Attributes:
        kind: the name of the Rust ``PnpError`` variant (``"TooFewPoints"``,
            ``"NonFinite"``, ...) or of the package's check (``"Shape"``, ``"DType"``, ...).
        details: the variant's fields as a dict; each is also an attribute of the exception
            (e.g. ``e.index`` and ``e.input`` of a non-finite value).

    Exceptions raised by the package pickle with their ``kind`` and fields.
    """
    kind: str
    details: dict[str, Any]

class InvalidInputError(PnpError, ValueError):
    """Bad input (also a ``ValueError``): too few points (``got``, ``need``), mismatched lengths
    (``world``, ``image``; ``weights``, ``points``), a NaN or infinite value (``index``,
    ``input``: ``"world"``, ``"image"`` or ``"weights"``), a negative weight (``index``),
    an array of the wrong shape (kind ``"Shape"``, ``argument``); for a rig, camera indices
    not one per point (kind ``"CameraIndicesLength"``, ``indices``, ``points``) or naming a
    camera the rig does not have (kind ``"UnknownCamera"``: correspondence ``index`` is in
    ``camera``); a COLMAP frame without images (kind ``"EmptyFrame"``, ``id``).
    """
class InputTypeError(InvalidInputError, TypeError):
    """An input that is not an array of real numbers (also a ``TypeError``; kind ``"DType"``,
    ``argument``): complex, boolean, object or string data.
    """
class DegenerateError(PnpError, ValueError):
    """A degenerate configuration (also a ``ValueError``; kind ``"Degenerate"``);
    ``degeneracy`` is one of ``"coincident_world_points"``, ``"collinear_world_points"``,
    ``"coincident_image_points"``, ``"scale_out_of_range"``.
    """
class NoSolutionError(PnpError, RuntimeError):
    """No candidate pose survived (also a ``RuntimeError``): numerical failure on extremely
    ill-conditioned input.
    """
class InvalidOptionError(PnpError, ValueError):
    """An option out of its range or of the wrong form (also a ``ValueError``; ``option``: its
    name).
    """
class NoConsensusError(PnpError, RuntimeError):
    """RANSAC found no consensus (also a ``RuntimeError``): no pose had enough inliers for a fit,
    or the best pose's ``inliers`` are no more than a wrong pose reaches by chance
    (``needed``: the least accepted; ``iterations``: samples drawn).
    """
class GravityMismatchError(PnpError, ValueError):
    """The images contradict the known vertical given as ``gravity=`` (also a ``ValueError``; kind
    ``"GravityMismatch"``): the vertical of the maximum-likelihood pose is ``angle_deg``
    degrees off the measured one, ``sigmas`` standard deviations of their combined
    uncertainty (a right vertical is reported with a probability of 0.27 %).
    """
    angle_deg: float
    sigmas: float
class CameraError(PnpError, ValueError):
    """An invalid camera (also a ``ValueError``): unsupported model, wrong number of parameters,
    non-finite or non-positive focal lengths, a malformed ``K`` or distortion vector.
    """
class ModelError(PnpError):
    """A COLMAP model that cannot be read: ``file``, ``line`` or ``offset`` (or None), and
    ``reason``.
    """
class UnknownIdError(PnpError, LookupError):
    """No image (kind ``"UnknownImage"``), camera (``"UnknownCamera"``), frame
    (``"UnknownFrame"``) or rig (``"UnknownRig"``) with this ``id`` in the model, or a
    frame's camera without a known pose in its rig (``"NoSensorPose"``: ``rig_id``,
    ``camera_id``, and ``id`` the camera's) (also a ``LookupError``).
    """

@final
class SolverOptions:
    """The options of the solver (the Rust ``eopnp::Solver``), for ``options=`` of every function
    that solves (``solve``, ``solve_all``, ``refine``, ``solve_ransac``, ``solve_batch``,
    ``solve_ransac_batch``, ``solve_batch_arrays``, ``register_image``, ``register_images``, and
    for rigs ``solve_generalized``, ``solve_generalized_ransac``, ``refine_generalized``,
    ``solve_generalized_batch``, ``solve_generalized_ransac_batch``, ``register_frame``,
    ``register_frames``).
    Those functions also take each option as a keyword argument (not together with
    ``options=``).

    Every option is checked here: a value out of its range raises ``InvalidOptionError``
    (``option``: its name) at construction, before anything is solved. Immutable (``replace``
    returns a changed copy), hashable, picklable; ``==`` compares every attribute.

    Args:
        refinement: "ml" (default; alias "reprojection"): EOPnP then Levenberg-Marquardt on
            the reprojection error, the maximum-likelihood pose; "algebraic": EOPnP alone.
        planar: planar branch selection: "auto" (default), "planar" or "nonplanar".
        newton_iterations: maximum damped-Newton iterations per candidate (None: the
            library's default, 50).
        newton_step_tolerance: Newton stops when the step falls to this (None: the library's
            default, 1e-12); finite and >= 0.
        reprojection_iterations: maximum Levenberg-Marquardt iterations (None: the library's
            default, 200).
        exhaustive: refine every start of every generator (default False: a start certified
            globally optimal ends the search).
        loss: the loss of the final refinement: None or "squared" (default; the
            maximum-likelihood pose for Gaussian noise), ``("huber", s)`` (quadratic up to a
            residual of ``s``, linear beyond: a few moderate outliers; ``s`` about 1-3 times
            the noise) or ``("cauchy", s)`` (the influence of a residual decays beyond ``s``:
            gross outliers hardly move the pose, when RANSAC is not run). ``s`` is in pixels
            for pixel input (with a ``camera``), in normalised units otherwise; it must be
            finite and > 0 (about 1e-154 < s < 1e154). ``Solution.cost`` is then the loss's
            cost.
        covariance: None (default: no covariance), "estimated" (the noise estimated from the
            residuals, ``sigma^2 = sum of squared residuals / (2 n - 6)``) or the noise standard
            deviation of each image coordinate (pixels for pixel input, normalised units
            otherwise; pycolmap assumes 1 px): fills ``Solution.covariance``, the 6x6
            covariance of ``[delta_q, delta_t]`` with ``R = Exp(2 delta_q) R_hat``,
            ``t = t_hat + delta_t`` (pycolmap's convention), and ``Solution.sigma``.

    Attributes:
        The arguments, as given (``refinement`` "reprojection" reads "ml", ``loss`` None
        reads "squared", a ``loss`` list reads as a tuple).
    """
    def __new__(
        cls,
        *,
        refinement: _Refinement = "ml",
        planar: _Planar = "auto",
        newton_iterations: int | None = None,
        newton_step_tolerance: float | None = None,
        reprojection_iterations: int | None = None,
        exhaustive: bool = False,
        loss: _Loss = None,
        covariance: _Covariance = None,
    ) -> "SolverOptions": ...
    @property
    def refinement(self) -> Literal["ml", "algebraic"]:
        """"ml" or "algebraic"."""
    @property
    def planar(self) -> _Planar:
        """"auto", "planar" or "nonplanar"."""
    @property
    def newton_iterations(self) -> int | None:
        """Maximum damped-Newton iterations per candidate, or None (the library's default, 50)."""
    @property
    def newton_step_tolerance(self) -> float | None:
        """Newton's step tolerance, or None (the library's default, 1e-12)."""
    @property
    def reprojection_iterations(self) -> int | None:
        """Maximum Levenberg-Marquardt iterations, or None (the library's default, 200)."""
    @property
    def exhaustive(self) -> bool:
        """Refine every start of every generator."""
    @property
    def loss(self) -> Literal["squared"] | tuple[Literal["huber", "cauchy"], float]:
        """"squared", ``("huber", s)`` or ``("cauchy", s)``."""
    @property
    def covariance(self) -> Literal["estimated"] | float | None:
        """None, "estimated" or the noise standard deviation."""
    def as_dict(self) -> dict[str, Any]:
        """The options as a dict (``SolverOptions(**d)`` gives them back)."""
    def replace(self, **changes: Any) -> "SolverOptions":
        """A copy with the given options changed: ``options.replace(loss=("huber", 2.0))``."""
    def __eq__(self, value: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, Any]]: ...

# options=: a SolverOptions, a dict of its fields, or None (the defaults).
_Options = Union[SolverOptions, Mapping[str, Any], None]

@final
class Solution:
    """A camera pose and how it was found (``x_cam = R @ X + t``, world to camera); from the
    generalized functions (``solve_generalized``, ...), the rig's pose (``x_rig = R @ X + t``,
    rig_from_world).

    Attributes:
        R: rotation matrix, shape (3, 3).
        t: translation, shape (3,).
        rvec: OpenCV's rotation vector (axis times angle, radians), shape (3,).
        q: unit quaternion (w, x, y, z), COLMAP's order, shape (4,).
        Rt: the 3x4 matrix [R | t].
        cost: the minimised cost (refinement "ml"): the (weighted) sum of the loss of the
            squared reprojection residuals, in pixels^2 for pixel input (through the camera),
            in normalised units otherwise (the sum of squared residuals with the default
            loss); or the algebraic cost (refinement "algebraic").
        algebraic_cost: the paper's algebraic cost of the rotation.
        reprojection_rmse: RMS normalised reprojection residual (multiply by the focal length
            for pixels); inf if a point lies in the focal plane (algebraic mode only).
        cheirality_ok: more than half of the points are in front of the camera.
        degenerate: the configuration is close to degenerate; the pose may be ambiguous.
        planar: the planar branch produced the starting candidate.
        source: the candidate generator of the winning start ("case1", ..., "planar1",
            "planar2", "extra_start", "p3p"; for a rig "generalized" or "gp3p"; "initial" for
            ``refine`` and ``refine_generalized``).
        newton_iterations: damped-Newton iterations of the winning candidate (0 when skipped:
            an exact fit, whose start is already the minimum of the algebraic cost).
        reprojection_iterations: Levenberg-Marquardt iterations of the refinement.
        converged: the refinement stopped at a minimum (False when it ran out of iterations or
            could not start; True in algebraic mode).
        used: correspondences that entered the solve (weight > 0, undistorted).
        skipped: correspondences left out because their pixel could not be undistorted.
        covariance: the pose's 6x6 covariance (``covariance=`` of ``solve``), or None: of
            ``[delta_q, delta_t]`` with ``R = Exp(2 delta_q) R_hat``, ``t = t_hat + delta_t``
            (pycolmap's ``return_covariance=True`` convention).
        sigma: the image noise standard deviation the covariance assumes (given or estimated;
            pixels for pixel input, normalised units otherwise), or None.
        camera: with estimated intrinsics (``estimate_focal``, ``refine_principal_point``,
            ``refine_distortion``), the estimated ``Camera`` (the given one with those
            intrinsics replaced); None otherwise.
        focal: the estimated camera's focal lengths ``(fx, fy)`` in pixels, or None.
        focal_sigma: with ``estimate_focal`` and a covariance, the estimated focal length's
            standard deviation in pixels (the covariance is then the pose's marginal one);
            None otherwise.
    """

    @property
    def R(self) -> _F64Array:
        """Rotation matrix, shape (3, 3) (a new array on each access)."""
    @property
    def t(self) -> _F64Array:
        """Translation, shape (3,)."""
    @property
    def rvec(self) -> _F64Array:
        """OpenCV's rotation vector (``cv2.Rodrigues``), shape (3,)."""
    @property
    def q(self) -> _F64Array:
        """Unit quaternion (w, x, y, z), shape (4,)."""
    @property
    def Rt(self) -> _F64Array:
        """The 3x4 matrix [R | t]."""
    @property
    def cost(self) -> float:
        """The minimised cost (refinement "ml"): the (weighted) sum of the loss of the squared
        reprojection residuals, in pixels^2 for pixel input (through the camera), in normalised
        units otherwise (the sum of squared residuals with the default loss); or the algebraic
        cost (refinement "algebraic").
        """
    @property
    def algebraic_cost(self) -> float:
        """The paper's algebraic cost of the rotation."""
    @property
    def reprojection_rmse(self) -> float:
        """RMS normalised reprojection residual (multiply by the focal length for pixels); inf if
        a point lies in the focal plane (algebraic mode only).
        """
    @property
    def cheirality_ok(self) -> bool:
        """More than half of the points are in front of the camera."""
    @property
    def degenerate(self) -> bool:
        """The configuration is close to degenerate; the pose may be ambiguous."""
    @property
    def planar(self) -> bool:
        """The planar branch produced the starting candidate."""
    @property
    def source(self) -> _Source:
        """The candidate generator of the winning start ("case1", ..., "planar1", "planar2",
        "extra_start", "p3p"; for a rig "generalized" or "gp3p"; "initial" for ``refine`` and
        ``refine_generalized``).
        """
    @property
    def newton_iterations(self) -> int:
        """Damped-Newton iterations of the winning candidate (0 when skipped: an exact fit, whose
        start is already the minimum of the algebraic cost).
        """
    @property
    def reprojection_iterations(self) -> int:
        """Levenberg-Marquardt iterations of the refinement (0 in algebraic mode)."""
    @property
    def converged(self) -> bool:
        """The refinement stopped at a minimum (False when it ran out of iterations or could not
        start; True in algebraic mode).
        """
    @property
    def used(self) -> int:
        """Correspondences that entered the solve (weight > 0, undistorted)."""
    @property
    def skipped(self) -> int:
        """Correspondences left out because their pixel could not be undistorted."""
    @property
    def covariance(self) -> _F64Array | None:
        """The pose's 6x6 covariance of ``[delta_q, delta_t]`` (pycolmap's convention), or None
        when not asked for (``covariance=``) or not defined (degenerate normal equations).
        """
    @property
    def sigma(self) -> float | None:
        """The image noise standard deviation the covariance assumes, or None."""
    @property
    def camera(self) -> Camera | None:
        """The estimated camera with ``estimate_focal``, ``refine_principal_point`` or
        ``refine_distortion`` (the given camera with those intrinsics replaced), or None.
        """
    @property
    def focal(self) -> tuple[float, float] | None:
        """The estimated camera's focal lengths ``(fx, fy)`` in pixels, or None."""
    @property
    def focal_sigma(self) -> float | None:
        """The estimated focal length's standard deviation in pixels (``estimate_focal`` with a
        covariance), or None.
        """
    def as_dict(self) -> dict[str, Any]:
        """Every field as a dict (arrays for R, t, rvec, q, covariance)."""

@final
class Gravity:
    """The direction of gravity (or any direction known in both frames) measured in the camera's
    frame and known in the world's, with the measurement's uncertainty.

    Args:
        in_camera: the direction in the camera's frame, shape (3,) (for a rig: the rig's frame),
            e.g. an IMU's gravity vector rotated into the camera. Any non-zero length.
        in_world: the same direction in the world's frame, shape (3,): ``(0, 0, -1)`` for a
            world whose z axis points up. "Down" in both, or "up" in both.
        sigma_deg: the measurement's standard deviation in degrees, about each of the two axes
            across the direction (an IMU's tilt accuracy, 0.1 to 1 degree).

    Passed as ``gravity=`` to ``solve``, ``refine``, ``solve_ransac``, ``solve_generalized``,
    ``solve_generalized_ransac`` and ``refine_generalized``: the pose is then the maximum a
    posteriori one with the vertical as a prior, RANSAC draws samples of two points (the upright
    two-point pose), and a vertical the images contradict raises ``GravityMismatchError``.

    Raises:
        InvalidOptionError: a zero or non-finite direction, or ``sigma_deg`` not finite and
            > 0 (``option`` ``"gravity"``).
    """
    def __new__(cls, in_camera: _ArrayLike, in_world: _ArrayLike, sigma_deg: float) -> Gravity: ...
    @property
    def in_camera(self) -> _F64Array:
        """The direction in the camera's (rig's) frame, unit length, shape (3,)."""
    @property
    def in_world(self) -> _F64Array:
        """The direction in the world's frame, unit length, shape (3,)."""
    @property
    def sigma_deg(self) -> float:
        """The measurement's standard deviation, degrees."""
    def __eq__(self, value: object, /) -> bool: ...

@final
class Camera:
    """A camera: a model, its parameters in COLMAP's order, and the image size.

    ``Camera(model, params, width=0, height=0)`` takes COLMAP's model name and parameters, e.g.
    ``Camera("SIMPLE_RADIAL", [f, cx, cy, k], 1200, 1600)``. Models: SIMPLE_PINHOLE (f, cx, cy),
    PINHOLE (fx, fy, cx, cy), SIMPLE_RADIAL (f, cx, cy, k), RADIAL (f, cx, cy, k1, k2), OPENCV
    (fx, fy, cx, cy, k1, k2, p1, p2), OPENCV_FISHEYE (fx, fy, cx, cy, k1, k2, k3, k4),
    FULL_OPENCV (fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6), SIMPLE_RADIAL_FISHEYE
    (f, cx, cy, k), RADIAL_FISHEYE (f, cx, cy, k1, k2), and OpenCV's full model
    OPENCV_THIN_PRISM_TILTED (the 12 of FULL_OPENCV, s1, s2, s3, s4, tau_x, tau_y; not a COLMAP
    model). The size is recorded only (no computation uses it).

    Pixels follow COLMAP's convention (the upper-left image corner is (0, 0)) for cameras built
    from COLMAP parameters, and OpenCV's (the centre of the upper-left pixel is (0, 0)) for
    cameras built by ``from_opencv``: the mapping is the one the parameters define, with no
    half-pixel shift.

    Raises:
        CameraError: an unknown model, the wrong number of parameters, a non-finite parameter
            or a non-positive focal length.
    """

    def __new__(
        cls, model: str, params: _ArrayLike, width: int = 0, height: int = 0
    ) -> "Camera": ...
    @staticmethod
    def from_opencv(K: _ArrayLike, dist: _ArrayLike | None = None) -> "Camera":
        """A camera from OpenCV's camera matrix ``K`` (3x3, zero skew) and distortion vector
        ``dist`` in OpenCV's order (k1, k2, p1, p2[, k3[, k4, k5, k6[, s1, s2, s3, s4[, tauX,
        tauY]]]]): 0, 4, 5, 8, 12 or 14 coefficients (None: no distortion), shape (n,), (1, n)
        or (n, 1). ``project`` then equals ``cv2.projectPoints`` with rvec = tvec = 0; pixels
        are in OpenCV's convention. The model follows from the length: PINHOLE (0), OPENCV (4),
        FULL_OPENCV (5, 8), OPENCV_THIN_PRISM_TILTED (12, 14).
        """
    @staticmethod
    def from_opencv_fisheye(K: _ArrayLike, dist: _ArrayLike) -> "Camera":
        """A camera from ``cv2.fisheye``'s ``K`` (zero skew) and its 4 coefficients (k1, k2, k3,
        k4): the OPENCV_FISHEYE model.
        """
    @staticmethod
    def pinhole(fx: float, fy: float, cx: float, cy: float) -> "Camera":
        """A pinhole camera without distortion (COLMAP's PINHOLE, image size 0)."""
    @property
    def model(self) -> str:
        """The model's name, e.g. "SIMPLE_RADIAL"."""
    @property
    def width(self) -> int:
        """Image width (0: unknown)."""
    @property
    def height(self) -> int:
        """Image height (0: unknown)."""
    @property
    def params(self) -> _F64Array:
        """The parameters in COLMAP's order, shape (n,)."""
    @property
    def focal(self) -> tuple[float, float]:
        """The focal lengths (fx, fy) in pixels."""
    @property
    def principal_point(self) -> tuple[float, float]:
        """The principal point (cx, cy) in pixels."""
    @property
    def has_distortion(self) -> bool:
        """Whether the model has (non-zero) distortion terms."""
    def to_opencv(self) -> tuple[_F64Array, _F64Array] | None:
        """OpenCV's ``(K, dist)`` of this camera for ``cv2.projectPoints`` / ``cv2.solvePnP``, or
        None for the fisheye models (see ``to_opencv_fisheye``).
        """
    def to_opencv_fisheye(self) -> tuple[_F64Array, _F64Array] | None:
        """``cv2.fisheye``'s ``(K, dist)`` of an OPENCV_FISHEYE camera, else None."""
    def project(self, normalised: _ArrayLike) -> _F64Array:
        """Pixels of normalised image points (x/z, y/z), shape (N, 2) -> (N, 2)."""
    def undistort(self, pixels: _ArrayLike) -> _F64Array:
        """Normalised image points (x/z, y/z) of pixels, shape (N, 2) -> (N, 2), by iterative
        undistortion. A pixel that cannot be undistorted (NaN, outside the region where the
        lens model is invertible, beyond 90 degrees of a fisheye) gives a row of NaN.
        """

@final
class RansacOptions:
    """RANSAC options (the Rust ``eopnp::ransac::Ransac``); every argument is also a settable
    attribute. Out-of-range values raise ``InvalidOptionError`` when used.

    Args:
        threshold_px: inlier threshold on the pixel reprojection error (default 4.0).
        confidence: probability of drawing at least one all-inlier sample, for the adaptive
            iteration count (default 0.999).
        max_iterations: hard bound on the samples drawn (default 10000).
        min_iterations: samples always drawn (default 20).
        seed: seed of the sampling generator (default 0): results are reproducible.
        local_optimisation: refit every new best hypothesis by EOPnP (default True).
        final_threshold_factor: the final inlier classification uses threshold_px times this
            (default 2.0; 1.0 keeps the scoring threshold).
    """

    threshold_px: float
    confidence: float
    max_iterations: int
    min_iterations: int
    seed: int
    local_optimisation: bool
    final_threshold_factor: float
    def __new__(
        cls,
        *,
        threshold_px: float | None = None,
        confidence: float | None = None,
        max_iterations: int | None = None,
        min_iterations: int | None = None,
        seed: int | None = None,
        local_optimisation: bool | None = None,
        final_threshold_factor: float | None = None,
    ) -> "RansacOptions":
        ...
    def as_dict(self) -> dict[str, Any]:
        """The options as a dict (``RansacOptions(**d)`` gives them back)."""

_RansacArg = Union[RansacOptions, Mapping[str, Any], None]
_Problem = Union[
    tuple[_ArrayLike, _ArrayLike], tuple[_ArrayLike, _ArrayLike, _ArrayLike | None]
]

class _RansacInfo(TypedDict):
    inliers: npt.NDArray[np.bool_]
    num_inliers: int
    inlier_ratio: float
    iterations: int
    hypotheses: int
    local_fits: int
    final_fits: int
    cost: float
    rmse: float
    rmse_px: float
    micros: float

@final
class Image:
    """An image of a COLMAP model: its pose, camera and 2D observations."""

    @property
    def id(self) -> int:
        """Image id."""
    @property
    def name(self) -> str:
        """Image name."""
    @property
    def camera_id(self) -> int:
        """Id of the image's camera."""
    @property
    def q(self) -> _F64Array:
        """The pose's quaternion (w, x, y, z) as stored, shape (4,)."""
    @property
    def t(self) -> _F64Array:
        """The pose's translation, shape (3,)."""
    @property
    def R(self) -> _F64Array:
        """The pose's rotation matrix (from the normalised quaternion), shape (3, 3)."""
    @property
    def points2D(self) -> _F64Array:
        """The observations' pixels, shape (K, 2)."""
    @property
    def point3D_ids(self) -> npt.NDArray[np.int64]:
        """The observations' 3D point ids, -1 for an untriangulated observation, shape (K,)."""

@final
class Frame:
    """A frame of a COLMAP model with rigs: the images one rig took at once, and the rig's pose
    then (``rig_from_world``: ``x_rig = R(q) X + t``).
    """

    @property
    def id(self) -> int:
        """Frame id."""
    @property
    def rig_id(self) -> int:
        """Id of the frame's rig (in ``Model.rigs``)."""
    @property
    def image_ids(self) -> list[int]:
        """The frame's images' ids, in the frame's order (data of other sensors left out)."""
    @property
    def q(self) -> _F64Array:
        """The rig's pose (rig_from_world): its quaternion (w, x, y, z) as stored, shape (4,)."""
    @property
    def t(self) -> _F64Array:
        """The rig's pose: its translation, shape (3,)."""
    @property
    def R(self) -> _F64Array:
        """The rig's pose: its rotation matrix (from the normalised quaternion), shape (3, 3)."""

@final
class SensorRig:
    """A rig of a COLMAP model with rigs: cameras fixed to one body, each with its pose in the rig
    (``cam_from_rig``: ``x_cam = R x_rig + t``); the reference camera's is the identity. Only
    the rig's cameras are shown (COLMAP's other sensors, IMUs, are left out).
    """

    @property
    def id(self) -> int:
        """Rig id."""
    @property
    def ref_camera_id(self) -> int | None:
        """The reference camera's id, or None if the reference sensor is not a camera."""
    @property
    def cams_from_rig(self) -> dict[int, _F64Array | None]:
        """The rig's cameras by id, the reference first: each camera's ``[R | t]``
        (cam_from_rig), shape (3, 4), or None if the model does not know it (a new dict on
        each access).
        """

@final
class Model:
    """A COLMAP sparse reconstruction, as read by ``read_colmap_model`` (read-only).

    Poses are COLMAP's: world to camera, ``x_cam = R(q) X + t``.
    """

    @property
    def cameras(self) -> dict[int, Camera]:
        """Cameras by id (a new dict of new ``Camera`` objects on each access)."""
    @property
    def images(self) -> dict[int, Image]:
        """Images by id (a new dict of new ``Image`` objects on each access)."""
    @property
    def image_ids(self) -> list[int]:
        """The image ids, ascending."""
    @property
    def frames(self) -> dict[int, Frame]:
        """Frames by id (a new dict of new ``Frame`` objects on each access): empty unless the
        model has rigs (COLMAP 3.12 and later).
        """
    @property
    def frame_ids(self) -> list[int]:
        """The frame ids, ascending."""
    @property
    def rigs(self) -> dict[int, SensorRig]:
        """Rigs by id (a new dict of new ``SensorRig`` objects on each access): empty unless the
        model has rigs.
        """
    @property
    def num_points3D(self) -> int:
        """Number of 3D points."""
    @property
    def point3D_ids(self) -> npt.NDArray[np.uint64]:
        """The 3D points' ids (ascending), shape (M,)."""
    @property
    def points3D(self) -> _F64Array:
        """The 3D points' coordinates in the order of ``point3D_ids``, shape (M, 3)."""
    def image(self, image_id: int) -> Image:
        """The image with this id. Raises ``UnknownIdError`` if there is none."""
    def frame(self, frame_id: int) -> Frame:
        """The frame with this id. Raises ``UnknownIdError`` if there is none."""
    def camera_of(self, image_id: int) -> Camera:
        """The camera of an image. Raises ``UnknownIdError``."""
    def correspondences(self, image_id: int) -> tuple[_F64Array, _F64Array]:
        """The 2D-3D correspondences of an image: ``(world (N, 3), pixels (N, 2))``, the
        observations that have a 3D point, in the image's order. Raises ``UnknownIdError``.
        """
    def __len__(self) -> int: ...

@final
class Registration:
    """The result of ``register_image``.

    Attributes:
        image_id, name: the image.
        n: its 2D-3D correspondences.
        inliers: correspondences the pose was fitted to (all that could be undistorted, or
            RANSAC's inliers).
        skipped: observations whose pixel could not be undistorted.
        solution: the estimated pose (``Solution``).
        ransac: RANSAC's statistics (dict: iterations, hypotheses, local_fits, final_fits,
            inliers, inlier_ratio, micros), or None without RANSAC.
        rotation_error_deg: rotation difference to the model's pose, degrees.
        translation_error_pct: translation difference, percent of the model's ``|t|``.
        rmse_px: RMS pixel reprojection error of the estimated pose over the fitted points
            (through the estimated camera with ``estimate_focal``).
        model_rmse_px: the same for the model's own pose and camera.
        focal_error_pct: with ``estimate_focal`` (or another intrinsic refined), the estimated
            focal length's error against the model camera's, percent; None otherwise.
        micros: wall time of undistortion plus solve, microseconds.
    """

    @property
    def image_id(self) -> int:
        """The image's id."""
    @property
    def name(self) -> str:
        """The image's name."""
    @property
    def n(self) -> int:
        """The image's 2D-3D correspondences."""
    @property
    def inliers(self) -> int:
        """Correspondences the pose was fitted to (all that could be undistorted, or RANSAC's
        inliers).
        """
    @property
    def skipped(self) -> int:
        """Observations whose pixel could not be undistorted."""
    @property
    def solution(self) -> Solution:
        """The estimated pose."""
    @property
    def ransac(self) -> dict[str, Any] | None:
        """RANSAC's statistics (iterations, hypotheses, local_fits, final_fits, inliers,
        inlier_ratio, micros), or None without RANSAC.
        """
    @property
    def rotation_error_deg(self) -> float:
        """Rotation difference to the model's pose, degrees."""
    @property
    def translation_error_pct(self) -> float:
        """Translation difference, percent of the model's ``|t|``."""
    @property
    def rmse_px(self) -> float:
        """RMS pixel reprojection error of the estimated pose over the fitted points."""
    @property
    def model_rmse_px(self) -> float:
        """The same for the model's own pose."""
    @property
    def focal_error_pct(self) -> float | None:
        """With ``estimate_focal`` (or another intrinsic refined): the estimated focal length's
        error against the model camera's, percent (the larger of the two axes'); None
        otherwise.
        """
    @property
    def micros(self) -> float:
        """Wall time of undistortion plus solve, microseconds."""

@final
class FrameRegistration:
    """The result of ``register_frame``: a frame's rig pose, as ``Registration`` is an image's
    camera pose. Picklable.

    Attributes:
        frame_id, rig_id: the frame and its rig.
        image_ids: the frame's images, in the frame's order.
        n: their 2D-3D correspondences, all images together.
        inliers: correspondences the pose was fitted to (all that could be undistorted, or
            RANSAC's inliers).
        skipped: observations whose pixel could not be undistorted.
        solution: the estimated rig pose, rig_from_world ``x_rig = R @ X + t`` (``Solution``).
        ransac: RANSAC's statistics (dict, as ``Registration.ransac``), or None without RANSAC.
        rotation_error_deg: rotation difference to the model's rig_from_world, degrees.
        translation_error_pct: translation difference, percent of the model's ``|t|``.
        rmse_px: RMS pixel reprojection error of the estimated pose over the fitted points, each
            through its own camera.
        model_rmse_px: the same for the model's frame pose.
        micros: wall time of undistortion plus solve, microseconds.
        model_rig_from_world: the model's frame pose ``[R | t]``, shape (3, 4).
        cams_from_world: each image's camera pose from the estimate, ``[R_k | t_k]`` =
            cam_from_rig composed with ``solution``, in the order of ``image_ids``, shape
            (K, 3, 4).
    """

    @property
    def frame_id(self) -> int:
        """The frame's id."""
    @property
    def rig_id(self) -> int:
        """The frame's rig's id."""
    @property
    def image_ids(self) -> list[int]:
        """The frame's images, in the frame's order: camera ``k`` of the solved rig is image
        ``image_ids[k]``'s camera.
        """
    @property
    def n(self) -> int:
        """The 2D-3D correspondences of the frame's images."""
    @property
    def inliers(self) -> int:
        """Correspondences the pose was fitted to (all that could be undistorted, or RANSAC's
        inliers).
        """
    @property
    def skipped(self) -> int:
        """Observations whose pixel could not be undistorted."""
    @property
    def solution(self) -> Solution:
        """The estimated rig pose, rig_from_world (``x_rig = R @ X + t``)."""
    @property
    def ransac(self) -> dict[str, Any] | None:
        """RANSAC's statistics (iterations, hypotheses, local_fits, final_fits, inliers,
        inlier_ratio, micros), or None without RANSAC.
        """
    @property
    def rotation_error_deg(self) -> float:
        """Rotation difference to the model's rig_from_world, degrees."""
    @property
    def translation_error_pct(self) -> float:
        """Translation difference, percent of the model's ``|t|``."""
    @property
    def rmse_px(self) -> float:
        """RMS pixel reprojection error of the estimated pose over the fitted points, each through
        its own camera.
        """
    @property
    def model_rmse_px(self) -> float:
        """The same for the model's frame pose."""
    @property
    def micros(self) -> float:
        """Wall time of undistortion plus solve, microseconds."""
    @property
    def model_rig_from_world(self) -> _F64Array:
        """The model's frame pose (rig_from_world) ``[R | t]``, shape (3, 4)."""
    @property
    def cams_from_world(self) -> _F64Array:
        """Each image's camera pose from the estimated rig pose, ``[R_k | t_k]`` (its
        cam_from_rig composed with ``solution``: ``x_cam = R_k @ X + t_k``), in the order of
        ``image_ids``, shape (K, 3, 4).
        """

def solve(
    world: _ArrayLike,
    image: _ArrayLike,
    weights: _ArrayLike | None = None,
    *,
    camera: Camera | None = None,
    gravity: Gravity | None = None,
    estimate_focal: bool = False,
    focal_range: tuple[float, float] | None = None,
    refine_principal_point: bool = False,
    refine_distortion: bool = False,
    options: _Options = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> Solution:
    """The camera pose from 2D-3D correspondences.

    Args:
        world: world points, shape (N, 3), N >= 4.
        image: their image points, shape (N, 2): normalised coordinates (x/z, y/z), or pixels
            when ``camera`` is given.
        weights: optional non-negative weight per point, shape (N,); a point of weight 0 is
            ignored (exactly as if dropped), weights scale the squared residuals.
        camera: a ``Camera``: ``image`` holds observed (distorted) pixels. They are undistorted
            and, in the default mode, the refinement minimises the pixel reprojection error
            through the camera model, distortion included. Pixels that cannot be undistorted
            are left out and counted in ``Solution.skipped``.
        gravity: a ``Gravity``: the known vertical; the pose is the maximum a posteriori one
            with it as a prior (``GravityMismatchError`` if the images contradict it).
        estimate_focal: the camera's focal length is unknown (``camera`` required; its focal
            length is the starting guess): estimated with the pose, within a tenth and ten times
            the guess, returned in ``Solution.camera``
            (``Solution.focal``).
        focal_range: ``(min_px, max_px)``, the range of the unknown focal length (implies
            ``estimate_focal``).
        refine_principal_point: the principal point is refined with the pose (``camera``
            required; its principal point the starting guess), returned in ``Solution.camera``.
        refine_distortion: the camera's distortion parameters are refined with the pose
            (``camera`` required; its parameters the starting guess), returned in
            ``Solution.camera``.
        options: a ``SolverOptions`` (or a dict of its fields): refinement, planar branch,
            iteration limits, robust ``loss``, ``covariance``. None: the defaults.
        **keywords: the options of ``SolverOptions`` as keyword arguments instead
            (``refinement="algebraic"``, ``loss=("cauchy", 2.0)``, ``covariance=1.0``, ...),
            not together with ``options``. A ``loss`` scale or ``covariance`` noise is in
            pixels with ``camera``, in normalised units otherwise.

    Returns:
        Solution: the pose (``R``, ``t``, ``rvec``, ``q``), its cost and diagnostics.

    Raises:
        InvalidInputError: wrong shapes, too few points, mismatched lengths, NaN or infinite
            values, negative weights (``InputTypeError`` for non-numeric arrays).
        DegenerateError: coincident or collinear world points, coincident image points.
        NoSolutionError: numerical failure (not observed on valid input).
        InvalidOptionError: an option out of its range.
        TypeError: an unknown keyword, or both ``options`` and option keywords.
    """

def solve_all(
    world: _ArrayLike,
    image: _ArrayLike,
    *,
    options: _Options = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> list[Solution]:
    """Every distinct local minimum of the cost, best first: poses with most points in front of
    the camera first, then by increasing reprojection error (at most 32). For N <= 6 and for
    planar scenes several poses can explain the data about equally well; this lists them.

    ``world`` (N, 3) and ``image`` (N, 2) normalised, and ``options`` or the option keywords,
    as ``solve`` (no weights or camera: undistort pixels first with ``Camera.undistort``);
    ``covariance`` gives each pose its own, ``loss`` is in normalised units.

    Returns:
        list[Solution]: at least one.

    Raises:
        As ``solve``.
    """

# A rotation: a (3, 3) matrix, a (3,) rotation vector (OpenCV's rvec) or a (4,) quaternion
# (w, x, y, z).
_Rotation = _ArrayLike
# A pose (world to camera): a Solution, (rotation, t), or a (3, 4) [R | t] or (4, 4) matrix.
_Pose = Union[Solution, tuple[_Rotation, _ArrayLike], _ArrayLike]

def refine(
    world: _ArrayLike,
    image: _ArrayLike,
    initial: _Pose,
    *,
    weights: _ArrayLike | None = None,
    camera: Camera | None = None,
    gravity: Gravity | None = None,
    estimate_focal: bool = False,
    focal_range: tuple[float, float] | None = None,
    refine_principal_point: bool = False,
    refine_distortion: bool = False,
    options: _Options = None,
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> Solution:
    """Refines a prior pose (tracking: the previous frame's pose) to the maximum-likelihood pose
    of the basin it starts in: Levenberg-Marquardt on the reprojection error from
    ``initial``, without EOPnP's global search (OpenCV's ``solvePnPRefineLM``, PoseLib's
    ``refine_absolute_pose``). From a start in the basin of ``solve``'s pose, the same pose.

    Args:
        world: world points, shape (N, 3), N >= 4.
        image: their image points, shape (N, 2): normalised, or pixels with ``camera``.
        initial: the starting pose (world to camera, ``x_cam = R @ X + t``): a ``Solution``
            (e.g. the previous frame's), a pair ``(rotation, t)`` with ``t`` of shape (3,) and
            the rotation as a (3, 3) matrix ``R``, a (3,) rotation vector (OpenCV's ``rvec``)
            or a (4,) quaternion (w, x, y, z; COLMAP's order, normalised here), or a (3, 4)
            matrix ``[R | t]`` (``Solution.Rt``) or a (4, 4) homogeneous matrix. A matrix ``R``
            must be a rotation to 1e-6 (``R^T R = I``, ``det R > 0``).
        weights: optional non-negative weight per point, shape (N,), as ``solve``.
        camera: a ``Camera``: ``image`` holds observed pixels; the refinement minimises the
            pixel residuals through the camera model, as ``solve``.
        gravity: a ``Gravity``: the known vertical, a prior of the refinement, as ``solve``.
        estimate_focal: the camera's focal length is unknown (``camera`` required; its focal
            length is the starting guess): refined with the pose from ``initial`` and the
            guess, within a tenth and ten times the guess, returned in ``Solution.camera``
            (``Solution.focal``).
        focal_range: ``(min_px, max_px)``, the range of the unknown focal length (implies
            ``estimate_focal``).
        refine_principal_point: the principal point is refined with the pose (``camera``
            required; its principal point the starting guess), returned in ``Solution.camera``.
        refine_distortion: the camera's distortion parameters are refined with the pose
            (``camera`` required; its parameters the starting guess), returned in
            ``Solution.camera``.
        options: a ``SolverOptions`` (or a dict of its fields), as ``solve``. Its ``planar``
            and ``exhaustive`` (of the global search) have no effect here, and ``refine``
            always ends with the Levenberg-Marquardt refinement: ``refinement="algebraic"``
            only iterates the Newton start on to ``newton_step_tolerance`` (otherwise at least
            1e-6).
        **keywords: ``loss``, ``covariance``, ``newton_iterations``, ``newton_step_tolerance``
            and ``reprojection_iterations`` as keyword arguments instead, as ``solve``.

    Returns:
        Solution: the refined pose; ``converged`` says whether the refinement reached a
        minimum, ``source`` is "initial".

    Raises:
        As ``solve``; InvalidOptionError (``option`` "initial") for an initial pose that is
        not finite (the library's message) or not of the forms above.
    """

def solve_batch(
    problems: Sequence[_Problem],
    *,
    camera: Camera | Sequence[Camera] | None = None,
    gravity: Gravity | Sequence[Gravity | None] | None = None,
    estimate_focal: bool = False,
    focal_range: tuple[float, float] | None = None,
    refine_principal_point: bool = False,
    refine_distortion: bool = False,
    options: _Options = None,
    threads: int | None = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> list[Solution | PnpError]:
    """Solves many independent problems in parallel (``solve`` on each), the GIL released while
    they are solved.

    Each array is copied once, with the GIL held, and the solves read the copy (as ``solve``
    does): what other threads write to the arrays after the call copied them does not change
    its results.

    Args:
        problems: a sequence of ``(world, image)`` or ``(world, image, weights)`` tuples, as
            ``solve``'s arguments (weights may be None).
        camera: None (normalised image points), a ``Camera`` for every problem, or a sequence
            of one ``Camera`` per problem (image points in pixels).
        gravity: None, a ``Gravity`` for every problem, or a sequence of one ``Gravity`` (or
            None) per problem: the known vertical, as ``solve``'s.
        estimate_focal: every problem's focal length is unknown, as ``solve``'s (``camera``
            required: each problem's camera's focal length is its starting guess).
        focal_range: ``(min_px, max_px)``, as ``solve``'s, for every problem (implies
            ``estimate_focal``).
        refine_principal_point: every problem's principal point is refined, as ``solve``'s.
        refine_distortion: every problem's distortion parameters are refined, as ``solve``'s.
        options: a ``SolverOptions`` (or a dict of its fields), as ``solve``, for every
            problem.
        threads: None (rayon's global pool: one thread per core, or ``RAYON_NUM_THREADS``) or
            the number of threads (a pool per count, built once and kept).
        **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
            ``solve``.

    Returns:
        list: one entry per problem, in order: its ``Solution``, or the exception instance
        (a ``PnpError``) that ``solve`` would raise for it (as
        ``asyncio.gather(return_exceptions=True)``). Each entry equals ``solve``'s, whatever
        the thread count.

    Raises:
        InvalidInputError: a malformed batch (not a sequence of 2- or 3-tuples, an array of the
            wrong shape; the message names the problem's index), before anything is solved.
        InputTypeError: an array that is not real numbers.
        InvalidOptionError: an option out of range, a bad ``camera``, ``gravity`` or
            ``threads``; an unknown focal length without ``camera``, with a known vertical or
            an empty ``focal_range`` (``option`` "unknown_focal"): raised, as by ``solve``,
            not returned per problem.
        TypeError: as ``solve``.
    """

def solve_batch_arrays(
    world: _ArrayLike,
    image: _ArrayLike,
    weights: _ArrayLike | None = None,
    *,
    camera: Camera | Sequence[Camera] | None = None,
    gravity: Gravity | Sequence[Gravity | None] | None = None,
    estimate_focal: bool = False,
    focal_range: tuple[float, float] | None = None,
    options: _Options = None,
    threads: int | None = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> BatchResult:
    """Solves a batch of problems given as stacked arrays (``solve`` on each), in parallel with the
    GIL released, and returns the poses as stacked arrays: the form for throughput (no Python
    object per problem).

    Each array is copied once, with the GIL held, and the solves read the copy (as ``solve``
    does): what other threads write to the arrays after the call copied them does not change
    its results. Any array-like of real numbers is accepted.

    Args:
        world: world points of every problem, shape (B, N, 3).
        image: their image points, shape (B, N, 2): normalised, or pixels with ``camera``.
        weights: optional non-negative weights, shape (B, N), as ``solve``'s. Problems with
            fewer points: pad them (any finite values) with weight 0, which ``solve`` ignores
            exactly as if the points were dropped; or use ``solve_batch``.
        camera: None (normalised image points), a ``Camera`` for every problem, or a sequence
            of B ``Camera`` (pixels).
        gravity: None, a ``Gravity`` for every problem, or a sequence of B ``Gravity`` (or
            None), as ``solve``'s.
        estimate_focal: every problem's focal length is unknown, as ``solve``'s (``camera``
            required); the estimates in ``BatchResult.focal``.
        focal_range: ``(min_px, max_px)``, as ``solve``'s, for every problem (implies
            ``estimate_focal``).
        options: a ``SolverOptions`` (or a dict of its fields), as ``solve``, for every
            problem.
        threads: as ``solve_batch``.
        **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
            ``solve``.

    Returns:
        BatchResult: ``R`` (B, 3, 3), ``t`` (B, 3), ``cost`` (B,), ``reprojection_rmse``
        (B,), ``ok`` (B,) bool, ``covariance`` (B, 6, 6) and ``sigma`` (B,) with a
        ``covariance`` option (else None), ``focal`` (B, 2) with ``estimate_focal`` (else None),
        and ``errors``: {index: the exception ``solve`` would raise for that problem} (its rows
        are NaN and ``ok`` False). Row ``i`` equals ``solve(world[i], image[i], weights[i],
        ...)`` exactly, whatever the thread count.

    Raises:
        InvalidInputError: an array of the wrong shape (world not (B, N, 3), image not
            (B, N, 2) or weights not (B, N) with world's B and N), before anything is solved.
        InputTypeError: an array that is not real numbers.
        InvalidOptionError: an option out of range, a bad ``camera``, ``gravity`` or
            ``threads``; an unknown focal length as ``solve_batch`` (raised).
        TypeError: as ``solve``.
    """

def solve_ransac_batch(
    problems: Sequence[_Problem],
    *,
    camera: Camera | Sequence[Camera] | None = None,
    focal: float | tuple[float, float] | None = None,
    gravity: Gravity | Sequence[Gravity | None] | None = None,
    estimate_focal: bool = False,
    focal_range: tuple[float, float] | None = None,
    refine_principal_point: bool = False,
    refine_distortion: bool = False,
    ransac: _RansacArg = None,
    options: _Options = None,
    threads: int | None = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> list[tuple[Solution, _RansacInfo] | PnpError]:
    """Robust estimation of many independent problems in parallel (``solve_ransac`` on each),
    the GIL released for the whole batch. Problem ``i`` uses the seed
    ``problem_seed(ransac.seed, i)``, so results do not depend on the thread count.

    Args:
        problems: as ``solve_batch``.
        camera: a ``Camera`` for every problem or a sequence of one per problem (pixels), or
            None with ``focal``.
        focal: ``(fx, fy)`` (or one ``f``) in pixels for every problem, for normalised image
            points (exactly one of ``camera`` and ``focal``).
        gravity: None, a ``Gravity`` for every problem, or a sequence of one ``Gravity`` (or
            None) per problem, as ``solve_ransac``'s.
        estimate_focal: every problem's focal length is unknown, as ``solve_ransac``'s
            (``camera`` required).
        focal_range: ``(min_px, max_px)``, as ``solve_ransac``'s, for every problem.
        refine_principal_point: every problem's principal point is refined, as ``solve``'s.
        refine_distortion: every problem's distortion parameters are refined, as ``solve``'s.
        ransac: a ``RansacOptions``, a dict of its fields, or None; ``seed`` is the base seed.
        options: a ``SolverOptions`` (or a dict of its fields), as ``solve_ransac``, for every
            problem.
        threads: as ``solve_batch``.
        **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
            ``solve``.

    Returns:
        list: one entry per problem, in order: ``(Solution, info)`` as ``solve_ransac``
        returns with ``RansacOptions(seed=problem_seed(seed, i))``, or the exception instance
        it would raise (e.g. ``NoConsensusError``).

    Raises:
        As ``solve_batch``; InvalidOptionError also for neither or both of camera and focal.
    """

def problem_seed(base: int, index: int) -> int:
    """The RANSAC seed of problem ``index`` of a batch whose base seed is ``base``
    (``solve_ransac_batch``): ``solve_ransac(..., ransac=RansacOptions(seed=problem_seed(base,
    i)))`` equals entry ``i`` of the batch.
    """

def solve_ransac(
    world: _ArrayLike,
    image: _ArrayLike,
    weights: _ArrayLike | None = None,
    *,
    camera: Camera | None = None,
    focal: float | tuple[float, float] | None = None,
    gravity: Gravity | None = None,
    estimate_focal: bool = False,
    focal_range: tuple[float, float] | None = None,
    refine_principal_point: bool = False,
    refine_distortion: bool = False,
    ransac: _RansacArg = None,
    options: _Options = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> tuple[Solution, _RansacInfo]:
    """Robust camera pose from correspondences with outliers, by RANSAC: Lambda Twist P3P on
    3-point samples, MSAC scoring with an SPRT, adaptive iteration count, EOPnP local
    optimisation of each new best hypothesis and an EOPnP final fit on the inliers; seeded.

    Args:
        world: world points, shape (N, 3).
        image: image points, shape (N, 2): pixels with ``camera``, normalised with ``focal``.
        weights: optional non-negative weight per point, shape (N,).
        camera: a ``Camera``; the threshold applies to pixel reprojection errors through the
            lens model. Pixels that cannot be undistorted are outliers.
        focal: ``(fx, fy)`` (or one ``f``) in pixels, for normalised ``image``: the threshold
            applies to ``sqrt(fx^2 dx^2 + fy^2 dy^2)``. Exactly one of ``camera`` and ``focal``.
        gravity: a ``Gravity``: the known vertical; samples of two points (the upright
            two-point pose), the final fit with it as a prior.
        estimate_focal: the camera's focal length is unknown (``camera`` required, its focal
            length the starting guess): samples of four points solved by P4Pf, the fits and the
            final pose refined with the focal length; ``Solution.camera`` holds the camera.
        focal_range: ``(min_px, max_px)``, the range of the unknown focal length (implies
            ``estimate_focal``; default a tenth to ten times the guess).
        refine_principal_point: the principal point is refined with the pose (``camera``
            required; its principal point the starting guess), returned in ``Solution.camera``.
        refine_distortion: the camera's distortion parameters are refined with the pose
            (``camera`` required; its parameters the starting guess), returned in
            ``Solution.camera``.
        ransac: a ``RansacOptions``, a dict of its fields, or None (defaults: 4 px threshold,
            confidence 0.999, at most 10000 samples, seed 0).
        options: a ``SolverOptions`` (or a dict of its fields): the options of the EOPnP fits,
            as ``solve``. Its ``loss`` is the loss of the fits' final refinement (the local
            optimisations and the final fit on the inliers; ``s`` in pixels with ``camera``, in
            normalised units with ``focal``; the inlier classification is unchanged). Its
            ``covariance`` gives ``Solution.covariance`` of the returned pose from its inliers
            (with their weights), the noise in pixels with ``camera`` and in normalised units
            with ``focal`` (pycolmap's ``estimate_and_refine_absolute_pose(...,
            return_covariance=True)``).
        **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
            ``solve``.

    Returns:
        (Solution, dict): the pose fitted to the inliers, and ``info``: ``inliers`` (bool
        array, shape (N,)), ``num_inliers``, ``inlier_ratio``, ``iterations`` (samples drawn),
        ``hypotheses``, ``local_fits``, ``final_fits``, ``cost`` (the final fit's cost),
        ``rmse`` (its normalised RMS residual), ``rmse_px`` (RMS pixel reprojection error over
        the inliers) and ``micros`` (wall time).

    Raises:
        InvalidInputError: as ``solve``.
        InvalidOptionError: a RANSAC or solver option out of range, a focal length not finite
            and positive, neither or both of ``camera`` and ``focal``.
        NoConsensusError: no pose with at least 4 inliers.
        TypeError: as ``solve``.
    """

def read_colmap_model(path: str | os.PathLike[str]) -> Model:
    """Reads a COLMAP sparse model directory: ``cameras``, ``images`` and ``points3D``, and
    ``rigs`` and ``frames`` when present (COLMAP 3.12 and later), in the text (``.txt``) or
    binary (``.bin``) format (binary preferred when both are present), and checks its
    cross-references.

    Raises:
        ModelError: a missing or malformed file, with the file, line or byte offset and reason.
    """

def register_image(
    model: Model,
    image_id: int,
    *,
    ransac: _RansacArg | bool = None,
    estimate_focal: bool = False,
    focal_range: tuple[float, float] | None = None,
    refine_principal_point: bool = False,
    refine_distortion: bool = False,
    options: _Options = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> Registration:
    """Re-estimates an image's pose from its 2D-3D correspondences alone and compares it with the
    model's pose.

    Args:
        model: a ``Model`` from ``read_colmap_model``.
        image_id: the image.
        ransac: None or False: ``solve`` on every correspondence through the image's camera;
            True (default options), a ``RansacOptions`` or a dict of its fields: robust, as
            ``solve_ransac``.
        estimate_focal: the image's focal length is re-estimated with its pose, the model's
            camera the starting guess (as pycolmap's ``estimate_focal_length`` and
            ``refine_focal_length``); ``Registration.solution.camera`` holds the estimated
            camera, ``Registration.focal_error_pct`` its error against the model's.
        focal_range: ``(min_px, max_px)``, the range of the focal length sought (implies
            ``estimate_focal``; default a tenth to ten times the model camera's).
        refine_principal_point, refine_distortion: the principal point, the distortion
            parameters refined with the pose too, as ``solve``'s.
        options: a ``SolverOptions`` (or a dict of its fields), as ``solve``: ``loss``'s scale
            and ``covariance``'s noise in pixels; ``Registration.solution.covariance`` is from
            every correspondence used, or with RANSAC from the inliers.
        **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
            ``solve``.

    Returns:
        Registration: the pose, its errors against the model's, RANSAC's statistics.

    Raises:
        UnknownIdError: no such image (or its camera is missing).
        InvalidInputError, DegenerateError, NoConsensusError, ...: as ``solve`` and
            ``solve_ransac`` on the image's correspondences.
        InvalidOptionError: an option out of range (e.g. a bad ``focal_range``).
    """

def register_images(
    model: Model,
    image_ids: Iterable[int] | None = None,
    *,
    ransac: _RansacArg | bool = None,
    estimate_focal: bool = False,
    focal_range: tuple[float, float] | None = None,
    refine_principal_point: bool = False,
    refine_distortion: bool = False,
    options: _Options = None,
    threads: int | None = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> list[Registration | PnpError]:
    """Registers many images of a model (``register_image`` on each), in parallel, the GIL
    released for the whole call: each thread looks the model's 3D points up in a table it
    builds once (``register_image`` builds one per call).

    Args:
        model: a ``Model`` from ``read_colmap_model``.
        image_ids: the images (any iterable of ids), or None for every image in id order.
        ransac, estimate_focal, focal_range, refine_principal_point, refine_distortion,
        options, **keywords: as ``register_image``.
        threads: None (rayon's global pool) or the number of threads, as ``solve_batch``.

    Returns:
        list: one entry per id, in order: its ``Registration``, or the exception
        ``register_image`` would raise for it (an instance, not raised). Equal to
        ``register_image`` one by one but the times, whatever ``threads``.

    Raises:
        InvalidOptionError: an option out of range or a bad ``threads``.
        TypeError: as ``solve``.
    """

def register_frame(
    model: Model,
    frame_id: int,
    *,
    ransac: _RansacArg | bool = None,
    options: _Options = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> FrameRegistration:
    """Re-estimates the pose of a frame's rig from the 2D-3D correspondences of all its images at
    once and compares it with the model's frame pose (rig_from_world): the frame's images are
    the cameras of a rig, each with its cam_from_rig from ``Model.rigs``, as
    ``solve_generalized`` (``solve_generalized_ransac`` with RANSAC) solves it, every
    observation through its own camera, distortion included.

    Args:
        model: a ``Model`` from ``read_colmap_model`` of a model with rigs (COLMAP 3.12+).
        frame_id: the frame (``Model.frame_ids``).
        ransac: None or False: on every correspondence; True (default options), a
            ``RansacOptions`` or a dict of its fields: robust, as ``register_image``.
        options, **keywords: the solver's options, as ``register_image``.

    Returns:
        FrameRegistration: the rig pose, its errors against the model's, RANSAC's statistics,
        each image's camera pose.

    Raises:
        UnknownIdError: no such frame (kind ``"UnknownFrame"``), or its rig, an image or a
            camera is missing, or a camera has no known pose in the rig (``"NoSensorPose"``).
        InvalidInputError: a frame without images (``"EmptyFrame"``); and as
            ``register_image``: InvalidInputError, DegenerateError, NoConsensusError, ... on
            the frame's correspondences.
    """

def register_frames(
    model: Model,
    frame_ids: Iterable[int] | None = None,
    *,
    ransac: _RansacArg | bool = None,
    options: _Options = None,
    threads: int | None = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> list[FrameRegistration | PnpError]:
    """Registers many frames of a model (``register_frame`` on each), in parallel, the GIL
    released for the whole call, as ``register_images``.

    Args:
        model: a ``Model`` from ``read_colmap_model``.
        frame_ids: the frames (any iterable of ids), or None for every frame in id order.
        ransac, options, **keywords: as ``register_frame``.
        threads: None (rayon's global pool) or the number of threads, as ``solve_batch``.

    Returns:
        list: one entry per id, in order: its ``FrameRegistration``, or the exception
        ``register_frame`` would raise for it (an instance, not raised). Equal to
        ``register_frame`` one by one but the times, whatever ``threads``.

    Raises:
        InvalidOptionError: an option out of range or a bad ``threads``.
        TypeError: as ``solve``.
    """

@final
class Rig:
    """A multi-camera rig: calibrated cameras fixed to one body (a car's or a headset's cameras, a
    stereo pair), each with its pose in the rig.

    ``Rig(cameras, cams_from_rig)``: ``cameras`` a sequence of K ``Camera``, ``cams_from_rig``
    a sequence of K poses, camera ``k``'s pose in the rig: ``x_cam = R_k @ x_rig + t_k``
    (``cam_from_rig``, the convention of COLMAP's rigs and pycolmap's ``cams_from_rig``). Each
    pose is a ``(rotation, t)`` pair (the rotation a (3, 3) matrix, a (3,) rotation vector or a
    (4,) quaternion (w, x, y, z)), a (3, 4) ``[R | t]`` or a (4, 4) homogeneous matrix (a
    (K, 3, 4) array is a sequence of K such matrices), or a ``Solution``, as ``refine``'s
    ``initial``. From pycolmap: ``[p.matrix() for p in cams_from_rig]`` (``Rigid3d``) and
    ``Camera(c.model.name, c.params, c.width, c.height)``.

    The rig's own frame is any frame fixed to the body (often the first camera's: its pose is
    then the identity). A problem on the rig (``solve_generalized``) gives the rig's pose in
    the world, ``x_rig = R @ X + t`` (rig_from_world), and camera ``k``'s pose in the world is
    ``x_cam = R_k @ (R @ X + t) + t_k``.

    Immutable, comparable (``==``), picklable.

    Attributes:
        cameras: the K cameras, in index order.
        cams_from_rig: each camera's ``[R_k | t_k]``, shape (K, 3, 4).
        centres: each camera's centre in the rig frame, ``-R_k^T t_k``, shape (K, 3).

    Raises:
        InvalidOptionError: no camera (``option`` "cameras"), an entry of ``cameras`` that is
            not a ``Camera``, not K poses, a pose not of the forms above, not finite, or whose
            matrix is not a rotation to 1e-6 (``option`` "cams_from_rig").
    """
    def __new__(
        cls, cameras: Sequence[Camera], cams_from_rig: Sequence[_Pose] | _ArrayLike
    ) -> "Rig": ...
    @property
    def cameras(self) -> list[Camera]:
        """The cameras, in index order (a new list on each access)."""
    @property
    def cams_from_rig(self) -> _F64Array:
        """Each camera's pose in the rig, ``[R_k | t_k]`` with ``x_cam = R_k @ x_rig + t_k``,
        shape (K, 3, 4).
        """
    @property
    def centres(self) -> _F64Array:
        """Each camera's centre in the rig frame, ``-R_k^T t_k``, shape (K, 3)."""
    def __len__(self) -> int: ...
    def __eq__(self, value: object, /) -> bool: ...

# A rig problem of the rig batches: (points2D, points3D, camera_idxs) or (points2D, points3D,
# camera_idxs, weights), pixels first as pycolmap's generalized functions take them.
_RigProblem = Union[
    tuple[_ArrayLike, _ArrayLike, _ArrayLike],
    tuple[_ArrayLike, _ArrayLike, _ArrayLike, _ArrayLike | None],
]

def solve_generalized(
    points2D: _ArrayLike,
    points3D: _ArrayLike,
    camera_idxs: _ArrayLike,
    cams_from_rig: Sequence[_Pose] | _ArrayLike | None = None,
    cameras: Sequence[Camera] | None = None,
    *,
    rig: Rig | None = None,
    weights: _ArrayLike | None = None,
    gravity: Gravity | None = None,
    options: _Options = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> Solution:
    """The pose of a multi-camera rig from pixels observed by its cameras (the generalized PnP
    problem): each correspondence ``i`` is the world point ``points3D[i]`` observed at pixel
    ``points2D[i]`` of camera ``camera_idxs[i]``. Generalized EOPnP, then by default
    Levenberg-Marquardt on every pixel's reprojection error through its own camera (lens
    distortion included): the maximum-likelihood pose. When every point is in one camera, that
    camera's central problem (``solve`` with that camera), composed with its pose in the rig.

    The arguments follow pycolmap's ``estimate_and_refine_generalized_absolute_pose(points2D,
    points3D, camera_idxs, cams_from_rig, cameras)``: pixels first, unlike ``solve(world,
    image)``.

    Args:
        points2D: the observed (distorted) pixels, shape (N, 2), N >= 4.
        points3D: their world points, shape (N, 3).
        camera_idxs: the camera of each correspondence, integers of shape (N,), indices into
            ``cameras``.
        cams_from_rig: each camera's pose in the rig, ``x_cam = R_k @ x_rig + t_k`` (camera
            from rig, as pycolmap's ``cams_from_rig``), one per camera, in any form ``Rig``
            takes.
        cameras: the rig's cameras (``Camera``), indexed by ``camera_idxs``.
        rig: a ``Rig`` instead of ``cams_from_rig`` and ``cameras`` (built once, e.g. for many
            frames of one rig): give either ``cams_from_rig`` and ``cameras``, or ``rig``.
        weights: optional non-negative weight per correspondence, shape (N,), as ``solve``.
        options: a ``SolverOptions`` (or a dict of its fields), as ``solve``: ``loss`` scale
            and ``covariance`` noise in pixels.
        **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
            ``solve``.

    Returns:
        Solution: the rig's pose in the world, ``x_rig = R @ X + t`` (rig_from_world, as
        pycolmap's ``rig_from_world``); camera ``k`` is at ``x_cam = R_k @ (R @ X + t) + t_k``.
        ``cost`` is the pixel cost over every camera; ``reprojection_rmse`` is the RMS pixel
        error divided by the largest focal length of the rig's cameras (that camera's own
        normalised RMS when every point is in one camera); ``covariance`` is of the rig's pose.

    Raises:
        InvalidInputError: as ``solve``, and camera indices not one per point (kind
            ``"CameraIndicesLength"``) or naming a camera the rig does not have (kind
            ``"UnknownCamera"``, with the correspondence's ``index`` and its ``camera``).
        InputTypeError: arrays that are not real numbers, camera indices that are not
            integers.
        DegenerateError, NoSolutionError: as ``solve``.
        InvalidOptionError: an option out of range; a rig given in neither or both forms, or
            not as ``Rig`` takes it.
        TypeError: as ``solve``.
    """

def solve_generalized_ransac(
    points2D: _ArrayLike,
    points3D: _ArrayLike,
    camera_idxs: _ArrayLike,
    cams_from_rig: Sequence[_Pose] | _ArrayLike | None = None,
    cameras: Sequence[Camera] | None = None,
    *,
    rig: Rig | None = None,
    weights: _ArrayLike | None = None,
    gravity: Gravity | None = None,
    ransac: _RansacArg = None,
    options: _Options = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> tuple[Solution, _RansacInfo]:
    """Robust pose of a multi-camera rig from correspondences with outliers, by RANSAC:
    generalized three-point poses (gP3P) of samples spread over the cameras, MSAC scoring of
    each pixel's reprojection error through its own camera with an SPRT, adaptive iteration
    count, generalized EOPnP local optimisation and final fit on the inliers; seeded. With
    every point in one camera, that camera's ``solve_ransac``, composed with its pose in the
    rig.

    The arguments follow pycolmap's ``estimate_and_refine_generalized_absolute_pose(points2D,
    points3D, camera_idxs, cams_from_rig, cameras)``: pixels first, unlike ``solve_ransac``.

    Args:
        points2D, points3D, camera_idxs, cams_from_rig, cameras, rig, weights: as
            ``solve_generalized``.
        ransac: a ``RansacOptions``, a dict of its fields, or None (defaults: 4 px threshold,
            confidence 0.999, at most 10000 samples, seed 0); the threshold is on each pixel's
            reprojection error through its camera.
        options: a ``SolverOptions`` (or a dict of its fields), as ``solve_ransac``: the options
            of the fits; ``loss`` scale and ``covariance`` noise in pixels.
        **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
            ``solve``.

    Returns:
        (Solution, dict): the rig's pose fitted to the inliers (``x_rig = R @ X + t``,
        rig_from_world), and ``info`` as ``solve_ransac``'s: ``inliers`` (bool array, shape
        (N,)), ``num_inliers``, ``inlier_ratio``, ``iterations``, ``hypotheses``,
        ``local_fits``, ``final_fits``, ``cost``, ``rmse``, ``rmse_px`` (RMS pixel
        reprojection error over the inliers, each through its camera) and ``micros``.

    Raises:
        As ``solve_generalized``; InvalidOptionError also for a RANSAC option out of range;
        NoConsensusError: no pose with enough inliers.
    """

def refine_generalized(
    rig_from_world: _Pose,
    points2D: _ArrayLike,
    points3D: _ArrayLike,
    camera_idxs: _ArrayLike,
    cams_from_rig: Sequence[_Pose] | _ArrayLike | None = None,
    cameras: Sequence[Camera] | None = None,
    *,
    rig: Rig | None = None,
    weights: _ArrayLike | None = None,
    gravity: Gravity | None = None,
    options: _Options = None,
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> Solution:
    """Refines a prior pose of a multi-camera rig (tracking: the previous frame's pose) to the
    maximum-likelihood pose of the basin it starts in: Levenberg-Marquardt on every pixel's
    reprojection error through its own camera, from ``rig_from_world``, without the global
    search (``refine`` for rigs; pycolmap's ``refine_generalized_absolute_pose``). From a start
    in the basin of ``solve_generalized``'s pose, the same pose.

    The arguments follow pycolmap's ``refine_generalized_absolute_pose(rig_from_world,
    points2D, points3D, inlier_mask, camera_idxs, cams_from_rig, cameras)``, without
    ``inlier_mask``: pass ``weights=inlier_mask.astype(float)`` (a point of weight 0 is
    ignored exactly).

    Args:
        rig_from_world: the starting pose of the rig, ``x_rig = R @ X + t``: a ``Solution``
            (e.g. the previous frame's), a ``(rotation, t)`` pair, a (3, 4) ``[R | t]`` or a
            (4, 4) matrix, as ``refine``'s ``initial``.
        points2D, points3D, camera_idxs, cams_from_rig, cameras, rig, weights: as
            ``solve_generalized``.
        options: a ``SolverOptions`` (or a dict of its fields), as ``refine``.
        **keywords: ``loss``, ``covariance``, ``newton_iterations``, ``newton_step_tolerance``
            and ``reprojection_iterations`` as keyword arguments instead, as ``refine``.

    Returns:
        Solution: the refined pose of the rig (``x_rig = R @ X + t``); ``converged`` says
        whether the refinement reached a minimum, ``source`` is "initial".

    Raises:
        As ``solve_generalized``; InvalidOptionError (``option`` "rig_from_world") for a
        starting pose that is not finite or not of the forms above.
    """

def solve_generalized_batch(
    problems: Sequence[_RigProblem],
    *,
    rig: Rig | Sequence[Rig],
    gravity: Gravity | Sequence[Gravity | None] | None = None,
    options: _Options = None,
    threads: int | None = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> list[Solution | PnpError]:
    """Solves many independent rig problems in parallel (``solve_generalized`` on each), the GIL
    released while they are solved.

    Each array is copied once, with the GIL held, and the solves read the copy (as
    ``solve_generalized`` does): what other threads write to the arrays after the call copied
    them does not change its results.

    Args:
        problems: a sequence of ``(points2D, points3D, camera_idxs)`` or ``(points2D, points3D,
            camera_idxs, weights)`` tuples, as ``solve_generalized``'s arguments (pixels first;
            weights may be None).
        rig: a ``Rig`` for every problem, or a sequence of one ``Rig`` per problem.
        gravity: None, a ``Gravity`` for every problem, or a sequence of one ``Gravity`` (or
            None) per problem: the known vertical in the rig's frame, as
            ``solve_generalized``'s.
        options: a ``SolverOptions`` (or a dict of its fields), as ``solve_generalized``, for
            every problem.
        threads: as ``solve_batch``.
        **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
            ``solve``.

    Returns:
        list: one entry per problem, in order: its ``Solution`` (the rig's pose), or the
        exception instance that ``solve_generalized`` would raise for it. Each entry equals
        ``solve_generalized``'s, whatever the thread count.

    Raises:
        InvalidInputError: a malformed batch (not a sequence of 3- or 4-tuples, an array of the
            wrong shape; the message names the problem's index), before anything is solved.
        InputTypeError: an array that is not real numbers, camera indices that are not
            integers.
        InvalidOptionError: an option out of range, a bad ``rig``, ``gravity`` or ``threads``.
        TypeError: as ``solve``.
    """

def solve_generalized_ransac_batch(
    problems: Sequence[_RigProblem],
    *,
    rig: Rig | Sequence[Rig],
    gravity: Gravity | Sequence[Gravity | None] | None = None,
    ransac: _RansacArg = None,
    options: _Options = None,
    threads: int | None = None,
    refinement: _Refinement = "ml",
    planar: _Planar = "auto",
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    exhaustive: bool = False,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> list[tuple[Solution, _RansacInfo] | PnpError]:
    """Robust estimation of many independent rig problems in parallel
    (``solve_generalized_ransac`` on each), the GIL released for the whole batch. Problem
    ``i`` uses the seed ``problem_seed(ransac.seed, i)``, so results do not depend on the
    thread count.

    Args:
        problems: as ``solve_generalized_batch``.
        rig: a ``Rig`` for every problem, or a sequence of one ``Rig`` per problem.
        gravity: None, a ``Gravity`` for every problem, or a sequence of one ``Gravity`` (or
            None) per problem, as ``solve_generalized_ransac``'s.
        ransac: a ``RansacOptions``, a dict of its fields, or None; ``seed`` is the base seed.
        options: a ``SolverOptions`` (or a dict of its fields), as
            ``solve_generalized_ransac``, for every problem.
        threads: as ``solve_batch``.
        **keywords: the options of ``SolverOptions`` as keyword arguments instead, as
            ``solve``.

    Returns:
        list: one entry per problem, in order: ``(Solution, info)`` as
        ``solve_generalized_ransac`` returns with ``RansacOptions(seed=problem_seed(seed,
        i))``, or the exception instance it would raise (e.g. ``NoConsensusError``).

    Raises:
        As ``solve_generalized_batch``.
    """

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
