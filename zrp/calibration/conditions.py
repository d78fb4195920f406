"""The conditions a calibration holds under, recorded from the data and enforced on requests.

A calibrated robot predicts well only under the conditions of its data: the payloads and
tool points measured, the temperature range, the units, the joint limits, the instrument.
:class:`Conditions` records them (``conditions`` in the compensation file and a comment block
in the model TOML); :func:`missing_conditions` names what a compensation request leaves out
that the model needs (a payload-dependent joint map without a payload, thermal expansion
without a temperature), :func:`out_of_range` what lies outside the measured range, and
:func:`check_joint_limits` refuses a joint value outside a limit, naming the target and joint.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from zrp.arrays import F64
from zrp.calibration.jointmap import Term
from zrp.errors import InputError, ZRPWarning
from zrp.gap.data.measurements import Measurements
from zrp.model.manipulator import Manipulator
from zrp.version import __version__

__all__ = ["ANGLE_UNIT", "ConditionWarning", "Conditions", "MissingConditionError",
           "PayloadConditionError", "check_joint_limits", "check_payload", "file_sha256",
           "load_dependent", "missing_conditions", "out_of_range", "payload_separated"]

#: the angle unit of every angle in the calibration files (a data file may be in degrees).
ANGLE_UNIT = "rad"


class MissingConditionError(InputError):
    """A compensation request leaves out a condition the calibrated model depends on."""


class PayloadConditionError(InputError):
    """A request at a payload the calibration cannot predict: its data never varied the
    payload and no MJCF gave the masses, so the payload's effect is baked into the model."""


