"""The regression benchmark's data sets: small simulated sets that look like real ones.

Each set is a function of a size factor only (seeded: the same call gives the same data), so
the benchmark (``bench_regression.py``) and its check (tests/contracts/test_regression_benchmark.py)
measure the same thing. The sets are the cases that slid back or are easy to lose:

* ``payloads_compliance``: a 7-axis arm (KUKA iiwa 7 geometry) measured at three payloads
  (0, 1.25, 2.5 kg) with a compliant joint 2: the deflection is the MuJoCo arm's own static
  gravity torque (distributed link inertias, :meth:`sim.robot.real.RealRobot.static_torque`,
  not the diagnosis's lumped masses) times the compliance (issue 34).
* ``payloads_lookalikes``: the same arm at the same payloads with what made the real case
  hard (issue 34): joint 2's compliance smaller (a few tenths of a mm at the tool), smaller
  ones on joints 4 and 6 (near-collinear compliance terms), a cyclic error of joint 2 (a
  look-alike of its gravity torque), an encoder scale, joint offsets, body errors and a tilt,
  a tracker's 0.05 mm noise.
* ``probe_6d``: a PUMA with a 6-D probe (positions and orientations) and an axis tilt that
  positions alone see weakly, plus a joint offset.
* ``near_collinear``: the Panda over a narrow range around a home pose (offset, encoder scale
  and cyclic error of the same joint nearly collinear).
* ``parallel_axes``: a UR10 (three parallel axes) with tilts of the parallel axes, body
  errors and joint offsets.
* ``few_poses``: a PUMA with 30 poses, a joint offset and a cyclic error.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from scipy.spatial.transform import Rotation

import zrp
from tests.measured import full_pose_measurements
from zrp.gap import Injection, Measurements, synthesize
from zrp.kinematics import uniform_joint_values
from zrp.rotations import matrix_from_rotvec
from zrp.testing import panda_mdh

__all__ = ["IIWA_LIMITS", "LOOKALIKES", "SETS", "iiwa_mdh", "payload_compliance_set", "ur10_dh"]

#: KUKA LBR iiwa 7 R800 joint limits (deg in the datasheet), rad.
IIWA_LIMITS = tuple((-lim, lim) for lim in np.radians([170, 120, 170, 120, 170, 120, 175]))


def iiwa_mdh() -> zrp.Manipulator:
    """The KUKA LBR iiwa 7 R800 from its modified-DH table (mm), flange + 60 mm tool."""
    rows = [(0, 0, 340, 0), (0, -np.pi / 2, 0, 0), (0, np.pi / 2, 400, 0),
            (0, np.pi / 2, 0, 0), (0, -np.pi / 2, 400, 0), (0, -np.pi / 2, 0, 0),
            (0, np.pi / 2, 0, 0)]
    tool = np.eye(4)
    tool[2, 3] = 126.0 + 60.0
    m = zrp.from_mdh(rows, tool=tool)
    return zrp.Manipulator.from_arrays(m.axes, m.bodies, axial=m.end_effector.axial,
                                       transverse=m.end_effector.transverse,
                                       limits=IIWA_LIMITS, name="iiwa 7 (datasheet)")


def ur10_dh() -> zrp.Manipulator:
    """The UR10 from its published DH table (mm): joints 2, 3 and 4 parallel."""
    rows = [(127.3, 0, 0, np.pi / 2), (0, 0, -612.0, 0), (0, 0, -572.3, 0),
            (163.941, 0, 0, np.pi / 2), (115.7, 0, 0, -np.pi / 2), (92.2, 0, 0, 0)]
    return zrp.from_dh(rows, name="UR10 (DH)")


def payload_compliance_set(n_per_payload: int = 200, seed: int = 1, sigma: float = 0.1,
                           compliance: float = 2e-5,
                           payloads: tuple[float, ...] = (0.0, 1.25, 2.5),
                           hidden: Mapping[str, Any] | None = None
                           ) -> tuple[zrp.Manipulator, Measurements]:
    """The iiwa at each payload: commanded q uniform within the limits (0.1 rad inside), the
    link angles q + offset - c tau(link angles) (the static deflection of a servo of
    stiffness 1/c, three fixed-point passes), the tool points of the MuJoCo arm's true
    geometry with ``sigma`` mm noise, in an instrument frame; a ``load`` column in kg.
    ``compliance``: joint 2's (rad/(N m)); ``hidden``: more :class:`sim.robot.effects.
    HiddenEffects` (its ``joint_compliance`` adds other joints'; default: joint 3's offset
    of 0.5 mrad only)."""
    from sim.robot.effects import HiddenEffects
    from sim.robot.real import RealRobot

    arm = iiwa_mdh()
    rng = np.random.default_rng(seed)
    lo, hi = np.array(IIWA_LIMITS).T
    rb, tb = matrix_from_rotvec([0.02, -0.01, 0.8]), np.array([1500.0, -300.0, 200.0])
    effects = dict(hidden) if hidden is not None else {"joint_offset": {3: 5e-4}}
    effects["joint_compliance"] = {**effects.get("joint_compliance", {}), 2: compliance}
    c = np.zeros(arm.n)
    for k, v in effects["joint_compliance"].items():
        c[k - 1] = v
    parts = []
    for i, w in enumerate(payloads):
        with warnings.catch_warnings():  # the announced fallback inertias (rods)
            warnings.simplefilter("ignore")
            robot = RealRobot(arm, HiddenEffects(**effects, payload=w))
        q = rng.uniform(lo + 0.1, hi - 0.1, size=(n_per_payload, arm.n))
        qm = robot.motor_target(q)
        ql = qm.copy()
        for _ in range(3):
            ql = qm - c * robot.static_torque(ql)
        pts = robot.kinematic_points(ql) @ rb.T + tb
        pts = pts + rng.normal(scale=sigma, size=pts.shape)
        m = pts.shape[1]
        parts.append((np.repeat([f"w{i}p{k}" for k in range(n_per_payload)], m),
                      np.repeat(q, m, axis=0), pts.reshape(-1, 3),
                      np.tile([f"s{j + 1}" for j in range(m)], n_per_payload),
                      np.full(n_per_payload * m, w)))
    pose, qq, xyz, point, load = (np.concatenate(col) for col in zip(*parts, strict=True))
    return arm, Measurements.from_arrays(pose, qq, xyz, point=point, load=load)


def _payloads(size: float) -> tuple[zrp.Manipulator, Measurements]:
    return payload_compliance_set(max(int(200 * size), 40))


#: the hidden effects of ``payloads_lookalikes`` besides joint 2's compliance (1e-5 rad/(N m)).
LOOKALIKES: dict[str, Any] = {
    "joint_compliance": {4: 4e-6, 6: 2e-6},
    "joint_offset": {2: 3e-4, 3: 5e-4, 5: -4e-4},
    "encoder_scale": {4: 5e-4},
    "cyclic_error": {2: (1, 2e-4, 1e-4)},
    "link_length": {3: (0.1, -0.05, 0.08), 5: (-0.06, 0.1, 0.0)},
    "axis_misalignment": {4: (2e-4, -1e-4)},
}


def _payloads_lookalikes(size: float) -> tuple[zrp.Manipulator, Measurements]:
    return payload_compliance_set(max(int(200 * size), 40), seed=2, sigma=0.05,
                                  compliance=1e-5, hidden=LOOKALIKES)


def _probe_6d(size: float) -> tuple[zrp.Manipulator, Measurements]:
    puma = zrp.load_model("puma")
    m = full_pose_measurements(puma, max(int(200 * size), 40), 6, tilt=(6, 0, 1e-3),
                               tools=[[3.0, 0.0, 127.0]],
                               probe_rotation=Rotation.from_rotvec([0.3, -0.2, 0.1]).as_matrix(),
                               sigma_orientation=5e-5, joint_offset={2: 1e-3})
    return puma, m


def _near_collinear(size: float) -> tuple[zrp.Manipulator, Measurements]:
    panda = panda_mdh()
    rng = np.random.default_rng(7)
    home = np.array([0.0, 0.3, 0.0, -1.8, 0.0, 1.9, 0.8])
    q = home + rng.uniform(-0.35, 0.35, size=(max(int(160 * size), 40), 7))
    inj = Injection(joint_offset={4: 1e-3, 2: -6e-4}, encoder_scale={4: 2e-3},
                    cyclic_error={6: (1, 5e-4, -3e-4)})
    return panda, synthesize(panda, q, inj, rng=rng, noise_sigma=0.02)


def _parallel_axes(size: float) -> tuple[zrp.Manipulator, Measurements]:
    ur = ur10_dh()
    rng = np.random.default_rng(8)
    q = uniform_joint_values(ur, max(int(200 * size), 40), rng)
    inj = Injection(tilt={2: (5e-4, -3e-4), 3: (4e-4, 2e-4)}, link={3: (0.3, -0.2, 0.1)},
                    joint_offset={2: 8e-4, 4: -5e-4}, encoder_scale={3: 1e-3})
    return ur, synthesize(ur, q, inj, rng=rng, noise_sigma=0.03)


def _few_poses(size: float) -> tuple[zrp.Manipulator, Measurements]:
    puma = zrp.load_model("puma")
    rng = np.random.default_rng(9)
    q = uniform_joint_values(puma, 30, rng)
    inj = Injection(joint_offset={2: 1e-3}, cyclic_error={3: (2, 6e-4, 3e-4)})
    return puma, synthesize(puma, q, inj, rng=rng, noise_sigma=0.02)


#: name -> (what it is, builder(size) -> (nominal model, measurements)); size 1: the
#: reference sizes (the few-poses set keeps its 30 poses at every size).
SETS: dict[str, tuple[str, Callable[[float], tuple[zrp.Manipulator, Measurements]]]] = {
    "payloads_compliance": ("iiwa 7, 3 payloads, compliant joint 2 (MuJoCo torques)",
                            _payloads),
    "payloads_lookalikes": ("iiwa 7, 3 payloads, compliant joints 2/4/6, cyclic/scale "
                            "look-alikes, geometry", _payloads_lookalikes),
    "probe_6d": ("PUMA, 6-D probe, weakly seen axis tilt + offset", _probe_6d),
    "near_collinear": ("Panda, narrow range: offset/scale/cyclic near-collinear",
                       _near_collinear),
    "parallel_axes": ("UR10, tilts of its parallel axes, body and offset errors",
                      _parallel_axes),
    "few_poses": ("PUMA, 30 poses, offset + cyclic error", _few_poses),
}
