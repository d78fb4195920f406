"""Offscreen rendering of MuJoCo scenes with overlays (traces, arrows, text, a live plot).

:class:`OffscreenRenderer` owns one GL context and one ``MjrContext``; both are released
deterministically by :meth:`OffscreenRenderer.close` (or the ``with`` block), never left to the
garbage collector. ``fast=True`` (default) turns off what costs most on a CPU rasteriser and
adds nothing to these scenes: shadows, reflections, skybox and multisampling.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import mujoco
import numpy as np
from numpy.typing import ArrayLike

from sim.view.gl import create_context
from zrp.arrays import U8
from zrp.errors import InputError

__all__ = ["OffscreenRenderer"]

_EYE = np.eye(3).ravel()
_ZERO = np.zeros(3)


def _check_size(width: int, height: int, model: mujoco.MjModel) -> tuple[int, int]:
    try:
        w, h = int(width), int(height)
    except (TypeError, ValueError) as exc:
        raise InputError(f"width, height: expected integers (pixels), got {width!r}, "
                         f"{height!r}") from exc
    if w < 1 or h < 1:
        raise InputError(f"width, height: expected positive pixel counts, got {w} x {h}")
    ow, oh = model.vis.global_.offwidth, model.vis.global_.offheight
    if w > ow or h > oh:
        raise InputError(f"width, height: {w} x {h} exceeds the model's offscreen buffer "
                         f"{ow} x {oh}; build it with MJCFOptions(offscreen_size=({w}, {h}))")
    return w, h


class OffscreenRenderer:
    """Render a model offscreen; add extra arms, lines, arrows, text and figures per frame.

    Args:
        model: the main model (its scene is built by :meth:`update_scene`).
        width, height: image size, pixels.
        backend: "egl" or "osmesa"; None honours MUJOCO_GL or picks one that works.
        fast: disable shadows, reflections, skybox and multisampling.
        max_geom: capacity of the scene (arm geoms + overlay segments).
        font_scale: MuJoCo font scale in percent (50, 100, 150, ...).
    """

    def __init__(self, model: mujoco.MjModel, width: int = 640, height: int = 480, *,
                 backend: str | None = None, fast: bool = True, max_geom: int = 6000,
                 font_scale: int = 100) -> None:
        self._ctx = None
        self._con: mujoco.MjrContext | None = None
        if not isinstance(model, mujoco.MjModel):
            raise InputError(f"model: expected a mujoco.MjModel, got {type(model).__name__}")
        self.width, self.height = _check_size(width, height, model)
        self.model = model
        self._ctx, self.backend = create_context(self.width, self.height, backend)
        samples = model.vis.quality.offsamples
        try:
            if fast:
                model.vis.quality.offsamples = 0
            self._con = mujoco.MjrContext(model, int(font_scale))
            mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._con)
        except Exception:
            self.close()
            raise
        finally:
            model.vis.quality.offsamples = samples
        self.scene = mujoco.MjvScene(model, maxgeom=int(max_geom))
        self.option = mujoco.MjvOption()
        self.camera = mujoco.MjvCamera()
        mujoco.mjv_defaultFreeCamera(model, self.camera)
        self._pert = mujoco.MjvPerturb()
        if fast:
            for flag in (mujoco.mjtRndFlag.mjRND_SHADOW, mujoco.mjtRndFlag.mjRND_REFLECTION,
                         mujoco.mjtRndFlag.mjRND_SKYBOX):
                self.scene.flags[flag] = 0
        self.rect = mujoco.MjrRect(0, 0, self.width, self.height)
        self._rgb = np.empty((self.height, self.width, 3), dtype=np.uint8)

    # ---- lifetime ----------------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._con is None and self._ctx is None

    def close(self) -> None:
        """Free the MjrContext (with its GL context current), then the GL context. Idempotent."""
        if self._con is not None:
            if self._ctx is not None:
                self._ctx.make_current()
            self._con.free()
            self._con = None
        if self._ctx is not None:
            self._ctx.free()
            self._ctx = None

    def __enter__(self) -> OffscreenRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _require_open(self) -> mujoco.MjrContext:
        if self._con is None:
            raise InputError("renderer: used after close(); create a new OffscreenRenderer")
        return self._con

    # ---- scene -------------------------------------------------------------------------------
    def look_at(self, lookat: ArrayLike, distance: float, azimuth: float = 135.0,
                elevation: float = -20.0) -> None:
        """Free camera: target point (m), distance (m), azimuth and elevation (deg)."""
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self.camera.lookat[:] = np.asarray(lookat, dtype=float)
        self.camera.distance = float(distance)
        self.camera.azimuth = float(azimuth)
        self.camera.elevation = float(elevation)

    def update_scene(self, data: mujoco.MjData,
                     extra: Sequence[tuple[mujoco.MjModel, mujoco.MjData]] = (),
                     model: mujoco.MjModel | None = None) -> None:
        """Rebuild the scene from ``data`` (of ``model``, default the renderer's model), then
        add the geoms of each (model, data) in ``extra`` (e.g. a translucent "ghost" arm).

        Another ``model`` must use no textures or meshes beyond the renderer's model's (true
        of every model ``mjcf.build`` makes)."""
        self._require_open()
        mujoco.mjv_updateScene(model or self.model, data, self.option, None, self.camera,
                               mujoco.mjtCatBit.mjCAT_ALL.value, self.scene)
        for m, d in extra:
            mujoco.mjv_addGeoms(m, d, self.option, self._pert,
                                mujoco.mjtCatBit.mjCAT_DYNAMIC.value, self.scene)

    def _next_geom(self) -> mujoco.MjvGeom | None:
        if self.scene.ngeom >= self.scene.maxgeom:
            return None
        g = self.scene.geoms[self.scene.ngeom]
        self.scene.ngeom += 1
        return g

    def add_polyline(self, points: ArrayLike, rgba: ArrayLike, width: float = 2.0) -> int:
        """Add line segments through ``points`` (m, shape (M, 3)); returns segments added
        (fewer if the scene is full)."""
        pts = np.asarray(points, dtype=float)
        col = np.asarray(rgba, dtype=np.float32)
        added = 0
        for a, b in itertools.pairwise(pts):
            g = self._next_geom()
            if g is None:
                break
            mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_LINE, _ZERO, _ZERO, _EYE, col)
            mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_LINE, width, a, b)
            added += 1
        return added

    def add_arrow(self, start: ArrayLike, end: ArrayLike, rgba: ArrayLike,
                  radius: float = 0.004) -> bool:
        """Add an arrow from ``start`` to ``end`` (m), shaft radius in m."""
        g = self._next_geom()
        if g is None:
            return False
        col = np.asarray(rgba, dtype=np.float32)
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_ARROW, _ZERO, _ZERO, _EYE, col)
        mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_ARROW, radius,
                             np.asarray(start, dtype=float), np.asarray(end, dtype=float))
        return True

    def add_sphere(self, centre: ArrayLike, radius: float, rgba: ArrayLike) -> bool:
        g = self._next_geom()
        if g is None:
            return False
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_SPHERE, np.full(3, radius),
                            np.asarray(centre, dtype=float), _EYE,
                            np.asarray(rgba, dtype=np.float32))
        return True

    # ---- drawing -----------------------------------------------------------------------------
    def _current(self) -> mujoco.MjrContext:
        con = self._require_open()
        self._ctx.make_current()  # several renderers may live in one process
        return con

    def render(self) -> None:
        """Draw the scene into the offscreen buffer (overlays may be drawn after it)."""
        mujoco.mjr_render(self.rect, self.scene, self._current())

    def text(self, text: str, text2: str = "", *,
             corner: mujoco.mjtGridPos = mujoco.mjtGridPos.mjGRID_TOPLEFT,
             font: mujoco.mjtFont = mujoco.mjtFont.mjFONT_NORMAL,
             viewport: tuple[int, int, int, int] | None = None) -> None:
        """Two-column text block (``text`` left, ``text2`` right) in a corner of the frame,
        or of ``viewport`` (left, bottom, width, height in pixels)."""
        rect = self.rect if viewport is None else mujoco.MjrRect(*(int(v) for v in viewport))
        mujoco.mjr_overlay(font, corner, rect, text, text2, self._require_open())

    def figure(self, fig: mujoco.MjvFigure, left: int, bottom: int, width: int,
               height: int) -> None:
        """Draw a :class:`mujoco.MjvFigure` in a viewport (pixels from the bottom left)."""
        mujoco.mjr_figure(mujoco.MjrRect(left, bottom, width, height), fig,
                          self._require_open())

    def read(self, flip: bool = True) -> U8:
        """The RGB image, shape (height, width, 3), top row first (a fresh array)."""
        mujoco.mjr_readPixels(self._rgb, None, self.rect, self._current())
        return np.flipud(self._rgb).copy() if flip else self._rgb.copy()

    def render_image(self, data: mujoco.MjData,
                     extra: Sequence[tuple[mujoco.MjModel, mujoco.MjData]] = ()) -> U8:
        """update_scene + render + read, shape (height, width, 3)."""
        self.update_scene(data, extra)
        self.render()
        return self.read()
