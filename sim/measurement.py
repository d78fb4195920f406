"""Measuring the "real" robot like a laser-tracker calibration, and writing the result.

The procedure (:func:`measure`): for each commanded pose, in order,

1. move there (a joint-space quintic at a bounded joint speed) - with ``approach="gravity"``
   (default) or ``"random"`` to a pre-pose offset by ``approach_step`` on one side of each
   joint, then slowly the last ``approach_step`` (so every joint's approach direction is known;
   written as the ``dir1..dirn`` columns): against gravity for the joints that carry a gravity
   torque (so a backlash rests on the flank gravity loads whatever the torque), on a random
   side for the others (or for all with "random"); with ``approach="order"`` straight from the
   previous pose (the direction then follows from the measurement order);
2. let the servos settle (their integral action trims the motors onto their targets);
3. read the tool points (reflectors), add the tracker's noise, express them in the
   instrument's frame; log the time, the robot's temperature (warm-up curve, sensor noise)
   and the payload.

The measurement CSV (:func:`write_measurements`) is what a user would have: pose, point,
q1..qn (the controller's joint values), x, y, z (instrument frame, model length unit), t, temp,
load (and dir1..dirn). Everything else - the hidden effects, the true joint angles, the noise
level, the instrument pose - goes to a SEPARATE truth file (:func:`write_truth`), which the
blind benchmark never shows to the diagnosis.
"""

from __future__ import annotations

import csv
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from tqdm.auto import tqdm

from sim.effects import HiddenEffects
from sim.real_robot import RealRobot
from zrp.errors import InputError, OutputExistsError
from zrp.gap.data.measurements import Measurements
from zrp.kinematics.ik import track_trajectory
from zrp.model.manipulator import Manipulator
from zrp.output import atomic_path, check_writable, write_json
from zrp.paper.scenario import puma_circle
from zrp.rotations import matrix_from_rotvec
from zrp.units import units_per_mm

__all__ = [
    "APPROACHES",
    "TRACKER_NOISE_RANGE_MM",
    "TRANSFERS",
    "TRUTH_FORMAT",
    "Instrument",
    "MeasurementRun",
    "Procedure",
    "measure",
    "random_instrument",
    "trajectory_poses",
    "write_measurements",
    "write_truth",
]

F64 = NDArray[np.float64]
APPROACHES = ("random", "order", "gravity")
TRUTH_FORMAT = "zrp-real-robot-truth"
TRANSFERS = ("jump", "simulate")


def _num(v: object, name: str, unit: str, lo: float | None = None,
         strict: bool = False) -> float:
    try:
        x = float(v)  # type: ignore[arg-type]
    except (TypeError, ValueError) as exc:
        raise InputError(f"{name}: expected a number ({unit}), got {v!r}") from exc
    if not math.isfinite(x) or (lo is not None and (x <= lo if strict else x < lo)):
        cond = "" if lo is None else f" {'>' if strict else '>='} {lo:g}"
        raise InputError(f"{name}: expected a finite number{cond} ({unit}), got {v!r}")
    return x


@dataclass(frozen=True)
class Instrument:
    """The laser tracker: its noise and where it stands.

    Attributes:
        noise_sigma: isotropic Gaussian noise per coordinate, model length unit (0.01-0.03 mm
            is typical of a laser tracker at a few metres).
        rotvec: rotation vector of the instrument-from-base rotation, rad, shape (3,).
        translation: base origin in the instrument frame, model length unit, shape (3,).
    """

    noise_sigma: float = 0.02
    rotvec: tuple[float, float, float] = (0.01, -0.02, 2.4)
    translation: tuple[float, float, float] = (2500.0, 800.0, 300.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "noise_sigma", _num(self.noise_sigma, "noise_sigma",
                                                     "length unit", 0.0))
        for name in ("rotvec", "translation"):
            a = np.asarray(getattr(self, name), dtype=float)
            if a.shape != (3,) or not np.all(np.isfinite(a)):
                raise InputError(f"{name}: expected 3 finite numbers, got {getattr(self, name)!r}")
            object.__setattr__(self, name, tuple(float(x) for x in a))

    @property
    def rotation(self) -> F64:
        """Instrument-from-base rotation, shape (3, 3)."""
        return matrix_from_rotvec(self.rotvec)


