"""Kernel ridge regression of a residual on the joint angles, for what remains after the
final model (:mod:`.structure`, :mod:`.residual`).

* **inputs** (:class:`Inputs`) - per pose (sin q, cos q) of each revolute joint that moves
  (q of a prismatic one), and time, temperature and load where logged; each input's columns
  centred and scaled to unit spread on the poses the inputs are set on (the fitting poses);
* **targets** (:func:`pose_targets`) - per pose the residual of a fixed set of its measured
  points (x, y, z of each; all points, or the set :func:`target_points` chooses when the poses
  carry different points), the poses that measure all of the set only;
* **model** (:func:`fit_kernel_ridge`) - a Gaussian (RBF) kernel on the inputs scaled by
  per-input length scales (ARD) that a scikit-learn Gaussian process sets on at most
  :data:`ARD_POSES` poses (its leading :data:`ARD_COMPONENTS` principal components of the
  targets: its cost grows with their number); then the kernel width and, **per principal
  component of the targets**, the ridge of least exact leave-one-out error (eigendecomposition
  of the kernel matrix: every ridge value costs O(n^2)). One ridge per component, not one for
  all targets: an effect moves a pose's points together, so it lies in a few components of
  the 3M targets and the rest is noise; a single ridge, chosen on all of them, smooths the
  effect too much to keep the noise components from being fitted (on the two simulated gear
  errors of the remainder benchmark, 800 poses, the withheld RMS with the learned term fell
  from 1.22 and 1.25 to 1.15 and 1.16 times the noise's).

scikit-learn is imported inside the functions, so that ``import zrp`` stays fast.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from zrp.arrays import F64
from zrp.gap.model.context import MIN_EXCITATION_RAD, Context
from zrp.rotations.rodrigues import er_from_axis_angle, matrix_from_er

__all__ = ["Inputs", "KernelModel", "arm_frames", "fit_kernel_ridge", "length_scales",
           "measured_points", "pose_inputs", "pose_targets", "target_points"]

#: most poses the Gaussian process that sets the length scales sees.
ARD_POSES = 200
#: leading principal components of the residual the Gaussian process fits.
ARD_COMPONENTS = 3
#: kernel widths tried on the inputs scaled by their length scales: RBF
#: exp(-gamma |x - x'|^2) (0.5: the Gaussian process's own).
GAMMAS = (0.125, 0.25, 0.5, 1.0, 2.0)
#: ridge values tried, relative to the mean eigenvalue of the kernel matrix (the largest
#: ones shrink a component that is noise to nearly nothing).
RIDGES = tuple(10.0 ** np.arange(-5.0, 3.5, 0.5))


@dataclass(frozen=True)
class Inputs:
    """The inputs of the regression, as set on the training poses.

    Attributes:
        names: "q1".."qn" (joints that move), "time", "temperature", "load".
        center, scale: per column, from the training poses.
        ranges: per input, its smallest and largest raw value on the training poses (rad or
            length unit for joints, s, deg C, kg).
        widths: per input, its number of columns (2 for a revolute joint).
    """

    names: tuple[str, ...]
    center: F64
    scale: F64
    ranges: tuple[tuple[float, float], ...]
    widths: tuple[int, ...]

    @property
    def groups(self) -> list[list[int]]:
        """The columns of each input."""
        out, i = [], 0
        for w in self.widths:
            out.append(list(range(i, i + w)))
            i += w
        return out

    def __call__(self, ctx: Context, rows: NDArray[np.int64]) -> F64:
        """The scaled inputs of the poses of ``rows`` (one row per pose)."""
        return (_raw(ctx, rows, self.names) - self.center) / self.scale


def _column(ctx: Context, rows: NDArray[np.int64], name: str) -> F64:
    meas = ctx.meas
    if name.startswith("q"):
        k = int(name[1:]) - 1
        qk = ctx.q[meas.pose_index[rows], k]
        return qk[:, None] if ctx.model.prismatic[k] else np.column_stack([np.sin(qk),
                                                                           np.cos(qk)])
    arr = {"time": meas.t, "temperature": meas.temp, "load": meas.load}[name]
    assert arr is not None
    return arr[rows][:, None]


def _raw(ctx: Context, rows: NDArray[np.int64], names: tuple[str, ...]) -> F64:
    cols = [_column(ctx, rows, n) for n in names]
    return np.column_stack(cols) if cols else np.zeros((len(rows), 0))


def _raw_value(ctx: Context, rows: NDArray[np.int64], name: str) -> F64:
    if name.startswith("q"):
        return ctx.q[ctx.meas.pose_index[rows], int(name[1:]) - 1]
    return _column(ctx, rows, name)[:, 0]


def pose_inputs(ctx: Context, rows: NDArray[np.int64], *, logged: bool = True) -> Inputs:
    """The inputs set on the poses of ``rows`` (one row per pose): joints that move at least
    the excitation threshold, and (with ``logged``) the logged columns that vary."""
    meas = ctx.meas
    names = [f"q{k + 1}" for k in range(ctx.n)
             if ctx.excited[k] and np.ptp(ctx.q[meas.pose_index[rows], k]) >= MIN_EXCITATION_RAD]
    names += [n for n, a in (("time", meas.t), ("temperature", meas.temp), ("load", meas.load))
              if logged and a is not None and np.ptp(a[rows]) > 0]
    center, scale, widths = [], [], []
    for n in names:
        f = _column(ctx, rows, n)
        widths.append(f.shape[1])
        s = math.sqrt(float(np.sum(f.var(0))))
        center.append(f.mean(0))
        scale.append(np.full(f.shape[1], s if s > 0 else 1.0))
    ranges = tuple((float(v.min()), float(v.max()))
                   for v in (_raw_value(ctx, rows, n) for n in names))
    return Inputs(tuple(names), _cat(center), _cat(scale), ranges, tuple(widths))


def _cat(parts: list[F64]) -> F64:
    return np.concatenate(parts) if parts else np.zeros(0)


def measured_points(ctx: Context, poses: NDArray[np.int64]) -> NDArray[np.bool_]:
    """Per pose of ``poses`` (sorted), which points it measures, shape (P, M)."""
    meas = ctx.meas
    rows = np.flatnonzero(np.isin(meas.pose_index, poses))
    up, inv = np.unique(meas.pose_index[rows], return_inverse=True)
    has = np.zeros((up.size, len(meas.point_labels)), dtype=bool)
    has[inv, meas.point_index[rows]] = True
    return has


def target_points(ctx: Context, poses: NDArray[np.int64]) -> NDArray[np.int64]:
    """The points (indices into the point labels) whose residual makes a pose's target: of
    the point sets the poses of ``poses`` carry, the one with the most measured values on the
    poses that measure all of it (poses x points; ties: more poses). Every point when every
    pose measures the same; with three points on some poses and one other on the rest, the
    three; with one point per pose (one label per run), the label of the most poses."""
    has = measured_points(ctx, poses)
    if has.size == 0:
        return np.arange(has.shape[1])
    best, key = np.flatnonzero(has[0]), (-1, -1)
    for cand in np.unique(has, axis=0):
        count = int(np.all(has[:, cand], axis=1).sum())
        k = (count * int(cand.sum()), count)
        if k > key:
            best, key = np.flatnonzero(cand), k
    return best


def pose_targets(ctx: Context, poses: NDArray[np.int64], residual: F64,
                 points: NDArray[np.int64] | None = None) -> tuple[F64, NDArray[np.int64]]:
    """Per pose of ``poses`` that measures every point of ``points`` (indices into the point
    labels; None: all) the residual (3R,) of those points, shape (P, 3 len(points)), and one
    row of each such pose (for its inputs)."""
    meas = ctx.meas
    pts = np.arange(len(meas.point_labels)) if points is None else np.asarray(points)
    rows = np.flatnonzero(np.isin(meas.pose_index, poses))
    r = residual[: 3 * rows.size].reshape(-1, 3)
    M = len(meas.point_labels)
    up, inv = np.unique(meas.pose_index[rows], return_inverse=True)
    Y = np.full((up.size, M, 3), np.nan)
    Y[inv, meas.point_index[rows]] = r
    first = np.full(up.size, -1, dtype=np.int64)
    first[inv[::-1]] = rows[::-1]
    Y = Y[:, pts]
    full = np.all(np.isfinite(Y.reshape(up.size, -1)), axis=1)
    return Y[full].reshape(int(full.sum()), 3 * pts.size), first[full]


def arm_frames(frame: F64, turn_axis: F64 | None, q1: F64) -> F64:
    """Per pose the frame F = frame R(turn_axis, q1), shape (P, 3, 3): the data's frame
    (``frame``: data-from-base rotation) turned with joint 1 about its axis (base frame;
    None: a prismatic joint 1, no turn). A residual y is expressed in it as F^T y."""
    q1 = np.asarray(q1, dtype=float)
    if turn_axis is None:
        return np.broadcast_to(np.asarray(frame, dtype=float), (q1.size, 3, 3)).copy()
    return np.asarray(frame, dtype=float) @ matrix_from_er(er_from_axis_angle(turn_axis, q1))


def length_scales(X: F64, Y: F64, rng: np.random.Generator) -> F64:
    """Per-column length scales (ARD) of a scikit-learn Gaussian process on at most
    :data:`ARD_POSES` poses: an input the residual does not depend on gets a long one."""
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    sub = rng.choice(len(X), min(len(X), ARD_POSES), replace=False)
    Ys = Y[sub] - Y[sub].mean(0)
    u, sv, _ = np.linalg.svd(Ys, full_matrices=False)
    Ys = u[:, :ARD_COMPONENTS] * sv[:ARD_COMPONENTS]
    Ys = Ys / max(float(Ys.std()), 1e-300)
    kernel = (ConstantKernel(0.1, (1e-4, 1e2)) * RBF(np.ones(X.shape[1]), (1e-1, 1e3))
              + WhiteKernel(1.0, (1e-4, 1e1)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a bound reached: an irrelevant input, as it should
        gp = GaussianProcessRegressor(kernel, random_state=0).fit(X[sub], Ys)
    return np.asarray(gp.kernel_.k1.k2.length_scale, dtype=float).reshape(-1)


def _kernel(A: F64, B: F64, gamma: float) -> F64:
    from sklearn.metrics.pairwise import rbf_kernel
    return rbf_kernel(A, B, gamma=gamma)


@dataclass(frozen=True)
class KernelModel:
    """A fitted kernel ridge regression (training inputs scaled, dual coefficients)."""

    Xtr: F64
    coef: F64
    mean: F64
    gamma: float
    scale: F64

    def predict(self, X: F64) -> F64:
        """Predicted targets at the (scaled) inputs X."""
        return self.mean + _kernel(X * self.scale, self.Xtr, self.gamma) @ self.coef


def fit_kernel_ridge(X: F64, Y: F64, scale: F64) -> KernelModel:
    """Kernel ridge on the inputs multiplied by ``scale`` (1 / length scales): the width of
    least exact leave-one-out error, with each principal component of the centred targets
    given its own ridge of least leave-one-out error (module docstring)."""
    Xs = X * scale
    mean = Y.mean(0)
    Yc = Y - mean
    _, _, Vt = np.linalg.svd(Yc, full_matrices=False)
    Z = Yc @ Vt.T  # the targets' principal components
    best: tuple[float, float, F64, F64, F64] | None = None
    for gamma in GAMMAS:
        w, V = np.linalg.eigh(_kernel(Xs, Xs, gamma))
        w = np.clip(w, 0.0, None)
        lam = np.asarray(RIDGES) * max(float(w.mean()), 1e-12)
        sse = _loo_sse(w, V, Z, lam)  # (ridges, components)
        if best is None or float(sse.min(0).sum()) < best[0]:
            best = (float(sse.min(0).sum()), gamma, w, V, lam[sse.argmin(0)])
    assert best is not None
    _, gamma, w, V, lam_of = best
    coef = V @ ((V.T @ Z) / (w[:, None] + lam_of[None, :]))
    return KernelModel(Xs, coef @ Vt, mean, gamma, scale)


def _loo_sse(w: F64, V: F64, Z: F64, lam: F64) -> F64:
    """Exact leave-one-out squared error per ridge (rows) and target column, for the kernel
    matrix V diag(w) V^T."""
    VtZ = V.T @ Z
    V2 = V**2
    out = np.empty((lam.size, Z.shape[1]))
    for i, lam_abs in enumerate(lam):
        h = w / (w + lam_abs)
        loo = (Z - V @ (h[:, None] * VtZ)) / (1.0 - V2 @ h)[:, None]
        out[i] = np.sum(loo**2, axis=0)
    return out
