"""The manufacturing study's named settings: the paper's levels and parameters
(:mod:`.study`) and the tolerance distributions (:mod:`.tolerance`).

A light module (no NumPy, SciPy or numba): the command line offers these choices in its help
without importing the numerical code that uses them (``zrp --help`` stays quick).
"""

from __future__ import annotations

__all__ = ["DISTRIBUTIONS", "PAPER_PARAMETERS", "PAPER_SIGN_ZERO", "PAPER_XI"]

#: The perturbation levels of the paper's study, in percent.
PAPER_XI: tuple[float, ...] = (-0.1, -0.07, -0.05, -0.02, 0.0, 0.02, 0.05, 0.07, 0.1)
#: The perturbed parameters of the paper's study (links 5 and 6 have zero length).
PAPER_PARAMETERS: tuple[str, ...] = ("LE2", "LE3", "LE4", "LE7", "JE1", "JE2", "JE3", "JE4",
                                     "JE5", "JE6")
#: sign(0) implied by the published tables: links 0, axes +1 (see :mod:`.perturb`).
PAPER_SIGN_ZERO: dict[str, int] = {"links": 0, "axes": 1}
#: Parameter distributions of a tolerance: "uniform" (half-width) or "normal" (3 sigma).
DISTRIBUTIONS = ("uniform", "normal")
