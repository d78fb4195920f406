"""A gallery of runnable lessons, one concept each, writing their figures and videos into
``renders/lessons/`` (``zrp lessons``; the test suite runs them all at reduced size).

| lesson | concept |
|---|---|
| ``tilt`` | what a joint-axis tilt does along a circle: theta = 2 |sin(q_k / 2)| alpha |
| ``links`` | why link errors leave the orientation alone: a pure translation by xi ||b_k|| |
| ``stack`` | how a tolerance stack becomes a distribution of the maximum deviation |
| ``backlash`` | how a calibration finds a hidden backlash in a simulated "real" robot |

Each lesson is a function ``lesson(out, small=False) -> Lesson`` that writes into an entered
:class:`zrp.output.OutputDir` and returns its files, one sentence per file, and the numbers
it measured (:mod:`.lesson`: :class:`Lesson` and the figure helper). The registry
(:mod:`.registry`) imports the lessons; :func:`run_lessons` runs several into one folder.
"""

from sim.lessons.lesson import Lesson as Lesson
from sim.lessons.registry import LESSONS as LESSONS
from sim.lessons.registry import lesson_file_names as lesson_file_names
from sim.lessons.registry import run_lessons as run_lessons

__all__ = ["LESSONS", "Lesson", "lesson_file_names", "run_lessons"]
