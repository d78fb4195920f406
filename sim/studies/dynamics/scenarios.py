"""The blind benchmark's scenarios (the truth): one hidden dynamic effect (or none) with a
random size scaled to the arm, and the real arm's log.

Sizes are scaled to each joint's torque along the command: T_k = RMS of the nominal model's
torques, and the torque noise is sigma_k = 0.01 T_k + 0.01 N m (a torque sensor or current
measurement of 1 % of its range). Per kind (u: uniform in the range):

* coulomb: u(0.03, 0.15) T_k on joint k; viscous: u(0.03, 0.15) T_k / RMS(qd_k);
* stribeck: u(0.05, 0.2) T_k, v_s = u(0.04, 0.15) rad/s;
* armature: u(0.03, 0.15) T_k / RMS(qdd_k); offset: +-u(0.03, 0.15) T_k;
* payload: u(0.03, 0.1) of the arm's moving mass at the tool point, offset u(-2, 2) cm;
* inertial: one link (not the tool's) +u(10, 30) % mass and a 2 cm shift of its centre;
* none.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mjcf.arm import Arm
from mjcf.inverse import body_params, inverse_dynamics
from sim.studies.dynamics.truth import HiddenDynamics, add_point_mass
from zrp.arrays import F64
from zrp.gap.dynamics.fourier import Fourier, random_fourier

__all__ = ["KINDS", "Scenario", "draw_hidden", "scenario_command"]

KINDS = ("coulomb", "viscous", "stribeck", "armature", "offset", "payload", "inertial", "none")


@dataclass(frozen=True)
class Scenario:
    """One benchmark case: arm, effect kind, seed, log length."""

    arm: str
    kind: str
    seed: int
    seconds: float = 20.0

    @property
    def name(self) -> str:
        return f"{self.arm}_{self.kind}_{self.seed}"


def scenario_command(q0: F64, amplitude: float, seed: int) -> Fourier:
    return random_fourier(q0, amplitude, 1.0, 3.0, seed=seed)


def _joint(arm: Arm, rng: np.random.Generator, scale: F64) -> int:
    """A joint whose torques are not negligible (T_k above 2 % of the largest)."""
    ok = np.flatnonzero(scale > 0.02 * scale.max())
    return int(rng.choice(ok))


def _per_joint(n: int, k: int, v: float) -> F64:
    out = np.zeros(n)
    out[k] = v
    return out


def _inertial(arm: Arm, rng: np.random.Generator) -> dict[int, F64]:
    bodies = [b for b in arm.moving_bodies() if b != arm.tool_body and arm.model.body_mass[b] > 0.2]
    b = int(rng.choice(bodies))
    m = float(arm.model.body_mass[b])
    phi = body_params(arm.model, b)
    c = phi[1:4] / m
    shift = rng.normal(size=3)
    shift *= 0.02 / np.linalg.norm(shift)
    dm = rng.uniform(0.1, 0.3) * m
    # the extra mass as a point mass at c + shift (eq. R1), keeping the link physical
    return {b: add_point_mass(phi, dm, c + shift) - phi}


def draw_hidden(arm: Arm, command: Fourier, kind: str, seed: int
                ) -> tuple[HiddenDynamics, F64, dict]:
    """The hidden effect of a scenario, the torque noise sigma (n,) and a description."""
    rng = np.random.default_rng([seed, 1000 + KINDS.index(kind)])  # joints differ by kind
    t = np.linspace(0.0, 1.0 / command.f0_hz, 2000, endpoint=False)
    q, qd, qdd = command.evaluate(t)
    scale = np.sqrt(np.mean(inverse_dynamics(arm.model, q, qd, qdd) ** 2, axis=0))
    sigma = 0.01 * scale + 0.01
    n = arm.n
    k = _joint(arm, rng, scale)
    rms = lambda x: float(np.sqrt(np.mean(x**2)))  # noqa: E731
    desc: dict = {"kind": kind, "joint": None}
    if kind in ("coulomb", "viscous", "armature", "offset", "stribeck"):
        desc["joint"] = k
    size = rng.uniform(0.03, 0.15) * scale[k]
    if kind == "coulomb":
        h = HiddenDynamics(coulomb=_per_joint(n, k, size))
    elif kind == "viscous":
        h = HiddenDynamics(viscous=_per_joint(n, k, size / rms(qd[:, k])))
    elif kind == "stribeck":
        h = HiddenDynamics(stribeck=_per_joint(n, k, rng.uniform(0.05, 0.2) * scale[k]),
                           stribeck_speed=rng.uniform(0.04, 0.15))
    elif kind == "armature":
        h = HiddenDynamics(armature=_per_joint(n, k, size / rms(qdd[:, k])))
    elif kind == "offset":
        h = HiddenDynamics(offset=_per_joint(n, k, size * rng.choice([-1.0, 1.0])))
    elif kind == "payload":
        moving = float(arm.model.body_mass[arm.moving_bodies()].sum())
        h = HiddenDynamics(payload_kg=rng.uniform(0.03, 0.1) * moving,
                           payload_offset_m=rng.uniform(-0.02, 0.02, 3))
    elif kind == "inertial":
        h = HiddenDynamics(inertial=_inertial(arm, rng))
        desc["body"] = int(next(iter(h.inertial)))
        desc["body_name"] = arm.body_name(desc["body"])
    else:
        h = HiddenDynamics()
    return h, sigma, desc
