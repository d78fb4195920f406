"""Lesson 3: how a tolerance stack becomes a distribution (Monte Carlo of the PUMA circle)."""

from __future__ import annotations

import numpy as np

from sim.lessons.lesson import Lesson, figure
from zrp.manufacturing.population import monte_carlo
from zrp.manufacturing.tolerance import Tolerances
from zrp.output import OutputDir
from zrp.paper.scenario import circle_joint_path, puma_circle

__all__ = ["CONCEPT", "FILES", "stack_lesson"]

CONCEPT = ("Every robot built within the same tolerances is a different robot: drawing each "
           "link component within +-0.01 mm and each axis tilt within +-0.05 mrad gives a "
           "distribution of the maximum deviation (a median and a P99), not one number.")
FILES = ("lesson3_tolerance_stack.png",)
LENGTH_TOL_MM = 0.01
ANGLE_TOL_RAD = 5e-5


def stack_lesson(out: OutputDir, small: bool = False) -> Lesson:
    """Uniform tolerances on the PUMA, N robots along the circle (``small``: 2,000 robots
    on 60 points; otherwise 50,000 on 360), histogram of max delta_p with P50, P99."""
    model = puma_circle().model
    path = circle_joint_path(model, steps=60 if small else 360)
    tol = Tolerances.build(model, length=LENGTH_TOL_MM, angle_rad=ANGLE_TOL_RAD)
    n = 2000 if small else 50000
    mc = monte_carlo(model, path.q, tol, n, rng=np.random.default_rng(0), first_order=True)
    p50, p99 = (float(np.percentile(mc.max_delta_p, v)) for v in (50, 99))
    with figure(out, FILES[0]) as (_, ax):
        ax.hist(mc.max_delta_p, bins=60, color="tab:blue", alpha=0.75,
                label=f"{n} robots (nonlinear)")
        if mc.first_order_delta_p is not None:
            ax.hist(mc.first_order_delta_p, bins=60, histtype="step", color="k", lw=1.2,
                    label="first-order model, same draws")
        for v, lab, ls in ((p50, "median", "--"), (p99, "P99", ":")):
            ax.axvline(v, color="tab:red", ls=ls, label=f"{lab} {v:.3f} mm")
        ax.set_xlabel("max delta_p along the circle (mm)")
        ax.set_ylabel("robots")
        ax.set_title(f"tolerances: links +-{LENGTH_TOL_MM} mm, axes +-{ANGLE_TOL_RAD * 1e3:g} "
                     "mrad (uniform)")
        ax.legend(fontsize=8)
    return Lesson("stack", CONCEPT, (out.root / FILES[0],), {
        FILES[0]: f"The maximum deviation of {n} PUMAs built within the same tolerances: a "
                  f"distribution with median {p50:.3f} mm and P99 {p99:.3f} mm, the first-order "
                  "model on top of it."},
        {"robots": n, "p50_mm": p50, "p99_mm": p99, "max_mm": float(mc.max_delta_p.max())})
