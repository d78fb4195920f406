"""Figures 2-7 of the paper's numerical example (Matplotlib, imported only when drawing)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.output import OutputDir, tight_layout_once
from zrp.paper.comparison import kind_columns
from zrp.paper.example import PaperExample
from zrp.paper.published import LIKELY_TYPOS, PUBLISHED_ROWS, PUBLISHED_TABLE2, PUBLISHED_TABLE3

__all__ = ["FIGURES", "coincident_with", "figure_names", "paper_figures", "why_apart"]

#: One line style and marker per series, so that no series hides another.
LINESTYLES = ("-", "--", "-.", ":", (0, (5, 1)), (0, (3, 1, 1, 1)))
MARKERS = ("o", "s", "^", "v", "D", "P", "X", "*")
#: Published markers of neighbouring columns are shifted by this (percent of xi) apart.
PUBLISHED_OFFSET = 0.0025

#: Figures 2-7: file name, the parameter kind it shows, "sweep" (max over t against xi, with
#: the published values) or "history" (deviation against t at xi = 0.1 %), the quantity
#: (a :class:`~zrp.manufacturing.study.StudyResult` attribute) and the published table.
FIGURES: tuple[tuple[str, str, str, str, int], ...] = (
    ("fig2_je_max_position.png", "JE", "sweep", "max_delta_p", 2),
    ("fig3_je_max_rotation.png", "JE", "sweep", "max_delta_r", 3),
    ("fig4_le_max_position.png", "LE", "sweep", "max_delta_p", 2),
    ("fig5_je_position_time.png", "JE", "history", "delta_p", 2),
    ("fig6_je_rotation_time.png", "JE", "history", "delta_r", 3),
    ("fig7_le_position_time.png", "LE", "history", "delta_p", 2),
)


def figure_names(ex: PaperExample) -> list[str]:
    """The figures :func:`paper_figures` draws for ``ex`` (those whose parameters it has)."""
    return [f[0] for f in FIGURES if kind_columns(ex.study, f[1])]


def _labels(name: str, unit: str, typos_noted: bool) -> tuple[str, str]:
    """(y label, title) of a figure."""
    pos = f"positional deviation ({unit})"
    rot = "rotational deviation, eq (15) (dimensionless)"
    return {
        "fig2_je_max_position.png": (
            f"max {pos}", "Fig. 2: joint-axis misalignments vs max positional deviation"
            + ("\n(published typos JE1, JE2 at 0.1 % omitted)" if typos_noted else "")),
        "fig3_je_max_rotation.png": (
            f"max {rot}", "Fig. 3: joint-axis misalignments vs max rotational deviation"),
        "fig4_le_max_position.png": (
            f"max {pos}", "Fig. 4: link-dimension perturbations vs max positional deviation"),
        "fig5_je_position_time.png": (
            pos, "Fig. 5: joint-axis misalignments, positional deviation vs time"),
        "fig6_je_rotation_time.png": (
            rot, "Fig. 6: joint-axis misalignments, rotational deviation vs time"),
        "fig7_le_position_time.png": (
            pos, "Fig. 7: link-dimension perturbations, positional deviation vs time"),
    }[name]


def why_apart(ex: PaperExample) -> str:
    """The sentence Figures 2-3 print under the axes when they show the published squares:
    on the default circle, why the joint-axis curves sit below them (the joint angles the
    paper's Table 3 implies against ours, ``ex.checks``); on the recovered circle, that they
    meet. Empty without published values (another model or a custom trajectory)."""
    if not ex.cells:
        return ""
    if ex.circle == "recovered":
        return ("On the circle recovered from the published Tables 2-3 the curves go through "
                "the squares (comparison.md).")
    imp = ex.checks.get("paper_implied_max_abs_q_deg") or {}
    ours = ex.checks.get("table3_closed_form") or {}
    if not imp or not ours:
        return ""
    lo = min(v["deg_min"] for v in imp.values())
    hi = max(v["max_abs_q_deg"] for v in ours.values())
    return (f"Why the curves sit below the squares: the paper does not publish its circle. On "
            f"this documented circle the joints turn at most {hi:.0f} deg from the zero "
            f"reference; the published Table 3 implies {lo:.0f}-180 deg, and a joint-axis "
            "error grows with 2 |sin(q_k / 2)|.\nOn the circle recovered from the published "
            "tables (`zrp paper --circle recovered`) the curves go through the squares; "
            "comparison.md gives every cell.")


def _caption(ex: PaperExample, kind: str, style: str) -> str:
    """The sentence under a figure: :func:`why_apart` for Figures 2-3, else none."""
    return why_apart(ex) if kind == "JE" and style == "sweep" else ""


def _draw_caption(fig: Any, caption: str) -> float:
    """Draw ``caption`` under the axes (what the reader must know, in the figure itself);
    returns the bottom margin the axes leave for it (fraction of the figure height)."""
    if not caption:
        return 0.03
    fig.text(0.01, 0.045, caption, ha="left", va="bottom", fontsize=8, color="darkred",
             wrap=True)
    return 0.13


def coincident_with(data: F64, names: list[str], rtol: float = 1e-2) -> dict[str, str]:
    """For each series equal to an earlier one (every sample within ``rtol`` of its largest
    value), the earlier
    one's name: these are drawn with open markers and named in the legend ("= X within 1 %"),
    never hidden."""
    out: dict[str, str] = {}
    for i in range(len(names)):
        for j in range(i):
            a, b = data[j].ravel(), data[i].ravel()
            if np.max(np.abs(a - b)) <= rtol * max(float(np.abs(a).max()), 1e-300):
                out[names[i]] = out.get(names[j], names[j])
                break
    return out


def _style(c: int, colors: list[str]) -> dict[str, Any]:
    return {"color": colors[c % len(colors)], "ls": LINESTYLES[c % len(LINESTYLES)],
            "marker": MARKERS[c % len(MARKERS)]}


def _sweep(ax: Any, ex: PaperExample, params: list[str], data: F64,
           pub: dict[str, tuple[float, ...]] | None, table: int, colors: list[str]) -> None:
    st = ex.study
    rows = [st.index(p) for p in params]
    same = coincident_with(data[rows], params)
    for c, p in enumerate(params):
        i = st.index(p)
        sty = _style(c, colors)
        note = f" (= {same[p]} within 1 %)" if p in same else ""
        ax.plot(st.xi_percent, data[i], ms=4 + 2 * (p in same), mfc="none" if p in same else
                sty["color"], lw=1.2, label=f"{p} ours{note}", **sty)
        if pub is not None and p in pub:
            dx = PUBLISHED_OFFSET * (c - (len(params) - 1) / 2)
            xs = [x + dx for x in PUBLISHED_ROWS if (table, p, x) not in LIKELY_TYPOS]
            ys = [v for x, v in zip(PUBLISHED_ROWS, pub[p], strict=True)
                  if (table, p, x) not in LIKELY_TYPOS]
            ax.plot(xs, ys, "s", mfc="none", color=sty["color"], ms=7, mew=1.2,
                    label=f"{p} published")
    ax.set_xlabel("perturbation xi (%)")


def _history(ax: Any, ex: PaperExample, params: list[str], data: F64,
             colors: list[str], suffix: str = "") -> None:
    st = ex.study
    j = int(np.argmin(np.abs(st.xi_percent - 0.1)))
    rows = data[[st.index(p) for p in params], j]
    same = coincident_with(rows, params)
    every = max(1, st.t.size // 12)
    for c, p in enumerate(params):
        note = f" (= {same[p]} within 1 %)" if p in same else ""
        ax.plot(st.t, data[st.index(p), j], lw=1.3, markevery=(c * every // 6 or 1, every),
                ms=5, mfc="none", label=f"{p}, xi = 0.1 %{note}{suffix}", **_style(c, colors))
    ax.set_xlabel("time (s)")


def _angle_twin(ax: Any) -> None:
    """A right-hand axis with the plain error angle theta (mrad) of an eq (15) value
    delta_R = 2 sqrt(2) sin(theta / 2)."""
    def to_theta(v: Any) -> Any:
        return 2e3 * np.arcsin(np.clip(np.asarray(v, dtype=float) / np.sqrt(8.0), -1, 1))

    def to_dr(th: Any) -> Any:
        return np.sqrt(8.0) * np.sin(np.asarray(th, dtype=float) / 2e3)

    ax.secondary_yaxis("right", functions=(to_theta, to_dr)).set_ylabel(
        "error angle theta (mrad)")


def paper_figures(ex: PaperExample, out: OutputDir, *, suffix: str = "",
                  only: tuple[str, ...] | None = None, circle: str = "") -> list[Path]:
    """Draw Figures 2-7 (:func:`figure_names`) into the open output folder ``out``.

    Args:
        suffix: appended to each file's stem (``fig5_je_position_time<suffix>.png``).
        only: the file names (without suffix) to draw; default all.
        circle: appended to each title (e.g. "on the recovered circle").
    """
    suffix_title = f"\n({circle})" if circle else ""
    import matplotlib  # a plotting dependency: loaded on first use only

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    st = ex.study
    conv = f"sign(0): links {st.sign_zero_links:+d}, axes {st.sign_zero_axes:+d}".replace(
        "+0", "0")
    pubs = {2: PUBLISHED_TABLE2, 3: PUBLISHED_TABLE3} if ex.cells else {}
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    files: list[Path] = []
    for name, kind, style, quantity, table in FIGURES:
        params = kind_columns(st, kind)
        if not params or (only is not None and name not in only):
            continue
        ylabel, title = _labels(name, st.unit, bool(pubs))
        caption = _caption(ex, kind, style)
        fig, ax = plt.subplots(figsize=(9.5, 4.8 + 0.6 * bool(caption)))
        try:
            if style == "sweep":
                _sweep(ax, ex, params, getattr(st, quantity), pubs.get(table), table, colors)
            else:
                _history(ax, ex, params, getattr(st, quantity), colors)
            ax.set_ylabel(ylabel)
            if quantity.endswith("delta_r"):
                _angle_twin(ax)
            ax.set_title(title + suffix_title)
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.12 if "delta_r" in
                      quantity else 1.01, 1.0), borderaxespad=0.0)
            note = ("published squares offset in xi for legibility; "
                    if style == "sweep" and pubs else "")
            fig.text(0.99, 0.01, f"{note}{conv}; {ex.path.label}", ha="right", va="bottom",
                     fontsize=7, color="0.4")
            tight_layout_once(fig, rect=(0, _draw_caption(fig, caption), 1, 1))
            files.append(out.savefig(name.replace(".png", f"{suffix}.png"), fig, dpi=110))
        finally:
            plt.close(fig)
    return files
