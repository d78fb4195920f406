"""The largest joint torque (force, for slides) an MJCF model can deliver, from every limit it
states (issue 41 finding 1):

- the joint's own ``actuatorfrcrange`` (a URDF's ``<limit effort=>`` lands there);
- each actuator on the joint (transmission ``joint`` or ``jointinparent``): its
  ``forcerange`` times ``|gear|``; for a motor (fixed gain, no bias, no activation dynamics)
  also its ``ctrlrange`` times ``|gain|`` times ``|gear|`` (a motor whose control is capped
  cannot push harder); with activation dynamics, its ``actrange`` in place of the control's.

The actuators on one joint add up; the joint's own range caps the sum. A joint with no stated
limit has none (inf). Where a limit comes from is returned in words for the command file.
"""

from __future__ import annotations

import mujoco
import numpy as np

from zrp.arrays import F64

__all__ = ["actuator_torque_limits"]

_JOINT_TRN = (int(mujoco.mjtTrn.mjTRN_JOINT), int(mujoco.mjtTrn.mjTRN_JOINTINPARENT))


def _actuator_cap(m: mujoco.MjModel, a: int) -> tuple[float, str]:
    """The largest |force| actuator ``a`` applies, before its gear, and what says so."""
    cap, why = np.inf, ""
    if m.actuator_forcelimited[a]:
        cap, why = float(np.abs(m.actuator_forcerange[a]).max()), "forcerange"
    motor = (int(m.actuator_gaintype[a]) == int(mujoco.mjtGain.mjGAIN_FIXED)
             and int(m.actuator_biastype[a]) == int(mujoco.mjtBias.mjBIAS_NONE))
    if not motor:
        return cap, why
    if int(m.actuator_dyntype[a]) == int(mujoco.mjtDyn.mjDYN_NONE):
        limited, rng, name = m.actuator_ctrllimited[a], m.actuator_ctrlrange[a], "ctrlrange"
    else:
        limited, rng, name = m.actuator_actlimited[a], m.actuator_actrange[a], "actrange"
    if limited:
        by_ctrl = abs(float(m.actuator_gainprm[a, 0])) * float(np.abs(rng).max())
        if by_ctrl < cap:
            cap, why = by_ctrl, f"{name} x gain"
    return cap, why


def actuator_torque_limits(m: mujoco.MjModel) -> tuple[F64, list[str]]:
    """Per dof (one hinge/slide joint each, the arm's order): the largest |torque| the model
    states, inf where none, and the source of each ("" where none)."""
    n = int(m.njnt)
    joint = np.full(n, np.inf)
    src = [""] * n
    for k in range(n):
        if m.jnt_actfrclimited[k]:
            joint[k] = float(np.abs(m.jnt_actfrcrange[k]).max())
            src[k] = "joint actuatorfrcrange"
    total, count = np.zeros(n), np.zeros(n, dtype=int)
    why: list[list[str]] = [[] for _ in range(n)]
    for a in range(int(m.nu)):
        if int(m.actuator_trntype[a]) not in _JOINT_TRN:
            continue
        k = int(m.actuator_trnid[a, 0])
        if not 0 <= k < n:
            continue
        cap, what = _actuator_cap(m, a)
        total[k] += cap * abs(float(m.actuator_gear[a, 0]))
        count[k] += 1
        why[k].append(what)
    out = joint.copy()
    for k in range(n):
        if count[k] and np.isfinite(total[k]) and total[k] < out[k]:
            out[k] = total[k]
            name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, k) or f"joint {k + 1}"
            src[k] = f"actuator {' + '.join(sorted(set(why[k])))} x gear on {name}"
    return out, src