#: The range of laser-tracker noise per coordinate the simulations draw from, mm.
TRACKER_NOISE_RANGE_MM = (0.01, 0.03)


def random_instrument(model: Manipulator, rng: np.random.Generator,
                      noise_sigma: float | tuple[float, float] | None = None) -> Instrument:
    """A tracker 1.2-2.4 reaches away in a random direction, turned about the vertical at
    random and levelled within 0.02 rad; noise drawn uniformly from ``noise_sigma`` (a range,
    or one value, model length unit; None: :data:`TRACKER_NOISE_RANGE_MM` in the model's
    unit)."""
    if noise_sigma is None:
        per_mm = units_per_mm(model.length_unit, "model.length_unit")
        noise_sigma = (TRACKER_NOISE_RANGE_MM[0] * per_mm, TRACKER_NOISE_RANGE_MM[1] * per_mm)
    lo, hi = (noise_sigma, noise_sigma) if np.isscalar(noise_sigma) else noise_sigma  # type: ignore[misc]
    sigma = float(rng.uniform(float(lo), float(hi)))
    rot = np.array([*rng.uniform(-0.02, 0.02, 2), rng.uniform(-math.pi, math.pi)])
    ang = rng.uniform(-math.pi, math.pi)
    dist = rng.uniform(1.2, 2.4) * model.reach
    trans = np.array([dist * math.cos(ang), dist * math.sin(ang),
                      rng.uniform(-0.3, 0.3) * model.reach])
    return Instrument(sigma, tuple(rot), tuple(trans))  # type: ignore[arg-type]


@dataclass(frozen=True)
class Procedure:
    """How the poses are approached and logged.

    Attributes:
        approach: "gravity" (default: a final slow approach, written as dir columns; joints
            that carry a gravity torque approach against gravity, i.e. lifting, so that a
            backlash rests on the same flank whether gravity or the approach decides; the
            others from a random side; the torque comes from the nominal model and the known
            payload), "random" (every joint from a random side) or "order" (straight from
            pose to pose; direction from the order).
        approach_step: length of the final approach, rad (longer than any backlash).
        approach_time: duration of the final approach, s.
        speed: peak joint speed of the transfer moves, rad/s.
        settle_time: longest settling wait per pose, s.
        dwell: time a tracker reading takes (the robot rests), s.
        temp_start: robot temperature at the start, deg C.
        temp_rise: warm-up amplitude, K (T = start + rise (1 - exp(-t / tau))).
        temp_tau: warm-up time constant, s.
        temp_noise: temperature sensor noise (standard deviation), K.
        transfer: how the move to the pre-pose of the "random" and "gravity" approaches is
            simulated: "jump" (default) puts the motors at rest on the pre-pose and advances
            the clock by the move's duration (the slow approach and the settling that follow
            are simulated as before and decide the backlash flank and the trims); "simulate"
            steps the whole quintic move (3.4x the physics steps on 200 random poses; the
            settled tool points of both agree within 0.22 um on seeded scenarios of every
            effect, backlash included, see sim/README.md).
    """

    approach: str = "gravity"
    approach_step: float = 0.02
    approach_time: float = 0.5
    speed: float = 2.5
    settle_time: float = 2.0
    dwell: float = 5.0
    temp_start: float = 20.0
    temp_rise: float = 10.0
    temp_tau: float = 1200.0
    temp_noise: float = 0.05
    transfer: str = "jump"

    def __post_init__(self) -> None:
        if self.approach not in APPROACHES:
            raise InputError(f"approach: {self.approach!r}; expected one of {APPROACHES}")
        if self.transfer not in TRANSFERS:
            raise InputError(f"transfer: {self.transfer!r}; expected one of {TRANSFERS}")
        for name, unit, strict in (("approach_step", "rad", True), ("approach_time", "s", True),
                                   ("speed", "rad/s", True), ("settle_time", "s", True),
                                   ("dwell", "s", False), ("temp_rise", "K", False),
                                   ("temp_tau", "s", True), ("temp_noise", "K", False)):
            object.__setattr__(self, name, _num(getattr(self, name), name, unit, 0.0, strict))
        object.__setattr__(self, "temp_start", _num(self.temp_start, "temp_start", "deg C"))

    def temperature(self, t: ArrayLike) -> F64:
        """True robot temperature at times ``t`` (s), deg C."""
        t = np.asarray(t, dtype=float)
        return self.temp_start + self.temp_rise * (1.0 - np.exp(-t / self.temp_tau))


