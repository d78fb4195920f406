"""Issue 41 finding 1: a command within every limit the model states. An MJCF's actuators
cap the torque (``forcerange``, a motor's ``ctrlrange`` times gear); the command stays within
them, ``max_torque`` is never above them, and a default is never recorded as given."""

from __future__ import annotations

import numpy as np
import pytest

from zrp.errors import InputError
from zrp.gap.dynamics.command import (
    ExciteOptions,
    excitation_command,
    read_command_conditions,
    write_excitation_command,
)

pytest.importorskip("mujoco")

_ARM = """<mujoco model="capped">
  <compiler angle="radian"/>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="l1" pos="0 0 0.1">
      <joint name="j1" type="hinge" axis="0 0 1" range="-3 3"/>
      <inertial pos="0 0 0.1" mass="4" diaginertia="0.05 0.05 0.02"/>
      <body name="l2" pos="0 0 0.2">
        <joint name="j2" type="hinge" axis="0 1 0" range="-3 3"/>
        <inertial pos="0.2 0 0" mass="3" diaginertia="0.02 0.04 0.04"/>
        <body name="l3" pos="0.4 0 0">
          <joint name="j3" type="hinge" axis="0 1 0" range="-3 3"/>
          <inertial pos="0.2 0 0" mass="2" diaginertia="0.01 0.03 0.03"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    {actuators}
  </actuator>
</mujoco>
"""
MOTORS = ('<motor joint="j1" ctrlrange="-1 1" gear="20"/>'
          '<motor joint="j2" ctrlrange="-1 1" gear="20"/>'
          '<motor joint="j3" ctrlrange="-0.5 0.5" gear="40"/>')
FORCE = ('<position joint="j1" kp="100" forcerange="-20 20"/>'
         '<position joint="j2" kp="100" forcerange="-20 20"/>'
         '<general joint="j3" gainprm="1" forcerange="-10 10" gear="2"/>')
FAST = {"candidates": 1, "iterations": 0, "rate_hz": 100.0}


def _arm(tmp_path, actuators):
    from mjcf.arm import load_arm

    path = tmp_path / "capped.xml"
    path.write_text(_ARM.format(actuators=actuators))
    return load_arm(path), path


@pytest.mark.parametrize("actuators", [MOTORS, FORCE])
def test_the_models_actuator_limits_are_the_torque_limits(tmp_path, actuators):
    arm, _ = _arm(tmp_path, actuators)
    np.testing.assert_allclose(arm.torque_limits(), [20.0, 20.0, 20.0])


def test_the_command_stays_within_the_actuators_limits_and_says_model(tmp_path):
    arm, path = _arm(tmp_path, MOTORS)
    cmd = excitation_command(arm, ExciteOptions(q0=[0.0, 0.3, -0.6], amplitude=1.0,
                                                max_velocity=2.0, max_acceleration=10.0,
                                                **FAST))
    assert np.abs(cmd.tau).max() <= 20.0
    out = write_excitation_command(cmd, tmp_path / "c.csv", model=path)
    cond = read_command_conditions(out)
    assert cond["torque limits [N m]"] == "20 20 20 (model; inf: none known)"
    assert cond["acceleration limits [rad/s^2]"].endswith("(given)")


def test_a_default_limit_is_never_recorded_as_given(tmp_path):
    arm, path = _arm(tmp_path, MOTORS)
    cmd = excitation_command(arm, ExciteOptions(q0=[0.0, 0.3, -0.6], amplitude=0.3, **FAST))
    cond = read_command_conditions(write_excitation_command(cmd, tmp_path / "c.csv",
                                                            model=path))
    assert cond["acceleration limits [rad/s^2]"] == "3 3 3 (default)"
    assert "(model" in cond["torque limits [N m]"]
    assert not any(v.endswith("(given)") for k, v in cond.items() if "limits" in k)


def test_max_torque_above_an_actuators_limit_is_refused(tmp_path):
    arm, _ = _arm(tmp_path, MOTORS)
    with pytest.raises(InputError, match=r"max_torque: joint 3 \(j3\) 25 N m is above the "
                                         r"model's own limit 20 N m"):
        excitation_command(arm, ExciteOptions(q0=[0.0, 0.3, -0.6], max_torque=[10, 10, 25],
                                              **FAST))


def test_ur5e_max_torque_1000_is_refused(ur5e):
    np.testing.assert_allclose(ur5e.torque_limits(), [150, 150, 150, 28, 28, 28])
    with pytest.raises(InputError, match=r"max_torque: joint 1 \(shoulder_pan_joint\) 1000 "
                                         r"N m is above the model's own limit 150"):
        excitation_command(ur5e, ExciteOptions(q0=[0.0, -1.2, 1.2, -1.5, -1.5, 0.0],
                                               max_torque=1000, **FAST))
