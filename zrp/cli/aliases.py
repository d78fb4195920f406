"""Deprecated option names (issue 33: one name per idea across commands): an old name kept as
an alias of the new one for one minor version, announced on stderr when used and listed in
zrp/CHANGELOG.md.

    action = p.add_argument("--load", ...)
    deprecated_alias(p, "--payload", action)

:data:`SYNONYMS` is the table of the names each idea had: the current name and the old names it
replaced. tests/cli/test_one_name.py walks every command's parser and checks that no command
shows two names of one idea, that every old name still accepted is a hidden alias listed here,
and that no option is accepted abbreviated (every parser has ``allow_abbrev=False``, so
``measure --temp`` is refused instead of silently meaning ``--temp-rise``).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

__all__ = ["DISTINCT", "REMOVED_IN", "SYNONYMS", "DeprecatedAlias", "deprecated_alias"]

#: the version that removes the aliases of this one
REMOVED_IN = "0.6.0"

#: One idea, one name: the current option name -> the old names of the same idea, accepted as
#: deprecated aliases (hidden from --help) until :data:`REMOVED_IN`.
SYNONYMS: dict[str, tuple[str, ...]] = {
    # a payload at the tool point, kg (measure --payload; compensate --load)
    "--load": ("--payload",),
    # the arm's shipped URDF or MJCF (measure, gap-benchmark --arm; diagnose, calibrate --mjcf)
    "--mjcf": ("--arm",),
    # where the outputs go (render --out-dir; every other command --out)
    "--out": ("--out-dir",),
    # silence the progress display (render --quiet; --progress/--no-progress elsewhere)
    "--no-progress": ("--quiet",),
    # the last link (URDF) or body (MJCF) of the chain (export, import --end; mjcf --body;
    # excite, diagnose-dynamics --end-link)
    "--end-link": ("--end", "--body"),
    # skip the PNG plots (paper --no-figures; diagnose, gap-benchmark --no-plots)
    "--no-plots": ("--no-figures",),
    # the poses measured: random or along the PUMA circle (gap-benchmark --poses-from;
    # measure --trajectory)
    "--trajectory": ("--poses-from",),
}

#: Look-alike names of different ideas, kept apart on purpose (each with why); never
#: abbreviated, so neither can be typed for the other.
DISTINCT: dict[tuple[str, str], str] = {
    ("--temp", "--temp-rise"): "compensate --temp is the robot's temperature when the commands "
    "run (deg C); measure --temp-rise is the warm-up during a simulated session (K)",
}


_USES = "_zrp_option_uses"


def _record(p: argparse.ArgumentParser, ns: argparse.Namespace, dest: str, name: str) -> None:
    """Record that option ``name`` set ``dest``; an old and a new name of one option that
    set it to different values are refused naming both (issue 41 finding 9: the last no
    longer wins silently)."""
    uses: dict[str, list[tuple[str, Any]]] = ns.__dict__.setdefault(_USES, {})
    value = getattr(ns, dest, None)
    for other, was in uses.get(dest, []):
        if other != name and was != value:
            p.error(f"{other} and {name} are two names of one option (one deprecated) and "
                    f"were given different values ({was!r}, {value!r}); give it once")
    uses.setdefault(dest, []).append((name, value))


class _Recorded:
    """Mixed into the current name's action of an alias: records each use (:func:`_record`)."""

    def __call__(self, p: argparse.ArgumentParser, ns: argparse.Namespace, values: Any,
                 option_string: str | None = None) -> None:
        super().__call__(p, ns, values, option_string)  # type: ignore[misc]
        _record(p, ns, self.dest, option_string or "")  # type: ignore[attr-defined]


def _recorded(action: argparse.Action) -> None:
    cls = type(action)
    if not issubclass(cls, _Recorded):
        action.__class__ = type(f"Recorded{cls.__name__}", (_Recorded, cls), {})


class DeprecatedAlias(argparse.Action):
    """An old option name: stores through ``target`` (the action of the current name) after a
    one-line notice on stderr; given with the current name and another value: refused."""

    def __init__(self, option_strings: list[str], dest: str, *, target: argparse.Action,
                 new_name: str, **kwargs: Any) -> None:
        super().__init__(option_strings, dest, **kwargs)
        self.target, self.new_name = target, new_name

    def __call__(self, p: argparse.ArgumentParser, ns: argparse.Namespace, values: Any,
                 option_string: str | None = None) -> None:
        print(f"zrp: warning: {option_string} is deprecated and will be removed in "
              f"{REMOVED_IN}; use {self.new_name}", file=sys.stderr)
        # the target stores (not recorded as the new name: this use is the old name's)
        super(_Recorded, self.target).__call__(p, ns, values, self.new_name)  # type: ignore[misc]
        _record(p, ns, self.dest, option_string or "")


def deprecated_alias(parser: argparse.ArgumentParser | argparse._ArgumentGroup, old: str,
                     new: argparse.Action, new_name: str | None = None) -> None:
    """Accept ``old`` as ``new`` (the action of the current name), with a one-line notice on
    stderr; hidden from ``--help``. ``new_name``: the option string ``new`` is called with
    (default its first; e.g. ``--no-progress`` of a ``--progress/--no-progress`` pair). Both
    given with different values: refused naming both."""
    _recorded(new)
    parser.add_argument(old, dest=new.dest, nargs=new.nargs, type=new.type, choices=new.choices,
                        metavar=new.metavar, action=DeprecatedAlias, help=argparse.SUPPRESS,
                        default=argparse.SUPPRESS, target=new,
                        new_name=new_name or new.option_strings[0])
