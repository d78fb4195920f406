"""The blind benchmark of the gap diagnosis: physics-made measurements with withheld causes.

For each scenario (:func:`draw_scenarios`): a hidden effect (or none, or two) with a random
magnitude is built into the MuJoCo "real" robot (:mod:`sim.real_robot`), the robot is measured
like a laser-tracker calibration (:mod:`sim.measurement`), and the measurement CSV and a SEPARATE
truth file are written. The diagnosis then runs on the CSV alone (:func:`diagnose_blind`: it
receives the CSV path, the nominal model and the nominal MJCF - never the scenario, the truth
file or anything derived from them). Only afterwards does :func:`score` open the truth file and
judge the diagnosis:

* **excitation**: how much of each hidden effect the poses make visible, i.e. the RMS of its
  own tool-point signature after the best registration (instrument frame and tool offsets) has
  absorbed what it can, over the noise RMS sqrt(3) sigma. Below 1 the effect hides in the
  noise or in the registration (e.g. a joint-1 offset is a turn of the instrument frame), and
  the right answer is ``none``;
* **effect named first** is the right one (or ``none`` when nothing visible was hidden);
* **joints located**: the injected joints (bodies for ``link_length``) are among those the
  diagnosis names for that effect;
* **withheld RMS after correction** over the true noise RMS (target <= 1.5), and the shrink
  ratio final / nominal withheld RMS.

:func:`run_benchmark` does all of it with a progress bar and writes the confusion matrix and
summary tables (:func:`write_outputs`).
"""

from __future__ import annotations

import csv
import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from zrp.errors import InputError, OutputExistsError
from zrp.kinematics.forward import forward_kinematics
from zrp.model.manipulator import Manipulator

__all__ = [
    "BenchmarkConfig",
    "BenchmarkResult",
    "Scenario",
    "ScenarioScore",
    "confusion_matrix",
    "diagnose_blind",
    "draw_scenarios",
    "effect_signatures",
    "run_benchmark",
    "score",
    "simulate_scenario",
    "summary_rows",
    "write_outputs",
]

if TYPE_CHECKING:
    from sim.real_robot import HiddenEffects

F64 = NDArray[np.float64]
KINDS = ("none", "single", "pair")
OUTPUT_FILES = ("summary.md", "confusion.csv", "scenarios.csv", "results.json", "confusion.png")
JOINT_SPACE = ("joint_offset", "encoder_scale", "cyclic_error", "joint_compliance", "backlash")


def _effect_names() -> tuple[str, ...]:
    from sim.real_robot import EFFECT_NAMES

    return EFFECT_NAMES


