"""The diagnosis's figures (Matplotlib, imported on use): withheld residuals before and after,
the residual against the implicated joint, and the shrink per step."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from zrp.gap.results import Diagnosis

__all__ = ["PLOT_FILES", "figures", "implicated_joint", "withheld_rows"]

PLOT_FILES = ("residuals_before_after.png", "residual_vs_joint.png", "shrink.png")
DPI = 110


def implicated_joint(diag: Diagnosis) -> int:
    """The joint to plot the residual against: among the joints of the first effect found
    (all joints when none was found), the one whose geometric parameters carry the largest
    share of the nominal residual (the "where" projection)."""
    n = diag.context.n
    cands = set(range(1, n + 1))
    for st in diag.steps:
        if st.joints and st.effect != "link_length":
            cands = {j for j in st.joints if j <= n}
            break
    proj = [p for p in diag.where.nominal.projection if p.joint in cands]
    if proj:
        return int(max(proj, key=lambda p: p.share).joint)
    return min(cands) if cands else 1


def withheld_rows(diag: Diagnosis) -> np.ndarray:
    """Measurement rows of the withheld poses, in the order of the withheld residuals."""
    return np.flatnonzero(np.isin(diag.context.meas.pose_index, diag.withheld_poses))


def _errors(diag: Diagnosis) -> tuple[np.ndarray, np.ndarray]:
    eb = np.linalg.norm(diag.withheld_residual_before.reshape(-1, 3), axis=1)
    ea = np.linalg.norm(diag.withheld_residual_after.reshape(-1, 3), axis=1)
    return eb, ea


def _before_after(plt: Any, diag: Diagnosis) -> Any:
    unit, floor = diag.length_unit, diag.noise_floor.rms
    eb, ea = _errors(diag)
    rows = withheld_rows(diag)
    fig, ax = plt.subplots(1, 2, figsize=(11, 4))
    bins = np.linspace(0, max(eb.max(), ea.max()) * 1.02, 40)
    ax[0].hist(eb, bins=bins, alpha=0.6, label=f"after registration (RMS {diag.nominal.rms:.3g})")
    ax[0].hist(ea, bins=bins, alpha=0.6, label=f"after correction (RMS {diag.final.rms:.3g})")
    if floor is not None:
        ax[0].axvline(floor, color="k", ls="--", lw=1, label=f"noise floor RMS {floor:.3g}")
    ax[0].set_xlabel(f"withheld |error| ({unit})")
    ax[0].set_ylabel("points")
    ax[0].legend(fontsize=8)
    ax[1].plot(rows, eb, ".", ms=3, label="after registration")
    ax[1].plot(rows, ea, ".", ms=3, label="after correction")
    ax[1].set_xlabel("row (measurement order)")
    ax[1].set_ylabel(f"withheld |error| ({unit})")
    ax[1].legend(fontsize=8)
    fig.suptitle("Withheld residuals before and after the diagnosed corrections")
    fig.tight_layout()
    return fig


def _against_joint(plt: Any, diag: Diagnosis) -> Any:
    unit = diag.length_unit
    eb, ea = _errors(diag)
    k = implicated_joint(diag)
    qk = diag.context.meas.q[withheld_rows(diag), k - 1]
    deg = not diag.context.model.prismatic[k - 1]
    x = np.degrees(qk) if deg else qk
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(x, eb, ".", ms=3, label="after registration")
    ax.plot(x, ea, ".", ms=3, label="after correction")
    ax.set_xlabel(f"q{k} ({'deg' if deg else unit})")
    ax.set_ylabel(f"withheld |error| ({unit})")
    ax.set_title(f"Residual against the implicated joint {k}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def _shrink(plt: Any, diag: Diagnosis) -> Any:
    unit, floor = diag.length_unit, diag.noise_floor.rms
    labels = ["registration"] + [f"+ {s.effect}" for s in diag.steps]
    rms = [diag.nominal.rms] + [s.withheld.rms for s in diag.steps]
    p95 = [diag.nominal.p95] + [s.withheld.p95 for s in diag.steps]
    fig, ax = plt.subplots(figsize=(max(6, 1.6 * len(labels)), 4))
    xs = np.arange(len(labels))
    ax.bar(xs - 0.2, rms, 0.4, label="RMS")
    ax.bar(xs + 0.2, p95, 0.4, label="p95")
    if floor is not None:
        ax.axhline(floor, color="k", ls="--", lw=1, label="noise floor RMS")
    ax.set_xticks(xs, labels, rotation=20, ha="right")
    ax.set_ylabel(f"withheld error ({unit})")
    ax.set_title("Shrink of the withheld error per step")
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def figures(diag: Diagnosis) -> Iterator[tuple[str, Any]]:
    """(file name, figure) for each of :data:`PLOT_FILES`, one at a time; each figure is
    closed when the caller asks for the next one."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for name, draw in zip(PLOT_FILES, (_before_after, _against_joint, _shrink), strict=True):
        fig = draw(plt, diag)
        try:
            yield name, fig
        finally:
            plt.close(fig)
