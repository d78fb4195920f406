"""A coupled motor found by the diagnosis is written into corrected.xml as a fixed tendon over
the joints it turns (its frictionloss, damping, armature), and the file reproduces the
diagnosis's corrected torques: mj_inverse on it (constraints off: rigid bodies, damping and
armature of joints and tendon) plus the smooth Coulomb laws and offsets (MuJoCo's
frictionloss is a constraint) equals tau0 + eq. V1. On the real TX40 drive log
(../shared/data/tx40-currents, its first 6.3 s, its transmission); skipped without it."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mjcf.arm import load_arm
from mjcf.corrected import CorrectedMJCF
from zrp.gap.dynamics.data import load_torque_log
from zrp.gap.dynamics.diagnosis import (
    DynamicsOptions,
    decimated_states,
    diagnose_dynamics,
    model_torques,
)
from zrp.gap.dynamics.inertia import V_EPS
from zrp.gap.dynamics.prediction import corrected_torques
from zrp.gap.dynamics.transmission import Transmission

pytestmark = pytest.mark.slow


def _ratio() -> np.ndarray:
    r = np.diag([32.0, 32.0, 45.0, -48.0, 45.0, 32.0])
    r[5, 4] = 32.0
    return r


@pytest.fixture(scope="module")
def tx40(shared_dir, tmp_path_factory):
    folder = shared_dir / "data" / "tx40-currents"
    if not (folder / "tx40_mdh_modified.urdf").is_file():
        pytest.skip("../shared/data/tx40-currents not present")
    p = np.loadtxt(folder / "pos_read_data.csv", delimiter=",", skiprows=1, max_rows=31500)
    c = np.loadtxt(folder / "curr_data.csv", delimiter=",", skiprows=1, max_rows=31500)
    path = tmp_path_factory.mktemp("tx40") / "fit.csv"
    head = ",".join(["t [s]", *(f"qm{k} [rad]" for k in range(1, 7)),
                     *(f"taum{k} [Nm]" for k in range(1, 7))])
    np.savetxt(path, np.column_stack([np.arange(len(p)) * 2e-4, p, c]), delimiter=",",
               header=head, comments="", fmt="%.9g")
    tr = Transmission(ratio=_ratio(), joint_offset=np.array([0, -np.pi / 2, np.pi / 2, 0, 0,
                                                                0]))
    log = load_torque_log(path, transmission=tr)
    arm = load_arm(folder / "tx40_mdh_modified.urdf", n_joints=6)
    return arm, log, diagnose_dynamics(arm, log, DynamicsOptions(window_s=0.05))


def test_coupled_motor_is_a_tendon_that_reproduces_the_torques(tx40):
    arm, log, d = tx40
    assert d.motors == {5: (0.0, 0.0, 0.0, 0.0, 1.0, 1.0)}
    found = {e.name: e.params[e.name].value for e in d.effects if e.joint == 5
             and e.name.startswith("motor_")}
    assert set(found) == {"motor_coulomb", "motor_viscous", "motor_armature"}
    text, notes = CorrectedMJCF(arm).corrected_model(d)
    assert any("motor 6" in n for n in notes)
    m = mujoco.MjModel.from_xml_string(text)
    assert m.ntendon == 1
    assert m.tendon_frictionloss[0] == pytest.approx(found["motor_coulomb"], rel=1e-12)
    assert m.tendon_damping[0] == pytest.approx(found["motor_viscous"], rel=1e-12)
    assert m.tendon_armature[0] == pytest.approx(found["motor_armature"], rel=1e-12)

    s, stride = decimated_states(log, DynamicsOptions(window_s=d.window_s))
    tau0 = model_torques(arm, log, s, stride)
    want = tau0 + corrected_torques(arm, d, s.q, s.qd, s.qdd, tau0, log.transmission)
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    data = mujoco.MjData(m)
    got = np.empty_like(want)
    for i, (q, qd, qdd) in enumerate(zip(s.q, s.qd, s.qdd, strict=True)):
        data.qpos[:], data.qvel[:], data.qacc[:] = q, qd, qdd
        mujoco.mj_inverse(m, data)
        got[i] = data.qfrc_inverse
    g = np.array(d.motors[5])
    for e in d.effects:  # what MuJoCo holds as a constraint or not at all, by its own law
        if e.name == "coulomb":
            vc = float(e.detail.split("=")[1].split()[0]) if e.detail else V_EPS
            got[:, e.joint] += e.params["coulomb"].value * np.tanh(s.qd[:, e.joint] / vc)
        elif e.name == "motor_coulomb":
            got += np.outer(np.tanh(s.qd @ g / V_EPS), g) * e.params[e.name].value
        elif e.name == "offset":
            got[:, e.joint] += e.params["offset"].value
        else:
            assert e.name in ("viscous", "armature", "motor_viscous", "motor_armature",
                              "inertial", "payload", "link_mass", "absent_part"), e.name
    np.testing.assert_allclose(got, want, atol=1e-9 * np.abs(want).max())
