"""``zrp excite``: design an exciting joint command for identifying an arm's dynamics."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.cli.options import FINITE, SEED, real, whole

POSITIVE = real(0.0, 1e6, open_lo=True)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "excite", help="design an exciting trajectory (Fourier series) for the dynamic gap",
        description="A finite Fourier series about --q0 within position, velocity, "
        "acceleration and torque limits that minimises the identification regressor's "
        "condition number (zrp/gap/dynamics/README.md). Writes the command as a CSV "
        "(t [s], qc1..qcn [rad]) for the robot's controller; log the run as a torque log.")
    p.add_argument("--model", required=True, metavar="M.xml|M.urdf|NAME")
    p.add_argument("--end-link", metavar="LINK", help="URDF: the arm's last link")
    p.add_argument("--q0", type=FINITE, nargs="+", required=True, metavar="RAD",
                   help="the posture the motion is centred on, rad")
    p.add_argument("--amplitude", type=POSITIVE, default=0.5, help="rad (default 0.5)")
    p.add_argument("--max-velocity", type=POSITIVE, default=1.0, help="rad/s (default 1)")
    p.add_argument("--max-acceleration", type=POSITIVE, default=3.0, help="rad/s^2 (default 3)")
    p.add_argument("--max-torque", type=POSITIVE, nargs="+", metavar="NM",
                   help="per joint or one for all, N m (default: the model's force ranges)")
    p.add_argument("--period", type=real(0.5, 3600.0, unit="s"), default=10.0,
                   help="period of the series, s (default 10)")
    p.add_argument("--harmonics", type=whole(2, 20), default=5)
    p.add_argument("--rate", type=real(1.0, 1e5, unit="Hz"), default=1000.0,
                   help="samples a second of the CSV (default 1000)")
    p.add_argument("--candidates", type=whole(1, 1000), default=8)
    p.add_argument("--iterations", type=whole(0, 10_000), default=20)
    p.add_argument("--seed", type=SEED, default=0)
    p.add_argument("--out", required=True, metavar="COMMAND.csv")
    p.add_argument("--force", action="store_true", help="replace --out")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo: only when this command runs.
    from zrp.cli.dynamics_runs import run_excite

    payload, text = run_excite(args, Path(args.out))
    emit(args, payload, text)
    return 0
