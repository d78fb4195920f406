"""The paper's percentage perturbations of link vectors and joint axes, eqs (8)-(12).

A perturbation xi (in percent, -1 < xi < 1 by eq (8); xi = 0.02 means 0.02 % = 2e-4) acts on
each component i of a zero-reference vector v (a body vector b_{k,0} or an axis u_{k,0}):

    v'_i = sign(v_i) [ (xi / 100) ||v|| + |v_i| ]            eqs (10), (11)

and an axis is then normalised again, u_{k,0} = u' / ||u'|| (eq 9).

**sign(0).** The paper does not say what sign(0) is, and it matters: with sign(0) = 0 (NumPy's
``np.sign``) an axis with a single nonzero component, e.g. (0, 0, 1), becomes (0, 0, 1 + xi) and
eq (9) normalises it straight back, so every joint-axis error would be exactly zero. With
sign(0) = +1 (Fortran's ``SIGN(a, b)`` returns +|a| for b = 0) it becomes (xi, xi, 1 + xi)/norm,
a tilt of atan(sqrt(2) xi / (1 + xi)) rad. The published numbers imply sign(0) = 0 for link
vectors (LE2 = xi ||b_2|| exactly) and sign(0) = +1 for joint axes, so those are the defaults
(:data:`PAPER_SIGN_ZERO`); both are options and every result states the convention in use.

Parameters are named as in the paper: ``LE{k}`` perturbs the body vector b_{k,0} (k = 1..n+1;
``LE{n+1}`` is the end effector's, LE7 for a 6-joint arm) and ``JE{k}`` the axis u_{k,0}
(k = 1..n).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.manufacturing.choices import PAPER_SIGN_ZERO
from zrp.model.manipulator import Manipulator

__all__ = [
    "PAPER_SIGN_ZERO",
    "Perturbation",
    "SignZero",
    "check_xi_percent",
    "parameter_label",
    "parse_parameter",
    "perturb_axis",
    "perturb_components",
    "perturbation_names",
]

SignZero = Literal[-1, 0, 1]


_NAME_RX = re.compile(r"^\s*(LE|JE)\s*(\d+)\s*$", re.IGNORECASE)


def check_xi_percent(xi: float, name: str = "xi") -> float:
    """Validate a percentage perturbation against eq (8), -1 < xi < 1 (percent)."""
    try:
        val = float(xi)
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number in percent, got {xi!r}") from exc
    if not math.isfinite(val) or not -1.0 < val < 1.0:
        raise InputError(f"{name}: {val!r} % is outside -1 < xi < 1 (eq 8); xi is in percent, "
                         f"e.g. 0.02 for 0.02 %")
    return val


def _check_sign_zero(value: int, name: str) -> int:
    if isinstance(value, bool) or value not in (-1, 0, 1):
        raise InputError(f"{name}: sign(0) must be -1, 0 or +1, got {value!r}")
    return int(value)


def perturb_components(v: ArrayLike, xi_percent: ArrayLike, sign_zero: int = 0) -> F64:
    """Eqs (10)/(11): v'_i = sign(v_i) [xi/100 ||v|| + |v_i|], with sign(0) = ``sign_zero``.

    Args:
        v: vectors, shape (..., 3).
        xi_percent: perturbations in percent, shape (...) broadcastable to v[..., 0]; not
            validated here (use :func:`check_xi_percent`).
        sign_zero: the value used for sign(0): 0, +1 or -1.

    Returns:
        perturbed vectors, shape (..., 3) (not normalised).
    """
    v = np.asarray(v, dtype=float)
    xi = np.asarray(xi_percent, dtype=float)[..., None] / 100.0
    s = np.sign(v)
    s = np.where(v == 0.0, float(sign_zero), s)
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return s * (xi * norm + np.abs(v))


def perturb_axis(u: ArrayLike, xi_percent: ArrayLike, sign_zero: int = 1) -> F64:
    """Eqs (9)-(10): perturbed and renormalised unit axes, shape (..., 3)."""
    up = perturb_components(u, xi_percent, sign_zero)
    norm = np.linalg.norm(up, axis=-1, keepdims=True)
    if np.any(norm < 1e-12):
        raise InputError("xi: the perturbed axis has zero length (eq 9 cannot normalise it)")
    return up / norm


def perturbation_names(model: Manipulator) -> tuple[str, ...]:
    """All parameter names of a model: LE1..LE{n+1}, JE1..JE{n}."""
    return (*(f"LE{k}" for k in range(1, model.n + 2)),
            *(f"JE{k}" for k in range(1, model.n + 1)))


def parse_parameter(name: str, model: Manipulator) -> tuple[str, int]:
    """``"LE3"`` -> ("LE", 3), ``"je1"`` -> ("JE", 1); errors name the valid range."""
    m = _NAME_RX.match(str(name))
    valid = f"LE1..LE{model.n + 1} (link vectors b_k,0) or JE1..JE{model.n} (joint axes u_k,0)"
    if not m:
        raise InputError(f"parameter {name!r}: unknown name; expected {valid}")
    kind, k = m.group(1).upper(), int(m.group(2))
    top = model.n + 1 if kind == "LE" else model.n
    if not 1 <= k <= top:
        raise InputError(f"parameter {name!r}: index {k} out of range for {model.name!r} "
                         f"({model.n} joints); expected {valid}")
    return kind, k


def parameter_label(kind: str, k: int) -> str:
    """Inverse of :func:`parse_parameter`."""
    return f"{kind}{k}"


@dataclass(frozen=True, eq=False)
class Perturbation:
    """A set of percentage perturbations (eqs 8-12) and the sign(0) convention.

    Attributes:
        xi_percent: {name: xi in percent}, names ``LE{k}`` / ``JE{k}``; -1 < xi < 1.
        sign_zero_links: sign(0) in eq (11) (link vectors); default 0.
        sign_zero_axes: sign(0) in eq (10) (joint axes); default +1.
    """

    xi_percent: Mapping[str, float] = field(default_factory=dict)
    sign_zero_links: int = PAPER_SIGN_ZERO["links"]
    sign_zero_axes: int = PAPER_SIGN_ZERO["axes"]

    def __post_init__(self) -> None:
        if not isinstance(self.xi_percent, Mapping):
            raise InputError(f"xi_percent: expected a mapping such as {{'LE2': 0.02}}, got "
                             f"{type(self.xi_percent).__name__}")
        clean: dict[str, float] = {}
        for name, xi in self.xi_percent.items():
            m = _NAME_RX.match(str(name))
            if not m:
                raise InputError(f"parameter {name!r}: unknown name; expected LE<k> (link "
                                 f"vector b_k,0) or JE<k> (joint axis u_k,0)")
            key = f"{m.group(1).upper()}{int(m.group(2))}"
            if key in clean:
                raise InputError(f"parameter {name!r}: given twice")
            clean[key] = check_xi_percent(xi, f"xi for {key}")
        object.__setattr__(self, "xi_percent", dict(clean))
        object.__setattr__(self, "sign_zero_links",
                           _check_sign_zero(self.sign_zero_links, "sign_zero_links"))
        object.__setattr__(self, "sign_zero_axes",
                           _check_sign_zero(self.sign_zero_axes, "sign_zero_axes"))

    @classmethod
    def single(cls, name: str, xi_percent: float, *, sign_zero_links: int = 0,
               sign_zero_axes: int = 1) -> Perturbation:
        """One parameter perturbed, the others zero (the paper's one-at-a-time study)."""
        return cls({name: xi_percent}, sign_zero_links, sign_zero_axes)

    @property
    def convention(self) -> str:
        """Human-readable sign(0) convention, printed with every result."""
        return (f"sign(0) = {self.sign_zero_links:+d} for link vectors (eq 11), "
                f"{self.sign_zero_axes:+d} for joint axes (eq 10)").replace("+0", "0")

    def arrays(self, model: Manipulator) -> tuple[F64, F64]:
        """Perturbed zero-reference arrays: axes shape (n, 3), bodies shape (n + 1, 3)."""
        axes = np.array(model.axes, dtype=float)
        bodies = np.array(model.bodies, dtype=float)
        for name, xi in self.xi_percent.items():
            kind, k = parse_parameter(name, model)
            if kind == "LE":
                bodies[k - 1] = perturb_components(bodies[k - 1], xi, self.sign_zero_links)
            else:
                axes[k - 1] = perturb_axis(axes[k - 1], xi, self.sign_zero_axes)
        return axes, bodies

    def apply(self, model: Manipulator) -> Manipulator:
        """The perturbed ("actual") model; the input model is the nominal one."""
        axes, bodies = self.arrays(model)
        return model.with_arrays(axes=axes, bodies=bodies, name=f"{model.name} (perturbed)")
