"""The ``zrp`` command line. Subcommands live in :mod:`zrp.cli.commands`, one module each.

Every module in ``zrp/cli/commands/`` defines ``register(subparsers)``, which adds its parser and
sets ``func`` (called with the parsed namespace, returning an exit code). Errors derived from
:class:`zrp.ZRPError` are printed as one clear line (exit code 2) instead of a traceback, and
every warning as one line ``zrp CMD: warning: ...`` (:func:`one_line_warnings`), the same in
every command; output closed early (``zrp fk --json | head -c 10``) ends quietly with status
141, and a full device is one line too (:mod:`zrp.cli.streams`).

Registration stays light: a command module imports its numerical code (SciPy, numba, MuJoCo,
Matplotlib, Dask) inside the function that runs it, so ``zrp --help`` and ``zrp CMD --help``
start quickly (tests/cli/test_startup.py checks it; tests/benchmarks/bench_cli_startup.py
times it).
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import pkgutil
import re
import signal
import sys
import warnings
from collections.abc import Iterator, Sequence
from typing import Any, TextIO

from zrp import __version__
from zrp.cli import commands
from zrp.cli.signals import handling
from zrp.cli.streams import CLOSED_EXIT, closed_output, device_error, path_error
from zrp.errors import OutputExistsError, ZRPError
from zrp.output.inputs import reading
from zrp.packages import PackageShadowedError, check_own_packages

__all__ = ["API_TO_CLI", "build_parser", "cli_message", "emit", "main", "one_line_warnings"]


class _Parser(argparse.ArgumentParser):
    """The ``zrp`` parser: an option it does not know is refused by the command's own parser,
    naming the options it may have been short for (options are never abbreviated)."""

    def parse_args(self, args: Sequence[str] | None = None,  # type: ignore[override]
                   namespace: argparse.Namespace | None = None) -> argparse.Namespace:
        ns, extras = self.parse_known_args(args, namespace)
        if extras:
            sub = next(a for a in self._actions if isinstance(a, argparse._SubParsersAction))
            cmd = sub.choices.get(getattr(ns, "command", None) or "", self)
            cmd.error(f"unrecognized arguments: {' '.join(extras)}"
                      + "".join(_near(cmd, e) for e in extras))
        return ns


def _near(cmd: argparse.ArgumentParser, extra: str) -> str:
    """The hint after a refused ``extra``: the options of ``cmd`` it is the start of
    (``--temp`` could be ``--temp-rise``), or "" if none."""
    typed = extra.split("=")[0]
    near = sorted(o for a in cmd._actions if a.help != argparse.SUPPRESS
                  for o in a.option_strings if o.startswith(typed))
    if not typed.startswith("--") or not near:
        return ""
    return f" (options are not abbreviated: {typed} could be {' or '.join(near)})"


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="zrp", allow_abbrev=False,
        description="Robot accuracy: zero-reference-position kinematics, manufacturing-error "
        "analysis, MuJoCo playback and video, sim-to-real gap diagnosis.",
    )
    parser.add_argument("--version", action="version", version=f"zrp {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for info in sorted(pkgutil.iter_modules(commands.__path__), key=lambda m: m.name):
        mod = importlib.import_module(f"{commands.__name__}.{info.name}")
        mod.register(sub)
    # no abbreviations: `measure --temp` would silently be --temp-rise, and a new option could
    # change what an abbreviation typed in a script means (tests/cli/test_one_name.py)
    for cmd in sub.choices.values():
        cmd.allow_abbrev = False
    return parser


def emit(args: argparse.Namespace, payload: dict[str, Any], text: str) -> None:
    """Print ``payload`` as JSON when ``--json`` was given, else the human-readable ``text``."""
    if getattr(args, "json", False):
        from zrp.jsonio import dumps  # NumPy: only when a command prints JSON

        print(dumps(payload), end="")
    else:
        print(text)


#: How library messages name API arguments, and the command-line option each stands for.
#: Library code names what the Python caller passes; the command line shows its own flags.
API_TO_CLI = {
    "overwrite=True": "--force",
    "deg=True": "--deg",
}
#: Argument names used as the field of a message ("q0: expected ..."), per command's
#: ``api_names`` default, are shown as that command's option.
_BOTH = re.compile(r"[\w.=]+ \((--[\w-]+) on the command line\)")


def cli_message(exc: BaseException, api_names: dict[str, str] | None = None) -> str:
    """The message of ``exc`` for the command line: API arguments become options.

    A library message may name both ("pass deg=True (--deg on the command line)"): the
    command line shows only its option. ``api_names`` maps argument names used as a
    message's field (``q0: ...``, ``noise_sigma=...``) to the command's options.
    """
    text = exc.message("--force") if isinstance(exc, OutputExistsError) else str(exc)
    text = _BOTH.sub(r"\1", text)
    for api, flag in API_TO_CLI.items():
        text = text.replace(api, flag)
    for api, flag in (api_names or {}).items():
        text = re.sub(rf"(?<![\w.-]){re.escape(api)}(?=\s*[:=])", flag, text)
    return text


@contextlib.contextmanager
def one_line_warnings(prog: str) -> Iterator[None]:
    """Print each warning as one clean line ``prog: warning: message`` on stderr (not Python's
    file:line plus source line), each distinct message once. Where a caller records warnings
    (``warnings.catch_warnings(record=True)``, ``pytest.warns``), they go to its record
    instead, as they would without this context."""
    seen: set[str] = set()
    outer = warnings._showwarnmsg_impl  # type: ignore[attr-defined]
    recording = not (getattr(outer, "__module__", "") == "warnings"
                     and outer.__name__ == "_showwarnmsg_impl")

    def show(message: Warning | str, category: type[Warning], filename: str, lineno: int,
             file: TextIO | None = None, line: str | None = None) -> None:
        if recording:
            outer(warnings.WarningMessage(message, category, filename, lineno, file, line))
            return
        text = " ".join(str(message).split())
        if text not in seen:
            seen.add(text)
            print(f"{prog}: warning: {text}", file=sys.stderr if file is None else file)

    with warnings.catch_warnings():
        warnings.simplefilter("always")
        warnings.showwarning = show
        yield


#: options naming files the command writes (or reads and rewrites, as a checkpoint); a
#: command adds its own with ``set_defaults(writes=(dest, ...))``
_WRITTEN = frozenset({"out", "video", "checkpoint", "workdir", "hist", "writes"})


def _inputs(parser: argparse.ArgumentParser, args: argparse.Namespace
            ) -> Iterator[tuple[str, str]]:
    """(how given, value) of every other option's string values: the existing regular files
    among them are the command's inputs, which no output may replace
    (:func:`zrp.output.reading`)."""
    sub = next((a for a in parser._actions if isinstance(a, argparse._SubParsersAction)), None)
    cmd = sub.choices.get(args.command) if sub is not None else None
    names = {a.dest: (a.option_strings[-1] if a.option_strings else str(a.metavar or a.dest))
             for a in (cmd._actions if cmd is not None else ())}
    written = _WRITTEN | set(getattr(args, "writes", ()))
    for dest, value in vars(args).items():
        if dest in written:
            continue
        for v in value if isinstance(value, (list, tuple)) else (value,):
            if isinstance(v, str) and v:
                yield f"{names.get(dest, dest)} {v}", v


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command ``argv`` (default ``sys.argv[1:]``); returns its exit code: 0, 2 for an
    error (one line on stderr), 130 when interrupted, 141 when its output was closed early
    (``zrp measure ... | head -1``: no traceback, :mod:`zrp.cli.streams`)."""
    try:
        code = _run(argv)
        _flush_output()
        return code
    except BrokenPipeError:
        if not closed_output():
            raise
        return CLOSED_EXIT