def trajectory_poses(model: Manipulator, count: int, trajectory: str = "circle") -> F64:
    """``count`` poses evenly spaced in time along a trajectory, rad, shape (count, n).

    ``"circle"``: the paper's 125 mm circle of the PUMA (:func:`zrp.puma_circle`), solved by
    the nominal inverse kinematics (what a controller would command).
    """
    if trajectory != "circle":
        raise InputError(f"trajectory: {trajectory!r}; expected 'circle'")
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 8:
        raise InputError(f"count: expected at least 8 poses along the trajectory, got {count!r}")
    if model.n != 6:
        raise InputError(f"trajectory 'circle' is the PUMA's; the model {model.name!r} has "
                         f"{model.n} joints")
    setup = puma_circle(model)
    res = track_trajectory(model, setup.trajectory, setup.q0, max(2000, 40 * count))
    # evenly spaced along the arc (the time law is slow at both ends)
    c = setup.trajectory
    r = np.asarray(res.desired_position) - np.asarray(c.center)
    e1 = np.asarray(c.start_point) - np.asarray(c.center)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(np.asarray(c.normal), e1)
    ang = np.unwrap(np.arctan2(r @ e2, r @ e1))
    want = ang[0] + (ang[-1] - ang[0]) * np.arange(count) / count
    idx = np.argmin(np.abs(ang[None, :] - want[:, None]), axis=1)
    return np.array(res.q[idx])


@dataclass(frozen=True, eq=False)
class MeasurementRun:
    """The result of :func:`measure`.

    Attributes:
        measurements: what the user gets (:class:`zrp.gap.Measurements`, instrument frame).
        direction: commanded approach direction per pose and joint (-1/+1), shape (P, n), or
            None with ``approach="order"`` (not written then).
        truth: everything hidden from the user (JSON-ready dict; see :func:`write_truth`).
    """

    measurements: Measurements
    direction: F64 | None
    truth: dict[str, Any]


