"""The result of ``eopnp.solve_batch_arrays``: stacked arrays, one row per problem."""

from __future__ import annotations

import operator
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import numpy as np
    import numpy.typing as npt

    from . import PnpError

__all__ = ["BatchResult"]


class BatchResult:
    """The poses of a batch of B problems (``eopnp.solve_batch_arrays``), as stacked arrays.

    Row ``i`` equals ``eopnp.solve`` on problem ``i``: ``R[i]``, ``t[i]``, ``cost[i]`` and
    ``reprojection_rmse[i]`` are that ``Solution``'s ``R``, ``t``, ``cost`` and
    ``reprojection_rmse`` (``covariance[i]`` and ``sigma[i]`` with ``covariance=``), to the
    last bit. A problem that ``solve`` would raise for has ``ok[i]`` False, NaN rows, and the
    exception instance ``solve`` would raise in ``errors[i]`` (also ``error(i)``).

    Attributes:
        R: rotations, shape (B, 3, 3) (``x_cam = R @ X + t``).
        t: translations, shape (B, 3).
        cost: the minimised costs, shape (B,).
        reprojection_rmse: RMS normalised reprojection residuals, shape (B,).
        ok: shape (B,), bool: the problem was solved.
        covariance: the 6x6 pose covariances, shape (B, 6, 6), or None (no ``covariance=``).
        sigma: the noise standard deviations the covariances assume, shape (B,), or None.
        focal: the estimated focal lengths ``(fx, fy)`` (``Solution.focal``), shape (B, 2),
            with ``estimate_focal=`` (NaN rows where a problem failed), or None.
        errors: {index: exception} for the problems that failed (``PnpError`` instances).
    """

    __slots__ = (
        "R",
        "t",
        "cost",
        "reprojection_rmse",
        "ok",
        "covariance",
        "sigma",
        "errors",
        "focal",
    )

    R: npt.NDArray[np.float64]
    t: npt.NDArray[np.float64]
    cost: npt.NDArray[np.float64]
    reprojection_rmse: npt.NDArray[np.float64]
    ok: npt.NDArray[np.bool_]
    covariance: npt.NDArray[np.float64] | None
    sigma: npt.NDArray[np.float64] | None
    errors: dict[int, PnpError]
    focal: npt.NDArray[np.float64] | None

    def __init__(
        self,
        R: npt.NDArray[np.float64],
        t: npt.NDArray[np.float64],
        cost: npt.NDArray[np.float64],
        reprojection_rmse: npt.NDArray[np.float64],
        ok: npt.NDArray[np.bool_],
        covariance: npt.NDArray[np.float64] | None,
        sigma: npt.NDArray[np.float64] | None,
        errors: dict[int, PnpError],
        focal: npt.NDArray[np.float64] | None = None,
    ) -> None:
        self.R = R
        self.t = t
        self.cost = cost
        self.reprojection_rmse = reprojection_rmse
        self.ok = ok
        self.covariance = covariance
        self.sigma = sigma
        self.errors = errors
        self.focal = focal

    def __len__(self) -> int:
        return len(self.ok)

    def error(self, index: int) -> PnpError | None:
        """The exception ``solve`` would raise for problem ``index`` (an instance, not raised),
        or None when it was solved. Negative indices count from the end."""
        i = operator.index(index)
        n = len(self.ok)
        if not -n <= i < n:
            raise IndexError(f"problem index {index} out of range for a batch of {n}")
        return self.errors.get(i % n)

    def __reduce__(self) -> Any:
        return (
            BatchResult,
            (
                self.R,
                self.t,
                self.cost,
                self.reprojection_rmse,
                self.ok,
                self.covariance,
                self.sigma,
                self.errors,
                self.focal,
            ),
        )

    def __repr__(self) -> str:
        n = len(self.ok)
        return f"BatchResult({n} problems, {n - len(self.errors)} solved, {len(self.errors)} failed)"
