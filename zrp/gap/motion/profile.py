"""Starting values of the residual vibration (eq. M5) by a profile search over the mode's
frequency and damping: the nonlinear omega and zeta are gridded, the linear gain is solved at
each grid point (against the current residual, projected off the current model's Jacobian
columns, so the registration and the effects already found are re-fitted implicitly), and the
best point per joint starts the Gauss-Newton fit of :class:`~zrp.gap.motion.fitting.Engine`.

A joint enters the candidate only when its best gain explains more than ``screen`` times the
residual variance per degree of freedom (an F-like ratio; the maximum over the grid is taken,
so the screen is set far above the single-test quantile; the Wald, F and BIC tests of the
search decide afterwards).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from zrp.arrays import F64, I64
from zrp.gap.model.problem import Problem
from zrp.gap.motion.effects import MotionParam, joint_mode, mode_band
from zrp.gap.motion.fitting import Engine, ModelFit
from zrp.gap.motion.kernels import mode_response

__all__ = ["SERVO_ZETA_GRID", "ZETA_GRID", "compliance_start", "vibration_start"]

#: damping ratios tried (a lightly damped mode: well below 1)
ZETA_GRID = (0.01, 0.03, 0.1, 0.3)
#: damping ratios tried for a compliant joint's servo response (eq. M8; servos are tuned near
#: critical damping)
SERVO_ZETA_GRID = (0.3, 0.7, 1.0, 2.0)


def _explained(col: F64, r: F64, Q: F64) -> tuple[float, float, F64]:
    """Sum of squares of r explained by ``col`` off span(Q), the gain, the projected column."""
    col = col - Q @ (Q.T @ col)
    cc = float(col @ col)
    if cc <= 0.0:
        return 0.0, 0.0, col
    cr = float(col @ r)
    return cr * cr / cc, -cr / cc, col


def _refine(eng: Engine, poses: I64, k: int, c: F64, r: F64, Q: F64, w0: float, z0: float
            ) -> tuple[float, float, float, F64]:
    """The profile maximum near a grid point (Nelder-Mead on log omega, log zeta; each
    evaluation solves the gain in closed form): (explained, omega, zeta, column)."""
    traj = eng.traj
    rows = r.size // poses.size

    def column(x: F64) -> F64:
        y = joint_mode(traj, k, float(np.exp(x[0])), float(np.exp(x[1])), eng.terms,
                       derivatives=False)[0]
        return c * np.repeat(y[poses], rows)

    res = minimize(lambda x: -_explained(column(x), r, Q)[0], np.log([w0, z0]),
                   method="Nelder-Mead", options={"xatol": 1e-4, "fatol": 1e-9 * float(r @ r),
                                                  "maxfev": 120})
    ex, _, col = _explained(column(res.x), r, Q)
    return ex, float(np.exp(res.x[0])), float(np.exp(res.x[1])), col


def _joint_columns(eng: Engine, cur: ModelFit, poses: I64, joints: list[int]
                   ) -> tuple[F64, F64, F64]:
    """Current residual and per-joint position sensitivities, both projected off the current
    model's Jacobian: r (3R,), C (3R, len(joints)); and Q (3R, p) the projector basis."""
    s, n = eng.traj.q.shape
    probes = []
    for k in joints:
        b = np.zeros((s, n))
        b[:, k] = 1.0
        probes.append(MotionParam(f"q{k + 1}.vib_probe", "1", "residual_vibration", "dq",
                                  k + 1, 0, b, f"q{k + 1}"))
    prob = Problem(cur.ctx, [*cur.specs, *probes], poses, eng.base_rotation)
    theta = np.concatenate([cur.result.theta, np.zeros(len(probes))])
    r, J = prob.residual_and_jacobian(theta)
    p = len(cur.specs)
    Q, _ = np.linalg.qr(J[:, :p])
    return r - Q @ (Q.T @ r), J[:, p:], Q


def _grid(eng: Engine, poses: I64, joints: list[int], n_omega: int
          ) -> dict[int, dict[tuple[float, float], F64]]:
    """Mode responses y at ``poses`` per joint and grid point; they depend on the command
    only, so they are computed once per engine and sample set (``eng.cache``)."""
    key = ("vibration_grid", n_omega, poses.tobytes())
    if key not in eng.cache:
        traj = eng.traj
        lo, hi = mode_band(traj.rate_hz)
        omegas = np.geomspace(lo, min(hi, 2.0 * np.pi * 100.0), n_omega)
        eng.cache[key] = {k: {(float(w), z): joint_mode(traj, k, w, z, eng.terms,
                                                        derivatives=False)[0][poses]
                              for w in omegas for z in ZETA_GRID} for k in joints}
    return eng.cache[key]


