"""``zrp plan --limits`` checked at the boundary (issue 26): NaN, infinite and inverted pairs
and all-fixed joints are named errors (they crashed, or returned 20 identical poses); the
output file is not written."""

from __future__ import annotations

import pytest

from zrp.cli import main


@pytest.mark.parametrize(("limits", "message"), [
    ("nan:1,0:1,0:1,0:1,0:1,0:1", "joint 1 is 'nan:1'; expected finite numbers"),
    ("0:1,0:1,0:1,0:1,0:1,0:inf", "joint 6 is '0:inf'; expected finite numbers"),
    ("0:1,1:0,0:1,0:1,0:1,0:1", "joint 2 is '1:0': LO > HI"),
    ("0:0,0:0,0:0,0:0,0:0,0:0", "every joint has LO = HI: no joint can move"),
    ("5:5,5:5,5:5,5:5,5:5,5:5", "every joint has LO = HI"),
])
def test_bad_limits_are_named_and_nothing_is_written(tmp_path, capsys, limits, message):
    out = tmp_path / "plan.csv"
    code = main(["plan", "--model", "puma", "--poses", "20", "--effects", "joint_offset",
                 "--out", str(out), "--limits", limits])
    err = capsys.readouterr().err
    assert code == 2 and message in err and "Traceback" not in err
    assert not out.exists()


def test_one_free_joint_is_enough_to_plan(tmp_path, capsys):
    out = tmp_path / "plan.csv"
    code = main(["plan", "--model", "puma", "--poses", "8", "--effects", "joint_offset",
                 "--out", str(out), "--candidates", "50",
                 "--limits", "0:0,-1:1,0:0,0:0,0:0,0:0"])
    capsys.readouterr()
    assert code == 0
    rows = out.read_text().splitlines()[1:]
    assert len({r.split(",")[2] for r in rows}) > 1  # q2 varies
