"""``zrp study``: custom one-at-a-time perturbation sweeps (eqs 8-17) along a trajectory.

Also holds the trajectory options shared by ``zrp study``, ``zrp tolerance`` and ``zrp paper``.
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

from zrp.cli.app import emit
from zrp.cli.options import (
    DURATION,
    FINITE,
    LENGTH,
    MAX_STEPS,
    PERCENT,
    add_deg,
    joint_angles,
    whole,
)
from zrp.errors import InputError, ZRPWarning
from zrp.kinematics.trajectory import TIME_LAWS
from zrp.manufacturing.perturb import PAPER_SIGN_ZERO
from zrp.manufacturing.study import (
    PAPER_PARAMETERS,
    PAPER_XI,
    JointPath,
    StudyResult,
    load_joint_csv,
    one_at_a_time,
)
from zrp.model.files import builtin_models, load_model
from zrp.model.manipulator import Manipulator
from zrp.output import OutputDir
from zrp.paper.scenario import PUMA_Q0_DEG, circle_joint_path, is_paper_model

#: The tables ``zrp study --out DIR`` writes.
STUDY_TABLES = tuple(f"study_{q}.{ext}" for q in ("delta_p", "delta_r", "angle_rad")
                     for ext in ("csv", "md"))


def add_path_options(p: argparse.ArgumentParser, steps: int = 360) -> None:
    """--model, trajectory options and --json."""
    p.add_argument("--model", default="puma", metavar="FILE",
                   help=f"model TOML file or built-in name ({', '.join(sorted(builtin_models()))}"
                        "; default puma)")
    g = p.add_argument_group("trajectory (nominal inverse kinematics of a circle, or a file)")
    g.add_argument("--joints", metavar="CSV", default=None,
                   help="joint trajectory CSV: header, then t (s) and q1..qn (rad, --deg or "
                        "q1[deg]; prismatic: length unit)"
                        " per row, e.g. written by `zrp ik`; replaces the circle")
    g.add_argument("--q0", nargs="+", type=FINITE, metavar="Q", default=None,
                   help="start configuration, rad (deg with --deg; prismatic joints in the "
                        "length unit); "
                        f"default {' '.join(f'{v:g}' for v in PUMA_Q0_DEG)} deg for the "
                        "paper's PUMA (the built-in puma), required for every other model")
    add_deg(g)
    g.add_argument("--radius", type=LENGTH, default=125.0,
                   help="circle radius, length unit (default 125)")
    g.add_argument("--normal", nargs=3, type=FINITE, default=None, metavar=("X", "Y", "Z"),
                   help="circle plane normal (default: the tool's axial direction at q0)")
    g.add_argument("--toward", nargs=3, type=FINITE, default=None, metavar=("X", "Y", "Z"),
                   help="from the start point towards the centre (default: base +z)")
    g.add_argument("--duration", type=DURATION, default=4.0, help="s (default 4)")
    g.add_argument("--time-law", choices=TIME_LAWS, default="quintic")
    g.add_argument("--steps", type=whole(2, MAX_STEPS), default=steps,
                   help=f"integration steps, samples = steps + 1 (default {steps})")
    p.add_argument("--json", action="store_true", help="print JSON")


def check_path_options(args: argparse.Namespace, model: Manipulator) -> None:
    """Check the trajectory options against ``model`` before any work: --q0 has one value per
    joint, and is given for every model but the paper's PUMA (which has a default start)."""
    if args.joints:
        return
    if args.q0 is None:
        if not is_paper_model(model):
            raise InputError(
                f"--q0: required for {model.name!r} ({model.n} joints): the default start "
                f"configuration ({' '.join(f'{v:g}' for v in PUMA_Q0_DEG)} deg) is the paper's,"
                f" for its PUMA only; give --q0 with {model.n} values (rad, or deg with --deg;"
                f" prismatic joints in {model.length_unit}), or a joint trajectory with "
                "--joints CSV")
    elif len(args.q0) != model.n:
        raise InputError(f"--q0: expected {model.n} values for {model.name!r}, got "
                         f"{len(args.q0)}")


def path_from_args(args: argparse.Namespace, model: Manipulator) -> JointPath:
    """The nominal joint trajectory the options describe."""
    check_path_options(args, model)
    if args.joints:
        return load_joint_csv(args.joints, model, deg=args.deg)
    q0 = None if args.q0 is None else joint_angles(model, args.q0, args.deg, "--q0")
    with warnings.catch_warnings():
        warnings.simplefilter("default", ZRPWarning)
        return circle_joint_path(model, q0=q0, radius=args.radius, duration=args.duration,
                                 steps=args.steps, normal=args.normal, toward=args.toward,
                                 time_law=args.time_law)


