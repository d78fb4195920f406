"""The blind benchmark of the dynamic gap diagnosis.

For each scenario (:mod:`sim.studies.dynamics.scenarios`) the physics robot with one hidden effect
(:mod:`sim.studies.dynamics.truth`) is driven along an exciting command and its log is written as a
torque log CSV, with a SEPARATE truth file (the hidden effect, the true noise, how visible the
effect is). :func:`diagnose_blind` then runs on the CSV alone: it receives the CSV path and
the arm's key (it loads the nominal model itself), never the scenario, the truth file or
anything derived from them. Only afterwards does :func:`score` read the truth:

* visibility: RMS of the effect's own torques along the log over the noise, worst joint;
  an effect below 1 is not visible and "none" is a right answer for it;
* right effect: the first effect named is the hidden one (for ``none``: nothing named), or an
  arm-wide effect named first is reported tied with the hidden one (e.g. a payload and a wrist
  link's mass: the log cannot tell them apart, and the report says so); a hidden link
  inertial error (a point mass added to one link) named as that link's ``link_mass``;
* right joint: for a joint effect, the joint of the first effect named;
* withheld ratio: the worst joint's withheld torque RMS after correction over its true noise
  (target <= 1.5).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from mjcf.arm import Arm
from mjcf.inverse import inverse_dynamics
from mjcf.tracking import TRUTH_V_EPS
from sim.studies.dynamics.arms import BENCH_ARMS
from sim.studies.dynamics.scenarios import Scenario, draw_hidden, scenario_command
from sim.studies.dynamics.truth import HiddenDynamics, simulate, true_model
from zrp.arrays import F64
from zrp.gap.dynamics.data import TorqueLog, load_torque_log, write_torque_log
from zrp.gap.dynamics.diagnosis import DynamicDiagnosis, diagnose_dynamics
from zrp.gap.dynamics.fourier import Fourier
from zrp.jsonio import to_jsonable
from zrp.output import write_json

__all__ = ["Row", "diagnose_blind", "run_scenario", "score", "simulate_scenario"]


def _visibility(arm: Arm, hidden: HiddenDynamics, log: TorqueLog, command: Fourier,
                sigma: F64) -> float:
    """RMS of the hidden effect's own torques along the log over sigma, worst joint."""
    _, _, qdd = command.evaluate(log.t - log.t[0])
    q, qd = log.q, log.qd
    sig = inverse_dynamics(true_model(arm, hidden), q, qd, qdd) - inverse_dynamics(
        arm.model, q, qd, qdd)
    n = arm.n
    fs = hidden.per_joint("stribeck", n)
    sig += fs * np.tanh(qd / TRUTH_V_EPS) * np.exp(-(qd / hidden.stribeck_speed) ** 2)
    sig += hidden.per_joint("offset", n)
    return float(np.max(np.sqrt(np.mean(sig**2, axis=0)) / sigma))


def simulate_scenario(sc: Scenario, log_dir: Path, truth_dir: Path) -> tuple[Path, Path]:
    """Simulate ``sc``; write ``log_dir/NAME.csv`` and ``truth_dir/NAME.truth.json``."""
    bench = BENCH_ARMS[sc.arm]
    arm = bench.load()
    command = scenario_command(bench.q0_array, bench.amplitude_rad, sc.seed)
    hidden, sigma, desc = draw_hidden(arm, command, sc.kind, sc.seed)
    log = simulate(arm, hidden, command, sc.seconds, noise_nm=sigma, seed=sc.seed)
    csv = write_torque_log(log, Path(log_dir) / f"{sc.name}.csv", overwrite=True)
    truth = {"scenario": asdict(sc), "effect": desc, "noise_nm": sigma,
             "visibility": _visibility(arm, hidden, log, command, sigma),
             "hidden": {k: v for k, v in asdict(hidden).items() if k != "inertial"},
             "inertial": {str(b): v for b, v in hidden.inertial.items()}}
    path = write_json(Path(truth_dir) / f"{sc.name}.truth.json", to_jsonable(truth),
                      overwrite=True)
    return csv, path


def summary(d: DynamicDiagnosis) -> dict:
    """The diagnosis's verdict as plain data."""
    return {"effects": [{"name": e.name, "joint": e.joint, "detail": e.detail,
                         "params": {k: asdict(p) for k, p in e.params.items()
                                    if not k.startswith("beta")}} for e in d.effects],
            "noise_nm": d.noise_nm.tolist(), "rms_before": d.rms_before.tolist(),
            "rms_after": d.rms_after.tolist(), "cannot_tell": d.cannot_tell,
            "steps": [(s.key, s.chi2, list(s.ties)) for s in d.steps]}


