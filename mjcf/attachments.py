"""The parts an arm model carries rigidly on its last link (a hand and its fingers, a tool, a
flange with mass), each lumped into one set of inertial parameters in the tool body's frame
(:class:`zrp.gap.dynamics.arm.Attachment`), so that the dynamic gap can say that a modelled
part is not on the real arm.

The model is compiled once as it is (no static bodies fused) at qpos = 0. Every body welded to
the last joint's body and below it in the tree belongs to a part; a part is named by its first
link with mass below the tool body (walking down through massless links with one child, e.g.
a URDF's ``panda_link8`` flange frame to ``panda_hand``), and lumps that link's subtree. With
world-frame centres x_i, inertia tensors about the centres I_i and the tool body's pose
(R_t, p_t), each piece's centre in the tool frame is c_i = R_t^T (x_i - p_t) and (eq. A1)::

    phi = sum_i [m_i, m_i c_i, I_o]   with   I_o = R_t^T I_i R_t + m_i (|c_i|^2 E - c_i c_i^T)

(the inertia about the tool body's origin, in its axes: the layout of eq. R1).
"""

from __future__ import annotations

import mujoco
import numpy as np

from zrp.arrays import F64
from zrp.gap.dynamics.arm import Attachment
from zrp.gap.dynamics.inertia import skew2

__all__ = ["find_attachments"]

#: A part lighter than this (kg) is not worth naming (a massless frame, a sensor housing).
MIN_PART_KG = 0.02


def _phi_in(m: mujoco.MjModel, d: mujoco.MjData, b: int, tool: int) -> F64:
    """phi of body ``b`` in the frame of body ``tool`` (eq. A1)."""
    mass = float(m.body_mass[b])
    rt = d.xmat[tool].reshape(3, 3)
    c = rt.T @ (d.xipos[b] - d.xpos[tool])
    ri = d.ximat[b].reshape(3, 3)
    ic = rt.T @ (ri @ np.diag(m.body_inertia[b]) @ ri.T) @ rt
    io = ic + mass * skew2(c)
    return np.array([mass, *(mass * c), io[0, 0], io[1, 1], io[2, 2], io[0, 1], io[0, 2],
                     io[1, 2]])


def _subtree(m: mujoco.MjModel, root: int) -> list[int]:
    out = [root]
    for b in range(root + 1, m.nbody):
        if int(m.body_parentid[b]) in out:
            out.append(b)
    return out


def _children(m: mujoco.MjModel, b: int) -> list[int]:
    return [c for c in range(b + 1, m.nbody) if int(m.body_parentid[c]) == b]


def _part_root(m: mujoco.MjModel, b: int) -> int:
    """Down from ``b`` through massless links with one child, to the first with mass."""
    while m.body_mass[b] <= 0.0:
        kids = _children(m, b)
        if len(kids) != 1:
            break
        b = kids[0]
    return b


def _name(m: mujoco.MjModel, b: int) -> str:
    return mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) or f"body {b}"


def _tool(m: mujoco.MjModel, tool_site: str | None) -> int:
    """The moving body that carries the tool: the last joint's body, or the body the site
    ``tool_site`` is welded to."""
    if tool_site is not None:
        sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, tool_site)
        if sid >= 0:
            return int(m.body_weldid[int(m.site_bodyid[sid])])
    return int(m.jnt_bodyid[m.njnt - 1]) if m.njnt else -1


def find_attachments(spec: mujoco.MjSpec, tool_site: str | None = None
                     ) -> tuple[Attachment, ...]:
    """The parts welded below the tool's body of ``spec`` (module docstring; call it before
    the spec is compiled with static bodies fused), heaviest first; empty when the model
    carries none (or cannot be compiled unfused)."""
    unfused = spec.copy()
    unfused.compiler.fusestatic = False
    try:
        m = unfused.compile()
    except ValueError:
        return ()
    tool = _tool(m, tool_site)
    if tool <= 0:
        return ()
    d = mujoco.MjData(m)
    mujoco.mj_kinematics(m, d)
    welded = int(m.body_weldid[tool])
    parts = []
    for child in _children(m, tool):
        if int(m.body_weldid[child]) != welded:
            continue  # a moving child (another joint): not a rigid part
        root = _part_root(m, child)
        members = [b for b in _subtree(m, child) if int(m.body_weldid[b]) == welded]
        phi = sum((_phi_in(m, d, b, tool) for b in members), np.zeros(10))
        if phi[0] >= MIN_PART_KG:
            names = tuple(_name(m, b) for b in members if m.body_mass[b] > 0.0)
            parts.append(Attachment(_name(m, root), phi, names))
    return tuple(sorted(parts, key=lambda a: -a.mass))
