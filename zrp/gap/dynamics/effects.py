"""The candidate effects of the dynamic gap: each a block of regressor columns, linear in its
parameters, added to the nominal model's torques (eq. E1: tau = tau0 + sum_e Y_e theta_e).

Per joint k (column only on joint k's torque; w = qd_k):

* ``coulomb``:  tanh(w / V_EPS)                                  [N m]    (MJCF frictionloss)
* ``viscous``:  w                                                [N m s/rad] (MJCF damping)
* ``stribeck``: tanh(w / V_EPS) exp(-(w / v_s)^2), v_s in :data:`STRIBECK_SPEEDS` [N m]
* ``armature``: qdd_k                                            [kg m^2] (MJCF armature)
* ``offset``:   1 (a torque sensor's zero offset)                [N m]
* ``gain``:     tau0_k (a torque sensor's or torque constant's scale error) [1]

Per coupled motor k of a motor-side log's transmission (a motor that turns several joints,
:meth:`~zrp.gap.dynamics.transmission.Transmission.coupled_motors`; g_k its joint-scale
direction, w = g_k . qd its velocity at the scale of its own joint; the column is g_k times):

* ``motor_coulomb``:  tanh(w / V_EPS)                          [N m]
* ``motor_viscous``:  w                                        [N m s/rad]
* ``motor_armature``: g_k . qdd (the rotor's inertia r_kk^2 J_m) [kg m^2]

(A motor that turns one joint is that joint's ``coulomb``, ``viscous``, ``armature``.)

Arm-wide:

* ``payload``: a mass m at the tool point p plus its first moment m d about p (eq. E2: the
  inertial regressor of the tool body at phi = [m, m (p + d), m |p|^2 ...], by linearity of
  eq. R2 in the point mass): columns [m, m d_x, m d_y, m d_z]; [kg, kg m x3].
  A negative mass is a tool lighter than the model's (bounded by the tool body's own mass).
* ``absent_part``, ``link_mass``: a modelled part (a hand) not on the arm, a link's mass or
  centre off (:mod:`zrp.gap.dynamics.bodies`).
* ``inertial``: the identifiable combinations of all link inertial parameters (eq. R4).

Bounds keep the corrected model physical: the model's own friction, damping and armature plus
the correction stay >= 0, a Stribeck bump is >= 0, the tool body's mass with a payload >= 0,
a gain is > -1.
"""

from __future__ import annotations

import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.bodies import body_effects, point_mass_columns
from zrp.gap.dynamics.effect import Effect
from zrp.gap.dynamics.inertia import V_EPS, base_directions
from zrp.gap.dynamics.transmission import Transmission

__all__ = ["JOINT_EFFECTS", "MOTOR_EFFECTS", "STRIBECK_SPEEDS", "Effect", "candidate_effects",
           "motor_effects", "payload_columns"]

#: Stribeck speeds tried, rad/s (each a separate candidate; the diagnosis picks by data).
STRIBECK_SPEEDS = (0.03, 0.1, 0.3)

#: Relative singular value below which a base combination counts as not excited (eq. R6).
EXCITED = 1e-2

#: Smoother sign functions tried for Coulomb friction besides tanh(w / V_EPS), rad/s: a
#: friction that builds up over a few hundredths of a rad/s (lubricated gears, a
#: controller's own friction observer) is still Coulomb friction.
SOFT_SIGNS = (0.05,)

JOINT_EFFECTS = ("coulomb", "viscous", "stribeck", "armature", "offset", "gain")

#: The effects of a coupled motor (friction and rotor inertia at the motor).
MOTOR_EFFECTS = ("motor_coulomb", "motor_viscous", "motor_armature")


def _on_joint(col: F64, k: int, n: int) -> F64:
    out = np.zeros((col.shape[0], n, 1))
    out[:, k, 0] = col
    return out


