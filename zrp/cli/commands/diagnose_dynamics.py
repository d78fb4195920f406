"""``zrp diagnose-dynamics``: the dynamic gap of a MuJoCo model along a joint torque log."""

from __future__ import annotations

import argparse
from pathlib import Path

from zrp.cli.app import emit
from zrp.cli.options import DURATION, add_progress, draw_bar, real
from zrp.output import claim_generated, safe_name

DEFAULT_OUT = Path("renders") / "dynamics"
GAIN = real(0.0, 1e9, open_lo=True)


def KT(text: str) -> float:
    """A signed torque constant, N m/A: finite, nonzero, |kt| <= 1e9."""
    value = real(-1e9, 1e9)(text)
    if value == 0.0:
        raise argparse.ArgumentTypeError("0 is no torque constant (nonzero; negative when the "
                                         "drive's current counts the other way)")
    return value


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "diagnose-dynamics", help="where a MuJoCo model's joint torques miss a torque log, and why",
        description="Diagnose the dynamic gap (zrp/gap/dynamics/README.md): inverse dynamics "
        "(mj_inverse) along the logged states against the logged torques; which effect "
        "(friction, armature, payload, link inertias, torque sensor offset/gain) on which "
        "joint, its size with an interval, the withheld torque error before and after. "
        "Writes report.html/.md, the residual plots, diagnosis.json and corrected.xml.")
    p.add_argument("--model", required=True, metavar="M.xml|M.urdf|NAME",
                   help="MJCF or URDF (with inertials) of the arm, or a ZRP model")
    p.add_argument("--data", required=True, metavar="LOG.csv|BAG",
                   help="the torque log: a CSV, or a ROS bag (.mcap, .db3, a ROS 2 bag "
                   "folder, a ROS 1 .bag) of sensor_msgs/msg/JointState")
    p.add_argument("--topic", metavar="NAME", help="the bag's JointState topic (default: its "
                   "only one)")
    p.add_argument("--end-link", metavar="LINK", help="URDF: the arm's last link")
    p.add_argument("--joints", nargs="+", metavar="NAME",
                   help="the arm's joints by name (its chain; default: those the log names, "
                   "or to --end-link); the log's others the model has are left out")
    p.add_argument("--tool-site", metavar="SITE", help="MJCF site where a payload sits")
    p.add_argument("--torque-constant", type=KT, nargs="+", metavar="KT",
                   help="the drive's signed torque constant per joint, N m/A at the joint "
                   "(gear included; negative when its current counts the other way), in the "
                   "log's joint order, when the log has currents i1..in (a bag: its efforts "
                   "are then the currents)")
    p.add_argument("--transmission", metavar="T.toml",
                   help="the log is motor side (positions and torques at the motors): the "
                   "drive's transmission, a TOML file with `ratio` (motor = ratio @ joint; "
                   "couplings off the diagonal) and `joint_offset` (rad); the coupled motors' "
                   "friction and rotor inertia become effects (zrp/gap/dynamics/README.md)")
    p.add_argument("--rate", type=real(1.0, 1e6, unit="Hz"), metavar="HZ",
                   help="the sampling rate of a log without a time column")
    p.add_argument("--validate", metavar="LOG2.csv|BAG2",
                   help="a second torque log of the same arm (another run): the corrected "
                   "model, fitted on --data, is scored on it (nothing refitted)")
    p.add_argument("--window", type=real(0.0, 10.0, open_lo=True, unit="s"), default=None,
                   help="Savitzky-Golay window for the velocities, accelerations and torques, "
                   "s (default: chosen from the data among 0.05, 0.1 and 0.2 s, said in the "
                   "report)")
    p.add_argument("--no-inertial", action="store_true",
                   help="do not fit link inertial parameters")
    p.add_argument("--kp", type=GAIN, nargs="+", help="servo stiffness per joint (N m/rad) "
                   "for the re-simulation; default: a 4 Hz servo from the model")
    p.add_argument("--kv", type=GAIN, nargs="+", help="servo damping per joint (N m s/rad)")
    p.add_argument("--seconds", type=DURATION, default=None,
                   help="re-simulate only the first SECONDS of the log")
    p.add_argument("--out", metavar="DIR",
                   help=f"output folder (default {DEFAULT_OUT}/LOG: generated output, "
                   "replaced; elsewhere existing files need --force)")
    p.add_argument("--force", action="store_true", help="replace outputs in --out")
    p.add_argument("--json", action="store_true", help="print diagnosis.json")
    add_progress(p, help="show the stage (reading, diagnosing, validating, re-simulating, "
                 "writing) on stderr when it is a terminal (default on; --no-progress: none)")
    p.set_defaults(func=_run, api_names={"torque_constant": "--torque-constant",
                                         "window_s": "--window", "end_link": "--end-link",
                                         "rate_hz": "--rate"})


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo: only when this command runs.
    from zrp.cli.dynamics_runs import run_diagnosis

    out = Path(args.out) if args.out else DEFAULT_OUT / safe_name(Path(args.data).stem,
                                                                  default="log")
    overwrite = args.force or (args.out is None and claim_generated(out))
    payload, text = run_diagnosis(args, out, overwrite=overwrite, progress=draw_bar(args))
    emit(args, payload, text)
    return 0