def measure(robot: RealRobot, q: ArrayLike, instrument: Instrument, rng: np.random.Generator,
            procedure: Procedure | None = None, *, progress: bool = False,
            directions: ArrayLike | None = None) -> MeasurementRun:
    """Measure the real robot at commanded poses ``q`` (rad, shape (P, n), in order).

    Args:
        robot: the real robot.
        q: commanded joint values (the controller's), rad (model unit for prismatic joints).
        instrument: tracker noise and pose.
        rng: approach directions, temperature-sensor noise and tracker noise are drawn from it.
        procedure: approach, speeds, timing, temperature.
        progress: tqdm bar over the poses.
        directions: planned approach direction per pose and joint (-1/+1), shape (P, n), used
            instead of the drawn ones with ``approach="random"`` (e.g. ``zrp plan``'s).
    """
    proc = procedure or Procedure()
    if not isinstance(robot, RealRobot):
        raise InputError(f"robot: expected a sim.real_robot.RealRobot, got "
                         f"{type(robot).__name__}")
    q = np.array(q, dtype=float)
    n = robot.n
    if q.ndim != 2 or q.shape[1] != n or q.shape[0] < 1 or not np.all(np.isfinite(q)):
        raise InputError(f"q: expected finite joint values of shape (P, {n}), got {q.shape}")
    P = q.shape[0]
    M = len(robot.tool_points)
    step = proc.approach_step
    dirs_plan = None if directions is None else np.asarray(directions, dtype=float)
    if dirs_plan is not None and (dirs_plan.shape != q.shape or proc.approach != "random"
                                  or not np.all(np.abs(dirs_plan) == 1.0)):
        raise InputError(f"directions: expected -1/+1 of shape {q.shape} with "
                         f"approach='random', got shape {dirs_plan.shape}")
    lift = (_nominal_static_torque(robot, q) if proc.approach == "gravity" else None)
    session = robot.session(q[0] - step, proc.temperature(0.0)[()])
    session.settle(max_time=proc.settle_time)
    clock = 0.0
    dirs = np.zeros((P, n))
    prev = q[0] - step
    pts = np.empty((P, M, 3))
    q_link = np.empty((P, n))
    q_motor = np.empty((P, n))
    torque = np.empty((P, n))
    temp_true = np.empty(P)
    t_log = np.empty(P)
    speed = np.empty(P)
    motor_err = np.empty(P)
    for i in tqdm(range(P), desc="measure", unit="pose", disable=not progress, leave=False):
        if proc.approach in ("random", "gravity"):
            d = rng.choice([-1.0, 1.0], size=n) if directions is None else dirs_plan[i]
            if lift is not None:
                d = np.where(np.abs(lift[i]) > 1e-3, np.sign(lift[i]), d)
            pre = q[i] - d * step
            dist = float(np.max(np.abs(pre - prev)))
            if dist > 0:
                go = session.jump if proc.transfer == "jump" else session.move
                go(pre, max(0.2, 1.875 * dist / proc.speed))
            session.set_temperature(proc.temperature(clock + session.time)[()])
            session.move(q[i], proc.approach_time)
        else:
            s = np.sign(q[i] - prev)
            d = np.where(s != 0, s, dirs[i - 1] if i else 0.0)
            dist = float(np.max(np.abs(q[i] - prev)))
            session.set_temperature(proc.temperature(clock + session.time)[()])
            if dist > 0:
                session.move(q[i], max(proc.approach_time, 1.875 * dist / proc.speed))
        dirs[i] = d
        sp = session.settle(max_time=proc.settle_time)
        rd = session.read(sp)
        pts[i] = rd.points
        q_link[i] = rd.q_link
        q_motor[i] = rd.q_motor
        torque[i] = rd.torque
        temp_true[i] = rd.temperature
        speed[i] = sp
        motor_err[i] = float(np.max(np.abs(rd.motor_target - rd.q_motor)))
        t_log[i] = clock + session.time
        clock += proc.dwell
        prev = q[i]
    rb = instrument.rotation
    tb = np.asarray(instrument.translation)
    clean = pts @ rb.T + tb
    noise = rng.normal(scale=instrument.noise_sigma, size=clean.shape) \
        if instrument.noise_sigma > 0 else np.zeros(clean.shape)
    xyz = clean + noise
    temp_log = temp_true + (rng.normal(scale=proc.temp_noise, size=P) if proc.temp_noise > 0
                            else 0.0)
    temp_log = np.round(temp_log, 3)
    load = np.full(P, robot.effects.payload)
    labels = [f"smr{j + 1}" for j in range(M)]
    direction = dirs if proc.approach != "order" else None
    meas = Measurements.from_arrays(
        np.repeat([f"P{i + 1:04d}" for i in range(P)], M), np.repeat(q, M, axis=0),
        xyz.reshape(-1, 3), point=np.tile(labels, P), frame="instrument",
        t=np.repeat(np.round(t_log, 3), M), temp=np.repeat(temp_log, M), load=np.repeat(load, M),
        direction=None if direction is None else np.repeat(direction, M, axis=0),
        source="real robot measurement")
    truth = {
        "format": TRUTH_FORMAT,
        "version": 1,
        "model": robot.nominal.name,
        "length_unit": robot.nominal.length_unit,
        "effects": robot.effects.to_dict(),
        "active": list(robot.effects.active),
        "instrument": {"noise_sigma": instrument.noise_sigma, "rotvec": list(instrument.rotvec),
                       "translation": list(instrument.translation)},
        "procedure": asdict(proc),
        "robot": robot.describe(),
        "poses": {
            "q_command": q.tolist(),
            "q_link": q_link.tolist(),
            "q_motor": q_motor.tolist(),
            "approach_direction": dirs.tolist(),
            "servo_torque_Nm": torque.tolist(),
            "temperature_true": temp_true.tolist(),
            "points_base_noisefree": pts.tolist(),
            "residual_speed": speed.tolist(),
            "motor_error_rad": motor_err.tolist(),
        },
    }
    return MeasurementRun(meas, direction, truth)


