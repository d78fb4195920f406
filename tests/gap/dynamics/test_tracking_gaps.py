"""The tracking gap of a log as controllers write it: a gap in the log is time the log does
not show (each stretch is re-simulated from its own start), and a jittered clock is read at
its real sample times. Reference: the same run logged whole, where the model tracks itself."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from mjcf.tracking import tracking_gap
from sim.studies.dynamics.truth import HiddenDynamics, Servo, simulate
from zrp.gap.dynamics.data import TorqueLog


def _keep(log: TorqueLog, rows: np.ndarray, segments: tuple[tuple[int, int], ...]) -> TorqueLog:
    return TorqueLog(log.t[rows], log.q[rows], None, log.tau[rows], log.qc[rows],
                     source="gapped.csv", segments=segments)


@pytest.fixture(scope="module")
def self_run(ur5e, ur5e_command):
    """The nominal arm logged along the command: the model tracks it exactly but for the
    encoder noise."""
    log = simulate(ur5e, HiddenDynamics(), ur5e_command, 4.0, noise_nm=np.zeros(6), seed=3)
    return log, Servo.tuned(ur5e, ur5e_command.q0)


def test_a_log_with_a_gap_is_resimulated_per_stretch(ur5e, self_run):
    log, servo = self_run
    whole = tracking_gap(ur5e.model, ur5e.model, log, servo)
    n = log.n_samples
    a, b = n // 3, n // 2  # a second of log lost in the middle, clock running on
    rows = np.r_[0:a, b:n]
    gapped = _keep(log, rows, ((0, a), (a, rows.size)))
    split = tracking_gap(ur5e.model, ur5e.model, gapped, servo)
    assert np.all(np.isfinite(split))
    # the model tracks its own log after the gap as before it (start in motion, no jump)
    # (sample k after the gap is compared with the simulation at its own time, not k * dt)
    assert np.all(split <= 1.2 * whole + 1e-6)
    # the stretch after the gap starts from its own state: a log restarted elsewhere (its
    # second stretch shifted by 0.3 rad) is tracked as well as the arm tracks itself
    moved = dataclasses.replace(gapped, q=gapped.q + np.where(np.arange(rows.size) >= a, 0.3,
                                                              0.0)[:, None],
                                qc=gapped.qc + np.where(np.arange(rows.size) >= a, 0.3,
                                                        0.0)[:, None])
    assert np.max(tracking_gap(ur5e.model, ur5e.model, moved, servo)) < 1e-3


def test_a_jittered_clock_is_read_at_its_sample_times(ur5e, self_run):
    log, servo = self_run
    rng = np.random.default_rng(0)
    rows = np.sort(rng.choice(log.n_samples, size=log.n_samples * 3 // 4, replace=False))
    uneven = _keep(log, rows, ())  # the kept rows have steps of 1, 2, 3 ... samples
    whole = tracking_gap(ur5e.model, ur5e.model, log, servo)
    assert np.all(tracking_gap(ur5e.model, ur5e.model, uneven, servo) <= 1.2 * whole + 1e-6)
