"""One interval story (issue 33): every parameter table shows what the data determine; a
parameter held at nominal or undetermined is shown so, with the direction it belongs to, never
as plausible with an interval wider than its physical domain; an undetermined tool or base
direction is flagged in calibrated.toml and compensation.json."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tests.gap.test_wellposed import OFFSETS, TILT, _diagnose, ur_like
from tests.measured import full_pose_measurements
from zrp.calibration import CalibratedRobot, read_calibration, write_calibration
from zrp.gap.model.domains import parameter_domain
from zrp.gap.report import report_markdown


def _ur(span_rad: float, n_poses: int):
    """A UR-type arm, one reflector, positions only, joints within +-``span_rad``."""
    m = ur_like()
    meas = full_pose_measurements(m, n_poses, 3, tilt=TILT, tools=[[0.0, 60.0, 40.0]],
                                  probe_rotation=np.eye(3), sigma_orientation=1e-4,
                                  joint_offset=OFFSETS, quat=False, span_rad=span_rad)
    return _diagnose(m, meas)


@pytest.fixture(scope="module")
def ur_positions():
    return _ur(0.35, 120)


def _wider_than_domain(d, name: str) -> bool:
    p = d.parameter(name)
    dom = parameter_domain(p.name, p.effect, p.unit, max_tilt_rad=d.context.max_tilt_rad)
    if dom is None:
        return False
    return any(not (math.isfinite(lo) and math.isfinite(hi)) or hi - lo > dom.hi - dom.lo
               for lo, hi in (p.ci95, p.ci95_effect or p.ci95))


def _table_rows(md: str) -> dict[str, list[str]]:
    """Parameter -> cells of the rows of report.md's "Identified parameters" tables."""
    part = md.split("## Identified parameters", 1)[1].split("\n## ", 1)[0]
    rows = [ln.strip("|").split(" | ") for ln in part.splitlines() if ln.startswith("| ")]
    return {r[0].strip(): [c.strip() for c in r] for r in rows if r[0].strip() != "parameter"}


def test_no_parameter_is_shown_plausible_with_an_interval_wider_than_its_domain(ur_positions):
    d = ur_positions
    rows = _table_rows(report_markdown(d, figures=False))
    assert set(rows) == {p.name for p in d.final_parameters}
    wide = [n for n in rows if _wider_than_domain(d, n)]
    assert wide, "the common tilt of the axes is not pinned by one reflector's positions"
    for name, cells in rows.items():
        if cells[-1].startswith("determined"):
            assert not _wider_than_domain(d, name), (name, cells)
    # the held ones are shown held, with the combination they belong to, and no interval
    for name in wide:
        assert rows[name][-1].startswith("in a combination held at nominal: axis 6 tilted"), \
            rows[name]
        assert rows[name][2] == "not pinned (held)"
    # the same story in diagnosis.json
    und = {u["name"]: u for u in d.identification()["undetermined"]}
    assert set(wide) <= set(und) and all(und[n]["status"] == "held" for n in wide)


def test_an_undetermined_tool_and_base_are_flagged_in_the_controller_files(tmp_path,
                                                                           ur_positions):
    # joints within +-0.05 rad: the tool point and the base trade against the axis tilts
    d = _ur(0.05, 80)
    det = d.determination
    assert det["tool[s1].y"].status == "undetermined" and "u5.t2" in det["tool[s1].y"].direction
    cal = CalibratedRobot.from_diagnosis(d)
    write_calibration(cal, tmp_path / "calibrated.toml", tmp_path / "compensation.json")
    doc = json.loads((tmp_path / "compensation.json").read_text(encoding="utf-8"))
    flagged = {u.split(":")[0] for u in doc["undetermined"]}
    assert {"tool[s1].y", "base.rx"} <= flagged
    toml = (tmp_path / "calibrated.toml").read_text(encoding="utf-8")
    assert "# NOT DETERMINED by the data" in toml and "#   tool[s1].y: undetermined" in toml
    assert read_calibration(tmp_path / "compensation.json").undetermined == cal.undetermined
    # control: the wider poses pin the tool and the base, and nothing says otherwise
    wide = CalibratedRobot.from_diagnosis(ur_positions)
    assert not any(u.startswith(("tool[", "base.")) for u in wide.undetermined)
    assert all(u.split(":")[0] in {"b5.z", "u1.t2", "u2.t2", "u3.t2", "u4.t2", "u5.t2"}
               for u in wide.undetermined)