def _nominal_static_torque(robot: RealRobot, q: F64) -> F64:
    """Torque each servo must supply to hold the NOMINAL arm (with the known payload) at the
    poses ``q``, N m, shape (P, n) (positive: held against gravity turning the joint
    negatively). Uses only what a user knows: the nominal model, its inertias, the payload."""
    nominal = RealRobot(robot.nominal, HiddenEffects(payload=robot.effects.payload),
                        robot.options)
    return nominal.static_torque(q)


#: How a refusal to replace a file names the way out. The API argument comes first; the
#: command line (which rewrites it to ``--force`` itself) is named too, as tests pin it.
REPLACE = "overwrite=True (--force on the command line)"


def _check_new(path: str | os.PathLike[str], overwrite: bool) -> Path:
    """``path`` as a Path, refused if it exists (unless ``overwrite``) or cannot be a file."""
    try:
        (p,) = check_writable([path], overwrite)
    except OutputExistsError as exc:
        raise OutputExistsError(exc.paths or [path], REPLACE) from None
    return p


def write_measurements(run: MeasurementRun, path: str | os.PathLike[str], *, deg: bool = False,
                       overwrite: bool = False) -> Path:
    """Write the measurement CSV (the diagnosis's format; q in deg with ``deg``) atomically;
    an existing file is replaced only with ``overwrite=True``."""
    path = _check_new(path, overwrite)
    meas = run.measurements
    n = meas.n_joints
    q = np.degrees(meas.q) if deg else meas.q
    cols = ["pose", "point", *[f"q{k}" for k in range(1, n + 1)], "x", "y", "z", "t", "temp",
            "load"]
    if run.direction is not None:
        cols += [f"dir{k}" for k in range(1, n + 1)]
    with atomic_path(path, overwrite=overwrite) as tmp, \
            open(tmp, "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for i in range(meas.n_rows):
            row = [meas.pose[i], meas.point[i], *(repr(float(v)) for v in q[i]),
                   *(repr(float(v)) for v in meas.xyz[i]), repr(float(meas.t[i])),  # type: ignore[index]
                   repr(float(meas.temp[i])), repr(float(meas.load[i]))]  # type: ignore[index]
            if run.direction is not None:
                row += [str(int(v)) for v in meas.direction[i]]  # type: ignore[index]
            w.writerow(row)
    return path


def write_truth(run: MeasurementRun, path: str | os.PathLike[str], *,
                overwrite: bool = False) -> Path:
    """Write the truth file (strict JSON: hidden effects, true joint angles, noise, instrument)
    atomically; an existing file is replaced only with ``overwrite=True``."""
    path = _check_new(path, overwrite)
    return write_json(path, run.truth, overwrite=overwrite, indent=1)
