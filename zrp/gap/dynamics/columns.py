"""Column names of a torque log as controllers write them, by explicit tables.

A header is matched against each *form* below (case-insensitive; a unit in brackets,
``q_0 [rad]``, is split off first by :func:`zrp.units.split_unit`); the form that gives
positions and torques (or currents) and claims the most columns is used, and said
(:attr:`Mapping.describe`). Per-joint columns are numbered 0- or 1-based (decided by the
positions: ``0..n-1`` or ``1..n``; another group may count from the other), with the
separators listed.

================  ==========================================================================
form              per-joint columns (group: base names; separators)
================  ==========================================================================
zrp               q, qd, tau, i (currents), qc (command): ``q1``, ``tau1`` ...; ``payload``
motor side        the same at the motors (``qm1``, ``qdm1``, ``taum1``, ``im1``), read
                  through a transmission (:mod:`zrp.gap.dynamics.transmission`)
libfranka         q: ``q``; qd: ``dq``; tau: ``tau_J``; qc: ``q_d``; as ``q0``, ``q_0``,
                  ``q[0]``, ``q.0``; and as ``franka::logToCSV`` writes them:
                  ``state.q[0]``, ``state.dq[0]``, ``state.tau_J[0]``, ``state.q_d[0]``
                  (or ``cmd.q_d[0]``), time ``time`` in ms
UR RTDE           q: ``actual_q``; qd: ``actual_qd``; tau: ``actual_current_as_torque``;
                  i: ``actual_current`` (needs torque constants); qc: ``target_q``; as
                  ``actual_q_0``, ``actual_q[0]``, ``actual_q0``
KUKA FRI/Sunrise  q: ``MeasuredJointPosition``, ``measured_joint_position``, ``A1..A7``
                  and a Sunrise trace's ``axisQMsr_<robot>[0]`` (these two in degrees unless
                  declared); tau: ``MeasuredTorque``, ``measured_torque``,
                  ``MeasuredJointTorque``, ``measured_joint_torque``; qc:
                  ``CommandedJointPosition``, ``commanded_joint_position``,
                  ``axisQCmdT1m_<robot>[0]``, ``axisQCmdIPO_<robot>[0]`` (degrees); as ``_1``,
                  ``1``, ``[1]``, ``_a1``, ``a1``; time ``ZeitInSec`` plus ``ZeitInNanoSec``
                  when present. (A trace's torque columns are not in this table: their names
                  were not confirmed; name them ``MeasuredTorque_1``.. or ``tau1``..)
KUKA FRI pyfri    q: ``mp``; tau: ``mt`` (measured torque); qc: ``ip`` (the interpolator's
                  position), 1-based (``mp1..mp7``), as lbr-stack/pyfri's
                  ``collect_data`` writes them; time ``tsec`` plus ``tnsec`` (the FRI
                  controller's clock), not its ``time`` (a sum of nominal sample times
                  printed to 6 significant digits); ``et1..`` (external torque) not used
ROS joint_states  q/qd/tau: ``position``/``velocity``/``effort``, by joint name as
                  ``/joint_states/position/<joint>`` (any topic), ``position_<joint>``, or by
                  index as ``field.position0`` (rostopic echo -p, the names from the
                  ``field.name0..`` cells of the first data row)
================  ==========================================================================

Time (any form; the first present in this order is used): ``t``, ``tsec`` (with ``tnsec``),
``time``, ``timestamp``,
``time_stamp``, ``field.header.stamp``, ``header.stamp``, ``<topic>/header/stamp``,
``__time`` (PlotJuggler), ``ZeitInSec`` (Sunrise), ``%time`` (rostopic receive time). Its unit
is the declared one, else inferred from the step (:mod:`zrp.gap.dynamics.timebase`).

In the zrp form every column must be known (an unknown one is an error, as before); in a
controller's form the columns it does not use (poses, targets, temperatures ...) are ignored
and named. Where the joints are named (ROS), the names are kept in log order
(:attr:`Mapping.joint_names`) to be matched to the model's joints.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from zrp.errors import InputError
from zrp.gap.dynamics.ambiguous import check_one_form
from zrp.units import split_unit

__all__ = ["FORMS", "GROUP_KIND", "Mapping", "accepted_forms", "map_header", "time_columns"]

#: Per-joint groups: name -> unit kind (zrp.units).
GROUP_KIND = {"q": "position", "qd": "velocity", "tau": "effort", "i": "current",
              "qc": "position"}

#: Longest accepted column name (a real header has names of tens of characters).
MAX_NAME = 1000

_SEPS = {"zrp": ("",), "motor side": ("",), "libfranka": ("", "_", "[]", "."),
         "UR RTDE": ("_", "[]", ""), "KUKA FRI/Sunrise": ("_a", "a", "_", "[]", ""),
         "KUKA FRI pyfri": ("",)}

#: form -> group -> base names (lowercase).
FORMS: dict[str, dict[str, tuple[str, ...]]] = {
    "zrp": {"q": ("q",), "qd": ("qd",), "tau": ("tau",), "i": ("i",), "qc": ("qc",)},
    "motor side": {"q": ("qm",), "qd": ("qdm",), "tau": ("taum",), "i": ("im",)},
    "libfranka": {"q": ("q", "state.q"), "qd": ("dq", "state.dq"),
                  "tau": ("tau_j", "state.tau_j"), "qc": ("q_d", "state.q_d", "cmd.q_d")},
    "UR RTDE": {"q": ("actual_q",), "qd": ("actual_qd",), "tau": ("actual_current_as_torque",),
                "i": ("actual_current",), "qc": ("target_q",)},
    "KUKA FRI/Sunrise": {
        "q": ("measuredjointposition", "measured_joint_position", "", "axisqmsr_*"),
        "tau": ("measuredtorque", "measured_torque", "measuredjointtorque",
                "measured_joint_torque"),
        "qc": ("commandedjointposition", "commanded_joint_position", "axisqcmdt1m_*",
               "axisqcmdipo_*")},
    "KUKA FRI pyfri": {"q": ("mp",), "tau": ("mt",), "qc": ("ip",)},
}

#: Time column names in order of preference (regular expressions, whole name).
TIME = ("t", "tsec", "time", "timestamp", "time_stamp", r"field\.header\.stamp", r"header\.stamp",
        r"(?:/[^/]+)+/header/stamp", "__time", "zeitinsec", "%time")

_ROS_GROUP = {"position": "q", "velocity": "qd", "effort": "tau"}
_ROS_NAMED = (re.compile(r"(?:/[^/]+)*/(position|velocity|effort)/(.+)", re.I),
              re.compile(r"(position|velocity|effort)_(.+)", re.I))
_ROS_INDEXED = re.compile(r"field\.(position|velocity|effort)(0|[1-9]\d{0,3})", re.I)
_ROS_NAME_CELL = re.compile(r"field\.name(0|[1-9]\d{0,3})", re.I)

#: Units assumed for an undeclared column of a base (KUKA's axis columns are degrees).
DEFAULT_UNITS = {("KUKA FRI/Sunrise", ""): "deg", ("KUKA FRI/Sunrise", "axisqmsr_*"): "deg",
                 ("KUKA FRI/Sunrise", "axisqcmdt1m_*"): "deg",
                 ("KUKA FRI/Sunrise", "axisqcmdipo_*"): "deg"}


def _indexed(base: str, seps: tuple[str, ...]) -> re.Pattern[str]:
    alts = []
    for s in seps:
        if not base and "a" not in s:
            continue
        idx = r"(0|[1-9]\d{0,3})"
        head = re.escape(base[:-1]) + r"[^\[\]]+" if base.endswith("*") else re.escape(base)
        alts.append(head + (r"\[" + idx + r"\]" if s == "[]" else re.escape(s) + idx))
    return re.compile("|".join(alts), re.I)


_PATTERNS = {form: {g: [(b, _indexed(b, _SEPS[form])) for b in bases]
                    for g, bases in groups.items()} for form, groups in FORMS.items()}


@dataclass(frozen=True)
class Mapping:
    """How a header maps onto the torque log.

    Attributes:
        form: the form used (a key of :data:`FORMS`, or "ROS joint_states").
        n: the number of joints.
        time: the time column's index.
        groups: group -> the column index of each joint, in log order.
        units: column index -> its declared unit (None: undeclared).
        defaults: column index -> the form's unit when undeclared (else SI).
        names: column index -> its name (unit stripped).
        payload: the payload column's index, or None.
        joint_names: the joints' names in log order (ROS), else empty.
        name_cells: columns whose first-row cells name the joints (rostopic ``field.nameK``).
        index_base: 0 or 1 (indexed forms), None (named).
        ignored: the columns not used.
    """

    form: str
    n: int
    time: int | None
    groups: dict[str, tuple[int, ...]]
    units: dict[int, str | None]
    defaults: dict[int, str] = field(default_factory=dict)
    names: dict[int, str] = field(default_factory=dict)
    payload: int | None = None
    joint_names: tuple[str, ...] = ()
    name_cells: tuple[int, ...] = ()
    index_base: int | None = 1
    ignored: tuple[str, ...] = ()
    time_ns: int | None = None

    def describe(self) -> str:
        cols = ", ".join(f"{g} <- {self.names[c[0]]}..{self.names[c[-1]]}"
                         for g, c in self.groups.items())
        base = "" if self.index_base is None else f", {self.index_base}-based"
        clock = "none (the given rate)" if self.time is None else self.names[self.time]
        text = (f"columns read as the {self.form} form ({self.n} joints{base}): time <- "
                f"{clock}, {cols}")
        if self.form not in ("zrp", "motor side"):
            text += ("; undeclared units are the form's own (SI: rad, rad/s, N m, A; KUKA "
                     "A1..A7 in deg)")
        if self.ignored:
            shown = ", ".join(self.ignored[:8]) + (" ..." if len(self.ignored) > 8 else "")
            text += f"; {len(self.ignored)} column(s) not used: {shown}"
        return text


def accepted_forms() -> str:
    """The accepted header forms, in words (for error messages)."""
    parts = [f"{form}: " + ", ".join(f"{g}={'/'.join(b or 'A' for b in bases)}<k>"
                                     for g, bases in groups.items())
             for form, groups in FORMS.items()]
    parts.append("ROS joint_states: /joint_states/position/<joint>, position_<joint>, "
                 "field.position<k> (and velocity, effort)")
    return ("; ".join(parts) + "; time: t, tsec, time, timestamp, field.header.stamp, __time, "
            "ZeitInSec, %time")


def _time_column(names: list[str]) -> int | None:
    for pat in TIME:
        for i, c in enumerate(names):
            if re.fullmatch(pat, c, re.I):
                return i
    return None


def time_columns(names: list[str]) -> list[int]:
    """Every column whose name is a clock's (:data:`TIME`)."""
    return [i for i, c in enumerate(names) if any(re.fullmatch(p, c, re.I) for p in TIME)]


