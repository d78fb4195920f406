"""The joint torque log: a strict reader (:func:`load_torque_log`) and the writer.

One row per sample, rows in time order, constant rate (any rate). Columns (header names, any
order; a unit may be declared in brackets, ``q1 [deg]`` or ``q1[deg]``, read by
:func:`zrp.units.split_unit` with the units of :data:`zrp.units.QUANTITY_UNITS`; without one a
column is SI):

* ``t`` (required): time stamp; s (``ms``, ``us``).
* ``q1`` .. ``qn`` (required): joint positions; rad (``deg``) for hinges, m (``mm``) for slides.
* ``qd1`` .. ``qdn`` (optional, all n): joint velocities; rad/s (``deg/s``), m/s (``mm/s``).
  Without them the velocities are derived (:func:`zrp.gap.dynamics.states.derive_states`).
* ``tau1`` .. ``taun``: measured joint torques; N m (``mNm``), N for slides. Or
* ``i1`` .. ``in``: motor currents; A (``mA``), with ``torque_constant`` (N m/A at the joint,
  gear ratio included): torque = k_t * i. One of the two groups is required; with both, the
  torques are used and the currents are ignored (said in a warning).
* ``qc1`` .. ``qcn`` (optional, all n): the commanded positions (the re-simulation drives them).
* ``payload`` (optional): an external payload mass at the tool, kg (``g``), per row.

Lines starting with ``#`` are comments. Nothing is dropped silently: an unknown column, an
incomplete group, a missing value, a non-number, a NaN, a time going backwards or a gap in the
sampling is an :class:`~zrp.errors.InputError` naming the file, line and column, as the
measurement CSV (:mod:`zrp.gap.data.csvfile`).

Cost: linear in the rows. The numbers are parsed by NumPy's C reader (``np.loadtxt``, about
1 s a million rows of 20 columns); only when that fails is the file read again row by row to
name the first bad line and column.
"""

from __future__ import annotations

import csv
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.data.csvrows import number_cell
from zrp.gap.data.measurements import DataWarning
from zrp.output import atomic_path
from zrp.units import SI_UNITS, si_factor, split_unit

__all__ = ["GROUPS", "MAX_ROWS", "TorqueLog", "load_torque_log", "write_torque_log"]

#: Most data rows read by default (about 0.2 GB of numbers at 12 joints).
MAX_ROWS = 5_000_000

#: Per-joint column groups: prefix -> unit kind.
GROUPS = {"q": "position", "qd": "velocity", "tau": "effort", "i": "current", "qc": "position"}

#: Largest relative deviation of a time step from the median step.
JITTER = 0.05


@dataclass(frozen=True)
class TorqueLog:
    """A loaded torque log, all in SI (rad, rad/s, N m; m, m/s, N for slides).

    Attributes:
        t: time, s, shape (S,), strictly increasing at a constant step.
        q: joint positions, shape (S, n).
        qd: joint velocities, shape (S, n), or None (derive them).
        tau: measured joint torques, shape (S, n) (from currents times ``torque_constant``
            when the log has currents).
        qc: commanded joint positions, shape (S, n), or None.
        payload: payload mass per row, kg, shape (S,), or None.
        lines: the file line of each row, shape (S,).
        source: the file name (for messages).
        torque_from: "tau" (measured torques) or "current" (currents times k_t).
    """

    t: F64
    q: F64
    qd: F64 | None
    tau: F64
    qc: F64 | None = None
    payload: F64 | None = None
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    source: str = "log"
    torque_from: str = "tau"

    @property
    def n_joints(self) -> int:
        return int(self.q.shape[1])

    @property
    def n_samples(self) -> int:
        return int(self.t.size)

    @property
    def dt(self) -> float:
        """The sampling step, s (median of the steps)."""
        return float(np.median(np.diff(self.t)))


@dataclass(frozen=True)
class _Layout:
    """The checked header: each column's position and its factor to SI."""

    n: int
    index: dict[str, int]
    factor: dict[str, float]
    groups: tuple[str, ...]
    defaulted: tuple[str, ...]


def _split_name(name: str) -> tuple[str, int] | None:
    """(group prefix, joint number) of ``q3``/``qd3``/``tau3``/``i3``/``qc3``; None otherwise."""
    for prefix in sorted(GROUPS, key=len, reverse=True):
        rest = name[len(prefix):]
        if name.startswith(prefix) and rest.isdigit() and not rest.startswith("0"):
            return prefix, int(rest)
    return None


def _kind(name: str, src: str) -> str:
    if name == "t":
        return "time"
    if name == "payload":
        return "mass"
    split = _split_name(name)
    if split is None:
        raise InputError(f"{src} line 1: unknown column {name!r}; valid columns are t, q1..qn, "
                         "qd1..qdn, tau1..taun, i1..in, qc1..qcn, payload")
    return GROUPS[split[0]]


