"""The exciting command a robot plays (step 1 of the dynamic gap): the design of
:mod:`zrp.gap.dynamics.excitation` sampled at the controller's rate, every sample checked
against every limit (:func:`zrp.gap.dynamics.limits.check_command_limits`) before the file
is written, and the file recording what it is valid for.

The limits (:func:`command_limits`): the model's position limits; the velocity limit given
(default 1 rad/s, or the model's own where lower), never above the model's own (a URDF's
``<limit velocity=>``); the acceleration limit given (default 3 rad/s^2); the torque limit
given, never above the model's own (their default: every limit the model states, the MJCF
reader's ``mjcf.actuator_limits``). The file records where each comes from: "model",
"default", "none known" or "given" (only for a value given). q0 must lie inside the position
limits and q0 +- amplitude too (a value beyond one turn, or one that fits only read as degrees, is
named as likely degrees: ``deg`` reads q0 and the amplitude in degrees).

Sizes are bounded before anything is allocated: at most :data:`MAX_SAMPLES` samples (period
x rate), at least :data:`MIN_SAMPLES_PER_CYCLE` samples a cycle of the highest harmonic
(linear interpolation between samples then stays within 1.3 % of the amplitude), period x
rate a whole number (the command loops), and the design's own bounds
(:mod:`~zrp.gap.dynamics.excitation`).
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from zrp.arguments import check_float, check_int, check_seed
from zrp.arrays import F64
from zrp.errors import InputError, UnitError
from zrp.escape import one_line
from zrp.gap.dynamics.arm import DynamicArm as Arm
from zrp.gap.dynamics.excitation import (
    MAX_CANDIDATES,
    MAX_ITERATIONS,
    Excitation,
    condition_number,
    design_excitation,
    within_torque,
)
from zrp.gap.dynamics.fourier import MAX_HARMONICS
from zrp.gap.dynamics.limits import JointLimits, check_command_limits
from zrp.limits import MAX_COMMAND_SAMPLES as MAX_SAMPLES
from zrp.output import atomic_path
from zrp.units import angle_bounds
from zrp.version import __version__

__all__ = ["DEFAULT_ACCELERATION", "MAX_SAMPLES", "MIN_SAMPLES_PER_CYCLE", "ExcitationCommand",
           "ExciteOptions", "command_limits", "command_summary", "excitation_command",
           "read_command_conditions", "write_excitation_command"]

#: The acceleration limit when none is given, rad/s^2 (m/s^2).
DEFAULT_ACCELERATION = 3.0
#: Fewest samples a cycle of the series' highest harmonic.
MIN_SAMPLES_PER_CYCLE = 20
_TURN = 2.0 * np.pi
_MIN_PERIOD, _MAX_PERIOD = 0.5, 3600.0
_DEG_HINT = "; did you type degrees? use deg=True (--deg on the command line), or give radians"

PerJoint = float | list[float] | tuple[float, ...]


@dataclass(frozen=True, kw_only=True)
class ExciteOptions:
    """What ``zrp excite`` asks for (SI units; ``deg``: q0 and amplitude in degrees).

    Attributes:
        q0: the posture the motion is centred on, one value a joint.
        amplitude: largest |q - q0|, one for all joints or one a joint.
        max_velocity: largest |qd|; None: 1 rad/s (m/s), or the model's own where lower.
        max_acceleration: largest |qdd|; None: :data:`DEFAULT_ACCELERATION` (recorded as
            the default, not as given).
        max_torque: largest |tau| of the model; None: the model's own effort limits.
        deg: q0 and amplitude of the hinges in degrees.
        period_s, rate_hz: the period of the series and the samples a second of the command.
        harmonics, candidates, iterations, seed: the design's
            (:func:`~zrp.gap.dynamics.excitation.design_excitation`).
    """

    q0: PerJoint
    amplitude: PerJoint = 0.5
    max_velocity: PerJoint | None = None
    max_acceleration: PerJoint | None = None
    max_torque: PerJoint | None = None
    deg: bool = False
    period_s: float = 10.0
    rate_hz: float = 1000.0
    harmonics: int = 5
    candidates: int = 8
    iterations: int = 20
    seed: int = 0


@dataclass(frozen=True)
class ExcitationCommand:
    """The command as it will be written: times (S,), positions, the series' velocities and
    accelerations and the model's torques at them (S, n), all checked against ``limits``."""

    t: F64
    q: F64
    qd: F64
    qdd: F64
    tau: F64
    q0: F64
    excitation: Excitation
    limits: JointLimits
    options: ExciteOptions
    sources: dict[str, str]

    @property
    def samples(self) -> int:
        return int(self.t.size)


