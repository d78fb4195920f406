"""Simulated Panda logs for the dynamic gap's model-part tests: the shipped URDF carries the
hand (panda_hand with its fingers, 0.76 kg) and the simulated real arm does not; Coulomb
friction on six joints. The truth (the arm without the hand) is built here and reaches the
diagnosis only as a log."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from zrp.gap.dynamics.data import TorqueLog

FRICTION = np.array([0.8, 0.0, 0.6, 0.5, 0.4, 0.3, 0.3])
HAND_KG = 0.76  # panda_hand 0.73 + two fingers of 0.015 in example-robot-data's URDF


def panda_arm():
    from mjcf.arm import load_arm
    from sim.studies.dynamics.arms import panda_urdf

    try:
        path = panda_urdf()
    except Exception as exc:  # the package is optional: skip without it
        pytest.skip(f"example-robot-data: {exc}")
    return load_arm(path, end_link="panda_link8", name="panda")


def truth_without_hand():
    """The Panda as MuJoCo would build it from the URDF with the hand removed."""
    from mjcf.arm import _fix_off_chain
    from mjcf.shipped import load_shipped_spec
    from sim.studies.dynamics.arms import panda_urdf

    spec = load_shipped_spec(panda_urdf())
    _fix_off_chain(spec, "panda_link8")
    spec.delete(spec.body("panda_hand"))
    spec.compiler.fusestatic = True
    return spec.compile()


def simulated_log(arm, plant, seed: int, seconds: float = 20.0, coulomb=FRICTION
                  ) -> tuple[TorqueLog, np.ndarray]:
    """The servo-driven plant along a benchmark command, 1 % torque noise + 0.01 N m."""
    from mjcf.tracking import Servo, run_servo
    from sim.studies.dynamics.arms import BENCH_ARMS
    from sim.studies.dynamics.scenarios import scenario_command

    bench = BENCH_ARMS["panda"]
    cmd = scenario_command(bench.q0_array, bench.amplitude_rad, seed)
    plant = copy.deepcopy(plant)
    plant.dof_frictionloss[:] += coulomb
    run = run_servo(plant, arm.model, Servo.tuned(arm, cmd.q0), cmd, seconds, 1000.0)
    t = np.linspace(0.0, 1.0 / cmd.f0_hz, 2000, endpoint=False)
    sigma = 0.01 * np.sqrt(np.mean(arm.inverse_dynamics(*cmd.evaluate(t)) ** 2, 0)) + 0.01
    rng = np.random.default_rng(seed)
    tau = run.tau + rng.normal(size=run.tau.shape) * sigma
    q = run.q + rng.normal(size=run.q.shape) * 1e-5
    return TorqueLog(run.t, q, run.qd.copy(), tau, run.qc, None,
                     np.arange(2, run.t.size + 2), f"panda seed {seed}", "tau"), sigma
