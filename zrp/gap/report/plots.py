"""The diagnosis's figures (Matplotlib, imported on use): withheld residuals before and after,
the signed residual per axis against every joint, the residual over the workspace, the shrink
per step on a log axis with the noise floor and the geometric baseline, and the correlation
matrix of the final model's parameters."""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from zrp.gap.results import Diagnosis
from zrp.output import tight_layout_once

__all__ = ["PLOT_FILES", "figures", "implicated_joint", "withheld_rows"]

PLOT_FILES = ("residuals_before_after.png", "residual_vs_joint.png", "shrink.png",
              "residual_map.png", "correlation.png")
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
    ax[1].plot(rows, eb, ".", ms=3, label="after registration", rasterized=True)
    ax[1].plot(rows, ea, ".", ms=3, label="after correction", rasterized=True)
    ax[1].set_xlabel("row (measurement order)")
    ax[1].set_ylabel(f"withheld |error| ({unit})")
    ax[1].legend(fontsize=8)
    fig.suptitle("Withheld residuals before and after the diagnosed corrections")
    tight_layout_once(fig)
    return fig


def _against_joint(plt: Any, diag: Diagnosis) -> Any:
    """Signed withheld residual (x, y, z, instrument frame) of the final model against each
    joint."""
    unit = diag.length_unit
    ra = diag.withheld_residual_after.reshape(-1, 3)
    q = diag.context.meas.q[withheld_rows(diag)]
    n = q.shape[1]
    cols = min(n, 4)
    rows = -(-n // cols)
    fig, axs = plt.subplots(rows, cols, figsize=(3.6 * cols, 2.9 * rows), squeeze=False,
                            sharey=True)
    for k in range(n):
        ax = axs[k // cols][k % cols]
        deg = not diag.context.model.prismatic[k]
        x = np.degrees(q[:, k]) if deg else q[:, k]
        for c, lab in enumerate("xyz"):
            ax.plot(x, ra[:, c], ".", ms=2, alpha=0.6, label=lab, rasterized=True)
        ax.axhline(0.0, color="k", lw=0.5)
        ax.set_xlabel(f"q{k + 1} ({'deg' if deg else unit})")
        if k % cols == 0:
            ax.set_ylabel(f"residual ({unit})")
    for k in range(n, rows * cols):
        axs[k // cols][k % cols].set_visible(False)
    axs[0][0].legend(fontsize=7, markerscale=3)
    fig.suptitle("Withheld residual of the final model per axis (signed) against each joint")
    tight_layout_once(fig)
    return fig


def _shrink(plt: Any, diag: Diagnosis) -> Any:
    unit, floor = diag.length_unit, diag.noise_floor.rms
    a = diag.assessment
    source = "search" if a is None or a.choice is None else a.choice.source
    last = {"search": "final (pruned)", "geometric_baseline": "final (geometric)"}.get(
        source, "final (geometric + non-geometric)")
    labels = ["registration"] + [f"+ {s.effect}" for s in diag.steps] + [last]
    rms = [diag.nominal.rms] + [s.withheld.rms for s in diag.steps] + [diag.final.rms]
    p95 = [diag.nominal.p95] + [s.withheld.p95 for s in diag.steps] + [diag.final.p95]
    if a is not None:
        labels.append("geometric calibration")
        rms.append(a.baseline.withheld.rms)
        p95.append(a.baseline.withheld.p95)
        if a.baseline.combined is not None:  # the third candidate of the final choice
            labels.append("geometric + non-geometric")
            rms.append(a.baseline.combined.rms)
            p95.append(a.baseline.combined.p95)
    fig, ax = plt.subplots(figsize=(max(6, 1.5 * len(labels)), 4))
    xs = np.arange(len(labels))
    ax.bar(xs - 0.2, rms, 0.4, label="RMS")
    ax.bar(xs + 0.2, p95, 0.4, label="p95")
    if floor:
        ax.axhline(floor, color="k", ls="--", lw=1, label=f"noise floor RMS {floor:.3g}")
    else:  # a legend entry beside the axes: inside them it covered the last bars
        ax.plot([], [], " ", label="no noise floor\ncan be estimated")
    ax.set_yscale("log")
    ax.set_xticks(xs, labels, rotation=20, ha="right")
    ax.set_ylabel(f"withheld error ({unit}, log)")
    ax.set_title("Withheld error per step (log axis)")
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))  # beside, not over bars
    tight_layout_once(fig)
    return fig


def _workspace(plt: Any, diag: Diagnosis) -> Any:
    """The final model's withheld error over the workspace (base frame: top and side view)."""
    unit = diag.length_unit
    pos = diag.context.nominal_fk.position[diag.context.meas.pose_index[withheld_rows(diag)]]
    _, ea = _errors(diag)
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.2))
    vmax = float(np.percentile(ea, 99)) if ea.size else 1.0
    for a, (i, j, t) in zip(ax, ((0, 1, "top view (x, y)"), (0, 2, "side view (x, z)")),
                            strict=True):
        sc = a.scatter(pos[:, i], pos[:, j], c=ea, s=8, cmap="viridis", vmin=0, vmax=vmax,
                       rasterized=True)
        a.set_xlabel(f"{'xyz'[i]} ({unit}, base)")
        a.set_ylabel(f"{'xyz'[j]} ({unit}, base)")
        a.set_title(t)
        a.set_aspect("equal", adjustable="datalim")
    fig.colorbar(sc, ax=ax, label=f"withheld |error| after correction ({unit})")
    fig.suptitle("Where in the workspace the final error lies")
    return fig


def _correlation(plt: Any, diag: Diagnosis) -> Any:
    a = diag.assessment
    fig, ax = plt.subplots(figsize=(8, 7))
    if a is None or not a.correlations.names:
        ax.text(0.5, 0.5, "no correlation matrix", ha="center")
        return fig
    c = a.correlations
    im = ax.imshow(c.matrix, cmap="RdBu_r", vmin=-1, vmax=1)
    k = len(c.names)
    fs = max(3, min(8, int(400 / max(k, 1))))
    ax.set_xticks(range(k), c.names, rotation=90, fontsize=fs)
    ax.set_yticks(range(k), c.names, fontsize=fs)
    fig.colorbar(im, ax=ax, label="correlation")
    ax.set_title("Parameter correlations of the final model (robust covariance)")
    tight_layout_once(fig)
    return fig


def figures(diag: Diagnosis) -> Iterator[tuple[str, Any]]:
    """(file name, figure) for each of :data:`PLOT_FILES`, one at a time; each figure is
    closed when the caller asks for the next one."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    draws = (_before_after, _against_joint, _shrink, _workspace, _correlation)
    for name, draw in zip(PLOT_FILES, draws, strict=True):
        fig = draw(plt, diag)
        try:
            yield name, fig
        finally:
            plt.close(fig)