def add_sign_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--sign0-links", type=int, choices=(-1, 0, 1),
                   default=PAPER_SIGN_ZERO["links"],
                   help="sign(0) in eq (11) for link vectors (default 0, as the published LE "
                        "values imply)")
    p.add_argument("--sign0-axes", type=int, choices=(-1, 0, 1), default=PAPER_SIGN_ZERO["axes"],
                   help="sign(0) in eq (10) for joint axes (default +1; 0 makes every "
                        "single-component axis error vanish)")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "study", help="one-at-a-time perturbation sweep (paper eqs 8-17)",
        description="Perturb each parameter alone (LE<k>: link vector b_k,0; JE<k>: joint axis "
        "u_k,0) by each xi (percent, -1 < xi < 1), replay the nominal IK joints on the "
        "perturbed arm and report max delta_p (eq 17), max delta_R (eq 15) and the error angle.")
    add_path_options(p)
    p.add_argument("--params", nargs="+", default=list(PAPER_PARAMETERS), metavar="NAME",
                   help="parameters (default: the paper's LE2 LE3 LE4 LE7 JE1..JE6)")
    p.add_argument("--xi", nargs="+", type=PERCENT, default=list(PAPER_XI), metavar="PCT",
                   help="levels in percent (default: 0, +-0.02, +-0.05, +-0.07, +-0.1)")
    add_sign_options(p)
    p.add_argument("--out", default=None, metavar="DIR",
                   help="also write study_delta_p / study_delta_r / study_angle_rad CSV and "
                        "Markdown tables into DIR (checked before the study runs)")
    p.add_argument("--force", action="store_true",
                   help="replace tables that already exist in --out (without it, existing "
                        "files are never replaced)")
    p.set_defaults(func=_study, api_names={
        "q0": "--q0",
        "steps": "--steps",
        "xi_percent": "--xi",
        "parameters": "--params",
    })


def _run_study(args: argparse.Namespace, model: Manipulator,
               out: OutputDir | None) -> tuple[JointPath, StudyResult]:
    path = path_from_args(args, model)
    st = one_at_a_time(model, path, args.params, args.xi, sign_zero_links=args.sign0_links,
                       sign_zero_axes=args.sign0_axes)
    if out is not None:
        for name in STUDY_TABLES:
            quantity, fmt = name[len("study_"):].split(".")
            out.write_text(name, st.table_text(fmt, quantity))
    return path, st


def _study(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    check_path_options(args, model)
    files: list[str] = []
    if args.out:
        with OutputDir(args.out, overwrite=args.force, names=STUDY_TABLES) as out:
            path, st = _run_study(args, model, out)
        files = [str(f) for f in out.written]
    else:
        path, st = _run_study(args, model, None)
    payload = st.summary()
    payload["linearity_delta_p"] = {
        k: {f: (None if isinstance(x, float) and not np.isfinite(x) else x)
            for f, x in vars(v).items()} for k, v in st.linearity().items()}
    payload["files"] = files
    u = st.unit
    lines = [f"{model.name}: {path.label} ({st.t.size} samples)",
             f"convention: {st.convention}",
             "IK error of the nominal path: " + (f"{path.ik_position_error:.3g} {u}"
                                                 if path.ik_position_error is not None
                                                 else "unknown (not in the joint file)"),
             "",
             f"{'param':6s} {'xi %':>7s} {'max dp ' + u:>12s} {'max dR eq15':>12s} "
             f"{'max angle rad':>14s}"]
    for i, nm in enumerate(st.parameters):
        for j, xi in enumerate(st.xi_percent):
            lines.append(f"{nm:6s} {xi:7.3g} {st.max_delta_p[i, j]:12.4e} "
                         f"{st.max_delta_r[i, j]:12.4e} {st.max_angle_rad[i, j]:14.4e}")
    lines.append("")
    lin_all = st.linearity()
    if lin_all:
        lines.append("linearity of max delta_p vs |xi| (slope per %, R^2):")
        for nm, lin in lin_all.items():
            lines.append(f"  {nm:6s} slope {lin.slope:.5g} {u}/%  R^2 {lin.r2:.8f}")
    else:
        lines.append("linearity: needs at least two distinct |xi| levels")
    lines += [f"wrote {f}" for f in files]
    emit(args, payload, "\n".join(lines))
    return 0
