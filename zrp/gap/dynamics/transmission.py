"""A drive's transmission: motor-side positions and torques mapped to the joints.

Industrial drives log what the motors see: positions after the encoder, torques (or currents)
at the motor shaft, before a gear and, on a wrist, a coupling. A :class:`Transmission` maps
them to the joint side the model speaks (eq. T1)::

    q_motor = R @ (q - offset)          q = R^-1 @ q_motor + offset
    qd = R^-1 @ qd_motor                tau = R^T @ tau_motor

``R`` (n x n, motor rows, joint columns) holds the gear ratios on its diagonal (a negative
one: the motor turns the other way) and the couplings off it (a Staubli wrist: motor 6 turns
with joints 5 + 6, ``R[5, 4] = R[5, 5] = 32``). Motor power equals joint power,
``tau_motor . qd_motor = tau . qd``, for every ``R``.

A coupled motor (a row with more than one joint) has a velocity no joint has: its friction
and rotor inertia act on every joint it turns. :meth:`Transmission.coupled_motors` gives
each one's direction at the joints ``g_k = R[k, :] / R[k, k]`` (joint-scale: its velocity is
``g_k . qd``, its torque reaches the joints as ``g_k * f``), from which
:mod:`zrp.gap.dynamics.effects` builds the motor's effects.

Read from a small TOML file (``zrp diagnose-dynamics --transmission FILE``)::

    # motor = ratio @ joint (positions); joint torque = ratio^T @ motor torque
    ratio = [[32, 0, 0, 0, 0, 0], [0, 32, 0, 0, 0, 0], [0, 0, 45, 0, 0, 0],
             [0, 0, 0, -48, 0, 0], [0, 0, 0, 0, 45, 0], [0, 0, 0, 0, 32, 32]]
    joint_offset = [0.0, -1.5707963267948966, 1.5707963267948966, 0.0, 0.0, 0.0]  # rad

``ratio`` may also be a list of n numbers (no coupling). ``joint_offset`` (rad or m, added
after the inverse; default 0) is optional. ``log = "joint"`` says that the log was already
converted to the joints (by hand, or by the controller): nothing is mapped, and the coupled
motors' effects are still candidates (default ``log = "motor"``).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError

try:
    import tomllib
except ModuleNotFoundError:  # pragma: no cover - Python 3.10
    import tomli as tomllib  # type: ignore[no-redef]

__all__ = ["MAX_RATIO", "Transmission", "load_transmission"]

#: Largest gear ratio accepted (harmonic drives reach a few hundred; 1e4 is no gear).
MAX_RATIO = 1e4
#: Largest transmission file read, bytes.
MAX_BYTES = 1_000_000
_KEYS = ("ratio", "joint_offset", "log")
_SIDES = ("motor", "joint")


@dataclass(frozen=True, kw_only=True)
class Transmission:
    """Motor side -> joint side (module docstring, eq. T1).

    Attributes:
        ratio: R, shape (n, n): motor positions = R @ joint positions.
        joint_offset: added to the joint positions after R^-1, shape (n,).
        source: where it was read (for messages and the report).
        log: "motor" (the log is at the motors: mapped) or "joint" (already at the joints).
    """

    ratio: F64
    joint_offset: F64
    source: str = "transmission"
    log: str = "motor"

    def __post_init__(self) -> None:
        _check(self.ratio, self.joint_offset, self.source)
        if self.log not in _SIDES:
            raise InputError(f"{self.source}: log must be one of {', '.join(_SIDES)}, got "
                             f"{self.log!r}")

    @property
    def n(self) -> int:
        return int(self.ratio.shape[0])

    def positions(self, q_motor: F64) -> F64:
        """Joint positions (S, n) from motor positions (S, n)."""
        return np.linalg.solve(self.ratio, q_motor.T).T + self.joint_offset

    def velocities(self, qd_motor: F64) -> F64:
        """Joint velocities (S, n) from motor velocities (S, n)."""
        return np.linalg.solve(self.ratio, qd_motor.T).T

    def torques(self, tau_motor: F64) -> F64:
        """Joint torques (S, n) from motor torques (S, n): R^T @ tau_motor."""
        return tau_motor @ self.ratio

    def coupled_motors(self) -> list[tuple[int, F64]]:
        """Each coupled motor (0-based) and its joint-scale direction g_k (n,)."""
        out = []
        for k in range(self.n):
            row = self.ratio[k]
            if np.count_nonzero(row) > 1:
                out.append((k, row / row[k]))
        return out

    def joints_of(self, k: int) -> list[int]:
        """The joints (0-based) motor ``k`` turns."""
        return [int(j) for j in np.flatnonzero(self.ratio[k])]

    def describe(self) -> str:
        """One line for the report's notes."""
        ratios = ", ".join(f"{r:g}" for r in np.diag(self.ratio))
        what = ("motor-side log mapped to the joints by" if self.log == "motor" else
                "joint-side log; the drive's motors as declared in")
        text = f"{what} the transmission of {self.source} (gear ratios {ratios}"
        couples = [f"motor {k + 1} turns with joints "
                   + " and ".join(str(j + 1) for j in self.joints_of(k))
                   for k, _ in self.coupled_motors()]
        if couples:
            text += "; " + "; ".join(couples)
        if np.any(self.joint_offset):
            text += "; joint offsets " + ", ".join(f"{v:.6g}" for v in self.joint_offset)
        return text + ")"

    def as_json(self) -> dict[str, Any]:
        return {"source": self.source, "ratio": self.ratio.tolist(),
                "joint_offset": self.joint_offset.tolist(), "log": self.log}


