"""Registration, nonlinear least squares with the analytic Jacobians, identifiability and
statistics (covariance, Wald and F tests, information criteria, linearised cross-validation).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import (
    special,  # chdtrc/fdtrc: the chi2/F survival functions without scipy.stats (1 s import)
)

from zrp.arrays import F64
from zrp.errors import InputError, ZRPWarning
from zrp.gap.fit.aliasing import Acceptance, Aliased
from zrp.gap.fit.heldname import tilt_reading
from zrp.gap.fit.orientation import alias_jacobian, solve_with_orientation
from zrp.gap.fit.wellposed import HeldDirection, parameter_scales, prior_values, rank_chi2, solve
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.problem import Evaluation, Problem
from zrp.kinematics.forward import forward_kinematics

#: Two-sided 95 % quantile of the standard normal (the one home of the constant in zrp.gap).
Z95 = 1.959963984540054

__all__ = [
    "Z95",
    "FitResult",
    "FitWarning",
    "check_identifiable",
    "cv_rms",
    "f_test",
    "fit",
    "group_key",
    "identifiable_start",
    "initial_registration",
    "orthonormal_basis",
    "point_errors",
    "wald_groups",
]




class FitWarning(ZRPWarning):
    """A fit is poorly conditioned, did not converge, or the data hide some parameter."""


@dataclass(frozen=True, eq=False)
class FitResult:
    """A least-squares fit of the corrected model on a set of poses.

    Attributes:
        specs: the parameters (p).
        theta: values, shape (p,), in the units of the specs.
        cov: covariance, shape (p, p) (from sigma^2 (J^T J)^-1 at the solution).
        residual: predicted minus measured, shape (3R,).
        jac: Jacobian at the solution, shape (3R, p).
        base_rotation: R_b0 used by the problem, shape (3, 3).
        poses: pose indices fitted, shape (S,).
        converged: the solver met its stop test.
        held: the parameter combinations the data cannot pin, kept at their nominal values
            (:mod:`zrp.gap.fit.wellposed`).
        stop_reason: why the solver stopped, in words.
        iterations: its Gauss-Newton iterations.
        probe_rotation: R_t identified with the orientations (3, 3), or None when the fit
            used positions only. ``residual``, ``jac`` and the statistics built on them are
            the positions' in both cases; ``cov`` is the fit's (with orientations: of both).
        held_cov: the held directions' share of ``cov`` (their prior's, eq. W3), shape
            (p, p), or None when not known (then ``cov`` is taken as all estimated).
        tied: the linear equality constraints the fit met, as the map theta = tied @ phi
            from its free coordinates phi, shape (p, f), or None when every parameter was
            free (:mod:`zrp.gap.fit.sumzero`: lumped weights held at sum 0). ``cov`` and
            ``jac`` are the parameters' (``cov`` of rank f); the statistics count f.
    """

    specs: tuple[ParamSpec, ...]
    theta: F64
    cov: F64
    residual: F64
    jac: F64
    base_rotation: F64
    poses: NDArray[np.int64]
    converged: bool
    held: tuple[HeldDirection, ...] = ()
    stop_reason: str = ""
    iterations: int = 0
    probe_rotation: F64 | None = None
    held_cov: F64 | None = None
    tied: F64 | None = None

    def __post_init__(self) -> None:
        p = len(self.specs)
        if self.theta.shape != (p,) or self.cov.shape != (p, p):
            raise InputError(f"FitResult: theta/cov shapes {self.theta.shape}/{self.cov.shape} "
                             f"do not match {p} parameters")
        if self.tied is not None and (self.tied.ndim != 2 or self.tied.shape[0] != p):
            raise InputError(f"FitResult: tied of shape {self.tied.shape} does not map onto "
                             f"{p} parameters")

    @property
    def n_free(self) -> int:
        """The number of free parameters (``len(specs)`` less the equality constraints)."""
        return len(self.specs) if self.tied is None else int(self.tied.shape[1])

    @property
    def free_jac(self) -> F64:
        """The Jacobian in the free coordinates (``jac @ tied``; ``jac`` when all are free)."""
        return self.jac if self.tied is None else self.jac @ self.tied

    @property
    def rss(self) -> float:
        """Residual sum of squares, length unit^2."""
        return float(self.residual @ self.residual)

    @property
    def n_res(self) -> int:
        return int(self.residual.size)

    @property
    def dof(self) -> int:
        return max(self.n_res - self.n_free, 1)

    @property
    def sigma(self) -> float:
        """Residual standard deviation per coordinate, length unit."""
        return float(np.sqrt(self.rss / self.dof))

    @property
    def stderr(self) -> F64:
        """Standard errors, shape (p,)."""
        return np.sqrt(np.clip(np.diag(self.cov), 0.0, None))

    @property
    def bic(self) -> float:
        """Bayesian information criterion (Gaussian errors, unknown variance)."""
        return float(self.n_res * np.log(self.rss / self.n_res) + self.n_free
                     * np.log(self.n_res))

    def value(self, name: str) -> float:
        """The value of the parameter called ``name``."""
        for s, v in zip(self.specs, self.theta, strict=False):
            if s.name == name:
                return float(v)
        raise InputError(f"no parameter {name!r}; fitted: {', '.join(s.name for s in self.specs)}")


def point_errors(residual: F64) -> F64:
    """3-D error per measured point |r|, shape (R,), from a residual of shape (3R,)."""
    return np.linalg.norm(np.asarray(residual).reshape(-1, 3), axis=1)


def _kabsch(a: F64, b: F64) -> tuple[F64, F64]:
    """R, t minimising |R a + t - b| (a, b shape (N, 3))."""
    ca, cb = a.mean(0), b.mean(0)
    h = (a - ca).T @ (b - cb)
    u, _, vt = np.linalg.svd(h)
    d = np.sign(np.linalg.det(vt.T @ u.T)) or 1.0
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, cb - r @ ca


def initial_registration(ctx: Context, specs: Sequence[ParamSpec], poses: ArrayLike,
                         iterations: int = 60) -> tuple[F64, F64]:
    """Starting values for the registration parameters (other parameters 0) and R_b0.

    Alternates a Kabsch fit of the base frame with a linear solve of the tool offsets (the
    nominal model is used for p and R_n).

    Returns:
        theta0 shape (p,), R_b0 shape (3, 3).
    """
    poses = np.asarray(poses, dtype=np.int64)
    prob = Problem(ctx, specs, poses)
    if poses.size < len(ctx.meas.pose_ids) and "nominal_fk" not in vars(ctx):
        # a subset (the motion search's 2,500 of 1e6 samples): the kinematics of those poses
        # only; caching it for every pose held ~0.5 KB a pose for the whole diagnosis
        fk = forward_kinematics(ctx.model, ctx.q[poses])
        p, rn = fk.position[prob.row_pose], fk.rotation[prob.row_pose]
    else:
        fk = ctx.nominal_fk
        p = fk.position[poses][prob.row_pose]
        rn = fk.rotation[poses][prob.row_pose]
    m = prob.measured
    M = len(ctx.meas.point_labels)
    t = np.zeros((M, 3))
    rb, tb = np.eye(3), np.zeros(3)
    for _ in range(iterations if prob.instrument else 1):
        x = p + np.einsum("rij,rj->ri", rn, t[prob.row_point])
        if prob.instrument:
            rb, tb = _kabsch(x, m)
        local = (m - tb) @ rb  # = R_b^T (m - t_b)
        for j in range(M):
            sel = prob.row_point == j
            t[j] = np.linalg.lstsq(rn[sel].reshape(-1, 3), (local[sel] - p[sel]).ravel(),
                                   rcond=None)[0]
    theta = np.zeros(len(specs))
    for i, s in enumerate(specs):
        if s.kind == "trans":
            theta[i] = tb[s.comp]
        elif s.kind == "tool":
            theta[i] = t[s.comp // 3, s.comp % 3]
    return theta, rb


def orthonormal_basis(a: F64, rtol: float = 1e-10) -> F64:
    """An orthonormal basis of the column span of a (m, k) -> (m, r), via the Gram matrix
    (much faster than a QR for tall matrices; columns should be normalised)."""
    if a.shape[1] == 0:
        return np.zeros((a.shape[0], 0))
    w, v = np.linalg.eigh(a.T @ a)
    keep = w > max(w.max(), 1e-300) * rtol
    q = (a @ v[:, keep]) / np.sqrt(w[keep])
    # one re-orthogonalisation pass for accuracy
    w2, v2 = np.linalg.eigh(q.T @ q)
    return (q @ v2) / np.sqrt(w2)


def fit(ctx: Context, specs: Sequence[ParamSpec], poses: ArrayLike, theta0: ArrayLike,
        base_rotation: ArrayLike, *, start: Evaluation | None = None,
        orientation: bool = True) -> FitResult:
    """Least squares with the analytic Jacobian of :class:`~zrp.gap.model.problem.Problem`:
    the scaled truncated-SVD Gauss-Newton solver of :mod:`zrp.gap.fit.wellposed` (eqs. W1-W3),
    which keeps the combinations the data cannot pin at their nominal values (the effect
    parameters at 0, the registration at ``theta0``) and reports them (``held``).

    Args:
        specs: parameters (p).
        poses: pose indices, shape (S,).
        theta0: starting values, shape (p,).
        base_rotation: R_b0, shape (3, 3).
        start: the evaluation at theta0 when already known (used only when its poses and
            theta equal ``poses`` and ``theta0``).
        orientation: use the measured orientations when ``ctx.orientation`` says how they
            weigh (False: positions only, whatever the context).
    """
    prob = Problem(ctx, specs, poses, base_rotation)
    theta0 = np.asarray(theta0, dtype=float)
    if prob.n_residuals <= prob.size:
        raise InputError(f"{prob.n_residuals // 3} measured points give {prob.n_residuals} "
                         f"coordinates, not enough for {prob.size} parameters; measure more "
                         "poses")
    at0 = None
    if (start is not None and np.array_equal(start.poses, prob.poses)
            and np.array_equal(start.theta, theta0) and start.jac.shape[1] == prob.size):
        at0 = (start.residual, start.jac)
    else:
        at0 = prob.residual_and_jacobian(theta0)
    scales = parameter_scales(ctx, specs, at0[1])
    if orientation and ctx.orientation is not None:
        return _fit_with_orientation(ctx, prob, theta0, scales)
    sol = solve(prob.residual_and_jacobian, prob.residual, theta0, prior_values(specs, theta0),
                scales, [s.name for s in specs], start=at0,
                reading=tilt_reading(ctx, specs, scales))
    if not sol.converged:
        warnings.warn(f"least squares with {len(specs)} parameters: {sol.reason}", FitWarning,
                      stacklevel=2)
    return FitResult(tuple(specs), sol.theta, sol.cov, sol.residual, sol.jac,
                     np.asarray(base_rotation), np.asarray(poses, dtype=np.int64),
                     sol.converged, sol.held, sol.reason, sol.iterations,
                     held_cov=sol.held_cov)


def _fit_with_orientation(ctx: Context, prob: Problem, theta0: F64, scales: F64) -> FitResult:
    """:func:`fit` from positions and orientations (:func:`~zrp.gap.fit.orientation.
    solve_with_orientation`); residual, jac: the positions' at the solution."""
    sol, rt = solve_with_orientation(ctx, prob, theta0, scales)
    if not sol.converged:
        warnings.warn(f"least squares with {sol.theta.size} parameters (positions and "
                      f"orientations): {sol.reason}", FitWarning, stacklevel=3)
    p = prob.size
    r, J = prob.residual_and_jacobian(sol.theta[:p])
    return FitResult(prob.specs, sol.theta[:p], sol.cov[:p, :p], r, J, prob.base_rotation,
                     prob.poses, sol.converged, sol.held, sol.reason, sol.iterations, rt,
                     None if sol.held_cov is None else sol.held_cov[:p, :p])


