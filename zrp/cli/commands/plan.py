"""``zrp plan``: choose the poses to measure (D-optimal) and predict what they identify."""

from __future__ import annotations

import argparse
import math
import warnings
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from collections.abc import Callable

    import numpy as np

    from zrp.model.manipulator import Manipulator

from zrp.cli.app import emit
from zrp.cli.options import FINITE, LENGTH, SEED, add_deg, joint_angles, whole
from zrp.errors import InputError
from zrp.gap.model.choices import EFFECTS
from zrp.output import check_writable


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plan", help="plan the measurement poses of a calibration (D-optimal)",
        description="Choose N poses within the joint limits (above a floor) that make the "
        "chosen effects identifiable (D-optimal, DETMAX-style exchange); print the predicted "
        "standard deviation of every parameter and list the unidentifiable ones. Writes "
        "OUT.csv: pose, q1..qn, dir1..dirn, which zrp measure --poses OUT.csv measures "
        "(zrp/calibration/README.md).")
    p.add_argument("--model", required=True, metavar="M.toml", help="model TOML or built-in")
    p.add_argument("--poses", type=whole(1, 100_000), required=True, metavar="N",
                   help="poses to measure")
    p.add_argument("--effects", nargs="+", choices=EFFECTS, required=True, metavar="EFFECT",
                   help="effects to identify (registration is always included)")
    p.add_argument("--out", required=True, metavar="OUT.csv", help="planned poses CSV")
    p.add_argument("--force", action="store_true", help="overwrite the output file")
    add_deg(p)
    p.add_argument("--limits", metavar="LO:HI,...", help="joint limits, one LO:HI per joint, "
                   "comma-separated, within the model's (default: the model's limits, at most "
                   "+-2.5 rad)")
    p.add_argument("--floor", type=FINITE, metavar="Z", help="keep every joint and tool point "
                   "above z = Z (base frame, length unit)")
    p.add_argument("--mjcf", metavar="FILE",
                   help="MJCF, or the arm's shipped URDF, with the robot's inertias: "
                        "joint_compliance is planned on its gravity torques, the basis zrp "
                        "diagnose --mjcf fits (without it: lumped unit masses on the joints, "
                        "the basis of a diagnosis without --mjcf); its joints named as the "
                        "model's, or one hinge/slide joint per model joint, same order and "
                        "zero. Only with joint_compliance in "
                        "--effects (refused otherwise: it would change nothing)")
    p.add_argument("--tool", nargs=3, type=FINITE, action="append", metavar=("X", "Y", "Z"),
                   help="a tool point offset (repeat per reflector; default the end point)")
    p.add_argument("--noise", type=LENGTH, default=None, metavar="SIGMA",
                   help="instrument noise per coordinate, model length unit (default 0.02 mm "
                        "in the model's unit)")
    p.add_argument("--candidates", type=whole(1, 1_000_000), default=1000,
                   help="candidate poses (1000)")
    p.add_argument("--seed", type=SEED, default=0, help="random seed")
    p.add_argument("--json", action="store_true", help="print the prediction as JSON")
    p.set_defaults(func=_run, api_names={"n_poses": "--poses", "floor_z": "--floor",
                                         "limits": "--limits", "effects": "--effects",
                                         "noise_sigma": "--noise",
                                         "candidates": "--candidates",
                                         "gravity_torque_fn": "--mjcf"})


def _limits(text: str | None, model: Manipulator, deg: bool) -> np.ndarray | None:
    import numpy as np  # on use: keeps --help quick

    if text is None:
        return None
    pairs = text.split(",")
    try:
        lim = np.array([[float(v) for v in s.split(":")] for s in pairs], dtype=float)
    except ValueError:
        raise InputError(f"--limits: expected LO:HI numbers, got {text!r}") from None
    if lim.shape != (model.n, 2):
        raise InputError(f"--limits: expected {model.n} LO:HI pairs, got {text!r}")
    _check_limits(lim, pairs)
    return joint_angles(model, lim, deg, "--limits")