def _per_joint(value: object, n: int, field: str, *, finite: bool = True) -> F64:
    try:
        a = np.asarray(value, dtype=float).ravel()
    except (TypeError, ValueError):
        raise InputError(f"{field}: expected 1 or {n} numbers, got {value!r}") from None
    if a.size == 1:
        a = np.full(n, a[0])
    if a.shape != (n,):
        raise InputError(f"{field}: expected 1 or {n} values (one a joint), got {a.size}")
    bad = np.isnan(a) | (a <= 0) | (~np.isfinite(a) if finite else np.zeros(n, bool))
    if bad.any():
        k = int(np.argmax(bad))
        raise InputError(f"{field}: joint {k + 1} is {a[k]:g}; expected a "
                         f"{'finite ' if finite else ''}number > 0")
    return a


def _check_sizes(o: ExciteOptions) -> int:
    """The number of samples of the command; every size within its bound (module docstring),
    before anything is allocated."""
    period = check_float(o.period_s, "period_s", _MIN_PERIOD, _MAX_PERIOD, unit="s")
    rate = check_float(o.rate_hz, "rate_hz", 0.0, open_lo=True, unit="Hz")
    check_int(o.harmonics, "harmonics", 2, MAX_HARMONICS)
    check_int(o.candidates, "candidates", 1, MAX_CANDIDATES)
    check_int(o.iterations, "iterations", 0, MAX_ITERATIONS)
    check_seed(o.seed)
    exact = period * rate
    if exact > MAX_SAMPLES:
        raise InputError(f"rate_hz: a period of {period:g} s at {rate:g} Hz is "
                         f"{exact:,.0f} samples; at most {MAX_SAMPLES:,} (a shorter period or a "
                         "lower rate; play the command several times for a longer run)")
    top = o.harmonics / period
    if rate < MIN_SAMPLES_PER_CYCLE * top:
        raise InputError(f"rate_hz: {rate:g} Hz is below {MIN_SAMPLES_PER_CYCLE} samples a "
                         f"cycle of the series' highest harmonic ({o.harmonics} / {period:g} s "
                         f"= {top:g} Hz): at least {MIN_SAMPLES_PER_CYCLE * top:g} Hz")
    samples = round(exact)
    if abs(exact - samples) > 1e-6 * max(samples, 1):
        raise InputError(f"rate_hz: a period of {period:g} s at {rate:g} Hz is {exact:g} "
                         "samples, not a whole number: the command would not loop smoothly")
    return samples


def _own(given: object, own: F64, default: F64, field: str, limits_names: list[str],
         unit: list[str]) -> tuple[F64, str]:
    """A user's limit, refused above the model's own; the default where none given."""
    if given is None:
        return default, _default_source(default, own)
    v = _per_joint(given, own.size, field)
    above = v > own
    if above.any():
        k = int(np.argmax(above))
        raise InputError(f"{field}: joint {k + 1} ({limits_names[k]}) {v[k]:g} {unit[k]} is "
                         f"above the model's own limit {own[k]:g} {unit[k]}")
    return v, "given"


def _default_source(default: F64, own: F64) -> str:
    """Where a limit nobody gave comes from, as the command file records it: "model" (the
    model's own), "default" (the built-in one), "none known" (inf); never "given"."""
    if np.all(np.isinf(default)):
        return "none known"
    if np.all(default == own):
        return "model" if np.all(np.isfinite(own)) else "model; inf: none known"
    if np.all(default < own):
        return "default"
    return "default, or the model's where lower"


