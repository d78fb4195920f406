"""Do K planned poses diagnose as well as 200 random ones? (issue 11, measurement planning)

For each scenario of the blind benchmark (:func:`sim.studies.benchmark.draw_scenarios`: its hidden
effects, payload, tracker noise and seed; the tracker placed as the benchmark places it), the
physics robot is measured

* at ``random_poses`` random reachable poses with the benchmark's procedure (approach against
  gravity, random side otherwise): the reference, exactly the blind benchmark's measurement;
* at K poses planned by :func:`zrp.calibration.plan_poses` (D-optimal DETMAX exchange over the
  registration and every candidate effect's parameters except thermal expansion, at the
  nominal reflector offsets, MJCF gravity torques; the gravity-loaded joints approached
  lifting, as the benchmark's procedure does, the others from the planned side) for each K;
* at ``validation`` fresh random poses (the benchmark's procedure): the common yardstick.

Each measurement is diagnosed blind (nominal model, nominal MJCF) and scored the way the blind
benchmark scores (:func:`sim.studies.benchmark.scoring.score`: right effect named first, joints
located), except that the visible effects are judged on the common validation poses and the
RMS is the calibrated robot's (:class:`zrp.calibration.CalibratedRobot`) error on the
validation poses, over the tracker's pure-noise RMS sqrt(3) sigma (success: <= the benchmark's
``ratio_target``, 1.5). The predicted standard deviation of every planned parameter
(registration + all effects; sigma sqrt(diag((J^T J)^-1)) at the poses and approach directions
actually measured) is recorded per design, to set precision beside diagnosis.
"""

from __future__ import annotations

import sys
import tempfile
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mjcf.gravity import gravity_torques
from sim.robot.instrument import random_instrument
from sim.robot.measurement import Procedure, _nominal_static_torque, measure
from sim.robot.real import RealRobot, default_tool_points
from sim.studies.benchmark.runner import _nominal_mjcf
from sim.studies.benchmark.scenarios import BenchmarkConfig, Scenario, draw_scenarios
from sim.studies.benchmark.scoring import score
from zrp.arrays import F64
from zrp.calibration import (
    CalibratedRobot,
    Calibration,
    CalibrationOptions,
    PoseConditions,
    calibrate,
    plan_poses,
)
from zrp.calibration.planning import design_std
from zrp.errors import InputError
from zrp.gap import EFFECTS, Measurements
from zrp.kinematics import reachable_poses
from zrp.model.manipulator import Manipulator

__all__ = [
    "PLANNED_EFFECTS",
    "DesignScore",
    "design_rows",
    "render_k_study",
    "run_k_study",
    "score_from_row",
    "smallest_matching_k",
    "study_scenario",
]

#: What the plan makes identifiable: every candidate effect the poses can excite.
PLANNED_EFFECTS = tuple(e for e in EFFECTS if e != "thermal_expansion")


@dataclass(frozen=True)
class DesignScore:
    """One design (K planned or N random poses) of one scenario, scored.

    Attributes:
        scenario: benchmark scenario index; hidden: its hidden effects.
        design: "planned" or "random"; poses: number of measured poses.
        expected: the hidden effects visible on the validation poses, or ("none",).
        found: the effects the diagnosis named, in order (("none",) if nothing).
        top_correct, joints_correct: as in the blind benchmark.
        noise_rms: sqrt(3) sigma (length unit).
        validation_rms: RMS error of the calibrated robot on the validation poses.
        ratio: validation_rms / noise_rms.
        success: top_correct and joints_correct and ratio <= the target.
        std: predicted standard deviation of every planned parameter at the measured poses
            (name -> value, their units).
        temp_span: temperature spread of the measurement, K (thermal expansion needs it).
    """

    scenario: int
    hidden: tuple[str, ...]
    design: str
    poses: int
    expected: tuple[str, ...]
    found: tuple[str, ...]
    top_correct: bool
    joints_correct: bool
    noise_rms: float
    validation_rms: float
    ratio: float
    success: bool
    std: dict[str, float]
    temp_span: float

    def __post_init__(self) -> None:
        if self.design not in ("planned", "random"):
            raise InputError(f"design: {self.design!r}; expected 'planned' or 'random'")
        if not (self.noise_rms > 0 and np.isfinite(self.validation_rms)):
            raise InputError(f"scenario {self.scenario}: noise_rms must be > 0 and "
                             f"validation_rms finite")

    def row(self) -> dict[str, Any]:
        """A flat row (tables, JSON)."""
        return {"scenario": self.scenario, "hidden": ", ".join(self.hidden) or "none",
                "design": self.design, "poses": self.poses,
                "expected": ", ".join(self.expected), "found": ", ".join(self.found),
                "top_correct": self.top_correct, "joints_correct": self.joints_correct,
                "noise_rms": self.noise_rms, "validation_rms": self.validation_rms,
                "ratio": self.ratio, "success": self.success, "temp_span": self.temp_span}


