"""The corrected model: the arm's MJCF with the identified effects written in (the
re-simulation of the logged command through it is :mod:`mjcf.tracking`).

Written into the MJCF: Coulomb friction (``frictionloss``), viscous friction (``damping``),
armature (``armature``), each added to the model's own value; a payload (a child body of the
tool body with an explicit inertial: a point mass at the fitted centre, so that MuJoCo holds
it under ``inertiafromgeom="false"`` too, where a geom's mass is ignored); the resulting
inertial (``mass``, ``ipos``, principal inertias and their frame) of every body the diagnosis
changes, and of no other: link inertias, a link's mass, a modelled part (a hand) not on the
arm, a payload taken away (:attr:`zrp.gap.dynamics.diagnosis.DynamicDiagnosis.bodies`, all
physical). Not written, because MJCF has no place for them: a Stribeck bump, a torque
sensor's offset and gain (they are listed in :attr:`Corrections.not_in_model` and reported).

Every other element keeps the model's values: the text is MuJoCo's writer at full double
precision (:func:`mjcf.xmltext.spec_xml`), so the file reloads to the arm's own model but for
the changes. After compiling, every changed body is checked to be what MuJoCo holds (a
compiler that takes inertias from geoms would silently drop them): else an InputError.

The corrected model's torques are the diagnosis's own prediction (eq. V1,
:func:`zrp.gap.dynamics.prediction.corrected_torques`): ``mj_inverse`` on it gives the model,
the bodies, damping and armature terms; frictionloss (a constraint force in MuJoCo) and what
MJCF cannot hold are the analytic terms (``tests/mjcf/test_corrected_inverse.py``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from mjcf.arm import Arm
from mjcf.inverse import body_params, principal_inertia
from mjcf.tracking import TrackingGap, track_log
from mjcf.xmltext import spec_xml
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.data import TorqueLog
from zrp.gap.dynamics.diagnosis import DynamicDiagnosis
from zrp.gap.dynamics.inertia import add_point_mass
from zrp.output import write_text

__all__ = ["CorrectedMJCF", "Corrections", "corrected_spec", "corrected_xml", "corrections",
           "write_corrected_mjcf"]

#: The smallest mass written for a body (kg): MuJoCo refuses a moving body without mass.
MIN_MASS_KG = 1e-6

#: The smallest principal inertia written for a body (kg m^2): above MuJoCo's mjMINVAL
#: (1e-15), far below any torque it could move.
MIN_INERTIA = 1e-12

#: Relative agreement of a written body with what MuJoCo compiled from it.
HELD_RTOL = 1e-9

#: The name of the identified payload's body.
PAYLOAD_BODY = "identified_payload"

_JOINT_FIELDS = {"coulomb": "frictionloss", "viscous": "damping", "armature": "armature"}
_MOTOR_FIELDS = {"motor_coulomb": 1, "motor_viscous": 2, "motor_armature": 3}


@dataclass(frozen=True)
class Corrections:
    """What goes into the MJCF: per joint additions (n,), the payload, body inertias."""

    frictionloss: F64
    damping: F64
    armature: F64
    payload_kg: float = 0.0
    payload_pos_m: F64 = field(default_factory=lambda: np.zeros(3))
    inertial: dict[int, F64] = field(default_factory=dict)
    not_in_model: list[str] = field(default_factory=list)
    # a coupled motor (0-based) -> (joint-scale direction, frictionloss, damping, armature):
    # a fixed tendon over the joints it turns
    motors: dict[int, tuple[F64, float, float, float]] = field(default_factory=dict)


def _separate_payload(arm: Arm, diag: DynamicDiagnosis) -> tuple[float, F64]:
    """A payload added as a body of its own (mass > 0 and nothing else changes the tool
    body): its mass and position in the tool body's frame; (0, tool point) otherwise."""
    pos = np.array(arm.tool_point, dtype=float)
    e = diag.effect("payload")
    change = diag.bodies.get(arm.tool_body)
    if e is None or e.params["mass"].value <= 0.0 or (change and change.effects != (e.key,)):
        return 0.0, pos
    mass = e.params["mass"].value
    return mass, pos + np.array([e.params[k].value for k in ("m*dx", "m*dy", "m*dz")]) / mass


