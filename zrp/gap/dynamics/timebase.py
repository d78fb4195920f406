"""The clock of a torque log as a controller writes it: its unit, repeated rows, gaps and
segments, and the record of what was done (:class:`Conditioning`).

* **Unit.** A declared unit (``t [ms]``) is cross-checked against the values: the median
  step must lie within :data:`STEP_RANGE` (20 us to 0.1 s: 50 kHz to 10 Hz), else the log is
  refused, saying which unit the values look like. An undeclared clock takes the form's
  unit (s; ns for ROS stamps) when that gives such a step, else the one of s, ms, us, ns
  that gives a plausible step nearest 1 ms (said). An absolute (epoch) clock, first stamp
  beyond :data:`EPOCH_S`, is taken relative to the first row (said).
* **Repeats.** A row whose time stamp equals the previous row's is dropped: an exact repeat
  (every value equal: a logger writing the same sample twice) is counted; a repeated stamp
  with other values keeps the first row, and is counted and named apart. A time going
  backwards is an error naming the line.
* **Gaps and segments.** A step longer than :data:`GAP` median steps is a gap: the log is
  split there into segments, and nothing downstream is differentiated or filtered across
  a gap (:func:`zrp.gap.dynamics.states.derive_states` works per segment). Segments with
  fewer than :data:`MIN_ROWS` rows are dropped and named (a single segment is kept: the
  filter says if it is too short).
* **Jitter.** Steps within a segment may vary (0.8-1.6 ms at 1 kHz is usual): the
  derivatives are taken on the real time axis (:mod:`zrp.gap.dynamics.localpoly`), not on
  an assumed grid, so nothing is resampled and no sample is invented.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.units import QUANTITY_UNITS

__all__ = ["EPOCH_S", "GAP", "MIN_ROWS", "STEP_RANGE", "Conditioning", "Gap", "clock",
           "condition"]

#: Plausible median step of a controller's joint log, s (50 kHz .. 10 Hz).
STEP_RANGE = (2e-5, 0.1)
#: A first time stamp beyond this (s) is an absolute (epoch) clock.
EPOCH_S = 1e6
#: A step longer than this many median steps is a gap.
GAP = 1.75
#: Fewest rows of a segment kept (a cubic local fit needs five).
MIN_ROWS = 5
_SHOWN = 8


@dataclass(frozen=True)
class Gap:
    """A gap: the file line of the row after it, its length (s) and in median steps."""

    line: int
    seconds: float
    steps: float


@dataclass(frozen=True)
class Conditioning:
    """What was done to a log on reading (all counts of rows; lines are file lines).

    Attributes:
        columns: how the header was read (:meth:`zrp.gap.dynamics.columns.Mapping.describe`).
        clock: the clock's unit and origin, in words.
        step_s: the median step, s; step_min_s, step_max_s: the extremes within segments.
        repeats: exact repeats dropped; repeat_lines: the first of them.
        conflicts: rows dropped for repeating the previous time stamp with other values;
            conflict_lines: the first of them.
        gaps: the gaps found (the log is split there).
        dropped: the segments dropped as too short, in words.
        skipped_lines: blank, whitespace-only and comment lines skipped.
        excluded: the joints whose torque is not used (:attr:`TorqueLog.unmeasured`), words.
        joints: how the log's joints were matched to the model's (names, order, left out).
    """

    columns: str = ""
    clock: str = ""
    step_s: float = 0.0
    step_min_s: float = 0.0
    step_max_s: float = 0.0
    repeats: int = 0
    repeat_lines: tuple[int, ...] = ()
    conflicts: int = 0
    conflict_lines: tuple[int, ...] = ()
    gaps: tuple[Gap, ...] = ()
    dropped: tuple[str, ...] = ()
    skipped_lines: int = 0
    excluded: tuple[str, ...] = ()
    joints: tuple[str, ...] = ()

    def describe(self) -> list[str]:
        """What was done to the log, one line each (for the report)."""
        out = [s for s in (self.columns, self.clock) if s]
        if self.step_s > 0.0:
            out.append(f"sampling: median step {self.step_s * 1e3:.4g} ms "
                       f"({1.0 / self.step_s:.4g} Hz), steps {self.step_min_s * 1e3:.3g}-"
                       f"{self.step_max_s * 1e3:.3g} ms within segments; derivatives on the "
                       "real time axis (no resampling)")
        if self.repeats:
            out.append(f"{self.repeats} exact repeated row(s) dropped (lines "
                       f"{_lines(self.repeat_lines, self.repeats)})")
        if self.conflicts:
            out.append(f"{self.conflicts} row(s) repeating the previous time stamp with other "
                       f"values dropped, the first kept (lines "
                       f"{_lines(self.conflict_lines, self.conflicts)})")
        if self.gaps:
            shown = ", ".join(f"line {g.line} ({g.seconds * 1e3:.3g} ms)"
                              for g in self.gaps[:_SHOWN])
            out.append(f"{len(self.gaps)} gap(s) longer than {GAP:g} steps: the log is split "
                       f"into {len(self.gaps) + 1} segments, never filtered across a gap: "
                       f"{shown}{' ...' if len(self.gaps) > _SHOWN else ''}")
        out += [f"dropped: {d}" for d in self.dropped]
        out += [f"excluded: {e}" for e in self.excluded]
        out += [f"joints: {j}" for j in self.joints]
        if self.skipped_lines:
            out.append(f"{self.skipped_lines} blank or comment line(s) skipped")
        return out


def _lines(lines: tuple[int, ...], count: int) -> str:
    return ", ".join(map(str, lines)) + (" ..." if count > len(lines) else "")


def _plausible(step_s: float) -> bool:
    return STEP_RANGE[0] <= step_s <= STEP_RANGE[1]


def _looks_like(step_raw: float) -> str | None:
    """The time unit that makes ``step_raw`` a plausible step nearest 1 ms, or None."""
    table = QUANTITY_UNITS["time"]
    ok = [u for u, f in table.items() if _plausible(step_raw * f)]
    return min(ok, key=lambda u: abs(math.log10(step_raw * table[u] / 1e-3)), default=None)


def clock(t_raw: F64, declared: str | None, default: str, col: str, src: str
          ) -> tuple[F64, str]:
    """The time in s from the column's values (module docstring), and what was assumed."""
    table = QUANTITY_UNITS["time"]
    steps = np.diff(t_raw)
    pos = steps[steps > 0.0]
    if pos.size == 0:
        raise InputError(f"{src}: column {col} never advances; a torque log needs a clock")
    step = float(np.median(pos))
    seen = _looks_like(step)
    if declared is not None:
        unit = declared.strip().lower()
        if unit not in table:
            raise InputError(f"{src}: column {col} [{declared}]: {declared!r} is not a clock "
                             f"unit; declare one of {', '.join(table)} (e.g. {col} [s])")
        if not _plausible(step * table[unit]):
            hint = (f"the values look like {seen}: declare {col} [{seen}]" if seen else
                    "no time unit gives a controller's step")
            raise InputError(f"{src}: column {col} [{declared}]: the median step is {step:.4g} "
                             f"{declared} ({step * table[unit]:.3g} s), implausible for a "
                             f"controller log ({STEP_RANGE[0]:g}-{STEP_RANGE[1]:g} s); {hint}")
        said = f"clock {col} in {declared} (declared)"
    elif _plausible(step * table[default]):
        unit, said = default, f"clock {col} taken in {default} (no unit declared)"
    elif seen is not None:
        unit = seen
        said = (f"clock {col} read as {seen}: no unit declared, and a median step of "
                f"{step:.4g} gives {step * table[seen] * 1e3:.4g} ms in {seen}")
    else:
        raise InputError(f"{src}: column {col}: a median step of {step:.4g} is no plausible "
                         f"controller step ({STEP_RANGE[0]:g}-{STEP_RANGE[1]:g} s) in any of "
                         f"{', '.join(table)}")
    factor = table[unit]
    if abs(t_raw[0]) * factor > EPOCH_S:
        if np.spacing(abs(t_raw[0])) > 0.01 * step:
            raise InputError(f"{src}: column {col}: the stamps ({t_raw[0]:.17g}) are too "
                             f"large for float64 to resolve the step {step:g}")
        said += f"; an absolute clock (first stamp {t_raw[0]:.17g}), taken from the first row"
        return (t_raw - t_raw[0]) * factor, said
    return t_raw * factor, said


