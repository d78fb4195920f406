"""The post-hoc repair the physical fit replaced (sim/dynamics/feasible.py before the
log-Cholesky fit), kept here only as the reference it is compared against: physically
consistent link inertias with the identified base combinations kept.

The fit fixes only the identifiable combinations V^T dphi_s = beta (eq. R4, dphi_s: the change
of the scaled parameters); the rest of dphi_s (the null space N of V^T) the log cannot see and
is free. The minimum-norm choice (N z = 0) can leave a link with a non-physical pseudo-inertia
(eq. R5); then z is chosen to make every link physical (eq. H1)::

    min_z |z|^2  subject to  lambda_min(J_b(phi(z))) >= eps_b  for every link b

(eps_b: 1e-6 of the link's mass; SLSQP) -- the torques the log shows do not change. Only
if no such z is found is the correction shrunk toward the model's
(feasible) values, and the diagnosis says by how much.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import null_space
from scipy.optimize import minimize

from mjcf.arm import Arm
from mjcf.inverse import body_params
from zrp.arrays import F64
from zrp.gap.dynamics.inertia import pseudo_inertia_min

__all__ = ["feasible_inertias"]


def _phis(arm: Arm, dphi: F64) -> dict[int, F64]:
    return {b: body_params(arm.model, b) + dphi[10 * i:10 * i + 10]
            for i, b in enumerate(arm.moving_bodies())}


def _violation(phis: dict[int, F64]) -> float:
    out = 0.0
    for phi in phis.values():
        eps = 1e-6 * max(abs(phi[0]), 1e-3)
        out += max(0.0, eps - pseudo_inertia_min(phi)) ** 2 / eps**2
    return out


def feasible_inertias(arm: Arm, beta: F64, basis: tuple[F64, F64]
                      ) -> tuple[bool, float, dict[int, F64]]:
    """(minimum-norm correction was physical, shrink factor applied (1: none), phi per body)."""
    v, scale = basis
    base = scale * (v @ beta)
    phis = _phis(arm, base)
    if _violation(phis) == 0.0:
        return True, 1.0, phis
    free = null_space(v.T)
    free = free[:, np.any(np.abs(scale[:, None] * free) > 0, axis=0)]

    bodies = list(phis)

    def margins(z: F64) -> F64:
        p = _phis(arm, base + scale * (free @ z))
        return np.array([pseudo_inertia_min(p[b]) - 1e-6 * max(abs(p[b][0]), 1e-3)
                         for b in bodies])

    res = minimize(lambda z: float(z @ z), np.zeros(free.shape[1]), method="SLSQP",
                   jac=lambda z: 2.0 * z, constraints=[{"type": "ineq", "fun": margins}],
                   options={"maxiter": 300, "ftol": 1e-12})
    phis = _phis(arm, base + scale * (free @ res.x))
    if _violation(phis) == 0.0:
        return False, 1.0, phis
    lo, hi = 0.0, 1.0
    for _ in range(30):
        mid = 0.5 * (lo + hi)
        if _violation(_phis(arm, mid * base)) == 0.0:
            lo = mid
        else:
            hi = mid
    return False, lo, _phis(arm, lo * base)
