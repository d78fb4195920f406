"""Blind benchmark, part 1: the configuration and the scenarios it draws (the truth).

Scenario i draws from its own generator (child i of ``SeedSequence(seed)``), so the first
scenarios are the same whatever their number: none, one or two hidden effects with random
magnitudes, a payload, the tracker noise. A :class:`Scenario` IS the truth; it goes to the
simulation (:mod:`sim.studies.benchmark.blind`) and to the scorer, never to the diagnosis.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sim.robot.effects import EFFECT_NAMES, HiddenEffects, default_tool_points
from sim.robot.measurement import TRACKER_NOISE_RANGE_MM
from sim.robot.model import RealRobotOptions
from sim.robot.real import RealRobot
from zrp.errors import InputError
from zrp.kinematics.sampling import default_limits
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit, units_per_mm

__all__ = [
    "DEFAULT_NOISE_MM",
    "KINDS",
    "BenchmarkConfig",
    "Scenario",
    "draw_scenarios",
    "pose_limits",
    "typical_gravity_torque",
]

F64 = NDArray[np.float64]
KINDS = ("none", "single", "pair")
#: The default range of the tracker noise sigma per coordinate, mm (a laser tracker's 10-30 um).
DEFAULT_NOISE_MM = TRACKER_NOISE_RANGE_MM


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
        effects: effects to draw from (names of :data:`sim.robot.effects.EFFECT_NAMES`).
        noise: range of the tracker noise sigma per coordinate, model length unit; None (the
            default): :data:`DEFAULT_NOISE_MM`, 0.01-0.03 mm expressed in the model's unit
            (a model in metres gets 1e-5-3e-5, not 10-30 mm), see :meth:`noise_range`.
        poses_from: "random" (random reachable poses) or "circle" (the PUMA's circle).
        approach: "random", "gravity" or "order" (see :class:`sim.robot.measurement.Procedure`).
        payload_probability: chance that a scenario carries a payload (0.5-3 kg, known: it is
            logged in the ``load`` column).
        use_mjcf: give the diagnosis the nominal MJCF (inertias for the gravity torques).
        excitation_threshold: an effect counts as visible when its registered signature RMS
            is at least this multiple of the noise RMS.
        ratio_target: withheld RMS after correction / noise RMS regarded as success.
        reflectors: reflectors on the tool, 1-3 (the first of
            :func:`sim.robot.effects.default_tool_points`); with one there are no rigid links,
            so the diagnosis has no noise floor unless poses repeat.
        compensate: fresh random targets (plus half as many circle points for a 6-joint arm)
            compensated with each scenario's diagnosis, commanded and measured (the
            "compensated" column, :mod:`sim.studies.benchmark.compensated`); 0: no column.
    """

    scenarios: int = 50
    seed: int = 0
    poses: int = 200
    none_fraction: float = 0.1
    pair_fraction: float = 0.15
    effects: tuple[str, ...] = ()
    noise: tuple[float, float] | None = None
    poses_from: str = "random"
    approach: str = "gravity"
    payload_probability: float = 0.5
    use_mjcf: bool = True
    excitation_threshold: float = 1.0
    ratio_target: float = 1.5
    compensate: int = 0
    reflectors: int = 3

    def __post_init__(self) -> None:
        for name, lo, hi in (("scenarios", 1, None), ("poses", 16, None),
                             ("compensate", 0, None), ("reflectors", 1, 3)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo \
                    or (hi is not None and v > hi):
                raise InputError(f"{name}: expected an integer >= {lo}"
                                 + (f" and <= {hi}" if hi is not None else "") + f", got {v!r}")
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
        names = EFFECT_NAMES
        eff = tuple(self.effects) or names
        bad = [e for e in eff if e not in names]
        if bad:
            raise InputError(f"effects: unknown {bad}; expected some of {list(names)}")
        if self.pair_fraction > 0 and len(eff) < 2:
            raise InputError("pair_fraction > 0 needs at least two effects to draw from")
        object.__setattr__(self, "effects", eff)
        if self.noise is not None:
            lo, hi = (float(x) for x in self.noise)
            if not 0 < lo <= hi:
                raise InputError(f"noise: expected 0 < low <= high (length unit), got "
                                 f"{self.noise!r}")
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

    def robot_options(self, model: Manipulator) -> RealRobotOptions:
        """How the benchmark builds the real robot: the first :attr:`reflectors` default
        reflectors."""
        tp = default_tool_points(model)[:self.reflectors]
        return RealRobotOptions(tool_points=tuple(tuple(float(x) for x in r) for r in tp))

    def noise_range(self, model: Manipulator) -> tuple[float, float]:
        """(low, high) tracker noise sigma per coordinate in ``model``'s length unit:
        :attr:`noise`, or :data:`DEFAULT_NOISE_MM` converted with :mod:`zrp.units`."""
        if self.noise is not None:
            return self.noise
        per_mm = units_per_mm(model.length_unit, "model.length_unit")
        return (DEFAULT_NOISE_MM[0] * per_mm, DEFAULT_NOISE_MM[1] * per_mm)


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


#: The length per rad of the joint-space magnitudes drawn for a prismatic joint, fraction of the
#: reach (1 mrad of a revolute joint's range <-> 0.1 mm on the PUMA).
SLIDE_PER_RAD = 100.0 / 1244.6


def pose_limits(model: Manipulator) -> F64:
    """Where the benchmark's random poses lie, shape (n, 2): the core's
    :func:`zrp.kinematics.sampling.default_limits` (+-2.5 rad within the model's limits; slides
    within theirs, or +-10 % of the reach)."""
    return default_limits(model)


def typical_gravity_torque(model: Manipulator, payload: float,
                           rng: np.random.Generator, count: int = 64) -> F64:
    """RMS over random poses of the static torque each joint carries (arm and payload), N m,
    shape (n,) (nominal model, PUMA 560 or rod inertias)."""
    robot = RealRobot(model, HiddenEffects(payload=payload))
    lim = pose_limits(model)
    tau = robot.static_torque(rng.uniform(lim[:, 0], lim[:, 1], (count, model.n)))
    return np.sqrt(np.mean(tau**2, axis=0))


def _draw_effect(name: str, model: Manipulator, rng: np.random.Generator, payload: float,
                 tau_rms: Callable[[], F64]) -> tuple[dict[str, Any], tuple[int, ...]]:
    """Keyword arguments of HiddenEffects for one effect with a random magnitude."""
    n = model.n
    k = int(rng.integers(1, n + 1))
    sign = float(rng.choice([-1.0, 1.0]))
    lscale = model.reach / 1244.6  # the PUMA's reach: magnitudes in mm scale with the arm
    # a prismatic joint's offset, play and sag are lengths (no cyclic error: not a function
    # of a slide's angle, and the diagnosis has none on slides)
    if name == "cyclic_error" and model.prismatic[k - 1]:
        rev = np.flatnonzero(~model.prismatic) + 1
        k = int(rng.choice(rev)) if rev.size else k
    jscale = SLIDE_PER_RAD * model.reach if model.prismatic[k - 1] else 1.0
    if name == "joint_offset":
        return {name: {k: sign * rng.uniform(0.2e-3, 1.0e-3) * jscale}}, (k,)
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
        if model.prismatic[k - 1]:  # m per N (the servo's 1/kp in MuJoCo's metres)
            to_m = metres_per_unit(model.length_unit, "model.length_unit")
            c = sag * jscale * to_m / tau if tau > 1e-9 else 5e-5
            return {name: {k: float(np.clip(c, 2e-8, 5e-5))}}, (k,)
        c = sag / tau if tau > 1e-9 else 5e-3
        return {name: {k: float(np.clip(c, 2e-6, 5e-3))}}, (k,)
    if name == "backlash":
        return {name: {k: rng.uniform(0.4e-3, 1.6e-3) * jscale}}, (k,)
    if name == "thermal_expansion":
        return {name: rng.uniform(1.0e-5, 2.5e-5)}, ()
    raise InputError(f"effect: {name!r} cannot be drawn")


def draw_scenarios(model: Manipulator, config: BenchmarkConfig) -> list[Scenario]:
    """The K scenarios of ``config`` (reproducible from ``config.seed``)."""
    children = np.random.SeedSequence(config.seed).spawn(config.scenarios)
    noise = config.noise_range(model)
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
        sigma = float(rng.uniform(*noise))
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