def command_limits(arm: Arm, o: ExciteOptions) -> tuple[JointLimits, dict[str, str]]:
    """The limits the command must meet (module docstring) and where each came from."""
    n, names, rev = arm.n, list(arm.joint_names), np.asarray(arm.revolute(), dtype=bool)
    per_s = ["rad/s" if r else "m/s" for r in rev]
    nm = ["N m" if r else "N" for r in rev]
    own_v = np.asarray(arm.velocity_limits(), dtype=float)
    own_t = np.asarray(arm.torque_limits(), dtype=float)
    vel, v_src = _own(o.max_velocity, own_v, np.minimum(1.0, own_v), "max_velocity", names,
                      per_s)
    tau, t_src = _own(o.max_torque, own_t, own_t, "max_torque", names, nm)
    acc_given = o.max_acceleration is not None
    acc = _per_joint(o.max_acceleration if acc_given else DEFAULT_ACCELERATION, n,
                     "max_acceleration")
    lo, hi = arm.position_limits()
    lim = JointLimits(lower=lo, upper=hi, velocity=vel, acceleration=acc, torque=tau,
                      names=tuple(names), revolute=rev)
    sources = {"position": "model", "velocity": v_src,
               "acceleration": "given" if acc_given else "default",
               "torque": t_src}
    return lim, sources


def _to_rad(values: F64, rev: np.ndarray, deg: bool) -> F64:
    return np.where(rev, np.radians(values), values) if deg else values


def _check_q0(q0_typed: F64, lim: JointLimits, deg: bool) -> F64:
    """q0 in SI, inside the position limits and within one turn; else a named error (with
    the degrees hint where it fits: module docstring)."""
    rev = lim.revolute
    q0 = _to_rad(q0_typed, rev, deg)
    bound = np.maximum(angle_bounds(lim.lower, lim.upper), _TURN)
    turn = rev & (np.abs(q0) > bound + 1e-9)
    out = (q0 < lim.lower) | (q0 > lim.upper) | turn
    if not out.any():
        return q0
    k = int(np.argmax(out))
    u = lim.unit(k)
    typed = f"{q0_typed[k]:g} deg ({q0[k]:.6g} rad)" if deg and rev[k] else f"{q0[k]:g} {u}"
    where = (f"outside its limits [{lim.lower[k]:.6g}, {lim.upper[k]:.6g}] {u}"
             if np.isfinite(lim.lower[k]) or np.isfinite(lim.upper[k])
             else "beyond one turn (2 pi rad)")
    msg = f"q0: {lim.joint(k)} is {typed}, {where}"
    as_deg = _to_rad(q0_typed, rev, True)
    fits = np.all((as_deg >= lim.lower) & (as_deg <= lim.upper))
    if rev[k] and not deg and (turn[k] or fits):
        raise UnitError(msg + _DEG_HINT)
    raise InputError(msg)


def _check_envelope(q0: F64, amp: F64, lim: JointLimits) -> None:
    room = np.minimum(q0 - lim.lower, lim.upper - q0)
    bad = amp > room
    if bad.any():
        k = int(np.argmax(bad))
        u = lim.unit(k)
        raise InputError(f"amplitude: {lim.joint(k)} would move over [{q0[k] - amp[k]:.6g}, "
                         f"{q0[k] + amp[k]:.6g}] {u}, beyond its limits [{lim.lower[k]:.6g}, "
                         f"{lim.upper[k]:.6g}] {u}: use an amplitude of at most "
                         f"{room[k]:.6g} {u} there, or move q0")


