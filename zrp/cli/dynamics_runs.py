"""The work of ``zrp diagnose-dynamics``, ``zrp excite`` and
``zrp dynamics-benchmark`` (arguments parsed in :mod:`zrp.cli.commands`)."""

from __future__ import annotations

import argparse
import tempfile
from dataclasses import asdict
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from mjcf.arm import Arm, resolve_arm
from mjcf.corrected import corrected_spec, corrections
from mjcf.tracking import Servo, tracking_gap
from sim.studies.dynamics import benchmark as bm
from sim.studies.dynamics.arms import available_arms
from sim.studies.dynamics.scenarios import KINDS
from zrp.errors import InputError
from zrp.gap.dynamics.data import TorqueLog, load_torque_log
from zrp.gap.dynamics.diagnosis import DynamicDiagnosis, DynamicsOptions, diagnose_dynamics
from zrp.gap.dynamics.excitation import design_excitation
from zrp.gap.dynamics.report import diagnosis_json, write_report
from zrp.jsonio import to_jsonable
from zrp.output import OutputDir, atomic_path, write_text

__all__ = ["run_benchmark", "run_diagnosis", "run_excite"]


def _servo(arm: Arm, log: TorqueLog, kp: list[float] | None, kv: list[float] | None
           ) -> tuple[Servo, str]:
    if (kp is None) != (kv is None):
        raise InputError("--kp, --kv: give both (the servo's stiffness and damping) or neither")
    if kp is None:
        return Servo.tuned(arm, log.qc[0]), "a 4 Hz servo tuned from the model (--kp/--kv: yours)"
    for name, v in (("--kp", kp), ("--kv", kv)):
        if len(v) != arm.n:
            raise InputError(f"{name}: expected {arm.n} values (one a joint), got {len(v)}")
    return Servo(np.array(kp), np.array(kv)), "the servo gains given"


def _truncate(log: TorqueLog, seconds: float | None) -> TorqueLog:
    if seconds is None:
        return log
    return log.first(int(np.searchsorted(log.t - log.t[0], seconds)))


def _tracking(arm: Arm, log: TorqueLog, model: mujoco.MjModel, args: argparse.Namespace
              ) -> dict[str, Any]:
    if log.qc is None:
        return {"lines": ["- the log has no commanded positions qc1..qcn: no re-simulation"]}
    servo, how = _servo(arm, log, args.kp, args.kv)
    part = _truncate(log, args.seconds)
    before = tracking_gap(arm.model, arm.model, part, servo)
    after = tracking_gap(model, arm.model, part, servo)
    lines = [f"Re-simulation of the logged command (mj_step) with {how}; RMS of simulated minus "
             "logged joint positions (rad):", "", "| joint | model | corrected model |",
             "|---|---|---|"]
    lines += [f"| {k + 1} | {before[k]:.3g} | {after[k]:.3g} |" for k in range(arm.n)]
    return {"lines": lines, "before_rad": before, "after_rad": after}


def run_diagnosis(args: argparse.Namespace, out: Path) -> tuple[dict, str]:
    """Diagnose, write the report and the corrected MJCF; the JSON and the summary text."""
    arm = resolve_arm(args.model, end_link=args.end_link, tool_site=args.tool_site)
    log = load_torque_log(args.data, torque_constant=args.torque_constant, n_joints=arm.n)
    diag: DynamicDiagnosis = diagnose_dynamics(
        arm, log, DynamicsOptions(window_s=args.window, inertial=not args.no_inertial))
    fix = corrections(arm, diag)
    spec = corrected_spec(arm, fix)
    model = spec.compile()
    track = _tracking(arm, log, model, args)
    sections = {"Corrected model": [
        "corrected.xml: the model with the identified frictionloss, damping, armature"
        + (", payload" if fix.payload_kg else "") + (", link inertias" if fix.inertial else "")
        + "."] + ([f"- not in MJCF (report only): {', '.join(fix.not_in_model)}"]
                  if fix.not_in_model else []),
        "Tracking": track["lines"]}
    extra = {k: v for k, v in track.items() if k != "lines"}
    folder = write_report(diag, out, overwrite=args.force, extra={"sections": sections,
                                                                  "tracking": extra})
    write_text(folder / "corrected.xml", spec.to_xml(), overwrite=args.force)
    text = (f"{diag.arm}: " + (", ".join(e.label for e in diag.effects) or "no effect needed")
            + "\nwithheld torque RMS / noise per joint: "
            + " ".join(f"{a / s:.2f}" for a, s in zip(diag.rms_after, diag.noise_nm,
                                                     strict=True))
            + f"\nwrote {folder}/report.html, report.md, diagnosis.json, corrected.xml")
    return diagnosis_json(diag, {"tracking": extra}), text


