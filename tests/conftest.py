"""Shared fixtures: random arms and the shared-data location."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import zrp
from zrp.testing import random_arm  # noqa: F401  (re-exported for tests)

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def puma() -> zrp.Manipulator:
    return zrp.load_model("puma")


@pytest.fixture(scope="session")
def shared_dir() -> Path:
    if not SHARED.is_dir():
        pytest.skip("../shared is not present")
    return SHARED
