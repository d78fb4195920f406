"""The diagnosis's figures are built once and drawn once for each file they are saved to (PNG
and the SVG that report.html embeds), with the same bytes as a figure left with Matplotlib's
tight-layout placeholder engine, which savefig drew twice (zrp/output/figures.py)."""

from __future__ import annotations

import io

import numpy as np
import pytest

import zrp
from zrp.gap import Injection, diagnose, synthesize
from zrp.gap.report import plots
from zrp.kinematics import uniform_joint_values


@pytest.fixture(scope="module")
def diag():
    model = zrp.load_model("puma")
    rng = np.random.default_rng(3)
    q = uniform_joint_values(model, 120, rng)
    meas = synthesize(model, q, Injection(joint_offset={2: 1e-3}), rng=rng, noise_sigma=0.02)
    return diagnose(model, meas, seed=0)


def _saved(diag) -> tuple[list[int], list[bytes]]:
    """Draws per savefig and the bytes of each figure's PNG and SVG (no date, fixed ids)."""
    import matplotlib

    draws: list[int] = []
    files: list[bytes] = []
    with matplotlib.rc_context({"svg.hashsalt": "zrp"}):
        for _, fig in plots.figures(diag):
            count: list[int] = []
            fig.canvas.mpl_connect("draw_event", lambda _e, c=count: c.append(1))
            for fmt, meta in (("png", {"Software": None}), ("svg", {"Date": None})):
                buf = io.BytesIO()
                n = len(count)
                fig.savefig(buf, format=fmt, dpi=plots.DPI, metadata=meta)
                draws.append(len(count) - n)
                files.append(buf.getvalue())
    return draws, files


def test_each_figure_is_drawn_once_a_file_with_the_same_bytes(diag, monkeypatch):
    draws, files = _saved(diag)
    assert draws == [1] * 2 * len(plots.PLOT_FILES)
    # the former layout: Matplotlib's tight_layout alone (a placeholder engine left behind)
    monkeypatch.setattr(plots, "tight_layout_once", lambda fig, **kw: fig.tight_layout(**kw))
    former_draws, former_files = _saved(diag)
    assert sum(d == 2 for d in former_draws) >= 4  # the control: it did draw twice
    assert len(former_files) == len(files) == 2 * len(plots.PLOT_FILES)
    for new, old, name in zip(files, former_files, np.repeat(plots.PLOT_FILES, 2), strict=True):
        assert new == old, name
