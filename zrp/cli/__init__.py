"""The ``zrp`` command line: the application layer above :mod:`zrp` (the core), :mod:`mjcf`
and :mod:`sim`. :mod:`zrp.cli.app` builds the parser; each module of
:mod:`zrp.cli.commands` registers one subcommand.
"""

from zrp.cli.app import build_parser as build_parser
from zrp.cli.app import emit as emit
from zrp.cli.app import main as main

__all__ = ["build_parser", "emit", "main"]