def _joint_effects(arm: Arm, qd: F64, qdd: F64, tau0: F64) -> list[Effect]:
    n = arm.n
    coulomb, damping, armature = arm.joint_terms()
    out: list[Effect] = []
    inf = np.inf
    for k in range(n):
        w = qd[:, k]
        sgn = np.tanh(w / V_EPS)
        spec = [("coulomb", sgn, "N m", -float(coulomb[k]), inf, ""),
                ("viscous", w, "N m s/rad", -float(damping[k]), inf, ""),
                ("armature", qdd[:, k], "kg m^2", -float(armature[k]), inf, ""),
                ("offset", np.ones_like(w), "N m", -inf, inf, ""),
                ("gain", tau0[:, k], "1", -1.0 + 1e-6, inf, "")]
        spec += [("stribeck", sgn * np.exp(-(w / vs) ** 2), "N m", 0.0, inf, f"v_s={vs:g} rad/s")
                 for vs in STRIBECK_SPEEDS]
        spec += [("coulomb", np.tanh(w / vc), "N m", -float(coulomb[k]), inf,
                  f"v_c={vc:g} rad/s") for vc in SOFT_SIGNS]
        for name, col, unit, lo, hi, detail in spec:
            out.append(Effect(name, k, _on_joint(col, k, n), (name,), (unit,), np.array([lo]),
                              np.array([hi]), detail))
    return out


def motor_effects(transmission: Transmission | None, qd: F64, qdd: F64) -> list[Effect]:
    """The coupled motors' friction and rotor inertia (module docstring); none without a
    coupled motor."""
    if transmission is None:
        return []
    out: list[Effect] = []
    inf = np.inf
    for k, g in transmission.coupled_motors():
        w, a = qd @ g, qdd @ g
        detail = f"motor {k + 1}"
        for name, col, unit in (("motor_coulomb", np.tanh(w / V_EPS), "N m"),
                                ("motor_viscous", w, "N m s/rad"),
                                ("motor_armature", a, "kg m^2")):
            out.append(Effect(name, k, (col[:, None] * g[None, :])[..., None], (name,),
                              (unit,), np.array([0.0]), np.array([inf]), detail))
    return out


def payload_columns(arm: Arm, q: F64, qd: F64, qdd: F64) -> F64:
    """The payload block (eq. E2), shape (S, n, 4)."""
    y, _ = arm.regressor(q, qd, qdd, [arm.tool_body])
    return point_mass_columns(y, np.asarray(arm.tool_point, dtype=float))


def candidate_effects(arm: Arm, q: F64, qd: F64, qdd: F64, tau0: F64,
                      inertial: bool = True, transmission: Transmission | None = None
                      ) -> list[Effect]:
    """Every candidate effect along the states (module docstring)."""
    out = _joint_effects(arm, qd, qdd, tau0) + motor_effects(transmission, qd, qdd)
    inf = np.inf
    # a negative payload is a tool lighter than modelled: the tool body's mass stays >= 0
    tool_mass = float(arm.body_params(arm.tool_body)[0])
    out.append(Effect("payload", None, payload_columns(arm, q, qd, qdd),
                      ("mass", "m*dx", "m*dy", "m*dz"), ("kg", "kg m", "kg m", "kg m"),
                      np.array([-tool_mass, -inf, -inf, -inf]), np.full(4, inf)))
    y, _ = arm.regressor(q, qd, qdd)
    out += body_effects(arm, y)
    if inertial:
        v, scale = base_directions(arm)
        # only the combinations this log excites (eq. R6): directions of the base whose
        # singular value along the log is below EXCITED of the largest would be fitted to
        # noise (and make the links unphysical); they keep the model's values
        _, sv, wt = np.linalg.svd(((y * scale) @ v).reshape(-1, v.shape[1]),
                                  full_matrices=False)
        v = v @ wt[sv > EXCITED * sv[0]].T
        yb = (y * scale) @ v
        r = v.shape[1]
        out.append(Effect("inertial", None, yb, tuple(f"beta{i + 1}" for i in range(r)),
                          ("(scaled)",) * r, np.full(r, -inf), np.full(r, inf),
                          basis=(v, scale), full=y))
    return out


def inertial_correction(arm: Arm, beta: F64, basis: tuple[F64, F64]) -> dict[int, F64]:
    """phi_b of each moving body after the fitted base combination ``beta`` (eq. R4: the
    minimum-norm change in scaled parameters; directions the arm cannot show keep the
    model's values)."""
    v, scale = basis
    dphi = scale * (v @ beta)
    out = {}
    for i, b in enumerate(arm.moving_bodies()):
        out[b] = arm.body_params(b) + dphi[10 * i:10 * i + 10]
    return out
