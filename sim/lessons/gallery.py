"""The lesson registry, the runner and the lessons' figure helper (see the package
docstring)."""

from __future__ import annotations

from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from zrp.errors import InputError
from zrp.output import OutputDir

__all__ = ["LESSONS", "Lesson", "figure", "lesson_file_names", "run_lessons"]


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


LessonFn = Callable[[OutputDir, bool], Lesson]


def _registry() -> dict[str, tuple[str, tuple[str, ...], LessonFn]]:
    # the lessons import MuJoCo, Matplotlib and the gap diagnosis: loaded when a lesson runs
    from sim.lessons import calibration, errors_along_path, population

    return {
        "tilt": (errors_along_path.TILT_CONCEPT, errors_along_path.TILT_FILES,
                 errors_along_path.tilt_lesson),
        "links": (errors_along_path.LINKS_CONCEPT, errors_along_path.LINKS_FILES,
                  errors_along_path.links_lesson),
        "stack": (population.CONCEPT, population.FILES, population.stack_lesson),
        "backlash": (calibration.CONCEPT, calibration.FILES, calibration.backlash_lesson),
    }


#: Lesson names, in teaching order.
LESSONS: tuple[str, ...] = ("tilt", "links", "stack", "backlash")


def _check(names: Sequence[str] | None) -> list[str]:
    chosen = list(LESSONS if names is None else names)
    bad = [n for n in chosen if n not in LESSONS]
    if bad or not chosen:
        raise InputError(f"names: unknown lesson(s) {bad}; expected some of {LESSONS}")
    return chosen


def lesson_file_names(names: Sequence[str] | None = None) -> list[str]:
    """The files the lessons ``names`` (default all) write, to check before running."""
    reg = _registry()
    return [f for n in _check(names) for f in reg[n][1]]


def run_lessons(out: OutputDir, names: Sequence[str] | None = None, *,
                small: bool = False) -> list[Lesson]:
    """Run the lessons ``names`` (default all) into the entered folder ``out``;
    ``small``: reduced size (what the test suite runs: fewer frames, robots and poses)."""
    reg = _registry()
    return [reg[n][2](out, small) for n in _check(names)]


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
