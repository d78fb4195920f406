"""The first minute of a verdict: a headline of at most :data:`MAX_WORDS` words
(:func:`headline_text`: the withheld error before -> after with the share removed, the effects
that matter with their joints, what remains and whether more data would help) and a small
table of the withheld errors (:func:`summary_rows`), rendered for Markdown
(:func:`summary_markdown`) and the terminal (:func:`summary_terminal`). All are plain functions
of the :class:`~zrp.gap.Diagnosis`; the details follow in their own sections
(:mod:`zrp.gap.report.verdict`)."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from zrp.gap.analysis.identifiability import GEOMETRIC
from zrp.gap.results import Diagnosis

__all__ = ["MAX_WORDS", "headline_text", "more_data_text", "remains_headline",
           "summary_markdown", "summary_rows", "summary_terminal"]

#: the most words a headline has (issue 33: an engineer reads it in a minute).
MAX_WORDS = 80
#: common share of a pose's points above which what remains is called a shift per pose.
POSE_SHIFT_SHARE = 0.8
#: withheld over fitting RMS above which the final model is limited by the number of poses.
DATA_LIMITED_RATIO = 1.25


def ranges(joints: Sequence[int]) -> str:
    """1, 2, 3, 5 -> "1-3, 5" ("-" for none)."""
    runs: list[list[int]] = []
    for j in joints:
        if runs and runs[-1][1] == j - 1:
            runs[-1][1] = j
        else:
            runs.append([j, j])
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in runs) or "-"


def effect_joints(name: str, joints: Sequence[int]) -> str:
    """"backlash", (2,) -> "backlash (joint 2)"; (2, 3) -> "backlash (joints 2-3)"; no
    joints: the name alone. Joints counted from 1, as everywhere a user reads."""
    if not joints:
        return name
    return f"{name} ({'joint' if len(joints) == 1 else 'joints'} {ranges(joints)})"


def _effect(name: str, joints: Sequence[int], with_joints: bool) -> str:
    return effect_joints(name, joints) if with_joints else name


def _matters(diag: Diagnosis, level: int) -> str:
    """The effects of the final model, the non-geometric ones first; ``level`` 0 names the
    joints of every effect, 1 only of the non-geometric ones, 2 none."""
    fj = diag.final_joints
    if not fj:
        return "No effect in the library improves on the registration."
    other = [_effect(e, j, level < 2) for e, j in fj.items() if e not in GEOMETRIC]
    geo = [_effect(e, j, level < 1) for e, j in fj.items() if e in GEOMETRIC]
    if other and geo:
        return f"What matters: {', '.join(other)}, on top of the geometry ({', '.join(geo)})."
    return f"What matters: {', '.join(other or geo)}."


def _before_after(diag: Diagnosis, baseline: bool) -> str:
    u, before, after = diag.length_unit, diag.nominal.rms, diag.final.rms
    removed = 100 * (1 - after / before) if before > 0 else 0.0
    a = diag.assessment
    base = ""
    if baseline and a is not None and diag.final_joints.keys() - set(GEOMETRIC):
        base = f"; geometric calibration alone {a.baseline.withheld.rms:.3g} {u}"
    return (f"Withheld error {before:.3g} -> {after:.3g} {u} RMS ({removed:.0f} % "
            f"removed{base}).")


def remains_headline(diag: Diagnosis) -> str:
    """What remains, in one sentence: against the noise floor, and its shape when no effect
    explains it."""
    u, floor, final = diag.length_unit, diag.noise_floor, diag.final
    if floor.rms is None:
        return (f"What remains ({final.rms:.3g} {u}) cannot be weighed: these data give no "
                "noise floor.")
    if floor.rms <= (diag.assessment.resolution if diag.assessment else 0.0):
        return ("What remains is at numerical precision." if not diag.unexplained else
                f"What remains ({final.rms:.3g} {u}) is far above these noise-free data.")
    ratio = final.rms / floor.rms
    if not diag.unexplained:
        return f"What remains is at the noise floor ({ratio:.2g}x)."
    common = diag.where_final.common_share
    shape = ("" if common is None or common < POSE_SHIFT_SHARE else
             f", {100 * common:.0f} % of it whole poses shifted")
    return (f"What remains is {ratio:.2g}x the noise floor{shape}, explained by no effect "
            "in the library.")


def _limited_by_data(diag: Diagnosis) -> float | None:
    """Withheld over fitting RMS of the final model, when that shows it is data-limited."""
    a = diag.assessment
    if a is None or not a.remainder.rms > 0:
        return None
    ratio = diag.final.rms / a.remainder.rms
    return ratio if ratio > DATA_LIMITED_RATIO else None


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def _would_pin(diag: Diagnosis) -> list[str]:
    """What more varied poses would identify: held combinations, unexcited joints, joints
    that gravity loads one way only."""
    a = diag.assessment
    held = [h for h in diag.held_directions if not h.exact]
    out = [f"pin {_plural(len(held), 'held combination')}"] if held else []
    if a is not None and a.unexcited:
        out.append(f"excite joint(s) {ranges(a.unexcited)}")
    if a is not None and a.one_sided:
        out.append(f"reverse gravity on joint(s) {ranges(a.one_sided)}")
    return out


def more_data_text(diag: Diagnosis) -> str:
    """Whether more data would help, and which data: more poses when the withheld error is
    well above the fitted one, more varied poses for what the data leave unpinned, repeated
    poses for a remainder no effect explains."""
    if diag.noise_floor.rms is None:
        return "Repeated poses or several points per pose would measure the noise floor."
    pin, ratio, a = _would_pin(diag), _limited_by_data(diag), diag.assessment
    out = []
    if ratio is not None:
        out.append(f"More poses would lower it (withheld error {ratio:.2g}x the fitted one).")
    if pin:
        out.append("More varied poses would " + " and ".join(pin)
                   + ("." if ratio is not None or not diag.unexplained else
                      ", not lower what remains."))
    elif ratio is None:
        out.append("More data would only narrow the intervals." if not diag.unexplained else
                   "More poses of this kind would not lower it.")
    if diag.unexplained and a is not None and a.remainder.repeat_rms is None:
        out.append("Repeated poses would separate robot repeatability from the instrument.")
    return " ".join(out)


def _words(text: str) -> int:
    return len(text.split())


def headline_text(diag: Diagnosis) -> str:
    """The headline (at most :data:`MAX_WORDS` words): before -> after with the share removed,
    the effects that matter with their joints, what remains, whether more data would help.
    Detail is shed in this order until it fits: the geometry's joints, the geometric
    baseline, every effect's joints, the advice on more data."""
    remains, more = remains_headline(diag), more_data_text(diag)
    tries: list[Callable[[], list[str]]] = [
        lambda: [_before_after(diag, True), _matters(diag, 0), remains, more],
        lambda: [_before_after(diag, True), _matters(diag, 1), remains, more],
        lambda: [_before_after(diag, False), _matters(diag, 1), remains, more],
        lambda: [_before_after(diag, False), _matters(diag, 2), remains, more],
        lambda: [_before_after(diag, False), _matters(diag, 2), remains],
    ]
    for make in tries:
        text = " ".join(make())
        if _words(text) <= MAX_WORDS:
            return text
    words = text.split()  # a pathological list of effects: cut, and say so
    return " ".join(words[:MAX_WORDS - 1]) + " (...)"


