"""The Python API on hostile input (issue 13): joint values must be real and in range in
every kinematics entry point, tolerances are bounded, and a wrong type anywhere is an error
of the project's hierarchy naming the argument, never a bare Python exception."""

from __future__ import annotations

import numpy as np
import pytest

import zrp
from zrp.errors import InputError, ZRPError
from zrp.gap import Injection, load_measurements, synthesize
from zrp.model.files import loads_model

PUMA = zrp.load_model("puma")


# ---- joint values --------------------------------------------------------------------------
@pytest.mark.parametrize("q, match", [
    (np.zeros(6) + 1j, "expected real numbers.*complex128"),
    (np.zeros(6, dtype="datetime64[s]"), "expected real numbers.*datetime64"),
    (np.ma.masked_array(np.zeros(6), mask=[1, 0, 0, 0, 0, 0]), "masked array"),
    (np.full(6, 1e19), r"joint 1 \(q1\) is 1e\+19; expected finite values within \+-1e\+06 rad"),
    (np.full(6, 1e20), r"joint 1 \(q1\) is 1e\+20"),
    ([0, 0, 0, 0, 0, float("nan")], r"joint 6 \(q6\) is nan"),
])
@pytest.mark.parametrize("fn", [zrp.end_effector_pose, zrp.jacobian, zrp.forward_kinematics])
def test_joint_values_real_and_in_range(fn, q, match):
    with pytest.raises(InputError, match=match):
        fn(PUMA, q)


def test_large_but_accepted_angles_agree_with_numpy():
    """Up to the 1e6 rad limit the fast kernels give what NumPy's exactly reduced sin/cos give."""
    q = np.array([9.9e5, -7.7e5, 3.3e5, 1e5, -5e5, 8.8e5])
    p_fast, _ = zrp.end_effector_pose(PUMA, q)
    np.testing.assert_allclose(p_fast, zrp.forward_kinematics(PUMA, q).position, atol=1e-9)


def test_tolerances_bounded():
    with pytest.raises(InputError, match=r"tolerance of b1.x: expected a finite value from 0"):
        zrp.Tolerances.build(PUMA, length=1e308)
    with pytest.raises(InputError, match=r"tolerance of u1\.t1"):
        zrp.Tolerances.build(PUMA, angle_rad=4.0)


# ---- wrong types ---------------------------------------------------------------------------
def test_only_project_errors_for_wrong_types(tmp_path):
    for call in (lambda: load_measurements(None, PUMA),
                 lambda: load_measurements(tmp_path / "none.csv", None),
                 lambda: loads_model(b"name = 1"),
                 lambda: zrp.jacobian(PUMA, "abc")):
        with pytest.raises(ZRPError):
            call()


@pytest.mark.parametrize("call, match", [
    (lambda: zrp.track_trajectory(None, zrp.puma_circle().trajectory, np.zeros(6), steps=10),
     "model: expected a zrp.Manipulator"),
    (lambda: zrp.uniform_joint_values(PUMA, -1, np.random.default_rng(0)),
     "count: expected a whole number >= 0"),
    (lambda: zrp.uniform_joint_values(PUMA, 3, 0), "rng: expected a numpy.random.Generator"),
    (lambda: synthesize(PUMA, None, Injection(), rng=np.random.default_rng(0)), "q: expected"),
    (lambda: zrp.from_dh(None), "rows: expected a sequence of DH rows"),
    (lambda: zrp.from_dh([["a", 0, 0, 0]]), "DH row 1"),
    (lambda: zrp.gap.Measurements.from_arrays(["a"], [["x"] * 6], [[0, 0, 0]]),
     "q and xyz: expected numbers"),
])
def test_public_api_wrong_types(call, match):
    with pytest.raises(InputError, match=match):
        call()
