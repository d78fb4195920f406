"""The joint torque log: the reader (:func:`load_torque_log`) of logs as controllers write
them, and the writer.

One row per sample, rows in time order. Columns (header names, any order; a unit may be
declared in brackets, ``q1 [deg]`` or ``q1[deg]``, read by :func:`zrp.units.split_unit` with
the units of :data:`zrp.units.QUANTITY_UNITS`; without one a column is SI):

* ``t`` (required): time stamp; s (``ms``, ``us``, ``ns``), or an absolute (epoch) clock.
* ``q1`` .. ``qn`` (required): joint positions; rad (``deg``) for hinges, m (``mm``) for slides.
* ``qd1`` .. ``qdn`` (optional, all n): joint velocities; rad/s (``deg/s``), m/s (``mm/s``).
  Without them the velocities are derived (:func:`zrp.gap.dynamics.states.derive_states`).
* ``tau1`` .. ``taun``: measured joint torques; N m (``mNm``), N for slides. Or
* ``i1`` .. ``in``: motor currents; A (``mA``), with ``torque_constant`` (N m/A at the joint,
  gear ratio included, signed: negative when the drive's current counts the other way; zero
  refused): torque = k_t * i. One of the two groups is required; with both, the
  torques are used and the currents are ignored (said in a warning).
* ``qc1`` .. ``qcn`` (optional, all n): the commanded positions (the re-simulation drives them).
* ``payload`` (optional): an external payload mass at the tool, kg (``g``), per row.

The names controllers log (libfranka, UR RTDE, KUKA FRI/Sunrise, a ROS ``joint_states``
export) are read directly, by the tables of :mod:`zrp.gap.dynamics.columns`; the form used is
said. The clock may jitter, repeat rows and have gaps (:mod:`zrp.gap.dynamics.timebase`: the
log is split into segments at gaps, repeats dropped); a joint whose torque never changes or
whose position never moves is excluded and named (:attr:`TorqueLog.unmeasured`). All that was
done is recorded in :attr:`TorqueLog.conditioning`, for the report.

Lines that are blank or start with ``#`` are skipped. Every problem (a non-number, a value
outside the physical domain of :mod:`zrp.gap.dynamics.logcheck`, a time going backwards, a
clock unit the values contradict, bytes that are not UTF-8, an overlong line) is an
:class:`~zrp.errors.InputError` naming the file, line and column
(:mod:`zrp.gap.dynamics.logfile`). Cost: linear in the rows.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.data.measurements import DataWarning
from zrp.gap.dynamics.ambiguous import other_clock, seconds_and_nanos
from zrp.gap.dynamics.columns import GROUP_KIND, Mapping, map_header, time_columns
from zrp.gap.dynamics.frozen import frozen_joints
from zrp.gap.dynamics.logcheck import check_log, unmeasured_joints
from zrp.gap.dynamics.logfile import RawTable, read_table
from zrp.gap.dynamics.timebase import Conditioning, clock, condition
from zrp.gap.dynamics.transmission import Transmission
from zrp.output import atomic_path
from zrp.units import SI_UNITS, si_factor

__all__ = ["GROUPS", "MAX_ROWS", "Conditioning", "TorqueLog", "excluded_notes",
           "load_torque_log", "torque_constants", "write_torque_log"]

#: Most data rows read by default (about 0.2 GB of numbers at 12 joints).
MAX_ROWS = 5_000_000

#: Per-joint column groups: prefix -> unit kind.
GROUPS = GROUP_KIND


@dataclass(frozen=True)
class TorqueLog:
    """A loaded torque log, all in SI (rad, rad/s, N m; m, m/s, N for slides).

    Attributes:
        t: time, s, shape (S,), strictly increasing (steps may jitter; gaps split segments).
        q: joint positions, shape (S, n).
        qd: joint velocities, shape (S, n), or None (derive them).
        tau: measured joint torques, shape (S, n) (from currents times ``torque_constant``
            when the log has currents).
        qc: commanded joint positions, shape (S, n), or None.
        payload: payload mass per row, kg, shape (S,), or None.
        lines: the file line of each row, shape (S,).
        source: the file name (for messages).
        torque_from: "tau" (measured torques) or "current" (currents times k_t).
        segments: (start, stop) sample ranges without a gap, tiling the samples; empty: one.
        unmeasured: joint index (0-based) -> why its torque is not data (excluded).
        joint_names: the joints' names in log order when the log names them (ROS), else ().
        conditioning: what was done to the log on reading (:class:`Conditioning`).
        transmission: the motor-to-joint map the log was read through (a motor-side log),
            or None (the log is at the joints).
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
    segments: tuple[tuple[int, int], ...] = ()
    unmeasured: dict[int, str] = field(default_factory=dict)
    joint_names: tuple[str, ...] = ()
    conditioning: Conditioning = field(default_factory=Conditioning)
    transmission: Transmission | None = None

    def __post_init__(self) -> None:
        check_log(self)

    @property
    def n_joints(self) -> int:
        return int(self.q.shape[1])

    @property
    def n_samples(self) -> int:
        return int(self.t.size)

    @property
    def segment_ranges(self) -> tuple[tuple[int, int], ...]:
        """The (start, stop) sample ranges without a gap (one when none was found)."""
        return self.segments or ((0, self.n_samples),)

    @property
    def measured(self) -> np.ndarray:
        """Per joint, whether its torque is data (not in :attr:`unmeasured`)."""
        return np.array([k not in self.unmeasured for k in range(self.n_joints)])

    def first(self, k: int) -> TorqueLog:
        """The first ``k`` samples (at least 2), segments and record kept."""
        k = min(max(2, int(k)), self.n_samples)
        cut = lambda a: None if a is None else a[:k]  # noqa: E731
        segs = tuple((a, min(b, k)) for a, b in self.segments if a < k)
        return TorqueLog(self.t[:k], self.q[:k], cut(self.qd), self.tau[:k], cut(self.qc),
                         cut(self.payload), self.lines[:k] if self.lines.size else self.lines,
                         self.source, self.torque_from, segs if len(segs) > 1 else (),
                         dict(self.unmeasured), self.joint_names, self.conditioning,
                         self.transmission)

    @property
    def dt(self) -> float:
        """The sampling step, s (median of the steps within segments)."""
        steps = [np.diff(self.t[a:b]) for a, b in self.segment_ranges if b - a > 1]
        return float(np.median(np.concatenate(steps))) if steps else float(np.diff(self.t)[0])


