"""A spec's MJCF text at full double precision.

MuJoCo's XML writer keeps 6 significant digits by default: a model saved and reloaded is not
the model (a mass of 4.970684 kg comes back as 4.97068 kg). Its library exports the writer's
precision as ``_mjPRIVATE__set_xml_precision`` (what MuJoCo's own tests use for full
precision); :func:`spec_xml` sets it to 17 digits (every double reads back as itself) for one
:meth:`mujoco.MjSpec.to_xml` and restores it. A MuJoCo without that symbol writes its default
(:data:`FULL_PRECISION` then False).
"""

from __future__ import annotations

import ctypes
import glob
import os
import threading

import mujoco

__all__ = ["FULL_PRECISION", "spec_xml"]

#: Digits that make every double read back as itself.
DIGITS = 17

_LOCK = threading.Lock()


def _library() -> ctypes.CDLL | None:
    """MuJoCo's shared library as the bindings loaded it (dlopen returns the same handle)."""
    here = os.path.dirname(mujoco.__file__)
    for pattern in ("libmujoco.so*", "libmujoco*.dylib", "mujoco.dll"):
        for path in sorted(glob.glob(os.path.join(here, pattern))):
            try:
                lib = ctypes.CDLL(path)
                getter = lib._mjPRIVATE__get_xml_precision
                setter = lib._mjPRIVATE__set_xml_precision
            except (OSError, AttributeError):
                continue
            getter.restype, getter.argtypes = ctypes.c_int, []
            setter.restype, setter.argtypes = None, [ctypes.c_int]
            return lib
    return None


_LIB = _library()

#: Whether :func:`spec_xml` writes at full precision with this MuJoCo.
FULL_PRECISION = _LIB is not None


def spec_xml(spec: mujoco.MjSpec) -> str:
    """``spec.to_xml()`` with every number at full double precision (module docstring)."""
    if _LIB is None:
        return spec.to_xml()
    with _LOCK:
        before = int(_LIB._mjPRIVATE__get_xml_precision())
        _LIB._mjPRIVATE__set_xml_precision(DIGITS)
        try:
            return spec.to_xml()
        finally:
            _LIB._mjPRIVATE__set_xml_precision(before)
