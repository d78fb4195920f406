"""``zrp motion-benchmark``: the blind benchmark's motion scenarios."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.cli.options import SEED, add_progress, draw_bar, whole
from zrp.errors import InputError
from zrp.output import claim_generated

DEFAULT_OUT = Path("renders") / "motion_benchmark"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "motion-benchmark", help="blind benchmark of the motion diagnosis (MuJoCo real robot)",
        description="Draw scenarios hiding motion effects (none, singles, pairs), execute random "
        "joint moves on the MuJoCo real robot, stream 1 kHz tracker points, diagnose the CSV "
        "blind and score (sim/README.md). Writes summary.json and summary.md.")
    p.add_argument("--model", default="puma", metavar="M.toml")
    p.add_argument("--scenarios", type=whole(1, 10_000), default=34,
                   help="number of scenarios (default 34)")
    p.add_argument("--seed", type=SEED, default=0)
    p.add_argument("--moves", type=whole(1, 1000), default=10,
                   help="joint moves per scenario (default 10)")
    p.add_argument("--out", metavar="DIR", help=f"output folder (default {DEFAULT_OUT})")
    p.add_argument("--force", action="store_true", help="replace outputs in --out")
    add_progress(p)
    p.add_argument("--json", action="store_true", help="print the summary JSON")
    p.set_defaults(func=_run, api_names={"count": "--scenarios", "moves": "--moves"})


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo: only when this command runs.
    from sim.studies.benchmark.motion import markdown, run_motion_benchmark
    from zrp.model.files import load_model  # on use: keeps --help quick

    if args.moves < 2:
        raise InputError(f"--moves: expected at least 2 moves, got {args.moves}")
    out = Path(args.out) if args.out else DEFAULT_OUT
    summary = run_motion_benchmark(load_model(args.model), args.scenarios, args.seed, out,
                                   moves=args.moves,
                                   overwrite=args.force or (args.out is None
                                                            and claim_generated(out)),
                                   progress=draw_bar(args))
    emit(args, summary, markdown(summary) + f"wrote {out}/summary.json, {out}/summary.md")
    return 0
