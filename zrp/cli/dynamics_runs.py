"""The work of ``zrp diagnose-dynamics`` and ``zrp dynamics-benchmark`` (arguments parsed in
:mod:`zrp.cli.commands`)."""

from __future__ import annotations

import argparse
import tempfile
from dataclasses import asdict
from pathlib import Path

import numpy as np

from mjcf.arm import Arm, resolve_arm
from mjcf.corrected import CorrectedMJCF
from mjcf.joint_names import chain_end, model_joints
from sim.studies.dynamics import benchmark as bm
from sim.studies.dynamics.arms import available_arms
from sim.studies.dynamics.scenarios import KINDS
from zrp.errors import InputError
from zrp.escape import md_row
from zrp.gap.dynamics.bag import read_log
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.diagnosis import DynamicsOptions
from zrp.gap.dynamics.joints import match_joints
from zrp.gap.dynamics.report import REPORT_FILES, run_json, write_run
from zrp.gap.dynamics.run import TrackingOptions, run_dynamics
from zrp.gap.dynamics.samelog import check_other_log
from zrp.gap.dynamics.transmission import load_transmission
from zrp.gap.dynamics.verdict import headline
from zrp.output import OutputDir, check_writable

__all__ = ["arm_of_joints", "run_benchmark", "run_diagnosis"]


class Stages:
    """The stages of a run on stderr: a bar naming the stage, on a terminal only
    (``progress``: from :func:`zrp.cli.options.draw_bar`)."""

    def __init__(self, total: int, progress: bool, desc: str) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=total, desc=desc, unit="stage", disable=not progress,
                        leave=False)

    def __call__(self, name: str) -> None:
        self.bar.set_postfix_str(name, refresh=False)
        self.bar.update(1)

    def close(self) -> None:
        self.bar.close()


def run_diagnosis(args: argparse.Namespace, out: Path, *, overwrite: bool = False,
                  progress: bool = False) -> tuple[dict, str]:
    """Diagnose (:func:`zrp.gap.dynamics.run.run_dynamics`), write the outputs; the JSON and
    the summary text (``overwrite``: replace files in ``out``, from --force or the default
    folder's mark; checked before any work; ``progress``: the stages on stderr)."""
    check_writable([out / n for n in REPORT_FILES], overwrite)
    if (args.kp is None) != (args.kv is None):
        raise InputError("--kp, --kv: give both (the servo's stiffness and damping) or neither")
    stage = Stages(7 if args.validate else 6, progress, "diagnose-dynamics")
    try:
        return _diagnose(args, out, overwrite, stage)
    finally:
        stage.close()


def _diagnose(args: argparse.Namespace, out: Path, overwrite: bool, stage: Stages
              ) -> tuple[dict, str]:
    stage("reading the log")
    check_other_log(args.data, args.validate)
    tr = None if args.transmission is None else load_transmission(args.transmission)
    log = read_log(args.data, torque_constant=args.torque_constant, topic=args.topic,
                   transmission=tr, rate_hz=args.rate)
    stage("loading the model")
    arm = _arm(args, log)
    every = model_joints(args.model) or tuple(arm.joint_names)
    log = match_joints(log, arm.joint_names, model_joints=every, option="--data")
    second = None if args.validate is None else match_joints(
        read_log(args.validate, torque_constant=args.torque_constant, topic=args.topic,
                 transmission=tr, rate_hz=args.rate),
        arm.joint_names, model_joints=every, option="--validate")
    run = run_dynamics(arm, log, options=DynamicsOptions(window_s=args.window,
                                                         inertial=not args.no_inertial),
                       validation_log=second, writer=CorrectedMJCF(arm),
                       tracking=TrackingOptions(kp=_gains(args.kp), kv=_gains(args.kv),
                                                seconds=args.seconds),
                       progress=stage)
    stage("writing the report")
    folder = write_run(run, out, overwrite=overwrite)
    text = headline(run.diagnosis, run.validation) + (
        f"\nwrote {folder}/report.html, report.md, diagnosis.json, corrected.xml")
    return run_json(run), text


def _arm(args: argparse.Namespace, log: TorqueLog) -> Arm:
    """The arm: the chain of ``--joints`` or to ``--end-link``; for a log naming its joints,
    the whole model otherwise (its joints matched by name); for an unnamed log, as many
    leading joints as the log has when they form a chain (said in the notes)."""
    joints = getattr(args, "joints", None)
    if joints and args.end_link:
        raise InputError("--joints, --end-link: give one (both choose the arm's chain)")
    if joints:
        return arm_of_joints(args.model, joints, tool_site=args.tool_site)
    return resolve_arm(args.model, end_link=args.end_link, tool_site=args.tool_site,
                       n_joints=None if log.joint_names else log.n_joints)


def arm_of_joints(model: str, joints: list[str], *, tool_site: str | None = None) -> Arm:
    """The arm whose chain is ``joints`` (``--joints``, by name): the model's chain to the
    last of them, which must hold exactly them."""
    end = chain_end(model, joints)
    arm = resolve_arm(model, end_link=end, tool_site=tool_site)
    if sorted(arm.joint_names) != sorted(joints):
        raise InputError(f"--joints: the chain from the model's root to link {end!r} has the "
                         f"joints {', '.join(arm.joint_names)}; --joints names "
                         f"{', '.join(joints)}")
    return arm


def _gains(values: list[float] | None) -> np.ndarray | None:
    return None if values is None else np.asarray(values, dtype=float)


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
    lines += [md_row(r.arm, r.kind, r.seed, "" if r.joint is None else r.joint + 1,
                     f"{r.visibility:.1f}", r.named, r.success, f"{r.withheld_ratio:.2f}")
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