def _match_indexed(form: str, names: list[str]) -> dict[str, dict[int, int]]:
    """group -> {index: column} of one indexed form (the first base present per group)."""
    out: dict[str, dict[int, int]] = {}
    for g, pats in _PATTERNS[form].items():
        for _, pat in pats:
            found = {}
            for i, c in enumerate(names):
                m = pat.fullmatch(c)
                if m:
                    found[int(next(x for x in m.groups() if x is not None))] = i
            if found:
                out[g] = found
                break
    return out


def _match_ros(names: list[str]) -> tuple[dict[str, dict[str, int]], bool]:
    """group -> {joint name or index: column} of the ROS form; True if indexed."""
    named: dict[str, dict[str, int]] = {}
    indexed: dict[str, dict[str, int]] = {}
    for i, c in enumerate(names):
        m = _ROS_INDEXED.fullmatch(c)
        if m:
            indexed.setdefault(_ROS_GROUP[m.group(1).lower()], {})[m.group(2)] = i
            continue
        for pat in _ROS_NAMED:
            m = pat.fullmatch(c)
            if m:
                named.setdefault(_ROS_GROUP[m.group(1).lower()], {})[m.group(2)] = i
                break
    return (indexed, True) if len(indexed) >= len(named) and indexed else (named, False)


