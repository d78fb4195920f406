"""The calibrated IRB 120 from the real laser-tracker data in ../shared (skipped without it):
the written files reproduce the diagnosis's withheld error, and compensating the measured
joint program stays within the joint limits with a converged solve on the reachable poses."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import zrp
from zrp.calibration import (
    CalibratedRobot,
    PoseConditions,
    compensate_program,
    read_calibration,
    write_calibration,
)
from zrp.gap import diagnose, load_measurements

# IRB 120 datasheet joint ranges (deg); joint 6 is +-400 deg
LIMITS = np.radians([[-165, 165], [-110, 110], [-110, 70], [-160, 160], [-120, 120],
                     [-400, 400]])


@pytest.fixture(scope="module")
def real(shared_dir):
    d = shared_dir / "data" / "irb120-lasertracker"
    model = zrp.load_model(d / "irb120.toml")
    meas = load_measurements(d / "measurements.csv", model, deg=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(model, meas, seed=0)


def test_real_round_trip_and_program(real, tmp_path):
    cal = CalibratedRobot.from_diagnosis(real)
    _, c = write_calibration(cal, tmp_path / "calibrated.toml", tmp_path / "compensation.json")
    back = read_calibration(c)
    ctx = real.context
    w = real.withheld_poses
    cond = PoseConditions(direction=ctx.meas.approach_direction()[w])
    pred = np.stack([back.predict(ctx.q[w], lab, cond) for lab in back.tool_labels], 1)
    rows = np.flatnonzero(np.isin(ctx.meas.pose_index, w))
    local = np.full(len(ctx.meas.pose_ids), -1)
    local[w] = np.arange(len(w))
    r = (pred[local[ctx.meas.pose_index[rows]], ctx.meas.point_index[rows]]
         - ctx.meas.xyz[rows]).ravel()
    assert np.abs(r - real.withheld_residual_after).max() < 1e-9
    comp = compensate_program(back, ctx.q, limits=LIMITS)
    ok = comp.converged
    assert ok.mean() > 0.95
    assert comp.residual[ok].max() < 1e-6
    s = comp.summary()
    print(f"IRB 120: withheld {real.nominal.rms:.3f} -> {real.final.rms:.3f} mm; program "
          f"predicted correction RMS {s['rms_before']:.3f} mm, {s}")
