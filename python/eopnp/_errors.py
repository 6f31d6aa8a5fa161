"""The exceptions of the eopnp package.

They mirror the Rust crate's ``PnpError`` (one class per family of variants) and add the
families of the camera and COLMAP APIs. Every exception carries the library's message
(``str(e)``), the variant's name in ``e.kind`` and the variant's fields as attributes
(e.g. ``e.index`` and ``e.input`` of a non-finite value); ``e.details`` holds the same
fields as a dict.

::

    PnpError(Exception)                        base of every error of this package
    ├── InvalidInputError(PnpError, ValueError)  TooFewPoints, LengthMismatch, WeightsLength,
    │   │                                        NonFinite, InvalidWeight; wrong array shapes
    │   └── InputTypeError(InvalidInputError, TypeError)   arrays that are not real numbers
    ├── DegenerateError(PnpError, ValueError)    Degenerate (e.degeneracy: which kind)
    ├── NoSolutionError(PnpError, RuntimeError)  NoSolution (numerical failure)
    ├── InvalidOptionError(PnpError, ValueError) InvalidOption: an option out of its range
    ├── NoConsensusError(PnpError, RuntimeError) NoConsensus: RANSAC found no consensus
    ├── CameraError(PnpError, ValueError)        an invalid camera (model, parameters, K)
    ├── ModelError(PnpError)                     a COLMAP model that cannot be read
    └── UnknownIdError(PnpError, LookupError)    no such image or camera in a COLMAP model
"""

from __future__ import annotations

from typing import Any

__all__ = [
    "PnpError",
    "InvalidInputError",
    "InputTypeError",
    "DegenerateError",
    "NoSolutionError",
    "InvalidOptionError",
    "NoConsensusError",
    "CameraError",
    "ModelError",
    "UnknownIdError",
]


def _rebuild(cls: type, message: str, kind: str, details: dict) -> "PnpError":
    return cls(message, kind, **details)


class PnpError(Exception):
    """Base class of every exception raised by eopnp.

    Attributes:
        kind: the name of the Rust ``PnpError`` variant (``"TooFewPoints"``, ``"NonFinite"``,
            ...) or of the binding's check (``"Shape"``, ``"DType"``, ...).
        details: the variant's fields, also set as attributes of the exception.
    """

    def __init__(self, message: str, kind: str = "", **details: Any) -> None:
        super().__init__(message)
        self.kind = kind
        self.details = details
        for key, value in details.items():
            setattr(self, key, value)

    def __reduce__(self):  # picklable with its kind and fields (e.g. across processes)
        return (_rebuild, (type(self), str(self), self.kind, self.details))


class InvalidInputError(PnpError, ValueError):
    """Bad input: too few points (``got``, ``need``), mismatched lengths (``world``, ``image``;
    ``weights``, ``points``), a NaN or infinite value (``index``, ``input``: ``"world"``,
    ``"image"`` or ``"weights"``), a negative weight (``index``), or an array of the wrong shape
    (kind ``"Shape"``, ``argument``)."""


class InputTypeError(InvalidInputError, TypeError):
    """An input that is not an array of real numbers (kind ``"DType"``, ``argument``): complex,
    boolean, object or string data."""


class DegenerateError(PnpError, ValueError):
    """A degenerate configuration (kind ``"Degenerate"``); ``degeneracy`` is one of
    ``"coincident_world_points"``, ``"collinear_world_points"``, ``"coincident_image_points"``,
    ``"scale_out_of_range"``."""


class NoSolutionError(PnpError, RuntimeError):
    """No candidate pose survived (numerical failure on extremely ill-conditioned input)."""


class InvalidOptionError(PnpError, ValueError):
    """An option out of its range (``option``: its name)."""


class NoConsensusError(PnpError, RuntimeError):
    """RANSAC found no consensus: no pose had enough inliers for a fit, or the best pose's
    ``inliers`` are no more than a wrong pose reaches by chance (``needed``: the least
    accepted; ``iterations``: samples drawn)."""


class CameraError(PnpError, ValueError):
    """An invalid camera: unsupported model, wrong number of parameters, non-finite or
    non-positive focal lengths, a malformed ``K`` or distortion vector."""


class ModelError(PnpError):
    """A COLMAP model that cannot be read: ``file``, ``line`` or ``offset`` (or None), and
    ``reason``."""


class UnknownIdError(PnpError, LookupError):
    """No image (kind ``"UnknownImage"``) or camera (``"UnknownCamera"``) with this ``id`` in
    the model."""
