"""Blind benchmark, part 3: scoring a diagnosis against the truth (read only afterwards).

* **excitation**: how much of each hidden effect the poses make visible, i.e. the RMS of its
  own tool-point signature after the best registration (instrument frame and tool offsets) has
  absorbed what it can (:func:`effect_signatures`, :func:`registered_rms`), over the noise RMS
  sqrt(3) sigma. Below 1 the effect hides in the noise or in the registration, and the right
  answer is ``none``;
* **effect named first** is the right one; **joints located**; **withheld RMS after
  correction** over the true noise RMS, and the shrink ratio (:func:`score`);
* **interval coverage**: the final 95 % intervals of the hidden effect's parameters against
  the true values (:mod:`sim.studies.benchmark.coverage`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from sim.robot.effects import HiddenEffects, motor_map, true_geometry
from sim.studies.benchmark.coverage import interval_coverage
from sim.studies.benchmark.scenarios import BenchmarkConfig
from zrp.arrays import F64
from zrp.gap.results import DiagnosisRecord, load_diagnosis
from zrp.kinematics.forward import forward_kinematics
from zrp.model.manipulator import Manipulator

__all__ = [
    "JOINT_SPACE",
    "ScenarioScore",
    "effect_signatures",
    "registered_rms",
    "score",
]

JOINT_SPACE = ("joint_offset", "encoder_scale", "cyclic_error", "joint_compliance", "backlash")


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
    """How the diagnosis did on one scenario (see :mod:`sim.studies.benchmark`).

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


@dataclass(frozen=True)
class _Truth:
    """What the scorer reads from the truth file: the hidden effects, their joints and how
    visible each is (registered signature RMS over the noise RMS)."""

    eff: HiddenEffects
    index: int
    kind: str
    hidden: tuple[str, ...]
    joints: dict[str, tuple[int, ...]]
    noise_rms: float
    snr: dict[str, float]
    visible: tuple[str, ...]

    @property
    def expected(self) -> tuple[str, ...]:
        """The visible hidden effects, or ("none",)."""
        return self.visible or ("none",)

    @property
    def accept(self) -> tuple[str, ...]:
        """Effects that are right to name first: the visible ones; with none visible,
        "none" or a hidden effect (found below the excitation threshold: right, not
        required)."""
        return self.expected if self.visible else ("none", *self.hidden)


def _truth(model: Manipulator, truth: dict[str, Any], config: BenchmarkConfig) -> _Truth:
    eff = HiddenEffects.from_dict(truth["effects"])
    scn = truth.get("scenario", {})
    hidden = tuple(scn.get("labels", eff.active))
    noise_rms = math.sqrt(3.0) * float(truth["instrument"]["noise_sigma"])
    snr = {k: v / noise_rms for k, v in effect_signatures(model, truth).items()}
    visible = tuple(e for e in hidden if snr.get(e, 0.0) >= config.excitation_threshold)
    return _Truth(eff, int(scn.get("index", -1)), str(scn.get("kind", "")), hidden,
                  {e: eff.joints(e) for e in hidden}, noise_rms, snr, visible)


def _found(diag: DiagnosisRecord) -> tuple[str, ...]:
    """The effects named, in order ("none" alone if nothing; "refused" for a refusal)."""
    return ("refused",) if diag.error else diag.effects


def _tied(diag: DiagnosisRecord, first: str) -> tuple[str, ...]:
    """Significant candidates of the first step within 1 % of the best cross-validated RMS,
    other than the effect named first."""
    if not diag.steps:
        return ()
    cands = [c for c in diag.steps[0].candidates if c.significant and not math.isnan(c.cv_rms)]
    if not cands:
        return ()
    best = min(c.cv_rms for c in cands)
    return tuple(c.effect for c in cands if c.cv_rms <= 1.01 * best and c.effect != first)


