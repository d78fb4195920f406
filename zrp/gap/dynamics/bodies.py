"""Candidate effects on the model's own bodies: a modelled part that is not on the arm, and a
link whose mass or centre is off (a posture-dependent, gravity-like error on the joints
below it). Each is linear in its parameters, a block of the inertial regressor Y (eq. R2):

* ``absent_part`` (one per :class:`~zrp.gap.dynamics.arm.Attachment`, e.g. a hand): the
  torques of the part taken away, -Y_tool phi_part s, with s in [0, 1] the share of the part
  missing (eq. B1; 1: the part is not mounted, between: it is lighter). The resulting tool
  body is the model's link without (a share of) the part: physical by construction.
* ``link_mass`` (one per moving body with mass but the tool body, whose changes are the
  payload's): a point mass dm added to link b at d from its centre c_b, the payload's block
  (eq. E2) at p = c_b (eq. B2): [dm, dm d] (kg, kg m), exact in dm, first order in d, with
  m_b + dm >= 0 (a negative dm: the link is lighter). The resulting link is phi_b plus that
  point mass (eq. R1); whether it is physical (pseudo-inertia positive definite, eq. R5) is
  checked on the fitted values by the diagnosis, which drops an effect that needs a
  non-physical link.
"""

from __future__ import annotations

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.effect import Effect

__all__ = ["BODY_EFFECTS", "body_effects", "link_centre", "point_mass_columns"]

BODY_EFFECTS = ("absent_part", "link_mass")

#: A link's mass grows by at most this share of the model's (a CAD mass off by more is not
#: a link's mass off: a part the model lacks, named as a payload, or another effect).
MAX_GAIN = 1.0

#: A link whose mass columns move the torques by less than this share of the largest link's
#: is not a candidate (it cannot be seen in the log).
VISIBLE = 1e-3


def _absent_parts(arm: Arm, y_tool: F64) -> list[Effect]:
    out = []
    for part in arm.attachments:
        col = -(y_tool @ part.phi)[..., None]
        out.append(Effect("absent_part", None, col, ("share",), ("1",), np.zeros(1),
                          np.ones(1), part.name))
    return out


def point_mass_columns(y: F64, p: F64) -> F64:
    """A point mass m at p + d on a body whose regressor block is ``y`` (S, n, 10): the
    columns of [m, m d_x, m d_y, m d_z] (eq. E2), shape (S, n, 4)."""
    ym, yh = y[..., 0], y[..., 1:4]
    yi = y[..., 4:10]
    # a point mass m at p + d: phi = m [1, p + d, |p+d|^2 - (p+d)_i^2 ..., -(p+d)_i (p+d)_j]
    # to first order in d; exact in m for d = 0 (the mass column), linear in m d.
    pp = float(p @ p)
    inert_m = np.array([pp - p[0] ** 2, pp - p[1] ** 2, pp - p[2] ** 2,
                        -p[0] * p[1], -p[0] * p[2], -p[1] * p[2]])
    col_m = ym + yh @ p + yi @ inert_m
    # d(phi_I)/d(m d) at d = 0: the first moments' own columns plus the inertia's
    # linear terms 2 p.d - 2 p_i d_i (diagonal) and -(p_i d_j + d_i p_j) (off-diagonal)
    cols = [col_m]
    for a in range(3):
        e = np.zeros(3)
        e[a] = 1.0
        di = np.array([2 * p @ e - 2 * p[0] * e[0], 2 * p @ e - 2 * p[1] * e[1],
                       2 * p @ e - 2 * p[2] * e[2], -(p[0] * e[1] + e[0] * p[1]),
                       -(p[0] * e[2] + e[0] * p[2]), -(p[1] * e[2] + e[1] * p[2])])
        cols.append(yh[..., a] + yi @ di)
    return np.stack(cols, axis=-1)



def link_centre(arm: Arm, b: int) -> F64:
    """Body ``b``'s centre of mass in its frame, m (its origin when massless)."""
    phi = arm.body_params(b)
    return phi[1:4] / phi[0] if phi[0] > 0.0 else np.zeros(3)


def _link_masses(arm: Arm, y: F64, bodies: list[int]) -> list[Effect]:
    norms = [float(np.linalg.norm(y[..., 10 * i:10 * i + 4])) for i in range(len(bodies))]
    top = max(norms, default=0.0)
    out = []
    inf = np.inf
    for i, b in enumerate(bodies):
        m0 = float(arm.body_params(b)[0])
        if b == arm.tool_body or norms[i] <= VISIBLE * top or m0 <= 0.0:
            continue
        cols = point_mass_columns(y[..., 10 * i:10 * i + 10], link_centre(arm, b))
        out.append(Effect("link_mass", None, cols, ("mass", "m*dx", "m*dy", "m*dz"),
                          ("kg", "kg m", "kg m", "kg m"), np.array([-m0, -inf, -inf, -inf]),
                          np.array([MAX_GAIN * m0, inf, inf, inf]), arm.body_name(b)))
    return out


def body_effects(arm: Arm, y: F64) -> list[Effect]:
    """The body effects (module docstring) from the full regressor ``y`` of the moving
    bodies (S, n, 10 B), in :meth:`DynamicArm.moving_bodies` order."""
    bodies = arm.moving_bodies()
    out: list[Effect] = []
    if arm.tool_body in bodies:
        i = bodies.index(arm.tool_body)
        out += _absent_parts(arm, y[..., 10 * i:10 * i + 10])
    return out + _link_masses(arm, y, bodies)