def vibration_start(eng: Engine, cur: ModelFit, poses: I64, screen: float = 30.0,
                    n_omega: int = 36) -> dict[str, float]:
    """Start values ``q{k}.vib_gain/omega/zeta`` for the joints whose best grid point passes
    the screen (empty when none does). Joints are taken one at a time, best first; each
    chosen mode is projected off before the next joint is screened (a big mode on one joint
    otherwise leaks into its neighbours' correlated columns)."""
    traj = eng.traj
    joints = [k for k in range(traj.n_joints)
              if np.ptp(traj.q[:, k]) > 1e-4 and np.any(traj.qdd[:, k] != 0.0)]
    if not joints:
        return {}
    r, C, Q = _joint_columns(eng, cur, poses, joints)
    rows = r.size // poses.size
    dof = max(r.size - Q.shape[1], 1)
    grid = _grid(eng, poses, joints, n_omega)
    out: dict[str, float] = {}
    left = list(range(len(joints)))
    while left:
        var = float(r @ r) / dof
        best = (0.0, -1, 0.0, 0.0)
        for j in left:
            for (w, z), y in grid[joints[j]].items():
                ex = _explained(C[:, j] * np.repeat(y, rows), r, Q)[0]
                if ex > best[0]:
                    best = (ex, j, w, z)
        j = best[1]
        if j < 0 or best[0] <= screen * var:
            break
        ex, w, z, col = _refine(eng, poses, joints[j], C[:, j], r, Q, best[2], best[3])
        _, g, col = _explained(col, r, Q)
        if g <= 0.0:
            break
        p = f"q{joints[j] + 1}.vib_"
        out.update({p + "gain": g, p + "omega": w, p + "zeta": z})
        u = col / np.linalg.norm(col)
        r = r - u * float(u @ r)
        Q = np.column_stack([Q, u])
        dof -= 3
        left.remove(j)
    return out


def compliance_start(eng: Engine, cur: ModelFit, poses: I64, screen: float = 30.0,
                     n_omega: int = 24) -> dict[str, float]:
    """Start values of ``dynamic_compliance`` per joint carrying a torque: ``q{k}.dyn_compliance``
    from the quasi-static column (-tau_k), and ``q{k}.dyn_omega``, ``q{k}.dyn_zeta`` too when
    the joint's spring-mass response (eq. M8, gridded over omega in :func:`mode_band` and
    :data:`SERVO_ZETA_GRID`) explains more than the quasi-static column by ``screen`` times
    the residual variance per degree of freedom (the rule of :func:`vibration_start`).
    Joints whose compliance would be negative are left out."""
    tau = eng.torque
    traj = eng.traj
    if tau is None:
        return {}
    joints = [k for k in range(traj.n_joints) if np.any(tau[:, k] != 0.0)]
    if not joints:
        return {}
    r, C, Q = _joint_columns(eng, cur, poses, joints)
    rows = r.size // poses.size
    var = float(r @ r) / max(r.size - Q.shape[1], 1)
    key = ("compliance_grid", n_omega, poses.tobytes())
    if key not in eng.cache:
        lo, hi = mode_band(traj.rate_hz)
        omegas = np.geomspace(lo, min(hi, 2.0 * np.pi * 100.0), n_omega)
        eng.cache[key] = {k: {(float(w), z): w * w * mode_response(
            traj.t, -tau[:, k], float(w), z, derivatives=False)[0][poses]
            for w in omegas for z in SERVO_ZETA_GRID} for k in joints}
    grid = eng.cache[key]
    out: dict[str, float] = {}
    for j, k in enumerate(joints):
        ex0, g0, _ = _explained(C[:, j] * np.repeat(-tau[poses, k], rows), r, Q)
        best = max(((*_explained(C[:, j] * np.repeat(y, rows), r, Q)[:2], w, z)
                    for (w, z), y in grid[k].items()), key=lambda b: b[0])
        p = f"q{k + 1}.dyn_"
        if best[0] - ex0 > screen * var and best[1] > 0.0:
            out.update({p + "compliance": best[1], p + "omega": best[2], p + "zeta": best[3]})
        elif g0 > 0.0:
            out[p + "compliance"] = g0
    return out
