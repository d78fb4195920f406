"""``zrp fk``, ``zrp ik`` and ``zrp models``: kinematics from the command line."""

from __future__ import annotations

import argparse
import warnings
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

    from zrp.model.manipulator import Manipulator

from zrp.cli.app import emit
from zrp.cli.options import (
    DURATION,
    FINITE,
    LENGTH,
    MAX_STEPS,
    add_deg,
    joint_angles,
    real,
    whole,
)
from zrp.errors import InputError, ZRPWarning
from zrp.kinematics.choices import CORRECTIONS, TIME_LAWS
from zrp.limits import MAX_LENGTH
from zrp.model.builtin import builtin_models
from zrp.output import check_writable, claim_generated, safe_name
from zrp.paper.choices import PUMA_DURATION_S, PUMA_Q0_DEG, PUMA_RADIUS_MM


def _joint_values(model: Manipulator, values: list[float], deg: bool, name: str) -> np.ndarray:
    return joint_angles(model, values, deg, name)


def _add_model(p: argparse.ArgumentParser) -> None:
    p.add_argument("--model", default="puma", metavar="FILE",
                   help=f"model TOML file or built-in name ({', '.join(sorted(builtin_models()))}"
                        "; default puma)")
    add_deg(p)
    p.add_argument("--json", action="store_true", help="print JSON")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fk", help="forward kinematics of one joint vector",
                       description="End-effector point, u_a, u_t, hand rotation and its "
                       "Euler-Rodrigues parameters, and the current joint axes and points.")
    _add_model(p)
    p.add_argument("--q", nargs="+", type=FINITE, required=True, metavar="Q",
                   help="joint values q1..qn")
    p.set_defaults(func=_fk)

    p = sub.add_parser("ik", help="inverse kinematics along a circle or line",
                       description="Integrate eq (7) along a trajectory (ABM4 predictor-"
                       "corrector, RK4 start, Newton drift correction). Default: the paper's "
                       "125 mm circle on the Table 1 PUMA (see README).")
    _add_model(p)
    p.add_argument("--q0", nargs="+", type=FINITE, metavar="Q",
                   help="start configuration (default "
                        f"{' '.join(f'{v:g}' for v in PUMA_Q0_DEG)} deg for the paper's PUMA, "
                        "the built-in puma; required for every other model)")
    p.add_argument("--trajectory", choices=("circle", "line"), default="circle")
    p.add_argument("--radius", type=LENGTH, default=PUMA_RADIUS_MM,
                   help="circle radius in length units (default 125)")
    p.add_argument("--normal", nargs=3, type=FINITE, default=[1.0, 0.0, 0.0],
                   help="circle plane normal (default 1 0 0)")
    p.add_argument("--toward", nargs=3, type=FINITE, default=[0.0, 0.0, 1.0],
                   help="direction from the start point to the circle centre (default 0 0 1)")
    p.add_argument("--displacement", nargs=3, type=real(-MAX_LENGTH, MAX_LENGTH),
                   default=[0.0, 100.0, 0.0],
                   help="line: end minus start point (default 0 100 0)")
    p.add_argument("--duration", type=DURATION, default=PUMA_DURATION_S, help="s (default 4)")
    p.add_argument("--time-law", choices=TIME_LAWS, default="quintic")
    p.add_argument("--steps", type=whole(1, MAX_STEPS),
                   default=1000, help="integration steps (default 1000)")
    p.add_argument("--task", choices=("pose", "position"), default=None)
    p.add_argument("--correction", choices=CORRECTIONS, default="newton")
    p.add_argument("--posture", action="store_true",
                   help="resolve redundancy toward the start configuration in the null space "
                        "and keep inside the joint limits (track_posture); a closed path then "
                        "returns to its start")
    p.add_argument("--limits", choices=("error", "warn", "ignore"), default="error",
                   help="when the path needs a joint beyond its limits (default error, naming "
                        "the joint and time)")
    p.add_argument("--target", nargs=3, type=FINITE, default=None, metavar=("X", "Y", "Z"),
                   help="single-pose IK: reach this point (length unit) from --q0 instead of "
                        "following a trajectory; with --target-er also the hand rotation")
    p.add_argument("--target-er", nargs=4, type=FINITE, default=None,
                   metavar=("E0", "E1", "E2", "E3"),
                   help="hand rotation for --target (Euler-Rodrigues, relative to the zero "
                        "reference, as zrp fk prints it)")
    p.add_argument("--out", default=None, metavar="CSV",
                   help="joint trajectory CSV (default renders/<model>_<trajectory>_joints.csv,"
                        " generated output that is replaced on every run)")
    p.add_argument("--force", action="store_true",
                   help="replace the --out file if it exists (without it, an existing file is "
                        "never replaced; checked before solving)")
    p.set_defaults(func=_ik, api_names={"q0": "--q0", "steps": "--steps",
                                        "position": "--target", "limits": "--limits"})

    p = sub.add_parser("models", help="list the built-in model files")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_models)


