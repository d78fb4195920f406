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


# ---- real arms as shipped (example-robot-data, the Menagerie UR5e) -------------------------

#: name -> (file under example-robot-data's robots folder, end link or None: the deepest)
SHIPPED_URDFS = {
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "tool0"),
    "ur10": ("ur_description/urdf/ur10_robot.urdf", "tool0"),
    "panda": ("panda_description/urdf/panda.urdf", "panda_hand"),
    "xarm7": ("xarm_description/urdf/xarm7.urdf", None),
    "kinova": ("kinova_description/robots/kinova.urdf", None),
    "z1": ("z1_description/urdf/z1.urdf", "link06"),
}


def erd_root():
    """example-robot-data's robots folder (installed beside Pinocchio), or skip the test."""
    import pytest

    from mjcf.shipped import example_robot_data_root

    pytest.importorskip("pinocchio", reason="optional: pip install pin")
    root = example_robot_data_root()
    if root is None:
        pytest.skip("optional: pip install example-robot-data")
    return root


def shipped_arm(name: str):
    """(the shipped URDF's path, its ZRP model in mm) of :data:`SHIPPED_URDFS` ``name``."""
    rel, end = SHIPPED_URDFS[name]
    path = erd_root() / rel
    return path, zrp.import_urdf(path, end_link=end).model
