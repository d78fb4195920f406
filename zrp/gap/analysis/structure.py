"""Is what remains structured? A multivariate, cross-validated test on the fitting poses.

The one-joint R^2 of :mod:`.where` misses a remainder that depends on several joints together.
Here the final model's residual on the fitting poses (never the withheld ones) is regressed on
all joint angles at once, as (sin q, cos q) per revolute joint (q per prismatic joint), plus
time, temperature and load where logged, by kernel ridge regression with a Gaussian (RBF)
kernel (scikit-learn's kernel; one target vector per pose, all its points' x, y, z):

* **share** - the out-of-fold explained share of the residual's variance (S1):
  ``1 - sum |y - yhat_oof|^2 / sum |y - ybar|^2`` over pose-grouped folds, each fold predicted
  by a model that never saw it; the kernel width and the ridge are chosen inside each training
  fold by exact leave-one-out (eigendecomposition of the kernel matrix, so every ridge value
  costs O(n^2)), on the inputs scaled by per-input length scales (ARD) that a Gaussian
  process (scikit-learn) sets once on a subsample of the poses (:mod:`.kernel`; a few
  hyperparameters against hundreds of poses: a negligible optimism). It is the share a smooth
  function of the inputs predicts on unseen poses: a lower bound of the structured share, below
  it by the regression's estimation error (on the simulated sag of the tests, 0.51 found for a
  true 0.55 with 300 poses, 95 % 0.47-0.54; 0.49 with one ridge for all targets). Its 95 %
  interval: a bootstrap over poses of the out-of-fold errors.
* **structure** - the share is clearly above zero (S2): the interval's lower end above 0 and
  the share at least :data:`MIN_SHARE` (below it a model of it would lower the RMS by < 2.5 %).
* **frame** - each pose's residual is taken in the arm's frame, the data's frame turned with
  joint 1 (:func:`~zrp.gap.analysis.kernel.arm_frames`), as the learned term of
  :mod:`.residual` is: an effect of the arm's own links (a sag, a gear error of joint 2) then
  does not depend on joint 1 and joint 1 is not named for it; an effect fixed in the data's
  frame names joint 1 instead.
* **relevance per input** (S3): permutation importance - the drop of the out-of-fold share
  when one joint's (sin, cos) pair (or time, temperature, load) is permuted among the poses of
  the held-out fold.
* **where** - the workspace region (horizontal reach third x upper/lower half) where the
  out-of-fold prediction of the structured part is largest (RMS).

Cost: at most :data:`MAX_POSES` poses (a seeded subsample), ``folds`` eigendecompositions per
kernel width.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.analysis.kernel import (
    arm_frames,
    fit_kernel_ridge,
    length_scales,
    pose_inputs,
    pose_targets,
    target_points,
)
from zrp.gap.analysis.notrun import NotRun
from zrp.gap.fit.leastsq import FitResult
from zrp.gap.model.context import Context
from zrp.jsonio import dict_from_dataclass

__all__ = ["MAX_POSES", "MIN_SHARE", "Structure", "remainder_structure"]

#: most poses the test uses (a seeded subsample beyond): the kernel matrix is n x n.
MAX_POSES = 1500
#: fewest complete poses for the test.
MIN_POSES = 30
#: smallest share called structure (S2).
MIN_SHARE = 0.05
#: relevance, as a fraction of the largest, above which an input is named.
NAMED_FRACTION = 0.3
N_BOOT = 400
SEED = 20260


@dataclass(frozen=True)
class Structure:
    """The multivariate test of what remains (see the module docstring).

    Attributes:
        share: out-of-fold explained share of the residual variance (S1); can be negative.
        interval: its 95 % bootstrap interval over poses.
        structured: the share is clearly above zero (S2).
        relevance: per input ("q1".."qn", "time", "temperature", "load"), the permutation drop
            of the share (S3).
        named: inputs the structure depends on (relevance >= NAMED_FRACTION x the largest),
            empty without structure.
        region: where the structured part is largest: (reach band lo, hi, "upper"/"lower",
            its RMS), None without structure.
        n_poses: poses used; folds: cross-validation folds.
        points: the measured points whose residual the test takes (every point, or the set
            :func:`~zrp.gap.analysis.kernel.target_points` chose when the poses carry
            different points: on the poses that measure all of it).
        subset: ``points`` are not every point of the data, or not every fitting pose
            measures them (the words say on which poses the test ran).
    """

    share: float
    interval: tuple[float, float]
    structured: bool
    relevance: dict[str, float]
    named: tuple[str, ...]
    region: tuple[float, float, str, float] | None
    n_poses: int
    folds: int
    points: tuple[str, ...] = ()
    subset: bool = False

    def to_dict(self) -> dict[str, Any]:
        out = dict_from_dataclass(self, exclude=("region",))
        out["region"] = None if self.region is None else {
            "radius": list(self.region[:2]), "height": self.region[2], "rms": self.region[3]}
        out["method"] = ("kernel ridge (RBF) on (sin q, cos q) and logged time/temperature/load, "
                         "pose-grouped cross-validation on the fitting poses")
        return out

    def candidates(self) -> str:
        """Plausible causes for the inputs named."""
        named = set(self.named)
        joints = [n for n in self.named if n.startswith("q")]
        out = []
        if named & {"time", "temperature"}:
            out.append("thermal expansion or drift")
        if "load" in named:
            out.append("a load-dependent deflection the model's shape misses")
        if len(joints) == 1:
            out.append(f"a cyclic error of {joints[0]} at a harmonic the library lacks")
        elif joints:
            out.append("link bending or a compliance with a shape the library lacks")
            out.append("cable or hose forces")
        return ", ".join(out)

    def words(self, unit: str) -> str:
        """One short sentence for the verdict (``unit``: the length unit)."""
        on = (f" (tested on the {self.n_poses} fitting poses that measure the same "
              f"{len(self.points)} point(s), listed in diagnosis.json)"
              if self.subset and self.points else "")
        text = self._words(unit)
        return text[:-1] + on + "." if on else text

    def _words(self, unit: str) -> str:
        lo, hi = self.interval
        if not self.structured:
            return (f"No structure: the joint angles together predict {_pct(max(self.share, 0))}"
                    f" of what remains on unseen poses (95 % {_pct(lo)} to {_pct(hi)}); it is "
                    "pose-to-pose scatter to these data.")
        joints = [n[1:] for n in self.named if n.startswith("q")]
        on = _and(([("joint " if len(joints) == 1 else "joints ") + _and(joints)]
                   if joints else []) + [n for n in self.named if not n.startswith("q")])
        where = ("" if self.region is None else
                 f"; largest in the {self.region[2]} part of reach "
                 f"{self.region[0]:.3g}-{self.region[1]:.3g} {unit}")
        return (f"{_fraction(self.share).capitalize()} of what remains ({_pct(lo)} to "
                f"{_pct(hi)}, predicted on unseen poses) depends smoothly on {on}: an "
                f"effect the library does not model{where}; candidates: {self.candidates()}.")


def _pct(x: float) -> str:
    return f"{100 * x:.0f} %"


def _fraction(x: float) -> str:
    for v, w in ((0.9, "nearly all"), (0.7, "three quarters"), (0.6, "two thirds"),
                 (0.45, "half"), (0.3, "a third"), (0.2, "a quarter"), (0.12, "a sixth")):
        if x >= v - 0.04:
            return w
    return f"{100 * x:.0f} %"


def _and(items: list[str]) -> str:
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def _region(ctx: Context, first: NDArray[np.int64], P: F64
            ) -> tuple[float, float, str, float] | None:
    pe = ctx.nominal_fk.position[ctx.meas.pose_index[first]]
    rad = np.linalg.norm(pe[:, :2], axis=1)
    edges = np.quantile(rad, [0, 1 / 3, 2 / 3, 1])
    zmid = float(np.median(pe[:, 2]))
    e2 = np.sum(P**2, axis=1)
    best = None
    for a in range(3):
        for up in (False, True):
            sel = ((rad >= edges[a]) & (rad <= edges[a + 1])
                   & ((pe[:, 2] > zmid) if up else (pe[:, 2] <= zmid)))
            if sel.sum() >= 5:
                rms = math.sqrt(float(np.mean(e2[sel])) / (P.shape[1] / 3))
                if best is None or rms > best[3]:
                    best = (float(edges[a]), float(edges[a + 1]), "upper" if up else "lower",
                            rms)
    return best


def _share(Y: F64, P: F64, idx: NDArray[np.int64] | None = None) -> float:
    if idx is not None:
        Y, P = Y[idx], P[idx]
    sst = float(np.sum((Y - Y.mean(0)) ** 2))
    return 1.0 - float(np.sum((Y - P) ** 2)) / sst if sst > 0 else 0.0


def _out_of_fold(X: F64, Y: F64, scale: F64, groups: list[list[int]], folds: int,
                 rng: np.random.Generator) -> tuple[F64, F64]:
    """Out-of-fold predictions (P, 3M) and, per input, the squared error with that input
    permuted among the poses of each held-out fold."""
    fold_of = rng.permutation(len(Y)) % folds
    P = np.empty_like(Y)
    perm_sse = np.zeros(len(groups))
    for k in range(folds):
        te, tr = fold_of == k, fold_of != k
        f = fit_kernel_ridge(X[tr], Y[tr], scale)
        P[te] = f.predict(X[te])
        for j, g in enumerate(groups):
            Xp = X[te].copy()
            Xp[:, g] = Xp[rng.permutation(int(te.sum()))][:, g]
            perm_sse[j] += float(np.sum((Y[te] - f.predict(Xp)) ** 2))
    return P, perm_sse


def _targets(ctx: Context, fit: FitResult, max_poses: int, rng: np.random.Generator
             ) -> tuple[F64, NDArray[np.int64], tuple[str, ...], bool]:
    """The targets (at most ``max_poses`` poses, a seeded subsample), one row of each of
    their poses, the points they are of and whether that is a subset (:attr:`Structure.subset`);
    :class:`NotRun` when too few poses measure the
    chosen points."""
    pts = target_points(ctx, fit.poses)
    labels = tuple(ctx.meas.point_labels[i] for i in pts)
    Y, first = pose_targets(ctx, fit.poses, fit.residual, pts)
    subset = len(labels) < len(ctx.meas.point_labels) or Y.shape[0] < np.unique(fit.poses).size
    if Y.shape[0] < MIN_POSES:
        raise NotRun(f"only {Y.shape[0]} fitting poses measure the same {len(labels)} "
                     f"point(s); the test needs {MIN_POSES}")
    if Y.shape[0] > max_poses:
        keep = np.sort(rng.choice(Y.shape[0], max_poses, replace=False))
        Y, first = Y[keep], first[keep]
    return Y, first, labels, subset


def remainder_structure(ctx: Context, fit: FitResult, *, folds: int = 5,
                        max_poses: int = MAX_POSES) -> Structure:
    """The multivariate test of what ``fit`` leaves on its fitting poses (module docstring),
    on the points :func:`~zrp.gap.analysis.kernel.target_points` chooses.

    Raises:
        NotRun: fewer than :data:`MIN_POSES` poses measure those points, no input varies or
            the residual is zero (the message says which).
    """
    rng = np.random.default_rng(SEED)
    Y, first, labels, subset = _targets(ctx, fit, max_poses, rng)
    inputs = pose_inputs(ctx, first)
    X, names = inputs(ctx, first), inputs.names
    F = arm_frames(fit.base_rotation, None if ctx.model.prismatic[0] else
                   np.asarray(ctx.model.axes[0], dtype=float), ctx.q[ctx.meas.pose_index[first], 0])
    Y = np.einsum("pji,pmj->pmi", F, Y.reshape(len(Y), -1, 3)).reshape(Y.shape)  # F^T y
    n = Y.shape[0]
    if X.shape[1] == 0:
        raise NotRun("no joint moves and no logged time, temperature or load varies")
    if not np.any(Y):
        raise NotRun("the final model leaves no residual on the fitting poses")
    scale = 1.0 / length_scales(X, Y, rng)
    P, perm_sse = _out_of_fold(X, Y, scale, inputs.groups, min(folds, n), rng)
    share = _share(Y, P)
    boot = [_share(Y, P, rng.integers(0, n, n)) for _ in range(N_BOOT)]
    lo, hi = (float(v) for v in np.percentile(boot, [2.5, 97.5]))
    sst = float(np.sum((Y - Y.mean(0)) ** 2))
    sse = float(np.sum((Y - P) ** 2))
    relevance = {nm: float((perm_sse[j] - sse) / sst) if sst > 0 else 0.0
                 for j, nm in enumerate(names)}
    structured = bool(lo > 0.0 and share >= MIN_SHARE)
    top = max(relevance.values())
    named = (tuple(nm for nm, v in relevance.items() if v >= NAMED_FRACTION * top and v > 0)
             if structured else ())
    return Structure(share, (lo, hi), structured, relevance, named,
                     _region(ctx, first, P - Y.mean(0)) if structured else None, n, folds,
                     labels, subset)
