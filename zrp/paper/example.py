"""The paper's numerical example (Tables 2-3, Figures 2-7) and its comparison with the
published values.

:func:`run_paper_example` solves the nominal inverse kinematics of the 125 mm circle
(:func:`zrp.paper.scenario.circle_joint_path`, the setup of :mod:`zrp.paper.scenario`), runs
the one-at-a-time study of LE2, LE3, LE4, LE7, JE1-JE6 at 0, +-0.02, +-0.05, +-0.07, +-0.1 %,
compares every cell with the published Tables 2 and 3 (:mod:`zrp.paper.published`, compared in
:mod:`zrp.paper.comparison`) and checks the paper's claims (:mod:`zrp.paper.claims`).
:func:`zrp.paper.report.write_paper_outputs` writes the tables (CSV and Markdown), Figures 2-7
(PNG, :mod:`zrp.paper.figures`), the comparison report and a JSON summary.

What the comparison can and cannot show:

* LE columns of Table 2 do not depend on the trajectory: a link error at fixed joint values
  translates the end effector by exactly xi ||b_k|| (sign(0) = 0). LE2, LE4, LE7 reproduce to
  the printed digits; LE3 does not (the published values imply ||b_3|| ~ 444.4 mm, i.e.
  17.5 in, against Table 1's 431.8 mm = 17 in).
* JE columns depend on the unpublished circle placement and start configuration. Table 3
  even constrains them: the error rotation of JE_k depends only on the joint's own angle,
  through max_t |sin(q_k / 2)|, so the published values reveal how far each joint turned in
  the paper's run (:func:`implied_joint_angles`). Cells are flagged, not tuned.
* Two cells look like typos: Table 2 at 0.1 %, JE1 = 7.88E+0 (trend: 7.88E-1) and
  JE2 = 1.33E-1 (trend: 1.33E+0).
* The 0 % rows are not deviations: 1.07E-8 mm is the paper's inverse-kinematics error and
  5.96E-8 = 2^-24 the rounding floor of eq (15) evaluated literally
  (:mod:`zrp.manufacturing.deviation`).
"""


from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from zrp.errors import InputError
from zrp.manufacturing.perturb import PAPER_SIGN_ZERO
from zrp.manufacturing.study import (
    PAPER_PARAMETERS,
    PAPER_XI,
    JointPath,
    StudyResult,
    one_at_a_time,
)
from zrp.model.files import load_model
from zrp.model.manipulator import Manipulator
from zrp.paper.choices import CIRCLES
from zrp.paper.claims import check_claims
from zrp.paper.comparison import Cell, compare_with_published, kind_columns, table_value
from zrp.paper.placement import RECOVERED, placement_path
from zrp.paper.published import PUBLISHED_ROWS, PUBLISHED_TABLE2
from zrp.paper.scenario import circle_joint_path, is_paper_model

__all__ = ["CIRCLES", "PaperExample", "default_parameters", "run_paper_example"]


def default_parameters(model: Manipulator) -> tuple[str, ...]:
    """The paper's ten parameters for the Table 1 PUMA; otherwise every nonzero link vector
    LE{k} and every joint axis JE{k}."""
    if is_paper_model(model):
        return PAPER_PARAMETERS
    le = [f"LE{k}" for k in range(1, model.n + 2)
          if np.linalg.norm(model.bodies[k - 1]) > 0]
    return (*le, *(f"JE{k}" for k in range(1, model.n + 1)))


