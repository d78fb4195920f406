"""Blind benchmark, part 1: the configuration and the scenarios it draws (the truth).

Scenario i draws from its own generator (child i of ``SeedSequence(seed)``), so the first
scenarios are the same whatever their number: none, one or two hidden effects with random
magnitudes, a payload, the tracker noise. A :class:`Scenario` IS the truth; it goes to the
simulation (:mod:`sim.studies.benchmark.blind`) and to the scorer, never to the diagnosis.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mjcf.own_dynamics import ArmDynamics, arm_dynamics
from sim.robot.effects import EFFECT_NAMES, HiddenEffects, default_tool_points
from sim.robot.instrument import TRACKER_NOISE_RANGE_MM
from sim.robot.mass import DynamicsFallbackWarning, is_paper_puma
from sim.robot.model import RealRobotOptions
from sim.robot.real import RealRobot
from zrp.arrays import F64
from zrp.errors import InputError
from zrp.kinematics.sampling import default_limits
from zrp.model.files import dumps_model
from zrp.model.manipulator import Manipulator
from zrp.units import metres_per_unit, units_per_mm

__all__ = [
    "DEFAULT_NOISE_MM",
    "KINDS",
    "BenchmarkConfig",
    "Scenario",
    "draw_scenarios",
    "own_dynamics",
    "pose_limits",
    "typical_gravity_torque",
]

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
        arm_file: the arm's shipped URDF/MJCF: the simulated robot has its inertias, damping,
            friction and tool (:func:`mjcf.arm_dynamics`) and the diagnosis gets the file as
            its MJCF (as ``zrp diagnose --mjcf``); None: the announced fallback
            (:mod:`sim.robot.mass`) and the nominal MJCF built with it.
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
    arm_file: str | None = None

    def __post_init__(self) -> None:
        for name, lo, hi in (("scenarios", 1, None), ("poses", 16, None),
                             ("compensate", 0, None), ("reflectors", 1, 3)):
            _check_int(getattr(self, name), name, lo, hi)
        if isinstance(self.seed, bool) or not isinstance(self.seed, (int, np.integer)) \
                or self.seed < 0:
            raise InputError(f"seed: expected an integer >= 0, got {self.seed!r}")
        _check_fractions(self)
        if self.arm_file is not None and not (isinstance(self.arm_file, str)
                                              and Path(self.arm_file).is_file()):
            raise InputError(f"arm_file: no such file {self.arm_file!r} (the arm's URDF or "
                             "MJCF)")
        object.__setattr__(self, "effects", _checked_effects(self.effects, self.pair_fraction))
        if self.noise is not None:
            object.__setattr__(self, "noise", _checked_noise(self.noise))
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
        reflectors, the arm's own dynamics from :attr:`arm_file`."""
        tp = default_tool_points(model)[:self.reflectors]
        dyn = None if self.arm_file is None else own_dynamics(self.arm_file, model)
        return RealRobotOptions(tool_points=tuple(tuple(float(x) for x in r) for r in tp),
                                dynamics=dyn)

    def dynamics_note(self, model: Manipulator) -> str:
        """One line: whose dynamics the simulated robot has (the fallback announced)."""
        if self.arm_file is not None:
            return own_dynamics(self.arm_file, model).summary()
        if is_paper_puma(model):
            return "PUMA 560 literature inertias (the arm's own)"
        kind = "PUMA 560" if model.n == 6 and not model.prismatic.any() else "uniform-rod"
        return (f"FALLBACK: {kind} inertias (no inertias given for this arm; pass its "
                "URDF/MJCF, --mjcf)")

    def noise_range(self, model: Manipulator) -> tuple[float, float]:
        """(low, high) tracker noise sigma per coordinate in ``model``'s length unit:
        :attr:`noise`, or :data:`DEFAULT_NOISE_MM` converted with :mod:`zrp.units`."""
        if self.noise is not None:
            return self.noise
        per_mm = units_per_mm(model.length_unit, "model.length_unit")
        return (DEFAULT_NOISE_MM[0] * per_mm, DEFAULT_NOISE_MM[1] * per_mm)


