"""One name per idea (issue 33), checked on every command's parser as ``zrp`` builds it: no
command shows two names of one idea of zrp/cli/aliases.py's SYNONYMS table, every old name
still accepted is a hidden deprecated alias listed there, every command with a progress display
has the one ``--progress/--no-progress`` option, and no option is accepted abbreviated."""

from __future__ import annotations

import argparse
import inspect
import re
import sys

import pytest

from zrp.cli.aliases import DISTINCT, SYNONYMS, DeprecatedAlias
from zrp.cli.app import build_parser


def _commands() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


COMMANDS = _commands()


def _visible(p: argparse.ArgumentParser) -> set[str]:
    return {s for a in p._actions if a.help != argparse.SUPPRESS for s in a.option_strings}


def _hidden(p: argparse.ArgumentParser) -> set[str]:
    return {s for a in p._actions if a.help == argparse.SUPPRESS for s in a.option_strings}


def test_the_walk_finds_every_command():
    # the walk is over the parser zrp runs: a command missing here would go unchecked
    assert len(COMMANDS) >= 25
    assert {"measure", "compensate", "export", "import", "mjcf", "paper", "render",
            "gap-benchmark", "tolerance", "diagnose"} <= set(COMMANDS)


def test_no_two_names_of_one_idea_are_shown_anywhere():
    shown: dict[str, list[str]] = {}
    for name, p in COMMANDS.items():
        for opt in _visible(p):
            shown.setdefault(opt, []).append(name)
    clashes = []
    for new, olds in SYNONYMS.items():
        names = [o for o in (new, *olds) if o in shown]
        if len(names) > 1:
            clashes.append(", ".join(f"{o} ({' '.join(sorted(shown[o]))})" for o in names))
    assert not clashes, "one idea shown under several names: " + "; ".join(clashes)


def test_every_old_name_is_a_hidden_alias_of_its_new_name():
    olds = {old: new for new, names in SYNONYMS.items() for old in names}
    for name, p in COMMANDS.items():
        for a in p._actions:
            if isinstance(a, DeprecatedAlias):
                old = a.option_strings[0]
                assert olds.get(old) == a.new_name, (
                    f"zrp {name} {old}: a deprecated alias not in SYNONYMS[{a.new_name!r}]")
                assert a.help == argparse.SUPPRESS
                assert a.new_name in _visible(p) and a.dest == a.target.dest
        for opt in _hidden(p) & set(olds):
            action = p._option_string_actions[opt]
            assert isinstance(action, DeprecatedAlias), f"zrp {name} {opt}: hidden, no alias"


def test_every_old_name_in_the_table_is_still_accepted_somewhere():
    # an old name nobody accepts any more is a stale entry (or an alias forgotten)
    hidden = set().union(*(_hidden(p) for p in COMMANDS.values()))
    for new, olds in SYNONYMS.items():
        for old in olds:
            assert old in hidden, f"{old} (now {new}) is not a deprecated alias of any command"


def _has_progress_display(p: argparse.ArgumentParser) -> bool:
    """The command's code hands a progress setting to the library or draws its own bar."""
    src = inspect.getsource(sys.modules[p._defaults["func"].__module__])
    return bool(re.search(r"\bprogress=(?!False)|\btqdm\b|args\.progress", src))


def test_every_command_with_a_progress_display_has_progress_no_progress():
    with_display = {n for n, p in COMMANDS.items() if _has_progress_display(p)}
    assert {"measure", "tolerance", "render", "gap-benchmark", "motion-benchmark", "diagnose",
            "calibrate", "paper", "plan-benchmark"} <= with_display
    for name, p in COMMANDS.items():
        acts = [a for a in p._actions if a.help != argparse.SUPPRESS and any(
            "progress" in s or "quiet" in s for s in a.option_strings)]
        if name not in with_display:
            assert not acts, f"zrp {name}: a progress option but no progress display"
            continue
        assert len(acts) == 1, f"zrp {name}: {[a.option_strings for a in acts]}"
        a = acts[0]
        assert a.option_strings == ["--progress", "--no-progress"], f"zrp {name}"
        assert isinstance(a, argparse.BooleanOptionalAction) and a.default is True, name
        assert a.dest == "progress" and p.get_default("progress") is True, name


def test_no_option_is_accepted_abbreviated():
    assert all(p.allow_abbrev is False for p in COMMANDS.values())
    assert build_parser().allow_abbrev is False


def test_temp_is_not_temp_rise(capsys):
    # compensate --temp (deg C) and measure --temp-rise (K) are different ideas: typing the
    # one in the other command is refused, not silently read as the other
    assert ("--temp", "--temp-rise") in DISTINCT
    parser = build_parser()
    with pytest.raises(SystemExit) as exc:
        parser.parse_args(["measure", "--out", "d.csv", "--temp", "20"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "zrp measure: error: unrecognized arguments: --temp 20 (options are not " \
           "abbreviated: --temp could be --temp-rise)" in err
    assert parser.parse_args(["measure", "--out", "d.csv", "--temp-rise", "20"]).temp_rise == 20
    args = parser.parse_args(["compensate", "--calibration", "c.json", "--targets", "t.csv",
                              "--out", "o.csv", "--temp", "20"])
    assert args.temp == 20


@pytest.mark.parametrize("argv", [["tolerance", "--no-prog"], ["render", "--no-dyn"],
                                  ["diagnose", "--model", "m", "--data", "d", "--out", "o",
                                   "--no-pl"]])
def test_a_shortened_option_is_refused(argv, capsys):
    with pytest.raises(SystemExit):
        build_parser().parse_args(argv)
    err = capsys.readouterr().err
    assert f"zrp {argv[0]}: error: unrecognized arguments: {argv[-1]} (options are not " \
           f"abbreviated: {argv[-1]} could be {argv[-1]}" in err


class _Stream:
    def __init__(self, tty: bool) -> None:
        self.tty = tty

    def isatty(self) -> bool:
        return self.tty


@pytest.mark.parametrize(("tty", "argv", "drawn"), [
    (True, [], True), (True, ["--no-progress"], False), (False, [], False),
    (False, ["--progress"], False)])
def test_a_bar_is_drawn_on_a_terminal_only(tty, argv, drawn, monkeypatch):
    # a bar's carriage returns would garble a pipe or a log: --progress (the default) draws
    # one only when stderr is a terminal
    from zrp.cli.options import draw_bar

    args = build_parser().parse_args(["tolerance", *argv])
    monkeypatch.setattr(sys, "stderr", _Stream(tty))
    assert draw_bar(args) is drawn
    monkeypatch.setattr(sys, "stderr", None)  # started with stderr closed (`2>&-`)
    assert draw_bar(args) is False
