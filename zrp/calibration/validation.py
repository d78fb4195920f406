"""The last gate before a calibration file or an export: every value within its physical domain.

:func:`validate_calibration` is called by every writer (:func:`zrp.calibration.write_calibration`,
the exports of :mod:`zrp.calibration.export`) and by the reader. It checks, against the one
domain table :mod:`zrp.gap.model.domains`: each joint-map term (backlash, compliance, encoder
scale), each cyclic harmonic's amplitude sqrt(sin^2 + cos^2), thermal expansion kappa, and each
axis's total tilt from its nominal (the folded axes unfolded exactly, see below), plus that
every number is finite. A value outside is an :class:`ImplausibleValueError` naming the
parameter, its value and its domain.

Tilt: the folded axes are u'_k = R_{k-1}(delta) u_k (zrp.calibration.calibrated), so the
identified axes are u_k = R_{k-1}(delta)^T u'_k, R_k(delta) = R_{k-1}(delta) Rot(u_k, delta_k)
(revolute joints), and the tilt is the angle between u_k and the nominal axis.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from zrp.arrays import F64
from zrp.calibration.calibrated import CalibratedRobot
from zrp.calibration.jointmap import Term
from zrp.gap.model.domains import (
    DOMAINS,
    ImplausibleValueError,
    domain_key,
    sum_inside,
    violation,
)

__all__ = ["axis_tilts", "implausible_values", "validate_calibration"]


def axis_tilts(cal: CalibratedRobot) -> F64:
    """Angle (rad) between each identified axis and the nominal one, shape (n,)."""
    rots = cal.fold_rotations()
    out = np.empty(cal.n)
    for k in range(cal.n):
        r = np.eye(3) if k == 0 else rots[k - 1]
        u = r.T @ np.asarray(cal.model.axes[k])
        u0 = np.asarray(cal.nominal.axes[k])
        out[k] = float(np.arctan2(np.linalg.norm(np.cross(u, u0)), float(u @ u0)))
    return out


def _term_problems(cal: CalibratedRobot, widen: Mapping[str, float] | None) -> list[str]:
    out = []
    cyclic: dict[tuple[int, str], float] = {}
    lumped: dict[int, list[Term]] = {}
    for t in cal.terms:
        key = domain_key(t.name, t.effect)
        if key == "lumped_compliance":
            lumped.setdefault(t.joint, []).append(t)
        elif key == "cyclic_amplitude":
            h = t.what[3:]
            cyclic[(t.joint, h)] = cyclic.get((t.joint, h), 0.0) + t.value ** 2
        elif key is not None:
            msg = violation(key, t.name, t.value, t.unit, widen)
            if msg:
                out.append(msg)
    for k, terms in sorted(lumped.items()):
        if sum_inside([t.value for t in terms]):  # held at 0: within one rounding of it
            continue
        msg = violation("lumped_compliance", " + ".join(t.name for t in terms)
                        + f" (the sum of joint {k}'s lumped weights)",
                        math.fsum(t.value for t in terms), terms[0].unit, widen)
        if msg:
            out.append(msg)
    for (k, h), a2 in sorted(cyclic.items()):
        msg = violation("cyclic_amplitude", f"q{k}.amplitude{h} (sqrt(sin{h}^2 + cos{h}^2))",
                        float(np.sqrt(a2)), "rad", widen)
        if msg:
            out.append(msg)
    return out


def implausible_values(cal: CalibratedRobot, widen: Mapping[str, float] | None = None
                       ) -> list[str]:
    """Every value of ``cal`` outside its physical domain, one message each (empty: none).
    ``widen``: domain key -> a larger upper bound (:data:`zrp.gap.model.domains.DOMAINS`)."""
    unknown = sorted(set(widen or ()) - set(DOMAINS))
    if unknown:
        raise ImplausibleValueError(f"widen: unknown domains {unknown}; known: "
                                    f"{sorted(DOMAINS)}")
    out = _term_problems(cal, widen)
    msg = violation("thermal_expansion", "kappa", cal.kappa, "1/degC", widen)
    if msg:
        out.append(msg)
    for k, tilt in enumerate(axis_tilts(cal), start=1):
        msg = violation("axis_tilt", f"u{k}.tilt (joint {k} axis from its nominal)",
                        float(tilt), "rad", widen)
        if msg:
            out.append(msg)
    for name, arr in (("base_rotation", cal.base_rotation),
                      ("base_translation", cal.base_translation),
                      ("tool_points", cal.tool_points), ("joint_offsets", cal.joint_offsets),
                      ("model bodies", cal.model.bodies)):
        if not np.all(np.isfinite(np.asarray(arr, dtype=float))):
            out.append(f"{name}: not every value is finite")
    return out


def validate_calibration(cal: CalibratedRobot, widen: Mapping[str, float] | None = None,
                         where: str = "calibration") -> None:
    """Refuse a calibration with a value outside its physical domain.

    Raises:
        ImplausibleValueError: naming every such parameter, its value and its domain.
    """
    bad = implausible_values(cal, widen)
    if bad:
        raise ImplausibleValueError(
            f"{where}: {len(bad)} value(s) outside their physical domain, refused (nothing "
            "implausible is written or used): " + "; ".join(bad)
            + ". Rerun the diagnosis without that effect; an upper bound can be raised, "
            "widen= (--widen on the command line), only for an arm known to need it")
