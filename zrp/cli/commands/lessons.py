"""``zrp lessons``: the gallery of runnable lessons (one concept each) into renders/lessons/,
with the renders/ index page refreshed."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.output import OutputDir, default_overwrite
from zrp.paper.index import DESCRIPTIONS, INDEX_NAME, write_described_index, write_index

DEFAULT_OUT = "renders/lessons"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "lessons", help="run the teaching lessons (one concept each) into renders/lessons/",
        description="Lessons: tilt (what a joint-axis tilt does along a circle), links (why "
        "link errors leave the orientation alone), stack (how a tolerance stack becomes a "
        "distribution), backlash (how a calibration finds a hidden backlash). Each writes its "
        "figures/video into --out with one sentence per file and an index.html (for the "
        "default folder, renders/index.html is refreshed too).")
    p.add_argument("names", nargs="*", metavar="LESSON",
                   help="lessons to run (default all): tilt, links, stack, backlash")
    p.add_argument("--out", default=DEFAULT_OUT, metavar="DIR",
                   help="output folder (default renders/lessons: generated output, replaced; "
                        "elsewhere existing files need --force)")
    p.add_argument("--small", action="store_true",
                   help="reduced size (fewer frames, robots and poses), as the tests run them")
    p.add_argument("--force", action="store_true", help="replace existing files in --out")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_run, api_names={"names": "LESSON"})


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo, the lessons Matplotlib and the diagnosis: only when this command runs
    from sim.lessons import lesson_file_names, run_lessons

    out = Path(args.out)
    names = args.names or None
    default = out == Path(DEFAULT_OUT)
    # the renders/ page and the default folder are replaced only as generated output (their
    # mark) or with --force: checked before any lesson runs
    parent_overwrite = default_overwrite(out.parent, default=default, force=args.force,
                                         page=INDEX_NAME if default else None)
    overwrite = default_overwrite(out, default=default, force=args.force)
    files = [*lesson_file_names(names), DESCRIPTIONS, INDEX_NAME]
    with OutputDir(out, overwrite=overwrite, names=files) as folder:
        lessons = run_lessons(folder, names, small=args.small)
        sentences = {k: v for les in lessons for k, v in les.sentences.items()}
        index = write_described_index(folder, sentences)
    if default:   # the renders/ page links the lessons too
        with OutputDir(out.parent, overwrite=parent_overwrite, names=[INDEX_NAME]) as parent:
            index = write_index(parent)
    payload = {"out": str(out), "index": str(index) if index else None,
               "lessons": [{"name": les.name, "concept": les.concept,
                            "files": [str(f) for f in les.files], "numbers": les.numbers}
                           for les in lessons]}
    text = "\n".join([f"{les.name}: {les.concept}\n  " + "\n  ".join(
        f"{f.name}: {les.sentences[f.name]}" for f in les.files) for les in lessons]
        + ([f"index: {index}"] if index else []))
    emit(args, payload, text)
    return 0
