"""One exception hierarchy for the whole toolkit.

Every error raised on bad user input derives from :class:`ZRPError`, and from the matching
built-in (``ValueError``, ``FileExistsError``...) so that generic handlers keep working.
Messages name the field, joint, file line or option at fault and say what was expected.
"""

from __future__ import annotations

__all__ = [
    "IKError",
    "InputError",
    "ModelError",
    "ModelFileError",
    "OutputExistsError",
    "SingularityWarning",
    "TrackingWarning",
    "UnreachableError",
    "ZRPError",
    "ZRPWarning",
]


class ZRPError(Exception):
    """Base class of every error raised by this toolkit."""


class ModelError(ZRPError, ValueError):
    """A manipulator model is invalid (the message names the joint and field)."""


class ModelFileError(ModelError):
    """A model file cannot be read (the message names the file and line)."""


class InputError(ZRPError, ValueError):
    """A function argument or option has the wrong shape, type or value."""


class OutputExistsError(ZRPError, FileExistsError):
    """Refusing to overwrite an existing file without ``overwrite=True``."""


class IKError(ZRPError, RuntimeError):
    """Inverse kinematics failed (the message names the time and the point)."""


class UnreachableError(IKError):
    """A trajectory point lies outside the reachable workspace."""


class ZRPWarning(UserWarning):
    """Base class of this toolkit's warnings."""


class SingularityWarning(ZRPWarning):
    """The trajectory passes close to a kinematic singularity."""


class TrackingWarning(ZRPWarning):
    """Inverse kinematics could not reach the requested tolerance at some steps."""
