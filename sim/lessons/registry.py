"""The lesson registry and the runner (see the package docstring). The registry imports the
lessons; each lesson imports only :mod:`sim.lessons.lesson`."""

from __future__ import annotations

from collections.abc import Sequence

from sim.lessons.lesson import Lesson, LessonFn
from zrp.errors import InputError
from zrp.output import OutputDir

__all__ = ["LESSONS", "lesson_file_names", "run_lessons"]


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
