"""``--validate`` must be another log than ``--data`` (issue 41 finding 5): the same path, a
link to it, a hard link (one inode) or a copy (the same SHA-256 of the content) is the
training log again, and its "withheld" error would be the fit's own. Refused, naming both
options; so is a validation log whose samples equal the training log's (the API)."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import numpy as np

from zrp.errors import InputError

__all__ = ["check_other_arrays", "check_other_log"]

_BLOCK = 1 << 20


def _digest(p: Path) -> str:
    h = hashlib.sha256()
    with open(p, "rb") as fh:
        while block := fh.read(_BLOCK):
            h.update(block)
    return h.hexdigest()


def _tree_digest(p: Path) -> str:
    """A bag folder's content: its files' relative names and digests."""
    h = hashlib.sha256()
    for f in sorted(x for x in p.rglob("*") if x.is_file()):
        h.update(str(f.relative_to(p)).encode("utf-8", "surrogateescape") + b"\0")
        h.update(_digest(f).encode())
    return h.hexdigest()


def _same(a: Path, b: Path) -> str | None:
    """How ``a`` and ``b`` are the same log, or None."""
    try:
        if os.path.samefile(a, b):
            return "the same file (one inode)"
        if a.is_file() and b.is_file():
            if a.stat().st_size == b.stat().st_size and _digest(a) == _digest(b):
                return "a copy (the same SHA-256 of the content)"
        elif a.is_dir() and b.is_dir() and _tree_digest(a) == _tree_digest(b):
            return "a copy (the same SHA-256 of every file)"
    except OSError:
        return None  # an unreadable file is said by its reader
    return None


def check_other_log(data: str | os.PathLike[str], validate: str | os.PathLike[str] | None
                    ) -> None:
    """Refuse ``validate`` when it is the ``data`` log again (module docstring)."""
    if validate is None:
        return
    how = _same(Path(data), Path(validate))
    if how is not None:
        raise InputError(f"--data, --validate: {str(validate)!r} is {how} of the training log "
                         f"{str(data)!r}: its error would be the fit's own, not withheld; "
                         "give --validate another recording (or leave it out: the diagnosis "
                         "withholds part of --data)")


def check_other_arrays(t: np.ndarray, q: np.ndarray, tau: np.ndarray, t2: np.ndarray,
                       q2: np.ndarray, tau2: np.ndarray) -> None:
    """Refuse a validation log whose samples are the training log's (module docstring)."""
    if q.shape == q2.shape and tau.shape == tau2.shape and np.array_equal(q, q2) \
            and np.array_equal(tau, tau2) and np.array_equal(t - t[0], t2 - t2[0]):
        raise InputError("validation_log (--validate): its samples are the training log's "
                         "(--data): its error would be the fit's own, not withheld; give "
                         "another recording")