def _flush_output() -> None:
    """Flush stdout and stderr: a pipe closed early or a full device fails here, inside
    ``main``'s handlers, not in the interpreter's final flush (the recipe of the signal
    module's documentation)."""
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:  # None: started with the descriptor closed (`>&-`)
            stream.flush()


def _run(argv: Sequence[str] | None) -> int:
    try:  # the commands import mjcf and sim: another package of either name must not shadow them
        check_own_packages()
    except PackageShadowedError as exc:
        print(f"zrp: error: {exc}", file=sys.stderr)
        return 2
    parser = build_parser()
    args = parser.parse_args(argv)
    vars(args).pop("_zrp_option_uses", None)  # the aliases' record (zrp.cli.aliases)
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    try:
        # SIGTERM (a batch scheduler's time limit, `kill`) stops a command like Ctrl-C: it
        # closes its cluster and keeps what it saves when stopped (a Monte Carlo checkpoint)
        with handling(signal.SIGTERM, _interrupt), one_line_warnings(f"zrp {args.command}"), \
                reading(_inputs(parser, args)):
            code = int(args.func(args) or 0)
            _flush_output()
            return code
    except ZRPError as exc:
        msg = cli_message(exc, getattr(args, "api_names", None))
        print(f"zrp {args.command}: error: {msg}", file=sys.stderr)
        return 2
    except OSError as exc:  # a full disk (`> /dev/full`), a bad file name: one line, no traceback
        msg = device_error(exc) or path_error(exc)
        if msg is None:
            raise
        print(f"zrp {args.command}: error: {msg}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # pragma: no cover
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
