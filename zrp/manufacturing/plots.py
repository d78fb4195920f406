"""Figures of the tolerance analysis (Matplotlib, imported only when a figure is drawn)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.manufacturing.histogram import Histogram
from zrp.manufacturing.population import MonteCarloResult
from zrp.manufacturing.reduction import MonteCarloSummary
from zrp.output import atomic_path, tight_layout_once

__all__ = ["check_png_path", "histogram_png"]


def check_png_path(path: str | Path, name: str = "path") -> Path:
    """``path`` as a Path when it names a ``.png`` file; else an error naming ``name`` (the
    file written is exactly the one named, never a different one with a suffix added)."""
    p = Path(path)
    if p.suffix.lower() != ".png":
        raise InputError(f"{name}: {str(path)!r} is not a .png file name; the histogram is a "
                         f"PNG image (e.g. {p.stem or 'hist'}.png)")
    return p


#: Bars a panel shows.
BARS = 80


def _bars(h: Histogram, scale: float) -> tuple[F64, F64, F64]:
    """(left, width, count) of :data:`BARS` equal-width bars from the exact minimum to the
    exact maximum of a reduced histogram: the robots of each fixed bin are spread uniformly
    over it and shared among the bars it overlaps (linear interpolation of the cumulative
    count; the underflow and overflow bins span the exact minimum / maximum); values times
    ``scale``."""
    x = np.concatenate([[h.minimum], np.clip(h.edges, h.minimum, h.maximum), [h.maximum]])
    cum = np.concatenate([[0.0], np.cumsum(h.counts, dtype=float)])
    last = np.concatenate([np.diff(x) > 0, [True]])  # of equal x, the largest count
    x, cum = x[last], cum[last]
    if x.size < 2:  # every robot has the same value
        x, cum = np.array([x[0], x[0] * (1 + 1e-6) + 1e-12]), np.array([0.0, cum[-1]])
    edges = np.linspace(x[0], x[-1], BARS + 1)
    return edges[:-1] * scale, np.diff(edges) * scale, np.diff(np.interp(edges, x, cum))


def _panels(mc: MonteCarloResult | MonteCarloSummary) -> list[tuple[Any, float, str]]:
    return [(mc.max_delta_p if isinstance(mc, MonteCarloResult) else mc.delta_p, 1.0,
             f"max delta_p ({mc.unit})"),
            (mc.max_angle_rad if isinstance(mc, MonteCarloResult) else mc.angle_rad, 1e3,
             "max error angle (mrad)")]


def histogram_png(mc: MonteCarloResult | MonteCarloSummary, path: str | Path, *,
                  overwrite: bool = False, title: str = "") -> Path:
    """Histograms of max_t delta_p and max_t theta of a Monte Carlo run, with percentile
    markers, written atomically as a PNG (:mod:`zrp.output`). A run reduced on the workers
    (:class:`~zrp.manufacturing.reduction.MonteCarloSummary`) is drawn from its fixed bins,
    added up to about :data:`BARS` bars, with its percentile estimates.

    Raises:
        OutputExistsError: ``path`` exists and ``overwrite`` is False (checked before drawing).
        InputError: ``path`` does not end in ``.png``.
    """
    check_png_path(path)
    import matplotlib  # a plotting dependency: loaded on first use only

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    with atomic_path(path, overwrite=overwrite) as tmp:
        fig, axs = plt.subplots(1, 2, figsize=(11, 4))
        try:
            for ax, (data, scale, label) in zip(axs, _panels(mc), strict=True):
                if isinstance(data, Histogram):
                    left, width, count = _bars(data, scale)
                    ax.bar(left, count, width=width, align="edge", color="#4477aa", alpha=0.85)
                else:
                    ax.hist(data * scale, bins=BARS, color="#4477aa", alpha=0.85)
                for pct, ls in ((50, ":"), (95, "--"), (99, "-")):
                    v = (data.percentile(pct)[0] if isinstance(data, Histogram)
                         else np.percentile(data, pct)) * scale
                    ax.axvline(v, color="#cc3311", ls=ls, label=f"P{pct} = {v:.4g}")
                ax.set_xlabel(label)
                ax.set_ylabel("robots")
                ax.legend()
            reduced = ", reduced on the workers" if isinstance(mc, MonteCarloSummary) else ""
            fig.suptitle(title or f"Monte Carlo, {mc.n_robots:,} robots x {mc.n_points} points, "
                         f"{mc.distribution}{reduced}")
            tight_layout_once(fig)
            fig.savefig(tmp, dpi=110, format="png")
        finally:
            plt.close(fig)
    return Path(path)
