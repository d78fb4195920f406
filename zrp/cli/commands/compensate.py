"""``zrp compensate``: joint commands that put the calibrated robot on its targets."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

    from zrp.model.manipulator import Manipulator

from zrp.cli.app import emit
from zrp.cli.options import add_deg, joint_angles, real
from zrp.errors import InputError
from zrp.output import check_writable


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "compensate", help="compensate targets or a joint program with a calibrated robot",
        description="Read a calibration (compensation.json from zrp calibrate) and a targets "
        "CSV (target, q1..qn [, x, y, z [, qw, qx, qy, qz]]); write the joint commands with "
        "the predicted residual and flags per target (zrp/calibration/README.md).")
    p.add_argument("--calibration", required=True, metavar="C.json",
                   help="compensation file (its model_file beside it)")
    p.add_argument("--model-file", metavar="M.toml",
                   help="the calibrated model file (default: the compensation file's "
                   "model_file, which must lie in its folder)")
    p.add_argument("--targets", required=True, metavar="T.csv", help="targets CSV")
    p.add_argument("--out", required=True, metavar="OUT.csv", help="commands CSV")
    p.add_argument("--force", action="store_true", help="overwrite the output file")
    add_deg(p)
    p.add_argument("--point", help="tool point the x, y, z targets are for (default with "
                   "--frame base: the model's end point; required with --frame instrument)")
    p.add_argument("--frame", choices=("base", "instrument"), default="base",
                   help="frame of x, y, z (default base)")
    p.add_argument("--limits", metavar="LO:HI,...",
                   help="joint limits, one LO:HI per joint, comma-separated (deg with --deg), "
                   "e.g. --limits=-165:165,-110:110,... (default: the calibrated model's own); "
                   "every target row and every command is checked against them")
    p.add_argument("--mjcf", metavar="M.xml", help="MJCF or the arm's URDF with inertias "
                   "(needed when the compliance was identified with MJCF torques)")
    p.add_argument("--temp", type=real(-100.0, 500.0), metavar="DEGC",
                   help="robot temperature when the commands run, deg C (required when the "
                   "calibration found thermal expansion)")
    p.add_argument("--load", type=real(0.0, 1e4), metavar="KG",
                   help="payload when the commands run, kg (required when the calibration's "
                   "joint map depends on a payload measured in the data)")
    p.add_argument("--accept-flagged", action="store_true",
                   help="compensate targets whose commands lie outside the joint ranges the "
                   "calibration measured, or near a singularity (relative to the arm's own "
                   "conditioning), too, flagged per row (outside_measured, near_singular); "
                   "default: refused")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=_run, api_names={"limits": "--limits", "point": "--point",
                                         "gravity_torque": "--mjcf", "temp": "--temp",
                                         "load": "--load",
                                         "accept_flagged": "--accept-flagged"})


def _limits(args: argparse.Namespace, model: Manipulator) -> np.ndarray | None:
    import numpy as np  # on use: keeps --help quick

    if args.limits is None:
        return None
    pairs = args.limits.split(",")
    if len(pairs) != model.n:
        raise InputError(f"--limits: expected {model.n} LO:HI pairs, got {len(pairs)}")
    try:
        lim = np.array([[float(v) for v in s.split(":")] for s in pairs], dtype=float)
    except ValueError:
        raise InputError(f"--limits: expected LO:HI numbers, got {args.limits}") from None
    if lim.shape != (model.n, 2):
        raise InputError(f"--limits: expected LO:HI pairs, got {args.limits}")
    return joint_angles(model, lim, args.deg, "--limits")


def _run(args: argparse.Namespace) -> int:
    import numpy as np  # on use: keeps --help quick

    from zrp.calibration import (  # on use: keeps --help quick
        PoseConditions,
        compensate_program,
        read_calibration,
    )
    from zrp.calibration import compensate as compensate_targets  # on use: quick --help
    from zrp.calibration.conditions import missing_conditions  # on use: keeps --help quick
    from zrp.calibration.expected import expected_accuracy, expected_words  # on use
    from zrp.calibration.targets import load_targets, write_commands  # on use: keeps --help quick

    check_writable([args.out], args.force)
    cal = read_calibration(args.calibration, args.model_file)
    tg = load_targets(args.targets, cal.n, deg=args.deg, model=cal.model)
    lim = _limits(args, cal.model)
    grav = None
    if args.mjcf is not None:
        # mjcf loads MuJoCo (+0.25 s): only when asked for
        from mjcf.gravity import gravity_torques

        def grav(q: np.ndarray) -> np.ndarray:
            return gravity_torques(args.mjcf, q, field="--mjcf",
                                   joint_names=[j.name for j in cal.model.joints])
    elif cal.compliance_model == "mjcf" and any(
            t.effect == "joint_compliance" for t in cal.terms):
        raise InputError("--mjcf: this calibration used --mjcf (its joint compliance was "
                         "identified with the MJCF's gravity torques, in rad/(N m)); pass the "
                         "same MJCF or URDF with --mjcf")
    missing_conditions(cal.terms, cal.compliance_model, cal.kappa, cal.conditions,
                       temp=args.temp, load=args.load)
    T = len(tg.q)
    cond = PoseConditions(temp=None if args.temp is None else np.full(T, args.temp),
                          load=None if args.load is None else np.full(T, args.load))
    if tg.xyz is None:
        comp = compensate_program(cal, tg.q, limits=lim, gravity_torque=grav,
                                  target_ids=tg.ids, conditions=cond,
                                  accept_flagged=args.accept_flagged)
    else:
        comp = compensate_targets(cal, tg.xyz, tg.q, orientations=tg.rotation, point=args.point,
                          frame=args.frame, limits=lim, gravity_torque=grav,
                          target_ids=tg.ids, conditions=cond,
                          accept_flagged=args.accept_flagged)
    path = write_commands(comp, args.out, deg=args.deg, overwrite=args.force)
    acc = expected_accuracy(cal, comp)
    s = {**comp.summary(), **acc}
    text = (f"{expected_words(acc, cal.model.length_unit)}\n{s['not_converged']} not "
            f"converged, {s['near_singular']} near a singularity, {s['near_limit']} near a "
            f"limit, {s['outside_measured']} outside the measured joint ranges\nwrote {path}")
    emit(args, s, text)
    return 0