def _factors(m: Mapping, src: str) -> tuple[dict[int, float], list[str]]:
    """Column -> factor to SI, and the columns without a declared unit (SI assumed)."""
    out: dict[int, float] = {}
    bare: list[str] = []
    kinds = {c: GROUP_KIND[g] for g, cols in m.groups.items() for c in cols}
    if m.payload is not None:
        kinds[m.payload] = "mass"
    for c, kind in kinds.items():
        unit = m.units[c] or m.defaults.get(c)
        if m.units[c] is None and c not in m.defaults and m.form in ("zrp", "motor side"):
            bare.append(m.names[c])  # a controller's form has its documented (SI) units
        out[c] = si_factor(kind, unit, f"{src} line 1: column {m.names[c]}")
    return out, bare


def _torques(block: dict[str, F64], m: Mapping, torque_constant: Sequence[float] | None,
             src: str, first_row: list[str]) -> tuple[F64, str]:
    n = m.n
    if "tau" in block:
        if "i" in block:
            warnings.warn(f"{src}: both torques and currents are given; the torques are used, "
                          "the currents ignored", DataWarning, stacklevel=4)
        return block["tau"], "tau"
    if torque_constant is None:
        raise InputError(f"torque_constant: {src} has motor currents ({m.form} form) but no "
                         f"torques; give the {n} torque constants (N m/A at the joint, gear "
                         "included)")
    return block["i"] * torque_constants(torque_constant, n, _joint_names(m, first_row)), \
        "current"


