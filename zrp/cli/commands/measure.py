"""``zrp measure``: measure the MuJoCo "real" robot like a laser-tracker calibration."""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import numpy as np

    from zrp.model.manipulator import Manipulator

from zrp.cli.aliases import deprecated_alias
from zrp.cli.app import emit
from zrp.cli.options import SEED, add_deg, add_progress, draw_bar, real, whole
from zrp.errors import InputError
from zrp.model.builtin import builtin_models
from zrp.output import check_writable, write_text


def _robot_options(arm: str | None, model: object) -> object:
    """The real robot's options: the arm's own dynamics from ``--mjcf`` (None: the
    default)."""
    if arm is None:
        return None
    import mjcf  # loads MuJoCo: only when this command runs
    import sim  # the same (sim imports MuJoCo)

    return sim.RealRobotOptions(dynamics=mjcf.arm_dynamics(arm, model))  # type: ignore[arg-type]


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "measure", help="simulate a laser-tracker measurement of a MuJoCo 'real' robot",
        description="Build the MuJoCo 'real' robot of a model with hidden effects (--effect), "
        "command poses (random reachable ones or the PUMA circle), let the servos settle, read "
        "the tool reflectors, add tracker noise, express them in an instrument frame and write "
        "the measurement CSV of `zrp diagnose` plus a separate truth file "
        "(sim/README.md).")
    p.add_argument("--model", default="puma", metavar="M.toml",
                   help=f"model TOML file or built-in name ({', '.join(sorted(builtin_models()))}"
                        "; default puma)")
    arm = p.add_argument("--mjcf", default=None, metavar="FILE",
                   help="the arm's shipped URDF or MJCF (joints named as the model's): the "
                        "simulated robot (at rest or with --stream) takes its inertias, "
                        "damping, friction and tool (the truth file names it and its "
                        "SHA-256 for zrp verify); "
                        "without it an arm with no inertias of its own borrows the PUMA "
                        "560's (6R) or rods' (announced)")
    p.add_argument("--out", required=True, metavar="D.csv", help="measurement CSV to write")
    p.add_argument("--truth", metavar="T.json",
                   help="truth file to write (default: next to --out, D.truth.json)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME[:J]=VALUE[UNIT]",
                   help="a hidden effect, repeatable: joint_offset:2=0.5mrad, "
                        "encoder_scale:3=300ppm, cyclic_error:2[:h2]=0.3mrad, "
                        "link_length:4=0.1,0.2,-0.1mm, axis_misalignment:3=0.5,0.2mrad, "
                        "joint_compliance:2=20urad/Nm, backlash:1=0.8mrad, "
                        "thermal_expansion=12ppm/K")
    load = p.add_argument("--load", type=real(0.0, 1e4, unit="kg"), default=0.0, metavar="KG",
                          help="payload at the tool point, kg (logged in the load column)")
    deprecated_alias(p, "--payload", load)
    deprecated_alias(p, "--arm", arm)
    p.add_argument("--poses", type=_count_or_plan, default=200, metavar="N|PLAN.csv",
                   help="number of poses (default 200), or a plan file of zrp plan: its poses "
                        "and approach directions, in its order")
    p.add_argument("--trajectory", choices=("random", "circle", "moves"), default="random",
                   help="random reachable poses (default) or poses along the PUMA circle; with "
                        "--stream: the circle or random joint moves, executed in motion")
    p.add_argument("--stream", type=real(1.0, 1000.0), metavar="HZ",
                   help="execute the trajectory in motion and stream time-stamped tracker "
                        "points at HZ (1-1000) as a trajectory CSV (zrp diagnose-motion)")
    p.add_argument("--motion-effect", action="append", default=[], metavar="NAME[:J]=VALUE",
                   help="with --stream, a hidden motion effect, repeatable: sync_delay=2ms, "
                        "servo_lag:2=5ms, reversal_friction:2=15Nm, "
                        "dynamic_compliance:3=20urad/Nm, residual_vibration:2=8Hz")
    p.add_argument("--approach", choices=("gravity", "random", "order"), default=None,
                   help="final approach against gravity for the joints that carry a "
                        "gravity torque, the others from a random side (default; written as "
                        "dir columns), every joint from a random side, or straight moves in "
                        "measurement order (default with a plan file: the plan's directions)")
    p.add_argument("--noise", type=real(0.0, 1e3), default=None, metavar="SIGMA",
                   help="tracker noise per coordinate, model length unit (default 0.02 mm in "
                        "the model's unit)")
    p.add_argument("--temp-rise", type=real(-100.0, 100.0, unit="K"), default=10.0, metavar="K",
                   help="warm-up of the robot during the session, K (default 10)")
    p.add_argument("--seed", type=SEED, default=0, help="seed of poses, noise and instrument")
    add_deg(p)
    p.add_argument("--force", action="store_true",
                   help="replace --out and --truth if they exist (refused otherwise, before "
                        "anything is simulated)")
    add_progress(p)
    p.add_argument("--json", action="store_true", help="print a JSON summary")
    p.set_defaults(func=_run, writes=("truth",),
                   api_names={"count": "--poses", "specs": "--effect", "rate_hz": "--stream"})