def _drop_repeats(t: F64, values: np.ndarray, lines: np.ndarray, src: str
                  ) -> tuple[np.ndarray, dict[str, object]]:
    """The rows kept (mask) and the counts, for stamps equal to the previous row's."""
    dt = np.diff(t)
    back = np.flatnonzero(dt < 0.0)
    if back.size:
        i = int(back[0]) + 1
        raise InputError(f"{src} line {lines[i]}: column t is {float(t[i])!r} s, earlier "
                         f"than the previous row's {float(t[i - 1])!r} s; rows must be in "
                         "time order")
    same_t = np.concatenate([[False], dt == 0.0])
    same_v = np.concatenate([[False], np.all(values[1:] == values[:-1], axis=1)])
    rep, con = np.flatnonzero(same_t & same_v), np.flatnonzero(same_t & ~same_v)
    return ~same_t, {"repeats": int(rep.size),
                     "repeat_lines": tuple(lines[rep[:_SHOWN]].tolist()),
                     "conflicts": int(con.size),
                     "conflict_lines": tuple(lines[con[:_SHOWN]].tolist())}


def _short_dropped(segs: list[tuple[int, int]], lk: np.ndarray, step: float, src: str
                   ) -> tuple[list[tuple[int, int]], tuple[str, ...]]:
    """The segments kept (all when one) and those dropped as too short, in words."""
    if len(segs) == 1:
        return segs, ()
    short = [(a, b) for a, b in segs if b - a < MIN_ROWS]
    kept = [s for s in segs if s not in short]
    if not kept:
        raise InputError(f"{src}: no stretch of {MIN_ROWS} rows without a gap (a step over "
                         f"{GAP:g} x the median {step:g} s)")
    return kept, tuple(f"lines {lk[a]}-{lk[b - 1]} ({b - a} row(s) between gaps, fewer than "
                       f"{MIN_ROWS})" for a, b in short)


