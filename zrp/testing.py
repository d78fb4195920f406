"""Helpers for tests and benchmarks: random serial arms, a 7-axis reference arm."""

from __future__ import annotations

import numpy as np

from zrp.model.dh import from_mdh
from zrp.model.manipulator import Manipulator

__all__ = ["PANDA_LIMITS", "panda_mdh", "random_arm"]

#: The Franka Panda's published joint limits, rad, shape (7, 2).
PANDA_LIMITS = ((-2.8973, 2.8973), (-1.7628, 1.7628), (-2.8973, 2.8973), (-3.0718, -0.0698),
                (-2.8973, 2.8973), (-0.0175, 3.7525), (-2.8973, 2.8973))


def panda_mdh() -> Manipulator:
    """The Franka Panda from its published modified-DH table (mm; tool: flange + hand), with
    :data:`PANDA_LIMITS`: a 7-axis arm that needs no robot-description package."""
    rows = [(0, 0, 333, 0), (0, -np.pi / 2, 0, 0), (0, np.pi / 2, 316, 0),
            (82.5, np.pi / 2, 0, 0), (-82.5, -np.pi / 2, 384, 0), (0, np.pi / 2, 0, 0),
            (88, np.pi / 2, 0, 0)]
    tool = np.eye(4)
    tool[2, 3] = 107 + 103.4
    m = from_mdh(rows, tool=tool)
    return Manipulator.from_arrays(
        m.axes, m.bodies, axial=m.end_effector.axial, transverse=m.end_effector.transverse,
        limits=PANDA_LIMITS)


def random_arm(rng: np.random.Generator, n: int, p_prismatic: float = 0.0,
               scale: float = 300.0) -> Manipulator:
    """A random ``n``-joint arm: random unit axes and body vectors of about ``scale`` length
    units (normal components), each joint prismatic with probability ``p_prismatic``."""
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    bodies = rng.normal(size=(n + 1, 3)) * scale
    ua = rng.normal(size=3)
    ua /= np.linalg.norm(ua)
    ut = np.cross(ua, rng.normal(size=3))
    ut /= np.linalg.norm(ut)
    types = ["prismatic" if rng.random() < p_prismatic else "revolute" for _ in range(n)]
    return Manipulator.from_arrays(axes, bodies, axial=ua, transverse=ut, types=types,
                                   name=f"random {n}-joint arm")
