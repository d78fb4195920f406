"""A command's input files are never its outputs, even with ``--force``.

``zrp excite --model arm.xml --out arm.xml --force`` replaced the model it read. The command
line registers the files a command reads (:func:`reading`, from its options); every write goes
through :func:`~zrp.output.check_writable`, which calls :func:`check_not_input`: a target that
is one of those files (the same file: compared by device and inode, so another spelling, a
link or a hard link is caught) is refused with :class:`~zrp.errors.OutputIsInputError`
naming the option; an :class:`~zrp.output.OutputDir` whose declared names include an input is
refused before any work (so its pruning never reaches one).
"""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Iterable, Iterator
from contextvars import ContextVar
from pathlib import Path

from zrp.errors import OutputIsInputError

__all__ = ["check_not_input", "is_input", "reading"]

#: (device, inode) -> how the command was given the file (e.g. ``--model arm.xml``)
_INPUTS: ContextVar[dict[tuple[int, int], str] | None] = ContextVar("zrp_inputs", default=None)


def _key(p: str | os.PathLike[str]) -> tuple[int, int] | None:
    try:
        st = os.stat(p)
    except (OSError, ValueError):
        return None
    return (st.st_dev, st.st_ino) if stat.S_ISREG(st.st_mode) else None


@contextlib.contextmanager
def reading(named: Iterable[tuple[str, str | os.PathLike[str]]]) -> Iterator[None]:
    """While the block runs, the existing regular files among ``named`` ((how given, path)
    pairs; other values are ignored) are inputs that no write may replace."""
    found = dict(_INPUTS.get() or {})
    for how, path in named:
        key = _key(path)
        if key is not None:
            found.setdefault(key, how)
    token = _INPUTS.set(found)
    try:
        yield
    finally:
        _INPUTS.reset(token)


def is_input(p: Path) -> str | None:
    """How the command was given the file ``p`` when it is one of its inputs, else None."""
    inputs = _INPUTS.get()
    if not inputs:
        return None
    key = _key(p)
    return inputs.get(key) if key is not None else None


def check_not_input(p: Path) -> None:
    """Refuse writing onto a file the running command reads.

    Raises:
        OutputIsInputError: naming the output and the option it was read from.
    """
    how = is_input(p)
    if how is not None:
        raise OutputIsInputError(f"{p}: is this command's input ({how}); an output never "
                                 "replaces an input, even with --force: write elsewhere")