def excitation_command(arm: Arm, options: ExciteOptions, *,
                       progress: Callable[[int, int], None] | None = None
                       ) -> ExcitationCommand:
    """Design the exciting command and sample it (module docstring); every sample checked;
    ``progress(done, total)`` after each start and step of the design.

    Raises:
        InputError: a size beyond its bound, a limit that is not a finite number > 0, a limit
            above the model's own, q0 or q0 +- amplitude outside the position limits
            (UnitError when it looks like degrees), torque limits the motion cannot meet,
            or a sample beyond a limit.
    """
    o = options
    samples = _check_sizes(o)
    n = arm.n
    q0_typed = np.asarray(o.q0, dtype=float).ravel()
    if q0_typed.shape != (n,) or not np.all(np.isfinite(q0_typed)):
        raise InputError(f"q0: expected {n} finite joint values, got {q0_typed.size}")
    amp_typed = _per_joint(o.amplitude, n, "amplitude")
    lim, sources = command_limits(arm, o)
    q0 = _check_q0(q0_typed, lim, o.deg)
    amp = _to_rad(amp_typed, lim.revolute, o.deg)
    _check_envelope(q0, amp, lim)
    e = design_excitation(arm, q0, amp, lim.velocity, lim.acceleration,
                          torque_limit=lim.torque, harmonics=o.harmonics,
                          f0_hz=1.0 / o.period_s, candidates=o.candidates,
                          iterations=o.iterations, seed=o.seed, progress=progress)
    t = np.arange(samples) / float(o.rate_hz)
    f, tau = within_torque(arm, e.command, lim.torque, t)  # at the samples written
    if f is not e.command:
        e = Excitation(f, condition_number(arm, f), e.kappa_start, np.abs(tau).max(0))
    q, qd, qdd = f.evaluate(t)
    check_command_limits(q, lim, t=t, qd=qd, qdd=qdd, tau=tau, what="the command")
    return ExcitationCommand(t, q, qd, qdd, tau, q0, e, lim, o, sources)


def _row(values: F64) -> str:
    return " ".join(f"{v:.6g}" for v in values)


def _model_line(model: str | os.PathLike[str] | None) -> str:
    if model is None:
        return "not given"
    p = Path(model)
    if not p.is_file():
        return one_line(str(model))
    with open(p, "rb") as fh:
        digest = hashlib.file_digest(fh, "sha256").hexdigest()
    return f"{one_line(p.name)} (sha256 {digest})"


def _conditions(cmd: ExcitationCommand, model: str | os.PathLike[str] | None) -> list[str]:
    lim, o, s = cmd.limits, cmd.options, cmd.sources
    rev = lim.revolute
    u = "rad" if rev.all() else ("m" if not rev.any() else "rad|m")
    peaks = (np.abs(cmd.q - cmd.q0).max(0), np.abs(cmd.qd).max(0), np.abs(cmd.qdd).max(0),
             np.abs(cmd.tau).max(0))
    return [
        "zrp excite: a joint position command for the robot's controller, checked sample by "
        "sample against the limits below; valid only for this model and these limits",
        f"zrp: {__version__}",
        f"model: {_model_line(model)}",
        "joints: " + " ".join(f"{k + 1}={one_line(nm)}" for k, nm in enumerate(lim.names)),
        f"units: t s; positions {u}; velocities {u}/s; accelerations {u}/s^2; torques "
        + ("N m" if rev.all() else "N m (hinges), N (slides)")
        + ("" if rev.all() or not rev.any() else "; rad for hinges, m for slides"),
        f"q0 [{u}]: {_row(cmd.q0)}",
        f"period [s]: {o.period_s:g}",
        f"rate [Hz]: {o.rate_hz:g}",
        f"samples: {cmd.samples}; harmonics: {o.harmonics}; seed: {o.seed}",
        f"position limits [{u}]: lower {_row(lim.lower)}; upper {_row(lim.upper)} "
        f"({s['position']})",
        f"velocity limits [{u}/s]: {_row(lim.velocity)} ({s['velocity']})",
        f"acceleration limits [{u}/s^2]: {_row(lim.acceleration)} ({s['acceleration']})",
        f"torque limits [N m]: {_row(lim.torque)} ({s['torque']}; inf: none known)",
        f"peaks of the samples: |q - q0| {_row(peaks[0])}; |qd| {_row(peaks[1])}; "
        f"|qdd| {_row(peaks[2])}; |tau| {_row(peaks[3])}",
        f"condition number: {cmd.excitation.kappa:.6g} (best random start "
        f"{cmd.excitation.kappa_start:.6g})",
    ]


