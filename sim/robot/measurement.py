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

import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from tqdm.auto import tqdm

from sim.robot.effects import HiddenEffects
from sim.robot.instrument import Instrument, check_number
from sim.robot.real import Reading, RealRobot, Session
from zrp.arrays import F64
from zrp.errors import InputError, OutputExistsError
from zrp.escape import csv_text
from zrp.gap.data.measurements import Measurements
from zrp.kinematics.ik import track_trajectory
from zrp.kinematics.trajectory import Circle
from zrp.model.manipulator import Manipulator
from zrp.output import atomic_path, check_writable, write_json

__all__ = [
    "APPROACHES",
    "TRANSFERS",
    "TRUTH_FORMAT",
    "MeasurementRun",
    "Procedure",
    "measure",
    "trajectory_poses",
    "write_measurements",
    "write_truth",
]

APPROACHES = ("random", "order", "gravity")
TRUTH_FORMAT = "zrp-real-robot-truth"
TRANSFERS = ("jump", "simulate")


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
            settled tool points of both agree far below the tracker's noise, backlash
            included: tests/sim/test_real_robot.py).
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
            object.__setattr__(self, name,
                               check_number(getattr(self, name), name, unit, 0.0, strict))
        object.__setattr__(self, "temp_start",
                           check_number(self.temp_start, "temp_start", "deg C"))

    def temperature(self, t: ArrayLike) -> F64:
        """True robot temperature at times ``t`` (s), deg C."""
        t = np.asarray(t, dtype=float)
        return self.temp_start + self.temp_rise * (1.0 - np.exp(-t / self.temp_tau))


