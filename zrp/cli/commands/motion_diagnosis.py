"""``zrp diagnose-motion``: the sim-to-real gap along a measured trajectory."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.cli.options import LENGTH, SEED, add_deg, real, whole
from zrp.errors import InputError
from zrp.escape import md_text
from zrp.gap.data.choices import MAX_ROWS
from zrp.gap.model.choices import EFFECTS
from zrp.gap.motion.choices import MOTION_EFFECTS, RATE_RANGE_HZ, TIME_UNITS
from zrp.output import OutputDir, check_writable

OUTPUT_FILES = ("diagnosis_motion.json", "report_motion.md")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "diagnose-motion", help="sim-to-real gap diagnosis along a measured trajectory",
        description="Register a time-stamped trajectory measurement (t, q1..qn, x, y, z; "
        "optional point, tq), then find which motion effect (sync delay, servo lag, friction "
        "at reversals, compliance under the dynamic torque, residual vibration) explains the "
        "gap, where along the path it lies and how far it shrinks on withheld time segments "
        "(zrp/gap/README.md).")
    p.add_argument("--model", required=True, metavar="M.toml", help="model file or built-in name")
    p.add_argument("--data", required=True, metavar="D.csv|BAG",
                   help="trajectory CSV, or a ROS bag (.mcap, .db3, a ROS 2 bag folder, a "
                   "ROS 1 .bag) with the joint states and the instrument's points")
    p.add_argument("--topic", metavar="NAME", help="a bag's sensor_msgs/msg/JointState topic "
                   "(default: its only one)")
    p.add_argument("--point-topic", metavar="NAME", help="a bag's instrument topic, "
                   "geometry_msgs/msg/PointStamped or PoseStamped, in m (default: its only "
                   "one); each topic on its own clock, aligned as the CSV's tq column")
    add_deg(p)
    p.add_argument("--time-unit", choices=sorted(TIME_UNITS), default="s",
                   help="unit of the t (and tq) column (default s; a median sample rate outside "
                        f"{RATE_RANGE_HZ[0]:g} Hz to {RATE_RANGE_HZ[1]:g} Hz is refused)")
    p.add_argument("--max-rows", type=whole(1), default=MAX_ROWS, metavar="N",
                   help=f"most data rows read (default {MAX_ROWS:,}); a larger file is refused "
                        "at the first row beyond")
    p.add_argument("--mjcf", metavar="M.xml", help="MJCF with the inertias (inverse-dynamics "
                   "torques for dynamic_compliance, the arm's own stiffness and damping for "
                   "residual_vibration; one hinge/slide joint per model joint)")
    p.add_argument("--inertia", choices=("puma560", "rods"),
                   help="instead of --mjcf: build the nominal MJCF with these inertias")
    p.add_argument("--frame", choices=("instrument", "base"), default="instrument")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--seed", type=SEED, default=0, help="seed of the time-segment split")
    p.add_argument("--segments", type=whole(4, 10_000), default=20,
                   help="time segments (default 20)")
    p.add_argument("--effects", nargs="+", choices=MOTION_EFFECTS + EFFECTS,
                   default=list(MOTION_EFFECTS), metavar="EFFECT",
                   help=f"candidates (default: {', '.join(MOTION_EFFECTS)}; static ones allowed)")
    p.add_argument("--noise", type=LENGTH, metavar="SIGMA",
                   help="known tracker noise per coordinate (default: from the stream)")
    p.add_argument("--video", metavar="V.mp4", help="also render the arm along the path with "
                   "the measured path and the simulated paths before and after overlaid")
    p.add_argument("--magnify", type=real(0.0, 1e9, open_lo=True), default=50.0,
                   help="magnification of the path differences in the video (default 50)")
    p.add_argument("--json", action="store_true", help="print the diagnosis JSON")
    p.set_defaults(func=_run, api_names={"noise_sigma": "--noise", "n_segments": "--segments",
                                         "seed": "--seed", "effects": "--effects",
                                         "torque": "--mjcf", "magnify": "--magnify",
                                         "overwrite": "--force", "time_unit": "--time-unit",
                                         "max_rows": "--max-rows"})


def _torque(args: argparse.Namespace, model: object, traj: object) -> tuple[object, object]:
    """The inverse-dynamics torques and the mode terms (eq. M6) from the MJCF, or Nones."""
    if args.mjcf and args.inertia:
        raise InputError("--mjcf and --inertia: give one of them")
    if not (args.mjcf or args.inertia):
        return None, None
    # mjcf loads MuJoCo: only when torques are asked for.
    from mjcf import MJCFOptions, build, inverse_dynamics_torques, mode_terms

    src = args.mjcf or build(model, MJCFOptions(inertia=args.inertia)).model  # type: ignore[arg-type]
    qs = (traj.q, traj.qd, traj.qdd)  # type: ignore[attr-defined]
    return (inverse_dynamics_torques(src, *qs, field="--mjcf"),
            mode_terms(src, *qs, field="--mjcf"))


def _trajectory(args: argparse.Namespace, model: object, load_csv: object) -> object:
    """The trajectory of --data: a ROS bag's two topics, or the CSV."""
    from zrp.gap.data.rosbag import is_bag  # on use: keeps --help quick

    if is_bag(args.data):
        from zrp.gap.motion.trajbag import load_trajectory_bag  # on use: keeps --help quick

        return load_trajectory_bag(args.data, model, topic=args.topic,  # type: ignore[arg-type]
                                   point_topic=args.point_topic, frame=args.frame,
                                   max_rows=args.max_rows)
    if args.topic or args.point_topic:
        raise InputError("--topic, --point-topic: for a ROS bag; --data is a CSV")
    return load_csv(args.data, model, deg=args.deg, frame=args.frame,  # type: ignore[operator]
                    time_unit=args.time_unit, max_rows=args.max_rows)