@dataclass(frozen=True)
class BenchmarkConfig:
    """What the benchmark draws and how it measures.

    Attributes:
        scenarios: K, number of scenarios.
        seed: master seed; scenario i uses the i-th child of ``SeedSequence(seed)``, so the
            first scenarios are the same whatever K.
        poses: measured poses per scenario.
        none_fraction, pair_fraction: shares of scenarios with no hidden effect and with two
            (the rest have one).
        effects: effects to draw from (names of :data:`sim.real_robot.EFFECT_NAMES`).
        noise: range of the tracker noise sigma per coordinate, model length unit.
        poses_from: "random" (random reachable poses) or "circle" (the PUMA's circle).
        approach: "random", "gravity" or "order" (see :class:`sim.measurement.Procedure`).
        payload_probability: chance that a scenario carries a payload (0.5-3 kg, known: it is
            logged in the ``load`` column).
        use_mjcf: give the diagnosis the nominal MJCF (inertias for the gravity torques).
        excitation_threshold: an effect counts as visible when its registered signature RMS
            is at least this multiple of the noise RMS.
        ratio_target: withheld RMS after correction / noise RMS regarded as success.
    """

    scenarios: int = 50
    seed: int = 0
    poses: int = 200
    none_fraction: float = 0.1
    pair_fraction: float = 0.15
    effects: tuple[str, ...] = ()
    noise: tuple[float, float] = (0.01, 0.03)
    poses_from: str = "random"
    approach: str = "gravity"
    payload_probability: float = 0.5
    use_mjcf: bool = True
    excitation_threshold: float = 1.0
    ratio_target: float = 1.5

    def __post_init__(self) -> None:
        for name, lo in (("scenarios", 1), ("poses", 16)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo:
                raise InputError(f"{name}: expected an integer >= {lo}, got {v!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) \
                or self.seed < 0:
            raise InputError(f"seed: expected an integer >= 0, got {self.seed!r}")
        for name in ("none_fraction", "pair_fraction", "payload_probability"):
            v = float(getattr(self, name))
            if not 0.0 <= v <= 1.0:
                raise InputError(f"{name}: expected a fraction in [0, 1], got {v!r}")
        if self.none_fraction + self.pair_fraction > 1.0:
            raise InputError(f"none_fraction + pair_fraction = "
                             f"{self.none_fraction + self.pair_fraction:g} > 1")
        names = _effect_names()
        eff = tuple(self.effects) or names
        bad = [e for e in eff if e not in names]
        if bad:
            raise InputError(f"effects: unknown {bad}; expected some of {list(names)}")
        if self.pair_fraction > 0 and len(eff) < 2:
            raise InputError("pair_fraction > 0 needs at least two effects to draw from")
        object.__setattr__(self, "effects", eff)
        lo, hi = (float(x) for x in self.noise)
        if not 0 < lo <= hi:
            raise InputError(f"noise: expected 0 < low <= high (length unit), got {self.noise!r}")
        object.__setattr__(self, "noise", (lo, hi))
        if self.poses_from not in ("random", "circle"):
            raise InputError(f"poses_from: {self.poses_from!r}; expected 'random' or 'circle'")
        if self.approach not in ("random", "order", "gravity"):
            raise InputError(f"approach: {self.approach!r}; expected 'random', 'gravity' or "
                             "'order'")
        for name in ("excitation_threshold", "ratio_target"):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and v > 0):
                raise InputError(f"{name}: expected a positive number, got {v!r}")


@dataclass(frozen=True, eq=False)
class Scenario:
    """One drawn scenario (this object is the truth: it never reaches the diagnosis).

    Attributes:
        index: 0-based scenario number.
        seed: entropy of its own generator (poses, approaches, noise).
        kind: "none", "single" or "pair".
        effects: the hidden effects (and the payload).
        labels: names of the hidden effects, in drawing order.
        noise_sigma: tracker noise per coordinate, model length unit.
    """

    index: int
    seed: int
    kind: str
    effects: HiddenEffects
    labels: tuple[str, ...]
    noise_sigma: float

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise InputError(f"kind: {self.kind!r}; expected one of {KINDS}")


def typical_gravity_torque(model: Manipulator, payload: float,
                           rng: np.random.Generator, count: int = 64) -> F64:
    """RMS over random poses of the static torque each joint carries (arm and payload), N m,
    shape (n,) (nominal model, PUMA 560 or rod inertias)."""
    from sim.real_robot import HiddenEffects, RealRobot

    robot = RealRobot(model, HiddenEffects(payload=payload))
    tau = robot.static_torque(rng.uniform(-2.5, 2.5, (count, model.n)))
    return np.sqrt(np.mean(tau**2, axis=0))


def _draw_effect(name: str, model: Manipulator, rng: np.random.Generator, payload: float,
                 tau_rms: Callable[[], F64]) -> tuple[dict[str, Any], tuple[int, ...]]:
    """Keyword arguments of HiddenEffects for one effect with a random magnitude."""
    n = model.n
    k = int(rng.integers(1, n + 1))
    sign = float(rng.choice([-1.0, 1.0]))
    lscale = model.reach / 1244.6  # the PUMA's reach: magnitudes in mm scale with the arm
    if name == "joint_offset":
        return {name: {k: sign * rng.uniform(0.2e-3, 1.0e-3)}}, (k,)
    if name == "encoder_scale":
        return {name: {k: sign * rng.uniform(1.5e-4, 6e-4)}}, (k,)
    if name == "cyclic_error":
        amp = rng.uniform(0.2e-3, 0.8e-3)
        ph = rng.uniform(0, 2 * math.pi)
        return {name: {k: (int(rng.integers(1, 3)), amp * math.cos(ph), amp * math.sin(ph))}}, (k,)
    if name == "link_length":
        b = int(rng.integers(1, n + 2))
        v = rng.normal(size=3)
        v *= rng.uniform(0.2, 0.8) * lscale / np.linalg.norm(v)
        return {name: {b: tuple(float(x) for x in v)}}, (b,)
    if name == "axis_misalignment":
        ang = rng.uniform(0, 2 * math.pi)
        mag = rng.uniform(0.3e-3, 1.5e-3)
        return {name: {k: (mag * math.cos(ang), mag * math.sin(ang))}}, (k,)
    if name == "joint_compliance":
        # a sag of 0.3-1.5 mrad under the joint's typical static torque, stiffness kept within
        # 200 .. 5e5 N m/rad (a joint without a gravity torque gets the softest)
        tau = float(tau_rms()[k - 1])
        sag = rng.uniform(0.3e-3, 1.5e-3)
        c = sag / tau if tau > 1e-9 else 5e-3
        return {name: {k: float(np.clip(c, 2e-6, 5e-3))}}, (k,)
    if name == "backlash":
        return {name: {k: rng.uniform(0.4e-3, 1.6e-3)}}, (k,)
    if name == "thermal_expansion":
        return {name: rng.uniform(1.0e-5, 2.5e-5)}, ()
    raise InputError(f"effect: {name!r} cannot be drawn")


def draw_scenarios(model: Manipulator, config: BenchmarkConfig) -> list[Scenario]:
    """The K scenarios of ``config`` (reproducible from ``config.seed``)."""
    from sim.real_robot import HiddenEffects

    children = np.random.SeedSequence(config.seed).spawn(config.scenarios)
    out = []
    tau_cache: dict[float, F64] = {}
    for i, child in enumerate(children):
        rng = np.random.default_rng(child)
        u = rng.uniform()
        kind = ("none" if u < config.none_fraction else
                "pair" if u < config.none_fraction + config.pair_fraction else "single")
        payload = (float(rng.uniform(0.5, 3.0)) if rng.uniform() < config.payload_probability
                   else 0.0)
        payload = round(payload, 2)
        sigma = float(rng.uniform(*config.noise))
        count = {"none": 0, "single": 1, "pair": 2}[kind]
        # balanced classes: the first effect cycles through a seeded permutation of the
        # effects (one per block of len(effects) scenarios), the second is drawn at random
        ne = len(config.effects)
        perm = np.random.default_rng([config.seed, 7919, i // ne]).permutation(ne)
        first = config.effects[int(perm[i % ne])]
        rest = [e for e in config.effects if e != first]
        names = ([first] + [str(x) for x in rng.choice(rest, size=count - 1, replace=False)]
                 if count else [])

        def tau_rms(p: float = payload) -> F64:
            if p not in tau_cache:
                tau_cache[p] = typical_gravity_torque(model, p, np.random.default_rng(0))
            return tau_cache[p]

        kw: dict[str, Any] = {}
        for name in names:
            part, _ = _draw_effect(name, model, rng, payload, tau_rms)
            kw.update(part)
        seed = int(rng.integers(2**31))
        out.append(Scenario(i, seed, kind, HiddenEffects(payload=payload, **kw), tuple(names),
                            sigma))
    return out


# ---- simulation (sees the truth) ------------------------------------------------------------

def simulate_scenario(model: Manipulator, scenario: Scenario, config: BenchmarkConfig,
                      measurement_dir: Path, truth_dir: Path) -> tuple[Path, Path, float]:
    """Simulate and measure one scenario; write ``measurement_dir/scenario_XXX.csv`` and
    ``truth_dir/scenario_XXX.truth.json``. Returns both paths and the wall time (s)."""
    from sim.measurement import (
        Procedure,
        measure,
        random_instrument,
        trajectory_poses,
        write_measurements,
        write_truth,
    )
    from sim.real_robot import RealRobot
    from zrp.kinematics import reachable_poses

    t0 = time.perf_counter()
    rng = np.random.default_rng(scenario.seed)
    q = (reachable_poses(model, config.poses, rng) if config.poses_from == "random"
         else trajectory_poses(model, config.poses, "circle"))
    inst = random_instrument(model, rng, scenario.noise_sigma)
    robot = RealRobot(model, scenario.effects)
    run = measure(robot, q, inst, rng, Procedure(approach=config.approach))
    run.truth["scenario"] = {"index": scenario.index, "seed": scenario.seed,
                             "kind": scenario.kind, "labels": list(scenario.labels)}
    name = f"scenario_{scenario.index:03d}"
    csv_path = write_measurements(run, measurement_dir / f"{name}.csv", force=True)
    truth_path = write_truth(run, truth_dir / f"{name}.truth.json", force=True)
    return csv_path, truth_path, time.perf_counter() - t0


# ---- the blind diagnosis (sees only the CSV) ------------------------------------------------

def diagnose_blind(csv_path: str | Path, model: Manipulator, *, mjcf_path: str | Path | None,
                   seed: int = 0) -> dict[str, Any]:
    """Run the diagnosis on a measurement CSV exactly as a user would, and return its JSON.

    This is the only place the benchmark calls the diagnosis. It receives the CSV path, the
    nominal model and the nominal MJCF - nothing about the scenario. Warnings of the diagnosis
    are kept in the returned document, not printed.
    """
    import warnings

    from mjcf.gravity import gravity_torques
    from zrp.gap import diagnose, load_measurements

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        meas = load_measurements(csv_path, model)
        tau = None if mjcf_path is None else gravity_torques(mjcf_path, meas.q_pose)
        diag = diagnose(model, meas, gravity_torque=tau, seed=seed)
    return diag.to_dict()


# ---- scoring (sees the truth, after the diagnosis) -----------------------------------------

def _tool_points(model: Manipulator, q: F64, tool: F64, scale: F64 | None = None) -> F64:
    """Tool points p + R_n t_j, shape (P, M, 3); body vectors scaled per pose by ``scale``."""
    if scale is None:
        fk = forward_kinematics(model, q)
        return fk.position[:, None, :] + np.einsum("pij,mj->pmi", fk.rotation, tool)
    out = np.empty((len(q), len(tool), 3))
    for i, s in enumerate(scale):
        m = model.with_arrays(bodies=np.asarray(model.bodies) * s)
        fk = forward_kinematics(m, q[i])
        out[i] = fk.position + tool @ fk.rotation.T
    return out


def registered_rms(model: Manipulator, q: F64, tool: F64, signature: F64) -> float:
    """RMS (per point, 3-D) of a tool-point signature (P, M, 3) after the best small
    registration (instrument rotation and translation, one offset per tool point) is removed
    by linear least squares."""
    P, M, _ = signature.shape
    fk = forward_kinematics(model, q)
    y = fk.position[:, None, :] + np.einsum("pij,mj->pmi", fk.rotation, tool)
    cols = 6 + 3 * M
    A = np.zeros((P, M, 3, cols))
    yx, yy, yz = y[..., 0], y[..., 1], y[..., 2]
    # d(phi x y)/dphi = -[y]_x
    A[..., 0, 1], A[..., 0, 2] = yz, -yy
    A[..., 1, 0], A[..., 1, 2] = -yz, yx
    A[..., 2, 0], A[..., 2, 1] = yy, -yx
    A[..., :, 3:6] = np.eye(3)
    for m in range(M):
        A[:, m, :, 6 + 3 * m:9 + 3 * m] = fk.rotation
    A = A.reshape(-1, cols)
    b = signature.reshape(-1)
    sol, *_ = np.linalg.lstsq(A, b, rcond=None)
    r = (b - A @ sol).reshape(P, M, 3)
    return float(np.sqrt(np.mean(np.sum(r**2, axis=-1))))


def effect_signatures(model: Manipulator, truth: dict[str, Any]) -> dict[str, float]:
    """Visible RMS (model length unit) of each hidden effect on its own, after registration.

    Joint-space effects are attributed from the simulation (compliance: motor deflection;
    backlash: the load's position in the play; encoder effects: their mapping), geometric and
    thermal ones from the true geometry; each is then played through the nominal kinematics.
    """
    from sim.real_robot import HiddenEffects, motor_map, true_geometry

    eff = HiddenEffects.from_dict(truth["effects"])
    poses = truth["poses"]
    q = np.asarray(poses["q_command"], dtype=float)
    q_link = np.asarray(poses["q_link"], dtype=float)
    q_motor = np.asarray(poses["q_motor"], dtype=float)
    tool = np.asarray(truth["robot"]["tool_points"], dtype=float)
    t_ref = float(truth["robot"]["t_ref_degC"])
    base = _tool_points(model, q, tool)
    out: dict[str, float] = {}
    for name in eff.active:
        if name in JOINT_SPACE:
            only = HiddenEffects(**{name: getattr(eff, name)})
            dq = np.zeros_like(q)
            for k in eff.joints(name):
                j = k - 1
                if name == "joint_compliance":
                    dq[:, j] = q_motor[:, j] - motor_map(eff, q)[:, j]
                elif name == "backlash":
                    dq[:, j] = q_link[:, j] - q_motor[:, j]
                else:
                    dq[:, j] = (motor_map(only, q) - q)[:, j]
            sig = _tool_points(model, q + dq, tool) - base
        elif name in ("link_length", "axis_misalignment"):
            only = HiddenEffects(**{name: getattr(eff, name)})
            geo = true_geometry(model, only)
            sig = _tool_points(geo, q, tool) - base
        else:  # thermal_expansion
            temp = np.asarray(poses["temperature_true"], dtype=float)
            s = 1.0 + eff.thermal_expansion * (temp - t_ref)
            sig = _tool_points(model, q, tool, s) - base
        out[name] = registered_rms(model, q, tool, sig)
    return out


@dataclass(frozen=True)
class ScenarioScore:
    """How the diagnosis did on one scenario (see the module docstring).

    Attributes:
        index, kind: of the scenario.
        hidden: the hidden effects.
        hidden_joints: per hidden effect, the injected joints (bodies for link_length).
        snr: per hidden effect, registered signature RMS / noise RMS.
        expected: the visible hidden effects, or ("none",).
        found: effects named by the diagnosis, in order ("none" alone if nothing).
        found_joints: joints named for each found effect.
        top_correct: the first effect named is one of ``expected``.
        tied: effects the diagnosis itself reports as fitting the first step equally well
            (significant candidates with a cross-validated RMS within 1 % of the winner's).
        joints_correct: the joints named for the (first) hidden effect that was found include
            the injected ones (True for ``thermal_expansion`` and for ``none``).
        all_found: every expected effect was named (pairs).
        noise_rms: true noise RMS sqrt(3) sigma, length unit.
        nominal_rms, final_rms: withheld RMS after registration and after correction.
        ratio: final_rms / noise_rms.
        shrink: final_rms / nominal_rms.
        unexplained: the diagnosis's own verdict.
        sim_s, diag_s: wall times, s.
    """

    index: int
    kind: str
    hidden: tuple[str, ...]
    hidden_joints: dict[str, tuple[int, ...]]
    snr: dict[str, float]
    expected: tuple[str, ...]
    found: tuple[str, ...]
    found_joints: tuple[tuple[int, ...], ...]
    top_correct: bool
    tied: tuple[str, ...]
    joints_correct: bool
    all_found: bool
    noise_rms: float
    nominal_rms: float
    final_rms: float
    ratio: float
    shrink: float
    unexplained: bool | None
    sim_s: float = 0.0
    diag_s: float = 0.0
    payload: float = 0.0
    note: str = ""
    values: dict[str, Any] = field(default_factory=dict)

    @property
    def excited(self) -> bool:
        """Every hidden effect is visible (vacuously true for ``none``)."""
        return self.expected != ("none",) or not self.hidden

    @property
    def success(self) -> bool:
        """Right effect first, joints located, withheld RMS within the target (set later)."""
        return bool(self.values.get("success", False))

    def to_dict(self) -> dict[str, Any]:
        return {"index": self.index, "kind": self.kind, "hidden": list(self.hidden),
                "hidden_joints": {k: list(v) for k, v in self.hidden_joints.items()},
                "snr": self.snr, "expected": list(self.expected), "found": list(self.found),
                "found_joints": [list(j) for j in self.found_joints],
                "top_correct": self.top_correct, "tied": list(self.tied),
                "joints_correct": self.joints_correct,
                "all_found": self.all_found, "noise_rms": self.noise_rms,
                "nominal_rms": self.nominal_rms, "final_rms": self.final_rms,
                "ratio": self.ratio, "shrink": self.shrink, "unexplained": self.unexplained,
                "excited": self.excited, "payload": self.payload, "sim_s": self.sim_s,
                "diag_s": self.diag_s, "note": self.note, **self.values}


def score(model: Manipulator, truth: dict[str, Any], diagnosis: dict[str, Any],
          config: BenchmarkConfig) -> ScenarioScore:
    """Judge one diagnosis (its JSON) against the truth file's content."""
    from sim.real_robot import HiddenEffects

    eff = HiddenEffects.from_dict(truth["effects"])
    scn = truth.get("scenario", {})
    hidden = tuple(scn.get("labels", eff.active))
    sigma = float(truth["instrument"]["noise_sigma"])
    noise_rms = math.sqrt(3.0) * sigma
    sig = effect_signatures(model, truth)
    snr = {k: v / noise_rms for k, v in sig.items()}
    visible = tuple(e for e in hidden if snr.get(e, 0.0) >= config.excitation_threshold)
    expected = visible or ("none",)
    steps = diagnosis.get("steps", [])
    refused = diagnosis.get("error")
    found = ("refused",) if refused else (tuple(s["effect"] for s in steps) or ("none",))
    found_joints = tuple(tuple(int(j) for j in s.get("joints", [])) for s in steps)
    # an effect hidden below the excitation threshold may still be found: naming it is right
    # too (but not required)
    accept = expected if expected != ("none",) else ("none", *hidden)
    top_correct = found[0] in accept
    tied: tuple[str, ...] = ()
    if steps:
        cands = [c for c in steps[0].get("candidates", []) if c.get("significant")
                 and c.get("cv_rms") is not None]
        if cands:
            best = min(c["cv_rms"] for c in cands)
            tied = tuple(c["effect"] for c in cands if c["cv_rms"] <= 1.01 * best
                         and c["effect"] != found[0])
    hj = {e: eff.joints(e) for e in hidden}
    joints_ok = True
    if found[0] not in ("none", "refused"):
        joints_ok = False
        for e in accept:
            if e in found:
                named = set(found_joints[found.index(e)])
                joints_ok = set(hj[e]) <= named if hj[e] else True
                break
    if expected != ("none",):
        all_found = all(e in found for e in expected)
    else:  # nothing visible: nothing, or only hidden effects, may be named
        all_found = set(found) <= {"none", *hidden}
    nominal = float(diagnosis["nominal"]["rms"])
    final = float(diagnosis["final"]["rms"])
    ratio = final / noise_rms
    notes = []
    if refused:
        notes.append(f"the diagnosis refused the data: {str(refused).split(': ', 1)[-1]}")
    hid = [e for e in hidden if e not in visible]
    if hid:
        notes.append(f"{', '.join(hid)} not visible (SNR "
                     f"{min(snr.get(e, 0.0) for e in hid):.2g})")
    if not top_correct and not refused:
        if found[0] == "none":
            notes.append("missed: nothing significant found")
        else:
            lk = f"look-alike: named {found[0]}"
            if any(e in tied for e in accept):
                lk += " (the diagnosis reports the hidden effect as fitting equally well)"
            notes.append(lk)
    elif not joints_ok and not refused:
        notes.append("joints not located")
    if ratio > config.ratio_target:
        notes.append(f"withheld RMS {ratio:.2f}x the noise"
                     + (" (the diagnosis says unexplained)" if diagnosis.get("unexplained")
                        else ""))
    note = "; ".join(notes)
    values = {"success": bool(top_correct and joints_ok and ratio <= config.ratio_target)}
    return ScenarioScore(int(scn.get("index", -1)), str(scn.get("kind", "")), hidden, hj, snr,
                         expected, found, found_joints, bool(top_correct), tied,
                         bool(joints_ok),
                         bool(all_found), noise_rms, nominal, final, ratio,
                         final / nominal if nominal > 0 else 1.0,
                         diagnosis.get("unexplained"), payload=eff.payload, note=note,
                         values=values)


# ---- the run ---------------------------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class BenchmarkResult:
    """Scores of all scenarios plus timings (s)."""

    config: BenchmarkConfig
    model_name: str
    scores: tuple[ScenarioScore, ...]
    wall_s: float
    sim_s: float
    diag_s: float
    workdir: str

    def to_dict(self) -> dict[str, Any]:
        cfg = {k: (list(v) if isinstance(v, tuple) else v)
               for k, v in self.config.__dict__.items()}
        return {"model": self.model_name, "config": cfg, "wall_s": self.wall_s,
                "sim_s": self.sim_s, "diag_s": self.diag_s, "workdir": self.workdir,
                "summary": summary_rows(self), "confusion": confusion_matrix(self),
                "scenarios": [s.to_dict() for s in self.scores]}


def _scenario(model: Manipulator, scn: Scenario, config: BenchmarkConfig, work: Path,
              mjcf_path: Path | None) -> ScenarioScore:
    """Simulate, diagnose blind, then score one scenario (in this process or a worker)."""
    csv_path, truth_path, sim_s = simulate_scenario(model, scn, config, work / "measurements",
                                                    work / "truth")
    t1 = time.perf_counter()
    try:
        diag = diagnose_blind(csv_path, model, mjcf_path=mjcf_path, seed=scn.index)
    except InputError as exc:  # the diagnosis refused the data: report, do not crash
        diag = {"steps": [], "nominal": {"rms": math.nan}, "final": {"rms": math.nan},
                "unexplained": None, "error": str(exc)}
    diag_s = time.perf_counter() - t1
    (work / "diagnoses" / f"{csv_path.stem}.diagnosis.json").write_text(
        json.dumps(diag, default=str))
    # only now, after the diagnosis has answered, is the truth read
    truth = json.loads(truth_path.read_text(encoding="utf-8"))
    sc = score(model, truth, diag, config)
    return ScenarioScore(**{**sc.__dict__, "sim_s": sim_s, "diag_s": diag_s})


def run_benchmark(model: Manipulator, config: BenchmarkConfig, workdir: str | Path, *,
                  progress: bool = True, jobs: int = 1) -> BenchmarkResult:
    """Draw, simulate, diagnose blind and score ``config.scenarios`` scenarios.

    Files: ``workdir/measurements/*.csv`` (what the diagnosis sees), ``workdir/truth/*.json``
    (what only the scorer reads, after the diagnosis), ``workdir/diagnoses/*.json`` and the
    nominal MJCF ``workdir/nominal.xml``. ``jobs`` > 1 runs scenarios in that many worker
    processes (results are identical: each scenario has its own seed).
    """
    from tqdm.auto import tqdm

    import mjcf

    if isinstance(jobs, bool) or not isinstance(jobs, int) or jobs < 1:
        raise InputError(f"jobs: expected a positive number of worker processes, got {jobs!r}")
    work = Path(workdir)
    for d in ("measurements", "truth", "diagnoses"):
        (work / d).mkdir(parents=True, exist_ok=True)
    mjcf_path: Path | None = None
    if config.use_mjcf:
        inertia = "puma560" if model.n == 6 and not model.prismatic.any() else "rods"
        mjcf_path = mjcf.save_mjcf(mjcf.build(model, mjcf.MJCFOptions(
            inertia=inertia, visuals=False, floor=False)), work / "nominal.xml", overwrite=True)
    t0 = time.perf_counter()
    scenarios = draw_scenarios(model, config)
    scores: list[ScenarioScore] = []
    bar = tqdm(total=len(scenarios), desc="gap-benchmark", unit="scenario",
               disable=not progress)

    def done(sc: ScenarioScore) -> None:
        scores.append(sc)
        bar.update(1)
        bar.set_postfix(ok=f"{sum(s.success for s in scores)}/{len(scores)}")

    if jobs == 1:
        for scn in scenarios:
            done(_scenario(model, scn, config, work, mjcf_path))
    else:
        import multiprocessing as mp
        from concurrent.futures import ProcessPoolExecutor, as_completed

        with ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("spawn")) as ex:
            futs = [ex.submit(_scenario, model, scn, config, work, mjcf_path)
                    for scn in scenarios]
            for f in as_completed(futs):
                done(f.result())
    bar.close()
    scores.sort(key=lambda s: s.index)
    return BenchmarkResult(config, model.name, tuple(scores), time.perf_counter() - t0,
                           sum(s.sim_s for s in scores), sum(s.diag_s for s in scores),
                           str(work))


# ---- tables ------------------------------------------------------------------------------

def confusion_matrix(result: BenchmarkResult) -> dict[str, dict[str, int]]:
    """Single-effect and none scenarios: hidden effect (row; "<effect> (not visible)" when
    its signature hides in the noise) -> effect named first (column) -> count."""
    rows: dict[str, dict[str, int]] = {}
    for s in result.scores:
        if s.kind == "pair":
            continue
        true = s.hidden[0] if s.hidden else "none"
        if s.hidden and s.expected == ("none",):
            true += " (not visible)"
        rows.setdefault(true, {})
        rows[true][s.found[0]] = rows[true].get(s.found[0], 0) + 1
    return rows


def _pct(ok: int, n: int) -> str:
    return "-" if n == 0 else f"{100.0 * ok / n:.0f} % ({ok}/{n})"


def _group(scores: Sequence[ScenarioScore], target: float) -> dict[str, Any]:
    n = len(scores)
    ratios = [s.ratio for s in scores if math.isfinite(s.ratio)]
    shr = [s.shrink for s in scores if math.isfinite(s.shrink)]
    return {"n": n,
            "top": _pct(sum(s.top_correct for s in scores), n),
            "top_or_tie": _pct(sum(s.top_correct or any(e in s.tied for e in s.expected)
                                   for s in scores), n),
            "top_and_joints": _pct(sum(s.top_correct and s.joints_correct for s in scores), n),
            "ratio_ok": _pct(sum(s.ratio <= target for s in scores), n),
            "all_three": _pct(sum(s.success for s in scores), n),
            "median_ratio": float(np.median(ratios)) if ratios else math.nan,
            "median_shrink": float(np.median(shr)) if shr else math.nan}


def summary_rows(result: BenchmarkResult) -> list[dict[str, Any]]:
    """Rows of the summary table: per hidden effect (single scenarios), then totals."""
    t = result.config.ratio_target
    sc = result.scores
    rows = []
    singles = [s for s in sc if s.kind == "single"]
    for e in result.config.effects:
        grp = [s for s in singles if s.hidden == (e,)]
        if grp:
            vis = [s for s in grp if s.excited]
            rows.append({"group": e, "visible": f"{len(vis)}/{len(grp)}", **_group(vis, t)})
    vis = [s for s in singles if s.excited]
    rows.append({"group": "single, visible", "visible": f"{len(vis)}/{len(singles)}",
                 **_group(vis, t)})
    rows.append({"group": "single, all", "visible": f"{len(vis)}/{len(singles)}",
                 **_group(singles, t)})
    nones = [s for s in sc if s.kind == "none"]
    if nones:
        rows.append({"group": "none", "visible": "-", **_group(nones, t)})
    pairs = [s for s in sc if s.kind == "pair"]
    if pairs:
        row = {"group": "pairs", "visible": f"{sum(s.excited for s in pairs)}/{len(pairs)}",
               **_group(pairs, t)}
        row["both_found"] = _pct(sum(s.all_found for s in pairs), len(pairs))
        rows.append(row)
    return rows


def _md_table(header: list[str], rows: list[list[Any]]) -> str:
    def fmt(v: Any) -> str:
        if isinstance(v, float):
            return "-" if not math.isfinite(v) else f"{v:.3g}"
        return str(v)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(fmt(v) for v in r) + " |" for r in rows]
    return "\n".join(lines)


def render_text(result: BenchmarkResult) -> str:
    """Markdown: summary table, confusion matrix, pairs, failures and timings."""
    cfg = result.config
    sc = result.scores
    out = [f"# Blind gap benchmark: {result.model_name}", "",
           f"{len(sc)} scenarios (seed {cfg.seed}), {cfg.poses} poses each "
           f"({cfg.poses_from} poses, {cfg.approach} approach), tracker noise "
           f"{cfg.noise[0]:g}-{cfg.noise[1]:g} per coordinate, MJCF inertias "
           f"{'given' if cfg.use_mjcf else 'not given'} to the diagnosis. Visible: signature "
           f"after registration >= {cfg.excitation_threshold:g} x noise RMS. Target: withheld "
           f"RMS after correction <= {cfg.ratio_target:g} x noise RMS.", "", "## Summary", ""]
    rows = summary_rows(result)
    out.append(_md_table(["group", "visible", "n", "right effect first",
                          "right or reported tie", "+ joints located",
                          f"RMS <= {cfg.ratio_target:g}x noise", "all three", "median ratio",
                          "median shrink", "both found"],
                         [[r["group"], r["visible"], r["n"], r["top"], r["top_or_tie"],
                           r["top_and_joints"],
                           r["ratio_ok"], r["all_three"], r["median_ratio"],
                           r["median_shrink"], r.get("both_found", "")] for r in rows]))
    conf = confusion_matrix(result)
    cols = sorted({c for r in conf.values() for c in r})
    out += ["", "## Confusion matrix (single effect and none; row: hidden, column: named first)",
            "", _md_table(["hidden \\ named", *cols],
                          [[r, *[conf[r].get(c, 0) or "" for c in cols]] for r in sorted(conf)])]
    pairs = [s for s in sc if s.kind == "pair"]
    if pairs:
        out += ["", "## Pairs", "", _md_table(
            ["#", "hidden (SNR)", "named", "both found", "ratio"],
            [[s.index, ", ".join(f"{e} {list(s.hidden_joints[e])} ({s.snr.get(e, 0):.2g})"
                                 for e in s.hidden),
              ", ".join(s.found), s.all_found, s.ratio] for s in pairs])]
    bad = [s for s in sc if not s.success]
    if bad:
        out += ["", "## Scenarios not fully right", "", _md_table(
            ["#", "kind", "hidden [joints] (SNR)", "named [joints]", "ratio", "note"],
            [[s.index, s.kind,
              ", ".join(f"{e} {list(s.hidden_joints[e])} ({s.snr.get(e, 0):.2g})"
                        for e in s.hidden) or "none",
              ", ".join(f"{e} {list(j)}" for e, j in zip(s.found, s.found_joints,
                                                          strict=False)) or "none",
              s.ratio, s.note]
             for s in bad])]
    out += ["", f"Wall time {result.wall_s:.1f} s: simulation {result.sim_s:.1f} s, diagnosis "
            f"{result.diag_s:.1f} s ({result.wall_s / max(len(sc), 1):.2f} s per scenario)."]
    return "\n".join(out) + "\n"


def write_outputs(result: BenchmarkResult, out: str | Path, *, force: bool = False,
                  plots: bool = True) -> list[Path]:
    """Write summary.md, confusion.csv, scenarios.csv, results.json (and confusion.png);
    refuses to replace existing files unless ``force``."""
    out = Path(out)
    targets = [f for f in OUTPUT_FILES if plots or not f.endswith(".png")]
    existing = [f for f in targets if (out / f).exists()]
    if existing and not force:
        raise OutputExistsError(f"--out {out}: {', '.join(existing)} exist(s); pass --force to "
                                "replace")
    out.mkdir(parents=True, exist_ok=True)
    written = []
    p = out / "summary.md"
    p.write_text(render_text(result), encoding="utf-8")
    written.append(p)
    conf = confusion_matrix(result)
    cols = sorted({c for r in conf.values() for c in r})
    p = out / "confusion.csv"
    with open(p, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["hidden", *cols])
        for r in sorted(conf):
            w.writerow([r, *[conf[r].get(c, 0) for c in cols]])
    written.append(p)
    p = out / "scenarios.csv"
    with open(p, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["index", "kind", "hidden", "hidden_joints", "snr", "payload", "found",
                    "found_joints", "top_correct", "tied", "joints_correct", "all_found",
                    "noise_rms", "nominal_rms", "final_rms", "ratio", "shrink", "unexplained",
                    "success", "note", "sim_s", "diag_s"])
        for s in result.scores:
            w.writerow([s.index, s.kind, ";".join(s.hidden) or "none",
                        ";".join(f"{e}:{'/'.join(map(str, j))}"
                                 for e, j in s.hidden_joints.items()),
                        ";".join(f"{e}:{v:.3g}" for e, v in s.snr.items()), s.payload,
                        ";".join(s.found),
                        ";".join("/".join(map(str, j)) for j in s.found_joints),
                        s.top_correct, ";".join(s.tied), s.joints_correct, s.all_found,
                        f"{s.noise_rms:.5g}",
                        f"{s.nominal_rms:.5g}", f"{s.final_rms:.5g}", f"{s.ratio:.4g}",
                        f"{s.shrink:.4g}", s.unexplained, s.success, s.note,
                        f"{s.sim_s:.2f}", f"{s.diag_s:.2f}"])
    written.append(p)
    p = out / "results.json"
    p.write_text(json.dumps(result.to_dict(), indent=1, default=str), encoding="utf-8")
    written.append(p)
    if plots:
        written.append(_plot_confusion(conf, out / "confusion.png"))
    return written


def _plot_confusion(conf: dict[str, dict[str, int]], path: Path) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = sorted(conf)
    cols = sorted({c for r in conf.values() for c in r})
    a = np.array([[conf[r].get(c, 0) for c in cols] for r in rows], dtype=float)
    fig, ax = plt.subplots(figsize=(1.2 + 0.9 * len(cols), 1.0 + 0.45 * len(rows)))
    ax.imshow(a, cmap="Blues")
    ax.set_xticks(range(len(cols)), cols, rotation=40, ha="right")
    ax.set_yticks(range(len(rows)), rows)
    for i in range(len(rows)):
        for j in range(len(cols)):
            if a[i, j]:
                ax.text(j, i, int(a[i, j]), ha="center", va="center",
                        color="white" if a[i, j] > a.max() / 2 else "black")
    ax.set_xlabel("named first by the diagnosis")
    ax.set_ylabel("hidden in the real robot")
    ax.set_title("Blind gap benchmark: confusion matrix")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