def _joints_located(t: _Truth, found: tuple[str, ...],
                    found_joints: tuple[tuple[int, ...], ...]) -> bool:
    """The joints named for the first acceptable effect found include the injected ones (True
    when nothing was named or the effect has no joints)."""
    if found[0] in ("none", "refused"):
        return True
    for e in t.accept:
        if e in found:
            return set(t.joints[e]) <= set(found_joints[found.index(e)]) if t.joints[e] else True
    return False


def _all_found(t: _Truth, found: tuple[str, ...]) -> bool:
    """Every visible effect was named; with none visible, nothing but hidden effects was."""
    if t.visible:
        return all(e in found for e in t.expected)
    return set(found) <= {"none", *t.hidden}


def _miss_note(t: _Truth, found: tuple[str, ...], tied: tuple[str, ...]) -> str:
    """Why the first effect named is wrong."""
    if found[0] == "none":
        return "missed: nothing significant found"
    lk = f"look-alike: named {found[0]}"
    if any(e in tied for e in t.accept):
        lk += " (the diagnosis reports the hidden effect as fitting equally well)"
    return lk


def _note(t: _Truth, diag: DiagnosisRecord, found: tuple[str, ...], tied: tuple[str, ...],
          verdict: tuple[bool, bool, float], config: BenchmarkConfig) -> str:
    """The scenario's remarks; ``verdict``: (top effect right, joints located, RMS ratio)."""
    top_correct, joints_ok, ratio = verdict
    notes = []
    if diag.error:
        notes.append(f"the diagnosis refused the data: {str(diag.error).split(': ', 1)[-1]}")
    hid = [e for e in t.hidden if e not in t.visible]
    if hid:
        notes.append(f"{', '.join(hid)} not visible (SNR "
                     f"{min(t.snr.get(e, 0.0) for e in hid):.2g})")
    if not diag.error and not top_correct:
        notes.append(_miss_note(t, found, tied))
    elif not diag.error and not joints_ok:
        notes.append("joints not located")
    if ratio > config.ratio_target:
        notes.append(f"withheld RMS {ratio:.2f}x the noise"
                     + (" (the diagnosis says unexplained)" if diag.unexplained else ""))
    return "; ".join(notes)


def _coverage(t: _Truth, diag: DiagnosisRecord) -> dict[str, Any]:
    """The interval-coverage columns (:mod:`sim.studies.benchmark.coverage`)."""
    params = diag.final_parameters
    covered, compared, misses = interval_coverage(t.eff, t.hidden, params)
    eff_cov, eff_cmp, _ = interval_coverage(t.eff, t.hidden, params, "ci95_effect")
    return {"ci_covered": covered, "ci_compared": compared, "ci_misses": misses,
            "ci_effect_all": bool(eff_cmp and eff_cov == eff_cmp)}


def score(model: Manipulator, truth: dict[str, Any],
          diagnosis: DiagnosisRecord | Mapping[str, Any],
          config: BenchmarkConfig) -> ScenarioScore:
    """Judge one diagnosis (read back by :func:`zrp.gap.results.load_diagnosis`, or its JSON
    document) against the truth file's content."""
    diag = diagnosis if isinstance(diagnosis, DiagnosisRecord) else load_diagnosis(diagnosis)
    t = _truth(model, truth, config)
    found = _found(diag)
    found_joints = tuple(s.joints for s in diag.steps)
    tied = _tied(diag, found[0])
    top_correct = found[0] in t.accept
    joints_ok = _joints_located(t, found, found_joints)
    ratio = diag.final_rms / t.noise_rms
    note = _note(t, diag, found, tied, (top_correct, joints_ok, ratio), config)
    values = {"success": bool(top_correct and joints_ok and ratio <= config.ratio_target),
              **_coverage(t, diag)}
    nominal = diag.nominal_rms
    return ScenarioScore(t.index, t.kind, t.hidden, t.joints, t.snr, t.expected, found,
                         found_joints, bool(top_correct), tied, bool(joints_ok),
                         bool(_all_found(t, found)), t.noise_rms, nominal, diag.final_rms,
                         ratio, diag.final_rms / nominal if nominal > 0 else 1.0,
                         diag.unexplained, payload=t.eff.payload, note=note, values=values)
