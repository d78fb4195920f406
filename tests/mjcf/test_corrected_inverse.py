"""The corrected MJCF reproduces the diagnosis's corrected torques (issue 43, item 5).

For each arm a log is simulated with hidden effects (friction, armature, a torque offset, a
payload off the tool point, a link heavier than modelled), diagnosed, and its corrected.xml
(:meth:`mjcf.corrected.CorrectedMJCF.corrected_model`) loaded in MuJoCo. Along the log's
states, what that file's torques are must equal the diagnosis's own corrected prediction
tau0 + eq. V1 (:func:`zrp.gap.dynamics.prediction.corrected_torques`) to rounding.

Like with like: ``mj_inverse`` (constraints off) on corrected.xml gives M(q) qdd + bias -
passive, i.e. the rigid bodies as written (every changed inertial, the payload body), the
``damping`` (a passive force) and the ``armature`` (in M). It does not give ``frictionloss``:
in MuJoCo that is a constraint force, solved in the forward dynamics, not a smooth law of qd.
The diagnosis's Coulomb friction is c tanh(qd / v) (v = V_EPS, or the soft sign's v_c), so
the friction is added here analytically: the file's ``frictionloss`` is checked to be the
model's plus every Coulomb term found on the joint, and its torque is the model's
frictionloss times tanh(qd / V_EPS) (as in tau0) plus each term's own law. What MJCF cannot
hold (a Stribeck bump, a torque offset, a gain: the report's "not in MJCF") is added from its
law and fitted value, written out here, not taken from the diagnosis's columns.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from mjcf.arm import load_arm
from mjcf.corrected import (
    CorrectedMJCF,
    Corrections,
    compilable_inertia,
    corrected_xml,
    corrections,
)
from mjcf.inverse import body_params
from sim.studies.dynamics.truth import HiddenDynamics, simulate
from zrp.errors import InputError
from zrp.gap.dynamics.diagnosis import (
    DynamicsOptions,
    decimated_states,
    diagnose_dynamics,
    model_torques,
)
from zrp.gap.dynamics.fourier import random_fourier
from zrp.gap.dynamics.inertia import V_EPS, add_point_mass
from zrp.gap.dynamics.prediction import corrected_torques

#: Agreement of corrected.xml's torques with the diagnosis's prediction, relative to each
#: joint's largest torque along the log.
RTOL = 1e-6

#: A 4R arm whose last link carries a hand (its own body and explicit inertial), with two
#: finger slides under it when FINGERS is in; inertials explicit (a geom's mass is ignored).
ARM_XML = """<mujoco model="hand_arm">
  <compiler angle="radian" inertiafromgeom="false"/>
  <worldbody>
    <body name="link1" pos="0 0 0.3">
      <joint name="j1" axis="0 0 1"/>
      <inertial pos="0 0 0.05" mass="3" diaginertia="0.02 0.02 0.01"/>
      <geom type="capsule" size="0.04" fromto="0 0 0 0 0 0.1"/>
      <body name="link2" pos="0 0 0.1">
        <joint name="j2" axis="0 1 0"/>
        <inertial pos="0.15 0 0" mass="2.5" diaginertia="0.005 0.03 0.03"/>
        <geom type="capsule" size="0.035" fromto="0 0 0 0.3 0 0"/>
        <body name="link3" pos="0.3 0 0">
          <joint name="j3" axis="0 1 0"/>
          <inertial pos="0.12 0 0.01" quat="0.99 0 0.1 0" mass="1.5"
                    diaginertia="0.003 0.015 0.014"/>
          <geom type="capsule" size="0.03" fromto="0 0 0 0.25 0 0"/>
          <body name="link4" pos="0.25 0 0">
            <joint name="j4" axis="1 0 0"/>
            <inertial pos="0.03 0 0" mass="0.6" diaginertia="0.001 0.0008 0.0008"/>
            <geom type="cylinder" size="0.03 0.03" pos="0.03 0 0"/>
            <body name="hand" pos="0.07 0 0">
              <inertial pos="0.03 0.005 0" mass="0.7" diaginertia="0.0012 0.001 0.0009"/>
              <geom type="box" size="0.03 0.04 0.02" pos="0.03 0 0"/>
              FINGERS
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""