def condition(t: F64, values: np.ndarray, lines: np.ndarray, src: str
              ) -> tuple[np.ndarray, tuple[tuple[int, int], ...], dict[str, object]]:
    """The rows kept, the segments (start, stop) in the kept rows, and the record fields."""
    keep, rec = _drop_repeats(t, values, lines, src)
    tk, lk = t[keep], lines[keep]
    if tk.size < 2:
        raise InputError(f"{src}: one distinct time stamp; a torque log needs a time series")
    dt = np.diff(tk)
    step = float(np.median(dt))
    cut = np.flatnonzero(dt > GAP * step) + 1
    rec["gaps"] = tuple(Gap(int(lk[i]), float(dt[i - 1]), float(dt[i - 1] / step)) for i in cut)
    segs, rec["dropped"] = _short_dropped(list(itertools.pairwise([0, *cut.tolist(), tk.size])),
                                          lk, step, src)
    rows = np.flatnonzero(keep)
    kept = np.concatenate([rows[a:b] for a, b in segs])
    starts = np.cumsum([0] + [b - a for a, b in segs])
    inner = np.concatenate([np.diff(tk[a:b]) for a, b in segs])
    rec.update(step_s=step, step_min_s=float(inner.min()) if inner.size else step,
               step_max_s=float(inner.max()) if inner.size else step)
    return kept, tuple((int(starts[k]), int(starts[k + 1])) for k in range(len(segs))), rec
