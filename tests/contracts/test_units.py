"""One units module for every layer: the same robot described in mm, dm, ft or in gets the
same gravity torques in N m everywhere, and an unknown unit is an error everywhere."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import zrp
from zrp.units import G_STANDARD, LENGTH_UNITS, canonical_length_unit, metres_per_unit

UNITS = ("dm", "ft", "in", "m", "cm")


def in_unit(model: zrp.Manipulator, unit: str) -> zrp.Manipulator:
    """The same physical robot as ``model`` (in mm), described in ``unit``."""
    f = 1e-3 / metres_per_unit(unit)
    joints = tuple(dataclasses.replace(j, body=np.asarray(j.body) * f) for j in model.joints)
    ee = dataclasses.replace(model.end_effector, body=np.asarray(model.end_effector.body) * f)
    return dataclasses.replace(model, joints=joints, end_effector=ee, length_unit=unit)


@pytest.fixture(scope="module")
def q():
    return zrp.uniform_joint_values(zrp.load_model("puma"), 12, np.random.default_rng(3))


def test_units_table():
    assert metres_per_unit("mm") == 1e-3
    assert metres_per_unit("ft") == pytest.approx(0.3048)
    assert metres_per_unit("in") == pytest.approx(0.0254)
    assert metres_per_unit("dm") == pytest.approx(0.1)
    assert canonical_length_unit("Millimetres") == "mm"
    assert G_STANDARD == 9.80665
    assert set(UNITS) <= set(LENGTH_UNITS)


@pytest.mark.parametrize("unit", ["furlong", "", "MM2", 3])
def test_unknown_unit_is_an_error_everywhere(puma, unit):
    with pytest.raises(zrp.InputError, match="length_unit"):
        metres_per_unit(unit)
    with pytest.raises(zrp.ZRPError, match="length_unit"):
        dataclasses.replace(puma, length_unit=unit)


@pytest.mark.parametrize("unit", UNITS)
def test_model_in_another_unit_has_the_same_kinematics(puma, q, unit):
    other = in_unit(puma, unit)
    p_mm = zrp.end_effector_pose(puma, q)[0]
    p_u = zrp.end_effector_pose(other, q)[0]
    np.testing.assert_allclose(p_u * metres_per_unit(unit), p_mm * 1e-3, atol=1e-12)


@pytest.mark.parametrize("unit", UNITS)
def test_mjcf_gravity_torques_do_not_depend_on_the_unit(puma, q, unit, tmp_path):
    mjcf = pytest.importorskip("mjcf")
    opts = mjcf.MJCFOptions(inertia="rods", visuals=False, floor=False)
    paths = []
    for m, name in ((puma, "mm.xml"), (in_unit(puma, unit), f"{unit}.xml")):
        paths.append(mjcf.save_mjcf(mjcf.build(m, opts), tmp_path / name))
    tau_mm = mjcf.gravity_torques(paths[0], q)
    tau_u = mjcf.gravity_torques(paths[1], q)
    assert np.abs(tau_mm).max() > 1.0  # N m: a real load
    np.testing.assert_allclose(tau_u, tau_mm, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("unit", UNITS)
def test_real_robot_static_torque_does_not_depend_on_the_unit(puma, q, unit):
    sim = pytest.importorskip("sim")
    t_mm = sim.RealRobot(puma).static_torque(q)
    t_u = sim.RealRobot(in_unit(puma, unit)).static_torque(q)
    assert np.abs(t_mm).max() > 1.0
    np.testing.assert_allclose(t_u, t_mm, rtol=1e-7, atol=1e-7)


@pytest.mark.parametrize("unit", UNITS)
def test_gap_payload_and_gravity_torques_do_not_depend_on_the_unit(puma, q, unit):
    """The diagnosis's gravity torques with a payload (N m) and its payload-compliance columns
    (N m per kg): the same numbers for the model in mm and in ``unit``. (Before one units module,
    the gap's own table lacked dm and ft and fell back to mm silently: 100x and 305x off.)"""
    from zrp.gap import Context, Measurements, effect_parameters

    tau = np.random.default_rng(1).normal(size=q.shape) * 20.0  # N m, from an MJCF say
    load = np.linspace(0.0, 3.0, len(q))  # kg logged per pose

    def torques(model):
        xyz = np.zeros((len(q), 3))
        meas = Measurements.from_arrays(np.arange(len(q)), q, xyz, load=load)
        ctx = Context(model, meas, gravity_torque=tau, payload_kg=2.5)
        specs, _ = effect_parameters(ctx, "joint_compliance")
        cols = {s.name: s.basis[:, s.joint - 1] for s in specs}
        return ctx.gravity_side_torque(), cols

    side_mm, cols_mm = torques(puma)
    side_u, cols_u = torques(in_unit(puma, unit))
    assert np.abs(side_mm - tau).max() > 1.0  # the payload adds a real torque
    np.testing.assert_allclose(side_u, side_mm, rtol=1e-9, atol=1e-9)
    assert cols_u.keys() == cols_mm.keys()
    assert any(k.endswith("compliance_payload") for k in cols_mm)
    for name in cols_mm:
        np.testing.assert_allclose(cols_u[name], cols_mm[name], rtol=1e-9, atol=1e-9,
                                   err_msg=name)


def test_units_per_mm_and_the_planning_default_follow_the_model_unit(puma):
    import warnings

    from zrp.calibration.planning import PlanWarning, design_std, plan_poses
    from zrp.errors import InputError
    from zrp.units import TRACKER_NOISE_MM, units_per_mm

    assert units_per_mm("mm") == 1.0 and units_per_mm("m") == pytest.approx(1e-3)
    assert units_per_mm("in") == pytest.approx(1 / 25.4)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PlanWarning)  # aliased link components are left out
        p_mm, p_m = (plan_poses(model, 30, ["link_length"], rng=np.random.default_rng(0),
                                candidates=60) for model in (puma, in_unit(puma, "m")))
    assert p_mm.names == p_m.names and np.array_equal(p_mm.q, p_m.q)
    # the default is the same 20 um instrument in both units: an angle's std is the same, a
    # length's is the same length (1e-3 times the number); it used to be 0.02 model units
    length = np.array([u != "rad" for u in p_mm.units])
    assert length.any() and (~length).any()
    np.testing.assert_allclose(p_m.std[~length], p_mm.std[~length], rtol=1e-6)
    np.testing.assert_allclose(p_m.std[length] * 1e3, p_mm.std[length], rtol=1e-6)
    d = np.ones_like(p_mm.q)
    _, default = design_std(puma, p_mm.q, d, ["link_length"])
    _, explicit = design_std(puma, p_mm.q, d, ["link_length"], noise_sigma=TRACKER_NOISE_MM)
    np.testing.assert_allclose(default, explicit, rtol=1e-12)
    with pytest.raises(InputError, match="noise_sigma"):
        design_std(puma, p_mm.q, d, ["link_length"], noise_sigma=-1.0)
