"""zrp verify rebuilds the robot a measurement ran on, with the arm's own file: the truth file
names it and records its SHA-256 (hashlib of the bytes, independently), the rebuilt robot has
the same servo gains and static torques, and a file gone or changed is a named error. The
robot in motion (measure --stream --mjcf) is built from the same file."""

from __future__ import annotations

import hashlib
import shutil

import numpy as np
import pytest

import mjcf
from sim.robot.instrument import Instrument
from sim.robot.mass import DynamicsFallbackWarning
from sim.robot.model import RealRobotOptions
from sim.robot.motion import MotionEffects, execute_trajectory
from sim.robot.real import RealRobot
from sim.studies.verify import ArmFileError, arm_options
from tests.arms import shipped_arm
from zrp.gap.motion.paths import exercise_moves
from zrp.kinematics import reachable_poses


def test_the_truth_names_the_arm_file_and_rebuilds_the_same_robot(tmp_path):
    src, model = shipped_arm("ur5")
    path = tmp_path / "ur_description" / "urdf" / "ur5_robot.urdf"
    shutil.copytree(src.parents[1], tmp_path / "ur_description")
    robot = RealRobot(model, None, RealRobotOptions(dynamics=mjcf.arm_dynamics(path, model)))
    build = robot.describe()
    assert build["arm_file"] == str(path.resolve())
    assert build["arm_sha256"] == hashlib.sha256(path.read_bytes()).hexdigest()
    again = RealRobot(model, None, arm_options(model, build, field="--truth"))
    assert again.describe()["servo_kp_Nm_per_rad"] == build["servo_kp_Nm_per_rad"]
    q = reachable_poses(model, 5, np.random.default_rng(2))
    np.testing.assert_allclose(again.static_torque(q), robot.static_torque(q), rtol=0,
                               atol=1e-12)
    with pytest.warns(DynamicsFallbackWarning):  # no file of its own: nothing to read again
        assert arm_options(model, RealRobot(model).describe()) is None

    path.write_text(path.read_text() + "\n<!-- edited -->\n")
    with pytest.raises(ArmFileError, match=r"--truth: .*changed since the measurement"):
        arm_options(model, build, field="--truth")
    path.unlink()
    with pytest.raises(ArmFileError, match=r"--truth: .*gone"):
        arm_options(model, build, field="--truth")


def test_the_robot_in_motion_is_the_arm_itself():
    """measure --stream --mjcf: the moving robot has the file's dynamics and says so."""
    path, model = shipped_arm("ur5")
    dyn = mjcf.arm_dynamics(path, model)
    mv = exercise_moves(np.radians([0, -60, 60, 0, 60, 0]), np.random.default_rng(1), moves=1)
    run = execute_trajectory(model, mv, 0.2, MotionEffects(), Instrument(0.01),
                             np.random.default_rng(0), rate_hz=500.0, dynamics=dyn)
    build = run.truth["robot"]
    assert build["inertia"] == "own" and build["arm_file"] == str(path.resolve())
    static = RealRobot(model, None, RealRobotOptions(dynamics=dyn)).describe()
    assert build["servo_kp_Nm_per_rad"] == static["servo_kp_Nm_per_rad"]
