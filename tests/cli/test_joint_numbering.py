"""Joints are counted the same way in every file a user reads (issue 33): from 1, as the
parameter names (``q2.backlash``) and the report do; the registration's parameters belong to
no joint (null, never 0)."""

from __future__ import annotations

import contextlib
import io
import json
import re
import warnings

import pytest

from zrp.cli.app import main

N_JOINTS = 6  # the built-in PUMA


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("numbering")
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()), \
            contextlib.redirect_stderr(io.StringIO()):
        warnings.simplefilter("ignore")
        assert main(["measure", "--out", str(folder / "d.csv"), "--poses", "150", "--seed", "1",
                     "--effect", "backlash:2=0.5mrad", "--effect", "cyclic_error:5=0.4mrad"]) == 0
        assert main(["calibrate", "--model", "puma", "--data", str(folder / "d.csv"), "--out",
                     str(folder / "cal"), "--no-progress"]) == 0
    return folder / "cal"


def _joint_values(x, path=""):
    """(path, value) of every "joint"/"joints"/"*_joints" entry of a JSON document."""
    if isinstance(x, dict):
        for k, v in x.items():
            if k == "joint" or k == "joints" or k.endswith("_joints"):
                yield f"{path}/{k}", v
            yield from _joint_values(v, f"{path}/{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from _joint_values(v, f"{path}[{i}]")


def _numbers(v):
    if isinstance(v, dict):
        return [v["joint"]] if "joint" in v else []
    if isinstance(v, list):
        return [j for e in v for j in _numbers(e)]
    return [v]


def _named(x, path=""):
    """(path, name, joint) of every entry with a parameter name and a joint."""
    if isinstance(x, dict):
        if "name" in x and "joint" in x:
            yield path, x["name"], x["joint"]
        for k, v in x.items():
            yield from _named(v, f"{path}/{k}")
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from _named(v, f"{path}[{i}]")


@pytest.mark.parametrize("name", ["diagnosis.json", "compensation.json"])
def test_every_joint_number_is_one_based_or_null(run, name):
    doc = json.loads((run / name).read_text())
    seen = list(_joint_values(doc))
    numbers = [(p, j) for p, v in seen for j in _numbers(v) if j is not None]
    assert numbers, f"{name}: no joint numbers found (the walk would pass vacuously)"
    bad = [(p, j) for p, j in numbers if not (isinstance(j, int) and 1 <= j <= N_JOINTS)]
    assert not bad, f"{name}: joints outside 1..{N_JOINTS}: {bad[:5]}"


@pytest.mark.parametrize("name", ["diagnosis.json", "compensation.json"])
def test_a_parameter_name_and_its_joint_agree(run, name):
    doc = json.loads((run / name).read_text())
    named = list(_named(doc))
    assert named
    for path, pname, joint in named:
        m = re.match(r"[qub](\d+)\.", pname)
        if m is None:  # base, tool and registration parameters belong to no joint
            assert joint is None, f"{path}: {pname} has joint {joint}"
        elif pname.startswith(("q", "u")):  # b{k}: the body after joint k-1 (k = 1..n+1)
            assert joint == int(m.group(1)), f"{path}: {pname} has joint {joint}"


def test_the_report_names_the_joints_diagnosis_json_names(run):
    """Every effect of diagnosis.json's final model appears in the report's verdict and its
    section heading with the same joint numbers ("joint 2", "joints 2-3")."""
    from zrp.gap.report.headline import effect_joints

    doc = json.loads((run / "diagnosis.json").read_text())
    report = (run / "report.md").read_text()
    effects = [e for e in doc["final"]["effects"] if e["joints"]]
    assert effects, "the run's final model names no joint (the check would be vacuous)"
    for eff in effects:
        words = effect_joints(eff["effect"], eff["joints"])
        assert re.search(r"\(joints? \d", words)
        assert report.count(words) >= 3, (words, "verdict, final-model line, heading")
        assert f"### {words}" in report


def test_joint_words_count_from_one():
    from zrp.gap.report.headline import effect_joints

    assert effect_joints("backlash", [2]) == "backlash (joint 2)"
    assert effect_joints("backlash", [2, 3, 5]) == "backlash (joints 2-3, 5)"
    assert effect_joints("thermal", []) == "thermal"
