"""The look-alike of ``thermal_expansion``: a common scale of all links, independent of the
temperature.

The thermal model scales every body vector by 1 + kappa dT_i, dT_i = temp_i - T_ref (20 deg C
by default). Its column is dT_i sum_k R_{k-1} b_{k,0}: the column of a common scale s of all
links (sum_k R_{k-1} b_{k,0}, eq. T1 below with dT_i = 1) times a factor that is nearly
constant when the measurement spans a few kelvin far from T_ref. One parameter then absorbs
any misfit that a common scale absorbs - part of a link error, or of a joint compliance - with
nothing of the temperature in it (tests/gap/test_thermal_lookalike.py: three arms, 16-30
planned poses, a hidden link error and shoulder compliance and no thermal effect, where
``thermal_expansion`` was added and then ``compensate`` asked for a temperature).

What the temperature alone can explain is the part of kappa's column that the scale's column
does not: the drift of dT_i across the poses. So kappa is kept only when it explains what the
scale cannot, by the F test of

    current + s + kappa   against   current + s                                (T1)

at the search's alpha, the scale's column being the thermal column with 1 in place of dT_i
(``thermal`` kind, comp 1, in :mod:`zrp.gap.model.problem`). When the current model already
holds a common scale (all link vectors fitted), the test is the search's own.
"""

from __future__ import annotations

import numpy as np

from zrp.gap.fit.leastsq import FitResult, f_test, fit, identifiable_start
from zrp.gap.model.context import Context, ParamSpec

__all__ = ["SCALE", "temperature_needed"]

#: a common scale of all body vectors (unit 1), the pose-order-independent look-alike of kappa
SCALE = ParamSpec("links.scale", "1", "link_length", "thermal", 0, 1, group="links.scale")


def temperature_needed(ctx: Context, current: FitResult, thermal: FitResult,
                       fitting: np.ndarray, rb0: np.ndarray, alpha: float
                       ) -> tuple[bool, float, str]:
    """Whether ``thermal`` (``current`` + kappa) explains what a common scale of the links
    cannot (eq. T1).

    Returns:
        the answer, the p-value of the F test (NaN when the current model already holds a
        common scale) and, when the answer is no, why in words.
    """
    kappa = [p for p in thermal.specs if p.effect == "thermal_expansion"]
    keep, _, start = identifiable_start(ctx, current, [SCALE])
    if not keep or not kappa:
        return True, float("nan"), ""
    scaled = fit(ctx, [*current.specs, SCALE], fitting,
                 np.concatenate([current.theta, [0.0]]), rb0, start=start)
    k_val = [float(v) for p, v in zip(thermal.specs, thermal.theta, strict=True)
             if p.effect == "thermal_expansion"]
    both = fit(ctx, [*scaled.specs, *kappa], fitting,
               np.concatenate([scaled.theta, k_val]), rb0)
    pval = f_test(scaled, both)
    if pval < alpha:
        return True, pval, ""
    return False, pval, (f"a common scale of all links, independent of the temperature, fits "
                         f"as well (F test of kappa on top of it: p = {pval:.2g}): the "
                         "temperature's drift is not needed")
