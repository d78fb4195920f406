"""``zrp verify``: a compensated program commanded on the simulated robot, before and after."""

from __future__ import annotations

import argparse

from zrp.cli.app import emit
from zrp.cli.options import SEED, add_deg, whole
from zrp.errors import InputError
from zrp.escape import csv_text
from zrp.output import check_writable, write_text


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "verify", help="what a calibration achieves: on a fresh measurement (--data) or on "
        "the simulated robot (--truth)",
        description="With --data FRESH.csv (a measurement CSV as zrp diagnose reads, of the "
        "robot after calibration: uncompensated at any joint values, or compensated at the "
        "commands zrp compensate wrote): the achieved position error of each measured point "
        "against what the calibration says the robot reaches there, as RMS, 95th percentile "
        "and maximum, against the diagnosis's withheld prediction, within and outside the "
        "measured joint ranges, and ISO 9283 pose accuracy and repeatability where poses are "
        "repeated (zrp/calibration/verification.py); --out DIR writes verification.json, "
        "errors.csv, verification.md and verification.png. With --truth, --targets and "
        "--commands instead: rebuild the simulated 'real' robot and tracker of a zrp measure "
        "run, command the program as it is and compensated, measure both, and report the "
        "error of each against the program's targets (sim/studies/verify.py).")
    p.add_argument("--calibration", required=True, metavar="C.json",
                   help="compensation file of zrp calibrate (its model_file beside it)")
    p.add_argument("--data", metavar="FRESH.csv",
                   help="a fresh measurement of the calibrated robot (measurement CSV)")
    p.add_argument("--frame", choices=("instrument", "base"), default="instrument",
                   help="with --data: frame of x, y, z (default instrument: the "
                   "calibration's registration)")
    p.add_argument("--reregister", action="store_true",
                   help="with --data: fit the instrument frame again to the fresh set (the "
                   "tracker was set up anew; slightly optimistic)")
    p.add_argument("--min-repeats", type=whole(2, 1000), default=3, metavar="K",
                   help="with --data: a pose measured at least K times enters ISO 9283 "
                   "(default 3)")
    p.add_argument("--mjcf", metavar="M.xml", help="with --data: the MJCF or URDF with "
                   "inertias (when the compliance was identified with --mjcf)")
    p.add_argument("--no-plots", action="store_true", help="with --data: no PNG plot")
    p.add_argument("--truth", metavar="T.json",
                   help="truth file of the zrp measure run the calibration came from")
    p.add_argument("--targets", metavar="T.csv",
                   help="the program: the targets CSV given to zrp compensate (target, "
                        "q1..qn; a joint program)")
    p.add_argument("--commands", metavar="CMD.csv",
                   help="the compensated commands zrp compensate wrote")
    add_deg(p)
    p.add_argument("--out", metavar="OUT", help="per target: error before and after "
                   "(OUT.csv); with --data: the folder of the verification files")
    p.add_argument("--force", action="store_true", help="overwrite --out")
    p.add_argument("--seed", type=SEED, default=0, help="seed of the tracker noise")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=_run, api_names={"truth": "--truth", "calibration": "--calibration",
                                         "point": "--data"})


def _run(args: argparse.Namespace) -> int:
    if args.data is not None:
        from zrp.cli.verify_data import run_data  # on use: keeps --help quick

        summary, text = run_data(args)
        emit(args, summary, text)
        return 0
    missing = [o for o, v in (("--truth", args.truth), ("--targets", args.targets),
                              ("--commands", args.commands)) if v is None]
    if missing:
        raise InputError(f"{', '.join(missing)}: required without --data (zrp verify checks a "
                         "fresh measurement with --data FRESH.csv, or the simulated robot with "
                         "--truth, --targets and --commands)")
    return _simulated(args)


def _simulated(args: argparse.Namespace) -> int:
    import numpy as np  # on use: keeps --help quick

    from sim.studies.verify import read_truth, verify_program  # sim loads MuJoCo: only here
    from zrp.calibration import read_calibration  # on use: keeps --help quick
    from zrp.calibration.targets import load_commands, load_targets  # on use: keeps --help quick

    if args.out:
        check_writable([args.out], args.force)
    cal = read_calibration(args.calibration)
    model = cal.nominal
    tg = load_targets(args.targets, model.n, deg=args.deg, model=model)
    if tg.xyz is not None:
        raise InputError(f"--targets: {args.targets} has x, y, z targets; zrp verify checks a "
                         "joint program (target, q1..qn)")
    cmd = load_commands(args.commands, model, deg=args.deg)
    if cmd.ids != tg.ids:
        raise InputError(f"--commands: its targets ({len(cmd.ids)}) are not those of "
                         f"--targets ({len(tg.ids)}) in the same order; compensate them again")
    truth = read_truth(args.truth, field="--truth")
    res = verify_program(model, truth, cal, tg.q, cmd.q, seed=args.seed)
    s = res.summary()
    s["not_converged"] = int((~cmd.converged).sum())
    u = model.length_unit
    lines = [f"{s['targets']} targets on the simulated {model.name} ({', '.join(res.points)}):"
             f" RMS error {s['rms_before']:.4g} {u} as programmed -> {s['rms_after']:.4g} "
             f"{u} compensated (max {s['max_after']:.3g}); tracker noise "
             f"{s['noise_rms']:.3g} {u} RMS: {s['ratio_after_to_noise']:.2f}x the noise"]
    if s["not_converged"]:
        lines.append(f"warning: {s['not_converged']} command(s) did not converge in zrp "
                     "compensate (commanded as written)")
    if args.out:
        rows = ([t, repr(float(b)), repr(float(a))]
                for t, b, a in zip(tg.ids, res.error_before, res.error_after, strict=True))
        text = csv_text(["target", f"error_before[{u}]", f"error_after[{u}]"], rows)
        lines.append(f"wrote {write_text(args.out, text, overwrite=args.force)}")
    emit(args, s, "\n".join(lines))
    return 0 if np.isfinite(s["rms_after"]) else 1
