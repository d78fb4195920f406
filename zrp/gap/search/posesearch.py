"""Effects that the orientations reveal: a forward search on the full-pose problem.

The diagnosis's stepwise search (:mod:`zrp.gap.search.greedy`) sees positions only, so an effect
visible mainly in orientation (e.g. the tilt of the last axis when the reflector sits close
to the wrist centre) is never added. After the full-pose refit of the final model
(:mod:`zrp.gap.search.posefit`), this search tries every (effect, joint) group of the candidate
effects that turns the hand (joint corrections ``dq`` and axis tilts: the only kinds with
orientation columns, eq. O2 of :mod:`zrp.gap.fit.fullpose`) by a score (Lagrange multiplier)
test at the current full-pose solution, on the fitting poses only:

    r, J: weighted residual (positions / sigma_p, orientations / sigma_o) and Jacobian,
    C: the group's k columns, C_perp = (I - Q Q^T) C with Q an orthonormal basis of J,
    Delta = r^T C_perp (C_perp^T C_perp)^+ C_perp^T r   (the drop of chi^2 to first order),
    F = (Delta / k) / ((chi^2 - Delta) / (N - p - k)),  p-value from F(k, N - p - k).  (S1)

The best group (smallest p-value) is added when its p-value is below alpha / m (m groups
tried: Bonferroni) and, refitted, it lowers the withheld orientation RMS by at least
``min_gain`` without raising the withheld position RMS by more than ``min_gain``. A group
whose columns lie within the current model's (|C_perp| < 1e-6 |C|, e.g. a joint-1 tilt and
the base rotation) is aliased and not tried.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.gap.fit.fullpose import FullPoseFit, orientation_residual
from zrp.gap.model.context import Context, ParamSpec
from zrp.gap.model.problem import Problem
from zrp.jsonio import dict_from_dataclass

__all__ = ["OrientationStep", "forward_search", "orientation_groups", "score_test"]

#: kinds of parameters with orientation columns (eq. O2); the others turn no hand.
TURNING = ("dq", "tilt")
ALIASED = 1e-6


@dataclass(frozen=True)
class OrientationStep:
    """One group added by the orientation search.

    Attributes:
        effect, joint: the group (joint 0: not joint-specific); names: its parameters.
        p_value: of the score test (S1) on the fitting poses; n_tried: groups tried (m).
        withheld_orientation_before, withheld_orientation_after: RMS angle on the withheld
            poses before and after adding it (rad).
        withheld_rms_before, withheld_rms_after: withheld position RMS (length unit).
    """

    effect: str
    joint: int
    names: tuple[str, ...]
    p_value: float
    n_tried: int
    withheld_orientation_before: float
    withheld_orientation_after: float
    withheld_rms_before: float
    withheld_rms_after: float

    def __post_init__(self) -> None:
        if not (0.0 <= self.p_value <= 1.0) or self.n_tried < 1 or not self.names:
            raise InputError(f"OrientationStep {self.effect}: invalid p-value, count or names")

    def to_dict(self) -> dict[str, Any]:
        pairs = ("withheld_orientation_before", "withheld_orientation_after",
                 "withheld_rms_before", "withheld_rms_after")
        return {**dict_from_dataclass(self, exclude=pairs, rename={"names": "parameters"}),
                "withheld_orientation_rms_rad": [self.withheld_orientation_before,
                                                 self.withheld_orientation_after],
                "withheld_rms": [self.withheld_rms_before, self.withheld_rms_after]}


def orientation_groups(specs_of: dict[str, list[ParamSpec]], present: Sequence[ParamSpec]
                       ) -> list[tuple[str, int, list[ParamSpec]]]:
    """Candidate (effect, joint, specs) groups: parameters that turn the hand, not already in
    ``present`` (by name), grouped by effect and joint."""
    have = {s.name for s in present}
    groups: dict[tuple[str, int], list[ParamSpec]] = {}
    for eff, specs in specs_of.items():
        for s in specs:
            if s.kind in TURNING and s.name not in have:
                groups.setdefault((eff, s.joint), []).append(s)
    return [(e, j, g) for (e, j), g in groups.items()]


def _weighted(ctx: Context, fp: FullPoseFit, extra: Sequence[ParamSpec],
              poses: NDArray[np.int64], measured: F64) -> tuple[F64, F64, int]:
    """Weighted residual (N,) and Jacobian (N, p + 3 + k) at the full-pose solution, the
    ``extra`` columns last (at zero); returns also p + 3."""
    specs = tuple(fp.specs) + tuple(extra)
    prob = Problem(ctx, specs, poses, fp.position.base_rotation)
    theta = np.concatenate([fp.theta, np.zeros(len(extra))])
    rp, jp = prob.residual_and_jacobian(theta)
    eo, jo = orientation_residual(prob, theta, np.zeros(3), fp.probe_rotation, measured)
    jo = jo.reshape(-1, prob.size + 3)
    p = len(fp.specs)
    cur = np.hstack([jp[:, :p], np.zeros((len(rp), 3))])
    cur = np.vstack([cur / fp.sigma_position, jo[:, list(range(p)) + list(range(prob.size,
                                                                                prob.size + 3))]
                     / fp.sigma_orientation])
    new = np.vstack([jp[:, p:] / fp.sigma_position, jo[:, p:prob.size] / fp.sigma_orientation])
    r = np.concatenate([rp / fp.sigma_position, eo.ravel() / fp.sigma_orientation])
    return r, np.hstack([cur, new]), p + 3


def score_test(ctx: Context, fp: FullPoseFit, groups: list[tuple[str, int, list[ParamSpec]]],
               poses: NDArray[np.int64], measured: F64) -> list[float]:
    """p-value of the score test (S1) of each group at ``fp`` (1.0 when aliased).

    Args:
        ctx: the data context; fp: the current full-pose fit on ``poses``.
        groups: from :func:`orientation_groups`; poses: the fitting poses, shape (S,).
        measured: R_meas of those poses, shape (S, 3, 3).
    """
    extra = [s for _, _, g in groups for s in g]
    r, J, p0 = _weighted(ctx, fp, extra, poses, measured)
    q, _ = np.linalg.qr(J[:, :p0])
    chi = float(r @ r)
    out, col = [], p0
    for _, _, g in groups:
        c = J[:, col:col + len(g)]
        col += len(g)
        cp = c - q @ (q.T @ c)
        k = len(g)
        dof = len(r) - p0 - k
        if dof < 1 or np.linalg.norm(cp) < ALIASED * max(np.linalg.norm(c), 1e-300):
            out.append(1.0)
            continue
        coef, *_ = np.linalg.lstsq(cp, r, rcond=None)
        delta = float(min(max(r @ (cp @ coef), 0.0), chi))
        f = (delta / k) / max((chi - delta) / dof, 1e-300)
        out.append(float(stats.f.sf(f, k, dof)))
    return out


def forward_search(ctx: Context, fp: FullPoseFit, specs_of: dict[str, list[ParamSpec]],
                   fitting: NDArray[np.int64], measured: F64,
                   refit: Callable[[tuple[ParamSpec, ...]], tuple[FullPoseFit, float, float]],
                   judged: tuple[float, float], alpha: float, min_gain: float,
                   max_steps: int) -> tuple[FullPoseFit, tuple[OrientationStep, ...]]:
    """Add groups by (S1) while they pass the test and the withheld check (module doc).

    Args:
        refit: specs -> (full-pose fit, withheld orientation RMS (rad), withheld position
            RMS); judged: those two RMS values for ``fp``.
    """
    steps: list[OrientationStep] = []
    for _ in range(max_steps):
        groups = orientation_groups(specs_of, fp.specs)
        if not groups:
            break
        pv = score_test(ctx, fp, groups, fitting, measured)
        best = int(np.argmin(pv))
        if pv[best] >= alpha / len(groups):
            break
        eff, joint, g = groups[best]
        new, ori, pos = refit(tuple(fp.specs) + tuple(g))
        if ori > (1.0 - min_gain) * judged[0] or pos > (1.0 + min_gain) * judged[1]:
            break
        steps.append(OrientationStep(eff, joint, tuple(s.name for s in g), pv[best],
                                     len(groups), judged[0], ori, judged[1], pos))
        fp, judged = new, (ori, pos)
    return fp, tuple(steps)
