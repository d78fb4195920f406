"""The orientation residual of a pose and its Jacobian (eqs. O1-O2 of
:mod:`zrp.gap.fit.fullpose`): the one home of the orientation block, used by the full-pose
refit, the orientation search and every fit of the diagnosis when the measurements carry
orientations (:func:`zrp.gap.fit.leastsq.fit` with :class:`OrientationWeights`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial.transform import Rotation

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.fit.heldname import tilt_reading
from zrp.gap.fit.wellposed import Solution, prior_values, solve
from zrp.gap.model.context import Context, OrientationWeights
from zrp.gap.model.problem import Problem
from zrp.rotations import left_jacobian

__all__ = ["OrientationWeights", "alias_jacobian", "orientation_residual", "pose_rotations",
           "probe_start",
           "solve_with_orientation", "stacked"]


def pose_rotations(ctx: Context) -> F64:
    """Measured orientation per pose (its first row's quaternion, scalar first), shape
    (P, 3, 3).

    Raises:
        InputError: the measurements carry no ``qw, qx, qy, qz`` columns.
    """
    quat = ctx.meas.quat
    if quat is None:
        raise InputError("measurements: no qw, qx, qy, qz columns; full-pose identification "
                         "needs measured orientations")
    q = np.asarray(quat, dtype=float)[ctx.meas.first_row]
    return Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix()


def orientation_residual(prob: Problem, theta: ArrayLike, psi: ArrayLike, rt0: ArrayLike,
                         measured: ArrayLike) -> tuple[F64, F64]:
    """Orientation residuals (O1) and their Jacobian (O2) on the poses of ``prob``.

    Args:
        prob: the position problem (its parameters and poses).
        theta: its parameters, shape (p,); psi: probe rotation correction, rad, shape (3,).
        rt0: R_t0, shape (3, 3); measured: R_meas per pose of ``prob``, shape (S, 3, 3).

    Returns:
        e, shape (S, 3) (rad), and d e / d(theta, psi), shape (S, 3, p + 3).
    """
    theta = np.asarray(theta, dtype=float)
    psi = np.asarray(psi, dtype=float)
    ch = prob._chain(theta)
    n = prob.ctx.model.n
    rn = ch.rprev[:, n]
    rb, _ = prob.base(theta)
    rt = Rotation.from_rotvec(psi).as_matrix() @ np.asarray(rt0, dtype=float)
    pred = rb @ rn @ rt
    e = Rotation.from_matrix(pred @ np.swapaxes(np.asarray(measured), 1, 2)).as_rotvec()
    S = len(e)
    cols = np.zeros((S, 3, prob.size + 3))
    if prob.instrument:
        cols[:, :, prob.idx["rot"]] = left_jacobian(theta[prob.idx["rot"]])
    rev = ~np.asarray(prob.ctx.model.prismatic)
    if prob.idx["dq"].size:
        cols[:, :, prob.idx["dq"]] = np.einsum("ij,skj,skp->sip", rb, ch.ucur * rev[None, :,
                                                                                    None], prob.B)
    tang = prob.ctx.tangents
    for i in prob.idx["tilt"]:
        s = prob.specs[i]
        k = s.joint - 1
        if not rev[k]:
            continue
        uk = ch.u[k]
        du = (tang[k, s.comp] - uk * (uk @ tang[k, s.comp])) / np.linalg.norm(ch.v[k])
        loc = (np.sin(ch.q[:, k])[:, None] * du
               + (1.0 - np.cos(ch.q[:, k]))[:, None] * np.cross(uk, du))
        cols[:, :, i] = np.einsum("ij,sjk,sk->si", rb, ch.rprev[:, k], loc)
    cols[:, :, prob.size:] = rb @ rn @ left_jacobian(psi)
    jinv = np.linalg.inv(left_jacobian(e))
    return e, jinv @ cols



def probe_start(prob: Problem, theta: F64, measured: F64) -> F64:
    """R_t0: the rotation closest to the mean of (R_b R_n)^T R_meas over the poses."""
    n = prob.ctx.model.n
    rb, _ = prob.base(theta)
    a = np.swapaxes(rb @ prob._chain(theta).rprev[:, n], 1, 2) @ measured
    u, _, vt = np.linalg.svd(a.mean(axis=0))
    return u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt


def stacked(prob: Problem, measured: F64, rt0: F64, sigma_position: float,
            sigma_orientation: float, x: F64) -> tuple[F64, F64]:
    """The weighted residual (positions / sigma_p, then orientations / sigma_o) and its
    Jacobian in (theta, psi), shapes (3R + 3S,) and (3R + 3S, p + 3): the objective of the
    full-pose fit (module doc of :mod:`zrp.gap.fit.fullpose`)."""
    p = prob.size
    rp, jp = prob.residual_and_jacobian(x[:p])
    eo, jo = orientation_residual(prob, x[:p], x[p:], rt0, measured)
    jp = np.hstack([jp, np.zeros((jp.shape[0], 3))])
    return (np.concatenate([rp / sigma_position, eo.ravel() / sigma_orientation]),
            np.vstack([jp / sigma_position, jo.reshape(-1, p + 3) / sigma_orientation]))


def solve_with_orientation(ctx: Context, prob: Problem, theta0: F64, scales: F64
                           ) -> tuple[Solution, F64]:
    """Identify the parameters of ``prob`` from positions and orientations, each block
    weighted by its noise (``ctx.orientation``; the objective of :mod:`zrp.gap.fit.fullpose`),
    by the well-posed solver (:func:`zrp.gap.fit.wellposed.solve`), the probe rotation refined
    by psi from ``ctx.orientation.probe_rotation`` with them.

    Args:
        ctx: the context (its ``orientation`` set); prob: the position problem.
        theta0: start and prior of the registration (p,); scales: the parameters' d_j (p,).

    Returns:
        the solution in (theta, psi), shape (p + 3,), and R_t = exp([psi]) R_t0.
    """
    w = ctx.orientation
    if w is None:
        raise InputError("solve_with_orientation: the context carries no orientation weights")
    measured = pose_rotations(ctx)[prob.poses]
    rt0 = np.asarray(w.probe_rotation, dtype=float)

    def both(v: F64) -> tuple[F64, F64]:
        return stacked(prob, measured, rt0, w.sigma_position, w.sigma_orientation, v)

    names = [s.name for s in prob.specs] + ["probe.rx", "probe.ry", "probe.rz"]
    sol = solve(both, lambda v: both(v)[0], np.concatenate([theta0, np.zeros(3)]),
                np.concatenate([prior_values(prob.specs, theta0), np.zeros(3)]),
                np.concatenate([scales, np.ones(3)]), names,
                reading=tilt_reading(ctx, prob.specs, scales))
    return sol, Rotation.from_rotvec(sol.theta[prob.size:]).as_matrix() @ rt0


def alias_jacobian(ctx: Context, prob: Problem, theta: F64, jac: F64) -> tuple[F64, F64]:
    """The Jacobian that decides which parameters the data can identify: the positions' ``jac``
    (3R, p) alone, or, with ``ctx.orientation``, stacked over the orientation rows, each block
    divided by its noise (3R + 3S, p); and the probe rotation's columns (the same rows; none
    without orientations), which every full-pose fit carries beside the parameters."""
    w = ctx.orientation
    if w is None:
        return jac, np.zeros((jac.shape[0], 0))
    measured = pose_rotations(ctx)[prob.poses]
    _, jo = orientation_residual(prob, theta, np.zeros(3), w.probe_rotation, measured)
    jo = jo.reshape(-1, prob.size + 3) / w.sigma_orientation
    top = np.zeros((jac.shape[0], 3))
    return (np.vstack([jac / w.sigma_position, jo[:, :prob.size]]),
            np.vstack([top, jo[:, prob.size:]]))
