"""``zrp calibrate``: diagnose, then write the calibrated robot (model TOML + compensation
JSON) beside the diagnosis outputs (zrp/calibration/README.md)."""

from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from zrp.calibration.fullpose import FullPoseCalibration
    from zrp.calibration.recipe import Calibration, CalibrationOptions
from zrp.cli.app import emit
from zrp.cli.options import LENGTH, SEED, add_deg, add_progress, real, whole
from zrp.errors import InputError
from zrp.gap.model.choices import EFFECTS
from zrp.gap.model.domains import DOMAINS  # light: no NumPy
from zrp.output import OutputDir

FILES = ("calibrated.toml", "compensation.json")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "calibrate", help="diagnose and write the calibrated model and compensation file",
        description="Run the gap diagnosis (as zrp diagnose) and write DIR/calibrated.toml "
        "(identified offsets, body vectors and axis tilts folded into the geometry) and "
        "DIR/compensation.json (registration, tool points, joint map, thermal), plus the "
        "diagnosis outputs without plots. With --diagnosis D/diagnosis.json, reuse that "
        "diagnosis (no search: the same files as a fresh run on the same data) and write "
        "the two calibration files only.")
    p.add_argument("--model", required=True, metavar="M.toml", help="model TOML or built-in")
    p.add_argument("--mjcf", metavar="M.xml", help="MJCF with inertias (gravity torques)")
    p.add_argument("--data", required=True, metavar="D.csv", help="measurement CSV")
    p.add_argument("--diagnosis", metavar="D/diagnosis.json",
                   help="reuse this diagnosis of the same --data and --model (written by zrp "
                        "diagnose or zrp calibrate 0.5.0 or later) instead of diagnosing "
                        "again; the options that shape a diagnosis (--mjcf, --seed, "
                        "--effects, --max-steps, --noise, --orientation-sigma, "
                        "--no-orientation) are its own and refused here")
    add_deg(p)
    p.add_argument("--frame", choices=("instrument", "base"), default="instrument",
                   help="frame of x, y, z (default instrument)")
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--force", action="store_true", help="overwrite existing output files")
    p.add_argument("--seed", type=SEED, help="seed of the fitting/withheld split (default 0)")
    p.add_argument("--effects", nargs="+", choices=EFFECTS,
                   metavar="EFFECT", help="candidate effects (default all)")
    p.add_argument("--max-steps", type=whole(1, 8), help="most effects added (default 4)")
    p.add_argument("--noise", type=LENGTH, metavar="SIGMA", help="known noise per coordinate")
    p.add_argument("--orientation-sigma", type=real(0.0, 1.0, open_lo=True), metavar="RAD",
                   help="orientation noise per component when the data carry qw..qz "
                   "(default: estimated from the residuals)")
    p.add_argument("--no-orientation", action="store_true",
                   help="ignore measured orientations (qw..qz): positions only")
    p.add_argument("--instrument", metavar="NAME",
                   help="the measuring instrument (recorded in the calibration's conditions)")
    p.add_argument("--widen", action="append", default=[], metavar="DOMAIN=BOUND",
                   help="raise a physical domain's upper bound (zrp/gap/model/domains.py: "
                   f"{', '.join(DOMAINS)}), e.g. --widen axis_tilt=0.02, for an arm known "
                   "to need it; repeatable")
    p.add_argument("--residual-model", action="store_true",
                   help="also train a learned residual term on the joint angles (as zrp "
                   "diagnose --residual-model); kept only when it lowers the withheld error "
                   "clearly, it is then written into compensation.json (learned_residual) and "
                   "applied by zrp compensate within its training ranges")
    add_progress(p, help="show the diagnosis's progress on stderr: a bar on a terminal, a line "
                 "every 10 s when piped (default on; --no-progress: silent)")
    p.add_argument("--json", action="store_true", help="print the compensation file")
    p.set_defaults(func=_run, api_names={"noise_sigma": "--noise", "seed": "--seed",
                                         "effects": "--effects", "max_steps": "--max-steps",
                                         "gravity_torque": "--mjcf",
                                         "orientation_sigma": "--orientation-sigma",
                                         "residual_model": "--residual-model"})


def _widen(items: list[str]) -> dict[str, float] | None:
    out: dict[str, float] = {}
    for item in items:
        key, _, val = item.partition("=")
        if key not in DOMAINS:
            raise InputError(f"--widen: {key!r} is not a domain; expected one of "
                             f"{', '.join(DOMAINS)}")
        try:
            out[key] = float(val)
        except ValueError:
            raise InputError(f"--widen: expected DOMAIN=BOUND, got {item!r}") from None
        if not DOMAINS[key].upper <= out[key] < float("inf"):
            raise InputError(f"--widen: {item!r}: the bound must be finite and at least "
                             f"{DOMAINS[key].upper:g}")
    return out or None


#: options that shape a diagnosis (refused with --diagnosis: it has its own)
_SHAPING = (("mjcf", "--mjcf"), ("seed", "--seed"), ("effects", "--effects"),
            ("max_steps", "--max-steps"), ("noise", "--noise"),
            ("orientation_sigma", "--orientation-sigma"), ("no_orientation", "--no-orientation"),
            ("residual_model", "--residual-model"))