def check_identifiable(ctx: Context, base: FitResult, candidates: Sequence[ParamSpec],
                       poses: ArrayLike | None = None) -> tuple[list[ParamSpec], list[Aliased]]:
    """Which candidate parameters the data can identify on top of ``base``.

    The Jacobian of base + candidates is evaluated at the base solution; each candidate column
    (normalised) is projected on the span of the base columns and of the candidates accepted
    before it. A column that keeps less than ``ALIAS_TOL`` of its norm is dropped and reported
    with the parameters it is aliased with; one that keeps less than ``WEAK_TOL`` is kept and
    reported as weakly identifiable.

    Returns:
        the identifiable candidates, and the aliasing report.
    """
    keep, report, _ = identifiable_start(ctx, base, candidates, poses)
    return keep, report


def identifiable_start(ctx: Context, base: FitResult, candidates: Sequence[ParamSpec],
                       poses: ArrayLike | None = None
                       ) -> tuple[list[ParamSpec], list[Aliased], Evaluation]:
    """:func:`check_identifiable`, and the evaluation of base + the kept candidates at
    (base.theta, 0) that it computed (the start of the fit that usually follows)."""
    poses = base.poses if poses is None else np.asarray(poses, dtype=np.int64)
    specs = list(base.specs) + list(candidates)
    prob = Problem(ctx, specs, poses, base.base_rotation)
    theta = np.concatenate([base.theta, np.zeros(len(candidates))])
    r, J = prob.residual_and_jacobian(theta)
    Jt, probe = alias_jacobian(ctx, prob, theta, J)  # with orientations: their rows too
    norms = np.linalg.norm(Jt, axis=0)
    nb = len(base.specs)
    A = Jt[:, :nb] / np.where(norms[:nb] > 0, norms[:nb], 1.0)
    Q = orthonormal_basis(np.hstack([A, probe / np.linalg.norm(probe, axis=0)])
                          if probe.shape[1] else A)
    names = [s.name for s in specs]
    # every candidate projected off the base span at once (two passes, one matrix product each
    # instead of one matrix-vector product per candidate), then, in order, off the candidates
    # accepted before it: the same projection onto span(base, accepted)
    C = Jt[:, nb:] / np.where(norms[nb:] > 0, norms[nb:], 1.0)
    P = C - Q @ (Q.T @ C)
    P = P - Q @ (Q.T @ P)
    acc = Acceptance(Jt, norms, nb, names, P)
    deferred = []
    for i, spec in enumerate(candidates):  # pass 1: the clearly identifiable ones, in order
        if not acc.consider(i, spec, defer_weak=True):
            deferred.append(i)
    for i in deferred:  # pass 2: the weak ones against all of them (near gauges drop here)
        acc.consider(i, candidates[i], defer_weak=False)
    order = sorted(range(len(acc.keep)), key=lambda j: acc.keep_index[j])
    keep = [acc.keep[j] for j in order]
    report = sorted(acc.report, key=lambda a: acc.index_of[a.name])
    accepted_cols = list(range(nb)) + sorted(nb + acc.keep_index[j] for j in order)
    return keep, report, Evaluation(prob.poses, theta[accepted_cols], r, J[:, accepted_cols])


