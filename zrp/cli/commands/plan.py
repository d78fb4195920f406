"""``zrp plan``: choose the poses to measure (D-optimal) and predict what they identify."""

from __future__ import annotations

import argparse
import csv
import io
import warnings

import numpy as np

from zrp.calibration import plan_poses
from zrp.cli.app import emit
from zrp.cli.options import FINITE, LENGTH, SEED, whole
from zrp.errors import InputError
from zrp.gap.model.context import EFFECTS
from zrp.model.files import load_model
from zrp.output import check_writable, write_text


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plan", help="plan the measurement poses of a calibration (D-optimal)",
        description="Choose N poses within the joint limits (above a floor) that make the "
        "chosen effects identifiable (D-optimal, DETMAX-style exchange); print the predicted "
        "standard deviation of every parameter and warn about unidentifiable ones. Writes "
        "OUT.csv: pose, q1..qn, dir1..dirn (zrp/calibration/README.md).")
    p.add_argument("--model", required=True, metavar="M.toml", help="model TOML or built-in")
    p.add_argument("--poses", type=whole(1, 100_000), required=True, metavar="N",
                   help="poses to measure")
    p.add_argument("--effects", nargs="+", choices=EFFECTS, required=True, metavar="EFFECT",
                   help="effects to identify (registration is always included)")
    p.add_argument("--out", required=True, metavar="OUT.csv", help="planned poses CSV")
    p.add_argument("--force", action="store_true", help="overwrite the output file")
    p.add_argument("--deg", action="store_true", help="limits and output in degrees")
    p.add_argument("--limits", metavar="LO:HI,...", help="joint limits, one LO:HI per joint, "
                   "comma-separated (default +-2.5 rad)")
    p.add_argument("--floor", type=FINITE, metavar="Z", help="keep every joint and tool point "
                   "above z = Z (base frame, length unit)")
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
                                         "noise_sigma": "--noise"})


def _limits(text: str | None, n: int, deg: bool) -> np.ndarray | None:
    if text is None:
        return None
    pairs = text.split(",")
    try:
        lim = np.array([[float(v) for v in s.split(":")] for s in pairs], dtype=float)
    except ValueError:
        raise InputError(f"--limits: expected LO:HI numbers, got {text!r}") from None
    if lim.shape != (n, 2):
        raise InputError(f"--limits: expected {n} LO:HI pairs, got {text!r}")
    _check_limits(lim, pairs)
    return np.radians(lim) if deg else lim


def _check_limits(lim: np.ndarray, pairs: list[str]) -> None:
    """Every pair finite with LO <= HI and at least one joint free to move: a NaN, an inverted
    pair or all joints fixed (20 identical poses) is an error naming the joint."""
    for k, (lo, hi) in enumerate(lim, start=1):
        if not (np.isfinite(lo) and np.isfinite(hi)):
            raise InputError(f"--limits: joint {k} is {pairs[k - 1]!r}; expected finite "
                             "numbers LO:HI")
        if lo > hi:
            raise InputError(f"--limits: joint {k} is {pairs[k - 1]!r}: LO > HI; expected "
                             "LO <= HI")
    if np.all(lim[:, 1] - lim[:, 0] <= 0.0):
        raise InputError("--limits: every joint has LO = HI: no joint can move, so every "
                         "planned pose would be the same; give at least one joint a range")


def _run(args: argparse.Namespace) -> int:
    check_writable([args.out], args.force)
    model = load_model(args.model)
    with warnings.catch_warnings(record=True) as wl:
        warnings.simplefilter("always")
        plan = plan_poses(model, args.poses, args.effects, rng=np.random.default_rng(args.seed),
                          limits=_limits(args.limits, model.n, args.deg),
                          tool_points=args.tool or ((0.0, 0.0, 0.0),), floor_z=args.floor,
                          noise_sigma=args.noise,  # None: a tracker's 20 um in the model's unit
                          candidates=args.candidates)
    n = model.n
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(["pose", *[f"q{k}" for k in range(1, n + 1)], *[f"dir{k}" for k in
                                                               range(1, n + 1)]])
    q = np.degrees(plan.q) if args.deg else plan.q
    for i in range(len(q)):
        w.writerow([f"P{i + 1:03d}", *(repr(float(v)) for v in q[i]),
                    *(int(v) for v in plan.direction[i])])
    path = write_text(args.out, buf.getvalue(), overwrite=args.force)
    lines = [f"{p}: predicted std {s:.3g} {u}"
             for p, s, u in zip(plan.names, plan.std, plan.units, strict=True)]
    lines += [f"warning: {w.message}" for w in wl]
    lines += [f"log det per pose: {plan.log_det:.4g} (random start {plan.log_det_random:.4g})",
              f"wrote {path}"]
    payload = {"parameters": [{"name": p, "std": s, "unit": u} for p, s, u in
                              zip(plan.names, plan.std, plan.units, strict=True)],
               "unidentifiable": list(plan.unidentifiable), "log_det": plan.log_det,
               "log_det_random": plan.log_det_random, "warnings": [str(w.message) for w in wl]}
    emit(args, payload, "\n".join(lines))
    return 0
