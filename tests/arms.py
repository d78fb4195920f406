"""Arms the MJCF and simulation tests share: a random serial arm from a seed, and the Table 1
PUMA with a tilted joint-2 axis and a lengthened link 3."""

from __future__ import annotations

import numpy as np

import zrp


def random_arm(seed: int, n: int = 6, unit: str = "mm", prismatic: bool = False
               ) -> zrp.Manipulator:
    """A random serial arm: random unit axes, body vectors of 50-400 mm (or the same in m)."""
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    scale = 1.0 if unit == "mm" else 1e-3
    bodies = rng.uniform(-400, 400, size=(n + 1, 3)) * scale
    ua = rng.normal(size=3)
    ua /= np.linalg.norm(ua)
    ut = np.cross(ua, rng.normal(size=3))
    ut /= np.linalg.norm(ut)
    types = ["revolute"] * n
    if prismatic:
        types[n // 2] = "prismatic"
    return zrp.Manipulator.from_arrays(axes, bodies, axial=ua, transverse=ut, types=types,
                                       name=f"random{seed}", length_unit=unit)


def perturbed_puma() -> zrp.Manipulator:
    """The Table 1 PUMA with a tilted joint-2 axis and a lengthened link 3 (as eqs 10-11)."""
    m = zrp.load_model("puma")
    axes = np.array(m.axes)
    bodies = np.array(m.bodies)
    axes[1] = np.array([1e-3, 1.0 + 1e-3, 1e-3]) / np.linalg.norm([1e-3, 1.0 + 1e-3, 1e-3])
    bodies[2] *= 1.001
    return m.with_arrays(axes=axes, bodies=bodies, name="puma perturbed")
