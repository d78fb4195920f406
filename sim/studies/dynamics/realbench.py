"""The blind benchmark of the dynamic gap on real-looking logs.

Per scenario (:mod:`sim.studies.dynamics.realscenarios`) the physics robot (the shipped model
with the hidden effects) is driven along two exciting commands; each run is written as its
controller would (:mod:`sim.studies.dynamics.reallog`), the truth in a SEPARATE file.
:func:`diagnose_real` then runs on the first log's CSV and the arm's key alone (it loads the
shipped model itself): the log is read as is by the library's reader
(:func:`zrp.gap.dynamics.data.load_torque_log`); only when the reader refuses it is it
prepared as a user does by hand today (:func:`sim.studies.dynamics.logprep.prepare_by_hand`),
and the row says so. Only afterwards does :func:`score` read the truth:

* the first finding (and whether it is among the findings at all, on the right link): for
  a scenario with ``hand``, the model's hand named absent with its mass within 10 %
  (``absent_part`` with share 0.9 to 1.1, or a payload of minus the hand's mass within
  10 %); else with ``gravity``, a link's mass or centre (``link_mass`` of the right link;
  ``inertial``: right effect, link not named); else friction on one of the distal joints;
  for ``none``, nothing named;
* friction found: of the true friction joints, those with a friction effect named;
* torque gains named (none expected: the arm has no sensor error);
* withheld torque RMS per joint and overall, before and after, over the true noise sigma and
  over the floor (noise, vibration and quantisation: what no dynamic model explains);
* the second log: the corrected model (:func:`zrp.gap.dynamics.validation.validate`: the
  diagnosis's effects with their fitted values, the link inertias after it) against the model
  as shipped, over the true noise (target <= 1.2).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from sim.studies.dynamics.logprep import prepare_by_hand
from sim.studies.dynamics.reallog import controller_log, write_controller_log
from sim.studies.dynamics.realscenarios import REAL_ARMS, RealScenario, draw_truth
from sim.studies.dynamics.truth import simulate
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.data import TorqueLog, load_torque_log
from zrp.gap.dynamics.diagnosis import DynamicDiagnosis, FoundEffect, diagnose_dynamics
from zrp.gap.dynamics.validation import validate
from zrp.jsonio import to_jsonable
from zrp.output import write_json

__all__ = ["RealRow", "diagnose_real", "read_log", "run_real", "score", "simulate_real"]

FRICTION = ("coulomb", "viscous", "stribeck")


def _torque_constant(n: int) -> F64:
    """The simulated RTDE-like controller's torque constants, N m/A (a unit conversion)."""
    return np.linspace(12.0, 4.0, n)


def simulate_real(sc: RealScenario, log_dir: Path, truth_dir: Path) -> tuple[Path, Path, Path]:
    """Simulate ``sc``: ``log_dir/NAME.csv`` and ``NAME.second.csv`` (the validation run),
    ``truth_dir/NAME.truth.json``."""
    arm = REAL_ARMS[sc.arm].load()
    hidden, sigma, desc = draw_truth(sc, arm)
    paths = []
    ripple = np.zeros(arm.n)
    for second in (False, True):
        seed = sc.seed + (7919 if second else 0)
        clean = simulate(arm, hidden, sc.command(second), sc.seconds, noise_nm=np.zeros(arm.n),
                         encoder_noise_rad=0.0, seed=seed)
        ctl = controller_log(clean, sigma, sc.defects, seed=seed)
        ripple = ctl.ripple_nm
        name = f"{sc.name}{'.second' if second else ''}.csv"
        paths.append(write_controller_log(ctl, Path(log_dir) / name, overwrite=True,
                                          torque_constant=_torque_constant(arm.n)))
    lsb = sc.defects.torque_lsb_nm
    floor = np.sqrt(sigma**2 + ripple**2 / 2.0 + lsb**2 / 12.0)
    truth = {"scenario": {"arm": sc.arm, "kind": sc.kind, "seed": sc.seed,
                          "seconds": sc.seconds, "defects": asdict(sc.defects)},
             "effect": desc, "noise_nm": sigma, "floor_nm": floor,
             "hidden": {k: v for k, v in asdict(hidden).items() if k != "inertial"},
             "inertial": {str(b): v for b, v in hidden.inertial.items()}}
    truth_path = write_json(Path(truth_dir) / f"{sc.name}.truth.json", to_jsonable(truth),
                            overwrite=True)
    return paths[0], paths[1], truth_path


def read_log(path: str | Path, n: int) -> tuple[TorqueLog, str]:
    """The log as the library reads it, or (refused) as prepared by hand; and how it was
    read, in words."""
    try:
        return load_torque_log(path, n_joints=n), "as is"
    except InputError as exc:
        if "torque_constant" in str(exc):
            # motor currents: the user passes the controller's stated constants
            # (--torque-constant), as the log's comment line gives them
            log = load_torque_log(path, n_joints=n, torque_constant=_torque_constant(n))
            return log, "as is, with the controller's torque constants (--torque-constant)"
        log, done = prepare_by_hand(path)
        return log, f"refused ({str(exc)[:90]}); by hand: {'; '.join(done)}"


