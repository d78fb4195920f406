"""Compiled inner loop of the trajectory inverse kinematics (see :mod:`zrp.kinematics.ik`).

Joint rates come from eq (7), J qdot = [omega_h; V_p], solved by damped least squares on the
row-scaled Jacobian [J_omega; J_v / L] (L: characteristic length), integrated with the
Adams-Bashforth-Moulton predictor-corrector of order 4 (PECE) started by classical RK4, and
projected back onto the desired pose by Newton steps (closed-loop drift correction).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from zrp.kinematics._kernels import fk_jac_one

STATUS_OK = 0
STATUS_NONFINITE = 1


@njit(cache=True)
def _pose_error(pose, pd, erd, err):
    """err[0:3] = rotation vector of R_d R^T (rad), err[3:6] = p_d - p."""
    # q_err = e_d * conj(e)
    a0, a1, a2, a3 = erd[0], erd[1], erd[2], erd[3]
    b0, b1, b2, b3 = pose[3], -pose[4], -pose[5], -pose[6]
    w = a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3
    x = a0 * b1 + b0 * a1 + a2 * b3 - a3 * b2
    y = a0 * b2 + b0 * a2 + a3 * b1 - a1 * b3
    z = a0 * b3 + b0 * a3 + a1 * b2 - a2 * b1
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    if s > 1e-300:
        k = 2.0 * math.atan2(s, w) / s
    else:
        k = 2.0
    err[0] = k * x
    err[1] = k * y
    err[2] = k * z
    err[3] = pd[0] - pose[0]
    err[4] = pd[1] - pose[1]
    err[5] = pd[2] - pose[2]


@njit(cache=True)
def _scaled_jacobian(jac, m, inv_l, cscale, js):
    """js <- T J S: the task rows (m = 6: [omega; v / L], m = 3: [v / L]) of the Jacobian with
    its joint columns scaled by ``cscale``."""
    n = jac.shape[1]
    off = 6 - m
    for i in range(m):
        sc = 1.0 if (i + off) < 3 else inv_l
        for j in range(n):
            js[i, j] = jac[i + off, j] * sc * cscale[j]


@njit(cache=True)
def _gram_lower(js, a):
    """Lower triangle of a <- js js^T."""
    m, n = js.shape
    for i in range(m):
        for j in range(i + 1):
            acc = 0.0
            for k in range(n):
                acc += js[i, k] * js[j, k]
            a[i, j] = acc


@njit(cache=True)
def _cholesky(a, lam2, c, check):
    """c <- lower Cholesky factor of a + lam2 I (lower triangle of ``a`` used).

    With ``check``, stops at the first pivot <= 1e-300 and returns 0; otherwise returns the
    product of the diagonal, sqrt(det(a + lam2 I)).
    """
    m = a.shape[0]
    w = 1.0
    for j in range(m):
        d = a[j, j] + lam2
        for k in range(j):
            d -= c[j, k] * c[j, k]
        if check and d <= 1e-300:
            return 0.0
        c[j, j] = math.sqrt(d)
        w *= c[j, j]
        for i in range(j + 1, m):
            acc = a[i, j]
            for k in range(j):
                acc -= c[i, k] * c[j, k]
            c[i, j] = acc / c[j, j]
    return w


@njit(cache=True)
def _cho_solve(c, rhs, y):
    """Solve C C^T y = rhs for the lower-triangular C."""
    m = c.shape[0]
    for i in range(m):
        acc = rhs[i]
        for k in range(i):
            acc -= c[i, k] * y[k]
        y[i] = acc / c[i, i]
    for i in range(m - 1, -1, -1):
        acc = y[i]
        for k in range(i + 1, m):
            acc -= c[k, i] * y[k]
        y[i] = acc / c[i, i]


@njit(cache=True)
def _dls_solve(jac, rhs, m, inv_l, cscale, w0, lam_max, out, info):
    """qdot = S Js^T (Js Js^T + lam^2 I)^-1 rhs with the dimensionless Js = T J S.

    Task rows T: m = 6 -> [omega; v / L], m = 3 -> [v / L]; ``rhs`` is already scaled.
    Joint columns S: 1 for revolute joints (rad), L for prismatic ones (length), so that every
    entry of Js is dimensionless. info[0] <- manipulability sqrt(det(Js Js^T)),
    info[1] <- lam^2 used.
    """
    n = jac.shape[1]
    js = np.empty((m, n))
    _scaled_jacobian(jac, m, inv_l, cscale, js)
    a = np.zeros((m, m))
    _gram_lower(js, a)
    # Cholesky of A (no damping) for the manipulability.
    c = np.zeros((m, m))
    w = _cholesky(a, 0.0, c, True)
    lam2 = 0.0
    if w < w0:
        r = 1.0 - w / w0
        lam2 = lam_max * lam_max * r * r
    if lam2 > 0.0:
        _cholesky(a, lam2, c, False)
    y = np.empty(m)
    _cho_solve(c, rhs, y)
    for j in range(n):
        acc = 0.0
        for i in range(m):
            acc += js[i, j] * y[i]
        out[j] = acc * cscale[j]
    info[0] = w
    info[1] = lam2


@njit(cache=True)
def _rate(q, pd, vd, erd, wd, axes, bodies, prism, m, inv_l, cscale, kp, w0, lam_max,
          pose, jac, err, rhs, out, info):
    """f(t, q): joint rates tracking the desired velocity (+ kp times the pose error)."""
    fk_jac_one(q, axes, bodies, prism, pose, jac)
    _pose_error(pose, pd, erd, err)
    if m == 6:
        for i in range(3):
            rhs[i] = wd[i] + kp * err[i]
            rhs[3 + i] = (vd[i] + kp * err[3 + i]) * inv_l
    else:
        for i in range(3):
            rhs[i] = (vd[i] + kp * err[3 + i]) * inv_l
    _dls_solve(jac, rhs, m, inv_l, cscale, w0, lam_max, out, info)


@njit(cache=True)
def _errnorms(err, m):
    ep = math.sqrt(err[3] ** 2 + err[4] ** 2 + err[5] ** 2)
    eo = math.sqrt(err[0] ** 2 + err[1] ** 2 + err[2] ** 2) if m == 6 else 0.0
    return ep, eo


@njit(cache=True)
def _newton(q, pd, erd, axes, bodies, prism, m, inv_l, cscale, w0, lam_max, tol_p, tol_o,
            max_iter, pose, jac, err, rhs, dq, info, res):
    """Project q onto the desired pose. res <- [ep0, eo0, ep, eo, |dq| total, iterations]."""
    n = q.shape[0]
    fk_jac_one(q, axes, bodies, prism, pose, jac)
    _pose_error(pose, pd, erd, err)
    ep, eo = _errnorms(err, m)
    res[0] = ep
    res[1] = eo
    total = 0.0
    it = 0
    prev = 1e300
    while it < max_iter and (ep > tol_p or eo > tol_o):
        score = ep * inv_l + eo
        if score > 0.5 * prev:
            # no more quadratic progress: rounding floor (or a damped singular step)
            if it >= 3:
                break
        prev = score
        if m == 6:
            for i in range(3):
                rhs[i] = err[i]
                rhs[3 + i] = err[3 + i] * inv_l
        else:
            for i in range(3):
                rhs[i] = err[3 + i] * inv_l
        # Newton steps are small: damp only very close to the singularity (w < w0 / 100),
        # so that the projection still converges quadratically where the rates were damped.
        _dls_solve(jac, rhs, m, inv_l, cscale, 0.01 * w0, lam_max, dq, info)
        s = 0.0
        for j in range(n):
            q[j] += dq[j]
            s += dq[j] * dq[j]
        total += math.sqrt(s)
        it += 1
        fk_jac_one(q, axes, bodies, prism, pose, jac)
        _pose_error(pose, pd, erd, err)
        ep, eo = _errnorms(err, m)
    res[2] = ep
    res[3] = eo
    res[4] = total
    res[5] = it


@njit(cache=True)
def integrate(q0, h, pd, vd, erd, wd, pm, vm, erm, wm, axes, bodies, prism, m, inv_l, cscale, kp,
              w0, lam_max, newton, tol_p, tol_o, max_iter,
              q_out, qd_out, manip, lam_out, drift_p, drift_o, err_p, err_o, corr, iters):
    """Integrate N = len(pd) - 1 steps. Midpoint data (pm, vm, erm, wm; 3 rows) serve RK4.

    Returns (status, step): status 0 when all steps finished, 1 when q became non-finite.
    """
    n = q0.shape[0]
    nsteps = pd.shape[0] - 1
    pose = np.empty(7)
    jac = np.empty((6, n))
    err = np.empty(6)
    rhs = np.empty(6)
    info = np.empty(2)
    res = np.empty(6)
    dq = np.empty(n)
    f = np.empty((nsteps + 1, n))
    q = q0.copy()

    def finish_step(k):
        if newton:
            _newton(q, pd[k], erd[k], axes, bodies, prism, m, inv_l, cscale, w0, lam_max, tol_p,
                    tol_o, max_iter, pose, jac, err, rhs, dq, info, res)
        else:
            fk_jac_one(q, axes, bodies, prism, pose, jac)
            _pose_error(pose, pd[k], erd[k], err)
            ep, eo = _errnorms(err, m)
            res[0] = ep
            res[1] = eo
            res[2] = ep
            res[3] = eo
            res[4] = 0.0
            res[5] = 0.0
        drift_p[k] = res[0]
        drift_o[k] = res[1]
        err_p[k] = res[2]
        err_o[k] = res[3]
        corr[k] = res[4]
        iters[k] = int(res[5])
        _rate(q, pd[k], vd[k], erd[k], wd[k], axes, bodies, prism, m, inv_l, cscale, kp, w0,
              lam_max, pose, jac, err, rhs, f[k], info)
        manip[k] = info[0]
        lam_out[k] = math.sqrt(info[1])
        for j in range(n):
            q_out[k, j] = q[j]
            qd_out[k, j] = f[k, j]

    finish_step(0)
    k1 = np.empty(n)
    k2 = np.empty(n)
    k3 = np.empty(n)
    k4 = np.empty(n)
    fp = np.empty(n)
    tmp = np.empty(n)
    for k in range(nsteps):
        if k < 3:  # classical RK4 start
            for j in range(n):
                k1[j] = f[k, j]
                tmp[j] = q[j] + 0.5 * h * k1[j]
            _rate(tmp, pm[k], vm[k], erm[k], wm[k], axes, bodies, prism, m, inv_l, cscale, kp, w0,
                  lam_max, pose, jac, err, rhs, k2, info)
            for j in range(n):
                tmp[j] = q[j] + 0.5 * h * k2[j]
            _rate(tmp, pm[k], vm[k], erm[k], wm[k], axes, bodies, prism, m, inv_l, cscale, kp, w0,
                  lam_max, pose, jac, err, rhs, k3, info)
            for j in range(n):
                tmp[j] = q[j] + h * k3[j]
            _rate(tmp, pd[k + 1], vd[k + 1], erd[k + 1], wd[k + 1], axes, bodies, prism, m,
                  inv_l, cscale, kp, w0, lam_max, pose, jac, err, rhs, k4, info)
            for j in range(n):
                q[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
        else:  # Adams-Bashforth-Moulton 4, PECE
            for j in range(n):
                tmp[j] = q[j] + h / 24.0 * (55.0 * f[k, j] - 59.0 * f[k - 1, j]
                                            + 37.0 * f[k - 2, j] - 9.0 * f[k - 3, j])
            _rate(tmp, pd[k + 1], vd[k + 1], erd[k + 1], wd[k + 1], axes, bodies, prism, m,
                  inv_l, cscale, kp, w0, lam_max, pose, jac, err, rhs, fp, info)
            for j in range(n):
                q[j] += h / 24.0 * (9.0 * fp[j] + 19.0 * f[k, j] - 5.0 * f[k - 1, j]
                                    + f[k - 2, j])
        for j in range(n):
            if not math.isfinite(q[j]):
                return STATUS_NONFINITE, k + 1
        finish_step(k + 1)
    return STATUS_OK, nsteps