def corrections(arm: Arm, diag: DynamicDiagnosis) -> Corrections:
    """The model changes of a diagnosis: joint terms added to the model's, a positive
    payload as a body of its own, every other body the effects change (link inertias, a
    link's mass, a part not on the arm, a payload taken away) with its resulting inertial."""
    add = {f: np.zeros(arm.n) for f in _JOINT_FIELDS.values()}
    skipped = []
    motors: dict[int, list] = {}
    for e in diag.effects:
        if e.name in _JOINT_FIELDS and e.joint is not None:
            add[_JOINT_FIELDS[e.name]][e.joint] += e.params[e.name].value
        elif e.name in _MOTOR_FIELDS and e.joint in diag.motors:
            row = motors.setdefault(e.joint, [np.array(diag.motors[e.joint]), 0.0, 0.0, 0.0])
            row[_MOTOR_FIELDS[e.name]] = e.params[e.name].value
        elif e.name not in ("payload", "inertial", "absent_part", "link_mass"):
            skipped.append(e.label)
    payload, pos = _separate_payload(arm, diag)
    # only the bodies the diagnosis changed (every other keeps the model's inertial)
    bodies = {b: c.phi for b, c in diag.bodies.items() if not (payload and b == arm.tool_body)}
    return Corrections(add["frictionloss"], add["damping"], add["armature"], payload, pos,
                       bodies, skipped, {k: tuple(v) for k, v in motors.items()})


def _body_name(m: mujoco.MjModel, b: int) -> str:
    name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b)
    if not name:
        raise InputError(f"model: body {b} has no name; the corrected MJCF needs named bodies")
    return name


def compilable_inertia(w: F64) -> F64:
    """Principal inertias (3,) of a physical body (eq. R5) as MuJoCo's compiler takes them:
    each at least :data:`MIN_INERTIA`, none above the sum of the other two. A physical body
    satisfies both but for rounding; a body on the boundary (a model's own flat link, a
    point mass, a link the log never moves keeps its values to rounding) would otherwise be
    refused ("inertia must satisfy A + B >= C"). The change is of the order of rounding."""
    w = np.maximum(np.asarray(w, dtype=float), MIN_INERTIA)
    for i in range(3):
        others = w[(i + 1) % 3] + w[(i + 2) % 3]
        w[i] = min(w[i], others)
    return w


def _set_inertial(body: mujoco.MjsBody, phi: F64) -> None:
    """Write phi_b (eq. R1) as mass, centre, principal inertias and their frame."""
    mass = max(float(phi[0]), MIN_MASS_KG)  # a link emptied of its mass stays compilable
    c, quat, w = principal_inertia(phi, mass)
    w = compilable_inertia(w)
    body.explicitinertial = True
    body.mass = mass
    body.ipos = c
    body.iquat = quat
    body.inertia = w
    body.fullinertia = [np.nan, 0.0, 0.0, 0.0, 0.0, 0.0]  # "not given" (the default)


def _add_motors(spec: mujoco.MjSpec, arm: Arm, fix: Corrections) -> None:
    """Each coupled motor as a fixed tendon over the joints it turns (length g . q): its
    damping, armature and frictionloss act on the motor's velocity g . qd and reach every
    joint it turns through g, as the diagnosis's motor effects do."""
    for k, (g, friction, damping, armature) in sorted(fix.motors.items()):
        t = spec.add_tendon(name=f"identified_motor{k + 1}")
        for j, coef in enumerate(g):
            if coef != 0.0:
                t.wrap_joint(arm.joint_names[j], float(coef))
        t.frictionloss = float(friction)
        d = np.array(t.damping, dtype=float).ravel()  # MuJoCo 4: [linear, higher...]
        d[0] = damping
        t.damping = d
        t.armature = float(armature)


def corrected_spec(arm: Arm, fix: Corrections) -> mujoco.MjSpec:
    """A copy of the arm's spec with ``fix`` written in (module docstring)."""
    spec = arm.spec.copy()
    m = arm.model
    for k, name in enumerate(arm.joint_names):
        j = spec.joint(name)
        j.frictionloss = float(m.dof_frictionloss[k] + fix.frictionloss[k])
        damping = np.array(j.damping, dtype=float).ravel()  # MuJoCo 4: [linear, higher...]
        damping[0] = m.dof_damping[k] + fix.damping[k]
        j.damping = damping
        j.armature = float(m.dof_armature[k] + fix.armature[k])
    for b, phi in fix.inertial.items():
        _set_inertial(spec.body(_body_name(m, b)), phi)
    _add_motors(spec, arm, fix)
    if fix.payload_kg > 0.0:
        tool = spec.body(_body_name(m, arm.tool_body))
        load = tool.add_body(name=PAYLOAD_BODY, pos=list(fix.payload_pos_m))
        # a point mass, the diagnosis's payload: an explicit inertial (a geom's mass is
        # ignored under inertiafromgeom="false"); the sphere only shows it (massless, no
        # collisions)
        load.explicitinertial = True
        load.mass = fix.payload_kg
        load.ipos = [0.0, 0.0, 0.0]
        load.inertia = [0.0, 0.0, 0.0]
        load.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.005, 0.0, 0.0], mass=0.0,
                      contype=0, conaffinity=0, group=3)
    return spec


