"""Fixtures of the calibration tests."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

from zrp.calibration import CalibratedRobot, PoseConditions
from zrp.gap import Diagnosis


def _withheld_residual(cal: CalibratedRobot, diag: Diagnosis) -> np.ndarray:
    """Predicted minus measured on the withheld poses, in the diagnosis's row order."""
    ctx = diag.context
    w = diag.withheld_poses
    cond = PoseConditions(direction=ctx.meas.approach_direction()[w])
    pred = np.stack([cal.predict(ctx.q[w], lab, cond) for lab in cal.tool_labels], 1)
    rows = np.flatnonzero(np.isin(ctx.meas.pose_index, w))
    local = np.full(len(ctx.meas.pose_ids), -1)
    local[w] = np.arange(len(w))
    got = pred[local[ctx.meas.pose_index[rows]], ctx.meas.point_index[rows]]
    return (got - ctx.meas.xyz[rows]).ravel()


@pytest.fixture(scope="session")
def withheld_residual() -> Callable[[CalibratedRobot, Diagnosis], np.ndarray]:
    """``withheld_residual(cal, diag)``: the calibrated robot's prediction minus the
    measurement on the diagnosis's withheld poses (to compare with its
    ``withheld_residual_after``)."""
    return _withheld_residual