FINGERS = """<body name="left_finger" pos="0.07 0.01 0">
                <joint name="f1" type="slide" axis="0 1 0" range="0 0.04"/>
                <inertial pos="0.02 0 0" mass="0.05" diaginertia="1e-5 1e-5 1e-5"/>
                <geom type="box" size="0.02 0.005 0.01" pos="0.02 0 0"/>
              </body>
              <body name="right_finger" pos="0.07 -0.01 0">
                <joint name="f2" type="slide" axis="0 -1 0" range="0 0.04"/>
                <inertial pos="0.02 0 0" mass="0.05" diaginertia="1e-5 1e-5 1e-5"/>
                <geom type="box" size="0.02 0.005 0.01" pos="0.02 0 0"/>
              </body>"""

Q0_HAND = (0.0, -0.6, 1.0, 0.0)


def _hand_arm(tmp_path, fingers: bool):
    path = tmp_path / ("fingers.xml" if fingers else "hand.xml")
    path.write_text(ARM_XML.replace("FINGERS", FINGERS if fingers else ""), encoding="utf-8")
    return load_arm(path, name=path.stem)


def _bench(key: str):
    from sim.studies.dynamics.arms import BENCH_ARMS

    bench = BENCH_ARMS[key]
    try:
        arm = bench.load()
    except (ImportError, InputError) as exc:  # optional assets
        pytest.skip(f"{key}: {exc}")
    return arm, bench.q0_array, np.full(arm.n, bench.amplitude_rad)


def _arm(key: str, tmp_path):
    if key in ("hand", "fingers"):
        arm = _hand_arm(tmp_path, key == "fingers")
        q0 = np.array([*Q0_HAND, *((0.02, 0.02) if key == "fingers" else ())])
        amp = np.array([0.6] * 4 + [0.015] * (arm.n - 4))
        return arm, q0, amp
    return _bench(key)


def _hidden(arm, n: int) -> HiddenDynamics:
    """Friction (Coulomb and viscous), armature, an offset, a payload off the tool point and
    a link 30 % heavier with its centre 2 cm off: every kind of term of eq. V1."""
    z = np.zeros(n)
    coulomb, viscous, armature, offset = z.copy(), z.copy(), z.copy(), z.copy()
    coulomb[1], viscous[2], armature[0], offset[3] = 1.0, 0.8, 0.3, 0.4
    link = arm.moving_bodies()[2]
    phi = body_params(arm.model, link)
    c = phi[1:4] / phi[0] + np.array([0.02, 0.0, 0.0])
    return HiddenDynamics(coulomb=coulomb, viscous=viscous, armature=armature, offset=offset,
                          payload_kg=1.0, payload_offset_m=np.array([0.02, -0.01, 0.03]),
                          inertial={link: add_point_mass(np.zeros(10), 0.3 * phi[0], c)})


def _mj_inverse(m: mujoco.MjModel, q, qd, qdd) -> np.ndarray:
    """qfrc_inverse along the states, constraints (frictionloss, limits) off."""
    m.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONSTRAINT)
    d = mujoco.MjData(m)
    out = np.empty(q.shape)
    for i in range(q.shape[0]):
        d.qpos[:], d.qvel[:], d.qacc[:] = q[i], qd[i], qdd[i]
        mujoco.mj_inverse(m, d)
        out[i] = d.qfrc_inverse
    return out


def _speed(detail: str, key: str, default: float) -> float:
    """The speed of a smooth law from an effect's detail ("v_c=0.05 rad/s")."""
    for part in detail.split(","):
        name, _, value = part.strip().partition("=")
        if name == key:
            return float(value.split()[0])
    return default


def _analytic(diag, arm, m_fixed: mujoco.MjModel, qd, tau_nominal) -> tuple[np.ndarray, list]:
    """The terms mj_inverse does not give (module docstring), from their laws, and the labels
    of the effects added that MJCF cannot hold."""
    n = arm.n
    coulomb0 = arm.joint_terms()[0]
    out = coulomb0 * np.tanh(qd / V_EPS)
    found_fl = np.zeros(n)
    outside = []
    for e in diag.effects:
        k, value = e.joint, next(iter(e.params.values())).value
        if e.name == "coulomb":
            found_fl[k] += value
            out[:, k] += value * np.tanh(qd[:, k] / _speed(e.detail, "v_c", V_EPS))
        elif e.name == "stribeck":
            vs = _speed(e.detail, "v_s", np.nan)
            out[:, k] += value * np.tanh(qd[:, k] / V_EPS) * np.exp(-(qd[:, k] / vs) ** 2)
            outside.append(e.label)
        elif e.name == "offset":
            out[:, k] += value
            outside.append(e.label)
        elif e.name == "gain":
            out[:, k] += value * tau_nominal[:, k]
            outside.append(e.label)
    # the file's frictionloss is the model's plus what was found
    np.testing.assert_allclose(m_fixed.dof_frictionloss, coulomb0 + found_fl, rtol=1e-12,
                               atol=1e-12)
    return out, outside


