"""A torque log's header that could be read two ways is refused, naming the columns and how
to choose, or read the one documented way and said (issue 41 finding 9):

* **Two complete forms.** Positions and torques of one form (``q1..``, ``tau1..``) beside
  those of another in other columns (``actual_q_0..``, ``actual_current_as_torque_0..``):
  which are the arm's is not the reader's to guess; refused, naming both forms' columns
  (keep one set).
* **Two clocks.** Two time columns (``t`` and ``timestamp``) are refused, naming both
  (delete one), except the documented pairs: a ROS header stamp beside the receive time
  (``field.header.stamp`` and ``%time``, a ``.../header/stamp`` and ``__time``: the stamp
  is the sensor's), and FRI's ``tsec`` + ``tnsec`` beside pyfri's ``time`` (a sum of
  nominal steps): the one read and the one not are said in the clock's note.
* **A nanoseconds column written as a total.** A seconds clock completed by nanoseconds
  (Sunrise ``ZeitInSec`` + ``ZeitInNanoSec``, FRI ``tsec`` + ``tnsec``) holds the fraction of
  a second, 0 .. 1e9. A column beyond that whose seconds agree with the seconds column is the
  whole time in ns (adding both would double the clock): it is read alone and said. One that
  is beyond a second and agrees with nothing, or negative, is refused.
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError

__all__ = ["check_one_form", "other_clock", "seconds_and_nanos"]

_STAMP = re.compile(r"(?:field\.)?header\.stamp|(?:/[^/]+)+/header/stamp", re.I)
_RECEIVE = ("%time", "__time")


def _span(names: Sequence[str], cols: dict) -> str:
    c = sorted(cols.values())
    return names[c[0]] if len(c) == 1 else f"{names[c[0]]}..{names[c[-1]]}"


def check_one_form(full: list[tuple[str, dict]], best: tuple[str, dict], names: Sequence[str],
                   src: str) -> None:
    """Refuse a header where another form than ``best`` has complete positions and torques
    in columns of its own (module docstring)."""
    form, found = best
    mine = set(found["q"].values())
    for other, ofound in full:
        if other == form or set(ofound["q"].values()) & mine:
            continue
        tau = "tau" if "tau" in found else "i"
        otau = "tau" if "tau" in ofound else "i"
        raise InputError(
            f"{src} line 1: two complete column forms: the {form} form's positions "
            f"{_span(names, found['q'])} and torques {_span(names, found[tau])}, and the "
            f"{other} form's {_span(names, ofound['q'])} and {_span(names, ofound[otau])}; "
            "which are the arm's is ambiguous: keep one set of columns (delete the other)")


def other_clock(names: Sequence[str], t: int, clocks: Sequence[int], src: str) -> str:
    """The words for the clocks not read beside column ``t`` (``clocks``: every time column
    of the header), or an InputError naming both when the choice is not documented."""
    chosen = names[t]
    others = [names[i] for i in clocks if i != t]
    if not others:
        return ""
    ok = all((_STAMP.fullmatch(chosen) and o.lower() in _RECEIVE)
             or (chosen.lower() == "tsec" and o.lower() == "time"
                 and any(n.lower() == "tnsec" for n in names)) for o in others)
    if not ok:
        raise InputError(f"{src} line 1: two clocks: columns {chosen} and {', '.join(others)}; "
                         "which one the samples were taken on is ambiguous: keep one time "
                         "column (delete the other)")
    return (f"; the log's other clock column(s) {', '.join(others)} not used (the "
            f"{'sensor stamp' if _STAMP.fullmatch(chosen) else 'FRI controller clock'} "
            f"{chosen} is)")


def seconds_and_nanos(sec: F64, ns: F64, sec_name: str, ns_name: str, src: str
                      ) -> tuple[F64, str]:
    """The time from a seconds column and its nanoseconds (module docstring), origin at the
    first row, and a note ("" when the nanoseconds are the fraction of a second)."""
    if np.any(ns < 0):
        i = int(np.argmax(ns < 0))
        raise InputError(f"{src}: column {ns_name} is {ns[i]:g} at data row {i + 1}; "
                         "nanoseconds of a second are 0 .. 999,999,999")
    if np.all(ns < 1e9):
        return (sec - sec[0]) + ns * 1e-9, ""
    whole = ns * 1e-9
    if np.all(np.abs(whole - sec) < 1.0 + 1e-6):
        return whole - whole[0], (f"; {ns_name} holds the whole time in ns (its seconds agree "
                                  f"with {sec_name}), not the fraction of a second: read "
                                  f"alone, not added to {sec_name}")
    i = int(np.argmax(ns >= 1e9))
    raise InputError(f"{src}: column {ns_name} is {ns[i]:.17g} at data row {i + 1}: beyond one "
                     f"second, and its seconds do not agree with {sec_name}'s "
                     f"{sec[i]:.17g}; expected the fraction of a second in ns (0 .. "
                     "999,999,999) or the whole time in ns")
