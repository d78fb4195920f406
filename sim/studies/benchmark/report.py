"""Blind benchmark, part 6: the report - Markdown text, CSV tables, JSON and the confusion
plot - written through :class:`zrp.output.OutputDir` (checked up front, atomic, one run at a
time per folder). Text cells reach summary.md through :func:`zrp.escape.md_text` and the CSV
tables through :func:`zrp.escape.csv_text`: a model name or an error message is only text.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from sim.robot.measurement import REPLACE
from sim.studies.benchmark.results import BenchmarkResult, confusion_matrix, summary_rows
from sim.studies.benchmark.scenarios import DEFAULT_NOISE_MM, BenchmarkConfig
from sim.studies.benchmark.scoring import ScenarioScore
from zrp.errors import OutputExistsError
from zrp.escape import csv_text, md_text
from zrp.output import OutputDir

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = ["OUTPUT_FILES", "compensated_summary", "output_names", "render_text", "write_outputs"]

OUTPUT_FILES = ("summary.md", "confusion.csv", "scenarios.csv", "results.json", "confusion.png")


def output_names(plots: bool = True) -> tuple[str, ...]:
    """The files :func:`write_outputs` writes (without the PNG unless ``plots``)."""
    return tuple(f for f in OUTPUT_FILES if plots or not f.endswith(".png"))


def _md_table(header: list[str], rows: list[list[Any]]) -> str:
    def fmt(v: Any) -> str:
        if isinstance(v, float):
            return "-" if not math.isfinite(v) else f"{v:.3g}"
        return md_text(v)
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(fmt(v) for v in r) + " |" for r in rows]
    return "\n".join(lines)


def _noise_text(cfg: BenchmarkConfig) -> str:
    """The configured noise range (model length unit), or the default's in mm."""
    lo, hi = cfg.noise if cfg.noise is not None else DEFAULT_NOISE_MM
    return f"{lo:g}-{hi:g}" + (" mm" if cfg.noise is None else "")


def render_text(result: BenchmarkResult) -> str:
    """Markdown: summary table, confusion matrix, pairs, failures and timings."""
    rows = summary_rows(result)
    out = [*_intro(result), *_summary_section(result.config, rows), *_coverage_section(rows),
           *_confusion_section(result), *_pairs_section(result.scores),
           *_compensated_section(result), *_not_right_section(result.scores),
           *_failures_section(result)]
    if result.resumed:
        out += ["", f"Resumed: {result.resumed} scores taken from the interrupted run."]
    out += ["", f"Wall time {result.wall_s:.1f} s: simulation {result.sim_s:.1f} s, diagnosis "
            f"{result.diag_s:.1f} s ({result.wall_s / max(len(result.scores), 1):.2f} s per "
            f"scenario)."]
    return "\n".join(out) + "\n"


def _intro(result: BenchmarkResult) -> list[str]:
    cfg = result.config
    return [f"# Blind gap benchmark: {md_text(result.model_name)}", "",
            f"{len(result.scores)} scenarios (seed {cfg.seed}), {cfg.poses} poses each "
            f"({cfg.poses_from} poses, {cfg.approach} approach, {cfg.reflectors} "
            f"reflector{'s' if cfg.reflectors > 1 else ''}), tracker noise "
            f"{_noise_text(cfg)} per coordinate, MJCF inertias "
            f"{'given' if cfg.use_mjcf else 'not given'} to the diagnosis. Visible: signature "
            f"after registration >= {cfg.excitation_threshold:g} x noise RMS. Target: withheld "
            f"RMS after correction <= {cfg.ratio_target:g} x noise RMS.", "",
            f"Simulated robot's dynamics: {result.dynamics or 'not recorded'}."]


def _summary_section(cfg: BenchmarkConfig, rows: list[dict[str, Any]]) -> list[str]:
    return ["", "## Summary", "", _md_table(
        ["group", "visible", "n", "right effect first", "right or reported tie",
         "+ joints located", f"RMS <= {cfg.ratio_target:g}x noise", "all three",
         "median ratio", "median shrink", "both found"],
        [[r["group"], r["visible"], r["n"], r["top"], r["top_or_tie"], r["top_and_joints"],
          r["ratio_ok"], r["all_three"], r["median_ratio"], r["median_shrink"],
          r.get("both_found", "")] for r in rows])]


def _coverage_section(rows: list[dict[str, Any]]) -> list[str]:
    return ["", "95 % interval coverage of the true values (final parameters of the hidden "
            "effect, 0 where not injected; sim/studies/benchmark/coverage.py):", "",
            _md_table(["group", "parameters covered", "scenarios with all covered",
                       "same, simultaneous 95 % intervals of the effect"],
                      [[r["group"], r["ci95_parameters"], r["ci95_scenarios"],
                        r.get("ci95_effect_scenarios", "-")] for r in rows])]


