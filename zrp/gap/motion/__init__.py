"""The sim-to-real gap along trajectories: time-stamped tracker streams, effects that live in
motion (sync delay, servo lag, friction at reversals, compliance under inertial load), split
by time segments, on the static engine's fitting (README.md in zrp/gap)."""

from zrp.gap.motion.data import Trajectory as Trajectory
from zrp.gap.motion.effects import MOTION_EFFECTS as MOTION_EFFECTS
from zrp.gap.motion.pipeline import diagnose_motion as diagnose_motion
from zrp.gap.motion.results import MotionDiagnosis as MotionDiagnosis
from zrp.gap.motion.results import MotionEstimate as MotionEstimate
from zrp.gap.motion.results import MotionStep as MotionStep
from zrp.gap.motion.trajcsv import load_trajectory as load_trajectory
from zrp.gap.motion.trajcsv import write_trajectory as write_trajectory