def validation_rms(cal: CalibratedRobot, meas: Measurements, tau: F64) -> float:
    """RMS (3-D, per point) of measured minus predicted positions of ``cal`` on ``meas``
    (its approach directions, temperatures, payloads; ``tau`` the MJCF gravity torques per
    pose, shape (P, n))."""
    err = np.empty(meas.n_rows)
    pidx = meas.pose_index
    for lab in cal.tool_labels:
        sel = np.asarray(meas.point) == lab
        if not sel.any():
            continue
        cond = PoseConditions(
            direction=None if meas.direction is None else meas.direction[sel],
            gravity_torque=tau[pidx[sel]],
            temp=None if meas.temp is None else meas.temp[sel],
            load=None if meas.load is None else meas.load[sel])
        err[sel] = np.linalg.norm(meas.xyz[sel] - cal.predict(meas.q[sel], lab, cond), axis=1)
    return float(np.sqrt(np.mean(err ** 2)))


def _calibrate(model: Manipulator, meas: Measurements, xml: Path, seed: int) -> Calibration:
    """The one calibration recipe (:func:`zrp.calibration.calibrate`), as ``zrp calibrate``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return calibrate(model, meas, options=CalibrationOptions(
            gravity_torque=gravity_torques(xml, meas.q_pose), seed=seed))


def _score_design(model: Manipulator, scn: Scenario, design: str, meas: Measurements,
                  val: tuple[Measurements, F64, dict[str, Any]], xml: Path,
                  config: BenchmarkConfig, std: dict[str, float]) -> DesignScore:
    calibration = _calibrate(model, meas, xml, scn.index)
    val_meas, val_tau, val_truth = val
    sc = score(model, val_truth, calibration.diagnosis.to_dict(), config)
    rms = validation_rms(calibration.robot, val_meas, val_tau)
    ratio = rms / sc.noise_rms
    temps = meas.per_pose("temp")
    return DesignScore(scn.index, scn.labels, design, len(meas.pose_ids), sc.expected,
                       sc.found, sc.top_correct, sc.joints_correct, sc.noise_rms, rms, ratio,
                       bool(sc.top_correct and sc.joints_correct
                            and ratio <= config.ratio_target), std,
                       0.0 if temps is None else float(np.ptp(temps)))


def study_scenario(model: Manipulator, scn: Scenario, config: BenchmarkConfig,
                   ks: tuple[int, ...], *, random_poses: int = 200, validation: int = 100,
                   candidates: int = 1000, xml: Path, random_ks: tuple[int, ...] = ()
                   ) -> list[DesignScore]:
    """All designs of one scenario (module doc): ``random_poses`` random (0: none), then K
    planned for each K in ``ks``, then K random for each K in ``random_ks`` (controls: does
    planning matter?); every design measured on the same robot with the same tracker and
    judged on the same validation poses."""
    rng = np.random.default_rng(scn.seed)
    inst = random_instrument(model, rng, scn.noise_sigma)   # the benchmark's first draws
    robot = RealRobot(model, scn.effects)
    tool = default_tool_points(model)
    grav = Procedure(approach="gravity")
    q_val = reachable_poses(model, validation, np.random.default_rng([scn.seed, 1]))
    vrun = measure(robot, q_val, inst, np.random.default_rng([scn.seed, 2]), grav)
    vrun.truth["scenario"] = {"index": scn.index, "seed": scn.seed, "kind": scn.kind,
                              "labels": list(scn.labels)}
    val = (vrun.measurements, gravity_torques(xml, q_val), vrun.truth)

    def tau_fn(q: F64) -> F64:
        return gravity_torques(xml, q)

    def lift_fn(q: F64) -> F64:  # the benchmark procedure's rule: lift gravity-loaded joints
        lift = _nominal_static_torque(robot, q)
        return np.where(np.abs(lift) > 1e-3, np.sign(lift), 0.0)

    def stds(q: F64, d: F64) -> dict[str, float]:
        names, std = design_std(model, q, d, PLANNED_EFFECTS, tool_points=tool,
                                noise_sigma=scn.noise_sigma, gravity_torque=tau_fn(q))
        return dict(zip(names, std.tolist(), strict=True))

    out = []
    if random_poses:
        q = reachable_poses(model, random_poses, rng)
        run = measure(robot, q, inst, rng, grav)
        out.append(_score_design(model, scn, "random", run.measurements, val, xml, config,
                                 stds(q, run.measurements.per_pose("direction"))))
    floor = -0.8 * model.reach
    for k in ks:
        prng = np.random.default_rng([scn.seed, 3, k])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            plan = plan_poses(model, k, PLANNED_EFFECTS, rng=prng, tool_points=tool,
                              floor_z=floor, noise_sigma=scn.noise_sigma,
                              candidates=candidates, gravity_torque_fn=tau_fn,
                              direction_fn=lift_fn)
        run = measure(robot, plan.q, inst, prng, Procedure(approach="random"),
                      directions=plan.direction)
        out.append(_score_design(model, scn, "planned", run.measurements, val, xml, config,
                                 stds(plan.q, plan.direction)))
    for k in random_ks:
        rrng = np.random.default_rng([scn.seed, 4, k])
        q = reachable_poses(model, k, rrng)
        run = measure(robot, q, inst, rrng, grav)
        out.append(_score_design(model, scn, "random", run.measurements, val, xml, config,
                                 stds(q, run.measurements.per_pose("direction"))))
    return out


def run_k_study(model: Manipulator, config: BenchmarkConfig, ks: tuple[int, ...] = (
        20, 30, 40, 50, 75), *, random_poses: int = 200, validation: int = 100,
        candidates: int = 1000, scenarios: tuple[int, ...] | None = None,
        progress: bool = False, random_ks: tuple[int, ...] = ()) -> list[DesignScore]:
    """:func:`study_scenario` over the blind benchmark's scenarios of ``config`` (all, or
    the indices ``scenarios``); ``progress``: a line per scenario and design on stderr."""
    if any(int(k) < 2 for k in (*ks, *random_ks)):
        raise InputError(f"ks, random_ks: expected pose counts >= 2, got {ks!r}, "
                         f"{random_ks!r}")
    scns = draw_scenarios(model, config)
    if scenarios is not None:
        scns = [s for s in scns if s.index in set(scenarios)]
    out: list[DesignScore] = []
    with tempfile.TemporaryDirectory() as tmp:
        xml = _nominal_mjcf(model, Path(tmp) / "nominal.xml")
        for scn in scns:
            rows = study_scenario(model, scn, config, ks, random_poses=random_poses,
                                  validation=validation, candidates=candidates, xml=xml,
                                  random_ks=random_ks)
            out += rows
            if progress:
                for r in rows:
                    print(f"scenario {r.scenario:3d} {r.design:7s} {r.poses:4d}: "
                          f"found {', '.join(r.found):40s} ratio {r.ratio:6.2f} "
                          f"ok {r.success}", file=sys.stderr, flush=True)
    return out


def design_rows(scores: list[DesignScore]) -> list[dict[str, Any]]:
    """Per design (random N, planned K): scenarios, successes, right effect, joints, median
    and worst validation ratio, and the median over scenarios of the median / worst
    parameter std over the random design's (same scenario)."""
    ref = _reference_designs(scores)
    top = max((s.poses for s in ref.values()), default=0)
    keys = sorted({(s.design, s.poses) for s in scores},   # reference, planned, controls
                  key=lambda k: (0 if k == ("random", top) else 1 if k[0] == "planned" else 2,
                                 k[1]))
    return [_design_row(design, poses,
                        [s for s in scores if (s.design, s.poses) == (design, poses)], ref)
            for design, poses in keys]