def diagnose_real(csv_path: str | Path, arm_key: str) -> tuple[DynamicDiagnosis, str]:
    """The blind diagnosis of a log from its CSV and the shipped arm alone."""
    arm = REAL_ARMS[arm_key].load()
    log, how = read_log(csv_path, arm.n)
    return diagnose_dynamics(arm, log), how


@dataclass(frozen=True)
class RealRow:
    """One scored scenario (per joint lists, N m; ratios over the true noise)."""

    name: str
    arm: str
    kind: str
    log: str
    read: str
    expected: str
    named: str
    right_first: bool
    right_where: bool | None
    found_anywhere: bool
    friction_found: str
    gains_named: int
    noise: list[float]
    floor: list[float]
    before: list[float]
    after: list[float]
    second_before: list[float] = field(default_factory=list)
    second_after: list[float] = field(default_factory=list)
    not_carried: list[str] = field(default_factory=list)
    seconds: float = 0.0
    peer: dict = field(default_factory=dict)

    @staticmethod
    def overall(x: list[float]) -> float:
        return float(np.sqrt(np.mean(np.square(x)))) if x else float("nan")

    def ratio(self, which: str) -> float:
        """Overall RMS of ``which`` (an attribute) over the overall noise."""
        return self.overall(getattr(self, which)) / self.overall(self.noise)


def _named(e: FoundEffect) -> str:
    joint = "" if e.joint is None else f" j{e.joint + 1}"
    return f"{e.name}{joint}{' ' + e.detail if e.detail else ''}"


def _expected(truth: dict) -> str:
    eff = truth["effect"]
    if "hand" in eff:
        return f"absent hand {eff['hand']['hand']} ({eff['hand']['hand_kg']:.2f} kg)"
    if "gravity" in eff:
        return f"link mass/centre {eff['gravity']['link']}"
    if "friction" not in eff:
        return "nothing"
    return "friction j" + "/".join(str(k + 1) for k in eff["friction"]["joints"])


def _first(diag: DynamicDiagnosis, truth: dict, at: int = 0) -> tuple[bool, bool | None]:
    """(right effect, right link/joint; None: the effect names none) of finding ``at``."""
    eff = truth["effect"]
    if eff["kind"] == "none":
        return not diag.effects, True
    if len(diag.effects) <= at:
        return False, False
    e = diag.effects[at]
    if "hand" in eff:
        kg = eff["hand"]["hand_kg"]
        if e.name == "absent_part":
            return abs(e.params["share"].value - 1.0) <= 0.1, e.detail == eff["hand"]["hand"]
        if e.name == "payload":
            return abs(e.params["mass"].value + kg) <= 0.1 * kg, True
        return False, False
    if "gravity" in eff:
        if e.name == "link_mass":
            return True, e.detail == eff["gravity"]["link"]
        return e.name == "inertial", None if e.name == "inertial" else False
    return e.name in FRICTION, e.joint in eff["friction"]["joints"]


def score(diag: DynamicDiagnosis, how: str, truth: dict, name: str) -> RealRow:
    """Judge a blind diagnosis against its truth (module docstring)."""
    sc, eff = truth["scenario"], truth["effect"]
    right, where = _first(diag, truth)
    anywhere = any(ok and at is not False for ok, at in
                   (_first(diag, truth, i) for i in range(max(len(diag.effects), 1))))
    fj = eff.get("friction", {}).get("joints", [])
    found = {e.joint for e in diag.effects if e.name in FRICTION}
    d = sc["defects"]
    clean = not (d["jitter"] or d["gaps"] or d["repeat_share"] or d["ripple_sigma"])
    return RealRow(name, sc["arm"], sc["kind"], "clean" if clean else f"real ({d['naming']})",
                   how, _expected(truth), _named(diag.effects[0]) if diag.effects else "none",
                   right, where, anywhere, f"{len(found & set(fj))} of {len(fj)}" if fj else "-",
                   sum(e.name == "gain" for e in diag.effects), list(truth["noise_nm"]),
                   list(truth["floor_nm"]), diag.rms_before.tolist(), diag.rms_after.tolist())


def run_real(sc: RealScenario, work: Path,
             peer: Callable[[str, TorqueLog, TorqueLog], dict] | None = None) -> RealRow:
    """Simulate, diagnose blind, score and validate one scenario (files under ``work``);
    ``peer(arm_key, log, log2)`` -> dict: another identification on the same logs."""
    csv, csv2, truth_path = simulate_real(sc, work / "logs", work / "truth")
    t0 = time.perf_counter()
    diag, how = diagnose_real(csv, sc.arm)
    seconds = time.perf_counter() - t0
    truth = json.loads(truth_path.read_text(encoding="utf-8"))
    row = score(diag, how, truth, sc.name)
    arm = REAL_ARMS[sc.arm].load()
    log2, _ = read_log(csv2, arm.n)
    try:  # the library's --validate (zrp.gap.dynamics.validation)
        v = validate(arm, diag, log2)
        before2, after2, missing = v.rms_before.tolist(), v.rms_after.tolist(), []
    except InputError as exc:
        before2, after2, missing = [], [], [str(exc)]
    extra = {} if peer is None else peer(sc.arm, read_log(csv, arm.n)[0], log2)
    return replace(row, second_before=before2, second_after=after2,
                   not_carried=missing, seconds=seconds, peer=extra)