def group_key(spec: ParamSpec) -> str:
    """The significance group of a parameter, unique across effects ("effect:group")."""
    return f"{spec.effect}:{spec.group}"


def wald_groups(result: FitResult, first: int,
                tested: Callable[[ParamSpec], bool] | None = None) -> dict[str, float]:
    """p-value of the Wald test (all parameters of a group zero) per :func:`group_key`, for
    the parameters from index ``first`` on; with ``tested``, only the parameters it accepts
    enter the test (e.g. a mode's amplitude, not its frequency, whose null is not zero)."""
    groups: dict[str, list[int]] = {}
    for i in range(first, len(result.specs)):
        if tested is None or tested(result.specs[i]):
            groups.setdefault(group_key(result.specs[i]), []).append(i)
    out: dict[str, float] = {}
    for g, idx in groups.items():
        th = result.theta[idx]
        C = result.cov[np.ix_(idx, idx)]
        if not np.all(np.isfinite(C)):
            out[g] = 1.0
            continue
        if result.tied is not None and np.any(result.tied[idx] < 0):  # singular: constrained
            chi2, df = rank_chi2(th, C, C)
            out[g] = float(special.chdtrc(df, chi2)) if df else 1.0
            continue
        try:
            chi2 = float(th @ np.linalg.solve(C, th))
        except np.linalg.LinAlgError:
            out[g] = 1.0
            continue
        out[g] = float(special.chdtrc(len(idx), chi2))
    return out