def _reference_designs(scores: list[DesignScore]) -> dict[int, DesignScore]:
    """The reference of each scenario: its largest random design."""
    ref: dict[int, DesignScore] = {}
    for s in scores:
        if s.design == "random" and (s.scenario not in ref or s.poses > ref[s.scenario].poses):
            ref[s.scenario] = s
    return ref


def _std_ratios(sel: list[DesignScore], ref: dict[int, DesignScore]
                ) -> tuple[list[float], list[float]]:
    """Per scenario with a reference: the median and the worst ratio of the parameter stds
    over the reference's (parameters both estimate, with a reference std > 0)."""
    med, worst = [], []
    for s in sel:
        r = ref.get(s.scenario)
        if r is None:
            continue
        names = [k for k in s.std if k in r.std and r.std[k] > 0]
        ratio = np.array([s.std[k] / r.std[k] for k in names])
        if ratio.size:
            med.append(float(np.median(ratio)))
            worst.append(float(ratio.max()))
    return med, worst


def _design_row(design: str, poses: int, sel: list[DesignScore],
                ref: dict[int, DesignScore]) -> dict[str, Any]:
    med, worst = _std_ratios(sel, ref)
    ratios = np.array([s.ratio for s in sel])
    return {"design": design, "poses": poses, "scenarios": len(sel),
            "success": sum(s.success for s in sel),
            "top_correct": sum(s.top_correct for s in sel),
            "joints_correct": sum(s.joints_correct for s in sel),
            "ratio_median": float(np.median(ratios)),
            "ratio_max": float(ratios.max()),
            "within_target": int(np.sum(ratios <= 1.5)),
            "std_ratio_median": float(np.median(med)) if med else float("nan"),
            "std_ratio_worst": float(np.median(worst)) if worst else float("nan")}


