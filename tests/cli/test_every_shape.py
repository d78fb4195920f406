"""Every shape of measurement the readers accept goes through every stage (issue 45).

Sets drawn by hypothesis (derandomized: the same draws on every run) from
:mod:`tests.shapes`: different points per pose, points missing on some poses, one label per
run, orientation rows, repeated poses, time/temperature/load columns, few poses, a joint that
never moves, either frame. Each goes through the commands a user runs - ``zrp diagnose``
(search, baseline, what remains, the learned residual term, plots, report), ``zrp calibrate``
on that diagnosis, ``zrp export`` of the calibration, ``zrp compensate`` of a joint program -
and none may end in anything but a named :class:`~zrp.errors.ZRPError` (exit code 2, one line
on stderr); a diagnosis that runs writes its report. The quick test draws a few shapes, the
slow one 200.
"""

from __future__ import annotations

import csv
import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.shapes import LAYOUTS, PUMA, Shape, draw_set
from zrp.cli.app import main

pytestmark = pytest.mark.filterwarnings("ignore")  # the data's own warnings (aliases, ...)

shapes = st.builds(
    Shape, n_poses=st.integers(6, 60), n_points=st.integers(1, 3),
    layout=st.sampled_from(LAYOUTS), quat=st.booleans(), repeats=st.sampled_from([0, 0, 3]),
    t=st.booleans(), temp=st.booleans(), load=st.booleans(),
    still=st.sampled_from([None, None, 0, 3, 5]), frame=st.sampled_from(["instrument", "base"]),
    seed=st.integers(0, 2**16))


def _run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> int:
    """Run one command; any exception but a ZRPError escapes (the CLI turns those into 2)."""
    with warnings.catch_warnings(record=True):  # the data's own warnings, recorded and dropped
        rc = main(argv)
    err = capsys.readouterr().err
    assert rc in (0, 2), (argv, rc, err)
    if rc == 2:
        assert "error: " in err, err
    return rc


def _program(path: Path, meas_q: np.ndarray) -> None:
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["target", *[f"q{k}" for k in range(1, PUMA.n + 1)]])
        for i, row in enumerate(meas_q[:5]):
            w.writerow([f"T{i}", *row])


def pipeline(shape: Shape, root: Path, capsys: pytest.CaptureFixture[str], *,
             plots: bool) -> dict[str, int]:
    """Exit code of each stage that ran."""
    meas = draw_set(shape)
    data = meas.to_csv(root / "d.csv", overwrite=True)
    frame = ["--frame", shape.frame]
    out = root / "diag"
    rc = {"diagnose": _run(["diagnose", "--model", "puma", "--data", str(data), *frame,
                            "--out", str(out), "--force", "--no-progress", "--max-steps", "2",
                            "--residual-model", *([] if plots else ["--no-plots"])], capsys)}
    if rc["diagnose"]:
        return rc
    assert (out / "report.md").is_file() and (out / "report.html").is_file()
    assert (out / "diagnosis.json").is_file()
    cal = root / "cal"
    rc["calibrate"] = _run(["calibrate", "--model", "puma", "--data", str(data), *frame,
                            "--diagnosis", str(out / "diagnosis.json"), "--out", str(cal),
                            "--force", "--no-progress"], capsys)
    if rc["calibrate"]:
        return rc
    comp = cal / "compensation.json"
    rc["export"] = _run(["export", "--calibration", str(comp), "--to", "urdf", "--out",
                         str(root / "robot.urdf"), "--force"], capsys)
    _program(root / "prog.csv", meas.q_pose)
    extra = (["--temp", "22"] if shape.temp else []) + (["--load", "1"] if shape.load else [])
    rc["compensate"] = _run(["compensate", "--calibration", str(comp), "--targets",
                             str(root / "prog.csv"), "--out", str(root / "cmd.csv"), "--force",
                             "--accept-flagged", *extra], capsys)
    return rc


#: with this many distinct poses or more, every shape is diagnosed (fewer may be refused:
#: "not enough coordinates for the parameters", "a point measured in fewer than 3 poses").
ENOUGH_POSES = 25


def _check(shape: Shape, tmp: Path, capsys: pytest.CaptureFixture[str], seen: list) -> None:
    rc = pipeline(shape, tmp, capsys, plots=len(seen) % 10 == 0)
    seen.append((shape, rc))
    if shape.n_poses >= ENOUGH_POSES:
        assert rc == dict.fromkeys(("diagnose", "calibrate", "export", "compensate"), 0), (
            shape, rc)


def test_an_analysis_that_cannot_run_says_so_and_the_others_run(tmp_path, capsys):
    """One label per run, 30 poses a run: about 22 fitting poses share a point, too few for
    the test of what remains and none measures every point for the learned term; the report
    says both did not run and why, and the diagnosis goes on."""
    shape = Shape(90, 3, "runs", False, 0, False, False, True, None, "instrument", 7)
    rc = pipeline(shape, tmp_path, capsys, plots=False)
    assert rc == dict.fromkeys(("diagnose", "calibrate", "export", "compensate"), 0)
    doc = json.loads((tmp_path / "diag" / "diagnosis.json").read_text(encoding="utf-8"))
    assert doc["remainder"]["structure"] is None and doc["residual_model"] is None
    assert "fitting poses measure the same 1 point(s)" in doc["remainder"]["structure_not_run"]
    assert "measure every one of the 3 points" in doc["residual_model_not_run"]
    report = (tmp_path / "diag" / "report.md").read_text(encoding="utf-8")
    assert "The multivariate test of what remains did not run: only " in report
    assert "The learned residual term did not run: only 0 fitting poses" in report


QUICK: list = []
SLOW: list = []


@pytest.mark.parametrize("layout", ["mixed", "runs"])
def test_the_two_real_shapes_are_diagnosed_calibrated_and_compensated(layout, tmp_path, capsys):
    """Three points on some poses and one test point on the others; one point label per
    payload run (the two real sets that ended in a traceback): every stage runs, and the test
    of what remains says on which poses it ran."""
    shape = Shape(90 if layout == "mixed" else 150, 3, layout, False, 0, False, False,
                  layout == "runs", None, "instrument", 7)
    rc = pipeline(shape, tmp_path, capsys, plots=False)
    assert rc == dict.fromkeys(("diagnose", "calibrate", "export", "compensate"), 0)
    doc = json.loads((tmp_path / "diag" / "diagnosis.json").read_text(encoding="utf-8"))
    structure = doc["remainder"]["structure"]
    # mixed: the three points of 2/3 of the poses; runs: the label of the most fitting poses
    assert structure["subset"] and len(structure["points"]) == (3 if layout == "mixed" else 1)
    assert structure["n_poses"] >= 20


@settings(max_examples=12, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(shape=shapes)
def test_drawn_shapes_go_through_every_stage(shape, tmp_path, capsys):
    _check(shape, tmp_path, capsys, QUICK)


@pytest.mark.slow
@settings(max_examples=200, deadline=None, derandomize=True, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(shape=shapes)
def test_two_hundred_drawn_shapes_go_through_every_stage(shape, tmp_path, capsys):
    _check(shape, tmp_path, capsys, SLOW)
