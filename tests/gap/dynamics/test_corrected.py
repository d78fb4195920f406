"""The corrected MJCF: it loads in MuJoCo, holds the identified friction, damping and payload,
and driven along the logged command by the same servo it tracks like the real arm."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mjcf.corrected import write_corrected_mjcf
from mjcf.inverse import inverse_dynamics
from mjcf.tracking import tracking_gap
from sim.studies.dynamics.truth import HiddenDynamics, Servo, simulate, true_model
from tests.gap.dynamics.conftest import UR5E_NOISE
from zrp.gap.dynamics.diagnosis import diagnose_dynamics


@pytest.mark.slow
def test_corrected_model_tracks_like_the_real_arm(ur5e, ur5e_command, tmp_path):
    hidden = HiddenDynamics(coulomb=np.array([0, 2.0, 0, 0, 0, 0]),
                            viscous=np.array([0, 0, 0, 0.5, 0, 0]), payload_kg=1.0)
    log = simulate(ur5e, hidden, ur5e_command, 20.0, noise_nm=UR5E_NOISE, seed=2)
    diag = diagnose_dynamics(ur5e, log)
    path = write_corrected_mjcf(ur5e, diag, tmp_path / "corrected.xml")
    with pytest.raises(Exception, match="exists"):
        write_corrected_mjcf(ur5e, diag, path)
    m = mujoco.MjModel.from_xml_path(str(path))
    assert m.dof_frictionloss[1] == pytest.approx(2.0, abs=0.1)
    assert m.dof_damping[3] == pytest.approx(0.5, abs=0.05)
    assert m.body_mass.sum() == pytest.approx(ur5e.model.body_mass.sum() + 1.0, abs=0.05)
    # its torques are the real arm's (independent: the truth model's mj_inverse)
    rng = np.random.default_rng(0)
    q, qd, qdd = rng.normal(size=(3, 30, 6))
    qd += np.sign(qd) * 0.2  # away from zero speed, where friction laws differ
    err = inverse_dynamics(m, q, qd, qdd) - inverse_dynamics(true_model(ur5e, hidden), q, qd,
                                                             qdd)
    assert np.abs(err).max() < 0.05
    servo = Servo.tuned(ur5e, ur5e_command.q0)
    before = tracking_gap(ur5e.model, ur5e.model, log, servo)
    after = tracking_gap(m, ur5e.model, log, servo)
    assert np.all(after[1:5] < 0.2 * before[1:5])
    assert np.all(after < 3e-5)  # the encoder noise (1e-5 rad) and little more


@pytest.mark.slow
def test_corrected_link_inertias_load_and_are_physical(ur5e, tmp_path):
    from mjcf.inverse import body_params
    from sim.studies.dynamics.scenarios import draw_hidden, scenario_command
    from zrp.gap.dynamics.inertia import pseudo_inertia_ok

    command = scenario_command(np.array([0.0, -1.2, 1.2, -1.5, -1.5, 0.0]), 0.6, 1)
    hidden, sigma, desc = draw_hidden(ur5e, command, "inertial", 1)
    log = simulate(ur5e, hidden, command, 20.0, noise_nm=sigma, seed=1)
    diag = diagnose_dynamics(ur5e, log)
    # a point mass added to one link: named as that link's mass, or as the link inertias
    first = diag.effects[0]
    assert first.name == "inertial" or (first.name, first.detail) == ("link_mass",
                                                                      desc["body_name"])
    m = mujoco.MjModel.from_xml_path(str(write_corrected_mjcf(ur5e, diag, tmp_path / "c.xml")))
    assert all(pseudo_inertia_ok(body_params(m, b)) for b in ur5e.moving_bodies())
    t = np.linspace(0.0, 10.0, 200)
    q, qd, qdd = command.evaluate(t)
    truth = inverse_dynamics(true_model(ur5e, hidden), q, qd, qdd)
    nominal = np.abs(inverse_dynamics(ur5e.model, q, qd, qdd) - truth).max()
    corrected = np.abs(inverse_dynamics(m, q, qd, qdd) - truth).max()
    assert corrected < nominal
    # the link fit is physical by construction; how far from the unconstrained one is noted
    if diag.inertial_fit is not None:
        assert diag.inertial_fit.describe() in diag.notes