def smallest_matching_k(scores: list[DesignScore]) -> int | None:
    """The smallest K whose planned design succeeds in at least as many scenarios as the
    random design (same scenarios), and from which every larger K does too; None if none."""
    rows = design_rows(scores)
    randoms = [r for r in rows if r["design"] == "random"]
    if not randoms:
        return None
    ref = max(randoms, key=lambda r: r["poses"])
    planned = [r for r in rows if r["design"] == "planned"]
    best = None
    for r in reversed(planned):
        if r["success"] < ref["success"]:
            break
        best = r["poses"]
    return best


def render_k_study(scores: list[DesignScore], ratio_target: float = 1.5) -> str:
    """Markdown: the per-design table, the smallest matching K, the scenarios where a design
    failed."""
    rows = design_rows(scores)
    n_scn = len({s.scenario for s in scores})
    out = ["# K planned poses against 200 random ones (blind benchmark scenarios)", "",
           f"{n_scn} scenarios. Success: the right effect named first, its joints located, and "
           f"the calibrated robot's RMS on the common validation poses <= {ratio_target:g}x "
           "the tracker noise. std ratio: predicted standard deviation of each planned "
           "parameter over the random design's (same scenario), median over parameters "
           "(and worst parameter), then median over scenarios.", "",
           "| design | poses | success | right effect | joints | validation RMS / noise "
           "(median, max) | <= target | std ratio median | std ratio worst |",
           "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        n = r["scenarios"]
        out.append(f"| {r['design']} | {r['poses']} | {r['success']}/{n} | "
                   f"{r['top_correct']}/{n} | {r['joints_correct']}/{n} | "
                   f"{r['ratio_median']:.2f}, {r['ratio_max']:.2f} | {r['within_target']}/{n} | "
                   f"{r['std_ratio_median']:.2f} | {r['std_ratio_worst']:.2f} |")
    k = smallest_matching_k(scores)
    out += ["", "Smallest K that succeeds in as many scenarios as the random design (and every "
            f"larger K too): {k if k is not None else 'none of those tried'}."]
    bad = [s for s in scores if not s.success]
    if bad:
        out += ["", "Designs that did not succeed:", "",
                "| scenario | hidden | design | poses | expected | found | ratio |",
                "|---|---|---|---|---|---|---|"]
        out += [f"| {s.scenario} | {', '.join(s.hidden) or 'none'} | {s.design} | {s.poses} | "
                f"{', '.join(s.expected)} | {', '.join(s.found)} | {s.ratio:.2f} |"
                for s in bad]
    return "\n".join(out) + "\n"


def score_from_row(d: dict[str, Any]) -> DesignScore:
    """The inverse of :meth:`DesignScore.row` plus its ``std`` (JSON files of a run)."""
    def tup(v: str) -> tuple[str, ...]:
        return tuple(x for x in str(v).split(", ") if x)
    return DesignScore(int(d["scenario"]), () if d["hidden"] == "none" else tup(d["hidden"]),
                       str(d["design"]), int(d["poses"]), tup(d["expected"]), tup(d["found"]),
                       bool(d["top_correct"]), bool(d["joints_correct"]), float(d["noise_rms"]),
                       float(d["validation_rms"]), float(d["ratio"]), bool(d["success"]),
                       {k: float(v) for k, v in d.get("std", {}).items()},
                       float(d["temp_span"]))
