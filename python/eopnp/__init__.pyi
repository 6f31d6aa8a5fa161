"""Type stubs of the eopnp package (the extension module eopnp._eopnp and eopnp._batch).

Conventions: world points are (N, 3), image points (N, 2), normalised (x/z, y/z) unless a
``camera`` is given (then pixels). Any array-like of real numbers is accepted (float or integer
dtype, any layout) and read as float64; arrays returned are new float64 arrays (bool for
inlier masks). Poses map world to camera: ``x_cam = R @ X + t``.
"""

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
    "other",
]
_Loss = Union[
    Literal["squared"], tuple[Literal["huber", "cauchy"], float], None
]
"""``loss=``: None or "squared" (default), ``("huber", s)`` or ``("cauchy", s)``, the scale
``s`` in pixels with a camera, in normalised units otherwise (finite, > 0)."""

class PnpError(Exception):
    """Base class of every exception raised by eopnp: the library's message (``str(e)``), the
    error's name (``kind``) and its fields (attributes, and the dict ``details``)."""

    kind: str
    details: dict[str, Any]

class InvalidInputError(PnpError, ValueError): ...
class InputTypeError(InvalidInputError, TypeError): ...
class DegenerateError(PnpError, ValueError): ...
class NoSolutionError(PnpError, RuntimeError): ...
class InvalidOptionError(PnpError, ValueError): ...
class NoConsensusError(PnpError, RuntimeError): ...
class CameraError(PnpError, ValueError): ...
class ModelError(PnpError): ...
class UnknownIdError(PnpError, LookupError): ...

_Covariance = Union[Literal["estimated"], float, None]

@final
class SolverOptions:
    """The solver's options, for ``options=`` of every function that solves (which also take
    them as keyword arguments, not together with ``options=``). Checked at construction
    (``InvalidOptionError``); immutable (``replace`` returns a changed copy), hashable,
    picklable."""

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
    def refinement(self) -> Literal["ml", "algebraic"]: ...
    @property
    def planar(self) -> _Planar: ...
    @property
    def newton_iterations(self) -> int | None: ...
    @property
    def newton_step_tolerance(self) -> float | None: ...
    @property
    def reprojection_iterations(self) -> int | None: ...
    @property
    def exhaustive(self) -> bool: ...
    @property
    def loss(self) -> Literal["squared"] | tuple[Literal["huber", "cauchy"], float]: ...
    @property
    def covariance(self) -> Literal["estimated"] | float | None: ...
    def as_dict(self) -> dict[str, Any]: ...
    def replace(self, **changes: Any) -> "SolverOptions": ...
    def __eq__(self, value: object, /) -> bool: ...
    def __hash__(self) -> int: ...
    def __getnewargs_ex__(self) -> tuple[tuple[()], dict[str, Any]]: ...

_Options = Union[SolverOptions, Mapping[str, Any], None]
"""``options=``: a ``SolverOptions``, a dict of its fields, or None (the defaults)."""