_COUNT = whole(1, 100_000)


def _count_or_plan(text: str) -> int | str:
    """--poses: a whole number of poses, or the name of a plan file (anything else)."""
    return _COUNT(text) if text.strip().lstrip("+-").isdigit() else text


def _poses(args: argparse.Namespace, model: Manipulator, rng: np.random.Generator
           ) -> tuple[np.ndarray, np.ndarray | None]:
    """The poses to measure and the planned approach directions (None: the procedure's)."""
    import numpy as np  # on use: keeps --help quick

    from sim.studies.trajectories import circle_poses  # with sim: MuJoCo only when run
    from zrp.calibration.planfile import read_plan  # on use: keeps --help quick
    from zrp.kinematics import reachable_poses  # on use: keeps --help quick

    if isinstance(args.poses, str):
        if args.trajectory != "random":
            raise InputError("--trajectory: a plan file gives the poses; drop --trajectory")
        plan = read_plan(args.poses, model, deg=args.deg)
        if len(plan.q) < 8:
            raise InputError(f"--poses: the plan has {len(plan.q)} poses; at least 8 expected")
        if args.approach is None:
            args.approach = "random"  # the plan's sides (0: a random side)
            return plan.q, np.where(plan.direction != 0, plan.direction,
                                    rng.choice([-1.0, 1.0], size=plan.q.shape))
        return plan.q, None
    if args.poses < 8:
        raise InputError(f"--poses: expected at least 8 poses, got {args.poses}")
    q = (reachable_poses(model, args.poses, rng) if args.trajectory == "random"
         else circle_poses(model, args.poses))
    return q, None