def torque_constants(torque_constant: Sequence[float], n: int, names: Sequence[str] = ()
                     ) -> F64:
    """The drives' signed torque constants, N m/A at the joint (gear included), one per
    joint: finite and nonzero; negative is a drive whose current counts the other way. A
    zero is refused naming the joint (``names``: the log's, else numbered)."""
    try:
        kt = np.asarray(torque_constant, dtype=float).ravel()
    except (TypeError, ValueError):
        kt = np.zeros(0)
    if kt.shape != (n,) or not np.all(np.isfinite(kt)):
        raise InputError(f"torque_constant: expected {n} finite values (N m/A, signed), got "
                         f"{torque_constant!r}")
    zero = [k for k in range(n) if kt[k] == 0.0]
    if zero:
        who = ", ".join(f"joint {k + 1}" + (f" ({names[k]})" if len(names) == n else "")
                        for k in zero)
        raise InputError(f"torque_constant: zero for {who}; a drive's torque constant is "
                         "nonzero (negative when its current counts the other way)")
    return kt


def _joint_names(m: Mapping, first_row: list[str]) -> tuple[str, ...]:
    if m.joint_names:
        return m.joint_names
    if m.name_cells and len(first_row) > max(m.name_cells):
        return tuple(first_row[c].strip() for c in m.name_cells)
    return ()


def excluded_notes(unmeasured: dict[int, str], names: tuple[str, ...]) -> tuple[str, ...]:
    """The words of :attr:`TorqueLog.unmeasured` for :attr:`Conditioning.excluded`."""
    return tuple(f"joint {k + 1}{f' ({names[k]})' if names else ''}: {why}; its torque is "
                 "not used" for k, why in sorted(unmeasured.items()))


def _read(p: Path, src: str, n_joints: int | None, max_rows: int | None, clock_required: bool
          ) -> tuple[Mapping, dict[int, int], RawTable, dict[int, float], list[str]]:
    """The mapping, column -> position in the numbers read, the numbers, the factors to SI
    and the columns of no declared unit."""
    try:
        header, _ = read_table(p, src, None, max_rows)
        m = map_header(header, src, clock_required=clock_required)
        if n_joints is not None and n_joints != m.n:
            raise InputError(f"{src} line 1: the log has {m.n} joints ({m.form} form), but "
                             f"the model has {n_joints}")
        factor, bare = _factors(m, src)
        cols = sorted({c for g in m.groups.values() for c in g}
                      | {c for c in (m.time, m.payload, m.time_ns) if c is not None})
        _, raw = read_table(p, src, cols, max_rows)
    except OSError as exc:
        raise InputError(f"{src}: cannot read ({exc.strerror or exc})") from None
    if raw is None:
        raise InputError(f"{src}: no data rows after the header")
    bare = ([m.names[m.time]] if m.time is not None and m.units[m.time] is None
            and m.form == "zrp" else []) + bare
    return m, {c: k for k, c in enumerate(cols)}, raw, factor, bare


def _time(m: Mapping, raw: RawTable, at: dict[int, int], rate_hz: float | None, src: str
          ) -> tuple[F64, str]:
    """The clock in s and what was assumed: the log's own, or the given rate."""
    if m.time is None:
        if rate_hz is None or not np.isfinite(rate_hz) or not 1.0 <= rate_hz <= 1e6:
            raise InputError(f"--rate: expected a sampling rate of 1 Hz .. 1 MHz for {src}, "
                             f"got {rate_hz!r}")
        n = raw.values.shape[0]
        return np.arange(n) / float(rate_hz), (f"no clock column: samples {1e3 / rate_hz:.4g} "
                                               f"ms apart (the given rate, {rate_hz:g} Hz)")
    names = [m.names[i] for i in range(len(m.names))]
    also = other_clock(names, m.time, time_columns(names), src)
    t_raw, ns_note = raw.values[:, at[m.time]], ""
    if m.time_ns is not None:  # a Sunrise trace: ZeitInSec + ZeitInNanoSec
        t_raw, ns_note = seconds_and_nanos(t_raw, raw.values[:, at[m.time_ns]],
                                           names[m.time], names[m.time_ns], src)
    t, said = clock(t_raw, m.units[m.time], _default_time(m), m.names[m.time], src)
    return t, said + ns_note + also


