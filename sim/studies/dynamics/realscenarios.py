"""The scenarios of the blind benchmark on real-looking logs (the truth): what the simulated
real arm has that its shipped model has not, and how its controller writes the log.

Arms (:data:`REAL_ARMS`), each with its own inertias: the Franka Panda (example-robot-data's
URDF, with its hand, 0.76 kg with the fingers), the Unitree Z1 (example-robot-data's URDF, with
its gripper, 0.80 kg), the Menagerie UR5e (MJCF, no hand) and the PUMA 560 (ZRP model with the
literature inertias, no hand).

Kinds (combinations joined by ``+``):

* ``hand``: the model's hand is not on the real arm. The truth is the shipped model with the
  hand's links deleted from the file (:func:`arm_without`): its tool link's inertial
  parameters minus the model's are the change (a negative mass of the hand's at its centre);
* ``gravity``: a posture-dependent gravity error: one link among those of joints 2 to 4 (mass
  above 0.3 kg) is 20 % heavier, the extra mass 3 cm off its centre (a point mass, eq. R1);
* ``none``: nothing hidden (what the log's defects and the simulator alone leave);
* ``friction``: on each of the last three joints, Coulomb friction F_c = u(0.01, 0.03) max_j
  T_j and viscous friction u(0.3, 1) F_c / RMS(qd_k) (T_j: RMS of joint j's nominal torques;
  a wrist's friction is set by its gear, not by the small torques its links need).

The torque noise is sigma_k = 0.01 T_k + 0.01 N m as in :mod:`sim.studies.dynamics.scenarios`.
Each scenario says which log defects its controller has (:class:`~sim.studies.dynamics.reallog.
LogDefects`); its second log (validation) is the same arm along another excitation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mjcf.arm import Arm, load_arm
from mjcf.inverse import body_params, inverse_dynamics
from mjcf.shipped import example_robot_data_root, load_shipped_spec
from sim.studies.dynamics.arms import BENCH_ARMS
from sim.studies.dynamics.reallog import LogDefects
from sim.studies.dynamics.scenarios import scenario_command
from sim.studies.dynamics.truth import HiddenDynamics, add_point_mass
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.dynamics.fourier import Fourier

__all__ = ["REAL_ARMS", "RealArm", "RealScenario", "arm_without", "draw_truth", "erd_file"]


@dataclass(frozen=True)
class RealArm:
    """A benchmark arm: how to load its shipped model, its URDF (relative to
    example-robot-data's robots folder) and hand when it has one, a posture, an amplitude."""

    key: str
    load: Callable[[], Arm]
    q0: tuple[float, ...]
    amplitude_rad: float
    urdf: str | None = None
    end_link: str | None = None
    hand: str | None = None

    @property
    def q0_array(self) -> F64:
        return np.array(self.q0)


def erd_file(rel: str) -> Path:
    """A file of example-robot-data's robots folder."""
    root = example_robot_data_root()
    if root is None:
        raise InputError("example-robot-data not found (pip install pin example-robot-data)")
    return root / rel


def _z1() -> Arm:
    return load_arm(erd_file(REAL_ARMS["z1"].urdf or ""), end_link="link06", name="z1")


def _bench(key: str, **kw) -> RealArm:
    b = BENCH_ARMS[key]
    return RealArm(key, b.load, b.q0, b.amplitude_rad, **kw)


REAL_ARMS = {
    "panda": _bench("panda", urdf="panda_description/urdf/panda.urdf", end_link="panda_link8",
                    hand="panda_hand"),
    "z1": RealArm("z1", _z1, (0.0, 1.0, -1.0, 0.0, 0.0, 0.0), 0.4,
                  urdf="z1_description/urdf/z1.urdf", end_link="link06", hand="gripperStator"),
    "ur5e": _bench("ur5e"),
    "puma": _bench("puma"),
}


def arm_without(real: RealArm) -> Arm:
    """The arm as it really is: the shipped URDF with the hand's links (the hand body and
    its subtree) deleted, loaded as the model is (same end link, static links fused)."""
    if real.urdf is None or real.hand is None:
        raise InputError(f"{real.key}: the model has no hand to take away")
    spec = load_shipped_spec(erd_file(real.urdf))
    spec.delete(spec.body(real.hand))  # with its subtree: the fingers and their joints
    spec.compiler.fusestatic = True
    return load_arm(spec, name=f"{real.key} without its hand")


@dataclass(frozen=True)
class RealScenario:
    """One case: arm, kind (``hand``, ``gravity``, ``friction`` or a ``+`` combination),
    seed, log length, the controller's log defects, and the second log's seed."""

    arm: str
    kind: str
    seed: int
    seconds: float = 20.0
    defects: LogDefects = field(default_factory=LogDefects)

    @property
    def name(self) -> str:
        tag = "clean" if self.defects.clean else f"real-{self.defects.naming}"
        return f"{self.arm}_{self.kind.replace('+', '-')}_{tag}_{self.seed}"

    @property
    def parts(self) -> tuple[str, ...]:
        return tuple(self.kind.split("+"))

    def command(self, second: bool = False) -> Fourier:
        real = REAL_ARMS[self.arm]
        return scenario_command(real.q0_array, real.amplitude_rad,
                                self.seed + (7919 if second else 0))


def torque_scale(arm: Arm, command: Fourier) -> tuple[F64, F64]:
    """T_k (RMS of the nominal torques along one period) and RMS(qd_k)."""
    t = np.linspace(0.0, 1.0 / command.f0_hz, 2000, endpoint=False)
    q, qd, qdd = command.evaluate(t)
    tau = inverse_dynamics(arm.model, q, qd, qdd)
    return np.sqrt(np.mean(tau**2, axis=0)), np.sqrt(np.mean(qd**2, axis=0))


def _hand(real: RealArm, arm: Arm) -> tuple[dict[int, F64], dict]:
    true = arm_without(real)
    b = arm.tool_body
    name = arm.body_name(b)
    tb = [i for i in true.moving_bodies() if true.body_name(i) == name]
    if len(tb) != 1:
        raise InputError(f"{real.key}: the tool link {name!r} is not in the model without hand")
    dphi = body_params(true.model, tb[0]) - arm.body_params(b)
    c = dphi[1:4] / dphi[0]  # the hand's centre (the change is minus the hand)
    return {b: dphi}, {"hand": real.hand, "hand_kg": float(-dphi[0]), "link": name,
                       "hand_centre_m": c.tolist()}


def _gravity(arm: Arm, rng: np.random.Generator) -> tuple[dict[int, F64], dict]:
    m = arm.model
    bodies = [int(m.jnt_bodyid[k]) for k in range(1, min(4, arm.n))]
    bodies = [b for b in bodies if m.body_mass[b] > 0.3 and b != arm.tool_body]
    b = int(rng.choice(bodies))
    phi = arm.body_params(b)
    mass = float(phi[0])
    shift = rng.normal(size=3)
    shift *= 0.03 / np.linalg.norm(shift)
    point = phi[1:4] / mass + shift
    return ({b: add_point_mass(phi, 0.2 * mass, point) - phi},
            {"link": arm.body_name(b), "dmass_kg": 0.2 * mass, "at_m": point.tolist()})


def _friction(n: int, scale: F64, qd_rms: F64, rng: np.random.Generator
              ) -> tuple[F64, F64, dict]:
    joints = list(range(n - 3, n))
    coulomb, viscous = np.zeros(n), np.zeros(n)
    top = float(scale.max())
    for k in joints:
        coulomb[k] = rng.uniform(0.01, 0.03) * top
        viscous[k] = rng.uniform(0.3, 1.0) * coulomb[k] / qd_rms[k]
    return coulomb, viscous, {"joints": joints, "coulomb_nm": coulomb[joints].tolist(),
                              "viscous_nms": viscous[joints].tolist()}


def draw_truth(sc: RealScenario, arm: Arm) -> tuple[HiddenDynamics, F64, dict]:
    """The hidden effects of ``sc`` on ``arm`` (its nominal model), the torque noise sigma
    (n,) and a description (module docstring)."""
    real = REAL_ARMS[sc.arm]
    rng = np.random.default_rng([sc.seed, 4242])
    scale, qd_rms = torque_scale(arm, sc.command())
    sigma = 0.01 * scale + 0.01
    inertial: dict[int, F64] = {}
    desc: dict = {"kind": sc.kind}
    coulomb, viscous = np.zeros(arm.n), np.zeros(arm.n)
    for part in sc.parts:
        if part == "hand":
            dphi, desc["hand"] = _hand(real, arm)
        elif part == "gravity":
            dphi, desc["gravity"] = _gravity(arm, rng)
        elif part == "friction":
            coulomb, viscous, desc["friction"] = _friction(arm.n, scale, qd_rms, rng)
            continue
        elif part == "none":
            continue
        else:
            raise InputError(f"kind: unknown part {part!r} (hand, gravity, friction, none)")
        for b, d in dphi.items():
            inertial[b] = inertial.get(b, np.zeros(10)) + d
    return HiddenDynamics(coulomb=coulomb, viscous=viscous, inertial=inertial), sigma, desc
