"""The log-Cholesky parametrisation of a rigid body's inertial parameters (Rucker & Wensing
2022, "Smooth parameterization of rigid-body inertia", IEEE RA-L 7(2)): every real vector
theta in R^10 is a physically consistent body, and every physically consistent body (positive
definite pseudo-inertia, eq. R5 of :mod:`zrp.gap.dynamics.inertia`) is exactly one theta.

With theta = [alpha, d1, d2, d3, s12, s23, s13, t1, t2, t3] (eq. L1)::

    U = e^alpha [[e^d1, s12, s13, t1],
                 [0,    e^d2, s23, t2],
                 [0,    0,    e^d3, t3],
                 [0,    0,    0,    1 ]]

    J = U U^T                                    (eq. L2)

J is positive definite for every theta (U is triangular with a positive diagonal), and the
body's standard parameters phi (eq. R1) are read off it linearly (eq. L3)::

    m = J_44,  h = m c = J_{1:3,4},  Sigma = J_{1:3,1:3},  I = tr(Sigma) 1 - Sigma

The inverse (eq. L4): U is the "upper" Cholesky factor of J, U = P chol(P J P) P with P the
row reversal, so theta = [log U_44, log(U_ii / U_44), U_ij / U_44, U_i4 / U_44].
The Jacobian d phi / d theta (eq. L5) follows from dJ = dU U^T + U dU^T.
"""

from __future__ import annotations

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.inertia import pseudo_inertia

__all__ = ["phi_from_pseudo", "phi_from_theta", "phi_jacobian", "theta_from_phi", "upper"]

# (row, column) of U for s12, s23, s13 and t1, t2, t3 (eq. L1)
_OFF = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))


def upper(theta: F64) -> F64:
    """U of eq. L1, shape (4, 4)."""
    th = np.asarray(theta, dtype=float)
    u = np.zeros((4, 4))
    u[[0, 1, 2], [0, 1, 2]] = np.exp(th[1:4])
    u[3, 3] = 1.0
    for k, (i, j) in enumerate(_OFF):
        u[i, j] = th[4 + k]
    return np.exp(th[0]) * u


def phi_from_pseudo(j: F64) -> F64:
    """phi (eq. R1) of a pseudo-inertia J (eq. L3); linear in J."""
    sigma = j[:3, :3]
    i = np.trace(sigma) * np.eye(3) - sigma
    return np.array([j[3, 3], j[0, 3], j[1, 3], j[2, 3], i[0, 0], i[1, 1], i[2, 2], i[0, 1],
                     i[0, 2], i[1, 2]])


def phi_from_theta(theta: F64) -> F64:
    """phi of theta (eq. L1-L3): physically consistent for every theta."""
    u = upper(theta)
    return phi_from_pseudo(u @ u.T)


def phi_jacobian(theta: F64) -> F64:
    """d phi / d theta (eq. L5), shape (10, 10)."""
    u = upper(theta)
    th = np.asarray(theta, dtype=float)
    scale = np.exp(th[0])
    out = np.empty((10, 10))
    for k in range(10):
        du = np.zeros((4, 4))
        if k == 0:
            du = u
        elif k < 4:
            du[k - 1, k - 1] = scale * np.exp(th[k])
        else:
            du[_OFF[k - 4]] = scale
        out[:, k] = phi_from_pseudo(du @ u.T + u @ du.T)
    return out


def theta_from_phi(phi: F64, what: str = "body") -> F64:
    """theta of a physically consistent phi (eq. L4); InputError naming ``what`` if its
    pseudo-inertia is not positive definite (no theta gives it)."""
    flip = pseudo_inertia(np.asarray(phi, dtype=float))[::-1, ::-1]
    try:
        low = np.linalg.cholesky(flip)
    except np.linalg.LinAlgError:
        raise InputError(f"{what}: inertial parameters not physically consistent (the "
                         "pseudo-inertia is not positive definite: a mass <= 0, or principal "
                         "moments that break the triangle inequality)") from None
    u = low[::-1, ::-1]
    a = u[3, 3]
    return np.array([np.log(a), *np.log(np.diag(u)[:3] / a),
                     *(u[i, j] / a for i, j in _OFF)])