def _check(ratio: F64, offset: F64, src: str) -> None:
    n = ratio.shape[0] if ratio.ndim == 2 else 0
    if ratio.ndim != 2 or ratio.shape != (n, n) or n == 0:
        raise InputError(f"{src}: ratio must be a square matrix (one row per motor, one column "
                         f"per joint), got shape {ratio.shape}")
    if not np.all(np.isfinite(ratio)) or np.any(np.abs(ratio) > MAX_RATIO):
        raise InputError(f"{src}: ratio: every entry must be finite and within +-{MAX_RATIO:g}")
    zero = [k + 1 for k in range(n) if ratio[k, k] == 0.0]
    if zero:
        raise InputError(f"{src}: ratio: motor {zero[0]}'s own ratio ratio[{zero[0] - 1}]"
                         f"[{zero[0] - 1}] is 0; each motor drives its own joint")
    if np.linalg.cond(ratio) > 1e8:
        raise InputError(f"{src}: ratio is singular: the joints cannot be recovered from the "
                         "motors")
    if offset.shape != (n,) or not np.all(np.isfinite(offset)) or np.any(np.abs(offset)
                                                                          > 4 * np.pi):
        raise InputError(f"{src}: joint_offset must be {n} finite values within +-4 pi "
                         f"(rad), got {offset.tolist()!r}")


def _matrix(value: Any, src: str) -> F64:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"{src}: ratio must be numbers (a list of n, or n rows of n)"
                         ) from None
    return np.diag(arr) if arr.ndim == 1 else arr


def load_transmission(path: str | os.PathLike[str]) -> Transmission:
    """Read a transmission TOML file (module docstring); an InputError naming the file and
    the key on any problem."""
    p = Path(path)
    src = p.name
    if not p.is_file():
        raise InputError(f"--transmission: {path}: no such file")
    if p.stat().st_size > MAX_BYTES:
        raise InputError(f"--transmission: {src} is over {MAX_BYTES} bytes; not a "
                         "transmission file")
    try:
        data = tomllib.loads(p.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        raise InputError(f"--transmission: {src} is not UTF-8 text") from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"--transmission: {src}: not TOML ({exc})") from None
    unknown = sorted(set(data) - set(_KEYS))
    if unknown:
        raise InputError(f"--transmission: {src}: unknown key {unknown[0]!r}; known: "
                         f"{', '.join(_KEYS)}")
    if "ratio" not in data:
        raise InputError(f"--transmission: {src}: missing key 'ratio' (the gear ratios)")
    ratio = _matrix(data["ratio"], f"--transmission: {src}")
    n = ratio.shape[0] if ratio.ndim else 0
    try:
        offset = np.asarray(data.get("joint_offset", np.zeros(n)), dtype=float).ravel()
    except (TypeError, ValueError):
        raise InputError(f"--transmission: {src}: joint_offset must be numbers") from None
    side = data.get("log", "motor")
    return Transmission(ratio=ratio, joint_offset=offset, source=src,
                        log=side if isinstance(side, str) else repr(side))