def run_excite(args: argparse.Namespace, out: Path) -> tuple[dict, str]:
    """Design the exciting command and write it as t, qc1..qcn."""

    arm = resolve_arm(args.model, end_link=args.end_link)
    if len(args.q0) != arm.n:
        raise InputError(f"--q0: expected {arm.n} joint values, got {len(args.q0)}")
    tl = None
    if args.max_torque is not None:
        if len(args.max_torque) not in (1, arm.n):
            raise InputError(f"--max-torque: expected 1 or {arm.n} values")
        tl = np.broadcast_to(np.array(args.max_torque), arm.n)
    e = design_excitation(arm, np.array(args.q0), args.amplitude, args.max_velocity,
                          args.max_acceleration, torque_limit=tl, harmonics=args.harmonics,
                          f0_hz=1.0 / args.period, candidates=args.candidates,
                          iterations=args.iterations, seed=args.seed)
    t = np.arange(round(args.period * args.rate)) / args.rate
    q, _, _ = e.command.evaluate(t)
    header = "t [s]," + ",".join(f"qc{k + 1} [rad]" for k in range(arm.n))
    with atomic_path(out, overwrite=args.force) as tmp:
        np.savetxt(tmp, np.column_stack([t, q]), delimiter=",", fmt="%.12g", header=header,
                   comments="")
    dq, dqd, dqdd = e.command.peaks()
    payload = {"condition_number": e.kappa, "condition_number_random_start": e.kappa_start,
               "peak_position_rad": dq, "peak_velocity_rad_s": dqd,
               "peak_acceleration_rad_s2": dqdd, "peak_torque_nm": e.peak_torque,
               "q0": e.command.q0, "f0_hz": e.command.f0_hz, "a": e.command.a,
               "b": e.command.b}
    text = (f"condition number {e.kappa:.4g} (best random start {e.kappa_start:.4g}); peak "
            f"torque per joint {np.array2string(e.peak_torque, precision=3)} N m\nwrote {out}")
    return to_jsonable(payload), text


def run_benchmark(args: argparse.Namespace, out: Path) -> tuple[dict, str]:
    """The blind benchmark; summary.json and summary.md in ``out``."""
    arms = args.arms or available_arms()
    kinds = tuple(args.effects or KINDS)
    rows = []
    with tempfile.TemporaryDirectory() as work:
        for sc in bm.draw_scenarios(arms, kinds, args.reps, args.seed, args.seconds):
            rows.append(bm.run_scenario(sc, Path(work)))
    t = bm.tally(rows)
    lines = ["| arm | effect | seed | joint | visibility | named | right | withheld ratio |",
             "|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r.arm} | {r.kind} | {r.seed} | {'' if r.joint is None else r.joint + 1} | "
              f"{r.visibility:.1f} | {r.named} | {r.success} | {r.withheld_ratio:.2f} |"
              for r in rows]
    head = (f"visible single effects right (effect, joint, withheld <= 1.5 sigma): {t['right']}"
            f" of {t['visible_singles']}; 'none' clean: {t['none_clean']} of "
            f"{t['none_scenarios']}")
    payload = {"summary": t, "rows": [asdict(r) for r in rows]}
    with OutputDir(out, overwrite=args.force) as od:
        od.write_json("summary.json", payload)
        od.write_text("summary.md", "# Dynamic gap blind benchmark\n\n" + head + "\n\n"
                      + "\n".join(lines) + "\n")
    return payload, head + f"\nwrote {out}/summary.json, {out}/summary.md"
