"""The calibration round trip with a learned residual term, on the simulated robot (issue 36):
measure -> calibrate --residual-model -> compensate -> verify, each step from the command line
reading the previous step's files.

The simulated PUMA 560 hides a joint offset and a cyclic error of joint 2 at the third
harmonic, which the library's cyclic-error effect (harmonics 1 and 2) cannot take: a smooth
remainder of the joint angles. The compensated program (random reachable poses inside the
learned term's training ranges), commanded on the simulated robot, must

* miss its targets by what the calibration predicts: the achieved RMS (``zrp verify``) equal
  to the withheld RMS of the physical model with the learned term (compensation.json) within
  three standard errors of the two estimates. Both are means of squared errors over poses
  drawn alike (T program targets, N withheld poses); the standard error of each mean is the
  spread of the per-target squared errors (verify's per-target output: tracker noise plus
  what remains) over sqrt(T) and sqrt(N), halved for the RMS (delta method: d RMS =
  d MS / (2 RMS));
* miss them by less than the same program compensated by the physical model alone
  (``zrp calibrate`` without --residual-model, the same data).
"""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import zrp
from zrp.calibration.guards import RANGE_SHARE
from zrp.cli import main

HIDDEN = ["joint_offset:2=0.5mrad", "cyclic_error:2:h3=0.5mrad"]
POSES = 800
TARGETS = 100
SEED = 3


def _run(capsys, argv):
    rc = main([*argv, "--json"])
    out, err = capsys.readouterr()
    assert rc == 0, err
    return json.loads(out)


def _program(model, training_ranges, path):
    """TARGETS random reachable joint vectors inside the training ranges, as a program CSV."""
    rng = np.random.default_rng(7)
    q = zrp.reachable_poses(model, 4 * TARGETS, rng)
    inside = np.ones(len(q), dtype=bool)
    for name, (lo, hi) in training_ranges.items():
        k = int(name[1:]) - 1
        tol = RANGE_SHARE * (hi - lo)
        inside &= (q[:, k] >= lo + tol) & (q[:, k] <= hi - tol)
    q = q[inside][:TARGETS]
    assert len(q) == TARGETS
    with open(path, "w") as fh:
        fh.write("target," + ",".join(f"q{k}" for k in range(1, model.n + 1)) + "\n")
        for i, row in enumerate(q):
            fh.write(f"T{i + 1}," + ",".join(repr(float(v)) for v in row) + "\n")


def _per_target(path):
    with open(path) as fh:
        return np.array([float(r["error_after[mm]"]) for r in csv.DictReader(fh)])


@pytest.mark.slow
def test_compensated_program_with_the_learned_term_meets_its_prediction(tmp_path, capsys):
    model = zrp.load_model("puma")
    hidden = [a for spec in HIDDEN for a in ("--effect", spec)]
    _run(capsys, ["measure", "--model", "puma", *hidden, "--poses", str(POSES), "--seed",
                  str(SEED), "--out", str(tmp_path / "meas.csv")])
    for tag, extra in (("hybrid", ["--residual-model"]), ("physical", [])):
        _run(capsys, ["calibrate", "--model", "puma", "--data", str(tmp_path / "meas.csv"),
                      "--out", str(tmp_path / tag), "--no-progress", *extra])
    doc = json.loads((tmp_path / "hybrid" / "compensation.json").read_text())
    term = doc["learned_residual"]
    assert term is not None, "the learned term was not kept"
    assert json.loads((tmp_path / "physical" / "compensation.json").read_text())[
        "learned_residual"] is None
    _program(model, term["training_ranges"], tmp_path / "program.csv")
    achieved = {}
    for tag in ("hybrid", "physical"):
        comp_json = str(tmp_path / tag / "compensation.json")
        # near-singular program rows are compensated too (flagged); none is outside a range
        comp = _run(capsys, ["compensate", "--accept-flagged", "--calibration", comp_json,
                             "--targets", str(tmp_path / "program.csv"),
                             "--out", str(tmp_path / f"cmd_{tag}.csv")])
        assert comp["outside_measured"] == 0
        achieved[tag] = _run(capsys, [
            "verify", "--calibration", comp_json, "--truth", str(tmp_path / "meas.truth.json"),
            "--targets", str(tmp_path / "program.csv"), "--commands",
            str(tmp_path / f"cmd_{tag}.csv"), "--out", str(tmp_path / f"verify_{tag}.csv")])
    e2 = _per_target(tmp_path / "verify_hybrid.csv") ** 2
    withheld = len(json.loads((tmp_path / "hybrid" / "diagnosis.json").read_text())[
        "split"]["withheld"])
    predicted = term["withheld_rms_hybrid"]
    after = achieved["hybrid"]["rms_after"]
    assert after == pytest.approx(float(np.sqrt(e2.mean())), rel=1e-9)
    se_ms = float(e2.std(ddof=1)) * np.sqrt(1 / len(e2) + 1 / withheld)
    tol = 3 * se_ms / (2 * after)
    print(f"predicted {predicted:.4g} mm (physical alone {term['withheld_rms_physical']:.4g}),"
          f" achieved {after:.4g} +- {tol:.2g} (3 se); physical model alone achieved "
          f"{achieved['physical']['rms_after']:.4g}; noise {achieved['hybrid']['noise_rms']:.4g}")
    assert abs(after - predicted) <= tol
    assert after < achieved["physical"]["rms_after"]
    assert term["withheld_rms_hybrid"] < term["withheld_rms_physical"]
