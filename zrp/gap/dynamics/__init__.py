"""The dynamic gap's data: the joint torque log (a time series of joint positions, velocities
and measured torques) and its zero-phase derivatives. NumPy/SciPy only; the diagnosis against a
MuJoCo model lives in :mod:`sim.dynamics`."""

from zrp.gap.dynamics.data import TorqueLog, load_torque_log, write_torque_log
from zrp.gap.dynamics.states import States, derive_states

__all__ = ["States", "TorqueLog", "derive_states", "load_torque_log", "write_torque_log"]
