"""Numeric limits of the toolkit's inputs, in a light module (no NumPy): the command line's
option types state them in ``zrp --help`` without loading the numerical code.

Re-exported where they apply: :data:`MAX_SEED` by :mod:`zrp.arguments`, :data:`MAX_LENGTH` by
:mod:`zrp.model.manipulator`, the excitation's bounds by :mod:`zrp.gap.dynamics.fourier`,
:mod:`~zrp.gap.dynamics.excitation` and :mod:`~zrp.gap.dynamics.command`.
"""

from __future__ import annotations

__all__ = ["MAX_COMMAND_SAMPLES", "MAX_DESIGN_CANDIDATES", "MAX_DESIGN_ITERATIONS",
           "MAX_HARMONICS", "MAX_LENGTH", "MAX_SEED"]

#: Largest seed accepted (NumPy's SeedSequence takes any non-negative integer; 2**63 - 1 keeps
#: it an int64 everywhere a seed is recorded).
MAX_SEED = 2**63 - 1
#: Largest magnitude of a model vector component, in the model's length unit (1e9 mm is
#: 1000 km): beyond it sums and products of lengths lose all precision or overflow.
MAX_LENGTH = 1e9
#: The exciting command of the dynamic gap (:mod:`zrp.gap.dynamics.command`): largest number
#: of harmonics of its Fourier series, of random starts and of hill-climbing steps of its
#: design, and of samples of one command (period x rate; about 50 MB of arrays a 7-joint
#: arm). They bound the time and memory of ``zrp excite`` before anything is allocated.
MAX_HARMONICS = 50
MAX_DESIGN_CANDIDATES = 1000
MAX_DESIGN_ITERATIONS = 10_000
MAX_COMMAND_SAMPLES = 200_000