class ConditionWarning(ZRPWarning):
    """A request lies outside the conditions measured (payload, temperature)."""


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex)."""
    h = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for chunk in iter(lambda: fh.read(1 << 20), b""):
                h.update(chunk)
    except OSError as exc:
        raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from exc
    return h.hexdigest()


def _range(a: F64 | None) -> tuple[float, float] | None:
    return None if a is None else (float(np.min(a)), float(np.max(a)))


@dataclass(frozen=True)
class Conditions:
    """What the data of a calibration were measured under.

    Attributes:
        payloads_kg: the distinct payloads of the data's ``load`` column (kg), or None when
            the data had no load column (the payload mounted then is unknown: the joint map
            holds for that payload only).
        tool_points: the tool-point labels measured.
        temp_range_degC: (min, max) of the data's ``temp`` column, or None (not recorded).
        length_unit: the length unit of every length in the files.
        angle_unit: the angle unit of the files (always ``rad``).
        data_angle_unit: the unit of the data file's joint angles (``rad`` or ``deg``).
        joint_limits: per joint (lower, upper) in rad / length unit, or None (unlimited).
        frame: the frame of the measured positions (``instrument`` or ``base``).
        instrument: the instrument (e.g. "Leica AT960"), or None when not given.
        data_file: the data file's name, or None (in-memory data).
        data_sha256: SHA-256 of the data file's bytes, or None.
        software: the toolkit and version that identified the calibration.
        joint_ranges: per joint the (smallest, largest) value the data measured (rad /
            length unit), or None (files before 0.5.0: not recorded; nothing is guarded).
    """

    payloads_kg: tuple[float, ...] | None
    tool_points: tuple[str, ...]
    temp_range_degC: tuple[float, float] | None
    length_unit: str
    joint_limits: tuple[tuple[float, float] | None, ...]
    frame: str = "instrument"
    angle_unit: str = ANGLE_UNIT
    data_angle_unit: str = ANGLE_UNIT
    instrument: str | None = None
    data_file: str | None = None
    data_sha256: str | None = None
    software: str = f"zrp-accuracy {__version__}"
    joint_ranges: tuple[tuple[float, float] | None, ...] | None = None

    @classmethod
    def from_measurements(cls, meas: Measurements, model: Manipulator, *,
                          data_path: str | Path | None = None, data_angle_unit: str = "rad",
                          instrument: str | None = None) -> Conditions:
        """The conditions of ``meas`` (measured on ``model``, whose joint limits hold);
        ``data_path``: the data file (its name and SHA-256 are recorded)."""
        if data_angle_unit not in ("rad", "deg"):
            raise InputError(f"data_angle_unit: expected 'rad' or 'deg', got "
                             f"{data_angle_unit!r}")
        load = meas.per_pose("load")
        return cls(None if load is None else tuple(sorted({float(v) for v in load})),
                   tuple(meas.point_labels), _range(meas.per_pose("temp")), model.length_unit,
                   tuple(j.limits for j in model.joints), meas.frame, ANGLE_UNIT,
                   data_angle_unit, instrument,
                   None if data_path is None else Path(data_path).name,
                   None if data_path is None else file_sha256(data_path),
                   joint_ranges=tuple((float(lo), float(hi)) for lo, hi in zip(
                       meas.q_pose.min(axis=0), meas.q_pose.max(axis=0), strict=True)))

    @property
    def load_range_kg(self) -> tuple[float, float] | None:
        p = self.payloads_kg
        return None if not p else (min(p), max(p))

    def to_dict(self) -> dict[str, Any]:
        return {"payloads_kg": None if self.payloads_kg is None else list(self.payloads_kg),
                "tool_points": list(self.tool_points),
                "temp_range_degC": (None if self.temp_range_degC is None
                                    else list(self.temp_range_degC)),
                "length_unit": self.length_unit, "angle_unit": self.angle_unit,
                "data_angle_unit": self.data_angle_unit,
                "joint_limits": [None if lim is None else list(lim)
                                 for lim in self.joint_limits],
                "frame": self.frame, "instrument": self.instrument,
                "data_file": self.data_file, "data_sha256": self.data_sha256,
                "software": self.software,
                "joint_ranges": None if self.joint_ranges is None else [
                    None if r is None else list(r) for r in self.joint_ranges]}

    @classmethod
    def from_dict(cls, d: object, where: str) -> Conditions:
        """Read :meth:`to_dict` back; a malformed entry is an error naming ``where``."""
        if not isinstance(d, dict):
            raise InputError(f"{where}: expected an object")
        try:
            pay = d["payloads_kg"]
            temp = d["temp_range_degC"]
            lims = tuple(None if v is None else (float(v[0]), float(v[1]))
                         for v in d["joint_limits"])
            out = cls(None if pay is None else tuple(float(v) for v in pay),
                      tuple(str(v) for v in d["tool_points"]),
                      None if temp is None else (float(temp[0]), float(temp[1])),
                      str(d["length_unit"]), lims, str(d["frame"]), str(d["angle_unit"]),
                      str(d["data_angle_unit"]), _opt_str(d.get("instrument")),
                      _opt_str(d.get("data_file")), _opt_str(d.get("data_sha256")),
                      str(d["software"]), _ranges_from(d.get("joint_ranges")))
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            raise InputError(f"{where}: malformed conditions ({type(exc).__name__}: "
                             f"{exc})") from None
        if out.angle_unit != ANGLE_UNIT:
            raise InputError(f"{where}.angle_unit: {out.angle_unit!r}; the files' angles are "
                             f"in {ANGLE_UNIT}")
        return out


def _ranges_from(v: object) -> tuple[tuple[float, float] | None, ...] | None:
    """joint_ranges as read (absent in files before 0.5.0)."""
    if v is None:
        return None
    return tuple(None if r is None else (float(r[0]), float(r[1])) for r in v)  # type: ignore[attr-defined]


def _opt_str(v: object) -> str | None:
    return None if v is None else str(v)


def load_dependent(terms: tuple[Term, ...], compliance_model: str) -> tuple[str, ...]:
    """The joint-map terms whose correction depends on the payload of the request: the MJCF
    compliance (its basis adds g load h_ee) and ``w_load`` (load x h_ee)."""
    return tuple(t.name for t in terms
                 if t.what == "w_load" or (t.what == "compliance"
                                           and compliance_model == "mjcf"))


def payload_separated(conditions: Conditions | None, compliance_model: str) -> bool:
    """Whether the data separated the payload's effect: the masses came from an MJCF
    (``compliance_model == "mjcf"``), or the data measured several payloads."""
    return compliance_model == "mjcf" or (
        conditions is not None and conditions.payloads_kg is not None
        and len(set(conditions.payloads_kg)) > 1)


def check_payload(conditions: Conditions | None, compliance_model: str, load: object, *,
                  required: bool) -> None:
    """Refuse a payload the calibration cannot predict: when the
    data never varied the payload and no MJCF gave the masses, the model holds at the one
    payload measured only.

    Args:
        load: the request's payload(s), kg, or None (not given).
        required: a missing ``load`` is refused when the data measured a non-zero payload
            (the command line); the API takes a missing one as the calibration's own.

    Raises:
        PayloadConditionError: another payload than the one measured (or a non-zero one
            when the data recorded none).
        MissingConditionError: ``load`` missing, ``required`` and a non-zero payload in the
            data (naming ``--load``).
    """
    if conditions is None or payload_separated(conditions, compliance_model):
        return
    pay = conditions.payloads_kg
    if load is None:
        if required and pay is not None and pay[0] != 0.0:
            raise MissingConditionError(
                f"--load: the calibration was identified with a payload of {pay[0]:g} kg in "
                "every pose and holds at that payload only; give --load "
                f"{pay[0]:g} (the payload the commands will run with)")
        return
    v = np.atleast_1d(np.asarray(load, dtype=float))
    held = 0.0 if pay is None else pay[0]
    if np.any(v != held):
        other = float(v[np.argmax(v != held)])
        what = ("no payload was recorded (no load column)" if pay is None else
                f"its data had {held:g} kg in every pose")
        raise PayloadConditionError(
            f"--load {other:g}: the calibration holds at one payload only ({what}, and no "
            f"MJCF gave the masses), so it cannot predict {other:g} kg; measure at several "
            "payloads or calibrate with --mjcf to separate the payload's effect"
            + ("" if pay is None else f", or run at --load {held:g}"))


def missing_conditions(terms: tuple[Term, ...], compliance_model: str, kappa: float,
                       conditions: Conditions | None, *, temp: object, load: object) -> None:
    """Refuse a request that leaves out a condition the model needs.

    Raises:
        MissingConditionError: a payload-dependent joint map identified on data with a
            payload, and no ``load``; a model identified at one non-zero payload and no
            ``load``; thermal expansion and no ``temp`` (naming the option).
        PayloadConditionError: a payload other than the one a model identified at one
            payload holds at (:func:`check_payload`).
    """
    check_payload(conditions, compliance_model, load, required=True)
    dep = load_dependent(terms, compliance_model)
    loaded = conditions is not None and conditions.payloads_kg is not None and any(
        p != 0.0 for p in conditions.payloads_kg)
    if load is None and dep and loaded:
        assert conditions is not None and conditions.payloads_kg is not None
        raise MissingConditionError(
            f"--load: the calibration was identified with payloads "
            f"{list(conditions.payloads_kg)} kg and its terms {list(dep)} depend on the "
            "payload; give the payload (kg) at which the commands will run (--load 0 for none)")
    if kappa != 0.0 and temp is None:
        raise MissingConditionError(
            f"--temp: the calibration found thermal expansion (kappa = {kappa:.3g} 1/degC); "
            "give the robot temperature at which the commands will run")


def out_of_range(conditions: Conditions | None, *, temp: ArrayLike | None,
                 load: ArrayLike | None) -> list[str]:
    """What in a request lies outside the measured conditions (one message each)."""
    if conditions is None:
        return []
    out = []
    for name, val, rng, unit in (("temperature", temp, conditions.temp_range_degC, "degC"),
                                 ("payload", load, conditions.load_range_kg, "kg")):
        if val is None:
            continue
        v = np.asarray(val, dtype=float)
        if rng is None:
            if name == "payload" and conditions.payloads_kg is None and np.any(v != 0.0):
                out.append("payload: the data recorded no payload (no load column); the "
                           "prediction for a payload of "
                           f"{float(np.max(np.abs(v))):g} kg is an extrapolation")
            continue
        lo, hi = rng
        if np.any((v < lo) | (v > hi)):
            out.append(f"{name} {float(v.min()):g}..{float(v.max()):g} {unit} is outside the "
                       f"measured range {lo:g}..{hi:g} {unit}: the prediction extrapolates")
    return out


def check_joint_limits(q: ArrayLike, limits: ArrayLike, ids: tuple[str, ...], what: str
                       ) -> None:
    """Refuse joint values q (T, n) outside limits (n, 2) (+-inf: unlimited).

    Raises:
        InputError: naming the first target and joint outside, its value and the limit.
    """
    q = np.asarray(q, dtype=float)
    lim = np.asarray(limits, dtype=float)
    out = (q < lim[:, 0]) | (q > lim[:, 1]) | ~np.isfinite(q)
    if out.any():
        i, k = map(int, np.argwhere(out)[0])
        raise InputError(
            f"target {ids[i]}: {what} of joint {k + 1} is {q[i, k]:.6g}, outside its limit "
            f"[{_fmt(lim[k, 0])}, {_fmt(lim[k, 1])}] ({int(out.any(axis=1).sum())} target(s) "
            "outside the joint limits)")


def _fmt(v: float) -> str:
    return f"{v:.6g}" if math.isfinite(v) else ("-inf" if v < 0 else "inf")
