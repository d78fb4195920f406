"""``zrp diagnose``: where the sim-to-real gap lies, which effect causes it, how far it shrinks."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from zrp.cli.main import emit
from zrp.errors import InputError
from zrp.model.files import load_model


def register(sub: argparse._SubParsersAction) -> None:
    from zrp.gap.effects import EFFECTS

    p = sub.add_parser(
        "diagnose", help="sim-to-real gap diagnosis from measured tool positions",
        description="Register the measurements (base frame, tool offsets), then find which "
        "unmodelled effects explain the remaining gap and how far it shrinks on withheld poses. "
        "Writes DIR/diagnosis.json, DIR/report.md, DIR/residuals.csv and PNG plots "
        "(docs/diagnosis.md).")
    p.add_argument("--model", required=True, metavar="M.toml",
                   help="model TOML file or built-in name")
    p.add_argument("--mjcf", metavar="M.xml",
                   help="MJCF with the robot's inertias (gravity torques for joint_compliance; "
                        "one hinge/slide joint per model joint, same order and zero)")
    p.add_argument("--data", required=True, metavar="D.csv", help="measurement CSV")
    p.add_argument("--deg", action="store_true", help="revolute joint values are in degrees")
    p.add_argument("--frame", choices=("instrument", "base"), default="instrument",
                   help="frame of x, y, z (default instrument: the base frame is estimated)")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--seed", type=int, default=0, help="seed of the fitting/withheld split")
    p.add_argument("--withheld", type=float, default=0.25, metavar="FRACTION",
                   help="share of the poses withheld (default 0.25)")
    p.add_argument("--folds", type=int, default=5, help="cross-validation folds (default 5)")
    p.add_argument("--effects", nargs="+", choices=EFFECTS, default=list(EFFECTS),
                   metavar="EFFECT", help=f"candidate effects (default all: {', '.join(EFFECTS)})")
    p.add_argument("--max-steps", type=int, default=4, help="most effects added (default 4)")
    p.add_argument("--alpha", type=float, default=1e-3,
                   help="significance level for adding an effect (default 1e-3)")
    p.add_argument("--noise", type=float, metavar="SIGMA",
                   help="known instrument noise per coordinate (length unit); default: "
                        "estimated from rigidly linked points or repeats")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="show a progress bar (default: when stderr is a terminal)")
    p.add_argument("--json", action="store_true", help="print diagnosis.json to stdout")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    from mjcf.gravity import gravity_torques
    from zrp.gap import diagnose, load_measurements
    from zrp.gap.report import OUTPUT_FILES, jsonable, write_outputs

    out = Path(args.out)
    if not args.force:
        existing = [f for f in OUTPUT_FILES if (out / f).exists()]
        if existing:
            raise InputError(f"--out {out}: {', '.join(existing)} already exist(s); pass "
                             "--force to overwrite")
    if args.max_steps < 1:
        raise InputError(f"--max-steps: expected at least 1, got {args.max_steps}")
    model = load_model(args.model)
    meas = load_measurements(args.data, model, deg=args.deg, frame=args.frame)
    tau = None if args.mjcf is None else gravity_torques(args.mjcf, meas.q_pose, field="--mjcf")
    diag = diagnose(model, meas, gravity_torque=tau, effects=args.effects, seed=args.seed,
                    withheld_fraction=args.withheld, folds=args.folds, alpha=args.alpha,
                    max_steps=args.max_steps, noise_sigma=args.noise,
                    progress=sys.stderr.isatty() if args.progress is None else args.progress)
    files = write_outputs(diag, out, force=args.force, plots=not args.no_plots)
    text = diag.verdict + "\n" + "\n".join(f"wrote {f}" for f in files)
    emit(args, jsonable(diag.to_dict()), text)
    return 0
