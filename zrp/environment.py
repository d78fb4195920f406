"""Environment variables the toolkit's layers read, checked before anything reads them.

``MUJOCO_GL`` selects MuJoCo's OpenGL backend, and MuJoCo reads it when it is first imported:
an unknown value makes ``import mujoco`` itself fail with a bare ``RuntimeError``. The
``mjcf`` and ``sim`` layers call :func:`check_mujoco_gl` before they import MuJoCo (it lives
in the core, which never imports MuJoCo, so that both can reach it without loading it).
"""

from __future__ import annotations

import os
import platform

from zrp.errors import InputError

__all__ = ["MUJOCO_GL_VALUES", "EnvironmentVariableError", "check_mujoco_gl"]

_OFF = ("disable", "disabled", "off", "false", "0")
_ON = ("enable", "enabled", "on", "true", "1", "glfw", "")
_PLATFORM = {"Linux": ("glx", "egl", "osmesa"), "Windows": ("wgl",), "Darwin": ("cgl",)}
#: The values MuJoCo accepts for ``MUJOCO_GL`` on this platform (lower case, stripped).
MUJOCO_GL_VALUES = _OFF + _ON + _PLATFORM.get(platform.system(), ())


class EnvironmentVariableError(InputError):
    """An environment variable holds a value the program cannot use (names it and the choices)."""


def check_mujoco_gl() -> str:
    """The value of ``MUJOCO_GL`` (lower case), checked against :data:`MUJOCO_GL_VALUES`.

    Raises:
        EnvironmentVariableError: naming the value and the valid choices.
    """
    value = os.environ.get("MUJOCO_GL", "").strip().lower()
    if value not in MUJOCO_GL_VALUES:
        offscreen = [v for v in ("egl", "osmesa") if v in MUJOCO_GL_VALUES]
        raise EnvironmentVariableError(
            f"MUJOCO_GL environment variable: {os.environ['MUJOCO_GL']!r} is not a backend "
            f"MuJoCo knows; expected {' or '.join(offscreen) or 'glfw'} for offscreen rendering"
            f" (or one of {', '.join(v for v in MUJOCO_GL_VALUES if v)}), or unset it")
    return value