def _confusion_section(result: BenchmarkResult) -> list[str]:
    conf = confusion_matrix(result)
    cols = sorted({c for r in conf.values() for c in r})
    return ["", "## Confusion matrix (single effect and none; row: hidden, column: named first)",
            "", _md_table(["hidden \\ named", *cols],
                          [[r, *[conf[r].get(c, 0) or "" for c in cols]] for r in sorted(conf)])]


def _hidden_text(s: ScenarioScore) -> str:
    """The hidden effects of a scenario with their joints and signal-to-noise ratios."""
    return ", ".join(f"{e} {list(s.hidden_joints[e])} ({s.snr.get(e, 0):.2g})"
                     for e in s.hidden)


def _pairs_section(scores: Sequence[ScenarioScore]) -> list[str]:
    pairs = [s for s in scores if s.kind == "pair"]
    if not pairs:
        return []
    return ["", "## Pairs", "", _md_table(
        ["#", "hidden (SNR)", "named", "both found", "ratio"],
        [[s.index, _hidden_text(s), ", ".join(s.found), s.all_found, s.ratio]
         for s in pairs])]


def _not_right_section(scores: Sequence[ScenarioScore]) -> list[str]:
    bad = [s for s in scores if not s.success]
    if not bad:
        return []
    return ["", "## Scenarios not fully right", "", _md_table(
        ["#", "kind", "hidden [joints] (SNR)", "named [joints]", "ratio", "note"],
        [[s.index, s.kind, _hidden_text(s) or "none",
          ", ".join(f"{e} {list(j)}" for e, j in zip(s.found, s.found_joints,
                                                      strict=False)) or "none",
          s.ratio, s.note]
         for s in bad])]


def _failures_section(result: BenchmarkResult) -> list[str]:
    if not result.failures:
        return []
    return ["", "## Scenarios that failed (the others completed)", "", _md_table(
        ["input", "error"], [[f.task, f.error] for f in result.failures])]


def _comp(s: Any, key: str) -> float:
    v = s.values.get(key)
    return math.nan if v is None else float(v)


def compensated_summary(result: BenchmarkResult) -> str:
    """The compensated column's summary line ("" when the run has no such column)."""
    t = result.config.ratio_target
    comp = [s for s in result.scores if "comp_ratio" in s.values]
    if not comp:
        return ""
    ok = [s for s in comp if math.isfinite(_comp(s, "comp_ratio"))]
    r = np.array([_comp(s, "comp_ratio") for s in ok])
    vis = [s for s in ok if _comp(s, "comp_ratio_before") > t]
    rv = np.array([_comp(s, "comp_ratio") for s in vis])
    med = f"{np.median(r):.2f}" if r.size else "-"
    medv = f"{np.median(rv):.2f}" if rv.size else "-"
    return (f"Compensated: {int(np.sum(r <= t))}/{len(comp)} scenarios land within {t:g}x "
            f"the tracker noise after compensation (median {med}x); where the error was "
            f"visible before (> {t:g}x the noise) {int(np.sum(rv <= t))}/{len(vis)} "
            f"(median {medv}x); {len(comp) - len(ok)} refused.")


def _compensated_section(result: BenchmarkResult) -> list[str]:
    """The "compensated" column: per scenario, the measured error of fresh targets before and
    after compensation over the tracker's pure-noise RMS (sim/studies/benchmark/compensated.py)."""
    line = compensated_summary(result)
    if not line:
        return []
    cfg = result.config
    rows = [[s.index, ", ".join(s.hidden) or "none", ", ".join(s.found),
             int(s.values.get("comp_targets", 0)), _comp(s, "comp_ratio_before"),
             _comp(s, "comp_ratio"), s.values.get("comp_error", "")]
            for s in result.scores if "comp_ratio" in s.values]
    return ["", "## Compensated", "",
            f"Fresh targets ({cfg.compensate} random per scenario, plus half as many points "
            "of the paper's circle on a 6-joint arm, each approached from a chosen side) "
            "compensated with the scenario's diagnosis, commanded on the same real robot and "
            "measured by the same tracker: measured RMS over the pure-noise RMS, before "
            f"(program as it is) and after compensation (target <= {cfg.ratio_target:g}).",
            "", line, "",
            _md_table(["#", "hidden", "named", "targets", "before / noise",
                       "compensated / noise", "refused"], rows)]


