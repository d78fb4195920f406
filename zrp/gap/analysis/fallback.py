"""The final model is never worse than a standard complete geometric calibration.

The greedy search (:mod:`zrp.gap.search.greedy`) adds one effect at a time and stops after
``max_steps`` or when no effect passes its tests, so on a robot with many geometric errors (a
7-axis arm, an optical tracker's larger noise, several payloads) the model it ends with can
leave more on the withheld poses than the complete geometric calibration fitted beside it
(:mod:`zrp.gap.analysis.baseline`). That module also fits a third model, the complete geometric
calibration plus the non-geometric effects of the search's model (when it has any): on few
poses with many geometric errors the search may stop before it has added them all, while the
non-geometric effect it did find is real, and then that third model beats both others (an
xArm7 with 20 poses and a shoulder compliance: 0.0385 mm withheld against the search's 0.136
mm). The rule here makes "the final withheld error is at or below the geometric calibration's"
hold by construction, and lets the third model win only clearly:

    two   = search's model        if RMS_w(search) <= RMS_w(geometric calibration)
            geometric calibration otherwise                                    (F1)
    final = geometric + non-geometric   if it exists, RMS_w(it) < RMS_w(two) and the two
                                        are not "equally good"                 (F2)
            two otherwise

Simpler first: the candidates are ordered by how many parameters they add to the
registration. The third model nests the geometric calibration (the same complete base set
plus the non-geometric parameters) and holds the search's non-geometric effects with every
geometric parameter rather than the few the search chose, so it is the most complex of the
three; when it is only equally good the simpler model that (F1) chose is kept, and (F1) itself
is unchanged (its choice was already the smaller withheld RMS, ties to the search's model).

This is the one place where the withheld poses choose something (one of two or three models,
decided once, never fed back into a fit): the reported withheld error of the final model is
then the smallest of k (k = 2 or 3), a slightly optimistic figure, which the report states
whenever the final model is not the search's. Whether two models differ by more than chance
is judged by a paired comparison over the withheld poses: the per-pose difference of the
summed squared errors, d_g, and its mean over its standard error, z = mean(d) / (sd(d) /
sqrt(G)) (F3). Two are "equally good" only when both |z| < 2 and the ratio of their withheld
RMS values is within :data:`EQUAL_RATIO` (the geometric calibration can win by a hair on
noise-only data or a single geometric effect - 4 of the 80 single-effect benchmark scenarios,
each by at most 0.5 % - and the report then says that the difference is within the noise). A
z alone does not measure size: a few poses with large errors inflate sd(d), so a five-fold
worse model can have |z| ~ 1; such a pair is reported as a clear difference, with the ratio.
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

__all__ = ["COMBINED", "EQUAL_RATIO", "SOURCES", "FinalChoice", "choose_final", "clearly_better",
           "final_source", "paired_z"]

#: the third candidate: the complete geometric calibration plus the search's non-geometric effects.
COMBINED = "geometric_plus_non_geometric"
#: where the final model comes from (simpler first, see the module docstring).
SOURCES = ("search", "geometric_baseline", COMBINED)
#: Largest ratio of two withheld RMS values still called "equally good" (with |z| < 2).
EQUAL_RATIO = 1.1
_K_WORDS = {2: "smaller of two", 3: "smallest of three"}


def _equally_good(z: float, worse_rms: float, better_rms: float) -> bool:
    """|z| < 2 and the two withheld RMS values within :data:`EQUAL_RATIO` of each other."""
    r = _ratio(worse_rms, better_rms)
    return abs(z) < 2.0 and max(r, 1.0 / r if r > 0 else float("inf")) <= EQUAL_RATIO


def _ratio(a: float, b: float) -> float:
    """a / b (inf when b is 0 and a is not; 1 when both are 0)."""
    if b > 0:
        return a / b
    return 1.0 if a == 0 else float("inf")


@dataclass(frozen=True)
class FinalChoice:
    """Which model is final, and the withheld RMS values that decided it.

    Attributes:
        source: ``"search"`` (the effects found), ``"geometric_baseline"`` (the complete
            geometric calibration, because the search's model was worse on withheld poses) or
            ``"geometric_plus_non_geometric"`` (that calibration plus the search's
            non-geometric effects, because it clearly beats both: (F2) of the module).
        search_rms: withheld RMS of the search's model (length unit).
        baseline_rms: withheld RMS of the complete geometric calibration (length unit).
        z: paired z of the withheld squared-error difference, search minus baseline (see the
            module docstring; positive: the baseline is better).
        search_fit: the search's model (in-process only; the final one when source is search).
        combined_rms: withheld RMS of the geometric calibration plus the search's
            non-geometric effects (length unit), or None when the search's model has none.
        combined_z: paired z, the better of the first two minus the combination (positive:
            the combination is better; 0 without it).
        non_geometric: the non-geometric effects of that combination (empty without it).
    """

    source: str
    search_rms: float
    baseline_rms: float
    z: float = 0.0
    search_fit: FitResult | None = field(default=None, compare=False, repr=False)
    combined_rms: float | None = None
    combined_z: float = 0.0
    non_geometric: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        if self.source not in SOURCES:
            raise InputError(f"FinalChoice.source: expected one of {SOURCES}, got "
                             f"{self.source!r}")
        rms = (self.search_rms, self.baseline_rms,
               0.0 if self.combined_rms is None else self.combined_rms)
        if not all(v >= 0 for v in rms):
            raise InputError(f"FinalChoice: withheld RMS values must be >= 0, got {rms!r}")
        if self.source == COMBINED and self.combined_rms is None:
            raise InputError("FinalChoice.source: geometric_plus_non_geometric needs "
                             "combined_rms")

    @property
    def fell_back(self) -> bool:
        """True when the final model is the geometric calibration alone (not the search's
        model, nor the combination)."""
        return self.source == "geometric_baseline"

    @property
    def n_candidates(self) -> int:
        """How many models the withheld poses chose among (2, or 3 with the combination)."""
        return 2 if self.combined_rms is None else 3

    @property
    def final_rms(self) -> float:
        """Withheld RMS of the final model (the smallest of :attr:`n_candidates`)."""
        return {"search": self.search_rms, "geometric_baseline": self.baseline_rms}.get(
            self.source, self.combined_rms or 0.0)

    @property
    def ratio(self) -> float:
        """Search over baseline withheld RMS (inf when the baseline's is 0 and the search's
        is not; 1 when both are 0)."""
        return _ratio(self.search_rms, self.baseline_rms)

    @property
    def within_noise(self) -> bool:
        """The search's model and the geometric calibration are equally good on the withheld
        poses: |z| < 2 and their withheld RMS values within :data:`EQUAL_RATIO` of each other."""
        return _equally_good(self.z, self.search_rms, self.baseline_rms)

    @property
    def combined_ratio(self) -> float | None:
        """The better of the first two over the combination's withheld RMS (> 1: the
        combination is better), or None without it."""
        if self.combined_rms is None:
            return None
        return _ratio(min(self.search_rms, self.baseline_rms), self.combined_rms)

    @property
    def combined_within_noise(self) -> bool | None:
        """The combination and the better of the first two are equally good, or None."""
        if self.combined_rms is None:
            return None
        return _equally_good(self.combined_z, min(self.search_rms, self.baseline_rms),
                             self.combined_rms)

    def _optimistic(self) -> str:
        return (f"(chosen on the withheld poses: its withheld error is the "
                f"{_K_WORDS[self.n_candidates]}, slightly optimistic)")

    def _combined_words(self, unit: str) -> str:
        return (f"the complete geometric calibration plus the search's non-geometric effects "
                f"({', '.join(self.non_geometric)}; {self.combined_rms:.4g} {unit})")

    def note(self, unit: str) -> str:
        """One or two sentences for the report ("" when the search's model is final and no
        combination came close to it)."""
        if self.source == COMBINED:
            return self._combined_note(unit)
        kept = ""
        if self.combined_rms is not None and self.combined_rms < min(self.search_rms,
                                                                     self.baseline_rms):
            kept = (f" {self._combined_words(unit)[0].upper()}{self._combined_words(unit)[1:]} "
                    f"is within the noise of it (paired z = {self.combined_z:.2g}, "
                    f"{self.combined_ratio:.3g}x): equally good, so the simpler model is kept.")
        if not self.fell_back:
            return kept.strip()
        how = ("a difference within the noise (paired z = "
               f"{self.z:.2g}): the two are equally good" if self.within_noise else
               f"a clear difference: the search's model is {self.ratio:.3g}x worse (paired z = "
               f"{self.z:.2g}); the search went wrong on these data (an effect that fits the "
               "fitting poses but not the withheld ones, or a step that stopped too early)")
        return (f"The search's model ({self.search_rms:.4g} {unit} withheld RMS) does not beat "
                f"a complete geometric calibration ({self.baseline_rms:.4g} {unit}) on the "
                f"withheld poses, {how}; so the final model is that geometric calibration "
                f"{self._optimistic()}." + kept)

    def _combined_note(self, unit: str) -> str:
        two = ("the search's model" if self.search_rms <= self.baseline_rms else
               "the complete geometric calibration")
        return (f"Neither the search's model ({self.search_rms:.4g} {unit} withheld RMS) nor a "
                f"complete geometric calibration ({self.baseline_rms:.4g} {unit}) is as good on "
                f"the withheld poses as {self._combined_words(unit)}: a clear difference, "
                f"{two} is {self.combined_ratio:.3g}x worse (paired z = {self.combined_z:.2g}); "
                "the search stopped before it had added every geometric error (or took a "
                "step these data do not support), and the non-geometric effects it found hold "
                "on top of a complete geometric calibration; so the final model is that "
                f"combination {self._optimistic()}.")

    def to_dict(self) -> dict[str, Any]:
        return {**dict_from_dataclass(self, exclude=("z", "search_fit", "combined_rms",
                                                     "combined_z", "non_geometric"),
                                      rename={"search_rms": "search_withheld_rms",
                                              "baseline_rms": "baseline_withheld_rms"}),
                "fell_back": self.fell_back, "paired_z": self.z, "rms_ratio": self.ratio,
                "within_noise": self.within_noise, "n_candidates": self.n_candidates,
                "combined_withheld_rms": self.combined_rms,
                "combined_non_geometric": list(self.non_geometric),
                "combined_paired_z": self.combined_z if self.combined_rms is not None else None,
                "combined_rms_ratio": self.combined_ratio,
                "combined_within_noise": self.combined_within_noise,
                "final_withheld_rms": self.final_rms}


def _paired_z(ctx: Context, withheld: NDArray[np.int64], r_a: F64, r_b: F64) -> float:
    """Paired z (F3) of the per-pose summed squared errors, a minus b (0 when the withheld
    poses are too few or the differences all equal)."""
    rows = np.flatnonzero(np.isin(ctx.meas.pose_index, withheld))
    _, inv = np.unique(ctx.meas.pose_index[rows], return_inverse=True)
    diff = (np.sum(r_a.reshape(-1, 3) ** 2, axis=1)
            - np.sum(r_b.reshape(-1, 3) ** 2, axis=1))
    d = np.bincount(inv, weights=diff)
    if d.size < 3:
        return 0.0
    sd = float(np.std(d, ddof=1))
    return float(np.mean(d) / (sd / np.sqrt(d.size))) if sd > 0 else 0.0


def final_source(search_rms: float, baseline_rms: float, combined_rms: float | None = None,
                 combined_z: float = 0.0) -> str:
    """The rule (F1)-(F2) of the module docstring on the withheld RMS values: the source of
    the final model (``combined_z``: the better of the first two minus the combination)."""
    two = "search" if search_rms <= baseline_rms else "geometric_baseline"           # (F1)
    best = min(search_rms, baseline_rms)
    if combined_rms is None or combined_rms >= best or _equally_good(combined_z, best,
                                                                      combined_rms):
        return two
    return COMBINED                                                                  # (F2)


def _residual(ctx: Context, f: FitResult, withheld: NDArray[np.int64]) -> F64:
    return Problem(ctx, f.specs, withheld, f.base_rotation).residual(f.theta)


def choose_final(ctx: Context, search_fit: FitResult, baseline: GeometricBaseline,
                 withheld: NDArray[np.int64]) -> tuple[FitResult, F64,
                                                        FinalChoice]:
    """The final model (see the module docstring: (F1), (F2)): its fit, its withheld residual
    (3 Rw,) and the choice. The baseline must carry its fit (and its combination's fit when it
    has a combination)."""
    if baseline.fit is None:
        raise InputError("choose_final: the geometric baseline carries no fit")
    if baseline.combined is not None and baseline.combined_fit is None:
        raise InputError("choose_final: the geometric baseline carries no fit of its "
                         "combination with the non-geometric effects")
    r_search = _residual(ctx, search_fit, withheld)
    s_rms = Metrics.of(r_search).rms
    b_rms = baseline.model_withheld.rms  # the physically held one: a model may be final
    b = baseline.fit
    r_base = _residual(ctx, b, withheld)
    z = _paired_z(ctx, withheld, r_search, r_base)
    two, r_two = (search_fit, r_search) if s_rms <= b_rms else (b, r_base)
    c = baseline.combined_fit
    if baseline.combined is None or c is None:
        return two, r_two, FinalChoice(final_source(s_rms, b_rms), s_rms, b_rms, z, search_fit)
    r_comb = _residual(ctx, c, withheld)
    c_rms = Metrics.of(r_comb).rms
    cz = _paired_z(ctx, withheld, r_two, r_comb)
    choice = FinalChoice(final_source(s_rms, b_rms, c_rms, cz), s_rms, b_rms, z, search_fit,
                         c_rms, cz, baseline.non_geometric)
    return (c, r_comb, choice) if choice.source == COMBINED else (two, r_two, choice)


def clearly_better(z: float, worse_rms: float, better_rms: float) -> bool:
    """``better_rms`` is lower and not "equally good" (the rule of (F2)): the test a learned
    residual term must pass too (:mod:`zrp.gap.analysis.residual`)."""
    return better_rms < worse_rms and not _equally_good(z, worse_rms, better_rms)


#: the paired z of (F3), public for the residual model's test.
paired_z = _paired_z