def _group_present(names: list[str], prefix: str, n: int, src: str) -> bool:
    """Whether all of prefix1..prefixn are given (none: False; some: an error)."""
    cols = [c for c in names if (_split_name(c) or ("", 0))[0] == prefix]
    want = [f"{prefix}{k}" for k in range(1, n + 1)]
    extra = sorted(set(cols) - set(want))
    if extra:
        raise InputError(f"{src} line 1: column(s) {', '.join(extra)} beyond the {n} joints "
                         f"of q1..q{n}")
    if cols and len(cols) != n:
        raise InputError(f"{src} line 1: {prefix}1..{prefix}{n} must all be given; got "
                         f"only {', '.join(c for c in want if c in cols)}")
    return bool(cols)


def _groups(names: list[str], src: str) -> tuple[int, tuple[str, ...]]:
    """The number of joints (from q1..qn) and the complete groups present."""
    n = sum(1 for c in names if (_split_name(c) or ("", 0))[0] == "q")
    missing = [c for c in ["t", *(f"q{k}" for k in range(1, n + 1))] if c not in names]
    if n == 0 or missing:
        raise InputError(f"{src} line 1: missing column(s) {', '.join(missing) or 'q1'}; a "
                         "torque log needs t, q1..qn and tau1..taun (or i1..in)")
    present = tuple(p for p in GROUPS if _group_present(names, p, n, src))
    if "tau" not in present and "i" not in present:
        raise InputError(f"{src} line 1: no torques: give tau1..tau{n} (N m) or the motor "
                         f"currents i1..i{n} (A) with a torque constant")
    return n, present


def _layout(header: list[str], src: str) -> _Layout:
    parsed = [split_unit(h, f"{src} line 1") for h in header]
    names = [p[0] for p in parsed]
    dup = sorted({c for c in names if names.count(c) > 1})
    if dup:
        raise InputError(f"{src} line 1: column(s) {', '.join(dup)} appear more than once")
    kinds = [_kind(c, src) for c in names]
    n, groups = _groups(names, src)
    factor = {c: si_factor(k, u, f"{src} line 1: column {c}")
              for (c, u), k in zip(parsed, kinds, strict=True)}
    defaulted = tuple(c for (c, u) in parsed if u is None)
    return _Layout(n, {c: i for i, c in enumerate(names)}, factor, groups, defaulted)


def _locate_error(path: Path, src: str, names: list[str]) -> InputError:
    """Read the file again row by row and return the error of its first bad row."""
    with open(path, newline="", encoding="utf-8-sig") as fh:
        reader = csv.reader(fh)
        next(reader)
        for rec in reader:
            line = reader.line_num
            if not rec or all(not f.strip() for f in rec) or rec[0].lstrip().startswith("#"):
                continue
            if len(rec) != len(names):
                return InputError(f"{src} line {line}: {len(rec)} fields, but the header has "
                                  f"{len(names)} ({', '.join(names)})")
            for text, col in zip(rec, names, strict=True):
                number_cell(text, src, line, col)
    return InputError(f"{src}: not a numeric CSV after its header")


def _row_lines(path: Path) -> np.ndarray:
    """The file line of each data row (comments and blank lines skipped)."""
    lines = []
    with open(path, encoding="utf-8-sig") as fh:
        next(fh, None)
        for k, text in enumerate(fh, start=2):
            s = text.strip()
            if s and not s.startswith("#") and s.strip(",").strip():
                lines.append(k)
    return np.asarray(lines, dtype=np.int64)


def _read_numbers(path: Path, src: str, names: list[str], max_rows: int) -> np.ndarray:
    try:
        a = np.loadtxt(path, delimiter=",", skiprows=1, comments="#", ndmin=2, dtype=float,
                       encoding="utf-8-sig", max_rows=max_rows + 1)
    except ValueError:
        raise _locate_error(path, src, names) from None
    if a.shape[0] == 0:
        raise InputError(f"{src}: no data rows after the header")
    if a.shape[1] != len(names):
        raise _locate_error(path, src, names)
    if a.shape[0] > max_rows:
        raise InputError(f"{src}: more than max_rows = {max_rows} data rows; pass a larger "
                         "max_rows (or None) to read it")
    if not np.isfinite(a).all():
        raise _locate_error(path, src, names)
    return a


def _time_checks(t: F64, lines: np.ndarray, src: str) -> None:
    """Strictly increasing at a constant step (within :data:`JITTER`)."""
    if t.size < 2:
        raise InputError(f"{src}: one data row; a torque log needs a time series")
    dt = np.diff(t)
    bad = np.flatnonzero(dt <= 0.0)
    if bad.size:
        i = int(bad[0]) + 1
        raise InputError(f"{src} line {lines[i]}: column t is {t[i]!r} s, not later than the "
                         f"previous row's {t[i - 1]!r} s; rows must be in time order")
    step = float(np.median(dt))
    off = np.flatnonzero(np.abs(dt - step) > JITTER * step)
    if off.size:
        i = int(off[0]) + 1
        raise InputError(f"{src} line {lines[i]}: time step {dt[i - 1]:.6g} s, but the log's "
                         f"step is {step:.6g} s; the log must be sampled at a constant rate "
                         f"(within {JITTER:.0%}): resample it or split it at the gap")