def _fk(args: argparse.Namespace) -> int:
    import numpy as np  # on use: keeps --help quick

    from zrp.kinematics.forward import forward_kinematics  # on use: keeps --help quick
    from zrp.model.files import load_model  # on use: keeps --help quick
    from zrp.rotations.rodrigues import er_angle  # on use: keeps --help quick

    model = load_model(args.model)
    q = _joint_values(model, args.q, args.deg, "--q")
    fk = forward_kinematics(model, q)
    payload = {
        "model": model.name, "length_unit": model.length_unit, "q_rad_or_length": q,
        "position": fk.position, "axial": fk.axial, "transverse": fk.transverse,
        "rotation": fk.rotation, "euler_rodrigues": fk.er, "rotation_angle_rad": er_angle(fk.er),
        "joint_axes": fk.axes, "joint_points": fk.points,
    }
    u = model.length_unit
    text = "\n".join([
        f"{model.name}",
        f"p   = {np.array2string(fk.position, precision=6)} {u}",
        f"u_a = {np.array2string(fk.axial, precision=6)}",
        f"u_t = {np.array2string(fk.transverse, precision=6)}",
        f"E   = {np.array2string(fk.er, precision=9)} (e0, e1, e2, e3)",
    ])
    emit(args, payload, text)
    return 0


def _refuse_lone_target_er(args: argparse.Namespace) -> None:
    """``--target-er`` without ``--target`` would be ignored (a trajectory is followed)."""
    if args.target_er is not None and args.target is None:
        raise InputError("--target-er: only with --target (the hand rotation of a single-pose "
                         "IK); without --target a trajectory is followed and the rotation "
                         "would be ignored: add --target X Y Z, or drop --target-er")