def _run(args: argparse.Namespace) -> int:
    # sim loads MuJoCo (+0.1-0.2 s measured): only when this command runs, not for every `zrp`.
    import numpy as np  # on use: keeps --help quick

    import sim  # MuJoCo: on use (see above)
    from zrp.model.files import load_model  # on use: keeps --help quick

    if args.noise is not None and not args.noise > 0:
        raise InputError(f"--noise: expected a positive sigma (model length unit), got "
                         f"{args.noise}")
    if args.seed < 0:
        raise InputError(f"--seed: expected an integer >= 0, got {args.seed}")
    out = Path(args.out)
    truth = Path(args.truth) if args.truth else out.with_name(out.stem + ".truth.json")
    if truth.resolve() == out.resolve():
        raise InputError("--truth: must differ from --out")
    check_writable([out, truth], args.force)  # before the simulation, which takes a while
    model = load_model(args.model)
    if args.noise is None:  # a laser tracker's 20 um, whatever the model's unit
        from zrp.units import TRACKER_NOISE_MM, units_per_mm  # NumPy: on use (quick --help)

        args.noise = TRACKER_NOISE_MM * units_per_mm(model.length_unit, "model.length_unit")
    if args.stream is not None:
        if isinstance(args.poses, str):
            raise InputError("--poses: a plan file is measured at rest; drop --stream")
        return _stream(args, model, out, truth)
    effects = sim.parse_effects(args.effect, model, args.load, field="--effect")
    rng = np.random.default_rng(args.seed)
    q, directions = _poses(args, model, rng)
    args.approach = args.approach or "gravity"
    inst = sim.random_instrument(model, rng, args.noise)
    t0 = time.perf_counter()
    robot = sim.RealRobot(model, effects, _robot_options(args.mjcf, model))
    procedure = sim.Procedure(approach=args.approach, temp_rise=args.temp_rise)
    run = sim.measure(robot, q, inst, rng, procedure, progress=draw_bar(args),
                      directions=directions)
    wall = time.perf_counter() - t0
    sim.write_measurements(run, out, deg=args.deg, overwrite=args.force, model=model)
    sim.write_truth(run, truth, overwrite=args.force)
    payload = {"measurements": str(out), "truth": str(truth), "poses": len(q),
               "points": run.measurements.n_rows, "effects": list(effects.active),
               "payload_kg": effects.payload, "noise_sigma": args.noise,
               "approach": args.approach, "wall_s": wall,
               "trajectory": "plan" if isinstance(args.poses, str) else args.trajectory}
    text = (f"measured {len(q)} poses ({run.measurements.n_rows} points) of the real "
            f"{model.name} with hidden effects: {', '.join(effects.active) or 'none'}; "
            f"noise {args.noise:g} {model.length_unit} per coordinate; {wall:.1f} s\n"
            f"wrote {out}\nwrote {truth} (the truth: keep it away from the diagnosis)")
    emit(args, payload, text)
    return 0


def _stream(args: argparse.Namespace, model: object, out: Path, truth: Path) -> int:
    """``--stream``: the real robot in motion (sim/studies/trajectories.py)."""
    from sim.studies.trajectories import measure_stream  # MuJoCo: only when this command runs
    from zrp.gap.motion import write_trajectory  # on use: keeps --help quick
    from zrp.jsonio import dumps  # on use: keeps --help quick

    if args.effect:
        raise InputError("--effect: static effects are not simulated with --stream; use "
                         "--motion-effect")
    traj_name = "moves" if args.trajectory == "random" else args.trajectory
    t0 = time.perf_counter()
    opts = _robot_options(args.mjcf, model)
    run = measure_stream(model, traj_name, args.motion_effect, args.stream,  # type: ignore[arg-type]
                         args.noise, args.seed, field="--motion-effect",
                         dynamics=getattr(opts, "dynamics", None))
    wall = time.perf_counter() - t0
    write_trajectory(run.trajectory, out, deg=args.deg, model=model,  # type: ignore[arg-type]
                     overwrite=args.force)
    write_text(truth, dumps(run.truth), overwrite=args.force)
    tr = run.trajectory
    payload = {"measurements": str(out), "truth": str(truth), "samples": tr.n_samples,
               "rate_hz": args.stream, "duration_s": tr.duration, "trajectory": traj_name,
               "effects": list(run.effects.active), "noise_sigma": args.noise, "wall_s": wall}
    text = (f"streamed {tr.n_samples} samples ({tr.duration:.1f} s at {args.stream:g} Hz) of "
            f"the real robot drawing '{traj_name}' with hidden motion effects: "
            f"{', '.join(run.effects.active) or 'none'}; {wall:.1f} s\nwrote {out}\n"
            f"wrote {truth} (the truth: keep it away from the diagnosis)")
    emit(args, payload, text)
    return 0