@final
class Solution:
    """A camera pose (world to camera, ``x_cam = R @ X + t``) and how it was found.

    Picklable; ``==`` compares every field exactly.
    """

    @property
    def R(self) -> _F64Array:
        """Rotation matrix, shape (3, 3)."""
    @property
    def t(self) -> _F64Array:
        """Translation, shape (3,)."""
    @property
    def rvec(self) -> _F64Array:
        """OpenCV's rotation vector (axis times angle in radians, ``cv2.Rodrigues``), (3,)."""
    @property
    def q(self) -> _F64Array:
        """Unit quaternion (w, x, y, z), COLMAP's order, shape (4,)."""
    @property
    def Rt(self) -> _F64Array:
        """The 3x4 matrix [R | t]."""
    @property
    def cost(self) -> float:
        """The minimised cost (refinement "ml"): the (weighted) sum of the loss of the squared
        reprojection residuals, in pixels^2 for pixel input (through the camera), normalised
        units otherwise (the sum of squares with the default loss); or the algebraic cost
        (refinement "algebraic")."""
    @property
    def algebraic_cost(self) -> float:
        """The paper's algebraic cost of the rotation."""
    @property
    def reprojection_rmse(self) -> float:
        """RMS normalised reprojection residual (times the focal length: pixels); inf if a
        point lies in the focal plane (algebraic mode only)."""
    @property
    def cheirality_ok(self) -> bool:
        """More than half of the points are in front of the camera."""
    @property
    def degenerate(self) -> bool:
        """The configuration is close to degenerate: the pose may be ambiguous."""
    @property
    def planar(self) -> bool:
        """The planar branch produced the winning start."""
    @property
    def source(self) -> _Source:
        """The candidate generator of the winning start."""
    @property
    def newton_iterations(self) -> int:
        """Damped-Newton iterations of the winning candidate (0 when skipped: an exact fit)."""
    @property
    def reprojection_iterations(self) -> int:
        """Levenberg-Marquardt iterations of the refinement (0 in algebraic mode)."""
    @property
    def converged(self) -> bool:
        """The refinement stopped at a minimum (False when it ran out of iterations or could
        not start; True in algebraic mode)."""
    @property
    def used(self) -> int:
        """Correspondences that entered the solve (weight > 0, undistorted)."""
    @property
    def skipped(self) -> int:
        """Correspondences left out because their pixel could not be undistorted."""
    @property
    def covariance(self) -> _F64Array | None:
        """The pose's 6x6 covariance (``covariance=`` of ``solve``), or None: of
        ``[delta_q, delta_t]`` with ``R = Exp(2 delta_q) R_hat``, ``t = t_hat + delta_t``
        (pycolmap's ``return_covariance=True`` convention; ``delta_q`` is half the rotation
        vector, so the covariance of ``[rotation vector, t]`` has the rotation block times 4
        and the cross blocks times 2)."""
    @property
    def sigma(self) -> float | None:
        """The noise standard deviation the covariance assumes (given or estimated), or
        None."""
    def as_dict(self) -> dict[str, Any]:
        """Every field as a dict (arrays for R, t, rvec, q, covariance)."""

@final
class Camera:
    """A camera model: COLMAP's model name and parameters (COLMAP's order), image size.

    Models: SIMPLE_PINHOLE (f, cx, cy), PINHOLE (fx, fy, cx, cy), SIMPLE_RADIAL (f, cx, cy, k),
    RADIAL (f, cx, cy, k1, k2), OPENCV (fx, fy, cx, cy, k1, k2, p1, p2), OPENCV_FISHEYE
    (fx, fy, cx, cy, k1, k2, k3, k4), FULL_OPENCV (fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5,
    k6), SIMPLE_RADIAL_FISHEYE (f, cx, cy, k), RADIAL_FISHEYE (f, cx, cy, k1, k2), and
    OPENCV_THIN_PRISM_TILTED (FULL_OPENCV's 12, s1, s2, s3, s4, tau_x, tau_y; OpenCV's, not
    COLMAP's). Picklable.

    Raises:
        CameraError: unknown model, wrong parameter count, non-finite parameters,
            non-positive focal lengths.
    """

    def __new__(
        cls, model: str, params: _ArrayLike, width: int = 0, height: int = 0
    ) -> "Camera": ...
    @staticmethod
    def from_opencv(K: _ArrayLike, dist: _ArrayLike | None = None) -> "Camera":
        """From OpenCV's camera matrix (zero skew) and distortion vector (0, 4, 5, 8, 12 or 14
        coefficients in OpenCV's order; shape (n,), (1, n) or (n, 1)): ``project`` equals
        ``cv2.projectPoints`` with rvec = tvec = 0 (OpenCV's pixel convention)."""
    @staticmethod
    def from_opencv_fisheye(K: _ArrayLike, dist: _ArrayLike) -> "Camera":
        """From ``cv2.fisheye``'s K (zero skew) and its 4 coefficients: OPENCV_FISHEYE."""
    @staticmethod
    def pinhole(fx: float, fy: float, cx: float, cy: float) -> "Camera":
        """PINHOLE without distortion, image size 0."""
    @property
    def model(self) -> str:
        """The model's name, e.g. "SIMPLE_RADIAL"."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def params(self) -> _F64Array:
        """The parameters in COLMAP's order, shape (n,)."""
    @property
    def focal(self) -> tuple[float, float]:
        """(fx, fy) in pixels."""
    @property
    def principal_point(self) -> tuple[float, float]:
        """(cx, cy) in pixels."""
    @property
    def has_distortion(self) -> bool: ...
    def to_opencv(self) -> tuple[_F64Array, _F64Array] | None:
        """OpenCV's (K, dist), or None for the fisheye models."""
    def to_opencv_fisheye(self) -> tuple[_F64Array, _F64Array] | None:
        """cv2.fisheye's (K, dist) of an OPENCV_FISHEYE camera, else None."""
    def project(self, normalised: _ArrayLike) -> _F64Array:
        """Pixels of normalised points (x/z, y/z): (N, 2) -> (N, 2)."""
    def undistort(self, pixels: _ArrayLike) -> _F64Array:
        """Normalised points of pixels: (N, 2) -> (N, 2); NaN rows for pixels that cannot be
        undistorted."""

