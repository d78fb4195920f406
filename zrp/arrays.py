"""Array type aliases, the one home for them: NumPy arrays of one dtype, any shape.

Shapes are given in each function's docstring (pytransform3d style), e.g. ``(n, 3)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["F64", "I64", "U8"]

#: float64 array of any shape.
F64 = NDArray[np.float64]
#: int64 array of any shape.
I64 = NDArray[np.int64]
#: uint8 array of any shape (images).
U8 = NDArray[np.uint8]