def diagnose_blind(csv_path: str | Path, arm_key: str) -> dict:
    """The diagnosis of a benchmark log from the CSV and the nominal arm alone."""
    arm = BENCH_ARMS[arm_key].load()
    return summary(diagnose_dynamics(arm, load_torque_log(csv_path, n_joints=arm.n)))


@dataclass(frozen=True)
class Row:
    """One scored scenario."""

    arm: str
    kind: str
    seed: int
    joint: int | None
    visibility: float
    named: str
    right_effect: bool
    right_joint: bool
    withheld_ratio: float
    shrink: float
    seconds: float

    @property
    def visible(self) -> bool:
        return self.visibility >= 1.0

    @property
    def success(self) -> bool:
        return self.right_effect and self.right_joint and self.withheld_ratio <= 1.5


def _right_link(first: dict, eff: dict) -> bool:
    """A hidden link inertial error named as that link's mass (a point mass added to it):
    the more specific right answer."""
    return (eff["kind"] == "inertial" and first["name"] == "link_mass"
            and first.get("detail") == eff.get("body_name"))


def _right(diag: dict, first: dict | None, eff: dict, visible: bool) -> tuple[bool, bool]:
    """(right effect, right joint) of a diagnosis (module docstring)."""
    kind, joint = eff["kind"], eff["joint"]
    if kind == "none" or not visible:
        return first is None or (kind != "none" and first["name"] == kind), True
    tied = [] if len(diag["steps"]) < 2 else [t.split("_j")[0] for t in diag["steps"][1][2]]
    # named first, or reported as a tie with the first (the log cannot tell them apart)
    right = first is not None and (first["name"] == kind or
                                   (kind in tied and first["joint"] is None) or
                                   _right_link(first, eff))
    return right, joint is None or (first is not None and first["joint"] == joint)


def score(diag: dict, truth: dict, seconds: float = 0.0) -> Row:
    """Judge a blind diagnosis against its truth (module docstring)."""
    sc, eff = truth["scenario"], truth["effect"]
    first = diag["effects"][0] if diag["effects"] else None
    named = "none" if first is None else (
        first["name"] + ("" if first["joint"] is None else f" j{first['joint'] + 1}"))
    kind, joint = eff["kind"], eff["joint"]
    right, right_joint = _right(diag, first, eff, truth["visibility"] >= 1.0)
    sigma = np.asarray(truth["noise_nm"])
    after, before = np.asarray(diag["rms_after"]), np.asarray(diag["rms_before"])
    return Row(sc["arm"], kind, sc["seed"], joint, float(truth["visibility"]), named, right,
               right_joint, float(np.max(after / sigma)),
               float(np.sqrt(np.mean(after**2)) / np.sqrt(np.mean(before**2))), seconds)


def run_scenario(sc: Scenario, work: Path) -> Row:
    """Simulate, diagnose blind, then score one scenario (files under ``work``)."""
    import json

    csv, truth_path = simulate_scenario(sc, work / "logs", work / "truth")
    t0 = time.perf_counter()
    diag = diagnose_blind(csv, sc.arm)
    seconds = time.perf_counter() - t0
    truth = json.loads(truth_path.read_text(encoding="utf-8"))
    return score(diag, truth, seconds)


def draw_scenarios(arms: list[str], kinds: tuple[str, ...], reps: int, seed: int,
                   seconds: float = 20.0) -> list[Scenario]:
    """Every (arm, kind) ``reps`` times, seeds seed, seed + 1, ..."""
    return [Scenario(a, k, seed + r, seconds) for a in arms for k in kinds for r in range(reps)]


def tally(rows: list[Row]) -> dict[str, float]:
    """The headline numbers: visible single effects right (effect, joint, withheld <= 1.5
    sigma) and their share; 'none' scenarios with nothing named."""
    vis = [r for r in rows if r.kind != "none" and r.visible]
    none = [r for r in rows if r.kind == "none"]
    ok = sum(r.success for r in vis)
    first = sum(r.success and r.named.split(" ")[0] == r.kind for r in vis)
    return {"visible_singles": len(vis), "right": ok, "right_named_first": first,
            "share": ok / len(vis) if vis else float("nan"),
            "none_scenarios": len(none), "none_clean": sum(r.named == "none" for r in none),
            "median_ratio": float(np.median([r.withheld_ratio for r in rows])) if rows else
            float("nan")}
