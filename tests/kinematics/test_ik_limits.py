"""IK that respects the robot: a 7-DOF arm's closed circle returns to its start inside its
limits (rest-posture objective in the null space), limit violations name the joint and the
time, single-pose IK, and singularities named as such. The 7-DOF arm is the Franka Panda of
example-robot-data when it is installed, else a 7-DOF model built here with its DH values."""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

import zrp
from zrp.kinematics.posture import solve_pose
from zrp.kinematics.redundant import track_posture
from zrp.testing import panda_mdh

Q_READY = np.array([0, -0.785, 0, -2.356, 0, 1.571, 0.785])


def _panda() -> zrp.Manipulator:
    try:
        import pinocchio as pin  # optional: the shipped URDF
        root = os.path.join(os.path.dirname(pin.__file__),
                            "../../../../share/example-robot-data/robots")
        f = os.path.join(root, "panda_description/urdf/panda.urdf")
        if os.path.isfile(f):
            return zrp.import_urdf(f, end_link="panda_hand").model
    except ImportError:
        pass
    return panda_mdh()


@pytest.fixture(scope="module")
def panda():
    return _panda()


def test_closed_circle_returns_to_start_within_limits(panda):
    p0 = zrp.forward_kinematics(panda, Q_READY).position
    c = zrp.Circle.from_start(p0, 150.0, [0, 0, 1], [0, 1, 0], duration=4.0)
    r = track_posture(panda, c, Q_READY, 400)
    assert np.abs(r.q[-1] - Q_READY).max() < 1e-6
    assert r.position_error.max() < 1e-9 and r.orientation_error.max() < 1e-12
    assert np.all(r.q >= panda.lower) and np.all(r.q <= panda.upper)
    # independent check of the result: FK of the solved joints lies on the circle
    p = zrp.forward_kinematics(panda, r.q).position
    assert np.abs(p - r.desired_position).max() < 1e-9
    # the minimum-norm rates (zrp.track_trajectory) do not come back: the reason for the above
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plain = zrp.track_trajectory(panda, c, Q_READY, 400, limits="ignore")
    assert np.abs(plain.q[-1] - Q_READY).max() > 1e-2


def test_path_beyond_a_limit_names_joint_and_time(panda):
    p0 = zrp.forward_kinematics(panda, Q_READY).position
    around = zrp.Circle(center=[0, 0, p0[2]], normal=[0, 0, 1], start_point=p0, duration=4.0)
    with pytest.raises(zrp.JointLimitError,
                       match=r"joint \d \(\w+\) (would )?leaves? its limits .* at t = [\d.]+ s"):
        track_posture(panda, around, Q_READY, 200)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", zrp.SingularityWarning)
        free = zrp.track_trajectory(panda, around, Q_READY, 200, task="position",
                                    limits="ignore")
        with pytest.raises(zrp.JointLimitError) as info:
            zrp.track_trajectory(panda, around, Q_READY, 200, task="position")
    over = (free.q < panda.lower) | (free.q > panda.upper)
    i, k = np.argwhere(over)[0]  # the first sample and joint out, checked independently
    assert (f"joint {k + 1} ({panda.joint_names[k]}) leaves its limits "
            f"[{panda.lower[k]:.6g}, {panda.upper[k]:.6g}] rad at t = {free.t[i]:.6g} s"
            ) in str(info.value)


def test_single_pose_ik_within_limits(panda):
    rng = np.random.default_rng(3)
    for _ in range(5):
        qt = np.clip(Q_READY + rng.uniform(-0.4, 0.4, 7), panda.lower, panda.upper)
        p, er = zrp.end_effector_pose(panda, qt)
        s = solve_pose(panda, p, er, q0=Q_READY)
        p2, er2 = zrp.end_effector_pose(panda, s.q)
        assert np.abs(p2 - p).max() < 1e-9
        rot = zrp.rotations
        assert rot.er_angle(rot.er_multiply(er2, rot.er_conjugate(er))) < 1e-9
        assert np.all(s.q >= panda.lower) and np.all(s.q <= panda.upper)


def _two_link():
    return zrp.Manipulator.from_arrays([[0, 0, 1], [0, 0, 1]],
                                       [[0, 0, 0], [100, 0, 0], [100, 0, 0]],
                                       axial=[0, 0, 1], transverse=[0, 1, 0])


def test_singularity_is_named_not_outside_the_workspace():
    two = _two_link()  # stretched at q = 0: the point 150 mm out is reachable, J is singular
    with pytest.raises(zrp.SingularityError, match=r"within reach \(150 of 200 mm\).*singularity"):
        solve_pose(two, [150, 0, 0], q0=[0, 0])
    line = zrp.Line([200, 0, 0], [120, 0, 0], duration=1.0)
    with pytest.raises(zrp.SingularityError, match=r"at t = [\d.]+ s.*within reach.*singularity"):
        track_posture(two, line, [0, 0], 100)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(zrp.SingularityError, match=r"within reach.*singularity"):
            zrp.track_trajectory(two, line, [0, 0], 100)
    with pytest.raises(zrp.UnreachableError, match="beyond the arm's reach"):
        solve_pose(two, [250, 0, 0], q0=[0.1, 0.2])