def _at_joints(block: dict[str, F64], tau: F64, m: Mapping, tr: Transmission | None, src: str
               ) -> tuple[dict[str, F64], F64]:
    """Motor-side positions and torques mapped to the joints (eq. T1 of
    :mod:`zrp.gap.dynamics.transmission`), or the block as it is."""
    if tr is None:
        if m.form == "motor side":
            raise InputError(f"--transmission: {src} is a motor-side log (qm.., taum..); give "
                             "the transmission that maps it to the joints (gear ratios, "
                             "coupling, offsets)")
        return block, tau
    if tr.n != m.n:
        raise InputError(f"--transmission: {tr.source} maps {tr.n} motors, but {src} has "
                         f"{m.n}")
    if tr.log == "joint":
        if m.form == "motor side":
            raise InputError(f"--transmission: {tr.source} says log = \"joint\", but {src} "
                             "names motor-side columns (qm.., taum..)")
        return block, tau
    out = dict(block)
    out["q"] = tr.positions(block["q"])
    for g in ("qd",):
        if g in block:
            out[g] = tr.velocities(block[g])
    if "qc" in block:
        out["qc"] = tr.positions(block["qc"])
    return out, tr.torques(tau)


def load_torque_log(path: str | os.PathLike[str], *, torque_constant: Sequence[float] | None = None,
                    n_joints: int | None = None, max_rows: int | None = MAX_ROWS,
                    transmission: Transmission | None = None,
                    rate_hz: float | None = None) -> TorqueLog:
    """Read a torque log (format in the module docstring), converting to SI.

    Args:
        path: the CSV file.
        torque_constant: per joint, N m/A at the joint, signed; needed when the log has
            currents only.
        n_joints: the model's number of joints; None: as many as the position columns.
        max_rows: most data rows read; a larger file is refused (None: no limit).
        transmission: the log is motor side (positions, torques or currents at the motors):
            mapped to the joints by it (a torque constant is then N m/A at the motor).
        rate_hz: the sampling rate of a log without a time column.

    Raises:
        InputError: naming the file, line and column of the first problem.
    """
    p = Path(path)
    src = str(p.name)
    if not p.is_file():
        raise InputError(f"{path}: no such file" if not p.exists() else
                         f"{path}: not a regular file")
    m, at, raw, factor, bare = _read(p, src, n_joints, max_rows, rate_hz is None)
    t, said = _time(m, raw, at, rate_hz, src)
    kept, segments, rec = condition(t, raw.values, raw.lines, src)
    vals, lines, t = raw.values[kept], raw.lines[kept], t[kept]
    block = {g: vals[:, [at[c] for c in cs]] * np.array([factor[c] for c in cs])
             for g, cs in m.groups.items()}
    tau, tfrom = _torques(block, m, torque_constant, src, raw.first_row)
    block, tau = _at_joints(block, tau, m, transmission, src)
    payload = None if m.payload is None else vals[:, at[m.payload]] * factor[m.payload]
    names = _joint_names(m, raw.first_row)
    frozen, frozen_notes = frozen_joints(t, block["q"], tau, lines)
    unmeasured = {**frozen, **unmeasured_joints(block["q"], tau)}
    if len(unmeasured) == m.n:
        raise InputError(f"{src}: no joint's torque is data: " + "; ".join(
            f"joint {k + 1}: {w}" for k, w in sorted(unmeasured.items())))
    if bare:
        warnings.warn(f"{src}: no unit declared for {', '.join(bare)}; "
                      f"taken as SI ({', '.join(f'{k} {u}' for k, u in SI_UNITS.items())}; m, "
                      "m/s, N for slides)", DataWarning, stacklevel=2)
    columns = m.describe() + ("" if transmission is None else "; " + transmission.describe())
    cond = Conditioning(columns=columns, clock=said, skipped_lines=raw.skipped,
                        excluded=(*excluded_notes(unmeasured, names), *frozen_notes),
                        **rec)  # type: ignore[arg-type]
    return TorqueLog(t, block["q"], block.get("qd"), tau, block.get("qc"), payload, lines, src,
                     tfrom, segments if len(segments) > 1 else (), unmeasured, names, cond,
                     transmission)


def _default_time(m: Mapping) -> str:
    """The time unit a form's clock is in when undeclared (ROS stamps: ns)."""
    name = m.names[m.time].lower()
    return "ns" if name in ("field.header.stamp", "header.stamp", "%time") else "s"


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
