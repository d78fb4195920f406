"""Shared fixtures: a seeded generator, the PUMA, the shared-data location, and the diagnoses that
tests in several folders read (each run once per session: they are the suite's most expensive
studies)."""

from __future__ import annotations

import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pytest

import zrp
import zrp.testing  # the tests call zrp.testing.random_arm without importing it
from tests.measured import puma_full_pose
from zrp.blas import blas_threads
from zrp.gap import Diagnosis, Measurements, diagnose, load_measurements

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


@pytest.fixture(scope="session", autouse=True)
def one_blas_thread() -> Iterator[None]:
    """Every test runs with one BLAS thread. The suite's linear algebra is small dense
    problems, on which OpenBLAS's threads spin waiting for each other (zrp/blas.py): the
    diagnosis limits itself to one thread, the motion diagnosis does not, and its tests took
    15x the CPU time with the default threads (143 s instead of 9 s for the delay-or-lag
    pair on this 2-core machine). Results agree to rounding either way (zrp/blas.py)."""
    with blas_threads(1):
        yield


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


class RealRun(NamedTuple):
    """The real IRB 120 laser-tracker data (../shared), its diagnosis and its warnings."""

    model: zrp.Manipulator
    measurements: Measurements
    diagnosis: Diagnosis
    warnings: list[warnings.WarningMessage]


@pytest.fixture(scope="session")
def irb120_real(shared_dir) -> RealRun:
    """``diagnose(irb120, measurements, seed=0)`` of the real data, shared by the command-line,
    report and calibration tests (skipped without ../shared/data/irb120-lasertracker)."""
    d = shared_dir / "data" / "irb120-lasertracker"
    if not (d / "measurements.csv").is_file():
        pytest.skip("real IRB 120 data (../shared/data/irb120-lasertracker) not present")
    model = zrp.load_model(d / "irb120.toml")
    meas = load_measurements(d / "measurements.csv", model, deg=True)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        diag = diagnose(model, meas, seed=0)
    return RealRun(model, meas, diag, list(caught))


@pytest.fixture(scope="session")
def full_pose_diagnosis() -> Diagnosis:
    """``diagnose(puma, puma_full_pose(), seed=0)`` (tests/measured.py), shared by the
    full-pose calibration and diagnosis tests."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose(zrp.load_model("puma"), puma_full_pose(), seed=0)
