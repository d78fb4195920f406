"""The fleet summary: which robots are out of tolerance and which effect dominates - as a
document (fleet.json), a table (CSV, Markdown) and a plot (Matplotlib, imported on use).

Robot names are the users' file names: every one (and every failure message) reaches fleet.md
through :func:`zrp.escape.md_text` and fleet.csv through :func:`zrp.escape.csv_text`."""

from __future__ import annotations

import math
from collections import Counter
from typing import Any

from zrp.escape import csv_text
from zrp.escape import md_text as _t
from zrp.tasks import TaskFailure

__all__ = ["COLUMNS", "fleet_csv", "fleet_figure", "fleet_markdown", "fleet_summary"]

COLUMNS = ("robot", "points", "error_rms", "error_p95", "error_max", "out_of_tolerance",
           "corrected_max", "within_after_correction", "top_effect", "top_joints", "effects",
           "shrink", "unexplained", "data")


def _num(x: Any) -> float:
    return math.nan if x is None else float(x)


def _marked(rows: list[dict[str, Any]], tolerance: float) -> list[dict[str, Any]]:
    """The rows sorted by robot, each marked out of tolerance / within after correction."""
    rows = sorted(rows, key=lambda r: r["robot"])
    for r in rows:
        r["out_of_tolerance"] = bool(_num(r["error_max"]) > tolerance)
        r["within_after_correction"] = bool(_num(r["corrected_max"]) <= tolerance)
    return rows


def _effect_counts(rows: list[dict[str, Any]]) -> tuple[Counter, Counter, Counter]:
    """How often each effect is named first, named at all, and (effect, joint) named first."""
    first = Counter(r["top_effect"] for r in rows if r["top_effect"] != "none")
    named = Counter(e for r in rows for e in set(r["effects"]) if e != "none")
    joints = Counter((r["top_effect"], j) for r in rows if r["top_effect"] != "none"
                     for j in r["top_joints"])
    return first, named, joints


def fleet_summary(rows: list[dict[str, Any]], failures: list[TaskFailure], tolerance: float,
                  unit: str, resumed: int = 0) -> dict[str, Any]:
    """The fleet document (fleet.json).

    A robot is *out of tolerance* when its largest withheld error after registration (the
    nominal model's accuracy, ``error_max``) exceeds ``tolerance``; *within after correction*
    when the diagnosed model's largest withheld error (``corrected_max``) does not. The
    dominant effect is the one named first for the most robots (``none`` not counted).
    """
    rows = _marked(rows, tolerance)
    first, named, joints = _effect_counts(rows)
    dominant = first.most_common(1)[0][0] if first else "none"
    return {
        "robots": len(rows) + len(failures), "diagnosed": len(rows), "failed": len(failures),
        "resumed": resumed, "tolerance": tolerance, "length_unit": unit,
        "tolerance_meaning": "largest withheld error after registration (error_max)",
        "out_of_tolerance": [r["robot"] for r in rows if r["out_of_tolerance"]],
        "fixed_by_correction": [r["robot"] for r in rows
                                if r["out_of_tolerance"] and r["within_after_correction"]],
        "dominant_effect": dominant,
        "named_first": dict(first.most_common()),
        "named_at_all": dict(named.most_common()),
        "dominant_joints": {f"{e} joint {j}": c for (e, j), c in joints.most_common(5)},
        "rows": rows,
        "failures": [f.to_dict() for f in failures],
    }


def fleet_csv(doc: dict[str, Any]) -> str:
    return csv_text(COLUMNS, ([";".join(map(str, r[c])) if isinstance(r[c], list) else r[c]
                               for c in COLUMNS] for r in doc["rows"]))


def _f(x: Any) -> str:
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.4g}"


def fleet_markdown(doc: dict[str, Any]) -> str:
    u = doc["length_unit"]
    n = doc["diagnosed"]
    out = [f"# Fleet diagnosis: {doc['robots']} robots", "",
           f"Tolerance: largest withheld error after registration <= {doc['tolerance']:g} {u}.",
           f"Out of tolerance: **{len(doc['out_of_tolerance'])} of {n}** diagnosed robots"
           + (f" ({', '.join(map(_t, doc['out_of_tolerance']))})" if doc["out_of_tolerance"]
              else "")
           + f"; {len(doc['fixed_by_correction'])} of them within tolerance once the "
           "diagnosed effects are corrected.",
           f"Dominant effect across the fleet (named first most often): "
           f"**{doc['dominant_effect']}**.", "",
           "| effect | named first | named at all |", "|---|---|---|"]
    for e in sorted(set(doc["named_first"]) | set(doc["named_at_all"]),
                    key=lambda e: (-doc["named_first"].get(e, 0), e)):
        out.append(f"| {e} | {doc['named_first'].get(e, 0)} | {doc['named_at_all'].get(e, 0)} |")
    out += ["", f"| robot | points | RMS {u} | max {u} | out of tolerance | corrected max {u} "
            "| first effect [joints] | shrink |", "|---|---|---|---|---|---|---|---|"]
    for r in doc["rows"]:
        out.append(f"| {_t(r['robot'])} | {r['points']} | {_f(r['error_rms'])} | "
                   f"{_f(r['error_max'])} | {'**yes**' if r['out_of_tolerance'] else 'no'} | "
                   f"{_f(r['corrected_max'])} | {r['top_effect']} {r['top_joints']} | "
                   f"{_f(r['shrink'])} |")
    if doc["failures"]:
        out += ["", "## Robots that could not be diagnosed (the others were)", "",
                "| input | error |", "|---|---|"]
        out += [f"| {_t(f['task'])} | {_t(f['error'])} |" for f in doc["failures"]]
    if doc["resumed"]:
        out += ["", f"Resumed: {doc['resumed']} diagnoses taken from an interrupted run."]
    out += ["", "Each robot's own report: robots/NAME/report.md."]
    return "\n".join(out) + "\n"


def fleet_figure(doc: dict[str, Any]) -> Any:
    """Each robot's largest withheld error before (bar, coloured by the effect named first)
    and after correction (tick) against the tolerance line."""
    from matplotlib.figure import Figure  # ~0.3 s to import: only when a plot is written

    rows = sorted(doc["rows"], key=lambda r: -r["error_max"])
    effects = sorted({r["top_effect"] for r in rows})
    palette = {e: f"C{i % 10}" for i, e in enumerate(effects)}
    fig = Figure(figsize=(max(6.0, 0.28 * len(rows) + 2.0), 4.2), layout="constrained")
    ax = fig.add_subplot()
    x = range(len(rows))
    ax.bar(x, [r["error_max"] for r in rows], color=[palette[r["top_effect"]] for r in rows])
    ax.scatter(x, [r["corrected_max"] for r in rows], marker="_", s=160, color="k", zorder=3,
               label="after correction")
    ax.axhline(doc["tolerance"], color="r", ls="--", lw=1, label="tolerance")
    for e in effects:
        ax.bar([0], [0], color=palette[e], label=f"first: {e}")
    ax.set_xticks(list(x), [r["robot"] for r in rows], rotation=90, fontsize=7)
    ax.set_ylabel(f"largest withheld error ({doc['length_unit']})")
    ax.set_title(f"{len(doc['out_of_tolerance'])} of {doc['diagnosed']} robots out of "
                 f"tolerance; dominant effect: {doc['dominant_effect']}")
    ax.legend(fontsize=7)
    return fig
