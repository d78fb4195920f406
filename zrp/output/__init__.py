"""The output-writing policy: one helper that every writer in every layer uses.

* Nothing the user has is replaced without ``overwrite=True`` (``--force`` on the command
  line): :func:`check_writable` refuses, naming every file that exists, before any work is done.
* Each file appears whole or not at all: it is written under a temporary name in the same
  folder and moved into place with :func:`os.replace` (atomic on POSIX and Windows), so an
  interrupted run never leaves half a CSV behind.
* Only regular files are replaced: a symbolic link, a device, a FIFO or a socket at an output
  path is refused with :class:`~zrp.errors.OutputKindError`, even with ``overwrite=True`` (as
  root, ``--out /dev/null --force`` would otherwise replace the system's). An output folder
  that is itself a symbolic link is refused, not resolved (the message names its target, to
  pass instead), so a run never writes through a link into another folder.
* A name longer than the file system allows (255 bytes a component) is refused by name.
* An output folder belongs to one run at a time: :class:`OutputDir` holds a lock file
  (``.zrp-output.lock``, created with ``O_EXCL``) while it writes, so two concurrent runs into
  one folder never mix their files; the second waits at most ``lock_wait_s`` seconds
  (:data:`LOCK_WAIT_S`), then is refused with :class:`OutputBusyError` naming the lock file and
  the holder's process. A lock left by a process that no longer runs is taken over.
* A writer that declares the files it owns (``names``) with ``prune=True`` removes, on a clean
  exit, those of them an earlier run left and this run did not write (the plots of a run
  before ``--no-plots``), so no stale file is left beside (or linked from) the new results.

Typical use::

    with OutputDir("results", overwrite=False, names=("a.csv", "b.png")) as out:
        ...                                      # compute: the names were checked up front
        out.write_text("a.csv", text)
        with out.path("b.png") as tmp:           # for writers that want a file name
            fig.savefig(tmp)
    out.written                                  # the paths written, in order

* A default output name built from an input's name goes through :func:`safe_name` (a log
  named ``...csv`` cannot write into the folder above), and a command's default folder is
  replaced without ``--force`` only when :func:`claim_generated` says it is generated output.

* A command's input is never its output, even with ``--force``: the command line registers
  the files it reads (:func:`reading`) and every write refuses them (:func:`check_not_input`).

The policy lives in seven modules: :mod:`zrp.output.paths` (names and file kinds, the refusal to
replace), :mod:`zrp.output.atomic` (the atomic writes, the default folders' mark),
:mod:`zrp.output.names` (default names from inputs, no links on the way),
:mod:`zrp.output.inputs` (inputs are not outputs),
:mod:`zrp.output.lock` (one run a folder), :mod:`zrp.output.folder` (:class:`OutputDir`) and
:mod:`zrp.output.figures` (a figure drawn once for each file it is saved to); import the names
from here.
"""

from __future__ import annotations

from zrp.output.atomic import (
    GENERATED_MARK,
    atomic_path,
    claim_generated,
    default_overwrite,
    write_bytes,
    write_json,
    write_text,
)
from zrp.output.figures import tight_layout_once
from zrp.output.folder import OutputDir
from zrp.output.inputs import check_not_input, reading
from zrp.output.lock import LOCK_NAME, LOCK_WAIT_S
from zrp.output.names import check_no_links, safe_name
from zrp.output.paths import NAME_MAX_BYTES, check_regular, check_writable

__all__ = [
    "GENERATED_MARK",
    "LOCK_NAME",
    "LOCK_WAIT_S",
    "NAME_MAX_BYTES",
    "OutputDir",
    "atomic_path",
    "check_no_links",
    "check_not_input",
    "check_regular",
    "check_writable",
    "claim_generated",
    "default_overwrite",
    "reading",
    "safe_name",
    "tight_layout_once",
    "write_bytes",
    "write_json",
    "write_text",
]
