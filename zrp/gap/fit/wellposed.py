"""Well-posed identification: a scaled Gauss-Newton solver with a prior on the manufacturing
tolerances that leaves at their nominal values the parameter combinations the data cannot pin.

Each parameter is scaled by its manufacturing tolerance d_j (:func:`zrp.gap.model.domains.
tolerance`; the registration, which has none, by 1 rad (rotation) and the arm's length
(translations, tool points), so that it is practically free; the compliances by the value that
moves the tool by 1 mm RMS): x = D^-1 (theta - theta_nom), so one
unit of x is one typical error (column scaling; Hollerbach & Wampler 1996, Schroer et al. 1997).
Linearised at the current theta, with the SVD of the scaled Jacobian J D = U S V^T, the
combination c_i = v_i^T x of the parameters is estimated from the data with the standard error

    se(c_i) = sigma / s_i                                                             (W1)

(sigma: the residual standard deviation per coordinate, of the full linearised fit: the noise
the estimate actually sees, measurement noise plus what the model leaves). Where se(c_i) > 1
the data know c_i less well than the tolerance already does. Such a combination is held at
its nominal value (truncated SVD, Hansen 1987):

    held:  s_i <= tau,   tau = max(sigma, 1e-10 s_1)                                   (W2)

and the others are estimated with the prior x ~ N(0, I) on the tolerances (the MAP estimate;
Tikhonov 1963; the Bayesian reading: Tarantola 2005, ch. 3), whose Gauss-Newton step from x
in the SVD basis (c = V^T x, b = U^T r) is, per direction,

    e_i = -(s_i b_i + sigma^2 c_i) / (s_i^2 + sigma^2)   (kept),    e_i = -c_i   (held),
    dx = V e                                                                           (W4)

(the linear problem's MAP solution filters each direction by s_i^2 / (s_i^2 + sigma^2), which
passes more than half exactly when s_i > sigma: the hard hold of W2 is where the prior
dominates). The objective |r|^2 + sigma^2 |x|^2 is lowered by backtracking (Armijo) from the
linearised solution; the iteration stops when the predicted decrease is below 1e-14 of it or the
step below 1e-10 tolerances. The threshold is fixed after :data:`FREEZE_AFTER` iterations (the
held set cannot flip). An iteration limit, when reached, is reported (``converged`` False with
the reason), never only warned.

The covariance is that of the estimate on the kept directions plus the prior's on the held
ones:

    C = D (V_k S_k^-2 V_k^T sigma^2 + V_h V_h^T) D                                    (W3)

(a held combination is known to within its tolerance, no better).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.domains import tolerance
from zrp.gap.model.problem import compressed
from zrp.jsonio import dict_from_dataclass
from zrp.units import units_per_mm

__all__ = ["MAX_ITERATIONS", "HeldDirection", "Solution", "parameter_scales", "prior_values",
           "rank_chi2", "solve"]

#: Gauss-Newton iterations before the solver stops and says so.
MAX_ITERATIONS = 200
#: Singular values below this fraction of the largest are exactly null (numerical rank).
RANK_RTOL = 1e-10
#: From this iteration on the threshold tau stays fixed (the held set cannot flip).
FREEZE_AFTER = 5


@dataclass(frozen=True)
class HeldDirection:
    """A combination of parameters that the data cannot pin, left at its nominal value.

    Attributes:
        parameters: the parameters that make it up (largest weight first).
        weights: their weights in tolerance units (the direction v_i of eq. W2, unit norm;
            the parameters whose |weight| >= 0.1 are listed).
        singular_value: s_i of the tolerance-scaled Jacobian (length unit: the residual norm
            that one tolerance along the direction changes).
        threshold: the noise it fell below (sigma per coordinate, length unit).
        exact: True when it is (numerically) not seen at all (a gauge or structural alias).
        reading: the same direction in the arm's terms, e.g. "axis 6 tilted against axes
            1-5" for a common tilt of axes 1-5 (:mod:`zrp.gap.fit.heldname`); "" when the
            loadings are its only name.
    """

    parameters: tuple[str, ...]
    weights: tuple[float, ...]
    singular_value: float
    threshold: float
    exact: bool
    reading: str = ""

    @property
    def combination(self) -> str:
        """The combination in words, e.g. ``0.71 u2.t1 + 0.70 u3.t1``."""
        out = ""
        for i, (n, w) in enumerate(zip(self.parameters, self.weights, strict=True)):
            sign = "-" if w < 0 else ("+" if i else "")
            out += f"{' ' if i else ''}{sign}{' ' if i else ''}{abs(w):.2f} {n}"
        return out

    @property
    def label(self) -> str:
        """The name a reader sees: the reading (when there is one), then the combination."""
        return f"{self.reading}: {self.combination}" if self.reading else self.combination

    def describe(self, unit: str) -> str:
        """One line: the direction (:attr:`label`) and why it was held."""
        why = ("not seen by these data at all" if self.exact else
               f"singular value {self.singular_value:.3g} {unit} per tolerance <= the noise "
               f"{self.threshold:.3g} {unit}: the data pin it less well than the tolerance")
        return f"{self.label} ({why})"

    def to_dict(self) -> dict[str, Any]:
        return {**dict_from_dataclass(self), "combination": self.combination}


@dataclass(frozen=True, eq=False)
class Solution:
    """What :func:`solve` returns.

    Attributes:
        theta: the solution, shape (p,).
        residual, jac: at the solution.
        cov: covariance (eq. W3), shape (p, p).
        held: the held directions at the solution.
        held_cov: the held directions' share of ``cov`` (the second term of eq. W3: their
            prior's), shape (p, p); zero when none is held.
        converged: the stop test was met (False: ``reason`` says why not).
        iterations: Gauss-Newton iterations.
        reason: why the solver stopped, in words.
    """

    theta: F64
    residual: F64
    jac: F64
    cov: F64
    held: tuple[HeldDirection, ...]
    converged: bool
    iterations: int
    reason: str
    held_cov: F64 | None = None


def parameter_scales(ctx: Context, specs: Sequence[ParamSpec], jac: F64) -> F64:
    """d_j of the module docstring, shape (p,): the tolerance of each parameter; for the
    registration and parameters without one, the value that moves the tool by 1 mm RMS
    (the base rotation: 1 rad, the translations and tool points: the arm's length)."""
    n_pts = max(jac.shape[0] // 3, 1)
    mm = units_per_mm(ctx.model.length_unit)
    out = np.empty(len(specs))
    for j, s in enumerate(specs):
        tol = tolerance(s.name, s.effect, s.unit)
        if s.kind == "rot":
            tol = 1.0
        elif s.kind in ("trans", "tool"):
            tol = ctx.model.characteristic_length
        if tol is None:
            col = float(np.linalg.norm(jac[:, j])) / math.sqrt(n_pts)
            tol = mm / col if col > 0 else 1.0
        out[j] = tol
    return out


def prior_values(specs: Sequence[ParamSpec], theta0: F64) -> F64:
    """The nominal values the held directions keep: the starting registration, 0 for every
    effect parameter (the nominal model)."""
    reg = np.array([s.kind in ("rot", "trans", "tool") for s in specs])
    return np.where(reg, theta0, 0.0)


def _held(vt: F64, s: F64, keep: NDArray[np.bool_], names: Sequence[str], tau: float,
          exact_tol: float, reading: Callable[[F64], str] | None = None
          ) -> tuple[HeldDirection, ...]:
    out = []
    for i in np.flatnonzero(~keep):
        v = vt[i] * (1.0 if vt[i][np.argmax(np.abs(vt[i]))] > 0 else -1.0)
        order = [j for j in np.argsort(-np.abs(v)) if abs(v[j]) >= 0.1][:6]
        out.append(HeldDirection(tuple(names[j] for j in order),
                                 tuple(float(v[j]) for j in order), float(s[i]), float(tau),
                                 bool(s[i] <= exact_tol), reading(v) if reading else ""))
    return tuple(out)


def _decompose(r: F64, J: F64, scales: F64, tau_fixed: float | None = None
               ) -> tuple[F64, F64, F64, F64, float, float]:
    """g, U, s, Vt of the compressed scaled problem, sigma (per coordinate, of the full
    linearised fit) and the threshold tau (eq. W2; ``tau_fixed`` when given)."""
    g, R = compressed(r, J)
    U, s, Vt = np.linalg.svd(R * scales, full_matrices=False)
    m, p = J.shape
    sigma = abs(float(g[p])) / math.sqrt(max(m - p, 1))
    tau = max(sigma, RANK_RTOL * float(s[0]) if s.size else 0.0)
    return g, U, s, Vt, sigma, (tau if tau_fixed is None else tau_fixed)


def _covariance(r: F64, s: F64, Vt: F64, keep: NDArray[np.bool_], scales: F64
                ) -> tuple[F64, F64]:
    """Eq. W3, and its second term alone (the held directions' prior)."""
    k = int(keep.sum())
    dof = max(r.size - k, 1)
    s2 = float(r @ r) / dof
    vk, vh = Vt[keep], Vt[~keep]
    d2 = np.outer(scales, scales)
    held = (vh.T @ vh) * d2
    return ((vk.T / s[keep] ** 2) @ vk * s2) * d2 + held, held


def _map_step(g: F64, U: F64, s: F64, Vt: F64, x: F64, keep: NDArray[np.bool_], s2: float
              ) -> tuple[F64, float, float]:
    """Eq. W4 in the SVD basis: the step e (held components reset to 0), the predicted
    decrease of the objective |r|^2 + sigma^2 |x|^2 on the kept directions, and its value."""
    c = Vt @ x
    b = U.T @ g
    e = np.where(keep, -(s * b + s2 * c) / (s * s + s2), -c)
    after = (b + s * e) ** 2 + s2 * (c + e) ** 2
    pred = float(np.sum(np.where(keep, b * b + s2 * c * c - after, 0.0)))
    return e, pred, float(g @ g) + s2 * float(c @ c)


def _line_search(evaluate: Callable[[F64], tuple[F64, F64]],
                 residual: Callable[[F64], F64], theta: F64, step: F64, prior: F64,
                 scales: F64, s2: float, phi0: float, pred: float, resets: bool
                 ) -> tuple[F64, F64, F64 | None] | None:
    """Backtracking (Armijo) on the objective along ``step``: (theta, r, J or None) of the
    first accepted point, or None when none lowers it. A step that resets held directions is
    taken whole (the reset is the point of it)."""
    t = 1.0
    while t >= 2.0 ** -30:
        trial = theta + t * step
        r_t, J_t = evaluate(trial) if t == 1.0 else (residual(trial), None)
        xt = (trial - prior) / scales
        if (float(r_t @ r_t) + s2 * float(xt @ xt) <= phi0 - 1e-4 * t * pred
                or pred <= 1e-14 * phi0 or (resets and t == 1.0)):
            return trial, r_t, J_t
        t *= 0.5
    return None


def solve(evaluate: Callable[[F64], tuple[F64, F64]], residual: Callable[[F64], F64],
          theta0: F64, prior: F64, scales: F64, names: Sequence[str], *,
          start: tuple[F64, F64] | None = None,
          max_iterations: int = MAX_ITERATIONS,
          reading: Callable[[F64], str] | None = None) -> Solution:
    """Minimise |r(theta)|^2 + sigma^2 |x|^2 by the Gauss-Newton steps of eq. W4, the
    directions at or below the noise held at the prior (eq. W2).

    Args:
        evaluate: theta -> (r (m,), J (m, p)).
        residual: theta -> r (cheaper; the line search).
        theta0: start (p,); prior: the nominal values held directions keep (p,).
        scales: d_j (p,), > 0.
        names: the parameters' names (for the held directions).
        start: (r, J) at theta0 when already known.
        reading: a held direction (tolerance units) -> its name in the arm's terms
            (:func:`zrp.gap.fit.heldname.tilt_reading`); only the description, no number.
    """
    theta = np.array(theta0, dtype=float)
    r, J = start if start is not None else evaluate(theta)
    reason, converged, it = "", False, 0
    tau_fixed: float | None = None
    for it in range(1, max_iterations + 1):
        g, U, s, Vt, _, tau = _decompose(r, J, scales, tau_fixed)
        if it == FREEZE_AFTER:
            tau_fixed = tau  # the threshold settles with the fit: fixed, no held set flips
        keep = s > tau
        x = (theta - prior) / scales
        s2 = tau * tau  # the prior's weight sigma^2 (eq. W4)
        e, pred, phi0 = _map_step(g, U, s, Vt, x, keep, s2)
        resets = float(np.linalg.norm(e[~keep])) > 1e-9
        dx = Vt.T @ e
        if float(np.linalg.norm(dx)) <= 1e-10 * (1.0 + float(np.linalg.norm(x))) or (
                pred <= 1e-14 * phi0 and not resets):
            converged, reason = True, "converged"
            break
        found = _line_search(evaluate, residual, theta, scales * dx, prior, scales, s2,
                             phi0, pred, resets)
        if found is None:
            converged = pred <= 1e-10 * phi0
            reason = ("converged (no step lowers the objective further)" if converged else
                      "stopped: no step along the Gauss-Newton direction lowers the objective")
            break
        theta, r, J_t = found
        r, J = (r, J_t) if J_t is not None else evaluate(theta)
    else:
        reason = f"stopped at the iteration limit ({max_iterations}) before converging"
    if reason != "converged":  # the decomposition at theta is not at hand
        _, _, s, Vt, _, tau = _decompose(r, J, scales, tau_fixed)
        keep = s > tau
    held = _held(Vt, s, keep, names, tau, RANK_RTOL * float(s[0]) if s.size else 0.0,
                 reading)
    cov, held_cov = _covariance(r, s, Vt, keep, scales)
    return Solution(theta, r, J, cov, held, converged, it, reason, held_cov)


def rank_chi2(theta: F64, c_est: F64, c_full: F64, rtol: float = 1e-10) -> tuple[float, int]:
    """chi2 = theta^T c_est^+ theta and its rank (df), the pseudo-inverse in the scale of the
    variances of ``c_full`` (eigenvalues below ``rtol`` of the largest: directions without an
    estimate, not tested)."""
    d = np.sqrt(np.clip(np.diag(c_full), 0.0, None))
    d = np.where(d > 0, d, 1.0)
    w, v = np.linalg.eigh(c_est / np.outer(d, d))
    ok = w > rtol * max(1.0, float(w.max()) if w.size else 0.0)
    if not np.any(ok):
        return 0.0, 0
    z = v[:, ok].T @ (theta / d)
    return float(np.sum(z * z / w[ok])), int(ok.sum())