@final
class RansacOptions:
    """RANSAC options; each is a settable attribute. Out-of-range values raise
    ``InvalidOptionError`` when used. Picklable."""

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
        """Defaults: threshold_px 4.0, confidence 0.999, max_iterations 10000,
        min_iterations 20, seed 0, local_optimisation True, final_threshold_factor 2.0."""
    def as_dict(self) -> dict[str, Any]: ...

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
    """An image of a COLMAP model."""

    @property
    def id(self) -> int: ...
    @property
    def name(self) -> str: ...
    @property
    def camera_id(self) -> int: ...
    @property
    def q(self) -> _F64Array:
        """Pose quaternion (w, x, y, z) as stored."""
    @property
    def t(self) -> _F64Array:
        """Pose translation (3,)."""
    @property
    def R(self) -> _F64Array:
        """Pose rotation (3, 3)."""
    @property
    def points2D(self) -> _F64Array:
        """Observations' pixels (K, 2)."""
    @property
    def point3D_ids(self) -> npt.NDArray[np.int64]:
        """Observations' 3D point ids (K,), -1 if untriangulated."""

@final
class Model:
    """A COLMAP sparse reconstruction (read-only)."""

    @property
    def cameras(self) -> dict[int, Camera]: ...
    @property
    def images(self) -> dict[int, Image]: ...
    @property
    def image_ids(self) -> list[int]: ...
    @property
    def num_points3D(self) -> int: ...
    @property
    def point3D_ids(self) -> npt.NDArray[np.uint64]: ...
    @property
    def points3D(self) -> _F64Array:
        """3D points (M, 3) in the order of point3D_ids."""
    def image(self, image_id: int) -> Image: ...
    def camera_of(self, image_id: int) -> Camera: ...
    def correspondences(self, image_id: int) -> tuple[_F64Array, _F64Array]:
        """(world (N, 3), pixels (N, 2)) of the image's triangulated observations."""
    def __len__(self) -> int: ...

@final
class Registration:
    """The result of ``register_image``."""

    @property
    def image_id(self) -> int: ...
    @property
    def name(self) -> str: ...
    @property
    def n(self) -> int:
        """The image's 2D-3D correspondences."""
    @property
    def inliers(self) -> int:
        """Correspondences the pose was fitted to."""
    @property
    def skipped(self) -> int: ...
    @property
    def solution(self) -> Solution: ...
    @property
    def ransac(self) -> dict[str, Any] | None:
        """iterations, hypotheses, local_fits, final_fits, inliers, inlier_ratio, micros."""
    @property
    def rotation_error_deg(self) -> float: ...
    @property
    def translation_error_pct(self) -> float: ...
    @property
    def rmse_px(self) -> float: ...
    @property
    def model_rmse_px(self) -> float: ...
    @property
    def micros(self) -> float: ...

