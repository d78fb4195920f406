"""The sim-to-real gap along trajectories: time-stamped tracker streams, effects that live in
motion (sync delay, servo lag, friction at reversals, compliance under inertial load), split
by time segments, on the static engine's fitting (README.md in zrp/gap)."""

from typing import TYPE_CHECKING

from zrp.lazy import lazy_names

#: public name -> (module, name there): imported on first use (zrp/lazy.py)
_LAZY = {
    "Trajectory": "zrp.gap.motion.data",
    "MOTION_EFFECTS": "zrp.gap.motion.effects",
    "diagnose_motion": "zrp.gap.motion.pipeline",
    "MotionDiagnosis": "zrp.gap.motion.results",
    "MotionEstimate": "zrp.gap.motion.results",
    "MotionStep": "zrp.gap.motion.results",
    "load_trajectory": "zrp.gap.motion.trajcsv",
    "write_trajectory": "zrp.gap.motion.trajcsv",
}
__getattr__, __dir__ = lazy_names(__name__, _LAZY)

if TYPE_CHECKING:  # type checkers and IDEs see the same names, imported eagerly
    from zrp.gap.motion.data import Trajectory as Trajectory
    from zrp.gap.motion.effects import MOTION_EFFECTS as MOTION_EFFECTS
    from zrp.gap.motion.pipeline import diagnose_motion as diagnose_motion
    from zrp.gap.motion.results import MotionDiagnosis as MotionDiagnosis
    from zrp.gap.motion.results import MotionEstimate as MotionEstimate
    from zrp.gap.motion.results import MotionStep as MotionStep
    from zrp.gap.motion.trajcsv import load_trajectory as load_trajectory
    from zrp.gap.motion.trajcsv import write_trajectory as write_trajectory
