"""The report's "What the data could not pin" section: the directions held at their nominal
values (:mod:`zrp.gap.fit.wellposed`), the values refused for leaving their physical domains
(:mod:`zrp.gap.model.domains`) and whether every fit converged."""

from __future__ import annotations

from zrp.escape import md_text
from zrp.gap.results import Diagnosis

__all__ = ["identification_markdown"]


def _short(note: str) -> str:
    """A candidate's domain note with the reason given once (the first item in full, the
    others as name = value)."""
    head, _, items = note.partition("domain: ")
    parts = items.split("; earlier")[0].split("; ")
    return head + "domain: " + "; ".join(parts[:1] + [p.split(" outside ")[0].split(" above ")[0]
                                                      for p in parts[1:]])


def identification_markdown(diag: Diagnosis) -> list[str]:
    """Lines of report.md."""
    u = diag.length_unit
    L = ["## What the data could not pin, and what is not physical\n",
         "Each parameter is scaled by its manufacturing tolerance; a combination whose "
         "singular value is at or below the residual noise is known less well from the data "
         "than from the tolerance, so it stays at its nominal value (zrp/gap/fit/wellposed.py, "
         "eqs. W1-W4).\n"]
    held = diag.held_directions
    if held:
        L.append("| held combination (tolerance units) | singular value | noise | seen at "
                 "all |")
        L.append("|---|---|---|---|")
        L += [f"| {md_text(h.label)} | {h.singular_value:.3g} {u} | {h.threshold:.3g} {u} | "
              f"{'no' if h.exact else 'weakly'} |" for h in held]
        L.append("")
    else:
        L.append("Every combination of the final model's parameters is pinned by the data.\n")
    if diag.outside_domain:
        L.append("Fitted values outside their physical domain (taken out, never used; "
                 "lumped compliance weights whose sum left it held at sum 0; the first time "
                 "per effect, all in diagnosis.json `identification`):\n")
        seen: set[str] = set()
        for e, note in diag.outside_domain:
            if e not in seen:
                seen.add(e)
                L.append(f"- {e}: {_short(note)}")
        L.append("")
    f = diag.final_fit
    L.append(f"Solver: {f.stop_reason or 'converged'} after {f.iterations} iteration(s)"
             + ("." if not diag.solver_stops else
                "; fits that stopped early: " + "; ".join(diag.solver_stops) + ".") + "\n")
    return L
