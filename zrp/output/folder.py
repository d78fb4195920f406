"""An output folder owned by one run (part of :mod:`zrp.output`): :class:`OutputDir` checks the
declared names up front, holds the folder's lock (:mod:`zrp.output.lock`) while the ``with``
block lasts, writes every file atomically (:mod:`zrp.output.atomic`) and, with ``prune``,
removes on a clean exit the declared files an earlier run left and this run did not write."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from zrp.errors import InputError, OutputKindError
from zrp.output.atomic import (
    atomic_path,
    clean_stale_temporaries,
    write_bytes,
    write_json,
    write_text,
)
from zrp.output.lock import LOCK_WAIT_S, acquire, release
from zrp.output.paths import as_path, check_regular, check_writable, make_folder

__all__ = ["OutputDir"]


class OutputDir:
    """An output folder owned by this run while the ``with`` block lasts.

    Args:
        path: the folder (created with its parents when missing).
        overwrite: replace files that exist; without it an existing file is an error.
        names: the files this run will write, checked on entry so that a refusal comes
            before any work is done.
        prune: on a clean exit, remove those of ``names`` that an earlier run left and this
            run did not write.
        lock_wait_s: longest wait for another run's lock on the folder.
    """

    def __init__(self, path: str | os.PathLike[str], *, overwrite: bool = False,
                 names: Sequence[str] = (), prune: bool = False,
                 lock_wait_s: float = LOCK_WAIT_S) -> None:
        self.root = as_path(path, "out_dir")
        self.overwrite = bool(overwrite)
        self.names = tuple(names)
        self.prune = bool(prune)
        self.lock_wait_s = float(lock_wait_s)
        self.written: list[Path] = []
        #: files of an earlier run removed on exit (``prune``): declared, not written now
        self.removed: list[Path] = []
        self._lock: Path | None = None

    def __enter__(self) -> OutputDir:
        if self.root.is_symlink():
            raise OutputKindError(f"{self.root}: the output folder is a symbolic link (to "
                                  f"{os.readlink(self.root)}); refused, not resolved: pass the "
                                  f"real folder ({self.root.resolve()}) to write there")
        if self.root.exists() and not self.root.is_dir():
            raise InputError(f"{self.root}: exists and is not a folder; expected an output "
                             "folder")
        make_folder(self.root)
        self._lock = acquire(self.root, self.lock_wait_s)
        clean_stale_temporaries(self.root)
        try:
            check_writable([self.root / n for n in self.names], self.overwrite)
        except BaseException:
            self._release()
            raise
        return self

    def _release(self) -> None:
        if self._lock is not None:
            release(self._lock)
            self._lock = None

    def __exit__(self, exc_type: object, *exc: object) -> None:
        try:
            if exc_type is None and self.prune and self._lock is not None:
                self._prune()
        finally:
            self._release()

    def _prune(self) -> None:
        """Remove the declared files this run did not write (left by an earlier run)."""
        mine = set(self.written)
        for name in self.names:
            p = self.root / name
            if p not in mine and check_regular(p):
                try:
                    p.unlink()
                except OSError as exc:
                    raise InputError(f"{p}: an earlier run's output that this run does not "
                                     f"make cannot be removed ({exc.strerror or exc})") from exc
                self.removed.append(p)

    # ---- writing ---------------------------------------------------------------------------
    def _target(self, name: str) -> Path:
        if self._lock is None:
            raise InputError(f"{self.root}: write inside `with OutputDir(...)`")
        p = self.root / name
        if Path(name).is_absolute() or ".." in Path(name).parts:
            raise InputError(f"{name!r}: expected a file name inside {self.root}")
        for sub in list(p.parents)[: len(Path(name).parts) - 1]:  # folders inside the root
            if sub.is_symlink():
                raise OutputKindError(f"{sub}: is a symbolic link inside the output folder; "
                                      "refused, not resolved: remove it")
        return p

    @contextlib.contextmanager
    def path(self, name: str) -> Iterator[Path]:
        """A temporary path for ``name``, moved into place on a clean exit."""
        target = self._target(name)
        with atomic_path(target, overwrite=self.overwrite, clean=False) as tmp:
            yield tmp
        self.written.append(target)

    def write_text(self, name: str, text: str) -> Path:
        p = write_text(self._target(name), text, overwrite=self.overwrite)
        self.written.append(p)
        return p

    def write_bytes(self, name: str, data: bytes) -> Path:
        p = write_bytes(self._target(name), data, overwrite=self.overwrite)
        self.written.append(p)
        return p

    def write_json(self, name: str, obj: Any, indent: int | None = 2) -> Path:
        p = write_json(self._target(name), obj, overwrite=self.overwrite, indent=indent)
        self.written.append(p)
        return p

    def savefig(self, name: str, fig: Any, **kwargs: Any) -> Path:
        """Save a Matplotlib figure as ``name`` (format from its suffix)."""
        with self.path(name) as tmp:
            fig.savefig(tmp, **kwargs)
        return self.root / name