def _refuse_shaping(args: argparse.Namespace) -> None:
    given = [opt for name, opt in _SHAPING if getattr(args, name) not in (None, False)]
    if given:
        raise InputError(f"{', '.join(given)}: the diagnosis {args.diagnosis} has its own "
                         "(diagnosis.json 'settings'); drop them, or calibrate without "
                         "--diagnosis to diagnose anew")


def _options(args: argparse.Namespace, tau: object) -> CalibrationOptions:
    from zrp.calibration import CalibrationOptions  # on use: keeps --help quick

    shaping = {} if args.diagnosis is not None else {
        "gravity_torque": tau, "effects": args.effects or list(EFFECTS),
        "seed": 0 if args.seed is None else args.seed,
        "max_steps": 4 if args.max_steps is None else args.max_steps,
        "noise_sigma": args.noise, "use_orientation": not args.no_orientation,
        "orientation_sigma": args.orientation_sigma, "residual_model": args.residual_model}
    return CalibrationOptions(
        **shaping, widen=_widen(args.widen), data_path=args.data,
        data_angle_unit="deg" if args.deg else "rad", instrument=args.instrument,
        progress=args.progress)


def _run(args: argparse.Namespace) -> int:
    # mjcf loads MuJoCo (+0.25 s): only when this command runs
    from mjcf.gravity import gravity_torques
    from zrp.calibration import calibrate  # on use: keeps --help quick
    from zrp.calibration.storage import calibration_document  # on use: keeps --help quick
    from zrp.gap import load_measurements  # on use: keeps --help quick
    from zrp.gap.report import OUTPUT_FILES  # on use: keeps --help quick
    from zrp.model.files import load_model  # on use: keeps --help quick

    reuse = args.diagnosis is not None
    if reuse:
        _refuse_shaping(args)
    model = load_model(args.model)
    meas = load_measurements(args.data, model, deg=args.deg, frame=args.frame)
    tau = None if args.mjcf is None else gravity_torques(
        args.mjcf, meas.q_pose, field="--mjcf", joint_names=[j.name for j in model.joints])
    opt = _options(args, tau)
    if reuse and args.progress:
        print(f"zrp calibrate: reusing the diagnosis {args.diagnosis} (no search)",
              file=sys.stderr, flush=True)
    out_dir = Path(args.out)
    created = not out_dir.exists()
    try:
        with OutputDir(out_dir, overwrite=args.force,
                       names=FILES if reuse else OUTPUT_FILES + FILES, prune=True) as out:
            result = calibrate(model, meas, options=opt, diagnosis=args.diagnosis)
            files = _write(result, out, out_dir)
    except BaseException:
        if created:
            with contextlib.suppress(OSError):
                out_dir.rmdir()
        raise
    text = _summary(result, model.length_unit) + "\n".join(f"wrote {f}" for f in files)
    emit(args, calibration_document(result.robot, FILES[0], None if result.record is None
                                    else result.record.probe), text)
    return 0


def _write(result: Calibration, out: OutputDir, out_dir: Path) -> list[Path]:
    """The diagnosis outputs (a fresh diagnosis only) and the two calibration files."""
    from zrp.gap.model.domains import ImplausibleValueError  # on use: keeps --help quick
    from zrp.gap.report import write_outputs  # on use: keeps --help quick

    files = [] if result.diagnosis is None else write_outputs(result.diagnosis, out,
                                                              plots=False)
    try:
        cal_files = result.write(out_dir / FILES[0], out_dir / FILES[1], overwrite=True)
    except ImplausibleValueError as exc:
        where = out_dir if result.diagnosis is not None else "the diagnosis's folder"
        raise ImplausibleValueError(
            f"{exc}. No calibration file was written; the diagnosis outputs in "
            f"{where} show the fit") from None
    out.written += cal_files  # this run's (the folder's prune keeps them)
    return list(files) + cal_files


def _summary(result: Calibration, unit: str) -> str:
    diag, full = result.diagnosis, result.full_pose
    if diag is None:
        rec = result.record
        return ("" if rec is None else
                f"from the stored diagnosis: final withheld RMS {rec.withheld_rms:.4g} {unit}\n"
                ) + _learned_line(result, unit)
    return (f"withheld RMS {diag.nominal.rms:.4g} -> {diag.final.rms:.4g} "
            f"{unit} (effects: {', '.join(diag.effects)})\n"
            + ("" if full is None else _full_pose_line(full, unit))
            + _learned_line(result, unit))


def _learned_line(result: Calibration, unit: str) -> str:
    """What the learned residual term adds (or why it is not in the files), one line."""
    assessment = result.diagnosis.assessment if result.diagnosis is not None else None
    rm = assessment.residual_model if assessment is not None else None
    if result.robot.learned is not None:
        return f"with the {result.robot.learned.words(unit)} (in compensation.json)\n"
    if result.learned_note is not None:
        return f"note: {result.learned_note}\n"
    return "" if rm is None else rm.words(unit) + "\n"


def _full_pose_line(full: FullPoseCalibration, unit: str) -> str:
    s = full.summary()
    return (f"full pose (measured orientations, noise {s['sigma_orientation_rad']:.3g} rad): "
            f"parameter std x{s['std_ratio_median']:.2f} (median; best x"
            f"{s['std_ratio_min']:.2g}) of the position-only fit; withheld RMS "
            f"{s['withheld_rms_position_only']:.4g} -> {s['withheld_rms']:.4g} {unit}, "
            f"orientation {s['withheld_orientation_rms_rad']:.3g} rad; the calibration "
            "written is the full-pose one\n")
