"""The final model is never worse than a standard complete geometric calibration.

The greedy search (:mod:`zrp.gap.search.greedy`) adds one effect at a time and stops after
``max_steps`` or when no effect passes its tests, so on a robot with many geometric errors (a
7-axis arm, an optical tracker's larger noise, several payloads) the model it ends with can
leave more on the withheld poses than the complete geometric calibration fitted beside it
(:mod:`zrp.gap.analysis.baseline`). The rule here makes "the final withheld error is at or below the
geometric calibration's" hold by construction:

    final = search's model   if RMS_w(search) <= RMS_w(geometric calibration)
            geometric calibration otherwise (and the report says so)

This is the one place where the withheld poses choose something (one of two models, decided
once, never fed back into a fit): the reported withheld error of the final model is then the
smaller of two, a slightly optimistic figure, which the report states whenever the fallback is
taken. Whether the two differ by more than chance is judged by a paired comparison over the
withheld poses: the per-pose difference of the summed squared errors, d_g, and its mean over
its standard error, z = mean(d) / (sd(d) / sqrt(G)). The two are "equally good" only when
both |z| < 2 and the ratio of the two withheld RMS values is within :data:`EQUAL_RATIO` (the
geometric calibration can win by a hair on noise-only data or a single geometric effect - 4 of
the 80 single-effect benchmark scenarios, each by at most 0.5 % - and the report then says that
the difference is within the noise). A z alone does not measure size: a few poses with large
errors inflate sd(d), so a five-fold worse model can have |z| ~ 1; such a pair is reported as
a clear difference, with the ratio.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.analysis.baseline import GeometricBaseline
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.fit.metrics import Metrics
from zrp.gap.model.context import Context
from zrp.gap.model.problem import Problem
from zrp.jsonio import dict_from_dataclass

__all__ = ["SOURCES", "FinalChoice", "choose_final"]

#: where the final model comes from.
SOURCES = ("search", "geometric_baseline")
#: Largest ratio of two withheld RMS values still called "equally good" (with |z| < 2).
EQUAL_RATIO = 1.1


@dataclass(frozen=True)
class FinalChoice:
    """Which model is final, and the two withheld RMS values that decided it.

    Attributes:
        source: ``"search"`` (the effects found) or ``"geometric_baseline"`` (the complete
            geometric calibration, because the search's model was worse on withheld poses).
        search_rms: withheld RMS of the search's model (length unit).
        baseline_rms: withheld RMS of the complete geometric calibration (length unit).
        z: paired z of the withheld squared-error difference, search minus baseline (see the
            module docstring; positive: the baseline is better).
        search_fit: the search's model (in-process only; the final one unless it fell back).
    """

    source: str
    search_rms: float
    baseline_rms: float
    z: float = 0.0
    search_fit: FitResult | None = field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        if self.source not in SOURCES:
            raise InputError(f"FinalChoice.source: expected one of {SOURCES}, got "
                             f"{self.source!r}")
        if not (self.search_rms >= 0 and self.baseline_rms >= 0):
            raise InputError(f"FinalChoice: withheld RMS values must be >= 0, got "
                             f"{self.search_rms!r}, {self.baseline_rms!r}")

    @property
    def fell_back(self) -> bool:
        """True when the final model is the geometric calibration instead of the search's."""
        return self.source == "geometric_baseline"

    @property
    def ratio(self) -> float:
        """Search over baseline withheld RMS (inf when the baseline's is 0 and the search's
        is not; 1 when both are 0)."""
        if self.baseline_rms > 0:
            return self.search_rms / self.baseline_rms
        return 1.0 if self.search_rms == 0 else float("inf")

    @property
    def within_noise(self) -> bool:
        """The two models are equally good on the withheld poses: |z| < 2 and their withheld
        RMS values within :data:`EQUAL_RATIO` of each other."""
        r = self.ratio
        return abs(self.z) < 2.0 and max(r, 1.0 / r if r > 0 else float("inf")) <= EQUAL_RATIO

    def note(self, unit: str) -> str:
        """One sentence for the report ("" when the search's model is final)."""
        if not self.fell_back:
            return ""
        how = ("a difference within the noise (paired z = "
               f"{self.z:.2g}): the two are equally good" if self.within_noise else
               f"a clear difference: the search's model is {self.ratio:.3g}x worse (paired z = "
               f"{self.z:.2g}); the search went wrong on these data (an effect that fits the "
               "fitting poses but not the withheld ones, or a step that stopped too early)")
        return (f"The search's model ({self.search_rms:.4g} {unit} withheld RMS) does not beat "
                f"a complete geometric calibration ({self.baseline_rms:.4g} {unit}) on the "
                f"withheld poses, {how}; so the final model is that geometric calibration "
                "(chosen on the withheld poses: its withheld error is the smaller of two, "
                "slightly optimistic).")

    def to_dict(self) -> dict[str, Any]:
        return {**dict_from_dataclass(self, exclude=("z", "search_fit"),
                                      rename={"search_rms": "search_withheld_rms",
                                              "baseline_rms": "baseline_withheld_rms"}),
                "fell_back": self.fell_back, "paired_z": self.z, "rms_ratio": self.ratio,
                "within_noise": self.within_noise}


def _paired_z(ctx: Context, withheld: NDArray[np.int64], r_search: F64,
              r_base: F64) -> float:
    """Paired z of the per-pose summed squared errors, search minus baseline (0 when the
    withheld poses are too few or the differences all equal)."""
    rows = np.flatnonzero(np.isin(ctx.meas.pose_index, withheld))
    _, inv = np.unique(ctx.meas.pose_index[rows], return_inverse=True)
    diff = (np.sum(r_search.reshape(-1, 3) ** 2, axis=1)
            - np.sum(r_base.reshape(-1, 3) ** 2, axis=1))
    d = np.bincount(inv, weights=diff)
    if d.size < 3:
        return 0.0
    sd = float(np.std(d, ddof=1))
    return float(np.mean(d) / (sd / np.sqrt(d.size))) if sd > 0 else 0.0


def choose_final(ctx: Context, search_fit: FitResult, baseline: GeometricBaseline,
                 withheld: NDArray[np.int64]) -> tuple[FitResult, F64,
                                                        FinalChoice]:
    """The final model (see the module docstring): its fit, its withheld residual (3 Rw,) and
    the choice. The baseline must carry its fit."""
    if baseline.fit is None:
        raise InputError("choose_final: the geometric baseline carries no fit")
    r_search = Problem(ctx, search_fit.specs, withheld,
                       search_fit.base_rotation).residual(search_fit.theta)
    s_rms = Metrics.of(r_search).rms
    b_rms = baseline.withheld.rms
    b = baseline.fit
    r_base = Problem(ctx, b.specs, withheld, b.base_rotation).residual(b.theta)
    z = _paired_z(ctx, withheld, r_search, r_base)
    if s_rms <= b_rms:
        return search_fit, r_search, FinalChoice("search", s_rms, b_rms, z, search_fit)
    return b, r_base, FinalChoice("geometric_baseline", s_rms, b_rms, z, search_fit)
