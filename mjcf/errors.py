"""Errors of the MJCF layer (all derive from :class:`zrp.ZRPError`)."""

from __future__ import annotations

from zrp.errors import InputError, ZRPError

__all__ = ["MJCFCompileError", "MJCFImportError", "MJCFOutputError"]


class MJCFCompileError(ZRPError, ValueError):
    """MuJoCo refused to compile a generated or loaded model (its message is included)."""


class MJCFImportError(InputError):
    """An MJCF/URDF file cannot be read as a serial arm (the message names the body/joint)."""


class MJCFOutputError(ZRPError, OSError):
    """An output file cannot be written (the message names the path and the reason)."""
