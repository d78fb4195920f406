"""The paper's unpublished circle as an inverse problem: which placement reproduces the 48
joint-axis cells of Tables 2-3?

Residual of a cell: r = ln(ours / published) (a ratio error, so that 4E-3 and 7E-2 weigh
alike); the two likely typos (:data:`zrp.paper.published.LIKELY_TYPOS`) are left out of the fit
and reported beside it. Cost: sum of r^2 over the 46 others.

The landscape has many minima (every joint can wrap, the plane can flip), so
:func:`recover_circle` searches globally: SciPy's differential evolution (Storn & Price) over
the 9 unknowns of :class:`~zrp.paper.placement.CirclePlacement` for each orientation law, then
least-squares polishing (trust region reflective) of the best distinct members of the final
population: a multi-start whose spread says how well the data pin each unknown. Beside it,
:func:`local_pinning` gives the Gauss-Newton 1-sigma of each unknown at a solution (finite
differences, residual scale = the fit's RMS).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import differential_evolution, least_squares

from zrp.arrays import F64
from zrp.errors import InputError
from zrp.paper.placement import (
    CELL_LABELS,
    ORIENTATION_LAWS,
    PUBLISHED_JE_CELLS,
    TYPO_MASK,
    UNKNOWNS,
    CirclePlacement,
    evaluate_placement,
)

__all__ = ["BOUNDS", "CellFit", "RecoveryResult", "fit_cells", "local_pinning",
           "recover_circle"]

#: Search box of the 9 unknowns (deg).
BOUNDS = [(-180.0, 180.0)] * 6 + [(-180.0, 180.0), (-90.0, 90.0), (-180.0, 180.0)]
_PENALTY = 1e3   # cost of a placement the arm cannot track (the fit's cost is O(1) or less)


@dataclass(frozen=True, eq=False)
class CellFit:
    """The 48 cells of one placement against the published ones.

    Attributes:
        placement: the circle.
        ours: shape (48,) in the order of :data:`~zrp.paper.placement.CELL_LABELS`.
        ratio: ours / published, shape (48,).
        within_5pct: |ratio - 1| <= 0.05 per cell, shape (48,).
        rms_log: RMS of ln(ratio) over the 46 non-typo cells.
    """

    placement: CirclePlacement
    ours: F64
    ratio: F64 = field(init=False)
    within_5pct: NDArray[np.bool_] = field(init=False)
    rms_log: float = field(init=False)

    def __post_init__(self) -> None:
        ours = np.asarray(self.ours, dtype=float)
        if ours.shape != PUBLISHED_JE_CELLS.shape:
            raise InputError(f"ours: expected shape {PUBLISHED_JE_CELLS.shape}, got {ours.shape}")
        ratio = ours / PUBLISHED_JE_CELLS
        object.__setattr__(self, "ours", ours)
        object.__setattr__(self, "ratio", ratio)
        object.__setattr__(self, "within_5pct", np.abs(ratio - 1.0) <= 0.05)
        r = np.log(np.maximum(ratio[~TYPO_MASK], 1e-12))
        object.__setattr__(self, "rms_log", float(np.sqrt(np.mean(r**2))))

    def rows(self) -> list[dict[str, object]]:
        """One dict per cell: table, column, xi, ours, published, ratio, typo."""
        return [{"table": tab, "column": col, "xi": xi, "ours": float(o),
                 "published": float(p), "ratio": float(r), "typo": bool(ty)}
                for (tab, col, xi), o, p, r, ty in zip(CELL_LABELS, self.ours,
                                                       PUBLISHED_JE_CELLS, self.ratio,
                                                       TYPO_MASK, strict=True)]


def fit_cells(placement: CirclePlacement, steps: int = 360) -> CellFit:
    """Evaluate ``placement`` (``steps`` IK steps) against the 48 published cells.

    Raises:
        InputError: naming ``placement`` when the arm cannot track the circle.
    """
    ours = evaluate_placement(placement, steps)
    if ours is None:
        raise InputError(f"placement: the PUMA cannot track this circle ({placement})")
    return CellFit(placement, ours)


def _residuals(x: F64, orientation: str, steps: int) -> F64:
    ours = evaluate_placement(CirclePlacement.from_vector(x, orientation), steps)
    if ours is None:
        return np.full(int((~TYPO_MASK).sum()), np.sqrt(_PENALTY / (~TYPO_MASK).sum()))
    return np.log(np.maximum(ours / PUBLISHED_JE_CELLS, 1e-12))[~TYPO_MASK]


def _cost(x: F64, orientation: str, steps: int) -> float:
    return float(np.sum(_residuals(x, orientation, steps) ** 2))


def local_pinning(placement: CirclePlacement, steps: int = 360,
                  step_deg: float = 0.05) -> dict[str, float]:
    """Gauss-Newton 1-sigma (deg) of each unknown at ``placement``: J from central
    differences of the log-ratio residuals (``step_deg``), sigma^2 = RMS^2 diag((J^T J)^-1)
    (pseudo-inverse; an unknown the cells do not see gets inf)."""
    x0 = placement.vector()
    r0 = _residuals(x0, placement.orientation, steps)
    jac = np.empty((r0.size, x0.size))
    for i in range(x0.size):
        dx = np.zeros_like(x0)
        dx[i] = step_deg
        jac[:, i] = (_residuals(x0 + dx, placement.orientation, steps)
                     - _residuals(x0 - dx, placement.orientation, steps)) / (2 * step_deg)
    s2 = max(float(np.mean(r0**2)), 1e-12)
    _u, sv, vt = np.linalg.svd(jac, full_matrices=False)
    inv = np.where(sv > sv[0] * 1e-8, 1.0 / np.maximum(sv, 1e-300) ** 2, np.inf)
    var = (vt.T**2) @ np.where(np.isinf(inv), 0.0, inv)
    blind = (vt.T[:, np.isinf(inv)] ** 2).sum(axis=1) > 1e-3
    return {name: (float("inf") if b else float(np.sqrt(s2 * v)))
            for name, v, b in zip(UNKNOWNS, var, blind, strict=True)}


@dataclass(frozen=True, eq=False)
class RecoveryResult:
    """What :func:`recover_circle` found.

    Attributes:
        best: the best fit over all orientation laws (evaluated at 360 steps).
        starts: every polished multi-start solution, best first.
        spread_deg: per unknown, the range (max - min, deg, wrapped) over the polished starts
            whose cost is within 2x the best (how well the data pin it).
        evaluations: placements evaluated.
    """

    best: CellFit
    starts: tuple[CellFit, ...]
    spread_deg: dict[str, float]
    evaluations: int


def _spread(fits: list[CellFit]) -> dict[str, float]:
    good = [f for f in fits if f.rms_log <= np.sqrt(2.0) * fits[0].rms_log]
    v = np.array([f.placement.vector() for f in good])
    out = {}
    for i, name in enumerate(UNKNOWNS):
        d = (v[:, i] - v[0, i] + 180.0) % 360.0 - 180.0
        out[name] = float(d.max() - d.min())
    return out


def recover_circle(*, orientations: tuple[str, ...] = ORIENTATION_LAWS, seed: int = 0,
                   popsize: int = 12, maxiter: int = 60, polish_starts: int = 6,
                   steps: int = 120) -> RecoveryResult:
    """Global search for the placement that best reproduces the 46 non-typo joint-axis cells.

    Args:
        orientations: orientation laws to search (each searched separately).
        seed: seeds differential evolution (``np.random.default_rng(seed)``).
        popsize, maxiter: differential evolution's population multiplier and generations.
        polish_starts: distinct members of each final population polished by least squares.
        steps: IK steps during the search (the results are re-evaluated at 360).
    """
    for o in orientations:
        if o not in ORIENTATION_LAWS:
            raise InputError(f"orientations: unknown law {o!r}; expected {ORIENTATION_LAWS}")
    rng = np.random.default_rng(seed)
    fits: list[CellFit] = []
    n_eval = 0
    for o in orientations:
        de = differential_evolution(_cost, BOUNDS, args=(o, steps), popsize=popsize,
                                    maxiter=maxiter, seed=rng, polish=False, tol=1e-8,
                                    init="sobol")
        n_eval += int(de.nfev)
        order = np.argsort(de.population_energies)
        picked: list[F64] = []
        for i in order:
            x = de.population[i]
            if all(np.max(np.abs((x - y + 180) % 360 - 180)) > 5.0 for y in picked):
                picked.append(x)
            if len(picked) >= polish_starts:
                break
        for x in picked:
            ls = least_squares(_residuals, x, args=(o, steps), method="trf", diff_step=1e-4,
                               max_nfev=200)
            n_eval += int(ls.nfev) * 10
            try:
                fits.append(fit_cells(CirclePlacement.from_vector(ls.x, o)))
            except InputError:
                continue
    if not fits:
        raise InputError("orientations: no placement could be tracked; widen the search")
    fits.sort(key=lambda f: f.rms_log)
    return RecoveryResult(fits[0], tuple(fits), _spread(fits), n_eval)
