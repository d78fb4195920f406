"""Issue 41 finding 9: an old and a new name of one option given different values were
resolved silently (the last won); now refused naming both. The same value twice, or the old
name alone, still runs (with the deprecation notice)."""

from __future__ import annotations

import pytest

from zrp.cli import main


@pytest.mark.parametrize("argv", [
    ["mjcf", "--from", "x.xml", "--end-link", "a", "--body", "b"],
    ["mjcf", "--from", "x.xml", "--body", "b", "--end-link", "a"],
    ["render", "--progress", "--quiet"],
])
def test_an_old_and_a_new_name_with_different_values_are_refused(argv, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    err = capsys.readouterr().err
    assert exc.value.code == 2
    assert "are two names of one option (one deprecated) and were given different values" in err
    old, new = ("--body", "--end-link") if "--body" in argv else ("--quiet", "--progress")
    assert old in err.splitlines()[-1] and new in err.splitlines()[-1]


def test_the_same_value_under_both_names_is_not_a_conflict():
    from zrp.cli.app import build_parser

    args = build_parser().parse_args(["mjcf", "--from", "x.xml", "--body", "a", "--end-link", "a"])
    assert args.end_link == "a"
