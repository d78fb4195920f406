"""A held direction's name in the arm's terms (:class:`~zrp.gap.fit.wellposed.HeldDirection`
``reading``): which axis is tilted against which.

The solver names a held direction v by its largest loadings in the fit's parameters, and
those are proximal whenever the fit carries the tilts of the proximal axes but not of the
distal ones: a tilt of the wrist axis 6, which positions with one reflector barely see, is
held as "a common tilt of axes 1-5". Both describe the same change of the arm's shape,
because only relative directions change the measured positions (a rotation of the whole
arm is the base registration's). This module says so when the numbers show it:

the tilts of v (physical units: rad, the parameter t of axis k moves u_k along its tangent
t_{k,t}) are

    du_k = sum_t v_{k,t} d_{k,t} t_{k,t}                                                (H1)

and v is read as "axes K+1..n tilted against axes 1..K" when

* the tilted axes (|du_k| >= 0.1 max_k |du_k|) are at least two, the last of them K < n;
* one rotation omega of axes 1..K explains their tilts, du_k = omega x u_k, to within
  10 % (least squares over k <= K, every axis of the block, tilted or not)               (H2)
* the rotation would tilt a distal axis (|omega x u_j| >= 0.5 |omega| for some j > K), so the
  distal part really turns against the block (a distal axis parallel to omega would only
  turn about itself).

Otherwise the direction has no reading and is named by its loadings alone. The reading
speaks of the axes only (the other loadings, e.g. a link length, follow it in the
combination) and changes no number: the direction, its weights and its singular value are
the solver's.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from zrp.arrays import F64
from zrp.gap.model.context import Context, ParamSpec
from zrp.rotations import skew

__all__ = ["read_tilts", "tilt_reading"]

#: Share of the largest axis tilt from which an axis counts as tilted (H1).
TILTED = 0.1
#: Largest misfit of the common rotation, relative to the block's tilts (H2).
RIGID_RTOL = 0.1


def _axes(first: int, last: int) -> str:
    return f"axis {first}" if first == last else f"axes {first}-{last}"


def read_tilts(axes: F64, du: F64) -> str:
    """The reading of the tilts ``du`` (n, 3) of the unit ``axes`` (n, 3), or ''."""
    n = len(axes)
    size = np.linalg.norm(du, axis=1)
    if size.max() <= 0.0:
        return ""
    tilted = np.flatnonzero(size >= TILTED * size.max())
    k = int(tilted.max()) + 1  # the block is axes 1..k
    if tilted.size < 2 or k >= n:
        return ""
    A = np.vstack([-skew(u) for u in axes[:k]])  # omega x u = -[u]x omega  (H2)
    b = du[:k].ravel()
    omega = np.linalg.lstsq(A, b, rcond=None)[0]
    w = float(np.linalg.norm(omega))
    if w <= 0.0 or np.linalg.norm(A @ omega - b) > RIGID_RTOL * np.linalg.norm(b):
        return ""
    if not any(np.linalg.norm(np.cross(omega, u)) >= 0.5 * w for u in axes[k:]):
        return ""
    return (f"{_axes(k + 1, n)} tilted against {_axes(1, k)} (written as a common tilt of "
            f"{_axes(1, k)}: a rotation of the whole arm is the registration's)")


def tilt_reading(ctx: Context, specs: Sequence[ParamSpec], scales: F64
                 ) -> Callable[[F64], str]:
    """The reading of a held direction v (tolerance units, eq. W2; its first ``len(specs)``
    entries are the parameters') as a function for :func:`~zrp.gap.fit.wellposed.solve`."""
    axes = np.asarray(ctx.model.axes, dtype=float)
    axes = axes / np.linalg.norm(axes, axis=1, keepdims=True)
    tang = ctx.tangents
    tilts = [(i, s.joint - 1, s.comp) for i, s in enumerate(specs) if s.kind == "tilt"]
    d = np.asarray(scales, dtype=float)

    def reading(v: F64) -> str:
        if not tilts:
            return ""
        du = np.zeros_like(axes)
        for i, k, t in tilts:  # eq. H1
            du[k] += v[i] * d[i] * tang[k, t]
        return read_tilts(axes, du)

    return reading