def _check_int(v: object, name: str, lo: int, hi: int | None) -> None:
    if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < lo \
            or (hi is not None and v > hi):
        raise InputError(f"{name}: expected an integer >= {lo}"
                         + (f" and <= {hi}" if hi is not None else "") + f", got {v!r}")


def _check_fractions(config: BenchmarkConfig) -> None:
    for name in ("none_fraction", "pair_fraction", "payload_probability"):
        v = float(getattr(config, name))
        if not 0.0 <= v <= 1.0:
            raise InputError(f"{name}: expected a fraction in [0, 1], got {v!r}")
    if config.none_fraction + config.pair_fraction > 1.0:
        raise InputError(f"none_fraction + pair_fraction = "
                         f"{config.none_fraction + config.pair_fraction:g} > 1")


def _checked_effects(effects: tuple[str, ...], pair_fraction: float) -> tuple[str, ...]:
    """The effects to draw from (all when empty), each known; two at least for pairs."""
    names = EFFECT_NAMES
    eff = tuple(effects) or names
    bad = [e for e in eff if e not in names]
    if bad:
        raise InputError(f"effects: unknown {bad}; expected some of {list(names)}")
    if pair_fraction > 0 and len(eff) < 2:
        raise InputError("pair_fraction > 0 needs at least two effects to draw from")
    return eff


def _checked_noise(noise: tuple[float, float]) -> tuple[float, float]:
    lo, hi = (float(x) for x in noise)
    if not 0 < lo <= hi:
        raise InputError(f"noise: expected 0 < low <= high (length unit), got {noise!r}")
    return (lo, hi)


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


_OWN: dict[tuple[str, str], ArmDynamics] = {}


def own_dynamics(path: str, model: Manipulator) -> ArmDynamics:
    """:func:`mjcf.arm_dynamics` of ``path`` for ``model``, read once per process."""
    key = (str(path), dumps_model(model))
    if key not in _OWN:
        _OWN[key] = arm_dynamics(path, model)
    return _OWN[key]