def solve(
    world: _ArrayLike,
    image: _ArrayLike,
    weights: _ArrayLike | None = None,
    *,
    camera: Camera | None = None,
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
    """The camera pose from N >= 4 correspondences: world (N, 3), image (N, 2) normalised, or
    pixels with ``camera``; optional weights (N,) >= 0. Default: EOPnP + maximum-likelihood
    refinement. Releases the GIL.

    ``covariance``: None, "estimated" (noise from the residuals) or the noise standard
    deviation in image units (pixels with ``camera``): fills ``Solution.covariance`` and
    ``Solution.sigma``.

    ``loss``: the loss of the final refinement: None or "squared" (default, the
    maximum-likelihood pose for Gaussian noise), ``("huber", s)`` (a few moderate outliers;
    ``s`` 1-3 times the noise) or ``("cauchy", s)`` (gross outliers hardly move the pose);
    ``s`` in pixels with ``camera``, normalised units otherwise.

    Raises InvalidInputError (InputTypeError), DegenerateError, NoSolutionError,
    InvalidOptionError."""

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
    """Every distinct local minimum, best first (normalised image points)."""

_Rotation = _ArrayLike
"""A rotation: a (3, 3) matrix, a (3,) rotation vector (OpenCV's rvec) or a (4,) quaternion
(w, x, y, z)."""
_Pose = Union[Solution, tuple[_Rotation, _ArrayLike], _ArrayLike]
"""A pose (world to camera): a ``Solution``, ``(rotation, t)``, or a (3, 4) ``[R | t]`` or
(4, 4) matrix."""

def refine(
    world: _ArrayLike,
    image: _ArrayLike,
    initial: _Pose,
    *,
    weights: _ArrayLike | None = None,
    camera: Camera | None = None,
    options: _Options = None,
    newton_iterations: int | None = None,
    newton_step_tolerance: float | None = None,
    reprojection_iterations: int | None = None,
    loss: _Loss = None,
    covariance: _Covariance = None,
) -> Solution:
    """Refines a prior pose (tracking: the previous frame's) to the maximum-likelihood pose of
    the basin it starts in, without the global search (OpenCV's ``solvePnPRefineLM``,
    PoseLib's ``refine_absolute_pose``). ``initial``: a ``Solution``, ``(R, t)``,
    ``(rvec, t)``, ``(q_wxyz, t)``, or a (3, 4) ``[R | t]`` or (4, 4) matrix. Pixels with
    ``camera`` (through the camera model, as ``solve``); ``weights`` (N,) >= 0 as ``solve``.
    Releases the GIL.

    Returns a ``Solution`` with ``converged`` and ``source == "initial"``. Raises as
    ``solve``, and InvalidOptionError (option "initial") for a non-finite initial pose or
    one of another form."""

def solve_batch(
    problems: Sequence[_Problem],
    *,
    camera: Camera | Sequence[Camera] | None = None,
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
    """``solve`` on many problems, ``(world, image)`` or ``(world, image, weights)`` tuples,
    in parallel (``threads``: None for rayon's default, or a count), the GIL released.
    ``camera``: one for all problems or one per problem (pixels), or None (normalised).
    The arrays are copied first, with the GIL held: another thread may modify them during
    the call without changing its results.

    Returns one entry per problem: its ``Solution``, or the exception ``solve`` would raise
    for it (an instance, not raised). Equal to ``solve`` one by one, whatever ``threads``.
    Raises InvalidInputError (InputTypeError) for a malformed batch before solving anything,
    InvalidOptionError for bad options."""

def solve_batch_arrays(
    world: _ArrayLike,
    image: _ArrayLike,
    weights: _ArrayLike | None = None,
    *,
    camera: Camera | Sequence[Camera] | None = None,
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
    """``solve`` on B problems given as stacked arrays, world (B, N, 3) and image (B, N, 2)
    (normalised, or pixels with ``camera``: one for all or one per problem), optional weights
    (B, N), in parallel (``threads`` as ``solve_batch``), the GIL released; the throughput
    form: no Python object per problem. Problems with fewer points: pad them with weight 0
    (any finite values), exactly as if dropped.

    Returns a ``BatchResult``: ``R`` (B, 3, 3), ``t`` (B, 3), ``cost``, ``reprojection_rmse``,
    ``ok`` (B,), ``covariance`` (B, 6, 6) and ``sigma`` with ``covariance=``, and ``errors``
    {index: exception}. Row ``i`` equals ``solve(world[i], image[i], weights[i], ...)``
    exactly, whatever ``threads``. The arrays are copied first, with the GIL held: another
    thread may modify them during the call without changing its results. Raises InvalidInputError (InputTypeError) for arrays of
    the wrong shape (dtype) before solving anything, InvalidOptionError for bad options."""

def solve_ransac_batch(
    problems: Sequence[_Problem],
    *,
    camera: Camera | Sequence[Camera] | None = None,
    focal: float | tuple[float, float] | None = None,
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
    """``solve_ransac`` on many problems in parallel: entry ``i`` is what ``solve_ransac``
    returns with seed ``problem_seed(ransac.seed, i)`` (or the exception instance it would
    raise, e.g. NoConsensusError), whatever ``threads``."""

def problem_seed(base: int, index: int) -> int:
    """The RANSAC seed of problem ``index`` of a batch with base seed ``base``."""

def solve_ransac(
    world: _ArrayLike,
    image: _ArrayLike,
    weights: _ArrayLike | None = None,
    *,
    camera: Camera | None = None,
    focal: float | tuple[float, float] | None = None,
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
    """Robust pose by RANSAC: pixels with ``camera``, or normalised points with
    ``focal=(fx, fy)`` (exactly one). Returns the pose and the info dict (inlier mask,
    iterations, inlier ratio, cost, RMSE). ``loss``: of the fits' final refinement (pixels with
    ``camera``, normalised units with ``focal``). ``covariance``: as ``solve``, the returned
    pose's covariance from its inliers. Raises NoConsensusError if no pose has 4 inliers."""

def read_colmap_model(path: str | os.PathLike[str]) -> Model:
    """Reads a COLMAP model directory (text or binary). Raises ModelError."""

def register_image(
    model: Model,
    image_id: int,
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
) -> Registration:
    """Re-estimates an image's pose from its correspondences (plain, or RANSAC with
    ``ransac=True`` / options) and compares it with the model's (``covariance``: as ``solve``,
    in pixels; with RANSAC from the inliers). Raises UnknownIdError."""

def register_images(
    model: Model,
    image_ids: Iterable[int] | None = None,
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
) -> list[Registration | PnpError]:
    """``register_image`` on many images (None: every image, in id order), in parallel
    (``threads`` as ``solve_batch``), the GIL released; each thread builds the table of the
    model's 3D points once. Returns one entry per id: its ``Registration``, or the exception
    ``register_image`` would raise for it (an instance, not raised). Equal to
    ``register_image`` one by one but the times."""

__all__ = [
    "BatchResult",
    "Camera",
    "CameraError",
    "DegenerateError",
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
    "Solution",
    "SolverOptions",
    "UnknownIdError",
    "__version__",
    "problem_seed",
    "read_colmap_model",
    "refine",
    "register_image",
    "register_images",
    "solve",
    "solve_all",
    "solve_batch",
    "solve_batch_arrays",
    "solve_ransac",
    "solve_ransac_batch",
]