@dataclass(frozen=True, eq=False)
class PaperExample:
    """Everything :func:`run_paper_example` computes.

    Attributes:
        model: the Table 1 PUMA (or the given model).
        path: the nominal joint trajectory.
        study: the one-at-a-time study with the default conventions.
        alt_links_plus1: LE study with sign(0) = +1 for links (shows why 0 is the default).
        alt_axes_zero: JE study with sign(0) = 0 for axes (shows why +1 is the default).
        cells: the comparison (:func:`compare_with_published`).
        checks: the paper's claims checked with numbers.
        timings_s: compute time per stage (s).
        circle: "default" (:func:`zrp.paper.scenario.puma_circle`), "recovered"
            (:data:`zrp.paper.placement.RECOVERED`) or "custom" (a given path / other model).
        other_circle: for the paper's PUMA on one of the two named circles, the study on the
            other one (comparison.md shows both; Figures 5-7 are drawn on it too), else None.
    """

    model: Manipulator
    path: JointPath
    study: StudyResult
    alt_links_plus1: StudyResult
    alt_axes_zero: StudyResult
    cells: list[Cell]
    checks: dict[str, Any]
    timings_s: dict[str, float] = field(default_factory=dict)
    circle: str = "custom"
    other_circle: StudyResult | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.study, StudyResult) or not isinstance(self.path, JointPath):
            raise InputError("PaperExample: study must be a StudyResult and path a JointPath")




def _circle_path(name: str, steps: int) -> JointPath:
    """The joint path of a named circle on the Table 1 PUMA."""
    if name == "recovered":
        return placement_path(RECOVERED, steps)
    return circle_joint_path(load_model("puma"), steps=steps)


def run_paper_example(model: Manipulator | None = None, path: JointPath | None = None, *,
                      steps: int = 360, circle: str | None = None) -> PaperExample:
    """The whole numerical example: IK, study, alternative conventions, comparison, checks.

    Args:
        model: default the Table 1 PUMA.
        path: default the 125 mm circle of :func:`zrp.paper.scenario.circle_joint_path` with
            ``steps`` integration steps (T = steps + 1 samples); required for models other
            than the paper's PUMA, which have no default start configuration.
        circle: "default" or "recovered" (:data:`zrp.paper.placement.RECOVERED`, the circle
            recovered from the published tables), paper's PUMA only, without ``path``;
            default "default" when neither ``path`` nor another model is given.
    """
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    model = load_model("puma") if model is None else model
    if circle is not None:
        if circle not in CIRCLES:
            raise InputError(f"circle: expected one of {CIRCLES}, got {circle!r}")
        if path is not None or not is_paper_model(model):
            raise InputError("circle: a named circle belongs to the paper's Table 1 PUMA and "
                             "replaces path; give one or the other")
    elif path is None and is_paper_model(model):
        circle = "default"
    if path is None:
        path = (_circle_path(circle, steps) if circle is not None
                else circle_joint_path(model, steps=steps))
    timings["inverse_kinematics"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    published = is_paper_model(model)
    study = one_at_a_time(model, path, default_parameters(model), PAPER_XI)
    timings["study"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    le, je = kind_columns(study, "LE"), kind_columns(study, "JE")
    alt_l = one_at_a_time(model, path, le, PUBLISHED_ROWS, sign_zero_links=1,
                          sign_zero_axes=PAPER_SIGN_ZERO["axes"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        alt_a = one_at_a_time(model, path, je, PUBLISHED_ROWS,
                              sign_zero_links=PAPER_SIGN_ZERO["links"], sign_zero_axes=0)
    timings["alternative_conventions"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    cells = (compare_with_published(study, model, recovered=circle == "recovered")
             if published else [])
    other = None
    if circle is not None:
        name = "default" if circle == "recovered" else "recovered"
        other = one_at_a_time(model, _circle_path(name, steps), default_parameters(model),
                              PAPER_XI)
    checks = check_claims(study, path, published)
    first = le[0]
    checks["published_values_apply"] = published
    checks["sign_convention_evidence"] = {
        "link": first,
        "link_0.02pct_sign0_links_0": table_value(study, "delta_p", first, 0.02),
        "link_0.02pct_sign0_links_plus1": table_value(alt_l, "delta_p", first, 0.02),
        "link_0.02pct_published": PUBLISHED_TABLE2[first][0] if published else None,
        "JE_max_delta_p_sign0_axes_0": float(alt_a.max_delta_p.max()),
        "JE_max_delta_r_sign0_axes_0": float(alt_a.max_delta_r.max()),
    }
    timings["comparison"] = time.perf_counter() - t0
    timings["total_compute"] = sum(timings.values())
    return PaperExample(model, path, study, alt_l, alt_a, cells, checks, timings,
                        circle or "custom", other)
