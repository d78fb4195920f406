"""The standard complete geometric calibration, always fitted beside the chosen effects.

A calibration engineer's reference: all kinematic parameters (joint offsets, body vectors,
axis tilts: :data:`KINEMATIC`) on top of the registration, reduced to a base set that these
poses identify (column-pivoted Gram-Schmidt on the normalised Jacobian, :func:`~zrp.gap.fit.leastsq.
check_identifiable`: a QR reduction), fitted on the fitting poses and judged on the withheld
ones. Then the non-geometric effects of the search's model are added on top of it, which
answers the question "what do the non-geometric effects add beyond a full geometric
calibration, on withheld poses?" (and gives the third candidate for the final model,
:mod:`zrp.gap.analysis.fallback`). When the measurements carry orientations (and they are
used), every fit here identifies the parameters from positions and orientations together,
each weighted by its noise (``Context.orientation``, :func:`zrp.gap.fit.leastsq.fit`): a
direction that positions alone cannot pin (a common tilt of parallel axes) is then
estimated, not held at its nominal.

Two baselines, named honestly (issue 34). The reference every comparison is made against
("what the non-geometric effects add") is the plain complete geometric calibration: the
unconstrained least-squares fit of the base set, what a calibration engineer (or FIGAROH)
computes. The model the diagnosis may use as its final model is the physically held one:
the same fit with the parameters whose values leave their physical domains
(:mod:`zrp.gap.model.domains`, e.g. an axis tilt beyond ``max_tilt_rad``) taken out and the
rest refitted (:func:`~zrp.gap.fit.constrained.within_domains`), so that no impossible value
reaches an output file. When no parameter leaves its domain the two are the same fit; when
they differ, both withheld errors are reported, with the parameters that left their domain.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.fit.constrained import n_registration, within_domains
from zrp.gap.fit.leastsq import FitResult, cv_rms, fit, identifiable_start
from zrp.gap.fit.metrics import Metrics
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.effects import effect_parameters
from zrp.gap.model.problem import Problem

__all__ = ["KINEMATIC", "GeometricBaseline", "geometric_baseline", "geometric_specs"]

#: The effects of a standard complete kinematic calibration (an encoder scale is a drive
#: property and counts as non-geometric here).
KINEMATIC = ("joint_offset", "link_length", "axis_misalignment")


@dataclass(frozen=True)
class GeometricBaseline:
    """The complete geometric calibration and what the non-geometric effects add to it.

    Attributes:
        n_parameters: base-set size (identifiable geometric parameters, registration excluded).
        n_dropped: geometric parameters the reduction dropped (aliased).
        withheld: withheld errors of the plain (unconstrained) geometric calibration: the
            reference.
        cv_rms: its cross-validated RMS on the fitting poses.
        non_geometric: the non-geometric effects of the search's model added on top (empty:
            none).
        n_non_geometric: their parameters identifiable on top of the base set.
        combined: withheld errors of geometric + non-geometric (held in the physical
            domains), or None when the search's model has no non-geometric effect.
        held: withheld errors of the physically held geometric calibration, or None when
            it is the plain one (no parameter left its domain).
        outside: the plain fit's parameters outside their physical domains, in words
            ("name = value outside ..."; empty when ``held`` is None).
        fit: the physically held geometric calibration's fit (registration + base set; the
            final model when the search's model does not beat it on the withheld poses, see
            :mod:`zrp.gap.analysis.fallback`).
        combined_fit: the fit of geometric + non-geometric (None with ``combined``; the final
            model when it clearly beats both others on the withheld poses, same module).
        combined_outside: that fit's parameters taken out or held (lumped weights at sum 0)
            by the physical domains, in words.
    """

    n_parameters: int
    n_dropped: int
    withheld: Metrics
    cv_rms: float
    non_geometric: tuple[str, ...]
    n_non_geometric: int
    combined: Metrics | None
    held: Metrics | None = None
    outside: tuple[str, ...] = ()
    fit: FitResult | None = field(default=None, compare=False, repr=False)
    combined_fit: FitResult | None = field(default=None, compare=False, repr=False)
    combined_outside: tuple[str, ...] = ()

    @property
    def model_withheld(self) -> Metrics:
        """Withheld errors of the geometric calibration that may be a final model (``fit``):
        the physically held one."""
        return self.withheld if self.held is None else self.held

    @property
    def increment(self) -> float | None:
        """Share by which the non-geometric effects lower the plain baseline's withheld RMS
        (negative when they make it worse), or None."""
        if self.combined is None or self.withheld.rms <= 0:
            return None
        return 1.0 - self.combined.rms / self.withheld.rms

    def to_dict(self) -> dict[str, Any]:
        return {"n_parameters": self.n_parameters, "n_dropped": self.n_dropped,
                "withheld": self.withheld.to_dict(), "rms": self.withheld.rms,
                "cv_rms": self.cv_rms, "non_geometric": list(self.non_geometric),
                "n_non_geometric": self.n_non_geometric,
                "combined": None if self.combined is None else self.combined.to_dict(),
                "increment": self.increment, "reference": "plain",
                "physically_held": None if self.held is None else {
                    "withheld": self.held.to_dict(), "rms": self.held.rms,
                    "outside_domains": list(self.outside)}}


def _withheld(ctx: Context, f: FitResult, withheld: NDArray[np.int64]) -> Metrics:
    return Metrics.of(Problem(ctx, f.specs, withheld, f.base_rotation).residual(f.theta))


def _on_top(ctx: Context, base: FitResult, extra: list[ParamSpec], fitting: NDArray[np.int64],
            rb0: F64) -> tuple[FitResult, FitResult, tuple[str, ...], int, int]:
    """``extra`` fitted on top of ``base``: the plain fit, the fit held in the physical
    domains (the same object when nothing left them), the reasons, the number kept and
    dropped."""
    keep, _, start = identifiable_start(ctx, base, extra)
    plain = fit(ctx, list(base.specs) + keep, fitting,
                np.concatenate([base.theta, np.zeros(len(keep))]), rb0, start=start)
    held, outside = within_domains(ctx, plain, n_registration(plain.specs), fitting, rb0)
    return plain, held, outside, len(keep), len(extra) - len(keep)


def geometric_specs(ctx: Context, reg: FitResult) -> list[ParamSpec]:
    """The geometric parameters (:data:`KINEMATIC`) identifiable on top of ``reg`` with its
    poses (the base set the baseline fits)."""
    geo: list[ParamSpec] = []
    for e in KINEMATIC:
        geo += effect_parameters(ctx, e)[0]
    return identifiable_start(ctx, reg, geo)[0]


def geometric_baseline(ctx: Context, reg: FitResult, final: FitResult,
                       fitting: NDArray[np.int64], withheld: NDArray[np.int64],
                       folds: list[NDArray[np.int64]], rb0: F64
                       ) -> GeometricBaseline:
    """Fit the complete geometric calibration on top of the registration ``reg`` and then the
    non-geometric parameters of ``final`` (the search's model) on top of it (see the module
    docstring). With ``ctx.orientation`` the fits use the measured orientations too
    (:func:`zrp.gap.fit.leastsq.fit`); the withheld errors are the positions'."""
    geo: list[ParamSpec] = []
    for e in KINEMATIC:
        geo += effect_parameters(ctx, e)[0]
    plain, base, outside, n_geo, n_drop = _on_top(ctx, reg, geo, fitting, rb0)
    nreg = len(reg.specs)
    non_geo = [s for s in final.specs[nreg:] if s.effect not in KINEMATIC]
    effects = tuple(dict.fromkeys(s.effect for s in non_geo))
    combined, n_ng, both, both_out = None, 0, None, ()
    if non_geo:
        _, both, both_out, n_ng, _ = _on_top(ctx, base, non_geo, fitting, rb0)
        combined = _withheld(ctx, both, withheld)
    held = None if base is plain else _withheld(ctx, base, withheld)
    return GeometricBaseline(n_geo, n_drop, _withheld(ctx, plain, withheld),
                             cv_rms(ctx, plain, folds), effects, n_ng, combined, held,
                             outside if held is not None else (), base, both, both_out)
