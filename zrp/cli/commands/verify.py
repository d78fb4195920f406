"""``zrp verify``: a compensated program commanded on the simulated robot, before and after."""

from __future__ import annotations

import argparse

from zrp.cli.app import emit
from zrp.cli.options import SEED, add_deg
from zrp.errors import InputError
from zrp.escape import csv_text
from zrp.output import check_writable, write_text


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "verify", help="command a compensated program on the simulated robot: before/after",
        description="Rebuild the simulated 'real' robot and tracker of a zrp measure run "
        "from its truth file, command the program (the targets CSV of zrp compensate) as it "
        "is and the compensated commands (its output), measure both with the tracker, and "
        "report the error of each against the program's targets (sim/studies/verify.py).")
    p.add_argument("--calibration", required=True, metavar="C.json",
                   help="compensation file of zrp calibrate (its model_file beside it)")
    p.add_argument("--truth", required=True, metavar="T.json",
                   help="truth file of the zrp measure run the calibration came from")
    p.add_argument("--targets", required=True, metavar="T.csv",
                   help="the program: the targets CSV given to zrp compensate (target, "
                        "q1..qn; a joint program)")
    p.add_argument("--commands", required=True, metavar="CMD.csv",
                   help="the compensated commands zrp compensate wrote")
    add_deg(p)
    p.add_argument("--out", metavar="OUT.csv", help="per target: error before and after")
    p.add_argument("--force", action="store_true", help="overwrite --out")
    p.add_argument("--seed", type=SEED, default=0, help="seed of the tracker noise")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=_run, api_names={"truth": "--truth", "calibration": "--calibration"})


def _run(args: argparse.Namespace) -> int:
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
