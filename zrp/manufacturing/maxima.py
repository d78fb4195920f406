"""Per-robot maxima along a nominal trajectory: the exact (nonlinear) ones from the compiled
kernel (:mod:`zrp.manufacturing._mc_kernels`) and the first-order model's, for given parameter
steps. The building blocks of :mod:`.population` and :mod:`.chunks`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.forward import check_q, end_effector_pose
from zrp.kinematics.identification import perturbed_arrays
from zrp.manufacturing import _mc_kernels as MK
from zrp.model.manipulator import Manipulator

__all__ = ["first_order_max", "nonlinear_maxima", "trajectory_arrays"]



def trajectory_arrays(model: Manipulator, q: ArrayLike) -> tuple[F64, F64, F64, F64, F64]:
    """The Monte Carlo kernel's view of a nominal joint trajectory q, shape (T, n):
    (q, cos(q/2), sin(q/2), nominal p, nominal E), each C-contiguous."""
    q = check_q(model, q)
    if q.ndim != 2:
        raise InputError(f"q: expected a joint trajectory of shape (T, {model.n}), got {q.shape}")
    q = np.ascontiguousarray(q, dtype=float)
    pd, ed = end_effector_pose(model, q)
    return (q, np.ascontiguousarray(np.cos(0.5 * q)), np.ascontiguousarray(np.sin(0.5 * q)),
            np.ascontiguousarray(pd), np.ascontiguousarray(ed))


def nonlinear_maxima(model: Manipulator, arrays: tuple[F64, F64, F64, F64, F64], dx: F64,
                     joint_offsets: bool) -> tuple[F64, F64]:
    """Exact per-robot maxima along the trajectory for parameter steps ``dx`` (N, P):
    max_t delta_p (length unit) and max_t error angle (rad), each shape (N,)."""
    q, ch, sh, pd, ed = arrays
    axes, bodies, off = perturbed_arrays(model, dx, joint_offsets=joint_offsets)
    n_r = dx.shape[0]
    out_dp = np.empty(n_r)
    out_s = np.empty(n_r)
    tr = np.ascontiguousarray  # the kernel reads the path joint-major: (n, T), (3, T), (4, T)
    MK.mc_max_deviation(tr(ch.T), tr(sh.T), tr(q.T), tr(axes), tr(bodies),
                        np.array(model.prismatic, dtype=np.bool_), tr(off),
                        bool(joint_offsets), tr(pd.T), tr(ed.T), out_dp, out_s)
    return out_dp, 2.0 * np.arcsin(np.minimum(out_s, 1.0))


def first_order_max(jac: ArrayLike, dx: ArrayLike) -> tuple[F64, F64]:
    """First-order per-robot maxima: max_t ||J_p(t) dx|| and max_t ||J_r(t) dx||.

    Args:
        jac: identification Jacobian along the trajectory, shape (T, 6, P) (rows 0-2
            rotation, 3-5 position).
        dx: parameter steps, shape (N, P).

    Returns:
        max delta_p (length unit) and max angle (rad), each shape (N,).
    """
    jac = np.ascontiguousarray(jac, dtype=float)
    dx = np.asarray(dx, dtype=float)
    if jac.ndim != 3 or jac.shape[1] != 6 or dx.ndim != 2 or dx.shape[1] != jac.shape[2]:
        raise InputError(f"jac, dx: expected shapes (T, 6, P) and (N, P), got {jac.shape} "
                         f"and {dx.shape}")
    n, b = dx.shape[0], MK.FO_BLOCK
    dxt = np.zeros((dx.shape[1], -(-n // b) * b))  # robots last, padded to whole blocks
    dxt[:, :n] = dx.T
    out_p = np.empty(n)
    out_r = np.empty(n)
    MK.first_order_maxima(jac, dxt, out_p, out_r)
    return out_p, out_r