def _order_indexed(found: dict[str, dict[int, int]], names: list[str], src: str
                   ) -> tuple[int, int, dict[str, tuple[int, ...]]]:
    """(n, index base, group -> columns in joint order), checking every group is complete."""
    qs = found["q"]
    base = 0 if 0 in qs else 1
    n = len(qs)
    want = list(range(base, base + n))
    missing = [k for k in want if k not in qs]
    if missing:
        raise InputError(f"{src} line 1: missing column(s) for joint index "
                         f"{', '.join(map(str, missing))} of the positions "
                         f"({names[qs[min(qs)]]}..); missing column q{missing[0]}")
    out: dict[str, tuple[int, ...]] = {}
    for g, cols in found.items():
        # each group 0- or 1-based on its own (a trace's axes [0].. beside MeasuredTorque_1..)
        gb = base if g == "q" or len(cols) != n else (0 if 0 in cols else 1)
        want = list(range(gb, gb + n))
        extra = sorted(set(cols) - set(want))
        if extra:
            raise InputError(f"{src} line 1: column(s) {', '.join(names[cols[k]] for k in extra)}"
                             f" beyond the {n} joints of the positions")
        if len(cols) != n:
            raise InputError(f"{src} line 1: {g}{gb}..{g}{gb + n - 1} must all be given; "
                             f"got only {', '.join(names[cols[k]] for k in sorted(cols))}")
        out[g] = tuple(cols[k] for k in want)
    return n, base, out


