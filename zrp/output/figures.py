"""Figures laid out once, then drawn once for each file they are saved to.

Matplotlib's ``Figure.tight_layout`` leaves a placeholder layout engine on the figure, and
``savefig`` draws a figure that has any layout engine twice: a layout pass with rendering
switched off, then the drawing, although the placeholder lays out nothing. A report that saves
each figure as PNG and as SVG thus drew it four times. :func:`tight_layout_once` lays the figure
out and leaves no engine, so each ``savefig`` draws it once; the files are the same to the byte
(``tests/gap/test_report_figures.py``). Matplotlib is not imported here: the caller has it.
"""

from __future__ import annotations

from typing import Any

__all__ = ["tight_layout_once"]


def tight_layout_once(fig: Any, **kwargs: Any) -> Any:
    """``fig.tight_layout(**kwargs)``, then no layout engine on ``fig`` (whatever the
    ``figure.autolayout`` and ``figure.constrained_layout.use`` settings say); returns
    ``fig``."""
    import matplotlib

    fig.tight_layout(**kwargs)
    with matplotlib.rc_context({"figure.autolayout": False,
                                "figure.constrained_layout.use": False}):
        fig.set_layout_engine(None)
    return fig
