"""Figures 2-7 of the paper's numerical example (Matplotlib, imported only when drawing)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.output import OutputDir
from zrp.paper.comparison import kind_columns
from zrp.paper.example import PaperExample
from zrp.paper.published import LIKELY_TYPOS, PUBLISHED_ROWS, PUBLISHED_TABLE2, PUBLISHED_TABLE3

__all__ = ["FIGURES", "figure_names", "paper_figures"]

F64 = NDArray[np.float64]

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
    rot = "rotational deviation, eq (15)"
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


def _sweep(ax: Any, ex: PaperExample, params: list[str], data: F64,
           pub: dict[str, tuple[float, ...]] | None, table: int, colors: list[str]) -> None:
    st = ex.study
    for c, p in enumerate(params):
        i = st.index(p)
        ax.plot(st.xi_percent, data[i], "-o", ms=3, color=colors[c % 10], label=f"{p} ours")
        if pub is not None and p in pub:
            xs = [x for x in PUBLISHED_ROWS if (table, p, x) not in LIKELY_TYPOS]
            ys = [v for x, v in zip(PUBLISHED_ROWS, pub[p], strict=True)
                  if (table, p, x) not in LIKELY_TYPOS]
            ax.plot(xs, ys, "s", mfc="none", color=colors[c % 10], ms=7,
                    label=f"{p} published")
    ax.set_xlabel("perturbation xi (%)")


def _history(ax: Any, ex: PaperExample, params: list[str], data: F64,
             colors: list[str]) -> None:
    st = ex.study
    j = int(np.argmin(np.abs(st.xi_percent - 0.1)))
    for c, p in enumerate(params):
        ax.plot(st.t, data[st.index(p), j], color=colors[c % 10], label=f"{p}, xi = 0.1 %")
    ax.set_xlabel("time (s)")


def paper_figures(ex: PaperExample, out: OutputDir) -> list[Path]:
    """Draw Figures 2-7 (:func:`figure_names`) into the open output folder ``out``."""
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
        if not params:
            continue
        ylabel, title = _labels(name, st.unit, bool(pubs))
        fig, ax = plt.subplots(figsize=(7, 4.6))
        try:
            if style == "sweep":
                _sweep(ax, ex, params, getattr(st, quantity), pubs.get(table), table, colors)
            else:
                _history(ax, ex, params, getattr(st, quantity), colors)
            ax.set_ylabel(ylabel)
            ax.set_title(title)
            ax.grid(alpha=0.3)
            if style == "sweep":
                ax.legend(fontsize=7, ncol=2)
            else:
                ax.legend(fontsize=8)
            fig.text(0.99, 0.01, f"{conv}; {ex.path.label}", ha="right", va="bottom",
                     fontsize=7, color="0.4")
            fig.tight_layout(rect=(0, 0.03, 1, 1))
            files.append(out.savefig(name, fig, dpi=110))
        finally:
            plt.close(fig)
    return files