def trajectory_poses(model: Manipulator, count: int, trajectory: Circle, q0: ArrayLike) -> F64:
    """``count`` poses evenly spaced along the arc of a circle, rad, shape (count, n).

    ``trajectory`` (a :class:`zrp.Circle`, built by the caller: e.g. the paper's 125 mm circle
    of the PUMA, :func:`sim.studies.trajectories.circle_poses`) is solved from ``q0`` by the
    nominal inverse kinematics (what a controller would command); the poses are then picked
    evenly in angle about its centre (the time law is slow at both ends).
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 8:
        raise InputError(f"count: expected at least 8 poses along the trajectory, got {count!r}")
    if not isinstance(trajectory, Circle):
        raise InputError(f"trajectory: expected a zrp.Circle, got {type(trajectory).__name__}")
    res = track_trajectory(model, trajectory, q0, max(2000, 40 * count))
    c = trajectory
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
    q, planned = _checked_poses(robot, q, proc, directions)
    lift = (_nominal_static_torque(robot, q) if proc.approach == "gravity" else None)
    session = robot.session(q[0] - proc.approach_step, proc.temperature(0.0)[()])
    session.settle(max_time=proc.settle_time)
    log = _Log.empty(len(q), robot.n, len(robot.tool_points))
    clock = 0.0
    prev = q[0] - proc.approach_step
    for i in tqdm(range(len(q)), desc="measure", unit="pose", disable=not progress,
                  leave=False):
        if proc.approach in ("random", "gravity"):
            d = rng.choice([-1.0, 1.0], size=robot.n) if planned is None else planned[i]
            if lift is not None:
                d = np.where(np.abs(lift[i]) > 1e-3, np.sign(lift[i]), d)
            _approach_from_side(session, proc, q[i], prev, d, clock)
        else:
            s = np.sign(q[i] - prev)
            d = np.where(s != 0, s, log.dirs[i - 1] if i else 0.0)
            _approach_in_order(session, proc, q[i], prev, clock)
        log.dirs[i] = d
        sp = session.settle(max_time=proc.settle_time)
        log.record(i, session.read(sp), sp, clock + session.time)
        clock += proc.dwell
        prev = q[i]
    return _run(robot, q, instrument, proc, rng, log)


def _checked_poses(robot: RealRobot, q: ArrayLike, proc: Procedure,
                   directions: ArrayLike | None) -> tuple[F64, F64 | None]:
    """The commanded poses as floats, shape (P, n), and the planned directions (or None)."""
    if not isinstance(robot, RealRobot):
        raise InputError(f"robot: expected a sim.robot.real.RealRobot, got "
                         f"{type(robot).__name__}")
    q = np.array(q, dtype=float)
    n = robot.n
    if q.ndim != 2 or q.shape[1] != n or q.shape[0] < 1 or not np.all(np.isfinite(q)):
        raise InputError(f"q: expected finite joint values of shape (P, {n}), got {q.shape}")
    planned = None if directions is None else np.asarray(directions, dtype=float)
    if planned is not None and (planned.shape != q.shape or proc.approach != "random"
                                or not np.all(np.abs(planned) == 1.0)):
        raise InputError(f"directions: expected -1/+1 of shape {q.shape} with "
                         f"approach='random', got shape {planned.shape}")
    return q, planned


def _approach_from_side(session: Session, proc: Procedure, target: F64, prev: F64, d: F64,
                        clock: float) -> None:
    """Transfer to the pre-pose ``target - d approach_step``, then approach slowly."""
    pre = target - d * proc.approach_step
    dist = float(np.max(np.abs(pre - prev)))
    if dist > 0:
        go = session.jump if proc.transfer == "jump" else session.move
        go(pre, max(0.2, 1.875 * dist / proc.speed))
    session.set_temperature(proc.temperature(clock + session.time)[()])
    session.move(target, proc.approach_time)


def _approach_in_order(session: Session, proc: Procedure, target: F64, prev: F64,
                       clock: float) -> None:
    """Move straight from the previous pose (``approach="order"``)."""
    dist = float(np.max(np.abs(target - prev)))
    session.set_temperature(proc.temperature(clock + session.time)[()])
    if dist > 0:
        session.move(target, max(proc.approach_time, 1.875 * dist / proc.speed))


@dataclass(frozen=True, eq=False)
class _Log:
    """What the simulation shows at each pose: approach directions, the settled reading (tool
    points in the base frame, joints, torques, temperature), the residual speed, the largest
    motor error and the log time."""

    dirs: F64
    pts: F64
    q_link: F64
    q_motor: F64
    torque: F64
    temp_true: F64
    t_log: F64
    speed: F64
    motor_err: F64

    @classmethod
    def empty(cls, poses: int, n: int, points: int) -> _Log:
        return cls(np.zeros((poses, n)), np.empty((poses, points, 3)), np.empty((poses, n)),
                   np.empty((poses, n)), np.empty((poses, n)), np.empty(poses),
                   np.empty(poses), np.empty(poses), np.empty(poses))

    def record(self, i: int, rd: Reading, speed: float, t: float) -> None:
        self.pts[i] = rd.points
        self.q_link[i] = rd.q_link
        self.q_motor[i] = rd.q_motor
        self.torque[i] = rd.torque
        self.temp_true[i] = rd.temperature
        self.speed[i] = speed
        self.motor_err[i] = float(np.max(np.abs(rd.motor_target - rd.q_motor)))
        self.t_log[i] = t


def _run(robot: RealRobot, q: F64, instrument: Instrument, proc: Procedure,
         rng: np.random.Generator, log: _Log) -> MeasurementRun:
    """The tracker's view of the log (instrument frame, noise), the logged temperature and
    payload as :class:`~zrp.gap.Measurements`, and the truth."""
    P, M = log.pts.shape[:2]
    clean = log.pts @ instrument.rotation.T + np.asarray(instrument.translation)
    noise = rng.normal(scale=instrument.noise_sigma, size=clean.shape) \
        if instrument.noise_sigma > 0 else np.zeros(clean.shape)
    xyz = clean + noise
    temp_log = log.temp_true + (rng.normal(scale=proc.temp_noise, size=P)
                                if proc.temp_noise > 0 else 0.0)
    temp_log = np.round(temp_log, 3)
    load = np.full(P, robot.effects.payload)
    labels = [f"smr{j + 1}" for j in range(M)]
    direction = log.dirs if proc.approach != "order" else None
    meas = Measurements.from_arrays(
        np.repeat([f"P{i + 1:04d}" for i in range(P)], M), np.repeat(q, M, axis=0),
        xyz.reshape(-1, 3), point=np.tile(labels, P), frame="instrument",
        t=np.repeat(np.round(log.t_log, 3), M), temp=np.repeat(temp_log, M),
        load=np.repeat(load, M),
        direction=None if direction is None else np.repeat(direction, M, axis=0),
        source="real robot measurement")
    return MeasurementRun(meas, direction, _truth(robot, q, instrument, proc, log))


def _truth(robot: RealRobot, q: F64, instrument: Instrument, proc: Procedure,
           log: _Log) -> dict[str, Any]:
    """Everything hidden from the user (see :func:`write_truth`)."""
    return {
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
            "q_link": log.q_link.tolist(),
            "q_motor": log.q_motor.tolist(),
            "approach_direction": log.dirs.tolist(),
            "servo_torque_Nm": log.torque.tolist(),
            "temperature_true": log.temp_true.tolist(),
            "points_base_noisefree": log.pts.tolist(),
            "residual_speed": log.speed.tolist(),
            "motor_error_rad": log.motor_err.tolist(),
        },
    }


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
                       overwrite: bool = False, model: Manipulator | None = None) -> Path:
    """Write the measurement CSV (the diagnosis's format; q in deg with ``deg``, declared in
    the header: ``q1[deg]``; ``model`` tells the prismatic joints, kept in its length unit)
    atomically; an existing file is replaced only with ``overwrite=True``."""
    path = _check_new(path, overwrite)
    meas = run.measurements
    n = meas.n_joints
    rev = np.ones(n, bool) if model is None else ~np.asarray(model.prismatic)
    q = np.where(rev, np.degrees(meas.q), meas.q) if deg else meas.q
    cols = ["pose", "point", *[f"q{k}{'[deg]' if deg and rev[k - 1] else ''}"
                               for k in range(1, n + 1)], "x", "y", "z", "t", "temp", "load"]
    if run.direction is not None:
        cols += [f"dir{k}" for k in range(1, n + 1)]
    rows = []
    for i in range(meas.n_rows):
        row = [meas.pose[i], meas.point[i], *(repr(float(v)) for v in q[i]),
               *(repr(float(v)) for v in meas.xyz[i]), repr(float(meas.t[i])),  # type: ignore[index]
               repr(float(meas.temp[i])), repr(float(meas.load[i]))]  # type: ignore[index]
        if run.direction is not None:
            row += [str(int(v)) for v in meas.direction[i]]  # type: ignore[index]
        rows.append(row)
    with atomic_path(path, overwrite=overwrite) as tmp:
        tmp.write_text(csv_text(cols, rows), encoding="utf-8", newline="")
    return path


def write_truth(run: MeasurementRun, path: str | os.PathLike[str], *,
                overwrite: bool = False) -> Path:
    """Write the truth file (strict JSON: hidden effects, true joint angles, noise, instrument)
    atomically; an existing file is replaced only with ``overwrite=True``."""
    path = _check_new(path, overwrite)
    return write_json(path, run.truth, overwrite=overwrite, indent=1)