def summary_rows(diag: Diagnosis) -> tuple[tuple[str, ...], list[tuple[str, ...]]]:
    """(header, rows) of the small table under the headline: withheld RMS, p95 and max after
    registration, of the complete geometric calibration, of the final model, and the noise
    floor."""
    u, nom = diag.length_unit, diag.nominal
    head = ("withheld poses", f"RMS ({u})", f"p95 ({u})", f"max ({u})", "removed")

    def row(name: str, rms: float, p95: float | None, mx: float | None) -> tuple[str, ...]:
        gone = "" if not nom.rms > 0 else f"{100 * (1 - rms / nom.rms):.0f} %"
        return (name, f"{rms:.4g}", "" if p95 is None else f"{p95:.4g}",
                "" if mx is None else f"{mx:.4g}", gone)

    rows = [(*row("after registration", nom.rms, nom.p95, nom.max)[:4], "")]
    a = diag.assessment
    if a is not None:
        b = a.baseline.withheld
        rows.append(row(f"geometric calibration ({a.baseline.n_parameters} parameters)",
                        b.rms, b.p95, b.max))
    f = diag.final
    n = len(diag.final_parameters)
    rows.append(row(f"final model ({len(diag.final_joints)} effects, {n} parameters)",
                    f.rms, f.p95, f.max))
    nf = diag.noise_floor
    rows.append(("noise floor", "not measurable" if nf.rms is None else f"{nf.rms:.4g}",
                 "" if nf.p95 is None else f"{nf.p95:.4g}", "", ""))
    return head, rows


def summary_markdown(diag: Diagnosis) -> list[str]:
    """The table as Markdown lines (no user text in it: effect names and numbers only)."""
    head, rows = summary_rows(diag)
    return (["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
            + ["| " + " | ".join(r) + " |" for r in rows])


def summary_terminal(diag: Diagnosis) -> str:
    """The table as aligned plain text."""
    head, rows = summary_rows(diag)
    table = [head, *rows]
    widths = [max(len(r[i]) for r in table) for i in range(len(head))]
    lines = ["  ".join(c.ljust(w) if i == 0 else c.rjust(w)
                       for i, (c, w) in enumerate(zip(r, widths, strict=True))).rstrip()
             for r in table]
    return "\n".join([lines[0], "-" * len(lines[0]), *lines[1:]])
