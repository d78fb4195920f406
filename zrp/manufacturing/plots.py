"""Figures of the tolerance analysis (Matplotlib, imported only when a figure is drawn)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from zrp.errors import InputError
from zrp.manufacturing.population import MonteCarloResult
from zrp.output import atomic_path

__all__ = ["check_png_path", "histogram_png"]


def check_png_path(path: str | Path, name: str = "path") -> Path:
    """``path`` as a Path when it names a ``.png`` file; else an error naming ``name`` (the
    file written is exactly the one named, never a different one with a suffix added)."""
    p = Path(path)
    if p.suffix.lower() != ".png":
        raise InputError(f"{name}: {str(path)!r} is not a .png file name; the histogram is a "
                         f"PNG image (e.g. {p.stem or 'hist'}.png)")
    return p


def histogram_png(mc: MonteCarloResult, path: str | Path, *, overwrite: bool = False,
                  title: str = "") -> Path:
    """Histograms of max_t delta_p and max_t theta of a Monte Carlo run, with percentile
    markers, written atomically as a PNG (:mod:`zrp.output`).

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
            for ax, data, label in ((axs[0], mc.max_delta_p, f"max delta_p ({mc.unit})"),
                                    (axs[1], mc.max_angle_rad * 1e3, "max error angle (mrad)")):
                ax.hist(data, bins=80, color="#4477aa", alpha=0.85)
                for pct, ls in ((50, ":"), (95, "--"), (99, "-")):
                    v = np.percentile(data, pct)
                    ax.axvline(v, color="#cc3311", ls=ls, label=f"P{pct} = {v:.4g}")
                ax.set_xlabel(label)
                ax.set_ylabel("robots")
                ax.legend()
            fig.suptitle(title or f"Monte Carlo, {mc.n_robots} robots x {mc.n_points} points, "
                         f"{mc.distribution}")
            fig.tight_layout()
            fig.savefig(tmp, dpi=110, format="png")
        finally:
            plt.close(fig)
    return Path(path)