def _run(args: argparse.Namespace) -> int:
    from zrp.gap.motion import diagnose_motion, load_trajectory  # on use: keeps --help quick
    from zrp.jsonio import dumps  # on use: keeps --help quick
    from zrp.model.files import load_model  # on use: keeps --help quick

    model = load_model(args.model)
    if args.video:
        check_writable([args.video], args.force)  # before the work
    traj = _trajectory(args, model, load_trajectory)
    tau, terms = _torque(args, model, traj)
    with OutputDir(Path(args.out), overwrite=args.force, names=OUTPUT_FILES) as folder:
        diag = diagnose_motion(model, traj, torque=tau, mode_terms=terms, effects=args.effects,
                               seed=args.seed,
                               n_segments=args.segments, noise_sigma=args.noise)
        doc = diag.to_dict()
        folder.write_text("diagnosis_motion.json", dumps(doc))
        folder.write_text("report_motion.md", _report(diag))
    if args.video:
        # sim loads MuJoCo and the renderer: only when a video is asked for.
        from sim.view.motion_video import render_motion_video

        render_motion_video(model, traj, diag, args.video, magnify=args.magnify,
                            overwrite=args.force)
    emit(args, doc, diag.verdict + f"\nwrote {args.out}/diagnosis_motion.json, "
         f"{args.out}/report_motion.md")
    return 0


def _report(diag: object) -> str:
    d = diag  # MotionDiagnosis
    u = d.length_unit  # type: ignore[attr-defined]
    lines = ["# Motion diagnosis", "", " ".join(d.verdict.split()), "",  # type: ignore[attr-defined]
             f"| phase | samples | RMS before ({u}) | after | withheld before | after |",
             "|---|---|---|---|---|---|"]
    for p in d.phases:  # type: ignore[attr-defined]
        cells = [p.phase, str(p.n_samples)] + [
            "-" if v is None else f"{v:.4g}"
            for v in (p.rms_before, p.rms_after, p.withheld_before, p.withheld_after)]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "| parameter | value | 95 % interval |", "|---|---|---|"]
    for e in d.parameters:  # type: ignore[attr-defined]
        lo, hi = e.ci95
        lines.append(f"| {md_text(e.name)} | {e.value:.4g} {e.unit} | [{lo:.4g}, {hi:.4g}] |")
    return "\n".join(lines) + "\n"
