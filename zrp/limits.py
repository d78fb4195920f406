"""Numeric limits of the toolkit's inputs, in a light module (no NumPy): the command line's
option types state them in ``zrp --help`` without loading the numerical code.

Re-exported where they apply: :data:`MAX_SEED` by :mod:`zrp.arguments`, :data:`MAX_LENGTH` by
:mod:`zrp.model.manipulator`.
"""

from __future__ import annotations

__all__ = ["MAX_LENGTH", "MAX_SEED"]

#: Largest seed accepted (NumPy's SeedSequence takes any non-negative integer; 2**63 - 1 keeps
#: it an int64 everywhere a seed is recorded).
MAX_SEED = 2**63 - 1
#: Largest magnitude of a model vector component, in the model's length unit (1e9 mm is
#: 1000 km): beyond it sums and products of lengths lose all precision or overflow.
MAX_LENGTH = 1e9