def _states(arm, log, diag):
    s, stride = decimated_states(log, DynamicsOptions(window_s=diag.window_s))
    return s, model_torques(arm, log, s, stride)


@pytest.mark.parametrize("key", ["ur5e", "puma", "panda", "hand", "fingers"])
def test_corrected_mjcf_reproduces_the_corrected_torques(key, tmp_path):
    arm, q0, amp = _arm(key, tmp_path)
    n = arm.n
    cmd = random_fourier(q0, amp, 1.0, 3.0, seed=5)
    log = simulate(arm, _hidden(arm, n), cmd, 7.0, noise_nm=np.full(n, 0.05), seed=1)
    diag = diagnose_dynamics(arm, log)
    xml, notes = CorrectedMJCF(arm).corrected_model(diag)
    m = mujoco.MjModel.from_xml_string(xml)
    s, tau0 = _states(arm, log, diag)
    predicted = tau0 + corrected_torques(arm, diag, s.q, s.qd, s.qdd, tau0)
    analytic, outside = _analytic(diag, arm, m, s.qd, tau0)
    got = _mj_inverse(m, s.q, s.qd, s.qdd) + analytic
    scale = np.abs(predicted).max(axis=0)
    assert np.all(np.abs(got - predicted) <= RTOL * scale), np.abs(got - predicted).max(0)
    # what was added analytically is what the report says MJCF cannot hold
    said = next((x for x in notes if x.startswith("not in MJCF")), "")
    assert sorted(outside) == sorted(corrections(arm, diag).not_in_model)
    assert outside and all(x in said for x in outside)
    # the log's payload and link mass reached the file (else the check above is about little)
    assert diag.bodies and m.body_mass.sum() > arm.model.body_mass.sum() + 0.9
    # and the corrected model is far from the nominal one along the log
    nominal = _mj_inverse(arm.model, s.q, s.qd, s.qdd) + analytic
    assert np.abs(nominal - predicted).max() > 1e3 * RTOL * scale.max()


@pytest.mark.parametrize("key", ["hand", "fingers"])
def test_the_payload_sits_on_the_tool_body_with_an_explicit_inertial(key, tmp_path):
    """inertiafromgeom="false": the payload body carries its own inertial (a geom's mass
    would be ignored), on the hand's link, never on a finger."""
    arm = _hand_arm(tmp_path, key == "fingers")
    assert arm.body_name(arm.tool_body) == ("hand" if key == "fingers" else "link4")
    fix = Corrections(np.zeros(arm.n), np.zeros(arm.n), np.zeros(arm.n), 0.8,
                      np.array([0.05, 0.0, 0.01]))
    m = mujoco.MjModel.from_xml_string(corrected_xml(arm, fix))
    b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "identified_payload")
    assert m.body_mass[b] == 0.8
    assert mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, m.body_parentid[b]) == \
        arm.body_name(arm.tool_body)
    np.testing.assert_array_equal(m.body_pos[b], [0.05, 0.0, 0.01])


def test_a_compiler_that_drops_the_inertial_is_refused(tmp_path):
    """A model whose inertias come from geoms (inertiafromgeom="true") would drop a written
    inertial while the report says the MJCF holds it: refused, saying so."""
    path = tmp_path / "geoms.xml"
    path.write_text(ARM_XML.replace("FINGERS", "").replace('inertiafromgeom="false"',
                                                            'inertiafromgeom="true"'))
    arm = load_arm(path)
    phi = arm.body_params(2) * 1.2
    fix = Corrections(np.zeros(4), np.zeros(4), np.zeros(4), inertial={2: phi})
    with pytest.raises(InputError, match="does not hold the inertial of body 'link2'"):
        corrected_xml(arm, fix)


def _compiled_fields(m: mujoco.MjModel) -> dict[str, np.ndarray]:
    fields = ("body_pos", "body_quat", "body_parentid", "geom_size", "geom_pos", "geom_quat",
              "geom_type", "jnt_axis", "jnt_pos", "jnt_range", "dof_frictionloss",
              "dof_armature")
    return {f: np.array(getattr(m, f)) for f in fields}


