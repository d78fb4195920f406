"""Drawing deviations larger than life: the arm with its parameter errors multiplied
(:func:`exaggerated_model`) and a round magnification factor (:func:`nice_factor`)."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.model.manipulator import Manipulator

__all__ = ["exaggerated_model", "nice_factor"]



def exaggerated_model(nominal: Manipulator, perturbed: Manipulator, factor: float
                      ) -> Manipulator:
    """The perturbed model with its parameter errors multiplied by ``factor`` (for drawing).

    b_k = b_k,nom + F (b_k,pert - b_k,nom); axes u_k = normalise(u_k,nom + F (u_k,pert -
    u_k,nom)); the hand vectors likewise, u_t re-orthogonalised to u_a. To first order in the
    errors the tool point moves F times as far from the nominal one as the perturbed arm's.
    """
    f = float(factor)

    def mix(a: ArrayLike, b: ArrayLike) -> F64:
        return np.asarray(a, dtype=float) + f * (np.asarray(b, dtype=float) - np.asarray(a))

    axes = mix(nominal.axes, perturbed.axes)
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    ua = mix(nominal.end_effector.axial, perturbed.end_effector.axial)
    ua /= np.linalg.norm(ua)
    ut = mix(nominal.end_effector.transverse, perturbed.end_effector.transverse)
    ut -= (ut @ ua) * ua
    ut /= np.linalg.norm(ut)
    return perturbed.with_arrays(axes=axes, bodies=mix(nominal.bodies, perturbed.bodies),
                                 axial=ua, transverse=ut,
                                 name=f"{perturbed.name} (errors x{f:g})")


def nice_factor(x: float) -> float:
    """Largest 1, 2 or 5 times a power of ten not above ``x`` (x > 0); 1 for x <= 0."""
    if not (x > 0 and math.isfinite(x)):
        return 1.0
    e = math.floor(math.log10(x))
    for m in (5.0, 2.0, 1.0):
        if m * 10**e <= x:
            return m * 10**e
    return 10.0**e