def _torques(a: np.ndarray, lay: _Layout, torque_constant: Sequence[float] | None, src: str
             ) -> tuple[F64, str]:
    n = lay.n
    if "tau" in lay.groups:
        if "i" in lay.groups:
            warnings.warn(f"{src}: both torques (tau..) and currents (i..) are given; the "
                          "torques are used, the currents ignored", DataWarning, stacklevel=3)
        return _block(a, lay, "tau"), "tau"
    if torque_constant is None:
        raise InputError(f"torque_constant: {src} has motor currents i1..i{n} but no torques; "
                         f"give the {n} torque constants (N m/A at the joint, gear included)")
    kt = np.asarray(torque_constant, dtype=float).ravel()
    if kt.shape != (n,) or not np.all(np.isfinite(kt)) or np.any(kt <= 0.0):
        raise InputError(f"torque_constant: expected {n} positive finite values (N m/A), got "
                         f"{list(np.atleast_1d(torque_constant))}")
    return _block(a, lay, "i") * kt, "current"


def _block(a: np.ndarray, lay: _Layout, prefix: str) -> F64:
    cols = [f"{prefix}{k}" for k in range(1, lay.n + 1)]
    return a[:, [lay.index[c] for c in cols]] * np.array([lay.factor[c] for c in cols])


def load_torque_log(path: str | os.PathLike[str], *, torque_constant: Sequence[float] | None = None,
                    n_joints: int | None = None, max_rows: int = MAX_ROWS) -> TorqueLog:
    """Read a torque log (format in the module docstring) strictly, converting to SI.

    Args:
        path: the CSV file.
        torque_constant: per joint, N m/A at the joint; needed when the log has currents only.
        n_joints: the model's number of joints; None: as many as the q columns.
        max_rows: most data rows read; a larger file is refused.

    Raises:
        InputError: naming the file, line and column of the first problem.
    """
    p = Path(path)
    src = str(p.name)
    if not p.is_file():
        raise InputError(f"{path}: no such file")
    try:
        with open(p, newline="", encoding="utf-8-sig") as fh:
            header = next(csv.reader(fh), None)
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{src}: cannot read as UTF-8 text ({exc})") from exc
    if not header:
        raise InputError(f"{src}: empty file; expected a header line t, q1..qn, tau1..taun")
    lay = _layout(header, src)
    if n_joints is not None and n_joints != lay.n:
        raise InputError(f"{src} line 1: q1..q{lay.n} are {lay.n} joints, but the model has "
                         f"{n_joints}")
    names = sorted(lay.index, key=lay.index.get)
    a = _read_numbers(p, src, names, max_rows)
    lines = _row_lines(p)[: a.shape[0]]
    t = a[:, lay.index["t"]] * lay.factor["t"]
    _time_checks(t, lines, src)
    tau, tfrom = _torques(a, lay, torque_constant, src)
    payload = None
    if "payload" in lay.index:
        payload = a[:, lay.index["payload"]] * lay.factor["payload"]
        if np.any(payload < 0.0):
            i = int(np.argmax(payload < 0.0))
            raise InputError(f"{src} line {lines[i]}: column payload is {payload[i]:g}; "
                             "expected a mass >= 0 kg")
    if lay.defaulted:
        warnings.warn(f"{src}: no unit declared for {', '.join(lay.defaulted)}; taken as SI "
                      f"({', '.join(f'{k} {u}' for k, u in SI_UNITS.items())}; m, m/s, N for "
                      "slides)", DataWarning, stacklevel=2)
    return TorqueLog(t, _block(a, lay, "q"), _block(a, lay, "qd") if "qd" in lay.groups
                     else None, tau, _block(a, lay, "qc") if "qc" in lay.groups else None,
                     payload, lines, src, tfrom)


def write_torque_log(log: TorqueLog, path: str | os.PathLike[str], *, overwrite: bool = False
                     ) -> Path:
    """Write ``log`` as a torque log CSV with SI units declared, atomically; an existing file
    is replaced only with ``overwrite``."""
    n = log.n_joints
    cols = [("t [s]", log.t[:, None])]
    groups = [("q", "rad", log.q), ("qd", "rad/s", log.qd), ("tau", "Nm", log.tau),
              ("qc", "rad", log.qc)]
    for prefix, unit, block in groups:
        if block is not None:
            cols += [(f"{prefix}{k + 1} [{unit}]", block[:, k:k + 1]) for k in range(n)]
    if log.payload is not None:
        cols.append(("payload [kg]", log.payload[:, None]))
    table = np.hstack([c[1] for c in cols])
    with atomic_path(path, overwrite=overwrite) as tmp:
        np.savetxt(tmp, table, delimiter=",", fmt="%.17g",
                   header=",".join(c[0] for c in cols), comments="")
    return Path(path)
