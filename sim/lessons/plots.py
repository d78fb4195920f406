"""Matplotlib for the lessons (imported only when a lesson draws)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from zrp.output import OutputDir

__all__ = ["figure"]


@contextmanager
def figure(out: OutputDir, name: str, rows: int = 1) -> Iterator[tuple[Any, Any]]:
    """A figure with ``rows`` stacked axes sharing x, saved as ``name`` into ``out``."""
    import matplotlib  # plotting only when a lesson draws

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(rows, 1, figsize=(8, 2.6 + 2.2 * rows), sharex=rows > 1)
    try:
        yield fig, axes
        for ax in (axes if rows > 1 else [axes]):
            ax.grid(alpha=0.3)
        fig.tight_layout()
        out.savefig(name, fig, dpi=100)
    finally:
        plt.close(fig)
