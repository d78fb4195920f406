"""``zrp excite``: design an exciting joint command for identifying an arm's dynamics."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.cli.options import FINITE, SEED, add_progress, draw_bar, real, whole
from zrp.errors import InputError
from zrp.limits import (
    MAX_COMMAND_SAMPLES,
    MAX_DESIGN_CANDIDATES,
    MAX_DESIGN_ITERATIONS,
    MAX_HARMONICS,
)

POSITIVE = real(0.0, 1e6, open_lo=True)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "excite", help="design an exciting trajectory (Fourier series) for the dynamic gap",
        description="A finite Fourier series about --q0 within position, velocity, "
        "acceleration and torque limits that minimises the identification regressor's "
        "condition number (zrp/gap/dynamics/README.md). Every sample is checked against every "
        "limit before the file is written. Writes the command as a CSV (# lines: its "
        "conditions; then t [s], qc1..qcn [rad]) for the robot's controller; log the run as a "
        "torque log.")
    p.add_argument("--model", required=True, metavar="M.xml|M.urdf|NAME")
    p.add_argument("--end-link", metavar="LINK", help="URDF: the arm's last link")
    p.add_argument("--joints", nargs="+", metavar="NAME",
                   help="instead of --end-link: the arm's joints by name (its chain)")
    p.add_argument("--q0", type=FINITE, nargs="+", required=True, metavar="RAD",
                   help="the posture the motion is centred on, rad (--deg: degrees); inside "
                   "the joint limits")
    p.add_argument("--deg", action="store_true",
                   help="--q0 and --amplitude in degrees (velocities and accelerations stay "
                   "rad/s, rad/s^2)")
    p.add_argument("--amplitude", type=POSITIVE, nargs="+", default=[0.5], metavar="RAD",
                   help="largest |q - q0|, one for all joints or one a joint, rad (default "
                   "0.5); q0 +- amplitude must lie inside the joint limits")
    p.add_argument("--max-velocity", type=POSITIVE, nargs="+", metavar="RAD_S",
                   help="one or one a joint, rad/s (default 1, or the model's own limit where "
                   "lower; never above it)")
    p.add_argument("--max-acceleration", type=POSITIVE, nargs="+",
                   metavar="RAD_S2", help="one or one a joint, rad/s^2 (default 3, recorded as "
                   "the default)")
    p.add_argument("--max-torque", type=POSITIVE, nargs="+", metavar="NM",
                   help="one or one a joint, N m (default: the model's own: URDF effort "
                   "limits, MJCF actuatorfrcrange, actuator forcerange or a motor's ctrlrange, "
                   "times gear; never above them)")
    p.add_argument("--period", type=real(0.5, 3600.0, unit="s"), default=10.0,
                   help="period of the series, s (default 10)")
    p.add_argument("--harmonics", type=whole(2, MAX_HARMONICS), default=5,
                   help="harmonics of the series (default 5)")
    p.add_argument("--rate", type=real(1.0, 1e5, unit="Hz"), default=1000.0,
                   help="samples a second of the CSV (default 1000; period x rate at most "
                   f"{MAX_COMMAND_SAMPLES:,} samples)")
    p.add_argument("--candidates", type=whole(1, MAX_DESIGN_CANDIDATES), default=8,
                   help="random starts (default 8)")
    p.add_argument("--iterations", type=whole(0, MAX_DESIGN_ITERATIONS), default=20,
                   help="hill-climbing steps (default 20)")
    p.add_argument("--seed", type=SEED, default=0)
    p.add_argument("--out", required=True, metavar="COMMAND.csv")
    p.add_argument("--force", action="store_true", help="replace --out")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    add_progress(p, help="show the design's starts and steps as a bar on stderr when it is a "
                 "terminal (default on; --no-progress: none)")
    p.set_defaults(func=_run, api_names={
        "end_link": "--end-link", "q0": "--q0", "amplitude": "--amplitude", "q_amp": "--amplitude",
        "max_velocity": "--max-velocity", "qd_max": "--max-velocity",
        "max_acceleration": "--max-acceleration", "qdd_max": "--max-acceleration",
        "max_torque": "--max-torque", "torque_limit": "--max-torque", "period_s": "--period",
        "rate_hz": "--rate", "harmonics": "--harmonics", "candidates": "--candidates",
        "iterations": "--iterations", "out": "--out"})


def _one(values: list[float] | None) -> float | list[float] | None:
    return values[0] if values is not None and len(values) == 1 else values


def _run(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from mjcf.arm import resolve_arm  # MuJoCo: only when this command runs
    from zrp.gap.dynamics import command as c  # on use: keeps --help quick

    if args.joints:
        from zrp.cli.dynamics_runs import arm_of_joints  # MuJoCo: only when this command runs

        if args.end_link:
            raise InputError("--joints, --end-link: give one (both choose the arm's chain)")
        arm = arm_of_joints(args.model, args.joints)
    else:
        arm = resolve_arm(args.model, end_link=args.end_link)
    opts = c.ExciteOptions(
        q0=args.q0, amplitude=_one(args.amplitude), max_velocity=_one(args.max_velocity),
        max_acceleration=_one(args.max_acceleration), max_torque=_one(args.max_torque),
        deg=args.deg, period_s=args.period, rate_hz=args.rate, harmonics=args.harmonics,
        candidates=args.candidates, iterations=args.iterations, seed=args.seed)
    with tqdm(total=args.candidates + args.iterations, desc="excite", unit="design",
              disable=not draw_bar(args), leave=False) as bar:
        cmd = c.excitation_command(arm, opts,
                                   progress=lambda done, _total: bar.update(done - bar.n))
    out = c.write_excitation_command(cmd, Path(args.out), model=args.model, overwrite=args.force)
    payload, text = c.command_summary(cmd, notes=getattr(arm, "notes", ()))
    emit(args, payload, text + f"\nwrote {out}")
    return 0