def write_excitation_command(cmd: ExcitationCommand, out: str | os.PathLike[str], *,
                             model: str | os.PathLike[str] | None = None,
                             overwrite: bool = False) -> Path:
    """Write ``cmd`` as CSV: ``#`` lines with its conditions (model file and its SHA-256,
    joints, units, q0, period, rate, every limit and its source, zrp version), then
    ``t [s], qc1 [rad] .. qcn [rad]`` (``[m]`` for slides), every number with the shortest
    digits that read back to the value checked.
    Checked against its limits again first: nothing is written otherwise.

    Raises:
        InputError: a sample beyond a limit, or ``out`` is the model file.
        OutputExistsError: ``out`` exists and not ``overwrite``.
    """
    out = Path(out)
    lim = cmd.limits
    check_command_limits(cmd.q, lim, t=cmd.t, qd=cmd.qd, qdd=cmd.qdd, tau=cmd.tau,
                         what="the command")
    if model is not None and out.exists() and Path(model).exists() \
            and os.path.samefile(out, model):
        raise InputError(f"out: {str(out)!r} is the model file: choose another file")
    head = "".join(f"# {line}\n" for line in _conditions(cmd, model))
    cols = ["t [s]"] + [f"qc{k + 1} [{lim.unit(k)}]" for k in range(lim.n)]
    with atomic_path(out, overwrite=overwrite) as tmp:
        with open(tmp, "w", encoding="utf-8", newline="\n") as fh:
            fh.write(head + ",".join(cols) + "\n")
            for i in range(0, cmd.samples, 4096):  # shortest exact digits, a block at a time
                block = np.column_stack([cmd.t[i:i + 4096], cmd.q[i:i + 4096]]).tolist()
                fh.write("".join(",".join(map(repr, row)) + "\n" for row in block))
    return out


def command_summary(cmd: ExcitationCommand, notes: tuple[str, ...] = ()
                    ) -> tuple[dict[str, object], str]:
    """The command's result as JSON-ready values and as a few lines of text (the headline:
    its condition number; then its peaks and what the limits could not cover)."""
    e, lim = cmd.excitation, cmd.limits
    peak = {"position_rad": np.abs(cmd.q - cmd.q0).max(0), "velocity_rad_s":
            np.abs(cmd.qd).max(0), "acceleration_rad_s2": np.abs(cmd.qdd).max(0),
            "torque_nm": np.abs(cmd.tau).max(0)}
    payload: dict[str, object] = {
        "condition_number": e.kappa, "condition_number_random_start": e.kappa_start,
        **{f"peak_{k}": v.tolist() for k, v in peak.items()},
        "q0": cmd.q0.tolist(), "f0_hz": e.command.f0_hz, "a": e.command.a.tolist(),
        "b": e.command.b.tolist(), "samples": cmd.samples,
        "limits": {"lower": lim.lower.tolist(), "upper": lim.upper.tolist(),
                   "velocity": lim.velocity.tolist(), "acceleration": lim.acceleration.tolist(),
                   "torque": lim.torque.tolist(), "sources": dict(cmd.sources)},
        "notes": list(notes)}
    lines = [f"condition number {e.kappa:.4g} (best random start {e.kappa_start:.4g}); "
             f"{cmd.samples} samples, every one within the position, velocity, acceleration "
             "and torque limits",
             f"peak torque per joint {_row(peak['torque_nm'])} (limits {_row(lim.torque)})"]
    free = [k + 1 for k in range(lim.n) if not np.isfinite(lim.torque[k])]
    if free:
        lines.append(f"no torque limit known for joints {', '.join(map(str, free))}: check the "
                     "peaks above against the arm's, or give max_torque")
    lines += [f"note: {one_line(n)}" for n in notes]
    return payload, "\n".join(lines)


def read_command_conditions(path: str | os.PathLike[str]) -> dict[str, str]:
    """The ``# key: value`` conditions heading a command file written here."""
    out: dict[str, str] = {}
    with open(path, encoding="utf-8") as fh:
        for line in fh:
            if not line.startswith("#"):
                break
            key, sep, value = line[1:].strip().partition(": ")
            if sep:
                out[key] = value
    return out
