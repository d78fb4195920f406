"""A torque log's joints matched to the model's, by name where the log names them (a ROS bag,
a ROS-style CSV header ``/joint_states/position/<joint>`` or ``position_<joint>``).

* **Named log.** Its columns are reordered to the arm's joint order (UR's driver, for one,
  publishes its joints in alphabetical order). A name the model lacks is refused by name; a
  joint the model has off the arm's chain (fingers, a head, wheels) is left out and named in
  the notes; a joint of the arm's chain the log lacks is refused by name (never silently
  fixed).
* **Unnamed log** (the zrp, libfranka, UR RTDE, KUKA forms): its columns are the arm's joints
  in order, as many as the arm has, and the notes say so, naming each.

What was matched is recorded in :attr:`~zrp.gap.dynamics.timebase.Conditioning.joints` (the
report's notes). Cost: one copy of the log's arrays.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from zrp.errors import InputError
from zrp.gap.dynamics.data import TorqueLog, excluded_notes

__all__ = ["match_joints"]


def _unnamed(log: TorqueLog, arm: list[str], option: str) -> TorqueLog:
    if log.n_joints != len(arm):
        raise InputError(f"{option}: {log.source} has {log.n_joints} joints (unnamed "
                         f"columns), but the arm has {len(arm)} ({', '.join(arm)}); name the "
                         "log's joints (a ROS header) or choose the arm's joints with "
                         "--joints or --end-link")
    note = ("the log names no joints: its columns are taken as the arm's joints in the "
            "model's order (" + ", ".join(f"{k + 1} = {nm}" for k, nm in enumerate(arm)) + ")")
    return _with_notes(log, (note,))


def _with_notes(log: TorqueLog, notes: tuple[str, ...]) -> TorqueLog:
    cond = dataclasses.replace(log.conditioning, joints=log.conditioning.joints + notes)
    return dataclasses.replace(log, conditioning=cond)


def _checked(log: TorqueLog, arm: list[str], model: set[str], option: str) -> list[str]:
    """The log's joints off the arm's chain (the model has them); the errors otherwise."""
    names = list(log.joint_names)
    unknown = [nm for nm in names if nm not in model and nm not in arm]
    if unknown:
        raise InputError(f"{option}: {log.source} names joint(s) {', '.join(unknown)} that the "
                         f"model lacks (the arm's joints: {', '.join(arm)})")
    missing = [nm for nm in arm if nm not in names]
    if missing:
        raise InputError(f"{option}: {log.source} has no joint {', '.join(missing)} of the "
                         f"arm's chain ({', '.join(arm)}; the log names {', '.join(names)}); "
                         "choose the arm's joints with --joints or --end-link")
    return [nm for nm in names if nm not in arm]


def match_joints(log: TorqueLog, arm_joints: Sequence[str], *,
                 model_joints: Sequence[str] = (), option: str = "--data") -> TorqueLog:
    """``log`` with its columns in the arm's joint order (module docstring).

    Args:
        log: the torque log (:attr:`TorqueLog.joint_names` empty: unnamed).
        arm_joints: the arm's joints (its chain), in the model's order.
        model_joints: every joint of the model, the chain's and those off it (fingers ...);
            default the arm's.
        option: the option that gave the log, for messages.

    Raises:
        InputError: a name the model lacks, a chain joint the log lacks (by name), or an
            unnamed log of another number of joints than the arm.
    """
    arm = [str(j) for j in arm_joints]
    if not log.joint_names:
        return _unnamed(log, arm, option)
    off = _checked(log, arm, set(model_joints) | set(arm), option)
    idx = [log.joint_names.index(nm) for nm in arm]
    if idx == list(range(log.n_joints)):
        return _with_notes(log, (f"the log's joints are the arm's, by name, in its order "
                                 f"({', '.join(arm)})",))
    notes = []
    if sorted(idx) != idx:
        notes.append(f"the log's joints ({', '.join(log.joint_names)}) reordered by name to the "
                     f"model's order ({', '.join(arm)})")
    if off:
        notes.append(f"left out: joint(s) {', '.join(off)} of the log, off the arm's chain "
                     "(the model has them)")
    pick = lambda a: None if a is None else np.ascontiguousarray(a[:, idx])  # noqa: E731
    unmeasured = {arm.index(log.joint_names[k]): why for k, why in log.unmeasured.items()
                  if log.joint_names[k] in arm}
    if len(unmeasured) == len(arm):
        raise InputError(f"{option}: {log.source}: no joint of the arm has torque data: "
                         + "; ".join(f"{arm[k]}: {w}" for k, w in sorted(unmeasured.items())))
    cond = dataclasses.replace(log.conditioning,
                               excluded=excluded_notes(unmeasured, tuple(arm)),
                               joints=log.conditioning.joints + tuple(notes))
    return dataclasses.replace(log, q=pick(log.q), qd=pick(log.qd), tau=pick(log.tau),
                               qc=pick(log.qc), unmeasured=unmeasured, joint_names=tuple(arm),
                               conditioning=cond)
