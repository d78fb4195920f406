"""Each step of the calibration chain reads the previous step's file and refuses what does
not fit, by name: plan within the model's limits, unidentifiable parameters listed as such,
measure --poses PLAN.csv, compensate's seeds in degrees, verify's inputs."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

import zrp
from zrp.calibration.planfile import read_plan
from zrp.cli import main
from zrp.errors import InputError

PUMA = zrp.load_model("puma")
#: the PUMA with joint 2 limited to +-1.2 rad and joint 3 to [-0.5, 2.0]
LIMITS = [None, (-1.2, 1.2), (-0.5, 2.0), None, None, None]


def _limited(tmp_path):
    m = zrp.Manipulator.from_arrays(PUMA.axes, PUMA.bodies, axial=PUMA.end_effector.axial,
                                    transverse=PUMA.end_effector.transverse, name="puma_lim",
                                    limits=LIMITS)
    return str(zrp.save_model(m, tmp_path / "lim.toml")), m


def _json(capsys, argv, code=0):
    rc = main([*argv, "--json"])
    out, err = capsys.readouterr()
    assert rc == code, err
    return json.loads(out) if code == 0 else err


def test_plan_keeps_to_the_model_limits_and_names_unidentifiable(tmp_path, capsys):
    path, m = _limited(tmp_path)
    out = tmp_path / "plan.csv"
    res = _json(capsys, ["plan", "--model", path, "--poses", "20", "--effects", "joint_offset",
                         "--out", str(out), "--candidates", "300"])
    plan = read_plan(out, m)
    assert np.all(plan.q[:, 1] >= -1.2) and np.all(plan.q[:, 1] <= 1.2)
    assert np.all(plan.q[:, 2] >= -0.5) and np.all(plan.q[:, 2] <= 2.0)
    assert np.all(np.abs(plan.q) <= 2.5)  # the default range elsewhere
    # with the tool point on joint 6's axis its offset moves nothing: listed, not a number
    assert "q6.offset" in res["unidentifiable"] and "q1.offset" in res["unidentifiable"]
    assert all(p["name"] not in res["unidentifiable"] for p in res["parameters"])
    assert max(p["std"] for p in res["parameters"]) < 1e-2
    main(["plan", "--model", path, "--poses", "20", "--effects", "joint_offset", "--out",
          str(tmp_path / "p2.csv"), "--candidates", "300"])
    assert "q6.offset: unidentifiable" in capsys.readouterr().out
    err = _json(capsys, ["plan", "--model", path, "--poses", "20", "--effects", "joint_offset",
                         "--out", str(tmp_path / "p3.csv"),
                         "--limits=-2:2,-1.5:1.5,-0.5:2,-2:2,-2:2,-2:2"], code=2)
    assert "joint 2" in err and "beyond the model's limits" in err


def test_measure_reads_a_plan_and_refuses_a_broken_one(tmp_path, capsys):
    path, m = _limited(tmp_path)
    plan = tmp_path / "plan.csv"
    _json(capsys, ["plan", "--model", path, "--poses", "10", "--effects", "joint_offset",
                   "--out", str(plan), "--candidates", "200", "--deg"])
    assert "q2[deg]" in plan.read_text().splitlines()[0]  # written with --deg: declared
    res = _json(capsys, ["measure", "--model", path, "--poses", str(plan), "--out",
                         str(tmp_path / "m.csv")])
    assert res["poses"] == 10 and res["trajectory"] == "plan" and res["approach"] == "random"
    planned = read_plan(plan, m)
    with open(tmp_path / "m.csv") as fh:
        rows = list(csv.DictReader(fh))
    first = {r["pose"]: r for r in rows}
    got = np.array([[float(first[p][f"q{k}"]) for k in range(1, 7)] for p in first])
    assert np.allclose(got, planned.q, atol=1e-12)  # the plan's poses, in its order
    assert np.array_equal(np.array([[float(first[p][f"dir{k}"]) for k in range(1, 7)]
                                    for p in first]), planned.direction)
    bad = tmp_path / "bad.csv"
    bad.write_text(plan.read_text().replace("dir6", "colour"))
    err = _json(capsys, ["measure", "--model", path, "--poses", str(bad), "--out",
                         str(tmp_path / "m2.csv")], code=2)
    assert "missing ['dir6'], unknown ['colour']" in err
    rad_as_deg = tmp_path / "rad.csv"  # radians declared as degrees
    text = plan.read_text().splitlines()
    qs = np.radians([[float(v) for v in line.split(",")[1:7]] for line in text[1:]])
    rad_as_deg.write_text("\n".join([text[0]] + [
        ",".join([line.split(",")[0], *(repr(float(v)) for v in q), *line.split(",")[7:]])
        for line, q in zip(text[1:], qs, strict=True)]) + "\n")
    err = _json(capsys, ["measure", "--model", path, "--poses", str(rad_as_deg), "--out",
                         str(tmp_path / "m3.csv")], code=2)
    assert "look like radians in a degree column" in err
    with pytest.raises(InputError, match=r"none\.csv: no such file"):
        read_plan(tmp_path / "none.csv", m)


def test_compensate_refuses_seeds_in_degrees(tmp_path, capsys, measured_csv):
    """Issue 26: seeds in degrees wrote q1 = 93.96 rad with converged=1."""
    _json(capsys, ["calibrate", "--model", "puma", "--data", str(measured_csv), "--out",
                   str(tmp_path / "cal")])
    q = np.degrees(zrp.reachable_poses(PUMA, 4, np.random.default_rng(0)))
    t = tmp_path / "t.csv"
    t.write_text("target,q1,q2,q3,q4,q5,q6\n" + "".join(
        f"T{i},{','.join(repr(float(v)) for v in r)}\n" for i, r in enumerate(q)))
    err = _json(capsys, ["compensate", "--calibration", str(tmp_path / "cal/compensation.json"),
                         "--targets", str(t), "--out", str(tmp_path / "c.csv")], code=2)
    assert "looks like degrees" in err and "--deg" in err
    assert not (tmp_path / "c.csv").exists()
    res = _json(capsys, ["compensate", "--calibration", str(tmp_path / "cal/compensation.json"),
                         "--targets", str(t), "--out", str(tmp_path / "c.csv"), "--deg",
                         "--accept-flagged"])
    assert res["not_converged"] == 0


def test_verify_refuses_mismatched_inputs(tmp_path, capsys, measured_csv):
    _json(capsys, ["calibrate", "--model", "puma", "--data", str(measured_csv), "--out",
                   str(tmp_path / "cal")])
    comp = str(tmp_path / "cal/compensation.json")
    q = zrp.reachable_poses(PUMA, 3, np.random.default_rng(1))
    t = tmp_path / "t.csv"
    t.write_text("target,q1,q2,q3,q4,q5,q6\n" + "".join(
        f"T{i},{','.join(repr(float(v)) for v in r)}\n" for i, r in enumerate(q)))
    _json(capsys, ["compensate", "--calibration", comp, "--targets", str(t), "--out",
                   str(tmp_path / "c.csv"), "--accept-flagged"])
    truth = tmp_path / "truth.json"
    truth.write_text(json.dumps({"format": "zrp-real-robot-truth", "model": "stanford",
                                 "length_unit": "mm"}))
    common = ["verify", "--calibration", comp, "--targets", str(t), "--commands",
              str(tmp_path / "c.csv")]
    err = _json(capsys, [*common, "--truth", str(truth)], code=2)
    assert "--truth" in err and "'stanford'" in err
    truth.write_text("{not json")
    assert "not a JSON truth file" in _json(capsys, [*common, "--truth", str(truth)], code=2)
    t2 = tmp_path / "t2.csv"
    t2.write_text(t.read_text().replace("T2,", "T9,"))
    err = _json(capsys, ["verify", "--calibration", comp, "--targets", str(t2), "--commands",
                         str(tmp_path / "c.csv"), "--truth", str(truth)], code=2)
    assert "--commands" in err