def typical_gravity_torque(model: Manipulator, payload: float,
                           rng: np.random.Generator, count: int = 64,
                           options: RealRobotOptions | None = None) -> F64:
    """RMS over random poses of the static torque each joint carries (arm and payload), N m,
    shape (n,) (nominal model, with ``options``' inertias: the arm's own or the fallback)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DynamicsFallbackWarning)  # the run announces it
        robot = RealRobot(model, HiddenEffects(payload=payload), options)
    lim = pose_limits(model)
    tau = robot.static_torque(rng.uniform(lim[:, 0], lim[:, 1], (count, model.n)))
    return np.sqrt(np.mean(tau**2, axis=0))


@dataclass(frozen=True, eq=False)
class _Pick:
    """What every effect's draw shares: the joint ``k`` (1-based) and sign drawn, the
    joint-space scale (a slide's lengths per rad, 1 for a revolute joint) and the tool-length
    scale (the PUMA's reach: magnitudes in mm scale with the arm)."""

    model: Manipulator
    rng: np.random.Generator
    k: int
    sign: float
    jscale: float
    lscale: float
    tau_rms: Callable[[], F64]


Drawn = tuple[dict[str, Any], tuple[int, ...]]


def _offset(p: _Pick) -> Drawn:
    return {"joint_offset": {p.k: p.sign * p.rng.uniform(0.2e-3, 1.0e-3) * p.jscale}}, (p.k,)


def _scale(p: _Pick) -> Drawn:
    return {"encoder_scale": {p.k: p.sign * p.rng.uniform(1.5e-4, 6e-4)}}, (p.k,)


def _cyclic(p: _Pick) -> Drawn:
    amp = p.rng.uniform(0.2e-3, 0.8e-3)
    ph = p.rng.uniform(0, 2 * math.pi)
    h = int(p.rng.integers(1, 3))
    return {"cyclic_error": {p.k: (h, amp * math.cos(ph), amp * math.sin(ph))}}, (p.k,)


def _link(p: _Pick) -> Drawn:
    b = int(p.rng.integers(1, p.model.n + 2))
    v = p.rng.normal(size=3)
    v *= p.rng.uniform(0.2, 0.8) * p.lscale / np.linalg.norm(v)
    return {"link_length": {b: tuple(float(x) for x in v)}}, (b,)


def _tilt(p: _Pick) -> Drawn:
    ang = p.rng.uniform(0, 2 * math.pi)
    mag = p.rng.uniform(0.3e-3, 1.5e-3)
    return {"axis_misalignment": {p.k: (mag * math.cos(ang), mag * math.sin(ang))}}, (p.k,)


def _compliance(p: _Pick) -> Drawn:
    """A sag of 0.3-1.5 mrad under the joint's typical static torque, stiffness kept within
    200 .. 5e5 N m/rad (a joint without a gravity torque gets the softest)."""
    tau = float(p.tau_rms()[p.k - 1])
    sag = p.rng.uniform(0.3e-3, 1.5e-3)
    if p.model.prismatic[p.k - 1]:  # m per N (the servo's 1/kp in MuJoCo's metres)
        to_m = metres_per_unit(p.model.length_unit, "model.length_unit")
        c = sag * p.jscale * to_m / tau if tau > 1e-9 else 5e-5
        return {"joint_compliance": {p.k: float(np.clip(c, 2e-8, 5e-5))}}, (p.k,)
    c = sag / tau if tau > 1e-9 else 5e-3
    return {"joint_compliance": {p.k: float(np.clip(c, 2e-6, 5e-3))}}, (p.k,)


def _backlash(p: _Pick) -> Drawn:
    return {"backlash": {p.k: p.rng.uniform(0.4e-3, 1.6e-3) * p.jscale}}, (p.k,)


def _thermal(p: _Pick) -> Drawn:
    return {"thermal_expansion": p.rng.uniform(1.0e-5, 2.5e-5)}, ()


_DRAWS: dict[str, Callable[[_Pick], Drawn]] = {
    "joint_offset": _offset, "encoder_scale": _scale, "cyclic_error": _cyclic,
    "link_length": _link, "axis_misalignment": _tilt, "joint_compliance": _compliance,
    "backlash": _backlash, "thermal_expansion": _thermal,
}


def _draw_effect(name: str, model: Manipulator, rng: np.random.Generator, payload: float,
                 tau_rms: Callable[[], F64]) -> Drawn:
    """Keyword arguments of HiddenEffects for one effect with a random magnitude."""
    k = int(rng.integers(1, model.n + 1))
    sign = float(rng.choice([-1.0, 1.0]))
    # a prismatic joint's offset, play and sag are lengths (no cyclic error: not a function
    # of a slide's angle, and the diagnosis has none on slides)
    if name == "cyclic_error" and model.prismatic[k - 1]:
        rev = np.flatnonzero(~model.prismatic) + 1
        k = int(rng.choice(rev)) if rev.size else k
    jscale = SLIDE_PER_RAD * model.reach if model.prismatic[k - 1] else 1.0
    draw = _DRAWS.get(name)
    if draw is None:
        raise InputError(f"effect: {name!r} cannot be drawn")
    return draw(_Pick(model, rng, k, sign, jscale, model.reach / 1244.6, tau_rms))


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
                tau_cache[p] = typical_gravity_torque(model, p, np.random.default_rng(0),
                                                      options=config.robot_options(model))
            return tau_cache[p]

        kw: dict[str, Any] = {}
        for name in names:
            part, _ = _draw_effect(name, model, rng, payload, tau_rms)
            kw.update(part)
        seed = int(rng.integers(2**31))
        out.append(Scenario(i, seed, kind, HiddenEffects(payload=payload, **kw), tuple(names),
                            sigma))
    return out
