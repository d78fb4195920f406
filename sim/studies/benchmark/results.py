"""Blind benchmark, part 4: the result of a run and its tables (confusion, summary rows)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from sim.studies.benchmark.scenarios import BenchmarkConfig
from sim.studies.benchmark.scoring import ScenarioScore
from zrp.tasks import TaskFailure

__all__ = ["BenchmarkResult", "confusion_matrix", "coverage", "summary_rows"]


@dataclass(frozen=True, eq=False)
class BenchmarkResult:
    """Scores of all scenarios plus timings (s); the scenarios that raised (``failures``, each
    with its input) and how many scores a resumed run took from the previous one."""

    config: BenchmarkConfig
    model_name: str
    scores: tuple[ScenarioScore, ...]
    wall_s: float
    sim_s: float
    diag_s: float
    workdir: str
    failures: tuple[TaskFailure, ...] = ()
    resumed: int = 0
    dynamics: str = ""

    def to_dict(self) -> dict[str, Any]:
        cfg = {k: (list(v) if isinstance(v, tuple) else v)
               for k, v in self.config.__dict__.items()}
        return {"model": self.model_name, "config": cfg, "dynamics": self.dynamics,
                "dynamics_fallback": self.dynamics.startswith("FALLBACK"),
                "wall_s": self.wall_s,
                "sim_s": self.sim_s, "diag_s": self.diag_s, "workdir": self.workdir,
                "summary": summary_rows(self), "confusion": confusion_matrix(self),
                "scenarios": [s.to_dict() for s in self.scores],
                "failures": [f.to_dict() for f in self.failures], "resumed": self.resumed}



def confusion_matrix(result: BenchmarkResult) -> dict[str, dict[str, int]]:
    """Single-effect and none scenarios: hidden effect (row; "<effect> (not visible)" when
    its signature hides in the noise) -> effect named first (column) -> count."""
    rows: dict[str, dict[str, int]] = {}
    for s in result.scores:
        if s.kind == "pair":
            continue
        true = s.hidden[0] if s.hidden else "none"
        if s.hidden and s.expected == ("none",):
            true += " (not visible)"
        rows.setdefault(true, {})
        rows[true][s.found[0]] = rows[true].get(s.found[0], 0) + 1
    return rows


def _pct(ok: int, n: int) -> str:
    return "-" if n == 0 else f"{100.0 * ok / n:.0f} % ({ok}/{n})"


def _counts(scores: Sequence[ScenarioScore], target: float) -> dict[str, str]:
    """The scenario counts of a group (named first, or tied; joints; ratio; both; all)."""
    n = len(scores)
    return {"top": _pct(sum(s.top_correct for s in scores), n),
            "top_or_tie": _pct(sum(s.top_correct or any(e in s.tied for e in s.expected)
                                   for s in scores), n),
            "top_and_joints": _pct(sum(s.top_correct and s.joints_correct for s in scores), n),
            "ratio_ok": _pct(sum(s.ratio <= target for s in scores), n),
            "named_and_corrected": _pct(sum(s.top_correct and s.ratio <= target
                                            for s in scores), n),
            "all_three": _pct(sum(s.success for s in scores), n)}


def _group(scores: Sequence[ScenarioScore], target: float) -> dict[str, Any]:
    n = len(scores)
    ratios = [s.ratio for s in scores if math.isfinite(s.ratio)]
    shr = [s.shrink for s in scores if math.isfinite(s.shrink)]
    return {"n": n, **_counts(scores, target),
            "median_ratio": float(np.median(ratios)) if ratios else math.nan,
            "median_shrink": float(np.median(shr)) if shr else math.nan,
            **coverage(scores)}


def coverage(scores: Sequence[ScenarioScore]) -> dict[str, Any]:
    """Share of the compared parameters whose 95 % interval covers the truth, share of the
    scenarios (with a comparison) in which every one does, and in which the simultaneous 95 %
    intervals of the whole effect cover every one (sim/studies/benchmark/coverage.py says why)."""
    cov = sum(int(s.values.get("ci_covered", 0)) for s in scores)
    tot = sum(int(s.values.get("ci_compared", 0)) for s in scores)
    with_cmp = [s for s in scores if s.values.get("ci_compared", 0)]
    full = sum(s.values["ci_covered"] == s.values["ci_compared"] for s in with_cmp)
    joint = sum(bool(s.values.get("ci_effect_all")) for s in with_cmp)
    return {"ci95_parameters": _pct(cov, tot), "ci95_scenarios": _pct(full, len(with_cmp)),
            "ci95_effect_scenarios": _pct(joint, len(with_cmp)),
            "ci95_fraction": cov / tot if tot else math.nan}


def summary_rows(result: BenchmarkResult) -> list[dict[str, Any]]:
    """Rows of the summary table: per hidden effect (single scenarios), then totals."""
    t = result.config.ratio_target
    singles = [s for s in result.scores if s.kind == "single"]
    return [*_effect_rows(singles, result.config.effects, t), *_single_rows(singles, t),
            *_none_rows(result.scores, t), *_pair_rows(result.scores, t)]


def _effect_rows(singles: Sequence[ScenarioScore], effects: Sequence[str], target: float
                 ) -> list[dict[str, Any]]:
    """One row per effect hidden alone in some scenario: its visible scenarios."""
    rows = []
    for e in effects:
        grp = [s for s in singles if s.hidden == (e,)]
        if grp:
            vis = [s for s in grp if s.excited]
            rows.append({"group": e, "visible": f"{len(vis)}/{len(grp)}", **_group(vis, target)})
    return rows


def _single_rows(singles: Sequence[ScenarioScore], target: float) -> list[dict[str, Any]]:
    """The single-effect scenarios: the visible ones, then all."""
    vis = [s for s in singles if s.excited]
    return [{"group": "single, visible", "visible": f"{len(vis)}/{len(singles)}",
             **_group(vis, target)},
            {"group": "single, all", "visible": f"{len(vis)}/{len(singles)}",
             **_group(singles, target)}]


def _none_rows(scores: Sequence[ScenarioScore], target: float) -> list[dict[str, Any]]:
    nones = [s for s in scores if s.kind == "none"]
    return [{"group": "none", "visible": "-", **_group(nones, target)}] if nones else []


def _pair_rows(scores: Sequence[ScenarioScore], target: float) -> list[dict[str, Any]]:
    pairs = [s for s in scores if s.kind == "pair"]
    if not pairs:
        return []
    row = {"group": "pairs", "visible": f"{sum(s.excited for s in pairs)}/{len(pairs)}",
           **_group(pairs, target)}
    row["both_found"] = _pct(sum(s.all_found for s in pairs), len(pairs))
    return [row]
