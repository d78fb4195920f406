"""``zrp index``: renders/index.html, a page linking every output with one sentence each."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.errors import InputError
from zrp.output import OutputDir, claim_generated
from zrp.paper.index import INDEX_NAME, index_entries, write_index

DEFAULT_OUT = "renders"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "index", help="write renders/index.html linking every output with one sentence",
        description="One HTML page linking every file under the folder (subfolders too), "
        "with one sentence each on what it shows; images inline, videos playable. `zrp paper` "
        "and `zrp lessons` refresh it; run this after other commands that write there.")
    p.add_argument("--out", default=DEFAULT_OUT, metavar="DIR",
                   help="folder to index (default renders/, whose index is replaced; "
                        "elsewhere an existing index.html needs --force)")
    p.add_argument("--force", action="store_true", help="replace an existing index.html")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if not out.is_dir():
        raise InputError(f"--out: {str(out)!r} is not a folder; run `zrp paper` first")
    with OutputDir(out, overwrite=args.force or (out == Path(DEFAULT_OUT)
                                                 and claim_generated(out)),
                   names=[INDEX_NAME]) as folder:
        path = write_index(folder)
    entries = index_entries(out)
    emit(args, {"index": str(path), "files": [e[0] for e in entries]},
         f"wrote {path}: {len(entries)} files linked")
    return 0
