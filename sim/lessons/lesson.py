"""What a lesson returns (:class:`Lesson`) and the figure helper every lesson draws with; the
lessons import this module, the registry (:mod:`sim.lessons.registry`) imports the lessons."""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from zrp.errors import InputError
from zrp.output import OutputDir

__all__ = ["Lesson", "LessonFn", "figure"]


@dataclass(frozen=True, eq=False)
class Lesson:
    """What one lesson wrote and measured.

    Attributes:
        name: registry key. concept: the one idea it teaches (one sentence).
        files: written files. sentences: file name -> what it shows (one sentence).
        numbers: what it measured (plain values, units in the keys).
    """

    name: str
    concept: str
    files: tuple[Path, ...]
    sentences: dict[str, str]
    numbers: dict[str, float | str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        missing = [f.name for f in self.files if f.name not in self.sentences]
        if missing:
            raise InputError(f"Lesson {self.name}: files without a sentence: {missing}")


#: A lesson: ``lesson(out, small) -> Lesson``, writing into the entered folder ``out``.
LessonFn = Callable[[OutputDir, bool], Lesson]


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
