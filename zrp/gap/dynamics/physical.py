"""Link inertial parameters identified physically consistent by construction: each moving
body's phi_b is the image of a free log-Cholesky vector theta_b (:mod:`zrp.gap.dynamics.logchol`,
eq. L1-L3), so every set the fit can return has positive definite pseudo-inertias (eq. R5)
and nothing is repaired afterwards.

The fit (eq. P1) is the maximum a posteriori estimate of the other chosen effects x (with
their physical bounds) and of the link changes dphi = phi(theta) - phi0::

    min  |W (A x + Y dphi - b)|^2  +  lam^2 |w * dphi|^2                         (eq. P1)

* the first term is the weighted least squares of :mod:`zrp.gap.dynamics.fit` (eq. F1: rows
  weighted by 1 / sigma_k, so it is a chi^2 in noise units), with the *exact* torque change
  of the links, Y dphi (Y the full inertial regressor, eq. R2), not only its excited base
  combinations;
* the second is a Gaussian prior toward the model's own values, in the scaled coordinates
  of eq. R4 (w_j: the norm of column j of Y over random states; a parameter that moves no
  torque takes the largest w of its kind, mass, first moment or inertia, and keeps the
  model's value); its weight lam = EXCITED * s_max (s_max: the largest singular value of the
  weighted, scaled Y along the log) is the excitation cut of eq. R6 made smooth: a
  combination excited at the cut is halved, one ten times above it kept to 1 %, one the log
  does not see keeps the model's value. As lam -> 0 the unconstrained solution is the
  minimum-norm one the diagnosis used before.

Every body keeps a small margin inside the physical set (eq. P5): phi_b is the image of
J_b = U U^T + eps_b E (E = diag(1, 1, 1, 0), eps_b = min((1 mm)^2 m0_b, half the model's own
smallest second moment about its centre)), i.e. its mass is spread at least about 1 mm along
every direction about its centre, so that MuJoCo's compiler accepts it (strictly positive
principal inertias and triangle inequalities).

The data term is reduced once by a QR factorisation (A_w = Q R, c = Q^T b_w: eq. P2), so each
iteration works on a few dozen rows. The same problem without the physical constraint (a
linear bounded least squares, eq. P3) is solved first; when its links are already physical it
is the answer. Otherwise eq. P1 is solved in (x, theta) by :func:`scipy.optimize.least_squares`
(analytic Jacobian, eq. L5), and the result says how far the physical set is from the
unconstrained one: the rise of the objective (a chi^2 in noise units, so its square root is
the distance in standard errors, eq. P4) and the weighted residual RMS of both.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import block_diag
from scipy.optimize import least_squares, lsq_linear
from scipy.stats import chi2

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.effects import EXCITED, Effect
from zrp.gap.dynamics.fit import design, folds, lag_one
from zrp.gap.dynamics.inertia import pseudo_inertia, pseudo_inertia_min
from zrp.gap.dynamics.logchol import phi_from_pseudo, phi_from_theta, phi_jacobian, theta_from_phi

__all__ = ["InertialFit", "physical_cross_validate", "physical_fit"]

#: Function evaluations of the physical fit, then of its convergence check.
MAX_NFEV, CHECK_NFEV = 400, 100

#: The smallest spread of a link's mass about its centre along any direction, m (eq. P5).
MIN_SPREAD_M = 1e-3

#: The physical set matches the unconstrained base combinations when its distance is below
#: this quantile of the chi^2 of their number (eq. P4): what the noise alone explains.
MATCHED_QUANTILE = 0.95


@dataclass(frozen=True)
class InertialFit:
    """The physically consistent fit of eq. P1.

    Attributes:
        theta: every chosen effect's parameters in design order (the inertial block: the
            excited base combinations beta = V^T (dphi / scale) of the physical set, eq. R4).
        phi: phi_b (eq. R1) of each moving body, all physically consistent.
        unconstrained_physical: the unconstrained fit (eq. P3) was already physical (then
            ``theta`` and ``phi`` are its values).
        distance_se: how far the physical set is from the unconstrained one, in the standard
            errors of the fit's intervals (eq. P4; 0 when already physical).
        noise_se: the distance the noise alone explains (eq. P4): the square root of the
            MATCHED_QUANTILE quantile of chi^2 with as many degrees of freedom as base
            combinations fitted.
        torque_gap: the RMS of the torque difference between the physical and the
            unconstrained fit along the rows fitted, in noise units (1 = the noise floor).
        min_margin: the smallest pseudo-inertia eigenvalue over the body's mass, all bodies.
        converged: whether the optimiser met its tolerances.
        unconstrained_phi: phi_b of each moving body in the unconstrained fit (eq. P3).
    """

    theta: F64
    phi: dict[int, F64]
    unconstrained_physical: bool
    distance_se: float
    noise_se: float
    torque_gap: float
    min_margin: float
    converged: bool = True
    unconstrained_phi: dict[int, F64] = field(default_factory=dict)

    def unphysical_links(self) -> list[int]:
        """The bodies whose unconstrained fit (eq. P3) is not physical (eq. R5): where the
        physical set cannot follow the data."""
        return [b for b, ph in self.unconstrained_phi.items() if pseudo_inertia_min(ph) <= 0.0]

    @property
    def matched(self) -> bool:
        """The physical set matches the unconstrained base combinations to within what the
        noise explains (eq. P4)."""
        return self.distance_se <= self.noise_se

    def describe(self) -> str:
        """In words, for the report."""
        if self.unconstrained_physical:
            return ("link inertias fitted physically consistent (log-Cholesky); the "
                    "unconstrained fit was already physical")
        how = ("matches the unconstrained base combinations to within the noise "
               f"({self.distance_se:.3g} standard errors from them, the noise alone explaining "
               f"up to {self.noise_se:.3g})" if self.matched else
               f"cannot match the unconstrained base combinations: it lies {self.distance_se:.3g}"
               f" standard errors from them, more than the noise explains ({self.noise_se:.3g}; "
               "the torques the log shows ask for a non-physical link)")
        return (f"link inertias fitted physically consistent (log-Cholesky); the physical set "
                f"{how}; its torques differ from the unconstrained fit's by "
                f"{self.torque_gap:.3g} noise RMS"
                + ("" if self.converged else "; the optimiser stopped before its tolerance"))


@dataclass(frozen=True)
class _Problem:
    """Eq. P1 reduced (eq. P2): rows [R; 0 lam diag(w)], right side [c; 0], residual r0."""

    m: F64
    rhs: F64
    r0: float
    aw: F64
    bw: F64
    n: int
    p_other: int
    lower: F64
    upper: F64
    phi0: list[F64]
    floor: list[F64]  # phi of eps_b E (eq. P5) per body


def _prior_weights(scale: F64) -> F64:
    """w of eq. P1: 1 / scale, or the largest of its kind for a parameter with scale 0."""
    present = scale > 0.0
    w = np.where(present, 1.0 / np.where(present, scale, 1.0), 0.0)
    kind = np.tile(np.array([0, 1, 1, 1, 2, 2, 2, 2, 2, 2]), scale.size // 10)
    for k in range(3):
        sel = kind == k
        top = float(w[sel].max()) if np.any(w[sel] > 0) else 1.0
        w[sel & ~present] = top
    return w


def _split(effects: list[Effect]) -> tuple[int, Effect]:
    idx = [i for i, e in enumerate(effects) if e.name == "inertial"]
    if len(idx) != 1 or effects[idx[0]].full is None or effects[idx[0]].basis is None:
        raise InputError("physical_fit: needs exactly one 'inertial' effect with its full "
                         "regressor and basis")
    return idx[0], effects[idx[0]]


def _columns(effects: list[Effect], s: int, n: int) -> tuple[F64, F64, F64, F64, F64]:
    """[other effects' columns | Y (physical units)], bounds of the others, scale, v."""
    i, ein = _split(effects)
    others = [e for j, e in enumerate(effects) if j != i]
    d = design(others, s, n)
    v, scale = ein.basis  # type: ignore[misc]
    y = ein.full * (scale > 0.0)  # a column that moves no torque (to rounding) stays out
    return np.concatenate([d.a, y], axis=-1), d.lower, d.upper, scale, v


def _problem(arm: Arm, a: F64, lo: F64, hi: F64, scale: F64, b: F64, sigma: F64,
             rows: np.ndarray) -> _Problem:
    aw = (a[rows] / sigma[:, None]).reshape(-1, a.shape[-1])
    bw = (b[rows] / sigma).ravel()
    q, r = np.linalg.qr(aw)  # eq. P2
    c = q.T @ bw
    po = lo.size
    w = _prior_weights(scale)
    s_max = float(np.linalg.norm(r[:, po:] / w, 2))
    lam = EXCITED * s_max
    prior = np.zeros((w.size, a.shape[-1]))
    prior[:, po:] = lam * np.diag(w)
    phi0 = [arm.body_params(bb) for bb in arm.moving_bodies()]
    return _Problem(np.vstack([r, prior]), np.concatenate([c, np.zeros(w.size)]),
                    max(float(bw @ bw - c @ c), 0.0), aw, bw, b.shape[1], po, lo, hi, phi0,
                    [phi_from_pseudo(_floor(ph)) for ph in phi0])


def _floor(phi0: F64) -> F64:
    """eps_b E of eq. P5: eps_b = min(MIN_SPREAD_M^2 m0, half the model's own smallest
    second moment about its centre), E = diag(1, 1, 1, 0)."""
    j = pseudo_inertia(phi0)
    m0 = float(phi0[0])
    own = float(np.linalg.eigvalsh(j[:3, :3] - np.outer(j[:3, 3], j[:3, 3]) / m0).min()) \
        if m0 > 0.0 else 0.0
    eps = max(min(MIN_SPREAD_M**2 * m0, 0.5 * own), 0.0)
    return eps * np.diag([1.0, 1.0, 1.0, 0.0])


def _inside(phi: F64, floor: F64) -> bool:
    """Physical with the margin of eq. P5: J(phi) - eps_b E positive semi-definite, to
    rounding (a model's own flat or thin link sits on the boundary, eps_b = 0)."""
    j = pseudo_inertia(phi - floor)
    return float(np.linalg.eigvalsh(j).min()) >= -1e-12 * float(np.abs(j).max())


def _unconstrained(p: _Problem) -> F64:
    """Eq. P3: eq. P1 without the physical constraint (bounded linear least squares)."""
    col = np.linalg.norm(p.m, axis=0)
    col[col == 0.0] = 1.0
    nz = p.m.shape[1]
    lo = np.concatenate([p.lower, np.full(nz - p.p_other, -np.inf)]) * col
    hi = np.concatenate([p.upper, np.full(nz - p.p_other, np.inf)]) * col
    if np.all(np.isinf(lo)) and np.all(np.isinf(hi)):
        return np.linalg.lstsq(p.m / col, p.rhs, rcond=None)[0] / col
    return lsq_linear(p.m / col, p.rhs, bounds=(lo, hi), method="bvls").x / col


def _phis(p: _Problem, dphi: F64) -> list[F64]:
    return [phi0 + dphi[10 * i:10 * i + 10] for i, phi0 in enumerate(p.phi0)]


def _margin(phi: F64) -> float:
    return pseudo_inertia_min(phi) / max(abs(float(phi[0])), 1e-12)


def _start_theta(phi: F64, phi0: F64, floor: F64) -> F64:
    """A log-Cholesky start (eq. P5: of phi less the floor): the unconstrained body if
    physical, else the model's (made positive definite by a tiny ridge if the model's body is
    itself on the boundary, e.g. a flat link)."""
    j0 = pseudo_inertia(phi0 - floor)
    ridge = 1e-9 * max(float(np.abs(j0).max()), 1e-9) * np.eye(4)
    for cand in (phi - floor, phi0 - floor, phi_from_pseudo(j0 + ridge)):
        try:
            return theta_from_phi(cand)
        except InputError:
            continue
    raise InputError("physical_fit: the model's own link inertias are not physical")


def _solve_physical(p: _Problem, z_u: F64, se2: float) -> tuple[F64, bool]:
    """Eq. P1 in (x, theta) from the unconstrained solution's physical bodies; converged when
    the optimiser meets its tolerances, or when a last run of CHECK_NFEV evaluations lowers
    the objective by less than 1e-3 of a squared standard error ``se2`` (a link driven to the
    boundary of the physical set, theta -> -inf, meets no step tolerance)."""
    po, nb = p.p_other, len(p.phi0)
    th0 = np.concatenate([_start_theta(ph, ph0, fl) for ph, ph0, fl in
                          zip(_phis(p, z_u[po:]), p.phi0, p.floor, strict=True)])
    x0 = np.clip(z_u[:po], p.lower, p.upper)

    def unpack(u: F64) -> F64:
        dphi = np.concatenate([phi_from_theta(u[po + 10 * i:po + 10 * i + 10]) + p.floor[i]
                               - p.phi0[i] for i in range(nb)])
        return np.concatenate([u[:po], dphi])

    def jac(u: F64) -> F64:
        jb = block_diag(*[phi_jacobian(u[po + 10 * i:po + 10 * i + 10]) for i in range(nb)])
        return np.hstack([p.m[:, :po], p.m[:, po:] @ jb])

    bounds = (np.concatenate([p.lower, np.full(10 * nb, -np.inf)]),
              np.concatenate([p.upper, np.full(10 * nb, np.inf)]))

    def run(u0: F64, nfev: int):  # scipy's OptimizeResult
        # a trial step may overflow exp(theta): "trf" rejects a non-finite residual and
        # shrinks its trust region, so the warning is no news
        with np.errstate(over="ignore", invalid="ignore"):
            return least_squares(lambda u: p.m @ unpack(u) - p.rhs, u0, jac=jac,
                                 bounds=bounds, method="trf", x_scale="jac", ftol=1e-10,
                                 xtol=1e-10, gtol=1e-10, max_nfev=nfev)

    res = run(np.concatenate([x0, th0]), MAX_NFEV)
    if res.success:
        return unpack(res.x), True
    last = run(res.x, CHECK_NFEV)
    return unpack(last.x), bool(last.success or 2.0 * (res.cost - last.cost) < 1e-3 * se2)


def _objective(p: _Problem, z: F64) -> float:
    """Eq. P1's objective, in noise units squared."""
    r = p.m @ z - p.rhs
    return float(r @ r) + p.r0


def _standard_error2(p: _Problem, z_u: F64) -> float:
    """The variance unit of the fit's intervals (eq. F2): the residual variance of the
    unconstrained fit, widened for its lag-one autocorrelation rho by (1 + rho) / (1 - rho)."""
    r = p.aw @ z_u - p.bw
    rho = lag_one(r.reshape(-1, p.n))
    return float(r @ r) / max(r.size - p.m.shape[1], 1) * (1.0 + rho) / (1.0 - rho)


def physical_fit(arm: Arm, effects: list[Effect], b: F64, sigma: F64,
                 rows: np.ndarray | None = None) -> InertialFit:
    """Eq. P1 on ``rows`` (all by default) of b = tau - tau0 (S, n); ``effects`` the chosen
    ones, one of them "inertial" (module docstring)."""
    s, n = b.shape
    rows = np.arange(s) if rows is None else rows
    a, lo, hi, scale, v = _columns(effects, s, n)
    p = _problem(arm, a, lo, hi, scale, b, sigma, rows)
    z_u = _unconstrained(p)
    ok_u = all(_inside(ph, fl) for ph, fl in zip(_phis(p, z_u[p.p_other:]), p.floor,
                                                 strict=True))
    se2 = _standard_error2(p, z_u)
    z, converged = (z_u, True) if ok_u else _solve_physical(p, z_u, se2)
    rise = max(_objective(p, z) - _objective(p, z_u), 0.0)
    gap = p.aw @ (z - z_u)
    phis = _phis(p, z[p.p_other:])
    i, _ = _split(effects)
    dphi_s = z[p.p_other:] / np.where(scale > 0.0, scale, np.inf)
    beta = v.T @ dphi_s
    others = z[:p.p_other]
    start = sum(e.columns.shape[-1] for e in effects[:i])
    theta = np.concatenate([others[:start], beta, others[start:]])
    return InertialFit(theta, dict(zip(arm.moving_bodies(), phis, strict=True)), ok_u,
                       float(np.sqrt(rise / se2)),
                       float(np.sqrt(chi2.ppf(MATCHED_QUANTILE, v.shape[1]))),
                       float(np.sqrt(gap @ gap / gap.size)), min(_margin(ph) for ph in phis),
                       converged, dict(zip(arm.moving_bodies(), _phis(p, z_u[p.p_other:]),
                                           strict=True)))


def predict(arm: Arm, effects: list[Effect], fit: InertialFit, rows: np.ndarray) -> F64:
    """The torques of the chosen effects at ``rows`` (len, n): other effects plus the exact
    link torque change Y dphi (eq. R2)."""
    s, n = effects[0].columns.shape[:2]
    a, _, _, _, _ = _columns(effects, s, n)
    i, _ = _split(effects)
    start = sum(e.columns.shape[-1] for e in effects[:i])
    r = effects[i].columns.shape[-1]
    others = np.concatenate([fit.theta[:start], fit.theta[start + r:]])
    dphi = np.concatenate([fit.phi[bb] - arm.body_params(bb)
                           for bb in arm.moving_bodies()])
    return a[rows] @ np.concatenate([others, dphi])


def physical_cross_validate(arm: Arm, effects: list[Effect], b: F64, sigma: F64, k: int,
                            guard: int = 0) -> tuple[F64, list[InertialFit]]:
    """Out-of-segment predictions (S, n) with eq. P1 fitted on the other segments (as
    :func:`zrp.gap.dynamics.fit.cross_validate`, a guard each side), and each segment's fit."""
    s = b.shape[0]
    pred = np.zeros_like(b)
    fits = []
    for seg in folds(s, k):
        keep = np.ones(s, dtype=bool)
        keep[max(seg[0] - guard, 0):seg[-1] + guard + 1] = False
        fit = physical_fit(arm, effects, b, sigma, np.flatnonzero(keep))
        pred[seg] = predict(arm, effects, fit, seg)
        fits.append(fit)
    return pred, fits
