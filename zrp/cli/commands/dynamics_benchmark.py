"""``zrp dynamics-benchmark``: the blind benchmark of the dynamic gap diagnosis."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.cli.options import SEED, real, whole
from zrp.output import default_overwrite

DEFAULT_OUT = Path("renders") / "dynamics_benchmark"
ARMS = ("ur5e", "puma", "panda")
EFFECTS = ("coulomb", "viscous", "stribeck", "armature", "offset", "payload", "inertial", "none")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "dynamics-benchmark", help="blind benchmark of the dynamic gap diagnosis",
        description="Hide one dynamic effect (friction laws, armature, torque offset, payload, "
        "link inertias, or none) in the physics robot of each arm, log it along an exciting "
        "command, diagnose the log blind and score against the truth (zrp/gap/dynamics/README.md)."
        " Writes summary.json and summary.md.")
    p.add_argument("--arms", nargs="+", choices=ARMS, help="default: every installed arm")
    p.add_argument("--effects", nargs="+", choices=EFFECTS, help="default: all")
    p.add_argument("--reps", type=whole(1, 1000), default=1, help="scenarios per arm and effect")
    p.add_argument("--seconds", type=real(2.0, 3600.0, unit="s"), default=20.0,
                   help="log length, s (default 20)")
    p.add_argument("--seed", type=SEED, default=1)
    p.add_argument("--out", metavar="DIR", help=f"output folder (default {DEFAULT_OUT})")
    p.add_argument("--force", action="store_true", help="replace outputs in --out")
    p.add_argument("--json", action="store_true", help="print the summary JSON")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo: only when this command runs.
    from zrp.cli.dynamics_runs import run_benchmark

    out = Path(args.out) if args.out else DEFAULT_OUT
    # the default folder is replaced as generated output only when it carries the mark
    args.force = default_overwrite(out, default=args.out is None, force=args.force)
    payload, text = run_benchmark(args, out)
    emit(args, payload, text)
    return 0