def _check_limits(lim: np.ndarray, pairs: list[str]) -> None:
    """Every pair finite with LO <= HI and at least one joint free to move: a NaN, an inverted
    pair or all joints fixed (20 identical poses) is an error naming the joint."""
    for k, (lo, hi) in enumerate(lim, start=1):
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise InputError(f"--limits: joint {k} is {pairs[k - 1]!r}; expected finite "
                             "numbers LO:HI")
        if lo > hi:
            raise InputError(f"--limits: joint {k} is {pairs[k - 1]!r}: LO > HI; expected "
                             "LO <= HI")
    if bool((lim[:, 1] - lim[:, 0] <= 0.0).all()):
        raise InputError("--limits: every joint has LO = HI: no joint can move, so every "
                         "planned pose would be the same; give at least one joint a range")


def _refuse_unused_mjcf(args: argparse.Namespace) -> None:
    """``--mjcf`` without ``joint_compliance``, the one effect planned on its gravity torques
    (backlash is planned on the approach directions alone: no switching torque is known before
    the diagnosis, so its plan is the same with or without them): the file would be read and
    change nothing, so it is refused by name, as other commands refuse an option that does
    nothing (``zrp diagnose --workers`` on one file, ``zrp import --base`` for an MJCF)."""
    if args.mjcf is not None and "joint_compliance" not in args.effects:
        raise InputError("--mjcf: only with joint_compliance in --effects (planned on the "
                         "file's gravity torques; backlash is planned on the approach "
                         f"directions alone); --effects {' '.join(args.effects)} uses no "
                         "torques: drop --mjcf, or add joint_compliance")


def _gravity(path: str | None, model: Manipulator) -> Callable[[np.ndarray], np.ndarray] | None:
    """q (C, n) -> the gravity torques (C, n) of the file ``path`` (N m), as zrp diagnose
    --mjcf computes them (the file's joints read through the model's joint names), or None.
    A file that does not load or whose joints do not match is a named error (InputError)."""
    if path is None:
        return None
    # mjcf loads MuJoCo (+0.25 s): only when --mjcf is given, never for `zrp --help`
    from mjcf.gravity import gravity_torques

    names = [j.name for j in model.joints]
    return lambda q: gravity_torques(path, q, field="--mjcf", joint_names=names)


def _run(args: argparse.Namespace) -> int:
    import numpy as np  # on use: keeps --help quick

    from zrp.calibration import plan_poses  # on use: keeps --help quick
    from zrp.calibration.planfile import write_plan  # on use: keeps --help quick
    from zrp.model.files import load_model  # on use: keeps --help quick

    _refuse_unused_mjcf(args)
    check_writable([args.out], args.force)
    model = load_model(args.model)
    tau_fn = _gravity(args.mjcf, model)
    with warnings.catch_warnings(record=True) as wl:
        warnings.simplefilter("always")
        plan = plan_poses(model, args.poses, args.effects, rng=np.random.default_rng(args.seed),
                          limits=_limits(args.limits, model, args.deg),
                          tool_points=args.tool or ((0.0, 0.0, 0.0),), floor_z=args.floor,
                          noise_sigma=args.noise,  # None: a tracker's 20 um in the model's unit
                          candidates=args.candidates, gravity_torque_fn=tau_fn)
    path = write_plan(plan, model, args.out, deg=args.deg, overwrite=args.force)
    lines = [f"{p}: predicted std {s:.3g} {u}"
             for p, s, u in zip(plan.names, plan.std, plan.units, strict=True)]
    lines += [f"{p}: unidentifiable with these tool points (moves no point, or aliased with "
              "others, in every pose); not planned"
              for p in plan.unidentifiable]
    lines += [f"warning: {w.message}" for w in wl]
    if args.mjcf is not None:
        lines.append(f"gravity torques from {args.mjcf} (the basis of zrp diagnose --mjcf)")
    lines += [f"log det per pose: {plan.log_det:.4g} (random start {plan.log_det_random:.4g})",
              f"wrote {path}"]
    payload = {"parameters": [{"name": p, "std": s, "unit": u} for p, s, u in
                              zip(plan.names, plan.std, plan.units, strict=True)],
               "unidentifiable": list(plan.unidentifiable), "log_det": plan.log_det,
               "log_det_random": plan.log_det_random, "gravity_torques": args.mjcf,
               "warnings": [str(w.message) for w in wl]}
    emit(args, payload, "\n".join(lines))
    return 0