def f_test(small: FitResult, big: FitResult) -> float:
    """p-value of the F test that the extra parameters of ``big`` do not help."""
    dp = big.n_free - small.n_free
    if dp <= 0 or big.rss <= 0:
        return 1.0
    f = ((small.rss - big.rss) / dp) / (big.rss / big.dof)
    return float(special.fdtrc(dp, big.dof, f)) if f > 0 else 1.0


def cv_rms(ctx: Context, result: FitResult, folds: Sequence[NDArray[np.int64]]) -> float:
    """Cross-validated 3-D RMS error (length unit) over the folds of the fitted poses.

    For each fold, the parameters are refitted without it by one Gauss-Newton step from the
    full solution (exact for parameters that enter linearly, second-order accurate for the
    registration), and the error is evaluated on the fold. The folds' squared errors are pooled.
    """
    rows = np.flatnonzero(np.isin(ctx.meas.pose_index, result.poses))  # Problem's row order
    prob_rows_pose = ctx.meas.pose_index[rows]
    r = result.residual.reshape(-1, 3)
    jac = result.free_jac  # a constrained fit: refitted within its constraints
    J = jac.reshape(r.shape[0], 3, -1)
    d = np.linalg.norm(jac, axis=0)
    d = np.where(d > 0, d, 1.0)
    Js = J / d
    A = np.einsum("rcp,rcq->pq", Js, Js)
    b = np.einsum("rcp,rc->p", Js, r)
    sq = 0.0
    cnt = 0
    for f in folds:
        held = np.isin(prob_rows_pose, f)
        if not held.any():
            continue
        Jh = Js[held]
        Ah = A - np.einsum("rcp,rcq->pq", Jh, Jh)
        bh = b - np.einsum("rcp,rc->p", Jh, r[held])
        try:
            step = -np.linalg.solve(Ah, bh)
        except np.linalg.LinAlgError:
            step = -np.linalg.lstsq(Ah, bh, rcond=None)[0]
        rh = r[held] + np.einsum("rcp,p->rc", Jh, step)
        sq += float(np.sum(rh**2))
        cnt += int(held.sum())
    return float(np.sqrt(sq / max(cnt, 1)))
