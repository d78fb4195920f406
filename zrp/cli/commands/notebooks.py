"""``zrp notebooks``: list the teaching notebooks, or execute them (nbclient, with a time
limit) into renders/notebooks/ as executed .ipynb and HTML, with the renders/ index page
refreshed."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.cli.options import real
from zrp.output import OutputDir, default_overwrite
from zrp.paper.index import DESCRIPTIONS, INDEX_NAME, write_described_index, write_index

DEFAULT_OUT = "renders/notebooks"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "notebooks", help="list or run the teaching notebooks (executed HTML into "
        "renders/notebooks/)",
        description="The teaching notebooks, in order: kinematics (ZRP kinematics and the "
        "Euler-Rodrigues parameters), circle (the paper's circle, one link and one axis "
        "perturbed, on video), tolerances (Monte Carlo and tolerance allocation), gap (the "
        "sim-to-real gap: measure, diagnose, compensate). With --list: their names and files; "
        "otherwise each is executed top to bottom in a fresh Jupyter kernel and written as "
        "<name>.ipynb and <name>.html into --out (needs the notebooks extra: pip install "
        "'zrp-accuracy[notebooks]'). For the default folder renders/index.html is refreshed. "
        "The sources are jupytext text files (sim/lessons/notebooks/): open them in Jupyter.")
    p.add_argument("names", nargs="*", metavar="NOTEBOOK",
                   help="notebooks to run (default all): kinematics, circle, tolerances, gap")
    p.add_argument("--list", action="store_true", help="list the notebooks and exit")
    p.add_argument("--out", default=DEFAULT_OUT, metavar="DIR",
                   help="output folder (default renders/notebooks: generated output, "
                        "replaced; elsewhere existing files need --force)")
    p.add_argument("--timeout", type=real(0.0, 86400.0, open_lo=True, unit="s"), default=None,
                   metavar="S",
                   help="time limit per notebook, s (default 300; the goal on a laptop is "
                        "120)")
    p.add_argument("--force", action="store_true", help="replace existing files in --out")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run, api_names={"names": "NOTEBOOK", "timeout_s": "--timeout"})


def _list(args: argparse.Namespace) -> int:
    # sim loads its GL backend check on import: only when this command runs
    from sim.lessons.notebook_runner import NOTEBOOKS, notebook_source

    rows = [{"name": n, "title": title, "learns": what, "source": str(notebook_source(n))}
            for n, _, title, what in NOTEBOOKS]
    emit(args, {"notebooks": rows}, "\n".join(
        f"{i}. {r['name']}: {r['title']}\n   {r['learns']}\n   {r['source']}"
        for i, r in enumerate(rows, 1)))
    return 0


def _run(args: argparse.Namespace) -> int:

    if args.list:
        return _list(args)
    # sim (MuJoCo) and the Jupyter packages load only when notebooks run
    from sim.lessons.notebook_runner import (
        DEFAULT_TIMEOUT_S,
        NOTEBOOKS,
        notebook_file_names,
        run_notebooks,
    )

    out = Path(args.out)
    names = args.names or None
    default = out == Path(DEFAULT_OUT)
    # the renders/ page and the default folder are replaced only as generated output (their
    # mark) or with --force: checked before any notebook runs
    parent_overwrite = default_overwrite(out.parent, default=default, force=args.force,
                                         page=INDEX_NAME if default else None)
    overwrite = default_overwrite(out, default=default, force=args.force)
    timeout = DEFAULT_TIMEOUT_S if args.timeout is None else args.timeout
    with OutputDir(out, overwrite=overwrite,
                   names=[*notebook_file_names(names), DESCRIPTIONS, INDEX_NAME]) as folder:
        runs = run_notebooks(folder, names, timeout_s=timeout)
        learns = {n: (i, what) for i, (n, _, _, what) in enumerate(NOTEBOOKS, 1)}
        sentences = {}
        for r in runs:
            i, what = learns[r.name]
            sentences[r.html.name] = f"Notebook {i}, {r.title} (executed): {what}"
            sentences[r.ipynb.name] = (f"Notebook {i}, {r.title}, executed, to open in "
                                       "Jupyter.")
        index = write_described_index(folder, sentences)
    if default:   # the renders/ page links the notebooks too
        with OutputDir(out.parent, overwrite=parent_overwrite, names=[INDEX_NAME]) as parent:
            index = write_index(parent)
    payload = {"out": str(out), "index": str(index),
               "notebooks": [{"name": r.name, "title": r.title, "ipynb": str(r.ipynb),
                              "html": str(r.html), "seconds": r.seconds,
                              "mediapy_outputs": r.mediapy_outputs} for r in runs]}
    text = "\n".join([f"{r.name}: {r.title} ({r.seconds:.1f} s) -> {r.html}" for r in runs]
                     + [f"index: {index}"])
    emit(args, payload, text)
    return 0
