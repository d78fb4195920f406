"""The dynamic gap: where a model's joint torques miss what the real arm needs, which
unmodelled effect causes it, and how far the withheld torque error shrinks with it in the
model ([README](README.md)). NumPy/SciPy only: the arm model is behind
:class:`~zrp.gap.dynamics.arm.DynamicArm` (MuJoCo's implementation: :mod:`mjcf.arm`).

Modules: ``data`` (the torque log; its reader's parts: ``columns`` the controllers' column
names, ``logfile`` the text, ``timebase`` the clock and segments, ``logcheck`` the physical
domain), ``states`` (zero-phase derivatives, on the real time axis by ``localpoly``), ``arm`` (the
interface), ``inertia`` (link inertial parameters), ``effects``, ``fit``, ``cvgram``,
``select``, ``regimes``, ``logchol``, ``physical``, ``diagnosis``, ``fourier``,
``excitation``, ``report``.
"""

from zrp.gap.dynamics.arm import DynamicArm
from zrp.gap.dynamics.data import Conditioning, TorqueLog, load_torque_log, write_torque_log
from zrp.gap.dynamics.states import States, derive_states

__all__ = ["Conditioning", "DynamicArm", "States", "TorqueLog", "derive_states", "load_torque_log",
           "write_torque_log"]
