"""Helpers for tests and benchmarks: random serial arms."""

from __future__ import annotations

import numpy as np

from zrp.model.manipulator import Manipulator

__all__ = ["random_arm"]


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
