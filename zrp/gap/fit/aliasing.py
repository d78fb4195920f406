"""Which parameters the data can tell apart: the tolerances of structural aliasing and weak
identifiability, the :class:`Aliased` record, and the in-order :class:`Acceptance` of the
candidates that :func:`zrp.gap.fit.leastsq.identifiable_start` projects off the base (a
Gram-Schmidt on normalised Jacobian columns)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.gap.model.context import ParamSpec
from zrp.jsonio import dict_from_dataclass

__all__ = ["ALIAS_TOL", "WEAK_TOL", "Acceptance", "Aliased"]

#: A parameter whose Jacobian column keeps less than this fraction of its norm after
#: projection on the other columns cannot be told apart from them (structural aliasing).
ALIAS_TOL = 1e-6
#: Below this fraction it is identifiable only weakly (reported, kept).
WEAK_TOL = 1e-2


@dataclass(frozen=True)
class Aliased:
    """A parameter that the data cannot tell apart from others.

    Attributes:
        name: the parameter.
        effect: its effect.
        partners: the parameters it trades against (largest share first).
        fraction: share of its Jacobian column outside the span of the others (0: identical).
        dropped: True when it was left out of the fit (structural), False when only weak.
    """

    name: str
    effect: str
    partners: tuple[str, ...]
    fraction: float
    dropped: bool

    def to_dict(self) -> dict[str, Any]:
        return dict_from_dataclass(self)


class Acceptance:
    """The in-order acceptance of :func:`identifiable_start`: a candidate is projected off
    the base and the candidates accepted before it; below ``ALIAS_TOL`` of its norm it is
    dropped (aliased), below ``WEAK_TOL`` kept and reported as weak. A weak candidate is
    considered only after every clearly identifiable one (two passes), so that a gauge
    direction blurred by a rounded model value (a URDF's rpy 1.5708 for pi/2 leaves a few
    1e-6 of a translation along an axis) is the one dropped against a real parameter, not the
    real parameter against it."""

    def __init__(self, Jt: F64, norms: F64, nb: int, names: list[str], P: F64) -> None:
        self.Jt, self.norms, self.nb, self.names, self.P = Jt, norms, nb, names, P
        self.Qa = np.empty((Jt.shape[0], P.shape[1]))
        self.na = 0
        self.keep: list[ParamSpec] = []
        self.keep_index: list[int] = []
        self.report: list[Aliased] = []
        self.index_of: dict[str, int] = {}

    def consider(self, i: int, spec: ParamSpec, defer_weak: bool) -> bool:
        """Accept or drop candidate i; False when it is weak and ``defer_weak``."""
        self.index_of[spec.name] = i
        nb, norms = self.nb, self.norms
        if norms[nb + i] <= 1e-12 * max(norms.max(), 1.0):
            self.report.append(Aliased(spec.name, spec.effect, (), 0.0, True))
            return True
        rr = self.P[:, i]
        if self.na:
            qa = self.Qa[:, :self.na]
            rr = rr - qa @ (qa.T @ rr)
            rr = rr - qa @ (qa.T @ rr)
        frac = float(np.linalg.norm(rr))
        if frac < WEAK_TOL:
            if defer_weak and frac >= ALIAS_TOL:
                return False
            self.report.append(Aliased(spec.name, spec.effect, self._partners(i), frac,
                                       frac < ALIAS_TOL))
            if frac < ALIAS_TOL:
                return True
        self.keep.append(spec)
        self.keep_index.append(i)
        self.Qa[:, self.na] = rr / frac
        self.na += 1
        return True

    def _partners(self, i: int) -> tuple[str, ...]:
        """The accepted parameters most like candidate i (cosines between normalised
        columns, at least half the largest, three at most)."""
        cols = list(range(self.nb)) + [self.nb + j for j in self.keep_index]
        acc = self.Jt[:, cols] / np.where(self.norms[cols] > 0, self.norms[cols], 1.0)
        c = self.Jt[:, self.nb + i] / self.norms[self.nb + i]
        corr = np.abs(acc.T @ c)
        order = np.argsort(-corr)
        return tuple(self.names[cols[o]] for o in order[:3] if corr[o] >= 0.5 * corr.max())
