"""One name per idea (issue 33): the old option names are deprecated aliases of the new ones
for one minor version: the same value, and a notice on stderr naming the new option."""

from __future__ import annotations

import pytest

from zrp.cli.aliases import REMOVED_IN
from zrp.cli.app import build_parser

CASES = [
    (["measure", "--out", "d.csv", "--payload", "2.5"], ["measure", "--out", "d.csv",
                                                          "--load", "2.5"], "load", 2.5),
    (["measure", "--out", "d.csv", "--arm", "ur10.urdf"], ["measure", "--out", "d.csv",
                                                            "--mjcf", "ur10.urdf"], "mjcf",
     "ur10.urdf"),
    (["gap-benchmark", "--arm", "a.urdf"], ["gap-benchmark", "--mjcf", "a.urdf"], "mjcf",
     "a.urdf"),
    (["render", "--out-dir", "videos"], ["render", "--out", "videos"], "out", "videos"),
    (["render", "--quiet"], ["render", "--no-progress"], "progress", False),
    (["export", "--to", "urdf", "--end", "tool0"], ["export", "--to", "urdf", "--end-link",
                                                    "tool0"], "end_link", "tool0"),
    (["import", "a.urdf", "--end", "tool0"], ["import", "a.urdf", "--end-link", "tool0"],
     "end_link", "tool0"),
    (["mjcf", "--from", "a.xml", "--body", "hand"], ["mjcf", "--from", "a.xml", "--end-link",
                                                     "hand"], "end_link", "hand"),
    (["paper", "--no-figures"], ["paper", "--no-plots"], "no_plots", True),
    (["gap-benchmark", "--poses-from", "circle"], ["gap-benchmark", "--trajectory", "circle"],
     "trajectory", "circle"),
]


@pytest.mark.parametrize(("old", "new", "dest", "value"), CASES)
def test_an_old_name_gives_the_new_value_and_says_so(old, new, dest, value, capsys):
    parser = build_parser()
    assert getattr(parser.parse_args(new), dest) == value
    assert capsys.readouterr().err == ""
    assert getattr(parser.parse_args(old), dest) == value
    err = capsys.readouterr().err
    name = next(a for a in old if a.startswith("--") and a not in new)
    assert f"{name} is deprecated and will be removed in {REMOVED_IN}; use " in err


def test_an_old_choice_is_still_checked(capsys):
    # the alias keeps the new option's choices: a typo through the old name is refused too
    with pytest.raises(SystemExit):
        build_parser().parse_args(["gap-benchmark", "--poses-from", "square"])
    assert "invalid choice: 'square'" in capsys.readouterr().err


def test_the_old_names_are_hidden_from_help(capsys):
    with pytest.raises(SystemExit):
        build_parser().parse_args(["render", "--help"])
    out = capsys.readouterr().out
    assert "--out-dir" not in out and "--quiet" not in out and "--no-progress" in out