def _ik(args: argparse.Namespace) -> int:
    import numpy as np  # on use: keeps --help quick

    from zrp.kinematics.forward import forward_kinematics  # on use: keeps --help quick
    from zrp.kinematics.ik import track_trajectory  # on use: keeps --help quick
    from zrp.kinematics.redundant import track_posture  # on use: keeps --help quick
    from zrp.kinematics.trajectory import Circle, Line  # on use: keeps --help quick
    from zrp.model.files import load_model  # on use: keeps --help quick
    from zrp.paper.scenario import is_paper_model  # on use: keeps --help quick

    _refuse_lone_target_er(args)
    model = load_model(args.model)
    if args.q0 is None:
        if not is_paper_model(model):
            raise InputError(
                f"--q0: required for {model.name!r} ({model.n} joints): the default start "
                f"configuration ({' '.join(f'{v:g}' for v in PUMA_Q0_DEG)} deg) is the "
                f"paper's, for its PUMA only; give --q0 with {model.n} values")
        q0 = _joint_values(model, list(PUMA_Q0_DEG), True, "--q0")
    else:
        q0 = _joint_values(model, args.q0, args.deg, "--q0")
    if args.target is not None:
        return _ik_target(args, model, q0)
    stem = safe_name(Path(args.model).stem)
    out = Path(args.out) if args.out else Path("renders") / f"{stem}_{args.trajectory}_joints.csv"
    overwrite = args.force or (args.out is None and claim_generated(out.parent))
    check_writable([out], overwrite)
    start = forward_kinematics(model, q0).position
    if args.trajectory == "circle":
        traj = Circle.from_start(start, args.radius, args.normal, args.toward,
                                 duration=args.duration, time_law=args.time_law)
    else:
        traj = Line(start, start + np.asarray(args.displacement), duration=args.duration,
                    time_law=args.time_law)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", ZRPWarning)
        if args.posture:
            res = track_posture(model, traj, q0, args.steps, task=args.task,
                                limits=args.limits)
        else:
            res = track_trajectory(model, traj, q0, args.steps, task=args.task,
                                   correction=args.correction, limits=args.limits)
    res.save_csv(out, overwrite=overwrite)
    s = res.summary()
    s["output"] = str(out)
    s["max_joint_change_end_start"] = float(np.max(np.abs(res.q[-1] - res.q[0])))
    s["warnings"] = [str(w.message) for w in caught]
    u = model.length_unit
    text = "\n".join([
        f"{model.name}: {args.trajectory}, {s['steps']} steps over {s['duration_s']:g} s "
        f"({s['method']}, task={s['task']})",
        f"  max position error     {s['max_position_error']:.3e} {u}",
        f"  max orientation error  {s['max_orientation_error_rad']:.3e} rad",
        f"  integrator drift/step  {s['max_drift_position']:.3e} {u}, "
        f"{s['max_drift_orientation_rad']:.3e} rad (removed by the correction)",
        f"  min manipulability     {s['min_manipulability']:.4f} at t = "
        f"{s['min_manipulability_t_s']:.3f} s ({s['damped_steps']} damped samples)",
        f"  |q(end) - q(start)|    {s['max_joint_change_end_start']:.3e} (largest joint)",
        f"  solve time             {s['elapsed_s'] * 1e3:.2f} ms"
        + (" (first call: includes compiling the kernels)"
           if s["elapsed_includes_compilation"] else ""),
        *[f"  warning: {w}" for w in s["warnings"]],
        f"  joint trajectory -> {out}",
    ])
    emit(args, s, text)
    return 0


def _ik_target(args: argparse.Namespace, model: Manipulator, q0: np.ndarray) -> int:
    import numpy as np  # on use: keeps --help quick

    from zrp.kinematics.posture import solve_pose  # on use: keeps --help quick

    sol = solve_pose(model, np.array(args.target), args.target_er, q0=q0)
    s = sol.summary()
    s["joint_names"] = list(model.joint_names)
    shown = np.where(model.prismatic, sol.q, np.degrees(sol.q) if args.deg else sol.q)
    unit = "deg" if args.deg else "rad"
    s["q_shown"], s["q_shown_unit"] = shown.tolist(), unit
    text = "\n".join([
        f"{model.name}: target {args.target} {model.length_unit} reached "
        f"({s['iterations']} iterations)",
        *[f"  {nm:<16s} {v: .9g}" for nm, v in zip(model.joint_names, shown, strict=True)],
        f"  ({unit}; prismatic joints in {model.length_unit})",
        f"  position error {s['position_error']:.3e} {model.length_unit}, orientation error "
        f"{s['orientation_error_rad']:.3e} rad, smallest singular value "
        f"{s['min_singular_value']:.3g}"])
    emit(args, s, text)
    return 0


def _models(args: argparse.Namespace) -> int:
    from zrp.model.files import load_model  # on use: keeps --help quick

    models = {name: str(path) for name, path in sorted(builtin_models().items())}
    text = "\n".join(f"{k:10s} {load_model(v).name}  ({v})" for k, v in models.items())
    emit(args, models, text)
    return 0