_SCENARIO_COLUMNS = ["index", "kind", "hidden", "hidden_joints", "snr", "payload", "found",
                     "found_joints", "top_correct", "tied", "joints_correct", "all_found",
                     "noise_rms", "nominal_rms", "final_rms", "ratio", "shrink", "unexplained",
                     "success", "note", "sim_s", "diag_s", "comp_ratio_before", "comp_ratio"]


def _confusion_rows(conf: dict[str, dict[str, int]]) -> list[list[Any]]:
    cols = sorted({c for r in conf.values() for c in r})
    return [["hidden", *cols]] + [[r, *[conf[r].get(c, 0) for c in cols]] for r in sorted(conf)]


def _scenario_rows(result: BenchmarkResult) -> list[list[Any]]:
    rows: list[list[Any]] = [_SCENARIO_COLUMNS]
    for s in result.scores:
        rows.append([s.index, s.kind, ";".join(s.hidden) or "none",
                     ";".join(f"{e}:{'/'.join(map(str, j))}"
                              for e, j in s.hidden_joints.items()),
                     ";".join(f"{e}:{v:.3g}" for e, v in s.snr.items()), s.payload,
                     ";".join(s.found),
                     ";".join("/".join(map(str, j)) for j in s.found_joints),
                     s.top_correct, ";".join(s.tied), s.joints_correct, s.all_found,
                     f"{s.noise_rms:.5g}",
                     f"{s.nominal_rms:.5g}", f"{s.final_rms:.5g}", f"{s.ratio:.4g}",
                     f"{s.shrink:.4g}", s.unexplained, s.success, s.note,
                     f"{s.sim_s:.2f}", f"{s.diag_s:.2f}",
                     *[f"{s.values[k]:.4g}" if k in s.values else ""
                       for k in ("comp_ratio_before", "comp_ratio")]])
    return rows


def _write_csv(out: OutputDir, name: str, rows: list[list[Any]]) -> None:
    out.write_text(name, csv_text(rows[0], rows[1:]))


def _write_all(result: BenchmarkResult, out: OutputDir, plots: bool) -> list[Path]:
    start = len(out.written)
    out.write_text("summary.md", render_text(result))
    conf = confusion_matrix(result)
    _write_csv(out, "confusion.csv", _confusion_rows(conf))
    _write_csv(out, "scenarios.csv", _scenario_rows(result))
    out.write_json("results.json", result.to_dict(), indent=1)
    if plots:
        out.savefig("confusion.png", _confusion_figure(conf), dpi=110)
    return list(out.written[start:])


def write_outputs(result: BenchmarkResult, out: str | os.PathLike[str] | OutputDir, *,
                  overwrite: bool = False, plots: bool = True) -> list[Path]:
    """Write summary.md, confusion.csv, scenarios.csv, results.json (and confusion.png).

    Args:
        result: the run.
        out: the output folder; or an :class:`zrp.output.OutputDir` the caller has entered
            (then its own ``overwrite`` applies), to hold one lock over a longer run.
        overwrite: replace existing files; without it nothing is written if one exists.
        plots: also write confusion.png.

    Returns:
        the files written, in order.
    """
    if isinstance(out, OutputDir):
        return _write_all(result, out, plots)
    try:
        # every file it may write is checked, and an earlier run's plot removed without plots
        with OutputDir(out, overwrite=overwrite, names=output_names(True), prune=True) as folder:
            return _write_all(result, folder, plots)
    except OutputExistsError as exc:
        if not exc.paths:
            raise
        raise OutputExistsError(exc.paths, REPLACE) from None


def _confusion_figure(conf: dict[str, dict[str, int]]) -> Figure:
    # Matplotlib (~0.4 s to import) only when a plot is wanted (``plots=False`` skips it).
    from matplotlib.figure import Figure

    rows = sorted(conf)
    cols = sorted({c for r in conf.values() for c in r})
    a = np.array([[conf[r].get(c, 0) for c in cols] for r in rows], dtype=float)
    fig = Figure(figsize=(1.2 + 0.9 * len(cols), 1.0 + 0.45 * len(rows)))
    ax = fig.subplots()
    ax.imshow(a, cmap="Blues")
    ax.set_xticks(range(len(cols)), cols, rotation=40, ha="right")
    ax.set_yticks(range(len(rows)), rows)
    for i in range(len(rows)):
        for j in range(len(cols)):
            if a[i, j]:
                ax.text(j, i, int(a[i, j]), ha="center", va="center",
                        color="white" if a[i, j] > a.max() / 2 else "black")
    ax.set_xlabel("named first by the diagnosis")
    ax.set_ylabel("hidden in the real robot")
    ax.set_title("Blind gap benchmark: confusion matrix")
    fig.tight_layout()
    return fig