def _order_named(found: dict[str, dict[str, int]], names: list[str], src: str
                 ) -> tuple[int, dict[str, tuple[int, ...]], tuple[str, ...]]:
    joints = sorted(found["q"], key=found["q"].get)
    out: dict[str, tuple[int, ...]] = {}
    for g, cols in found.items():
        if set(cols) != set(joints):
            odd = sorted(set(cols) ^ set(joints))
            raise InputError(f"{src} line 1: the {g} columns name joint(s) {', '.join(odd)} "
                             f"that the position columns do not (or the other way round)")
        out[g] = tuple(cols[j] for j in joints)
    return len(joints), out, tuple(joints)


def _candidates(names: list[str]) -> list[tuple[str, dict]]:
    cands: list[tuple[str, dict]] = [(f, _match_indexed(f, names)) for f in FORMS]
    ros, ros_indexed = _match_ros(names)
    cands.append(("ROS joint_states" + (" (indexed)" if ros_indexed else ""), ros))
    return [(f, m) for f, m in cands if "q" in m]


def _claimed(found: dict) -> set[int]:
    return {c for cols in found.values() for c in cols.values()}


_BRACKET_INDEX = re.compile(r"(.+\[\d+\])(?:\s*\[([^\[\]]+)\])?")


def _split(cell: str, src: str) -> tuple[str, str | None]:
    """Name and unit of a header cell; ``q[0]`` is an index (libfranka), ``q[0] [rad]``
    an index and a unit."""
    m = _BRACKET_INDEX.fullmatch(cell)
    if m:
        return m.group(1).strip(), m.group(2)
    return split_unit(cell, f"{src} line 1")


def _checked_names(header: list[str], src: str) -> tuple[list[str], list[str | None]]:
    for i, h in enumerate(header):
        if len(h) > MAX_NAME:
            raise InputError(f"{src} line 1: column {i + 1}'s name has {len(h)} characters "
                             f"(more than {MAX_NAME}); not a torque log header")
    parsed = [_split(h.strip(), src) for h in header]
    names = [p[0] for p in parsed]
    dup = sorted({c for c in names if c and names.count(c) > 1})
    if dup:
        raise InputError(f"{src} line 1: column(s) {', '.join(dup)} appear more than once")
    return names, [p[1] for p in parsed]


def _choose(names: list[str], src: str) -> tuple[str, dict]:
    """The form giving positions and torques that claims the most columns."""
    cands = _candidates(names)
    full = [(f, m) for f, m in cands if "tau" in m or "i" in m]
    if full:
        best = max(full, key=lambda fm: len(_claimed(fm[1])))
        check_one_form(full, best, names, src)
        return best
    if cands:
        raise InputError(f"{src} line 1: no torques: the {cands[0][0]} form's positions are "
                         "there, but no torques (tau1..taun, N m) or motor currents (i1..in, "
                         "A, with a torque constant)")
    raise InputError(f"{src} line 1: missing column(s) q1: no joint positions in a form this "
                     f"reader knows; accepted: {accepted_forms()}")


