"""The calibrated IRB 120 from the real laser-tracker data in ../shared (skipped without it):
the written files reproduce the diagnosis's withheld error, and compensating the measured
joint program stays within the joint limits with a converged solve on the reachable poses."""

from __future__ import annotations

import numpy as np
import pytest

from zrp.calibration import (
    CalibratedRobot,
    compensate_program,
    read_calibration,
    write_calibration,
)
from zrp.calibration.validation import implausible_values
from zrp.gap.model.domains import ImplausibleValueError

# IRB 120 datasheet joint ranges (deg); joint 6 is +-400 deg
LIMITS = np.radians([[-165, 165], [-110, 110], [-110, 70], [-160, 160], [-120, 120],
                     [-400, 400]])


@pytest.fixture(scope="module")
def real(irb120_real):
    return irb120_real.diagnosis


def test_real_implausible_values_never_reach_a_file(real, tmp_path):
    """The last gate: a value outside its physical domain (the IRB 120's final model had four
    negative backlash values) is refused by the writer, naming each; nothing is written."""
    cal = CalibratedRobot.from_diagnosis(real)
    bad = implausible_values(cal)
    if not bad:
        write_calibration(cal, tmp_path / "calibrated.toml", tmp_path / "compensation.json")
        return
    with pytest.raises(ImplausibleValueError) as err:
        write_calibration(cal, tmp_path / "calibrated.toml", tmp_path / "compensation.json")
    for msg in bad:
        assert msg.split(" = ")[0] + " = " in str(err.value)
    assert not list(tmp_path.iterdir())
    print(f"IRB 120: refused {len(bad)} implausible values: {bad}")


def test_real_round_trip_and_program(real, withheld_residual, tmp_path):
    cal = CalibratedRobot.from_diagnosis(real)
    if implausible_values(cal):
        pytest.skip("the diagnosis's final model carries values outside their physical "
                    "domain (refused by the writer, tested above)")
    _, c = write_calibration(cal, tmp_path / "calibrated.toml", tmp_path / "compensation.json")
    back = read_calibration(c)
    r = withheld_residual(back, real)
    assert np.abs(r - real.withheld_residual_after).max() < 1e-9
    comp = compensate_program(back, real.context.q, limits=LIMITS, accept_flagged=True)
    ok = comp.converged
    assert ok.mean() > 0.95
    assert comp.residual[ok].max() < 1e-6
    s = comp.summary()
    print(f"IRB 120: withheld {real.nominal.rms:.3f} -> {real.final.rms:.3f} mm; program "
          f"predicted correction RMS {s['rms_before']:.3f} mm, {s}")
