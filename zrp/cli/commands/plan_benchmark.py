"""``zrp plan-benchmark``: do K planned poses diagnose as well as 200 random ones?"""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.cli.options import SEED, add_progress, whole
from zrp.errors import InputError
from zrp.output import OutputDir, claim_generated

DEFAULT_OUT = "renders/plan_benchmark"
FILES = ("summary.md", "designs.json")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plan-benchmark", help="K planned measurement poses against 200 random ones, blind",
        description="For the blind benchmark's scenarios (zrp gap-benchmark: hidden effects, "
        "payload, tracker noise), measure the physics robot at N random poses and at K "
        "poses planned by zrp plan (D-optimal, all effects), diagnose each blind and score "
        "it: right effect and joints, and the calibrated robot's RMS on common fresh "
        "validation poses against the tracker noise; predicted parameter std per design. "
        "Writes summary.md and designs.json (zrp/calibration/README.md).")
    p.add_argument("--scenarios", type=whole(1, 100_000), default=50, metavar="K",
                   help="scenarios the benchmark draws (default 50)")
    p.add_argument("--only", type=whole(0, 100_000), nargs="+", metavar="I",
                   help="run only these scenario indices")
    p.add_argument("--seed", type=SEED, default=0, help="the benchmark's master seed")
    p.add_argument("--model", default="puma", metavar="M.toml", help="model (default puma)")
    p.add_argument("--ks", type=whole(2, 100_000), nargs="+", default=[20, 30, 40, 50, 75],
                   metavar="K", help="planned pose counts (default 20 30 40 50 75)")
    p.add_argument("--random-ks", type=whole(2, 100_000), nargs="+", default=[], metavar="K",
                   help="also K random poses for each K (controls: does planning matter?)")
    p.add_argument("--random-poses", type=whole(8, 100_000), default=200, metavar="N",
                   help="random poses of the reference design (default 200)")
    p.add_argument("--validation", type=whole(8, 100_000), default=100, metavar="N",
                   help="common fresh validation poses (default 100)")
    p.add_argument("--candidates", type=whole(10, 1_000_000), default=1000,
                   help="planner candidate poses (default 1000)")
    p.add_argument("--out", metavar="DIR", help=f"output folder (default {DEFAULT_OUT}, "
                   "generated output that is replaced)")
    p.add_argument("--force", action="store_true", help="replace existing files in --out")
    add_progress(p, help="print a line per scenario and design on stderr as it is scored "
                 "(default on; --no-progress: none)")
    p.add_argument("--json", action="store_true", help="print the rows as JSON")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo and the diagnosis: only when this command runs
    from sim.studies.benchmark import BenchmarkConfig

    # (the same reason: MuJoCo is loaded only when this command runs)
    from sim.studies.planning import design_rows, render_k_study, run_k_study
    from zrp.model.files import load_model  # on use: keeps --help quick

    out = Path(args.out or DEFAULT_OUT)
    overwrite = args.force or (args.out is None and claim_generated(out))
    model = load_model(args.model)
    cfg = BenchmarkConfig(scenarios=args.scenarios, seed=args.seed)
    if args.only and max(args.only) >= args.scenarios:
        raise InputError(f"--only: scenario indices must be below --scenarios "
                         f"{args.scenarios}")
    with OutputDir(out, overwrite=overwrite, names=FILES) as folder:
        scores = run_k_study(model, cfg, tuple(args.ks), random_poses=args.random_poses,
                             validation=args.validation, candidates=args.candidates,
                             scenarios=tuple(args.only) if args.only else None,
                             progress=args.progress, random_ks=tuple(args.random_ks))
        text = render_k_study(scores, cfg.ratio_target)
        folder.write_text("summary.md", text)
        doc = {"rows": design_rows(scores), "designs": [{**s.row(), "std": s.std}
                                                         for s in scores]}
        folder.write_json("designs.json", doc, indent=1)
    emit(args, doc, text + f"\nwrote {out / 'summary.md'} and {out / 'designs.json'}")
    return 0