def _held(arm: Arm, fix: Corrections, m: mujoco.MjModel) -> None:
    """Check that the compiled corrected model holds what was written, and the model's own
    inertial on every other moving body (module docstring)."""
    for b in arm.moving_bodies():
        name = _body_name(arm.model, b)
        want = fix.inertial.get(b, arm.body_params(b))
        if b == arm.tool_body and fix.payload_kg > 0.0:
            want = add_point_mass(want, fix.payload_kg, fix.payload_pos_m)
        cb = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
        got = body_params(m, cb) if cb >= 0 else np.full(10, np.nan)
        pb = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, PAYLOAD_BODY)
        if b == arm.tool_body and pb >= 0:  # not fused into the tool body
            got = add_point_mass(got, float(m.body_mass[pb]), np.array(m.body_pos[pb]))
        scale = max(float(np.abs(want).max()), MIN_MASS_KG)
        if not np.allclose(got, want, rtol=0.0, atol=HELD_RTOL * scale + 2 * MIN_MASS_KG):
            raise InputError(
                f"corrected model: MuJoCo does not hold the inertial of body {name!r} "
                f"(mass {got[0]:.6g} kg compiled, {want[0]:.6g} kg meant): the model's "
                "compiler settings override it (inertiafromgeom=\"true\", or the body fused "
                "away); set inertiafromgeom=\"auto\" in the model")


def corrected_xml(arm: Arm, fix: Corrections) -> str:
    """The corrected MJCF text, checked to hold ``fix`` (module docstring)."""
    spec = corrected_spec(arm, fix)
    try:
        m = spec.compile()
    except ValueError as exc:
        raise InputError(f"corrected model: MuJoCo cannot compile it: {exc}") from exc
    _held(arm, fix, m)
    return spec_xml(spec)


def write_corrected_mjcf(arm: Arm, diag: DynamicDiagnosis, path: str | os.PathLike[str], *,
                         overwrite: bool = False) -> Path:
    """Write the corrected MJCF (loads in MuJoCo as is); an existing file only with
    ``overwrite``."""
    return write_text(path, corrected_xml(arm, corrections(arm, diag)), overwrite=overwrite)


@dataclass(frozen=True)
class CorrectedMJCF:
    """The corrected model of a MuJoCo arm, as :func:`zrp.gap.dynamics.run.run_dynamics`
    asks for it (:class:`zrp.gap.dynamics.run.ModelWriter`): the MJCF text and the
    re-simulation of the logged command through it."""

    arm: Arm

    def corrected_model(self, diag: DynamicDiagnosis) -> tuple[str, list[str]]:
        """The MJCF text of the model with the diagnosis written in (:mod:`mjcf.corrected`)
        and what it holds, in words."""
        fix = corrections(self.arm, diag)
        text = corrected_xml(self.arm, fix)
        held = ["frictionloss, damping, armature"]
        held += ["an identified payload body"] if fix.payload_kg else []
        held += [f"the inertial of {', '.join(self.arm.body_name(b) for b in fix.inertial)}"
                 ] if fix.inertial else []
        motors = ", ".join(f"motor {k + 1}" for k in fix.motors)
        held += [f"a fixed tendon per coupled motor ({motors}: its frictionloss, damping and "
                 "armature)"] if fix.motors else []
        notes = [f"corrected.xml: the model with {'; '.join(held)}."]
        if fix.not_in_model:
            notes.append(f"not in MJCF (report only): {', '.join(fix.not_in_model)}")
        return text, notes

    def track(self, corrected_xml: str, log: TorqueLog, *, kp: F64 | None = None,
              kv: F64 | None = None, seconds: float | None = None) -> TrackingGap | None:
        """The logged command re-simulated through the model and ``corrected_xml``
        (:func:`mjcf.tracking.track_log`)."""
        return track_log(self.arm, corrected_xml, log, kp=kp, kv=kv, seconds=seconds)
