"""``zrp diagnose``: where the sim-to-real gap lies, which effect causes it, how far it shrinks."""

from __future__ import annotations

import argparse
import contextlib
from pathlib import Path

from zrp.cli.app import emit
from zrp.cli.fleet import add_fleet_options, is_fleet, refuse_fleet_options, run_fleet
from zrp.cli.options import LENGTH, SEED, add_deg, add_progress, draw_bar, real, whole
from zrp.errors import InputError
from zrp.gap.data.choices import MAX_POINTS, MAX_ROWS, MAX_WITHHELD
from zrp.gap.model.choices import EFFECTS
from zrp.output import OutputDir


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "diagnose", help="sim-to-real gap diagnosis from measured tool positions",
        description="Register the measurements (base frame, tool offsets), then find which "
        "unmodelled effects explain the remaining gap and how far it shrinks on withheld poses. "
        "Writes DIR/diagnosis.json, DIR/report.md, DIR/report.html, DIR/residuals.csv and "
        "PNG plots (zrp/gap/README.md).")
    p.add_argument("--model", required=True, metavar="M.toml",
                   help="model TOML file or built-in name")
    p.add_argument("--mjcf", metavar="M.xml",
                   help="MJCF, or the arm's shipped URDF, with the robot's inertias (gravity "
                        "torques for joint_compliance; its joints named as the model's, or one "
                        "hinge/slide joint per model joint, same order and zero)")
    p.add_argument("--data", required=True, metavar="D.csv",
                   help="measurement CSV, or a quoted glob ('fleet/*.csv') for a fleet")
    add_deg(p)
    p.add_argument("--frame", choices=("instrument", "base"), default="instrument",
                   help="frame of x, y, z (default instrument: the base frame is estimated)")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--seed", type=SEED, default=0, help="seed of the fitting/withheld split")
    p.add_argument("--withheld", type=real(0.0, MAX_WITHHELD, open_lo=True),
                   default=0.25, metavar="FRACTION",
                   help="share of the poses withheld (default 0.25)")
    p.add_argument("--folds", type=whole(2, 100),
                   default=5, help="cross-validation folds (default 5)")
    p.add_argument("--effects", nargs="+", choices=EFFECTS, default=list(EFFECTS),
                   metavar="EFFECT", help=f"candidate effects (default all: {', '.join(EFFECTS)})")
    p.add_argument("--max-steps", type=whole(1, len(EFFECTS)),
                   default=4, help="most effects added (default 4)")
    p.add_argument("--alpha", type=real(0.0, 1.0, open_lo=True, open_hi=True), default=1e-3,
                   help="significance level for adding an effect (default 1e-3)")
    p.add_argument("--noise", type=LENGTH, metavar="SIGMA",
                   help="known instrument noise per coordinate (length unit); default: "
                        "estimated from rigidly linked points or repeats")
    p.add_argument("--orientation-sigma", type=real(0.0, 1.0, open_lo=True), metavar="RAD",
                   help="orientation noise per component (rad) when the data carry qw..qz; "
                        "default: estimated from the orientation residuals")
    p.add_argument("--no-orientation", action="store_true",
                   help="ignore measured orientations (qw..qz): no full-pose refit")
    p.add_argument("--residual-model", action="store_true",
                   help="also train a learned residual term on the joint angles after the "
                        "final model; kept only when what remains has structure and it "
                        "lowers the withheld error clearly "
                        "(its withheld RMS beside the physical model's)")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    add_progress(p, help="show progress on stderr: a bar on a terminal, a line every 10 s "
                 "when piped (default on; --no-progress: silent)")
    p.add_argument("--max-points", type=whole(0), default=MAX_POINTS, metavar="N",
                   help=f"most measured points diagnosed (default {MAX_POINTS}); beyond it a "
                        "seeded random subsample of whole poses, announced and recorded in "
                        "diagnosis.json (rule: zrp/gap/data/subsample.py); 0 uses every point")
    p.add_argument("--max-rows", type=whole(1), default=MAX_ROWS, metavar="N",
                   help=f"most data rows read (default {MAX_ROWS:,}, about 1.4 GB at the peak);"
                        " a larger file is refused with guidance")
    p.add_argument("--json", action="store_true", help="print diagnosis.json to stdout")
    add_fleet_options(p)
    p.set_defaults(func=_run, api_names={
        "withheld_fraction": "--withheld",
        "noise_sigma": "--noise",
        "folds": "--folds",
        "alpha": "--alpha",
        "max_steps": "--max-steps",
        "seed": "--seed",
        "effects": "--effects",
        "gravity_torque": "--mjcf",
        "max_points": "--max-points",
        "max_rows": "--max-rows",
        "orientation_sigma": "--orientation-sigma",
    })


def _run(args: argparse.Namespace) -> int:
    # mjcf loads MuJoCo (+0.25 s measured): only when this command runs, not for every `zrp`.
    from mjcf.gravity import gravity_torques
    from zrp.gap import diagnose as run_diagnosis  # on use: keeps --help quick
    from zrp.gap import load_measurements  # on use: keeps --help quick
    from zrp.gap.report import (  # on use: keeps --help quick
        OUTPUT_FILES,
        diagnosis_document,
        verdict_text,
        write_outputs,
    )
    from zrp.model.files import load_model  # on use: keeps --help quick

    if args.max_steps < 1:
        raise InputError(f"--max-steps: expected at least 1, got {args.max_steps}")
    if is_fleet(args.data):  # one diagnosis per file, on a cluster or here (zrp/cli/fleet)
        return run_fleet(args)
    refuse_fleet_options(args)
    # reading the inputs creates nothing: a bad input leaves no output folder behind
    model = load_model(args.model)
    # the reader's bar only on a terminal; piped runs get the diagnosis's periodic lines
    meas = load_measurements(args.data, model, deg=args.deg, frame=args.frame,
                             progress=draw_bar(args), max_rows=args.max_rows)
    tau = None if args.mjcf is None else gravity_torques(
        args.mjcf, meas.q_pose, field="--mjcf", joint_names=[j.name for j in model.joints])
    out_dir = Path(args.out)
    created = not out_dir.exists()
    try:
        # the folder is this run's from here on: existing outputs are refused before the
        # computation, and a concurrent run into the same folder is refused, never mixed in
        with OutputDir(out_dir, overwrite=args.force, names=OUTPUT_FILES, prune=True) as out:
            diag = run_diagnosis(model, meas, gravity_torque=tau, effects=args.effects,
                            seed=args.seed, withheld_fraction=args.withheld, folds=args.folds,
                            alpha=args.alpha, max_steps=args.max_steps, noise_sigma=args.noise,
                            progress=args.progress, max_points=args.max_points or None,
                            use_orientation=not args.no_orientation,
                            orientation_sigma=args.orientation_sigma,
                            residual_model=args.residual_model)
            files = write_outputs(diag, out, plots=not args.no_plots)
    except BaseException:
        if created:  # a failed run leaves no empty folder it made
            with contextlib.suppress(OSError):
                out_dir.rmdir()
        raise
    text = verdict_text(diag) + "\n" + "\n".join(f"wrote {f}" for f in files)
    emit(args, diagnosis_document(diag), text)
    return 0
