"""Deprecated option names (issue 33: one name per idea across commands): an old name kept as
an alias of the new one for one minor version, announced on stderr when used and listed in
zrp/CHANGELOG.md.

    action = p.add_argument("--load", ...)
    deprecated_alias(p, "--payload", action)
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

__all__ = ["REMOVED_IN", "deprecated_alias"]

#: the version that removes the aliases of this one
REMOVED_IN = "0.6.0"


def deprecated_alias(parser: argparse.ArgumentParser, old: str, new: argparse.Action,
                     new_name: str | None = None) -> None:
    """Accept ``old`` as ``new`` (the action of the current name), with a one-line notice on
    stderr; hidden from ``--help``. ``new_name``: the option string ``new`` is called with
    (default its first; e.g. ``--no-progress`` of a ``--progress/--no-progress`` pair)."""
    name = new_name or new.option_strings[0]

    class _Alias(argparse.Action):
        def __call__(self, p: argparse.ArgumentParser, ns: argparse.Namespace, values: Any,
                     option_string: str | None = None) -> None:
            print(f"zrp: warning: {old} is deprecated and will be removed in {REMOVED_IN}; "
                  f"use {name}", file=sys.stderr)
            new(p, ns, values, name)

    parser.add_argument(old, dest=new.dest, nargs=new.nargs, type=new.type,
                        metavar=new.metavar, action=_Alias, help=argparse.SUPPRESS,
                        default=argparse.SUPPRESS)
