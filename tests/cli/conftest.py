"""Fixtures of the command-line tests."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import zrp
from zrp.kinematics import uniform_joint_values


@pytest.fixture(scope="session")
def measured_csv(tmp_path_factory) -> Path:
    """A small measurement file for ``zrp diagnose``: the PUMA with joint 2 off by 1 mrad,
    40 poses (zrp.gap.synthesize, seed 0)."""
    model = zrp.load_model("puma")
    rng = np.random.default_rng(0)
    meas = zrp.gap.synthesize(model, uniform_joint_values(model, 40, rng),
                              zrp.gap.Injection(joint_offset={2: 1e-3}), rng=rng)
    return meas.to_csv(tmp_path_factory.mktemp("data") / "d.csv")