def _unused(form: str, found: dict, names: list[str], src: str, clock_required: bool
            ) -> tuple[int | None, int | None, tuple[str, ...]]:
    """The time and payload columns, and the columns not used (an error in the zrp forms)."""
    t = _time_column(names)
    if t is not None and not clock_required:
        raise InputError(f"--rate: {src} has its own clock (column {names[t]}); give the "
                         "rate only for a log without a time column")
    if t is None and clock_required:
        raise InputError(f"{src} line 1: missing column(s) t: no time column (accepted: "
                         "t, tsec, time, timestamp, field.header.stamp, __time, ZeitInSec, %time)")
    payload = next((i for i, c in enumerate(names) if c.lower() == "payload"), None)
    used = _claimed(found) | {t, payload, None if t is None else _nanoseconds(names, t)}
    ignored = tuple(names[i] for i in range(len(names)) if i not in used)
    if form in ("zrp", "motor side") and ignored:
        raise InputError(f"{src} line 1: unknown column {ignored[0]!r}; valid columns are t, "
                         "q1..qn, qd1..qdn, tau1..taun, i1..in, qc1..qcn, payload (or a "
                         f"controller's form: {accepted_forms()})")
    return t, payload, ignored


def _nanoseconds(names: list[str], t: int) -> int | None:
    """The nanoseconds column that completes a seconds clock, if any (Sunrise's
    ``ZeitInSec`` + ``ZeitInNanoSec``; FRI's ``tsec`` + ``tnsec``)."""
    nanos = {"zeitinsec": "zeitinnanosec", "tsec": "tnsec"}.get(names[t].lower())
    if nanos is None:
        return None
    return next((i for i, c in enumerate(names) if c.lower() == nanos), None)


def _ros_name_cells(names: list[str], base: int, n: int) -> tuple[int, ...]:
    cells = {int(m.group(1)): i for i, c in enumerate(names)
             if (m := _ROS_NAME_CELL.fullmatch(c))}
    out = tuple(cells[k] for k in range(base, base + n) if k in cells)
    return out if len(out) == n else ()


def _defaults(form: str, groups: dict[str, tuple[int, ...]], names: list[str]) -> dict[int, str]:
    """Column -> the form's unit for an undeclared position column (KUKA's A1..A7: deg)."""
    return {c: DEFAULT_UNITS[(form, b)] for g in ("q", "qc") for c in groups.get(g, ())
            for b, pat in _PATTERNS.get(form, {}).get(g, [])
            if (form, b) in DEFAULT_UNITS and pat.fullmatch(names[c])}


def map_header(header: list[str], src: str, *, clock_required: bool = True) -> Mapping:
    """The :class:`Mapping` of ``header`` (module docstring); an InputError naming what is
    missing, or listing the accepted forms when nothing matches. ``clock_required=False``:
    the log has no time column (its rate is given; :attr:`Mapping.time` is None)."""
    names, units = _checked_names(header, src)
    form, found = _choose(names, src)
    t, payload, ignored = _unused(form, found, names, src, clock_required)
    joint_names: tuple[str, ...] = ()
    name_cells: tuple[int, ...] = ()
    base: int | None = None
    if form == "ROS joint_states":
        n, groups, joint_names = _order_named(found, names, src)
    elif form.startswith("ROS"):
        found = {g: {int(k): c for k, c in cols.items()} for g, cols in found.items()}
        n, base, groups = _order_indexed(found, names, src)
        name_cells = _ros_name_cells(names, base, n)
    else:
        n, base, groups = _order_indexed(found, names, src)
    return Mapping(form, n, t, groups, dict(enumerate(units)), _defaults(form, groups, names),
                   dict(enumerate(names)), payload, joint_names, name_cells, base, ignored,
                   None if t is None else _nanoseconds(names, t))
