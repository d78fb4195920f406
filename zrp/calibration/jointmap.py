"""The non-geometric part of a calibrated robot: the joint map q_actual = q + dq(q, ...).

Every non-geometric parameter of the gap diagnosis is a joint correction theta B(pose) with a
basis B that depends on the commanded joint values and the pose's conditions
(:mod:`zrp.gap.effects`). A calibrated robot keeps the parameter values (:class:`Term`) and
re-evaluates the bases on new poses with the diagnosis's own :class:`zrp.gap.Context`, so the
correction of a fresh target is computed exactly as the diagnosis computed it on the
measured poses:

==========================  =============================================================
term (``q{k}.``)            basis for joint k (per pose)
==========================  =============================================================
``offset`` (prismatic)      1 (revolute offsets are folded into the geometry)
``scale``                   q_k (encoder scale: q_actual = q (1 + s))
``sin{h}``, ``cos{h}``      sin(h q_k), cos(h q_k) (cyclic error)
``compliance``              gravity torque tau_k (MJCF) + g load h_ee (N m)
``compliance_payload``      g h_ee (moment arm of the tool, m) (unknown payload)
``w_{p}``, ``w_load``       lumped-mass moment arms (length unit), load x h_ee
``backlash``                -approach direction, or sign(tau_k) above the switching torque
==========================  =============================================================
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.errors import InputError
from zrp.gap.effects import Context
from zrp.units import G_STANDARD, metres_per_unit

__all__ = ["NON_GEOMETRIC", "Term", "term_basis"]

F64 = NDArray[np.float64]

#: effects whose parameters are joint corrections with a pose-dependent basis.
NON_GEOMETRIC = ("joint_offset", "encoder_scale", "joint_compliance", "backlash",
                 "cyclic_error")


@dataclass(frozen=True)
class Term:
    """One joint-correction parameter of the calibrated robot.

    Attributes:
        name: the diagnosis's parameter name, ``q{k}.{what}`` (e.g. ``q2.compliance``).
        effect: the effect it belongs to (one of :data:`NON_GEOMETRIC`).
        joint: 1-based joint.
        unit: the parameter's unit (e.g. ``rad/(N m)``).
        value: the identified value.
        stderr: its standard error (0 when unknown).
    """

    name: str
    effect: str
    joint: int
    unit: str
    value: float
    stderr: float = 0.0

    def __post_init__(self) -> None:
        if self.effect not in NON_GEOMETRIC:
            raise InputError(f"Term {self.name}: effect {self.effect!r} is not one of "
                             f"{NON_GEOMETRIC}")
        if not self.name.startswith(f"q{self.joint}."):
            raise InputError(f"Term {self.name}: name must start with 'q{self.joint}.'")
        if not np.isfinite(self.value):
            raise InputError(f"Term {self.name}: value {self.value} is not finite")

    @property
    def what(self) -> str:
        """The part after ``q{k}.`` (``scale``, ``sin1``, ``w_p3``...)."""
        return self.name.split(".", 1)[1]

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "effect": self.effect, "joint": self.joint,
                "unit": self.unit, "value": self.value, "stderr": self.stderr}

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str) -> Term:
        try:
            return cls(str(d["name"]), str(d["effect"]), int(d["joint"]), str(d["unit"]),
                       float(d["value"]), float(d.get("stderr", 0.0)))
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"{where}: a term needs name, effect, joint, unit, value "
                             f"({exc})") from exc


def _harmonic(what: str) -> tuple[str, int] | None:
    for fn in ("sin", "cos"):
        if what.startswith(fn) and what[3:].isdigit():
            return fn, int(what[3:])
    return None


def _lumped(ctx: Context, k: int, label: str) -> F64:
    labels, h = ctx.moment_arms()
    h = np.where(np.abs(h) > 1e-9 * ctx.model.characteristic_length, h, 0.0)
    if label not in labels:
        raise InputError(f"term q{k + 1}.w_{label}: no lumped mass point {label!r}; the model "
                         f"has {labels}")
    return h[:, k, labels.index(label)]


def _compliance(ctx: Context, k: int, what: str) -> F64:
    """Bases of the ``joint_compliance`` terms (as :mod:`zrp.gap.effects` builds them)."""
    load = ctx.meas.per_pose("load")
    to_m = metres_per_unit(ctx.model.length_unit, "model.length_unit")
    h_ee = ctx.end_effector_arms()[:, k]
    if what == "compliance":
        if ctx.gravity_torque is None:
            raise InputError(f"q{k + 1}.compliance: needs the gravity torque of every pose "
                             "(gravity_torque=, from mjcf.gravity.gravity_torques)")
        tau = np.array(ctx.gravity_torque[:, k], dtype=float)
        return tau if load is None else tau + G_STANDARD * load * h_ee * to_m
    if what == "compliance_payload":
        return G_STANDARD * h_ee * to_m
    if what == "w_load":
        return np.zeros(len(h_ee)) if load is None else load * h_ee
    return _lumped(ctx, k, what[2:])


def term_basis(term: Term, ctx: Context) -> F64:
    """The basis of ``term`` on the poses of ``ctx``, shape (P,) (joint ``term.joint``).

    Raises:
        InputError: a term this library does not know, or missing pose conditions.
    """
    k = term.joint - 1
    q = ctx.q[:, k]
    what = term.what
    harm = _harmonic(what)
    if what == "offset":
        return np.ones(len(q))
    if what == "scale":
        return np.array(q, dtype=float)
    if harm is not None:
        fn, h = harm
        return np.sin(h * q) if fn == "sin" else np.cos(h * q)
    if what == "backlash":
        # the parameter is the full play: each flank is half of it away (zrp.gap.effects)
        return 0.5 * np.array(ctx.backlash_basis()[:, k], dtype=float)
    if term.effect == "joint_compliance":
        return _compliance(ctx, k, what)
    raise InputError(f"term {term.name}: unknown joint-correction term")


def joint_correction(terms: tuple[Term, ...], ctx: Context) -> F64:
    """dq = sum_t value_t B_t per pose and joint, shape (P, n) (model joint units)."""
    dq = np.zeros(ctx.q.shape)
    for t in terms:
        dq[:, t.joint - 1] += t.value * term_basis(t, ctx)
    return dq
