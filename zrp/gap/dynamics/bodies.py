"""Candidate effects on the model's own bodies: a modelled part that is not on the arm, and a
link whose mass or centre is off (a posture-dependent, gravity-like error on the joints
below it). Each is linear in its parameters, a block of the inertial regressor Y (eq. R2):

* ``absent_part`` (one per :class:`~zrp.gap.dynamics.arm.Attachment`, e.g. a hand): the
  torques of the part taken away, -Y_tool phi_part s, with s in [0, 1] the share of the part
  missing (eq. B1; 1: the part is not mounted, between: it is lighter). The resulting tool
  body is the model's link without (a share of) the part: physical by construction.
* ``link_mass`` (one per moving body but the tool body, whose changes are the payload's):
  the change of link b's mass and first moment, Y_b[:, :, 0:4] [dm, d(m c)] (eq. B2), with
  m_b + dm >= 0. Its inertia about the body origin is kept, so the effect is the gravity and
  the translational inertia of a link whose mass or centre is off. Whether the resulting
  link is physical (pseudo-inertia positive definite, eq. R5) is checked on the fitted
  values by the diagnosis, which drops an effect that needs a non-physical link.
"""

from __future__ import annotations

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.effect import Effect

__all__ = ["BODY_EFFECTS", "body_effects"]

BODY_EFFECTS = ("absent_part", "link_mass")

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


def _link_masses(arm: Arm, y: F64, bodies: list[int]) -> list[Effect]:
    norms = [float(np.linalg.norm(y[..., 10 * i:10 * i + 4])) for i in range(len(bodies))]
    top = max(norms, default=0.0)
    out = []
    inf = np.inf
    for i, b in enumerate(bodies):
        if b == arm.tool_body or norms[i] <= VISIBLE * top:
            continue
        m0 = float(arm.body_params(b)[0])
        out.append(Effect("link_mass", None, y[..., 10 * i:10 * i + 4],
                          ("mass", "m*cx", "m*cy", "m*cz"), ("kg", "kg m", "kg m", "kg m"),
                          np.array([-m0, -inf, -inf, -inf]), np.full(4, inf),
                          arm.body_name(b)))
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