@pytest.mark.parametrize("key", ["ur5e", "puma", "panda", "hand"])
def test_only_the_changed_bodies_change(key, tmp_path):
    """A log with a heavier link and viscous friction: the corrected model differs from the
    arm's own only in the inertials the diagnosis changed (and a payload body when it found
    one) and that joint's damping, every other value identical (full precision, not
    MuJoCo's 6 digits; a mesh geom's frame to rounding)."""
    arm, q0, amp = _arm(key, tmp_path)
    n = arm.n
    link = arm.moving_bodies()[2]
    phi = body_params(arm.model, link)
    viscous = np.zeros(n)
    viscous[1] = 1.0
    hidden = HiddenDynamics(viscous=viscous, inertial={link: add_point_mass(
        np.zeros(10), 0.3 * phi[0], phi[1:4] / phi[0] + np.array([0.0, 0.02, 0.0]))})
    log = simulate(arm, hidden, random_fourier(q0, amp, 1.0, 3.0, seed=5), 6.0,
                   noise_nm=np.full(n, 0.05), seed=1)
    diag = diagnose_dynamics(arm, log)
    assert "inertial" not in {e.name for e in diag.effects}, [e.key for e in diag.effects]
    m = mujoco.MjModel.from_xml_string(CorrectedMJCF(arm).corrected_model(diag)[0])
    m0 = mujoco.MjModel.from_xml_path(str(tmp_path / "hand.xml")) if key == "hand" else \
        _arm(key, tmp_path)[0].model  # the arm as loaded, never used
    assert diag.bodies  # the heavier link (or a payload for it): else nothing is tested
    payload = ["identified_payload"] if corrections(arm, diag).payload_kg else []
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_BODY, b) for b in range(m.nbody)]
    assert names == [arm.body_name(b) for b in range(m0.nbody)] + payload
    changed = {b for b in range(1, m0.nbody) if np.any(body_params(m, b) != body_params(m0, b))}
    assert changed == set(diag.bodies) - ({arm.tool_body} if payload else set())
    before, after = _compiled_fields(m0), _compiled_fields(m)
    for f, v in before.items():
        if f.startswith("geom"):  # a mesh's frame is recomputed from its vertices
            np.testing.assert_allclose(after[f][:len(v)], v, rtol=1e-13, atol=1e-15, err_msg=f)
        else:  # the payload's body and geom come last
            np.testing.assert_array_equal(after[f][:len(v)], v, err_msg=f)
    damping = np.array(m0.dof_damping)
    damping[1] += diag.effect("viscous", 1).params["viscous"].value
    np.testing.assert_array_equal(m.dof_damping, damping)


def test_a_joint_that_never_moves_still_compiles():
    """Issue 41 finding 7: joint 1 of the PUMA never moves; its link (on the triangle
    inequality's boundary in the model) keeps its values to rounding in the link fit, and
    corrected.xml must still pass MuJoCo's inertia check."""
    from sim.studies.dynamics.scenarios import draw_hidden

    arm, q0, amp = _bench("puma")
    amp[0] = 0.0
    cmd = random_fourier(q0, amp, 1.0, 3.0, seed=3)
    hidden, sigma, _ = draw_hidden(arm, cmd, "inertial", 2)
    log = simulate(arm, hidden, cmd, 6.0, noise_nm=sigma, seed=1)
    diag = diagnose_dynamics(arm, log, DynamicsOptions(effects=("inertial",)))
    assert diag.effects[0].name == "inertial" and 1 in diag.bodies
    m = mujoco.MjModel.from_xml_string(CorrectedMJCF(arm).corrected_model(diag)[0])
    for b in diag.bodies:
        np.testing.assert_allclose(body_params(m, b), diag.bodies[b].phi, rtol=0,
                                   atol=1e-9 * np.abs(diag.bodies[b].phi).max())


def test_compilable_inertia_moves_only_rounding():
    flat = np.array([0.175, 0.175, 0.35 * (1 + 1e-13)])  # A + B < C by rounding
    w = compilable_inertia(flat)
    assert w[0] + w[1] >= w[2] and np.all(w > 0)
    np.testing.assert_allclose(w, flat, rtol=1e-12)
    np.testing.assert_array_equal(compilable_inertia(np.array([1.0, 2.0, 2.5])), [1, 2, 2.5])
