"""Choosing the offscreen OpenGL backend (EGL or OSMesa) and creating its context.

MuJoCo's own ``mujoco.gl_context`` fixes the backend from ``MUJOCO_GL`` when ``mujoco`` is first
imported, and PyOpenGL fixes its platform (``PYOPENGL_PLATFORM``) when ``OpenGL`` is first
imported. We therefore:

* honour ``MUJOCO_GL`` when it is set (``egl`` or ``osmesa``; anything else is an error that
  lists the valid choices);
* otherwise probe each backend in a subprocess (a failing driver cannot crash or poison this
  process), keep the first that renders, and export it as ``MUJOCO_GL``/``PYOPENGL_PLATFORM``
  before anything imports ``OpenGL``;
* import ``mujoco.egl`` / ``mujoco.osmesa`` directly, so it works even if ``mujoco`` itself was
  imported earlier without ``MUJOCO_GL``.

When no backend works the error names the Debian packages to install.
"""

from __future__ import annotations

import functools
import os
import subprocess
import sys
from typing import Any

from zrp.errors import InputError, ZRPError

__all__ = [
    "BACKENDS",
    "GLBackendError",
    "GLUnavailableError",
    "available_backend",
    "configure_backend",
    "create_context",
    "probe_backend",
    "resolve_backend",
]

#: Offscreen backends, in the order they are tried.
BACKENDS = ("egl", "osmesa")
#: Debian packages that provide each backend's system library.
PACKAGES = {"egl": "libegl1 libgl1 libegl-mesa0 libgl1-mesa-dri", "osmesa": "libosmesa6"}
_INSTALL_HINT = ("install one with `apt-get install -y libegl1 libgl1 libegl-mesa0 "
                 "libgl1-mesa-dri` (EGL; Mesa's software rasteriser when there is no GPU) or "
                 "`apt-get install -y libosmesa6` (OSMesa), or set MUJOCO_GL to a backend that "
                 "works")

_PROBE = """
import mujoco
import numpy as np
from mujoco.{mod} import GLContext
ctx = GLContext(16, 16)
ctx.make_current()
m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><geom size=".1"/></worldbody></mujoco>')
con = mujoco.MjrContext(m, mujoco.mjtFontScale.mjFONTSCALE_100.value)
mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, con)
rgb = np.zeros((16, 16, 3), np.uint8)
mujoco.mjr_readPixels(rgb, None, mujoco.MjrRect(0, 0, 16, 16), con)
con.free()
ctx.free()
print("ok")
"""


class GLBackendError(InputError):
    """An unknown offscreen backend was requested (the message lists the valid ones)."""


class GLUnavailableError(ZRPError, RuntimeError):
    """No offscreen OpenGL backend works here (the message names the packages to install)."""


def _check_name(name: str, where: str) -> str:
    key = str(name).strip().lower()
    if key not in BACKENDS:
        raise GLBackendError(f"{where}: unknown offscreen backend {name!r}; expected one of "
                             f"{BACKENDS}")
    return key


@functools.cache
def probe_backend(name: str, timeout: float = 60.0) -> tuple[bool, str]:
    """Try ``name`` in a subprocess; returns (works, last line of its error output)."""
    key = _check_name(name, "backend")
    env = dict(os.environ, MUJOCO_GL=key, PYOPENGL_PLATFORM=key)
    try:
        proc = subprocess.run([sys.executable, "-c", _PROBE.format(mod=key)], env=env,
                              capture_output=True, text=True, timeout=timeout, check=False)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return False, str(exc)
    ok = proc.returncode == 0 and proc.stdout.strip().endswith("ok")
    lines = [ln for ln in proc.stderr.strip().splitlines() if ln.strip()]
    return ok, (lines[-1] if lines else "")


def resolve_backend(requested: str | None = None) -> str:
    """The backend to use: ``requested``, else ``MUJOCO_GL``, else the first that works.

    Raises:
        GLBackendError: ``requested`` or ``MUJOCO_GL`` is not one of :data:`BACKENDS`.
        GLUnavailableError: nothing was requested and no backend works.
    """
    if requested is not None:
        return _check_name(requested, "backend")
    env = os.environ.get("MUJOCO_GL", "").strip()
    if env:
        return _check_name(env, "MUJOCO_GL environment variable")
    return available_backend()


@functools.lru_cache(maxsize=1)
def available_backend() -> str:
    """The first backend of :data:`BACKENDS` that renders here (probed in subprocesses)."""
    reasons = []
    for name in BACKENDS:
        ok, why = probe_backend(name)
        if ok:
            return name
        reasons.append(f"{name}: {why or 'failed'} (Debian: {PACKAGES[name]})")
    raise GLUnavailableError("no offscreen OpenGL backend works: " + "; ".join(reasons)
                             + f". {_INSTALL_HINT}")


def configure_backend(requested: str | None = None) -> str:
    """Resolve the backend and export ``MUJOCO_GL`` and ``PYOPENGL_PLATFORM`` for it.

    Call before the first ``import mujoco`` of the process when ``mujoco.Renderer`` (which
    reads ``MUJOCO_GL`` at import) must use the same backend; our own renderer does not need it.
    """
    name = resolve_backend(requested)
    os.environ["MUJOCO_GL"] = name
    if sys.modules.get("OpenGL") is None:
        os.environ["PYOPENGL_PLATFORM"] = name
    return name


def _context_class(name: str) -> Any:
    loaded = sys.modules.get("OpenGL") is not None
    platform = os.environ.get("PYOPENGL_PLATFORM", "").strip().lower()
    if loaded and platform and platform != name:
        raise GLBackendError(
            f"backend: {name!r} requested but PyOpenGL was already loaded for {platform!r} in "
            f"this process; use backend={platform!r} or set MUJOCO_GL={name} before starting")
    os.environ.setdefault("MUJOCO_GL", name)
    if not platform:
        os.environ["PYOPENGL_PLATFORM"] = name
    try:
        if name == "egl":
            from mujoco.egl import GLContext
        else:
            from mujoco.osmesa import GLContext
    except Exception as exc:  # ImportError, OSError, AttributeError from ctypes lookups
        raise GLUnavailableError(f"backend {name!r}: cannot load its library ({exc}); install "
                                 f"the Debian packages {PACKAGES[name]}, or {_INSTALL_HINT}"
                                 ) from exc
    return GLContext


def create_context(width: int, height: int, backend: str | None = None) -> tuple[Any, str]:
    """A current offscreen GL context of at least ``width`` x ``height`` pixels.

    Returns:
        (context, backend name); free it with ``context.free()``.
    """
    name = resolve_backend(backend)
    cls = _context_class(name)
    try:
        ctx = cls(width, height)
        ctx.make_current()
    except Exception as exc:
        raise GLUnavailableError(f"backend {name!r}: cannot create an offscreen context "
                                 f"({exc}); install the Debian packages {PACKAGES[name]}, or "
                                 f"{_INSTALL_HINT}") from exc
    return ctx, name
