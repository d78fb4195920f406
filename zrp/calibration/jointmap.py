"""The non-geometric part of a calibrated robot: the joint map q_actual = q + dq(q, ...).

Every non-geometric parameter of the gap diagnosis is a joint correction theta B(pose) with a
basis B that depends on the commanded joint values and the pose's conditions
(:mod:`zrp.gap.model.jointbases`). A calibrated robot keeps the parameter values (:class:`Term`)
and re-evaluates the bases on new poses with the diagnosis's own :class:`zrp.gap.Context` and
the diagnosis's own definition of each basis (:func:`zrp.gap.model.jointbases.joint_bases`, the
table there), so the correction of a fresh target is computed exactly as the diagnosis
computed it on the measured poses, and a change of a basis there changes both alike
(revolute offsets are folded into the geometry; ``offset`` terms are prismatic joints').
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.model.context import Context
from zrp.gap.model.jointbases import JOINT_EFFECTS, joint_bases
from zrp.jsonio import dict_from_dataclass

__all__ = ["NON_GEOMETRIC", "Term", "term_basis"]


#: effects whose parameters are joint corrections with a pose-dependent basis.
NON_GEOMETRIC = JOINT_EFFECTS


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
        return dict_from_dataclass(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any], where: str) -> Term:
        try:
            return cls(str(d["name"]), str(d["effect"]), int(d["joint"]), str(d["unit"]),
                       float(d["value"]), float(d.get("stderr", 0.0)))
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"{where}: a term needs name, effect, joint, unit, value "
                             f"({exc})") from exc


def term_basis(term: Term, ctx: Context) -> F64:
    """The basis of ``term`` on the poses of ``ctx``, shape (P,) (joint ``term.joint``): the
    diagnosis's own definition (:func:`zrp.gap.model.jointbases.joint_bases`).

    Raises:
        InputError: a term this library does not know, or missing pose conditions.
    """
    if term.effect == "joint_compliance" and term.what.startswith("compliance") and \
            ctx.gravity_torque is None:
        raise InputError(f"{term.name}: needs the gravity torque of every pose "
                         "(gravity_torque=, from mjcf.gravity.gravity_torques)")
    bases = joint_bases(ctx, term.effect)
    if term.what not in bases:
        raise InputError(f"term {term.name}: unknown joint-correction term of "
                         f"{term.effect} (known: {', '.join(bases)})")
    return np.array(bases[term.what][:, term.joint - 1], dtype=float)


def joint_correction(terms: tuple[Term, ...], ctx: Context) -> F64:
    """dq = sum_t value_t B_t per pose and joint, shape (P, n) (model joint units)."""
    dq = np.zeros(ctx.q.shape)
    for t in terms:
        dq[:, t.joint - 1] += t.value * term_basis(t, ctx)
    return dq
